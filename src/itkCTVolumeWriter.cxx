/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#include "itkCTVolumeWriter.h"

#include "itkClampImageFilter.h"
#include "itkGDCMImageIO.h"
#include "itkImageFileWriter.h"
#include "itkImageSeriesWriter.h"
#include "itkMetaDataObject.h"
#include "itkMetaImageIO.h"
#include "itkNrrdImageIO.h"
#include "itkRoundImageFilter.h"
#include "itkShiftScaleImageFilter.h"
#include "itkTIFFImageIO.h"

#include "gdcmUIDGenerator.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <random>
#include <sstream>

namespace itk {
namespace {
using ImageType = CTVolumeWriter::ImageType;

// Rounds to whole HU (plus an offset) and clamps to the stored type's range.
template <typename TPixel>
typename Image<TPixel, 3>::Pointer
Quantize(const ImageType * input, double offset)
{
  auto shift = ShiftScaleImageFilter<ImageType, ImageType>::New();
  shift->SetInput(input);
  shift->SetShift(offset);
  auto round = RoundImageFilter<ImageType, ImageType>::New();
  round->SetInput(shift->GetOutput());
  auto clamp = ClampImageFilter<ImageType, Image<TPixel, 3>>::New();
  clamp->SetInput(round->GetOutput());
  clamp->Update();
  return clamp->GetOutput();
}

std::string
Join(const double * values, unsigned count)
{
  std::ostringstream text;
  text.precision(10);
  for (unsigned i = 0; i < count; ++i)
  {
    text << (i ? "\\" : "") << values[i];
  }
  return text.str();
}

void
MakeDirectory(const std::string & path)
{
  std::error_code error;
  std::filesystem::create_directories(path, error);
  if (error || !std::filesystem::is_directory(path))
  {
    itkGenericExceptionMacro(<< "CTVolumeWriter: cannot create directory " << path);
  }
}
} // namespace

CTVolumeWriter::FormatType
CTVolumeWriter::FormatFromString(const std::string & name)
{
  for (FormatType format : { FormatType::Dicom, FormatType::Tiff, FormatType::MetaImage, FormatType::Nrrd })
  {
    if (name == FormatName(format))
    {
      return format;
    }
  }
  itkGenericExceptionMacro(<< "CTVolumeWriter: unknown format \"" << name << "\" (known: dicom, tiff, mha, nrrd)");
}

const char *
CTVolumeWriter::FormatName(FormatType format)
{
  switch (format)
  {
    case FormatType::Dicom:
      return "dicom";
    case FormatType::Tiff:
      return "tiff";
    case FormatType::MetaImage:
      return "mha";
    case FormatType::Nrrd:
      return "nrrd";
  }
  return "";
}

void
CTVolumeWriter::Write()
{
  if (!m_Input)
  {
    itkExceptionMacro(<< "no input volume");
  }
  if (m_FileName.empty())
  {
    itkExceptionMacro(<< "no file name");
  }
  if (m_Input->GetBufferedRegion() != m_Input->GetLargestPossibleRegion())
  {
    itkExceptionMacro(<< "the input volume is not fully buffered");
  }
  switch (m_Format)
  {
    case FormatType::Dicom:
      WriteDicom();
      break;
    case FormatType::Tiff:
      WriteTiff();
      break;
    case FormatType::MetaImage:
    case FormatType::Nrrd:
      WriteSingleFile();
      break;
  }
}

void
CTVolumeWriter::WriteDicom() const
{
  using StoredType = Image<int16_t, 3>;
  // GDCMImageIO applies the inverse rescale on write: give it HU, it stores HU + 1024.
  const auto volume = Quantize<int16_t>(m_Input, 0.0);
  MakeDirectory(m_FileName);

  const auto         size = volume->GetLargestPossibleRegion().GetSize();
  const auto         spacing = volume->GetSpacing();
  const auto &       direction = volume->GetDirection();
  gdcm::UIDGenerator uids;
  const std::string  study = uids.Generate(), series = uids.Generate(), frame = uids.Generate();
  char               date[16];
  const std::time_t  now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y%m%d", std::gmtime(&now));

  const double orientation[6] = { direction[0][0], direction[1][0], direction[2][0],
                                  direction[0][1], direction[1][1], direction[2][1] };
  const double pixelSpacing[2] = { spacing[1], spacing[0] };

  std::vector<MetaDataDictionary> dictionaries(size[2]);
  std::vector<std::string>        names(size[2]);
  std::vector<unsigned>           order(size[2]);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 random(m_Seed);
  std::shuffle(order.begin(), order.end(), random);
  for (unsigned k = 0; k < size[2]; ++k)
  {
    StoredType::PointType position;
    volume->TransformIndexToPhysicalPoint({ { 0, 0, static_cast<IndexValueType>(k) } }, position);
    MetaDataDictionary & d = dictionaries[k];
    auto set = [&d](const char * tag, const std::string & value) { EncapsulateMetaData<std::string>(d, tag, value); };
    set("0008|0008", "DERIVED\\SECONDARY\\AXIAL");
    set("0008|0016", "1.2.840.10008.5.1.4.1.1.2");
    set("0008|0018", uids.Generate());
    set("0008|0020", date);
    set("0008|0021", date);
    set("0008|0060", "CT");
    set("0008|0070", "VirtualUnwrapping");
    set("0008|103e", m_SeriesDescription);
    set("0010|0010", "Phantom^Sheet");
    set("0010|0020", "VU-PHANTOM");
    set("0020|000d", study);
    set("0020|000e", series);
    set("0020|0052", frame);
    set("0020|0011", "1");
    set("0020|0013", std::to_string(k + 1));
    set("0020|0032", Join(position.GetDataPointer(), 3));
    set("0020|0037", Join(orientation, 6));
    set("0020|1041", Join(&position[2], 1));
    set("0028|0004", "MONOCHROME2");
    set("0028|0030", Join(pixelSpacing, 2));
    set("0018|0050", Join(&spacing[2], 1));
    set("0018|0088", Join(&spacing[2], 1));
    set("0028|1052", "-1024");
    set("0028|1053", "1");
    set("0028|1054", "HU");
    char name[32];
    std::snprintf(name, sizeof(name), "IM%05u.dcm", order[k]);
    names[k] = (std::filesystem::path(m_FileName) / name).string();
  }
  auto io = GDCMImageIO::New();
  io->KeepOriginalUIDOn();
  auto writer = ImageSeriesWriter<StoredType, Image<int16_t, 2>>::New();
  writer->SetInput(volume);
  writer->SetImageIO(io);
  writer->SetFileNames(names);
  std::vector<MetaDataDictionary *> dictionaryPointers;
  for (MetaDataDictionary & d : dictionaries)
  {
    dictionaryPointers.push_back(&d);
  }
  writer->SetMetaDataDictionaryArray(&dictionaryPointers);
  writer->Update();
}

void
CTVolumeWriter::WriteTiff() const
{
  using StoredType = Image<uint16_t, 3>;
  const auto volume = Quantize<uint16_t>(m_Input, 1024.0);
  MakeDirectory(m_FileName);
  const auto               slices = volume->GetLargestPossibleRegion().GetSize()[2];
  std::vector<std::string> names(slices);
  for (unsigned k = 0; k < slices; ++k)
  {
    char name[32];
    std::snprintf(name, sizeof(name), "slice_%04u.tif", k);
    names[k] = (std::filesystem::path(m_FileName) / name).string();
  }
  auto writer = ImageSeriesWriter<StoredType, Image<uint16_t, 2>>::New();
  writer->SetInput(volume);
  writer->SetImageIO(TIFFImageIO::New());
  writer->SetFileNames(names);
  writer->Update();
}

void
CTVolumeWriter::WriteSingleFile() const
{
  using StoredType = Image<int16_t, 3>;
  const auto volume = Quantize<int16_t>(m_Input, 0.0);
  auto       writer = ImageFileWriter<StoredType>::New();
  writer->SetInput(volume);
  if (m_Format == FormatType::MetaImage)
  {
    writer->SetImageIO(MetaImageIO::New());
  }
  else
  {
    writer->SetImageIO(NrrdImageIO::New());
  }
  writer->SetFileName(m_FileName);
  writer->UseCompressionOn();
  writer->Update();
}

void
CTVolumeWriter::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Input: " << m_Input.GetPointer() << std::endl;
  os << indent << "FileName: " << m_FileName << std::endl;
  os << indent << "Format: " << FormatName(m_Format) << std::endl;
  os << indent << "SeriesDescription: " << m_SeriesDescription << std::endl;
  os << indent << "Seed: " << m_Seed << std::endl;
}
} // end namespace itk

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
#include "itkMultiThreaderBase.h"
#include "itkNrrdImageIO.h"
#include "itkRoundImageFilter.h"
#include "itkShiftScaleImageFilter.h"
#include "itkTIFFImageIO.h"
#include "itkWindowedSincInterpolateImageFunction.h"
#include "itkZarrImageIO.h"

#include "gdcmUIDGenerator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <numeric>
#include <random>
#include <sstream>

namespace itk {
namespace {
using ImageType = CTVolumeWriter::ImageType;

/** A gantry may tilt up to this many degrees either way (scanners reach about 30). */
constexpr double kMaximumGantryTilt = 60.0;

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
  for (FormatType format :
       { FormatType::Dicom, FormatType::Tiff, FormatType::MetaImage, FormatType::Nrrd, FormatType::Zarr })
  {
    if (name == FormatName(format))
    {
      return format;
    }
  }
  itkGenericExceptionMacro(<< "CTVolumeWriter: unknown format \"" << name
                           << "\" (known: dicom, tiff, mha, nrrd, zarr)");
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
    case FormatType::Zarr:
      return "zarr";
  }
  return "";
}

std::vector<double>
CTVolumeWriter::SliceLocationsWithSpacingChange(double extent, double firstSpacing, double secondSpacing)
{
  if (!(firstSpacing > 0.0) || !(secondSpacing > 0.0) || !(extent >= 0.0) ||
      !std::isfinite(extent + firstSpacing + secondSpacing))
  {
    itkGenericExceptionMacro(<< "CTVolumeWriter: slice spacings must be positive and the extent finite");
  }
  // A margin of a thousandth of a spacing keeps slices that land on the half or the end.
  std::vector<double> locations;
  for (double t = 0.0; t <= 0.5 * extent + 1e-3 * firstSpacing; t = locations.back() + firstSpacing)
  {
    locations.push_back(t);
  }
  for (double t = locations.back() + secondSpacing; t <= extent + 1e-3 * secondSpacing; t += secondSpacing)
  {
    locations.push_back(t);
  }
  return locations;
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
  if (!(std::abs(m_GantryTilt) < kMaximumGantryTilt))
  {
    itkExceptionMacro(<< "gantry tilt must lie within +-" << kMaximumGantryTilt << " degrees, not " << m_GantryTilt);
  }
  if (!std::isfinite(m_OutsideValue))
  {
    itkExceptionMacro(<< "the outside value must be finite");
  }
  if ((m_GantryTilt != 0.0 || !m_SliceLocations.empty()) && m_Format != FormatType::Dicom)
  {
    itkExceptionMacro(<< "a gantry tilt or slice locations need the DICOM format, not " << FormatName(m_Format));
  }
  if (!m_SliceLocations.empty())
  {
    const double extent =
      m_Input->GetSpacing()[2] * static_cast<double>(m_Input->GetLargestPossibleRegion().GetSize(2) - 1);
    const double margin = 1e-6 * m_Input->GetSpacing()[2];
    for (size_t k = 0; k < m_SliceLocations.size(); ++k)
    {
      const double t = m_SliceLocations[k];
      if (!(t >= -margin && t <= extent + margin) || (k > 0 && !(t > m_SliceLocations[k - 1])))
      {
        itkExceptionMacro(<< "slice locations must increase and lie within the input's 0 to " << extent << " mm; slice "
                          << k << " is at " << t << " mm");
      }
    }
    if (m_SliceLocations.size() < 2)
    {
      itkExceptionMacro(<< "a series needs at least two slice locations");
    }
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
    case FormatType::Zarr:
      WriteSingleFile();
      break;
  }
}

ImageType::Pointer
CTVolumeWriter::SampleSlices(const std::vector<double> & locations, std::vector<ImageType::PointType> & origins) const
{
  const auto   size = m_Input->GetLargestPossibleRegion().GetSize();
  const auto   spacing = m_Input->GetSpacing();
  const auto & direction = m_Input->GetDirection();
  // Origins move along the column axis by -tan(tilt) per mm along the normal; the slices
  // start where the highest one does, and grow by the drift so that each holds the input.
  const double        slope = -std::tan(m_GantryTilt * Math::pi / 180.0);
  std::vector<double> shift(locations.size());
  for (size_t k = 0; k < locations.size(); ++k)
  {
    shift[k] = slope * (locations[k] - locations.front());
  }
  const auto [lowest, highest] = std::minmax_element(shift.begin(), shift.end());
  const SizeValueType rows = size[1] + static_cast<SizeValueType>(std::ceil((*highest - *lowest) / spacing[1] - 1e-6));
  const double        top = *highest;

  auto                slices = ImageType::New();
  ImageType::SizeType stackSize{ { size[0], rows, locations.size() } };
  slices->SetRegions(stackSize);
  slices->Allocate();
  origins.resize(locations.size());
  for (size_t k = 0; k < locations.size(); ++k)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      origins[k][d] = m_Input->GetOrigin()[d] + direction[d][1] * (shift[k] - top) + direction[d][2] * locations[k];
    }
  }
  slices->SetOrigin(origins.front());
  slices->SetSpacing(spacing);
  slices->SetDirection(direction);

  auto interpolator = WindowedSincInterpolateImageFunction<ImageType, 4, Function::LanczosWindowFunction<4>>::New();
  interpolator->SetInputImage(m_Input);
  float * buffer = slices->GetBufferPointer();
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    locations.size(),
    [&](SizeValueType k) {
      float * out = buffer + k * size[0] * rows;
      for (SizeValueType j = 0; j < rows; ++j)
      {
        for (SizeValueType i = 0; i < size[0]; ++i)
        {
          ImageType::PointType p;
          for (unsigned d = 0; d < 3; ++d)
          {
            p[d] = origins[k][d] + direction[d][0] * static_cast<double>(i) * spacing[0] +
                   direction[d][1] * static_cast<double>(j) * spacing[1];
          }
          *out++ = interpolator->IsInsideBuffer(p) ? static_cast<float>(interpolator->Evaluate(p))
                                                   : static_cast<float>(m_OutsideValue);
        }
      }
    },
    nullptr);
  return slices;
}

void
CTVolumeWriter::WriteDicom() const
{
  using StoredType = Image<int16_t, 3>;
  const auto          inputSize = m_Input->GetLargestPossibleRegion().GetSize();
  std::vector<double> locations = m_SliceLocations;
  if (locations.empty())
  {
    for (SizeValueType k = 0; k < inputSize[2]; ++k)
    {
      locations.push_back(static_cast<double>(k) * m_Input->GetSpacing()[2]);
    }
  }
  std::vector<ImageType::PointType> origins(locations.size());
  ImageType::ConstPointer           slices = m_Input;
  if (m_GantryTilt != 0.0 || !m_SliceLocations.empty())
  {
    slices = this->SampleSlices(locations, origins);
  }
  else
  {
    for (SizeValueType k = 0; k < inputSize[2]; ++k)
    {
      m_Input->TransformIndexToPhysicalPoint({ { 0, 0, static_cast<IndexValueType>(k) } }, origins[k]);
    }
  }
  // GDCMImageIO applies the inverse rescale on write: give it HU, it stores HU + 1024.
  const auto volume = Quantize<int16_t>(slices, 0.0);
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
  bool         even = true;
  for (size_t k = 2; k < locations.size(); ++k)
  {
    even = even && std::abs((locations[k] - locations[k - 1]) - (locations[1] - locations[0])) <=
                     1e-6 * (locations[1] - locations[0]);
  }

  std::vector<MetaDataDictionary> dictionaries(size[2]);
  std::vector<std::string>        names(size[2]);
  std::vector<unsigned>           order(size[2]);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 random(m_Seed);
  std::shuffle(order.begin(), order.end(), random);
  for (unsigned k = 0; k < size[2]; ++k)
  {
    const ImageType::PointType & position = origins[k];
    const double                 thickness = locations.size() < 2       ? spacing[2]
                                             : k + 1 < locations.size() ? locations[k + 1] - locations[k]
                                                                        : locations[k] - locations[k - 1];
    double                       location = 0.0;
    for (unsigned d = 0; d < 3; ++d)
    {
      location += position[d] * direction[d][2];
    }
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
    set("0020|1041", Join(&location, 1));
    set("0028|0004", "MONOCHROME2");
    set("0028|0030", Join(pixelSpacing, 2));
    set("0018|0050", Join(&thickness, 1));
    if (even)
    {
      set("0018|0088", Join(&thickness, 1));
    }
    set("0018|1120", Join(&m_GantryTilt, 1));
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
  else if (m_Format == FormatType::Zarr)
  {
    writer->SetImageIO(ZarrImageIO::New());
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
  os << indent << "GantryTilt: " << m_GantryTilt << std::endl;
  os << indent << "OutsideValue: " << m_OutsideValue << std::endl;
  os << indent << "SliceLocations: " << m_SliceLocations.size() << std::endl;
}
} // end namespace itk

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
#include "itkCTVolumeReader.h"
#include "itkCTVolumeWriter.h"
#include "itkGDCMImageIO.h"
#include "itkGDCMSeriesFileNames.h"
#include "itkImageFileReader.h"
#include "itkImageSeriesReader.h"
#include "itkMetaDataObject.h"
#include "itkSheetPhantomSource.h"
#include "itkTIFFImageIO.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace {
using Writer = itk::CTVolumeWriter;
using VolumeType = Writer::ImageType;

// A small tilted phantom with thick slices, so that the three spacings differ.
VolumeType::Pointer
MakePhantom()
{
  auto source = itk::SheetPhantomSource::New();
  source->SetText("ROUND TRIP");
  source->SetSheetWidth(5.0);
  source->SetNumberOfTurns(1.5);
  source->SetSliceSpacing(0.15);
  source->SetTiltAngle(10.0);
  source->Update();
  return source->GetOutput();
}

std::string
OutputPath(const std::string & name)
{
  const std::filesystem::path path = std::filesystem::path(VU_BINARY_DIR) / "Testing" / "CTVolumeWriter" / name;
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path.parent_path());
  return path.string();
}

void
Write(const VolumeType * volume, Writer::FormatType format, const std::string & path)
{
  auto writer = Writer::New();
  writer->SetInput(volume);
  writer->SetFormat(format);
  writer->SetFileName(path);
  writer->Write();
}

// Same grid; values equal to the input rounded to whole HU, at least lowest, plus offset.
void
ExpectSameVolume(const VolumeType * expected,
                 const VolumeType * actual,
                 double             offset,
                 bool               compareGeometry,
                 double             lowest = -32768.0)
{
  ASSERT_EQ(expected->GetLargestPossibleRegion().GetSize(), actual->GetLargestPossibleRegion().GetSize());
  if (compareGeometry)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(expected->GetSpacing()[d], actual->GetSpacing()[d], 1e-6);
      EXPECT_NEAR(expected->GetOrigin()[d], actual->GetOrigin()[d], 1e-4);
      for (unsigned e = 0; e < 3; ++e)
      {
        EXPECT_NEAR(expected->GetDirection()[d][e], actual->GetDirection()[d][e], 1e-6);
      }
    }
  }
  size_t       wrong = 0;
  const size_t n = expected->GetLargestPossibleRegion().GetNumberOfPixels();
  for (size_t i = 0; i < n; ++i)
  {
    const double value = std::max(itk::Math::Round<double>(expected->GetBufferPointer()[i]), lowest) + offset;
    if (std::abs(value - actual->GetBufferPointer()[i]) > 1e-3 && wrong++ < 5)
    {
      ADD_FAILURE() << "voxel " << i << ": expected " << value << ", read " << actual->GetBufferPointer()[i];
    }
  }
  EXPECT_EQ(wrong, 0u) << "of " << n;
}
} // namespace

TEST(CTVolumeWriter, BasicObjectMethods)
{
  auto writer = Writer::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(writer, CTVolumeWriter, Object));
  EXPECT_EQ(Writer::FormatFromString("mha"), Writer::FormatType::MetaImage);
  EXPECT_STREQ(Writer::FormatName(Writer::FormatType::Dicom), "dicom");
  EXPECT_THROW(Writer::FormatFromString("png"), itk::ExceptionObject);
  EXPECT_THROW(writer->Write(), itk::ExceptionObject);
}

TEST(CTVolumeWriter, DicomSeriesReadsBackWithItsGeometry)
{
  const auto        volume = MakePhantom();
  const std::string directory = OutputPath("dicom");
  Write(volume, Writer::FormatType::Dicom, directory);

  auto names = itk::GDCMSeriesFileNames::New();
  names->SetDirectory(directory);
  const auto & series = names->GetSeriesUIDs();
  ASSERT_EQ(series.size(), 1u);
  const std::vector<std::string> files = names->GetFileNames(series.front());
  ASSERT_EQ(files.size(), volume->GetLargestPossibleRegion().GetSize()[2]);
  // Shuffled: the files in slice order are not in name order.
  EXPECT_FALSE(std::is_sorted(files.begin(), files.end()));

  auto io = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<VolumeType>::New();
  reader->SetImageIO(io);
  reader->SetFileNames(files);
  reader->Update();
  ExpectSameVolume(volume, reader->GetOutput(), 0.0, true);
  std::string modality;
  itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0008|0060", modality);
  EXPECT_EQ(modality.substr(0, 2), "CT");
  EXPECT_EQ(io->GetRescaleIntercept(), -1024.0);
  EXPECT_EQ(io->GetRescaleSlope(), 1.0);
  // Stored as signed 16-bit integers.
  std::string bitsAllocated, pixelRepresentation;
  itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0028|0100", bitsAllocated);
  itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0028|0103", pixelRepresentation);
  EXPECT_EQ(std::stoi(bitsAllocated), 16);
  EXPECT_EQ(std::stoi(pixelRepresentation), 1);
}

TEST(CTVolumeWriter, TiffStackReadsBackWithTheGivenSpacing)
{
  const auto        volume = MakePhantom();
  const std::string directory = OutputPath("tiff");
  Write(volume, Writer::FormatType::Tiff, directory);
  std::vector<std::string> files;
  for (const auto & entry : std::filesystem::directory_iterator(directory))
  {
    files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), volume->GetLargestPossibleRegion().GetSize()[2]);
  EXPECT_EQ(std::filesystem::path(files[1]).filename(), "slice_0001.tif");
  auto reader = itk::ImageSeriesReader<VolumeType>::New();
  reader->SetImageIO(itk::TIFFImageIO::New());
  reader->SetFileNames(files);
  reader->Update();
  VolumeType::Pointer read = reader->GetOutput();
  read->SetSpacing(volume->GetSpacing());
  read->SetOrigin(volume->GetOrigin());
  // Air noise below -1024 HU is clipped, as scanners do.
  ExpectSameVolume(volume, read, 1024.0, true, -1024.0);
}

TEST(CTVolumeWriter, MetaImageAndNrrdReadBackWithTheirGeometry)
{
  const auto volume = MakePhantom();
  for (const auto & [format, name] : { std::make_pair(Writer::FormatType::MetaImage, "volume.mha"),
                                       std::make_pair(Writer::FormatType::Nrrd, "volume.nrrd") })
  {
    const std::string path = OutputPath(name);
    Write(volume, format, path);
    auto reader = itk::ImageFileReader<VolumeType>::New();
    reader->SetFileName(path);
    reader->Update();
    ExpectSameVolume(volume, reader->GetOutput(), 0.0, true);
  }
}

// Every preset, written in each of the three formats, reads back through the module's own
// CT reader with the geometry it was written with (a TIFF stack carries no origin or
// direction, and its spacing is the user's: size and spacing are compared there).
TEST(CTVolumeWriter, EveryPresetReadsBackThroughTheCTReader)
{
  for (const std::string & preset : itk::SheetPhantomSource::GetPresetNames())
  {
    auto source = itk::SheetPhantomSource::New();
    source->ApplyPreset(preset);
    source->SetNoiseStandardDeviation(0.0);
    source->Update();
    const VolumeType * volume = source->GetOutput();
    for (auto format : { Writer::FormatType::Dicom, Writer::FormatType::Tiff, Writer::FormatType::MetaImage })
    {
      const bool        single = format == Writer::FormatType::MetaImage;
      const std::string path = OutputPath(preset + "-" + Writer::FormatName(format) + (single ? ".mha" : ""));
      Write(volume, format, path);
      auto reader = itk::CTVolumeReader::New();
      reader->SetFileName(path);
      if (format == Writer::FormatType::Tiff)
      {
        reader->SetSpacingOverride(volume->GetSpacing());
        reader->SetOverrideSpacing(true);
      }
      reader->Update();
      const VolumeType * read = reader->GetOutput();
      SCOPED_TRACE(preset + " as " + Writer::FormatName(format));
      ASSERT_EQ(read->GetLargestPossibleRegion().GetSize(), volume->GetLargestPossibleRegion().GetSize());
      for (unsigned d = 0; d < 3; ++d)
      {
        EXPECT_NEAR(read->GetSpacing()[d], volume->GetSpacing()[d], 1e-6);
        if (format != Writer::FormatType::Tiff)
        {
          EXPECT_NEAR(read->GetOrigin()[d], volume->GetOrigin()[d], 1e-4);
          for (unsigned e = 0; e < 3; ++e)
          {
            EXPECT_NEAR(read->GetDirection()[d][e], volume->GetDirection()[d][e], 1e-6);
          }
        }
      }
    }
  }
}

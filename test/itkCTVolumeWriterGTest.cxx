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
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageSeriesReader.h"
#include "itkMetaDataObject.h"
#include "itkSheetPhantomSource.h"
#include "itkTIFFImageIO.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

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
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(0.0, writer->GetGantryTilt());
                       ITK_TEST_SET_GET_VALUE(-1000.0, writer->GetOutsideValue()));
  EXPECT_TRUE(writer->GetSliceLocations().empty());
}

TEST(CTVolumeWriter, SliceLocationsWithSpacingChange)
{
  const std::vector<double> locations = Writer::SliceLocationsWithSpacingChange(1.0, 0.1, 0.15);
  const std::vector<double> expected = { 0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 0.95 };
  ASSERT_EQ(locations.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k)
  {
    EXPECT_NEAR(locations[k], expected[k], 1e-12);
  }
  EXPECT_THROW(Writer::SliceLocationsWithSpacingChange(1.0, 0.0, 0.15), itk::ExceptionObject);
  EXPECT_THROW(Writer::SliceLocationsWithSpacingChange(1.0, 0.1, -1.0), itk::ExceptionObject);
}

namespace {
VolumeType::Pointer
MakeQuietPhantom()
{
  auto source = itk::SheetPhantomSource::New();
  source->SetText("TILT");
  source->SetSheetWidth(5.0);
  source->SetNumberOfTurns(1.5);
  source->SetSliceSpacing(0.15);
  source->SetNoiseStandardDeviation(0.0);
  source->Update();
  return source->GetOutput();
}

struct SliceHeader
{
  std::array<double, 3> Position;
  std::string           Tilt;
  std::string           SpacingBetweenSlices;
  unsigned              Rows{ 0 };
};

std::vector<SliceHeader>
ReadHeaders(const std::string & directory)
{
  std::vector<SliceHeader> headers;
  for (const auto & entry : std::filesystem::directory_iterator(directory))
  {
    auto io = itk::GDCMImageIO::New();
    io->SetFileName(entry.path().string());
    io->ReadImageInformation();
    SliceHeader header;
    std::string position;
    itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0020|0032", position);
    std::replace(position.begin(), position.end(), '\\', ' ');
    std::istringstream(position) >> header.Position[0] >> header.Position[1] >> header.Position[2];
    itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0018|1120", header.Tilt);
    itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), "0018|0088", header.SpacingBetweenSlices);
    header.Rows = static_cast<unsigned>(io->GetDimensions(1));
    headers.push_back(header);
  }
  std::sort(headers.begin(), headers.end(), [](const SliceHeader & a, const SliceHeader & b) {
    return a.Position[2] < b.Position[2];
  });
  return headers;
}
} // namespace

// A hospital CT series: gantry tilted by 15 degrees, 0.15 mm slices, then 0.25 mm. Every
// slice is where the tilt puts it (origins moved along -y by tan(15) per mm of z), tagged
// with the tilt, and wide enough to hold the whole volume.
TEST(CTVolumeWriter, TiltedSeriesWithChangingSpacingHasItsGeometryInTheHeaders)
{
  const auto   volume = MakeQuietPhantom();
  const auto   size = volume->GetLargestPossibleRegion().GetSize();
  const double extent = 0.15 * static_cast<double>(size[2] - 1);
  const auto   locations = Writer::SliceLocationsWithSpacingChange(extent, 0.15, 0.25);
  for (const double tilt : { 15.0, -15.0 })
  {
    SCOPED_TRACE(tilt);
    const std::string directory = OutputPath("tilted" + std::to_string(static_cast<int>(tilt)));
    auto              writer = Writer::New();
    writer->SetInput(volume);
    writer->SetFileName(directory);
    writer->SetGantryTilt(tilt);
    writer->SetSliceLocations(locations);
    writer->Write();
    const std::vector<SliceHeader> headers = ReadHeaders(directory);
    ASSERT_EQ(headers.size(), locations.size());
    const double slope = -std::tan(tilt * itk::Math::pi / 180.0);
    // The highest slice starts where the volume does.
    const double top = std::max(0.0, slope * locations.back());
    const auto   drift = static_cast<unsigned>(std::ceil(std::abs(slope) * locations.back() / volume->GetSpacing()[1]));
    for (size_t k = 0; k < headers.size(); ++k)
    {
      EXPECT_NEAR(headers[k].Position[0], volume->GetOrigin()[0], 1e-6);
      EXPECT_NEAR(headers[k].Position[1], volume->GetOrigin()[1] + slope * locations[k] - top, 1e-6);
      EXPECT_NEAR(headers[k].Position[2], volume->GetOrigin()[2] + locations[k], 1e-6);
      EXPECT_EQ(std::stod(headers[k].Tilt), tilt);
      EXPECT_TRUE(headers[k].SpacingBetweenSlices.empty());
      EXPECT_EQ(headers[k].Rows, size[1] + drift);
    }
  }
}

// Read back (resampled by the CT reader), the tilted series gives the volume again: the
// reader's grid holds the volume's voxels, and they differ from the written volume only by
// the interpolation (here of a noiseless phantom) and the rounding to whole HU.
TEST(CTVolumeWriter, TiltedSeriesReadsBackToTheVolume)
{
  const auto        volume = MakeQuietPhantom();
  const std::string directory = OutputPath("tilted-readback");
  auto              writer = Writer::New();
  writer->SetInput(volume);
  writer->SetFileName(directory);
  writer->SetGantryTilt(15.0);
  writer->Write();
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(directory);
  reader->Update();
  const VolumeType * read = reader->GetOutput();
  EXPECT_TRUE(reader->GetResampled());
  double     sum = 0.0, worst = 0.0;
  size_t     count = 0, nan = 0;
  const auto size = volume->GetLargestPossibleRegion().GetSize();
  for (itk::ImageRegionConstIteratorWithIndex<VolumeType> it(volume, volume->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    VolumeType::PointType p;
    volume->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    VolumeType::IndexType index;
    ASSERT_TRUE(read->TransformPhysicalPointToIndex(p, index)) << p;
    const float value = read->GetPixel(index);
    nan += std::isnan(value) ? 1 : 0;
    // The outermost voxels meet the air written beyond the volume.
    if (std::isnan(value) || it.GetIndex()[1] < 3 || it.GetIndex()[1] + 3 >= static_cast<long>(size[1]))
    {
      continue;
    }
    const double difference = std::abs(value - it.Get());
    sum += difference;
    worst = std::max(worst, difference);
    ++count;
  }
  EXPECT_EQ(nan, 0u);
  std::cout << "[ tilted   ] mean |difference| " << sum / count << " HU, largest " << worst << " HU" << std::endl;
  EXPECT_LT(sum / count, 5.0);
  EXPECT_LT(worst, 150.0);
}

TEST(CTVolumeWriter, BadTiltOrSliceLocationsAreRefused)
{
  const auto volume = MakeQuietPhantom();
  auto       writer = Writer::New();
  writer->SetInput(volume);
  writer->SetFileName(OutputPath("bad"));
  writer->SetGantryTilt(60.0);
  EXPECT_THROW(writer->Write(), itk::ExceptionObject);
  writer->SetGantryTilt(10.0);
  writer->SetFormat(Writer::FormatType::Tiff);
  EXPECT_THROW(writer->Write(), itk::ExceptionObject);
  writer->SetFormat(Writer::FormatType::Dicom);
  writer->SetGantryTilt(0.0);
  for (const std::vector<double> & locations :
       std::vector<std::vector<double>>{ { 0.0, 0.3, 0.2 }, { 0.0, 1000.0 }, { 0.2 } })
  {
    writer->SetSliceLocations(locations);
    EXPECT_THROW(writer->Write(), itk::ExceptionObject);
  }
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

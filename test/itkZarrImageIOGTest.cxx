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
// ZarrImageIO on stores written by python3-zarr (test/zarr_stores.py, its shapes, chunks,
// types and compressors drawn at run time): every voxel, the OME-Zarr geometry, region
// reads that open only the chunks they overlap, and the refusals.
#include "itkCTVolumeReader.h"
#include "itkCastImageFilter.h"
#include "itkCommand.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkZarrImageIO.h"
#include "vuExpectRefusal.h"
#include "vuTestHelpers.h"
#include "vuVoxelCount.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace {
namespace fs = std::filesystem;
using Json = nlohmann::json;
using ImageType = itk::Image<double, 3>;

const std::string &
StoreDirectory()
{
  static const std::string directory = std::string(VU_BINARY_DIR) + "/Testing/Zarr";
  return directory;
}

Json
Manifest()
{
  std::ifstream in(StoreDirectory() + "/manifest.json");
  if (!in)
  {
    throw std::runtime_error("no manifest: run test/zarr_stores.py " + StoreDirectory() + " first");
  }
  return Json::parse(in);
}

// The value test/zarr_stores.py wrote at (x, y, z), in the store's type.
double
Expected(const Json & store, long x, long y, long z)
{
  const std::string dtype = store["dtype"].get<std::string>().substr(1);
  const auto        c = store["coefficients"];
  if (const Json & hole = store["hole_chunk_zyx"]; !hole.is_null())
  {
    const auto chunks = store["chunks_zyx"];
    if (z / chunks[0].get<long>() == hole[0].get<long>() && y / chunks[1].get<long>() == hole[1].get<long>() &&
        x / chunks[2].get<long>() == hole[2].get<long>())
    {
      return store["fill"].get<double>();
    }
  }
  if (dtype[0] == 'f')
  {
    const double v = c[0].get<double>() * x + c[1].get<double>() * y + c[2].get<double>() * z + c[3].get<double>();
    return dtype == "f4" ? static_cast<double>(static_cast<float>(v)) : v;
  }
  const int       bits = 8 * (dtype[1] - '0');
  const bool      isSigned = dtype[0] == 'i';
  const long long span = 1LL << bits;
  const long long low = isSigned ? -(span / 2) : 0;
  long long       v =
    c[0].get<long long>() * x + c[1].get<long long>() * y + c[2].get<long long>() * z + c[3].get<long long>();
  v = ((v % span) + span) % span + low;
  return static_cast<double>(v);
}

ImageType::Pointer
ReadRegion(const std::string & path, const ImageType::RegionType * region, itk::ZarrImageIO * io)
{
  auto reader = itk::ImageFileReader<ImageType>::New();
  reader->SetFileName(path);
  reader->SetImageIO(io);
  reader->UpdateOutputInformation();
  if (region != nullptr)
  {
    reader->GetOutput()->SetRequestedRegion(*region);
  }
  reader->Update();
  return reader->GetOutput();
}

// Values of the image over its buffered region against the store's formula; the count of
// voxels that differ.
size_t
Mismatches(const Json & store, const ImageType * image)
{
  size_t bad = 0;
  for (itk::ImageRegionConstIteratorWithIndex<ImageType> it(image, image->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    const auto   index = it.GetIndex();
    const double expected = Expected(store, index[0], index[1], index[2]);
    if (std::abs(it.Get() - expected) > 1e-9 * std::max(1.0, std::abs(expected)))
    {
      if (bad++ < 3)
      {
        ADD_FAILURE() << store["name"] << " at " << index << ": " << it.Get() << ", expected " << expected;
      }
    }
  }
  return bad;
}

std::vector<long>
ShapeXyz(const Json & store)
{
  const auto shape = store["shape_zyx"];
  return { shape[2].get<long>(), shape[1].get<long>(), shape[0].get<long>() };
}
} // namespace

TEST(ZarrImageIO, EveryStoreIsReadVoxelByVoxel)
{
  const Json manifest = Manifest();
  std::cout << "stores written with seed " << manifest["seed"] << std::endl;
  for (const Json & store : manifest["stores"])
  {
    if (store["kind"] == "flat")
    {
      continue;
    }
    const std::string path = StoreDirectory() + "/" + store["name"].get<std::string>();
    auto              io = itk::ZarrImageIO::New();
    ASSERT_TRUE(io->CanReadFile(path.c_str())) << path;
    const ImageType::Pointer image = ReadRegion(path, nullptr, io);
    const auto               size = image->GetLargestPossibleRegion().GetSize();
    const auto               shape = ShapeXyz(store);
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_EQ(static_cast<long>(size[d]), shape[d]) << store["name"] << " axis " << d;
    }
    EXPECT_EQ(Mismatches(store, image), 0u) << store["name"] << " (" << store["dtype"] << ", " << store["codec"]
                                            << ", separator " << store["separator"] << ")";
    if (store["kind"] == "ome")
    {
      EXPECT_TRUE(io->GetHasGeometry());
      for (unsigned d = 0; d < 3; ++d)
      {
        EXPECT_NEAR(image->GetSpacing()[d], 1e-3 * store["scale_um_zyx"][2 - d].get<double>(), 1e-12);
        EXPECT_NEAR(image->GetOrigin()[d], 1e-3 * store["translation_um_zyx"][2 - d].get<double>(), 1e-12);
      }
    }
    else
    {
      EXPECT_FALSE(io->GetHasGeometry());
    }
  }
}

TEST(ZarrImageIO, ARegionReadOpensOnlyTheChunksItOverlaps)
{
  const Json     manifest = Manifest();
  const unsigned seed = vu::RunTimeSeed();
  std::mt19937   random(seed);
  std::cout << "regions drawn with seed " << seed << std::endl;
  for (const Json & store : manifest["stores"])
  {
    if (store["kind"] == "flat")
    {
      continue;
    }
    const std::string path = StoreDirectory() + "/" + store["name"].get<std::string>();
    const auto        shape = ShapeXyz(store);
    for (int trial = 0; trial < 4; ++trial)
    {
      ImageType::RegionType region;
      size_t                expectedChunks = 1;
      for (unsigned d = 0; d < 3; ++d)
      {
        const long first = std::uniform_int_distribution<long>(0, shape[d] - 1)(random);
        const long last = std::uniform_int_distribution<long>(first, shape[d] - 1)(random);
        region.SetIndex(d, first);
        region.SetSize(d, static_cast<itk::SizeValueType>(last - first + 1));
        const long chunk = store["chunks_zyx"][2 - d].get<long>();
        expectedChunks *= static_cast<size_t>(last / chunk - first / chunk + 1);
      }
      auto                     io = itk::ZarrImageIO::New();
      const ImageType::Pointer image = ReadRegion(path, &region, io);
      EXPECT_EQ(image->GetBufferedRegion(), region) << store["name"];
      EXPECT_EQ(io->GetNumberOfChunksRead(), expectedChunks) << store["name"] << " region " << region;
      EXPECT_EQ(Mismatches(store, image), 0u) << store["name"] << " region " << region;
    }
  }
}

TEST(ZarrImageIO, TheFactoryLetsImageFileReaderFindIt)
{
  itk::ObjectFactoryBase::RegisterFactory(itk::ZarrImageIOFactory::New());
  const Json manifest = Manifest();
  for (const Json & store : manifest["stores"])
  {
    if (store["name"] == "ome")
    {
      auto reader = itk::ImageFileReader<ImageType>::New();
      reader->SetFileName(StoreDirectory() + "/ome");
      reader->Update();
      EXPECT_STREQ(reader->GetImageIO()->GetNameOfClass(), "ZarrImageIO");
      EXPECT_EQ(Mismatches(store, reader->GetOutput()), 0u);
    }
  }
}

TEST(ZarrImageIO, CTVolumeReaderReadsZarrWithItsGeometryAndARegionOfInterest)
{
  const Json manifest = Manifest();
  for (const Json & store : manifest["stores"])
  {
    if (store["kind"] == "flat")
    {
      auto reader = itk::CTVolumeReader::New();
      reader->SetFileName(StoreDirectory() + "/flat");
      vu::ExpectRefusal([&] { reader->Update(); }, "not a volume", "a 2D Zarr array was read as a volume");
      continue;
    }
    const auto shape = ShapeXyz(store);
    auto       reader = itk::CTVolumeReader::New();
    reader->SetFileName(StoreDirectory() + "/" + store["name"].get<std::string>());
    itk::CTVolumeReader::RegionType roi;
    for (unsigned d = 0; d < 3; ++d)
    {
      roi.SetIndex(d, shape[d] / 3);
      roi.SetSize(d, static_cast<itk::SizeValueType>(std::max(1L, shape[d] / 2)));
    }
    reader->SetRegionOfInterest(roi);
    reader->UseRegionOfInterestOn();
    reader->Update();
    const bool ome = store["kind"] == "ome";
    EXPECT_EQ(std::string(reader->GetInputKind()), ome ? "OME-Zarr image" : "Zarr array");
    bool warned = false;
    for (const std::string & w : reader->GetWarnings())
    {
      warned = warned || w.find("no voxel size") != std::string::npos;
    }
    EXPECT_EQ(warned, !ome) << store["name"];
    // The region of interest is indexed from 0: voxel i holds the store's voxel roi + i.
    const auto * image = reader->GetOutput();
    EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(), roi.GetSize());
    const size_t bad = vu::CountVoxelsNotHolding(image, [&](auto value, const auto & i) {
      const double expected = Expected(store, i[0] + roi.GetIndex(0), i[1] + roi.GetIndex(1), i[2] + roi.GetIndex(2));
      return !(std::abs(value - expected) > 1e-5 * std::max(1.0, std::abs(expected)));
    });
    EXPECT_EQ(bad, 0u) << store["name"];
    if (ome)
    {
      EXPECT_NEAR(image->GetSpacing()[0], 1e-3 * store["scale_um_zyx"][2].get<double>(), 1e-9);
    }
  }
}

TEST(ZarrImageIO, DamagedOrUnsupportedStoresAreRefusedWithTheReason)
{
  const Json manifest = Manifest();
  // A compressed store whose first chunk file is cut short, and a big-endian copy.
  const Json * compressed = nullptr;
  for (const Json & store : manifest["stores"])
  {
    if (compressed == nullptr && store["kind"] == "array" && store["codec"] != "none" && store["separator"] == ".")
    {
      compressed = &store;
    }
  }
  ASSERT_NE(compressed, nullptr) << "no compressed store with '.' separators was drawn";
  const fs::path source = fs::path(StoreDirectory()) / (*compressed)["name"].get<std::string>();
  const fs::path damaged = fs::path(StoreDirectory()) / "damaged";
  fs::remove_all(damaged);
  fs::copy(source, damaged, fs::copy_options::recursive);
  fs::path chunk;
  for (const auto & entry : fs::directory_iterator(damaged))
  {
    if (entry.path().filename().string()[0] != '.')
    {
      chunk = entry.path();
      break;
    }
  }
  ASSERT_FALSE(chunk.empty());
  fs::resize_file(chunk, fs::file_size(chunk) / 2);
  auto io = itk::ZarrImageIO::New();
  vu::ExpectRefusal(
    [&] { ReadRegion(damaged.string(), nullptr, io); }, chunk.filename().string(), "a truncated chunk was read");

  fs::resize_file(chunk, 0);
  fs::remove(chunk);
  std::ifstream in(damaged / ".zarray");
  Json          meta = Json::parse(in);
  in.close();
  std::string dtype = meta["dtype"];
  dtype[0] = '>';
  meta["dtype"] = dtype == ">u1" || dtype == ">i1" ? ">u2" : dtype;
  std::ofstream(damaged / ".zarray") << meta.dump();
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(damaged.string());
  vu::ExpectRefusal([&] { reader->Update(); }, "little-endian", "a big-endian store was read");
  fs::remove_all(damaged);
}

namespace {
// The value written at (x, y, z) in the written-store test, for a given salt.
double
WrittenValue(long x, long y, long z, int salt)
{
  return static_cast<double>((7 * x + 13 * y + 29 * z + salt) % 3000);
}

template <typename TPixel>
Json
WriteStore(const std::string & name, bool compressed, std::mt19937 & random)
{
  using WrittenType = itk::Image<TPixel, 3>;
  auto image = WrittenType::New();
  auto draw = [&](long low, long high) { return std::uniform_int_distribution<long>(low, high)(random); };
  typename WrittenType::SizeType    size;
  typename WrittenType::SpacingType spacing;
  typename WrittenType::PointType   origin;
  for (unsigned d = 0; d < 3; ++d)
  {
    size[d] = static_cast<itk::SizeValueType>(draw(5, 40));
    spacing[d] = 0.001 * static_cast<double>(draw(5, 400));
    origin[d] = 0.01 * static_cast<double>(draw(-5000, 5000));
  }
  image->SetRegions(size);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->Allocate();
  const int salt = static_cast<int>(draw(0, 1000));
  for (itk::ImageRegionIteratorWithIndex<WrittenType> it(image, image->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    const auto i = it.GetIndex();
    it.Set(static_cast<TPixel>(WrittenValue(i[0], i[1], i[2], salt)));
  }
  auto io = itk::ZarrImageIO::New();
  io->SetChunkEdge(static_cast<unsigned>(draw(3, 16)));
  // Through a filter that computes only the region asked of it, so that the writer streams
  // (given a whole image it writes it at once).
  auto pass = itk::CastImageFilter<WrittenType, WrittenType>::New();
  pass->SetInput(image);
  auto writer = itk::ImageFileWriter<WrittenType>::New();
  writer->SetInput(pass->GetOutput());
  writer->SetImageIO(io);
  size_t progress = 0;
  auto   count = itk::CStyleCommand::New();
  count->SetClientData(&progress);
  count->SetCallback([](itk::Object *, const itk::EventObject &, void * data) { ++*static_cast<size_t *>(data); });
  writer->AddObserver(itk::ProgressEvent(), count);
  writer->SetFileName(StoreDirectory() + "/" + name);
  writer->SetUseCompression(compressed);
  // Regions one after the other: chunks cut by a region's edge are merged.
  writer->SetNumberOfStreamDivisions(static_cast<unsigned>(draw(1, 5)));
  writer->Update();
  // One progress event before the first region and one after each (the splitter makes
  // fewer regions than asked when the image is thin along the axis it splits).
  itk::ImageIORegion whole(3);
  for (unsigned int d = 0; d < 3; ++d)
  {
    whole.SetIndex(d, 0);
    whole.SetSize(d, size[d]);
  }
  EXPECT_EQ(progress, io->GetActualNumberOfSplitsForWriting(writer->GetNumberOfStreamDivisions(), whole, whole) + 1)
    << name;
  return { { "name", name },
           { "salt", salt },
           { "size_xyz", { size[0], size[1], size[2] } },
           { "spacing_xyz", { spacing[0], spacing[1], spacing[2] } },
           { "origin_xyz", { origin[0], origin[1], origin[2] } },
           { "chunk_edge", io->GetChunkEdge() },
           { "compressed", compressed },
           { "streams", writer->GetNumberOfStreamDivisions() } };
}
} // namespace

TEST(ZarrImageIO, WrittenStoresReadBackVoxelByVoxelWithTheirGeometry)
{
  const unsigned seed = vu::RunTimeSeed();
  std::mt19937   random(seed);
  std::cout << "written stores drawn with seed " << seed << std::endl;
  fs::create_directories(StoreDirectory());
  Json written = Json::array();
  written.push_back(WriteStore<uint16_t>("written-u16.zarr", true, random));
  written.push_back(WriteStore<float>("written-f32.zarr", false, random));
  written.push_back(WriteStore<int16_t>("written-i16.zarr", true, random));
  for (const Json & store : written)
  {
    const std::string path = StoreDirectory() + "/" + store["name"].get<std::string>();
    auto              io = itk::ZarrImageIO::New();
    ASSERT_TRUE(io->CanReadFile(path.c_str())) << path;
    const ImageType::Pointer image = ReadRegion(path, nullptr, io);
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_EQ(image->GetLargestPossibleRegion().GetSize(d), store["size_xyz"][d].get<itk::SizeValueType>());
      EXPECT_NEAR(image->GetSpacing()[d], store["spacing_xyz"][d].get<double>(), 1e-12);
      EXPECT_NEAR(image->GetOrigin()[d], store["origin_xyz"][d].get<double>(), 1e-12);
    }
    size_t bad = 0;
    for (itk::ImageRegionConstIteratorWithIndex<ImageType> it(image, image->GetBufferedRegion()); !it.IsAtEnd(); ++it)
    {
      const auto i = it.GetIndex();
      bad += it.Get() != WrittenValue(i[0], i[1], i[2], store["salt"].get<int>()) ? 1 : 0;
    }
    EXPECT_EQ(bad, 0u) << store.dump();
  }
  // For test/zarr_check_written.py: python3-zarr reads them too.
  std::ofstream(StoreDirectory() + "/written.json") << written.dump(1);

  // The same image again with another origin and spacing: the store's geometry follows.
  {
    fs::remove_all(StoreDirectory() + "/again.zarr");
    auto again = ImageType::New();
    again->SetRegions(ImageType::SizeType{ { 6, 5, 4 } });
    again->Allocate(true);
    auto rewrite = itk::ImageFileWriter<ImageType>::New();
    rewrite->SetInput(again);
    rewrite->SetImageIO(itk::ZarrImageIO::New());
    rewrite->SetFileName(StoreDirectory() + "/again.zarr");
    rewrite->Update();
    again->SetOrigin(ImageType::PointType{ { { 1.5, -2.0, 3.0 } } });
    again->SetSpacing(vu::Triple<ImageType::SpacingType>(0.5, 0.25, 2.0));
    rewrite->Modified();
    rewrite->Update();
    auto                     io = itk::ZarrImageIO::New();
    const ImageType::Pointer back = ReadRegion(StoreDirectory() + "/again.zarr", nullptr, io);
    EXPECT_EQ(back->GetOrigin(), again->GetOrigin());
    EXPECT_EQ(back->GetSpacing(), again->GetSpacing());
  }

  // A path that is not a Zarr store is never overwritten; a rotated image is refused.
  const std::string occupied = StoreDirectory() + "/occupied.zarr";
  std::ofstream(occupied) << "not a store\n";
  auto image = ImageType::New();
  image->SetRegions(ImageType::SizeType{ { 4, 4, 4 } });
  image->Allocate(true);
  auto writer = itk::ImageFileWriter<ImageType>::New();
  writer->SetInput(image);
  writer->SetImageIO(itk::ZarrImageIO::New());
  writer->SetFileName(occupied);
  EXPECT_THROW(writer->Update(), itk::ExceptionObject);
  std::ifstream kept(occupied);
  std::string   line;
  std::getline(kept, line);
  EXPECT_EQ(line, "not a store");
  ImageType::DirectionType rotated;
  rotated.Fill(0.0);
  rotated[0][1] = rotated[1][0] = rotated[2][2] = 1.0;
  image->SetDirection(rotated);
  writer->SetFileName(StoreDirectory() + "/rotated.zarr");
  EXPECT_THROW(writer->Update(), itk::ExceptionObject);
}

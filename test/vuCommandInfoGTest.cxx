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
// The info subcommand run as a user runs it: JSON on success, one line on standard
// error and a non-zero exit status on failure.
#include "itkCTVolumeReader.h"
#include "itkImageFileWriter.h"
#include "itkStatisticsImageFilter.h"

#include "gtest/gtest.h"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <sys/wait.h>

namespace {
namespace fs = std::filesystem;

const std::string kPhilips = std::string(VU_TEST_DATA_DIR) + "/dicom/philips_ct/S2010";

struct ToolRun
{
  int         Status{ -1 };
  std::string Out;
  std::string Err;
};

std::string
Slurp(const std::string & file)
{
  std::ifstream     in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string
WorkDirectory()
{
  const auto *   info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path directory = fs::path(VU_BINARY_DIR) / "Testing" / "Temporary" / "vuCommandInfo" / info->name();
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory.string();
}

ToolRun
Tool(const std::string & subcommandAndArguments, const std::string & directory)
{
  const std::string out = directory + "/stdout.txt", err = directory + "/stderr.txt";
  const std::string command =
    std::string(VU_BINARY_DIR) + "/bin/virtual-unwrap " + subcommandAndArguments + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(command.c_str());
  ToolRun   run;
  run.Status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.Out = Slurp(out);
  run.Err = Slurp(err);
  return run;
}

ToolRun
Info(const std::string & arguments, const std::string & directory)
{
  return Tool("info " + arguments, directory);
}

void
ExpectOneLineError(const ToolRun & run, const std::string & part)
{
  EXPECT_NE(run.Status, 0);
  EXPECT_TRUE(run.Out.empty()) << run.Out;
  EXPECT_EQ(run.Err.rfind("virtual-unwrap: error: ", 0), 0u) << run.Err;
  EXPECT_EQ(std::count(run.Err.begin(), run.Err.end(), '\n'), 1) << run.Err;
  EXPECT_NE(run.Err.find(part), std::string::npos) << run.Err;
}
} // namespace

TEST(vuCommandInfo, PhilipsSeriesWithStatistics)
{
  const std::string directory = WorkDirectory();
  const ToolRun     run = Info("'" + kPhilips + "' --stats -o '" + directory + "/info.json'", directory);
  ASSERT_EQ(run.Status, 0) << run.Err;
  EXPECT_TRUE(run.Err.empty()) << run.Err;
  const nlohmann::json json = nlohmann::json::parse(Slurp(directory + "/info.json"));
  EXPECT_EQ(json["size"], nlohmann::json({ 512, 512, 28 }));
  EXPECT_NEAR(json["spacing"][0].get<double>(), 0.451171875, 1e-9);
  EXPECT_NEAR(json["spacing"][2].get<double>(), 5.0, 1e-9);
  EXPECT_NEAR(json["origin"][2].get<double>(), 696.21, 1e-9);
  EXPECT_EQ(json["direction"], nlohmann::json({ { 1.0, 0.0, 0.0 }, { 0.0, 1.0, 0.0 }, { 0.0, 0.0, 1.0 } }));
  EXPECT_EQ(json["pixel_type"], "uint16");
  EXPECT_EQ(json["modality"], "CT");
  EXPECT_EQ(json["series"]["chosen"]["number"], "201");
  EXPECT_EQ(json["series"]["chosen"]["slices"], 28);
  EXPECT_EQ(json["series"]["chosen"]["description"], "STD BRAIN 5MM");
  EXPECT_TRUE(json["series"]["alternatives"].empty());
  EXPECT_EQ(json["rescale"]["slope"], 1.0);
  EXPECT_EQ(json["rescale"]["intercept"], -1024.0);
  EXPECT_TRUE(json["warnings"].empty());

  // The streamed statistics of the tool equal those of the volume read whole.
  auto reader = itk::CTVolumeReader::New();
  reader->SetFileName(kPhilips);
  auto statistics = itk::StatisticsImageFilter<itk::CTVolumeReader::OutputImageType>::New();
  statistics->SetInput(reader->GetOutput());
  statistics->Update();
  EXPECT_EQ(json["stats"]["min"].get<double>(), statistics->GetMinimum());
  EXPECT_EQ(json["stats"]["max"].get<double>(), statistics->GetMaximum());
  EXPECT_NEAR(json["stats"]["mean"].get<double>(), statistics->GetMean(), 1e-6);
}

TEST(vuCommandInfo, RegionOfInterestAndShrinking)
{
  const std::string directory = WorkDirectory();
  const ToolRun     run = Info("'" + kPhilips + "' --roi 100 120 5 200 150 10 --shrink 2", directory);
  ASSERT_EQ(run.Status, 0) << run.Err;
  const nlohmann::json json = nlohmann::json::parse(run.Out);
  EXPECT_EQ(json["size"], nlohmann::json({ 100, 75, 5 }));
  EXPECT_EQ(json["full_size"], nlohmann::json({ 512, 512, 28 }));
  EXPECT_NEAR(json["spacing"][2].get<double>(), 10.0, 1e-9);
  EXPECT_FALSE(json.contains("stats"));

  // Physical corners: x and y beyond the volume (clipped, with a warning), z 700..712 mm
  // holds the slices at 701.21, 706.21 and 711.21 mm.
  const ToolRun physical = Info("'" + kPhilips + "' --roi-mm -1000 -1000 700 1000 1000 712", directory);
  ASSERT_EQ(physical.Status, 0) << physical.Err;
  const nlohmann::json clipped = nlohmann::json::parse(physical.Out);
  EXPECT_EQ(clipped["size"], nlohmann::json({ 512, 512, 3 }));
  EXPECT_NEAR(clipped["origin"][2].get<double>(), 701.21, 1e-9);
  EXPECT_EQ(clipped["warnings"].size(), 1u);
}

TEST(vuCommandInfo, TiffStackWithSpacing)
{
  const std::string directory = WorkDirectory();
  using SliceType = itk::Image<unsigned short, 2>;
  for (unsigned z = 0; z < 4; ++z)
  {
    auto slice = SliceType::New();
    slice->SetRegions(SliceType::SizeType{ { 8, 6 } });
    slice->Allocate();
    slice->FillBuffer(static_cast<unsigned short>(100 * z));
    itk::WriteImage(slice, directory + "/scan_" + std::to_string(z) + ".tiff");
  }
  const ToolRun run = Info("'" + directory + "/scan_*.tiff' --spacing 0.01 0.01 0.02 --stats", directory);
  ASSERT_EQ(run.Status, 0) << run.Err;
  const nlohmann::json json = nlohmann::json::parse(run.Out);
  EXPECT_EQ(json["size"], nlohmann::json({ 8, 6, 4 }));
  EXPECT_EQ(json["spacing"], nlohmann::json({ 0.01, 0.01, 0.02 }));
  EXPECT_EQ(json["pixel_type"], "uint16");
  EXPECT_TRUE(json["modality"].is_null());
  EXPECT_TRUE(json["series"]["chosen"].is_null());
  EXPECT_TRUE(json["warnings"].empty());
  EXPECT_EQ(json["stats"]["min"], 0.0);
  EXPECT_EQ(json["stats"]["max"], 300.0);
  EXPECT_EQ(json["stats"]["mean"], 150.0);
}

TEST(vuCommandInfo, BadInputGivesOneLineAndNonZeroStatus)
{
  const std::string directory = WorkDirectory();
  ExpectOneLineError(Info("'" + directory + "/missing'", directory), "no such file or directory: " + directory);
  ExpectOneLineError(Info("'" + kPhilips + "' --spacing 1 -1 1", directory), "--spacing");
  ExpectOneLineError(Info("'" + kPhilips + "' --roi 0 0 20 10 10 10", directory), "not inside the volume");
  ExpectOneLineError(Info("'" + kPhilips + "' --series 77", directory), "no series '77'");
  ExpectOneLineError(Info("'" + kPhilips + "/I10'", directory), "single 2D image");
  const ToolRun failed = Info("'" + directory + "/missing' -o '" + directory + "/out.json'", directory);
  EXPECT_NE(failed.Status, 0);
  EXPECT_FALSE(fs::exists(directory + "/out.json"));
}

// Meshes and volumes that parse but hold nothing usable are refused as bad input, by
// name, before any simulation or segmentation runs; nothing is written.
TEST(vuCommandInfo, EmptyMeshNaNVertexAndNaNVolumeAreNamed)
{
  const std::string directory = WorkDirectory();
  const std::string emptyObj = directory + "/empty.obj", nanObj = directory + "/nan_vertex.obj";
  std::ofstream(emptyObj).close();
  std::ofstream(nanObj) << "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
  const std::string flat = directory + "/flat.obj";
  // Progress lines go to standard error: the refusal is its last line.
  auto lastLine = [](std::string text) {
    while (!text.empty() && text.back() == '\n')
    {
      text.pop_back();
    }
    return text.substr(text.rfind('\n') + 1); // npos + 1 == 0: the whole text
  };
  ToolRun run = Tool("flatten '" + emptyObj + "' -o '" + flat + "'", directory);
  EXPECT_EQ(run.Status, 1);
  EXPECT_NE(lastLine(run.Err).find("no points"), std::string::npos) << run.Err;
  EXPECT_FALSE(fs::exists(flat));
  EXPECT_EQ(fs::file_size(emptyObj), 0u);

  run = Tool("flatten '" + nanObj + "' -o '" + flat + "'", directory);
  EXPECT_EQ(run.Status, 1);
  EXPECT_NE(lastLine(run.Err).find(":3: vertex 3 has a non-finite coordinate"), std::string::npos) << run.Err;
  EXPECT_FALSE(fs::exists(flat));

  using ImageType = itk::Image<float, 3>;
  auto                  volume = ImageType::New();
  ImageType::RegionType region;
  region.SetSize({ { 12, 12, 12 } });
  volume->SetRegions(region);
  volume->Allocate();
  volume->FillBuffer(std::numeric_limits<float>::quiet_NaN());
  const std::string nanVolume = directory + "/nan.mha";
  itk::WriteImage(volume, nanVolume);
  for (const std::string command : { "unwrap", "segment" })
  {
    const std::string out = directory + "/" + command + "-out";
    run = Tool(command + " '" + nanVolume + "' -o '" + out + "'", directory);
    EXPECT_EQ(run.Status, 1) << command;
    EXPECT_NE(lastLine(run.Err).find("no finite voxel (all 1728 are NaN)"), std::string::npos) << run.Err;
    EXPECT_FALSE(fs::exists(out)) << command;
  }
}

// A hospital head CT series (18.5 degree tilt, 4 then 7 mm): info reads it,
// resampled, and says what it found and did, with positions; --no-resample refuses it,
// naming the tilt and the spacing change; statistics leave out the voxels without data.
TEST(vuCommandInfo, TiltedUnevenSeriesIsResampledAndExplained)
{
  const std::string directory = WorkDirectory();
  const std::string series = std::string(VU_TEST_DATA_DIR) + "/dicom/tilted_ct/gantry18_4to7";
  const ToolRun     run = Info("'" + series + "' --stats", directory);
  ASSERT_EQ(run.Status, 0) << run.Err;
  EXPECT_TRUE(run.Err.empty()) << run.Err;
  const nlohmann::json json = nlohmann::json::parse(run.Out);
  EXPECT_EQ(json["size"], nlohmann::json({ 64, 78, 38 }));
  const nlohmann::json & corrections = json["geometry_corrections"];
  EXPECT_TRUE(corrections["sheared"].get<bool>());
  EXPECT_NEAR(corrections["tilt_deg"].get<double>(), 18.5, 1e-3);
  ASSERT_EQ(corrections["spacing_runs"].size(), 2u);
  EXPECT_NEAR(corrections["spacing_runs"][1]["spacing_mm"].get<double>(), 7.0, 1e-3);
  EXPECT_NEAR(corrections["spacing_runs"][1]["from"]["location_mm"].get<double>(), 748.21, 1e-3);
  EXPECT_EQ(corrections["resampled"]["interpolator"], "bspline");
  const auto without = corrections["resampled"]["voxels_without_data"].get<long>();
  EXPECT_GT(without, 0);
  EXPECT_EQ(json["stats"]["voxels_without_data"].get<long>(), without);
  EXPECT_TRUE(json["stats"]["mean"].is_number());
  ASSERT_EQ(json["warnings"].size(), 3u);
  EXPECT_NE(json["warnings"][0].get<std::string>().find("sheared slice stack"), std::string::npos);
  EXPECT_NE(json["warnings"][1].get<std::string>().find("uneven slice spacing: 4 mm from 696.2 mm"), std::string::npos);

  ExpectOneLineError(Info("'" + series + "' --no-resample", directory), "non-uniform slice spacing: 4 mm from");
  ExpectOneLineError(Info("'" + series + "' --no-resample", directory), "sheared slice stack");
  // Option values are checked by the command-line parser, which says so in its own words.
  const ToolRun unknown = Info("'" + series + "' --interpolator cubic", directory);
  EXPECT_NE(unknown.Status, 0);
  EXPECT_NE(unknown.Err.find("--interpolator: cubic not in {nearest,linear,bspline}"), std::string::npos)
    << unknown.Err;
}

// A regular series has nothing to correct.
TEST(vuCommandInfo, RegularSeriesHasNoGeometryCorrections)
{
  const std::string directory = WorkDirectory();
  const ToolRun     run = Info("'" + kPhilips + "'", directory);
  ASSERT_EQ(run.Status, 0) << run.Err;
  EXPECT_TRUE(nlohmann::json::parse(run.Out)["geometry_corrections"].is_null());
}

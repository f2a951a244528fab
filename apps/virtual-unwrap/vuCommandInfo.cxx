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
// virtual-unwrap info PATH: what the CT reader makes of an input, as JSON.
#include "vuCommands.h"
#include "vuReaderOptions.h"

#include "itkBinaryThresholdImageFilter.h"
#include "itkCTVolumeReader.h"
#include "itkLabelStatisticsImageFilter.h"

namespace vu {
namespace {
nlohmann::json
SeriesJson(const itk::CTVolumeReader::SeriesInfo & series)
{
  return { { "uid", series.UID },
           { "number", series.Number },
           { "description", series.Description },
           { "modality", series.Modality },
           { "slices", series.NumberOfSlices } };
}
} // namespace

void
RegisterInfoCommand(CLI::App & app)
{
  auto * command = app.add_subcommand(
    "info",
    "Read a CT volume (DICOM directory or file, TIFF stack or glob, NRRD, MetaImage, NIfTI, multi-page TIFF) "
    "and print its geometry, calibration, series and warnings as JSON; nothing is written.");
  static std::string   path, outputPath;
  static bool          stats = false;
  static ReaderOptions options;
  command->add_option("PATH", path, "DICOM directory or file, directory or glob of 2D slices, or a volume file")
    ->required();
  command->add_flag(
    "--stats", stats, "also compute min, max and mean of the calibrated values, reading one slice at a time");
  command->add_option("-o,--output", outputPath, "write the JSON to this file instead of standard output");
  AddReaderOptions(*command, options);
  command->callback([] {
    auto reader = itk::CTVolumeReader::New();
    ConfigureReader(options, path, *reader);
    reader->VerifyCompressedDataOn();
    reader->UpdateOutputInformation();
    const itk::CTVolumeReader::OutputImageType * image = reader->GetOutput();

    nlohmann::json json;
    const auto     size = image->GetLargestPossibleRegion().GetSize();
    json["size"] = { size[0], size[1], size[2] };
    json["full_size"] = { reader->GetFullSize()[0], reader->GetFullSize()[1], reader->GetFullSize()[2] };
    json["spacing"] = { image->GetSpacing()[0], image->GetSpacing()[1], image->GetSpacing()[2] };
    json["origin"] = { image->GetOrigin()[0], image->GetOrigin()[1], image->GetOrigin()[2] };
    json["direction"] = nlohmann::json::array();
    for (unsigned r = 0; r < 3; ++r)
    {
      json["direction"].push_back(
        { image->GetDirection()[r][0], image->GetDirection()[r][1], image->GetDirection()[r][2] });
    }
    json["input"] = reader->GetInputKind();
    json["files"] = reader->GetSliceFileNames().size();
    json["pixel_type"] = reader->GetPixelType();
    json["modality"] =
      std::string(reader->GetModality()).empty() ? nlohmann::json() : nlohmann::json(reader->GetModality());
    json["series"]["chosen"] =
      reader->GetChosenSeries().UID.empty() ? nlohmann::json() : SeriesJson(reader->GetChosenSeries());
    json["series"]["alternatives"] = nlohmann::json::array();
    for (const auto & s : reader->GetAlternativeSeries())
    {
      json["series"]["alternatives"].push_back(SeriesJson(s));
    }
    json["rescale"] = { { "slope", reader->GetRescaleSlope() }, { "intercept", reader->GetRescaleIntercept() } };
    json["warnings"] = reader->GetWarnings();
    json["geometry_corrections"] = GeometryCorrectionsJson(*reader);

    if (stats)
    {
      // One slice per stream division: the whole volume never has to fit in memory.
      // Voxels without data (NaN in a resampled series) are counted, not summed.
      using ImageType = itk::CTVolumeReader::OutputImageType;
      using LabelType = itk::Image<unsigned char, 3>;
      auto hasData = itk::BinaryThresholdImageFilter<ImageType, LabelType>::New();
      hasData->SetInput(reader->GetOutput());
      hasData->SetLowerThreshold(itk::NumericTraits<float>::NonpositiveMin());
      hasData->SetUpperThreshold(itk::NumericTraits<float>::max());
      hasData->SetInsideValue(1);
      hasData->SetOutsideValue(0);
      auto statistics = itk::LabelStatisticsImageFilter<ImageType, LabelType>::New();
      statistics->SetInput(reader->GetOutput());
      statistics->SetLabelInput(hasData->GetOutput());
      statistics->SetNumberOfStreamDivisions(static_cast<unsigned>(size[2]));
      statistics->Update();
      const bool any = statistics->HasLabel(1);
      json["stats"] = { { "min", any ? nlohmann::json(statistics->GetMinimum(1)) : nlohmann::json() },
                        { "max", any ? nlohmann::json(statistics->GetMaximum(1)) : nlohmann::json() },
                        { "mean", any ? nlohmann::json(statistics->GetMean(1)) : nlohmann::json() },
                        { "voxels_without_data", statistics->HasLabel(0) ? statistics->GetCount(0) : 0 } };
    }
    EmitJson(json, outputPath);
  });
}
} // namespace vu

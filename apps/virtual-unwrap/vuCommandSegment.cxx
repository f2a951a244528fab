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
// virtual-unwrap segment VOLUME -o DIR: sheet mask, mid-surface mesh and a JSON summary.
#include "vuCommands.h"
#include "vuReaderOptions.h"
#include "vuSheetsJson.h"

#include "itkCTVolumeReader.h"

#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkMesh.h"
#include "itkMeshFileWriter.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSheetSegmentationImageFilter.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

namespace vu {
namespace {
struct SegmentOptions
{
  std::string   Volume;
  std::string   Output;
  std::string   Threshold{ "auto" };
  std::string   MeshSpacing{ "auto" };
  std::string   Method{ "auto" };
  double        ChordError{ 0.1 };
  unsigned long MinimumComponent{ 100 };
  unsigned int  Closing{ 0 };
  bool          EverySheet{ false };
  std::string   MinimumSheetArea{ "auto" };
  ReaderOptions Reader;
};

} // namespace

bool
ParseAutoOrNumber(const std::string & text, const std::string & option, double & value)
{
  if (text == "auto")
  {
    return false;
  }
  size_t used = 0;
  try
  {
    value = std::stod(text, &used);
  }
  catch (const std::exception &)
  {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value))
  {
    throw UsageError(option + " must be a number or auto, not '" + text + "'");
  }
  return true;
}


bool
ParseMeshSpacing(const std::string & text, double spacing[2])
{
  if (text == "auto")
  {
    return false;
  }
  const auto comma = text.find(',');
  ParseAutoOrNumber(text.substr(0, comma), "--mesh-spacing", spacing[0]);
  spacing[1] = spacing[0];
  if (comma != std::string::npos)
  {
    ParseAutoOrNumber(text.substr(comma + 1), "--mesh-spacing", spacing[1]);
  }
  if (!(spacing[0] > 0.0) || !(spacing[1] > 0.0))
  {
    throw UsageError("--mesh-spacing must be positive");
  }
  return true;
}

namespace {
void
RunSegment(const SegmentOptions & options)
{
  using VolumeType = itk::Image<float, 3>;
  using MaskType = itk::Image<unsigned char, 3>;
  using MeshType = itk::Mesh<float, 3>;
  double     threshold = 0.0, spacing[2] = { 0.0, 0.0 };
  const bool fixedThreshold = ParseAutoOrNumber(options.Threshold, "--threshold", threshold);
  ParseMeshSpacing(options.MeshSpacing, spacing);
  const itk::SheetSurfaceMethodEnum method = itk::SheetSurfaceMethodFromString(options.Method);
  const auto                        start = std::chrono::steady_clock::now();

  // The CT reader with unwrap's options (spacing, region, series, geometry corrections):
  // headers checked before ITK's readers see them; voxels without data filled as unwrap
  // fills them for segmentation and meshing.
  auto reader = itk::CTVolumeReader::New();
  ConfigureReader(options.Reader, options.Volume, *reader);
  reader->Update();
  const FilledVolume filled = FillVoxelsWithoutData(reader->GetOutput());
  auto               segmentation = itk::SheetSegmentationImageFilter<VolumeType, MaskType>::New();
  segmentation->SetInput(filled.Volume);
  segmentation->SetAutomaticThreshold(!fixedThreshold);
  segmentation->SetThreshold(threshold);
  segmentation->SetMinimumComponentSize(options.MinimumComponent);
  segmentation->SetClosingRadius(options.Closing);
  auto surface = itk::SheetMidSurfaceMeshFilter<MaskType, MeshType>::New();
  surface->SetInput(segmentation->GetOutput());
  surface->SetIntensityImage(filled.Volume);
  surface->SetMethod(method);
  surface->SetSpacingAlongSheet(spacing[0]);
  surface->SetSpacingAlongAxis(spacing[1]);
  surface->SetChordErrorFraction(options.ChordError);
  double minimumArea = 0.0;
  if (ParseAutoOrNumber(options.MinimumSheetArea, "--minimum-sheet-area", minimumArea) && !(minimumArea > 0.0))
  {
    throw UsageError("--minimum-sheet-area must be auto or an area in mm^2 above 0");
  }
  surface->SetEverySheet(options.EverySheet);
  surface->SetMinimumSheetArea(minimumArea);
  surface->Update();
  const unsigned int sheets = surface->GetNumberOfSheets();
  const double       seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Everything is written into a staging folder beside the output, moved into place at the
  // end: an error or a kill leaves the output as it was.
  OutputStaging               staging(options.Output, OutputStaging::Kind::Folder);
  const std::filesystem::path directory = staging.Path();
  const auto                  maskSize = segmentation->GetOutput()->GetLargestPossibleRegion().GetNumberOfPixels();
  // The mask (compressed, at most its raw size) and two text meshes of ~40 bytes a point
  // and ~30 a triangle.
  staging.RequireSpace(
    maskSize +
    2 * (40 * surface->GetSheetMesh().GetNumberOfPoints() + 30 * surface->GetSheetMesh().GetNumberOfTriangles()) +
    (1u << 20));
  auto maskWriter = itk::ImageFileWriter<MaskType>::New();
  maskWriter->SetInput(segmentation->GetOutput());
  maskWriter->SetFileName((directory / "mask.mha").string());
  maskWriter->UseCompressionOn();
  maskWriter->Update();
  // One sheet: its mesh in the output folder; several: a folder sheet-NN for each, and the
  // sheet of every voxel of the mask.
  for (unsigned int i = 0; i < sheets; ++i)
  {
    char name[24]; // "sheet-" and up to ten digits
    std::snprintf(name, sizeof(name), "sheet-%02u", i + 1);
    const std::filesystem::path folder = sheets > 1 ? directory / name : directory;
    std::filesystem::create_directories(folder);
    for (const char * file : { "surface.obj", "surface.vtk" })
    {
      auto meshWriter = itk::MeshFileWriter<MeshType>::New();
      meshWriter->SetInput(surface->GetSheetOutput(i));
      meshWriter->SetFileName((folder / file).string());
      meshWriter->Update();
    }
  }
  if (sheets > 1)
  {
    auto labelWriter = itk::ImageFileWriter<itk::Image<uint16_t, 3>>::New();
    labelWriter->SetInput(surface->GetSheetLabelImage());
    labelWriter->SetFileName((directory / "sheets.mha").string());
    labelWriter->UseCompressionOn();
    labelWriter->Update();
  }

  const itk::SheetMesh &             mesh = surface->GetSheetMesh();
  const itk::SheetMidSurfaceReport & report = surface->GetReport();
  nlohmann::json                     json;
  json["volume"] = options.Volume;
  json["geometry_corrections"] = GeometryCorrectionsJson(*reader);
  json["voxels_without_data"] = filled.Filled;
  json["threshold"] = { { "value", segmentation->GetThreshold() }, { "automatic", !fixedThreshold } };
  json["components_kept"] = segmentation->GetNumberOfComponents();
  json["method"] = itk::ToString(report.Method);
  json["points"] = mesh.GetNumberOfPoints();
  json["triangles"] = mesh.GetNumberOfTriangles();
  json["grid"] = { { "rows", mesh.GridRows }, { "columns", mesh.GridColumns } };
  json["mesh_spacing_mm"] = { { "along_sheet", report.SpacingAlongSheet }, { "along_axis", report.SpacingAlongAxis } };
  json["sheet_thickness_mm"] = report.SheetThickness;
  json["traced_share"] = report.TracedShare;
  json["sheet_length_mm"] = report.SheetLength;
  json["minimum_curvature_radius_mm"] = report.MinimumCurvatureRadius;
  json["interpolated_slices"] = report.InterpolatedSlices;
  json["trace"] = TraceJson(report);
  json["warnings"] = report.Warnings;
  json["conventions"] = "rows along the roll axis (w, slice order), columns along the sheet (s) from its inner end; "
                        "point (row r, column c) at index r * columns + c; roll: normals towards the roll axis, "
                        "general: normals dP/dw x dP/ds";
  json["seconds"] = seconds;
  if (options.EverySheet)
  {
    json["sheets"] = nlohmann::json::array();
    for (unsigned int i = 0; i < sheets; ++i)
    {
      json["sheets"].push_back(SheetEntryJson(*surface, i));
    }
    json["dropped"] = DroppedJson(*surface);
  }
  EmitJson(json, (directory / "segment.json").string());
  RemoveOtherLayout(options.Output, sheets > 1, { "surface.obj", "surface.vtk" });
  if (sheets <= 1)
  {
    std::error_code error;
    std::filesystem::remove(std::filesystem::path(options.Output) / "sheets.mha", error);
  }
  staging.Commit();
  std::cout << "segment: " << itk::ToString(report.Method) << ", threshold " << segmentation->GetThreshold() << ", "
            << mesh.GetNumberOfPoints() << " points, " << mesh.GetNumberOfTriangles() << " triangles -> "
            << options.Output << std::endl;
  for (const std::string & warning : report.Warnings)
  {
    std::cerr << "virtual-unwrap: warning: " << warning << std::endl;
  }
}
} // namespace

nlohmann::json
TraceJson(const itk::SheetMidSurfaceReport & report)
{
  // Confidence below which a run of slices is named.
  constexpr double lowConfidence = 0.8;
  nlohmann::json   regions = nlohmann::json::array(), jumps = nlohmann::json::array();
  double           sum = 0.0;
  size_t           count = 0;
  const auto &     confidence = report.SliceConfidence;
  for (size_t k = 0; k < confidence.size(); ++k)
  {
    if (confidence[k] < 0.0)
    {
      continue;
    }
    sum += confidence[k];
    ++count;
    if (confidence[k] >= lowConfidence)
    {
      continue;
    }
    size_t last = k;
    double lowest = confidence[k];
    while (last + 1 < confidence.size() && confidence[last + 1] >= 0.0 && confidence[last + 1] < lowConfidence)
    {
      lowest = std::min(lowest, confidence[++last]);
      sum += confidence[last];
      ++count;
    }
    regions.push_back({ { "first_slice", k }, { "last_slice", last }, { "lowest_confidence", lowest } });
    k = last;
  }
  for (const auto & jump : report.LayerJumps)
  {
    jumps.push_back({ { "slice", jump.Slice }, { "turn", jump.Turn } });
  }
  nlohmann::json steps = nlohmann::json::array();
  for (const auto & step : report.GridSteps)
  {
    steps.push_back({ { "row", step.Row },
                      { "column", step.Column },
                      { "slice", step.Slice },
                      { "along", step.AlongAxis ? "axis" : "sheet" },
                      { "step_mm", step.Step } });
  }
  nlohmann::json offSheet = nlohmann::json::array();
  for (const auto & run : report.OffSheetRuns)
  {
    offSheet.push_back({ { "row", run.Row },
                         { "first_column", run.FirstColumn },
                         { "last_column", run.LastColumn },
                         { "slice", run.Slice },
                         { "lowest_level", run.Lowest } });
  }
  nlohmann::json json = { { "method", itk::ToString(report.Method) },
                          { "interpolated_slices", report.InterpolatedSlices },
                          { "low_confidence_regions", regions },
                          { "layer_jumps", jumps },
                          { "mesh_steps", steps },
                          { "off_sheet", offSheet },
                          { "slices", "indices of the slices across the roll axis (after any resampling along it)" } };
  if (report.Method == itk::SheetSurfaceMethodEnum::Roll)
  {
    json["turns"] = report.Turns;
    json["turn_spacing_mm"] = report.TurnSpacing;
    json["row_spikes_smoothed"] = report.RowSpikesSmoothed;
    json["column_spikes_smoothed"] = report.ColumnSpikesSmoothed;
    json["mean_confidence"] = count > 0 ? sum / static_cast<double>(count) : 0.0;
  }
  return json;
}

void
RegisterSegmentCommand(CLI::App & app)
{
  auto *                command = app.add_subcommand("segment",
                                      "Segment the sheet of a CT volume and mesh its mid-surface: writes mask.mha, "
                                                     "surface.obj, surface.vtk and segment.json into DIR.");
  static SegmentOptions options;
  command
    ->add_option(
      "VOLUME", options.Volume, "CT scan: DICOM directory, TIFF stack (directory or glob), NRRD/MHA/NIfTI file")
    ->required();
  command->add_option("-o,--output", options.Output, "output directory (created; files in it are replaced)")
    ->required();
  command->add_option("--threshold", options.Threshold, "material threshold in HU, or auto (Otsu on the object)")
    ->capture_default_str();
  command
    ->add_option("--mesh-spacing",
                 options.MeshSpacing,
                 "mesh spacing in mm along the sheet and the roll axis (MM or S,W), or auto (from curvature and "
                 "thickness)")
    ->capture_default_str();
  command->add_option("--method", options.Method, "roll, general or auto")->capture_default_str();
  command->add_option("--chord-error", options.ChordError, "automatic spacing: chord error / sheet thickness")
    ->capture_default_str()
    ->check(CLI::Range(1e-6, 1.0));
  command->add_option("--min-component", options.MinimumComponent, "remove components smaller than this (voxels)")
    ->capture_default_str();
  command->add_option("--closing", options.Closing, "binary closing radius in voxels (0: off)")->capture_default_str();
  command->add_flag("--every-sheet",
                    options.EverySheet,
                    "mesh every sheet (separate pieces, and sheets that touch split between them), each into "
                    "OUTDIR/sheet-NN when there are several, with sheets.mha (the sheet of every voxel); by default "
                    "the largest only");
  command
    ->add_option("--minimum-sheet-area",
                 options.MinimumSheetArea,
                 "with --every-sheet: pieces below this area (mm^2) are counted, not meshed; auto: 1 % of the largest "
                 "sheet's area and at least 400 voxels")
    ->capture_default_str();
  AddReaderOptions(*command, options.Reader);
  command->callback([] { RunSegment(options); });
}
} // namespace vu

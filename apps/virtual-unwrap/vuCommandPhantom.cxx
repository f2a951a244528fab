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
// virtual-unwrap phantom PRESET -o DIR: a synthetic CT scan of a written, rolled or
// folded sheet, with its ground truth (ink image, true mid-surface and its unrolling,
// JSON description), written atomically.
#include "vuCommands.h"

#include "itkCTVolumeWriter.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkMesh.h"
#include "itkMeshFileWriter.h"
#include "itkOBJMeshIO.h"
#include "itkPNGImageIO.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetPhantomSource.h"
#include "itkShiftScaleImageFilter.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <unistd.h>

namespace vu {
namespace {
namespace fs = std::filesystem;

struct PhantomOptions
{
  std::string Preset, Output, Format{ "dicom" }, Shape, Text, Font, InkImage;
  bool        Force{ false };
  double      MeshSpacing{ 0.0 };
  // Slices of the written DICOM series left out (indices in slice order).
  std::vector<unsigned> DropSlices;
  // Numeric overrides of the preset, by option name; applied only when given.
  std::map<std::string, double> Values;
};

std::string
UnescapeNewlines(const std::string & text)
{
  std::string result;
  for (size_t i = 0; i < text.size(); ++i)
  {
    if (text[i] == '\\' && i + 1 < text.size() && text[i + 1] == 'n')
    {
      result += '\n';
      ++i;
    }
    else
    {
      result += text[i];
    }
  }
  return result;
}

void
WriteInkPng(const itk::SheetPhantomGeometry::InkImageType * ink, const std::string & path)
{
  using PngType = itk::Image<unsigned char, 2>;
  auto scale = itk::ShiftScaleImageFilter<itk::SheetPhantomGeometry::InkImageType, PngType>::New();
  scale->SetInput(ink);
  scale->SetScale(255.0);
  auto writer = itk::ImageFileWriter<PngType>::New();
  writer->SetInput(scale->GetOutput());
  writer->SetImageIO(itk::PNGImageIO::New());
  writer->SetFileName(path);
  writer->Update();
}

void
WriteObj(const itk::SheetMesh & sheet, const std::string & path)
{
  using MeshType = itk::Mesh<double, 3>;
  auto writer = itk::MeshFileWriter<MeshType>::New();
  writer->SetInput(itk::SheetMeshToMesh<MeshType>(sheet));
  writer->SetMeshIO(itk::OBJMeshIO::New());
  writer->SetFileName(path);
  writer->Update();
}

nlohmann::json
Vector3(const double * v)
{
  return { v[0], v[1], v[2] };
}

using Source = itk::SheetPhantomSource;

// The phantom source: the preset with the options given over it, every option checked.
Source::Pointer
ConfiguredSource(const PhantomOptions & options)
{
  auto source = Source::New();
  try
  {
    source->ApplyPreset(options.Preset);
  }
  catch (const itk::ExceptionObject & e)
  {
    throw UsageError(e.GetDescription());
  }
  const auto format = itk::CTVolumeWriter::FormatFromString(options.Format);
  const auto has = [&](const char * name) { return options.Values.count(name) > 0; };
  const auto value = [&](const char * name) { return options.Values.at(name); };
  for (const char * name :
       { "length",         "width",          "thickness",   "inner-radius",  "pitch",
         "squash",         "wave-amplitude", "fold-radius", "fold-opening",  "tilt",
         "glyph-height",   "ink-contrast",   "ink-depth",   "air",           "sheet",
         "fibre-contrast", "fibre-length",   "voxel-size",  "slice-spacing", "margin",
         "blur-fwhm",      "noise",          "turns",       "gantry-tilt",   "second-slice-spacing" })
  {
    if (has(name) && !std::isfinite(value(name)))
    {
      throw UsageError(std::string("--") + name + " must be a finite number");
    }
  }
  if (has("length") && has("turns"))
  {
    throw UsageError("give either --length or --turns, not both");
  }
  // A rolled preset keeps its number of turns when the spiral changes.
  source->UpdateOutputInformation();
  const double presetTurns = source->GetGeometry().GetNumberOfTurns();

  if (!options.Shape.empty())
  {
    if (options.Shape != "rolled" && options.Shape != "folded")
    {
      throw UsageError("unknown shape \"" + options.Shape + "\" (rolled or folded)");
    }
    source->SetShape(options.Shape == "rolled" ? Source::ShapeType::Rolled : Source::ShapeType::Folded);
  }
  const std::pair<const char *, void (Source::*)(double)> setters[] = {
    { "width", &Source::SetSheetWidth },
    { "thickness", &Source::SetSheetThickness },
    { "inner-radius", &Source::SetInnerRadius },
    { "pitch", &Source::SetPitch },
    { "squash", &Source::SetSquash },
    { "wave-amplitude", &Source::SetWaveAmplitude },
    { "fold-radius", &Source::SetFoldRadius },
    { "fold-opening", &Source::SetFoldOpeningAngle },
    { "tilt", &Source::SetTiltAngle },
    { "glyph-height", &Source::SetGlyphHeight },
    { "ink-contrast", &Source::SetInkContrast },
    { "ink-depth", &Source::SetInkDepth },
    { "air", &Source::SetAirValue },
    { "sheet", &Source::SetSheetValue },
    { "fibre-contrast", &Source::SetFibreContrast },
    { "fibre-length", &Source::SetFibreLength },
    { "voxel-size", &Source::SetVoxelSize },
    { "slice-spacing", &Source::SetSliceSpacing },
    { "margin", &Source::SetMargin },
    { "blur-fwhm", &Source::SetBlurFWHM },
    { "noise", &Source::SetNoiseStandardDeviation },
  };
  for (const auto & [name, setter] : setters)
  {
    if (has(name))
    {
      (source.GetPointer()->*setter)(value(name));
    }
  }
  const std::pair<const char *, void (Source::*)(unsigned)> countSetters[] = {
    { "waves-per-turn", &Source::SetWavesPerTurn },
    { "fold-count", &Source::SetFoldCount },
    { "supersampling", &Source::SetSupersampling },
    { "ink-oversampling", &Source::SetInkOversampling },
  };
  for (const auto & [name, setter] : countSetters)
  {
    if (has(name))
    {
      (source.GetPointer()->*setter)(static_cast<unsigned>(value(name)));
    }
  }
  if (has("seed"))
  {
    source->SetSeed(static_cast<uint32_t>(value("seed")));
  }
  if (has("length"))
  {
    source->SetSheetLength(value("length"));
  }
  else if (source->GetShape() == Source::ShapeType::Rolled)
  {
    source->SetNumberOfTurns(has("turns") ? value("turns") : (presetTurns > 0.0 ? presetTurns : 3.0));
  }
  else if (has("turns"))
  {
    throw UsageError("--turns applies to rolled sheets only; give --length for a folded sheet");
  }
  if (!options.Text.empty())
  {
    source->SetText(UnescapeNewlines(options.Text));
  }
  if (!options.Font.empty())
  {
    source->SetFontFile(options.Font);
  }
  if (!options.InkImage.empty() && !options.Text.empty())
  {
    throw UsageError("give either --text or --ink-image, not both");
  }
  if (!options.InkImage.empty())
  {
    if (!fs::is_regular_file(options.InkImage))
    {
      throw UsageError("ink image not found: " + options.InkImage);
    }
    auto reader = itk::ImageFileReader<Source::InkImageType>::New();
    reader->SetFileName(options.InkImage);
    reader->Update();
    source->SetInkPattern(reader->GetOutput());
  }
  if ((has("gantry-tilt") || has("second-slice-spacing") || !options.DropSlices.empty()) &&
      format != itk::CTVolumeWriter::FormatType::Dicom)
  {
    throw UsageError(
      "--gantry-tilt, --second-slice-spacing and --drop-slices write a DICOM series: use --format dicom");
  }
  if (has("gantry-tilt") && !(std::abs(value("gantry-tilt")) < 60.0))
  {
    throw UsageError("--gantry-tilt must lie between -60 and 60 degrees");
  }
  if (has("second-slice-spacing") && !(value("second-slice-spacing") > 0.0))
  {
    throw UsageError("--second-slice-spacing must be positive");
  }
  if (options.MeshSpacing < 0.0 || !std::isfinite(options.MeshSpacing))
  {
    throw UsageError("--mesh-spacing must be positive");
  }

  return source;
}

// A hospital CT series: each slice's distance from the first along z (a slice spacing
// that changes, slices left out).
std::vector<double>
HospitalSliceLocations(const PhantomOptions & options, const Source::OutputImageType * volume)
{
  const auto          has = [&](const char * name) { return options.Values.count(name) > 0; };
  const auto          value = [&](const char * name) { return options.Values.at(name); };
  std::vector<double> sliceLocations;
  {
    const auto   volumeSize = volume->GetLargestPossibleRegion().GetSize();
    const double sliceSpacing = volume->GetSpacing()[2];
    const double extent = sliceSpacing * static_cast<double>(volumeSize[2] - 1);
    if (has("second-slice-spacing"))
    {
      sliceLocations =
        itk::CTVolumeWriter::SliceLocationsWithSpacingChange(extent, sliceSpacing, value("second-slice-spacing"));
    }
    else
    {
      for (size_t k = 0; k < volumeSize[2]; ++k)
      {
        sliceLocations.push_back(static_cast<double>(k) * sliceSpacing);
      }
    }
    std::vector<unsigned> drop = options.DropSlices;
    std::sort(drop.begin(), drop.end());
    drop.erase(std::unique(drop.begin(), drop.end()), drop.end());
    for (auto k = drop.rbegin(); k != drop.rend(); ++k)
    {
      if (*k == 0 || *k + 1 >= sliceLocations.size())
      {
        throw UsageError("--drop-slices: slice " + std::to_string(*k) +
                         " is not between the first and the last (0 and " + std::to_string(sliceLocations.size() - 1) +
                         ")");
      }
      sliceLocations.erase(sliceLocations.begin() + *k);
    }
  }
  return sliceLocations;
}

// ground_truth.json but for the timings: the phantom's parameters, the volume's geometry
// and how sheet coordinates map into it.
nlohmann::json
GroundTruthJson(const PhantomOptions &      options,
                const Source &              source,
                const std::string &         volumeName,
                const itk::CTVolumeWriter & writer,
                const std::vector<double> & sliceLocations,
                const itk::SheetMesh &      surface,
                double                      meshSpacing)
{
  const itk::SheetPhantomGeometry & geometry = source.GetGeometry();
  const Source::OutputImageType *   volume = source.GetOutput();
  const auto                        format = writer.GetFormat();
  const bool                        hospital = !sliceLocations.empty();
  const auto                        size = volume->GetLargestPossibleRegion().GetSize();
  const auto                        spacing = volume->GetSpacing();
  const auto                        origin = volume->GetOrigin();
  const auto *                      ink = geometry.GetInkImage();
  const auto                        inkSize = ink->GetLargestPossibleRegion().GetSize();
  nlohmann::json                    direction = nlohmann::json::array();
  for (unsigned r = 0; r < 3; ++r)
  {
    direction.push_back({ volume->GetDirection()[r][0], volume->GetDirection()[r][1], volume->GetDirection()[r][2] });
  }
  const auto &      p = geometry.GetParameters();
  const bool        rolled = p.Shape == itk::SheetPhantomGeometry::ShapeType::Rolled;
  nlohmann::json    json;
  const std::string stored =
    format == itk::CTVolumeWriter::FormatType::Dicom
      ? "int16 stored values, HU = stored * RescaleSlope (1) + RescaleIntercept (-1024)"
    : format == itk::CTVolumeWriter::FormatType::Tiff
      ? "uint16, HU = value - 1024 (HU below -1024 clipped); TIFF has no 3D geometry: use spacing_mm and origin_mm"
      : "int16 HU";
  json["text"] = geometry.GetText();
  json["preset"] = options.Preset;
  json["preset_description"] = Source::GetPresetDescription(options.Preset);
  json["sheet"] = { { "shape", itk::SheetPhantomGeometry::ShapeName(p.Shape) },
                    { "length_mm", p.SheetLength },
                    { "width_mm", p.SheetWidth },
                    { "thickness_mm", p.SheetThickness },
                    { "tilt_deg", p.TiltAngle },
                    { "minimum_curvature_radius_mm", geometry.GetMinimumCurvatureRadius() } };
  if (rolled)
  {
    json["sheet"]["turns"] = geometry.GetNumberOfTurns();
    json["sheet"]["inner_radius_mm"] = p.InnerRadius;
    json["sheet"]["pitch_mm"] = p.Pitch;
    json["sheet"]["gap_mm"] = p.Pitch - p.SheetThickness;
    json["sheet"]["squash"] = p.Squash;
    json["sheet"]["wave_amplitude_mm"] = p.WaveAmplitude;
    json["sheet"]["waves_per_turn"] = p.WavesPerTurn;
  }
  else
  {
    json["sheet"]["fold_count"] = p.FoldCount;
    json["sheet"]["fold_radius_mm"] = p.FoldRadius;
    json["sheet"]["fold_opening_deg"] = p.FoldOpeningAngle;
  }
  json["ink"] = { { "source", options.InkImage.empty() ? "text" : "image" },
                  { "image_file", options.InkImage },
                  { "font", source.GetFontFile() },
                  { "glyph_height_mm", source.GetGlyphHeight() },
                  { "contrast_hu", source.GetInkContrast() },
                  { "depth_mm", source.GetInkDepth() },
                  { "face", "the face SurfaceNormal points out of (rolled: the inner, concave face)" },
                  { "image_size", { inkSize[0], inkSize[1] } },
                  { "image_spacing_mm", { ink->GetSpacing()[0], ink->GetSpacing()[1] } } };
  json["material"] = { { "air_hu", source.GetAirValue() },
                       { "sheet_hu", source.GetSheetValue() },
                       { "fibre_contrast_hu", source.GetFibreContrast() },
                       { "fibre_length_mm", source.GetFibreLength() } };
  json["scan"] = { { "voxel_size_mm", source.GetVoxelSize() },
                   { "slice_spacing_mm", source.GetSliceSpacing() },
                   { "margin_mm", source.GetMargin() },
                   { "supersampling", source.GetSupersampling() },
                   { "ink_oversampling", source.GetInkOversampling() },
                   { "blur_fwhm_mm", source.GetBlurFWHM() },
                   { "noise_sd_hu", source.GetNoiseStandardDeviation() },
                   { "seed", source.GetSeed() } };
  json["volume"] = { { "format", options.Format },
                     { "path", volumeName },
                     { "size", { size[0], size[1], size[2] } },
                     { "voxels", size[0] * size[1] * size[2] },
                     { "spacing_mm", Vector3(spacing.GetDataPointer()) },
                     { "origin_mm", Vector3(origin.GetDataPointer()) },
                     { "direction", direction },
                     { "values", stored } };
  if (hospital)
  {
    json["series"] = { { "description",
                         "the DICOM series is sampled from the volume above (cubic B-spline) on tilted or relocated "
                         "slices: slice k lies at slice_locations_mm[k] along the volume's z axis from its first "
                         "slice, its origin moved along y by -tan(gantry_tilt_deg) times that distance (then the "
                         "slices are widened to hold the whole volume)" },
                       { "gantry_tilt_deg", writer.GetGantryTilt() },
                       { "slice_locations_mm", sliceLocations },
                       { "dropped_slices", options.DropSlices } };
  }
  json["mapping"] = {
    { "description",
      "Sheet coordinates: s = arc length from the inner end (0..length_mm), w = across the sheet along the roll "
      "axis (0..width_mm). Mid-surface point P(s, w) = R_x(tilt_deg) * (C(s), w - width_mm / 2) in the volume's "
      "physical frame (mm), where C is the cross-section curve (rolled: Archimedean spiral r = inner_radius + "
      "pitch * theta / 2pi + wave_amplitude * sin(waves_per_turn * theta), x = r cos theta, y = squash * r sin "
      "theta, counter-clockwise from the inner end; folded: flat panels joined by creases of fold_radius_mm turning "
      "alternately left and right by 180 - fold_opening_deg degrees). Ink normal n = dP/dw x dP/ds." },
    { "surface_obj", "ground_truth_surface.obj" },
    { "flat_obj", "ground_truth_flat.obj" },
    { "mesh_spacing_mm", meshSpacing },
    { "grid_rows", surface.GridRows },
    { "grid_columns", surface.GridColumns },
    { "vertex_order",
      "vertex r * grid_columns + c (1-based in OBJ: +1) lies at s = c * length_mm / (grid_columns - 1), "
      "w = r * width_mm / (grid_rows - 1); the flat OBJ has the same faces with vertices (s, w, 0)" },
    { "faces", "oriented so that right-hand normals of the surface OBJ point out of the inked face" },
    { "ink_png",
      "ground_truth_ink.png: 8-bit, 255 = full ink coverage; column = s / image_spacing_mm[0] - 0.5, row = w / "
      "image_spacing_mm[1] - 0.5; text upright and unmirrored when shown with row 0 at the top" }
  };
  return json;
}

void
RunPhantom(const PhantomOptions & options)
{
  const auto     source = ConfiguredSource(options);
  const auto     format = itk::CTVolumeWriter::FormatFromString(options.Format);
  const fs::path output(options.Output);
  if (output.empty())
  {
    throw UsageError("no output directory given");
  }
  std::error_code error;
  if (fs::exists(output) && !fs::is_directory(output))
  {
    throw UsageError(output.string() + " exists and is not a directory");
  }
  if (fs::is_directory(output) && !fs::is_empty(output, error) && !options.Force)
  {
    throw UsageError(output.string() + " exists and is not empty (use --force to replace it)");
  }

  // Everything is written into a staging folder beside the target and moved into place at
  // the end, so a failure, a signal or a kill leaves no partial output.
  OutputStaging staging(output, OutputStaging::Kind::Folder);
  const auto    start = std::chrono::steady_clock::now();
  source->UpdateOutputInformation();
  {
    const auto volumeSize = source->GetOutput()->GetLargestPossibleRegion().GetSize();
    SetActivity("generating a phantom volume of " + std::to_string(volumeSize[0]) + " x " +
                std::to_string(volumeSize[1]) + " x " + std::to_string(volumeSize[2]) + " voxels");
  }
  source->Update();
  const double generationSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const itk::SheetPhantomGeometry & geometry = source->GetGeometry();
  const Source::OutputImageType *   volume = source->GetOutput();

  const bool series =
    format == itk::CTVolumeWriter::FormatType::Dicom || format == itk::CTVolumeWriter::FormatType::Tiff;
  const std::string volumeName = series ? "volume" : std::string("volume.") + itk::CTVolumeWriter::FormatName(format);
  // The volume at 16 bits a voxel, file headers, the ink image and the meshes.
  staging.RequireSpace(2 * volume->GetLargestPossibleRegion().GetNumberOfPixels() + (16u << 20));
  auto writer = itk::CTVolumeWriter::New();
  writer->SetInput(volume);
  writer->SetFormat(format);
  writer->SetFileName((staging.Path() / volumeName).string());
  writer->SetSeed(source->GetSeed());
  writer->SetSeriesDescription("VirtualUnwrapping phantom " + options.Preset);
  // A hospital CT series: tilted gantry, spacing that changes, slices left out.
  const auto                has = [&](const char * name) { return options.Values.count(name) > 0; };
  const bool                hospital = has("gantry-tilt") || has("second-slice-spacing") || !options.DropSlices.empty();
  const std::vector<double> sliceLocations = hospital ? HospitalSliceLocations(options, volume) : std::vector<double>{};
  if (hospital)
  {
    writer->SetGantryTilt(has("gantry-tilt") ? options.Values.at("gantry-tilt") : 0.0);
    writer->SetSliceLocations(sliceLocations);
  }
  writer->Write();

  WriteInkPng(geometry.GetInkImage(), (staging.Path() / "ground_truth_ink.png").string());
  const double meshSpacing = options.MeshSpacing > 0.0 ? options.MeshSpacing : source->GetVoxelSize();
  if ((geometry.GetSheetLength() / meshSpacing + 1.0) * (geometry.GetSheetWidth() / meshSpacing + 1.0) > 5.0e7)
  {
    throw UsageError("--mesh-spacing " + std::to_string(meshSpacing) +
                     " mm would make ground-truth meshes of more than 5e7 vertices");
  }
  itk::SheetMesh flat;
  const auto     surface = geometry.MakeMidSurfaceMesh(meshSpacing, &flat);
  WriteObj(surface, (staging.Path() / "ground_truth_surface.obj").string());
  WriteObj(flat, (staging.Path() / "ground_truth_flat.obj").string());
  const double totalSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  nlohmann::json json = GroundTruthJson(options, *source, volumeName, *writer, sliceLocations, surface, meshSpacing);
  json["timing_seconds"] = { { "volume", generationSeconds }, { "total", totalSeconds } };
  WriteTextFileAtomically((staging.Path() / "ground_truth.json").string(), json.dump(2) + "\n");

  staging.Commit(OutputStaging::Existing::Replace);
  const auto   size = volume->GetLargestPossibleRegion().GetSize();
  const auto & p = geometry.GetParameters();
  std::cout << "phantom " << options.Preset << ": " << size[0] << " x " << size[1] << " x " << size[2]
            << " voxels, sheet " << p.SheetLength << " x " << p.SheetWidth << " mm, volume " << generationSeconds
            << " s, total " << totalSeconds << " s -> " << output.string() << std::endl;
}
} // namespace

void
RegisterPhantomCommand(CLI::App & app)
{
  static PhantomOptions options;
  std::string           presets;
  for (const auto & name : itk::SheetPhantomSource::GetPresetNames())
  {
    presets += "\n  " + name + ": " + itk::SheetPhantomSource::GetPresetDescription(name);
  }
  auto * command = app.add_subcommand(
    "phantom",
    "Synthesise a CT scan of a written sheet rolled into a scroll or folded, with its ground truth: "
    "DIR/volume/ (DICOM series or TIFF stack) or DIR/volume.mha|.nrrd, ground_truth_ink.png, ground_truth.json, "
    "ground_truth_surface.obj and ground_truth_flat.obj. Options not given keep the preset's values (all are "
    "recorded in ground_truth.json). Presets:" +
      presets);
  command->add_option("PRESET", options.Preset, "preset to start from (options below override it)")->required();
  command->add_option("-o,--output", options.Output, "output directory (created; replaced only with --force)")
    ->required();
  command->add_option("--format", options.Format, "volume format: dicom, tiff, mha, nrrd or zarr (OME-Zarr)")
    ->capture_default_str();
  command->add_flag("--force", options.Force, "replace an existing, non-empty output directory");
  command->add_option(
    "--mesh-spacing", options.MeshSpacing, "grid spacing of the ground-truth OBJ meshes, mm (default: the voxel size)");
  command->add_option("--shape", options.Shape, "rolled or folded");
  command->add_option("--text", options.Text, "text to write ('\\n' separates lines; long lines are word-wrapped)");
  command->add_option("--font", options.Font, "TrueType font file (default DejaVuSans-Bold)");
  command->add_option(
    "--ink-image", options.InkImage, "image to write instead of text (dark = ink), fitted into the sheet");
  const std::pair<const char *, const char *> numbers[] = {
    { "length", "sheet length, mm (folded sheets; rolled sheets may give --turns instead)" },
    { "turns", "number of turns of a rolled sheet (sets the length)" },
    { "width", "sheet width along the roll axis, mm" },
    { "thickness", "sheet thickness, mm" },
    { "inner-radius", "inner radius of the spiral, mm" },
    { "pitch", "radial distance between turns, mm (> thickness; gap = pitch - thickness)" },
    { "squash", "ratio of the cross-section's axes, (0, 1]" },
    { "wave-amplitude", "amplitude of radial ripples whose ridges run along the roll axis, mm" },
    { "waves-per-turn", "ripples per turn" },
    { "fold-count", "number of creases of a folded sheet" },
    { "fold-radius", "radius of the creases, mm" },
    { "fold-opening", "angle between neighbouring panels, degrees [0, 90)" },
    { "tilt", "tilt of the roll axis about x, degrees (-60, 60)" },
    { "glyph-height", "height of capital letters, mm" },
    { "ink-contrast", "ink density above the sheet, HU" },
    { "ink-depth", "depth of ink below the inked face, mm (>= thickness: soaks through)" },
    { "air", "air, HU" },
    { "sheet", "sheet material, HU" },
    { "fibre-contrast", "standard deviation of the fibre texture, HU (0: none)" },
    { "fibre-length", "length of fibres, mm" },
    { "voxel-size", "voxel size in x and y, mm" },
    { "slice-spacing", "slice spacing along z, mm" },
    { "margin", "air around the sheet, mm" },
    { "supersampling", "sub-voxel samples per voxel along each axis, 1..8" },
    { "ink-oversampling", "ink image pixels per voxel, 1..16" },
    { "blur-fwhm", "full width at half maximum of the scanner's blur, mm (0: none)" },
    { "noise", "standard deviation of the noise, HU (0: none)" },
    { "seed", "random seed of noise, fibres and file order" },
    { "gantry-tilt",
      "write the DICOM series as a CT with its gantry tilted by this many degrees: slice origins shifted along y, "
      "GantryDetectorTilt set (-60, 60)" },
    { "second-slice-spacing",
      "write the second half of the DICOM series' slices this many mm apart (the first half keeps --slice-spacing)" },
  };
  command->add_option("--drop-slices",
                      options.DropSlices,
                      "leave these slices (indices in slice order, not the first or last) out of the DICOM series");
  for (const auto & [name, help] : numbers)
  {
    const std::string key = name;
    command->add_option_function<double>(
      std::string("--") + name, [key](const double & v) { options.Values[key] = v; }, help);
  }
  command->callback([] {
    for (const char * name : { "waves-per-turn", "fold-count", "supersampling", "ink-oversampling", "seed" })
    {
      const auto found = options.Values.find(name);
      if (found != options.Values.end() &&
          (found->second < 0.0 || found->second != std::floor(found->second) || found->second > 4294967295.0))
      {
        throw UsageError(std::string("--") + name + " must be a non-negative whole number");
      }
    }
    RunPhantom(options);
  });
}
} // namespace vu

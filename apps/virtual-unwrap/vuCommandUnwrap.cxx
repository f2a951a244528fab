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
// virtual-unwrap unwrap INPUT -o OUTDIR: the module's main job, from a CT scan to a flat,
// readable image: read, segment, mesh the sheet's mid-surface, unroll and flatten it by
// mass-spring simulation, render the layered texture, report.
#include "vuCommands.h"
#include "vuOutput.h"
#include "vuProgress.h"
#include "vuReaderOptions.h"
#include "vuSheetMeshIO.h"
#include "vuSheetsJson.h"
#include "vuSimulationOptions.h"
#include "vuTextureOutput.h"

#include "itkCTVolumeReader.h"
#include "itkFlipImageFilter.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkLayerStackTexture.h"
#include "itkLayeredTextureMeshFilter.h"
#include "itkMassSpringFlatteningMeshFilter.h"
#include "itkMultiThreaderBase.h"
#include "itkReadableTextureImageFilter.h"
#include "itkRescaleIntensityImageFilter.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSheetSegmentationImageFilter.h"
#include "itkTextLegibility.h"
#include "itkTextureFidelityCalculator.h"
#include "itkTextureLayers.h"
#include "itkTouchingSheetSplitter.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <limits>
#include <numeric>
#include <sstream>

namespace vu {
namespace {
// Peak memory of unwrap per voxel of the volume read, beyond the program itself: 47 bytes
// between the standard phantom at 0.1 and 0.05 mm (0.78 and 3.06 million voxels, peaks of
// 127 and 230 MiB; docs/robustness.md), the texture stage's share included.
constexpr double UnwrapBytesPerVoxel = 48.0;
namespace fs = std::filesystem;
using VolumeType = itk::Image<float, 3>;
using MaskType = itk::Image<unsigned char, 3>;
// Every stage passes the sheet as this mesh (double precision, as the simulation works).
using MeshType = itk::Mesh<double, 3>;
using TextureType = itk::Image<float, 2>;
using TextureMaskType = itk::Image<unsigned char, 2>;
using LayerStackType = itk::Image<float, 3>;
using Texture8Type = itk::Image<unsigned char, 2>;

struct UnwrapOptions
{
  std::string       Input;
  std::string       Output;
  ReaderOptions     Reader;
  std::string       Threshold{ "auto" };
  std::string       MeshSpacing{ "auto" };
  std::string       Method{ "auto" };
  std::string       Sheet{ "all" };
  std::string       SeedPoint;
  std::string       MinimumSheetArea{ "auto" };
  unsigned int      Layers{ 0 };
  double            LayerSpacing{ 0.0 };
  std::string       Side{ "auto" };
  std::string       Filter{ "max" };
  std::string       SubtractCore{ "auto" };
  std::string       Median{ "auto" };
  std::string       Smooth{ "auto" };
  std::string       Restore{ "off" };
  std::string       DisplayBorder{ "auto" };
  double            Focus{ 0.0 };
  double            PixelSize{ 0.0 };
  SimulationOptions Simulation;
  std::string       GroundTruth;
  bool              Quiet{ false };
  bool              JsonLog{ false };
};

double
PeakMemoryMiB()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

itk::TextureLayersEnums::Side
SideFromName(const std::string & name)
{
  using S = itk::TextureLayersEnums::Side;
  return name == "positive" ? S::Positive : (name == "negative" ? S::Negative : S::Both);
}

std::string
SideName(itk::TextureLayersEnums::Side side)
{
  using S = itk::TextureLayersEnums::Side;
  return side == S::Positive ? "positive" : (side == S::Negative ? "negative" : "both");
}

itk::TextureLayersEnums::CoreSubtraction
CoreFromName(const std::string & name)
{
  using C = itk::TextureLayersEnums::CoreSubtraction;
  return name == "yes" ? C::Yes : (name == "no" ? C::No : C::Auto);
}

// The texture's parameters as applied (report.json).
nlohmann::json
TextureParametersJson(const itk::ReadableTextureImageFilter<VolumeType, TextureType, MeshType> & texturer,
                      const UnwrapOptions &                                                      options,
                      double                                                                     displayBorder)
{
  const itk::ReadableTextureSelection & selection = texturer.GetSelection();
  const itk::ReadableTextureCandidate & chosen = selection.ChosenCandidate();
  nlohmann::json                        candidates = nlohmann::json::array();
  for (const auto & c : selection.Candidates)
  {
    if (c.Count > 0)
    {
      candidates.push_back({ { "layers", { c.First, c.First + c.Count - 1 } }, { "stroke_contrast", c.Score } });
    }
    else
    {
      candidates.push_back(
        { { "side", SideName(c.Side) }, { "subtract_core", c.SubtractCore }, { "ink_contrast", c.Score } });
    }
  }
  const bool restore = texturer.GetRestoreFWHM() >= 0.0;
  return { { "layers", texturer.GetAppliedNumberOfLayers() },
           { "layers_combined", selection.VertexLayers },
           { "layer_spacing_mm", texturer.GetAppliedLayerSpacing() },
           { "side", SideName(chosen.Side) },
           { "side_requested", options.Side },
           { "filter", chosen.Count > 0 ? std::string("mean") : options.Filter },
           { "filter_requested", options.Filter },
           { "focal_slab",
             chosen.Count > 0
               ? nlohmann::json{ { "layers", { chosen.First, chosen.First + chosen.Count - 1 } },
                                 { "depth_mm", selection.Depth },
                                 { "pixels_left_out_of_scores", selection.PixelsLeftOut },
                                 { "sheet_shift_mm",
                                   { { "median", selection.SheetShiftMedian }, { "p95", selection.SheetShiftP95 } } } }
               : nlohmann::json(false) },
           { "subtract_core", chosen.SubtractCore },
           { "subtract_core_requested", options.SubtractCore },
           { "core_width_mm", selection.CoreWidth },
           { "median_radius_mm", selection.MedianRadius },
           { "smooth_sigma_mm", selection.SmoothSigma },
           { "restore",
             restore ? nlohmann::json{ { "psf_fwhm_mm", texturer.GetRestoreFWHM() },
                                       { "psf_sigma_mm", selection.PsfSigma },
                                       { "bilateral_domain_sigma_mm", selection.RestoreDomainSigma },
                                       { "bilateral_range_factor", selection.RestoreRangeFactor },
                                       { "tikhonov_regularization", selection.RestoreRegularization } }
                     : nlohmann::json(false) },
           { "display_border_mm", displayBorder },
           { "focus_mm", options.Focus },
           { "pixel_size_mm", texturer.GetAppliedPixelSize() },
           { "selection",
             { { "criterion",
                 selection.FocalSlabs ? "noisy scan: focal slabs (mean of 3 or 5 layers) at every depth; highest "
                                        "stroke contrast, the 99th percentile of the denoised slab band-passed "
                                        "between Gaussians of 0.5 and 3 voxels, in the block along the sheet "
                                        "where it is highest, over the band's spread"
                                      : "highest ink contrast, (99th percentile - median) / (1.4826 median "
                                        "absolute deviation) of the denoised texture" },
               { "candidates", candidates } } } };
}

// "auto" (giving `automatic`) or a non-negative length in mm.
double
AutoOrLength(const std::string & value, const std::string & option, double automatic)
{
  if (value == "auto")
  {
    return automatic;
  }
  size_t used = 0;
  double length = 0.0;
  try
  {
    length = std::stod(value, &used);
  }
  catch (const std::exception &)
  {
    used = 0;
  }
  if (used != value.size() || !std::isfinite(length) || length < 0.0)
  {
    throw UsageError(option + " must be auto or a length >= 0 in mm, not '" + value + "'");
  }
  return length;
}

// --restore: the scanner's PSF FWHM in mm, or -1 for off.
double
RestoreFWHM(const std::string & value)
{
  if (value == "off")
  {
    return -1.0;
  }
  if (value != "auto")
  {
    try
    {
      return AutoOrLength(value, "--restore", 0.0);
    }
    catch (const UsageError &)
    {}
  }
  throw UsageError("--restore must be off or the scanner's PSF FWHM in mm (>= 0), not '" + value + "'");
}

// Where an image with its rows (axis 1) in reverse order lies, as itk::FlipImageFilter
// about axis 1 (not about the origin) places it: starting where the last row lay, the
// axis's direction reversed.
template <typename TImage>
void
FlippedRowsGeometry(const TImage *                   image,
                    typename TImage::PointType &     origin,
                    typename TImage::DirectionType & direction)
{
  const auto &               region = image->GetLargestPossibleRegion();
  typename TImage::IndexType last = region.GetIndex();
  last[1] = static_cast<itk::IndexValueType>(region.GetSize(1)) - 1;
  image->TransformIndexToPhysicalPoint(last, origin);
  typename TImage::DirectionType reverse;
  reverse.SetIdentity();
  reverse[1][1] = -1.0;
  direction = image->GetDirection() * reverse;
}

// Flat y grows upwards when the sheet is seen from the side its normals face; image rows
// grow downwards. Flipping rows shows the sheet as seen from that side, not mirrored.
template <typename TImage>
typename TImage::Pointer
FlipRows(const TImage * image)
{
  const auto & region = image->GetLargestPossibleRegion();
  if (region.GetIndex() != typename TImage::IndexType() || image->GetBufferedRegion() != region)
  {
    auto flip = itk::FlipImageFilter<TImage>::New();
    flip->SetInput(image);
    typename itk::FlipImageFilter<TImage>::FlipAxesArrayType axes;
    axes.Fill(false);
    axes[1] = true;
    flip->SetFlipAxes(axes);
    flip->FlipAboutOriginOff();
    flip->Update();
    typename TImage::Pointer result = flip->GetOutput();
    result->DisconnectPipeline();
    return result;
  }
  // The same image as itk::FlipImageFilter gives: the last row first, rows copied whole.
  auto result = TImage::New();
  result->CopyInformation(image);
  result->SetRegions(region);
  typename TImage::PointType     origin;
  typename TImage::DirectionType direction;
  FlippedRowsGeometry(image, origin, direction);
  result->SetOrigin(origin);
  result->SetDirection(direction);
  result->Allocate();
  const itk::SizeValueType columns = region.GetSize(0), rows = region.GetSize(1);
  const itk::SizeValueType planes = region.GetNumberOfPixels() / (columns * rows);
  const auto *             in = image->GetBufferPointer();
  auto *                   out = result->GetBufferPointer();
  for (itk::SizeValueType plane = 0; plane < planes; ++plane)
  {
    for (itk::SizeValueType row = 0; row < rows; ++row)
    {
      const auto * from = in + (plane * rows + rows - 1 - row) * columns;
      std::copy(from, from + columns, out + (plane * rows + row) * columns);
    }
  }
  return result;
}

// FlipRows on the image itself, rows swapped in its own buffer (the layer stack, the largest
// image the tool writes, is not copied); an image whose buffer does not start at the origin
// is flipped into a copy.
template <typename TImage>
typename TImage::Pointer
FlipRowsInPlace(TImage * image)
{
  const auto & region = image->GetLargestPossibleRegion();
  if (region.GetIndex() != typename TImage::IndexType() || image->GetBufferedRegion() != region)
  {
    return FlipRows(image);
  }
  typename TImage::PointType     origin;
  typename TImage::DirectionType direction;
  FlippedRowsGeometry(image, origin, direction);
  const itk::SizeValueType columns = region.GetSize(0), rows = region.GetSize(1);
  const itk::SizeValueType planes = region.GetNumberOfPixels() / (columns * rows);
  auto *                   buffer = image->GetBufferPointer();
  for (itk::SizeValueType plane = 0; plane < planes; ++plane)
  {
    for (itk::SizeValueType row = 0; row < rows / 2; ++row)
    {
      auto * top = buffer + (plane * rows + row) * columns;
      std::swap_ranges(top, top + columns, buffer + (plane * rows + rows - 1 - row) * columns);
    }
  }
  image->SetOrigin(origin);
  image->SetDirection(direction);
  return image;
}

template <typename TImage>
void
WriteImageFile(const TImage * image, const fs::path & path)
{
  auto writer = itk::ImageFileWriter<TImage>::New();
  writer->SetInput(image);
  writer->SetFileName(path.string());
  writer->Update();
}

// Preview: a slice across the roll axis with the mesh's cross-section in red, beside the
// flat texture, on one RGB canvas.
void
WritePreview(const VolumeType *                   volume,
             const itk::SheetMesh &               surface,
             const itk::Image<unsigned char, 2> * texture8,
             const fs::path &                     path)
{
  using RGB = itk::RGBPixel<unsigned char>;
  using Canvas = itk::Image<RGB, 2>;
  const auto size = volume->GetLargestPossibleRegion().GetSize();
  const auto index0 = volume->GetLargestPossibleRegion().GetIndex();
  // The slice through a point in the middle of the mesh (a middle row of a grid mesh).
  const size_t          middle = surface.GetNumberOfPoints() / 2;
  itk::Point<double, 3> probe;
  for (int d = 0; d < 3; ++d)
  {
    probe[d] = surface.Points[3 * middle + d];
  }
  itk::ContinuousIndex<double, 3> c;
  volume->TransformPhysicalPointToContinuousIndex(probe, c);
  const long slice = std::clamp<long>(std::lround(c[2]), index0[2], index0[2] + long(size[2]) - 1);
  // Slice intensities windowed to their 1st..99th percentiles.
  std::vector<float> values;
  for (unsigned y = 0; y < size[1]; ++y)
  {
    for (unsigned x = 0; x < size[0]; ++x)
    {
      values.push_back(volume->GetPixel({ { index0[0] + long(x), index0[1] + long(y), slice } }));
    }
  }
  std::vector<float> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  const float lo = sorted[sorted.size() / 100], hi = std::max(sorted[sorted.size() * 99 / 100], lo + 1e-6f);
  const auto  textureSize = texture8->GetLargestPossibleRegion().GetSize();
  // Scale both panels to a common height of at most 600 pixels.
  const double     sliceScale = 600.0 / std::max<double>(size[1], 1);
  const double     textureScale = std::min(600.0 / textureSize[1], 1400.0 / textureSize[0]);
  const unsigned   sliceW = unsigned(size[0] * sliceScale), sliceH = unsigned(size[1] * sliceScale);
  const unsigned   texW = unsigned(textureSize[0] * textureScale), texH = unsigned(textureSize[1] * textureScale);
  auto             canvas = Canvas::New();
  Canvas::SizeType canvasSize = { { sliceW + 10 + texW, std::max(sliceH, texH) } };
  canvas->SetRegions(canvasSize);
  canvas->Allocate();
  RGB background;
  background.Fill(32);
  canvas->FillBuffer(background);
  for (unsigned y = 0; y < sliceH; ++y)
  {
    for (unsigned x = 0; x < sliceW; ++x)
    {
      const float v = values[unsigned(y / sliceScale) * size[0] + unsigned(x / sliceScale)];
      RGB         p;
      p.Fill(static_cast<unsigned char>(std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f) * 255.0f));
      canvas->SetPixel({ { long(x), long(y) } }, p);
    }
  }
  // The mesh's points near that slice.
  const double halfSlice = 0.75 * volume->GetSpacing()[2];
  for (size_t i = 0; i < surface.GetNumberOfPoints(); ++i)
  {
    itk::Point<double, 3> p;
    for (int d = 0; d < 3; ++d)
    {
      p[d] = surface.Points[3 * i + d];
    }
    itk::ContinuousIndex<double, 3> ci;
    volume->TransformPhysicalPointToContinuousIndex(p, ci);
    if (std::abs(ci[2] - slice) > halfSlice / volume->GetSpacing()[2])
    {
      continue;
    }
    const long x = std::lround((ci[0] - index0[0]) * sliceScale), y = std::lround((ci[1] - index0[1]) * sliceScale);
    for (long dy = -1; dy <= 1; ++dy)
    {
      for (long dx = -1; dx <= 1; ++dx)
      {
        if (x + dx >= 0 && y + dy >= 0 && x + dx < long(sliceW) && y + dy < long(sliceH))
        {
          RGB red;
          red[0] = 255;
          red[1] = 40;
          red[2] = 40;
          canvas->SetPixel({ { x + dx, y + dy } }, red);
        }
      }
    }
  }
  for (unsigned y = 0; y < texH; ++y)
  {
    for (unsigned x = 0; x < texW; ++x)
    {
      RGB p;
      p.Fill(texture8->GetPixel({ { long(x / textureScale), long(y / textureScale) } }));
      canvas->SetPixel({ { long(sliceW + 10 + x), long(y) } }, p);
    }
  }
  WriteImageFile(canvas.GetPointer(), path);
}

// Times the stages for the report and tells the progress display.
class StageClock
{
public:
  explicit StageClock(Progress & progress)
    : m_Progress(progress)
  {}
  void
  Start(const std::string & stage, const std::string & message)
  {
    m_Progress.Start(stage, message);
    m_StageStart = std::chrono::steady_clock::now();
  }
  void
  End(const std::string & stage)
  {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_StageStart).count();
    m_Stages.push_back({ { "stage", stage }, { "seconds", seconds }, { "peak_memory_mib", PeakMemoryMiB() } });
    m_Progress.Done(stage, seconds);
  }
  const nlohmann::json &
  Stages() const
  {
    return m_Stages;
  }
  double
  Seconds() const
  {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_Started).count();
  }

private:
  Progress &                            m_Progress;
  nlohmann::json                        m_Stages = nlohmann::json::array();
  std::chrono::steady_clock::time_point m_Started{ std::chrono::steady_clock::now() };
  std::chrono::steady_clock::time_point m_StageStart{ m_Started };
};

// The options that can be checked before the long stages (their automatic values need the
// scan and the mesh), and the threshold and mesh spacing as numbers.
struct CheckedOptions
{
  bool   FixedThreshold{ false };
  double Threshold{ 0.0 };
  double MeshSpacing[2]{ 0.0, 0.0 }; // 0: automatic
  /** 0: every sheet; otherwise the sheet's number (from 1, largest first). */
  unsigned int          Sheet{ 0 };
  bool                  HasSeedPoint{ false };
  itk::Point<double, 3> SeedPoint;
  double                MinimumSheetArea{ 0.0 }; // 0: automatic
};

CheckedOptions
CheckUnwrapOptions(const UnwrapOptions & options)
{
  if (fs::exists(options.Output) && !fs::is_directory(options.Output))
  {
    throw UsageError("output " + options.Output + " exists and is not a directory");
  }
  for (const auto & [value, option] : { std::make_pair(options.Median, "--median"),
                                        std::make_pair(options.Smooth, "--smooth"),
                                        std::make_pair(options.DisplayBorder, "--display-border") })
  {
    AutoOrLength(value, option, 0.0);
  }
  if (RestoreFWHM(options.Restore) >= 0.0 && options.Smooth != "auto")
  {
    throw UsageError("--restore replaces the Gaussian smoothing: leave --smooth at auto");
  }
  if (options.Side == "auto" && options.Layers > 0 && options.Layers % 2 == 0)
  {
    throw UsageError("--side auto splits the layers at the focus: give an odd number of --layers");
  }
  CheckedOptions checked;
  checked.FixedThreshold = ParseAutoOrNumber(options.Threshold, "--threshold", checked.Threshold);
  ParseMeshSpacing(options.MeshSpacing, checked.MeshSpacing);
  if (options.Sheet != "all")
  {
    char *              end = nullptr;
    const unsigned long n = std::strtoul(options.Sheet.c_str(), &end, 10);
    if (options.Sheet.empty() || *end != '\0' || n == 0 || n > 9999 || options.Sheet[0] == '-')
    {
      throw UsageError("--sheet must be all or a sheet number from 1, got " + options.Sheet);
    }
    checked.Sheet = static_cast<unsigned int>(n);
  }
  if (!options.SeedPoint.empty())
  {
    if (checked.Sheet != 0)
    {
      throw UsageError("give --sheet or --seed-point, not both");
    }
    std::istringstream in(options.SeedPoint);
    char               comma1 = 0, comma2 = 0;
    in >> checked.SeedPoint[0] >> comma1 >> checked.SeedPoint[1] >> comma2 >> checked.SeedPoint[2];
    if (!in || comma1 != ',' || comma2 != ',' || !(in >> std::ws).eof() || !std::isfinite(checked.SeedPoint[0]) ||
        !std::isfinite(checked.SeedPoint[1]) || !std::isfinite(checked.SeedPoint[2]))
    {
      throw UsageError("--seed-point must be X,Y,Z in mm, got " + options.SeedPoint);
    }
    checked.HasSeedPoint = true;
  }
  if (ParseAutoOrNumber(options.MinimumSheetArea, "--minimum-sheet-area", checked.MinimumSheetArea) &&
      !(checked.MinimumSheetArea > 0.0))
  {
    throw UsageError("--minimum-sheet-area must be auto or an area in mm^2 above 0");
  }
  return checked;
}

// A phantom's ground truth (virtual-unwrap phantom): the ink image and the text.
struct GroundTruth
{
  TextureType::Pointer Ink;
  std::string          Text;
};

GroundTruth
ReadGroundTruth(const std::string & directory)
{
  GroundTruth truth;
  if (directory.empty())
  {
    return truth;
  }
  std::ifstream in(fs::path(directory) / "ground_truth.json");
  if (!in)
  {
    throw UsageError("no ground_truth.json in " + directory);
  }
  const nlohmann::json json = nlohmann::json::parse(in);
  truth.Text = json.at("text").get<std::string>();
  auto inkReader = itk::ImageFileReader<TextureType>::New();
  inkReader->SetFileName((fs::path(directory) / "ground_truth_ink.png").string());
  inkReader->Update();
  truth.Ink = inkReader->GetOutput();
  const auto               spacing = json.at("ink").at("image_spacing_mm");
  TextureType::SpacingType inkSpacing;
  inkSpacing[0] = spacing.at(0).get<double>();
  inkSpacing[1] = spacing.at(1).get<double>();
  truth.Ink->SetSpacing(inkSpacing);
  return truth;
}

// The scan as read, and with its voxels without data filled for segmentation and meshing;
// its description goes into `input`, the reader's warnings into `warnings`.
struct Scan
{
  VolumeType::Pointer Volume;
  FilledVolume        Filled;
};

Scan
ReadScan(const UnwrapOptions &      options,
         Progress &                 progress,
         nlohmann::json &           input,
         std::vector<std::string> & warnings)
{
  auto reader = itk::CTVolumeReader::New();
  ConfigureReader(options.Reader, options.Input, *reader);
  progress.Observe(reader);
  reader->UpdateOutputInformation();
  {
    // The volume as read (float), its copies and the mask, segmentation's and meshing's
    // work images: about UnwrapBytesPerVoxel bytes a voxel at the peak.
    const auto voxels = reader->GetOutput()->GetLargestPossibleRegion().GetNumberOfPixels();
    const auto size = reader->GetOutput()->GetLargestPossibleRegion().GetSize();
    RequireMemory(static_cast<std::uintmax_t>(UnwrapBytesPerVoxel * static_cast<double>(voxels)),
                  "unwrapping a volume of " + std::to_string(size[0]) + " x " + std::to_string(size[1]) + " x " +
                    std::to_string(size[2]) + " voxels");
  }
  reader->Update();
  Scan scan;
  scan.Volume = reader->GetOutput();
  for (const auto & w : reader->GetWarnings())
  {
    warnings.push_back("read: " + w);
  }
  // Segmentation and meshing need a value in every voxel; the texture samples the scan as
  // read, so a sheet that crosses voxels without data shows holes (NaN) there.
  scan.Filled = FillVoxelsWithoutData(scan.Volume);
  if (scan.Filled.Filled > 0)
  {
    std::ostringstream text;
    text << scan.Filled.Filled << " voxels without data (NaN) taken as " << scan.Filled.Value
         << " (the median of the scan) for segmentation, meshing and the preview; the texture samples them as NaN";
    warnings.push_back("read: " + text.str());
  }
  const auto size = scan.Volume->GetLargestPossibleRegion().GetSize();
  const auto spacing = scan.Volume->GetSpacing();
  const auto origin = scan.Volume->GetOrigin();
  input = { { "path", options.Input },
            { "kind", reader->GetInputKind() },
            { "modality", reader->GetModality() },
            { "pixel_type", reader->GetPixelType() },
            { "size", { size[0], size[1], size[2] } },
            { "spacing_mm", { spacing[0], spacing[1], spacing[2] } },
            { "origin_mm", { origin[0], origin[1], origin[2] } },
            { "rescale", { { "slope", reader->GetRescaleSlope() }, { "intercept", reader->GetRescaleIntercept() } } },
            { "geometry_corrections", GeometryCorrectionsJson(*reader) } };
  return scan;
}

using TexturerType = itk::ReadableTextureImageFilter<VolumeType, TextureType, MeshType>;

// The readable-texture filter set up with the tool's options.
TexturerType::Pointer
MakeTexturer(const UnwrapOptions & options, double sheetThickness, double denoisingSigma)
{
  auto texturer = TexturerType::New();
  texturer->SetPixelSize(options.PixelSize);
  texturer->SetNumberOfLayers(options.Layers);
  texturer->SetLayerSpacing(options.LayerSpacing);
  texturer->SetSheetThickness(sheetThickness);
  texturer->SetFocus(options.Focus);
  texturer->SetAutomaticSide(options.Side == "auto");
  if (options.Side != "auto")
  {
    texturer->SetLayerSide(SideFromName(options.Side));
  }
  texturer->SetSubtractCore(CoreFromName(options.SubtractCore));
  texturer->SetLayerFilter(FilterFromName(options.Filter));
  texturer->SetDenoisingSigma(denoisingSigma);
  texturer->SetMedianRadius(AutoOrLength(options.Median, "--median", -1.0));
  texturer->SetSmoothSigma(AutoOrLength(options.Smooth, "--smooth", -1.0));
  texturer->SetRestoreFWHM(RestoreFWHM(options.Restore));
  return texturer;
}

// The per-vertex texture (surface.vtp): the chosen side with the same filter, without core
// subtraction or denoising.
std::vector<float>
VertexTexture(MeshType * surfaceMesh, const VolumeType * volume, const TexturerType & texturer)
{
  const itk::ReadableTextureSelection & selection = texturer.GetSelection();
  auto perVertex = itk::LayeredTextureMeshFilter<MeshType, VolumeType, MeshType>::New();
  perVertex->SetInput(surfaceMesh);
  perVertex->SetVolume(volume);
  perVertex->SetNumberOfLayers(selection.VertexLayers);
  perVertex->SetLayerSpacing(texturer.GetAppliedLayerSpacing());
  perVertex->SetFocus(selection.Depth);
  perVertex->SetLayerSide(selection.VertexSide);
  perVertex->SetLayerFilter(selection.VertexFilter);
  perVertex->Update();
  std::vector<float> values(surfaceMesh->GetNumberOfPoints(), 0.0f);
  for (auto it = perVertex->GetOutput()->GetPointData()->Begin(); it != perVertex->GetOutput()->GetPointData()->End();
       ++it)
  {
    if (it.Index() < values.size())
    {
      values[it.Index()] = it.Value();
    }
  }
  return values;
}

// What the tool writes besides the report, as written (rows top-down), but for the layer
// stack, which is flipped to that order as its file is written, on the writer's thread.
struct Results
{
  itk::SheetMesh           Surface, Flat;
  std::vector<float>       VertexTexture;
  TextureType::Pointer     Texture, Display;
  Texture8Type::Pointer    Texture8;
  TextureMaskType::Pointer Mask;
  LayerStackType::Pointer  Layers;
  VolumeType::Pointer      Preview;
};

// The files of one sheet's results.
const char * const OneSheetFiles[] = { "texture.png", "texture.tif", "layers.tif", "mask.png",   "surface.obj",
                                       "surface.vtp", "flat.obj",    "flat.mtl",   "preview.png" };

void
WriteResults(const Results & results, const TexturerType & texturer, OutputStaging & output, const fs::path & staging)
{
  const auto textureSize = results.Texture->GetLargestPossibleRegion().GetSize();
  {
    // Images at their raw size (PNG and TIFF seldom exceed it), text meshes at ~60 bytes a
    // point and ~40 a triangle, the preview and the report.
    const std::uintmax_t pixels = textureSize[0] * textureSize[1];
    const std::uintmax_t layerCountInStack =
      results.Layers->GetLargestPossibleRegion().GetNumberOfPixels() / std::max<std::uintmax_t>(1, pixels);
    const auto &         surface = results.Surface;
    const auto &         flat = results.Flat;
    const std::uintmax_t meshBytes = 2 * (60 * surface.GetNumberOfPoints() + 40 * surface.GetNumberOfTriangles()) +
                                     (60 * flat.GetNumberOfPoints() + 40 * flat.GetNumberOfTriangles());
    output.RequireSpace(pixels * (4 + 1 + 1 + 4 * layerCountInStack) + meshBytes + (8u << 20));
  }
  // The TIFF files (the layer stack is the largest output) on a second thread while the rest
  // is written, given two threads or more.
  auto writeTiffs = [&]() {
    WriteImageFile(results.Texture.GetPointer(), staging / "texture.tif");
    // Flipped in its own buffer: nothing reads the stack after it is written.
    WriteImageFile(FlipRowsInPlace(results.Layers.GetPointer()).GetPointer(), staging / "layers.tif");
  };
  std::future<void> tiffs;
  if (itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads() > 1)
  {
    tiffs = std::async(std::launch::async, writeTiffs);
  }
  else
  {
    writeTiffs();
  }
  WriteImageFile(results.Texture8.GetPointer(), staging / "texture.png");
  auto mask8 = itk::RescaleIntensityImageFilter<TextureMaskType, TextureMaskType>::New();
  mask8->SetInput(results.Mask);
  mask8->SetOutputMinimum(0);
  mask8->SetOutputMaximum(255);
  mask8->Update();
  WriteImageFile(mask8->GetOutput(), staging / "mask.png");
  WriteSheetMeshObj((staging / "surface.obj").string(), results.Surface);
  WriteSheetMeshVtp((staging / "surface.vtp").string(), results.Surface, results.VertexTexture, "texture");
  // Texture coordinates: the flat point's position in texture.png, (0, 0) bottom left.
  const auto                origin = texturer.GetOutput()->GetOrigin();
  const double              corner[2] = { origin[0], origin[1] };
  const std::vector<double> uv =
    FlatTextureCoordinates(results.Flat, corner, texturer.GetAppliedPixelSize(), textureSize[0], textureSize[1]);
  WriteSheetMeshObj((staging / "flat.obj").string(), results.Flat, uv, "texture.png");
  WritePreview(results.Preview, results.Surface, results.Texture8, staging / "preview.png");
  if (tiffs.valid())
  {
    tiffs.get();
  }
}

// Texture NCC against the true ink and OCR of the image a person looks at (texture.png's).
nlohmann::json
LegibilityJson(const GroundTruth & truth, const TextureType * texture, const TextureType * display)
{
  // The registration inside the fidelity measure warns about every empty overlap it tries;
  // those are expected while it searches.
  const bool warningsWereOn = itk::Object::GetGlobalWarningDisplay();
  itk::Object::GlobalWarningDisplayOff();
  auto fidelity = itk::TextureFidelityCalculator::New();
  fidelity->SetReference(truth.Ink);
  fidelity->SetTexture(texture);
  fidelity->Compute();
  itk::Object::SetGlobalWarningDisplay(warningsWereOn);
  nlohmann::json result = { { "texture_ncc", fidelity->GetNormalizedCrossCorrelation() },
                            { "mirrored", fidelity->GetMirrored() },
                            { "rotation_degrees", fidelity->GetRotationDegrees() },
                            { "truth_text", truth.Text } };
  // OCR that fails (tesseract missing or refusing the image) is reported, not fatal: the
  // sheet's results are written all the same.
  auto legibility = itk::TextLegibility::New();
  legibility->SetImage(display);
  legibility->SetTruthText(truth.Text);
  try
  {
    legibility->Compute();
    result["character_error_rate"] = legibility->GetCharacterErrorRate();
    result["recognized_text"] = legibility->GetRecognizedText();
    result["ocr_scale"] = legibility->GetAppliedScale();
  }
  catch (const itk::ExceptionObject & e)
  {
    result["character_error_rate"] = nullptr;
    result["ocr_error"] = OneLine(e.GetDescription());
  }
  return result;
}

using SurfaceFilterType = itk::SheetMidSurfaceMeshFilter<MaskType, MeshType>;
using SegmentationType = itk::SheetSegmentationImageFilter<VolumeType, MaskType>;

// What every sheet's unwrapping shares: the options, the scan, its segmentation, the truth
// and the clock.
struct SheetContext
{
  const UnwrapOptions &    Options;
  const Scan &             Input;
  const SegmentationType & Segmentation;
  const GroundTruth &      Truth;
  Progress &               Display;
  StageClock &             Clock;
  OutputStaging &          Output;
};

// A sheet that could not be flattened or textured (the others go on).
class SheetFailure : public UsageError
{
public:
  using UsageError::UsageError;
};

// Unroll and flatten, texture, write and measure one sheet into `folder` (inside the
// staging folder); returns its report.
nlohmann::json
UnwrapSheet(const SheetContext & context,
            SurfaceFilterType &  surfaceFilter,
            unsigned int         sheet,
            const fs::path &     folder);

nlohmann::json
UnwrapSheetOrFail(const SheetContext & context,
                  SurfaceFilterType &  surfaceFilter,
                  unsigned int         sheet,
                  const fs::path &     folder)
{
  try
  {
    return UnwrapSheet(context, surfaceFilter, sheet, folder);
  }
  catch (const SheetFailure &)
  {
    throw;
  }
  catch (const itk::ExceptionObject & e)
  {
    throw SheetFailure(e.GetDescription());
  }
}

nlohmann::json
UnwrapSheet(const SheetContext & context,
            SurfaceFilterType &  surfaceFilter,
            unsigned int         sheet,
            const fs::path &     folder)
{
  const UnwrapOptions &              options = context.Options;
  StageClock &                       clock = context.Clock;
  Progress &                         progress = context.Display;
  const itk::SheetMidSurfaceReport & meshReport = surfaceFilter.GetSheetReport(sheet);
  MeshType *                         surfaceMesh = surfaceFilter.GetSheetOutput(sheet);
  const std::string                  which =
    surfaceFilter.GetNumberOfSheets() > 1 ? "sheet " + std::to_string(sheet + 1) + ": " : std::string();
  Results results;
  results.Surface = surfaceFilter.GetSheetMesh(sheet);

  clock.Start("flatten", which + "unrolling and flattening by mass-spring simulation");
  auto flattening = itk::MassSpringFlatteningMeshFilter<MeshType>::New();
  flattening->SetInput(surfaceMesh);
  flattening->SetParameters(ResolveSimulationParameters(options.Simulation, results.Surface));
  flattening->AddObserver(itk::IterationEvent(), [&progress, &flattening](const itk::EventObject &) {
    progress.Tick(itk::ToString(flattening->GetCurrentPhase()), flattening->GetCurrentStep());
  });
  flattening->Update();
  results.Flat = itk::MeshToSheetMesh(flattening->GetOutput());
  clock.End("flatten");

  clock.Start("texture", which + "sampling the layered texture");
  auto texturer = MakeTexturer(options, meshReport.SheetThickness, context.Segmentation.GetAppliedDenoisingSigma());
  texturer->SetSurfaceMesh(surfaceMesh);
  texturer->SetFlatMesh(flattening->GetOutput());
  // Several sheets: each sampled without the others, which may touch it.
  VolumeType::Pointer volume = context.Input.Volume;
  if (surfaceFilter.GetNumberOfSheets() > 1 && surfaceFilter.GetSheetLabelImage() != nullptr &&
      surfaceFilter.GetSheetLabelImage()->GetBufferedRegion() == volume->GetBufferedRegion())
  {
    volume = itk::BlankOtherSheets(volume, surfaceFilter.GetSheetLabelImage(), static_cast<uint16_t>(sheet + 1));
  }
  texturer->SetVolume(volume);
  progress.Observe(texturer);
  texturer->Update();
  results.VertexTexture = VertexTexture(surfaceMesh, volume, *texturer);
  results.Texture = FlipRows(texturer->GetOutput());
  results.Mask = FlipRows(texturer->GetMaskOutput());
  results.Layers = texturer->GetLayerStackOutput();
  // The image to look at and to read: the texture less a border of the sheet, where the
  // mid-surface meets the sheet's ends and edges and the samples mix in air.
  const double displayBorder = AutoOrLength(options.DisplayBorder, "--display-border", meshReport.SheetThickness);
  results.Display = itk::LayerStackTexture::TrimBorder(results.Texture, displayBorder);
  try
  {
    results.Texture8 = EightBit(results.Display);
  }
  catch (const UsageError & e)
  {
    throw SheetFailure(e.what());
  }
  results.Preview = context.Input.Filled.Volume;
  clock.End("texture");

  clock.Start("write", "writing " + (folder == context.Output.Path() ? options.Output : folder.filename().string()));
  fs::create_directories(folder);
  try
  {
    WriteResults(results, *texturer, context.Output, folder);
  }
  catch (const std::bad_alloc &)
  {
    throw;
  }
  catch (const itk::ExceptionObject & e)
  {
    // A writer's own words ("error out of disk space", "Write Error") with the file.
    throw UsageError("cannot write the results into " + options.Output + ": " + e.GetDescription());
  }
  catch (const std::exception & e)
  {
    throw UsageError("cannot write the results into " + options.Output + ": " + e.what());
  }
  clock.End("write");

  // Measures: distortion, and against the ground truth when there is one.
  const itk::SheetMesh & surface = results.Surface;
  nlohmann::json         report;
  report["parameters"] = { { "mesh",
                             { { "method", itk::ToString(meshReport.Method) },
                               { "spacing_along_sheet_mm", meshReport.SpacingAlongSheet },
                               { "spacing_along_axis_mm", meshReport.SpacingAlongAxis } } },
                           { "texture", TextureParametersJson(*texturer, options, displayBorder) },
                           { "simulation", ToJson(flattening->GetParameters()) } };
  report["mesh"] = { { "points", surface.GetNumberOfPoints() },
                     { "triangles", surface.GetNumberOfTriangles() },
                     { "grid", { surface.GridRows, surface.GridColumns } },
                     { "sheet_thickness_mm", meshReport.SheetThickness },
                     { "traced_share", meshReport.TracedShare },
                     { "sheet_length_mm", meshReport.SheetLength },
                     { "minimum_curvature_radius_mm", meshReport.MinimumCurvatureRadius },
                     { "trace", TraceJson(meshReport) } };
  report["simulation"] = ToJson(flattening->GetReport());
  report["warnings"] = nlohmann::json::array();
  for (const auto & w : flattening->GetReport().Warnings)
  {
    report["warnings"].push_back("flatten: " + w);
  }
  report["distortion"] = DistortionJson(surface, results.Flat);
  const auto textureSize = results.Texture->GetLargestPossibleRegion().GetSize();
  report["texture"] = { { "size", { textureSize[0], textureSize[1] } },
                        { "sheet_pixels", texturer->GetTextureFilter()->GetNumberOfSheetPixels() },
                        { "clamped_samples", texturer->GetTextureFilter()->GetNumberOfClampedSamples() } };
  if (context.Truth.Ink)
  {
    clock.Start("score", which + "comparing with the ground truth");
    report["legibility"] = LegibilityJson(context.Truth, results.Texture, results.Display);
    if (report["legibility"].contains("ocr_error"))
    {
      report["warnings"].push_back("score: no OCR: " + report["legibility"]["ocr_error"].get<std::string>());
    }
    clock.End("score");
  }
  return report;
}

// The sheets to unwrap: every one found, or the one picked by number or seed point.
std::vector<unsigned int>
PickSheets(const CheckedOptions & checked, const SurfaceFilterType & surfaceFilter)
{
  const unsigned int found = surfaceFilter.GetNumberOfSheets();
  if (checked.HasSeedPoint)
  {
    return { surfaceFilter.FindSheetNearestTo(checked.SeedPoint) };
  }
  if (checked.Sheet > found)
  {
    throw UsageError("--sheet " + std::to_string(checked.Sheet) + ": the scan holds " + std::to_string(found) +
                     " sheet(s)");
  }
  if (checked.Sheet != 0)
  {
    return { checked.Sheet - 1 };
  }
  std::vector<unsigned int> all(found);
  std::iota(all.begin(), all.end(), 0u);
  return all;
}

// Read, segment, mesh every sheet, then unroll and flatten, texture and write each; each
// stage one of the module's filters, the results staged and moved into place when complete.
void
RunUnwrap(UnwrapOptions & options)
{
  Progress                 progress(options.Quiet, options.JsonLog);
  StageClock               clock(progress);
  nlohmann::json           report;
  std::vector<std::string> warnings;
  const CheckedOptions     checked = CheckUnwrapOptions(options);
  const GroundTruth        truth = ReadGroundTruth(options.GroundTruth);

  clock.Start("read", "reading " + options.Input);
  const Scan scan = ReadScan(options, progress, report["input"], warnings);
  clock.End("read");

  clock.Start("segment", "segmenting the sheet");
  auto segmentation = SegmentationType::New();
  segmentation->SetInput(scan.Filled.Volume);
  segmentation->SetAutomaticThreshold(!checked.FixedThreshold);
  segmentation->SetThreshold(checked.Threshold);
  progress.Observe(segmentation);
  segmentation->Update();
  clock.End("segment");

  clock.Start("mesh", "meshing the sheets' mid-surfaces");
  auto surfaceFilter = SurfaceFilterType::New();
  surfaceFilter->SetInput(segmentation->GetOutput());
  surfaceFilter->SetIntensityImage(scan.Filled.Volume);
  surfaceFilter->SetMethod(itk::SheetSurfaceMethodFromString(options.Method));
  surfaceFilter->SetSpacingAlongSheet(checked.MeshSpacing[0]);
  surfaceFilter->SetSpacingAlongAxis(checked.MeshSpacing[1]);
  surfaceFilter->EverySheetOn();
  surfaceFilter->SetMinimumSheetArea(checked.MinimumSheetArea);
  progress.Observe(surfaceFilter);
  surfaceFilter->Update();
  for (unsigned int i = 0; i < surfaceFilter->GetNumberOfSheets(); ++i)
  {
    for (const auto & w : surfaceFilter->GetSheetReport(i).Warnings)
    {
      warnings.push_back((surfaceFilter->GetNumberOfSheets() > 1 ? "mesh, sheet " + std::to_string(i + 1) + ": "
                                                                 : std::string("mesh: ")) +
                         w);
    }
  }
  const std::vector<unsigned int> sheets = PickSheets(checked, *surfaceFilter);
  clock.End("mesh");

  // Into a staging folder beside the output, moved into place when complete: an error, a
  // signal or a kill leaves the output as it was. One sheet: its files in the output
  // folder; several: a folder sheet-NN for each.
  OutputStaging      output(fs::path(options.Output), OutputStaging::Kind::Folder);
  const SheetContext context{ options, scan, *segmentation, truth, progress, clock, output };
  nlohmann::json     found = nlohmann::json::array();
  for (unsigned int i = 0; i < surfaceFilter->GetNumberOfSheets(); ++i)
  {
    found.push_back(SheetEntryJson(*surfaceFilter, i));
    found.back()["unwrapped"] = std::find(sheets.begin(), sheets.end(), i) != sheets.end();
  }
  report["sheets"] = found;
  report["dropped"] = DroppedJson(*surfaceFilter);
  nlohmann::json threshold = { { "value", segmentation->GetThreshold() }, { "automatic", !checked.FixedThreshold } };
  if (sheets.size() == 1)
  {
    report.update(UnwrapSheet(context, *surfaceFilter, sheets.front(), output.Path()));
    report["sheet"] = sheets.front() + 1;
    for (const auto & w : report["warnings"])
    {
      warnings.push_back(w.get<std::string>());
    }
  }
  else
  {
    unsigned int unwrapped = 0;
    for (unsigned int i : sheets)
    {
      char name[16];
      std::snprintf(name, sizeof(name), "sheet-%02u", i + 1);
      nlohmann::json sheetReport;
      try
      {
        sheetReport = UnwrapSheetOrFail(context, *surfaceFilter, i, output.Path() / name);
      }
      catch (const SheetFailure & e)
      {
        // One sheet that cannot be flattened or textured leaves the others: it is named.
        fs::remove_all(output.Path() / name);
        found[i]["unwrapped"] = false;
        found[i]["error"] = e.what();
        warnings.push_back("sheet " + std::to_string(i + 1) + " could not be unwrapped: " + e.what());
        continue;
      }
      ++unwrapped;
      for (const auto & w : sheetReport["warnings"])
      {
        warnings.push_back("sheet " + std::to_string(i + 1) + ", " + w.get<std::string>());
      }
      sheetReport["sheet"] = found[i];
      sheetReport["parameters"]["threshold"] = threshold;
      WriteTextFileAtomically((output.Path() / name / "report.json").string(), sheetReport.dump(2) + "\n");
      found[i]["folder"] = name;
      if (sheetReport.contains("legibility"))
      {
        found[i]["legibility"] = sheetReport["legibility"];
      }
    }
    report["sheets"] = found;
    if (unwrapped == 0)
    {
      throw UsageError("none of the " + std::to_string(sheets.size()) +
                       " sheets found could be unwrapped: " + found[sheets.front()]["error"].get<std::string>());
    }
  }
  report["parameters"]["threshold"] = threshold;
  report["stages"] = clock.Stages();
  report["warnings"] = warnings;
  report["seconds"] = clock.Seconds();
  report["peak_memory_mib"] = PeakMemoryMiB();
  WriteTextFileAtomically((output.Path() / "report.json").string(), report.dump(2) + "\n");
  RemoveOtherLayout(
    fs::path(options.Output), sheets.size() > 1, { std::begin(OneSheetFiles), std::end(OneSheetFiles) });
  output.Commit();
  progress.Finish(options.Output, report);
}
} // namespace

void
RegisterUnwrapCommand(CLI::App & app)
{
  auto * command = app.add_subcommand(
    "unwrap",
    "From a CT scan to a flat, readable image: read, segment the sheet, mesh its mid-surface, unroll and flatten it by "
    "mass-spring simulation, sample the layered texture. Writes texture.png/.tif, mask.png, layers.tif, surface.obj/"
    ".vtp, flat.obj/.mtl, preview.png and report.json into OUTDIR.");
  static UnwrapOptions options;
  command->add_option("INPUT", options.Input, "DICOM directory, TIFF stack (directory or glob), NRRD/MHA/NIfTI file")
    ->required();
  command->add_option("-o,--output", options.Output, "output directory (created; files in it are replaced)")
    ->required();
  AddReaderOptions(*command, options.Reader);
  const std::string seg = "Segmentation and mesh";
  command->add_option("--threshold", options.Threshold, "sheet threshold in the volume's units (HU), or auto (Otsu)")
    ->capture_default_str()
    ->group(seg);
  command
    ->add_option("--mesh-spacing",
                 options.MeshSpacing,
                 "mesh spacing in mm along the sheet and the roll axis (MM or S,W), or auto (from curvature and "
                 "thickness)")
    ->capture_default_str()
    ->group(seg);
  command->add_option("--method", options.Method, "mid-surface method: auto, roll or general")
    ->capture_default_str()
    ->check(CLI::IsMember({ "auto", "roll", "general" }))
    ->group(seg);
  command
    ->add_option("--sheet",
                 options.Sheet,
                 "which sheet to unwrap: all (each into OUTDIR/sheet-NN when there are several, numbered from 1 "
                 "by size) or a sheet's number")
    ->capture_default_str()
    ->group(seg);
  command->add_option("--seed-point", options.SeedPoint, "unwrap only the sheet nearest this point X,Y,Z (mm)")
    ->group(seg);
  command
    ->add_option("--minimum-sheet-area",
                 options.MinimumSheetArea,
                 "pieces of material below this area (mm^2) are counted, not unwrapped; auto: 1 % of the largest "
                 "sheet's area and at least 400 voxels")
    ->capture_default_str()
    ->group(seg);
  const std::string tex = "Texture";
  command
    ->add_option("--layers",
                 options.Layers,
                 "number of layers sampled along the normal; 0: enough to span the measured sheet thickness")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(tex);
  command->add_option("--layer-spacing", options.LayerSpacing, "distance between layers in mm; 0: half the voxel size")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(tex);
  command
    ->add_option("--side",
                 options.Side,
                 "layers on both sides of the surface, positive / negative side only, or auto: sampled on both sides, "
                 "then the whole stack or either half, whichever shows the highest ink contrast")
    ->capture_default_str()
    ->check(CLI::IsMember({ "auto", "both", "positive", "negative" }))
    ->group(tex);
  command->add_option("--filter", options.Filter, "how layers combine: mean, gaussian, max, min, median, single")
    ->capture_default_str()
    ->check(CLI::IsMember({ "mean", "gaussian", "max", "min", "median", "single" }))
    ->group(tex);
  command
    ->add_option("--subtract-core",
                 options.SubtractCore,
                 "subtract the mean of the layers within half a voxel of the surface (the sheet's core: structure "
                 "running through the sheet's depth, like fibres, cancels; ink near a face stays): yes, no, or auto: "
                 "for one-sided textures, whichever shows the higher ink contrast")
    ->capture_default_str()
    ->check(CLI::IsMember({ "auto", "yes", "no" }))
    ->group(tex);
  command
    ->add_option("--median",
                 options.Median,
                 "half-side of the square median filter denoising the texture, mm (0: none), or auto: half the voxel "
                 "size (specks smaller than the scan resolves go, edges stay), on a noisy scan the segmentation's "
                 "smoothing width")
    ->capture_default_str()
    ->group(tex);
  command
    ->add_option("--smooth",
                 options.Smooth,
                 "Gaussian sigma smoothing the texture after the median, mm (0: none), or auto: half the voxel size, "
                 "on a noisy scan the segmentation's smoothing width")
    ->capture_default_str()
    ->group(tex);
  command
    ->add_option(
      "--restore",
      options.Restore,
      "restore the texture after the median instead of the Gaussian: edge-preserving (bilateral) smoothing "
      "over one voxel, then deconvolution of the scanner's blur, given as the full width at half maximum of its "
      "PSF in mm (0: the voxels' partial volume only), or off")
    ->capture_default_str()
    ->group(tex);
  command
    ->add_option("--display-border",
                 options.DisplayBorder,
                 "border of the sheet left out of texture.png and of the OCR, mm, or auto: the measured sheet "
                 "thickness (the mid-surface meets the sheet's ends and edges there)")
    ->capture_default_str()
    ->group(tex);
  command->add_option("--focus", options.Focus, "offset of the central layer along the normal, mm")
    ->capture_default_str()
    ->group(tex);
  command->add_option("--pixel-size", options.PixelSize, "texture pixel size in mm; 0: half the voxel size")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(tex);
  AddSimulationOptions(command, options.Simulation);
  command->add_option("--ground-truth",
                      options.GroundTruth,
                      "phantom directory (virtual-unwrap phantom): report texture NCC and OCR character error rate");
  command->add_flag("-q,--quiet", options.Quiet, "no progress output");
  command->add_flag("--json", options.JsonLog, "progress as JSON lines on standard error");
  command->callback([] { RunUnwrap(options); });
}
} // namespace vu

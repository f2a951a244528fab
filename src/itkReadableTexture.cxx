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
#include "itkReadableTexture.h"
#include "itkLayerStackTexture.h"
#include "itkMacro.h"
#include "itkMultiThreaderBase.h"
#include "vuCombineLayers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace itk {
namespace {
using SideEnum = TextureLayersEnums::Side;
using TextureType = LayerStackTexture::TextureType;
// Restoration: bilateral range as a multiple of the background's spread, Tikhonov
// regularization relative to the PSF's unit gain.
constexpr double RestoreRangeFactor = 2.0;
constexpr double RestoreRegularization = 0.1;

// Where the sheet is not on the mid-surface the focal slabs cannot show its writing: a
// bulge the mesh does not follow leaves air at the middle layer, another sheet pressed
// against this one puts material in the outermost layers (beyond the face and its blur).
// Pixels where the middle layer, smoothed over a voxel, lies below the midpoint between
// the air (the darkest layer's median) and the sheet (the middle layer's median), or an
// outermost layer above it, are left out of the focal slabs' scores, with the pixels
// within ForeignReach voxels of them (the band-pass of the score reaches three voxels,
// six stroke sigmas of half a voxel).
constexpr double ForeignReach = 3.0;
// More than this share of the pixels off the sheet is not a local defect (turns packed
// tighter than the stack reaches, a mesh off the sheet everywhere): nothing is left out.
constexpr double ForeignShareLimit = 0.25;
// The focal slabs are read from the stack registered to the sheet, its centre found over
// this many voxels across the texture (wider than a stroke of writing).
constexpr double RegistrationSigma = 2.0;

[[noreturn]] void
Fail(const std::string & message)
{
  itkGenericExceptionMacro(<< message);
}

double
Median(const TextureType * texture)
{
  const std::vector<double> q = LayerStackTexture::Quantiles(texture, { 0.5 });
  return q.empty() ? std::numeric_limits<double>::quiet_NaN() : q.front();
}

// NaN where the sheet is off the mid-surface, or within ForeignReach voxels of such a
// pixel; 1 elsewhere; `leftOut` counts the NaN pixels. Null (and 0) where no pixel or too
// many are off.
TextureType::Pointer
OwnSheetPixels(const Image<float, 3> * stack, unsigned int layers, double voxel, size_t & leftOut)
{
  leftOut = 0;
  if (layers < 3)
  {
    return nullptr;
  }
  const auto layer = [&](unsigned int k) {
    return LayerStackTexture::Smooth(LayerStackTexture::LayerWindow(stack, k, 1), voxel);
  };
  const auto inner = layer(layers / 2), first = layer(0), last = layer(layers - 1);
  double     air = std::numeric_limits<double>::infinity();
  for (unsigned int k = 0; k < layers; ++k)
  {
    const double level = Median(LayerStackTexture::LayerWindow(stack, k, 1));
    air = std::isfinite(level) ? std::min(air, level) : air;
  }
  const double sheet = Median(inner), level = 0.5 * (air + sheet);
  if (!std::isfinite(level) || !(sheet > air))
  {
    return nullptr;
  }
  auto          off = LayerStackTexture::LayerWindow(stack, 0, 1); // a texture of the stack's size, overwritten
  float *       mark = off->GetBufferPointer();
  const size_t  n = off->GetBufferedRegion().GetNumberOfPixels();
  const float * middle = inner->GetBufferPointer();
  const float * outer[2] = { first->GetBufferPointer(), last->GetBufferPointer() };
  size_t        count = 0;
  for (size_t i = 0; i < n; ++i)
  {
    const bool displaced = (std::isfinite(middle[i]) && middle[i] < level) ||
                           (std::isfinite(outer[0][i]) && outer[0][i] > level) ||
                           (std::isfinite(outer[1][i]) && outer[1][i] > level);
    mark[i] = displaced ? 1.0f : 0.0f;
    count += displaced ? 1 : 0;
  }
  if (count == 0 || static_cast<double>(count) > ForeignShareLimit * static_cast<double>(n))
  {
    return nullptr;
  }
  // Within the reach of a displaced pixel: the support of a Gaussian of a third of it.
  const auto    near = LayerStackTexture::Smooth(off, ForeignReach * voxel / 3.0);
  const float * reach = near->GetBufferPointer();
  for (size_t i = 0; i < n; ++i)
  {
    const bool within = reach[i] > 1e-3f;
    mark[i] = within ? std::numeric_limits<float>::quiet_NaN() : 1.0f;
    leftOut += within ? 1 : 0;
  }
  return off;
}
} // namespace

unsigned int
ReadableTextureLayers(double sheetThickness, double voxel, double layerSpacing, TextureLayersEnums::Side side)
{
  if (!(voxel > 0.0) || !(layerSpacing > 0.0) || !(sheetThickness >= 0.0))
  {
    Fail("ReadableTextureLayers: the voxel size and layer spacing must be positive and the thickness not negative");
  }
  const auto reach = static_cast<unsigned int>(std::ceil((0.5 * sheetThickness + 0.5 * voxel) / layerSpacing));
  return side == SideEnum::Both ? 1 + 2 * reach : 1 + reach;
}

ReadableTextureSelection
SelectReadableTexture(const Image<float, 3> * stack, const ReadableTextureSettings & settings)
{
  if (stack == nullptr)
  {
    Fail("SelectReadableTexture: no layer stack");
  }
  const unsigned int layers = settings.NumberOfLayers;
  if (layers == 0 || stack->GetLargestPossibleRegion().GetSize()[2] != layers)
  {
    std::ostringstream text;
    text << "SelectReadableTexture: the layer stack holds " << stack->GetLargestPossibleRegion().GetSize()[2]
         << " layers, not " << layers;
    Fail(text.str());
  }
  if (settings.AutomaticSide && (settings.StackSide != SideEnum::Both || layers % 2 == 0))
  {
    Fail("SelectReadableTexture: the automatic side splits the layers at the focus: the stack must lie on both sides "
         "with an odd number of layers");
  }
  if (!(settings.Voxel > 0.0) || !(settings.LayerSpacing > 0.0))
  {
    Fail("SelectReadableTexture: the voxel size and layer spacing must be positive");
  }
  ReadableTextureSelection selection;
  const bool               restore = settings.RestoreFWHM >= 0.0;
  if (restore && settings.SmoothSigma > 0.0)
  {
    Fail("SelectReadableTexture: restoration replaces the Gaussian smoothing: leave the smoothing automatic or 0");
  }
  // A noisy scan (the segmentation smoothed it) gets a texture denoised as strongly.
  const double denoiseWidth = std::max(0.5, settings.DenoisingSigma) * settings.Voxel;
  selection.MedianRadius = settings.MedianRadius >= 0.0 ? settings.MedianRadius : denoiseWidth;
  selection.SmoothSigma = restore ? 0.0 : settings.SmoothSigma >= 0.0 ? settings.SmoothSigma : denoiseWidth;
  selection.CoreWidth = 0.5 * settings.Voxel;
  if (restore)
  {
    selection.PsfSigma = LayerStackTexture::ScanBlurSigma(settings.RestoreFWHM, settings.Voxel);
    selection.RestoreDomainSigma = settings.Voxel;
    selection.RestoreRangeFactor = RestoreRangeFactor;
    selection.RestoreRegularization = RestoreRegularization;
  }
  // Each candidate's denoising: the median, then the Gaussian or the restoration (no
  // edge-preserving step on a texture without spread, which it would leave as it is).
  const auto denoise = [&](const TextureType * combined) {
    const auto despeckled = LayerStackTexture::Median(combined, selection.MedianRadius);
    if (!restore)
    {
      return LayerStackTexture::Smooth(despeckled, selection.SmoothSigma);
    }
    const double range = RestoreRangeFactor * LayerStackTexture::NoiseSpread(despeckled);
    const auto   smoothed = range > 0.0
                              ? LayerStackTexture::EdgePreservingSmooth(despeckled, selection.RestoreDomainSigma, range)
                              : despeckled;
    return LayerStackTexture::Deconvolve(smoothed, selection.PsfSigma, RestoreRegularization);
  };

  std::vector<TextureType::Pointer> textures;
  selection.FocalSlabs = settings.AutomaticSide && settings.DenoisingSigma > 0.0;
  if (selection.FocalSlabs)
  {
    // Each pixel's layers read again about the sheet as the stack shows it, where the mesh
    // is off it (LayerStackTexture::RegisterToSheet).
    const double         strokeSigma = 0.5 * settings.Voxel;
    TextureType::Pointer shift;
    const auto registered = LayerStackTexture::RegisterToSheet(stack, RegistrationSigma * settings.Voxel, &shift);
    float *    shifts = shift->GetBufferPointer();
    for (size_t i = 0; i < shift->GetBufferedRegion().GetNumberOfPixels(); ++i)
    {
      shifts[i] = std::abs(shifts[i]);
    }
    const std::vector<double> sizes = LayerStackTexture::Quantiles(shift, { 0.5, 0.95 });
    if (sizes.size() == 2)
    {
      selection.SheetShiftMedian = sizes[0];
      selection.SheetShiftP95 = sizes[1];
    }
    const auto own = OwnSheetPixels(registered, layers, settings.Voxel, selection.PixelsLeftOut);
    for (const unsigned int count : { 3u, 5u })
    {
      for (unsigned int first = 0; first + count <= layers; ++first)
      {
        textures.push_back(denoise(LayerStackTexture::LayerWindow(registered, first, count)));
        selection.Candidates.push_back({ SideEnum::Both,
                                         false,
                                         LayerStackTexture::StrokeContrast(textures.back(), strokeSigma, own),
                                         first,
                                         count });
      }
    }
  }
  const std::vector<SideEnum> sides =
    selection.FocalSlabs     ? std::vector<SideEnum>{}
    : settings.AutomaticSide ? std::vector<SideEnum>{ SideEnum::Both, SideEnum::Positive, SideEnum::Negative }
                             : std::vector<SideEnum>{ settings.StackSide };
  using Core = TextureLayersEnums::CoreSubtraction;
  std::vector<detail::LayerCombination> combinations;
  for (const SideEnum side : sides)
  {
    const std::vector<bool> cores = settings.SubtractCore == Core::Yes ? std::vector<bool>{ true }
                                    : settings.SubtractCore == Core::No || side == SideEnum::Both
                                      ? std::vector<bool>{ false }
                                      : std::vector<bool>{ false, true };
    for (const bool core : cores)
    {
      combinations.push_back({ side, core ? selection.CoreWidth : 0.0 });
      selection.Candidates.push_back({ side, core, 0.0, 0, 0 });
    }
  }
  // The sides' textures in one pass over the stack, then each denoised.
  for (const auto & combined : detail::CombineLayers(stack,
                                                     layers,
                                                     settings.LayerSpacing,
                                                     settings.Focus,
                                                     settings.StackSide,
                                                     settings.Filter,
                                                     settings.GaussianSigma,
                                                     combinations))
  {
    textures.push_back(denoise(combined));
  }
  // The sides' scores, all at once in parallel (each a few passes over its texture).
  const size_t scored = selection.FocalSlabs ? selection.Candidates.size() : 0;
  MultiThreaderBase::New()->ParallelizeArray(
    scored,
    selection.Candidates.size(),
    [&](SizeValueType i) { selection.Candidates[i].Score = LayerStackTexture::InkContrast(textures[i]); },
    nullptr);
  if (selection.Candidates.empty())
  {
    Fail("SelectReadableTexture: no candidate texture (too few layers for a focal slab)");
  }
  // The first of the highest scores.
  for (size_t i = 1; i < selection.Candidates.size(); ++i)
  {
    if (selection.Candidates[i].Score > selection.Candidates[selection.Chosen].Score)
    {
      selection.Chosen = i;
    }
  }
  selection.Texture = textures[selection.Chosen];
  const ReadableTextureCandidate & chosen = selection.ChosenCandidate();
  // A focal slab's depth: its middle layer's offset from the stack's middle (the focus).
  selection.Depth = chosen.Count > 0 ? settings.Focus + (static_cast<double>(chosen.First) +
                                                         0.5 * (static_cast<double>(chosen.Count) - 1.0) -
                                                         0.5 * (static_cast<double>(layers) - 1.0)) *
                                                          settings.LayerSpacing
                                     : settings.Focus;
  // The per-vertex texture samples the chosen side with the same filter (a focal slab: its
  // layers' mean), without core subtraction or denoising.
  selection.VertexLayers =
    chosen.Count > 0 ? chosen.Count : (chosen.Side == settings.StackSide ? layers : (layers + 1) / 2);
  selection.VertexSide = chosen.Side;
  selection.VertexFilter = chosen.Count > 0 ? TextureLayersEnums::Filter::Mean : settings.Filter;
  return selection;
}
} // end namespace itk

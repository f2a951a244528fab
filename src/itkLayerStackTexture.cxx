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
#include "itkLayerStackTexture.h"
#include "itkBilateralImageFilter.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkGaussianImageSource.h"
#include "itkMultiThreaderBase.h"
#include "itkTikhonovDeconvolutionImageFilter.h"
#include "vuCombineLayers.h"
#include "vuFiniteRanks.h"
#include "vuValidRegion.h"
#include "vuVectorClones.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace itk {
namespace {
using TextureType = LayerStackTexture::TextureType;
using LayerStackType = LayerStackTexture::LayerStackType;

constexpr float NaN = std::numeric_limits<float>::quiet_NaN();

// The smoothing along x of one row of `columns` values (NaN weighing nothing): sums of the
// kernel's 2 rx + 1 taps times the values and times their weights, into sv and sw; v and w
// hold the row's values and weights padded with rx zeros each side.
VU_VECTOR_CLONES void
SmoothRowAlongX(const float * __restrict line,
                long columns,
                const float * __restrict kernel,
                long rx,
                float * __restrict v,
                float * __restrict w,
                float * __restrict sv,
                float * __restrict sw)
{
  for (long x = 0; x < columns; ++x)
  {
    const bool ok = std::isfinite(line[x]);
    v[x + rx] = ok ? line[x] : 0.0f;
    w[x + rx] = ok ? 1.0f : 0.0f;
  }
  std::fill(sv, sv + columns, 0.0f);
  std::fill(sw, sw + columns, 0.0f);
  for (long r = 0; r <= 2 * rx; ++r)
  {
    const float   k = kernel[r];
    const float * vr = v + r;
    const float * wr = w + r;
    for (long x = 0; x < columns; ++x)
    {
      sv[x] += k * vr[x];
      sw[x] += k * wr[x];
    }
  }
}

// Adds k times a row of values and weights to the sums sv and sw.
VU_VECTOR_CLONES void
AddWeightedRow(float k,
               const float * __restrict v,
               const float * __restrict w,
               long columns,
               float * __restrict sv,
               float * __restrict sw)
{
  for (long x = 0; x < columns; ++x)
  {
    sv[x] += k * v[x];
    sw[x] += k * w[x];
  }
}

// The normalised result of a row: sums over weights where the input is finite, else NaN.
VU_VECTOR_CLONES void
NormaliseRow(const float * __restrict line,
             const float * __restrict sv,
             const float * __restrict sw,
             long columns,
             float * __restrict target)
{
  for (long x = 0; x < columns; ++x)
  {
    target[x] = std::isfinite(line[x]) && sw[x] > 0.0f ? sv[x] / sw[x] : NaN;
  }
}

float
MedianOfThree(float a, float b, float c)
{
  return std::max(std::min(a, b), std::min(std::max(a, b), c));
}

// The 3 x 3 median of a row (columns 1 to columns - 2) from the rows above, here and below:
// each column's three values sorted once (shared by three windows), then the median of nine
// is the median of (the largest of the lows, the median of the middles, the smallest of the
// highs). A pixel's check is 0 when its window's nine values are finite (v - v is 0 for
// finite v only, NaN otherwise); low, middle, high and columnCheck are work rows.
VU_VECTOR_CLONES void
MedianOfNineRow(const float * __restrict above,
                const float * __restrict here,
                const float * __restrict below,
                long columns,
                float * __restrict low,
                float * __restrict middle,
                float * __restrict high,
                float * __restrict columnCheck,
                float * __restrict check,
                float * __restrict target)
{
  for (long c = 0; c < columns; ++c)
  {
    const float a = above[c], b = here[c], d = below[c];
    columnCheck[c] = (a - a) + (b - b) + (d - d);
    const float lo = std::min(a, b), hi = std::max(a, b);
    const float mid = std::min(hi, d);
    high[c] = std::max(hi, d);
    low[c] = std::min(lo, mid);
    middle[c] = std::max(lo, mid);
  }
  for (long x = 1; x + 1 < columns; ++x)
  {
    check[x] = columnCheck[x - 1] + columnCheck[x] + columnCheck[x + 1];
    target[x] = MedianOfThree(std::max(std::max(low[x - 1], low[x]), low[x + 1]),
                              MedianOfThree(middle[x - 1], middle[x], middle[x + 1]),
                              std::min(std::min(high[x - 1], high[x]), high[x + 1]));
  }
}

// An empty texture with the geometry of `like` (2D), or of the first two axes of a stack.
TextureType::Pointer
NewTexture(const TextureType * like)
{
  auto texture = TextureType::New();
  texture->CopyInformation(like);
  texture->SetRegions(like->GetBufferedRegion());
  texture->Allocate();
  return texture;
}

// The ranks of a texture's finite pixels.
detail::FiniteRanks
TextureRanks(const TextureType * texture)
{
  return detail::FiniteRanks(texture->GetBufferPointer(), texture->GetBufferedRegion().GetNumberOfPixels());
}

// The display's black point lies this many noise spreads above the background's median
// (DisplayWindow).
constexpr double BackgroundClip = 0.5;

// ClearBackground: ink is what lies beyond the background by InkSpreads noise spreads and
// connects to a pixel beyond InkCoreSpreads (Gaussian noise passes 4.5 spreads about 3
// times in a million pixels).
constexpr double InkSpreads = 1.0;
constexpr double InkCoreSpreads = 4.5;
// ClearBackground: a component that reaches no core pixel is ink when its mass exceeds the
// heaviest noise blob's on the other side of the background and its box is at most this
// many times the median height, and width, of the components that reach a core pixel (a
// faint letter is the size of the others; a bright band across a roll's sheet, heavier
// than any blob of the noise, is not).
constexpr double InkBoxOverCores = 1.5;
// ... or when it is a few faint letters run together along a line (the lines run along the
// texture's longer side, the sheet's length): across the line, between this share and
// InkBoxOverCores of the letters' height (a thin band along the sheet is not a line), and
// along it at most InkRunHeights of that height. (The strong letters' own box tells no
// direction: where they join into words it is wider than tall.)
constexpr double InkRunHeightShare = 0.5;
constexpr double InkRunHeights = 4.0;

// StrokeContrast's blocks: at least this many pixels long, scored when at least this share
// of their pixels is on the sheet.
constexpr size_t StrokeBlockMinimum = 64;
// StrokeContrast's rank within a block: strokes cover more of a block than a blot does.
constexpr double StrokeQuantile = 0.96;
constexpr double StrokeBlockFiniteShare = 0.25;

// 1.4826 x the median absolute deviation of the ranked values from their `median`.
double
Spread(const detail::FiniteRanks & ranks, double median)
{
  return 1.4826 * ranks.Deviations(static_cast<float>(median)).Quantile(0.5);
}

// A copy of `texture` whose NaN pixels hold `fill`, and which pixels were NaN.
TextureType::Pointer
FilledCopy(const TextureType * texture, float fill, std::vector<bool> & wasNaN)
{
  auto          copy = NewTexture(texture);
  const size_t  n = texture->GetBufferedRegion().GetNumberOfPixels();
  const float * in = texture->GetBufferPointer();
  float *       out = copy->GetBufferPointer();
  wasNaN.assign(n, false);
  for (size_t k = 0; k < n; ++k)
  {
    wasNaN[k] = !std::isfinite(in[k]);
    out[k] = wasNaN[k] ? fill : in[k];
  }
  return copy;
}

// `result` (same grid as the input) with the input's NaN pixels NaN again.
void
RestoreNaN(TextureType * result, const std::vector<bool> & wasNaN)
{
  float * out = result->GetBufferPointer();
  for (size_t k = 0; k < wasNaN.size(); ++k)
  {
    if (wasNaN[k])
    {
      out[k] = NaN;
    }
  }
}

// Runs `filter`, an ITK filter of textures set up but for its input, on `texture` with
// its NaN pixels holding `fill`; those pixels are NaN again in the result.
template <typename TFilter>
TextureType::Pointer
RunFilled(TFilter * filter, const TextureType * texture, float fill)
{
  std::vector<bool> wasNaN;
  filter->SetInput(FilledCopy(texture, fill, wasNaN));
  filter->Update();
  TextureType::Pointer result = filter->GetOutput();
  result->DisconnectPipeline();
  RestoreNaN(result, wasNaN);
  return result;
}

void
CheckTexture(const TextureType * texture, const char * function)
{
  if (texture == nullptr)
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::" << function << ": no texture");
  }
  if (texture->GetBufferedRegion() != texture->GetLargestPossibleRegion())
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::" << function << ": the texture is not fully buffered");
  }
}

// Checks the texture and a length of `function` named `what` (physical units; 0 allowed).
void
CheckTextureAndLength(const TextureType * texture, double length, const char * function, const char * what)
{
  CheckTexture(texture, function);
  detail::CheckLayerParameter(length, true, function, what);
}

// `statistic` of the ranks of a checked texture's finite pixels; 0 when fewer than 2 are
// finite.
template <typename TStatistic>
double
FiniteStatistic(const TextureType * texture, const char * function, TStatistic statistic)
{
  CheckTexture(texture, function);
  const detail::FiniteRanks ranks = TextureRanks(texture);
  if (ranks.GetCount() < 2)
  {
    return 0.0;
  }
  return statistic(ranks);
}
} // namespace

namespace detail {
Image<float, 2>::Pointer
NewLayerTexture(const Image<float, 3> * stack)
{
  const auto                 size = stack->GetBufferedRegion().GetSize();
  auto                       texture = Image<float, 2>::New();
  Image<float, 2>::SizeType  textureSize = { { size[0], size[1] } };
  Image<float, 2>::PointType origin;
  origin[0] = stack->GetOrigin()[0];
  origin[1] = stack->GetOrigin()[1];
  Image<float, 2>::SpacingType spacing;
  spacing[0] = stack->GetSpacing()[0];
  spacing[1] = stack->GetSpacing()[1];
  texture->SetRegions(textureSize);
  texture->SetOrigin(origin);
  texture->SetSpacing(spacing);
  texture->Allocate();
  return texture;
}

void
CheckLayerParameter(double value, bool zeroAllowed, const char * function, const char * what)
{
  if (!std::isfinite(value) || value < 0.0 || (!zeroAllowed && value == 0.0))
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::" << function << ": " << what << " must be "
                             << (zeroAllowed ? ">= 0" : "> 0") << " and finite, got " << value);
  }
}

} // namespace detail

LayerStackTexture::TextureType::Pointer
LayerStackTexture::Combine(const LayerStackType * stack,
                           unsigned int           numberOfLayers,
                           double                 layerSpacing,
                           double                 focus,
                           SideType               stackSide,
                           SideType               side,
                           FilterType             filter,
                           double                 gaussianSigma,
                           double                 coreWidth)
{
  return detail::CombineLayers(
           stack, numberOfLayers, layerSpacing, focus, stackSide, filter, gaussianSigma, { { side, coreWidth } })
    .front();
}

double
LayerStackTexture::InkContrast(const TextureType * texture)
{
  return FiniteStatistic(texture, "InkContrast", [](const detail::FiniteRanks & ranks) {
    const auto   values = ranks.Quantiles({ 0.99, 0.5 });
    const double top = values[0], median = values[1];
    const double spread = Spread(ranks, median);
    return spread > 0.0 ? (top - median) / spread : 0.0;
  });
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::LayerWindow(const LayerStackType * stack, unsigned int first, unsigned int count)
{
  if (stack == nullptr)
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::LayerWindow: no layer stack");
  }
  const auto size = stack->GetBufferedRegion().GetSize();
  if (stack->GetBufferedRegion() != stack->GetLargestPossibleRegion() || count == 0 ||
      static_cast<SizeValueType>(first) + count > size[2])
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::LayerWindow: layers " << first << " to "
                             << static_cast<SizeValueType>(first) + count - 1 << " are not in a stack of " << size[2]
                             << " layers, or the stack is not fully buffered");
  }
  auto                texture = detail::NewLayerTexture(stack);
  const float *       in = stack->GetBufferPointer();
  float *             out = texture->GetBufferPointer();
  const SizeValueType plane = size[0] * size[1];
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      for (SizeValueType i = row * size[0]; i < (row + 1) * size[0]; ++i)
      {
        double sum = 0.0;
        int    finite = 0;
        for (unsigned int k = first; k < first + count; ++k)
        {
          const float v = in[k * plane + i];
          if (std::isfinite(v))
          {
            sum += v;
            ++finite;
          }
        }
        out[i] = finite > 0 ? static_cast<float>(sum / finite) : NaN;
      }
    },
    nullptr);
  return texture;
}

double
LayerStackTexture::StrokeContrast(const TextureType * texture, double strokeSigma, const TextureType * leaveOut)
{
  CheckTexture(texture, "StrokeContrast");
  detail::CheckLayerParameter(strokeSigma, false, "StrokeContrast", "the stroke sigma");
  if (leaveOut != nullptr && leaveOut->GetBufferedRegion().GetSize() != texture->GetBufferedRegion().GetSize())
  {
    itkGenericExceptionMacro(
      << "LayerStackTexture::StrokeContrast: the pixels to leave out are not the texture's size");
  }
  const float * keep = leaveOut != nullptr ? leaveOut->GetBufferPointer() : nullptr;
  const auto    fine = Smooth(texture, strokeSigma);
  const auto    coarse = Smooth(texture, 6.0 * strokeSigma);
  auto          band = NewTexture(texture);
  const float * f = fine->GetBufferPointer();
  const float * c = coarse->GetBufferPointer();
  float *       b = band->GetBufferPointer();
  const size_t  n = texture->GetBufferedRegion().GetNumberOfPixels();
  for (size_t i = 0; i < n; ++i)
  {
    b[i] = std::isfinite(f[i]) && std::isfinite(c[i]) ? f[i] - c[i] : NaN;
  }
  // The band-pass rings where the sheet ends: that border, as wide as the coarse
  // Gaussian's reach, takes no part in the score, nor do the pixels left out (which carry
  // their own reach).
  const auto scored = TrimBorder(band, 6.0 * strokeSigma);
  float *    v = scored->GetBufferPointer();
  for (size_t i = 0; keep != nullptr && i < n; ++i)
  {
    v[i] = std::isfinite(keep[i]) ? v[i] : NaN;
  }
  const detail::FiniteRanks ranks = TextureRanks(scored);
  if (ranks.GetCount() < 2)
  {
    return 0.0;
  }
  const double median = ranks.Quantile(0.5), spread = Spread(ranks, median);
  if (!(spread > 0.0))
  {
    return 0.0;
  }
  // Blocks along the texture's longer side, as long as its shorter side, overlapping by
  // half: the brightest 4 % (StrokeQuantile) of the block richest in strokes over the
  // whole texture's spread. Writing that covers a few per cent of a long sheet fills its
  // blocks' top 4 %, where over the whole texture it would not reach that rank; a compact
  // blot fills its block's top percent but not its top 4 %.
  const auto         size = scored->GetBufferedRegion().GetSize();
  const bool         alongX = size[0] >= size[1];
  const size_t       length = alongX ? size[0] : size[1], across = alongX ? size[1] : size[0];
  const size_t       block = std::max<size_t>(across, StrokeBlockMinimum), step = std::max<size_t>(1, block / 2);
  double             best = 0.0;
  std::vector<float> values;
  for (size_t start = 0; start < length; start += step)
  {
    const size_t end = std::min(length, start + block);
    values.clear();
    for (size_t a = start; a < end; ++a)
    {
      for (size_t k = 0; k < across; ++k)
      {
        const float x = alongX ? v[k * size[0] + a] : v[a * size[0] + k];
        if (std::isfinite(x))
        {
          values.push_back(x);
        }
      }
    }
    if (static_cast<double>(values.size()) >= StrokeBlockFiniteShare * static_cast<double>(block * across))
    {
      const auto top =
        values.begin() + static_cast<std::ptrdiff_t>(StrokeQuantile * static_cast<double>(values.size() - 1));
      std::nth_element(values.begin(), top, values.end());
      best = std::max(best, (static_cast<double>(*top) - median) / spread);
    }
    if (end == length)
    {
      break;
    }
  }
  return best > 0.0 ? best : (ranks.Quantile(0.99) - median) / spread;
}

std::vector<double>
LayerStackTexture::DisplayWindow(const TextureType * texture, bool inkIsBright)
{
  CheckTexture(texture, "DisplayWindow");
  const detail::FiniteRanks ranks = TextureRanks(texture);
  if (ranks.GetCount() == 0)
  {
    return {};
  }
  const std::vector<float> q = ranks.Quantiles({ 0.005, 0.5, 0.995 });
  const double             low = q[0], median = q[1], high = q[2];
  const double             clip = BackgroundClip * Spread(ranks, median);
  const double             black = inkIsBright ? std::max(low, median + clip) : low;
  const double             white = inkIsBright ? high : std::min(high, median - clip);
  if (white > black)
  {
    return { black, white };
  }
  return { low, std::max(high, low + 1e-6) };
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::ClearBackground(const TextureType * texture, bool inkIsBright)
{
  CheckTexture(texture, "ClearBackground");
  auto          result = NewTexture(texture);
  const float * in = texture->GetBufferPointer();
  float *       out = result->GetBufferPointer();
  const size_t  n = texture->GetBufferedRegion().GetNumberOfPixels();
  std::copy(in, in + n, out);
  const detail::FiniteRanks ranks = TextureRanks(texture);
  if (ranks.GetCount() < 2)
  {
    return result;
  }
  const double median = ranks.Quantile(0.5), spread = Spread(ranks, median);
  if (!(spread > 0.0))
  {
    return result;
  }
  // Beyond the background in the ink's direction, in noise spreads (NaN: not at all).
  const double sign = inkIsBright ? 1.0 : -1.0;
  using MaskType = Image<unsigned char, 2>;
  const auto mask = [&](double side, double spreads) {
    auto image = MaskType::New();
    image->CopyInformation(texture);
    image->SetRegions(texture->GetBufferedRegion());
    image->Allocate();
    std::transform(in, in + n, image->GetBufferPointer(), [&](float v) {
      return std::isfinite(v) && side * (v - median) > spreads * spread ? 1 : 0;
    });
    return image;
  };
  // Components of the pixels beyond the background by InkSpreads in direction `side`
  // (8 neighbours): for each (from label 1), its peak and its mass, the sum of its pixels'
  // excess over InkSpreads, in spreads.
  using LabelType = Image<uint32_t, 2>;
  struct Components
  {
    LabelType::Pointer  Labels;
    std::vector<double> Peak, Mass;
    std::vector<long>   Low[2], High[2];
  };
  const auto components = [&](double side) {
    auto label = ConnectedComponentImageFilter<MaskType, LabelType>::New();
    label->SetInput(mask(side, InkSpreads));
    label->FullyConnectedOn();
    label->Update();
    Components c;
    c.Labels = label->GetOutput();
    const size_t count = label->GetObjectCount();
    c.Peak.assign(count + 1, 0.0);
    c.Mass.assign(count + 1, 0.0);
    for (unsigned d = 0; d < 2; ++d)
    {
      c.Low[d].assign(count + 1, std::numeric_limits<long>::max());
      c.High[d].assign(count + 1, std::numeric_limits<long>::min());
    }
    const uint32_t * labels = c.Labels->GetBufferPointer();
    const auto       columns = static_cast<size_t>(texture->GetBufferedRegion().GetSize(0));
    for (size_t k = 0; k < n; ++k)
    {
      const uint32_t l = labels[k];
      if (l != 0)
      {
        const double excess = side * (in[k] - median) / spread;
        c.Peak[l] = std::max(c.Peak[l], excess);
        c.Mass[l] += excess - InkSpreads;
        const long at[2] = { static_cast<long>(k % columns), static_cast<long>(k / columns) };
        for (unsigned d = 0; d < 2; ++d)
        {
          c.Low[d][l] = std::min(c.Low[d][l], at[d]);
          c.High[d][l] = std::max(c.High[d][l], at[d]);
        }
      }
    }
    return c;
  };
  const Components bright = components(sign);
  if (std::none_of(bright.Peak.begin(), bright.Peak.end(), [](double peak) { return peak > InkCoreSpreads; }))
  {
    return result;
  }
  // The noise makes blobs on both sides of the background alike, the ink on one side only:
  // a component whose mass exceeds every such component's on the other side, and whose box is
  // about the size of the strong ink's, is ink too (a faint letter that nowhere reaches the
  // core's level); over a long sheet the noise's heaviest blob sets that bar high, over a
  // small page low.
  const Components dark = components(-sign);
  // Only the blobs within the noise's reach count (a dark blot past the core's level, where a
  // touching page was blanked, is no measure of the noise).
  double darkMass = 0.0;
  for (size_t l = 1; l < dark.Mass.size(); ++l)
  {
    darkMass = dark.Peak[l] <= InkCoreSpreads ? std::max(darkMass, dark.Mass[l]) : darkMass;
  }
  const size_t count = bright.Peak.size();
  const auto   extent = [&bright](size_t l, unsigned d) {
    return static_cast<double>(bright.High[d][l] - bright.Low[d][l] + 1);
  };
  // The strong ink's size: the median box of the components that reach the core (a band or
  // blot that reaches it too does not set the size).
  double coreExtent[2] = { 0.0, 0.0 };
  for (unsigned d = 0; d < 2; ++d)
  {
    std::vector<double> extents;
    for (size_t l = 1; l < count; ++l)
    {
      if (bright.Peak[l] > InkCoreSpreads)
      {
        extents.push_back(extent(l, d));
      }
    }
    std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
    coreExtent[d] = extents[extents.size() / 2];
  }
  const auto           size = texture->GetBufferedRegion().GetSize();
  const unsigned       along = size[0] >= size[1] ? 0 : 1, across = 1 - along;
  std::vector<uint8_t> keep(count, 0);
  for (size_t l = 1; l < count; ++l)
  {
    const bool letterSized =
      extent(l, 0) <= InkBoxOverCores * coreExtent[0] && extent(l, 1) <= InkBoxOverCores * coreExtent[1];
    const bool letterRun = extent(l, across) >= InkRunHeightShare * coreExtent[across] &&
                           extent(l, across) <= InkBoxOverCores * coreExtent[across] &&
                           extent(l, along) <= InkRunHeights * coreExtent[across];
    keep[l] = bright.Peak[l] > InkCoreSpreads || (bright.Mass[l] > darkMass && (letterSized || letterRun)) ? 1 : 0;
  }
  const uint32_t * labels = bright.Labels->GetBufferPointer();
  const auto       background = static_cast<float>(median);
  for (size_t k = 0; k < n; ++k)
  {
    out[k] = std::isfinite(in[k]) && keep[labels[k]] == 0 ? background : in[k];
  }
  return result;
}

double
LayerStackTexture::NoiseSpread(const TextureType * texture)
{
  return FiniteStatistic(
    texture, "NoiseSpread", [](const detail::FiniteRanks & ranks) { return Spread(ranks, ranks.Quantile(0.5)); });
}

std::vector<double>
LayerStackTexture::Quantiles(const TextureType * texture, const std::vector<double> & q)
{
  CheckTexture(texture, "Quantiles");
  for (const double p : q)
  {
    if (!(p >= 0.0 && p <= 1.0))
    {
      itkGenericExceptionMacro(<< "LayerStackTexture::Quantiles: a rank must lie in 0..1, got " << p);
    }
  }
  const detail::FiniteRanks ranks = TextureRanks(texture);
  if (ranks.GetCount() == 0)
  {
    return {};
  }
  const std::vector<float> values = ranks.Quantiles(q);
  return { values.begin(), values.end() };
}

LayerStackTexture::LayerStackType::Pointer
LayerStackTexture::RegisterToSheet(const LayerStackType * stack, double sigma, TextureType::Pointer * shift)
{
  if (stack == nullptr || stack->GetBufferedRegion() != stack->GetLargestPossibleRegion())
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::RegisterToSheet: no layer stack, or it is not fully buffered");
  }
  if (!(sigma >= 0.0) || !std::isfinite(sigma))
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::RegisterToSheet: sigma must be finite and not negative, not "
                             << sigma);
  }
  const auto          size = stack->GetBufferedRegion().GetSize();
  const auto          layers = static_cast<unsigned int>(size[2]);
  const SizeValueType plane = size[0] * size[1];
  auto                result = LayerStackType::New();
  result->CopyInformation(stack);
  result->SetRegions(stack->GetBufferedRegion());
  result->Allocate();
  const float * in = stack->GetBufferPointer();
  float *       out = result->GetBufferPointer();
  std::copy(in, in + plane * layers, out);
  if (shift != nullptr)
  {
    *shift = detail::NewLayerTexture(stack);
    std::fill((*shift)->GetBufferPointer(), (*shift)->GetBufferPointer() + plane, NaN);
  }
  if (layers < 3)
  {
    return result;
  }
  // Air: the darkest layer's median; sheet: the middle layer's.
  double air = std::numeric_limits<double>::infinity();
  for (unsigned int k = 0; k < layers; ++k)
  {
    const std::vector<double> q = Quantiles(LayerWindow(stack, k, 1), { 0.5 });
    air = q.empty() ? air : std::min(air, q.front());
  }
  const std::vector<double> middle = Quantiles(LayerWindow(stack, layers / 2, 1), { 0.5 });
  if (middle.empty() || !std::isfinite(air) || !(middle.front() > air))
  {
    return result;
  }
  const auto level = static_cast<float>(0.5 * (air + middle.front()));
  // The centroid of the excess over the level, layer by layer into two sums.
  auto    centre = LayerWindow(stack, 0, 1), mass = LayerWindow(stack, 0, 1); // overwritten
  float * moment = centre->GetBufferPointer();
  float * total = mass->GetBufferPointer();
  std::fill(moment, moment + plane, 0.0f);
  std::fill(total, total + plane, 0.0f);
  for (unsigned int k = 0; k < layers; ++k)
  {
    const auto    smooth = Smooth(LayerWindow(stack, k, 1), sigma);
    const float * v = smooth->GetBufferPointer();
    for (SizeValueType i = 0; i < plane; ++i)
    {
      const float excess = std::isfinite(v[i]) ? std::max(0.0f, v[i] - level) : 0.0f;
      total[i] += excess;
      moment[i] += excess * static_cast<float>(k);
    }
  }
  for (SizeValueType i = 0; i < plane; ++i)
  {
    moment[i] = total[i] > 0.0f ? moment[i] / total[i] : NaN;
  }
  centre = Smooth(centre, 0.25 * sigma);
  const std::vector<double> typical = Quantiles(centre, { 0.5 });
  if (typical.empty())
  {
    return result;
  }
  const float * c = centre->GetBufferPointer();
  const auto    last = static_cast<float>(layers - 1);
  float *       shifted = shift != nullptr ? (*shift)->GetBufferPointer() : nullptr;
  const auto    depthSpacing = static_cast<float>(stack->GetSpacing()[2]);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      for (SizeValueType i = row * size[0]; i < (row + 1) * size[0]; ++i)
      {
        if (!std::isfinite(c[i]))
        {
          continue;
        }
        const auto offset = static_cast<float>(c[i] - typical.front());
        if (shifted != nullptr)
        {
          shifted[i] = offset * depthSpacing;
        }
        for (unsigned int k = 0; k < layers; ++k)
        {
          const float at = std::clamp(static_cast<float>(k) + offset, 0.0f, last);
          const auto  below = static_cast<unsigned int>(std::floor(at));
          const auto  above = std::min(below + 1, layers - 1);
          const float t = at - static_cast<float>(below);
          const float a = in[below * plane + i], b = in[above * plane + i];
          out[k * plane + i] = !std::isfinite(a) ? (t > 0.0f ? b : a) : !std::isfinite(b) ? a : a + t * (b - a);
        }
      }
    },
    nullptr);
  return result;
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::Smooth(const TextureType * texture, double sigma)
{
  CheckTextureAndLength(texture, sigma, "Smooth", "sigma");
  auto          result = NewTexture(texture);
  const auto    size = texture->GetBufferedRegion().GetSize();
  const size_t  n = texture->GetBufferedRegion().GetNumberOfPixels();
  const float * in = texture->GetBufferPointer();
  float *       out = result->GetBufferPointer();
  if (sigma == 0.0)
  {
    std::copy(in, in + n, out);
    return result;
  }
  // Normalised convolution: the weighted sum of the finite values over the sum of their
  // weights, separably: along x row by row, then along y, each output row a weighted sum of
  // whole rows (in single precision).
  const auto columns = static_cast<long>(size[0]), rows = static_cast<long>(size[1]);
  const auto kernel = [&](unsigned int d) {
    const double       s = sigma / texture->GetSpacing()[d];
    const long         radius = std::max(1L, static_cast<long>(std::ceil(3.0 * s)));
    std::vector<float> k(2 * radius + 1);
    for (long r = -radius; r <= radius; ++r)
    {
      k[r + radius] = static_cast<float>(std::exp(-0.5 * r * r / (s * s)));
    }
    return k;
  };
  const std::vector<float> kx = kernel(0), ky = kernel(1);
  const long               rx = static_cast<long>(kx.size() / 2), ry = static_cast<long>(ky.size() / 2);
  // Bands of rows in parallel, each smoothing along x the rows it reads (its own and ry
  // either side, which the next band smooths again) into buffers small enough to stay in
  // the cache, then along y.
  constexpr long BandRows = 32;
  const long     bands = (rows + BandRows - 1) / BandRows;
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    static_cast<SizeValueType>(bands),
    [&](SizeValueType band) {
      const long first = static_cast<long>(band) * BandRows, last = std::min(rows, first + BandRows);
      const long readFirst = std::max(0L, first - ry), readLast = std::min(rows, last + ry);
      // The x sums of rows readFirst..readLast; a row's values and weights padded with rx
      // zeros each side, each tap added to the whole row at once.
      std::vector<float> value((readLast - readFirst) * columns), weight((readLast - readFirst) * columns);
      std::vector<float> v(columns + 2 * rx, 0.0f), w(columns + 2 * rx, 0.0f);
      for (long y = readFirst; y < readLast; ++y)
      {
        SmoothRowAlongX(in + y * columns,
                        columns,
                        kx.data(),
                        rx,
                        v.data(),
                        w.data(),
                        &value[(y - readFirst) * columns],
                        &weight[(y - readFirst) * columns]);
      }
      std::vector<float> sv(columns), sw(columns);
      for (long y = first; y < last; ++y)
      {
        std::fill(sv.begin(), sv.end(), 0.0f);
        std::fill(sw.begin(), sw.end(), 0.0f);
        for (long r = std::max(-ry, -y); r <= std::min(ry, rows - 1 - y); ++r)
        {
          AddWeightedRow(ky[r + ry],
                         &value[(y + r - readFirst) * columns],
                         &weight[(y + r - readFirst) * columns],
                         columns,
                         sv.data(),
                         sw.data());
        }
        NormaliseRow(in + y * columns, sv.data(), sw.data(), columns, out + y * columns);
      }
    },
    nullptr);
  return result;
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::Median(const TextureType * texture, double radius)
{
  CheckTextureAndLength(texture, radius, "Median", "the radius");
  auto          result = NewTexture(texture);
  const auto    size = texture->GetBufferedRegion().GetSize();
  const float * in = texture->GetBufferPointer();
  float *       out = result->GetBufferPointer();
  long          half[2];
  for (unsigned int d = 0; d < 2; ++d)
  {
    half[d] = std::lround(radius / texture->GetSpacing()[d]);
  }
  // Rows in parallel; a small window (3 x 3 or 5 x 5, the usual radii) is sorted by
  // insertion, which for so few values is several times faster than a selection.
  const size_t windowSize = static_cast<size_t>((2 * half[0] + 1) * (2 * half[1] + 1));
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      const auto         y = static_cast<long>(row);
      const auto         columns = static_cast<long>(size[0]);
      std::vector<float> window(windowSize);
      // A 3 x 3 window away from the border and from pixels off the sheet: whole rows at a
      // time by minima and maxima (MedianOfNineRow; a pixel is done there when its check is
      // 0), then the other pixels one by one.
      const bool         threeByThree = half[0] == 1 && half[1] == 1 && y > 0 && y + 1 < static_cast<long>(size[1]);
      std::vector<float> checkRow(columns, NaN);
      if (threeByThree)
      {
        std::vector<float> lowRow(columns), middleRow(columns), highRow(columns), columnCheckRow(columns);
        MedianOfNineRow(in + (y - 1) * columns,
                        in + y * columns,
                        in + (y + 1) * columns,
                        columns,
                        lowRow.data(),
                        middleRow.data(),
                        highRow.data(),
                        columnCheckRow.data(),
                        checkRow.data(),
                        out + y * columns);
      }
      for (long x = 0; x < columns; ++x)
      {
        if (checkRow[x] == 0.0f)
        {
          continue;
        }
        const float centre = in[y * size[0] + x];
        if (!std::isfinite(centre))
        {
          out[y * size[0] + x] = centre;
          continue;
        }
        size_t count = 0;
        for (long v = std::max(0L, y - half[1]); v <= std::min<long>(size[1] - 1, y + half[1]); ++v)
        {
          for (long u = std::max(0L, x - half[0]); u <= std::min<long>(size[0] - 1, x + half[0]); ++u)
          {
            const float value = in[v * size[0] + u];
            if (std::isfinite(value))
            {
              window[count++] = value;
            }
          }
        }
        // An even count takes the mean of the two middle values.
        const auto middle = window.begin() + static_cast<long>(count / 2);
        float      median;
        if (count <= 25)
        {
          for (size_t i = 1; i < count; ++i)
          {
            const float value = window[i];
            size_t      j = i;
            for (; j > 0 && window[j - 1] > value; --j)
            {
              window[j] = window[j - 1];
            }
            window[j] = value;
          }
          median = count % 2 == 0 ? 0.5f * (*middle + *(middle - 1)) : *middle;
        }
        else
        {
          std::nth_element(window.begin(), middle, window.begin() + static_cast<long>(count));
          median = *middle;
          if (count % 2 == 0)
          {
            median = 0.5f * (median + *std::max_element(window.begin(), middle));
          }
        }
        out[y * size[0] + x] = median;
      }
    },
    nullptr);
  return result;
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::EdgePreservingSmooth(const TextureType * texture, double domainSigma, double rangeSigma)
{
  CheckTextureAndLength(texture, domainSigma, "EdgePreservingSmooth", "the domain sigma");
  detail::CheckLayerParameter(rangeSigma, false, "EdgePreservingSmooth", "the range sigma");
  const float * begin = texture->GetBufferPointer();
  const float * end = begin + texture->GetBufferedRegion().GetNumberOfPixels();
  float         top = -std::numeric_limits<float>::infinity();
  for (const float * v = begin; v != end; ++v)
  {
    top = std::isfinite(*v) ? std::max(top, *v) : top;
  }
  if (domainSigma == 0.0 || !std::isfinite(top))
  {
    return Smooth(texture, 0.0);
  }
  // ITK's bilateral filter gives no weight to neighbours more than 4 range sigmas away
  // (its fixed RangeMu): NaN pixels are filled with a value 10 range sigmas above every
  // finite one, so they neither contribute nor take anything from their neighbours.
  auto bilateral = BilateralImageFilter<TextureType, TextureType>::New();
  bilateral->SetDomainSigma(domainSigma);
  bilateral->SetRangeSigma(rangeSigma);
  return RunFilled(bilateral.GetPointer(), texture, static_cast<float>(top + 10.0 * rangeSigma + 1.0));
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::Deconvolve(const TextureType * texture, double psfSigma, double regularization)
{
  CheckTextureAndLength(texture, psfSigma, "Deconvolve", "the PSF sigma");
  detail::CheckLayerParameter(regularization, false, "Deconvolve", "the regularization");
  const detail::FiniteRanks ranks = TextureRanks(texture);
  if (psfSigma == 0.0 || ranks.GetCount() == 0)
  {
    return Smooth(texture, 0.0);
  }
  // The PSF on the texture's grid, four sigmas each way, unit sum.
  auto                                        psf = GaussianImageSource<TextureType>::New();
  TextureType::SizeType                       size;
  GaussianImageSource<TextureType>::ArrayType sigma, mean;
  for (unsigned int d = 0; d < 2; ++d)
  {
    const double spacing = texture->GetSpacing()[d];
    size[d] = 2 * static_cast<SizeValueType>(std::ceil(4.0 * psfSigma / spacing)) + 1;
    sigma[d] = psfSigma;
    mean[d] = 0.5 * (size[d] - 1) * spacing;
  }
  psf->SetSize(size);
  psf->SetSpacing(texture->GetSpacing());
  psf->SetSigma(sigma);
  psf->SetMean(mean);
  psf->SetScale(1.0);
  psf->SetNormalized(true);
  auto deconvolve = TikhonovDeconvolutionImageFilter<TextureType, TextureType, TextureType>::New();
  deconvolve->SetKernelImage(psf->GetOutput());
  deconvolve->SetNormalize(true);
  deconvolve->SetRegularizationConstant(regularization);
  // The transform needs every pixel: those off the sheet hold the sheet's median, which
  // adds no edge at the sheet's outline.
  auto result = RunFilled(deconvolve.GetPointer(), texture, ranks.Quantile(0.5));
  // Tikhonov's filter has gain 1 / (1 + regularization) at zero frequency: undone, so
  // flat regions keep their value (NaN stays NaN).
  float * out = result->GetBufferPointer();
  for (SizeValueType k = 0; k < result->GetBufferedRegion().GetNumberOfPixels(); ++k)
  {
    out[k] = static_cast<float>(out[k] * (1.0 + regularization));
  }
  return result;
}

double
LayerStackTexture::ScanBlurSigma(double psfFWHM, double voxelSize)
{
  detail::CheckLayerParameter(psfFWHM, true, "ScanBlurSigma", "the PSF FWHM");
  detail::CheckLayerParameter(voxelSize, true, "ScanBlurSigma", "the voxel size");
  const double psfSigma = psfFWHM / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  return std::sqrt(psfSigma * psfSigma + voxelSize * voxelSize / 12.0);
}

LayerStackTexture::TextureType::Pointer
LayerStackTexture::TrimBorder(const TextureType * texture, double width)
{
  CheckTextureAndLength(texture, width, "TrimBorder", "the width");
  auto          result = NewTexture(texture);
  const float * in = texture->GetBufferPointer();
  float *       out = result->GetBufferPointer();
  std::copy(in, in + texture->GetBufferedRegion().GetNumberOfPixels(), out);
  if (width == 0.0)
  {
    return result;
  }
  // Pixels within `width` of the edge of the finite region become NaN.
  using MaskType = Image<unsigned char, 2>;
  auto finite = MaskType::New();
  finite->SetRegions(texture->GetBufferedRegion());
  finite->SetSpacing(texture->GetSpacing());
  finite->Allocate();
  const SizeValueType n = texture->GetBufferedRegion().GetNumberOfPixels();
  std::transform(in, in + n, finite->GetBufferPointer(), [](float v) { return std::isfinite(v) ? 1 : 0; });
  const std::vector<char> within = detail::WithinOfValidRegionEdge(finite, width);
  for (SizeValueType k = 0; k < n; ++k)
  {
    out[k] = within[k] ? NaN : out[k];
  }
  return result;
}
} // end namespace itk

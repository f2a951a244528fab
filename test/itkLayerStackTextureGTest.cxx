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

#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {
using LST = itk::LayerStackTexture;
using TextureType = LST::TextureType;
using StackType = LST::LayerStackType;
using Side = itk::TextureLayersEnums::Side;
using Filter = itk::TextureLayersEnums::Filter;
constexpr float NaN = std::numeric_limits<float>::quiet_NaN();

StackType::Pointer
MakeStack(unsigned                                                   columns,
          unsigned                                                   rows,
          unsigned                                                   layers,
          const std::function<float(unsigned, unsigned, unsigned)> & f)
{
  auto                stack = StackType::New();
  StackType::SizeType size = { { columns, rows, layers } };
  stack->SetRegions(size);
  stack->SetSpacing(vu::Triple<StackType::SpacingType>(0.5, 0.25, 1.0));
  stack->Allocate();
  for (unsigned k = 0; k < layers; ++k)
  {
    for (unsigned y = 0; y < rows; ++y)
    {
      for (unsigned x = 0; x < columns; ++x)
      {
        stack->SetPixel({ { long(x), long(y), long(k) } }, f(x, y, k));
      }
    }
  }
  return stack;
}

// `count` values drawn from `distribution` (a texture's noise, pixel by pixel).
template <typename Distribution>
std::vector<float>
Draw(size_t count, Distribution & distribution, std::mt19937 & random)
{
  std::vector<float> values(count);
  for (auto & v : values)
  {
    v = distribution(random);
  }
  return values;
}

TextureType::Pointer
MakeTexture(unsigned columns, unsigned rows, double pixel, const std::function<float(unsigned, unsigned)> & f)
{
  auto                  texture = TextureType::New();
  TextureType::SizeType size = { { columns, rows } };
  texture->SetRegions(size);
  TextureType::SpacingType spacing;
  spacing.Fill(pixel);
  texture->SetSpacing(spacing);
  texture->Allocate();
  for (unsigned y = 0; y < rows; ++y)
  {
    for (unsigned x = 0; x < columns; ++x)
    {
      texture->SetPixel({ { long(x), long(y) } }, f(x, y));
    }
  }
  return texture;
}

float
At(const TextureType * t, long x, long y)
{
  return t->GetPixel({ { x, y } });
}

double
Correlation(const TextureType * a, const TextureType * b)
{
  double        sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const size_t  n = a->GetBufferedRegion().GetNumberOfPixels();
  const float * x = a->GetBufferPointer();
  const float * y = b->GetBufferPointer();
  for (size_t k = 0; k < n; ++k)
  {
    sa += x[k];
    sb += y[k];
    saa += double(x[k]) * x[k];
    sbb += double(y[k]) * y[k];
    sab += double(x[k]) * y[k];
  }
  const double cov = sab - sa * sb / n, va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  return cov / std::sqrt(va * vb);
}
// A sheet of value 5 with NaN holes scattered over it (40 x 30 pixels of 0.5 mm).
TextureType::Pointer
HoledSheet()
{
  return MakeTexture(40, 30, 0.5, [](unsigned x, unsigned y) { return (x * 7 + y * 3) % 11 == 0 ? NaN : 5.0f; });
}

// `result` of a smoothing of HoledSheet(): still 5 where the sheet is, NaN in the holes.
void
ExpectHoledSheet(const TextureType * holed, const TextureType * result, float tolerance)
{
  for (unsigned y = 0; y < 30; ++y)
  {
    for (unsigned x = 0; x < 40; ++x)
    {
      if (std::isnan(At(holed, x, y)))
      {
        EXPECT_TRUE(std::isnan(At(result, x, y)));
      }
      else
      {
        EXPECT_NEAR(At(result, x, y), 5.0f, tolerance);
      }
    }
  }
}
} // namespace

// Five layers at offsets -2 .. 2 (focus 0), layer k holding k * 10 + x: the halves, the
// filters and the core subtraction on known numbers.
TEST(LayerStackTexture, CombinesHalvesFiltersAndCore)
{
  const auto stack = MakeStack(4, 3, 5, [](unsigned x, unsigned, unsigned k) { return float(10 * k + x); });
  auto       combine = [&](Side stackSide, Side side, Filter filter, double core) {
    return LST::Combine(stack, 5, 1.0, 0.0, stackSide, side, filter, 1.0, core);
  };
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Both, Filter::Max, 0.0), 1, 0), 41.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Positive, Filter::Max, 0.0), 1, 0), 41.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Positive, Filter::Mean, 0.0), 2, 1), 32.0f); // layers 2, 3, 4
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Negative, Filter::Max, 0.0), 3, 2), 23.0f);  // layers 2, 1, 0
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Negative, Filter::Min, 0.0), 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Negative, Filter::SingleLayer, 0.0), 0, 0), 20.0f);
  // Core: the layers of the half within the core width of the focus.
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Positive, Filter::Max, 0.5), 1, 0), 41.0f - 21.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Positive, Filter::Max, 1.0), 1, 0), 41.0f - 26.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Negative, Filter::Max, 1.0), 1, 0), 21.0f - 16.0f);
  EXPECT_FLOAT_EQ(At(combine(Side::Both, Side::Both, Filter::Max, 1.0), 1, 0), 41.0f - 21.0f);
  // A stack sampled on one side: all its layers are that side.
  EXPECT_FLOAT_EQ(At(combine(Side::Positive, Side::Positive, Filter::Mean, 1.0), 0, 0), 20.0f - 5.0f);
  // Geometry of the first two axes.
  const auto texture = combine(Side::Both, Side::Both, Filter::Mean, 0.0);
  EXPECT_EQ(texture->GetLargestPossibleRegion().GetSize()[0], 4u);
  EXPECT_EQ(texture->GetLargestPossibleRegion().GetSize()[1], 3u);
  EXPECT_DOUBLE_EQ(texture->GetSpacing()[0], 0.5);
  EXPECT_DOUBLE_EQ(texture->GetSpacing()[1], 0.25);

  // Off the sheet stays off the sheet.
  auto holed = MakeStack(4, 3, 5, [](unsigned x, unsigned y, unsigned k) { return x == 2 && y == 1 ? NaN : float(k); });
  EXPECT_TRUE(
    std::isnan(At(LST::Combine(holed, 5, 1.0, 0.0, Side::Both, Side::Positive, Filter::Max, 1.0, 0.5), 2, 1)));
  EXPECT_FALSE(
    std::isnan(At(LST::Combine(holed, 5, 1.0, 0.0, Side::Both, Side::Positive, Filter::Max, 1.0, 0.5), 1, 1)));
}

TEST(LayerStackTexture, CombineRejectsWhatItCannotSplit)
{
  const auto stack = MakeStack(2, 2, 4, [](unsigned, unsigned, unsigned k) { return float(k); });
  // An even stack has no layer at the focus to split at.
  EXPECT_THROW(LST::Combine(stack, 4, 1.0, 0.0, Side::Both, Side::Positive, Filter::Max, 1.0, 0.0),
               itk::ExceptionObject);
  // One side is not the other.
  EXPECT_THROW(LST::Combine(stack, 4, 1.0, 0.0, Side::Negative, Side::Positive, Filter::Max, 1.0, 0.0),
               itk::ExceptionObject);
  EXPECT_THROW(LST::Combine(stack, 5, 1.0, 0.0, Side::Both, Side::Both, Filter::Max, 1.0, 0.0), itk::ExceptionObject);
  EXPECT_THROW(LST::Combine(stack, 4, 1.0, 0.0, Side::Both, Side::Both, Filter::Max, 1.0, -1.0), itk::ExceptionObject);
  // Layers at +/- 0.5 and 1.5: none within 0.25 of the focus.
  EXPECT_THROW(LST::Combine(stack, 4, 1.0, 0.0, Side::Both, Side::Both, Filter::Max, 1.0, 0.25), itk::ExceptionObject);
  EXPECT_THROW(LST::Combine(nullptr, 4, 1.0, 0.0, Side::Both, Side::Both, Filter::Max, 1.0, 0.0), itk::ExceptionObject);
}

// A sheet whose structure (fibres) runs through its depth, with ink in its outermost layer
// on the positive side: the max of the positive half shows ink and structure, subtracting
// the core leaves the ink; the ink contrast ranks the two the same way, and ranks the
// ink-free negative half lowest.
TEST(LayerStackTexture, CoreSubtractionCancelsStructureThroughTheDepth)
{
  const unsigned                  columns = 120, rows = 80, layers = 7; // offsets -3 .. 3
  std::mt19937                    random(7);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::vector<float>              structure(columns * rows), noise(columns * rows * layers);
  for (float & s : structure)
  {
    s = 4.0f * normal(random);
  }
  for (float & n : noise)
  {
    n = 0.3f * normal(random);
  }
  auto       inkAt = [](unsigned x, unsigned y) { return (x / 10) % 3 == 0 && y > 20 && y < 60; };
  const auto stack = MakeStack(columns, rows, layers, [&](unsigned x, unsigned y, unsigned k) {
    const float sheet = k >= 1 && k <= 5 ? 10.0f + structure[y * columns + x] : 0.0f; // offsets -2 .. 2
    const float ink = k == 5 && inkAt(x, y) ? 8.0f : 0.0f;                            // offset 2
    return sheet + ink + noise[(k * rows + y) * columns + x];
  });
  const auto truth = MakeTexture(columns, rows, 1.0, [&](unsigned x, unsigned y) { return inkAt(x, y) ? 1.0f : 0.0f; });
  const auto plain = LST::Combine(stack, layers, 1.0, 0.0, Side::Both, Side::Positive, Filter::Max, 1.0, 0.0);
  const auto cored = LST::Combine(stack, layers, 1.0, 0.0, Side::Both, Side::Positive, Filter::Max, 1.0, 0.5);
  const auto back = LST::Combine(stack, layers, 1.0, 0.0, Side::Both, Side::Negative, Filter::Max, 1.0, 0.5);
  EXPECT_LT(Correlation(plain, truth), 0.7);
  EXPECT_GT(Correlation(cored, truth), 0.95);
  EXPECT_GT(LST::InkContrast(cored), LST::InkContrast(plain));
  EXPECT_GT(LST::InkContrast(cored), LST::InkContrast(back));
  EXPECT_LT(std::abs(Correlation(back, truth)), 0.1);
}

TEST(LayerStackTexture, InkContrastOfKnownDistributions)
{
  std::mt19937                    random(3);
  std::normal_distribution<float> normal(0.0f, 2.0f);
  // Gaussian: the 99th percentile lies 2.326 sigma above the median.
  const auto gaussian = MakeTexture(300, 300, 1.0, [&](unsigned, unsigned) { return normal(random); });
  EXPECT_NEAR(LST::InkContrast(gaussian), 2.326, 0.1);
  // Five percent of the pixels 10 sigma brighter: the score follows them.
  const auto inked =
    MakeTexture(300, 300, 1.0, [&](unsigned x, unsigned) { return normal(random) + (x % 20 == 0 ? 20.0f : 0.0f); });
  EXPECT_GT(LST::InkContrast(inked), 8.0);
  // NaN pixels take no part; too few finite pixels or no spread score 0.
  const auto holed = MakeTexture(300, 300, 1.0, [&](unsigned x, unsigned) { return x < 150 ? NaN : normal(random); });
  EXPECT_NEAR(LST::InkContrast(holed), 2.326, 0.15);
  EXPECT_EQ(LST::InkContrast(MakeTexture(3, 3, 1.0, [](unsigned x, unsigned y) { return x + y == 0 ? 1.0f : NaN; })),
            0.0);
  EXPECT_EQ(LST::InkContrast(MakeTexture(3, 3, 1.0, [](unsigned, unsigned) { return 4.0f; })), 0.0);
  EXPECT_THROW(LST::InkContrast(nullptr), itk::ExceptionObject);
}

TEST(LayerStackTexture, SmoothIsNormalisedAndKeepsTheSheet)
{
  // A constant sheet with holes stays exactly constant; the holes stay holes.
  const auto holed = HoledSheet();
  ExpectHoledSheet(holed, LST::Smooth(holed, 1.0), 1e-5f);
  // An impulse spreads into a Gaussian of the given physical sigma (2 pixels here).
  const auto impulse =
    MakeTexture(41, 41, 0.5, [](unsigned x, unsigned y) { return x == 20 && y == 20 ? 1.0f : 0.0f; });
  const auto   spread = LST::Smooth(impulse, 1.0);
  const double peak = At(spread, 20, 20);
  EXPECT_NEAR(At(spread, 22, 20) / peak, std::exp(-0.5), 0.01);
  EXPECT_NEAR(At(spread, 20, 18) / peak, std::exp(-0.5), 0.01);
  double sum = 0.0;
  for (size_t k = 0; k < 41 * 41; ++k)
  {
    sum += spread->GetBufferPointer()[k];
  }
  EXPECT_NEAR(sum, 1.0, 0.01);
  // Sigma 0 copies.
  EXPECT_EQ(At(LST::Smooth(impulse, 0.0), 20, 20), 1.0f);
  EXPECT_THROW(LST::Smooth(impulse, -1.0), itk::ExceptionObject);
  EXPECT_THROW(LST::Smooth(nullptr, 1.0), itk::ExceptionObject);
}

TEST(LayerStackTexture, MedianRemovesSpecksAndKeepsEdges)
{
  // A step edge with single-pixel specks on both sides, a NaN hole, 0.5 mm pixels.
  auto value = [](unsigned x, unsigned y) {
    if (x == 4 && y == 4)
    {
      return NaN;
    }
    const float base = x < 10 ? 0.0f : 10.0f;
    return (x == 5 && y == 7) || (x == 14 && y == 3) ? 10.0f - base : base;
  };
  const auto texture = MakeTexture(20, 12, 0.5, value);
  const auto median = LST::Median(texture, 0.5); // 3 x 3
  EXPECT_EQ(At(median, 5, 7), 0.0f);
  EXPECT_EQ(At(median, 14, 3), 10.0f);
  EXPECT_EQ(At(median, 9, 5), 0.0f); // the edge stays where it was
  EXPECT_EQ(At(median, 10, 5), 10.0f);
  EXPECT_TRUE(std::isnan(At(median, 4, 4)));
  EXPECT_EQ(At(median, 0, 0), 0.0f);
  const auto ramp = MakeTexture(5, 5, 1.0, [](unsigned x, unsigned y) { return float(x + 5 * y); });
  EXPECT_EQ(At(LST::Median(ramp, 1.0), 2, 2), 12.0f);
  EXPECT_EQ(At(LST::Median(ramp, 1.0), 0, 0), 3.0f); // 0, 1, 5, 6: mean of 1 and 5
  // Less than half a pixel: a copy.
  EXPECT_EQ(At(LST::Median(texture, 0.2), 5, 7), 10.0f);
  EXPECT_THROW(LST::Median(texture, -1.0), itk::ExceptionObject);
}

TEST(LayerStackTexture, TrimBorderRemovesRingsInsideTheSheetsEdge)
{
  // 1 mm pixels: the edge lies half a pixel beyond the outer pixel centres, so a width of
  // 1 mm takes one ring, 1.6 mm two; a hole is an edge too.
  const auto texture = MakeTexture(20, 12, 1.0, [](unsigned x, unsigned y) { return x == 10 && y == 6 ? NaN : 1.0f; });
  const auto one = LST::TrimBorder(texture, 1.0);
  EXPECT_TRUE(std::isnan(At(one, 0, 5)));
  EXPECT_TRUE(std::isnan(At(one, 19, 5)));
  EXPECT_TRUE(std::isnan(At(one, 5, 11)));
  EXPECT_FALSE(std::isnan(At(one, 1, 5)));
  EXPECT_TRUE(std::isnan(At(one, 9, 6)));
  EXPECT_FALSE(std::isnan(At(one, 8, 6)));
  const auto two = LST::TrimBorder(texture, 1.6);
  EXPECT_TRUE(std::isnan(At(two, 1, 5)));
  EXPECT_FALSE(std::isnan(At(two, 2, 5)));
  EXPECT_FALSE(std::isnan(At(LST::TrimBorder(texture, 0.0), 0, 0)));
  EXPECT_THROW(LST::TrimBorder(texture, -1.0), itk::ExceptionObject);
}

TEST(LayerStackTexture, TrimBorderEqualsTheDistanceToTheNearestHole)
{
  // Random holes, rectangular pixels: a pixel is trimmed exactly when the nearest hole's or
  // outside pixel's centre lies nearer than the width plus half the smaller pixel side.
  std::mt19937                          random(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto texture = MakeTexture(41, 29, 1.0, [&](unsigned, unsigned) { return unit(random) < 0.03f ? NaN : 1.0f; });
  TextureType::SpacingType spacing;
  spacing[0] = 0.3;
  spacing[1] = 0.45;
  texture->SetSpacing(spacing);
  for (const double width : { 0.2, 0.7, 1.33, 2.9 })
  {
    const auto trimmed = LST::TrimBorder(texture, width);
    for (long y = 0; y < 29; ++y)
    {
      for (long x = 0; x < 41; ++x)
      {
        double nearest = std::numeric_limits<double>::infinity();
        for (long v = -1; v <= 29; ++v)
        {
          for (long u = -1; u <= 41; ++u)
          {
            const bool outside = u < 0 || v < 0 || u > 40 || v > 28;
            if (outside || std::isnan(At(texture, u, v)))
            {
              nearest = std::min(nearest, std::hypot((u - x) * 0.3, (v - y) * 0.45));
            }
          }
        }
        ASSERT_EQ(std::isnan(At(trimmed, x, y)), nearest - 0.15 < width)
          << "width " << width << " at " << x << ", " << y << ", nearest hole " << nearest;
      }
    }
  }
}

TEST(LayerStackTexture, CombineEqualsTheFilterOfEachPixelsLayers)
{
  // Random samples with holes: every filter, half and core gives, pixel by pixel, the
  // layers' combination less the core's mean, or NaN where a layer of the half is NaN.
  std::mt19937                          random(13);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const auto                            stack = MakeStack(23, 17, 7, [&](unsigned, unsigned, unsigned) {
    const float v = unit(random);
    return v < 0.02f ? NaN : 10.0f * v;
  });
  for (const Filter filter : { Filter::Max, Filter::Min, Filter::Mean, Filter::Median })
  {
    for (const Side side : { Side::Both, Side::Positive, Side::Negative })
    {
      for (const double core : { 0.0, 1.0 })
      {
        const auto               combined = LST::Combine(stack, 7, 1.0, 0.0, Side::Both, side, filter, 1.0, core);
        const unsigned           count = side == Side::Both ? 7 : 4;
        const itk::TextureLayers layers(count, 1.0, 0.0, side, filter, 1.0);
        for (long y = 0; y < 17; ++y)
        {
          for (long x = 0; x < 23; ++x)
          {
            std::vector<float> samples;
            double             coreSum = 0.0;
            unsigned           coreCount = 0;
            for (unsigned k = 0; k < count; ++k)
            {
              const long layer = side == Side::Both ? k : side == Side::Positive ? 3 + k : 3 - long(k);
              samples.push_back(stack->GetPixel({ { x, y, layer } }));
              if (std::abs(layers.GetOffsets()[k]) <= core + 1e-9)
              {
                coreSum += samples.back();
                ++coreCount;
              }
            }
            const bool  hole = std::any_of(samples.begin(), samples.end(), [](float v) { return std::isnan(v); });
            const float value = At(combined, x, y);
            if (hole)
            {
              ASSERT_TRUE(std::isnan(value)) << filter << " " << side << " core " << core << " at " << x << ", " << y;
              continue;
            }
            const double coreMean = core > 0.0 ? coreSum / coreCount : 0.0;
            ASSERT_EQ(value, static_cast<float>(layers.Combine(samples.data()) - coreMean))
              << filter << " " << side << " core " << core << " at " << x << ", " << y;
          }
        }
      }
    }
  }
}

TEST(LayerStackTexture, NoiseSpreadIsTheStandardDeviationOfTheBackground)
{
  std::mt19937                    random(5);
  std::normal_distribution<float> normal(100.0f, 3.0f);
  EXPECT_NEAR(
    LST::NoiseSpread(MakeTexture(300, 300, 1.0, [&](unsigned, unsigned) { return normal(random); })), 3.0, 0.1);
  // Ink on a tenth of the sheet raises it by about a tenth; NaN pixels take no part.
  const auto inked = MakeTexture(
    300, 300, 1.0, [&](unsigned x, unsigned) { return x < 30 ? NaN : normal(random) + (x % 10 == 0 ? 500.0f : 0.0f); });
  EXPECT_NEAR(LST::NoiseSpread(inked), 3.0, 0.6);
  EXPECT_EQ(LST::NoiseSpread(MakeTexture(3, 3, 1.0, [](unsigned x, unsigned y) { return x + y == 0 ? 1.0f : NaN; })),
            0.0);
  EXPECT_THROW(LST::NoiseSpread(nullptr), itk::ExceptionObject);
}

TEST(LayerStackTexture, EdgePreservingSmoothAveragesNoiseAndKeepsEdges)
{
  // A noisy step (0 | 100, noise 5) with a NaN hole next to the edge, 0.5 mm pixels.
  std::mt19937                    random(7);
  std::normal_distribution<float> normal(0.0f, 5.0f);
  const auto                      clean = [](unsigned x) { return x < 30 ? 0.0f : 100.0f; };
  const auto                      noisy = MakeTexture(
    60, 40, 0.5, [&](unsigned x, unsigned y) { return x == 31 && y == 20 ? NaN : clean(x) + normal(random); });
  const auto bilateral = LST::EdgePreservingSmooth(noisy, 1.0, 10.0);
  const auto gaussian = LST::Smooth(noisy, 1.0);
  double     noiseBefore = 0.0, noiseAfter = 0.0, edgeBilateral = 0.0, edgeGaussian = 0.0;
  unsigned   flat = 0, edge = 0;
  for (unsigned y = 0; y < 40; ++y)
  {
    for (unsigned x = 0; x < 60; ++x)
    {
      if (x == 31 && y == 20)
      {
        EXPECT_TRUE(std::isnan(At(bilateral, x, y)));
        continue;
      }
      ASSERT_TRUE(std::isfinite(At(bilateral, x, y)));
      const double truth = clean(x);
      if ((x >= 5 && x < 25) || (x >= 35 && x < 55))
      {
        noiseBefore += std::pow(At(noisy, x, y) - truth, 2);
        noiseAfter += std::pow(At(bilateral, x, y) - truth, 2);
        ++flat;
      }
      if (x >= 28 && x < 32)
      {
        edgeBilateral += std::pow(At(bilateral, x, y) - truth, 2);
        edgeGaussian += std::pow(At(gaussian, x, y) - truth, 2);
        ++edge;
      }
    }
  }
  // The noise falls to under a third; at the edge the error stays far below a Gaussian's
  // of the same width, which blurs the step over several pixels.
  EXPECT_LT(std::sqrt(noiseAfter / flat), std::sqrt(noiseBefore / flat) / 3.0);
  EXPECT_LT(std::sqrt(edgeBilateral / edge), 0.25 * std::sqrt(edgeGaussian / edge));
  // NaN neighbours take no part: a constant sheet with holes stays exactly constant.
  const auto holed = HoledSheet();
  ExpectHoledSheet(holed, LST::EdgePreservingSmooth(holed, 1.0, 1.0), 1e-4f);
  EXPECT_EQ(At(LST::EdgePreservingSmooth(noisy, 0.0, 1.0), 3, 3), At(noisy, 3, 3));
  EXPECT_THROW(LST::EdgePreservingSmooth(noisy, -1.0, 1.0), itk::ExceptionObject);
  EXPECT_THROW(LST::EdgePreservingSmooth(noisy, 1.0, 0.0), itk::ExceptionObject);
  EXPECT_THROW(LST::EdgePreservingSmooth(nullptr, 1.0, 1.0), itk::ExceptionObject);
}

namespace {
// Sum of squared differences over the pixels at least 8 from the edges of a 96 x 64
// texture whose last 6 columns are NaN.
double
InteriorSquaredDifference(const TextureType * a, const TextureType * b)
{
  double sum = 0.0;
  for (unsigned y = 8; y < 56; ++y)
  {
    for (unsigned x = 8; x < 82; ++x)
    {
      sum += std::pow(At(a, x, y) - At(b, x, y), 2);
    }
  }
  return sum;
}
} // namespace

TEST(LayerStackTexture, DeconvolveUndoesAGaussianBlur)
{
  // Bars two pixels wide (0.1 mm pixels), blurred by a Gaussian of sigma 0.1 mm, with NaN
  // off the sheet (the last columns): deconvolution by the same Gaussian brings them back
  // much closer to the sharp bars than the blurred image is (squared error under 35%).
  const auto sharp =
    MakeTexture(96, 64, 0.1, [](unsigned x, unsigned y) { return (x / 2 + y / 8) % 4 == 0 ? 1.0f : 0.0f; });
  const auto blurredFull = LST::Smooth(sharp, 0.1);
  const auto blurred =
    MakeTexture(96, 64, 0.1, [&](unsigned x, unsigned y) { return x >= 90 ? NaN : At(blurredFull, x, y); });
  const auto restored = LST::Deconvolve(blurred, 0.1, 0.01);
  EXPECT_LT(InteriorSquaredDifference(restored, sharp), 0.35 * InteriorSquaredDifference(blurred, sharp));
  for (unsigned y = 0; y < 64; ++y)
  {
    EXPECT_TRUE(std::isnan(At(restored, 92, y)));
    EXPECT_TRUE(std::isfinite(At(restored, 5, y)));
  }
  // A stronger regularization sharpens less: closer to the blurred image. Flat regions
  // keep their value.
  const auto smooth = LST::Deconvolve(blurred, 0.1, 1.0);
  EXPECT_LT(InteriorSquaredDifference(smooth, blurred), 0.5 * InteriorSquaredDifference(restored, blurred));
  const auto flat = MakeTexture(32, 32, 0.1, [](unsigned x, unsigned) { return x < 28 ? 7.0f : NaN; });
  EXPECT_NEAR(At(LST::Deconvolve(flat, 0.1, 0.5), 10, 10), 7.0f, 1e-3f);
  EXPECT_EQ(At(LST::Deconvolve(blurred, 0.0, 0.1), 3, 3), At(blurred, 3, 3));
  EXPECT_THROW(LST::Deconvolve(blurred, -0.1, 0.1), itk::ExceptionObject);
  EXPECT_THROW(LST::Deconvolve(blurred, 0.1, 0.0), itk::ExceptionObject);
  EXPECT_THROW(LST::Deconvolve(nullptr, 0.1, 0.1), itk::ExceptionObject);
  // The blur of a scan: a PSF of FWHM 0.12 mm (sigma 0.05096) with 0.1 mm voxels.
  EXPECT_NEAR(LST::ScanBlurSigma(0.12, 0.1), std::sqrt(0.05096 * 0.05096 + 0.01 / 12.0), 1e-5);
  EXPECT_NEAR(LST::ScanBlurSigma(0.0, 0.3), 0.3 / std::sqrt(12.0), 1e-12);
  EXPECT_THROW(LST::ScanBlurSigma(-0.1, 0.1), itk::ExceptionObject);
}

// A focal slab is the mean of its layers over the finite samples; a window outside the
// stack is refused.
TEST(LayerStackTexture, LayerWindowAveragesTheFiniteSamplesOfItsLayers)
{
  auto       stack = MakeStack(8, 6, 7, [](unsigned x, unsigned y, unsigned k) {
    if (x == 0 && y == 0)
    {
      return NaN;
    }
    if (x == 1 && y == 0 && k == 3)
    {
      return NaN;
    }
    return static_cast<float>(k * 10 + x);
  });
  const auto slab = LST::LayerWindow(stack, 2, 3);
  EXPECT_FLOAT_EQ(At(slab, 4, 2), 34.0f); // layers 2, 3, 4: 24, 34, 44
  EXPECT_FLOAT_EQ(At(slab, 1, 0), 31.0f); // layer 3 is NaN: (21 + 41) / 2
  EXPECT_TRUE(std::isnan(At(slab, 0, 0)));
  EXPECT_DOUBLE_EQ(slab->GetSpacing()[0], 0.5);
  EXPECT_DOUBLE_EQ(slab->GetSpacing()[1], 0.25);
  EXPECT_THROW(LST::LayerWindow(stack, 5, 3), itk::ExceptionObject);
  EXPECT_THROW(LST::LayerWindow(stack, 0, 0), itk::ExceptionObject);
  EXPECT_THROW(LST::LayerWindow(nullptr, 0, 1), itk::ExceptionObject);
}

// Under noise as strong as the ink, the slab through the inked layers has the highest
// stroke contrast, and it shows the writing; a slab without ink scores lower.
TEST(LayerStackTexture, StrokeContrastFindsTheInkedSlabUnderNoise)
{
  std::mt19937                    random(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const unsigned                  layers = 11;
  // Strokes 3 pixels wide every 12 pixels in rows 20 to 40, in layers 6 to 8 only.
  auto       ink = [](unsigned x, unsigned y) { return y >= 20 && y < 40 && x % 12 < 3 ? 1.5f : 0.0f; };
  auto       stack = MakeStack(160, 60, layers, [&](unsigned x, unsigned y, unsigned k) {
    return 1.0f + (k >= 6 && k <= 8 ? ink(x, y) : 0.0f) + noise(random);
  });
  const auto truth = MakeTexture(160, 60, 0.5, [&](unsigned x, unsigned y) { return ink(x, y); });
  unsigned   best = 0;
  double     bestScore = -1.0;
  for (unsigned first = 0; first + 3 <= layers; ++first)
  {
    const double score = LST::StrokeContrast(LST::Smooth(LST::LayerWindow(stack, first, 3), 0.5), 0.5);
    if (score > bestScore)
    {
      bestScore = score;
      best = first;
    }
  }
  EXPECT_EQ(best, 6u);
  const auto slab = LST::Smooth(LST::LayerWindow(stack, best, 3), 0.5);
  EXPECT_GT(Correlation(slab, truth), 0.8);
  EXPECT_GT(bestScore, 1.5 * LST::StrokeContrast(LST::Smooth(LST::LayerWindow(stack, 0, 3), 0.5), 0.5));
  EXPECT_THROW(LST::StrokeContrast(slab, 0.0), itk::ExceptionObject);
}

// A few words on a long sheet: the strokes cover a small fraction of a per cent of the
// texture, below its 99th percentile, but fill the top percent of the blocks they lie in,
// so the inked slab still scores highest.
TEST(LayerStackTexture, StrokeContrastFindsAShortTextOnALongSheet)
{
  std::mt19937                    random(11);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const unsigned                  layers = 9, columns = 3000, rows = 40;
  // Strokes 3 pixels wide every 10 pixels in rows 12 to 28 of columns 1400 to 1480.
  auto ink = [](unsigned x, unsigned y) { return y >= 12 && y < 28 && x >= 1400 && x < 1480 && x % 10 < 3; };
  auto stack = MakeStack(columns, rows, layers, [&](unsigned x, unsigned y, unsigned k) {
    return 1.0f + (k >= 2 && k <= 4 && ink(x, y) ? 1.5f : 0.0f) + noise(random);
  });
  std::vector<double> scores;
  for (unsigned first = 0; first + 3 <= layers; ++first)
  {
    scores.push_back(LST::StrokeContrast(LST::Smooth(LST::LayerWindow(stack, first, 3), 0.5), 0.5));
  }
  const auto best = std::max_element(scores.begin(), scores.end());
  EXPECT_EQ(best - scores.begin(), 2);
  EXPECT_GT(*best, 1.5 * scores.back());
}

// Strong strokes with faint parts on a noisy background: the strokes and their faint parts
// are kept as they are, the background's speckle takes the median; NaN stays NaN; a
// texture of noise alone is returned unchanged; dark ink is cleared the other way round.
TEST(LayerStackTexture, ClearBackgroundKeepsTheInkAndClearsTheSpeckle)
{
  std::mt19937                    random(5);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const unsigned                  columns = 400, rows = 100;
  // Vertical strokes 4 pixels wide (+9) every 40 pixels, each with a faint tail (+4, as
  // far above the background as the noise often reaches) to its right.
  auto strong = [](unsigned x, unsigned y) { return y >= 30 && y < 70 && x % 40 < 4; };
  auto faint = [](unsigned x, unsigned y) { return y >= 45 && y < 49 && x % 40 >= 4 && x % 40 < 14; };
  const std::vector<float> values = Draw(columns * rows, noise, random);
  for (const bool bright : { true, false })
  {
    const float sign = bright ? 1.0f : -1.0f;
    const auto  texture = MakeTexture(columns, rows, 0.5, [&](unsigned x, unsigned y) {
      if (x < 2 && y < 2)
      {
        return NaN;
      }
      return 10.0f + values[y * columns + x] + sign * (strong(x, y) ? 9.0f : faint(x, y) ? 4.0f : 0.0f);
    });
    const auto  cleared = LST::ClearBackground(texture, bright);
    const float median = static_cast<float>(LST::Quantiles(texture, { 0.5 })[0]);
    size_t      inkKept = 0, inkPixels = 0, speckle = 0, background = 0;
    for (unsigned y = 0; y < rows; ++y)
    {
      for (unsigned x = 0; x < columns; ++x)
      {
        const itk::Index<2> i = { { long(x), long(y) } };
        const float         before = texture->GetPixel(i), after = cleared->GetPixel(i);
        if (!std::isfinite(before))
        {
          EXPECT_TRUE(std::isnan(after));
        }
        else if (strong(x, y) || faint(x, y))
        {
          ++inkPixels;
          inkKept += after == before ? 1 : 0;
        }
        else
        {
          ++background;
          speckle += after != median ? 1 : 0;
        }
      }
    }
    EXPECT_GT(static_cast<double>(inkKept), 0.95 * static_cast<double>(inkPixels)) << (bright ? "bright" : "dark");
    // Only the noise touching a stroke stays: under 2 % of the background (one spread
    // beyond the median: 16 %).
    EXPECT_LT(static_cast<double>(speckle), 0.02 * static_cast<double>(background)) << (bright ? "bright" : "dark");
  }
  const auto plain = MakeTexture(columns, rows, 0.5, [&](unsigned x, unsigned y) { return values[y * columns + x]; });
  const auto same = LST::ClearBackground(plain);
  EXPECT_TRUE(
    std::equal(plain->GetBufferPointer(), plain->GetBufferPointer() + columns * rows, same->GetBufferPointer()));
  EXPECT_THROW(LST::ClearBackground(nullptr), itk::ExceptionObject);
}

// What ClearBackground kept of a texture with strong ink, faint ink and a faint band: the
// faint and band pixels kept as they were, the faint and band pixels' peak in noise
// spreads, and the background pixels not cleared to the median.
struct ClearedCounts
{
  size_t FaintKept{ 0 }, FaintPixels{ 0 }, BandKept{ 0 }, Speckle{ 0 }, Background{ 0 };
  double FaintPeak{ 0.0 }, BandPeak{ 0.0 };
};

ClearedCounts
CountCleared(const LST::TextureType *                        texture,
             const std::function<bool(unsigned, unsigned)> & strong,
             const std::function<bool(unsigned, unsigned)> & faint,
             const std::function<bool(unsigned, unsigned)> & band)
{
  const double  median = LST::Quantiles(texture, { 0.5 })[0];
  const double  spread = LST::NoiseSpread(texture);
  const auto    cleared = LST::ClearBackground(texture);
  const auto    size = texture->GetBufferedRegion().GetSize();
  ClearedCounts c;
  for (unsigned y = 0; y < size[1]; ++y)
  {
    for (unsigned x = 0; x < size[0]; ++x)
    {
      const itk::Index<2> i = { { long(x), long(y) } };
      const float         before = texture->GetPixel(i), after = cleared->GetPixel(i);
      if (faint(x, y))
      {
        ++c.FaintPixels;
        c.FaintKept += after == before ? 1 : 0;
        c.FaintPeak = std::max(c.FaintPeak, (before - median) / spread);
      }
      else if (band(x, y))
      {
        c.BandKept += after == before ? 1 : 0;
        c.BandPeak = std::max(c.BandPeak, (before - median) / spread);
      }
      else if (!strong(x, y))
      {
        ++c.Background;
        c.Speckle += after != static_cast<float>(median) ? 1 : 0;
      }
    }
  }
  return c;
}

// A faint letter that nowhere reaches the ink's core level (1.5 noise spreads above the
// background, no pixel of it at 4.5) beside a strong one: it outweighs every blob of the
// noise below the background and is the strong letter's size, so it is kept; a faint band
// eight times as long as the strong ink is not; the background is cleared.
TEST(LayerStackTexture, ClearBackgroundKeepsAFaintLetterThatOutweighsTheNoise)
{
  std::mt19937                    random(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const unsigned                  columns = 400, rows = 100;
  auto strong = [](unsigned x, unsigned y) { return y >= 30 && y < 70 && x >= 20 && x < 28; };
  auto faint = [](unsigned x, unsigned y) { return y >= 32 && y < 68 && x >= 200 && x < 207; };
  // A band across the texture (2 spreads above the background, without noise: one piece),
  // eight times as long as the strong ink.
  auto                     band = [](unsigned x, unsigned y) { return y >= 86 && y < 90 && x >= 40 && x < 360; };
  const std::vector<float> values = Draw(columns * rows, noise, random);
  const auto               texture = MakeTexture(columns, rows, 0.5, [&](unsigned x, unsigned y) {
    if (band(x, y))
    {
      return 12.0f;
    }
    return 10.0f + values[y * columns + x] + (strong(x, y) ? 9.0f : faint(x, y) ? 1.5f : 0.0f);
  });
  const ClearedCounts      c = CountCleared(texture, strong, faint, band);
  // The faint letter has no pixel at the core's level: only its mass can keep it.
  ASSERT_LT(c.FaintPeak, 4.5);
  ASSERT_LT(c.BandPeak, 4.5);
  // Its pixels above one spread (about 70 %) are kept.
  EXPECT_GT(static_cast<double>(c.FaintKept), 0.6 * static_cast<double>(c.FaintPixels));
  EXPECT_LT(static_cast<double>(c.Speckle), 0.02 * static_cast<double>(c.Background));
  EXPECT_EQ(c.BandKept, 0u);
}

// Two faint letters run together into one component (as wide as three strong letters), no
// pixel of it at the ink's core level, on a line of strong letters: a run of letters, kept;
// a faint band across the lines (taller than a letter) is not. Noise drawn at run time.
TEST(LayerStackTexture, ClearBackgroundKeepsFaintLettersRunTogether)
{
  const unsigned int seed = vu::RunTimeSeed();
  SCOPED_TRACE("noise seed " + std::to_string(seed));
  std::mt19937                    random(seed);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  const unsigned                  columns = 400, rows = 100;
  // Strong letters 8 pixels wide and 40 tall every 40 pixels, left of the faint run.
  auto                     strong = [](unsigned x, unsigned y) { return y >= 30 && y < 70 && x < 160 && x % 40 < 8; };
  auto                     faint = [](unsigned x, unsigned y) { return y >= 32 && y < 68 && x >= 200 && x < 226; };
  auto                     band = [](unsigned x, unsigned y) { return y >= 4 && y < 96 && x >= 320 && x < 327; };
  const std::vector<float> values = Draw(columns * rows, noise, random);
  const auto               texture = MakeTexture(columns, rows, 0.5, [&](unsigned x, unsigned y) {
    const float v = values[y * columns + x];
    if (strong(x, y))
    {
      return 19.0f + v;
    }
    // The faint ink's noise is clipped below the core level: only its mass and shape count.
    return faint(x, y) ? 11.5f + std::min(v, 2.9f) : band(x, y) ? 12.0f : 10.0f + v;
  });
  const ClearedCounts      c = CountCleared(texture, strong, faint, band);
  ASSERT_LT(c.FaintPeak, 4.5);
  EXPECT_GT(static_cast<double>(c.FaintKept), 0.5 * static_cast<double>(c.FaintPixels));
  EXPECT_EQ(c.BandKept, 0u);
  EXPECT_LT(static_cast<double>(c.Speckle), 0.02 * static_cast<double>(c.Background));
}

TEST(LayerStackTexture, MedianEqualsTheMedianOfEachWindow)
{
  // Random values with holes off the sheet, 3 x 3 and 5 x 5 windows: every pixel equals the
  // median of the finite values of its window (the mean of the middle two for an even count).
  std::mt19937                          random(7);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  const auto                            texture = MakeTexture(37, 23, 0.5, [&](unsigned x, unsigned y) {
    const float v = value(random);
    return (x * 5 + y * 3) % 13 == 0 || x + y < 3 ? NaN : v;
  });
  for (const double radius : { 0.5, 1.0 })
  {
    const auto result = LST::Median(texture, radius);
    const long half = std::lround(radius / 0.5);
    for (long y = 0; y < 23; ++y)
    {
      for (long x = 0; x < 37; ++x)
      {
        if (!std::isfinite(At(texture, x, y)))
        {
          EXPECT_FALSE(std::isfinite(At(result, x, y)));
          continue;
        }
        std::vector<float> window;
        for (long v = std::max(0L, y - half); v <= std::min(22L, y + half); ++v)
        {
          for (long u = std::max(0L, x - half); u <= std::min(36L, x + half); ++u)
          {
            if (std::isfinite(At(texture, u, v)))
            {
              window.push_back(At(texture, u, v));
            }
          }
        }
        std::sort(window.begin(), window.end());
        const size_t n = window.size();
        const float  expected = n % 2 == 1 ? window[n / 2] : 0.5f * (window[n / 2 - 1] + window[n / 2]);
        ASSERT_FLOAT_EQ(At(result, x, y), expected) << "radius " << radius << " at " << x << ", " << y;
      }
    }
  }
}

TEST(LayerStackTexture, SmoothEqualsTheNormalisedConvolutionOfEachPixel)
{
  // Random values with holes, anisotropic pixels: every pixel equals the Gaussian-weighted
  // mean of the finite values about it (weights separable, three sigmas each way).
  std::mt19937                          random(vu::RunTimeSeed());
  std::uniform_real_distribution<float> value(-50.0f, 200.0f);
  const auto                            texture = MakeTexture(29, 31, 0.5, [&](unsigned x, unsigned y) {
    const float v = value(random);
    return (x * 7 + y * 5) % 11 == 0 || x + y < 4 ? NaN : v;
  });
  const double                          sigma = 0.8;
  const auto                            result = LST::Smooth(texture, sigma);
  const long                            radius = static_cast<long>(std::ceil(3.0 * sigma / 0.5));
  for (long y = 0; y < 31; ++y)
  {
    for (long x = 0; x < 29; ++x)
    {
      if (!std::isfinite(At(texture, x, y)))
      {
        EXPECT_FALSE(std::isfinite(At(result, x, y)));
        continue;
      }
      double sv = 0.0, sw = 0.0;
      for (long v = std::max(0L, y - radius); v <= std::min(30L, y + radius); ++v)
      {
        for (long u = std::max(0L, x - radius); u <= std::min(28L, x + radius); ++u)
        {
          const double w = std::exp(-0.5 * ((u - x) * (u - x) + (v - y) * (v - y)) * 0.25 / (sigma * sigma));
          if (std::isfinite(At(texture, u, v)))
          {
            sv += w * At(texture, u, v);
            sw += w;
          }
        }
      }
      ASSERT_NEAR(At(result, x, y), sv / sw, 1e-3) << "at " << x << ", " << y;
    }
  }
}

TEST(LayerStackTexture, RankMeasuresAreThoseOfTheSortedFiniteValues)
{
  // Random textures (seed drawn each run) of wide and narrow ranges, repeated values, signed
  // zeros, NaN and infinities: the ink contrast and the noise spread are those computed from
  // the sorted finite values.
  const unsigned int seed = vu::RunTimeSeed();
  std::mt19937       random(seed);
  SCOPED_TRACE("seed " + std::to_string(seed));
  constexpr float                         Inf = std::numeric_limits<float>::infinity();
  std::uniform_int_distribution<unsigned> extent(1, 150);
  std::uniform_real_distribution<float>   scale(-30.0f, 30.0f), unit(0.0f, 1.0f);
  for (int trial = 0; trial < 22; ++trial)
  {
    // The last two: a regular sample of the pixels sees only the first column, which holds
    // the smallest values (or the largest).
    const bool  striped = trial >= 20;
    const float range = std::pow(2.0f, scale(random));
    const auto  texture =
      MakeTexture(striped ? 3 : extent(random), striped ? 8192 : extent(random), 0.5, [&](unsigned x, unsigned y) {
        if (striped)
        {
          return (x == 0 ? -1.0f : 1.0f) * (trial == 20 ? 1.0f : -1.0f) * (1000.0f - 0.01f * y) + unit(random);
        }
        const float u = unit(random);
        return u < 0.05f   ? NaN
               : u < 0.06f ? Inf
               : u < 0.07f ? -Inf
               : u < 0.08f ? 0.0f
               : u < 0.09f ? -0.0f
               : u < 0.3f  ? std::round(range * (2.0f * unit(random) - 1.0f))
                           : range * (2.0f * unit(random) - 1.0f);
      });
    std::vector<float> sorted;
    const size_t       n = texture->GetBufferedRegion().GetNumberOfPixels();
    std::copy_if(texture->GetBufferPointer(), texture->GetBufferPointer() + n, std::back_inserter(sorted), [](float v) {
      return std::isfinite(v);
    });
    if (sorted.size() < 2)
    {
      EXPECT_EQ(LST::InkContrast(texture), 0.0);
      EXPECT_EQ(LST::Quantiles(texture, { 0.5 }).size(), sorted.size());
      continue;
    }
    std::sort(sorted.begin(), sorted.end());
    const auto rank = [&](const std::vector<float> & values, double q) {
      return static_cast<double>(values[static_cast<size_t>(q * (values.size() - 1) + 0.5)]);
    };
    const double       median = rank(sorted, 0.5), top = rank(sorted, 0.99);
    std::vector<float> deviations;
    for (const float v : sorted)
    {
      deviations.push_back(std::abs(v - static_cast<float>(median)));
    }
    std::sort(deviations.begin(), deviations.end());
    const double spread = 1.4826 * rank(deviations, 0.5);
    EXPECT_EQ(LST::NoiseSpread(texture), spread) << "trial " << trial;
    const std::vector<double> q{ 0.0, 0.005, 0.5, 0.99, 0.995, 1.0 };
    const std::vector<double> quantiles = LST::Quantiles(texture, q);
    ASSERT_EQ(quantiles.size(), q.size());
    for (size_t k = 0; k < q.size(); ++k)
    {
      EXPECT_EQ(quantiles[k], rank(sorted, q[k])) << "trial " << trial << ", q " << q[k];
    }
    EXPECT_EQ(LST::InkContrast(texture), spread > 0.0 ? (top - median) / spread : 0.0) << "trial " << trial;
  }
  EXPECT_THROW(LST::Quantiles(MakeTexture(2, 2, 0.5, [](unsigned, unsigned) { return 1.0f; }), { 1.5 }),
               itk::ExceptionObject);
}

// A sheet whose depth in the stack wanders as a mesh's does (a slow drift, a bulge the mesh
// misses), with ink in the outer third of one face and
// noise, all drawn at run time: registered to the sheet, every pixel's layers hold the
// sheet at the same depth, and the slab through the ink shows the ink far better.
TEST(LayerStackTexture, RegisterToSheetUndoesTheMeshsDepthErrors)
{
  const unsigned                         seed = vu::RunTimeSeed();
  std::mt19937                           random(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const unsigned                         columns = 240, rows = 90, layers = 13;
  const double                           pixel = 0.5, layerSpacing = 0.5;   // mm; voxels of 1 mm
  const double                           thickness = 2.5 + uniform(random); // mm
  // Wanderings wider than the registration's smoothing (narrower ones, such as a coarse
  // mesh's chords, are taken out where the texture's points are placed on the curved sheet).
  const double amplitude = 0.3 + 0.4 * uniform(random), period = 20.0 + 20.0 * uniform(random);
  const double phase = 6.283 * uniform(random);
  const double bulgeX = 30.0 + 60.0 * uniform(random), bulgeY = 10.0 + 25.0 * uniform(random);
  const double bulgeHeight = (uniform(random) < 0.5 ? -1.0 : 1.0) * (0.6 + 0.4 * uniform(random));
  const double inkSide = uniform(random) < 0.5 ? -1.0 : 1.0, noiseLevel = 0.12 + 0.08 * uniform(random);
  // Depth of the sheet's centre from the mesh (mm) at pixel (x, y).
  auto depth = [&](unsigned x, unsigned y) {
    const double px = x * pixel, py = y * pixel;
    const double r2 = ((px - bulgeX) * (px - bulgeX) + (py - bulgeY) * (py - bulgeY)) / 16.0;
    return amplitude * std::sin(6.283 * px / period + phase) + bulgeHeight * std::exp(-0.5 * r2);
  };
  // Letters' strokes: bars 3 pixels wide every 9 pixels, in bands of 24 rows.
  auto ink = [](unsigned x, unsigned y) { return (y % 40) >= 8 && (y % 40) < 32 && x % 9 < 3 ? 1.0 : 0.0; };
  // Material along the depth u (mm from the sheet's centre): a blurred box, and the ink
  // blurred in the outer third on its side.
  auto box = [](double u, double from, double to) {
    const double blur = 0.6 * std::sqrt(2.0);
    return 0.5 * (std::erf((u - from) / blur) - std::erf((u - to) / blur));
  };
  std::normal_distribution<float> noise(0.0f, static_cast<float>(noiseLevel));
  auto                            make = [&](bool withInk, bool withNoise) {
    auto                stack = StackType::New();
    StackType::SizeType size = { { columns, rows, layers } };
    stack->SetRegions(size);
    stack->SetSpacing(vu::Triple<StackType::SpacingType>(pixel, pixel, layerSpacing));
    stack->Allocate();
    for (unsigned k = 0; k < layers; ++k)
    {
      for (unsigned y = 0; y < rows; ++y)
      {
        for (unsigned x = 0; x < columns; ++x)
        {
          const double u = (k - 0.5 * (layers - 1)) * layerSpacing - depth(x, y);
          double       value = box(u, -0.5 * thickness, 0.5 * thickness);
          if (withInk)
          {
            const double face = inkSide * thickness / 3.0;
            value += 0.8 * ink(x, y) * box(u, face - thickness / 6.0, face + thickness / 6.0);
          }
          stack->SetPixel({ { long(x), long(y), long(k) } },
                          static_cast<float>(value) + (withNoise ? noise(random) : 0.0f));
        }
      }
    }
    return stack;
  };
  const auto sigma = 2.0; // mm: two voxels

  // Without ink or noise: after registration each layer is nearly the same in every pixel.
  const auto           plain = make(false, false);
  TextureType::Pointer shift;
  const auto           plainRegistered = LST::RegisterToSheet(plain, sigma, &shift);
  // The shifts map the sheet's depth (less its median).
  const auto wander = MakeTexture(columns, rows, pixel, [&](unsigned x, unsigned y) { return float(depth(x, y)); });
  EXPECT_GT(Correlation(shift, wander), 0.9) << "seed " << seed;
  auto spread = [&](const StackType * s, unsigned k) {
    const auto          layer = LST::LayerWindow(s, k, 1);
    std::vector<double> values(layer->GetBufferPointer(),
                               layer->GetBufferPointer() + layer->GetBufferedRegion().GetNumberOfPixels());
    double              mean = 0.0, square = 0.0;
    for (double v : values)
    {
      mean += v;
      square += v * v;
    }
    mean /= values.size();
    return std::sqrt(std::max(0.0, square / values.size() - mean * mean));
  };
  const unsigned faceLayer = static_cast<unsigned>(std::lround(0.5 * (layers - 1) + thickness / 2.0 / layerSpacing));
  EXPECT_LT(spread(plainRegistered, faceLayer), 0.35 * spread(plain, faceLayer)) << "seed " << seed;

  // With ink and noise: the 3-layer slab centred on the ink's depth.
  const auto inked = make(true, true);
  const auto registered = LST::RegisterToSheet(inked, sigma);
  const auto inkLayer =
    static_cast<unsigned>(std::lround(0.5 * (layers - 1) + inkSide * thickness / 3.0 / layerSpacing)) - 1;
  const auto   truth = MakeTexture(columns, rows, pixel, [&](unsigned x, unsigned y) { return float(ink(x, y)); });
  const double before = Correlation(LST::Smooth(LST::LayerWindow(inked, inkLayer, 3), 0.5), truth);
  const double after = Correlation(LST::Smooth(LST::LayerWindow(registered, inkLayer, 3), 0.5), truth);
  EXPECT_GT(after, before + 0.1) << "seed " << seed << ": correlation with the ink " << before << " -> " << after;
  EXPECT_GT(after, 0.6) << "seed " << seed;
}

TEST(LayerStackTexture, RegisterToSheetKeepsWhatItCannotRegister)
{
  // Two layers: a copy. No sheet brighter than the air: a copy. NaN stays NaN.
  const auto two = MakeStack(20, 10, 2, [](unsigned x, unsigned, unsigned k) { return float(x + k); });
  const auto same = LST::RegisterToSheet(two, 1.0);
  EXPECT_TRUE(std::equal(two->GetBufferPointer(), two->GetBufferPointer() + 400, same->GetBufferPointer()));
  const auto flat =
    MakeStack(20, 10, 5, [](unsigned x, unsigned y, unsigned) { return (x + y) % 7 == 0 ? NaN : 1.0f; });
  const auto kept = LST::RegisterToSheet(flat, 1.0);
  for (size_t i = 0; i < 1000; ++i)
  {
    const float a = flat->GetBufferPointer()[i], b = kept->GetBufferPointer()[i];
    EXPECT_TRUE(std::isnan(a) ? std::isnan(b) : a == b);
  }
  const auto sheet = MakeStack(20, 10, 7, [](unsigned x, unsigned y, unsigned k) {
    return (x + y) % 7 == 0 ? NaN : (k >= 2 && k <= 4 ? 1.0f : 0.0f);
  });
  const auto registered = LST::RegisterToSheet(sheet, 1.0);
  for (size_t i = 0; i < 1400; ++i)
  {
    EXPECT_EQ(std::isnan(sheet->GetBufferPointer()[i]), std::isnan(registered->GetBufferPointer()[i]));
  }
  EXPECT_THROW(LST::RegisterToSheet(sheet, -1.0), itk::ExceptionObject);
  EXPECT_THROW(LST::RegisterToSheet(nullptr, 1.0), itk::ExceptionObject);
}

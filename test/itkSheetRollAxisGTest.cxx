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
#include "itkSheetRollAxis.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace {
using MaskImage = itk::SheetRollAxis::SheetImageType;
using FloatImage = itk::SheetRollAxis::IntensityImageType;

constexpr long Nx = 40, Ny = 40, Nz = 8;

template <typename TImage>
typename TImage::Pointer
MakeImage(const typename TImage::SizeType & size = { { Nx, Ny, Nz } })
{
  auto                        image = TImage::New();
  typename TImage::RegionType region;
  region.SetSize(size);
  image->SetRegions(region);
  image->Allocate();
  image->FillBuffer(0);
  return image;
}

size_t
At(long i, long j, long k)
{
  return static_cast<size_t>((k * Ny + j) * Nx + i);
}

// Sheet 1 along y = 10..12; another sheet (2) along y = 24..26, which bends towards sheet 1
// for x >= 32 (there at y = 14..15, two voxels from it); air N(100, 10), sheets 1000.
struct Scene
{
  MaskImage::Pointer  Mask = MakeImage<MaskImage>();
  FloatImage::Pointer Values = MakeImage<FloatImage>();

  Scene()
  {
    std::mt19937                     random(7);
    std::normal_distribution<double> noise(100.0, 10.0);
    for (long k = 0; k < Nz; ++k)
    {
      for (long j = 0; j < Ny; ++j)
      {
        for (long i = 0; i < Nx; ++i)
        {
          const bool sheet = i >= 4 && i < 36 && j >= 10 && j <= 12;
          const bool other = i >= 4 && i < 36 && (i >= 32 ? (j >= 14 && j <= 15) : (j >= 24 && j <= 26));
          Mask->GetBufferPointer()[At(i, j, k)] = sheet ? 1 : other ? 2 : 0;
          Values->GetBufferPointer()[At(i, j, k)] = static_cast<float>(sheet || other ? 1000.0 : noise(random));
        }
      }
    }
    // The other sheet's blurred rim, one voxel out of its mask.
    for (long k = 0; k < Nz; ++k)
    {
      for (long i = 4; i < 32; ++i)
      {
        Values->GetBufferPointer()[At(i, 27, k)] = 500.0f;
      }
    }
  }
};
} // namespace

TEST(SheetRollAxis, OtherSheetsAreHiddenInTheBoxsAir)
{
  Scene         scene;
  const Scene   original;
  const float * before = original.Values->GetBufferPointer();
  const float * after = scene.Values->GetBufferPointer();
  itk::SheetRollAxis::HideOtherSheets(scene.Mask, scene.Values);

  double sum = 0.0, squares = 0.0;
  size_t hidden = 0;
  for (long k = 0; k < Nz; ++k)
  {
    for (long j = 0; j < Ny; ++j)
    {
      for (long i = 0; i < Nx; ++i)
      {
        const size_t  n = At(i, j, k);
        const uint8_t was = original.Mask->GetBufferPointer()[n];
        EXPECT_EQ(scene.Mask->GetBufferPointer()[n], was == 1 ? 1 : 0);
        if (was == 1)
        {
          EXPECT_EQ(after[n], before[n]);
        }
        else if (was == 2 || (j == 27 && i >= 4 && i < 32))
        {
          // The other sheet and its rim now read as air.
          EXPECT_LT(after[n], 160.0f) << i << " " << j << " " << k;
          sum += after[n];
          squares += after[n] * after[n];
          ++hidden;
        }
        else if (j >= 13 && j <= 14 && i >= 30 && i < 36)
        {
          // Within two voxels of both sheets (the gap where they come close): as scanned.
          EXPECT_EQ(after[n], before[n]);
        }
        else if (j <= 5 || j >= 32)
        {
          // Far from every sheet.
          EXPECT_EQ(after[n], before[n]);
        }
      }
    }
  }
  ASSERT_GT(hidden, 500u);
  const double mean = sum / static_cast<double>(hidden);
  const double deviation = std::sqrt(squares / static_cast<double>(hidden) - mean * mean);
  // Drawn from the air: its level and its noise.
  EXPECT_NEAR(mean, 100.0, 2.0);
  EXPECT_NEAR(deviation, 10.0, 2.0);
}

TEST(SheetRollAxis, ABoxWithoutOtherSheetsIsLeftAsItIs)
{
  Scene scene;
  for (size_t n = 0; n < static_cast<size_t>(Nx * Ny * Nz); ++n)
  {
    if (scene.Mask->GetBufferPointer()[n] == 2)
    {
      scene.Mask->GetBufferPointer()[n] = 0;
    }
  }
  const Scene copy;
  itk::SheetRollAxis::HideOtherSheets(scene.Mask, scene.Values);
  for (size_t n = 0; n < static_cast<size_t>(Nx * Ny * Nz); ++n)
  {
    ASSERT_EQ(scene.Values->GetBufferPointer()[n], copy.Values->GetBufferPointer()[n]);
  }

  // A mask without intensities: the other sheets' marks are cleared.
  Scene alone;
  itk::SheetRollAxis::HideOtherSheets(alone.Mask, nullptr);
  for (size_t n = 0; n < static_cast<size_t>(Nx * Ny * Nz); ++n)
  {
    ASSERT_LE(alone.Mask->GetBufferPointer()[n], 1);
  }
}

namespace {
// A short, wide roll (a disc more than a tube: 8 to 11 turns 5 voxels apart, 18 to 26
// voxels wide), its axis tilted 4 to 15 degrees from the slice normal about a random
// direction, in white noise of 0.8 to 1.1 times the sheet's contrast; drawn from
// `seed`. The mask is the noise-free sheet; the intensities carry the noise.
struct ShortRoll
{
  MaskImage::Pointer           Mask;
  FloatImage::Pointer          Values;
  itk::SheetRollAxis::AxisType Axis;
  double                       Noise = 0.0;

  // `acrossSlices`: the noise smoothed over three slices along z, as projection noise is
  // stronger within the slices than across them; its level then `noise`. `wave`: the
  // radius changes along the axis by this many voxels either way, one and a half periods
  // over the width; `squash`: the section's axes ratio.
  explicit ShortRoll(unsigned seed,
                     bool     acrossSlices = false,
                     double   noise = 0.0,
                     double   wave = 0.0,
                     double   squash = 1.0)
  {
    std::mt19937                           random(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double turns = 8.0 + 3.0 * uniform(random), pitch = 5.0, thickness = 2.5, inner = 8.0;
    const double width = 18.0 + 8.0 * uniform(random);
    const double tilt = (4.0 + 11.0 * uniform(random)) * M_PI / 180.0, about = 2.0 * M_PI * uniform(random);
    Noise = acrossSlices ? noise : 0.8 + 0.3 * uniform(random);
    const double outer = inner + turns * pitch + thickness;
    const long   n = static_cast<long>(2.0 * outer + 8.0),
               nz = static_cast<long>(width + 2.0 * outer * std::sin(tilt) + 8.0);
    // Roll frame: axis a = (sin t cos b, sin t sin b, cos t), u and v across it.
    const double a[3] = { std::sin(tilt) * std::cos(about), std::sin(tilt) * std::sin(about), std::cos(tilt) };
    double       u[3] = { -std::sin(about), std::cos(about), 0.0 };
    const double v[3] = { a[1] * u[2] - a[2] * u[1], a[2] * u[0] - a[0] * u[2], a[0] * u[1] - a[1] * u[0] };
    for (unsigned r = 0; r < 3; ++r)
    {
      Axis[r] = a[r];
    }
    const MaskImage::SizeType size = {
      { static_cast<itk::SizeValueType>(n), static_cast<itk::SizeValueType>(n), static_cast<itk::SizeValueType>(nz) }
    };
    Mask = MakeImage<MaskImage>(size);
    Values = MakeImage<FloatImage>(size);
    // White noise, or its mean over three slices scaled back to the level.
    std::normal_distribution<double> white(0.0, Noise);
    std::vector<double>              noiseAt(static_cast<size_t>(n * n * nz));
    std::generate(noiseAt.begin(), noiseAt.end(), [&]() { return white(random); });
    if (acrossSlices)
    {
      const std::vector<double> raw = noiseAt;
      const auto                plane = static_cast<size_t>(n * n);
      for (size_t q = 0; q < raw.size(); ++q)
      {
        const size_t below = q >= plane ? q - plane : q + plane, above = q + plane < raw.size() ? q + plane : q - plane;
        noiseAt[q] = (raw[below] + raw[q] + raw[above]) / std::sqrt(3.0);
      }
    }
    const double c = 0.5 * static_cast<double>(n - 1), cz = 0.5 * static_cast<double>(nz - 1);
    size_t       index = 0;
    for (long k = 0; k < nz; ++k)
    {
      for (long j = 0; j < n; ++j)
      {
        for (long i = 0; i < n; ++i, ++index)
        {
          const double p[3] = { static_cast<double>(i) - c, static_cast<double>(j) - c, static_cast<double>(k) - cz };
          const double x = p[0] * u[0] + p[1] * u[1] + p[2] * u[2], y = p[0] * v[0] + p[1] * v[1] + p[2] * v[2];
          const double w = p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
          const double rho = std::hypot(x, y / squash), phi = std::atan2(y / squash, x) + M_PI;
          const double start = inner + wave * std::sin(3.0 * M_PI * w / width);
          // Distance to the nearest turn of rho = start + pitch (phi + 2 pi m) / (2 pi).
          const double m = std::round((rho - start - pitch * phi / (2.0 * M_PI)) / pitch);
          const double along = phi / (2.0 * M_PI) + m;
          const double d = along < 0.0 || along > turns ? 1e9 : rho - start - pitch * along;
          const double occupancy = std::clamp(0.5 * thickness - std::abs(d) + 0.5, 0.0, 1.0) *
                                   std::clamp(0.5 * width - std::abs(w) + 0.5, 0.0, 1.0);
          Mask->GetBufferPointer()[index] = occupancy >= 0.5 ? 1 : 0;
          Values->GetBufferPointer()[index] = static_cast<float>(occupancy + noiseAt[index]);
        }
      }
    }
  }
};
} // namespace

// Noise adds gradient energy in every direction: strong enough, it brings a short roll's two
// large structure-tensor eigenvalues within 2.5 times its axis's, and the line through the
// slices' centroids, taken instead, wanders far from the axis. Two large eigenvalues that
// are comparable with each other and clearly above the axis's still make a roll. Rolls
// drawn at run time.
TEST(SheetRollAxis, AShortRollInStrongNoiseHasItsAxisFromTheTensor)
{
  const unsigned first = vu::RunTimeSeed();
  for (unsigned draw = 0; draw < 3; ++draw)
  {
    const ShortRoll roll(first + draw);
    bool            fromTensor = false;
    const auto      axis = itk::SheetRollAxis::Estimate(roll.Mask, roll.Values, fromTensor);
    const double    angle = std::acos(std::clamp(std::abs(axis * roll.Axis), 0.0, 1.0)) * 180.0 / M_PI;
    EXPECT_TRUE(fromTensor) << "seed " << first + draw;
    EXPECT_LT(angle, 2.0) << "seed " << first + draw << ", noise " << roll.Noise;
  }
}

// Noise stronger within the slices than across them (as projection noise is) adds gradient
// energy across the axis more than along it and tips the tensor's axis towards the slice
// normal; the noise's own tensor, measured in the air, is taken off. Rolls drawn at run time.
TEST(SheetRollAxis, NoiseStrongerWithinTheSlicesDoesNotTipTheAxis)
{
  // The tilt found less the true tilt, averaged over six rolls: each roll's noise moves its
  // axis a little either way; only the tipping is the same for all. Measured: 1.2 to 1.7
  // degrees towards the slice normal with the whole tensor, 0.4 to 0.7 with the air's off.
  const unsigned first = vu::RunTimeSeed();
  const unsigned draws = 6;
  double         meanError = 0.0;
  for (unsigned draw = 0; draw < draws; ++draw)
  {
    const ShortRoll roll(first + draw, true, 0.6);
    bool            fromTensor = false;
    const auto      axis = itk::SheetRollAxis::Estimate(roll.Mask, roll.Values, fromTensor);
    EXPECT_TRUE(fromTensor) << "seed " << first + draw;
    meanError += (std::acos(std::abs(axis[2])) - std::acos(std::abs(roll.Axis[2]))) * 180.0 / M_PI / draws;
  }
  EXPECT_LT(std::abs(meanError), 0.9) << "seeds from " << first;
}

// A disc-like roll whose radius changes along its axis and whose section is squashed tips
// its sheet's normals towards the axis and spreads them unevenly across it: the tensor's
// middle eigenvalue can come within 1.5 times its smallest, and the centroids of slices
// that cut the tilted disc's faces move across it, not along it, so that their line,
// refined on each resampled grid, leaves the axis by up to 90 degrees, or stays near the
// slice normal but 5 to 8 degrees off the axis (once in about 30 rolls). The tensor's axis,
// within 45 degrees of the slice normal, is then taken: wherever the centroids' line
// leaves the slice normal by more than 45 degrees, or the tensor's axis by more than 2
// where the tensor shows a spread of the normals. Rolls drawn at run time; measured over
// 1280 rolls: within 5.2 degrees of the axis (all but one within 4.6), against up to 90
// degrees with the centroids' line alone and up to 7.6 with only the first of those two
// rules.
TEST(SheetRollAxis, ADiscLikeRollIsResampledAlongTheTensorsAxis)
{
  const unsigned first = vu::RunTimeSeed();
  unsigned       fromCentroids = 0;
  for (unsigned draw = 0; draw < 8; ++draw)
  {
    ShortRoll  roll(first + draw, false, 0.0, 1.0, 0.6);
    bool       fromTensor = false;
    const auto estimate = itk::SheetRollAxis::Estimate(roll.Mask, roll.Values, fromTensor);
    fromCentroids += fromTensor ? 0 : 1;
    MaskImage::Pointer       mask = roll.Mask, data;
    FloatImage::Pointer      values = roll.Values;
    std::vector<std::string> warnings;
    itk::SheetRollAxis::Align(mask, values, data, 1.0, warnings);
    itk::SheetRollAxis::AxisType axis;
    for (unsigned r = 0; r < 3; ++r)
    {
      axis[r] = mask->GetDirection()[r][2];
    }
    const double angle = std::acos(std::clamp(std::abs(axis * roll.Axis), 0.0, 1.0)) * 180.0 / M_PI;
    std::cout << "seed " << first + draw << ": " << (fromTensor ? "tensor" : "centroids") << " estimate "
              << std::acos(std::clamp(std::abs(estimate * roll.Axis), 0.0, 1.0)) * 180.0 / M_PI
              << " degrees off, aligned " << angle << " degrees off" << std::endl;
    EXPECT_LT(angle, 6.0) << "seed " << first + draw;
  }
  std::cout << fromCentroids << " of 8 from the centroids first" << std::endl;
}

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

#include "gtest/gtest.h"

#include <cmath>
#include <random>

namespace {
using MaskImage = itk::SheetRollAxis::SheetImageType;
using FloatImage = itk::SheetRollAxis::IntensityImageType;

constexpr long Nx = 40, Ny = 40, Nz = 8;

template <typename TImage>
typename TImage::Pointer
MakeImage()
{
  auto                        image = TImage::New();
  typename TImage::RegionType region;
  typename TImage::SizeType   size = { { Nx, Ny, Nz } };
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

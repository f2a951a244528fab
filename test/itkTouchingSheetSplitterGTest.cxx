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
#include "itkTouchingSheetSplitter.h"

#include "itkDiscreteGaussianImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIterator.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

namespace {
using FloatImage = itk::Image<float, 3>;
using PieceImage = itk::Image<uint8_t, 3>;

struct Scene
{
  FloatImage::Pointer Values;
  PieceImage::Pointer Piece;
  // The true sheet of each voxel (0: air), nearest sheet middle.
  std::vector<int> Truth;
};

// Sheets parallel to the x-z plane, `thickness` voxels thick, centred at rows `middles`;
// the first bulges by `bump` voxels towards the second over a disc of radius 6 at the
// middle of the sheet, and the scene is blurred (sigma 0.7 voxel) with noise at SNR 8.
Scene
MakeScene(const std::vector<double> & middles, double thickness, double bump, unsigned seed)
{
  const unsigned         nx = 48, ny = 40, nz = 24;
  auto                   clean = FloatImage::New();
  FloatImage::RegionType region;
  region.SetSize({ { nx, ny, nz } });
  clean->SetRegions(region);
  clean->Allocate();
  Scene scene;
  scene.Truth.assign(region.GetNumberOfPixels(), 0);
  for (unsigned z = 0; z < nz; ++z)
  {
    for (unsigned y = 0; y < ny; ++y)
    {
      for (unsigned x = 0; x < nx; ++x)
      {
        double       value = 0.0, nearest = 1e9;
        int          owner = 0;
        const double r2 = (x - 24.0) * (x - 24.0) + (z - 12.0) * (z - 12.0);
        for (size_t s = 0; s < middles.size(); ++s)
        {
          const double middle = middles[s] + (s == 0 ? bump * std::exp(-r2 / (2.0 * 6.0 * 6.0)) : 0.0);
          const double d = std::abs(y - middle);
          value = std::max(value, std::clamp(0.5 * thickness - d + 0.5, 0.0, 1.0));
          if (d < nearest)
          {
            nearest = d;
            owner = static_cast<int>(s) + 1;
          }
        }
        const size_t v = (static_cast<size_t>(z) * ny + y) * nx + x;
        clean->GetBufferPointer()[v] = static_cast<float>(value);
        scene.Truth[v] = value > 0.5 ? owner : 0;
      }
    }
  }
  auto blur = itk::DiscreteGaussianImageFilter<FloatImage, FloatImage>::New();
  blur->SetInput(clean);
  blur->SetVariance(0.49);
  blur->SetUseImageSpacing(false);
  blur->Update();
  scene.Values = blur->GetOutput();
  std::mt19937                    random(seed);
  std::normal_distribution<float> noise(0.0f, 1.0f / 8.0f);
  scene.Piece = PieceImage::New();
  scene.Piece->SetRegions(region);
  scene.Piece->Allocate();
  for (size_t v = 0; v < region.GetNumberOfPixels(); ++v)
  {
    scene.Values->GetBufferPointer()[v] += noise(random);
    scene.Piece->GetBufferPointer()[v] = scene.Truth[v] != 0 ? 1 : 0;
  }
  return scene;
}
} // namespace

// Two sheets 2 voxels apart, fused where one bulges onto the other (no gap left): one
// piece of the mask, split into the two sheets; every voxel of each goes to its own.
TEST(TouchingSheetSplitter, FusedSheetsAreSplitBetweenThem)
{
  const unsigned seed = vu::RunTimeSeed();
  const Scene    scene = MakeScene({ 12.0, 17.0 }, 3.0, 2.25, seed);
  const auto     split = itk::SplitTouchingSheets(scene.Values, scene.Piece, 1.0, 200);
  ASSERT_EQ(split.Sheets, 2u) << "seed " << seed;
  // Each true sheet's voxels carry one label, the other sheet's the other.
  size_t counts[3][3] = {};
  for (size_t v = 0; v < scene.Truth.size(); ++v)
  {
    ++counts[scene.Truth[v]][split.Labels->GetBufferPointer()[v]];
  }
  EXPECT_EQ(counts[0][1] + counts[0][2], 0u) << "air labelled";
  const size_t a = counts[1][1] > counts[1][2] ? 1 : 2, b = 3 - a;
  const double wrongA = static_cast<double>(counts[1][b]) / (counts[1][1] + counts[1][2]);
  const double wrongB = static_cast<double>(counts[2][a]) / (counts[2][1] + counts[2][2]);
  EXPECT_LT(wrongA, 0.01) << "seed " << seed;
  EXPECT_LT(wrongB, 0.01) << "seed " << seed;
}

// One sheet, bent, thin or thick (its two faces are not two sheets): never split.
TEST(TouchingSheetSplitter, OneSheetStaysWhole)
{
  const unsigned seed = vu::RunTimeSeed();
  for (const double thickness : { 3.0, 7.0 })
  {
    const Scene scene = MakeScene({ 15.0 }, thickness, 4.0, seed);
    const auto  split = itk::SplitTouchingSheets(scene.Values, scene.Piece, 1.0, 200);
    EXPECT_EQ(split.Sheets, 1u) << "seed " << seed << ", thickness " << thickness;
    for (size_t v = 0; v < scene.Truth.size(); ++v)
    {
      ASSERT_EQ(split.Labels->GetBufferPointer()[v], scene.Truth[v] != 0 ? 1 : 0);
    }
  }
}

// Four pages 2.5 voxels apart whose gaps the mask fills (a noisy scan thresholded after
// smoothing): the piece is a slab as thick as the four with their gaps, and the scale its
// thickness sets sees one plate or two. Given the scan's thinnest sheet (a page lying apart
// elsewhere), the piece is split again at that sheet's scale, into the four pages.
TEST(TouchingSheetSplitter, FusedPagesAreSplitAtTheThinnestSheetsScale)
{
  const unsigned seed = vu::RunTimeSeed();
  const Scene    scene = MakeScene({ 10.0, 15.0, 20.0, 25.0 }, 2.5, 0.0, seed);
  auto           slab = PieceImage::New();
  slab->SetRegions(scene.Piece->GetBufferedRegion());
  slab->Allocate();
  const auto size = slab->GetBufferedRegion().GetSize();
  for (size_t v = 0; v < scene.Truth.size(); ++v)
  {
    const size_t y = (v / size[0]) % size[1];
    slab->GetBufferPointer()[v] = scene.Truth[v] != 0 || (y > 10 && y < 25) ? 1 : 0;
  }
  const auto split = itk::SplitTouchingSheets(scene.Values, slab, 1.0, 200, 2.5);
  ASSERT_EQ(split.Sheets, 4u) << "seed " << seed;
  // Each page's voxels carry one label, each its own.
  std::vector<std::array<size_t, 5>> counts(5, std::array<size_t, 5>{});
  for (size_t v = 0; v < scene.Truth.size(); ++v)
  {
    ++counts[scene.Truth[v]][split.Labels->GetBufferPointer()[v]];
  }
  std::vector<bool> taken(5, false);
  for (int page = 1; page <= 4; ++page)
  {
    const auto & row = counts[page];
    const auto   label = std::max_element(row.begin() + 1, row.end()) - row.begin();
    EXPECT_FALSE(taken[label]) << "seed " << seed << ": two pages share label " << label;
    taken[label] = true;
    const size_t total = row[1] + row[2] + row[3] + row[4];
    EXPECT_GE(static_cast<double>(row[label]) / static_cast<double>(total), 0.95)
      << "seed " << seed << ", page " << page;
  }
}

// A thick sheet in a scan whose thinnest sheet is much thinner: its two faces are not
// split into two sheets at the thinner sheet's scale.
TEST(TouchingSheetSplitter, AThickSheetStaysWholeAtAThinnerSheetsScale)
{
  const unsigned seed = vu::RunTimeSeed();
  const Scene    scene = MakeScene({ 15.0 }, 7.0, 4.0, seed);
  EXPECT_EQ(itk::SplitTouchingSheets(scene.Values, scene.Piece, 1.0, 200, 2.5).Sheets, 1u) << "seed " << seed;
}

// The other sheets' voxels and their blurred faces hold the background; this sheet's and
// the air elsewhere keep their values.
TEST(TouchingSheetSplitter, OtherSheetsAreBlanked)
{
  const Scene scene = MakeScene({ 10.0, 20.0 }, 3.0, 0.0, 7);
  auto        labels = itk::Image<uint16_t, 3>::New();
  labels->CopyInformation(scene.Values);
  labels->SetRegions(scene.Values->GetBufferedRegion());
  labels->Allocate();
  for (size_t v = 0; v < scene.Truth.size(); ++v)
  {
    labels->GetBufferPointer()[v] = static_cast<uint16_t>(scene.Truth[v]);
  }
  EXPECT_THROW(itk::BlankOtherSheets(scene.Values, nullptr, 1), itk::ExceptionObject);
  const auto blanked = itk::BlankOtherSheets(scene.Values, labels, 1);
  const auto size = scene.Values->GetBufferedRegion().GetSize();
  double     sum = 0.0, squares = 0.0;
  size_t     count = 0;
  for (size_t v = 0; v < scene.Truth.size(); ++v)
  {
    const float before = scene.Values->GetBufferPointer()[v], after = blanked->GetBufferPointer()[v];
    const long  y = static_cast<long>((v / size[0]) % size[1]);
    if (scene.Truth[v] == 2)
    {
      sum += after;
      squares += static_cast<double>(after) * after;
      ++count;
    }
    else if (scene.Truth[v] == 1 || std::abs(y - 20) > 3)
    {
      ASSERT_EQ(after, before) << "voxel " << v;
    }
  }
  // The other sheet holds air as scanned: about 0, with the scan's noise (1/8), not a
  // constant without noise.
  ASSERT_GT(count, 0u);
  const double mean = sum / count, deviation = std::sqrt(std::max(0.0, squares / count - mean * mean));
  EXPECT_LT(std::abs(mean), 0.05);
  EXPECT_GT(deviation, 0.6 / 8.0);
  EXPECT_LT(deviation, 1.4 / 8.0);
}

// The thickness of every label at once (twice its volume over the area of its faces to
// other voxels or the region's border) against a count made face by face, on labels drawn
// at run time, in the whole image and in a part of it; labels above the count asked for
// count as other voxels, and PlateThickness gives one label's.
TEST(TouchingSheetSplitter, PlateThicknessOfEveryLabelInOnePass)
{
  using LabelImage = itk::Image<uint16_t, 3>;
  const unsigned      seed = vu::RunTimeSeed();
  std::mt19937        random(seed);
  auto                labels = LabelImage::New();
  itk::ImageRegion<3> whole;
  whole.SetSize({ { 23, 17, 11 } });
  labels->SetRegions(whole);
  const double spacing[3] = { 0.5, 0.5, 0.8 };
  labels->SetSpacing(spacing);
  labels->Allocate();
  std::uniform_int_distribution<int> draw(0, 5);
  // Slabs along y with a label each, their borders moved at random: plates of a few voxels.
  for (itk::ImageRegionIterator<LabelImage> it(labels, whole); !it.IsAtEnd(); ++it)
  {
    const auto i = it.GetIndex();
    it.Set(static_cast<uint16_t>(draw(random) == 0 ? draw(random) : (i[1] + draw(random) / 3) / 4));
  }
  itk::ImageRegion<3> part;
  part.SetIndex({ { 2, 3, 1 } });
  part.SetSize({ { 18, 12, 9 } });
  const double voxel = std::cbrt(0.5 * 0.5 * 0.8);
  for (const auto & region : { whole, part })
  {
    const std::vector<double> all = itk::PlateThicknessPerLabel(labels.GetPointer(), region, 3);
    ASSERT_EQ(all.size(), 4u);
    for (uint16_t l = 1; l <= 3; ++l)
    {
      double voxels = 0.0, faces = 0.0;
      for (itk::ImageRegionConstIteratorWithIndex<LabelImage> it(labels, region); !it.IsAtEnd(); ++it)
      {
        if (it.Get() != l)
        {
          continue;
        }
        voxels += 1.0;
        for (unsigned d = 0; d < 3; ++d)
        {
          for (int side : { -1, 1 })
          {
            auto next = it.GetIndex();
            next[d] += side;
            faces += !region.IsInside(next) || labels->GetPixel(next) != l ? 1.0 : 0.0;
          }
        }
      }
      ASSERT_GT(faces, 0.0) << "seed " << seed;
      EXPECT_NEAR(all[l], 2.0 * voxel * voxels / faces, 1e-12) << "label " << l << ", seed " << seed;
      EXPECT_EQ(itk::PlateThickness(labels.GetPointer(), region, [l](uint16_t v) { return v == l; }), all[l]);
    }
    // Asked for two labels, label 3's voxels are other voxels, as they were for 1 and 2.
    const std::vector<double> two = itk::PlateThicknessPerLabel(labels.GetPointer(), region, 2);
    ASSERT_EQ(two.size(), 3u);
    EXPECT_EQ(two[1], all[1]);
    EXPECT_EQ(two[2], all[2]);
  }
}

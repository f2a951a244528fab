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
#include "itkDicomSeriesGeometry.h"

#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkMath.h"

#include "gtest/gtest.h"

#include <cmath>
#include <limits>

namespace {
using ImageType = itk::Image<float, 3>;

/** Axial slices of 20 x 10 pixels of 0.5 x 0.8 mm at the given locations (mm along z,
 * in the order given), their origins shifted along y by shear x location. */
itk::DicomSliceStack
AxialStack(const std::vector<double> & locations, double shear = 0.0)
{
  itk::DicomSliceStack stack;
  stack.Row[0] = 1.0;
  stack.Column[1] = 1.0;
  stack.PixelSpacing[0] = 0.5;
  stack.PixelSpacing[1] = 0.8;
  stack.Size[0] = 20;
  stack.Size[1] = 10;
  for (size_t k = 0; k < locations.size(); ++k)
  {
    ImageType::PointType position;
    position[0] = -3.0;
    position[1] = 2.0 + shear * locations[k];
    position[2] = locations[k];
    stack.Slices.push_back({ "slice" + std::to_string(k), position });
  }
  return stack;
}

std::vector<double>
Regular(size_t count, double spacing, double start = 0.0)
{
  std::vector<double> locations;
  for (size_t k = 0; k < count; ++k)
  {
    locations.push_back(start + static_cast<double>(k) * spacing);
  }
  return locations;
}

std::string
Failure(const itk::DicomSliceStack & stack)
{
  try
  {
    itk::AnalyseDicomSliceStack(stack, 0.05);
  }
  catch (const itk::ExceptionObject & e)
  {
    return e.GetDescription();
  }
  return {};
}

/** The stack's slices as read (slice k at index k), each pixel holding f at its position. */
template <typename TFunction>
ImageType::Pointer
SampleStack(const itk::DicomSliceStack & stack, TFunction f)
{
  auto image = ImageType::New();
  image->SetRegions(ImageType::SizeType{ { stack.Size[0], stack.Size[1], stack.Slices.size() } });
  image->Allocate();
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    const auto           index = it.GetIndex();
    ImageType::PointType p = stack.Slices[index[2]].Position;
    for (unsigned d = 0; d < 3; ++d)
    {
      p[d] += index[0] * stack.PixelSpacing[0] * stack.Row[d] + index[1] * stack.PixelSpacing[1] * stack.Column[d];
    }
    it.Set(f(p));
  }
  return image;
}

ImageType::Pointer
Resample(const ImageType::Pointer &       stack,
         const itk::DicomSeriesGeometry & geometry,
         const itk::RegularGrid &         grid,
         itk::SliceInterpolatorEnum       interpolator)
{
  std::vector<itk::ProcessObject::Pointer> pipeline;
  ImageType * output = itk::AppendSliceStackResampling(stack, geometry, grid, interpolator, pipeline);
  output->Update();
  return output;
}
} // namespace

TEST(DicomSeriesGeometry, InterpolatorNames)
{
  for (auto interpolator : { itk::SliceInterpolatorEnum::NearestNeighbor,
                             itk::SliceInterpolatorEnum::Linear,
                             itk::SliceInterpolatorEnum::BSpline })
  {
    EXPECT_EQ(itk::SliceInterpolatorFromString(itk::ToString(interpolator)), interpolator);
  }
  EXPECT_THROW(itk::SliceInterpolatorFromString("cubic"), itk::ExceptionObject);
}

TEST(DicomSeriesGeometry, RegularStackIsOrderedAndRegular)
{
  // Given out of order, with 0.1 mm rounding (within 5% of 2.5 mm).
  const auto geometry = itk::AnalyseDicomSliceStack(AxialStack({ 5.0, 0.0, 7.6, 2.5, 10.0 }), 0.05);
  EXPECT_TRUE(geometry.IsRegular());
  EXPECT_FALSE(geometry.Sheared);
  EXPECT_EQ(geometry.Stack.Slices.front().File, "slice1");
  EXPECT_EQ(geometry.Stack.Slices.back().File, "slice4");
  EXPECT_NEAR(geometry.MeanSpacing, 2.5, 1e-12);
  ASSERT_EQ(geometry.Runs.size(), 1u);
  EXPECT_TRUE(geometry.Gaps.empty());
  EXPECT_FALSE(geometry.HasSpacingChanges());
  EXPECT_NEAR(geometry.Normal[2], 1.0, 1e-12);
}

TEST(DicomSeriesGeometry, ShearIsMeasuredFromThePositions)
{
  const double shear = -std::tan(18.5 * itk::Math::pi / 180.0);
  const auto   geometry = itk::AnalyseDicomSliceStack(AxialStack(Regular(28, 5.0), shear), 0.05);
  EXPECT_TRUE(geometry.Sheared);
  EXPECT_TRUE(geometry.EvenlySpaced);
  EXPECT_FALSE(geometry.IsRegular());
  EXPECT_NEAR(geometry.TiltDegrees, 18.5, 1e-9);
  EXPECT_NEAR(geometry.DriftPerMillimetre[0], 0.0, 1e-12);
  EXPECT_NEAR(geometry.DriftPerMillimetre[1], shear, 1e-12);
  EXPECT_NEAR(geometry.MaximumDrift, 135.0 * -shear, 1e-9);
  EXPECT_EQ(geometry.MaximumDriftSlice, 27u);
  EXPECT_NEAR(geometry.ColumnOffsets.back(), 135.0 * shear, 1e-9);
  const std::string text = geometry.DescribeShear("18.5");
  EXPECT_NE(text.find("about 18.5 degrees, GantryDetectorTilt 18.5"), std::string::npos) << text;
  EXPECT_NE(text.find("slice27"), std::string::npos) << text;
  EXPECT_NE(text.find("column direction"), std::string::npos) << text;

  // Half a pixel (0.25 mm) of drift over the whole stack still reads as a box.
  EXPECT_FALSE(itk::AnalyseDicomSliceStack(AxialStack(Regular(28, 5.0), 0.24 / 135.0), 0.05).Sheared);
}

TEST(DicomSeriesGeometry, SpacingThatChangesIsTwoRunsNotAGap)
{
  // A hospital head CT series: 4 mm, then 7 mm (7 > 1.5 x 4, yet no slice is missing).
  std::vector<double> locations = Regular(10, 4.0);
  for (int k = 1; k <= 8; ++k)
  {
    locations.push_back(36.0 + 7.0 * k);
  }
  const auto geometry = itk::AnalyseDicomSliceStack(AxialStack(locations), 0.05);
  EXPECT_FALSE(geometry.EvenlySpaced);
  EXPECT_TRUE(geometry.Gaps.empty());
  ASSERT_EQ(geometry.Runs.size(), 2u);
  EXPECT_EQ(geometry.Runs[0].First, 0u);
  EXPECT_EQ(geometry.Runs[0].Last, 9u);
  EXPECT_NEAR(geometry.Runs[0].Spacing, 4.0, 1e-12);
  EXPECT_EQ(geometry.Runs[1].First, 9u);
  EXPECT_EQ(geometry.Runs[1].Last, 17u);
  EXPECT_NEAR(geometry.Runs[1].Spacing, 7.0, 1e-12);
  EXPECT_TRUE(geometry.HasSpacingChanges());
  EXPECT_NEAR(geometry.SmallestSpacing(), 4.0, 1e-12);
  EXPECT_EQ(geometry.DescribeRuns(),
            "4 mm from 0 mm (slice0) to 36 mm (slice9), 7 mm from 36 mm (slice9) to 92 mm (slice17)");
}

TEST(DicomSeriesGeometry, MissingSlicesAreNamedWithTheirPositions)
{
  // 4 mm apart; slices at 16 and 20 mm missing (a 12 mm gap), and one at 60 mm where the
  // spacing becomes 7 mm (a gap of 11 mm > 1.5 x the 5.5 mm around it).
  std::vector<double> locations = { 0, 4, 8, 12, 24, 28, 32, 36, 40, 44, 48, 52, 56, 67, 74, 81, 88 };
  const auto          geometry = itk::AnalyseDicomSliceStack(AxialStack(locations), 0.05);
  ASSERT_EQ(geometry.Gaps.size(), 2u);
  EXPECT_EQ(geometry.Gaps[0].Before, 3u);
  EXPECT_NEAR(geometry.Gaps[0].Size, 12.0, 1e-12);
  EXPECT_NEAR(geometry.Gaps[0].UsualSpacing, 4.0, 1e-12);
  EXPECT_EQ(geometry.Gaps[0].Missing, 2u);
  EXPECT_EQ(geometry.DescribeGap(geometry.Gaps[0]),
            "2 missing slice(s): a gap of 12 mm between 12 mm (slice3) and 24 mm (slice4), usual spacing 4 mm");
  EXPECT_EQ(geometry.Gaps[1].Before, 12u);
  EXPECT_EQ(geometry.Gaps[1].Missing, 1u);
  EXPECT_EQ(geometry.NumberOfMissingSlices(), 3u);
  // The gaps end the runs; the spacing change stays a change.
  ASSERT_EQ(geometry.Runs.size(), 3u);
  EXPECT_NEAR(geometry.Runs[2].Spacing, 7.0, 1e-12);
  EXPECT_TRUE(geometry.HasSpacingChanges());
}

TEST(DicomSeriesGeometry, BadStacksAreRefused)
{
  EXPECT_NE(Failure(AxialStack({ 1.0 })).find("fewer than two slices"), std::string::npos);
  auto flat = AxialStack(Regular(3, 1.0));
  flat.Column = flat.Row;
  EXPECT_NE(Failure(flat).find("degenerate ImageOrientationPatient"), std::string::npos);
  const std::string duplicate = Failure(AxialStack({ 0.0, 1.0, 1.0, 2.0 }));
  EXPECT_NE(duplicate.find("duplicate slice position (1 mm along the normal) in slice1 and slice2"), std::string::npos)
    << duplicate;
}

TEST(DicomSeriesGeometry, GridHoldsEverySlice)
{
  // 0.3 mm per mm of drift towards -y over 20 mm: 6 mm = 7.5 rows of 0.8 mm.
  const auto geometry = itk::AnalyseDicomSliceStack(AxialStack(Regular(5, 5.0), -0.3), 0.05);
  const auto grid = itk::MakeRegularGrid(geometry, 2.5);
  EXPECT_EQ(grid.Size, (ImageType::SizeType{ { 20, 18, 9 } }));
  EXPECT_NEAR(grid.Origin[0], -3.0, 1e-12);
  EXPECT_NEAR(grid.Origin[1], 2.0 - 8 * 0.8, 1e-12);
  EXPECT_NEAR(grid.Origin[2], 0.0, 1e-12);
  EXPECT_NEAR(grid.Spacing[1], 0.8, 1e-12);
  EXPECT_NEAR(grid.Spacing[2], 2.5, 1e-12);
  EXPECT_TRUE(grid.Direction == ImageType::DirectionType::GetIdentity());
  EXPECT_THROW(itk::MakeRegularGrid(geometry, 0.0), itk::ExceptionObject);
}

// A linear function of position is reproduced exactly by linear interpolation, whatever
// the shear and the spacing: the resampled grid must hold it wherever a slice covers it,
// and be NaN exactly where CountVoxelsWithoutData says (slice edges fall on half pixels
// of the grid here, the hardest case for that count).
TEST(DicomSeriesGeometry, ResamplingFollowsTheSlicePositions)
{
  std::vector<double> locations = { 0, 2, 4, 6, 8, 11, 14, 17, 20 };
  const auto          stack = AxialStack(locations, -0.25);
  const auto          geometry = itk::AnalyseDicomSliceStack(stack, 0.05);
  const auto          grid = itk::MakeRegularGrid(geometry, geometry.SmallestSpacing());
  auto       field = [](const ImageType::PointType & p) { return static_cast<float>(3 * p[0] - 2 * p[1] + p[2]); };
  const auto slices = SampleStack(geometry.Stack, field);
  for (auto interpolator : { itk::SliceInterpolatorEnum::Linear, itk::SliceInterpolatorEnum::BSpline })
  {
    SCOPED_TRACE(itk::ToString(interpolator));
    const ImageType::Pointer output = Resample(slices, geometry, grid, interpolator);
    EXPECT_EQ(output->GetLargestPossibleRegion().GetSize(), grid.Size);
    size_t nan = 0, checked = 0;
    double worst = 0.0;
    for (itk::ImageRegionConstIteratorWithIndex<ImageType> it(output, output->GetLargestPossibleRegion());
         !it.IsAtEnd();
         ++it)
    {
      if (std::isnan(it.Get()))
      {
        ++nan;
        continue;
      }
      ImageType::PointType p;
      output->TransformIndexToPhysicalPoint(it.GetIndex(), p);
      // Away from the slice edges, where interpolation keeps to the last pixel.
      const double row = (p[1] - 2.0 + 0.25 * p[2]) / 0.8;
      if (row < 1.0 || row > 8.0 || it.GetIndex()[0] < 1 || it.GetIndex()[0] > 18)
      {
        continue;
      }
      ++checked;
      const double error = std::abs(static_cast<double>(it.Get() - field(p)));
      worst = std::max(worst, error);
    }
    EXPECT_GT(checked, 1000u);
    // The cubic B-spline works in the slices' index space, where z is only piecewise linear
    // (2 mm, then 3 mm per slice) and the ends are mirrored: close, not exact.
    EXPECT_LT(worst, interpolator == itk::SliceInterpolatorEnum::Linear ? 1e-3 : 0.6);
    EXPECT_EQ(nan, itk::CountVoxelsWithoutData(geometry, grid));
    EXPECT_GT(nan, 0u);
  }
}

TEST(DicomSeriesGeometry, VoxelsInAGapAreNaN)
{
  // Slice at 6 mm missing from a 2 mm stack: the grid slice at 6 mm has no data, those at
  // 4 and 8 mm are the acquired slices.
  const auto geometry = itk::AnalyseDicomSliceStack(AxialStack({ 0, 2, 4, 8, 10, 12 }), 0.05);
  ASSERT_EQ(geometry.Gaps.size(), 1u);
  const auto grid = itk::MakeRegularGrid(geometry, 2.0);
  ASSERT_EQ(grid.Size[2], 7u);
  const auto slices =
    SampleStack(geometry.Stack, [](const ImageType::PointType & p) { return static_cast<float>(p[2]); });
  const ImageType::Pointer output = Resample(slices, geometry, grid, itk::SliceInterpolatorEnum::Linear);
  for (long z = 0; z < 7; ++z)
  {
    const float value = output->GetPixel({ { 5, 5, z } });
    if (z == 3)
    {
      EXPECT_TRUE(std::isnan(value)) << value;
    }
    else
    {
      EXPECT_NEAR(value, 2.0 * z, 1e-4);
    }
  }
  EXPECT_EQ(itk::CountVoxelsWithoutData(geometry, grid), grid.Size[0] * grid.Size[1]);
}

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
#include "itkTextureFidelityCalculator.h"

#include "itkImageFileWriter.h"
#include "itkImageRegionIteratorWithIndex.h"
#include "itkLinearInterpolateImageFunction.h"
#include "vuTestHelpers.h"
#include "vuTexturePhantom.h"

#include "gtest/gtest.h"

#include <cmath>
#include <limits>
#include <random>

namespace {
using CalculatorType = itk::TextureFidelityCalculator;
using ImageType = CalculatorType::ImageType;
using MaskType = CalculatorType::MaskType;

// The ink image seen through a similarity (optionally mirrored in x first) on a grid of
// another pixel size: what an unwrapping that came out flipped and turned would give.
// Pixels that map outside the ink image are NaN.
ImageType::Pointer
Transformed(const ImageType * ink, bool mirror, double degrees, double pixelSize, const double shift[2])
{
  // Texture point y maps to ink point x = R (y - c) + c + shift, mirrored in x after.
  auto                                          transform = CalculatorType::TransformType::New();
  CalculatorType::TransformType::InputPointType center;
  center[0] = 0.5 * vu::SheetLength;
  center[1] = 0.5 * vu::SheetHeight;
  transform->SetCenter(center);
  transform->SetAngle(degrees * M_PI / 180.0);
  CalculatorType::TransformType::OutputVectorType translation;
  translation[0] = shift[0];
  translation[1] = shift[1];
  transform->SetTranslation(translation);

  auto                texture = ImageType::New();
  ImageType::SizeType size;
  const double        extent = std::max(vu::SheetLength, vu::SheetHeight) + 10.0;
  size.Fill(static_cast<itk::SizeValueType>(extent / pixelSize));
  texture->SetRegions(size);
  ImageType::SpacingType spacing;
  spacing.Fill(pixelSize);
  texture->SetSpacing(spacing);
  ImageType::PointType origin;
  origin[0] = center[0] - 0.5 * extent;
  origin[1] = center[1] - 0.5 * extent;
  texture->SetOrigin(origin);
  texture->Allocate();
  auto interpolator = itk::LinearInterpolateImageFunction<ImageType, double>::New();
  interpolator->SetInputImage(ink);
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(texture, texture->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    ImageType::PointType y;
    texture->TransformIndexToPhysicalPoint(it.GetIndex(), y);
    ImageType::PointType x = transform->TransformPoint(y);
    if (mirror)
    {
      x[0] = vu::SheetLength - x[0];
    }
    it.Set(interpolator->IsInsideBuffer(x) ? static_cast<float>(interpolator->Evaluate(x))
                                           : std::numeric_limits<float>::quiet_NaN());
  }
  return texture;
}

CalculatorType::Pointer
Measure(const ImageType * reference, const ImageType * texture, const MaskType * textureMask = nullptr)
{
  auto calculator = CalculatorType::New();
  calculator->SetReference(reference);
  calculator->SetTexture(texture);
  calculator->SetTextureMask(textureMask);
  calculator->Compute();
  return calculator;
}
} // namespace

TEST(TextureFidelityCalculator, BasicObjectMethods)
{
  auto calculator = CalculatorType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(calculator, TextureFidelityCalculator, Object));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_BOOLEAN(calculator, AllowMirror, false));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_BOOLEAN(calculator, AllowQuarterTurns, false));
  calculator->SetCoarseSize(128);
  EXPECT_EQ(calculator->GetCoarseSize(), 128u);
  calculator->SetCoarseSize(2);
  EXPECT_EQ(calculator->GetCoarseSize(), 16u);
  calculator->SetNumberOfIterations(50);
  EXPECT_EQ(calculator->GetNumberOfIterations(), 50u);
  calculator->SetBorderWidth(0.5);
  EXPECT_EQ(calculator->GetBorderWidth(), 0.5);
  calculator->SetBorderWidth(-1.0);
  EXPECT_EQ(calculator->GetBorderWidth(), 0.0);
}

// A texture that is the ink image with a dark rim (a sheet's outline against air): the
// rim costs NCC over the whole region; a border at least as wide as the rim keeps it out,
// and the overlap fraction counts the compared interior only.
TEST(TextureFidelityCalculator, BorderWidthLeavesTheOutlineOut)
{
  const double pixel = 0.25;
  const auto   ink = vu::MakeInkImage(pixel);
  auto         rimmed = ImageType::New();
  rimmed->CopyInformation(ink);
  rimmed->SetRegions(ink->GetLargestPossibleRegion());
  rimmed->Allocate();
  const auto size = ink->GetLargestPossibleRegion().GetSize();
  const int  rim = 3; // pixels
  for (itk::ImageRegionIteratorWithIndex<ImageType> it(rimmed, rimmed->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    const auto i = it.GetIndex();
    const bool edge =
      i[0] < rim || i[1] < rim || i[0] >= static_cast<long>(size[0]) - rim || i[1] >= static_cast<long>(size[1]) - rim;
    it.Set(edge ? -1.0f : ink->GetPixel(i));
  }
  const auto whole = Measure(ink, rimmed);
  EXPECT_LT(whole->GetNormalizedCrossCorrelation(), 0.9);

  auto interior = CalculatorType::New();
  interior->SetReference(ink);
  interior->SetTexture(rimmed);
  interior->SetBorderWidth(rim * pixel);
  interior->Compute();
  EXPECT_NEAR(interior->GetNormalizedCrossCorrelation(), 1.0, 1e-3);
  EXPECT_NEAR(interior->GetScale(), 1.0, 0.01);
  EXPECT_NEAR(interior->GetOverlapFraction(), 1.0, 0.01);
  ASSERT_TRUE(interior->GetAlignedTexture() != nullptr);
  // The rim is outside the compared region: NaN in the aligned texture.
  EXPECT_TRUE(std::isnan(interior->GetAlignedTexture()->GetPixel({ { 1, 1 } })));
  EXPECT_FALSE(std::isnan(interior->GetAlignedTexture()->GetPixel({ { rim, rim } })));

  // One pixel too narrow: the rim's inner ring is compared again.
  interior->SetBorderWidth((rim - 1) * pixel);
  interior->Compute();
  EXPECT_LT(interior->GetNormalizedCrossCorrelation(), 0.99);

  // A border wider than half the sheet leaves nothing to compare.
  interior->SetBorderWidth(0.5 * vu::SheetHeight + 1.0);
  EXPECT_THROW(interior->Compute(), itk::ExceptionObject);
}

TEST(TextureFidelityCalculator, IdenticalImagesCorrelatePerfectly)
{
  const auto ink = vu::MakeInkImage(0.25);
  const auto calculator = Measure(ink, ink);
  EXPECT_NEAR(calculator->GetNormalizedCrossCorrelation(), 1.0, 1e-3);
  EXPECT_FALSE(calculator->GetMirrored());
  EXPECT_NEAR(calculator->GetRotationDegrees(), 0.0, 0.5);
  EXPECT_NEAR(calculator->GetScale(), 1.0, 0.01);
  EXPECT_NEAR(calculator->GetOverlapFraction(), 1.0, 0.01);
}

TEST(TextureFidelityCalculator, FindsMirrorAndQuarterTurnAcrossPixelSizes)
{
  const auto   ink = vu::MakeInkImage(0.25);
  const double shift[2] = { 1.5, -0.8 };
  const auto   texture = Transformed(ink, true, 90.0, 0.3, shift);
  const auto   calculator = Measure(ink, texture);
  std::cout << "mirrored, turned 90 degrees, 0.3 mm pixels: NCC " << calculator->GetNormalizedCrossCorrelation()
            << ", rotation " << calculator->GetRotationDegrees() << ", scale " << calculator->GetScale() << std::endl;
  EXPECT_GE(calculator->GetNormalizedCrossCorrelation(), 0.95);
  EXPECT_TRUE(calculator->GetMirrored());
  const double turn = std::abs(calculator->GetRotationDegrees());
  EXPECT_NEAR(turn, 90.0, 1.0);
  EXPECT_NEAR(calculator->GetScale(), 1.0, 0.01);
  EXPECT_GE(calculator->GetOverlapFraction(), 0.9);

  // Without the mirror the best alignment is poor.
  auto noMirror = CalculatorType::New();
  noMirror->SetReference(ink);
  noMirror->SetTexture(texture);
  noMirror->AllowMirrorOff();
  noMirror->Compute();
  EXPECT_FALSE(noMirror->GetMirrored());
  EXPECT_LT(noMirror->GetNormalizedCrossCorrelation(), 0.8);
}

TEST(TextureFidelityCalculator, SmallRotationAndShiftAreRefined)
{
  const auto   ink = vu::MakeInkImage(0.25);
  const double shift[2] = { -2.0, 1.0 };
  const auto   calculator = Measure(ink, Transformed(ink, false, 7.0, 0.2, shift));
  EXPECT_GE(calculator->GetNormalizedCrossCorrelation(), 0.95);
  EXPECT_FALSE(calculator->GetMirrored());
  // The transform maps the reference onto the texture: the inverse turn.
  EXPECT_NEAR(calculator->GetRotationDegrees(), -7.0, 1.0);
}

TEST(TextureFidelityCalculator, ALongStripWithANarrowerTextureStartsAtTheRightScale)
{
  // A strip 1200 mm long and 24 mm high (a long roll's flat sheet), written with strokes
  // a few millimetres long; the texture shows the same strip at the same scale, but its top
  // fifth is off the sheet (NaN), so that its area is 0.8 of the reference's.
  constexpr double    pixel = 0.5, length = 1200.0, height = 24.0;
  auto                reference = ImageType::New();
  ImageType::SizeType size = { { static_cast<itk::SizeValueType>(length / pixel),
                                 static_cast<itk::SizeValueType>(height / pixel) } };
  reference->SetRegions(size);
  ImageType::SpacingType spacing;
  spacing.Fill(pixel);
  reference->SetSpacing(spacing);
  reference->Allocate();
  reference->FillBuffer(0.0f);
  std::mt19937                       generator(11);
  std::uniform_int_distribution<int> column(0, static_cast<int>(size[0]) - 8);
  std::uniform_int_distribution<int> row(2, static_cast<int>(size[1]) - 10);
  std::uniform_int_distribution<int> extent(2, 8);
  for (int stroke = 0; stroke < 1500; ++stroke)
  {
    const int  i0 = column(generator), j0 = row(generator);
    const bool across = stroke % 2 == 0;
    const int  w = across ? 1 + stroke % 3 : extent(generator), h = across ? extent(generator) : 1 + stroke % 3;
    for (int j = j0; j < std::min<int>(j0 + h, size[1]); ++j)
    {
      for (int i = i0; i < std::min<int>(i0 + w, size[0]); ++i)
      {
        reference->SetPixel({ { i, j } }, 1.0f);
      }
    }
  }
  auto texture = ImageType::New();
  texture->CopyInformation(reference);
  texture->SetRegions(reference->GetLargestPossibleRegion());
  texture->Allocate();
  const itk::SizeValueType columns = size[0], offSheetFrom = size[1] * 4 / 5;
  for (itk::SizeValueType k = 0; k < reference->GetBufferedRegion().GetNumberOfPixels(); ++k)
  {
    texture->GetBufferPointer()[k] =
      k / columns >= offSheetFrom ? std::numeric_limits<float>::quiet_NaN() : reference->GetBufferPointer()[k];
  }
  const auto calculator = Measure(reference, texture);
  std::cout << "long strip, texture 0.8 of its area: NCC " << calculator->GetNormalizedCrossCorrelation() << ", scale "
            << calculator->GetScale() << std::endl;
  // Started at the area ratio (sqrt(0.8), 11 % small), the strip's ends would lie 60 mm
  // off among strokes that all look alike.
  EXPECT_NEAR(calculator->GetScale(), 1.0, 0.002);
  EXPECT_GE(calculator->GetNormalizedCrossCorrelation(), 0.95);
}

TEST(TextureFidelityCalculator, UnrelatedTextureScoresLow)
{
  const auto ink = vu::MakeInkImage(0.25);
  auto       noise = ImageType::New();
  noise->CopyInformation(ink);
  noise->SetRegions(ink->GetLargestPossibleRegion());
  noise->Allocate();
  std::mt19937                          generator(7);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  for (itk::SizeValueType k = 0; k < noise->GetBufferedRegion().GetNumberOfPixels(); ++k)
  {
    noise->GetBufferPointer()[k] = uniform(generator);
  }
  EXPECT_LT(Measure(ink, noise)->GetNormalizedCrossCorrelation(), 0.3);
}

TEST(TextureFidelityCalculator, MaskedAndNaNPixelsAreIgnored)
{
  const auto ink = vu::MakeInkImage(0.25);
  auto       texture = ImageType::New();
  texture->Graft(ink);
  auto corrupted = ImageType::New();
  corrupted->CopyInformation(ink);
  corrupted->SetRegions(ink->GetLargestPossibleRegion());
  corrupted->Allocate();
  auto mask = MaskType::New();
  mask->CopyInformation(ink);
  mask->SetRegions(ink->GetLargestPossibleRegion());
  mask->Allocate();
  const itk::SizeValueType columns = ink->GetLargestPossibleRegion().GetSize(0);
  for (itk::SizeValueType k = 0; k < ink->GetBufferedRegion().GetNumberOfPixels(); ++k)
  {
    const bool stain = k % columns < columns / 4; // a quarter of the sheet ruined
    const bool hole = k % columns > columns - 10; // and a strip off the sheet
    corrupted->GetBufferPointer()[k] =
      hole ? std::numeric_limits<float>::quiet_NaN() : (stain ? 5.0f : ink->GetBufferPointer()[k]);
    mask->GetBufferPointer()[k] = stain ? 0 : 1;
  }
  const auto unmasked = Measure(ink, corrupted);
  const auto masked = Measure(ink, corrupted, mask);
  EXPECT_LT(unmasked->GetNormalizedCrossCorrelation(), 0.9);
  EXPECT_GE(masked->GetNormalizedCrossCorrelation(), 0.99);
  EXPECT_NEAR(masked->GetOverlapFraction(), 0.72, 0.03);
  EXPECT_TRUE(std::isnan(masked->GetAlignedTexture()->GetPixel({ { 0, 0 } })));
}

TEST(TextureFidelityCalculator, BadInputThrows)
{
  const auto ink = vu::MakeInkImage(0.25);
  auto       calculator = CalculatorType::New();
  calculator->SetReference(ink);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject); // no texture

  auto nan = ImageType::New();
  nan->CopyInformation(ink);
  nan->SetRegions(ink->GetLargestPossibleRegion());
  nan->Allocate();
  nan->FillBuffer(std::numeric_limits<float>::quiet_NaN());
  calculator->SetTexture(nan);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject); // no valid pixel

  auto               smallMask = MaskType::New();
  MaskType::SizeType size;
  size.Fill(3);
  smallMask->SetRegions(size);
  smallMask->Allocate();
  smallMask->FillBuffer(1);
  calculator->SetTexture(ink);
  calculator->SetTextureMask(smallMask);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject); // mask does not cover the image
}

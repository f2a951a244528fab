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
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkSheetPhantomSource.h"
#include "itkTextLegibility.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <cmath>

namespace {
using Source = itk::SheetPhantomSource;
using VolumeType = Source::OutputImageType;

// For every voxel brighter than half-way between air and sheet: its centre lies within
// half a voxel of the true sheet. And voxels well inside the true sheet are that bright.
void
ExpectThresholdedSheetOnTheTrueSheet(const Source * source, const VolumeType * volume)
{
  const auto & g = source->GetGeometry();
  const double threshold = 0.5 * (source->GetAirValue() + source->GetSheetValue());
  const double halfVoxel = 0.5 * std::max(source->GetVoxelSize(), source->GetSliceSpacing());
  const double halfThickness = 0.5 * g.GetSheetThickness();
  size_t       bright = 0, misplaced = 0, deepInside = 0, deepInsideDark = 0;
  const auto   region = volume->GetLargestPossibleRegion();
  for (itk::ImageRegionConstIteratorWithIndex<VolumeType> it(volume, region); !it.IsAtEnd(); ++it)
  {
    VolumeType::PointType point;
    volume->TransformIndexToPhysicalPoint(it.GetIndex(), point);
    const double p[3] = { point[0], point[1], point[2] };
    double       s, w, d;
    const bool   onSheet = g.Project(p, s, w, d);
    if (it.Get() > threshold)
    {
      ++bright;
      const bool near = std::abs(d) <= halfThickness + halfVoxel && s >= -halfVoxel &&
                        s <= g.GetSheetLength() + halfVoxel && w >= -halfVoxel && w <= g.GetSheetWidth() + halfVoxel;
      misplaced += !near;
    }
    else if (onSheet && std::abs(d) < halfThickness - halfVoxel && s > 2 * halfVoxel &&
             s < g.GetSheetLength() - 2 * halfVoxel && w > 2 * halfVoxel && w < g.GetSheetWidth() - 2 * halfVoxel)
    {
      ++deepInsideDark;
    }
    if (onSheet && std::abs(d) < halfThickness - halfVoxel && s > 2 * halfVoxel &&
        s < g.GetSheetLength() - 2 * halfVoxel && w > 2 * halfVoxel && w < g.GetSheetWidth() - 2 * halfVoxel)
    {
      ++deepInside;
    }
  }
  // The sheet occupies about length * width * thickness of the volume.
  const double expected = g.GetSheetLength() * g.GetSheetWidth() * g.GetSheetThickness() /
                          (source->GetVoxelSize() * source->GetVoxelSize() * source->GetSliceSpacing());
  EXPECT_GT(bright, 0.8 * expected);
  EXPECT_LT(bright, 1.4 * expected);
  EXPECT_EQ(misplaced, 0u) << "of " << bright << " bright voxels";
  EXPECT_LE(deepInsideDark, deepInside / 200) << "of " << deepInside;
}

VolumeType::Pointer
Generate(Source * source)
{
  source->Update();
  VolumeType::Pointer volume = source->GetOutput();
  volume->DisconnectPipeline();
  return volume;
}
} // namespace

TEST(SheetPhantomSource, BasicObjectMethods)
{
  auto source = Source::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(source, SheetPhantomSource, ImageSource));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(0.1, source->GetVoxelSize()); source->SetVoxelSize(0.2);
                       ITK_TEST_SET_GET_VALUE(0.2, source->GetVoxelSize());
                       source->SetSeed(9);
                       ITK_TEST_SET_GET_VALUE(9u, source->GetSeed()));
}

TEST(SheetPhantomSource, DefaultsAreTheStandardPreset)
{
  auto fresh = Source::New();
  auto preset = Source::New();
  preset->ApplyPreset("tight");
  preset->ApplyPreset("standard");
  EXPECT_EQ(fresh->GetPresetName(), std::string("standard"));
  EXPECT_DOUBLE_EQ(fresh->GetSheetLength(), preset->GetSheetLength());
  EXPECT_EQ(fresh->GetShape(), preset->GetShape());
  EXPECT_EQ(fresh->GetSheetWidth(), preset->GetSheetWidth());
  EXPECT_EQ(fresh->GetSheetThickness(), preset->GetSheetThickness());
  EXPECT_EQ(fresh->GetInnerRadius(), preset->GetInnerRadius());
  EXPECT_EQ(fresh->GetPitch(), preset->GetPitch());
  EXPECT_EQ(fresh->GetSquash(), preset->GetSquash());
  EXPECT_EQ(fresh->GetFoldRadius(), preset->GetFoldRadius());
  EXPECT_EQ(fresh->GetFoldOpeningAngle(), preset->GetFoldOpeningAngle());
  EXPECT_EQ(std::string(fresh->GetText()), std::string(preset->GetText()));
  EXPECT_EQ(fresh->GetGlyphHeight(), preset->GetGlyphHeight());
  EXPECT_EQ(fresh->GetInkContrast(), preset->GetInkContrast());
  EXPECT_EQ(fresh->GetInkDepth(), preset->GetInkDepth());
  EXPECT_EQ(fresh->GetSheetValue(), preset->GetSheetValue());
  EXPECT_EQ(fresh->GetFibreContrast(), preset->GetFibreContrast());
  EXPECT_EQ(fresh->GetVoxelSize(), preset->GetVoxelSize());
  EXPECT_EQ(fresh->GetSliceSpacing(), preset->GetSliceSpacing());
  EXPECT_EQ(fresh->GetMargin(), preset->GetMargin());
  EXPECT_EQ(fresh->GetBlurFWHM(), preset->GetBlurFWHM());
  EXPECT_EQ(fresh->GetNoiseStandardDeviation(), preset->GetNoiseStandardDeviation());
  EXPECT_THROW(preset->ApplyPreset("no-such-preset"), itk::ExceptionObject);
  EXPECT_EQ(Source::GetPresetNames().size(), 6u);
}

TEST(SheetPhantomSource, StandardSheetVoxelsLieOnTheTrueSurface)
{
  auto source = Source::New();
  source->SetNoiseStandardDeviation(0.0);
  const auto volume = Generate(source);
  const auto size = volume->GetLargestPossibleRegion().GetSize();
  EXPECT_LT(size[0] * size[1] * size[2], 3000000u);
  EXPECT_NEAR(source->GetGeometry().GetNumberOfTurns(), 3.0, 1e-6);
  ExpectThresholdedSheetOnTheTrueSheet(source, volume);
}

TEST(SheetPhantomSource, TiltedWavyAndFoldedSheetsLieOnTheirTrueSurfaces)
{
  auto source = Source::New();
  source->SetNoiseStandardDeviation(0.0);
  source->SetSheetWidth(6.0);
  source->SetText("WAVY");
  source->SetWaveAmplitude(0.1);
  source->SetWavesPerTurn(6);
  source->SetTiltAngle(25.0);
  source->SetNumberOfTurns(2.0);
  ExpectThresholdedSheetOnTheTrueSheet(source, Generate(source));
  source->ApplyPreset("folded");
  source->SetNoiseStandardDeviation(0.0);
  source->SetTiltAngle(-10.0);
  ExpectThresholdedSheetOnTheTrueSheet(source, Generate(source));
}

TEST(SheetPhantomSource, InkIsDenserThanTheBareSheet)
{
  auto source = Source::New();
  source->SetNoiseStandardDeviation(0.0);
  const auto   volume = Generate(source);
  const auto & g = source->GetGeometry();
  const auto * ink = g.GetInkImage();
  using InterpolatorType = itk::LinearInterpolateImageFunction<Source::InkImageType>;
  auto interpolator = InterpolatorType::New();
  interpolator->SetInputImage(ink);
  double sum[2] = { 0, 0 };
  size_t count[2] = { 0, 0 };
  for (itk::ImageRegionConstIteratorWithIndex<VolumeType> it(volume, volume->GetLargestPossibleRegion()); !it.IsAtEnd();
       ++it)
  {
    VolumeType::PointType point;
    volume->TransformIndexToPhysicalPoint(it.GetIndex(), point);
    const double p[3] = { point[0], point[1], point[2] };
    double       s, w, d;
    if (!g.Project(p, s, w, d) || std::abs(d - 0.08) > 0.03)
    {
      continue;
    }
    Source::InkImageType::PointType inkPoint;
    inkPoint[0] = s;
    inkPoint[1] = w;
    if (!interpolator->IsInsideBuffer(inkPoint))
    {
      continue;
    }
    const double coverage = interpolator->Evaluate(inkPoint);
    if (coverage > 0.95 || coverage < 0.01)
    {
      sum[coverage > 0.95] += it.Get();
      ++count[coverage > 0.95];
    }
  }
  ASSERT_GT(count[0], 100u);
  ASSERT_GT(count[1], 100u);
  EXPECT_GT(sum[1] / count[1] - sum[0] / count[0], 300.0);
}

// The fibres of papyrus-microct have the same contrast at the sheet's ends as in its
// middle (the smoothing of their noise once reached past the noise image's edges and
// made bands of several times the contrast within a fibre length of the ends).
TEST(SheetPhantomSource, FibreContrastIsUniformAlongTheSheet)
{
  auto source = Source::New();
  source->ApplyPreset("papyrus-microct");
  source->SetInkContrast(0.0);
  source->SetNoiseStandardDeviation(0.0);
  const auto   volume = Generate(source);
  const auto & g = source->GetGeometry();
  auto         interpolator = itk::LinearInterpolateImageFunction<VolumeType>::New();
  interpolator->SetInputImage(volume);
  // Standard deviation of the sheet half-way into its inked half, over s in [s0, s1]
  // and w away from the long edges.
  auto spread = [&](double s0, double s1) {
    double sum = 0.0, sum2 = 0.0;
    size_t n = 0;
    for (double s = s0; s <= s1; s += 0.01)
    {
      for (double w = 0.5; w <= g.GetSheetWidth() - 0.5; w += 0.01)
      {
        double p[3], normal[3];
        g.SurfacePoint(s, w, p);
        g.SurfaceNormal(s, w, normal);
        VolumeType::PointType x;
        for (int d = 0; d < 3; ++d)
        {
          x[d] = p[d] + 0.25 * g.GetSheetThickness() * normal[d];
        }
        const double v = interpolator->Evaluate(x);
        sum += v;
        sum2 += v * v;
        ++n;
      }
    }
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
  };
  const double ends[2] = { spread(0.1, 0.4), spread(g.GetSheetLength() - 0.4, g.GetSheetLength() - 0.1) };
  const double middle = spread(12.0, 12.3);
  std::cout << "[ figures ] fibre spread (HU): ends " << ends[0] << ", " << ends[1] << ", middle " << middle
            << std::endl;
  EXPECT_GT(middle, 20.0);
  for (double end : ends)
  {
    EXPECT_LT(end, 1.5 * middle);
    EXPECT_GT(end, middle / 1.5);
  }
}

TEST(SheetPhantomSource, GroundTruthInkReadsAsTheText)
{
  auto legibility = itk::TextLegibility::New();
  if (!legibility->IsTesseractAvailable())
  {
    GTEST_SKIP() << "tesseract is not installed";
  }
  for (const std::string & name : Source::GetPresetNames())
  {
    auto source = Source::New();
    source->ApplyPreset(name);
    source->UpdateOutputInformation();
    const auto & g = source->GetGeometry();
    legibility->SetImage(g.GetInkImage());
    legibility->SetTruthText(g.GetText());
    legibility->Compute();
    EXPECT_LT(legibility->GetCharacterErrorRate(), 0.02)
      << name << ": read \"" << legibility->GetRecognizedText() << "\" for \"" << g.GetText() << "\"";
  }
}

TEST(SheetPhantomSource, EveryPresetGenerates)
{
  for (const std::string & name : Source::GetPresetNames())
  {
    auto source = Source::New();
    source->ApplyPreset(name);
    EXPECT_EQ(source->GetPresetName(), name);
    EXPECT_FALSE(Source::GetPresetDescription(name).empty());
    const auto volume = Generate(source);
    const auto size = volume->GetLargestPossibleRegion().GetSize();
    EXPECT_LT(size[0] * size[1] * size[2], 8000000u) << name;
    double lower[3], upper[3];
    source->GetGeometry().GetBoundingBox(lower, upper);
    for (unsigned d = 0; d < 3; ++d)
    {
      EXPECT_LE(volume->GetOrigin()[d], lower[d]) << name;
      EXPECT_GE(volume->GetOrigin()[d] + (size[d] - 1) * volume->GetSpacing()[d], upper[d]) << name;
    }
    float lowest = 1e9f, highest = -1e9f;
    for (size_t i = 0; i < volume->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
    {
      const float v = volume->GetBufferPointer()[i];
      ASSERT_TRUE(std::isfinite(v)) << name;
      lowest = std::min(lowest, v);
      highest = std::max(highest, v);
    }
    EXPECT_LT(lowest, source->GetAirValue() + 100.0) << name;
    EXPECT_GT(highest, source->GetSheetValue()) << name;
  }
}

TEST(SheetPhantomSource, NoiseIsReproducibleFromTheSeed)
{
  auto source = Source::New();
  source->SetText("SEED");
  source->SetSheetWidth(5.0);
  source->SetNumberOfTurns(1.0);
  const auto a = Generate(source);
  source->Modified();
  const auto b = Generate(source);
  source->SetSeed(2);
  const auto   c = Generate(source);
  const size_t n = a->GetLargestPossibleRegion().GetNumberOfPixels();
  size_t       same = 0, sameAsOtherSeed = 0;
  for (size_t i = 0; i < n; ++i)
  {
    same += a->GetBufferPointer()[i] == b->GetBufferPointer()[i];
    sameAsOtherSeed += a->GetBufferPointer()[i] == c->GetBufferPointer()[i];
  }
  EXPECT_EQ(same, n);
  EXPECT_LT(sameAsOtherSeed, n / 100);
}

TEST(SheetPhantomSource, InkPatternIsFittedDarkAsInk)
{
  // A white page with a black square in the middle third.
  auto pattern = Source::InkImageType::New();
  pattern->SetRegions(Source::InkImageType::SizeType{ { 90, 30 } });
  pattern->Allocate();
  pattern->FillBuffer(255.0f);
  for (unsigned y = 10; y < 20; ++y)
  {
    for (unsigned x = 30; x < 60; ++x)
    {
      pattern->SetPixel({ { x, y } }, 0.0f);
    }
  }
  auto source = Source::New();
  source->SetInkPattern(pattern);
  source->UpdateOutputInformation();
  const auto * ink = source->GetGeometry().GetInkImage();
  EXPECT_EQ(source->GetGeometry().GetText(), "");
  auto at = [&](double s, double w) {
    Source::InkImageType::PointType point;
    point[0] = s;
    point[1] = w;
    Source::InkImageType::IndexType index;
    ink->TransformPhysicalPointToIndex(point, index);
    return ink->GetPixel(index);
  };
  const double length = source->GetSheetLength(), width = source->GetSheetWidth();
  EXPECT_NEAR(at(0.5 * length, 0.5 * width), 1.0, 1e-3);
  EXPECT_NEAR(at(0.5 * length, 0.05 * width), 0.0, 1e-3);
  EXPECT_NEAR(at(0.1 * length, 0.5 * width), 0.0, 1e-3);
}

TEST(SheetPhantomSource, RefusesImpossibleParameters)
{
  int  caseNumber = 0;
  auto expectRefused = [&caseNumber](auto change) {
    auto source = Source::New();
    change(source.GetPointer());
    EXPECT_THROW(source->UpdateOutputInformation(), itk::ExceptionObject) << "case " << caseNumber;
    ++caseNumber;
  };
  expectRefused([](Source * s) { s->SetVoxelSize(-0.1); });
  expectRefused([](Source * s) { s->SetSheetThickness(-0.25); });
  expectRefused([](Source * s) { s->SetPitch(0.2); });
  expectRefused([](Source * s) { s->SetSheetValue(-2000.0); });
  expectRefused([](Source * s) { s->SetSupersampling(0); });
  expectRefused([](Source * s) { s->SetText("NOSPACESTOWRAPATANDFARTOOLONGFORFIFTYMILLIMETRES"); });
  expectRefused([](Source * s) { s->SetText("ONE\nTWO\nTHREE\nFOUR"); });
  // A character missing from DejaVu.
  expectRefused([](Source * s) { s->SetText("\xE4\xB8\xAD"); });
  expectRefused([](Source * s) { s->SetText("\xC3"); });
  expectRefused([](Source * s) { s->SetFontFile("/nonexistent/font.ttf"); });
  expectRefused([](Source * s) { s->SetVoxelSize(0.001); });
  auto source = Source::New();
  EXPECT_THROW(source->ApplyPreset("scroll"), itk::ExceptionObject);
  EXPECT_THROW(source->SetNumberOfTurns(0.0), itk::ExceptionObject);
}

TEST(SheetPhantomSource, PerfectUnwrappingOfTheStandardScanReads)
{
  auto legibility = itk::TextLegibility::New();
  if (!legibility->IsTesseractAvailable())
  {
    GTEST_SKIP() << "tesseract is not installed";
  }
  auto         source = Source::New();
  const auto   volume = Generate(source);
  const auto & g = source->GetGeometry();
  auto         interpolator = itk::LinearInterpolateImageFunction<VolumeType>::New();
  interpolator->SetInputImage(volume);
  // Sample the scan through the true geometry, half a voxel per pixel, averaging three
  // depths across the ink layer: what an ideal unwrapping and texturing would produce.
  const double                         pixel = 0.5 * source->GetVoxelSize();
  auto                                 texture = Source::InkImageType::New();
  const Source::InkImageType::SizeType size = { { static_cast<itk::SizeValueType>(g.GetSheetLength() / pixel),
                                                  static_cast<itk::SizeValueType>(g.GetSheetWidth() / pixel) } };
  texture->SetRegions(size);
  texture->Allocate();
  const double top = 0.5 * g.GetSheetThickness();
  for (itk::SizeValueType y = 0; y < size[1]; ++y)
  {
    for (itk::SizeValueType x = 0; x < size[0]; ++x)
    {
      const double s = (x + 0.5) * pixel, w = (y + 0.5) * pixel;
      double       p[3], n[3], sum = 0.0;
      g.SurfacePoint(s, w, p);
      g.SurfaceNormal(s, w, n);
      for (double depth : { 0.25, 0.5, 0.75 })
      {
        const double          offset = top - depth * source->GetInkDepth();
        VolumeType::PointType q;
        for (int d = 0; d < 3; ++d)
        {
          q[d] = p[d] + offset * n[d];
        }
        sum += interpolator->Evaluate(q);
      }
      texture->SetPixel({ { static_cast<itk::IndexValueType>(x), static_cast<itk::IndexValueType>(y) } }, sum / 3.0);
    }
  }
  legibility->SetImage(texture);
  legibility->SetTruthText(g.GetText());
  legibility->Compute();
  EXPECT_LT(legibility->GetCharacterErrorRate(), 0.02) << "read \"" << legibility->GetRecognizedText() << "\"";
}

TEST(SheetPhantomSource, HonoursAbort)
{
  auto source = Source::New();
  auto abort = [&source](const itk::EventObject &) { source->AbortGenerateDataOn(); };
  source->AddObserver(itk::ProgressEvent(), abort);
  EXPECT_THROW(source->Update(), itk::ProcessAborted);
}

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
#include "vuValidRegion.h"

#include "itkCorrelationImageToImageMetricv4.h"
#include "itkExhaustiveOptimizerv4.h"
#include "itkFlipImageFilter.h"
#include "itkImageMaskSpatialObject.h"
#include "itkImageRegistrationMethodv4.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkRegistrationParameterScalesFromPhysicalShift.h"
#include "itkRegularStepGradientDescentOptimizerv4.h"
#include "itkResampleImageFilter.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace itk {
namespace {
using ImageType = TextureFidelityCalculator::ImageType;
using MaskType = TextureFidelityCalculator::MaskType;
using TransformType = TextureFidelityCalculator::TransformType;

// An image with its invalid pixels filled, the validity mask, and the valid region's
// centroid (physical) and area.
struct PreparedImage
{
  ImageType::Pointer Image;
  MaskType::Pointer  Mask;
  double             Centroid[2]{ 0.0, 0.0 };
  double             Area{ 0.0 };
  /** The valid region's principal axes (physical): the unit direction of the longer one and
   * the standard deviations along the longer and the shorter. */
  double LongAxis[2]{ 1.0, 0.0 };
  double LongSpread{ 0.0 };
  double ShortSpread{ 0.0 };
};

PreparedImage
Prepare(const ImageType * image, const MaskType * mask, const char * what)
{
  if (image == nullptr)
  {
    itkGenericExceptionMacro(<< "TextureFidelityCalculator: no " << what << " image");
  }
  const ImageType::RegionType region = image->GetLargestPossibleRegion();
  if (region.GetNumberOfPixels() == 0 || image->GetBufferedRegion() != region)
  {
    itkGenericExceptionMacro(<< "TextureFidelityCalculator: the " << what << " image is empty or not fully buffered");
  }
  if (mask != nullptr && (mask->GetBufferedRegion() != region))
  {
    itkGenericExceptionMacro(<< "TextureFidelityCalculator: the " << what << " mask ("
                             << mask->GetBufferedRegion().GetSize() << ") does not cover the " << what << " image ("
                             << region.GetSize() << ")");
  }
  PreparedImage prepared;
  prepared.Image = ImageType::New();
  prepared.Image->CopyInformation(image);
  prepared.Image->SetRegions(region);
  prepared.Image->Allocate();
  prepared.Mask = MaskType::New();
  prepared.Mask->CopyInformation(image);
  prepared.Mask->SetRegions(region);
  prepared.Mask->Allocate();

  const float *         in = image->GetBufferPointer();
  const unsigned char * inMask = mask != nullptr ? mask->GetBufferPointer() : nullptr;
  float *               out = prepared.Image->GetBufferPointer();
  unsigned char *       outMask = prepared.Mask->GetBufferPointer();
  const SizeValueType   n = region.GetNumberOfPixels();
  const SizeValueType   columns = region.GetSize(0);
  double                sum = 0.0;
  double                sumIndex[2] = { 0.0, 0.0 };
  double                sumProducts[3] = { 0.0, 0.0, 0.0 };
  SizeValueType         valid = 0;
  for (SizeValueType k = 0; k < n; ++k)
  {
    const bool ok = std::isfinite(in[k]) && (inMask == nullptr || inMask[k] != 0);
    outMask[k] = ok ? 1 : 0;
    if (ok)
    {
      sum += in[k];
      const auto i = static_cast<double>(k % columns), j = static_cast<double>(k / columns);
      sumIndex[0] += i;
      sumIndex[1] += j;
      sumProducts[0] += i * i;
      sumProducts[1] += i * j;
      sumProducts[2] += j * j;
      ++valid;
    }
  }
  if (valid == 0)
  {
    itkGenericExceptionMacro(<< "TextureFidelityCalculator: the " << what << " image has no valid pixel");
  }
  const auto mean = static_cast<float>(sum / valid);
  for (SizeValueType k = 0; k < n; ++k)
  {
    out[k] = outMask[k] != 0 ? in[k] : mean;
  }
  ContinuousIndex<double, 2> centroidIndex;
  centroidIndex[0] = region.GetIndex(0) + sumIndex[0] / valid;
  centroidIndex[1] = region.GetIndex(1) + sumIndex[1] / valid;
  ImageType::PointType centroid;
  image->TransformContinuousIndexToPhysicalPoint(centroidIndex, centroid);
  prepared.Centroid[0] = centroid[0];
  prepared.Centroid[1] = centroid[1];
  prepared.Area = valid * image->GetSpacing()[0] * image->GetSpacing()[1];
  // Second moments about the centroid, from index to physical space (spacing, then
  // direction), and their principal axes.
  const double                   mi = sumIndex[0] / valid, mj = sumIndex[1] / valid;
  vnl_matrix_fixed<double, 2, 2> moments;
  moments(0, 0) = sumProducts[0] / valid - mi * mi;
  moments(0, 1) = moments(1, 0) = sumProducts[1] / valid - mi * mj;
  moments(1, 1) = sumProducts[2] / valid - mj * mj;
  vnl_matrix_fixed<double, 2, 2> toPhysical = image->GetDirection().GetVnlMatrix();
  toPhysical.set_column(0, toPhysical.get_column(0) * image->GetSpacing()[0]);
  toPhysical.set_column(1, toPhysical.get_column(1) * image->GetSpacing()[1]);
  const vnl_matrix_fixed<double, 2, 2> physical = toPhysical * moments * toPhysical.transpose();
  const double                         half = 0.5 * (physical(0, 0) + physical(1, 1));
  const double                         gap = std::hypot(0.5 * (physical(0, 0) - physical(1, 1)), physical(0, 1));
  prepared.LongSpread = std::sqrt(std::max(0.0, half + gap));
  prepared.ShortSpread = std::sqrt(std::max(0.0, half - gap));
  const double angle = 0.5 * std::atan2(2.0 * physical(0, 1), physical(0, 0) - physical(1, 1));
  prepared.LongAxis[0] = std::cos(angle);
  prepared.LongAxis[1] = std::sin(angle);
  return prepared;
}

// The valid pixels whose centre lies at least `border` inside the edge of the valid
// region, the edge taken half a pixel beyond the centres of the outermost valid pixels
// (outside the image counts as invalid).
MaskType::Pointer
ErodeMask(const MaskType * mask, double border)
{
  const std::vector<float> inside = detail::DistanceInsideValidRegion(mask);
  const unsigned char *    in = mask->GetBufferPointer();
  auto                     eroded = MaskType::New();
  eroded->CopyInformation(mask);
  eroded->SetRegions(mask->GetBufferedRegion());
  eroded->Allocate();
  unsigned char * out = eroded->GetBufferPointer();
  for (size_t k = 0; k < inside.size(); ++k)
  {
    out[k] = in[k] != 0 && inside[k] >= border ? 1 : 0;
  }
  return eroded;
}

// Mirrored about x = 0 in physical space.
template <typename TImage>
typename TImage::Pointer
MirrorX(const TImage * image)
{
  auto flip = FlipImageFilter<TImage>::New();
  flip->SetInput(image);
  typename FlipImageFilter<TImage>::FlipAxesArrayType axes;
  axes[0] = true;
  axes[1] = false;
  flip->SetFlipAxes(axes);
  flip->FlipAboutOriginOn();
  flip->Update();
  return flip->GetOutput();
}

struct Score
{
  double             NCC{ -2.0 };
  SizeValueType      Overlap{ 0 };
  ImageType::Pointer Aligned;
};

// Signed NCC of the texture resampled onto the reference grid, over the overlap.
Score
Evaluate(const PreparedImage & reference, const PreparedImage & texture, const TransformType * transform)
{
  auto resample = ResampleImageFilter<ImageType, ImageType, double>::New();
  resample->SetInput(texture.Image);
  resample->SetTransform(transform);
  resample->SetInterpolator(LinearInterpolateImageFunction<ImageType, double>::New());
  resample->SetOutputParametersFromImage(reference.Image);
  resample->SetDefaultPixelValue(std::numeric_limits<float>::quiet_NaN());
  resample->Update();
  auto resampleMask = ResampleImageFilter<MaskType, MaskType, double>::New();
  resampleMask->SetInput(texture.Mask);
  resampleMask->SetTransform(transform);
  resampleMask->SetInterpolator(NearestNeighborInterpolateImageFunction<MaskType, double>::New());
  resampleMask->SetOutputParametersFromImage(reference.Image);
  resampleMask->SetDefaultPixelValue(0);
  resampleMask->Update();

  Score score;
  score.Aligned = resample->GetOutput();
  float *               aligned = score.Aligned->GetBufferPointer();
  const unsigned char * alignedMask = resampleMask->GetOutput()->GetBufferPointer();
  const float *         ref = reference.Image->GetBufferPointer();
  const unsigned char * refMask = reference.Mask->GetBufferPointer();
  const SizeValueType   n = reference.Image->GetBufferedRegion().GetNumberOfPixels();
  double                sa = 0.0, sb = 0.0, saa = 0.0, sbb = 0.0, sab = 0.0;
  for (SizeValueType k = 0; k < n; ++k)
  {
    if (refMask[k] == 0 || alignedMask[k] == 0 || !std::isfinite(aligned[k]))
    {
      aligned[k] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    const double a = ref[k], b = aligned[k];
    sa += a;
    sb += b;
    saa += a * a;
    sbb += b * b;
    sab += a * b;
    ++score.Overlap;
  }
  if (score.Overlap < 2)
  {
    score.NCC = -1.0;
    return score;
  }
  const double m = static_cast<double>(score.Overlap);
  const double cov = sab - sa * sb / m;
  const double va = saa - sa * sa / m;
  const double vb = sbb - sb * sb / m;
  score.NCC = va > 0.0 && vb > 0.0 ? cov / std::sqrt(va * vb) : 0.0;
  return score;
}

// The scale a start turned by `angle` begins with: the ratio of the two valid regions' sizes,
// from their areas; for two long strips whose long axes the turn lines up, from their
// lengths (the spread along the long axis) instead, which a border of a few pixels along
// the strip (a mask a little wider than the other) does not skew. A start 0.4 % off in
// scale puts the ends of a strip 2400 mm long 10 mm off, beyond what the optimizer can
// pull back across repeating letters.
double
StartScale(const PreparedImage & reference, const PreparedImage & texture, double angle)
{
  const bool elongated =
    reference.LongSpread > 3.0 * reference.ShortSpread && texture.LongSpread > 3.0 * texture.ShortSpread;
  const double turned[2] = { std::cos(angle) * reference.LongAxis[0] - std::sin(angle) * reference.LongAxis[1],
                             std::sin(angle) * reference.LongAxis[0] + std::cos(angle) * reference.LongAxis[1] };
  const double alignment = std::abs(turned[0] * texture.LongAxis[0] + turned[1] * texture.LongAxis[1]);
  if (elongated && alignment > 0.9 && reference.LongSpread > 0.0)
  {
    return texture.LongSpread / reference.LongSpread;
  }
  return std::sqrt(texture.Area / reference.Area);
}

// Translation search on a coarse grid (exhaustive) or gradient descent of all four
// similarity parameters, both on the correlation metric over the valid pixels.
enum class Stage
{
  TranslationSearch,
  GradientDescent
};

TransformType::Pointer
AlignTexture(const PreparedImage &             reference,
             const PreparedImage &             texture,
             const TransformType *             start,
             const std::vector<unsigned int> & shrinkFactors,
             Stage                             stage,
             unsigned int                      iterations)
{
  using MetricType = CorrelationImageToImageMetricv4<ImageType, ImageType>;
  using RegistrationType = ImageRegistrationMethodv4<ImageType, ImageType, TransformType>;

  auto fixedMask = ImageMaskSpatialObject<2>::New();
  fixedMask->SetImage(reference.Mask);
  fixedMask->Update();
  auto movingMask = ImageMaskSpatialObject<2>::New();
  movingMask->SetImage(texture.Mask);
  movingMask->Update();
  auto metric = MetricType::New();
  metric->SetFixedImageMask(fixedMask);
  metric->SetMovingImageMask(movingMask);

  const double pixel = std::max(reference.Image->GetSpacing()[0], reference.Image->GetSpacing()[1]);
  ObjectToObjectOptimizerBaseTemplate<double>::Pointer optimizer;
  auto                                                 search = ExhaustiveOptimizerv4<double>::New();
  if (stage == Stage::TranslationSearch)
  {
    // A grid of shifts two coarse pixels apart over a quarter of the reference's extent
    // (at most 17 x 17 shifts), for textures that cover only part of the sheet.
    const auto   size = reference.Image->GetLargestPossibleRegion().GetSize();
    const double extent =
      std::max(size[0] * reference.Image->GetSpacing()[0], size[1] * reference.Image->GetSpacing()[1]);
    const double step = 2.0 * pixel * shrinkFactors.front();
    const auto   steps = static_cast<unsigned int>(std::min(8.0, std::ceil(0.25 * extent / step)));
    ExhaustiveOptimizerv4<double>::StepsType numberOfSteps(4);
    numberOfSteps[0] = numberOfSteps[1] = 0;
    numberOfSteps[2] = numberOfSteps[3] = steps;
    search->SetNumberOfSteps(numberOfSteps);
    search->SetStepLength(step);
    ExhaustiveOptimizerv4<double>::ScalesType scales(4);
    scales.Fill(1.0);
    search->SetScales(scales);
    optimizer = search;
  }
  else
  {
    auto scales = RegistrationParameterScalesFromPhysicalShift<MetricType>::New();
    scales->SetMetric(metric);
    auto descent = RegularStepGradientDescentOptimizerv4<double>::New();
    descent->SetScalesEstimator(scales);
    descent->SetDoEstimateLearningRateOnce(false);
    descent->SetDoEstimateLearningRateAtEachIteration(false);
    // Steps in physical units once scaled: a pixel of the coarsest level at first.
    descent->SetLearningRate(pixel * shrinkFactors.front());
    descent->SetMinimumStepLength(0.01 * pixel);
    descent->SetRelaxationFactor(0.5);
    descent->SetGradientMagnitudeTolerance(1e-8);
    descent->SetNumberOfIterations(iterations);
    optimizer = descent;
  }

  auto transform = TransformType::New();
  transform->SetFixedParameters(start->GetFixedParameters());
  transform->SetParameters(start->GetParameters());

  auto registration = RegistrationType::New();
  registration->SetFixedImage(reference.Image);
  registration->SetMovingImage(texture.Image);
  registration->SetMetric(metric);
  registration->SetOptimizer(optimizer);
  registration->SetInitialTransform(transform);
  registration->InPlaceOn();
  const auto levels = static_cast<unsigned int>(shrinkFactors.size());
  registration->SetNumberOfLevels(levels);
  typename RegistrationType::ShrinkFactorsArrayType   shrink(levels);
  typename RegistrationType::SmoothingSigmasArrayType sigmas(levels);
  for (unsigned int level = 0; level < levels; ++level)
  {
    shrink[level] = shrinkFactors[level];
    sigmas[level] = 0.5 * (shrinkFactors[level] - 1);
  }
  registration->SetShrinkFactorsPerLevel(shrink);
  registration->SetSmoothingSigmasPerLevel(sigmas);
  registration->SetSmoothingSigmasAreSpecifiedInPhysicalUnits(false);
  if (stage == Stage::GradientDescent)
  {
    // A regular quarter of the points, reproducibly jittered: as accurate here and four
    // times cheaper.
    registration->SetMetricSamplingStrategy(RegistrationType::MetricSamplingStrategyEnum::REGULAR);
    registration->SetMetricSamplingPercentage(0.25);
    registration->MetricSamplingReinitializeSeed(20040607);
  }
  registration->Update();
  if (stage == Stage::TranslationSearch)
  {
    // The exhaustive optimizer ends on the last grid point, not on the best.
    transform->SetParameters(search->GetMinimumMetricValuePosition());
  }
  return transform;
}
} // namespace

TextureFidelityCalculator::TextureFidelityCalculator()
  : m_Transform(TransformType::New())
{}

void
TextureFidelityCalculator::Compute()
{
  PreparedImage reference = Prepare(m_Reference, m_ReferenceMask, "reference");
  if (m_BorderWidth > 0.0)
  {
    // The starts are placed by the whole valid region (centroid and area stay); the
    // metric and the NCC see only its interior.
    reference.Mask = ErodeMask(reference.Mask, m_BorderWidth);
    const unsigned char * kept = reference.Mask->GetBufferPointer();
    if (std::find(kept, kept + reference.Mask->GetBufferedRegion().GetNumberOfPixels(), 1) ==
        kept + reference.Mask->GetBufferedRegion().GetNumberOfPixels())
    {
      itkExceptionMacro(<< "a border width of " << m_BorderWidth << " leaves no reference pixel to compare");
    }
  }
  std::vector<PreparedImage> textures{ Prepare(m_Texture, m_TextureMask, "texture") };
  const auto                 referenceSize = reference.Image->GetLargestPossibleRegion().GetSize();
  // The coarse level has at most CoarseSize pixels along the reference's longer side and
  // at least 8 along its shorter side.
  const double longer = static_cast<double>(std::max(referenceSize[0], referenceSize[1]));
  const double shorter = static_cast<double>(std::min(referenceSize[0], referenceSize[1]));
  const auto   coarseShrink =
    std::max(1u, static_cast<unsigned int>(std::min(std::ceil(longer / m_CoarseSize), std::floor(shorter / 8.0))));
  if (m_AllowMirror)
  {
    MaskType::ConstPointer mirroredMask;
    if (m_TextureMask.IsNotNull())
    {
      mirroredMask = MirrorX<MaskType>(m_TextureMask).GetPointer();
    }
    textures.push_back(Prepare(MirrorX<ImageType>(m_Texture), mirroredMask, "mirrored texture"));
  }

  struct Candidate
  {
    size_t                 Texture;
    TransformType::Pointer Transform;
    Score                  Result;
  };
  std::vector<Candidate> candidates;
  const unsigned int     turns = m_AllowQuarterTurns ? 4 : 1;
  for (size_t t = 0; t < textures.size(); ++t)
  {
    for (unsigned int turn = 0; turn < turns; ++turn)
    {
      auto                          start = TransformType::New();
      TransformType::InputPointType center;
      center[0] = reference.Centroid[0];
      center[1] = reference.Centroid[1];
      start->SetCenter(center);
      start->SetAngle(turn * 0.5 * Math::pi);
      start->SetScale(StartScale(reference, textures[t], turn * 0.5 * Math::pi));
      TransformType::OutputVectorType translation;
      translation[0] = textures[t].Centroid[0] - reference.Centroid[0];
      translation[1] = textures[t].Centroid[1] - reference.Centroid[1];
      start->SetTranslation(translation);
      TransformType::Pointer shifted =
        AlignTexture(reference, textures[t], start, { 2 * coarseShrink }, Stage::TranslationSearch, 0);
      TransformType::Pointer coarse = AlignTexture(reference,
                                                   textures[t],
                                                   shifted,
                                                   { coarseShrink },
                                                   Stage::GradientDescent,
                                                   std::max(1u, m_NumberOfIterations / 2));
      Score                  coarseScore = Evaluate(reference, textures[t], coarse);
      Score                  startScore = Evaluate(reference, textures[t], start);
      // The optimizer may leave a good start for a worse local optimum of the smoothed,
      // shrunk images: keep whichever correlates better at full resolution.
      if (coarseScore.NCC >= startScore.NCC)
      {
        candidates.push_back({ t, coarse, std::move(coarseScore) });
      }
      else
      {
        candidates.push_back({ t, start, std::move(startScore) });
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate & a, const Candidate & b) {
    return a.Result.NCC > b.Result.NCC;
  });
  // The runner-up is refined too unless the coarse stage already ruled it out.
  const bool close = candidates.size() > 1 && candidates[1].Result.NCC > 0.8 * candidates[0].Result.NCC;
  candidates.resize(close ? 2 : 1);
  std::vector<unsigned int> refinement;
  for (unsigned int shrink = coarseShrink / 2; shrink > 1; shrink /= 2)
  {
    refinement.push_back(shrink);
  }
  refinement.push_back(1);
  // Aligns the candidate again from its transform at the given shrink levels and keeps the
  // result when it scores higher.
  const auto refine = [&](Candidate & candidate, const std::vector<unsigned int> & levels) {
    TransformType::Pointer refined = AlignTexture(reference,
                                                  textures[candidate.Texture],
                                                  candidate.Transform,
                                                  levels,
                                                  Stage::GradientDescent,
                                                  m_NumberOfIterations);
    Score                  score = Evaluate(reference, textures[candidate.Texture], refined);
    if (score.NCC > candidate.Result.NCC)
    {
      candidate.Transform = refined;
      candidate.Result = std::move(score);
    }
  };
  for (Candidate & candidate : candidates)
  {
    refine(candidate, refinement);
    // The shrunk, smoothed levels can lead away from the optimum of the full-resolution
    // images (fine strokes blur into blobs there): polish the kept transform at the two
    // finest levels as well.
    if (refinement.size() > 2)
    {
      refine(candidate, { 2, 1 });
    }
  }
  const Candidate & best =
    *std::max_element(candidates.begin(), candidates.end(), [](const Candidate & a, const Candidate & b) {
      return a.Result.NCC < b.Result.NCC;
    });

  m_NormalizedCrossCorrelation = best.Result.NCC;
  m_Mirrored = best.Texture == 1;
  m_Transform = best.Transform;
  m_Scale = best.Transform->GetScale();
  m_RotationDegrees = std::remainder(best.Transform->GetAngle(), 2.0 * Math::pi) * 180.0 / Math::pi;
  m_OverlapFraction = static_cast<double>(best.Result.Overlap) /
                      static_cast<double>(std::count(reference.Mask->GetBufferPointer(),
                                                     reference.Mask->GetBufferPointer() +
                                                       reference.Mask->GetBufferedRegion().GetNumberOfPixels(),
                                                     static_cast<unsigned char>(1)));
  m_AlignedTexture = best.Result.Aligned;
  this->Modified();
}

void
TextureFidelityCalculator::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  itkPrintSelfObjectMacro(Reference);
  itkPrintSelfObjectMacro(ReferenceMask);
  itkPrintSelfObjectMacro(Texture);
  itkPrintSelfObjectMacro(TextureMask);
  os << indent << "AllowMirror: " << m_AllowMirror << std::endl;
  os << indent << "AllowQuarterTurns: " << m_AllowQuarterTurns << std::endl;
  os << indent << "CoarseSize: " << m_CoarseSize << std::endl;
  os << indent << "NumberOfIterations: " << m_NumberOfIterations << std::endl;
  os << indent << "BorderWidth: " << m_BorderWidth << std::endl;
  os << indent << "NormalizedCrossCorrelation: " << m_NormalizedCrossCorrelation << std::endl;
  os << indent << "Mirrored: " << m_Mirrored << std::endl;
  os << indent << "RotationDegrees: " << m_RotationDegrees << std::endl;
  os << indent << "Scale: " << m_Scale << std::endl;
  os << indent << "OverlapFraction: " << m_OverlapFraction << std::endl;
  itkPrintSelfObjectMacro(Transform);
  itkPrintSelfObjectMacro(AlignedTexture);
}
} // end namespace itk

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
#ifndef itkSheetSegmentationImageFilter_hxx
#define itkSheetSegmentationImageFilter_hxx

#include "itkBinaryBallStructuringElement.h"
#include "itkBinaryMorphologicalClosingImageFilter.h"
#include "itkBinaryThresholdImageFilter.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkOtsuThresholdCalculator.h"
#include "itkParallelImageRows.h"
#include "itkProgressAccumulator.h"
#include "itkRelabelComponentImageFilter.h"

#include "itkSheetMidSurfaceExtractor.h"
#include "itkSheetSegmentationImageFilter.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace itk {
template <typename TInputImage, typename TMaskImage>
void
SheetSegmentationImageFilter<TInputImage, TMaskImage>::GenerateInputRequestedRegion()
{
  Superclass::GenerateInputRequestedRegion();
  // Thresholds and components are global properties of the volume.
  if (auto * input = const_cast<InputImageType *>(this->GetInput()))
  {
    input->SetRequestedRegionToLargestPossibleRegion();
  }
}

template <typename TInputImage, typename TMaskImage>
void
SheetSegmentationImageFilter<TInputImage, TMaskImage>::EnlargeOutputRequestedRegion(DataObject * output)
{
  Superclass::EnlargeOutputRequestedRegion(output);
  output->SetRequestedRegionToLargestPossibleRegion();
}

namespace SheetSegmentationDetail {
/** The smallest and largest value in `region` of a 3D image, slice by slice in parallel:
 * of the finite values, or of all but NaN (as itk::MinimumMaximumImageCalculator finds
 * them); low > high when there is none. */
template <typename TImage>
void
ValueRange(const TImage * image, const ImageRegion<3> & region, bool finiteOnly, double & low, double & high)
{
  const auto          width = region.GetSize()[0];
  const auto          slices = region.GetSize()[2];
  std::vector<double> lows(slices, std::numeric_limits<double>::infinity()),
    highs(slices, -std::numeric_limits<double>::infinity());
  ForEachImageRow(image, region, [&](SizeValueType k, SizeValueType, const auto * row) {
    for (SizeValueType i = 0; i < width; ++i)
    {
      const auto v = static_cast<double>(row[i]);
      if (finiteOnly ? std::isfinite(v) : !std::isnan(v))
      {
        lows[k] = std::min(lows[k], v);
        highs[k] = std::max(highs[k], v);
      }
    }
  });
  // A slice without such a value keeps +inf / -inf, which min and max pass over; an
  // infinite value of the image (finiteOnly off) wins over them as it should.
  low = slices > 0 ? *std::min_element(lows.begin(), lows.end()) : 1.0;
  high = slices > 0 ? *std::max_element(highs.begin(), highs.end()) : 0.0;
  if (low > high)
  {
    low = 1.0;
    high = 0.0;
  }
}

/** Otsu's threshold of the finite voxels of `region` of a 3D image, whose finite values
 * range from `low` to `high`, on `bins` bins that span that range as
 * itk::ImageToHistogramFilter spans it (the maximum raised by a hundredth of a bin, ITK's
 * default marginal scale), found by itk::OtsuThresholdCalculator. The voxels are counted
 * slice by slice in parallel, each bin found by arithmetic and checked against the
 * histogram's own bin edges, so the histogram is the one ITK's filter would count. */
template <typename TImage>
double
OtsuThreshold(const TImage * image, const ImageRegion<3> & region, unsigned int bins, double low, double high)
{
  using PixelType = typename TImage::PixelType;
  if (!(high > low))
  {
    return low <= high ? low : 0.0;
  }
  using HistogramType = Statistics::Histogram<double>;
  auto histogram = HistogramType::New();
  histogram->SetMeasurementVectorSize(1);
  HistogramType::SizeType              histogramSize(1);
  HistogramType::MeasurementVectorType lower(1), upper(1);
  histogramSize[0] = bins;
  lower[0] = low;
  upper[0] = high + (high - low) / static_cast<double>(bins) / 100.0;
  histogram->Initialize(histogramSize, lower, upper);
  std::vector<double> edges(bins + 1);
  for (unsigned int b = 0; b < bins; ++b)
  {
    edges[b] = histogram->GetBinMin(0, b);
  }
  edges[bins] = histogram->GetBinMax(0, bins - 1);
  const double width = (upper[0] - lower[0]) / static_cast<double>(bins);
  // Counts per slice, added in slice order.
  const auto                              rowLength = region.GetSize()[0];
  std::vector<std::vector<SizeValueType>> counts(region.GetSize()[2], std::vector<SizeValueType>(bins, 0));
  ForEachImageRow(image, region, [&](SizeValueType k, SizeValueType, const PixelType * row) {
    std::vector<SizeValueType> & count = counts[k];
    for (SizeValueType i = 0; i < rowLength; ++i)
    {
      const auto v = static_cast<double>(row[i]);
      if (!std::isfinite(v))
      {
        continue;
      }
      auto b = std::clamp(static_cast<long>((v - lower[0]) / width), 0L, static_cast<long>(bins) - 1);
      while (b > 0 && v < edges[b])
      {
        --b;
      }
      while (b + 1 < static_cast<long>(bins) && v >= edges[b + 1])
      {
        ++b;
      }
      ++count[static_cast<size_t>(b)];
    }
  });
  for (unsigned int b = 0; b < bins; ++b)
  {
    SizeValueType total = 0;
    for (const auto & count : counts)
    {
      total += count[b];
    }
    histogram->SetFrequency(b, static_cast<HistogramType::AbsoluteFrequencyType>(total));
  }
  auto otsu = OtsuThresholdCalculator<HistogramType, double>::New();
  otsu->SetInput(histogram);
  otsu->Update();
  // As itk::OtsuThresholdImageFilter states it: in the pixel type.
  return static_cast<double>(static_cast<PixelType>(otsu->GetThreshold()));
}

/** OtsuThreshold over the finite values of `region`, their range found first. */
template <typename TImage>
double
OtsuThreshold(const TImage * image, const ImageRegion<3> & region, unsigned int bins)
{
  double low = 0.0, high = 0.0;
  ValueRange(image, region, true, low, high);
  return OtsuThreshold(image, region, bins, low, high);
}
} // namespace SheetSegmentationDetail

template <typename TInputImage, typename TMaskImage>
double
SheetSegmentationImageFilter<TInputImage, TMaskImage>::ComputeAutomaticThreshold(const InputImageType * input,
                                                                                 double                 minimum,
                                                                                 double                 maximum)
{
  const double first = SheetSegmentationDetail::OtsuThreshold(
    input, input->GetBufferedRegion(), m_NumberOfHistogramBins, minimum, maximum);

  // Bounding box of what lies above the first threshold, padded by two voxels.
  const typename InputImageType::RegionType box = BoundingRegionWhere(
    input, [first](InputPixelType v) { return static_cast<double>(v) > first; }, 2);
  if (box.GetNumberOfPixels() == 0)
  {
    return first;
  }
  return SheetSegmentationDetail::OtsuThreshold(input, box, m_NumberOfHistogramBins);
}

template <typename TInputImage, typename TMaskImage>
auto
SheetSegmentationImageFilter<TInputImage, TMaskImage>::ThresholdCandidates(const InputImageType * input,
                                                                           ProgressAccumulator *  progress) ->
  typename MaskImageType::Pointer
{
  // A noisy scan is smoothed before thresholding, enough to keep noise out of the mask but
  // not so much that turns two voxels apart merge.
  m_AppliedDenoisingSigma = m_DenoisingSigma;
  SheetIntensityLevels levels;
  if (m_DenoisingSigma < 0.0)
  {
    const size_t           count = input->GetBufferedRegion().GetNumberOfPixels();
    const size_t           stride = std::max<size_t>(1, count / 400000);
    std::vector<float>     below, above;
    const InputPixelType * values = input->GetBufferPointer();
    for (size_t i = 0; i < count; i += stride)
    {
      const auto value = static_cast<float>(values[i]);
      (value >= m_Threshold ? above : below).push_back(value);
    }
    levels = EstimateSheetIntensityLevels(std::move(below), std::move(above));
    m_AppliedDenoisingSigma = levels.DenoisingSigma();
  }
  typename MaskImageType::Pointer candidates;
  if (m_AppliedDenoisingSigma > 0.0)
  {
    using RealImageType = Image<float, ImageDimension>;
    auto smoothing = SmoothingRecursiveGaussianImageFilter<InputImageType, RealImageType>::New();
    smoothing->SetInput(input);
    typename SmoothingRecursiveGaussianImageFilter<InputImageType, RealImageType>::SigmaArrayType sigmas;
    for (unsigned d = 0; d < ImageDimension; ++d)
    {
      sigmas[d] = m_AppliedDenoisingSigma * input->GetSpacing()[d];
    }
    smoothing->SetSigmaArray(sigmas);
    if (m_AutomaticThreshold && levels.Sheet > levels.Air)
    {
      // Halfway between air and sheet as the smoothed scan has them: it has lost the noise
      // that set Otsu's threshold, which a sheet filling a small share of the scan pulls
      // towards the air, and with it the sheet's level measured above that threshold.
      smoothing->Update();
      const RealImageType * smoothed = smoothing->GetOutput();
      const size_t          count = smoothed->GetBufferedRegion().GetNumberOfPixels();
      const size_t          stride = std::max<size_t>(1, count / 400000);
      std::vector<float>    sample;
      sample.reserve(count / stride + 1);
      for (size_t i = 0; i < count; i += stride)
      {
        sample.push_back(smoothed->GetBufferPointer()[i]);
      }
      levels = RefineSheetIntensityLevels(sample, levels);
      m_Threshold = 0.5 * (levels.Air + levels.Sheet);
    }
    auto threshold = BinaryThresholdImageFilter<RealImageType, MaskImageType>::New();
    threshold->SetInput(smoothing->GetOutput());
    threshold->SetLowerThreshold(static_cast<float>(m_Threshold));
    threshold->SetInsideValue(1);
    threshold->SetOutsideValue(0);
    progress->RegisterInternalFilter(smoothing, 0.1f);
    threshold->Update();
    candidates = threshold->GetOutput();
  }
  else
  {
    auto threshold = BinaryThresholdImageFilter<InputImageType, MaskImageType>::New();
    threshold->SetInput(input);
    threshold->SetLowerThreshold(
      static_cast<InputPixelType>(std::max(m_Threshold, static_cast<double>(NumericTraits<InputPixelType>::lowest()))));
    threshold->SetInsideValue(1);
    threshold->SetOutsideValue(0);
    progress->RegisterInternalFilter(threshold, 0.1f);
    threshold->Update();
    candidates = threshold->GetOutput();
  }
  return candidates;
}

template <typename TInputImage, typename TMaskImage>
void
SheetSegmentationImageFilter<TInputImage, TMaskImage>::GenerateData()
{
  const InputImageType * input = this->GetInput();
  if (input == nullptr || input->GetLargestPossibleRegion().GetNumberOfPixels() == 0)
  {
    itkExceptionMacro(<< "the volume is empty");
  }
  double minimum = 0.0, maximum = 0.0;
  SheetSegmentationDetail::ValueRange(input, input->GetBufferedRegion(), false, minimum, maximum);
  if (minimum > maximum)
  {
    // Only NaN: no value was compared.
    itkExceptionMacro(<< "the volume has no finite voxel (all " << input->GetLargestPossibleRegion().GetNumberOfPixels()
                      << " are NaN): nothing to segment");
  }
  if (std::isinf(minimum) || std::isinf(maximum))
  {
    itkExceptionMacro(<< "the volume holds infinite values (range " << minimum << " to " << maximum
                      << "): nothing to segment");
  }
  if (!(maximum > minimum))
  {
    itkExceptionMacro(<< "the volume is constant (" << minimum << "): nothing to segment");
  }
  if (m_AutomaticThreshold)
  {
    m_Threshold = ComputeAutomaticThreshold(input, minimum, maximum);
  }
  if (!(maximum >= m_Threshold))
  {
    itkExceptionMacro(<< "nothing at or above the threshold " << m_Threshold << " (volume maximum " << maximum << ")");
  }

  auto progress = ProgressAccumulator::New();
  progress->SetMiniPipelineFilter(this);

  // Labels of 4 bytes a voxel, relabelled in place.
  using LabelImageType = Image<uint32_t, ImageDimension>;
  const typename MaskImageType::Pointer candidates = ThresholdCandidates(input, progress);
  auto components = ConnectedComponentImageFilter<MaskImageType, LabelImageType>::New();
  components->SetInput(candidates);
  components->FullyConnectedOff();
  auto relabel = RelabelComponentImageFilter<LabelImageType, LabelImageType>::New();
  relabel->SetInput(components->GetOutput());
  relabel->SetMinimumObjectSize(m_MinimumComponentSize);
  relabel->InPlaceOn();
  auto keep = BinaryThresholdImageFilter<LabelImageType, MaskImageType>::New();
  keep->SetInput(relabel->GetOutput());
  keep->SetLowerThreshold(1);
  keep->SetInsideValue(m_ForegroundValue);
  keep->SetOutsideValue(0);
  progress->RegisterInternalFilter(components, 0.4f);
  progress->RegisterInternalFilter(relabel, 0.2f);
  progress->RegisterInternalFilter(keep, m_ClosingRadius > 0 ? 0.1f : 0.3f);
  relabel->Update();
  m_NumberOfComponents = relabel->GetNumberOfObjects();
  if (relabel->GetOriginalNumberOfObjects() == 0)
  {
    itkExceptionMacro(<< "nothing at or above the threshold " << m_Threshold);
  }
  if (m_NumberOfComponents == 0)
  {
    itkExceptionMacro(<< "no component of at least " << m_MinimumComponentSize << " voxels above the threshold "
                      << m_Threshold << " (only noise)");
  }
  m_LargestComponentSize = relabel->GetSizeOfObjectsInPixels().front();

  if (m_ClosingRadius > 0)
  {
    using KernelType = BinaryBallStructuringElement<MaskPixelType, ImageDimension>;
    KernelType ball;
    ball.SetRadius(m_ClosingRadius);
    ball.CreateStructuringElement();
    auto closing = BinaryMorphologicalClosingImageFilter<MaskImageType, MaskImageType, KernelType>::New();
    closing->SetInput(keep->GetOutput());
    closing->SetKernel(ball);
    closing->SetForegroundValue(m_ForegroundValue);
    progress->RegisterInternalFilter(closing, 0.2f);
    closing->GraftOutput(this->GetOutput());
    closing->Update();
    this->GraftOutput(closing->GetOutput());
  }
  else
  {
    keep->GraftOutput(this->GetOutput());
    keep->Update();
    this->GraftOutput(keep->GetOutput());
  }
}

template <typename TInputImage, typename TMaskImage>
void
SheetSegmentationImageFilter<TInputImage, TMaskImage>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "AutomaticThreshold: " << m_AutomaticThreshold << std::endl;
  os << indent << "Threshold: " << m_Threshold << std::endl;
  os << indent << "NumberOfHistogramBins: " << m_NumberOfHistogramBins << std::endl;
  os << indent << "MinimumComponentSize: " << m_MinimumComponentSize << std::endl;
  os << indent << "ClosingRadius: " << m_ClosingRadius << std::endl;
  os << indent << "DenoisingSigma: " << m_DenoisingSigma << std::endl;
  os << indent << "AppliedDenoisingSigma: " << m_AppliedDenoisingSigma << std::endl;
  os << indent
     << "ForegroundValue: " << static_cast<typename NumericTraits<MaskPixelType>::PrintType>(m_ForegroundValue)
     << std::endl;
  os << indent << "NumberOfComponents: " << m_NumberOfComponents << std::endl;
  os << indent << "LargestComponentSize: " << m_LargestComponentSize << std::endl;
}
} // end namespace itk

#endif

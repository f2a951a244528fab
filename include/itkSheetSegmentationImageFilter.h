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
#ifndef itkSheetSegmentationImageFilter_h
#define itkSheetSegmentationImageFilter_h

#include "itkImageToImageFilter.h"
#include "itkProgressAccumulator.h"

namespace itk {
/** \class SheetSegmentationImageFilter
 * \brief Segments the writing material of a CT scan of a document: a binary mask of the
 * sheet, free of noise and small fragments.
 *
 * Steps:
 * 1. threshold: the user's Threshold, or (AutomaticThreshold, the default) Otsu's
 *    threshold computed on the region that holds the object: a first Otsu threshold over
 *    the whole volume finds the object's bounding box, padded by two voxels, and Otsu's
 *    threshold over that box alone is used, so that an air-only border of any size does
 *    not pull the threshold (itk::OtsuThresholdCalculator on NumberOfHistogramBins bins,
 *    the histogram itk::OtsuThresholdImageFilter would count, counted in parallel);
 * 2. a noisy scan is smoothed first (itk::SmoothingRecursiveGaussianImageFilter) by
 *    DenoisingSigma voxels; automatic by default: SheetIntensityLevels::DenoisingSigma of the
 *    levels below and above the threshold (none at a signal-to-noise ratio of 12 and above,
 *    else 0.5-1 voxel), and an automatic threshold then moves halfway between air and sheet;
 *    voxels >= threshold become candidates; face-connected components
 *    (itk::ConnectedComponentImageFilter) smaller than MinimumComponentSize voxels are
 *    removed as noise (itk::RelabelComponentImageFilter);
 * 3. optional binary closing with a ball of ClosingRadius voxels
 *    (itk::BinaryMorphologicalClosingImageFilter) to fill cracks; off by default, since it
 *    can bridge turns that lie closer than its diameter.
 *
 * Parameters: AutomaticThreshold (default true); Threshold (input units, e.g. HU, used when
 * AutomaticThreshold is off; after Update() GetThreshold() returns the threshold used);
 * NumberOfHistogramBins (256, >= 2); MinimumComponentSize (voxels, 100, >= 0);
 * ClosingRadius (voxels, 0 = off, >= 0); ForegroundValue (1; background 0); DenoisingSigma
 * (voxels; -1 = automatic, the default; 0 = off); GetAppliedDenoisingSigma() after Update().
 * Outputs: the mask; GetNumberOfComponents() (components kept, largest first) and
 * GetLargestComponentSize() (voxels).
 *
 * Errors (itk::ExceptionObject, one line): an empty or constant volume, one with no finite
 * voxel (all NaN; NaN voxels are otherwise ignored) or with infinite values, nothing at or
 * above the threshold, no component of at least MinimumComponentSize voxels.
 *
 * Reference: N. Otsu, "A threshold selection method from gray-level histograms", IEEE
 * Trans. SMC 9(1), 1979; W. B. Seales and Y. Lin, "Digital Restoration Using Volumetric
 * Scanning", JCDL 2004 (threshold chosen per case).
 *
 * \ingroup VirtualUnwrapping
 */
template <typename TInputImage, typename TMaskImage = Image<unsigned char, TInputImage::ImageDimension>>
class ITK_TEMPLATE_EXPORT SheetSegmentationImageFilter : public ImageToImageFilter<TInputImage, TMaskImage>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(SheetSegmentationImageFilter);

  using Self = SheetSegmentationImageFilter;
  using Superclass = ImageToImageFilter<TInputImage, TMaskImage>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using InputImageType = TInputImage;
  using MaskImageType = TMaskImage;
  using InputPixelType = typename TInputImage::PixelType;
  using MaskPixelType = typename TMaskImage::PixelType;
  static constexpr unsigned int ImageDimension = TInputImage::ImageDimension;

  itkNewMacro(Self);
  itkTypeMacro(SheetSegmentationImageFilter, ImageToImageFilter);

  itkSetMacro(AutomaticThreshold, bool);
  itkGetConstMacro(AutomaticThreshold, bool);
  itkBooleanMacro(AutomaticThreshold);
  itkSetMacro(Threshold, double);
  itkGetConstMacro(Threshold, double);
  itkSetClampMacro(NumberOfHistogramBins, unsigned int, 2, NumericTraits<unsigned int>::max());
  itkGetConstMacro(NumberOfHistogramBins, unsigned int);
  itkSetMacro(MinimumComponentSize, SizeValueType);
  itkGetConstMacro(MinimumComponentSize, SizeValueType);
  itkSetMacro(ClosingRadius, unsigned int);
  itkGetConstMacro(ClosingRadius, unsigned int);
  itkSetMacro(ForegroundValue, MaskPixelType);
  itkGetConstMacro(ForegroundValue, MaskPixelType);
  itkSetMacro(DenoisingSigma, double);
  itkGetConstMacro(DenoisingSigma, double);
  itkGetConstMacro(AppliedDenoisingSigma, double);

  itkGetConstMacro(NumberOfComponents, SizeValueType);
  itkGetConstMacro(LargestComponentSize, SizeValueType);

protected:
  SheetSegmentationImageFilter() = default;
  ~SheetSegmentationImageFilter() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;
  void
  GenerateInputRequestedRegion() override;
  void
  EnlargeOutputRequestedRegion(DataObject * output) override;
  void
  GenerateData() override;

private:
  /** Otsu's threshold of the object's box, the volume's finite values ranging from
   * `minimum` to `maximum`. */
  double
  ComputeAutomaticThreshold(const InputImageType * input, double minimum, double maximum);
  /** The voxels at or above the threshold (1, others 0), of the scan smoothed first when
   * it is noisy (the denoising sigma given, or measured when negative, in which case an
   * automatic threshold is refined on the smoothed scan). The filters run under
   * `progress`. */
  typename MaskImageType::Pointer
  ThresholdCandidates(const InputImageType * input, ProgressAccumulator * progress);

  bool          m_AutomaticThreshold{ true };
  double        m_Threshold{ 0.0 };
  unsigned int  m_NumberOfHistogramBins{ 256 };
  SizeValueType m_MinimumComponentSize{ 100 };
  unsigned int  m_ClosingRadius{ 0 };
  MaskPixelType m_ForegroundValue{ 1 };
  double        m_DenoisingSigma{ -1.0 };
  double        m_AppliedDenoisingSigma{ 0.0 };
  SizeValueType m_NumberOfComponents{ 0 };
  SizeValueType m_LargestComponentSize{ 0 };
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkSheetSegmentationImageFilter.hxx"
#endif

#endif

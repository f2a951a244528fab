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
#ifndef itkTextureFidelityCalculator_h
#define itkTextureFidelityCalculator_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkObject.h"
#include "itkObjectFactory.h"
#include "itkSimilarity2DTransform.h"

namespace itk {
/** \class TextureFidelityCalculator
 * \brief Texture fidelity: normalised cross-correlation between an unwrapped texture and
 * the true ink image after the best similarity alignment, allowing a mirror and any
 * rotation (an unrolled sheet can come out flipped or turned).
 *
 * Inputs: the reference (the true ink image) and the texture (the unwrapped result), both
 * itk::Image<float, 2> with their physical spacing (the two may differ in pixel size and
 * extent), and optional masks (non-zero = valid). NaN pixels of either image count as
 * invalid as well. Compute() then:
 * 1. replaces invalid pixels by the mean of the valid ones (so that interpolation near the
 *    sheet's edge stays finite) and keeps them out of every measure through masks;
 * 2. for each of the 8 starts (texture mirrored in x or not, times the 4 quarter turns),
 *    places the texture on the reference by the centroids of their valid regions and the
 *    square root of their valid-area ratio (scale), searches shifts of up to a quarter of
 *    the reference's extent on a coarse grid (ExhaustiveOptimizerv4, at half the coarse
 *    resolution) and runs a short coarse registration (ITK v4 registration:
 *    Similarity2DTransform, CorrelationImageToImageMetricv4,
 *    RegularStepGradientDescentOptimizerv4, a regular quarter of the pixels);
 * 3. refines the start of highest signed NCC (and the runner-up when its NCC is within
 *    80 % of the best) level by level up to full resolution;
 * 4. resamples the texture onto the reference grid with the best transform (linear
 *    interpolation) and reports the signed NCC over the overlap: the reference pixels
 *    that are valid and map onto valid texture pixels.
 *
 * Results: GetNormalizedCrossCorrelation() in [-1, 1], GetMirrored() (the texture had
 * to be mirrored in x), GetTransform() (maps reference physical points to physical points
 * of the texture, mirrored about x = 0 first when GetMirrored()), GetRotationDegrees(),
 * GetScale(), GetOverlapFraction() (overlap pixels / valid reference pixels) and
 * GetAlignedTexture() (the texture resampled onto the reference grid, NaN outside the
 * overlap).
 *
 * Parameters (defaults; ranges):
 * - AllowMirror (true): also try the mirrored texture;
 * - AllowQuarterTurns (true): start from 0, 90, 180 and 270 degrees, else from 0 only;
 * - CoarseSize (64; 16 .. 4096): pixels along the reference's longer side at the coarse
 *   level (the shrink factor follows from it), but the shorter side keeps at least 8
 *   pixels there (a long roll's texture is a strip a hundred times longer than wide,
 *   which would otherwise shrink to a single row);
 * - NumberOfIterations (100; >= 1): optimizer iterations per level;
 * - BorderWidth (0; >= 0, physical units): reference pixels whose centre lies less than
 *   this far inside the edge of the reference's valid region (taken half a pixel beyond
 *   the centres of its outermost valid pixels) are left out of the registration metric,
 *   the NCC and the overlap fraction. The placement of the starts still uses the whole
 *   valid region. A sheet's own outline (air beside the sheet's edge blurred into the
 *   texture) is not ink; a border of the scanner's blur reach keeps it out of the measure.
 *
 * Throws itk::ExceptionObject when an image is missing or empty, a mask's size differs
 * from its image, an image has no valid pixel, or BorderWidth leaves no reference pixel.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT TextureFidelityCalculator : public Object
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(TextureFidelityCalculator);

  using Self = TextureFidelityCalculator;
  using Superclass = Object;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(TextureFidelityCalculator, Object);

  using ImageType = Image<float, 2>;
  using MaskType = Image<unsigned char, 2>;
  using TransformType = Similarity2DTransform<double>;

  itkSetConstObjectMacro(Reference, ImageType);
  itkGetConstObjectMacro(Reference, ImageType);
  itkSetConstObjectMacro(ReferenceMask, MaskType);
  itkGetConstObjectMacro(ReferenceMask, MaskType);
  itkSetConstObjectMacro(Texture, ImageType);
  itkGetConstObjectMacro(Texture, ImageType);
  itkSetConstObjectMacro(TextureMask, MaskType);
  itkGetConstObjectMacro(TextureMask, MaskType);

  itkSetMacro(AllowMirror, bool);
  itkGetConstMacro(AllowMirror, bool);
  itkBooleanMacro(AllowMirror);
  itkSetMacro(AllowQuarterTurns, bool);
  itkGetConstMacro(AllowQuarterTurns, bool);
  itkBooleanMacro(AllowQuarterTurns);
  itkSetClampMacro(CoarseSize, unsigned int, 16, 4096);
  itkGetConstMacro(CoarseSize, unsigned int);
  itkSetClampMacro(NumberOfIterations, unsigned int, 1, 100000);
  itkGetConstMacro(NumberOfIterations, unsigned int);
  itkSetClampMacro(BorderWidth, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(BorderWidth, double);

  void
  Compute();

  itkGetConstMacro(NormalizedCrossCorrelation, double);
  itkGetConstMacro(Mirrored, bool);
  itkGetConstMacro(RotationDegrees, double);
  itkGetConstMacro(Scale, double);
  itkGetConstMacro(OverlapFraction, double);
  itkGetConstObjectMacro(Transform, TransformType);
  itkGetConstObjectMacro(AlignedTexture, ImageType);

protected:
  TextureFidelityCalculator();
  ~TextureFidelityCalculator() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  ImageType::ConstPointer m_Reference;
  MaskType::ConstPointer  m_ReferenceMask;
  ImageType::ConstPointer m_Texture;
  MaskType::ConstPointer  m_TextureMask;

  bool         m_AllowMirror{ true };
  bool         m_AllowQuarterTurns{ true };
  unsigned int m_CoarseSize{ 64 };
  unsigned int m_NumberOfIterations{ 100 };
  double       m_BorderWidth{ 0.0 };

  double                 m_NormalizedCrossCorrelation{ 0.0 };
  bool                   m_Mirrored{ false };
  double                 m_RotationDegrees{ 0.0 };
  double                 m_Scale{ 1.0 };
  double                 m_OverlapFraction{ 0.0 };
  TransformType::Pointer m_Transform;
  ImageType::Pointer     m_AlignedTexture;
};
} // end namespace itk

#endif

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
#ifndef itkReadableTextureImageFilter_h
#define itkReadableTextureImageFilter_h

#include "itkFlattenedTextureImageFilter.h"
#include "itkImageSource.h"
#include "itkReadableTexture.h"

namespace itk {
/** \class ReadableTextureImageFilter
 * \brief The flattened sheet's texture in which the writing reads best: the layered
 * texture (FlattenedTextureImageFilter) sampled with automatic pixel size, layer spacing
 * and layer count, then the side of the sheet, the core subtraction or the focal slab, and
 * the denoising chosen by ink contrast (SelectReadableTexture). `virtual-unwrap unwrap`
 * writes this filter's output as texture.tif (rows flipped to run top-down).
 *
 * Inputs (all required): SurfaceMesh (the sheet in the volume's physical space), FlatMesh
 * (the flattened sheet: same points and triangles), Volume (the CT scan).
 * Outputs: 0, GetOutput(): the chosen texture, denoised; NaN off the sheet. 1,
 * GetMaskOutput(): 1 on the sheet. 2, GetLayerStackOutput(): the sampled layers (see
 * FlattenedTextureImageFilter for the geometry of all three).
 * Parameters (defaults; ranges; lengths in physical units):
 * - PixelSize (0: half the scan's smallest voxel side; >= 0); Margin around the flat mesh
 *   (negative: two pixels);
 * - NumberOfLayers (0: from the focus to half a voxel beyond the faces of a sheet
 *   SheetThickness thick, on both sides or on LayerSide), LayerSpacing (0: half a voxel),
 *   SheetThickness (0; >= 0: SheetMidSurfaceMeshFilter measures it), Focus (0);
 * - AutomaticSide (true: the layers lie on both sides and the whole stack and each half
 *   are candidates; NumberOfLayers must then be odd), LayerSide (Both; used without
 *   AutomaticSide), SubtractCore (Auto; Yes, No), LayerFilter (Max), GaussianSigma (1.0,
 *   for the GaussianMean filter);
 * - DenoisingSigma: the Gaussian smoothing in voxels that segmentation applied to a noisy
 *   scan (0: none; SheetSegmentationImageFilter::GetAppliedDenoisingSigma()): the
 *   candidates become focal slabs and the denoising as strong;
 * - MedianRadius, SmoothSigma (negative: automatic), RestoreFWHM (negative: off): see
 *   ReadableTextureSettings.
 * After Update(): GetSelection() (every candidate's score, the choice, the applied
 * denoising, and how a per-vertex texture of the same choice is sampled), the applied
 * pixel size, layer spacing and layer count, GetTextureFilter() (the layered texture's
 * diagnostics: sheet pixels, clamped samples).
 * Throws itk::ExceptionObject with a one-line message on a missing input or a parameter
 * out of range.
 * \ingroup VirtualUnwrapping
 */
template <typename TImage, typename TOutputImage = Image<float, 2>, typename TMesh = Mesh<float, 3>>
class ITK_TEMPLATE_EXPORT ReadableTextureImageFilter : public ImageSource<TOutputImage>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(ReadableTextureImageFilter);

  using Self = ReadableTextureImageFilter;
  using Superclass = ImageSource<TOutputImage>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(ReadableTextureImageFilter, ImageSource);

  static_assert(std::is_same<TOutputImage, Image<float, 2>>::value,
                "the readable texture is a 2D float image (NaN off the sheet)");

  using VolumeType = TImage;
  using MeshType = TMesh;
  using OutputImageType = TOutputImage;
  using TextureFilterType = FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>;
  using MaskImageType = typename TextureFilterType::MaskImageType;
  using LayerStackImageType = typename TextureFilterType::LayerStackImageType;
  using SideEnum = TextureLayersEnums::Side;
  using FilterEnum = TextureLayersEnums::Filter;
  using CoreEnum = TextureLayersEnums::CoreSubtraction;
  using DataObjectPointerArraySizeType = ProcessObject::DataObjectPointerArraySizeType;

  itkSetInputMacro(SurfaceMesh, MeshType);
  itkGetInputMacro(SurfaceMesh, MeshType);
  itkSetInputMacro(FlatMesh, MeshType);
  itkGetInputMacro(FlatMesh, MeshType);
  itkSetInputMacro(Volume, VolumeType);
  itkGetInputMacro(Volume, VolumeType);

  MaskImageType *
  GetMaskOutput();
  LayerStackImageType *
  GetLayerStackOutput();

  itkSetMacro(PixelSize, double);
  itkGetConstMacro(PixelSize, double);
  itkSetMacro(Margin, double);
  itkGetConstMacro(Margin, double);
  itkSetMacro(NumberOfLayers, unsigned int);
  itkGetConstMacro(NumberOfLayers, unsigned int);
  itkSetMacro(LayerSpacing, double);
  itkGetConstMacro(LayerSpacing, double);
  itkSetMacro(SheetThickness, double);
  itkGetConstMacro(SheetThickness, double);
  itkSetMacro(Focus, double);
  itkGetConstMacro(Focus, double);
  itkSetMacro(AutomaticSide, bool);
  itkGetConstMacro(AutomaticSide, bool);
  itkBooleanMacro(AutomaticSide);
  itkSetEnumMacro(LayerSide, SideEnum);
  itkGetEnumMacro(LayerSide, SideEnum);
  itkSetEnumMacro(SubtractCore, CoreEnum);
  itkGetEnumMacro(SubtractCore, CoreEnum);
  itkSetEnumMacro(LayerFilter, FilterEnum);
  itkGetEnumMacro(LayerFilter, FilterEnum);
  itkSetMacro(GaussianSigma, double);
  itkGetConstMacro(GaussianSigma, double);
  itkSetMacro(DenoisingSigma, double);
  itkGetConstMacro(DenoisingSigma, double);
  itkSetMacro(MedianRadius, double);
  itkGetConstMacro(MedianRadius, double);
  itkSetMacro(SmoothSigma, double);
  itkGetConstMacro(SmoothSigma, double);
  itkSetMacro(RestoreFWHM, double);
  itkGetConstMacro(RestoreFWHM, double);

  /** Values applied by the last Update() (or UpdateOutputInformation()). */
  itkGetConstMacro(AppliedPixelSize, double);
  itkGetConstMacro(AppliedLayerSpacing, double);
  itkGetConstMacro(AppliedNumberOfLayers, unsigned int);
  /** The choice of the last Update(). */
  const ReadableTextureSelection &
  GetSelection() const
  {
    return m_Selection;
  }
  /** The chosen candidate's score (ink or stroke contrast). */
  double
  GetChosenScore() const
  {
    return m_Selection.Candidates.empty() ? 0.0 : m_Selection.ChosenCandidate().Score;
  }
  /** The chosen candidate's side and core subtraction, and a focal slab's first layer and
   * number of layers (0 for a side candidate). */
  SideEnum
  GetChosenSide() const
  {
    return m_Selection.Candidates.empty() ? SideEnum::Both : m_Selection.ChosenCandidate().Side;
  }
  bool
  GetChosenSubtractCore() const
  {
    return !m_Selection.Candidates.empty() && m_Selection.ChosenCandidate().SubtractCore;
  }
  unsigned int
  GetChosenFirstLayer() const
  {
    return m_Selection.Candidates.empty() ? 0 : m_Selection.ChosenCandidate().First;
  }
  unsigned int
  GetChosenNumberOfLayers() const
  {
    return m_Selection.Candidates.empty() ? 0 : m_Selection.ChosenCandidate().Count;
  }
  /** The layered texture filter inside (its diagnostics and pixel map). */
  const TextureFilterType *
  GetTextureFilter() const
  {
    return m_TextureFilter.GetPointer();
  }

protected:
  ReadableTextureImageFilter();
  ~ReadableTextureImageFilter() override = default;

  using Superclass::MakeOutput;
  DataObject::Pointer
  MakeOutput(DataObjectPointerArraySizeType idx) override;

  void
  VerifyPreconditions() ITKv5_CONST override;
  void
  GenerateOutputInformation() override;
  void
  EnlargeOutputRequestedRegion(DataObject * output) override;
  void
  GenerateData() override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  /** The applied values, and the layered texture filter set up with them. */
  void
  ConfigureTextureFilter();

  double       m_PixelSize{ 0.0 };
  double       m_Margin{ -1.0 };
  unsigned int m_NumberOfLayers{ 0 };
  double       m_LayerSpacing{ 0.0 };
  double       m_SheetThickness{ 0.0 };
  double       m_Focus{ 0.0 };
  bool         m_AutomaticSide{ true };
  SideEnum     m_LayerSide{ SideEnum::Both };
  CoreEnum     m_SubtractCore{ CoreEnum::Auto };
  FilterEnum   m_LayerFilter{ FilterEnum::Max };
  double       m_GaussianSigma{ 1.0 };
  double       m_DenoisingSigma{ 0.0 };
  double       m_MedianRadius{ -1.0 };
  double       m_SmoothSigma{ -1.0 };
  double       m_RestoreFWHM{ -1.0 };

  double       m_AppliedPixelSize{ 0.0 };
  double       m_AppliedLayerSpacing{ 0.0 };
  unsigned int m_AppliedNumberOfLayers{ 0 };
  double       m_Voxel{ 0.0 };

  typename TextureFilterType::Pointer m_TextureFilter;
  ReadableTextureSelection            m_Selection;
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkReadableTextureImageFilter.hxx"
#endif

#endif

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
#ifndef itkFlattenedTextureImageFilter_h
#define itkFlattenedTextureImageFilter_h

#include "itkImage.h"
#include "itkImageSource.h"
#include "itkInterpolateImageFunction.h"
#include "itkMesh.h"
#include "itkTextureLayers.h"
#include "itkTexturePixelMap.h"

namespace itk {
/** \class FlattenedTextureImageFilter
 * \brief Renders the flattened sheet: for every pixel of a 2D image laid over the
 * flattened mesh, samples the CT volume in layers along the surface normal at the
 * corresponding point of the 3D sheet and combines the layers into one texture value.
 *
 * Inputs (all required):
 * - SurfaceMesh: the sheet in the volume's physical space (triangles only, TMesh);
 * - FlatMesh: the flattened sheet, same points and triangles; x, y are the flattened
 *   coordinates in physical units (mm), z is ignored;
 * - Volume: the CT volume (3D image, TImage).
 *
 * Outputs:
 * - 0, GetOutput(): the texture (2D, floating point pixel). Pixels off the sheet are NaN;
 * - 1, GetMaskOutput(): 1 where the pixel centre is on the sheet, 0 elsewhere;
 * - 2, GetLayerStackOutput(): one slice per layer (3D, size columns x rows x layers);
 *   slice k holds layer k before combining; NaN off the sheet.
 *
 * Output geometry: pixel (i, j) has its centre at flat coordinates
 * (x_min - Margin + i * PixelSize, y_min - Margin + j * PixelSize), where x_min, y_min is
 * the lower corner of the flat mesh's bounding box: image x is flat x and image row
 * index grows with flat y; identity direction, spacing PixelSize, origin at the first
 * pixel centre. The layer stack shares x, y; its third axis is the signed offset along
 * the normal (origin the first layer's offset, spacing LayerSpacing, direction -1 for
 * the Negative side).
 *
 * Each output pixel finds its flat triangle by rasterisation (ComputeTexturePixelMap:
 * each triangle visits the pixel centres of its bounding box with a barycentric inside
 * test), maps by the same barycentric coordinates to a 3D point (moved from the flat
 * triangle onto the curved sheet its corners' normals describe: Phong tessellation) and
 * an interpolated area-weighted vertex normal, and samples the volume there
 * (LayeredVolumeSampler). The
 * pixel map, the "where to sample", is kept and reused while the meshes, PixelSize,
 * Margin and CurvedSurface stay the same, so changing the layers, focus or filter only resamples;
 * GetPixelMap() exposes it.
 *
 * Parameters (defaults; ranges):
 * - PixelSize: output pixel side, physical units (1.0; > 0), independent of the mesh
 *   resolution;
 * - Margin: border added around the flat mesh's bounding box, physical units (0; >= 0);
 * - CurvedSurface (false): place each pixel's point on the curved sheet the surface's
 *   vertices and normals describe instead of on its flat triangle (ComputeTexturePixelMap):
 *   a texture read from a thin slab at a fixed depth sees the triangles' chords, which
 *   lie inside a curved sheet by up to their sagitta, as stripes along the mesh's
 *   columns;
 * - NumberOfLayers (1; >= 1), LayerSpacing (1.0; > 0, physical units), Focus: offset of
 *   the central layer along the normal (0.0; any, physical units), LayerSide
 *   (Both; Both, Positive, Negative), LayerFilter (Mean; Mean, GaussianMean, Max, Min,
 *   Median, SingleLayer), GaussianSigma (1.0; > 0, physical units): see TextureLayers;
 * - Interpolator: any InterpolateImageFunction of the volume (linear by default;
 *   BSplineInterpolateImageFunction or WindowedSincInterpolateImageFunction for sharper
 *   textures).
 *
 * Diagnostics after Update(): GetNumberOfSheetPixels(), GetNumberOfDegenerateTriangles()
 * (skipped: zero 3D or flat area), GetNumberOfZeroNormalPixels() (left off the sheet),
 * GetNumberOfClampedSamples() (samples outside the volume, clamped to its boundary).
 *
 * Throws itk::ExceptionObject when the meshes differ in topology, a mesh is invalid or
 * has non-triangle cells, or a parameter is out of range. Runs in parallel over rows with
 * MultiThreaderBase::ParallelizeArray, reports progress and honours AbortGenerateData.
 *
 * References: W. B. Seales and Y. Lin, "Digital Restoration Using Volumetric Scanning",
 * JCDL 2004 (layered texture); the separation of the per-pixel map from the filters
 * follows volume-cartographer (EduceLab, University of Kentucky).
 *
 * \ingroup VirtualUnwrapping
 */
template <typename TImage, typename TOutputImage = Image<float, 2>, typename TMesh = Mesh<float, 3>>
class ITK_TEMPLATE_EXPORT FlattenedTextureImageFilter : public ImageSource<TOutputImage>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(FlattenedTextureImageFilter);

  using Self = FlattenedTextureImageFilter;
  using Superclass = ImageSource<TOutputImage>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(FlattenedTextureImageFilter, ImageSource);

  static_assert(TImage::ImageDimension == 3, "the volume must be 3D");
  static_assert(TOutputImage::ImageDimension == 2, "the texture must be 2D");
  static_assert(std::is_floating_point<typename TOutputImage::PixelType>::value,
                "the texture pixel must be floating point: pixels off the sheet are NaN");

  using VolumeType = TImage;
  using MeshType = TMesh;
  using OutputImageType = TOutputImage;
  using OutputPixelType = typename TOutputImage::PixelType;
  using MaskImageType = Image<unsigned char, 2>;
  using LayerStackImageType = Image<OutputPixelType, 3>;
  using InterpolatorType = InterpolateImageFunction<TImage, double>;
  using SideEnum = TextureLayersEnums::Side;
  using FilterEnum = TextureLayersEnums::Filter;
  using DataObjectPointerArraySizeType = ProcessObject::DataObjectPointerArraySizeType;

  itkSetInputMacro(SurfaceMesh, MeshType);
  itkGetInputMacro(SurfaceMesh, MeshType);
  itkSetInputMacro(FlatMesh, MeshType);
  itkGetInputMacro(FlatMesh, MeshType);
  itkSetInputMacro(Volume, VolumeType);
  itkGetInputMacro(Volume, VolumeType);

  MaskImageType *
  GetMaskOutput();
  const MaskImageType *
  GetMaskOutput() const;
  LayerStackImageType *
  GetLayerStackOutput();
  const LayerStackImageType *
  GetLayerStackOutput() const;

  itkSetMacro(PixelSize, double);
  itkGetConstMacro(PixelSize, double);
  itkSetMacro(Margin, double);
  itkGetConstMacro(Margin, double);
  itkSetMacro(CurvedSurface, bool);
  itkGetConstMacro(CurvedSurface, bool);
  itkBooleanMacro(CurvedSurface);
  itkSetMacro(NumberOfLayers, unsigned int);
  itkGetConstMacro(NumberOfLayers, unsigned int);
  itkSetMacro(LayerSpacing, double);
  itkGetConstMacro(LayerSpacing, double);
  itkSetMacro(Focus, double);
  itkGetConstMacro(Focus, double);
  itkSetEnumMacro(LayerSide, SideEnum);
  itkGetEnumMacro(LayerSide, SideEnum);
  itkSetEnumMacro(LayerFilter, FilterEnum);
  itkGetEnumMacro(LayerFilter, FilterEnum);
  itkSetMacro(GaussianSigma, double);
  itkGetConstMacro(GaussianSigma, double);
  itkSetObjectMacro(Interpolator, InterpolatorType);
  itkGetModifiableObjectMacro(Interpolator, InterpolatorType);

  itkGetConstMacro(NumberOfSheetPixels, SizeValueType);
  itkGetConstMacro(NumberOfDegenerateTriangles, SizeValueType);
  itkGetConstMacro(NumberOfZeroNormalPixels, SizeValueType);
  itkGetConstMacro(NumberOfClampedSamples, SizeValueType);

  /** The pixel map of the last Update(): 3D point, normal and triangle per pixel. */
  const TexturePixelMap &
  GetPixelMap() const
  {
    return m_PixelMap;
  }

protected:
  FlattenedTextureImageFilter();
  ~FlattenedTextureImageFilter() override = default;

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
  TextureLayers
  MakeLayers() const;

  double                             m_PixelSize{ 1.0 };
  double                             m_Margin{ 0.0 };
  bool                               m_CurvedSurface{ false };
  unsigned int                       m_NumberOfLayers{ 1 };
  double                             m_LayerSpacing{ 1.0 };
  double                             m_Focus{ 0.0 };
  SideEnum                           m_LayerSide{ SideEnum::Both };
  FilterEnum                         m_LayerFilter{ FilterEnum::Mean };
  double                             m_GaussianSigma{ 1.0 };
  typename InterpolatorType::Pointer m_Interpolator;

  SizeValueType m_NumberOfSheetPixels{ 0 };
  SizeValueType m_NumberOfDegenerateTriangles{ 0 };
  SizeValueType m_NumberOfZeroNormalPixels{ 0 };
  SizeValueType m_NumberOfClampedSamples{ 0 };

  TexturePixelMap m_PixelMap;
  // What m_PixelMap was computed from; a change in any of them rebuilds it.
  ModifiedTimeType m_PixelMapSurfaceTime{ 0 };
  ModifiedTimeType m_PixelMapFlatTime{ 0 };
  const MeshType * m_PixelMapSurface{ nullptr };
  const MeshType * m_PixelMapFlat{ nullptr };
  double           m_PixelMapMargin{ -1.0 };
  bool             m_PixelMapCurved{ false };
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkFlattenedTextureImageFilter.hxx"
#endif

#endif

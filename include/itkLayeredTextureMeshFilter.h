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
#ifndef itkLayeredTextureMeshFilter_h
#define itkLayeredTextureMeshFilter_h

#include "itkInterpolateImageFunction.h"
#include "itkMeshToMeshFilter.h"
#include "itkTextureLayers.h"

namespace itk {
/** \class LayeredTextureMeshFilter
 * \brief Textures a sheet mesh for 3D viewing: samples the CT volume in layers along the
 * surface normal at every vertex and stores the combined value as the vertex's point
 * data.
 *
 * Inputs: the sheet mesh (SetInput, triangles only, in the volume's physical space) and
 * the CT volume (SetVolume, 3D image). Output: a copy of the mesh (points and cells)
 * whose point data holds, per point, the layers combined with LayerFilter; NaN where the
 * vertex normal vanishes (isolated points, points of degenerate triangles only).
 *
 * Normals are the area-weighted vertex normals of the mesh (SheetMesh::ComputeVertexNormals),
 * oriented by the triangles' winding. Layer k of a vertex p with normal n is sampled at
 * p + offset_k * n (TextureLayers).
 *
 * Parameters (defaults; ranges): NumberOfLayers (1; >= 1), LayerSpacing (1.0; > 0,
 * physical units), Focus: offset of the central layer along the normal (0.0; any,
 * physical units), LayerSide (Both; Both, Positive, Negative), LayerFilter (Mean; Mean,
 * GaussianMean, Max, Min, Median, SingleLayer), GaussianSigma (1.0; > 0, physical
 * units), Interpolator (linear; any InterpolateImageFunction of the volume).
 *
 * Diagnostics after Update(): GetNumberOfZeroNormalPoints(), GetNumberOfClampedSamples()
 * (samples outside the volume, clamped to its boundary).
 *
 * Throws itk::ExceptionObject when a parameter is out of range or the mesh has
 * non-triangle cells. Runs in parallel over blocks of points
 * (MultiThreaderBase::ParallelizeArray), reports progress, honours AbortGenerateData.
 *
 * Reference: W. B. Seales and Y. Lin, "Digital Restoration Using Volumetric Scanning",
 * JCDL 2004 (layered texture: number of layers, distance between layers, filter).
 *
 * \ingroup VirtualUnwrapping
 */
template <typename TInputMesh, typename TImage, typename TOutputMesh = TInputMesh>
class ITK_TEMPLATE_EXPORT LayeredTextureMeshFilter : public MeshToMeshFilter<TInputMesh, TOutputMesh>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(LayeredTextureMeshFilter);

  using Self = LayeredTextureMeshFilter;
  using Superclass = MeshToMeshFilter<TInputMesh, TOutputMesh>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(LayeredTextureMeshFilter, MeshToMeshFilter);

  static_assert(TImage::ImageDimension == 3, "the volume must be 3D");
  static_assert(TInputMesh::PointDimension == 3, "the sheet mesh must be 3D");

  using InputMeshType = TInputMesh;
  using OutputMeshType = TOutputMesh;
  using VolumeType = TImage;
  using OutputPixelType = typename TOutputMesh::PixelType;
  using InterpolatorType = InterpolateImageFunction<TImage, double>;
  using SideEnum = TextureLayersEnums::Side;
  using FilterEnum = TextureLayersEnums::Filter;

  itkSetInputMacro(Volume, VolumeType);
  itkGetInputMacro(Volume, VolumeType);

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

  itkGetConstMacro(NumberOfZeroNormalPoints, SizeValueType);
  itkGetConstMacro(NumberOfClampedSamples, SizeValueType);

protected:
  LayeredTextureMeshFilter();
  ~LayeredTextureMeshFilter() override = default;

  void
  VerifyPreconditions() ITKv5_CONST override;
  void
  GenerateData() override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  TextureLayers
  MakeLayers() const;

  unsigned int                       m_NumberOfLayers{ 1 };
  double                             m_LayerSpacing{ 1.0 };
  double                             m_Focus{ 0.0 };
  SideEnum                           m_LayerSide{ SideEnum::Both };
  FilterEnum                         m_LayerFilter{ FilterEnum::Mean };
  double                             m_GaussianSigma{ 1.0 };
  typename InterpolatorType::Pointer m_Interpolator;

  SizeValueType m_NumberOfZeroNormalPoints{ 0 };
  SizeValueType m_NumberOfClampedSamples{ 0 };
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkLayeredTextureMeshFilter.hxx"
#endif

#endif

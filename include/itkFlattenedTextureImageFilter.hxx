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
#ifndef itkFlattenedTextureImageFilter_hxx
#define itkFlattenedTextureImageFilter_hxx

#include "itkFlattenedTextureImageFilter.h"

#include "itkLayeredVolumeSampler.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkProgressTransformer.h"
#include "itkSheetMeshAdaptor.h"

#include <algorithm>
#include <atomic>
#include <limits>

namespace itk {
template <typename TImage, typename TOutputImage, typename TMesh>
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::FlattenedTextureImageFilter()
  : m_Interpolator(LinearInterpolateImageFunction<TImage, double>::New())
{
  this->AddRequiredInputName("FlatMesh");
  this->AddRequiredInputName("Volume");
  this->SetPrimaryInputName("SurfaceMesh");
  this->SetNumberOfRequiredOutputs(3);
  this->SetNthOutput(1, this->MakeOutput(1));
  this->SetNthOutput(2, this->MakeOutput(2));
}

template <typename TImage, typename TOutputImage, typename TMesh>
DataObject::Pointer
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::MakeOutput(DataObjectPointerArraySizeType idx)
{
  switch (idx)
  {
    case 1:
      return MaskImageType::New().GetPointer();
    case 2:
      return LayerStackImageType::New().GetPointer();
    default:
      return TOutputImage::New().GetPointer();
  }
}

template <typename TImage, typename TOutputImage, typename TMesh>
auto
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GetMaskOutput() -> MaskImageType *
{
  return itkDynamicCastInDebugMode<MaskImageType *>(this->ProcessObject::GetOutput(1));
}

template <typename TImage, typename TOutputImage, typename TMesh>
auto
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GetLayerStackOutput() -> LayerStackImageType *
{
  return itkDynamicCastInDebugMode<LayerStackImageType *>(this->ProcessObject::GetOutput(2));
}

template <typename TImage, typename TOutputImage, typename TMesh>
auto
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GetMaskOutput() const -> const MaskImageType *
{
  return itkDynamicCastInDebugMode<const MaskImageType *>(this->ProcessObject::GetOutput(1));
}

template <typename TImage, typename TOutputImage, typename TMesh>
auto
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GetLayerStackOutput() const -> const LayerStackImageType *
{
  return itkDynamicCastInDebugMode<const LayerStackImageType *>(this->ProcessObject::GetOutput(2));
}

template <typename TImage, typename TOutputImage, typename TMesh>
TextureLayers
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::MakeLayers() const
{
  return TextureLayers(m_NumberOfLayers, m_LayerSpacing, m_Focus, m_LayerSide, m_LayerFilter, m_GaussianSigma);
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  if (!(m_PixelSize > 0.0) || !std::isfinite(m_PixelSize))
  {
    itkExceptionMacro(<< "PixelSize must be positive and finite, got " << m_PixelSize);
  }
  if (!(m_Margin >= 0.0) || !std::isfinite(m_Margin))
  {
    itkExceptionMacro(<< "Margin must be non-negative and finite, got " << m_Margin);
  }
  if (m_Interpolator.IsNull())
  {
    itkExceptionMacro(<< "no interpolator set");
  }
  this->MakeLayers();
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GenerateOutputInformation()
{
  // The grid follows the flat mesh's bounding box, known only once the mesh exists.
  auto * flatMesh = const_cast<MeshType *>(this->GetFlatMesh());
  flatMesh->Update();
  const TexturePixelMap grid = ComputeTextureGrid(MeshToSheetMesh(flatMesh), m_PixelSize, m_Margin);
  const TextureLayers   layers = this->MakeLayers();

  typename TOutputImage::RegionType region;
  region.SetSize(0, grid.Size[0]);
  region.SetSize(1, grid.Size[1]);
  typename TOutputImage::PointType   origin;
  typename TOutputImage::SpacingType spacing;
  for (unsigned int d = 0; d < 2; ++d)
  {
    origin[d] = grid.Origin[d];
    spacing[d] = grid.PixelSize;
  }
  for (unsigned int k = 0; k < 2; ++k)
  {
    ImageBase<2> * output =
      k == 0 ? static_cast<ImageBase<2> *>(this->GetOutput()) : static_cast<ImageBase<2> *>(this->GetMaskOutput());
    output->SetLargestPossibleRegion(region);
    output->SetOrigin(origin);
    output->SetSpacing(spacing);
    output->SetDirection(TOutputImage::DirectionType::GetIdentity());
  }

  typename LayerStackImageType::RegionType    stackRegion;
  typename LayerStackImageType::PointType     stackOrigin;
  typename LayerStackImageType::SpacingType   stackSpacing;
  typename LayerStackImageType::DirectionType stackDirection;
  stackDirection.SetIdentity();
  for (unsigned int d = 0; d < 2; ++d)
  {
    stackRegion.SetSize(d, grid.Size[d]);
    stackOrigin[d] = grid.Origin[d];
    stackSpacing[d] = grid.PixelSize;
  }
  stackRegion.SetSize(2, layers.GetNumberOfLayers());
  stackOrigin[2] = layers.GetOffsets()[0];
  stackSpacing[2] = m_LayerSpacing;
  if (m_LayerSide == SideEnum::Negative)
  {
    stackDirection[2][2] = -1.0;
  }
  LayerStackImageType * stack = this->GetLayerStackOutput();
  stack->SetLargestPossibleRegion(stackRegion);
  stack->SetOrigin(stackOrigin);
  stack->SetSpacing(stackSpacing);
  stack->SetDirection(stackDirection);
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::EnlargeOutputRequestedRegion(DataObject *)
{
  for (const auto & output : this->GetOutputs())
  {
    output->SetRequestedRegionToLargestPossibleRegion();
  }
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::GenerateData()
{
  const MeshType *   surfaceMesh = this->GetSurfaceMesh();
  const MeshType *   flatMesh = this->GetFlatMesh();
  const VolumeType * volume = this->GetVolume();
  const bool         mapIsCurrent = m_PixelMapSurface == surfaceMesh && m_PixelMapFlat == flatMesh &&
                            m_PixelMapSurfaceTime == surfaceMesh->GetMTime() &&
                            m_PixelMapFlatTime == flatMesh->GetMTime() && m_PixelMap.PixelSize == m_PixelSize &&
                            m_PixelMapMargin == m_Margin && m_PixelMapCurved == m_CurvedSurface &&
                            !m_PixelMap.Triangle.empty();
  constexpr float mapShare = 0.3f;
  if (!mapIsCurrent)
  {
    m_PixelMapSurface = nullptr;
    m_PixelMap = ComputeTexturePixelMap(MeshToSheetMesh(surfaceMesh),
                                        MeshToSheetMesh(flatMesh),
                                        m_PixelSize,
                                        m_Margin,
                                        this,
                                        0.0f,
                                        mapShare,
                                        m_CurvedSurface);
    m_PixelMapSurface = surfaceMesh;
    m_PixelMapFlat = flatMesh;
    m_PixelMapSurfaceTime = surfaceMesh->GetMTime();
    m_PixelMapFlatTime = flatMesh->GetMTime();
    m_PixelMapMargin = m_Margin;
    m_PixelMapCurved = m_CurvedSurface;
  }
  m_NumberOfSheetPixels = m_PixelMap.GetNumberOfSheetPixels();
  m_NumberOfDegenerateTriangles = m_PixelMap.NumberOfDegenerateTriangles;
  m_NumberOfZeroNormalPixels = m_PixelMap.NumberOfZeroNormalPixels;

  // ImageSource::AllocateOutputs allocates only outputs of TOutputImage's type.
  this->AllocateOutputs();
  MaskImageType * maskOutput = this->GetMaskOutput();
  maskOutput->SetBufferedRegion(maskOutput->GetRequestedRegion());
  maskOutput->Allocate();
  LayerStackImageType * stackOutput = this->GetLayerStackOutput();
  stackOutput->SetBufferedRegion(stackOutput->GetRequestedRegion());
  stackOutput->Allocate();
  const TextureLayers layers = this->MakeLayers();
  LayeredVolumeSampler<TImage>::ConnectInterpolator(m_Interpolator, volume);
  const LayeredVolumeSampler<TImage> sampler(volume, m_Interpolator, layers);

  const SizeValueType   columns = m_PixelMap.Size[0];
  const SizeValueType   rows = m_PixelMap.Size[1];
  const SizeValueType   sliceSize = columns * rows;
  const unsigned int    numberOfLayers = layers.GetNumberOfLayers();
  OutputPixelType *     texture = this->GetOutput()->GetBufferPointer();
  unsigned char *       mask = maskOutput->GetBufferPointer();
  OutputPixelType *     stack = stackOutput->GetBufferPointer();
  const OutputPixelType nan = std::numeric_limits<OutputPixelType>::quiet_NaN();

  // The texture is sampled in tiles of a few rows (along the roll axis) by a run of
  // columns (along the sheet): a tile's samples lie in a small block of the volume, which
  // its neighbouring rows read again while it is in the cache. Row by row, a long sheet's
  // row reads more of the volume than the cache holds before the next row comes back to
  // it, and every sample waits for memory. Each thread takes the next tile as it finishes
  // one: the sheet covers the texture unevenly (a roll's turns differ in length), and
  // fixed shares left one thread sampling alone for a fifth of the stage.
  constexpr SizeValueType    tileRows = 8;
  constexpr SizeValueType    tileColumns = 256;
  const SizeValueType        rowTiles = (rows + tileRows - 1) / tileRows;
  const SizeValueType        columnTiles = (columns + tileColumns - 1) / tileColumns;
  std::atomic<SizeValueType> clamped{ 0 };
  std::atomic<bool>          aborted{ false };
  std::atomic<SizeValueType> nextTile{ 0 };
  ProgressTransformer        progress(mapIsCurrent ? 0.0f : mapShare, 1.0f, this);
  const auto                 sampleTile = [&](SizeValueType tile) {
    std::vector<float>  samples(numberOfLayers);
    SizeValueType       tileClamped = 0;
    const SizeValueType firstRow = (tile / columnTiles) * tileRows;
    const SizeValueType firstColumn = (tile % columnTiles) * tileColumns;
    const SizeValueType lastColumn = std::min(columns, firstColumn + tileColumns);
    for (SizeValueType row = firstRow; row < std::min(rows, firstRow + tileRows); ++row)
    {
      for (SizeValueType pixel = row * columns + firstColumn; pixel < row * columns + lastColumn; ++pixel)
      {
        if (m_PixelMap.Triangle[pixel] < 0)
        {
          texture[pixel] = nan;
          mask[pixel] = 0;
          for (unsigned int k = 0; k < numberOfLayers; ++k)
          {
            stack[k * sliceSize + pixel] = nan;
          }
          continue;
        }
        const float * p = &m_PixelMap.Positions[3 * pixel];
        const float * n = &m_PixelMap.Normals[3 * pixel];
        const double  point[3] = { p[0], p[1], p[2] };
        const double  normal[3] = { n[0], n[1], n[2] };
        tileClamped += sampler.Sample(point, normal, samples.data());
        for (unsigned int k = 0; k < numberOfLayers; ++k)
        {
          stack[k * sliceSize + pixel] = static_cast<OutputPixelType>(samples[k]);
        }
        texture[pixel] = static_cast<OutputPixelType>(layers.Combine(samples.data()));
        mask[pixel] = 1;
      }
    }
    clamped += tileClamped;
  };
  this->GetMultiThreader()->ParallelizeArray(
    0,
    std::max<SizeValueType>(1, this->GetMultiThreader()->GetNumberOfWorkUnits()),
    [&](SizeValueType) {
      for (SizeValueType tile = nextTile++; tile < rowTiles * columnTiles; tile = nextTile++)
      {
        if (aborted || this->GetAbortGenerateData())
        {
          aborted = true;
          return;
        }
        sampleTile(tile);
      }
    },
    progress.GetProcessObject());
  if (aborted || this->GetAbortGenerateData())
  {
    ProcessAborted e(__FILE__, __LINE__);
    e.SetDescription("FlattenedTextureImageFilter: aborted");
    throw e;
  }
  m_NumberOfClampedSamples = clamped;
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
FlattenedTextureImageFilter<TImage, TOutputImage, TMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "PixelSize: " << m_PixelSize << std::endl;
  os << indent << "Margin: " << m_Margin << std::endl;
  os << indent << "CurvedSurface: " << m_CurvedSurface << std::endl;
  os << indent << "NumberOfLayers: " << m_NumberOfLayers << std::endl;
  os << indent << "LayerSpacing: " << m_LayerSpacing << std::endl;
  os << indent << "Focus: " << m_Focus << std::endl;
  os << indent << "LayerSide: " << m_LayerSide << std::endl;
  os << indent << "LayerFilter: " << m_LayerFilter << std::endl;
  os << indent << "GaussianSigma: " << m_GaussianSigma << std::endl;
  itkPrintSelfObjectMacro(Interpolator);
  os << indent << "NumberOfSheetPixels: " << m_NumberOfSheetPixels << std::endl;
  os << indent << "NumberOfDegenerateTriangles: " << m_NumberOfDegenerateTriangles << std::endl;
  os << indent << "NumberOfZeroNormalPixels: " << m_NumberOfZeroNormalPixels << std::endl;
  os << indent << "NumberOfClampedSamples: " << m_NumberOfClampedSamples << std::endl;
  os << indent << "PixelMap: " << m_PixelMap.Size[0] << " x " << m_PixelMap.Size[1] << " pixels" << std::endl;
  os << indent << "PixelMapMargin: " << m_PixelMapMargin << std::endl;
  os << indent << "PixelMapSurface: " << m_PixelMapSurface << " (time " << m_PixelMapSurfaceTime << ")" << std::endl;
  os << indent << "PixelMapFlat: " << m_PixelMapFlat << " (time " << m_PixelMapFlatTime << ")" << std::endl;
}
} // end namespace itk

#endif

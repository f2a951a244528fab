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
#ifndef itkLayeredTextureMeshFilter_hxx
#define itkLayeredTextureMeshFilter_hxx

#include "itkLayeredTextureMeshFilter.h"
#include "itkMultiThreaderBase.h"

#include "itkLayeredVolumeSampler.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkSheetMeshAdaptor.h"

#include <atomic>
#include <limits>

namespace itk {
template <typename TInputMesh, typename TImage, typename TOutputMesh>
LayeredTextureMeshFilter<TInputMesh, TImage, TOutputMesh>::LayeredTextureMeshFilter()
  : m_Interpolator(LinearInterpolateImageFunction<TImage, double>::New())
{
  this->AddRequiredInputName("Volume");
}

template <typename TInputMesh, typename TImage, typename TOutputMesh>
TextureLayers
LayeredTextureMeshFilter<TInputMesh, TImage, TOutputMesh>::MakeLayers() const
{
  return TextureLayers(m_NumberOfLayers, m_LayerSpacing, m_Focus, m_LayerSide, m_LayerFilter, m_GaussianSigma);
}

template <typename TInputMesh, typename TImage, typename TOutputMesh>
void
LayeredTextureMeshFilter<TInputMesh, TImage, TOutputMesh>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  if (m_Interpolator.IsNull())
  {
    itkExceptionMacro(<< "no interpolator set");
  }
  this->MakeLayers();
}

template <typename TInputMesh, typename TImage, typename TOutputMesh>
void
LayeredTextureMeshFilter<TInputMesh, TImage, TOutputMesh>::GenerateData()
{
  const InputMeshType * input = this->GetInput();
  const VolumeType *    volume = this->GetVolume();
  OutputMeshType *      output = this->GetOutput();
  this->CopyInputMeshToOutputMeshPoints();
  this->CopyInputMeshToOutputMeshCells();
  this->CopyInputMeshToOutputMeshCellData();

  const SheetMesh sheet = MeshToSheetMesh(input);
  sheet.Validate("LayeredTextureMeshFilter: input mesh");
  const std::vector<double> normals = sheet.ComputeVertexNormals();
  const TextureLayers       layers = this->MakeLayers();
  LayeredVolumeSampler<TImage>::ConnectInterpolator(m_Interpolator, volume);
  const LayeredVolumeSampler<TImage> sampler(volume, m_Interpolator, layers);

  const SizeValueType        numberOfPoints = sheet.GetNumberOfPoints();
  std::vector<float>         values(numberOfPoints);
  constexpr SizeValueType    blockSize = 4096;
  const SizeValueType        blocks = (numberOfPoints + blockSize - 1) / blockSize;
  std::atomic<SizeValueType> clamped{ 0 };
  std::atomic<SizeValueType> zeroNormals{ 0 };
  std::atomic<bool>          aborted{ false };
  this->GetMultiThreader()->ParallelizeArray(
    0,
    blocks,
    [&](SizeValueType block) {
      if (aborted || this->GetAbortGenerateData())
      {
        aborted = true;
        return;
      }
      std::vector<float>  samples(layers.GetNumberOfLayers());
      SizeValueType       blockClamped = 0;
      SizeValueType       blockZeroNormals = 0;
      const SizeValueType last = std::min(numberOfPoints, (block + 1) * blockSize);
      for (SizeValueType i = block * blockSize; i < last; ++i)
      {
        const double * n = &normals[3 * i];
        if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0)
        {
          values[i] = std::numeric_limits<float>::quiet_NaN();
          ++blockZeroNormals;
          continue;
        }
        blockClamped += sampler.Sample(&sheet.Points[3 * i], n, samples.data());
        values[i] = layers.Combine(samples.data());
      }
      clamped += blockClamped;
      zeroNormals += blockZeroNormals;
    },
    this);
  if (aborted || this->GetAbortGenerateData())
  {
    ProcessAborted e(__FILE__, __LINE__);
    e.SetDescription("LayeredTextureMeshFilter: aborted");
    throw e;
  }
  m_NumberOfClampedSamples = clamped;
  m_NumberOfZeroNormalPoints = zeroNormals;

  // MeshToSheetMesh numbers points in the order of the input's point container.
  auto pointData = OutputMeshType::PointDataContainer::New();
  pointData->Reserve(numberOfPoints);
  SizeValueType i = 0;
  for (auto it = input->GetPoints()->Begin(); it != input->GetPoints()->End(); ++it, ++i)
  {
    pointData->InsertElement(it.Index(), static_cast<OutputPixelType>(values[i]));
  }
  output->SetPointData(pointData);
  MarkMeshWhole(output);
}

template <typename TInputMesh, typename TImage, typename TOutputMesh>
void
LayeredTextureMeshFilter<TInputMesh, TImage, TOutputMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfLayers: " << m_NumberOfLayers << std::endl;
  os << indent << "LayerSpacing: " << m_LayerSpacing << std::endl;
  os << indent << "Focus: " << m_Focus << std::endl;
  os << indent << "LayerSide: " << m_LayerSide << std::endl;
  os << indent << "LayerFilter: " << m_LayerFilter << std::endl;
  os << indent << "GaussianSigma: " << m_GaussianSigma << std::endl;
  itkPrintSelfObjectMacro(Interpolator);
  os << indent << "NumberOfZeroNormalPoints: " << m_NumberOfZeroNormalPoints << std::endl;
  os << indent << "NumberOfClampedSamples: " << m_NumberOfClampedSamples << std::endl;
}
} // end namespace itk

#endif

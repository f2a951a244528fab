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
#ifndef itkReadableTextureImageFilter_hxx
#define itkReadableTextureImageFilter_hxx

#include "itkReadableTextureImageFilter.h"

#include "itkProgressAccumulator.h"

#include <algorithm>
#include <cmath>

namespace itk {
template <typename TImage, typename TOutputImage, typename TMesh>
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::ReadableTextureImageFilter()
  : m_TextureFilter(TextureFilterType::New())
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
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::MakeOutput(DataObjectPointerArraySizeType idx)
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
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::GetMaskOutput() -> MaskImageType *
{
  return itkDynamicCastInDebugMode<MaskImageType *>(this->ProcessObject::GetOutput(1));
}

template <typename TImage, typename TOutputImage, typename TMesh>
auto
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::GetLayerStackOutput() -> LayerStackImageType *
{
  return itkDynamicCastInDebugMode<LayerStackImageType *>(this->ProcessObject::GetOutput(2));
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::VerifyPreconditions() ITKv5_CONST
{
  Superclass::VerifyPreconditions();
  const auto finite = [](double v) { return std::isfinite(v); };
  if (!(m_PixelSize >= 0.0) || !finite(m_PixelSize))
  {
    itkExceptionMacro(<< "PixelSize must be 0 (automatic) or positive, got " << m_PixelSize);
  }
  if (!(m_LayerSpacing >= 0.0) || !finite(m_LayerSpacing))
  {
    itkExceptionMacro(<< "LayerSpacing must be 0 (automatic) or positive, got " << m_LayerSpacing);
  }
  if (!(m_SheetThickness >= 0.0) || !finite(m_SheetThickness))
  {
    itkExceptionMacro(<< "SheetThickness must be non-negative, got " << m_SheetThickness);
  }
  if (!finite(m_Focus) || !finite(m_Margin) || !finite(m_MedianRadius) || !finite(m_SmoothSigma) ||
      !finite(m_RestoreFWHM) || !(m_DenoisingSigma >= 0.0) || !finite(m_DenoisingSigma))
  {
    itkExceptionMacro(<< "Focus, Margin, MedianRadius, SmoothSigma and RestoreFWHM must be finite and "
                         "DenoisingSigma non-negative");
  }
  if (m_AutomaticSide && m_NumberOfLayers > 0 && m_NumberOfLayers % 2 == 0)
  {
    itkExceptionMacro(<< "the automatic side splits the layers at the focus: give an odd NumberOfLayers, not "
                      << m_NumberOfLayers);
  }
  if (m_RestoreFWHM >= 0.0 && m_SmoothSigma > 0.0)
  {
    itkExceptionMacro(<< "restoration replaces the Gaussian smoothing: leave SmoothSigma automatic (negative) or 0");
  }
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::ConfigureTextureFilter()
{
  auto * volume = const_cast<VolumeType *>(this->GetVolume());
  volume->UpdateOutputInformation();
  const auto spacing = volume->GetSpacing();
  m_Voxel = *std::min_element(spacing.Begin(), spacing.End());
  m_AppliedPixelSize = m_PixelSize > 0.0 ? m_PixelSize : 0.5 * m_Voxel;
  m_AppliedLayerSpacing = m_LayerSpacing > 0.0 ? m_LayerSpacing : 0.5 * m_Voxel;
  const SideEnum stackSide = m_AutomaticSide ? SideEnum::Both : m_LayerSide;
  m_AppliedNumberOfLayers = m_NumberOfLayers > 0
                              ? m_NumberOfLayers
                              : ReadableTextureLayers(m_SheetThickness, m_Voxel, m_AppliedLayerSpacing, stackSide);
  m_TextureFilter->SetSurfaceMesh(this->GetSurfaceMesh());
  m_TextureFilter->SetFlatMesh(this->GetFlatMesh());
  m_TextureFilter->SetVolume(volume);
  m_TextureFilter->SetPixelSize(m_AppliedPixelSize);
  m_TextureFilter->SetMargin(m_Margin >= 0.0 ? m_Margin : 2.0 * m_AppliedPixelSize);
  // The focal slabs of a noisy scan read a layer a voxel thick at a fixed depth, where
  // the triangles' chords would show as stripes: their points are placed on the curved
  // sheet. The other textures take a layer stack's extreme over a side or the whole
  // sheet, which such depth errors hardly change, and keep the triangles' points.
  m_TextureFilter->SetCurvedSurface(m_AutomaticSide && m_DenoisingSigma > 0.0);
  m_TextureFilter->SetNumberOfLayers(m_AppliedNumberOfLayers);
  m_TextureFilter->SetLayerSpacing(m_AppliedLayerSpacing);
  m_TextureFilter->SetFocus(m_Focus);
  m_TextureFilter->SetLayerSide(stackSide);
  m_TextureFilter->SetLayerFilter(m_LayerFilter);
  m_TextureFilter->SetGaussianSigma(m_GaussianSigma);
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::GenerateOutputInformation()
{
  this->ConfigureTextureFilter();
  m_TextureFilter->UpdateOutputInformation();
  this->GetOutput()->CopyInformation(m_TextureFilter->GetOutput());
  this->GetMaskOutput()->CopyInformation(m_TextureFilter->GetMaskOutput());
  this->GetLayerStackOutput()->CopyInformation(m_TextureFilter->GetLayerStackOutput());
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::EnlargeOutputRequestedRegion(DataObject *)
{
  for (const auto & output : this->GetOutputs())
  {
    output->SetRequestedRegionToLargestPossibleRegion();
  }
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::GenerateData()
{
  this->ConfigureTextureFilter();
  // Sampling is most of the work: its progress is this filter's up to 90 %.
  auto progress = ProgressAccumulator::New();
  progress->SetMiniPipelineFilter(this);
  progress->RegisterInternalFilter(m_TextureFilter, 0.9f);
  m_TextureFilter->Update();

  ReadableTextureSettings settings;
  settings.NumberOfLayers = m_AppliedNumberOfLayers;
  settings.LayerSpacing = m_AppliedLayerSpacing;
  settings.Focus = m_Focus;
  settings.StackSide = m_TextureFilter->GetLayerSide();
  settings.AutomaticSide = m_AutomaticSide;
  settings.SubtractCore = m_SubtractCore;
  settings.Filter = m_LayerFilter;
  settings.GaussianSigma = m_GaussianSigma;
  settings.Voxel = m_Voxel;
  settings.DenoisingSigma = m_DenoisingSigma;
  settings.MedianRadius = m_MedianRadius;
  settings.SmoothSigma = m_SmoothSigma;
  settings.RestoreFWHM = m_RestoreFWHM;
  m_Selection = SelectReadableTexture(m_TextureFilter->GetLayerStackOutput(), settings);

  this->GraftNthOutput(0, m_Selection.Texture);
  this->GraftNthOutput(1, m_TextureFilter->GetMaskOutput());
  this->GraftNthOutput(2, m_TextureFilter->GetLayerStackOutput());
  this->UpdateProgress(1.0f);
}

template <typename TImage, typename TOutputImage, typename TMesh>
void
ReadableTextureImageFilter<TImage, TOutputImage, TMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "PixelSize: " << m_PixelSize << " (applied " << m_AppliedPixelSize << ")\n";
  os << indent << "Margin: " << m_Margin << '\n';
  os << indent << "NumberOfLayers: " << m_NumberOfLayers << " (applied " << m_AppliedNumberOfLayers << ")\n";
  os << indent << "LayerSpacing: " << m_LayerSpacing << " (applied " << m_AppliedLayerSpacing << ")\n";
  os << indent << "SheetThickness: " << m_SheetThickness << '\n';
  os << indent << "Focus: " << m_Focus << '\n';
  os << indent << "AutomaticSide: " << m_AutomaticSide << '\n';
  os << indent << "LayerSide: " << m_LayerSide << '\n';
  os << indent << "SubtractCore: " << m_SubtractCore << '\n';
  os << indent << "LayerFilter: " << m_LayerFilter << '\n';
  os << indent << "GaussianSigma: " << m_GaussianSigma << '\n';
  os << indent << "DenoisingSigma: " << m_DenoisingSigma << '\n';
  os << indent << "MedianRadius: " << m_MedianRadius << '\n';
  os << indent << "SmoothSigma: " << m_SmoothSigma << '\n';
  os << indent << "RestoreFWHM: " << m_RestoreFWHM << '\n';
}
} // end namespace itk

#endif

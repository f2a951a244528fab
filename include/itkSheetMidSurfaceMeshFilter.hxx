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
#ifndef itkSheetMidSurfaceMeshFilter_hxx
#define itkSheetMidSurfaceMeshFilter_hxx

#include "itkConnectedComponentImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkRelabelComponentImageFilter.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetMidSurfaceMeshFilter.h"

#include <numeric>
#include <sstream>

#include "vnl/algo/vnl_determinant.h"

namespace itk {
template <typename TMaskImage, typename TOutputMesh>
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::SheetMidSurfaceMeshFilter()
{
  this->SetNumberOfRequiredInputs(1);
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::SetIntensityImage(const IntensityImageType * image)
{
  this->ProcessObject::SetNthInput(1, const_cast<IntensityImageType *>(image));
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::GetIntensityImage() const -> const IntensityImageType *
{
  return dynamic_cast<const IntensityImageType *>(this->ProcessObject::GetInput(1));
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::GenerateData()
{
  const MaskImageType *      mask = this->GetInput(0);
  const IntensityImageType * intensity = this->GetIntensityImage();
  if (mask == nullptr || mask->GetBufferedRegion().GetNumberOfPixels() == 0)
  {
    itkExceptionMacro(<< "the mask is empty");
  }
  const auto region = mask->GetBufferedRegion();
  if (intensity != nullptr && intensity->GetBufferedRegion() != region)
  {
    itkExceptionMacro(<< "the intensity image (" << intensity->GetBufferedRegion().GetSize()
                      << ") does not cover the mask (" << region.GetSize() << ")");
  }
  this->UpdateProgress(0.0f);

  // One sheet = one connected mesh: keep the largest face-connected component.
  using LabelImageType = Image<SizeValueType, 3>;
  auto components = ConnectedComponentImageFilter<MaskImageType, LabelImageType>::New();
  components->SetInput(mask);
  components->FullyConnectedOff();
  auto relabel = RelabelComponentImageFilter<LabelImageType, LabelImageType>::New();
  relabel->SetInput(components->GetOutput());
  relabel->Update();
  const LabelImageType * labels = relabel->GetOutput();
  m_Report = SheetMidSurfaceReport{};
  if (relabel->GetNumberOfObjects() == 0)
  {
    itkExceptionMacro(<< "the mask is empty");
  }
  std::vector<std::string> warnings;
  if (relabel->GetNumberOfObjects() > 1)
  {
    std::ostringstream text;
    text << "the mask holds " << relabel->GetNumberOfObjects() << " disconnected pieces; only the largest ("
         << relabel->GetSizeOfObjectsInPixels()[0] << " of "
         << std::accumulate(relabel->GetSizeOfObjectsInPixels().begin(),
                            relabel->GetSizeOfObjectsInPixels().end(),
                            SizeValueType{ 0 })
         << " voxels) was meshed";
    warnings.push_back(text.str());
  }

  // Read only the bounding box of that sheet, plus two voxels.
  using IndexType = typename MaskImageType::IndexType;
  IndexType lower = region.GetUpperIndex(), upper = region.GetIndex();
  for (ImageRegionConstIteratorWithIndex<LabelImageType> it(labels, region); !it.IsAtEnd(); ++it)
  {
    if (it.Get() == 1)
    {
      const IndexType index = it.GetIndex();
      for (unsigned d = 0; d < 3; ++d)
      {
        lower[d] = std::min(lower[d], index[d]);
        upper[d] = std::max(upper[d], index[d]);
      }
    }
  }
  typename MaskImageType::RegionType box;
  for (unsigned d = 0; d < 3; ++d)
  {
    lower[d] -= 2;
    upper[d] += 2;
  }
  box.SetIndex(lower);
  box.SetUpperIndex(upper);
  box.Crop(region);

  const auto           size = box.GetSize();
  std::vector<uint8_t> maskArray(box.GetNumberOfPixels());
  std::vector<float>   intensityArray(intensity != nullptr ? box.GetNumberOfPixels() : 0);
  size_t               offset = 0;
  for (ImageRegionConstIteratorWithIndex<LabelImageType> it(labels, box); !it.IsAtEnd(); ++it, ++offset)
  {
    maskArray[offset] = it.Get() == 1 ? 1 : 0;
    if (intensity != nullptr)
    {
      intensityArray[offset] = intensity->GetPixel(it.GetIndex());
    }
  }
  SheetVolumeView view;
  view.Mask = maskArray.data();
  view.Intensity = intensity != nullptr ? intensityArray.data() : nullptr;
  for (unsigned d = 0; d < 3; ++d)
  {
    view.Size[d] = size[d];
    view.Spacing[d] = mask->GetSpacing()[d];
  }

  SheetMidSurfaceExtractor  extractor;
  SheetMidSurfaceParameters parameters;
  parameters.Method = m_Method;
  parameters.SpacingAlongSheet = m_SpacingAlongSheet;
  parameters.SpacingAlongAxis = m_SpacingAlongAxis;
  parameters.ChordErrorFraction = m_ChordErrorFraction;
  extractor.SetParameters(parameters);
  extractor.SetProgressCallback([this](double fraction) {
    this->UpdateProgress(static_cast<float>(0.1 + 0.9 * fraction));
    return !this->GetAbortGenerateData();
  });
  SheetMesh sheet = extractor.Extract(view);
  m_Report = extractor.GetReport();
  m_Report.Warnings.insert(m_Report.Warnings.begin(), warnings.begin(), warnings.end());

  // From the box's scaled voxel frame to the physical frame.
  const auto &                      direction = mask->GetDirection();
  typename MaskImageType::PointType origin;
  mask->TransformIndexToPhysicalPoint(box.GetIndex(), origin);
  for (size_t i = 0; i < sheet.GetNumberOfPoints(); ++i)
  {
    double q[3] = { sheet.Points[3 * i], sheet.Points[3 * i + 1], sheet.Points[3 * i + 2] };
    for (unsigned r = 0; r < 3; ++r)
    {
      sheet.Points[3 * i + r] = origin[r] + direction[r][0] * q[0] + direction[r][1] * q[1] + direction[r][2] * q[2];
    }
  }
  if (vnl_determinant(direction.GetVnlMatrix()) < 0.0)
  {
    for (size_t t = 0; t < sheet.GetNumberOfTriangles(); ++t)
    {
      std::swap(sheet.Triangles[3 * t + 1], sheet.Triangles[3 * t + 2]);
    }
  }
  m_SheetMesh = std::move(sheet);

  typename OutputMeshType::Pointer mesh = SheetMeshToMesh<OutputMeshType>(m_SheetMesh);
  OutputMeshType *                 output = this->GetOutput();
  output->SetPoints(mesh->GetPoints());
  output->SetCells(mesh->GetCells());
  output->SetMetaDataDictionary(mesh->GetMetaDataDictionary());
  this->UpdateProgress(1.0f);
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Method: " << ToString(m_Method) << std::endl;
  os << indent << "SpacingAlongSheet: " << m_SpacingAlongSheet << std::endl;
  os << indent << "SpacingAlongAxis: " << m_SpacingAlongAxis << std::endl;
  os << indent << "ChordErrorFraction: " << m_ChordErrorFraction << std::endl;
  os << indent << "SheetMesh: " << m_SheetMesh.GetNumberOfPoints() << " points, " << m_SheetMesh.GetNumberOfTriangles()
     << " triangles" << std::endl;
  os << indent << "Report: method " << ToString(m_Report.Method) << ", spacing " << m_Report.SpacingAlongSheet << " x "
     << m_Report.SpacingAlongAxis << " mm, thickness " << m_Report.SheetThickness << " mm, " << m_Report.Warnings.size()
     << " warning(s)" << std::endl;
}
} // end namespace itk

#endif

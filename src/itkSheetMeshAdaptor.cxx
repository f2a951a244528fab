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
#include "itkSheetMeshAdaptor.h"

#include "itkMesh.h"
#include "itkQuadEdgeMesh.h"

namespace itk {
SheetMesh
DataObjectToSheetMesh(const DataObject * mesh)
{
  if (mesh == nullptr)
  {
    itkGenericExceptionMacro(<< "no mesh given");
  }
  if (const auto * m = dynamic_cast<const Mesh<float, 3> *>(mesh))
  {
    return MeshToSheetMesh(m);
  }
  if (const auto * m = dynamic_cast<const Mesh<double, 3> *>(mesh))
  {
    return MeshToSheetMesh(m);
  }
  if (const auto * m = dynamic_cast<const QuadEdgeMesh<double, 3> *>(mesh))
  {
    return MeshToSheetMesh(m);
  }
  itkGenericExceptionMacro(<< "unsupported mesh type " << mesh->GetNameOfClass()
                           << ": expected itk::Mesh<float, 3>, itk::Mesh<double, 3> or itk::QuadEdgeMesh<double, 3>");
}
} // end namespace itk

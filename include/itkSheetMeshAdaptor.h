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
#ifndef itkSheetMeshAdaptor_h
#define itkSheetMeshAdaptor_h

#include "VirtualUnwrappingExport.h"
#include "itkCellInterface.h"
#include "itkDataObject.h"
#include "itkMacro.h"
#include "itkMetaDataObject.h"
#include "itkSheetMesh.h"
#include "itkTriangleCell.h"

#include <algorithm>

#include <type_traits>

namespace itk {
/** Meta-data keys under which a grid-structured sheet mesh carries its grid. */
constexpr const char * SheetMeshGridIndexKey = "SheetGridIndex";
constexpr const char * SheetMeshGridRowsKey = "SheetGridRows";
constexpr const char * SheetMeshGridColumnsKey = "SheetGridColumns";

namespace detail {
template <typename TMesh, typename = void>
struct IsQuadEdgeMesh : std::false_type
{};
template <typename TMesh>
struct IsQuadEdgeMesh<TMesh, std::void_t<decltype(std::declval<TMesh &>().AddFaceTriangle(0, 0, 0))>> : std::true_type
{};
} // namespace detail

/** Copies the points and triangles of an itk::Mesh or itk::QuadEdgeMesh (3D) into plain
 * arrays, with the sheet grid if the mesh's meta-data carries one. Throws when a cell is
 * not a triangle. */
template <typename TMesh>
SheetMesh
MeshToSheetMesh(const TMesh * mesh)
{
  static_assert(TMesh::PointDimension == 3, "sheet meshes are 3D");
  if (mesh == nullptr)
  {
    itkGenericExceptionMacro(<< "MeshToSheetMesh: no mesh given");
  }
  SheetMesh  sheet;
  const auto numberOfPoints = mesh->GetNumberOfPoints();
  sheet.Points.resize(3 * numberOfPoints);
  // Point identifiers of a mesh need not be contiguous; map them to 0..n-1.
  std::vector<std::pair<typename TMesh::PointIdentifier, uint32_t>> idMap;
  idMap.reserve(numberOfPoints);
  uint32_t next = 0;
  if (mesh->GetPoints() == nullptr || mesh->GetNumberOfPoints() == 0)
  {
    itkGenericExceptionMacro(<< "MeshToSheetMesh: the mesh has no points");
  }
  if (mesh->GetCells() == nullptr || mesh->GetNumberOfCells() == 0)
  {
    itkGenericExceptionMacro(<< "MeshToSheetMesh: the mesh has no triangles");
  }
  for (auto it = mesh->GetPoints()->Begin(); it != mesh->GetPoints()->End(); ++it, ++next)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      sheet.Points[3 * next + d] = it.Value()[d];
    }
    idMap.emplace_back(it.Index(), next);
  }
  const bool contiguous = [&] {
    for (size_t k = 0; k < idMap.size(); ++k)
    {
      if (idMap[k].first != k)
      {
        return false;
      }
    }
    return true;
  }();
  std::sort(idMap.begin(), idMap.end());
  auto lookup = [&](typename TMesh::PointIdentifier id) -> uint32_t {
    if (contiguous)
    {
      return static_cast<uint32_t>(id);
    }
    auto found = std::lower_bound(idMap.begin(), idMap.end(), std::make_pair(id, uint32_t{ 0 }));
    if (found == idMap.end() || found->first != id)
    {
      itkGenericExceptionMacro(<< "MeshToSheetMesh: a cell refers to missing point " << id);
    }
    return found->second;
  };
  sheet.Triangles.reserve(3 * mesh->GetNumberOfCells());
  for (auto it = mesh->GetCells()->Begin(); it != mesh->GetCells()->End(); ++it)
  {
    const auto * cell = it.Value();
    if (cell->GetDimension() == 1 && detail::IsQuadEdgeMesh<TMesh>::value)
    {
      continue; // a QuadEdgeMesh stores its edges as cells too
    }
    if (cell->GetNumberOfPoints() != 3 || cell->GetDimension() != 2)
    {
      itkGenericExceptionMacro(<< "MeshToSheetMesh: cell " << it.Index() << " is not a triangle ("
                               << cell->GetNumberOfPoints() << " points)");
    }
    for (auto p = cell->PointIdsBegin(); p != cell->PointIdsEnd(); ++p)
    {
      sheet.Triangles.push_back(lookup(*p));
    }
  }
  const MetaDataDictionary & dict = mesh->GetMetaDataDictionary();
  std::vector<int32_t>       gridIndex;
  if (ExposeMetaData(dict, SheetMeshGridIndexKey, gridIndex) && gridIndex.size() == 2 * numberOfPoints)
  {
    sheet.GridIndex = std::move(gridIndex);
    ExposeMetaData(dict, SheetMeshGridRowsKey, sheet.GridRows);
    ExposeMetaData(dict, SheetMeshGridColumnsKey, sheet.GridColumns);
  }
  return sheet;
}

/** Fills `mesh` (an itk::Mesh or itk::QuadEdgeMesh, emptied first) with the points and
 * triangles of plain arrays; the sheet grid, if any, goes into its meta-data dictionary.
 * Filters build their output in place with it: a QuadEdgeMesh deletes its cells when it
 * is destroyed, so its containers must not be shared with a temporary mesh. */
template <typename TMesh>
void
SheetMeshIntoMesh(const SheetMesh & sheet, TMesh * mesh)
{
  static_assert(TMesh::PointDimension == 3, "sheet meshes are 3D");
  if (mesh == nullptr)
  {
    itkGenericExceptionMacro(<< "SheetMeshIntoMesh: no mesh given");
  }
  mesh->Initialize();
  mesh->GetPoints()->Reserve(sheet.GetNumberOfPoints());
  for (size_t i = 0; i < sheet.GetNumberOfPoints(); ++i)
  {
    typename TMesh::PointType point;
    for (unsigned d = 0; d < 3; ++d)
    {
      point[d] = static_cast<typename TMesh::CoordRepType>(sheet.Points[3 * i + d]);
    }
    mesh->SetPoint(i, point);
  }
  for (size_t t = 0; t < sheet.GetNumberOfTriangles(); ++t)
  {
    const uint32_t * tri = &sheet.Triangles[3 * t];
    if constexpr (detail::IsQuadEdgeMesh<TMesh>::value)
    {
      mesh->AddFaceTriangle(tri[0], tri[1], tri[2]);
    }
    else
    {
      using CellAutoPointer = typename TMesh::CellAutoPointer;
      using TriangleType = TriangleCell<typename TMesh::CellType>;
      CellAutoPointer cell;
      cell.TakeOwnership(new TriangleType);
      cell->SetPointId(0, tri[0]);
      cell->SetPointId(1, tri[1]);
      cell->SetPointId(2, tri[2]);
      mesh->SetCell(t, cell);
    }
  }
  if (sheet.IsGridStructured())
  {
    MetaDataDictionary & dict = mesh->GetMetaDataDictionary();
    EncapsulateMetaData(dict, SheetMeshGridIndexKey, sheet.GridIndex);
    EncapsulateMetaData(dict, SheetMeshGridRowsKey, sheet.GridRows);
    EncapsulateMetaData(dict, SheetMeshGridColumnsKey, sheet.GridColumns);
  }
}

/** Marks a filter's output mesh as holding all of itself (buffered region = requested
 * region). Without it, itk::PointSet's buffered region stays -1, the pipeline takes the
 * output as outside its requested region, and every later update downstream runs the
 * filter again. Every mesh filter of the module calls it at the end of GenerateData. */
template <typename TMesh>
void
MarkMeshWhole(TMesh * mesh)
{
  mesh->SetBufferedRegion(mesh->GetRequestedRegion());
}

/** Builds an itk::Mesh or itk::QuadEdgeMesh from plain arrays (see SheetMeshIntoMesh). */
template <typename TMesh>
typename TMesh::Pointer
SheetMeshToMesh(const SheetMesh & sheet)
{
  auto mesh = TMesh::New();
  SheetMeshIntoMesh(sheet, mesh.GetPointer());
  return mesh;
}

/** MeshToSheetMesh for the mesh types the module is wrapped for, behind a DataObject (as
 * Python and other type-erased callers hold them): itk::Mesh<float, 3>,
 * itk::Mesh<double, 3> and itk::QuadEdgeMesh<double, 3>. Throws itk::ExceptionObject for
 * a null pointer or another type. */
VirtualUnwrapping_EXPORT SheetMesh
DataObjectToSheetMesh(const DataObject * mesh);

} // end namespace itk

#endif

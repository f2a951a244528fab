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
#ifndef itkSheetMesh_h
#define itkSheetMesh_h

#include "VirtualUnwrappingExport.h"

#include <cstdint>
#include <string>
#include <vector>

namespace itk {
/** \class SheetMesh
 * \brief Plain arrays of a triangle mesh of one sheet: the common currency of the
 * simulation engine, the distortion metrics, the texture sampler and the benchmarks.
 *
 * Points are stored as x, y, z triples (physical units, mm), triangles as three point
 * indices each. When the mesh comes from a grid (rows along the roll axis, columns along
 * the sheet), GridIndex holds (row, column) per point and GridRows / GridColumns the grid
 * size; otherwise GridIndex is empty. Kept free of ITK's mesh headers so that the
 * non-templated numerics compile quickly; itkSheetMeshAdaptor.h converts to and from
 * itk::Mesh and itk::QuadEdgeMesh.
 *
 * \ingroup VirtualUnwrapping
 */
struct VirtualUnwrapping_EXPORT SheetMesh
{
  std::vector<double>   Points;
  std::vector<uint32_t> Triangles;
  std::vector<int32_t>  GridIndex;
  int32_t               GridRows{ 0 };
  int32_t               GridColumns{ 0 };

  size_t
  GetNumberOfPoints() const
  {
    return Points.size() / 3;
  }
  size_t
  GetNumberOfTriangles() const
  {
    return Triangles.size() / 3;
  }
  bool
  IsGridStructured() const
  {
    return !GridIndex.empty() && GridIndex.size() == 2 * GetNumberOfPoints();
  }

  /** Throws itk::ExceptionObject naming the problem when the arrays are inconsistent:
   * sizes not multiples of three, a triangle index out of range, a triangle that repeats
   * a point, a non-finite coordinate, or a grid index outside GridRows x GridColumns. */
  void
  Validate(const std::string & what) const;

  /** Unique undirected edges (i < j), sorted; two entries per edge. */
  std::vector<uint32_t>
  ComputeEdges() const;

  /** Area of each triangle. */
  std::vector<double>
  ComputeTriangleAreas() const;

  /** Unit normal per point (x, y, z triples): the sum of the normals of the triangles
   * around the point weighted by their areas (the unnormalised cross products), then
   * normalised. Orientation follows the triangles' winding (counter-clockwise seen from
   * the normal's side). A point whose weighted sum vanishes (isolated, only degenerate
   * triangles, or opposing triangles that cancel) gets (0, 0, 0). */
  std::vector<double>
  ComputeVertexNormals() const;

  /** A grid mesh laid out on its grid, a first flat guess before any simulation: each row
   * straight along its own arc length, each next row placed beside it by the median step
   * between the two rows (its part along the row's tangent and across it; a skewed grid
   * keeps its shear); MassSpringSheetFlattener restarts a folded sheet from it. Exact for sheets bent
   * about the roll axis only (a cylinder, a spiral of constant width); used to map a
   * texture onto a sheet not yet flattened. Same points and triangles. Throws for meshes
   * without a grid. Rows are numbered downwards instead where that makes the triangles
   * counter-clockwise seen from +z, as MassSpringSheetFlattener lays them. */
  SheetMesh
  ComputeGridLayout() const;
};

/** True when both meshes have the same number of points and identical triangles. */
VirtualUnwrapping_EXPORT bool
HaveSameTopology(const SheetMesh & a, const SheetMesh & b);

} // end namespace itk

#endif

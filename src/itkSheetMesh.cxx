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
#include "itkSheetMesh.h"
#include "vuFlatFrame.h"

#include "itkMacro.h"

#include <algorithm>
#include <cmath>

namespace itk {
void
SheetMesh::Validate(const std::string & what) const
{
  if (Points.size() % 3 != 0)
  {
    itkGenericExceptionMacro(<< what << ": point array size " << Points.size() << " is not a multiple of 3");
  }
  if (Triangles.size() % 3 != 0)
  {
    itkGenericExceptionMacro(<< what << ": triangle array size " << Triangles.size() << " is not a multiple of 3");
  }
  if (Triangles.empty())
  {
    itkGenericExceptionMacro(<< what << ": mesh has no triangles");
  }
  const size_t n = GetNumberOfPoints();
  for (size_t k = 0; k < Points.size(); ++k)
  {
    if (!std::isfinite(Points[k]))
    {
      itkGenericExceptionMacro(<< what << ": point " << k / 3 << " has a non-finite coordinate");
    }
  }
  for (size_t t = 0; t < GetNumberOfTriangles(); ++t)
  {
    const uint32_t a = Triangles[3 * t], b = Triangles[3 * t + 1], c = Triangles[3 * t + 2];
    if (a >= n || b >= n || c >= n)
    {
      itkGenericExceptionMacro(<< what << ": triangle " << t << " refers to a point beyond the " << n << " points");
    }
    if (a == b || b == c || a == c)
    {
      itkGenericExceptionMacro(<< what << ": triangle " << t << " repeats a point");
    }
  }
  if (!GridIndex.empty() && GridIndex.size() != 2 * n)
  {
    itkGenericExceptionMacro(<< what << ": grid index has " << GridIndex.size() / 2 << " entries for " << n
                             << " points");
  }
  // A sheet grid may miss some points (holes), not most of them: a far larger grid is a
  // corrupt index, whose lookup tables would not fit in memory.
  if (!GridIndex.empty() && static_cast<double>(GridRows) * static_cast<double>(GridColumns) > 16.0 * n + 16.0)
  {
    itkGenericExceptionMacro(<< what << ": a grid of " << GridRows << " x " << GridColumns << " for only " << n
                             << " points");
  }
  for (size_t k = 0; k < GridIndex.size() / 2; ++k)
  {
    if (GridIndex[2 * k] < 0 || GridIndex[2 * k] >= GridRows || GridIndex[2 * k + 1] < 0 ||
        GridIndex[2 * k + 1] >= GridColumns)
    {
      itkGenericExceptionMacro(<< what << ": point " << k << " has grid index (" << GridIndex[2 * k] << ", "
                               << GridIndex[2 * k + 1] << ") outside the grid of " << GridRows << " x " << GridColumns);
    }
  }
}

std::vector<uint32_t>
SheetMesh::ComputeEdges() const
{
  std::vector<uint64_t> keys;
  keys.reserve(Triangles.size());
  for (size_t t = 0; t < GetNumberOfTriangles(); ++t)
  {
    for (int e = 0; e < 3; ++e)
    {
      uint64_t a = Triangles[3 * t + e];
      uint64_t b = Triangles[3 * t + (e + 1) % 3];
      if (a > b)
      {
        std::swap(a, b);
      }
      keys.push_back((a << 32) | b);
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<uint32_t> edges(2 * keys.size());
  for (size_t k = 0; k < keys.size(); ++k)
  {
    edges[2 * k] = static_cast<uint32_t>(keys[k] >> 32);
    edges[2 * k + 1] = static_cast<uint32_t>(keys[k] & 0xffffffffu);
  }
  return edges;
}

std::vector<double>
SheetMesh::ComputeTriangleAreas() const
{
  std::vector<double> areas(GetNumberOfTriangles());
  for (size_t t = 0; t < areas.size(); ++t)
  {
    const double * p = &Points[3 * Triangles[3 * t]];
    const double * q = &Points[3 * Triangles[3 * t + 1]];
    const double * r = &Points[3 * Triangles[3 * t + 2]];
    const double   u[3] = { q[0] - p[0], q[1] - p[1], q[2] - p[2] };
    const double   v[3] = { r[0] - p[0], r[1] - p[1], r[2] - p[2] };
    const double   c[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
    areas[t] = 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  return areas;
}

std::vector<double>
SheetMesh::ComputeVertexNormals() const
{
  std::vector<double> normals(Points.size(), 0.0);
  for (size_t t = 0; t < GetNumberOfTriangles(); ++t)
  {
    const uint32_t * tri = &Triangles[3 * t];
    const double *   p = &Points[3 * tri[0]];
    const double *   q = &Points[3 * tri[1]];
    const double *   r = &Points[3 * tri[2]];
    const double     u[3] = { q[0] - p[0], q[1] - p[1], q[2] - p[2] };
    const double     v[3] = { r[0] - p[0], r[1] - p[1], r[2] - p[2] };
    // The cross product's length is twice the area: summing it weights by area.
    const double c[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
    for (int k = 0; k < 3; ++k)
    {
      for (int d = 0; d < 3; ++d)
      {
        normals[3 * tri[k] + d] += c[d];
      }
    }
  }
  for (size_t i = 0; i < GetNumberOfPoints(); ++i)
  {
    double *     n = &normals[3 * i];
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 0.0 && std::isfinite(length))
    {
      n[0] /= length;
      n[1] /= length;
      n[2] /= length;
    }
    else
    {
      n[0] = n[1] = n[2] = 0.0;
    }
  }
  return normals;
}

bool
HaveSameTopology(const SheetMesh & a, const SheetMesh & b)
{
  return a.GetNumberOfPoints() == b.GetNumberOfPoints() && a.Triangles == b.Triangles;
}

SheetMesh
SheetMesh::ComputeGridLayout() const
{
  if (!IsGridStructured() || GridRows < 1 || GridColumns < 1)
  {
    itkGenericExceptionMacro(<< "SheetMesh::ComputeGridLayout: the mesh has no grid");
  }
  SheetMesh layout = *this;
  layout.Points = FlatFrame::DevelopedRows(*this);
  // As the flattener lays a sheet: triangles counter-clockwise seen from +z (the side the
  // 3D triangles' normals face), so a texture over the layout reads as over the flat mesh.
  double signedArea = 0.0;
  for (size_t t = 0; t < layout.GetNumberOfTriangles(); ++t)
  {
    const double * a = &layout.Points[3 * layout.Triangles[3 * t]];
    const double * b = &layout.Points[3 * layout.Triangles[3 * t + 1]];
    const double * c = &layout.Points[3 * layout.Triangles[3 * t + 2]];
    signedArea += (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  }
  if (signedArea < 0.0)
  {
    double top = 0.0;
    for (size_t i = 0; i < layout.GetNumberOfPoints(); ++i)
    {
      top = std::max(top, layout.Points[3 * i + 1]);
    }
    for (size_t i = 0; i < layout.GetNumberOfPoints(); ++i)
    {
      layout.Points[3 * i + 1] = top - layout.Points[3 * i + 1];
    }
  }
  return layout;
}

} // end namespace itk

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
#include "vuMedian.h"

#include "itk_eigen.h"
#include ITK_EIGEN(Dense)

#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
  // Each row straight along its own arc length, each next row placed beside it by the
  // median, over the columns the two rows share, of the 3D step between them split into its
  // part along the row's tangent (a skewed grid's shear) and its part across it.
  const size_t         rows = static_cast<size_t>(GridRows), columns = static_cast<size_t>(GridColumns);
  std::vector<int64_t> at(rows * columns, -1);
  for (size_t i = 0; i < GetNumberOfPoints(); ++i)
  {
    at[static_cast<size_t>(GridIndex[2 * i]) * columns + static_cast<size_t>(GridIndex[2 * i + 1])] =
      static_cast<int64_t>(i);
  }
  using Vec3 = Eigen::Vector3d;
  auto point = [this](int64_t i) { return Vec3(Points[3 * i], Points[3 * i + 1], Points[3 * i + 2]); };
  // Each row's arc length at its columns (NaN where the grid has no point).
  std::vector<double> arc(rows * columns, std::numeric_limits<double>::quiet_NaN());
  for (size_t r = 0; r < rows; ++r)
  {
    double  u = 0.0;
    int64_t previous = -1;
    for (size_t c = 0; c < columns; ++c)
    {
      const int64_t i = at[r * columns + c];
      if (i < 0)
      {
        continue;
      }
      if (previous >= 0)
      {
        u += (point(i) - point(previous)).norm();
      }
      arc[r * columns + c] = u;
      previous = i;
    }
  }
  // Row r's offset along x and its place along y.
  std::vector<double> shift(rows, 0.0), place(rows, 0.0);
  double              lastStep = 0.0;
  std::vector<double> alongShifts, acrossSteps;
  for (size_t r = 0; r + 1 < rows; ++r)
  {
    alongShifts.clear();
    acrossSteps.clear();
    for (size_t c = 0; c < columns; ++c)
    {
      const int64_t here = at[r * columns + c], next = at[(r + 1) * columns + c];
      if (here < 0 || next < 0)
      {
        continue;
      }
      // The row's tangent at the column, from its neighbours in the row.
      const int64_t before = c > 0 ? at[r * columns + c - 1] : -1;
      const int64_t after = c + 1 < columns ? at[r * columns + c + 1] : -1;
      if (before < 0 && after < 0)
      {
        continue;
      }
      const Vec3   tangent = (point(after >= 0 ? after : here) - point(before >= 0 ? before : here)).normalized();
      const Vec3   step = point(next) - point(here);
      const double along = step.dot(tangent);
      alongShifts.push_back(shift[r] + arc[r * columns + c] + along - arc[(r + 1) * columns + c]);
      acrossSteps.push_back(std::sqrt(std::max(0.0, step.squaredNorm() - along * along)));
    }
    if (!alongShifts.empty())
    {
      shift[r + 1] = RollTracing::Median(alongShifts);
      lastStep = RollTracing::Median(acrossSteps);
    }
    else
    {
      shift[r + 1] = shift[r];
    }
    place[r + 1] = place[r] + lastStep;
  }
  SheetMesh layout = *this;
  for (size_t k = 0; k < at.size(); ++k)
  {
    if (at[k] >= 0)
    {
      const size_t i = static_cast<size_t>(at[k]);
      layout.Points[3 * i] = shift[k / columns] + arc[k];
      layout.Points[3 * i + 1] = place[k / columns];
      layout.Points[3 * i + 2] = 0.0;
    }
  }
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

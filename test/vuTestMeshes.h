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
#ifndef vuTestMeshes_h
#define vuTestMeshes_h

#include "itkFlatteningDistortionCalculator.h"
#include "itkSheetMesh.h"

#include <array>
#include <cmath>
#include <functional>
#include <vector>

namespace vu {
/** The triangles of a grid of rows x columns points numbered row by row, two a cell:
 * (a, b, e) and (a, e, d) for the cell whose corners are a, its next column b, its next
 * row d and e, so that the normal is (along a row) x (along a column). */
inline std::vector<uint32_t>
GridTriangles(int rows, int columns)
{
  std::vector<uint32_t> triangles;
  for (int r = 0; r + 1 < rows; ++r)
  {
    for (int c = 0; c + 1 < columns; ++c)
    {
      const uint32_t a = r * columns + c, b = a + 1, d = a + columns, e = d + 1;
      triangles.insert(triangles.end(), { a, b, e, a, e, d });
    }
  }
  return triangles;
}

/** The distortion of flat as the flattening of surface, computed. */
inline itk::FlatteningDistortionCalculator::Pointer
MeasureDistortion(const itk::SheetMesh & surface, const itk::SheetMesh & flat)
{
  auto calculator = itk::FlatteningDistortionCalculator::New();
  calculator->SetSurfaceMesh(surface);
  calculator->SetFlatMesh(flat);
  calculator->Compute();
  return calculator;
}

/** Grid mesh (rows along the axis z, columns along a planar curve given by arc length)
 * with its exact unrolling (arc length, z) in flat. The curve is sampled densely and
 * resampled at equal arc length. */
inline itk::SheetMesh
ExtrudedCurveMesh(const std::function<void(double, double &, double &)> & curve,
                  double                                                  parameterEnd,
                  double                                                  spacing,
                  double                                                  height,
                  itk::SheetMesh *                                        flat)
{
  const int           samples = 200000;
  std::vector<double> s(samples + 1, 0.0), px(samples + 1), py(samples + 1);
  curve(0.0, px[0], py[0]);
  for (int k = 1; k <= samples; ++k)
  {
    curve(parameterEnd * k / samples, px[k], py[k]);
    s[k] = s[k - 1] + std::hypot(px[k] - px[k - 1], py[k] - py[k - 1]);
  }
  const int      columns = static_cast<int>(s.back() / spacing) + 1;
  const int      rows = static_cast<int>(height / spacing) + 1;
  itk::SheetMesh mesh;
  mesh.GridRows = rows;
  mesh.GridColumns = columns;
  if (flat)
  {
    *flat = itk::SheetMesh();
  }
  int k = 0;
  for (int r = 0; r < rows; ++r)
  {
    k = 0;
    for (int c = 0; c < columns; ++c)
    {
      const double target = c * spacing;
      while (k + 1 < samples && s[k + 1] < target)
      {
        ++k;
      }
      const double t = (target - s[k]) / (s[k + 1] - s[k]);
      mesh.Points.insert(mesh.Points.end(),
                         { px[k] + t * (px[k + 1] - px[k]), py[k] + t * (py[k + 1] - py[k]), r * spacing });
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
      if (flat)
      {
        flat->Points.insert(flat->Points.end(), { target, r * spacing, 0.0 });
      }
    }
  }
  mesh.Triangles = GridTriangles(rows, columns);
  if (flat)
  {
    flat->Triangles = mesh.Triangles;
    flat->GridIndex = mesh.GridIndex;
    flat->GridRows = rows;
    flat->GridColumns = columns;
  }
  return mesh;
}

/** Archimedean spiral roll: inner radius r0, gap between turns (centre to centre) pitch. */
inline itk::SheetMesh
SpiralRollMesh(double innerRadius, double pitch, double turns, double spacing, double height, itk::SheetMesh * flat)
{
  const double twoPi = 2.0 * 3.14159265358979323846;
  return ExtrudedCurveMesh(
    [=](double theta, double & x, double & y) {
      const double r = innerRadius + pitch * theta / twoPi;
      x = r * std::cos(theta);
      y = r * std::sin(theta);
    },
    turns * twoPi,
    spacing,
    height,
    flat);
}

/** A rows x columns grid mesh, point (row r, column c) at point(r, c), two triangles a cell. */
inline itk::SheetMesh
GridMesh(int rows, int columns, const std::function<std::array<double, 3>(int, int)> & point)
{
  itk::SheetMesh mesh;
  mesh.GridRows = rows;
  mesh.GridColumns = columns;
  for (int r = 0; r < rows; ++r)
  {
    for (int c = 0; c < columns; ++c)
    {
      const std::array<double, 3> p = point(r, c);
      mesh.Points.insert(mesh.Points.end(), p.begin(), p.end());
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
    }
  }
  mesh.Triangles = GridTriangles(rows, columns);
  return mesh;
}

/** An n x n grid mesh, point (row r, column c) at point(r, c), two triangles a cell. */
inline itk::SheetMesh
SquareGridMesh(int n, const std::function<std::array<double, 3>(int, int)> & point)
{
  return GridMesh(n, n, point);
}

/** A spherical cap (non-developable) of radius R and opening half-angle alpha, as a grid. */
inline itk::SheetMesh
DomeMesh(double radius, double halfAngle, int n)
{
  return SquareGridMesh(n, [=](int r, int c) {
    const double u = (2.0 * c / (n - 1) - 1.0) * halfAngle, v = (2.0 * r / (n - 1) - 1.0) * halfAngle;
    return std::array<double, 3>{ radius * std::sin(u) * std::cos(v),
                                  radius * std::sin(v),
                                  radius * std::cos(u) * std::cos(v) };
  });
}
} // namespace vu

#endif

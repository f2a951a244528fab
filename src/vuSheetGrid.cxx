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
#include "vuSheetGrid.h"

#include <algorithm>
#include <cmath>

namespace itk {
namespace SheetTracing {
namespace {
// Weighted median of values (pairs of value and weight; reordered).
double
WeightedMedian(std::vector<std::pair<double, double>> & values)
{
  std::sort(values.begin(), values.end());
  double total = 0.0;
  for (const auto & v : values)
  {
    total += v.second;
  }
  double running = 0.0;
  for (const auto & v : values)
  {
    running += v.second;
    if (running >= 0.5 * total)
    {
      return v.first;
    }
  }
  return values.back().first;
}

// Point of column c of a grid row from the slices of its window (slice, weight): the
// weighted mean of the slices' points within `agreement` of their weighted median point
// (the median alone where none is).
void
RobustRowPoint(const std::vector<std::pair<long, double>> & window,
               const std::vector<Polyline> &                columnsOf,
               size_t                                       c,
               double                                       agreement,
               double                                       point[2])
{
  std::vector<std::pair<double, double>> values;
  values.reserve(window.size());
  double median[2];
  for (int axis = 0; axis < 2; ++axis)
  {
    values.clear();
    for (const auto & [k, weight] : window)
    {
      values.emplace_back(columnsOf[static_cast<size_t>(k)][2 * c + static_cast<size_t>(axis)], weight);
    }
    median[axis] = WeightedMedian(values);
  }
  double sum[2] = { 0.0, 0.0 }, weightSum = 0.0;
  for (const auto & [k, weight] : window)
  {
    const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
    if (std::hypot(p[0] - median[0], p[1] - median[1]) <= agreement)
    {
      sum[0] += weight * p[0];
      sum[1] += weight * p[1];
      weightSum += weight;
    }
  }
  point[0] = weightSum > 0.0 ? sum[0] / weightSum : median[0];
  point[1] = weightSum > 0.0 ? sum[1] / weightSum : median[1];
}
} // namespace

SheetMesh
BuildSheetGrid(const std::vector<Polyline> & columnsOf,
               long                          firstGood,
               long                          lastGood,
               double                        sz,
               double                        below,
               size_t                        rows,
               double                        rowSpacing,
               size_t                        columns,
               double                        agreement)
{
  const double kernel = std::max(rowSpacing, sz);
  SheetMesh    mesh;
  mesh.GridRows = static_cast<int32_t>(rows);
  mesh.GridColumns = static_cast<int32_t>(columns);
  mesh.Points.resize(3 * rows * columns);
  mesh.GridIndex.resize(2 * rows * columns);
  for (size_t r = 0; r < rows; ++r)
  {
    const double z = static_cast<double>(firstGood) * sz - below + static_cast<double>(r) * rowSpacing;
    const double zc = std::clamp(z, static_cast<double>(firstGood) * sz, static_cast<double>(lastGood) * sz);
    std::vector<std::pair<long, double>> window;
    for (long k = firstGood; k <= lastGood; ++k)
    {
      const double weight = 1.0 - std::abs(static_cast<double>(k) * sz - zc) / kernel;
      if (weight > 0.0)
      {
        window.emplace_back(k, weight);
      }
    }
    for (size_t c = 0; c < columns; ++c)
    {
      const size_t p = r * columns + c;
      double       point[2];
      RobustRowPoint(window, columnsOf, c, agreement, point);
      mesh.Points[3 * p] = point[0];
      mesh.Points[3 * p + 1] = point[1];
      mesh.Points[3 * p + 2] = z;
      mesh.GridIndex[2 * p] = static_cast<int32_t>(r);
      mesh.GridIndex[2 * p + 1] = static_cast<int32_t>(c);
    }
  }
  // Triangles with normals dP/dw x dP/ds.
  mesh.Triangles.reserve(6 * (rows - 1) * (columns - 1));
  for (size_t r = 0; r + 1 < rows; ++r)
  {
    for (size_t c = 0; c + 1 < columns; ++c)
    {
      const auto a = static_cast<uint32_t>(r * columns + c);
      const auto b = a + 1;
      const auto d = static_cast<uint32_t>(a + columns);
      const auto e = d + 1;
      mesh.Triangles.insert(mesh.Triangles.end(), { a, d, b, b, d, e });
    }
  }
  return mesh;
}

void
AlongTheTurn(const double p0[2], const double c0[2], const double p1[2], const double c1[2], double t, double out[2])
{
  const double x0 = p0[0] - c0[0], y0 = p0[1] - c0[1], x1 = p1[0] - c1[0], y1 = p1[1] - c1[1];
  const double turn = std::atan2(x0 * y1 - y0 * x1, x0 * x1 + y0 * y1);
  const double angle = std::atan2(y0, x0) + t * turn;
  const double radius = std::max(0.0, (1.0 - t) * std::hypot(x0, y0) + t * std::hypot(x1, y1));
  out[0] = (1.0 - t) * c0[0] + t * c1[0] + radius * std::cos(angle);
  out[1] = (1.0 - t) * c0[1] + t * c1[1] + radius * std::sin(angle);
}

void
ExtrapolateEdgeRows(SheetMesh &  mesh,
                    double       zFirst,
                    double       zLast,
                    const double axisCentre[2],
                    const double axisSlope[2],
                    double       largestShift)
{
  const auto rows = static_cast<long>(mesh.GridRows);
  const auto columns = static_cast<size_t>(mesh.GridColumns);
  auto       point = [&](long r, size_t c) { return &mesh.Points[3 * (static_cast<size_t>(r) * columns + c)]; };
  auto       rowZ = [&](long r) { return point(r, 0)[2]; };
  long       inFirst = -1, inLast = -1;
  for (long r = 0; r < rows; ++r)
  {
    if (rowZ(r) >= zFirst && rowZ(r) <= zLast)
    {
      inFirst = inFirst < 0 ? r : inFirst;
      inLast = r;
    }
  }
  // Column c at height z on the trend through rows a and b.
  auto predict = [&](long a, long b, size_t c, double z, double out[2]) {
    auto centre = [&](long r, double xy[2]) {
      xy[0] = axisCentre[0] + axisSlope[0] * rowZ(r);
      xy[1] = axisCentre[1] + axisSlope[1] * rowZ(r);
    };
    double ca[2], cb[2];
    centre(a, ca);
    centre(b, cb);
    AlongTheTurn(point(b, c), cb, point(a, c), ca, 1.0 + (z - rowZ(a)) / (rowZ(a) - rowZ(b)), out);
  };
  // The row inside the traced range, beyond `from` in `direction`, at least `distance`
  // from it (so that a trend is not amplified), or the last one there is.
  auto beyond = [&](long from, double distance, long direction) {
    long r = from + direction;
    while (r + direction >= inFirst && r + direction <= inLast && std::abs(rowZ(r) - rowZ(from)) < distance)
    {
      r += direction;
    }
    return r;
  };
  auto extrapolate = [&](long edge, long near, long direction) {
    const double distance = std::abs(rowZ(edge) - rowZ(near));
    const long   far = beyond(near, distance, direction), farther = beyond(far, distance, direction);
    if (far == farther || far < inFirst || far > inLast || farther < inFirst || farther > inLast)
    {
      return;
    }
    // Kept only where the trend would have foretold the near row from the two beyond it
    // better than the far row's curve does (a radius that swings along the axis has turned).
    std::vector<double> trendMiss(columns), curveMiss(columns);
    for (size_t c = 0; c < columns; ++c)
    {
      double foretold[2];
      predict(far, farther, c, rowZ(near), foretold);
      trendMiss[c] = std::hypot(foretold[0] - point(near, c)[0], foretold[1] - point(near, c)[1]);
      curveMiss[c] = std::hypot(point(far, c)[0] - point(near, c)[0], point(far, c)[1] - point(near, c)[1]);
    }
    std::nth_element(trendMiss.begin(), trendMiss.begin() + columns / 2, trendMiss.end());
    std::nth_element(curveMiss.begin(), curveMiss.begin() + columns / 2, curveMiss.end());
    if (trendMiss[columns / 2] >= curveMiss[columns / 2])
    {
      return;
    }
    for (size_t c = 0; c < columns; ++c)
    {
      double * e = point(edge, c);
      double   target[2];
      predict(near, far, c, e[2], target);
      const double shift = std::hypot(target[0] - e[0], target[1] - e[1]);
      const double keep = shift > largestShift ? largestShift / shift : 1.0;
      e[0] += keep * (target[0] - e[0]);
      e[1] += keep * (target[1] - e[1]);
    }
  };
  if (inFirst < 0 || inLast <= inFirst)
  {
    return;
  }
  for (long r = 0; r < inFirst; ++r)
  {
    extrapolate(r, inFirst, +1);
  }
  for (long r = inLast + 1; r < rows; ++r)
  {
    extrapolate(r, inLast, -1);
  }
}

void
OrientNormalsToAxis(SheetMesh & mesh, const double axisCentre[2], const double axisSlope[2])
{
  // Make the normals point to the roll axis (the inside face).
  double agreement = 0.0;
  for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
  {
    const double * p[3];
    for (int v = 0; v < 3; ++v)
    {
      p[v] = &mesh.Points[3 * mesh.Triangles[3 * t + v]];
    }
    const double u[3] = { p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2] };
    const double v[3] = { p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2] };
    const double normal[2] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2] };
    const double toAxis[2] = { axisCentre[0] + axisSlope[0] * p[0][2] - p[0][0],
                               axisCentre[1] + axisSlope[1] * p[0][2] - p[0][1] };
    agreement += normal[0] * toAxis[0] + normal[1] * toAxis[1];
  }
  if (agreement < 0.0)
  {
    for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
    {
      std::swap(mesh.Triangles[3 * t + 1], mesh.Triangles[3 * t + 2]);
    }
  }
}
} // namespace SheetTracing
} // end namespace itk

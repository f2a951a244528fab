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
#include "itkSheetMidSurfaceExtractor.h"
#include "vuMedian.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace itk {
namespace {
// Columns at either end of a row left out of the check along the sheet.
constexpr size_t EndColumns = 6;

// Residual of each value against the median of the values within `half` of it.
std::vector<double>
Residuals(const std::vector<double> & values, long half)
{
  std::vector<double> residual = RollTracing::RunningMedian(values, half);
  for (size_t i = 0; i < values.size(); ++i)
  {
    residual[i] = values[i] - residual[i];
  }
  return residual;
}

// Runs of consecutive entries above the limit, each reported once at its largest entry.
template <typename Report>
void
ReportRuns(const std::vector<double> & residual, double limit, Report report)
{
  for (size_t i = 0; i < residual.size(); ++i)
  {
    if (std::abs(residual[i]) <= limit)
    {
      continue;
    }
    size_t best = i;
    while (i + 1 < residual.size() && std::abs(residual[i + 1]) > limit)
    {
      ++i;
      best = std::abs(residual[i]) > std::abs(residual[best]) ? i : best;
    }
    report(best, std::abs(residual[best]));
  }
}

// The cubic (Lagrange, in the index) through the points at the four indices `x` of a line of
// grid points `stride` values apart from `first` (a row: 3; a column: 3 x columns), at index c.
void
LineCubic(const double * first, long stride, const std::array<long, 4> & x, long c, double out[3])
{
  out[0] = out[1] = out[2] = 0.0;
  for (int i = 0; i < 4; ++i)
  {
    double weight = 1.0;
    for (int j = 0; j < 4; ++j)
    {
      weight *= j == i ? 1.0 : static_cast<double>(c - x[j]) / static_cast<double>(x[i] - x[j]);
    }
    for (int d = 0; d < 3; ++d)
    {
      out[d] += weight * first[stride * x[i] + d];
    }
  }
}

// The cubic through the points of `row` at the four columns `x`, at column c.
void
RowCubic(const double * row, const std::array<long, 4> & x, long c, double out[3])
{
  LineCubic(row, 3, x, c, out);
}

// Distance in the slice plane from grid point p to q.
double
InPlane(const double * p, const double q[3])
{
  return std::hypot(p[0] - q[0], p[1] - q[1]);
}

// Distance in the slice plane from p to the row's polyline, leaving out the segments within
// four columns of column c (the row's own stretch about it): the nearest other turn.
double
DistanceToRow(const double * row, long columns, long c, const double p[3])
{
  double nearest = std::numeric_limits<double>::infinity();
  for (long k = 0; k + 1 < columns; ++k)
  {
    if (k + 1 >= c - 4 && k <= c + 4)
    {
      continue;
    }
    const double * a = row + 3 * k;
    const double * b = a + 3;
    const double   ex = b[0] - a[0], ey = b[1] - a[1], length2 = ex * ex + ey * ey;
    const double   t = length2 > 0.0 ? std::clamp(((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / length2, 0.0, 1.0) : 0.0;
    nearest = std::min(nearest, std::hypot(p[0] - a[0] - t * ex, p[1] - a[1] - t * ey));
  }
  return nearest;
}

// A grid's rows and columns, or 0 columns when the mesh is not a whole grid.
std::pair<size_t, long>
GridShape(const SheetMesh & mesh)
{
  const auto rows = static_cast<size_t>(std::max(0, mesh.GridRows));
  const auto columns = static_cast<long>(std::max(0, mesh.GridColumns));
  if (!mesh.IsGridStructured() || rows * static_cast<size_t>(columns) != mesh.GetNumberOfPoints())
  {
    return { 0, 0 };
  }
  return { rows, columns };
}
} // namespace

std::vector<SheetMidSurfaceReport::GridStep>
SheetMidSurfaceExtractor::FindGridSteps(const SheetMesh & mesh, double limit)
{
  std::vector<SheetMidSurfaceReport::GridStep> steps;
  const auto                                   shape = GridShape(mesh);
  const size_t                                 rows = shape.first, columns = static_cast<size_t>(shape.second);
  if (columns < 3 || !(limit > 0.0))
  {
    return steps;
  }
  auto at = [&](size_t r, size_t c, int d) { return mesh.Points[3 * (r * columns + c) + static_cast<size_t>(d)]; };
  // In-plane vectors against the median of their neighbours, component by component; the
  // length of the difference. (No normal is needed: a step tilts the curve's own tangent.)
  auto residualLengths = [](const std::vector<double> & x, const std::vector<double> & y, long half) {
    const std::vector<double> rx = Residuals(x, half), ry = Residuals(y, half);
    std::vector<double>       length(rx.size());
    for (size_t i = 0; i < rx.size(); ++i)
    {
      length[i] = std::hypot(rx[i], ry[i]);
    }
    return length;
  };
  // Along the sheet: the second difference of each row's curve.
  std::vector<double> bendX(columns - 2), bendY(columns - 2);
  for (size_t r = 0; r < rows; ++r)
  {
    for (size_t c = 1; c + 1 < columns; ++c)
    {
      bendX[c - 1] = at(r, c - 1, 0) - 2.0 * at(r, c, 0) + at(r, c + 1, 0);
      bendY[c - 1] = at(r, c - 1, 1) - 2.0 * at(r, c, 1) + at(r, c + 1, 1);
    }
    ReportRuns(residualLengths(bendX, bendY, 3), limit, [&](size_t i, double step) {
      // The last few columns at either end follow the trace's end, which bends and
      // jitters more than the rest of a correct mesh.
      if (i + 1 >= EndColumns && i + 1 + EndColumns < columns)
      {
        steps.push_back({ r, i + 1, false, step });
      }
    });
  }
  // Along the axis: the in-plane step between neighbouring rows.
  if (rows >= 3)
  {
    std::vector<double> shiftX(rows - 1), shiftY(rows - 1);
    for (size_t c = 0; c < columns; ++c)
    {
      for (size_t r = 0; r + 1 < rows; ++r)
      {
        shiftX[r] = at(r + 1, c, 0) - at(r, c, 0);
        shiftY[r] = at(r + 1, c, 1) - at(r, c, 1);
      }
      ReportRuns(residualLengths(shiftX, shiftY, 2), limit, [&](size_t i, double step) {
        steps.push_back({ i, c, true, step });
      });
    }
  }
  std::sort(steps.begin(), steps.end(), [](const auto & a, const auto & b) {
    return a.Row != b.Row ? a.Row < b.Row : a.Column < b.Column;
  });
  return steps;
}

size_t
SheetMidSurfaceExtractor::SmoothRowSpikes(SheetMesh & mesh, double limit)
{
  const auto [rows, columns] = GridShape(mesh);
  if (columns < 9 || !(limit > 0.0))
  {
    return 0;
  }
  // The cubic through columns a - 2, a - 1, b + 1 and b + 2 of a row, at column c.
  auto cubic = [](const double * row, long a, long b, long c, double out[3]) {
    RowCubic(row, { a - 2, a - 1, b + 1, b + 2 }, c, out);
  };
  size_t moved = 0;
  for (size_t r = 0; r < rows; ++r)
  {
    double * row = mesh.Points.data() + 3 * r * static_cast<size_t>(columns);
    for (long width = 1; width <= 2; ++width)
    {
      for (long a = 3; a + width + 2 < columns; ++a)
      {
        const long b = a + width - 1;
        double     fitted[2][3];
        bool       off = true;
        for (long c = a; c <= b && off; ++c)
        {
          cubic(row, a, b, c, fitted[c - a]);
          off = InPlane(row + 3 * c, fitted[c - a]) > limit;
        }
        double before[3], after[3];
        if (!off)
        {
          continue;
        }
        cubic(row, a - 1, b, a - 1, before);
        cubic(row, a, b + 1, b + 1, after);
        if (InPlane(row + 3 * (a - 1), before) > 0.5 * limit || InPlane(row + 3 * (b + 1), after) > 0.5 * limit)
        {
          continue;
        }
        for (long c = a; c <= b; ++c)
        {
          std::copy(fitted[c - a], fitted[c - a] + 3, row + 3 * c);
          ++moved;
        }
      }
    }
  }
  return moved;
}

size_t
SheetMidSurfaceExtractor::SmoothColumnSpikes(SheetMesh & mesh, double limit)
{
  const auto [rows, columns] = GridShape(mesh);
  const auto count = static_cast<long>(rows);
  if (columns < 1 || count < 6 || !(limit > 0.0))
  {
    return 0;
  }
  const long stride = 3 * columns;
  size_t     moved = 0;
  for (long c = 0; c < columns; ++c)
  {
    double * column = mesh.Points.data() + 3 * c;
    // How far the point at row r lies off the cubic through `x`.
    auto off = [&](const std::array<long, 4> & x, long r, double fitted[3]) {
      LineCubic(column, stride, x, r, fitted);
      return InPlane(column + stride * r, fitted);
    };
    for (long r = 2; r + 2 < count; ++r)
    {
      double fitted[3], check[3];
      if (!(off({ r - 2, r - 1, r + 1, r + 2 }, r, fitted) > limit))
      {
        continue;
      }
      // Rows r - 1 and r + 1 each lie on the cubic through their own neighbours, row r left
      // out (three rows on the side away from r where the grid ends within two).
      const bool belowFits = off(r >= 3 ? std::array<long, 4>{ r - 3, r - 2, r + 1, r + 2 }
                                        : std::array<long, 4>{ r - 2, r + 1, r + 2, r + 3 },
                                 r - 1,
                                 check) <= 0.5 * limit;
      const bool aboveFits = off(r + 3 < count ? std::array<long, 4>{ r - 2, r - 1, r + 2, r + 3 }
                                               : std::array<long, 4>{ r - 3, r - 2, r - 1, r + 2 },
                                 r + 1,
                                 check) <= 0.5 * limit;
      if (belowFits && aboveFits)
      {
        std::copy(fitted, fitted + 3, column + stride * r);
        ++moved;
      }
    }
  }
  return moved;
}

size_t
SheetMidSurfaceExtractor::SmoothTouchBumps(SheetMesh & mesh, double limit)
{
  const auto [rows, columns] = GridShape(mesh);
  if (columns < 11 || !(limit > 0.0))
  {
    return 0;
  }
  size_t moved = 0;
  for (size_t r = 0; r < rows; ++r)
  {
    double * row = mesh.Points.data() + 3 * r * static_cast<size_t>(columns);
    for (long c = 4; c + 4 < columns; ++c)
    {
      // Columns c - 1 .. c + 1 against the cubic through the two columns either side of them.
      double fitted[3][3];
      double off[3];
      for (long k = 0; k < 3; ++k)
      {
        RowCubic(row, { c - 3, c - 2, c + 2, c + 3 }, c - 1 + k, fitted[k]);
        off[k] = InPlane(row + 3 * (c - 1 + k), fitted[k]);
      }
      // A peak at c beyond the limit and at least twice as far off as its sides (a smooth
      // bend, such as the innermost curl, leaves the cubic by at most 1.5 times as much at c
      // as at its sides).
      if (!(off[1] > limit) || off[0] > 0.5 * off[1] || off[2] > 0.5 * off[1])
      {
        continue;
      }
      // The columns either side lie on one smooth curve without the bump.
      double before[3], after[3];
      RowCubic(row, { c - 4, c - 3, c + 2, c + 3 }, c - 2, before);
      RowCubic(row, { c - 3, c - 2, c + 3, c + 4 }, c + 2, after);
      if (InPlane(row + 3 * (c - 2), before) > 0.5 * limit || InPlane(row + 3 * (c + 2), after) > 0.5 * limit)
      {
        continue;
      }
      // The bump leans towards the row's nearest other turn, by at least a quarter of the
      // way: a smaller peak is the trace following the sheet's own unevenness, or noise,
      // and stays.
      const double away = DistanceToRow(row, columns, c, fitted[1]);
      if (!(DistanceToRow(row, columns, c, row + 3 * c) < 0.75 * away))
      {
        continue;
      }
      for (long k = 0; k < 3; ++k)
      {
        std::copy(fitted[k], fitted[k] + 3, row + 3 * (c - 1 + k));
      }
      moved += 3;
    }
  }
  return moved;
}

std::vector<SheetMidSurfaceReport::OffSheetRun>
SheetMidSurfaceExtractor::FindOffSheetRuns(const SheetMesh &       mesh,
                                           const SheetVolumeView & volume,
                                           double                  airLevel,
                                           double                  sheetLevel,
                                           double                  level,
                                           size_t                  minimumRun)
{
  std::vector<SheetMidSurfaceReport::OffSheetRun> runs;
  const auto                                      shape = GridShape(mesh);
  const size_t                                    rows = shape.first, columns = static_cast<size_t>(shape.second);
  const long nx = static_cast<long>(volume.Size[0]), ny = static_cast<long>(volume.Size[1]),
             nz = static_cast<long>(volume.Size[2]);
  if (volume.Intensity == nullptr || rows < 3 || columns < 2 * EndColumns + minimumRun || !(sheetLevel > airLevel) ||
      nx < 4 || ny < 4 || nz < 4)
  {
    return runs;
  }
  // The level at point p (view frame, mm) as a fraction of the contrast; NaN where it is
  // not checked: within a voxel of the volume's border, or next to a voxel without data.
  auto levelAt = [&](const double * p) {
    const double u = p[0] / volume.Spacing[0], v = p[1] / volume.Spacing[1], w = p[2] / volume.Spacing[2];
    if (!(u >= 1.0 && v >= 1.0 && w >= 1.0 && u < static_cast<double>(nx - 2) && v < static_cast<double>(ny - 2) &&
          w < static_cast<double>(nz - 2)))
    {
      return std::numeric_limits<double>::quiet_NaN();
    }
    const auto   i = static_cast<long>(u), j = static_cast<long>(v), k = static_cast<long>(w);
    const double a = u - static_cast<double>(i), b = v - static_cast<double>(j), c = w - static_cast<double>(k);
    double       value = 0.0;
    for (long dk = 0; dk < 2; ++dk)
    {
      for (long dj = 0; dj < 2; ++dj)
      {
        for (long di = 0; di < 2; ++di)
        {
          const auto index = static_cast<size_t>(((k + dk) * ny + (j + dj)) * nx + (i + di));
          if (volume.Data != nullptr && volume.Data[index] == 0)
          {
            return std::numeric_limits<double>::quiet_NaN();
          }
          value += (di ? a : 1.0 - a) * (dj ? b : 1.0 - b) * (dk ? c : 1.0 - c) * volume.Intensity[index];
        }
      }
    }
    return (value - airLevel) / (sheetLevel - airLevel);
  };
  for (size_t r = 1; r + 1 < rows; ++r)
  {
    size_t first = 0, count = 0;
    double lowest = 0.0;
    for (size_t c = EndColumns; c + EndColumns <= columns; ++c)
    {
      const double value = c + EndColumns < columns ? levelAt(&mesh.Points[3 * (r * columns + c)])
                                                    : std::numeric_limits<double>::quiet_NaN();
      if (value < level)
      {
        first = count == 0 ? c : first;
        lowest = count == 0 ? value : std::min(lowest, value);
        ++count;
        continue;
      }
      if (count >= minimumRun)
      {
        runs.push_back({ r, first, first + count - 1, lowest });
      }
      count = 0;
    }
  }
  return runs;
}
} // namespace itk

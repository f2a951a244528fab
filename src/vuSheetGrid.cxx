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

#include "itkMath.h"
#include "vuMedian.h"

#include <algorithm>
#include <cmath>
#include <optional>

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

// A column's radius and angle about a roll's axis along the slices of an edge row's
// window: their trends, taken at the row or the nearest agreeing slice (RollEdgeRowFit).
struct RollColumnTrend
{
  double Radius;      // at the row, or the nearest agreeing slice past them
  double Angle;       // likewise
  double RadiusSlope; // per slice
};

// Column c of an edge row (one whose window the traced slices cut) about a roll's axis
// (centre(k) in slice k): the radius and the angle fitted along the window's slices,
// robustly (Theil and Sen: the weighted median of the slopes between every two slices,
// then the weighted median offset), taken at slice `at` or, past the slices that agree
// with both trends within `agreement` (across the sheet: the radius; along it: the angle
// times the radius), at the nearest of them. A column drifts along the sheet from slice to
// slice (a skewed roll's columns are not square to the axis, by a voxel a slice and more):
// a straight line in x and y carries the row off the turn along its chord, and agreement
// measured in the plane leaves all but two or three slices out for the drift alone. Where
// the traces' ends slide along the sheet at its edge, their drift is no trend: carried past
// them it moves the row onto the neighbouring turn. None where no slice agrees.
std::optional<RollColumnTrend>
RollEdgeRowFit(const std::vector<std::pair<long, double>> & window,
               const std::vector<Polyline> &                columnsOf,
               size_t                                       c,
               double                                       agreement,
               double                                       at,
               const RollAxisLine &                         axis,
               double                                       sz)
{
  auto centre = [&](double slice, double xy[2]) {
    for (int d = 0; d < 2; ++d)
    {
      xy[d] = axis.Centre[d] + axis.Slope[d] * slice * sz;
    }
  };
  struct Sample
  {
    double Slice, Weight, Radius, Angle;
  };
  std::vector<Sample> samples;
  samples.reserve(window.size());
  double reference = 0.0;
  for (const auto & [k, weight] : window)
  {
    const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
    double         o[2];
    centre(static_cast<double>(k), o);
    const double x = p[0] - o[0], y = p[1] - o[1];
    double       angle = std::atan2(y, x);
    if (samples.empty())
    {
      reference = angle;
    }
    // Unwrapped about the first slice's angle.
    angle = reference + std::remainder(angle - reference, 2.0 * itk::Math::pi);
    samples.push_back({ static_cast<double>(k), weight, std::hypot(x, y), angle });
  }
  if (samples.empty())
  {
    return std::nullopt;
  }
  // The trends of the radius and of the angle along the slices, robustly: the weighted
  // median of the slopes between every two slices (Theil and Sen), and the weighted median
  // offset from it. A slice agrees when it lies within `agreement` of both, across the
  // sheet (radius) and along it (angle times radius): a slice on the neighbouring turn, or
  // whose column slid along the turn unlike the others' (the traces' ends at the sheet's
  // edge), is left out.
  std::vector<std::pair<double, double>> values;
  auto                                   trend = [&](auto value, double & slope, double & offset) {
    values.clear();
    for (size_t i = 0; i < samples.size(); ++i)
    {
      for (size_t j = i + 1; j < samples.size(); ++j)
      {
        values.emplace_back((value(samples[j]) - value(samples[i])) / (samples[j].Slice - samples[i].Slice),
                            samples[i].Weight * samples[j].Weight);
      }
    }
    slope = values.empty() ? 0.0 : WeightedMedian(values);
    values.clear();
    for (const auto & sample : samples)
    {
      values.emplace_back(value(sample) - slope * sample.Slice, sample.Weight);
    }
    offset = WeightedMedian(values);
  };
  double radiusTrend[2], angleTrend[2];
  trend([](const Sample & sample) { return sample.Radius; }, radiusTrend[0], radiusTrend[1]);
  trend([](const Sample & sample) { return sample.Angle; }, angleTrend[0], angleTrend[1]);
  auto agrees = [&](const Sample & sample) {
    const double radius = radiusTrend[1] + radiusTrend[0] * sample.Slice;
    return std::abs(sample.Radius - radius) <= agreement &&
           std::abs(sample.Angle - angleTrend[1] - angleTrend[0] * sample.Slice) * std::max(radius, 0.0) <= agreement;
  };
  // The trends, taken at `at` inside the agreeing slices and at the nearest of them past
  // them: the sheet runs along the axis, and a trend carried past the traces (whose ends
  // slide at the sheet's edge) only moves the row off the sheet.
  bool   any = false;
  double nearest = 0.0, farthest = 0.0;
  for (const auto & sample : samples)
  {
    if (agrees(sample))
    {
      nearest = any ? std::min(nearest, sample.Slice) : sample.Slice;
      farthest = any ? std::max(farthest, sample.Slice) : sample.Slice;
      any = true;
    }
  }
  if (!any)
  {
    return std::nullopt;
  }
  const double to = std::clamp(at, nearest, farthest);
  return RollColumnTrend{ radiusTrend[1] + radiusTrend[0] * to, angleTrend[1] + angleTrend[0] * to, radiusTrend[0] };
}

// Point of column c of a grid row from the slices of its window (slice, weight): the
// weighted mean of the slices' points within `agreement` of their weighted median point
// (the median alone where none is); returns the share of the window's weight that agrees.
// With `at` (a slice coordinate, for a row whose window the traced range cuts), a weighted
// straight-line fit along those slices taken at `at` instead: the mean lies inside the
// window, and a sheet that moves along the axis (a taper, a skew) would leave the edge row
// behind it. Inner rows keep the mean: where the agreement leaves out one side of a
// symmetric window (a touch's edge along the axis), a line through the other side would
// carry the row off along that side's slope.
double
RobustRowPoint(const std::vector<std::pair<long, double>> & window,
               const std::vector<Polyline> &                columnsOf,
               size_t                                       c,
               double                                       agreement,
               std::optional<double>                        at,
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
  auto agrees = [&](long k) {
    const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
    return std::hypot(p[0] - median[0], p[1] - median[1]) <= agreement;
  };
  double sum[2] = { 0.0, 0.0 }, weightSum = 0.0, sliceSum = 0.0, windowWeight = 0.0;
  for (const auto & [k, weight] : window)
  {
    windowWeight += weight;
    if (agrees(k))
    {
      const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
      sum[0] += weight * p[0];
      sum[1] += weight * p[1];
      sliceSum += weight * static_cast<double>(k);
      weightSum += weight;
    }
  }
  if (!(weightSum > 0.0))
  {
    point[0] = median[0];
    point[1] = median[1];
    return 0.0;
  }
  point[0] = sum[0] / weightSum;
  point[1] = sum[1] / weightSum;
  const double share = weightSum / windowWeight;
  if (!at)
  {
    return share;
  }
  const double meanSlice = sliceSum / weightSum;
  double       spread = 0.0, covariance[2] = { 0.0, 0.0 };
  for (const auto & [k, weight] : window)
  {
    if (agrees(k))
    {
      const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
      const double   dk = static_cast<double>(k) - meanSlice;
      spread += weight * dk * dk;
      covariance[0] += weight * dk * (p[0] - point[0]);
      covariance[1] += weight * dk * (p[1] - point[1]);
    }
  }
  if (spread > 1e-9 * weightSum)
  {
    point[0] += covariance[0] / spread * (*at - meanSlice);
    point[1] += covariance[1] / spread * (*at - meanSlice);
  }
  return share;
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
               double                        agreement,
               const RollAxisLine *          rollAxis)
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
    // A window the traced range cuts (the rows at the sheet's edges along the axis) reaches
    // twice as far inside, so that the fit's slope, carried to the row, rests on as many
    // slices as an inner row's mean.
    const bool cut =
      zc - kernel < static_cast<double>(firstGood) * sz || zc + kernel > static_cast<double>(lastGood) * sz;
    const double                         reach = cut ? 2.0 * kernel : kernel;
    std::vector<std::pair<long, double>> window;
    for (long k = firstGood; k <= lastGood; ++k)
    {
      const double weight = 1.0 - std::abs(static_cast<double>(k) * sz - zc) / reach;
      if (weight > 0.0)
      {
        window.emplace_back(k, weight);
      }
    }
    // An edge row of a roll: each column's trends about the axis; past the traced slices
    // the radius follows the row's median radial slope (a roll's taper, the same all
    // round), not its own column's (which sliding traces' ends bend).
    std::vector<std::optional<RollColumnTrend>> trends;
    double                                      radialSlope = 0.0;
    if (cut && rollAxis != nullptr)
    {
      trends.resize(columns);
      std::vector<double> slopes;
      for (size_t c = 0; c < columns; ++c)
      {
        trends[c] = RollEdgeRowFit(window, columnsOf, c, agreement, z / sz, *rollAxis, sz);
        if (trends[c])
        {
          slopes.push_back(trends[c]->RadiusSlope);
        }
      }
      radialSlope = slopes.empty() ? 0.0 : RollTracing::Median(slopes);
    }
    const double past = z / sz - std::clamp(z / sz, static_cast<double>(firstGood), static_cast<double>(lastGood));
    for (size_t c = 0; c < columns; ++c)
    {
      const size_t                   p = r * columns + c;
      double                         point[2];
      std::optional<RollColumnTrend> trend = trends.empty() ? std::nullopt : trends[c];
      if (!trend)
      {
        const double share =
          RobustRowPoint(window, columnsOf, c, agreement, cut ? std::optional<double>(z / sz) : std::nullopt, point);
        // A roll's column that slides along its turn from slice to slice (where the sheet's
        // length changes along the axis, by several voxels a slice) leaves no majority near
        // the window's median point, which, taken coordinate by coordinate, lies off the sheet
        // between two slices' points: there the column's radius and angle about the axis are
        // fitted along the window instead and taken at the row, which stays on the turn.
        if (share < 0.5 && !cut && rollAxis != nullptr)
        {
          trend = RollEdgeRowFit(window, columnsOf, c, agreement, z / sz, *rollAxis, sz);
        }
      }
      if (trend)
      {
        const double radius = std::max(0.0, trend->Radius + radialSlope * past);
        point[0] = rollAxis->Centre[0] + rollAxis->Slope[0] * z + radius * std::cos(trend->Angle);
        point[1] = rollAxis->Centre[1] + rollAxis->Slope[1] * z + radius * std::sin(trend->Angle);
      }
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

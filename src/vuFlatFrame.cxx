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
#include "vuFlatFrame.h"
#include "vuCoarseGrid.h"
#include "vuMedian.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace itk {
namespace FlatFrame {
using Vec3 = Eigen::Vector3d;

Eigen::Matrix3d
PrincipalAxes(const std::vector<double> & x, Vec3 & centroid)
{
  const size_t n = x.size() / 3;
  centroid.setZero();
  for (size_t i = 0; i < n; ++i)
  {
    centroid += PointOf(x, i);
  }
  centroid /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i)
  {
    const Vec3 d = PointOf(x, i) - centroid;
    covariance += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Matrix3d                                axes;
  for (int k = 0; k < 3; ++k)
  {
    axes.col(k) = eigen.eigenvectors().col(2 - k);
  }
  return axes;
}

std::vector<double>
ToPlane(const std::vector<double> & x, const Vec3 & origin, const Vec3 & u, const Vec3 & v)
{
  std::vector<double> planar(x.size());
  for (size_t i = 0; i < x.size() / 3; ++i)
  {
    const Vec3 d = PointOf(x, i) - origin;
    planar[3 * i] = d.dot(u);
    planar[3 * i + 1] = d.dot(v);
    planar[3 * i + 2] = 0.0;
  }
  return planar;
}

namespace {
// The mean direction of a flat grid mesh's rows (from each point to the next column's),
// in the plane; zero when the grid has no two neighbouring columns.
Vec3
MeanColumnDirection(const SheetMesh & flat)
{
  const std::vector<int64_t> at = CoarseToFine::GridLookup(flat);
  const size_t               columns = static_cast<size_t>(flat.GridColumns);
  Vec3                       sum = Vec3::Zero();
  for (size_t k = 0; k + 1 < at.size(); ++k)
  {
    if ((k + 1) % columns != 0 && at[k] >= 0 && at[k + 1] >= 0)
    {
      sum += PointOf(flat.Points, static_cast<size_t>(at[k + 1])) - PointOf(flat.Points, static_cast<size_t>(at[k]));
    }
  }
  sum.z() = 0.0;
  return sum;
}
// Twice the signed area of triangle t in the plane z = 0 (x, y of packed points `p`):
// positive when counter-clockwise seen from +z.
double
SignedArea2(const std::vector<double> & p, const SheetMesh & mesh, size_t t)
{
  const double * a = &p[3 * mesh.Triangles[3 * t]];
  const double * b = &p[3 * mesh.Triangles[3 * t + 1]];
  const double * c = &p[3 * mesh.Triangles[3 * t + 2]];
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}
} // namespace

namespace {
using Vec2 = Eigen::Vector2d;

// The line a centre line follows at each of its points (arc lengths `arc`): a weighted
// quadratic in arc length over a Gaussian window `sigma` wide, its value and unit slope at
// the point (a straight-line fit would cut inside an arc, and more so at the ends, where
// the window is one-sided). False where a fit is degenerate.
bool
FollowCentreLine(const std::vector<Vec2> &   centre,
                 const std::vector<double> & arc,
                 double                      sigma,
                 std::vector<Vec2> &         origin,
                 std::vector<Vec2> &         direction)
{
  const size_t columns = centre.size();
  origin.assign(columns, Vec2::Zero());
  direction.assign(columns, Vec2::Zero());
  size_t lo = 0, hi = 0;
  for (size_t c = 0; c < columns; ++c)
  {
    while (arc[c] - arc[lo] > 3.0 * sigma)
    {
      ++lo;
    }
    while (hi + 1 < columns && arc[hi + 1] - arc[c] <= 3.0 * sigma)
    {
      ++hi;
    }
    Eigen::Matrix3d             normal = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 3, 2> right = Eigen::Matrix<double, 3, 2>::Zero();
    // A few hundred points of the window are as good as all of them (the window is smooth
    // and wide against the columns' spacing), and keep a million-point mesh's fit cheap.
    const size_t stride = std::max<size_t>(1, (hi - lo + 1) / 400);
    for (size_t k = lo + (c - lo) % stride; k <= hi; k += stride)
    {
      const double a = (arc[k] - arc[c]) / sigma;
      const Vec3   basis(1.0, a, a * a);
      const double w = std::exp(-0.5 * a * a);
      normal += w * basis * basis.transpose();
      right += w * basis * centre[k].transpose();
    }
    const Eigen::LDLT<Eigen::Matrix3d> solver(normal);
    if (solver.info() != Eigen::Success || !(std::abs(normal.determinant()) > 1e-12 * normal.trace()))
    {
      return false;
    }
    const Eigen::Matrix<double, 3, 2> fit = solver.solve(right);
    origin[c] = fit.row(0).transpose();
    direction[c] = fit.row(1).transpose();
    if (!(direction[c].norm() > 1e-12))
    {
      return false;
    }
    direction[c].normalize();
  }
  return true;
}
} // namespace

double
StraightenRows(SheetMesh & flat)
{
  if (!flat.IsGridStructured() || flat.GridColumns < 3 || flat.GridRows < 2)
  {
    return 0.0;
  }
  const std::vector<int64_t> at = CoarseToFine::GridLookup(flat);
  const auto                 rows = static_cast<size_t>(flat.GridRows);
  const auto                 columns = static_cast<size_t>(flat.GridColumns);
  // The centre line: the mean point of each column over its rows, and its arc length.
  std::vector<Vec2>   centre(columns, Vec2::Zero());
  std::vector<double> across(columns, 0.0);
  for (size_t c = 0; c < columns; ++c)
  {
    size_t count = 0, first = 0, last = 0;
    for (size_t r = 0; r < rows; ++r)
    {
      if (at[r * columns + c] >= 0)
      {
        const auto i = static_cast<size_t>(at[r * columns + c]);
        centre[c] += Vec2(flat.Points[3 * i], flat.Points[3 * i + 1]);
        first = count == 0 ? i : first;
        last = i;
        ++count;
      }
    }
    if (count < 2)
    {
      return 0.0;
    }
    centre[c] /= static_cast<double>(count);
    across[c] = std::hypot(flat.Points[3 * last] - flat.Points[3 * first],
                           flat.Points[3 * last + 1] - flat.Points[3 * first + 1]);
  }
  std::vector<double> arc(columns, 0.0);
  for (size_t c = 1; c < columns; ++c)
  {
    arc[c] = arc[c - 1] + (centre[c] - centre[c - 1]).norm();
  }
  std::vector<double> widths = across;
  std::nth_element(widths.begin(), widths.begin() + columns / 2, widths.end());
  const double width = widths[columns / 2];
  if (!(arc.back() > 0.0) || !(width > 0.0))
  {
    return 0.0;
  }
  // The line the centre follows, over a Gaussian window of half the strip's width, so
  // that bends longer than the strip is wide are taken out and each column keeps its own
  // shape. Its point and unit direction give each column's frame.
  const double      sigma = 0.5 * width;
  std::vector<Vec2> origin, direction;
  if (!FollowCentreLine(centre, arc, sigma, origin, direction))
  {
    return 0.0;
  }
  // Along most of its length the frame may turn by at most a tenth of a radian over half
  // the strip's width: a sheet bent more than that in its plane (a ring) is not a slightly
  // bent strip, and is left as it is. A short stretch turning faster (a jog where the trace
  // of an inner turn curls, a few columns of a long strip) does not make it one, unless it
  // turns by half a radian over half the width: laid straight, it would be strained by half
  // (the strain is the turn times the distance from the centre line) or folded.
  std::vector<double> turns(columns - 1);
  for (size_t c = 1; c < columns; ++c)
  {
    const double turn = std::acos(std::clamp(direction[c].dot(direction[c - 1]), -1.0, 1.0));
    const double step = std::max(arc[c] - arc[c - 1], 1e-12);
    turns[c - 1] = turn / step * 0.5 * width;
  }
  if (RollTracing::Median(turns) > 0.1 || *std::max_element(turns.begin(), turns.end()) > 0.5)
  {
    return 0.0;
  }
  // The bend taken out: the followed line's largest distance from its chord.
  const Vec2 chord = (origin.back() - origin.front()).normalized();
  double     bend = 0.0;
  for (const auto & point : origin)
  {
    const Vec2 d = point - origin.front();
    bend = std::max(bend, std::abs(d.x() * chord.y() - d.y() * chord.x()));
  }
  // Each column's points in its frame: along the line by the followed line's own arc
  // length (not the centre's, which steps back where the mesh does, at a trace's curled
  // end), across it by their distance from the line.
  double along = 0.0;
  for (size_t c = 0; c < columns; ++c)
  {
    if (c > 0)
    {
      along += (origin[c] - origin[c - 1]).dot((direction[c] + direction[c - 1]).normalized());
    }
    const Vec2 t = direction[c];
    const Vec2 n(-t.y(), t.x());
    for (size_t r = 0; r < rows; ++r)
    {
      if (at[r * columns + c] < 0)
      {
        continue;
      }
      const auto i = static_cast<size_t>(at[r * columns + c]);
      const Vec2 d = Vec2(flat.Points[3 * i], flat.Points[3 * i + 1]) - origin[c];
      flat.Points[3 * i] = along + d.dot(t);
      flat.Points[3 * i + 1] = d.dot(n);
    }
  }
  return bend;
}

void
Normalise(SheetMesh & flat)
{
  Vec3                  centroid;
  const Eigen::Matrix3d axes = PrincipalAxes(flat.Points, centroid);
  Vec3                  u = axes.col(0);
  u.z() = 0.0;
  if (flat.IsGridStructured())
  {
    const Vec3 along = MeanColumnDirection(flat);
    if (along.norm() > 1e-12)
    {
      u = along;
    }
  }
  if (u.norm() < 1e-12)
  {
    u = Vec3::UnitX();
  }
  u.normalize();
  Vec3                v(-u.y(), u.x(), 0.0);
  std::vector<double> p = ToPlane(flat.Points, centroid, u, v);
  double              signedArea = 0.0;
  for (size_t t = 0; t < flat.GetNumberOfTriangles(); ++t)
  {
    signedArea += SignedArea2(p, flat, t);
  }
  if (signedArea < 0.0)
  {
    for (size_t i = 0; i < p.size() / 3; ++i)
    {
      p[3 * i + 1] = -p[3 * i + 1];
    }
  }
  double lo[2] = { std::numeric_limits<double>::max(), std::numeric_limits<double>::max() };
  for (size_t i = 0; i < p.size() / 3; ++i)
  {
    lo[0] = std::min(lo[0], p[3 * i]);
    lo[1] = std::min(lo[1], p[3 * i + 1]);
  }
  for (size_t i = 0; i < p.size() / 3; ++i)
  {
    p[3 * i] -= lo[0];
    p[3 * i + 1] -= lo[1];
  }
  flat.Points = std::move(p);
}

size_t
TurnedOverTriangles(const SheetMesh & flat)
{
  size_t turned = 0;
  for (size_t t = 0; t < flat.GetNumberOfTriangles(); ++t)
  {
    turned += SignedArea2(flat.Points, flat, t) < 0.0 ? 1 : 0;
  }
  return turned;
}
} // namespace FlatFrame
} // namespace itk

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

#include <algorithm>
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

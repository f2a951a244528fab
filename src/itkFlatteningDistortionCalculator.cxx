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
#include "itkFlatteningDistortionCalculator.h"

#include "itkMath.h"
#include "itkSheetMeshAdaptor.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace itk {
namespace {
using Vec3 = std::array<double, 3>;

Vec3
PointOf(const SheetMesh & mesh, uint32_t i)
{
  return { mesh.Points[3 * i], mesh.Points[3 * i + 1], mesh.Points[3 * i + 2] };
}

Vec3
Sub(const Vec3 & a, const Vec3 & b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}

double
Dot(const Vec3 & a, const Vec3 & b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

Vec3
Cross(const Vec3 & a, const Vec3 & b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}

double
Norm(const Vec3 & a)
{
  return std::sqrt(Dot(a, a));
}

double
CornerAngle(const Vec3 & apex, const Vec3 & b, const Vec3 & c)
{
  const Vec3 u = Sub(b, apex);
  const Vec3 v = Sub(c, apex);
  return std::atan2(Norm(Cross(u, v)), Dot(u, v));
}
} // namespace

void
FlatteningDistortionCalculator::SetSurfaceMesh(const DataObject * mesh)
{
  this->SetSurfaceMesh(DataObjectToSheetMesh(mesh));
}

void
FlatteningDistortionCalculator::SetFlatMesh(const DataObject * mesh)
{
  this->SetFlatMesh(DataObjectToSheetMesh(mesh));
}

void
FlatteningDistortionCalculator::SetSurfaceMesh(const SheetMesh & mesh)
{
  m_SurfaceMesh = mesh;
  this->Modified();
}

void
FlatteningDistortionCalculator::SetFlatMesh(const SheetMesh & mesh)
{
  m_FlatMesh = mesh;
  // Only the plane coordinates of the flattening count.
  for (size_t i = 0; i < m_FlatMesh.GetNumberOfPoints(); ++i)
  {
    m_FlatMesh.Points[3 * i + 2] = 0.0;
  }
  this->Modified();
}

void
FlatteningDistortionCalculator::Compute()
{
  m_SurfaceMesh.Validate("FlatteningDistortionCalculator surface mesh");
  m_FlatMesh.Validate("FlatteningDistortionCalculator flat mesh");
  if (!HaveSameTopology(m_SurfaceMesh, m_FlatMesh))
  {
    itkExceptionMacro(<< "surface mesh (" << m_SurfaceMesh.GetNumberOfPoints() << " points, "
                      << m_SurfaceMesh.GetNumberOfTriangles() << " triangles) and flat mesh ("
                      << m_FlatMesh.GetNumberOfPoints() << " points, " << m_FlatMesh.GetNumberOfTriangles()
                      << " triangles) do not share topology");
  }

  // Edge strain over unique edges.
  const std::vector<uint32_t> edges = m_SurfaceMesh.ComputeEdges();
  std::vector<double>         strain;
  strain.reserve(edges.size() / 2);
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    const double l3 = Norm(Sub(PointOf(m_SurfaceMesh, edges[e]), PointOf(m_SurfaceMesh, edges[e + 1])));
    const double l2 = Norm(Sub(PointOf(m_FlatMesh, edges[e]), PointOf(m_FlatMesh, edges[e + 1])));
    if (l3 > 0.0)
    {
      strain.push_back(std::abs(l2 - l3) / l3);
    }
  }
  m_NumberOfEdges = strain.size();
  m_EdgeStrainMean = m_EdgeStrainP95 = m_EdgeStrainMax = 0.0;
  if (!strain.empty())
  {
    double sum = 0.0;
    for (double s : strain)
    {
      sum += s;
    }
    m_EdgeStrainMean = sum / strain.size();
    m_EdgeStrainMax = *std::max_element(strain.begin(), strain.end());
    const size_t k = std::min(strain.size() - 1, static_cast<size_t>(std::ceil(0.95 * strain.size())) - 1);
    std::nth_element(strain.begin(), strain.begin() + k, strain.end());
    m_EdgeStrainP95 = strain[k];
  }

  // Orientation of the flat triangles: the majority sign is the sheet's side.
  const size_t        nt = m_SurfaceMesh.GetNumberOfTriangles();
  std::vector<double> signedFlatArea(nt);
  SizeValueType       positive = 0, negative = 0;
  for (size_t t = 0; t < nt; ++t)
  {
    const Vec3 p = PointOf(m_FlatMesh, m_FlatMesh.Triangles[3 * t]);
    const Vec3 q = PointOf(m_FlatMesh, m_FlatMesh.Triangles[3 * t + 1]);
    const Vec3 r = PointOf(m_FlatMesh, m_FlatMesh.Triangles[3 * t + 2]);
    signedFlatArea[t] = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]));
    positive += signedFlatArea[t] > 0.0;
    negative += signedFlatArea[t] < 0.0;
  }
  const double orientation = positive >= negative ? 1.0 : -1.0;

  double weightedAreaDistortion = 0.0, area3DSum = 0.0, areaFlatSum = 0.0, angleSum = 0.0, l2Sum = 0.0;
  double linf = 0.0;
  size_t angleCount = 0;
  m_NumberOfFlippedTriangles = m_NumberOfDegenerateFlatTriangles = m_NumberOfDegenerate3DTriangles = 0;
  for (size_t t = 0; t < nt; ++t)
  {
    const uint32_t * tri = &m_SurfaceMesh.Triangles[3 * t];
    const Vec3       P[3] = { PointOf(m_SurfaceMesh, tri[0]),
                              PointOf(m_SurfaceMesh, tri[1]),
                              PointOf(m_SurfaceMesh, tri[2]) };
    const Vec3       Q[3] = { PointOf(m_FlatMesh, tri[0]), PointOf(m_FlatMesh, tri[1]), PointOf(m_FlatMesh, tri[2]) };
    const double     a3 = 0.5 * Norm(Cross(Sub(P[1], P[0]), Sub(P[2], P[0])));
    const double     af = orientation * signedFlatArea[t];
    if (signedFlatArea[t] == 0.0)
    {
      ++m_NumberOfDegenerateFlatTriangles;
    }
    else if (af < 0.0)
    {
      ++m_NumberOfFlippedTriangles;
    }
    if (!(a3 > 0.0))
    {
      ++m_NumberOfDegenerate3DTriangles;
      continue;
    }
    area3DSum += a3;
    areaFlatSum += std::abs(af);
    weightedAreaDistortion += a3 * std::abs(std::abs(af) / a3 - 1.0);
    for (int c = 0; c < 3; ++c)
    {
      const double angle3 = CornerAngle(P[c], P[(c + 1) % 3], P[(c + 2) % 3]);
      const double angleF = CornerAngle(Q[c], Q[(c + 1) % 3], Q[(c + 2) % 3]);
      angleSum += std::abs(angle3 - angleF);
      ++angleCount;
    }
    // Stretch of the map flat (s, t) -> 3D: Sander et al. 2001, eq. for S_s, S_t.
    if (signedFlatArea[t] != 0.0)
    {
      const double A2 = 2.0 * signedFlatArea[t];
      const double s1 = Q[0][0], t1 = Q[0][1], s2 = Q[1][0], t2 = Q[1][1], s3 = Q[2][0], t3 = Q[2][1];
      Vec3         Ss, St;
      for (int d = 0; d < 3; ++d)
      {
        Ss[d] = (P[0][d] * (t2 - t3) + P[1][d] * (t3 - t1) + P[2][d] * (t1 - t2)) / A2;
        St[d] = (P[0][d] * (s3 - s2) + P[1][d] * (s1 - s3) + P[2][d] * (s2 - s1)) / A2;
      }
      const double a = Dot(Ss, Ss), b = Dot(Ss, St), c = Dot(St, St);
      const double root = std::sqrt((a - c) * (a - c) + 4.0 * b * b);
      l2Sum += a3 * 0.5 * (a + c);
      linf = std::max(linf, std::sqrt(0.5 * (a + c + root)));
    }
    else
    {
      linf = std::numeric_limits<double>::infinity();
    }
  }
  m_AreaDistortion = area3DSum > 0.0 ? weightedAreaDistortion / area3DSum : 0.0;
  m_TotalAreaRatio = area3DSum > 0.0 ? areaFlatSum / area3DSum : 0.0;
  m_AngleDistortionDegrees = angleCount > 0 ? angleSum / angleCount * 180.0 / itk::Math::pi : 0.0;
  m_L2Stretch = area3DSum > 0.0 ? std::sqrt(l2Sum / area3DSum) : 0.0;
  m_LinfStretch = linf;
}

void
FlatteningDistortionCalculator::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "SurfaceMesh: " << m_SurfaceMesh.GetNumberOfPoints() << " points, "
     << m_SurfaceMesh.GetNumberOfTriangles() << " triangles" << std::endl;
  os << indent << "FlatMesh: " << m_FlatMesh.GetNumberOfPoints() << " points, " << m_FlatMesh.GetNumberOfTriangles()
     << " triangles" << std::endl;
  os << indent << "EdgeStrainMean: " << m_EdgeStrainMean << std::endl;
  os << indent << "EdgeStrainP95: " << m_EdgeStrainP95 << std::endl;
  os << indent << "EdgeStrainMax: " << m_EdgeStrainMax << std::endl;
  os << indent << "AreaDistortion: " << m_AreaDistortion << std::endl;
  os << indent << "TotalAreaRatio: " << m_TotalAreaRatio << std::endl;
  os << indent << "AngleDistortionDegrees: " << m_AngleDistortionDegrees << std::endl;
  os << indent << "L2Stretch: " << m_L2Stretch << std::endl;
  os << indent << "LinfStretch: " << m_LinfStretch << std::endl;
  os << indent << "NumberOfFlippedTriangles: " << m_NumberOfFlippedTriangles << std::endl;
  os << indent << "NumberOfDegenerateFlatTriangles: " << m_NumberOfDegenerateFlatTriangles << std::endl;
  os << indent << "NumberOfDegenerate3DTriangles: " << m_NumberOfDegenerate3DTriangles << std::endl;
  os << indent << "NumberOfEdges: " << m_NumberOfEdges << std::endl;
}

} // end namespace itk

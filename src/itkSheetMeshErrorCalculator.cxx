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
#include "itkSheetMeshErrorCalculator.h"

#include "itkMultiThreaderBase.h"
#include "itkSheetMeshAdaptor.h"

#include <algorithm>
#include <cmath>

namespace itk {
namespace {
double
Dot(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Squared distance from p to triangle abc, by the Voronoi regions of its vertices, edges
// and face (C. Ericson, Real-Time Collision Detection, 2005, section 5.1.5).
double
SquaredDistanceToTriangle(const double p[3], const double a[3], const double b[3], const double c[3])
{
  double ab[3], ac[3], ap[3];
  for (int d = 0; d < 3; ++d)
  {
    ab[d] = b[d] - a[d];
    ac[d] = c[d] - a[d];
    ap[d] = p[d] - a[d];
  }
  auto distanceTo = [p](const double q[3]) {
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
  };
  auto onSegment = [&](const double from[3], const double direction[3], double t) {
    const double q[3] = { from[0] + t * direction[0], from[1] + t * direction[1], from[2] + t * direction[2] };
    return distanceTo(q);
  };
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0)
  {
    return distanceTo(a);
  }
  double bp[3], cp[3];
  for (int d = 0; d < 3; ++d)
  {
    bp[d] = p[d] - b[d];
    cp[d] = p[d] - c[d];
  }
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3)
  {
    return distanceTo(b);
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
  {
    return onSegment(a, ab, d1 / (d1 - d3));
  }
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6)
  {
    return distanceTo(c);
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
  {
    return onSegment(a, ac, d2 / (d2 - d6));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
  {
    const double bc[3] = { c[0] - b[0], c[1] - b[1], c[2] - b[2] };
    return onSegment(b, bc, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  const double q[3] = { a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w };
  return distanceTo(q);
}
// The triangles of a mesh binned in a uniform grid of cells at least 2 `tolerance` wide (at
// most 256 a side) over its bounding box grown by `tolerance`; each triangle in every cell
// its box grown by `tolerance` touches.
class TriangleGrid
{
public:
  TriangleGrid(const SheetMesh & mesh, double tolerance)
  {
    for (int d = 0; d < 3; ++d)
    {
      m_Lower[d] = m_Upper[d] = mesh.Points[d];
    }
    for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        m_Lower[d] = std::min(m_Lower[d], mesh.Points[3 * i + d]);
        m_Upper[d] = std::max(m_Upper[d], mesh.Points[3 * i + d]);
      }
    }
    m_Cell = 2.0 * tolerance;
    for (int d = 0; d < 3; ++d)
    {
      m_Lower[d] -= tolerance;
      m_Upper[d] += tolerance;
      m_Cell = std::max(m_Cell, (m_Upper[d] - m_Lower[d]) / 256.0);
    }
    for (int d = 0; d < 3; ++d)
    {
      m_Cells[d] = std::max(1L, static_cast<long>(std::ceil((m_Upper[d] - m_Lower[d]) / m_Cell)));
    }
    m_Bins.resize(static_cast<size_t>(m_Cells[0] * m_Cells[1] * m_Cells[2]));
    for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
    {
      long from[3], to[3];
      for (int d = 0; d < 3; ++d)
      {
        double lo = mesh.Points[3 * mesh.Triangles[3 * t] + d], hi = lo;
        for (int v = 1; v < 3; ++v)
        {
          lo = std::min(lo, mesh.Points[3 * mesh.Triangles[3 * t + v] + d]);
          hi = std::max(hi, mesh.Points[3 * mesh.Triangles[3 * t + v] + d]);
        }
        from[d] = CellOf(lo - tolerance, d);
        to[d] = CellOf(hi + tolerance, d);
      }
      for (long z = from[2]; z <= to[2]; ++z)
      {
        for (long y = from[1]; y <= to[1]; ++y)
        {
          for (long x = from[0]; x <= to[0]; ++x)
          {
            m_Bins[static_cast<size_t>((z * m_Cells[1] + y) * m_Cells[0] + x)].push_back(static_cast<uint32_t>(t));
          }
        }
      }
    }
  }

  /** The triangles near point p; null outside the grid. */
  const std::vector<uint32_t> *
  BinAt(const double p[3]) const
  {
    for (int d = 0; d < 3; ++d)
    {
      if (p[d] < m_Lower[d] || p[d] > m_Upper[d])
      {
        return nullptr;
      }
    }
    return &m_Bins[static_cast<size_t>((CellOf(p[2], 2) * m_Cells[1] + CellOf(p[1], 1)) * m_Cells[0] +
                                       CellOf(p[0], 0))];
  }

private:
  long
  CellOf(double x, int d) const
  {
    return std::clamp(static_cast<long>(std::floor((x - m_Lower[d]) / m_Cell)), 0L, m_Cells[d] - 1);
  }

  double                             m_Lower[3], m_Upper[3], m_Cell{ 0.0 };
  long                               m_Cells[3]{ 1, 1, 1 };
  std::vector<std::vector<uint32_t>> m_Bins;
};
} // namespace

void
SheetMeshErrorCalculator::SetGeometry(const SheetPhantomGeometry & geometry)
{
  m_Geometry = geometry;
  this->Modified();
}

void
SheetMeshErrorCalculator::SetMesh(const SheetMesh & mesh)
{
  m_Mesh = mesh;
  this->Modified();
}

void
SheetMeshErrorCalculator::SetPhantom(const SheetPhantomSource * phantom)
{
  if (phantom == nullptr)
  {
    itkExceptionMacro(<< "no phantom source given");
  }
  this->SetGeometry(phantom->GetGeometry());
}

void
SheetMeshErrorCalculator::SetMesh(const DataObject * mesh)
{
  this->SetMesh(DataObjectToSheetMesh(mesh));
}

void
SheetMeshErrorCalculator::Compute()
{
  if (!(m_Geometry.GetSheetLength() > 0.0))
  {
    itkExceptionMacro(<< "no ground-truth geometry set");
  }
  if (!(m_VoxelSize > 0.0) || !(m_CoverageTolerance > 0.0))
  {
    itkExceptionMacro(<< "VoxelSize and CoverageTolerance must be positive");
  }
  m_Mesh.Validate("SheetMeshErrorCalculator mesh");
  const size_t points = m_Mesh.GetNumberOfPoints();
  const size_t triangles = m_Mesh.GetNumberOfTriangles();
  if (points == 0 || triangles == 0)
  {
    itkExceptionMacro(<< "the mesh is empty");
  }
  const double length = m_Geometry.GetSheetLength(), width = m_Geometry.GetSheetWidth();

  // Vertex distances and the arc length of each vertex's foot point.
  std::vector<double> distance(points), arcLength(points);
  std::vector<char>   beyond(points, 0);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    points,
    [&](SizeValueType i) {
      const double * p = &m_Mesh.Points[3 * i];
      double         s = 0.0, w = 0.0, signedDistance = 0.0;
      if (m_Geometry.Project(p, s, w, signedDistance))
      {
        distance[i] = std::abs(signedDistance);
      }
      else
      {
        double q[3];
        m_Geometry.SurfacePoint(std::clamp(s, 0.0, length), std::clamp(w, 0.0, width), q);
        distance[i] =
          std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
        beyond[i] = 1;
      }
      arcLength[i] = s;
    },
    nullptr);
  double sum = 0.0, maximum = 0.0;
  for (size_t i = 0; i < points; ++i)
  {
    sum += distance[i];
    maximum = std::max(maximum, distance[i]);
  }
  m_MeanVertexDistance = sum / static_cast<double>(points) / m_VoxelSize;
  m_MaximumVertexDistance = maximum / m_VoxelSize;
  m_NumberOfVerticesBeyondSheet = static_cast<SizeValueType>(std::count(beyond.begin(), beyond.end(), 1));

  // Layer jumps.
  const std::vector<uint32_t> edges = m_Mesh.ComputeEdges();
  m_NumberOfEdges = edges.size() / 2;
  m_NumberOfLayerJumps = 0;
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    const double * a = &m_Mesh.Points[3 * edges[e]];
    const double * b = &m_Mesh.Points[3 * edges[e + 1]];
    const double   edgeLength =
      std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    if (std::abs(arcLength[edges[e]] - arcLength[edges[e + 1]]) > 2.0 * edgeLength + 4.0 * m_VoxelSize)
    {
      ++m_NumberOfLayerJumps;
    }
  }

  // Triangles binned in a uniform grid whose cells are at least the tolerance wide.
  const double       tolerance = m_CoverageTolerance * m_VoxelSize;
  const TriangleGrid grid(m_Mesh, tolerance);

  // The true mid-surface, sampled at cell centres of half a voxel.
  const double               step = 0.5 * m_VoxelSize;
  const auto                 samplesS = static_cast<size_t>(std::max(1.0, std::ceil(length / step)));
  const auto                 samplesW = static_cast<size_t>(std::max(1.0, std::ceil(width / step)));
  std::vector<SizeValueType> coveredInRow(samplesW, 0);
  const double               tolerance2 = tolerance * tolerance;
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    samplesW,
    [&](SizeValueType row) {
      const double w = (static_cast<double>(row) + 0.5) * width / static_cast<double>(samplesW);
      for (size_t column = 0; column < samplesS; ++column)
      {
        const double s = (static_cast<double>(column) + 0.5) * length / static_cast<double>(samplesS);
        double       p[3];
        m_Geometry.SurfacePoint(s, w, p);
        const std::vector<uint32_t> * bin = grid.BinAt(p);
        if (bin == nullptr)
        {
          continue;
        }
        for (uint32_t t : *bin)
        {
          const uint32_t * tri = &m_Mesh.Triangles[3 * t];
          if (SquaredDistanceToTriangle(
                p, &m_Mesh.Points[3 * tri[0]], &m_Mesh.Points[3 * tri[1]], &m_Mesh.Points[3 * tri[2]]) <= tolerance2)
          {
            ++coveredInRow[row];
            break;
          }
        }
      }
    },
    nullptr);
  SizeValueType covered = 0;
  for (SizeValueType count : coveredInRow)
  {
    covered += count;
  }
  m_Coverage = static_cast<double>(covered) / static_cast<double>(samplesS * samplesW);
}

void
SheetMeshErrorCalculator::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Geometry: " << m_Geometry.GetParameters().Shape << ", length " << m_Geometry.GetSheetLength()
     << " mm" << std::endl;
  os << indent << "Mesh: " << m_Mesh.GetNumberOfPoints() << " points, " << m_Mesh.GetNumberOfTriangles() << " triangles"
     << std::endl;
  os << indent << "VoxelSize: " << m_VoxelSize << std::endl;
  os << indent << "CoverageTolerance: " << m_CoverageTolerance << std::endl;
  os << indent << "MeanVertexDistance: " << m_MeanVertexDistance << std::endl;
  os << indent << "MaximumVertexDistance: " << m_MaximumVertexDistance << std::endl;
  os << indent << "Coverage: " << m_Coverage << std::endl;
  os << indent << "NumberOfLayerJumps: " << m_NumberOfLayerJumps << std::endl;
  os << indent << "NumberOfEdges: " << m_NumberOfEdges << std::endl;
  os << indent << "NumberOfVerticesBeyondSheet: " << m_NumberOfVerticesBeyondSheet << std::endl;
}
} // end namespace itk

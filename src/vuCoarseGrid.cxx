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
#include "vuCoarseGrid.h"

#include "itkMacro.h"
#include "itk_eigen.h"
#include ITK_EIGEN(Dense)
#include ITK_EIGEN(Sparse)
#include ITK_EIGEN(SparseCholesky)

#include <algorithm>
#include <cmath>

namespace itk {
namespace CoarseToFine {
namespace {
// Every factor-th grid line and the last one.
std::vector<int32_t>
CoarseLevels(int32_t count, unsigned int factor)
{
  std::vector<int32_t> kept;
  for (int32_t k = 0; k < count; k += static_cast<int32_t>(factor))
  {
    kept.push_back(k);
  }
  if (kept.back() != count - 1)
  {
    kept.push_back(count - 1);
  }
  return kept;
}

} // namespace

// Dense (row, column) -> point lookup of a grid-structured mesh; -1 where no point.
std::vector<int64_t>
GridLookup(const SheetMesh & mesh)
{
  std::vector<int64_t> lookup(static_cast<size_t>(mesh.GridRows) * mesh.GridColumns, -1);
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const int32_t r = mesh.GridIndex[2 * i], c = mesh.GridIndex[2 * i + 1];
    if (r < 0 || c < 0 || r >= mesh.GridRows || c >= mesh.GridColumns)
    {
      itkGenericExceptionMacro(<< "sheet mesh: grid index (" << r << ", " << c << ") of point " << i
                               << " lies outside the " << mesh.GridRows << " x " << mesh.GridColumns << " grid");
    }
    lookup[static_cast<size_t>(r) * mesh.GridColumns + c] = static_cast<int64_t>(i);
  }
  return lookup;
}

// Every n-th row and column of a grid mesh (and the last ones), as a grid mesh of its own.
SheetMesh
CoarseGrid(const SheetMesh & mesh, unsigned int factor, std::vector<uint32_t> & fineIds)
{
  const std::vector<int64_t> lookup = GridLookup(mesh);
  const std::vector<int32_t> rows = CoarseLevels(mesh.GridRows, factor);
  const std::vector<int32_t> columns = CoarseLevels(mesh.GridColumns, factor);
  const auto                 R = static_cast<int32_t>(rows.size()), C = static_cast<int32_t>(columns.size());
  auto                       fine = [&](int32_t r, int32_t c) {
    return lookup[static_cast<size_t>(rows[r]) * mesh.GridColumns + columns[c]];
  };
  // Keep coarse points that belong to a complete coarse quad.
  std::vector<int64_t> coarseId(static_cast<size_t>(R) * C, -1);
  std::vector<uint8_t> used(static_cast<size_t>(R) * C, 0);
  for (int32_t r = 0; r + 1 < R; ++r)
  {
    for (int32_t c = 0; c + 1 < C; ++c)
    {
      if (fine(r, c) >= 0 && fine(r, c + 1) >= 0 && fine(r + 1, c) >= 0 && fine(r + 1, c + 1) >= 0)
      {
        used[r * C + c] = used[r * C + c + 1] = used[(r + 1) * C + c] = used[(r + 1) * C + c + 1] = 1;
      }
    }
  }
  SheetMesh coarse;
  coarse.GridRows = R;
  coarse.GridColumns = C;
  fineIds.clear();
  for (int32_t r = 0; r < R; ++r)
  {
    for (int32_t c = 0; c < C; ++c)
    {
      if (used[r * C + c])
      {
        const auto f = static_cast<uint32_t>(fine(r, c));
        coarseId[r * C + c] = static_cast<int64_t>(fineIds.size());
        fineIds.push_back(f);
        coarse.Points.insert(coarse.Points.end(), &mesh.Points[3 * f], &mesh.Points[3 * f] + 3);
        coarse.GridIndex.insert(coarse.GridIndex.end(), { r, c });
      }
    }
  }
  // Triangulate each coarse quad with the orientation of the fine triangles there.
  auto orientationAt = [&](uint32_t finePoint) {
    // Sign of the fine triangle's (row, column) orientation that contains this point.
    for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
    {
      const uint32_t * tri = &mesh.Triangles[3 * t];
      if (tri[0] == finePoint || tri[1] == finePoint || tri[2] == finePoint)
      {
        const int32_t * a = &mesh.GridIndex[2 * tri[0]];
        const int32_t * b = &mesh.GridIndex[2 * tri[1]];
        const int32_t * c = &mesh.GridIndex[2 * tri[2]];
        return ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) > 0 ? 1 : -1;
      }
    }
    return 1;
  };
  const int orientation = orientationAt(fineIds.empty() ? 0 : fineIds[0]);
  for (int32_t r = 0; r + 1 < R; ++r)
  {
    for (int32_t c = 0; c + 1 < C; ++c)
    {
      const int64_t a = coarseId[r * C + c], b = coarseId[r * C + c + 1], d = coarseId[(r + 1) * C + c],
                    e = coarseId[(r + 1) * C + c + 1];
      if (a < 0 || b < 0 || d < 0 || e < 0 || fine(r, c) < 0 || fine(r, c + 1) < 0 || fine(r + 1, c) < 0 ||
          fine(r + 1, c + 1) < 0)
      {
        continue;
      }
      // In (row, column) coordinates (a, e, b) is counter-clockwise when orientation > 0.
      const auto A = static_cast<uint32_t>(a), B = static_cast<uint32_t>(b), D = static_cast<uint32_t>(d),
                 E = static_cast<uint32_t>(e);
      if (orientation > 0)
      {
        coarse.Triangles.insert(coarse.Triangles.end(), { A, E, B, A, D, E });
      }
      else
      {
        coarse.Triangles.insert(coarse.Triangles.end(), { A, B, E, A, E, D });
      }
    }
  }
  return coarse;
}

// Carries flat positions of the coarse grid's points to every point of the fine grid:
// bilinear in (row, column) inside complete coarse cells, harmonic (a sparse Laplace
// solve with the known points fixed) elsewhere.
std::vector<double>
Prolong(const SheetMesh & mesh, const SheetMesh & coarse, unsigned int factor, const std::vector<double> & coarseFlat)
{
  const size_t               n = mesh.GetNumberOfPoints();
  std::vector<double>        flat(3 * n, 0.0);
  std::vector<uint8_t>       known(n, 0);
  const auto                 R = coarse.GridRows, C = coarse.GridColumns;
  const std::vector<int32_t> rowOf = CoarseLevels(mesh.GridRows, factor);
  const std::vector<int32_t> columnOf = CoarseLevels(mesh.GridColumns, factor);
  std::vector<int64_t>       coarseAt(static_cast<size_t>(R) * C, -1);
  for (size_t k = 0; k < coarse.GetNumberOfPoints(); ++k)
  {
    coarseAt[static_cast<size_t>(coarse.GridIndex[2 * k]) * C + coarse.GridIndex[2 * k + 1]] = static_cast<int64_t>(k);
  }
  // Fine row/column -> the coarse level at or below it.
  auto levelBelow = [](const std::vector<int32_t> & levels, int32_t v) {
    return static_cast<int32_t>(std::upper_bound(levels.begin(), levels.end(), v) - levels.begin()) - 1;
  };
  for (size_t i = 0; i < n; ++i)
  {
    const int32_t r = mesh.GridIndex[2 * i], c = mesh.GridIndex[2 * i + 1];
    const int32_t r0 = std::max(0, std::min(R - 2, levelBelow(rowOf, r)));
    const int32_t c0 = std::max(0, std::min(C - 2, levelBelow(columnOf, c)));
    const int64_t q00 = coarseAt[r0 * C + c0], q01 = coarseAt[r0 * C + c0 + 1], q10 = coarseAt[(r0 + 1) * C + c0],
                  q11 = coarseAt[(r0 + 1) * C + c0 + 1];
    if (q00 < 0 || q01 < 0 || q10 < 0 || q11 < 0)
    {
      continue;
    }
    const double tr = double(r - rowOf[r0]) / double(rowOf[r0 + 1] - rowOf[r0]);
    const double tc = double(c - columnOf[c0]) / double(columnOf[c0 + 1] - columnOf[c0]);
    if (tr < 0.0 || tr > 1.0 || tc < 0.0 || tc > 1.0)
    {
      continue;
    }
    for (int d = 0; d < 2; ++d)
    {
      flat[3 * i + d] = (1 - tr) * (1 - tc) * coarseFlat[3 * q00 + d] + (1 - tr) * tc * coarseFlat[3 * q01 + d] +
                        tr * (1 - tc) * coarseFlat[3 * q10 + d] + tr * tc * coarseFlat[3 * q11 + d];
    }
    known[i] = 1;
  }
  std::vector<int64_t> unknownIndex(n, -1);
  Eigen::Index         unknowns = 0;
  for (size_t i = 0; i < n; ++i)
  {
    if (!known[i])
    {
      unknownIndex[i] = unknowns++;
    }
  }
  if (unknowns == 0)
  {
    return flat;
  }
  if (unknowns == static_cast<Eigen::Index>(n))
  {
    itkGenericExceptionMacro(<< "mass-spring flattening: the coarse grid covers no cell of the mesh");
  }
  const std::vector<uint32_t>         edges = mesh.ComputeEdges();
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd                     rhs = Eigen::MatrixXd::Zero(unknowns, 2);
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    const uint32_t a = edges[e], b = edges[e + 1];
    for (auto [p, q] : { std::pair<uint32_t, uint32_t>{ a, b }, { b, a } })
    {
      if (unknownIndex[p] < 0)
      {
        continue;
      }
      triplets.emplace_back(unknownIndex[p], unknownIndex[p], 1.0);
      if (unknownIndex[q] >= 0)
      {
        triplets.emplace_back(unknownIndex[p], unknownIndex[q], -1.0);
      }
      else
      {
        rhs(unknownIndex[p], 0) += flat[3 * q];
        rhs(unknownIndex[p], 1) += flat[3 * q + 1];
      }
    }
  }
  Eigen::SparseMatrix<double> L(unknowns, unknowns);
  L.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(L);
  if (ldlt.info() != Eigen::Success)
  {
    itkGenericExceptionMacro(<< "mass-spring flattening: part of the mesh is not connected to the coarse grid");
  }
  const Eigen::MatrixXd solution = ldlt.solve(rhs);
  for (size_t i = 0; i < n; ++i)
  {
    if (unknownIndex[i] >= 0)
    {
      flat[3 * i] = solution(unknownIndex[i], 0);
      flat[3 * i + 1] = solution(unknownIndex[i], 1);
    }
  }
  return flat;
}
} // namespace CoarseToFine
} // end namespace itk

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
// MassSpringSystem's implicit (backward Euler) step and quasi-static relaxation.
#include "itkMassSpringSystem.h"
#include "vuImplicitSolver.h"
#include "vuSolverThreads.h"

#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace itk {
// The implicit system's matrix (M / h^2 plus the springs' Laplacian over the free
// particles) assembled and factorised; its symbolic analysis kept while the free set holds.
void
MassSpringSystem::ImplicitSolver::Factorise(const MassSpringSystem & system, double invH2)
{
  const size_t n = system.m_Masses.size();
  freeIndex.assign(n, -1);
  freeParticles.clear();
  for (size_t i = 0; i < n; ++i)
  {
    if (!system.m_Locked[i])
    {
      freeIndex[i] = static_cast<int32_t>(freeParticles.size());
      freeParticles.push_back(static_cast<uint32_t>(i));
    }
  }
  const auto nf = static_cast<Eigen::Index>(freeParticles.size());
  // The lower triangle (all that either factorisation, Eigen::Lower, reads), column by
  // column, straight from the springs: each spring between free particles (AddSpring
  // refuses one from a particle to itself) is one entry of the column of its lower index;
  // its stiffness is added to both ends' diagonals, also where the other end is held.
  // Entries are summed in spring order, as Eigen's setFromTriplets sums duplicates, so the
  // matrix is the same to the last bit.
  std::vector<double>       diagonal(static_cast<size_t>(nf));
  std::vector<Eigen::Index> start(static_cast<size_t>(nf) + 1, 0);
  for (Eigen::Index r = 0; r < nf; ++r)
  {
    diagonal[r] = system.m_Masses[freeParticles[r]] * invH2;
  }
  for (size_t s = 0; s < system.m_SpringI.size(); ++s)
  {
    const int32_t a = freeIndex[system.m_SpringI[s]];
    const int32_t b = freeIndex[system.m_SpringJ[s]];
    const double  k = system.m_Stiffness[s];
    if (a >= 0)
    {
      diagonal[a] += k;
    }
    if (b >= 0)
    {
      diagonal[b] += k;
    }
    if (a >= 0 && b >= 0)
    {
      ++start[std::min(a, b) + 1];
    }
  }
  for (Eigen::Index c = 0; c < nf; ++c)
  {
    start[c + 1] += start[c] + 1; // and the diagonal, first in its column
  }
  std::vector<int32_t>      row(static_cast<size_t>(start[nf]));
  std::vector<double>       value(row.size());
  std::vector<Eigen::Index> fill(start.begin(), start.end() - 1);
  for (Eigen::Index c = 0; c < nf; ++c)
  {
    row[fill[c]] = static_cast<int32_t>(c);
    value[fill[c]++] = diagonal[c];
  }
  for (size_t s = 0; s < system.m_SpringI.size(); ++s)
  {
    const int32_t a = freeIndex[system.m_SpringI[s]];
    const int32_t b = freeIndex[system.m_SpringJ[s]];
    if (a >= 0 && b >= 0)
    {
      const int32_t c = std::min(a, b);
      row[fill[c]] = std::max(a, b);
      value[fill[c]++] = -system.m_Stiffness[s];
    }
  }
  // Each column's entries by row, duplicates (two springs joining one pair) summed in order.
  using Index = SparseMatrix::StorageIndex;
  std::vector<Index>  outer(static_cast<size_t>(nf) + 1, 0);
  std::vector<Index>  inner;
  std::vector<double> entries;
  inner.reserve(row.size());
  entries.reserve(row.size());
  std::vector<size_t> order;
  for (Eigen::Index c = 0; c < nf; ++c)
  {
    order.resize(static_cast<size_t>(start[c + 1] - start[c]));
    std::iota(order.begin(), order.end(), static_cast<size_t>(start[c]));
    std::stable_sort(order.begin(), order.end(), [&row](size_t x, size_t y) { return row[x] < row[y]; });
    for (size_t i = 0; i < order.size(); ++i)
    {
      if (i > 0 && row[order[i]] == row[order[i - 1]])
      {
        entries.back() += value[order[i]];
        continue;
      }
      inner.push_back(static_cast<Index>(row[order[i]]));
      entries.push_back(value[order[i]]);
    }
    outer[c + 1] = static_cast<Index>(inner.size());
  }
  const SparseMatrix A = Eigen::Map<const SparseMatrix>(
    nf, nf, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(), entries.data());
  if (!analysed)
  {
    factorisation.analyzePattern(A);
    analysed = factorisation.info() == Eigen::Success;
  }
  if (analysed)
  {
    factorisation.factorize(A);
  }
  if (!analysed || factorisation.info() != Eigen::Success)
  {
    analysed = false;
    itkGenericExceptionMacro(<< "MassSpringSystem: factorisation of the implicit system failed");
  }
  valid = true;
}

void
MassSpringSystem::StepImplicit(bool quasiStatic)
{
  const vu::SolverThreads solverThreads;
  if (!m_AdjacencyValid)
  {
    BuildAdjacency();
  }
  const double     h = m_TimeStep;
  const double     invH2 = 1.0 / (h * h);
  ImplicitSolver & solver = *m_Solver;
  if (!solver.valid)
  {
    solver.Factorise(*this, invH2);
  }

  const auto          nf = static_cast<Eigen::Index>(solver.freeParticles.size());
  Eigen::MatrixXd     y(nf, 3), rhs(nf, 3), solution(nf, 3);
  const double        dampingFactor = 1.0 / (1.0 + m_Damping * h);
  std::vector<double> xPrevious = m_X;
  for (Eigen::Index r = 0; r < nf; ++r)
  {
    const size_t i = solver.freeParticles[r];
    for (int d = 0; d < 3; ++d)
    {
      y(r, d) = m_X[3 * i + d] + h * dampingFactor * m_V[3 * i + d] + h * h * m_Gravity[d];
    }
  }
  // Start the iterations from the inertial prediction.
  for (Eigen::Index r = 0; r < nf; ++r)
  {
    const size_t i = solver.freeParticles[r];
    for (int d = 0; d < 3; ++d)
    {
      m_X[3 * i + d] = y(r, d);
    }
  }
  const uint64_t *  start = m_AdjacencyStart.data();
  const Neighbour * adjacency = m_Adjacency.data();
  for (unsigned int iteration = 0; iteration < m_ImplicitIterations; ++iteration)
  {
    const double * x = m_X.data();
    // Local step (each spring projected to its rest length) gathered into the global
    // step's right-hand side, particle by particle.
    ParallelFor(static_cast<size_t>(nf), [&](size_t begin, size_t end) {
      for (size_t r = begin; r < end; ++r)
      {
        const size_t i = solver.freeParticles[r];
        const double m = m_Masses[i] * invH2;
        double       b[3] = { m * y(r, 0), m * y(r, 1), m * y(r, 2) };
        for (uint64_t e = start[i]; e < start[i + 1]; ++e)
        {
          const Neighbour & nb = adjacency[e];
          const double *    xj = x + 3 * nb.other;
          const double      d[3] = { x[3 * i] - xj[0], x[3 * i + 1] - xj[1], x[3 * i + 2] - xj[2] };
          const double      len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
          const double      scale = len > 0.0 ? nb.stiffness * nb.restLength / len : 0.0;
          for (int c = 0; c < 3; ++c)
          {
            b[c] += scale * d[c];
            if (m_Locked[nb.other])
            {
              b[c] += nb.stiffness * xj[c];
            }
          }
        }
        rhs(r, 0) = b[0];
        rhs(r, 1) = b[1];
        rhs(r, 2) = b[2];
      }
    });
    // A sheet lying on a coordinate plane (the final relaxation) has a zero column: skip it;
    // the others are solved together (one pass over the factor, which on a large mesh is
    // far larger than the caches, instead of one per column).
    std::vector<int> live;
    for (int d = 0; d < 3; ++d)
    {
      if (rhs.col(d).isZero(0.0))
      {
        solution.col(d).setZero();
      }
      else
      {
        live.push_back(d);
      }
    }
    if (live.size() == 3)
    {
      solution = solver.factorisation.solve(rhs);
    }
    else if (!live.empty())
    {
      Eigen::MatrixXd part(nf, static_cast<Eigen::Index>(live.size()));
      for (size_t k = 0; k < live.size(); ++k)
      {
        part.col(static_cast<Eigen::Index>(k)) = rhs.col(live[k]);
      }
      const Eigen::MatrixXd solved = solver.factorisation.solve(part);
      for (size_t k = 0; k < live.size(); ++k)
      {
        solution.col(live[k]) = solved.col(static_cast<Eigen::Index>(k));
      }
    }
    for (Eigen::Index r = 0; r < nf; ++r)
    {
      const size_t i = solver.freeParticles[r];
      for (int d = 0; d < 3; ++d)
      {
        m_X[3 * i + d] = solution(r, d);
      }
    }
    ++m_ForceEvaluations;
  }
  const double invH = quasiStatic ? 0.0 : 1.0 / h;
  for (size_t k = 0; k < m_X.size(); ++k)
  {
    m_V[k] = (m_X[k] - xPrevious[k]) * invH;
  }
  ApplyConstraintsAndCollisions(m_X.data(), m_V.data());
}

void
MassSpringSystem::Relax(unsigned int iterations)
{
  if (m_Masses.empty())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: no particles");
  }
  SyncState();
  DoubleStateChanged();
  const unsigned int saved = m_ImplicitIterations;
  m_ImplicitIterations = iterations;
  try
  {
    StepImplicit(true);
  }
  catch (...)
  {
    m_ImplicitIterations = saved;
    throw;
  }
  m_ImplicitIterations = saved;
  for (double c : m_X)
  {
    if (!std::isfinite(c))
    {
      throw MassSpringDivergenceError("mass-spring relaxation diverged (non-finite state) with " + Describe());
    }
  }
}

} // end namespace itk

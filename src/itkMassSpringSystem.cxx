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
#include "itkMassSpringSystem.h"

#include "itkMacro.h"
#include "itkMultiThreaderBase.h"
#include "itk_eigen.h"
#include ITK_EIGEN(Sparse)
#include ITK_EIGEN(SparseCholesky)

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace itk {
const char *
ToString(MassSpringIntegratorEnum integrator)
{
  switch (integrator)
  {
    case MassSpringIntegratorEnum::ExplicitEuler:
      return "euler";
    case MassSpringIntegratorEnum::Midpoint:
      return "midpoint";
    case MassSpringIntegratorEnum::RungeKutta4:
      return "rk4";
    case MassSpringIntegratorEnum::SymplecticEuler:
      return "symplectic-euler";
    case MassSpringIntegratorEnum::ImplicitEuler:
      return "implicit-euler";
  }
  return "unknown";
}

MassSpringIntegratorEnum
MassSpringIntegratorFromString(const std::string & name)
{
  for (auto e : { MassSpringIntegratorEnum::ExplicitEuler,
                  MassSpringIntegratorEnum::Midpoint,
                  MassSpringIntegratorEnum::RungeKutta4,
                  MassSpringIntegratorEnum::SymplecticEuler,
                  MassSpringIntegratorEnum::ImplicitEuler })
  {
    if (name == ToString(e))
    {
      return e;
    }
  }
  throw std::invalid_argument("unknown integrator '" + name +
                              "' (euler, midpoint, rk4, symplectic-euler, implicit-euler)");
}

struct MassSpringSystem::ImplicitSolver
{
  using SparseMatrix = Eigen::SparseMatrix<double>;
  Eigen::SimplicialLDLT<SparseMatrix> ldlt;
  std::vector<int32_t>                freeIndex; // particle -> row, or -1 when locked
  std::vector<uint32_t>               freeParticles;
  double                              timeStep{ 0.0 };
  bool                                valid{ false };
  // Kept for the engine's lifetime: creating a threader per force loop costs more than a
  // small system's whole step.
  MultiThreaderBase::Pointer threader;
};

MassSpringSystem::MassSpringSystem()
  : m_Solver(new ImplicitSolver)
{}

MassSpringSystem::~MassSpringSystem() = default;

void
MassSpringSystem::SetNumberOfWorkUnits(unsigned int n)
{
  m_NumberOfWorkUnits = n;
  m_Solver->threader = nullptr;
}

void
MassSpringSystem::SetParticles(const std::vector<double> & positions, const std::vector<double> & masses)
{
  if (positions.size() != 3 * masses.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: " << positions.size() << " coordinates for " << masses.size()
                             << " particles");
  }
  for (double m : masses)
  {
    if (!(m > 0.0) || !std::isfinite(m))
    {
      itkGenericExceptionMacro(<< "MassSpringSystem: particle masses must be positive and finite");
    }
  }
  for (double c : positions)
  {
    if (!std::isfinite(c))
    {
      itkGenericExceptionMacro(<< "MassSpringSystem: particle positions must be finite");
    }
  }
  m_X = positions;
  m_V.assign(positions.size(), 0.0);
  m_Masses = masses;
  m_Locked.assign(masses.size(), 0);
  m_SpringI.clear();
  m_SpringJ.clear();
  m_RestLength.clear();
  m_Stiffness.clear();
  m_AdjacencyValid = false;
  m_Solver->valid = false;
  m_EnergyReferenceValid = false;
  m_Steps = 0;
  m_ForceEvaluations = 0;
}

void
MassSpringSystem::AddSpring(uint32_t i, uint32_t j, double restLength, double stiffness)
{
  if (i >= m_Masses.size() || j >= m_Masses.size() || i == j)
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: spring (" << i << ", " << j << ") does not join two of the "
                             << m_Masses.size() << " particles");
  }
  if (!(restLength >= 0.0) || !(stiffness > 0.0) || !std::isfinite(restLength) || !std::isfinite(stiffness))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: spring (" << i << ", " << j << ") needs rest length >= 0 and "
                             << "stiffness > 0");
  }
  m_SpringI.push_back(i);
  m_SpringJ.push_back(j);
  m_RestLength.push_back(restLength);
  m_Stiffness.push_back(stiffness);
  m_AdjacencyValid = false;
  m_Solver->valid = false;
  m_EnergyReferenceValid = false;
}

void
MassSpringSystem::SetPositions(const std::vector<double> & positions)
{
  if (positions.size() != m_X.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: SetPositions needs " << m_X.size() << " coordinates");
  }
  m_X = positions;
  m_EnergyReferenceValid = false;
}

void
MassSpringSystem::SetVelocities(const std::vector<double> & velocities)
{
  if (velocities.size() != m_V.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: SetVelocities needs " << m_V.size() << " components");
  }
  m_V = velocities;
  m_EnergyReferenceValid = false;
}

void
MassSpringSystem::SetLocked(uint32_t particle, bool locked)
{
  if (particle >= m_Locked.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: no particle " << particle << " to lock");
  }
  if ((m_Locked[particle] != 0) != locked)
  {
    m_Locked[particle] = locked;
    m_Solver->valid = false;
    m_EnergyReferenceValid = false;
  }
  if (locked)
  {
    m_V[3 * particle] = m_V[3 * particle + 1] = m_V[3 * particle + 2] = 0.0;
  }
}

void
MassSpringSystem::SetLockedParticles(const std::vector<uint32_t> & particles)
{
  UnlockAll();
  for (uint32_t p : particles)
  {
    SetLocked(p, true);
  }
}

void
MassSpringSystem::UnlockAll()
{
  if (std::any_of(m_Locked.begin(), m_Locked.end(), [](uint8_t l) { return l != 0; }))
  {
    std::fill(m_Locked.begin(), m_Locked.end(), 0);
    m_Solver->valid = false;
    m_EnergyReferenceValid = false;
  }
}

size_t
MassSpringSystem::GetNumberOfLockedParticles() const
{
  return static_cast<size_t>(std::count_if(m_Locked.begin(), m_Locked.end(), [](uint8_t l) { return l != 0; }));
}

void
MassSpringSystem::SetDamping(double c)
{
  if (!(c >= 0.0) || !std::isfinite(c))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: damping must be >= 0, got " << c);
  }
  m_Damping = c;
}

void
MassSpringSystem::SetSpringDamping(double c)
{
  if (!(c >= 0.0) || !std::isfinite(c))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: spring damping must be >= 0, got " << c);
  }
  m_SpringDamping = c;
}

void
MassSpringSystem::SetCollisionPlane(const Vector3 & point, const Vector3 & normal, double restitution)
{
  const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  if (!(length > 0.0) || !std::isfinite(length))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: collision plane normal must be non-zero");
  }
  if (!(restitution >= 0.0 && restitution <= 1.0))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: restitution must lie in [0, 1], got " << restitution);
  }
  m_PlanePoint = point;
  m_PlaneNormal = { normal[0] / length, normal[1] / length, normal[2] / length };
  m_Restitution = restitution;
  m_HasPlane = true;
  m_EnergyReferenceValid = false;
}

void
MassSpringSystem::SetTimeStep(double h)
{
  if (!(h > 0.0) || !std::isfinite(h))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: time step must be positive, got " << h);
  }
  if (h != m_TimeStep)
  {
    m_TimeStep = h;
    m_Solver->valid = false;
  }
}

void
MassSpringSystem::SetImplicitIterations(unsigned int n)
{
  if (n == 0)
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: implicit iterations must be >= 1");
  }
  m_ImplicitIterations = n;
}

void
MassSpringSystem::BuildAdjacency()
{
  const size_t          n = m_Masses.size();
  std::vector<uint64_t> count(n + 1, 0);
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    ++count[m_SpringI[s] + 1];
    ++count[m_SpringJ[s] + 1];
  }
  std::partial_sum(count.begin(), count.end(), count.begin());
  m_AdjacencyStart = count;
  m_Adjacency.resize(2 * m_SpringI.size());
  std::vector<uint64_t> fill(m_AdjacencyStart.begin(), m_AdjacencyStart.end() - 1);
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    const auto L = static_cast<float>(m_RestLength[s]);
    const auto k = static_cast<float>(m_Stiffness[s]);
    m_Adjacency[fill[m_SpringI[s]]++] = { m_SpringJ[s], L, k };
    m_Adjacency[fill[m_SpringJ[s]]++] = { m_SpringI[s], L, k };
  }
  // Neighbours in increasing order keep the gathered loads moving forward in memory.
  for (size_t i = 0; i < n; ++i)
  {
    std::sort(m_Adjacency.begin() + m_AdjacencyStart[i],
              m_Adjacency.begin() + m_AdjacencyStart[i + 1],
              [](const Neighbour & a, const Neighbour & b) { return a.other < b.other; });
  }
  m_AdjacencyValid = true;
}

void
MassSpringSystem::ParallelFor(size_t n, const std::function<void(size_t, size_t)> & body)
{
  // Chunks of a few thousand particles: enough work per call to hide the threader's cost.
  constexpr size_t grain = 4096;
  const size_t     chunks = (n + grain - 1) / grain;
  if (chunks <= 1)
  {
    body(0, n);
    return;
  }
  if (m_Solver->threader.IsNull())
  {
    m_Solver->threader = MultiThreaderBase::New();
    if (m_NumberOfWorkUnits > 0)
    {
      m_Solver->threader->SetMaximumNumberOfThreads(m_NumberOfWorkUnits);
      m_Solver->threader->SetNumberOfWorkUnits(m_NumberOfWorkUnits);
    }
  }
  m_Solver->threader->ParallelizeArray(
    0,
    chunks,
    [&](SizeValueType c) {
      const size_t begin = c * grain;
      body(begin, std::min(n, begin + grain));
    },
    nullptr);
}

namespace {
// Spring force on particle i gathered over its neighbours (Hooke, plus spring damping along
// the spring when cs > 0): the one force kernel of every explicit path.
template <typename TNeighbour>
inline void
GatherSpringForce(size_t             i,
                  const double *     x,
                  const double *     v,
                  const uint64_t *   start,
                  const TNeighbour * adjacency,
                  double             cs,
                  double             f[3])
{
  const double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2];
  double       f0 = 0.0, f1 = 0.0, f2 = 0.0;
  for (uint64_t e = start[i]; e < start[i + 1]; ++e)
  {
    const TNeighbour & nb = adjacency[e];
    const double *     xj = x + 3 * nb.other;
    const double       d0 = xj[0] - xi0, d1 = xj[1] - xi1, d2 = xj[2] - xi2;
    const double       len2 = d0 * d0 + d1 * d1 + d2 * d2;
    if (len2 <= 0.0)
    {
      continue;
    }
    const double len = std::sqrt(len2);
    double       scale = nb.stiffness * (len - nb.restLength) / len;
    if (cs > 0.0)
    {
      const double * vj = v + 3 * nb.other;
      const double * vi = v + 3 * i;
      scale += cs * nb.stiffness * ((vj[0] - vi[0]) * d0 + (vj[1] - vi[1]) * d1 + (vj[2] - vi[2]) * d2) / len2;
    }
    f0 += scale * d0;
    f1 += scale * d1;
    f2 += scale * d2;
  }
  f[0] = f0;
  f[1] = f1;
  f[2] = f2;
}

// The collision plane for one particle: pushed back onto the plane, and the paper's
// response V_new = V_old - (1 + k_r)(V_old . N) N; a rebound slower than RestingSpeed
// comes to rest instead (it would only start an endless micro-bounce).
struct PlaneContact
{
  bool   HasPlane;
  double Point[3];
  double N[3];
  double Restitution;
  double RestingSpeed;

  inline void
  Collide(double * xi, double * vi) const
  {
    const double depth = (xi[0] - Point[0]) * N[0] + (xi[1] - Point[1]) * N[1] + (xi[2] - Point[2]) * N[2];
    if (depth < 0.0)
    {
      for (int d = 0; d < 3; ++d)
      {
        xi[d] -= depth * N[d];
      }
      const double vn = vi[0] * N[0] + vi[1] * N[1] + vi[2] * N[2];
      if (vn < 0.0)
      {
        const double rebound = -Restitution * vn <= RestingSpeed ? 0.0 : Restitution;
        for (int d = 0; d < 3; ++d)
        {
          vi[d] -= (1.0 + rebound) * vn * N[d];
        }
      }
    }
  }
};

template <typename TVector>
PlaneContact
MakePlaneContact(bool hasPlane, const TVector & point, const TVector & normal, double restitution, double restingSpeed)
{
  return { hasPlane, { point[0], point[1], point[2] }, { normal[0], normal[1], normal[2] }, restitution, restingSpeed };
}
} // namespace

void
MassSpringSystem::Accelerations(const double * x, const double * v, double * a)
{
  if (!m_AdjacencyValid)
  {
    BuildAdjacency();
  }
  const double      c = m_Damping;
  const double      cs = m_SpringDamping;
  const Vector3     g = m_Gravity;
  const uint64_t *  start = m_AdjacencyStart.data();
  const Neighbour * adjacency = m_Adjacency.data();
  const double *    masses = m_Masses.data();
  const uint8_t *   locked = m_Locked.data();
  ParallelFor(m_Masses.size(), [=](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
    {
      double * ai = a + 3 * i;
      if (locked[i])
      {
        ai[0] = ai[1] = ai[2] = 0.0;
        continue;
      }
      double f[3];
      GatherSpringForce(i, x, v, start, adjacency, cs, f);
      const double invM = 1.0 / masses[i];
      for (int d = 0; d < 3; ++d)
      {
        ai[d] = f[d] * invM + g[d] - c * v[3 * i + d];
      }
    }
  });
  ++m_ForceEvaluations;
}

void
MassSpringSystem::ComputeAccelerations(const std::vector<double> & x,
                                       const std::vector<double> & v,
                                       std::vector<double> &       a)
{
  if (x.size() != m_X.size() || v.size() != m_X.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: state vectors need " << m_X.size() << " components");
  }
  a.resize(m_X.size());
  Accelerations(x.data(), v.data(), a.data());
}

void
MassSpringSystem::ApplyConstraintsAndCollisions(double * x, double * v)
{
  const uint8_t *    locked = m_Locked.data();
  const PlaneContact plane = MakePlaneContact(m_HasPlane, m_PlanePoint, m_PlaneNormal, m_Restitution, RestingSpeed());
  ParallelFor(m_Masses.size(), [=](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
    {
      if (locked[i])
      {
        v[3 * i] = v[3 * i + 1] = v[3 * i + 2] = 0.0;
      }
      else if (plane.HasPlane)
      {
        plane.Collide(x + 3 * i, v + 3 * i);
      }
    }
  });
}

double
MassSpringSystem::RestingSpeed() const
{
  // A rebound slower than what gravity adds in two steps comes to rest on the plane.
  const Vector3 & N = m_PlaneNormal;
  return 2.0 * m_TimeStep * std::abs(m_Gravity[0] * N[0] + m_Gravity[1] * N[1] + m_Gravity[2] * N[2]);
}

void
MassSpringSystem::StepEulerFused(bool symplectic)
{
  // One parallel pass per step: force, velocity and position of each particle, with its
  // lock and collision, into a second position buffer (neighbours read the old positions),
  // then the buffers swap. Used when no force reads the neighbours' velocities.
  if (!m_AdjacencyValid)
  {
    BuildAdjacency();
  }
  std::vector<double> & next = m_Scratch[1];
  next.resize(m_X.size());
  const double *     x = m_X.data();
  double *           xn = next.data();
  double *           v = m_V.data();
  const double       h = m_TimeStep;
  const double       c = m_Damping;
  const Vector3      g = m_Gravity;
  const uint64_t *   start = m_AdjacencyStart.data();
  const Neighbour *  adjacency = m_Adjacency.data();
  const double *     masses = m_Masses.data();
  const uint8_t *    locked = m_Locked.data();
  const PlaneContact plane = MakePlaneContact(m_HasPlane, m_PlanePoint, m_PlaneNormal, m_Restitution, RestingSpeed());
  ParallelFor(m_Masses.size(), [=](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
    {
      double *       vi = v + 3 * i;
      double *       xni = xn + 3 * i;
      const double * xi = x + 3 * i;
      if (locked[i])
      {
        vi[0] = vi[1] = vi[2] = 0.0;
        xni[0] = xi[0];
        xni[1] = xi[1];
        xni[2] = xi[2];
        continue;
      }
      double f[3];
      GatherSpringForce(i, x, v, start, adjacency, 0.0, f);
      const double invM = 1.0 / masses[i];
      for (int d = 0; d < 3; ++d)
      {
        const double a = f[d] * invM + g[d] - c * vi[d];
        if (symplectic)
        {
          vi[d] += h * a;
          xni[d] = xi[d] + h * vi[d];
        }
        else
        {
          xni[d] = xi[d] + h * vi[d];
          vi[d] += h * a;
        }
      }
      if (plane.HasPlane)
      {
        plane.Collide(xni, vi);
      }
    }
  });
  ++m_ForceEvaluations;
  m_X.swap(next);
}

void
MassSpringSystem::StepExplicit()
{
  const size_t n3 = m_X.size();
  const double h = m_TimeStep;
  double *     x = m_X.data();
  double *     v = m_V.data();
  for (auto & s : m_Scratch)
  {
    s.resize(n3);
  }
  double * a1 = m_Scratch[0].data();
  switch (m_Integrator)
  {
    case MassSpringIntegratorEnum::ExplicitEuler:
    case MassSpringIntegratorEnum::SymplecticEuler:
    {
      const bool symplectic = m_Integrator == MassSpringIntegratorEnum::SymplecticEuler;
      if (m_SpringDamping <= 0.0)
      {
        StepEulerFused(symplectic);
        return;
      }
      Accelerations(x, v, a1);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          if (symplectic)
          {
            v[k] += h * a1[k];
            x[k] += h * v[k];
          }
          else
          {
            x[k] += h * v[k];
            v[k] += h * a1[k];
          }
        }
      });
      break;
    }
    case MassSpringIntegratorEnum::Midpoint:
    {
      double * xm = m_Scratch[1].data();
      double * vm = m_Scratch[2].data();
      double * a2 = m_Scratch[3].data();
      Accelerations(x, v, a1);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          xm[k] = x[k] + 0.5 * h * v[k];
          vm[k] = v[k] + 0.5 * h * a1[k];
        }
      });
      Accelerations(xm, vm, a2);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          x[k] += h * vm[k];
          v[k] += h * a2[k];
        }
      });
      break;
    }
    case MassSpringIntegratorEnum::RungeKutta4:
    {
      double * xs = m_Scratch[1].data();
      double * vs = m_Scratch[2].data();
      double * a2 = m_Scratch[3].data();
      double * a3 = m_Scratch[4].data();
      double * a4 = m_Scratch[5].data();
      double * v2 = m_Scratch[6].data();
      double * v3 = m_Scratch[7].data();
      Accelerations(x, v, a1);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          v2[k] = v[k] + 0.5 * h * a1[k];
          xs[k] = x[k] + 0.5 * h * v[k];
        }
      });
      Accelerations(xs, v2, a2);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          v3[k] = v[k] + 0.5 * h * a2[k];
          xs[k] = x[k] + 0.5 * h * v2[k];
        }
      });
      Accelerations(xs, v3, a3);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          vs[k] = v[k] + h * a3[k];
          xs[k] = x[k] + h * v3[k];
        }
      });
      Accelerations(xs, vs, a4);
      ParallelFor(n3 / 3, [=](size_t begin, size_t end) {
        for (size_t k = 3 * begin; k < 3 * end; ++k)
        {
          x[k] += h / 6.0 * (v[k] + 2.0 * v2[k] + 2.0 * v3[k] + vs[k]);
          v[k] += h / 6.0 * (a1[k] + 2.0 * a2[k] + 2.0 * a3[k] + a4[k]);
        }
      });
      break;
    }
    case MassSpringIntegratorEnum::ImplicitEuler:
      break;
  }
  ApplyConstraintsAndCollisions(x, v);
}

void
MassSpringSystem::StepImplicit(bool quasiStatic)
{
  using SparseMatrix = ImplicitSolver::SparseMatrix;
  if (!m_AdjacencyValid)
  {
    BuildAdjacency();
  }
  const size_t     n = m_Masses.size();
  const double     h = m_TimeStep;
  const double     invH2 = 1.0 / (h * h);
  ImplicitSolver & solver = *m_Solver;
  if (!solver.valid)
  {
    solver.freeIndex.assign(n, -1);
    solver.freeParticles.clear();
    for (size_t i = 0; i < n; ++i)
    {
      if (!m_Locked[i])
      {
        solver.freeIndex[i] = static_cast<int32_t>(solver.freeParticles.size());
        solver.freeParticles.push_back(static_cast<uint32_t>(i));
      }
    }
    const auto                          nf = static_cast<Eigen::Index>(solver.freeParticles.size());
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(nf + 4 * m_SpringI.size());
    for (Eigen::Index r = 0; r < nf; ++r)
    {
      triplets.emplace_back(r, r, m_Masses[solver.freeParticles[r]] * invH2);
    }
    for (size_t s = 0; s < m_SpringI.size(); ++s)
    {
      const int32_t a = solver.freeIndex[m_SpringI[s]];
      const int32_t b = solver.freeIndex[m_SpringJ[s]];
      const double  k = m_Stiffness[s];
      if (a >= 0)
      {
        triplets.emplace_back(a, a, k);
      }
      if (b >= 0)
      {
        triplets.emplace_back(b, b, k);
      }
      if (a >= 0 && b >= 0)
      {
        triplets.emplace_back(a, b, -k);
        triplets.emplace_back(b, a, -k);
      }
    }
    SparseMatrix A(nf, nf);
    A.setFromTriplets(triplets.begin(), triplets.end());
    solver.ldlt.compute(A);
    if (solver.ldlt.info() != Eigen::Success)
    {
      itkGenericExceptionMacro(<< "MassSpringSystem: factorisation of the implicit system failed");
    }
    solver.timeStep = h;
    solver.valid = true;
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
    // A sheet lying on a coordinate plane (the final relaxation) has a zero column: skip it.
    for (int d = 0; d < 3; ++d)
    {
      if (rhs.col(d).isZero(0.0))
      {
        solution.col(d).setZero();
      }
      else
      {
        solution.col(d) = solver.ldlt.solve(rhs.col(d));
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

double
MassSpringSystem::ComputeKineticEnergy() const
{
  double e = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    const double * v = &m_V[3 * i];
    e += 0.5 * m_Masses[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
  return e;
}

double
MassSpringSystem::ComputeSpringEnergy() const
{
  double e = 0.0;
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    const double * a = &m_X[3 * m_SpringI[s]];
    const double * b = &m_X[3 * m_SpringJ[s]];
    const double   len =
      std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    const double stretch = len - m_RestLength[s];
    e += 0.5 * m_Stiffness[s] * stretch * stretch;
  }
  return e;
}

double
MassSpringSystem::ComputeGravityEnergy() const
{
  double e = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    const double * x = &m_X[3 * i];
    e -= m_Masses[i] * (m_Gravity[0] * x[0] + m_Gravity[1] * x[1] + m_Gravity[2] * x[2]);
  }
  return e;
}

double
MassSpringSystem::TotalEnergy() const
{
  return ComputeKineticEnergy() + ComputeSpringEnergy() + ComputeGravityEnergy();
}

double
MassSpringSystem::GetMeanStiffness() const
{
  return m_Stiffness.empty() ? 0.0 : std::accumulate(m_Stiffness.begin(), m_Stiffness.end(), 0.0) / m_Stiffness.size();
}

double
MassSpringSystem::GetMeanRestLength() const
{
  return m_RestLength.empty() ? 0.0
                              : std::accumulate(m_RestLength.begin(), m_RestLength.end(), 0.0) / m_RestLength.size();
}

double
MassSpringSystem::GetMeanMass() const
{
  return m_Masses.empty() ? 0.0 : std::accumulate(m_Masses.begin(), m_Masses.end(), 0.0) / m_Masses.size();
}

double
MassSpringSystem::EstimateMaximumAngularFrequency() const
{
  std::vector<double> rowSum(m_Masses.size(), 0.0);
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    rowSum[m_SpringI[s]] += 2.0 * m_Stiffness[s];
    rowSum[m_SpringJ[s]] += 2.0 * m_Stiffness[s];
  }
  double w2 = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    w2 = std::max(w2, rowSum[i] / m_Masses[i]);
  }
  return std::sqrt(w2);
}

double
MassSpringSystem::ComputeRelativeResidualForce()
{
  std::vector<double> zero(m_V.size(), 0.0), a(m_V.size());
  Accelerations(m_X.data(), zero.data(), a.data());
  --m_ForceEvaluations; // an analysis, not a simulation step
  double       sum = 0.0;
  size_t       count = 0;
  const double contactDepth = 1e-9 * GetMeanRestLength();
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    if (m_Locked[i])
    {
      continue;
    }
    double f[3] = { a[3 * i] * m_Masses[i], a[3 * i + 1] * m_Masses[i], a[3 * i + 2] * m_Masses[i] };
    if (m_HasPlane)
    {
      const double * x = &m_X[3 * i];
      const double   depth = (x[0] - m_PlanePoint[0]) * m_PlaneNormal[0] + (x[1] - m_PlanePoint[1]) * m_PlaneNormal[1] +
                           (x[2] - m_PlanePoint[2]) * m_PlaneNormal[2];
      const double fn = f[0] * m_PlaneNormal[0] + f[1] * m_PlaneNormal[1] + f[2] * m_PlaneNormal[2];
      // The plane carries what pushes a resting particle into it.
      if (depth <= contactDepth && fn < 0.0)
      {
        for (int d = 0; d < 3; ++d)
        {
          f[d] -= fn * m_PlaneNormal[d];
        }
      }
    }
    sum += f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    ++count;
  }
  const double scale = GetMeanStiffness() * GetMeanRestLength();
  return count > 0 && scale > 0.0 ? std::sqrt(sum / count) / scale : 0.0;
}

double
MassSpringSystem::ComputeRelativeKineticEnergy() const
{
  double scale = 0.0;
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    scale += 0.5 * m_Stiffness[s] * m_RestLength[s] * m_RestLength[s];
  }
  return scale > 0.0 ? ComputeKineticEnergy() / scale : 0.0;
}

std::string
MassSpringSystem::Describe() const
{
  std::ostringstream os;
  os << "integrator " << ToString(m_Integrator) << ", step " << m_Steps << ", time step " << m_TimeStep;
  const double w = EstimateMaximumAngularFrequency();
  os << " (w_max h = " << w * m_TimeStep << ")";
  return os.str();
}

void
MassSpringSystem::CheckDivergence()
{
  for (size_t k = 0; k < m_X.size(); ++k)
  {
    if (!std::isfinite(m_X[k]) || !std::isfinite(m_V[k]))
    {
      throw MassSpringDivergenceError("mass-spring simulation diverged (non-finite state) with " + Describe());
    }
  }
  const double energy = TotalEnergy();
  if (energy - m_InitialEnergy > m_EnergyGrowthLimit * m_EnergyReference)
  {
    std::ostringstream os;
    os << "mass-spring simulation diverged (energy grew from " << m_InitialEnergy << " to " << energy << ", beyond "
       << m_EnergyGrowthLimit << " times the energy scale " << m_EnergyReference << ") with " << Describe();
    throw MassSpringDivergenceError(os.str());
  }
}

void
MassSpringSystem::Step()
{
  if (m_Masses.empty())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: no particles");
  }
  if (!m_EnergyReferenceValid)
  {
    // Energy scale: what the springs, the motion and gravity across the system's extent can
    // hold; total energy may not grow beyond a multiple of it.
    double lo[3] = { m_X[0], m_X[1], m_X[2] }, hi[3] = { m_X[0], m_X[1], m_X[2] };
    for (size_t i = 0; i < m_Masses.size(); ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        lo[d] = std::min(lo[d], m_X[3 * i + d]);
        hi[d] = std::max(hi[d], m_X[3 * i + d]);
      }
    }
    const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                      (hi[2] - lo[2]) * (hi[2] - lo[2]));
    const double g = std::sqrt(m_Gravity[0] * m_Gravity[0] + m_Gravity[1] * m_Gravity[1] + m_Gravity[2] * m_Gravity[2]);
    double       springScale = 0.0;
    for (size_t s = 0; s < m_SpringI.size(); ++s)
    {
      springScale += 0.5 * m_Stiffness[s] * m_RestLength[s] * m_RestLength[s];
    }
    const double totalMass = std::accumulate(m_Masses.begin(), m_Masses.end(), 0.0);
    m_InitialEnergy = TotalEnergy();
    m_EnergyReference = ComputeSpringEnergy() + ComputeKineticEnergy() + totalMass * g * diagonal +
                        1e-6 * (springScale + std::abs(m_InitialEnergy)) + std::numeric_limits<double>::min();
    m_EnergyReferenceValid = true;
  }
  if (m_Integrator == MassSpringIntegratorEnum::ImplicitEuler)
  {
    StepImplicit(false);
  }
  else
  {
    StepExplicit();
  }
  ++m_Steps;
  if (m_Steps % m_DivergenceCheckInterval == 0)
  {
    CheckDivergence();
  }
}

} // end namespace itk

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
#include "vuImplicitSolver.h"
#include "vuSinglePrecisionState.h"

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
  itkGenericExceptionMacro(<< "unknown integrator '" << name
                           << "' (euler, midpoint, rk4, symplectic-euler, implicit-euler)");
}

MassSpringSystem::MassSpringSystem()
  : m_Solver(new ImplicitSolver)
  , m_Single(new SinglePrecisionState)
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
  DoubleStateChanged();
  m_Single->springsValid = false;
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
  m_Solver->analysed = false;
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
  m_Single->springsValid = false;
  m_Solver->valid = false;
  m_Solver->analysed = false;
  m_EnergyReferenceValid = false;
}

void
MassSpringSystem::SetPositions(const std::vector<double> & positions)
{
  if (positions.size() != m_X.size())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: SetPositions needs " << m_X.size() << " coordinates");
  }
  SyncState();
  DoubleStateChanged();
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
  SyncState();
  DoubleStateChanged();
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
    m_Solver->analysed = false;
    m_EnergyReferenceValid = false;
  }
  if (locked)
  {
    SyncState();
    DoubleStateChanged();
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
    m_Solver->analysed = false;
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
MassSpringSystem::SetRestitution(double restitution)
{
  if (!(restitution >= 0.0 && restitution <= 1.0))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: restitution must lie in [0, 1], got " << restitution);
  }
  m_Restitution = restitution;
}

void
MassSpringSystem::ScaleStiffnesses(double factor)
{
  if (!(factor > 0.0) || !std::isfinite(factor))
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: a stiffness factor must be a finite number > 0, got " << factor);
  }
  SyncState();
  for (double & k : m_Stiffness)
  {
    k *= factor;
  }
  m_AdjacencyValid = false;
  m_Single->springsValid = false;
  m_Solver->valid = false;
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
  m_Solver->Threader(m_NumberOfWorkUnits)
    ->ParallelizeArray(
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
MassSpringSystem::Step()
{
  if (m_Masses.empty())
  {
    itkGenericExceptionMacro(<< "MassSpringSystem: no particles");
  }
  const bool single = UsesSinglePrecisionStep();
  if (!single)
  {
    SyncState();
  }
  if (!m_EnergyReferenceValid)
  {
    SyncState();
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
  if (single)
  {
    StepEulerSingle(m_Integrator == MassSpringIntegratorEnum::SymplecticEuler);
  }
  else
  {
    if (m_Integrator == MassSpringIntegratorEnum::ImplicitEuler)
    {
      StepImplicit(false);
    }
    else
    {
      StepExplicit();
    }
    DoubleStateChanged();
  }
  ++m_Steps;
  if (m_Steps % m_DivergenceCheckInterval == 0)
  {
    CheckDivergence();
  }
}

} // end namespace itk

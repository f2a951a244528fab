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
#ifndef itkMassSpringSystem_h
#define itkMassSpringSystem_h

#include "VirtualUnwrappingExport.h"
#include "itkMacro.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace itk {
/** \class MassSpringSystemEnums
 * \brief Enumerations of MassSpringSystem, nested in a class the way ITK wraps them.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT MassSpringSystemEnums
{
public:
  /** Integrators of the mass-spring system. */
  enum class Integrator : uint8_t
  {
    /** Forward (explicit) Euler: x += h v(t), v += h a(t). Grows at every time step without damping. */
    ExplicitEuler,
    /** Explicit midpoint (second-order Runge-Kutta). Grows at every time step without damping. */
    Midpoint,
    /** Classical fourth-order Runge-Kutta: stable for w h < 2.83 on an undamped spring mode. */
    RungeKutta4,
    /** Semi-implicit (symplectic) Euler: v += h a(t), x += h v(t+h). Stable for w h < 2. */
    SymplecticEuler,
    /** Implicit Euler solved by the local/global method of Liu et al. 2013 with a prefactored
     * sparse Cholesky (LDLT) system: unconditionally stable. */
    ImplicitEuler
  };
};
/** Shorter name used throughout the module. */
using MassSpringIntegratorEnum = MassSpringSystemEnums::Integrator;

/** Name of an integrator as the tool and the reports spell it. */
VirtualUnwrapping_EXPORT const char *
ToString(MassSpringIntegratorEnum integrator);
/** Inverse of ToString; throws itk::ExceptionObject for an unknown name. */
VirtualUnwrapping_EXPORT MassSpringIntegratorEnum
MassSpringIntegratorFromString(const std::string & name);

/** Thrown when a run diverges: non-finite state, energy growth beyond the bound, or springs
 * stretched beyond any physical state. The message names the integrator, the step and the
 * time step. */
class VirtualUnwrapping_EXPORT MassSpringDivergenceError : public ExceptionObject
{
public:
  /** The message is the description (what() is the description alone, one line). */
  explicit MassSpringDivergenceError(const std::string & message)
    : ExceptionObject(__FILE__, __LINE__, message, "MassSpringSystem")
  {}
  const char *
  what() const noexcept override
  {
    return this->GetDescription();
  }
  const char *
  GetNameOfClass() const override
  {
    return "MassSpringDivergenceError";
  }
};

/** \class MassSpringSystem
 * \brief The simulation engine: particles joined by Hooke springs, integrated in time.
 *
 * The paper's particle system (Seales and Lin 2004): particles with mass, position and
 * velocity; ideal springs with rest length and stiffness; forces
 * F = F_springs + F_damping + m G; state [X, V] with X' = V, V' = F / m. Locked particles
 * keep their position (a constraint force cancels whatever acts on them, so it does no
 * work). An optional collision plane (point P, unit normal N) reflects particles that
 * cross it: V_new = V_old - (1 + k_r)(V_old . N) N, restitution k_r in [0, 1]; a rebound
 * slower than twice what gravity adds in one step ends in resting contact (k_r = 0).
 *
 * Damping: viscous drag -c m V on every particle (GetDamping, 1/s, >= 0) and spring
 * damping along each spring, c_s ((V_j - V_i) . d) d / |d|^2 scaled by the spring's
 * stiffness (GetSpringDamping, s, >= 0).
 *
 * Integrators: see MassSpringIntegratorEnum. The implicit one minimises
 * |x - y|_M^2 / (2 h^2) + E_springs(x) with y = x_n + h v_n + h^2 G (Liu, Bargteil, O'Brien
 * and Kavan, "Fast Simulation of Mass-Spring Systems", ACM TOG 32(6), 2013): a local step
 * projects each spring to its rest length, a global step solves (M + h^2 L) x = b with a
 * sparse LDLT factorisation computed once per (time step, stiffness, locked set).
 * Integrator, time step, damping, gravity, locked particles and plane can all change
 * between steps.
 *
 * Forces are gathered per particle (each particle sums its own springs), so the force loop
 * runs on all threads without atomics; each spring is thus evaluated from both ends.
 * Keep neighbouring particles close in memory (grid order) for speed.
 *
 * Divergence: every GetDivergenceCheckInterval() steps (default 1) the state is checked
 * for non-finite values and for total mechanical energy (kinetic + spring + gravity, which
 * damping, collisions and constraints can only lower) growing beyond
 * GetEnergyGrowthLimit() (default 100: a stable symplectic Euler run near
 * its bound swings its measured energy by 1 / (1 - (w h / 2)^2), 10 times at w h = 1.9) times the system's energy scale
 * (spring and kinetic energy plus total weight times extent, taken when the settings last changed); either throws
 * MassSpringDivergenceError and leaves the diverged state for inspection.
 *
 * Not an itk::Object: a plain engine shared by MassSpringFlatteningMeshFilter, the viewer
 * and the benchmarks.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT MassSpringSystem
{
public:
  using Vector3 = std::array<double, 3>;

  MassSpringSystem();
  ~MassSpringSystem();
  MassSpringSystem(const MassSpringSystem &) = delete;
  MassSpringSystem &
  operator=(const MassSpringSystem &) = delete;

  /** Particles: positions (x, y, z per particle) and masses (> 0). Clears springs and
   * velocities. */
  void
  SetParticles(const std::vector<double> & positions, const std::vector<double> & masses);
  /** Adds a spring between particles i and j; rest length >= 0, stiffness > 0. */
  void
  AddSpring(uint32_t i, uint32_t j, double restLength, double stiffness);

  size_t
  GetNumberOfParticles() const
  {
    return m_Masses.size();
  }
  size_t
  GetNumberOfSprings() const
  {
    return m_SpringI.size();
  }

  /** The springs: end particles, rest lengths and stiffnesses, in the order added. */
  const std::vector<uint32_t> &
  GetSpringFirstParticles() const
  {
    return m_SpringI;
  }
  const std::vector<uint32_t> &
  GetSpringSecondParticles() const
  {
    return m_SpringJ;
  }
  const std::vector<double> &
  GetSpringRestLengths() const
  {
    return m_RestLength;
  }
  const std::vector<double> &
  GetSpringStiffnesses() const
  {
    return m_Stiffness;
  }

  const std::vector<double> &
  GetPositions() const
  {
    SyncState();
    return m_X;
  }
  const std::vector<double> &
  GetVelocities() const
  {
    SyncState();
    return m_V;
  }
  const std::vector<double> &
  GetMasses() const
  {
    return m_Masses;
  }
  /** Replaces positions (same count); velocities are kept. */
  void
  SetPositions(const std::vector<double> & positions);
  void
  SetVelocities(const std::vector<double> & velocities);

  void
  SetLocked(uint32_t particle, bool locked);
  void
  SetLockedParticles(const std::vector<uint32_t> & particles);
  void
  UnlockAll();
  bool
  IsLocked(uint32_t particle) const
  {
    return m_Locked[particle] != 0;
  }
  size_t
  GetNumberOfLockedParticles() const;

  void
  SetGravity(const Vector3 & g)
  {
    m_Gravity = g;
  }
  const Vector3 &
  GetGravity() const
  {
    return m_Gravity;
  }
  void
  SetDamping(double c);
  double
  GetDamping() const
  {
    return m_Damping;
  }
  void
  SetSpringDamping(double c);
  double
  GetSpringDamping() const
  {
    return m_SpringDamping;
  }

  /** Collision plane through point with the given normal (normalised here); particles are
   * kept on the side the normal points to. */
  void
  SetCollisionPlane(const Vector3 & point, const Vector3 & normal, double restitution);
  void
  RemoveCollisionPlane()
  {
    m_HasPlane = false;
  }
  bool
  HasCollisionPlane() const
  {
    return m_HasPlane;
  }
  /** Restitution k_r of the collision plane, in [0, 1] (changeable between steps). */
  void
  SetRestitution(double restitution);
  double
  GetRestitution() const
  {
    return m_Restitution;
  }

  /** Multiplies every spring's stiffness by factor > 0 (between steps; the sparse
   * factorisation of the implicit solver is redone, its analysis kept). */
  void
  ScaleStiffnesses(double factor);

  void
  SetIntegrator(MassSpringIntegratorEnum integrator)
  {
    m_Integrator = integrator;
  }
  MassSpringIntegratorEnum
  GetIntegrator() const
  {
    return m_Integrator;
  }
  void
  SetTimeStep(double h);
  double
  GetTimeStep() const
  {
    return m_TimeStep;
  }
  /** Local/global iterations per implicit step (default 10, >= 1). */
  void
  SetImplicitIterations(unsigned int n);
  unsigned int
  GetImplicitIterations() const
  {
    return m_ImplicitIterations;
  }
  void
  SetEnergyGrowthLimit(double factor)
  {
    m_EnergyGrowthLimit = factor;
  }
  double
  GetEnergyGrowthLimit() const
  {
    return m_EnergyGrowthLimit;
  }
  /** Check for divergence every n steps (default 1, >= 1); larger values save a pass over
   * the springs per step in long explicit runs. */
  void
  SetDivergenceCheckInterval(unsigned int n)
  {
    m_DivergenceCheckInterval = n > 0 ? n : 1;
  }

  /** Advances the state by one time step with the current integrator. Throws
   * MassSpringDivergenceError when the state diverges. */
  void
  Step();

  /** Quasi-static relaxation: local/global iterations of the implicit solver without
   * inertia (each minimises the spring energy around the current positions, regularised
   * by M / h^2 with the current time step), velocities zeroed. For the final relaxation of
   * a flattened sheet; gravity and the plane apply as in Step(). */
  void
  Relax(unsigned int iterations);

  /** Steps taken since SetParticles(). */
  uint64_t
  GetNumberOfSteps() const
  {
    return m_Steps;
  }
  /** Force evaluations (of all springs) since SetParticles(); an RK4 step counts four. */
  uint64_t
  GetNumberOfForceEvaluations() const
  {
    return m_ForceEvaluations;
  }

  double
  ComputeKineticEnergy() const;
  double
  ComputeSpringEnergy() const;
  /** Gravitational potential energy, relative to the origin: -sum m G . x. */
  double
  ComputeGravityEnergy() const;
  /** RMS of the net force on free particles, excluding the plane's normal direction for
   * particles resting on the collision plane, divided by the mean spring force scale
   * (mean stiffness times mean rest length): dimensionless. */
  double
  ComputeRelativeResidualForce();
  /** Kinetic energy divided by the spring energy scale sum(k L^2) / 2: dimensionless. */
  double
  ComputeRelativeKineticEnergy() const;

  /** Mean stiffness, mean rest length and mean mass: scales for tolerances and steps. */
  double
  GetMeanStiffness() const;
  double
  GetMeanRestLength() const;
  double
  GetMeanMass() const;
  /** Upper bound of the highest angular frequency of the undamped system (rad/s): from
   * Gershgorin's theorem on M^-1 K, sqrt(max_i sum_springs 2 k / m_i). */
  double
  EstimateMaximumAngularFrequency() const;

  /** Accelerations for a given state (3 per particle), for tests and analysis. */
  void
  ComputeAccelerations(const std::vector<double> & x, const std::vector<double> & v, std::vector<double> & a);

  /** Maximum number of threads for the force loop (0 = ITK's global default). */
  void
  SetNumberOfWorkUnits(unsigned int n);

  /** Single precision for the explicit and symplectic Euler steps (without spring
   * damping): the state is stepped in float, structure of arrays, with each spring computed
   * once (vu::BandedSprings), about four times the double-precision loop's throughput on a
   * grid-numbered sheet. Off by default. Positions in float carry an absolute error of
   * about 6e-8 of the sheet's extent, so this suits the unrolling and interactive work,
   * not strains below about 1e-5 on fine meshes (docs/flattening.md gives the measured
   * difference from the double-precision trajectory). The double-precision state is
   * brought up to date whenever it is read (GetPositions, the energies, a divergence
   * check): with a check every step that costs a conversion per step, so raise
   * SetDivergenceCheckInterval for long runs. */
  void
  SetSinglePrecision(bool on);
  bool
  GetSinglePrecision() const
  {
    return m_SinglePrecision;
  }

private:
  void
  BuildAdjacency();
  void
  Accelerations(const double * x, const double * v, double * a);
  void
  ApplyConstraintsAndCollisions(double * x, double * v);
  double
  RestingSpeed() const;
  void
  StepEulerFused(bool symplectic);
  void
  StepEulerSingle(bool symplectic);
  bool
  UsesSinglePrecisionStep() const;
  /** Brings the double-precision state up to date with the single-precision one. */
  void
  SyncState() const;
  /** The double-precision state changed: the single-precision copy must be reloaded. */
  void
  DoubleStateChanged();
  void
  CheckDivergence();
  void
  StepExplicit();
  void
  StepImplicit(bool quasiStatic);
  void
  ParallelFor(size_t n, const std::function<void(size_t, size_t)> & body);
  double
  TotalEnergy() const;
  std::string
  Describe() const;

  // Particles (structure of arrays); mutable for SyncState().
  mutable std::vector<double> m_X;
  mutable std::vector<double> m_V;
  std::vector<double>         m_Masses;
  std::vector<uint8_t>        m_Locked;

  // Springs.
  std::vector<uint32_t> m_SpringI;
  std::vector<uint32_t> m_SpringJ;
  std::vector<double>   m_RestLength;
  std::vector<double>   m_Stiffness;

  // Per-particle adjacency (CSR) for the gathered force loop.
  struct Neighbour
  {
    uint32_t other;
    float    restLength;
    float    stiffness;
  };
  std::vector<uint64_t>  m_AdjacencyStart;
  std::vector<Neighbour> m_Adjacency;
  bool                   m_AdjacencyValid{ false };

  Vector3 m_Gravity{ { 0.0, 0.0, 0.0 } };
  double  m_Damping{ 0.0 };
  double  m_SpringDamping{ 0.0 };

  bool    m_HasPlane{ false };
  Vector3 m_PlanePoint{ { 0.0, 0.0, 0.0 } };
  Vector3 m_PlaneNormal{ { 0.0, 0.0, 1.0 } };
  double  m_Restitution{ 0.1 };

  MassSpringIntegratorEnum m_Integrator{ MassSpringIntegratorEnum::ImplicitEuler };
  double                   m_TimeStep{ 1e-3 };
  unsigned int             m_ImplicitIterations{ 10 };
  double                   m_EnergyGrowthLimit{ 100.0 };
  unsigned int             m_DivergenceCheckInterval{ 1 };
  double                   m_EnergyReference{ 0.0 };
  double                   m_InitialEnergy{ 0.0 };
  bool                     m_EnergyReferenceValid{ false };
  unsigned int             m_NumberOfWorkUnits{ 0 };

  uint64_t m_Steps{ 0 };
  uint64_t m_ForceEvaluations{ 0 };

  // Scratch buffers for the explicit integrators.
  std::vector<double> m_Scratch[8];

  // Prefactored implicit system (Eigen lives only in the .cxx).
  struct ImplicitSolver;
  std::unique_ptr<ImplicitSolver> m_Solver;

  // The single-precision state and banded springs of the float Euler step.
  bool m_SinglePrecision{ false };
  struct SinglePrecisionState;
  std::unique_ptr<SinglePrecisionState> m_Single;
};

} // end namespace itk

#endif

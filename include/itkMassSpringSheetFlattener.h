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
#ifndef itkMassSpringSheetFlattener_h
#define itkMassSpringSheetFlattener_h

#include "VirtualUnwrappingExport.h"
#include "itkMassSpringSystem.h"
#include "itkSheetMesh.h"

#include <cfloat>
#include <climits>
#include <functional>
#include <string>
#include <vector>

namespace itk {
/** \class MassSpringSheetFlattenerEnums
 * \brief Enumerations of MassSpringSheetFlattener, nested in a class the way ITK wraps them.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT MassSpringSheetFlattenerEnums
{
public:
  /** Which particles the unroll phase holds. */
  enum class LockedEdge : uint8_t
  {
    /** Nothing held: no unroll phase, the sheet is only dropped onto the plane. */
    None,
    /** Grid meshes: the end column (constant arc length) farther from the roll's axis. */
    OuterEdge,
    /** Grid meshes: the end column nearer the roll's axis. */
    InnerEdge,
    /** The particles listed in MassSpringFlatteningParameters::LockedParticles. */
    Custom,
    /** OuterEdge on a grid mesh (a rolled sheet's mid-surface), None on any other mesh. */
    Auto
  };
  /** The phases of a flattening, in order; RelaxFull is the relaxation of the full mesh
   * after a coarse-to-fine run. */
  enum class Phase : uint8_t
  {
    Unroll,
    Flatten,
    Relax,
    RelaxFull
  };
};
/** Shorter name used throughout the module. */
using SheetLockedEdgeEnum = MassSpringSheetFlattenerEnums::LockedEdge;
VirtualUnwrapping_EXPORT const char *
ToString(SheetLockedEdgeEnum edge);
VirtualUnwrapping_EXPORT SheetLockedEdgeEnum
SheetLockedEdgeFromString(const std::string & name);
using SheetFlatteningPhaseEnum = MassSpringSheetFlattenerEnums::Phase;
/** "unroll", "flatten", "relax", "relax-full". */
VirtualUnwrapping_EXPORT const char *
ToString(SheetFlatteningPhaseEnum phase);

/** The simulation's numeric parameters, one line each:
 *   X(type, Name, default, lowest, highest, "tool-option", "report_key", "meaning").
 * Lengths in the mesh's units (mm), times in seconds of simulated time; a value of 0 where
 * "automatic" is said picks it from the mesh (see MassSpringSheetFlattener). The members of
 * MassSpringFlatteningParameters, MassSpringFlatteningMeshFilter's Set/Get methods (which
 * clamp to [lowest, highest]) and its PrintSelf, and the command-line tool's options and
 * report are all made from this list: a new parameter is a line here and its use in the
 * simulation. */
// clang-format off
#define VU_MASS_SPRING_PARAMETERS(X)                                                                            \
  X(double, TimeStep, 0.0, 0.0, DBL_MAX, "time-step", "time_step",                                              \
    "simulation time step in seconds; 0: automatic (explicit: --time-step-safety times the "                    \
    "stability bound; implicit: the fall time divided by --steps-per-fall)")                                    \
  X(double, TimeStepSafety, 0.5, 1e-6, 100.0, "time-step-safety", "time_step_safety",                           \
    "automatic explicit step as a fraction of its linear stability bound")                                      \
  X(double, StepsPerFallTime, 40.0, 1e-3, DBL_MAX, "steps-per-fall", "steps_per_fall_time",                     \
    "automatic implicit step: the fall time (the sheet falling its own length) divided by this")                \
  X(double, Stiffness, 1.0, 1e-12, DBL_MAX, "stiffness", "stiffness",                                           \
    "stiffness of a structural spring of mean length; a spring of rest length L gets stiffness "                \
    "* mean / L")                                                                                               \
  X(double, ShearStiffnessRatio, 0.5, 0.0, DBL_MAX, "shear", "shear_stiffness_ratio",                           \
    "shear springs' stiffness (across each pair of triangles sharing an edge) relative to "                     \
    "structural; 0: off")                                                                                       \
  X(double, BendingStiffnessRatio, 0.0, 0.0, DBL_MAX, "bending", "bending_stiffness_ratio",                     \
    "bending springs' stiffness (grid meshes: every other particle along rows and columns) "                    \
    "relative to structural; 0: off")                                                                           \
  X(double, Density, 1.0, 1e-12, DBL_MAX, "density", "density",                                                 \
    "mass per unit area")                                                                                       \
  X(double, Gravity, 0.0, 0.0, DBL_MAX, "gravity", "gravity",                                                   \
    "gravity magnitude; 0: automatic (see --hanging-strain)")                                                   \
  X(double, HangingStrain, 0.01, 1e-9, 1.0, "hanging-strain", "hanging_strain",                                 \
    "automatic gravity stretches a hanging row by about this strain")                                           \
  X(double, Damping, -1.0, -DBL_MAX, DBL_MAX, "damping", "damping",                                             \
    "viscous damping (1/s); negative: automatic (2 / fall time)")                                               \
  X(double, SpringDamping, 0.0, 0.0, DBL_MAX, "spring-damping", "spring_damping",                               \
    "damping along springs (s), relative to their stiffness")                                                   \
  X(double, Restitution, 0.1, 0.0, 1.0, "restitution", "restitution",                                           \
    "collision restitution k_r in [0, 1] (the paper: 0.1)")                                                     \
  X(unsigned int, MaximumStepsPerPhase, 3000, 1, UINT_MAX, "max-steps", "max_steps_per_phase",                  \
    "step limit of the unroll and of the flatten phase")                                                        \
  X(double, KineticEnergyTolerance, 1e-9, 0.0, DBL_MAX, "kinetic-energy-tolerance", "kinetic_energy_tolerance", \
    "unroll and flatten phases converge when the relative kinetic energy stays below this at "                  \
    "three checks in a row (every 10 steps)")                                                                   \
  X(double, ResidualForceTolerance, 1e-3, 0.0, DBL_MAX, "residual-force-tolerance", "residual_force_tolerance", \
    "unroll and flatten phases converge when, besides the kinetic energy, the relative residual "               \
    "force is below this")                                                                                      \
  X(double, PlanarityTolerance, 0.25, 1e-9, DBL_MAX, "planarity-tolerance", "planarity_tolerance",              \
    "the unroll phase ends only when the sheet hangs in a plane: RMS distance from its plane "                  \
    "below this fraction of the mean spring length, and no triangle turned over")                               \
  X(unsigned int, RelaxationIterations, 300, 1, UINT_MAX, "relaxation-iterations", "relaxation_iterations",     \
    "iteration limit of the quasi-static relaxation on the plane")                                              \
  X(double, RelaxationTolerance, 1e-5, 0.0, DBL_MAX, "relaxation-tolerance", "relaxation_tolerance",            \
    "relaxation on the plane ends at this relative residual force")                                             \
  X(unsigned int, CoarseningFactor, 0, 0, UINT_MAX, "coarsening", "coarsening_factor",                          \
    "grid meshes: simulate every n-th row and column, then relax every particle; 0: automatic "                 \
    "(see --coarse-particles), 1: the full mesh")                                                               \
  X(unsigned int, CoarseParticles, 3000, 4, 1u << 30, "coarse-particles", "coarse_particles",                   \
    "grid meshes, automatic coarsening: simulate at most about this many particles")                            \
  X(unsigned int, StraightenRows, 1, 0, 1, "straighten-rows", "straighten_rows",                                \
    "grid meshes: after relaxing, lay the rows straight (the slow in-plane bend a long strip "                  \
    "keeps; a sheet rolled or folded about an axis develops with straight rows); 0: off")         \
  X(unsigned int, RestartFromDevelopedRows, 1, 0, 1, "restart-from-rows", "restart_from_developed_rows",        \
    "grid meshes: when the flat sheet comes out with triangles turned over, relax it again from "               \
    "its rows developed onto the plane and keep the flat sheet with fewer turned over; 0: off")
// clang-format on

/** Parameters of MassSpringSheetFlattener: the numeric ones of VU_MASS_SPRING_PARAMETERS
 * (defaults and meanings there), the integrator and what the unroll phase holds. */
struct VirtualUnwrapping_EXPORT MassSpringFlatteningParameters
{
#define VU_MASS_SPRING_PARAMETER_MEMBER(type, name, value, lowest, highest, option, key, meaning) type name{ value };
  VU_MASS_SPRING_PARAMETERS(VU_MASS_SPRING_PARAMETER_MEMBER)
#undef VU_MASS_SPRING_PARAMETER_MEMBER
  /** Integrator of the unroll and flatten phases (the final relaxation is always the
   * implicit, quasi-static solver). */
  MassSpringIntegratorEnum Integrator{ MassSpringIntegratorEnum::ImplicitEuler };
  /** Unroll phase: hold an edge and let gravity unfurl the sheet. */
  SheetLockedEdgeEnum   LockedEdge{ SheetLockedEdgeEnum::Auto };
  std::vector<uint32_t> LockedParticles;
  /** Threads for the force loops (0: ITK's default). */
  unsigned int NumberOfWorkUnits{ 0 };
};

/** What a flattening did, phase by phase. */
struct VirtualUnwrapping_EXPORT MassSpringFlatteningReport
{
  struct Phase
  {
    SheetFlatteningPhaseEnum Name{ SheetFlatteningPhaseEnum::Unroll };
    std::string              Integrator;
    double                   TimeStep{ 0.0 };
    uint64_t                 Steps{ 0 };
    std::string              StopReason; // "converged" or "step limit"
    double                   Seconds{ 0.0 };
    double                   RelativeKineticEnergy{ 0.0 };
    double                   RelativeResidualForce{ 0.0 };
  };
  std::vector<Phase> Phases;
  /** What the unroll phase held (Auto resolved). */
  SheetLockedEdgeEnum LockedEdge{ SheetLockedEdgeEnum::None };
  size_t              Particles{ 0 };
  size_t              SimulatedParticles{ 0 };
  size_t              Springs{ 0 };
  unsigned int        CoarseningFactor{ 1 };
  double              Gravity{ 0.0 };
  double              Damping{ 0.0 };
  /** Time for the sheet to fall its own length under the simulation's gravity (s). */
  double   FallTime{ 0.0 };
  uint64_t SpringEvaluations{ 0 };
  double   Seconds{ 0.0 };
  /** Triangles of the flat mesh turned over against the others (where the sheet lies folded
   * onto itself, so that its texture does not read there). */
  size_t FlippedTriangles{ 0 };
  /** The in-plane bend laid straight (StraightenRows): the centre line's largest distance
   * from its chord before, in the mesh's units; 0 when the rows were not straightened. */
  double RowBend{ 0.0 };
  /** Triangles turned over after the physical sequence when it left the sheet folded, so
   * that it was relaxed again from its rows developed onto the plane (0: no restart), and
   * whether that flat mesh, with fewer turned over, was kept. */
  size_t FlippedBeforeRestart{ 0 };
  bool   RestartKept{ false };
  /** What a caller should not miss: phases stopped at their step limit before they
   * converged, triangles turned over; empty when the flattening converged cleanly. */
  std::vector<std::string> Warnings;
};

/** \class MassSpringSheetFlattener
 * \brief Flattens a sheet mesh by the paper's physically based simulation: unroll (hold an
 * edge, let gravity unfurl the sheet), flatten (drop it onto a collision plane), relax.
 *
 * Seales and Lin, "Digital Restoration Using Volumetric Scanning" (2004), section 4. The
 * mesh becomes a MassSpringSystem: particles at vertices with a third of the area of each
 * incident triangle times Density as mass; structural springs along edges, shear springs
 * across each pair of triangles sharing an edge (on grid meshes: the quad's other
 * diagonal), optional bending springs; rest lengths from the 3D mesh.
 *
 * Phases:
 * 1. unroll (when an edge is held): gravity perpendicular to the held edge, pointing from
 *    it to the sheet's centre; the sheet unfurls and hangs; stops when converged or at
 *    MaximumStepsPerPhase;
 * 2. flatten: a collision plane is fitted to the sheet (normal = least principal axis) and
 *    placed under it, gravity turned towards it, everything released; the sheet settles
 *    on the plane (restitution k_r);
 * 3. relax: the sheet is laid on the plane and relaxed quasi-statically with the implicit
 *    solver (in-plane spring projection) until the residual force is below
 *    RelaxationTolerance;
 * 4. straighten (grid meshes, StraightenRows): the slow in-plane bend a long strip keeps
 *    is laid straight, since a sheet rolled or folded about an axis develops with straight
 *    rows (the bend taken out is reported as RowBend);
 * 5. restart (grid meshes that came out with triangles turned over: a long roll whose
 *    unrolling stopped at its step limit lies folded where it was pressed onto the plane):
 *    the sheet's rows are developed onto the plane (SheetMesh::ComputeGridLayout), relaxed from
 *    there on both levels and straightened; the result replaces the first when fewer of
 *    its triangles are turned over (FlippedBeforeRestart, RestartKept).
 * The flat mesh (same points, same triangles, z = 0) is expressed in the plane: x along
 * the sheet (on grid meshes the mean direction of the rows, towards increasing columns,
 * i.e. away from the sheet's start, so that what was written along the sheet runs along
 * x whatever the outline's shape; on other meshes the longest extent), triangles
 * counter-clockwise seen from +z (the side the 3D triangles' normals face), the bounding
 * box starting at (0, 0).
 *
 * Modelling no more than the scene needs: on grid meshes with more than CoarseParticles
 * particles the phases run on a coarser grid (every n-th row and column); the flat
 * positions are carried to the full mesh by harmonic interpolation (a sparse Laplace solve
 * with the simulated particles fixed) and relaxed there.
 *
 * A step callback sees the system after every step (positions for a viewer or snapshots)
 * and may lock or unlock particles, change damping, time step or integrator; returning
 * false aborts with an exception. Divergence throws MassSpringDivergenceError.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT MassSpringSheetFlattener
{
public:
  /** Called after every step: the system, the phase and the step within the phase.
   * Return false to abort. */
  using StepCallback = std::function<bool(MassSpringSystem &, SheetFlatteningPhaseEnum, uint64_t)>;

  void
  SetParameters(const MassSpringFlatteningParameters & parameters)
  {
    m_Parameters = parameters;
  }
  const MassSpringFlatteningParameters &
  GetParameters() const
  {
    return m_Parameters;
  }
  void
  SetStepCallback(StepCallback callback)
  {
    m_Callback = std::move(callback);
  }

  /** Decides when the unroll and flatten phases end: called every ten steps with whether
   * the phase has converged (at rest, small residual force); returning true ends the phase.
   * Unset, a phase ends when it converges. With MaximumStepsPerPhase raised, an
   * interactive program keeps a sheet hanging for as long as the user wants. */
  using PhaseEndCallback = std::function<bool(SheetFlatteningPhaseEnum phase, bool converged)>;
  void
  SetPhaseEndCallback(PhaseEndCallback callback)
  {
    m_PhaseEnd = std::move(callback);
  }

  /** Starts the next Flatten from a saved state of the simulated particles (positions and
   * velocities, 3 per particle, as the step callback saw them) at the start of `phase`
   * (Unroll, or Flatten to skip the unroll): a run resumed from its last stable state
   * after a divergence. The rest lengths still come from the surface. */
  void
  SetInitialState(SheetFlatteningPhaseEnum    phase,
                  const std::vector<double> & positions,
                  const std::vector<double> & velocities);
  void
  ClearInitialState()
  {
    m_InitialPositions.clear();
    m_InitialVelocities.clear();
  }

  /** The time step chosen when TimeStep is 0: implicit Euler FallTime / StepsPerFallTime,
   * explicit integrators TimeStepSafety times their stability bound over the system's
   * largest angular frequency (2.83 for RK4, 2 for the others). */
  static double
  AutomaticTimeStep(const MassSpringSystem &               system,
                    MassSpringIntegratorEnum               integrator,
                    const MassSpringFlatteningParameters & parameters,
                    double                                 fallTime);

  /** The particles of a grid mesh's end column (OuterEdge: the end farther from the roll's
   * axis; InnerEdge: the nearer one), one per row. Throws for other meshes or edges. */
  static std::vector<uint32_t>
  EdgeParticles(const SheetMesh & mesh, SheetLockedEdgeEnum edge);

  /** The paper's impulse that makes a hanging sheet wave: adds to every free particle a
   * velocity along the sheet's normal (its least principal axis), growing linearly from 0
   * at the locked particles' centroid to `speed` at the particle farthest from it. */
  static void
  ApplyWave(MassSpringSystem & system, double speed);

  /** Flattens the sheet; returns the flat mesh (same points and triangles, z = 0). */
  SheetMesh
  Flatten(const SheetMesh & surface);

  const MassSpringFlatteningReport &
  GetReport() const
  {
    return m_Report;
  }

  /** Builds the particle system of a sheet with the given parameters (also used by the
   * benchmarks and the stability analysis). */
  static void
  BuildSystem(const SheetMesh & mesh, const MassSpringFlatteningParameters & parameters, MassSpringSystem & system);

private:
  MassSpringFlatteningParameters m_Parameters;
  MassSpringFlatteningReport     m_Report;
  StepCallback                   m_Callback;
  PhaseEndCallback               m_PhaseEnd;
  SheetFlatteningPhaseEnum       m_InitialPhase{ SheetFlatteningPhaseEnum::Unroll };
  std::vector<double>            m_InitialPositions;
  std::vector<double>            m_InitialVelocities;
};

} // end namespace itk

#endif

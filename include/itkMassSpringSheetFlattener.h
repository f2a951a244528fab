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
    Custom
  };
};
/** Shorter name used throughout the module. */
using SheetLockedEdgeEnum = MassSpringSheetFlattenerEnums::LockedEdge;
VirtualUnwrapping_EXPORT const char *
ToString(SheetLockedEdgeEnum edge);
VirtualUnwrapping_EXPORT SheetLockedEdgeEnum
SheetLockedEdgeFromString(const std::string & name);

/** Parameters of MassSpringSheetFlattener; lengths in the mesh's units (mm), times in
 * seconds of simulated time. A value of 0 where "automatic" is said picks it from the
 * mesh (see MassSpringSheetFlattener). */
struct VirtualUnwrapping_EXPORT MassSpringFlatteningParameters
{
  /** Integrator of the unroll and flatten phases (the final relaxation is always the
   * implicit, quasi-static solver). */
  MassSpringIntegratorEnum Integrator{ MassSpringIntegratorEnum::ImplicitEuler };
  /** Time step; 0: automatic (explicit: TimeStepSafety times the linear stability bound;
   * implicit: the fall time / StepsPerFallTime). */
  double TimeStep{ 0.0 };
  /** Implicit steps per fall time (time for the sheet to fall its own length) of the
   * automatic implicit time step. > 0. */
  double StepsPerFallTime{ 40.0 };
  /** Fraction of the linear stability bound used by the automatic explicit time step. */
  double TimeStepSafety{ 0.5 };
  /** Stiffness of a structural spring of mean length (force per length); a spring of rest
   * length L gets Stiffness * meanLength / L, so the sheet responds uniformly. > 0. */
  double Stiffness{ 1.0 };
  /** Shear springs (across each pair of triangles sharing an edge; grid diagonals on grid
   * meshes), relative to the structural stiffness; 0 turns them off. */
  double ShearStiffnessRatio{ 0.5 };
  /** Bending springs (grid meshes: joining every other particle along rows and columns),
   * relative to the structural stiffness; 0 (default) turns them off. */
  double BendingStiffnessRatio{ 0.0 };
  /** Mass per unit area of the sheet. > 0. */
  double Density{ 1.0 };
  /** Gravity magnitude; 0: automatic, so that the sheet's own weight stretches a hanging
   * row by about HangingStrain. */
  double Gravity{ 0.0 };
  double HangingStrain{ 0.01 };
  /** Viscous damping (1/s); negative: automatic (2 / fall time). */
  double Damping{ -1.0 };
  /** Spring damping (s) along springs, relative to their stiffness. */
  double SpringDamping{ 0.0 };
  /** Collision response restitution k_r in [0, 1] (the paper: 0.1). */
  double Restitution{ 0.1 };
  /** Unroll phase: hold an edge and let gravity unfurl the sheet. */
  SheetLockedEdgeEnum   LockedEdge{ SheetLockedEdgeEnum::OuterEdge };
  std::vector<uint32_t> LockedParticles;
  /** Step limits of the unroll and flatten phases. */
  unsigned int MaximumStepsPerPhase{ 3000 };
  /** Convergence of the unroll and flatten phases: relative kinetic energy below
   * KineticEnergyTolerance at three checks in a row (checks every 10 steps), then relative
   * residual force below ResidualForceTolerance (see MassSpringSystem for both measures). */
  double KineticEnergyTolerance{ 1e-9 };
  double ResidualForceTolerance{ 1e-3 };
  /** The unroll phase is over only when the sheet hangs in a plane: RMS distance from its
   * best-fitting plane below this fraction of the mean spring length, and no triangle
   * turned over as seen along the plane's normal (a curl left at the free end would fold
   * over on the plane). */
  double PlanarityTolerance{ 0.25 };
  /** Quasi-static relaxation on the plane after the flatten phase: iteration limit and
   * tolerance on the relative residual force. */
  unsigned int RelaxationIterations{ 300 };
  double       RelaxationTolerance{ 1e-5 };
  /** Coarse-to-fine for grid meshes: simulate every n-th row and column, then carry the
   * result to every particle and relax there. 0: automatic (coarse grid of at most
   * CoarseParticles particles); 1: simulate the full mesh. */
  unsigned int CoarseningFactor{ 0 };
  unsigned int CoarseParticles{ 3000 };
  /** Threads for the force loops (0: ITK's default). */
  unsigned int NumberOfWorkUnits{ 0 };
};

/** What a flattening did, phase by phase. */
struct VirtualUnwrapping_EXPORT MassSpringFlatteningReport
{
  struct Phase
  {
    std::string Name;
    std::string Integrator;
    double      TimeStep{ 0.0 };
    uint64_t    Steps{ 0 };
    std::string StopReason; // "converged" or "step limit"
    double      Seconds{ 0.0 };
    double      RelativeKineticEnergy{ 0.0 };
    double      RelativeResidualForce{ 0.0 };
  };
  std::vector<Phase> Phases;
  size_t             Particles{ 0 };
  size_t             SimulatedParticles{ 0 };
  size_t             Springs{ 0 };
  unsigned int       CoarseningFactor{ 1 };
  double             Gravity{ 0.0 };
  double             Damping{ 0.0 };
  uint64_t           SpringEvaluations{ 0 };
  double             Seconds{ 0.0 };
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
 *    RelaxationTolerance.
 * The flat mesh (same points, same triangles, z = 0) is expressed in the plane: x along
 * the sheet's longest extent (on grid meshes pointing towards increasing columns, i.e.
 * away from the sheet's start), triangles counter-clockwise seen from +z (the side the 3D
 * triangles' normals face), the bounding box starting at (0, 0).
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
  /** Called after every step: the system, the phase name ("unroll", "flatten", "relax")
   * and the step within the phase. Return false to abort. */
  using StepCallback = std::function<bool(MassSpringSystem &, const std::string &, uint64_t)>;

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
};

} // end namespace itk

#endif

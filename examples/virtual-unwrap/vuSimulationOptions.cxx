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
#include "vuSimulationOptions.h"

#include "vuCommands.h"

namespace vu {
void
AddSimulationOptions(CLI::App * command, SimulationOptions & options)
{
  auto &            p = options.Parameters;
  const std::string group = "Simulation";
  command->add_option("--integrator", options.Integrator, "euler, midpoint, rk4, symplectic-euler or implicit-euler")
    ->capture_default_str()
    ->check(CLI::IsMember({ "euler", "midpoint", "rk4", "symplectic-euler", "implicit-euler" }))
    ->group(group);
  command->add_option("--time-step", p.TimeStep, "simulation time step in seconds; 0: automatic")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(group);
  command
    ->add_option("--time-step-safety", p.TimeStepSafety, "automatic explicit step as a fraction of its stability bound")
    ->capture_default_str()
    ->check(vu::Positive())
    ->group(group);
  command->add_option("--steps-per-fall", p.StepsPerFallTime, "automatic implicit step: fall time divided by this")
    ->capture_default_str()
    ->check(vu::Positive())
    ->group(group);
  command->add_option("--stiffness", p.Stiffness, "stiffness of a spring of mean length")
    ->capture_default_str()
    ->check(vu::Positive())
    ->group(group);
  command->add_option("--shear", p.ShearStiffnessRatio, "shear springs' stiffness relative to structural; 0: off")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(group);
  command->add_option("--bending", p.BendingStiffnessRatio, "bending springs' stiffness relative to structural; 0: off")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(group);
  command->add_option("--damping", p.Damping, "viscous damping (1/s); negative: automatic")
    ->capture_default_str()
    ->group(group);
  command->add_option("--spring-damping", p.SpringDamping, "damping along springs (s)")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(group);
  command->add_option("--gravity", p.Gravity, "gravity magnitude; 0: automatic (see --hanging-strain)")
    ->capture_default_str()
    ->check(vu::NonNegative())
    ->group(group);
  command->add_option("--hanging-strain", p.HangingStrain, "automatic gravity stretches a hanging row by this")
    ->capture_default_str()
    ->check(vu::Positive())
    ->group(group);
  command->add_option("--restitution", p.Restitution, "collision restitution k_r in [0, 1]")
    ->capture_default_str()
    ->check(CLI::Range(0.0, 1.0))
    ->group(group);
  command->add_option("--locked-edge", options.LockedEdge, "edge held while unrolling: auto, outer, inner, none")
    ->capture_default_str()
    ->check(CLI::IsMember({ "auto", "outer", "inner", "none" }))
    ->group(group);
  command->add_option("--lock", options.LockedParticles, "particle ids to hold while unrolling (instead of an edge)")
    ->group(group);
  command->add_option("--max-steps", p.MaximumStepsPerPhase, "step limit of the unroll and of the flatten phase")
    ->capture_default_str()
    ->check(vu::Positive())
    ->group(group);
  command
    ->add_option("--coarse-particles", p.CoarseParticles, "grid meshes: simulate at most about this many particles")
    ->capture_default_str()
    ->check(CLI::Range(4u, 1u << 30))
    ->group(group);
  command
    ->add_option("--coarsening", p.CoarseningFactor, "grid meshes: simulate every n-th row and column; 0: automatic")
    ->capture_default_str()
    ->group(group);
}

itk::MassSpringFlatteningParameters
ResolveSimulationParameters(const SimulationOptions & options, const itk::SheetMesh & mesh)
{
  itk::MassSpringFlatteningParameters p = options.Parameters;
  p.Integrator = itk::MassSpringIntegratorFromString(options.Integrator);
  if (!options.LockedParticles.empty())
  {
    p.LockedEdge = itk::SheetLockedEdgeEnum::Custom;
    p.LockedParticles = options.LockedParticles;
  }
  else if (options.LockedEdge == "auto")
  {
    p.LockedEdge = mesh.IsGridStructured() ? itk::SheetLockedEdgeEnum::OuterEdge : itk::SheetLockedEdgeEnum::None;
  }
  else
  {
    p.LockedEdge = itk::SheetLockedEdgeFromString(options.LockedEdge);
    if (p.LockedEdge != itk::SheetLockedEdgeEnum::None && !mesh.IsGridStructured())
    {
      throw UsageError("--locked-edge " + options.LockedEdge +
                       " needs a grid mesh (a .vtp with GridRow/GridColumn); give --lock ids instead");
    }
  }
  return p;
}

nlohmann::json
ToJson(const itk::MassSpringFlatteningParameters & p)
{
  return { { "integrator", itk::ToString(p.Integrator) },
           { "time_step", p.TimeStep },
           { "time_step_safety", p.TimeStepSafety },
           { "steps_per_fall_time", p.StepsPerFallTime },
           { "stiffness", p.Stiffness },
           { "shear_stiffness_ratio", p.ShearStiffnessRatio },
           { "bending_stiffness_ratio", p.BendingStiffnessRatio },
           { "density", p.Density },
           { "gravity", p.Gravity },
           { "hanging_strain", p.HangingStrain },
           { "damping", p.Damping },
           { "spring_damping", p.SpringDamping },
           { "restitution", p.Restitution },
           { "locked_edge", itk::ToString(p.LockedEdge) },
           { "locked_particles", p.LockedParticles.size() },
           { "max_steps_per_phase", p.MaximumStepsPerPhase },
           { "kinetic_energy_tolerance", p.KineticEnergyTolerance },
           { "residual_force_tolerance", p.ResidualForceTolerance },
           { "planarity_tolerance", p.PlanarityTolerance },
           { "relaxation_iterations", p.RelaxationIterations },
           { "relaxation_tolerance", p.RelaxationTolerance },
           { "coarsening_factor", p.CoarseningFactor },
           { "coarse_particles", p.CoarseParticles } };
}

nlohmann::json
ToJson(const itk::MassSpringFlatteningReport & report)
{
  nlohmann::json phases = nlohmann::json::array();
  for (const auto & phase : report.Phases)
  {
    phases.push_back({ { "name", phase.Name },
                       { "integrator", phase.Integrator },
                       { "time_step", phase.TimeStep },
                       { "steps", phase.Steps },
                       { "stop_reason", phase.StopReason },
                       { "seconds", phase.Seconds },
                       { "relative_kinetic_energy", phase.RelativeKineticEnergy },
                       { "relative_residual_force", phase.RelativeResidualForce } });
  }
  return { { "particles", report.Particles },
           { "simulated_particles", report.SimulatedParticles },
           { "springs", report.Springs },
           { "coarsening_factor", report.CoarseningFactor },
           { "gravity", report.Gravity },
           { "damping", report.Damping },
           { "spring_evaluations", report.SpringEvaluations },
           { "seconds", report.Seconds },
           { "phases", phases } };
}

nlohmann::json
DistortionJson(const itk::SheetMesh & surface, const itk::SheetMesh & flat)
{
  auto c = itk::FlatteningDistortionCalculator::New();
  c->SetSurfaceMesh(surface);
  c->SetFlatMesh(flat);
  c->Compute();
  return {
    { "edge_strain",
      { { "mean", c->GetEdgeStrainMean() }, { "p95", c->GetEdgeStrainP95() }, { "max", c->GetEdgeStrainMax() } } },
    { "area_distortion", c->GetAreaDistortion() },
    { "total_area_ratio", c->GetTotalAreaRatio() },
    { "angle_distortion_degrees", c->GetAngleDistortionDegrees() },
    { "l2_stretch", c->GetL2Stretch() },
    { "linf_stretch", c->GetLinfStretch() },
    { "flipped_triangles", c->GetNumberOfFlippedTriangles() },
    { "degenerate_flat_triangles", c->GetNumberOfDegenerateFlatTriangles() },
    { "edges", c->GetNumberOfEdges() }
  };
}
} // namespace vu

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

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace vu {
namespace {
/** A parameter's range as a check with a message a user reads: "> 0" where the lowest
 * value is only there to keep a division finite. */
CLI::Validator
ParameterRange(double lowest, double highest)
{
  std::ostringstream range;
  range << std::setprecision(12);
  if (lowest > 0.0 && lowest < 1e-2)
  {
    range << "> 0";
  }
  else if (lowest > std::numeric_limits<double>::lowest())
  {
    range << ">= " << lowest;
  }
  if (highest < static_cast<double>(std::numeric_limits<unsigned int>::max()))
  {
    range << (range.tellp() > 0 ? " and " : "") << "<= " << highest;
  }
  const bool        bounded = range.tellp() > 0;
  const std::string text = bounded ? "a number " + range.str() : std::string("a finite number");
  // The name shown in --help beside the type, as the other number checks name theirs.
  std::ostringstream name;
  name << std::setprecision(12);
  if (highest < static_cast<double>(std::numeric_limits<unsigned int>::max()))
  {
    name << "[" << lowest << ", " << highest << "]";
  }
  else if (lowest > 0.0 && lowest < 1e-2)
  {
    name << "POSITIVE";
  }
  else if (lowest == 0.0)
  {
    name << "NONNEGATIVE";
  }
  else if (bounded)
  {
    name << ">=" << lowest;
  }
  return CLI::Validator(
    [lowest, highest, text](std::string & value) -> std::string {
      double number = 0.0;
      if (CLI::detail::lexical_cast(value, number) && std::isfinite(number) && number >= lowest && number <= highest)
      {
        return {};
      }
      return "must be " + text + ", not " + value;
    },
    name.str());
}
} // namespace

void
AddSimulationOptions(CLI::App * command, SimulationOptions & options)
{
  auto &            p = options.Parameters;
  const std::string group = "Simulation";
  command->add_option("--integrator", options.Integrator, "euler, midpoint, rk4, symplectic-euler or implicit-euler")
    ->capture_default_str()
    ->check(CLI::IsMember({ "euler", "midpoint", "rk4", "symplectic-euler", "implicit-euler" }))
    ->group(group);
#define VU_SIMULATION_OPTION(type, name, value, lowest, highest, option, key, meaning)                                 \
  command->add_option("--" option, p.name, meaning)                                                                    \
    ->capture_default_str()                                                                                            \
    ->check(ParameterRange(static_cast<double>(lowest), static_cast<double>(highest)))                                 \
    ->group(group);
  VU_MASS_SPRING_PARAMETERS(VU_SIMULATION_OPTION)
#undef VU_SIMULATION_OPTION
  command->add_option("--locked-edge", options.LockedEdge, "edge held while unrolling: auto, outer, inner, none")
    ->capture_default_str()
    ->check(CLI::IsMember({ "auto", "outer", "inner", "none" }))
    ->group(group);
  command->add_option("--lock", options.LockedParticles, "particle ids to hold while unrolling (instead of an edge)")
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
  else
  {
    p.LockedEdge = itk::SheetLockedEdgeFromString(options.LockedEdge);
    if (p.LockedEdge != itk::SheetLockedEdgeEnum::None && p.LockedEdge != itk::SheetLockedEdgeEnum::Auto &&
        !mesh.IsGridStructured())
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
  nlohmann::json json = { { "integrator", itk::ToString(p.Integrator) },
                          { "locked_edge", itk::ToString(p.LockedEdge) },
                          { "locked_particles", p.LockedParticles.size() } };
#define VU_SIMULATION_JSON(type, name, value, lowest, highest, option, key, meaning) json[key] = p.name;
  VU_MASS_SPRING_PARAMETERS(VU_SIMULATION_JSON)
#undef VU_SIMULATION_JSON
  return json;
}

nlohmann::json
ToJson(const itk::MassSpringFlatteningReport & report)
{
  nlohmann::json phases = nlohmann::json::array();
  for (const auto & phase : report.Phases)
  {
    phases.push_back({ { "name", itk::ToString(phase.Name) },
                       { "integrator", phase.Integrator },
                       { "time_step", phase.TimeStep },
                       { "steps", phase.Steps },
                       { "stop_reason", phase.StopReason },
                       { "seconds", phase.Seconds },
                       { "relative_kinetic_energy", phase.RelativeKineticEnergy },
                       { "relative_residual_force", phase.RelativeResidualForce } });
  }
  return { { "locked_edge", itk::ToString(report.LockedEdge) },
           { "particles", report.Particles },
           { "simulated_particles", report.SimulatedParticles },
           { "springs", report.Springs },
           { "coarsening_factor", report.CoarseningFactor },
           { "gravity", report.Gravity },
           { "damping", report.Damping },
           { "spring_evaluations", report.SpringEvaluations },
           { "seconds", report.Seconds },
           { "flipped_triangles", report.FlippedTriangles },
           { "row_bend_straightened", report.RowBend },
           { "restart",
             { { "flipped_triangles_before", report.FlippedBeforeRestart }, { "kept", report.RestartKept } } },
           { "warnings", report.Warnings },
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

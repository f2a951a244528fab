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
#ifndef vuSimulationOptions_h
#define vuSimulationOptions_h

#include "itkFlatteningDistortionCalculator.h"
#include "itkMassSpringSheetFlattener.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vu {
/** The mass-spring simulation's options, shared by the flatten and unwrap subcommands. */
struct SimulationOptions
{
  itk::MassSpringFlatteningParameters Parameters;
  std::string                         Integrator{ "implicit-euler" };
  std::string                         LockedEdge{ "auto" };
  std::vector<uint32_t>               LockedParticles;
};

/** Adds every simulation option, with its default, to a subcommand. */
void
AddSimulationOptions(CLI::App * command, SimulationOptions & options);

/** The flattener's parameters for a mesh: resolves the integrator name and the locked edge
 * ("auto": the outer edge of a grid mesh, nothing otherwise). Throws UsageError. */
itk::MassSpringFlatteningParameters
ResolveSimulationParameters(const SimulationOptions & options, const itk::SheetMesh & mesh);

nlohmann::json
ToJson(const itk::MassSpringFlatteningParameters & parameters);
nlohmann::json
ToJson(const itk::MassSpringFlatteningReport & report);
/** Distortion of a flat mesh against its surface, by the names of the design document. */
nlohmann::json
DistortionJson(const itk::SheetMesh & surface, const itk::SheetMesh & flat);
} // namespace vu

#endif

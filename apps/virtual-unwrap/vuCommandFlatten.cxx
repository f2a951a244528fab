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
// virtual-unwrap flatten SURFACE -o FLAT: the mass-spring unrolling and flattening of a
// sheet mesh made elsewhere.
#include "vuCommands.h"
#include "vuSheetMeshIO.h"
#include "vuSimulationOptions.h"

#include <filesystem>

namespace vu {
void
RegisterFlattenCommand(CLI::App & app)
{
  auto * command = app.add_subcommand(
    "flatten",
    "Unroll and flatten a sheet mesh by mass-spring simulation (hold an edge and let gravity unfurl it, drop it on a "
    "plane, relax). Writes the flat mesh (same points and triangles, z = 0) and a JSON report.");
  static std::string       surfacePath, outputPath, reportPath;
  static SimulationOptions options;
  command
    ->add_option("SURFACE",
                 surfacePath,
                 "3D sheet mesh: .vtp with GridRow/GridColumn arrays for grid meshes, "
                 "or OBJ, VTK, OFF ...")
    ->required();
  command->add_option("-o,--output", outputPath, "flat mesh to write (.obj or .vtp)")->required();
  command->add_option("--report", reportPath, "write the JSON report here instead of standard output");
  AddSimulationOptions(command, options);
  command->callback([] {
    const std::string extension = std::filesystem::path(outputPath).extension().string();
    if (extension != ".obj" && extension != ".vtp")
    {
      throw UsageError("--output must end in .obj or .vtp: " + outputPath);
    }
    const itk::SheetMesh          surface = ReadSheetMesh(surfacePath);
    itk::MassSpringSheetFlattener flattener;
    flattener.SetParameters(ResolveSimulationParameters(options, surface));
    const itk::SheetMesh flat = flattener.Flatten(surface);
    // Written into a staging folder beside it and renamed, so a failure, a signal or a kill
    // leaves no partial mesh.
    OutputStaging staging(outputPath, OutputStaging::Kind::File);
    staging.RequireSpace(60 * flat.GetNumberOfPoints() + 40 * flat.GetNumberOfTriangles() + (1u << 20));
    const std::string temporary = staging.FilePath().string();
    if (extension == ".obj")
    {
      WriteSheetMeshObj(temporary, flat);
    }
    else
    {
      WriteSheetMeshVtp(temporary, flat);
    }
    staging.Commit();
    nlohmann::json report;
    report["input"] = surfacePath;
    report["output"] = outputPath;
    report["parameters"] = ToJson(flattener.GetParameters());
    report["simulation"] = ToJson(flattener.GetReport());
    report["distortion"] = DistortionJson(surface, flat);
    EmitJson(report, reportPath);
  });
}
} // namespace vu

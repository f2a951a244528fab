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
// virtual-unwrap distortion SURFACE FLAT: distortion of a flattening, as JSON.
#include "vuCommands.h"
#include "vuSheetMeshIO.h"
#include "vuSimulationOptions.h"

namespace vu {
void
RegisterDistortionCommand(CLI::App & app)
{
  auto *             command = app.add_subcommand("distortion",
                                      "Distortion of a flattening: compare a 3D sheet mesh with its flat "
                                                  "version (same points and triangles), print JSON.");
  static std::string surfacePath, flatPath, outputPath;
  command->add_option("SURFACE", surfacePath, "3D sheet mesh (OBJ, VTP, VTK, OFF, ...)")->required();
  command->add_option("FLAT", flatPath, "flattened mesh with the same points and triangles; z is ignored")->required();
  command->add_option("-o,--output", outputPath, "write the JSON to this file instead of standard output");
  command->callback([] {
    const itk::SheetMesh surface = ReadSheetMesh(surfacePath);
    const itk::SheetMesh flat = ReadSheetMesh(flatPath);
    if (!itk::HaveSameTopology(surface, flat))
    {
      throw UsageError(flatPath + " does not have the points and triangles of " + surfacePath);
    }
    EmitJson(DistortionJson(surface, flat), outputPath);
  });
}
} // namespace vu

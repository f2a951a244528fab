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
// The option parsers of the tool as a user's command line reaches them: the reader's
// (--roi, --roi-mm, --spacing, --shrink, --series ...), the simulation's (--lock,
// --locked-edge, --time-step ...) and the mesh spacing of segment ("MM" or "S,W" or auto)
// and of unwrap (a number). Input: the arguments, one per line; the values that parse
// are then applied as the commands apply them (to a reader, to a 4 x 3 grid sheet).
#include "vuFuzzCommon.h"

#include "vuCommands.h"
#include "vuReaderOptions.h"
#include "vuSimulationOptions.h"

#include <exception>
#include <vector>

namespace {
itk::SheetMesh
SmallGrid()
{
  itk::SheetMesh mesh;
  mesh.GridRows = 3;
  mesh.GridColumns = 4;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 4; ++c)
    {
      mesh.Points.insert(mesh.Points.end(), { 0.5 * c, 0.0, 0.5 * r });
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
    }
  }
  for (uint32_t r = 0; r + 1 < 3; ++r)
  {
    for (uint32_t c = 0; c + 1 < 4; ++c)
    {
      const uint32_t a = 4 * r + c;
      mesh.Triangles.insert(mesh.Triangles.end(), { a, a + 1, a + 4, a + 1, a + 5, a + 4 });
    }
  }
  return mesh;
}
} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size)
{
  using namespace vu::fuzz;
  Quiet();
  std::vector<std::string> arguments{ "fuzz" };
  std::string              current;
  for (size_t i = 0; i < size && arguments.size() < 40; ++i)
  {
    if (data[i] == '\n')
    {
      arguments.push_back(current);
      current.clear();
    }
    else
    {
      current.push_back(static_cast<char>(data[i]));
    }
  }
  arguments.push_back(current);
  std::vector<const char *> argv;
  for (const std::string & a : arguments)
  {
    argv.push_back(a.c_str());
  }

  vu::ReaderOptions     reader;
  vu::SimulationOptions simulation;
  std::string           meshSpacing = "auto";
  CLI::App              app{ "fuzz" };
  vu::AddReaderOptions(app, reader);
  vu::AddSimulationOptions(&app, simulation);
  // segment and unwrap take the same --mesh-spacing (MM, S,W or auto).
  app.add_option("--mesh-spacing", meshSpacing);
  try
  {
    app.parse(static_cast<int>(argv.size()), argv.data());
  }
  catch (const std::exception &)
  {
    return 0; // refused by the parser: the tool prints one line and exits with 2
  }
  try
  {
    double spacing[2] = { 0.0, 0.0 };
    vu::ParseMeshSpacing(meshSpacing, spacing);
    auto volumeReader = itk::CTVolumeReader::New();
    vu::ConfigureReader(reader, "volume.mha", *volumeReader);
    static const itk::SheetMesh         grid = SmallGrid();
    itk::MassSpringFlatteningParameters parameters = vu::ResolveSimulationParameters(simulation, grid);
    // Only the checks of the parameters and the locks, not a whole simulation.
    parameters.MaximumStepsPerPhase = 2;
    itk::MassSpringSheetFlattener flattener;
    flattener.SetParameters(parameters);
    (void)flattener.Flatten(grid);
  }
  catch (const std::exception &)
  {
    // Refused: the tool prints the message in one line.
  }
  return 0;
}

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
// The mesh readers of `flatten` and `distortion` (vu::ReadSheetMesh): Wavefront OBJ, VTK
// legacy, OFF and VTK XML PolyData, told apart by their first bytes as a user's file
// would be by its name.
#include "vuFuzzCommon.h"

#include "vuSheetMeshIO.h"

#include <exception>

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size)
{
  using namespace vu::fuzz;
  Quiet();
  std::string extension = ".obj";
  if (StartsWith(data, size, "OFF") || StartsWith(data, size, "COFF") || StartsWith(data, size, "NOFF"))
  {
    extension = ".off";
  }
  else if (StartsWith(data, size, "# vtk"))
  {
    extension = ".vtk";
  }
  else if (StartsWith(data, size, "<?xml") || StartsWith(data, size, "<VTKFile"))
  {
    extension = ".vtp";
  }
  const std::filesystem::path path = ScratchFolder() / ("mesh" + extension);
  WriteFile(path, data, size);
  try
  {
    const itk::SheetMesh mesh = vu::ReadSheetMesh(path.string());
    (void)mesh;
  }
  catch (const std::exception &)
  {
    // Refused: the tool prints the message in one line.
  }
  return 0;
}

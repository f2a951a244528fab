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
// The volume-file path of the CT reader: a MetaImage (.mha) or NRRD file, header and
// voxels, read as `info` reads it (the header only) and as `unwrap` reads it (all).
#include "vuFuzzCommon.h"


#include <exception>

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size)
{
  using namespace vu::fuzz;
  Quiet();
  const std::string           extension = StartsWith(data, size, "NRRD") ? ".nrrd" : ".mha";
  const std::filesystem::path folder = FreshFolder("volume");
  const std::filesystem::path path = folder / ("volume" + extension);
  WriteFile(path, data, size);
  ReadVolume(path.string());
  return 0;
}

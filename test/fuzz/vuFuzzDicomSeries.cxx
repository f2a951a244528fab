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
// The DICOM path of the CT reader on mutated real files: a folder holding two untouched
// slices of a real CT series and the fuzzer's bytes as a third file, inspected (series,
// geometry, truncation), sorted and read as `unwrap` reads a folder.
#include "vuFuzzCommon.h"


#include <algorithm>
#include <exception>
#include <vector>

#ifndef VU_FUZZ_DICOM_SERIES
#  error "VU_FUZZ_DICOM_SERIES: the folder of the real series"
#endif

namespace {
std::vector<std::filesystem::path>
FixedSlices()
{
  std::vector<std::filesystem::path> slices;
  for (const auto & entry : std::filesystem::directory_iterator(VU_FUZZ_DICOM_SERIES))
  {
    slices.push_back(entry.path());
  }
  std::sort(slices.begin(), slices.end());
  slices.resize(std::min<size_t>(slices.size(), 2));
  return slices;
}
} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size)
{
  using namespace vu::fuzz;
  Quiet();
  static const std::vector<std::filesystem::path> fixed = FixedSlices();
  const std::filesystem::path                     folder = FreshFolder("series");
  for (const auto & slice : fixed)
  {
    std::filesystem::copy_file(slice, folder / slice.filename());
  }
  WriteFile(folder / "fuzzed.dcm", data, size);
  ReadVolume(folder.string());
  return 0;
}

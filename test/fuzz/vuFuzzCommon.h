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
// What every fuzz target shares: a scratch folder of its own, files written from the
// fuzzer's bytes, and quiet libraries (their warnings are the tool's business, not a
// finding). A target returns normally when the input was refused with an exception the
// tool turns into a one-line error; anything else (a crash, a sanitizer report, a hang,
// another kind of exception escaping) is a finding.
#ifndef vuFuzzCommon_h
#define vuFuzzCommon_h

#include "itkCTVolumeReader.h"
#include "itkObject.h"

#include <vtkObject.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace vu {
namespace fuzz {
/** A folder for this process's files, removed at exit. */
inline const std::filesystem::path &
ScratchFolder()
{
  static const std::filesystem::path folder = [] {
    const char *          base = std::getenv("TMPDIR");
    std::filesystem::path path =
      std::filesystem::path(base != nullptr && *base != '\0' ? base : "/tmp") / ("vu-fuzz-" + std::to_string(getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(ScratchFolder(), ignored);
    });
    return path;
  }();
  return folder;
}

/** An empty sub-folder of the scratch folder, emptied anew on every call. */
inline std::filesystem::path
FreshFolder(const std::string & name)
{
  const std::filesystem::path folder = ScratchFolder() / name;
  std::error_code             ignored;
  std::filesystem::remove_all(folder, ignored);
  std::filesystem::create_directories(folder);
  return folder;
}

inline void
WriteFile(const std::filesystem::path & path, const uint8_t * data, size_t size)
{
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char *>(data), static_cast<std::streamsize>(size));
}

/** Turns ITK's and VTK's warning output off, once. */
inline void
Quiet()
{
  static const bool done = [] {
    itk::Object::GlobalWarningDisplayOff();
    vtkObject::GlobalWarningDisplayOff();
    return true;
  }();
  (void)done;
}

/** True when the bytes start with the given text. */
/** Reads `path` (a file, folder or pattern) as `unwrap` does; a refusal is the expected
 * answer to most inputs (the tool prints its message in one line). */
inline void
ReadVolume(const std::string & path)
{
  try
  {
    auto reader = itk::CTVolumeReader::New();
    reader->SetFileName(path);
    reader->UpdateOutputInformation();
    reader->Update();
  }
  catch (const std::exception &)
  {}
}

inline bool
StartsWith(const uint8_t * data, size_t size, const std::string & text)
{
  return size >= text.size() && std::equal(text.begin(), text.end(), reinterpret_cast<const char *>(data));
}
} // namespace fuzz
} // namespace vu

#endif

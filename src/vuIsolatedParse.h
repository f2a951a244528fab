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
#ifndef vuIsolatedParse_h
#define vuIsolatedParse_h

#include <functional>
#include <string>
#include <vector>

namespace itk {
namespace detail {
/** What a parse of some files in a child process gave: one result per file parsed, or
 * the file on which the child died (by a signal: an assertion's abort, a crash, the
 * memory or the time limit), or both when it died after some files. */
struct IsolatedParse
{
  std::vector<std::string> Results;
  /** The file the child was parsing when it died, or "". */
  std::string FailedFile;
  /** How it died: "aborted", "ran out of time", "crashed" (signal name otherwise). */
  std::string Failure;
};

/** Parses files with a third-party parser that may abort the process on a damaged file
 * (Debian's GDCM keeps its assertions) or allocate and clear whatever length a file claims:
 * `parse` runs on each file in turn in a child process whose address space is limited to
 * what it uses now plus eight times the largest file plus 256 MiB, and whose processor
 * time is limited to 10 s plus 50 ms a file (eight times that in a sanitizer build; four
 * times that in wall-clock time). Each result comes back through a pipe; the parse
 * stops at the first file the child dies on. Without fork (or a pipe), `parse` runs here. */
IsolatedParse
ParseInChildProcess(const std::vector<std::string> &                             files,
                    const std::function<std::string(const std::string & file)> & parse);
} // namespace detail
} // namespace itk

#endif

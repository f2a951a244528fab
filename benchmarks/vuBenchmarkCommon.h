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
#ifndef vuBenchmarkCommon_h
#define vuBenchmarkCommon_h

// Shared by the flattening benchmarks: the meshes every method flattens and the CSV row
// each result becomes. Free of ITK and Eigen headers so that a CGAL translation unit (with
// the system Eigen) can include it.
#include "itkSheetMesh.h"

#include <fstream>
#include <ostream>
#include <string>
#include <vector>

namespace vu {
/** The standard phantom's true mid-surface (a 3-turn roll) with about targetVertices
 * vertices, as a grid mesh. */
itk::SheetMesh
BenchmarkRollMesh(size_t targetVertices);
/** A spherical cap (non-developable) of about targetVertices vertices. */
itk::SheetMesh
BenchmarkDomeMesh(size_t targetVertices);
/** A mesh by name: roll-10k, roll-100k, roll-1M, dome-10k ... ("roll"/"dome" and a count
 * with an optional k or M suffix). */
itk::SheetMesh
BenchmarkMesh(const std::string & name);

/** "a,b,c" -> {"a", "b", "c"}: the benchmarks' list options. */
std::vector<std::string>
SplitList(const std::string & text);

void
WriteFlatteningCsvHeader(std::ostream & out);

/** The options every flattening benchmark takes: --meshes LIST, --methods LIST, --csv FILE. */
struct FlatteningBenchmarkOptions
{
  std::vector<std::string> Meshes;
  std::vector<std::string> Methods;
  std::string              CsvPath;
};
/** Reads argv[a] into options when it is one of those options with its value (and moves a
 * onto the value); false when it is not. */
bool
ReadFlatteningBenchmarkOption(int argc, char * argv[], int & a, FlatteningBenchmarkOptions & options);
/** Prints "usage: program [--meshes LIST] [--methods methods] [--csv FILE] extra" on
 * standard error and returns 2, the exit status of a wrong command line. */
int
FlatteningBenchmarkUsage(const std::string & program, const std::string & methods, const std::string & extra);
/** Where the CSV goes: the file at path, opened into file, or standard output when path is
 * empty; the header is written. */
std::ostream &
OpenFlatteningCsv(const std::string & path, std::ofstream & file);
/** One result: distortion of flat against surface (peers' flat meshes are first scaled by
 * the uniform factor that best matches edge lengths, since their scale is arbitrary), or
 * the failure status when flat is empty. */
void
WriteFlatteningCsvRow(std::ostream &         out,
                      const std::string &    meshName,
                      const itk::SheetMesh & surface,
                      const itk::SheetMesh & flat,
                      const std::string &    method,
                      const std::string &    setting,
                      double                 seconds,
                      const std::string &    status,
                      bool                   rescale);
} // namespace vu

#endif

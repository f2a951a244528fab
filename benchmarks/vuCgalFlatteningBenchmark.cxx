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
// CGAL 5.5's LSCM and ARAP parameterisations, as peers of the mass-spring flattener, on the
// same meshes and with the same CSV rows as vuFlatteningBenchmark (scale fitted, since a
// parameterisation's scale is arbitrary).
//
// Usage: vuCgalFlatteningBenchmark [--meshes roll-10k,roll-100k,roll-1M,dome-10k]
//                                  [--methods lscm,arap] [--csv FILE] [--max-arap N]
#include "vuBenchmarkCommon.h"
#include "vuCgalParameterize.h"

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>

int
main(int argc, char * argv[])
{
  vu::FlatteningBenchmarkOptions options{ { "roll-10k", "roll-100k", "roll-1M", "dome-10k" }, { "lscm", "arap" }, "" };
  size_t                         maxArap = 200000;
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    if (vu::ReadFlatteningBenchmarkOption(argc, argv, a, options))
    {
      continue;
    }
    if (arg == "--max-arap" && a + 1 < argc)
    {
      maxArap = std::stoul(argv[++a]);
    }
    else
    {
      return vu::FlatteningBenchmarkUsage("vuCgalFlatteningBenchmark", "lscm,arap", "[--max-arap N]");
    }
  }
  std::ofstream  file;
  std::ostream & out = vu::OpenFlatteningCsv(options.CsvPath, file);
  for (const std::string & meshName : options.Meshes)
  {
    const itk::SheetMesh surface = vu::BenchmarkMesh(meshName);
    for (const std::string & method : options.Methods)
    {
      if (method == "arap" && surface.GetNumberOfPoints() > maxArap)
      {
        vu::WriteFlatteningCsvRow(out, meshName, surface, {}, "cgal-" + method, "defaults", 0.0, "skipped", true);
        continue;
      }
      std::vector<double> uv;
      const auto          start = std::chrono::steady_clock::now();
      const std::string   error = vu::CgalParameterize(surface.Points, surface.Triangles, method, uv);
      const double        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      itk::SheetMesh      flat;
      if (error.empty())
      {
        flat = surface;
        flat.Points = uv;
      }
      else
      {
        std::cerr << "cgal-" << method << " on " << meshName << ": " << error << std::endl;
      }
      vu::WriteFlatteningCsvRow(out,
                                meshName,
                                surface,
                                flat,
                                "cgal-" + method,
                                "defaults",
                                seconds,
                                error.empty() ? "converged" : "failed",
                                true);
    }
  }
  return 0;
}

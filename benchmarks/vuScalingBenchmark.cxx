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
// Scaling of the default flattening (implicit Euler, coarse-to-fine, relaxation at full
// resolution) with the size of the sheet and the number of threads: wall time to
// convergence, steps, spring evaluations, edge strain p95 and the process's peak memory,
// on the standard phantom's true mid-surface at 10k to 4M vertices, with one thread and
// with all threads. CSV on standard output (or --csv FILE). Sizes run in increasing order,
// so the peak memory of a row is that of its size.
//
// Usage: vuScalingBenchmark [--sizes 10k,100k,1M,4M] [--threads 1,2] [--csv FILE]
#include "itkFlatteningDistortionCalculator.h"
#include "itkMassSpringSheetFlattener.h"
#include "itkMultiThreaderBase.h"
#include "vuBenchmarkCommon.h"

#include <sys/resource.h>

#include <chrono>
#include <fstream>
#include <iostream>

int
main(int argc, char * argv[])
{
  std::vector<std::string>  sizes = { "10k", "100k", "1M", "4M" };
  std::string               csvPath;
  std::vector<unsigned int> threadCounts = { 1u, itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads() };
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    if (arg == "--sizes" && a + 1 < argc)
    {
      sizes = vu::SplitList(argv[++a]);
    }
    else if (arg == "--csv" && a + 1 < argc)
    {
      csvPath = argv[++a];
    }
    else if (arg == "--threads" && a + 1 < argc)
    {
      threadCounts.clear();
      for (const std::string & t : vu::SplitList(argv[++a]))
      {
        threadCounts.push_back(static_cast<unsigned int>(std::stoul(t)));
      }
    }
    else
    {
      std::cerr << "usage: vuScalingBenchmark [--sizes 10k,100k,1M,4M] [--threads 1,2] [--csv FILE]" << std::endl;
      return 2;
    }
  }
  std::ofstream file;
  if (!csvPath.empty())
  {
    file.open(csvPath);
    if (!file)
    {
      std::cerr << "vuScalingBenchmark: error: cannot write " << csvPath << std::endl;
      return 1;
    }
  }
  std::ostream & out = csvPath.empty() ? std::cout : file;
  out
    << "mesh,vertices,threads,seconds,steps,spring_evaluations,stop_reasons,edge_strain_p95,flipped,peak_memory_mib\n";
  const unsigned int allThreads = itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads();
  for (const std::string & size : sizes)
  {
    const std::string    name = "roll-" + size;
    const itk::SheetMesh mesh = vu::BenchmarkMesh(name);
    for (unsigned int threads : threadCounts)
    {
      itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(threads);
      itk::MassSpringFlatteningParameters parameters;
      parameters.NumberOfWorkUnits = threads;
      itk::MassSpringSheetFlattener flattener;
      flattener.SetParameters(parameters);
      const auto           start = std::chrono::steady_clock::now();
      const itk::SheetMesh flat = flattener.Flatten(mesh);
      const double         seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const auto &         report = flattener.GetReport();
      uint64_t             steps = 0;
      std::string          reasons;
      for (const auto & phase : report.Phases)
      {
        steps += phase.Steps;
        reasons += std::string(reasons.empty() ? "" : ";") + itk::ToString(phase.Name) + ":" + phase.StopReason;
      }
      auto distortion = itk::FlatteningDistortionCalculator::New();
      distortion->SetSurfaceMesh(mesh);
      distortion->SetFlatMesh(flat);
      distortion->Compute();
      rusage usage{};
      getrusage(RUSAGE_SELF, &usage);
      out << name << ',' << mesh.GetNumberOfPoints() << ',' << threads << ',' << seconds << ',' << steps << ','
          << report.SpringEvaluations << ',' << reasons << ',' << distortion->GetEdgeStrainP95() << ','
          << distortion->GetNumberOfFlippedTriangles() << ',' << usage.ru_maxrss / 1024.0 << '\n'
          << std::flush;
    }
  }
  itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(allThreads);
  return 0;
}

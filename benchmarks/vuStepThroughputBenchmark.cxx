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
// Explicit step throughput of the mass-spring engine: symplectic Euler steps on the
// standard phantom's true mid-surface (structural and shear springs, grid vertex order) at
// several sizes, in double precision (the gathered force loop, which computes each spring
// from both of its ends) and in single precision (banded springs, each computed once), with
// one thread and with all threads. Reports seconds per step and spring evaluations per
// second (each spring counted once per step), the process's peak memory, and how far the
// state after the steps lies from the double-precision one-thread state (largest particle
// distance in mean rest lengths). CSV on standard output.
//
// Usage: vuStepThroughputBenchmark [--sizes 10k,100k,1M,4M] [--steps N]
#include "itkMassSpringSheetFlattener.h"
#include "itkMultiThreaderBase.h"
#include "vuBenchmarkCommon.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>

int
main(int argc, char * argv[])
{
  std::vector<std::string> sizes = { "roll-10k", "roll-100k", "roll-1M", "roll-4M" };
  int                      steps = 20;
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    if (arg == "--sizes" && a + 1 < argc)
    {
      sizes.clear();
      for (const std::string & s : vu::SplitList(argv[++a]))
      {
        sizes.push_back("roll-" + s);
      }
    }
    else if (arg == "--steps" && a + 1 < argc)
    {
      steps = std::stoi(argv[++a]);
    }
    else
    {
      std::cerr << "usage: vuStepThroughputBenchmark [--sizes 10k,100k,1M,4M] [--steps N]" << std::endl;
      return 2;
    }
  }
  const unsigned int allThreads = itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads();
  std::cout << "mesh,particles,springs,precision,threads,seconds_per_step,spring_evaluations_per_second,"
               "peak_memory_mib,largest_difference_rest_lengths\n";
  for (const std::string & name : sizes)
  {
    const itk::SheetMesh mesh = vu::BenchmarkMesh(name);
    std::vector<double>  reference; // the double-precision state after the steps, one thread
    for (bool single : { false, true })
    {
      for (unsigned int threads : { 1u, allThreads })
      {
        itk::MassSpringFlatteningParameters parameters;
        parameters.NumberOfWorkUnits = threads;
        itk::MassSpringSystem system;
        itk::MassSpringSheetFlattener::BuildSystem(mesh, parameters, system);
        system.SetIntegrator(itk::MassSpringIntegratorEnum::SymplecticEuler);
        system.SetTimeStep(0.5 * 2.0 / system.EstimateMaximumAngularFrequency());
        system.SetGravity({ 0.0, -1e-3, 0.0 });
        system.SetDivergenceCheckInterval(1000000);
        system.SetSinglePrecision(single);
        system.Step(); // builds the adjacency or the bands and loads the state
        const auto start = std::chrono::steady_clock::now();
        for (int s = 0; s < steps; ++s)
        {
          system.Step();
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / steps;
        // How far this run's state lies from the double-precision one (largest particle
        // distance, in mean rest lengths); reading it converts the state to double.
        const std::vector<double> & x = system.GetPositions();
        if (reference.empty())
        {
          reference = x;
        }
        double largest = 0.0;
        for (size_t i = 0; i < x.size(); i += 3)
        {
          largest = std::max(largest,
                             std::hypot(x[i] - reference[i], x[i + 1] - reference[i + 1], x[i + 2] - reference[i + 2]));
        }
        rusage usage{};
        getrusage(RUSAGE_SELF, &usage);
        std::cout << name << ',' << system.GetNumberOfParticles() << ',' << system.GetNumberOfSprings() << ','
                  << (single ? "single" : "double") << ',' << threads << ',' << seconds << ','
                  << system.GetNumberOfSprings() / seconds << ',' << usage.ru_maxrss / 1024.0 << ','
                  << largest / system.GetMeanRestLength() << '\n'
                  << std::flush;
      }
    }
  }
  return 0;
}

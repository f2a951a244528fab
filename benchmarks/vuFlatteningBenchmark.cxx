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
// Speed against accuracy of flattening methods on the same meshes: the mass-spring
// flattener with each integrator over a range of time steps, and ITK's
// ParameterizationQuadEdgeMeshFilter (fixed square or disk border, harmonic or conformal
// weights) as an in-process peer. CGAL's LSCM and ARAP run in vuCgalFlatteningBenchmark
// on the same meshes. One CSV row per run (see vuBenchmarkCommon.h).
//
// Usage: vuFlatteningBenchmark [--meshes roll-10k,roll-100k,roll-1M,dome-10k]
//                              [--methods implicit,explicit,itk] [--csv FILE] [--quick]
#include "VNLIterativeSparseSolverTraits.h"
#include "itkBorderQuadEdgeMeshFilter.h"
#include "itkMassSpringSheetFlattener.h"
#include "itkParameterizationQuadEdgeMeshFilter.h"
#include "itkQuadEdgeMesh.h"
#include "itkQuadEdgeMeshParamMatrixCoefficients.h"
#include "itkSheetMeshAdaptor.h"
#include "vuBenchmarkCommon.h"

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>

namespace {
using Clock = std::chrono::steady_clock;

void
RunMassSpring(std::ostream &                              out,
              const std::string &                         meshName,
              const itk::SheetMesh &                      surface,
              const itk::MassSpringFlatteningParameters & parameters,
              const std::string &                         setting)
{
  itk::MassSpringSheetFlattener flattener;
  flattener.SetParameters(parameters);
  const std::string method = std::string("mass-spring/") + itk::ToString(parameters.Integrator);
  const auto        start = Clock::now();
  try
  {
    const itk::SheetMesh flat = flattener.Flatten(surface);
    const double         seconds = std::chrono::duration<double>(Clock::now() - start).count();
    std::string          status = "converged";
    for (const auto & phase : flattener.GetReport().Phases)
    {
      if (phase.StopReason != "converged")
      {
        status = itk::ToString(phase.Name) + std::string(" ") + phase.StopReason;
      }
      std::cerr << meshName << " " << method << ": " << itk::ToString(phase.Name) << " " << phase.Steps << " steps, "
                << phase.Seconds << " s" << std::endl;
    }
    vu::WriteFlatteningCsvRow(out, meshName, surface, flat, method, setting, seconds, status, false);
  }
  catch (const itk::MassSpringDivergenceError &)
  {
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    vu::WriteFlatteningCsvRow(out, meshName, surface, {}, method, setting, seconds, "diverged", false);
  }
}

template <typename TCoefficients>
void
RunItkParameterization(std::ostream &                                               out,
                       const std::string &                                          meshName,
                       const itk::SheetMesh &                                       surface,
                       typename itk::BorderQuadEdgeMeshFilterEnums::BorderTransform border,
                       const std::string &                                          setting)
{
  using MeshType = itk::QuadEdgeMesh<double, 3>;
  using SolverTraits = VNLIterativeSparseSolverTraits<double>;
  using FilterType = itk::ParameterizationQuadEdgeMeshFilter<MeshType, MeshType, SolverTraits>;
  using BorderType = itk::BorderQuadEdgeMeshFilter<MeshType, MeshType>;
  auto       input = itk::SheetMeshToMesh<MeshType>(surface);
  const auto start = Clock::now();
  auto       borderFilter = BorderType::New();
  borderFilter->SetInput(input);
  borderFilter->SetTransformType(border);
  borderFilter->SetBorderPick(itk::BorderQuadEdgeMeshFilterEnums::BorderPick::LONGEST);
  TCoefficients coefficients;
  auto          filter = FilterType::New();
  filter->SetInput(input);
  filter->SetBorderTransform(borderFilter);
  filter->SetCoefficientsMethod(&coefficients);
  itk::SheetMesh flat;
  std::string    status = "converged";
  try
  {
    filter->Update();
    flat = surface;
    for (size_t i = 0; i < surface.GetNumberOfPoints(); ++i)
    {
      const auto p = filter->GetOutput()->GetPoint(i);
      flat.Points[3 * i] = p[0];
      flat.Points[3 * i + 1] = p[1];
      flat.Points[3 * i + 2] = 0.0;
    }
  }
  catch (const itk::ExceptionObject & e)
  {
    status = "failed";
    std::cerr << "itk-parameterization (" << setting << ") on " << meshName << ": " << e.GetDescription() << std::endl;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  vu::WriteFlatteningCsvRow(out, meshName, surface, flat, "itk-parameterization", setting, seconds, status, true);
}
} // namespace

int
main(int argc, char * argv[])
{
  vu::FlatteningBenchmarkOptions options{ { "roll-10k", "roll-100k", "roll-1M", "dome-10k" },
                                          { "implicit", "explicit", "itk" },
                                          "" };
  bool                           quick = false;
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    if (vu::ReadFlatteningBenchmarkOption(argc, argv, a, options))
    {
      continue;
    }
    if (arg == "--quick")
    {
      quick = true;
      options.Meshes = { "roll-1k", "dome-400" };
    }
    else
    {
      return vu::FlatteningBenchmarkUsage("vuFlatteningBenchmark", "implicit,explicit,itk", "[--quick]");
    }
  }
  std::ofstream  file;
  std::ostream & out = vu::OpenFlatteningCsv(options.CsvPath, file);
  auto           wants = [&](const std::string & m) {
    return std::find(options.Methods.begin(), options.Methods.end(), m) != options.Methods.end();
  };

  for (const std::string & meshName : options.Meshes)
  {
    const itk::SheetMesh                surface = vu::BenchmarkMesh(meshName);
    const bool                          roll = meshName.rfind("roll", 0) == 0;
    const size_t                        n = surface.GetNumberOfPoints();
    itk::MassSpringFlatteningParameters base;
    base.LockedEdge = roll ? itk::SheetLockedEdgeEnum::OuterEdge : itk::SheetLockedEdgeEnum::None;
    if (wants("implicit"))
    {
      RunMassSpring(out, meshName, surface, base, "auto");
      if (n <= 20000)
      {
        auto full = base;
        full.CoarseningFactor = 1;
        RunMassSpring(out, meshName, surface, full, "full-mesh");
      }
      for (double stepsPerFall : quick || n > 200000 ? std::vector<double>{} : std::vector<double>{ 10.0, 160.0 })
      {
        auto p = base;
        p.StepsPerFallTime = stepsPerFall;
        RunMassSpring(out, meshName, surface, p, "h=fall time/" + std::to_string(int(stepsPerFall)));
      }
    }
    if (wants("explicit") && n <= 200000)
    {
      for (auto integrator : { itk::MassSpringIntegratorEnum::ExplicitEuler,
                               itk::MassSpringIntegratorEnum::Midpoint,
                               itk::MassSpringIntegratorEnum::SymplecticEuler,
                               itk::MassSpringIntegratorEnum::RungeKutta4 })
      {
        for (double safety : quick ? std::vector<double>{ 0.5 } : std::vector<double>{ 0.5, 0.9, 1.2 })
        {
          auto p = base;
          p.Integrator = integrator;
          p.TimeStepSafety = safety;
          p.MaximumStepsPerPhase = quick ? 5000 : 30000;
          std::ostringstream setting;
          setting << "h=" << safety << "x bound";
          RunMassSpring(out, meshName, surface, p, setting.str());
        }
      }
    }
    if (wants("itk") && n <= 200000)
    {
      using QEMesh = itk::QuadEdgeMesh<double, 3>;
      RunItkParameterization<itk::HarmonicMatrixCoefficients<QEMesh>>(
        out,
        meshName,
        surface,
        itk::BorderQuadEdgeMeshFilterEnums::BorderTransform::SQUARE_BORDER_TRANSFORM,
        "harmonic/square border");
      RunItkParameterization<itk::ConformalMatrixCoefficients<QEMesh>>(
        out,
        meshName,
        surface,
        itk::BorderQuadEdgeMeshFilterEnums::BorderTransform::DISK_BORDER_TRANSFORM,
        "conformal/disk border");
    }
  }
  return 0;
}

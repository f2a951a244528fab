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
#include "vuBenchmarkCommon.h"

#include "itkFlatteningDistortionCalculator.h"
#include "itkSheetPhantomSource.h"
#include "vuTestMeshes.h"

#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace vu {
itk::SheetMesh
BenchmarkRollMesh(size_t targetVertices)
{
  auto source = itk::SheetPhantomSource::New();
  source->ApplyPreset("standard");
  source->UpdateOutputInformation();
  const itk::SheetPhantomGeometry & geometry = source->GetGeometry();
  const double spacing = std::sqrt(geometry.GetSheetLength() * geometry.GetSheetWidth() / double(targetVertices));
  return geometry.MakeMidSurfaceMesh(spacing);
}

itk::SheetMesh
BenchmarkDomeMesh(size_t targetVertices)
{
  return DomeMesh(10.0, 0.6, static_cast<int>(std::sqrt(double(targetVertices))));
}

itk::SheetMesh
BenchmarkMesh(const std::string & name)
{
  const auto dash = name.find('-');
  if (dash == std::string::npos)
  {
    throw std::invalid_argument("mesh name " + name + " is not shape-count");
  }
  const std::string shape = name.substr(0, dash);
  std::string       count = name.substr(dash + 1);
  double            scale = 1.0;
  if (!count.empty() && (count.back() == 'k' || count.back() == 'M'))
  {
    scale = count.back() == 'k' ? 1e3 : 1e6;
    count.pop_back();
  }
  const auto vertices = static_cast<size_t>(std::stod(count) * scale);
  if (shape == "roll")
  {
    return BenchmarkRollMesh(vertices);
  }
  if (shape == "dome")
  {
    return BenchmarkDomeMesh(vertices);
  }
  throw std::invalid_argument("unknown mesh shape " + shape + " (roll, dome)");
}

std::vector<std::string>
SplitList(const std::string & text)
{
  std::vector<std::string> parts;
  std::stringstream        stream(text);
  std::string              part;
  while (std::getline(stream, part, ','))
  {
    parts.push_back(part);
  }
  return parts;
}

void
WriteFlatteningCsvHeader(std::ostream & out)
{
  out << "mesh,vertices,method,setting,seconds,status,edge_strain_mean,edge_strain_p95,edge_strain_max,"
         "area_distortion,total_area_ratio,angle_distortion_deg,l2_stretch,linf_stretch,flipped,scale_applied\n";
}

bool
ReadFlatteningBenchmarkOption(int argc, char * argv[], int & a, FlatteningBenchmarkOptions & options)
{
  const std::string arg = argv[a];
  if (a + 1 >= argc)
  {
    return false;
  }
  if (arg == "--meshes")
  {
    options.Meshes = SplitList(argv[++a]);
  }
  else if (arg == "--methods")
  {
    options.Methods = SplitList(argv[++a]);
  }
  else if (arg == "--csv")
  {
    options.CsvPath = argv[++a];
  }
  else
  {
    return false;
  }
  return true;
}

int
FlatteningBenchmarkUsage(const std::string & program, const std::string & methods, const std::string & extra)
{
  std::cerr << "usage: " << program << " [--meshes LIST] [--methods " << methods << "] [--csv FILE] " << extra
            << std::endl;
  return 2;
}

std::ostream &
OpenFlatteningCsv(const std::string & path, std::ofstream & file)
{
  if (!path.empty())
  {
    file.open(path);
  }
  std::ostream & out = path.empty() ? std::cout : file;
  WriteFlatteningCsvHeader(out);
  return out;
}

void
WriteFlatteningCsvRow(std::ostream &         out,
                      const std::string &    meshName,
                      const itk::SheetMesh & surface,
                      const itk::SheetMesh & flat,
                      const std::string &    method,
                      const std::string &    setting,
                      double                 seconds,
                      const std::string &    status,
                      bool                   rescale)
{
  out << meshName << ',' << surface.GetNumberOfPoints() << ',' << method << ',' << setting << ',' << seconds << ','
      << status;
  if (flat.Points.empty())
  {
    out << ",,,,,,,,,,\n";
    out.flush();
    return;
  }
  itk::SheetMesh measured = flat;
  double         scale = 1.0;
  if (rescale)
  {
    // Least-squares uniform scale of the flat edge lengths onto the 3D ones.
    const std::vector<uint32_t> edges = surface.ComputeEdges();
    double                      num = 0.0, den = 0.0;
    for (size_t e = 0; e < edges.size(); e += 2)
    {
      const double * a3 = &surface.Points[3 * edges[e]];
      const double * b3 = &surface.Points[3 * edges[e + 1]];
      const double * a2 = &flat.Points[3 * edges[e]];
      const double * b2 = &flat.Points[3 * edges[e + 1]];
      const double   l3 = std::sqrt((a3[0] - b3[0]) * (a3[0] - b3[0]) + (a3[1] - b3[1]) * (a3[1] - b3[1]) +
                                  (a3[2] - b3[2]) * (a3[2] - b3[2]));
      const double   l2 = std::hypot(a2[0] - b2[0], a2[1] - b2[1]);
      num += l3 * l2;
      den += l2 * l2;
    }
    scale = den > 0.0 ? num / den : 1.0;
    for (size_t i = 0; i < measured.GetNumberOfPoints(); ++i)
    {
      measured.Points[3 * i] *= scale;
      measured.Points[3 * i + 1] *= scale;
      measured.Points[3 * i + 2] = 0.0;
    }
  }
  auto c = itk::FlatteningDistortionCalculator::New();
  c->SetSurfaceMesh(surface);
  c->SetFlatMesh(measured);
  c->Compute();
  out << ',' << c->GetEdgeStrainMean() << ',' << c->GetEdgeStrainP95() << ',' << c->GetEdgeStrainMax() << ','
      << c->GetAreaDistortion() << ',' << c->GetTotalAreaRatio() << ',' << c->GetAngleDistortionDegrees() << ','
      << c->GetL2Stretch() << ',' << c->GetLinfStretch() << ',' << c->GetNumberOfFlippedTriangles() << ',' << scale
      << '\n';
  out.flush();
}
} // namespace vu

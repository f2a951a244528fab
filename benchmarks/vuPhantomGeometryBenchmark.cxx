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
// Speed of the ground-truth queries that accuracy metrics rely on: a one-million-vertex
// mid-surface mesh of the standard phantom's sheet, and Project() of one million points
// scattered within a few voxels of the sheet. Prints one JSON line.
#include "itkSheetPhantomSource.h"

#include <chrono>
#include <cmath>
#include <iostream>
#include <random>

int
main()
{
  auto source = itk::SheetPhantomSource::New();
  source->ApplyPreset("standard");
  source->UpdateOutputInformation();
  const itk::SheetPhantomGeometry & geometry = source->GetGeometry();
  using Clock = std::chrono::steady_clock;

  // Spacing that gives about 1e6 vertices over the sheet.
  const double spacing = std::sqrt(geometry.GetSheetLength() * geometry.GetSheetWidth() / 1.0e6);
  auto         start = Clock::now();
  const auto   mesh = geometry.MakeMidSurfaceMesh(spacing);
  const double meshSeconds = std::chrono::duration<double>(Clock::now() - start).count();

  std::mt19937                           random(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const size_t                           count = 1000000;
  std::vector<double>                    points(3 * count);
  const double                           offset = 4.0 * source->GetVoxelSize();
  for (size_t i = 0; i < count; ++i)
  {
    double       p[3], n[3];
    const double s = unit(random) * geometry.GetSheetLength(), w = unit(random) * geometry.GetSheetWidth();
    const double d = offset * (2.0 * unit(random) - 1.0);
    geometry.SurfacePoint(s, w, p);
    geometry.SurfaceNormal(s, w, n);
    for (int k = 0; k < 3; ++k)
    {
      points[3 * i + k] = p[k] + d * n[k];
    }
  }
  start = Clock::now();
  double checksum = 0.0;
  for (size_t i = 0; i < count; ++i)
  {
    double s, w, d;
    geometry.Project(&points[3 * i], s, w, d);
    checksum += std::abs(d);
  }
  const double projectSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::cout << "{\"mesh_vertices\": " << mesh.GetNumberOfPoints() << ", \"mesh_seconds\": " << meshSeconds
            << ", \"projected_points\": " << count << ", \"project_seconds\": " << projectSeconds
            << ", \"mean_abs_distance_mm\": " << checksum / count << "}" << std::endl;
  return 0;
}

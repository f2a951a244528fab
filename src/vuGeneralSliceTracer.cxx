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
#include "vuGeneralSliceTracer.h"
#include "vuMedian.h"
#include "vuRollTracer.h"

#include "itkBinaryThinningImageFilter.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkImage.h"
#include "itkRelabelComponentImageFilter.h"

#include <algorithm>
#include <deque>
#include <limits>

namespace itk {
namespace SheetTracing {
namespace {
using RollTracing::Median;

// Weighted centroid of the sheet along a line p + u n, u in [lo, hi]: intensity above the
// air/material midpoint when available (sub-voxel middle of the sheet), else the mask.
double
CentreAlongLine(const SliceSampler & sampler,
                const TraceContext & context,
                const double         p[2],
                const double         n[2],
                double               lo,
                double               hi,
                double               step)
{
  double sum = 0.0, moment = 0.0;
  for (double u = lo; u <= hi + 1e-12; u += step)
  {
    const double x = p[0] + u * n[0], y = p[1] + u * n[1];
    const double weight = sampler.HasIntensity()
                            ? std::max(0.0, sampler.Intensity(x, y, context.AirLevel) - context.Base)
                            : sampler.Mask(x, y);
    sum += weight;
    moment += weight * u;
  }
  return sum > 0.0 ? moment / sum : 0.5 * (lo + hi);
}

} // namespace

Polyline
TraceGeneralSlice(const SliceSampler & sampler, const TraceContext & context, double spacingY)
{
  using SliceImage = Image<uint8_t, 2>;
  using LabelImage = Image<uint32_t, 2>;
  auto                   slice = SliceImage::New();
  SliceImage::RegionType region;
  region.SetSize({ { sampler.NX(), sampler.NY() } });
  slice->SetRegions(region);
  slice->Allocate();
  std::transform(sampler.MaskPointer(),
                 sampler.MaskPointer() + sampler.NX() * sampler.NY(),
                 slice->GetBufferPointer(),
                 [](uint8_t v) { return static_cast<uint8_t>(v != 0 ? 1 : 0); });
  auto components = ConnectedComponentImageFilter<SliceImage, LabelImage>::New();
  components->SetInput(slice);
  components->FullyConnectedOn();
  components->SetNumberOfWorkUnits(1);
  auto relabel = RelabelComponentImageFilter<LabelImage, LabelImage>::New();
  relabel->SetInput(components->GetOutput());
  relabel->SetNumberOfWorkUnits(1);
  relabel->Update();
  const uint32_t * labels = relabel->GetOutput()->GetBufferPointer();
  uint8_t *        pixels = slice->GetBufferPointer();
  for (size_t i = 0; i < sampler.NX() * sampler.NY(); ++i)
  {
    pixels[i] = labels[i] == 1 ? 1 : 0;
  }
  auto thinning = BinaryThinningImageFilter<SliceImage, SliceImage>::New();
  thinning->SetInput(slice);
  thinning->SetNumberOfWorkUnits(1);
  thinning->Update();
  const uint8_t * skeleton = thinning->GetOutput()->GetBufferPointer();

  const auto nx = static_cast<long>(sampler.NX()), ny = static_cast<long>(sampler.NY());
  // Breadth-first distances over the 8-connected skeleton; the farthest pixel from any
  // pixel is an end of the longest path, and the farthest from that end the other end.
  std::vector<long> parent(static_cast<size_t>(nx * ny), -1);
  auto              farthest = [&](long from) {
    std::vector<int> distance(static_cast<size_t>(nx * ny), -1);
    std::deque<long> queue{ from };
    distance[static_cast<size_t>(from)] = 0;
    parent[static_cast<size_t>(from)] = -1;
    long last = from;
    while (!queue.empty())
    {
      const long p = queue.front();
      queue.pop_front();
      last = p;
      const long px = p % nx, py = p / nx;
      for (long dy = -1; dy <= 1; ++dy)
      {
        for (long dx = -1; dx <= 1; ++dx)
        {
          const long qx = px + dx, qy = py + dy;
          if ((dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= nx || qy >= ny)
          {
            continue;
          }
          const long q = qy * nx + qx;
          if (skeleton[q] != 0 && distance[static_cast<size_t>(q)] < 0)
          {
            distance[static_cast<size_t>(q)] = distance[static_cast<size_t>(p)] + 1;
            parent[static_cast<size_t>(q)] = p;
            queue.push_back(q);
          }
        }
      }
    }
    return last;
  };
  long seed = -1;
  for (long p = 0; p < nx * ny && seed < 0; ++p)
  {
    if (skeleton[p] != 0)
    {
      seed = p;
    }
  }
  if (seed < 0)
  {
    return {};
  }
  const long end = farthest(farthest(seed));
  Polyline   line;
  for (long p = end; p >= 0; p = parent[static_cast<size_t>(p)])
  {
    line.push_back(static_cast<double>(p % nx) * context.Voxel);
    line.push_back(static_cast<double>(p / nx) * spacingY);
  }
  if (PolylineSize(line) < 3)
  {
    return {};
  }
  line = Smooth(line, 3);

  // Move each point to the middle of the sheet along the curve's normal.
  const double thickness = static_cast<double>(sampler.CountMaterial()) * context.Voxel * spacingY / ArcLength(line);
  const double reach = 0.5 * thickness + context.Voxel;
  Polyline     refined(line);
  const size_t n = PolylineSize(line);
  for (size_t i = 0; i < n; ++i)
  {
    double       chord[2];
    const double norm = NeighbourChord(line, i, chord);
    if (norm <= 0.0)
    {
      continue;
    }
    const double normal[2] = { -chord[1] / norm, chord[0] / norm };
    const double point[2] = { line[2 * i], line[2 * i + 1] };
    const double shift =
      std::clamp(CentreAlongLine(sampler, context, point, normal, -reach, reach, 0.25 * context.Voxel),
                 -0.5 * thickness,
                 0.5 * thickness);
    refined[2 * i] += shift * normal[0];
    refined[2 * i + 1] += shift * normal[1];
  }
  refined = Smooth(refined, 2);
  RollTracing::ExtendEnds(
    refined,
    [&](double x, double y) { return sampler.Mask(x, y) >= 0.5; },
    context.Voxel,
    2.0 * thickness + 2.0 * context.Voxel);
  return refined;
}
} // namespace SheetTracing
} // end namespace itk

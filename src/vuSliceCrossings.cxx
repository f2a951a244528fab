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
// The roll tracer's polar frame, the slices' samples on it and the crossings of the sheet
// with its rays.
#include "vuMedian.h"
#include "vuSliceTracer.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace itk {
namespace RollTracing {
std::vector<double>
SheetRadii(const std::vector<Crossing> & list)
{
  std::vector<double> radii;
  radii.reserve(list.size() + 2);
  for (const Crossing & c : list)
  {
    radii.push_back(c.Inner);
    if (c.Band())
    {
      radii.push_back(c.Outer);
    }
  }
  return radii;
}

void
Tracer::BuildFrame(const std::vector<size_t> & slices)
{
  const size_t        nx = m_Volume.Size[0], ny = m_Volume.Size[1];
  std::vector<double> reach(slices.size(), 0.0);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    slices.size(),
    [&](SizeValueType q) {
      const size_t    k = slices[q];
      const uint8_t * mask = m_Volume.Mask + k * nx * ny;
      double          c[2];
      Centre(k, c);
      double r2 = 0.0;
      for (size_t j = 0; j < ny; ++j)
      {
        for (size_t i = 0; i < nx; ++i)
        {
          if (mask[j * nx + i] != 0)
          {
            const double dx = static_cast<double>(i) * m_Volume.Spacing[0] - c[0];
            const double dy = static_cast<double>(j) * m_Volume.Spacing[1] - c[1];
            r2 = std::max(r2, dx * dx + dy * dy);
          }
        }
      }
      reach[q] = std::sqrt(r2);
    },
    nullptr);
  const double voxel = m_Settings.Voxel;
  m_Frame.RMax = *std::max_element(reach.begin(), reach.end()) + 2.0 * voxel;
  m_Frame.Dr = 0.25 * voxel;
  m_Frame.Samples = static_cast<size_t>(std::ceil(m_Frame.RMax / m_Frame.Dr)) + 1;
  m_Frame.Rays = std::max(16L, static_cast<long>(std::ceil(2.0 * Pi * m_Frame.RMax / (0.5 * voxel))));
  m_Frame.Step = 2.0 * Pi / static_cast<double>(m_Frame.Rays);
}

namespace {
// Tracer::Sample's common case, one ray of a single slice, compiled twice on x86-64 with
// GCC (for AVX2, whose rounding instruction takes the floors in Value, and for the
// baseline) and picked by the loader: the same arithmetic, value for value.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void
SampleRay(const ValueSlice & slice,
          const double       centre[2],
          const double       direction[2],
          double             dr,
          size_t             samples,
          double             air,
          double             contrast,
          float *            out)
{
  for (size_t j = 0; j < samples; ++j)
  {
    const double r = static_cast<double>(j) * dr;
    const double x = centre[0] + r * direction[0], y = centre[1] + r * direction[1];
    out[j] = static_cast<float>((slice.Value(x, y, air) - air) / contrast);
  }
}
} // namespace

PolarSlice
Tracer::Sample(size_t centreSlice, const std::vector<size_t> & slices, bool markNoData, bool parallel) const
{
  PolarSlice polar;
  polar.Rays = m_Frame.Rays;
  polar.Samples = static_cast<long>(m_Frame.Samples);
  polar.Dr = m_Frame.Dr;
  polar.Values.resize(static_cast<size_t>(polar.Rays) * m_Frame.Samples);
  if (markNoData && m_Volume.Data != nullptr)
  {
    polar.Known.assign(polar.Values.size(), 1);
  }
  std::vector<ValueSlice> samplers;
  for (size_t k : slices)
  {
    samplers.emplace_back(m_Volume, m_Values, k);
  }
  double c[2];
  Centre(centreSlice, c);
  const double air = m_Settings.AirLevel;
  auto         sampleRay = [&](long a) {
    const double direction[2] = { std::cos(a * m_Frame.Step), std::sin(a * m_Frame.Step) };
    const auto   row = static_cast<size_t>(a * polar.Samples);
    if (samplers.size() == 1 && polar.Known.empty())
    {
      SampleRay(samplers.front(), c, direction, m_Frame.Dr, m_Frame.Samples, air, m_Contrast, &polar.Values[row]);
      return;
    }
    for (size_t j = 0; j < m_Frame.Samples; ++j)
    {
      const double r = static_cast<double>(j) * m_Frame.Dr;
      const double x = c[0] + r * direction[0], y = c[1] + r * direction[1];
      double       sum = 0.0;
      for (const ValueSlice & sampler : samplers)
      {
        sum += sampler.Value(x, y, air);
      }
      polar.Values[row + j] = static_cast<float>((sum / static_cast<double>(samplers.size()) - air) / m_Contrast);
      if (!polar.Known.empty() && !samplers.front().Inside(x, y))
      {
        polar.Known[row + j] = 0;
      }
    }
  };
  ForEachIndex(m_Frame.Rays, parallel, sampleRay);
  return polar;
}

std::vector<Crossing>
Tracer::Peaks(const std::vector<double> & p) const
{
  const double      level = PeakLevel;
  const double      prominence = PeakProminence;
  const long        n = static_cast<long>(p.size());
  std::vector<long> peaks;
  // Within a voxel of the centre every ray sees the same material: no crossing there.
  const auto centre = static_cast<long>(std::ceil(m_Settings.Voxel / m_Frame.Dr));
  for (long j = std::max(1L, centre); j + 1 < n; ++j)
  {
    if (p[j] >= level && p[j] >= p[j - 1] && p[j] > p[j + 1])
    {
      peaks.push_back(j);
    }
  }
  // Merge peaks closer than 1.2 voxels or not separated by a dip: keep the higher.
  const long minimumSeparation = static_cast<long>(std::ceil(1.2 * m_Settings.Voxel / m_Frame.Dr));
  // The first pair that merges, again and again: the pairs before the one a merge changed
  // were kept and are not looked at again.
  bool   changed = true;
  size_t from = 0;
  while (changed && peaks.size() > 1)
  {
    changed = false;
    for (size_t q = from; q + 1 < peaks.size(); ++q)
    {
      const long   a = peaks[q], b = peaks[q + 1];
      const double dip = *std::min_element(p.begin() + a, p.begin() + b + 1);
      if (b - a < minimumSeparation || std::min(p[a], p[b]) - dip < prominence)
      {
        peaks.erase(peaks.begin() + static_cast<std::ptrdiff_t>(p[a] >= p[b] ? q + 1 : q));
        from = q > 0 ? q - 1 : 0;
        changed = true;
        break;
      }
    }
  }
  std::vector<Crossing> crossings;
  for (size_t q = 0; q < peaks.size(); ++q)
  {
    const long   lo = q > 0 ? peaks[q - 1] : 0, hi = q + 1 < peaks.size() ? peaks[q + 1] : n - 1;
    const long   j = peaks[q];
    const double left = *std::min_element(p.begin() + lo, p.begin() + j + 1);
    const double right = *std::min_element(p.begin() + j, p.begin() + hi + 1);
    // Weights above the higher of the dips beside the peak and the air/material midpoint:
    // the whole crossing, sub-voxel, but not its neighbours' flanks.
    const double half = std::max({ left, right, MaterialLevel });
    long         first = j, last = j;
    while (first > lo && p[first - 1] > half)
    {
      --first;
    }
    while (last < hi && p[last + 1] > half)
    {
      ++last;
    }
    // Centroid (sub-voxel) of p - half over [from, to]; `fallback` where it is empty.
    auto centroid = [&](long from, long to, double fallback) {
      double sum = 0.0, moment = 0.0;
      for (long i = from; i <= to; ++i)
      {
        sum += p[i] - half;
        moment += (p[i] - half) * static_cast<double>(i);
      }
      return (sum > 0.0 ? moment / sum : fallback) * m_Frame.Dr;
    };
    const long   count = last - first + 1;
    const double width = static_cast<double>(count) * m_Frame.Dr;
    Crossing     crossing;
    crossing.Radius = centroid(first, last, static_cast<double>(j));
    crossing.Width = width;
    crossing.Mass = std::accumulate(p.begin() + first, p.begin() + last + 1, 0.0) * m_Frame.Dr;
    crossing.Inner = crossing.Outer = crossing.Radius;
    crossing.InnerHalf = crossing.OuterHalf = crossing.Radius;
    if (count >= 2)
    {
      const long middle = first + count / 2;
      crossing.InnerHalf = centroid(first, middle - 1, 0.5 * static_cast<double>(first + middle - 1));
      crossing.OuterHalf = centroid(middle, last, 0.5 * static_cast<double>(middle + last));
    }
    const double widths = width / m_Width, masses = crossing.Mass / m_Mass;
    if (m_WidthMeasured && (widths > SplitWidth || masses > SplitMass))
    {
      const long pieces = std::max(2L, std::lround(std::max(widths, masses)));
      const long inner = first + count / pieces - 1, outer = first + (pieces - 1) * count / pieces;
      crossing.Inner = centroid(first, inner, 0.5 * static_cast<double>(first + inner));
      crossing.Outer = centroid(outer, last, 0.5 * static_cast<double>(outer + last));
    }
    crossings.push_back(crossing);
  }
  return crossings;
}

void
Tracer::MeasurePitch(const SliceCrossings & crossings)
{
  std::vector<double> spacings, widths, masses;
  for (const auto & list : crossings.Rays)
  {
    for (size_t q = 0; q < list.size(); ++q)
    {
      widths.push_back(list[q].Width);
      masses.push_back(list[q].Mass);
      if (q > 0)
      {
        spacings.push_back(list[q].Radius - list[q - 1].Radius);
      }
    }
  }
  m_Pitch = spacings.empty() ? m_Frame.RMax : Median(spacings);
  m_Width = Median(widths);
  m_Mass = Median(masses);
  m_WidthMeasured = m_Width > 0.0 && m_Mass > 0.0;
}
} // namespace RollTracing
} // end namespace itk

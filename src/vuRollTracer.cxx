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
#include "vuRollTracer.h"
#include "vuMedian.h"
#include "vuSpiralPath.h"

#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <future>
#include <limits>
#include <numeric>
#include <optional>
#include <thread>

namespace itk {
namespace RollTracing {
namespace {
constexpr double Pi = 3.14159265358979323846;

// A crossing must rise above air by this fraction of the sheet's contrast, and stand out
// of the dips on both sides by PeakProminence, to count as a sheet (not noise).
constexpr double PeakLevel = 0.3;
constexpr double PeakProminence = 0.1;
// Intensity, as a fraction of the contrast, above which a point is taken to hold material.
constexpr double MaterialLevel = 0.5;
// A crossing wider than this many typical sheet widths, or holding this many times the
// typical sheet's material (its profile's area: blur widens a sheet but leaves its area
// alone, so two blurred sheets that touch are barely wider than one but hold twice its
// material), is two or more turns that touch: it is traced on its inner or outer sheet,
// never on its middle, which lies between two turns.
constexpr double SplitWidth = 1.6;
constexpr double SplitMass = 1.6;
// The next crossing is accepted within this fraction of the local turn spacing.
constexpr double AcceptWindow = 0.4;
// Slices averaged on each side of the seed slice.
constexpr long SeedHalfWidth = 3;
// How much more of its crossings another candidate seed slice's trace must explain than
// the middle one's to be taken instead.
constexpr double SeedPreference = 0.05;
// How much more of the seed slice's crossings its trace turn by turn (minimal paths) must
// explain than the crossing follower's to be taken instead.
constexpr double PathsPreference = 0.02;
// Rays on which the seed slice's trace is started (at three depths each).
constexpr long AloneRays = 8;
// Voxels from the edge of the scan's data within which the intensities are not trusted.
constexpr long DataMargin = 3;

// Least-squares line y = intercept + slope x through the points added.
struct LineFit
{
  double SX{ 0.0 }, SY{ 0.0 }, SXX{ 0.0 }, SXY{ 0.0 }, N{ 0.0 };
  void
  Add(double x, double y)
  {
    SX += x;
    SY += y;
    SXX += x * x;
    SXY += x * y;
    N += 1.0;
  }
  // False (slope 0 through the mean) when the points do not span two x.
  bool
  Solve(double & intercept, double & slope) const
  {
    const double denominator = N * SXX - SX * SX;
    slope = denominator > 0.0 ? (N * SXY - SX * SY) / denominator : 0.0;
    intercept = N > 0.0 ? (SY - slope * SX) / N : 0.0;
    return denominator > 0.0;
  }
};

// f(0) ... f(count - 1), shared among ITK's threads when `parallel` (never from inside a
// parallel loop: ITK's pool would wait on itself).
template <typename TFunction>
void
ForEachIndex(long count, bool parallel, TFunction f)
{
  if (parallel)
  {
    MultiThreaderBase::New()->ParallelizeArray(
      0, static_cast<SizeValueType>(count), [&](SizeValueType i) { f(static_cast<long>(i)); }, nullptr);
    return;
  }
  for (long i = 0; i < count; ++i)
  {
    f(i);
  }
}

// Runs every task: given two ITK threads or more, the first on the calling thread and each
// other on a thread of its own, at the same time; otherwise one after another. An exception
// is passed on once every task has ended.
void
RunTogether(const std::vector<std::function<void()>> & tasks)
{
  if (MultiThreaderBase::GetGlobalDefaultNumberOfThreads() < 2)
  {
    for (const auto & task : tasks)
    {
      task();
    }
    return;
  }
  std::vector<std::future<void>> others;
  for (size_t t = 1; t < tasks.size(); ++t)
  {
    others.push_back(std::async(std::launch::async, tasks[t]));
  }
  std::exception_ptr failure;
  try
  {
    tasks.front()();
  }
  catch (...)
  {
    failure = std::current_exception();
  }
  for (auto & other : others)
  {
    try
    {
      other.get();
    }
    catch (...)
    {
      failure = failure ? failure : std::current_exception();
    }
  }
  if (failure)
  {
    std::rethrow_exception(failure);
  }
}

// Bilinear samples of one slice of the intensities (mm of the view's frame).
class ValueSlice
{
public:
  ValueSlice(const SheetVolumeView & volume, const float * values, size_t slice)
    : m_Values(values + slice * volume.Size[0] * volume.Size[1])
    , m_Data(volume.Data != nullptr ? volume.Data + slice * volume.Size[0] * volume.Size[1] : nullptr)
    , m_NX(static_cast<long>(volume.Size[0]))
    , m_NY(static_cast<long>(volume.Size[1]))
    , m_SX(volume.Spacing[0])
    , m_SY(volume.Spacing[1])
  {}

  bool
  Inside(double x, double y) const
  {
    const double u = x / m_SX, v = y / m_SY;
    if (!(u >= 0.0 && v >= 0.0 && u <= static_cast<double>(m_NX - 1) && v <= static_cast<double>(m_NY - 1)))
    {
      return false;
    }
    // Well within the data of the scan: its edge is blurred by the interpolation and the
    // denoising, which mix in the air the resampling put beyond it.
    if (m_Data == nullptr)
    {
      return true;
    }
    const long i = std::lround(u), j = std::lround(v);
    for (const auto & [di, dj] :
         { std::pair{ 0L, 0L }, { -DataMargin, 0L }, { DataMargin, 0L }, { 0L, -DataMargin }, { 0L, DataMargin } })
    {
      const long a = i + di, b = j + dj;
      if (a >= 0 && b >= 0 && a < m_NX && b < m_NY && m_Data[b * m_NX + a] == 0)
      {
        return false;
      }
    }
    return true;
  }

  double
  Value(double x, double y, double outside) const
  {
    const double u = x / m_SX, v = y / m_SY;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto   i0 = static_cast<long>(fu), j0 = static_cast<long>(fv);
    if (i0 < 0 || j0 < 0 || i0 + 1 >= m_NX || j0 + 1 >= m_NY)
    {
      return outside;
    }
    const double  a = u - fu, b = v - fv;
    const float * p = m_Values + j0 * m_NX + i0;
    return (1.0 - b) * ((1.0 - a) * p[0] + a * p[1]) + b * ((1.0 - a) * p[m_NX] + a * p[m_NX + 1]);
  }

private:
  const float *   m_Values;
  const uint8_t * m_Data;
  long            m_NX, m_NY;
  double          m_SX, m_SY;
};

struct Crossing
{
  double Radius;
  double Width;
  // Area of the profile over the crossing (fraction of the contrast times length).
  double Mass;
  // A band of touching turns (wider than SplitWidth typical widths): the middles of its
  // innermost and outermost sheets; Radius for one sheet.
  double Inner;
  double Outer;

  bool
  Band() const
  {
    return Inner != Outer;
  }
  // The sheet of the crossing nearest `target`: a band's inner or outer sheet, never its
  // middle, which lies between two turns.
  double
  SheetNear(double target) const
  {
    return !Band() ? Radius : std::abs(Inner - target) <= std::abs(Outer - target) ? Inner : Outer;
  }
};

// The radii of the sheets a ray crosses, in order: a band's inner and outer sheets apart.
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

// The polar frame shared by all slices: ray a at angle a * Step, samples j * Dr from the
// slice's centre. One angular index m = a + turn * Rays runs along the spiral.
struct PolarFrame
{
  long   Rays{ 0 };
  double Step{ 0.0 };
  double Dr{ 0.0 };
  size_t Samples{ 0 };
  double RMax{ 0.0 };
};

// Crossings of the sheet with every ray of a slice: peaks of the (averaged) profile.
struct SliceCrossings
{
  std::vector<std::vector<Crossing>> Rays;
};

class Tracer
{
public:
  using Trace = SpiralTrace;

  Tracer(const SheetVolumeView & volume, const float * values, const Settings & settings)
    : m_Volume(volume)
    , m_Values(values)
    , m_Settings(settings)
    , m_Contrast(settings.SheetLevel - settings.AirLevel)
  {}

  void
  Centre(size_t slice, double c[2]) const
  {
    const double z = static_cast<double>(slice) * m_Settings.SliceSpacing;
    c[0] = m_Settings.AxisCentre[0] + m_Settings.AxisSlope[0] * z + m_Offset[0];
    c[1] = m_Settings.AxisCentre[1] + m_Settings.AxisSlope[1] * z + m_Offset[1];
  }

  void
  SetOffset(double x, double y)
  {
    m_Offset[0] = x;
    m_Offset[1] = y;
  }
  const double *
  GetOffset() const
  {
    return m_Offset;
  }

  // The polar frame: rays half a voxel apart at the outermost material of any slice.
  void
  BuildFrame(const std::vector<size_t> & slices)
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

  const PolarFrame &
  Frame() const
  {
    return m_Frame;
  }

  // The mean of `slices` on the polar frame about the centre of `centreSlice`, as a fraction
  // of the contrast; with `markNoData`, the samples where the scan holds no data are marked.
  // With `parallel`, the rays are shared among ITK's threads (not from inside a parallel loop).
  PolarSlice
  Sample(size_t centreSlice, const std::vector<size_t> & slices, bool markNoData, bool parallel = false) const
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

  // Peaks of every ray's profile.
  SliceCrossings
  FindCrossings(const PolarSlice & polar, bool parallel = false) const
  {
    SliceCrossings result;
    result.Rays.resize(static_cast<size_t>(m_Frame.Rays));
    ForEachIndex(m_Frame.Rays, parallel, [&](long a) {
      const auto begin = polar.Values.begin() + a * polar.Samples;
      result.Rays[static_cast<size_t>(a)] = Peaks(std::vector<double>(begin, begin + polar.Samples));
    });
    return result;
  }

  // The trace of a slice again, turn by turn as minimal paths bounded by the turn before,
  // from a turn of its first trace `reference`; empty where that does not hold (not a
  // spiral, a turn not found). The first trace may have crossed between turns anywhere, so
  // the turns at a quarter, half and three quarters of it are tried (in parallel; not from
  // inside a parallel loop) and the trace that passes through most crossings is kept.
  Trace
  TracePaths(const PolarSlice & polar, const Trace & reference, const SliceCrossings & crossings) const
  {
    // Only a spiral: a trace that grows by a turn spacing every turn, or by two where it
    // crossed onto the next turn.
    if (reference.Empty() || !GrowsByPitch(MedianGrowth(reference), 2.5))
    {
      return Trace{};
    }
    SpiralPathSettings settings;
    settings.Width = m_Width;
    settings.Pitch = m_Pitch;
    settings.Voxel = m_Settings.Voxel;
    const long          length = reference.Last() - reference.First;
    const long          quarters[3] = { 2, 1, 3 };
    std::vector<Trace>  traces(3);
    std::vector<double> explained(3, -1.0);
    MultiThreaderBase::New()->ParallelizeArray(
      0,
      3,
      [&](SizeValueType q) {
        traces[q] = TraceSpiralPath(polar, reference, reference.First + quarters[q] * length / 4, settings);
        SnapToCrossings(traces[q], crossings);
        explained[q] = traces[q].Empty() ? -1.0 : Explained(crossings, traces[q]);
      },
      nullptr);
    size_t best = 0;
    for (size_t q = 1; q < 3; ++q)
    {
      best = explained[q] > explained[best] ? q : best;
    }
    return explained[best] > -1.0 ? traces[best] : Trace{};
  }

  // Each step of a trace moved to the crossing of its ray nearest it, if that lies within
  // AcceptWindow of the turn spacing and not on the turn before (inwards), which took it
  // already: where two turns touch, the path of the outer one may keep to the least distance
  // from the inner one, between the two sheets, while the split band has a crossing on each.
  void
  SnapToCrossings(Trace & trace, const SliceCrossings & crossings) const
  {
    const double apart = Apart();
    const double window = AcceptWindow * m_Pitch;
    for (long m = trace.First; m <= trace.Last(); ++m)
    {
      const auto   a = static_cast<size_t>(((m % m_Frame.Rays) + m_Frame.Rays) % m_Frame.Rays);
      const double rho = trace.At(m);
      const double inner = trace.Covers(m - m_Frame.Rays) ? trace.At(m - m_Frame.Rays) : -1.0;
      double       best = rho, bestDistance = window;
      for (const double radius : SheetRadii(crossings.Rays[a]))
      {
        const double d = std::abs(radius - rho);
        if (d < bestDistance && !(inner >= 0.0 && radius - inner < apart))
        {
          best = radius;
          bestDistance = d;
        }
      }
      trace.Rho[static_cast<size_t>(m - trace.First)] = best;
    }
  }

  // Local maxima of a profile (fraction of the contrast) that rise above air by PeakLevel of the contrast and stand out
  // of their dips by PeakProminence; each placed at the centroid of its upper half.
  std::vector<Crossing>
  Peaks(const std::vector<double> & p) const
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
    bool       changed = true;
    while (changed && peaks.size() > 1)
    {
      changed = false;
      for (size_t q = 0; q + 1 < peaks.size(); ++q)
      {
        const long   a = peaks[q], b = peaks[q + 1];
        const double dip = *std::min_element(p.begin() + a, p.begin() + b + 1);
        if (b - a < minimumSeparation || std::min(p[a], p[b]) - dip < prominence)
        {
          peaks.erase(peaks.begin() + static_cast<std::ptrdiff_t>(p[a] >= p[b] ? q + 1 : q));
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


  // Radial distance to the neighbouring turns of a trace at m (0 where it has none).
  double
  TraceSpacing(const Trace & trace, long m) const
  {
    double spacing = 0.0;
    for (long other : { m - m_Frame.Rays, m + m_Frame.Rays })
    {
      if (trace.Covers(other) && trace.Covers(m))
      {
        const double d = std::abs(trace.At(other) - trace.At(m));
        spacing = spacing > 0.0 ? std::min(spacing, d) : d;
      }
    }
    return spacing;
  }

  // The sheet a ray crosses next beyond the turn before at `below`, in the direction of
  // `next`, when the sheet after it lies within AcceptWindow turn spacings of `next` (the
  // next turn): the turn between them, wherever it lies; NaN otherwise.
  double
  Between(const std::vector<Crossing> & list, double below, double next, double spacing) const
  {
    const double              apart = Apart();
    const std::vector<double> radii = SheetRadii(list);
    const long                n = static_cast<long>(radii.size());
    const long                dir = next > below ? 1 : -1;
    long                      q = dir > 0 ? 0 : n - 1;
    while (q >= 0 && q < n && dir * (radii[static_cast<size_t>(q)] - below) <= apart)
    {
      q += dir;
    }
    const long after = q + dir;
    if (q < 0 || q >= n || after < 0 || after >= n)
    {
      return std::numeric_limits<double>::quiet_NaN();
    }
    const double turn = radii[static_cast<size_t>(q)], beyond = radii[static_cast<size_t>(after)];
    const bool   nextMatches = std::abs(beyond - next) < AcceptWindow * spacing;
    const bool   separate = dir * (beyond - turn) > apart;
    return nextMatches && separate ? turn : std::numeric_limits<double>::quiet_NaN();
  }

  struct Step
  {
    long   M;
    double Rho;
    bool   Confirmed;
  };

  // Follows the spiral from (start, rho) in direction dir (+1: counter-clockwise), with the
  // trace of the neighbouring slice as prior where it has one. `opposite` holds the steps
  // already followed from the same start the other way: the turn next to the first one.
  std::vector<Step>
  Follow(const SliceCrossings &    crossings,
         const ValueSlice &        slice,
         const double              centre[2],
         const Trace *             prior,
         long                      start,
         double                    rho,
         int                       dir,
         const std::vector<Step> & opposite = {}) const
  {
    const double      voxel = m_Settings.Voxel;
    const double      material = m_Settings.AirLevel + MaterialLevel * m_Contrast;
    const double      maximumSlope = 0.05 * m_Pitch;
    std::vector<Step> steps;
    std::vector<Step> confirmed{ { start, rho, true } };
    double            slope = 0.0, offset = 0.0;
    double            missedArc = 0.0, heldArc = 0.0;
    // A held stretch (material but no separate crossing: touching turns) may be long where
    // the neighbouring slice vouches for it, short where it does not.
    const double heldWithPrior = std::max(30.0 * voxel, 2.0 * m_Pitch);
    const double heldAlone = std::max(4.0 * voxel, 1.0 * m_Pitch);
    const long   maximumSteps = m_Frame.Rays * (static_cast<long>(std::ceil(m_Frame.RMax / m_Pitch)) + 2);
    // Radius at every step taken so far (NaN where none was found): the turn traced one
    // revolution before is the best predictor of the shape of this one (an ellipse, an
    // irregular section), offset by the distance between the two.
    std::vector<double> radiusAt{ rho };
    std::vector<double> oppositeAt(static_cast<size_t>(m_Frame.Rays), std::numeric_limits<double>::quiet_NaN());
    for (const Step & o : opposite)
    {
      const long back = dir * (start - o.M); // steps taken the other way
      if (back > 0 && back <= m_Frame.Rays)
      {
        oppositeAt[static_cast<size_t>(m_Frame.Rays - back)] = o.Rho;
      }
    }
    auto turnBefore = [&](long step) {
      return step >= m_Frame.Rays ? radiusAt[static_cast<size_t>(step - m_Frame.Rays)]
                                  : oppositeAt[static_cast<size_t>(step)];
    };
    // Where the turn before was pushed onto this one (a touch), the radius it took there;
    // its shape (radiusAt) leaves the bump out. NaN elsewhere.
    std::vector<double> bumpAt{ std::numeric_limits<double>::quiet_NaN() };
    auto                bumpBefore = [&](long step) {
      return step >= m_Frame.Rays ? bumpAt[static_cast<size_t>(step - m_Frame.Rays)]
                                                 : std::numeric_limits<double>::quiet_NaN();
    };
    double              turnOffset = 0.0;
    bool                turnKnown = false;
    std::vector<double> distances;
    // The turns two and three revolutions before, each with its own distance to this one:
    // where the turn before bulges onto this one (a touch), it alone would carry the bulge
    // outwards onto the next turn; the median of the three predictions does not.
    auto turnsBefore = [&](long step, long turns) {
      const long back = step - (turns - 1) * m_Frame.Rays;
      return back >= 0 ? turnBefore(back) : std::numeric_limits<double>::quiet_NaN();
    };
    std::vector<double> farDistances[2];
    double              farOffset[2]{ 0.0, 0.0 };
    bool                farKnown[2]{ false, false };
    auto                median = [&](std::vector<double> & values, double current) {
      const size_t window = std::max<size_t>(12, static_cast<size_t>(m_Frame.Rays / 8));
      if (values.size() > 24 && values.size() % 4 != 0)
      {
        return current;
      }
      return Median(
        std::vector<double>(values.end() - static_cast<std::ptrdiff_t>(std::min(window, values.size())), values.end()));
    };
    for (long step = 1; step < maximumSteps; ++step)
    {
      radiusAt.push_back(std::numeric_limits<double>::quiet_NaN());
      bumpAt.push_back(std::numeric_limits<double>::quiet_NaN());
      const double bump = bumpBefore(step);
      const long   m = start + dir * step;
      const auto   a = static_cast<size_t>(((m % m_Frame.Rays) + m_Frame.Rays) % m_Frame.Rays);
      const Step & last = confirmed.back();
      const bool   guided = prior != nullptr && prior->Covers(m);
      const double below = turnBefore(step);
      const double far[2] = { turnsBefore(step, 2), turnsBefore(step, 3) };
      double       fromTurns = below + turnOffset;
      if (farKnown[0] && farKnown[1] && std::isfinite(far[0]) && std::isfinite(far[1]))
      {
        std::vector<double> three{ fromTurns, far[0] + farOffset[0], far[1] + farOffset[1] };
        fromTurns = Median(three);
      }
      const double predicted = guided                              ? prior->At(m) + offset
                               : turnKnown && std::isfinite(below) ? fromTurns
                                                                   : last.Rho + slope * static_cast<double>(m - last.M);
      if (predicted <= 0.0)
      {
        break;
      }
      const double x = centre[0] + predicted * std::cos(static_cast<double>(m) * m_Frame.Step);
      const double y = centre[1] + predicted * std::sin(static_cast<double>(m) * m_Frame.Step);
      const bool   outside = !slice.Inside(x, y);
      // No material lies beyond the frame's reach within the scan's data; outside it (a roll
      // cut by the field of view) the turn is carried on, as below.
      if (predicted > m_Frame.RMax && !outside)
      {
        break;
      }
      const auto & list = crossings.Rays[a];
      // The last accepted radius, carried to this step along the shape of the turn before
      // (over a stretch out of the field of view an elliptic turn's radius changes a lot).
      double lastCarried = last.Rho;
      if (turnKnown && std::isfinite(below))
      {
        const double belowLast = turnBefore(dir * (last.M - start));
        lastCarried += std::isfinite(belowLast) ? below - belowLast : 0.0;
      }
      // The crossing nearest a prediction, if it is near enough to it (and to the last
      // accepted radius) and not on the turn traced one revolution before (the trace would
      // circle); list.size() otherwise. `sheet`: the radius of its sheet nearest the
      // prediction (a band of touching turns: its inner or outer sheet).
      double sheet = 0.0;
      auto   accept = [&](double target) {
        const auto it =
          std::lower_bound(list.begin(), list.end(), target, [](const Crossing & c, double r) { return c.Radius < r; });
        size_t best = list.size();
        double bestDistance = m_Frame.RMax;
        for (auto candidate : { it, it == list.begin() ? list.end() : it - 1 })
        {
          if (candidate != list.end() && std::abs(candidate->Radius - target) < bestDistance)
          {
            bestDistance = std::abs(candidate->Radius - target);
            best = static_cast<size_t>(candidate - list.begin());
          }
        }
        if (best == list.size())
        {
          return best;
        }
        double spacing = m_Pitch;
        if (best > 0)
        {
          spacing = std::min(spacing, list[best].Radius - list[best - 1].Radius);
        }
        if (best + 1 < list.size())
        {
          spacing = std::min(spacing, list[best + 1].Radius - list[best].Radius);
        }
        if (guided)
        {
          const double priorSpacing = TraceSpacing(*prior, m);
          if (priorSpacing > 0.0)
          {
            spacing = std::min(spacing, priorSpacing);
          }
        }
        const double window = AcceptWindow * std::max(spacing, voxel);
        const double apart = Apart();
        sheet = list[best].SheetNear(target);
        const bool near = bestDistance < window && (guided || std::abs(sheet - lastCarried) < window);
        const bool circling = (std::isfinite(below) && std::abs(sheet - below) < apart) ||
                              (std::isfinite(bump) && std::abs(sheet - bump) < apart);
        return near && !circling ? best : list.size();
      };
      size_t best = accept(predicted);
      if (best == list.size() && !guided && turnKnown && std::isfinite(below))
      {
        // The distance to the turn before changes (uneven winding): continue the radius.
        best = accept(last.Rho + slope * static_cast<double>(m - last.M));
      }
      if (best == list.size() && !outside && turnKnown && std::isfinite(below))
      {
        // Where a turn is pushed onto its neighbour (a touch) it leaves the prediction, and
        // no crossing is near it; the turn is then the crossing between the turn before and
        // the next turn, where the next turn is the crossing after it and lies where the
        // next turn is expected. The step follows it but leaves the turn's shape and its
        // distances alone (a touch is a bump, not the turn's course).
        const double nextTurn = guided && prior->Covers(m + dir * m_Frame.Rays)
                                  ? prior->At(m + dir * m_Frame.Rays) + offset
                                  : predicted + turnOffset;
        const double from = std::isfinite(bump) && (bump - below) * turnOffset > 0.0 ? bump : below;
        const double between = Between(list, from, nextTurn, std::abs(turnOffset));
        if (std::isfinite(between))
        {
          steps.push_back({ m, between, true });
          radiusAt.back() = predicted;
          bumpAt.back() = between;
          missedArc = heldArc = 0.0;
          continue;
        }
      }
      if (best < list.size())
      {
        const double r = sheet;
        steps.push_back({ m, r, true });
        confirmed.push_back({ m, r, true });
        radiusAt.back() = r;
        missedArc = heldArc = 0.0;
        const size_t count = std::min<size_t>(12, confirmed.size());
        // Distance to the turn before: the median over the last eighth of a turn of
        // confirmed steps, so that a short stretch where two turns touch (one merged
        // crossing between them) does not pull the next prediction onto the wrong turn.
        for (int j = 0; j < 2; ++j)
        {
          if (std::isfinite(far[j]))
          {
            farDistances[j].push_back(r - far[j]);
            farOffset[j] = median(farDistances[j], farOffset[j]);
            farKnown[j] = farDistances[j].size() >= 6;
          }
        }
        if (std::isfinite(below))
        {
          distances.push_back(r - below);
          turnOffset = median(distances, turnOffset);
          turnKnown = distances.size() >= 6;
          // Turns lie at least a sheet apart, however tightly they touch.
          const double least = 0.8 * std::max(m_Width, voxel);
          if (turnKnown && std::abs(turnOffset) < least)
          {
            turnOffset = std::copysign(least, turnOffset);
          }
        }
        if (guided)
        {
          // Mean offset from the prior over the last confirmed steps it covers.
          double sum = 0.0;
          size_t used = 0;
          for (size_t q = confirmed.size() - count; q < confirmed.size(); ++q)
          {
            if (prior->Covers(confirmed[q].M))
            {
              sum += confirmed[q].Rho - prior->At(confirmed[q].M);
              ++used;
            }
          }
          offset = used > 0 ? sum / static_cast<double>(used) : 0.0;
        }
        if (count >= 3)
        {
          // Least-squares slope of the radius per step along the trace direction.
          LineFit fit;
          for (size_t q = confirmed.size() - count; q < confirmed.size(); ++q)
          {
            fit.Add(static_cast<double>(confirmed[q].M), confirmed[q].Rho);
          }
          double intercept = 0.0, fitted = 0.0;
          if (fit.Solve(intercept, fitted))
          {
            slope = std::clamp(fitted, -maximumSlope, maximumSlope);
          }
        }
        continue;
      }
      if (outside || slice.Value(x, y, m_Settings.AirLevel) >= material)
      {
        // Material without a separate crossing, or the sheet out of the field of view
        // (for as long as it stays out): carry the prediction through.
        heldArc += outside ? 0.0 : predicted * m_Frame.Step;
        // In the seed slice (no neighbour yet) the turn before vouches for the shape as the
        // neighbouring slice does later: a touch longer than a turn spacing is held through.
        const bool vouched = guided || (prior == nullptr && turnKnown && std::isfinite(below));
        if (heldArc > (vouched ? heldWithPrior : heldAlone))
        {
          break;
        }
        steps.push_back({ m, predicted, false });
        radiusAt.back() = predicted;
      }
      else
      {
        missedArc += predicted * m_Frame.Step;
        if (missedArc > 2.0 * voxel)
        {
          break;
        }
      }
    }
    while (!steps.empty() && !steps.back().Confirmed)
    {
      steps.pop_back();
    }
    return steps;
  }

  // Traces one slice from a start crossing both ways; the result runs from the inner end.
  Trace
  TraceFrom(const SliceCrossings & crossings, size_t slice, const Trace * prior, long start, double rho) const
  {
    const ValueSlice sampler(m_Volume, m_Values, slice);
    double           c[2];
    Centre(slice, c);
    // Each way twice: the second time with the first turn of the other way as the shape of
    // the turn before.
    const auto first = Follow(crossings, sampler, c, prior, start, rho, +1);
    const auto inward = Follow(crossings, sampler, c, prior, start, rho, -1, first);
    const auto outward = Follow(crossings, sampler, c, prior, start, rho, +1, inward);
    Trace      trace;
    trace.First = inward.empty() ? start : inward.back().M;
    const long last = outward.empty() ? start : outward.back().M;
    trace.Rho.assign(static_cast<size_t>(last - trace.First + 1), 0.0);
    trace.Confirmed.assign(trace.Rho.size(), 0);
    std::vector<char> known(trace.Rho.size(), 0);
    auto              put = [&](const Step & s) {
      const auto i = static_cast<size_t>(s.M - trace.First);
      trace.Rho[i] = s.Rho;
      trace.Confirmed[i] = s.Confirmed ? 1 : 0;
      known[i] = 1;
    };
    put({ start, rho, true });
    for (const Step & s : inward)
    {
      put(s);
    }
    for (const Step & s : outward)
    {
      put(s);
    }
    // Steps skipped over short gaps: linear between their known neighbours.
    size_t previous = 0;
    for (size_t i = 1; i < known.size(); ++i)
    {
      if (known[i] == 0)
      {
        continue;
      }
      for (size_t g = previous + 1; g < i; ++g)
      {
        const double t = static_cast<double>(g - previous) / static_cast<double>(i - previous);
        trace.Rho[g] = (1.0 - t) * trace.Rho[previous] + t * trace.Rho[i];
      }
      previous = i;
    }
    return trace;
  }

  // Trace without a prior: from the middle crossing of a ray with the median number of
  // crossings (away from the noise of the centre and the loose outer end).
  Trace
  TraceAlone(const SliceCrossings & crossings, size_t slice) const
  {
    // A trace from one crossing can go wrong at its first hard place (a touch, a streak, an
    // artefact's circle) and lose the rest of the roll: starts on several rays and at
    // several depths, and the trace that passes through most crossings wins.
    Trace  best;
    double bestExplained = -1.0;
    for (long k = 0; k < AloneRays; ++k)
    {
      const long          ray = k * m_Frame.Rays / AloneRays;
      const auto &        list = crossings.Rays[static_cast<size_t>(ray)];
      std::vector<size_t> depths{ list.size() / 4, list.size() / 2, (3 * list.size()) / 4 };
      depths.erase(std::unique(depths.begin(), depths.end()), depths.end());
      for (size_t q : depths)
      {
        if (q >= list.size())
        {
          continue;
        }
        Trace        trace = TraceFrom(crossings, slice, nullptr, ray, list[q].Radius);
        const double explained = trace.Empty() ? 0.0 : Explained(crossings, trace);
        if (!trace.Empty() && explained > bestExplained)
        {
          best = std::move(trace);
          bestExplained = explained;
        }
      }
    }
    return best;
  }

  // Trace guided by a neighbouring slice's trace: starts where the prior meets a crossing,
  // nearest the prior's middle.
  Trace
  TraceGuided(const SliceCrossings & crossings, size_t slice, const Trace & prior) const
  {
    Trace trace = TraceNear(crossings, slice, prior, prior.First, prior.Last());
    return trace.Empty() ? TraceAlone(crossings, slice) : trace;
  }

  // Trace from the crossing that meets the prior nearest the middle of its stretch
  // [from, to] of angular indices; empty when no crossing there meets it.
  Trace
  TraceNear(const SliceCrossings & crossings, size_t slice, const Trace & prior, long from, long to) const
  {
    const long middle = (from + to) / 2;
    const long reach = (to - from) / 2;
    for (long d = 0; d <= reach; ++d)
    {
      for (long m : { middle - d, middle + d })
      {
        if (!prior.Covers(m))
        {
          continue;
        }
        const auto   a = static_cast<size_t>(((m % m_Frame.Rays) + m_Frame.Rays) % m_Frame.Rays);
        const double rho = prior.At(m);
        double       spacing = TraceSpacing(prior, m);
        spacing = spacing > 0.0 ? spacing : m_Pitch;
        for (const Crossing & c : crossings.Rays[a])
        {
          if (std::abs(c.Radius - rho) < 0.3 * spacing)
          {
            return TraceFrom(crossings, slice, &prior, m, c.Radius);
          }
        }
      }
    }
    return Trace{};
  }

  // Median radial growth of a trace per turn (0 for a trace shorter than a turn).
  double
  MedianGrowth(const Trace & trace) const
  {
    std::vector<double> growth;
    for (long m = trace.First; m + m_Frame.Rays <= trace.Last(); ++m)
    {
      growth.push_back(trace.At(m + m_Frame.Rays) - trace.At(m));
    }
    return growth.empty() ? 0.0 : std::abs(Median(growth));
  }
  // A spiral's growth per turn: about a turn spacing (at most `most` of them).
  bool
  GrowsByPitch(double growth, double most = 1.6) const
  {
    return growth >= 0.6 * m_Pitch && growth <= most * m_Pitch;
  }

  // Least distance between the middles of two turns (they touch a sheet's thickness apart):
  // a crossing nearer the turn before than this is that turn again.
  double
  Apart() const
  {
    return 0.6 * std::max(m_Width, m_Settings.Voxel);
  }

  // Median spacing of successive crossings and median crossing width.
  void
  MeasurePitch(const SliceCrossings & crossings)
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

  double
  Pitch() const
  {
    return m_Pitch;
  }
  double
  Width() const
  {
    return m_Width;
  }

  // Fraction of a slice's crossings that lie on its trace.
  double
  Explained(const SliceCrossings & crossings, const Trace & trace) const
  {
    size_t total = 0, onTrace = 0;
    for (long a = 0; a < m_Frame.Rays; ++a)
    {
      const auto & list = crossings.Rays[static_cast<size_t>(a)];
      total += list.size();
      for (const Crossing & c : list)
      {
        const long first = trace.First + (((a - trace.First) % m_Frame.Rays) + m_Frame.Rays) % m_Frame.Rays;
        for (long m = first; m <= trace.Last(); m += m_Frame.Rays)
        {
          if (std::abs(trace.At(m) - c.Radius) < AcceptWindow * m_Pitch)
          {
            ++onTrace;
            break;
          }
        }
      }
    }
    return total > 0 ? static_cast<double>(onTrace) / static_cast<double>(total) : 0.0;
  }

  Polyline
  ToPolyline(const Trace & trace, size_t slice) const
  {
    double c[2];
    Centre(slice, c);
    const auto n = static_cast<long>(trace.Rho.size());
    const long halfWidth = 4;
    Polyline   line(2 * trace.Rho.size());
    for (long i = 0; i < n; ++i)
    {
      const long h = std::min({ halfWidth, i, n - 1 - i });
      double     sum = 0.0;
      for (long j = i - h; j <= i + h; ++j)
      {
        sum += trace.Rho[static_cast<size_t>(j)];
      }
      const double rho = sum / static_cast<double>(2 * h + 1);
      const double angle = static_cast<double>(trace.First + i) * m_Frame.Step;
      line[2 * i] = c[0] + rho * std::cos(angle);
      line[2 * i + 1] = c[1] + rho * std::sin(angle);
    }
    return line;
  }

private:
  const SheetVolumeView & m_Volume;
  const float *           m_Values;
  Settings                m_Settings;
  double                  m_Contrast;
  double                  m_Offset[2]{ 0.0, 0.0 };
  PolarFrame              m_Frame;
  double                  m_Pitch{ 1.0 };
  double                  m_Width{ 1.0 };
  // The typical sheet's crossing's area (Crossing::Mass).
  double m_Mass{ 1.0 };
  // Whether m_Width and m_Mass were measured (bands of touching turns are told apart only
  // then).
  bool m_WidthMeasured{ false };
};
// Angular steps that make `arc` mm along a trace at radius rho (at least a voxel).
double
ArcSteps(double arc, double rho, double voxel, const PolarFrame & frame)
{
  return arc / (std::max(voxel, rho) * frame.Step);
}

// A trace whose end strays from the median end of the slices within EndReach of it (by more
// than EndTolerance of arc) is cut back to it or continued along its nearest neighbour
// that reaches it: a sheet's cut edge runs straight or slowly along the roll axis, while a
// trace that stops early (faint end) or runs on (noise) does not.
constexpr long   EndReach = 5;
constexpr double EndTolerance = 4.0; // voxels

void
MatchEndsToNeighbours(std::vector<Tracer::Trace> & traces,
                      const std::vector<size_t> &  slices,
                      const PolarFrame &           frame,
                      double                       voxel)
{
  const auto        n = static_cast<long>(slices.size());
  std::vector<long> firsts(slices.size(), 0), lasts(slices.size(), 0);
  for (long i = 0; i < n; ++i)
  {
    const auto & t = traces[slices[static_cast<size_t>(i)]];
    firsts[static_cast<size_t>(i)] = t.Empty() ? 0 : t.First;
    lasts[static_cast<size_t>(i)] = t.Empty() ? 0 : t.Last();
  }
  const std::vector<Tracer::Trace> original = traces;
  for (long i = 0; i < n; ++i)
  {
    auto & trace = traces[slices[static_cast<size_t>(i)]];
    if (trace.Empty())
    {
      continue;
    }
    std::vector<double> f, l;
    for (long j = std::max(0L, i - EndReach); j <= std::min(n - 1, i + EndReach); ++j)
    {
      if (!original[slices[static_cast<size_t>(j)]].Empty())
      {
        f.push_back(static_cast<double>(firsts[static_cast<size_t>(j)]));
        l.push_back(static_cast<double>(lasts[static_cast<size_t>(j)]));
      }
    }
    const auto medianFirst = static_cast<long>(Median(f)), medianLast = static_cast<long>(Median(l));
    auto       tolerance = [&](long m) {
      return static_cast<long>(
        std::ceil(ArcSteps(EndTolerance * voxel, trace.Covers(m) ? trace.At(m) : voxel, voxel, frame)));
    };
    // Cut back.
    if (trace.Last() > medianLast + tolerance(medianLast) && medianLast > trace.First)
    {
      trace.Rho.resize(static_cast<size_t>(medianLast - trace.First + 1));
      trace.Confirmed.resize(trace.Rho.size());
    }
    if (trace.First < medianFirst - tolerance(medianFirst) && medianFirst < trace.Last())
    {
      const auto cut = static_cast<std::ptrdiff_t>(medianFirst - trace.First);
      trace.Rho.erase(trace.Rho.begin(), trace.Rho.begin() + cut);
      trace.Confirmed.erase(trace.Confirmed.begin(), trace.Confirmed.begin() + cut);
      trace.First = medianFirst;
    }
    // Continue along the nearest neighbour that reaches the median end.
    for (int end = 0; end < 2; ++end)
    {
      const long target = end == 0 ? medianFirst : medianLast;
      const long at = end == 0 ? trace.First : trace.Last();
      if (std::abs(target - at) <= tolerance(at))
      {
        continue;
      }
      if ((end == 0 && target > at) || (end == 1 && target < at))
      {
        continue;
      }
      for (long d = 1; d <= EndReach; ++d)
      {
        const Tracer::Trace * neighbour = nullptr;
        for (long j : { i - d, i + d })
        {
          if (j >= 0 && j < n && original[slices[static_cast<size_t>(j)]].Covers(target) &&
              original[slices[static_cast<size_t>(j)]].Covers(at))
          {
            neighbour = &original[slices[static_cast<size_t>(j)]];
            break;
          }
        }
        if (neighbour == nullptr)
        {
          continue;
        }
        // Offset from the neighbour over the last quarter turn both have.
        double sum = 0.0;
        long   used = 0;
        for (long m = at; used < frame.Rays / 4 && trace.Covers(m) && neighbour->Covers(m); m += end == 0 ? 1 : -1)
        {
          sum += trace.At(m) - neighbour->At(m);
          ++used;
        }
        const double offset = used > 0 ? sum / static_cast<double>(used) : 0.0;
        if (end == 1)
        {
          for (long m = at + 1; m <= target; ++m)
          {
            trace.Rho.push_back(neighbour->At(m) + offset);
            trace.Confirmed.push_back(0);
          }
        }
        else
        {
          std::vector<double> rho;
          for (long m = target; m < at; ++m)
          {
            rho.push_back(neighbour->At(m) + offset);
          }
          trace.Rho.insert(trace.Rho.begin(), rho.begin(), rho.end());
          trace.Confirmed.insert(trace.Confirmed.begin(), rho.size(), 0);
          trace.First = target;
        }
        break;
      }
    }
  }
}
// A sheet's cut edges run along the roll axis in a straight or slowly drifting line: the
// ends of the traces, as functions of the slice, are fitted by lines over the middle 60 %
// of the slices, and a trace whose end lies further than DropTolerance of arc from its
// line (a slice that cuts the sheet's edge along the axis, faint and blurred; a trace lost
// before the end) is dropped: the mesh interpolates that slice from its neighbours, or
// ends before it.
constexpr double DropTolerance = 8.0; // voxels

size_t
DropIncompleteTraces(std::vector<Tracer::Trace> & traces,
                     const std::vector<size_t> &  slices,
                     const PolarFrame &           frame,
                     double                       voxel)
{
  const size_t n = slices.size();
  if (n < 5)
  {
    return 0;
  }
  // The angular index of a trace's inner (end 0) or outer (end 1) end, and whether it lies
  // further than the tolerance from a line of (slice, end).
  auto endOf = [](const Tracer::Trace & t, int end) { return end == 0 ? t.First : t.Last(); };
  auto offLine = [&](size_t i, int end, const double line[2]) {
    const Tracer::Trace & t = traces[slices[i]];
    const long            m = endOf(t, end);
    const double          tolerance = ArcSteps(DropTolerance * voxel, t.At(m), voxel, frame);
    return std::abs(static_cast<double>(m) - line[0] - line[1] * static_cast<double>(i)) > tolerance;
  };
  // Least-squares line of (slice, end) over the middle traces, refitted once without the
  // ones further than the tolerance.
  auto fit = [&](int end, double line[2]) {
    std::vector<char> use(n, 0);
    for (size_t i = n / 5; i < n - n / 5; ++i)
    {
      use[i] = traces[slices[i]].Empty() ? 0 : 1;
    }
    for (int pass = 0; pass < 2; ++pass)
    {
      LineFit points;
      for (size_t i = 0; i < n; ++i)
      {
        if (use[i] != 0)
        {
          points.Add(static_cast<double>(i), static_cast<double>(endOf(traces[slices[i]], end)));
        }
      }
      if (points.N < 3.0)
      {
        return false;
      }
      points.Solve(line[0], line[1]);
      for (size_t i = 0; i < n && pass == 0; ++i)
      {
        use[i] = use[i] != 0 && !offLine(i, end, line) ? 1 : 0;
      }
    }
    return true;
  };
  double firstLine[2], lastLine[2];
  if (!fit(0, firstLine) || !fit(1, lastLine))
  {
    return 0;
  }
  size_t dropped = 0;
  for (size_t i = 0; i < n; ++i)
  {
    if (!traces[slices[i]].Empty() && (offLine(i, 0, firstLine) || offLine(i, 1, lastLine)))
    {
      traces[slices[i]] = Tracer::Trace{};
      ++dropped;
    }
  }
  return dropped;
}

// Slices in a row whose traces may be dropped for disagreeing with the last kept one.
constexpr long MaximumRejected = 8;

// First angular index at which two traces differ by more than half the turn spacing (-1: none).
long
FirstDisagreement(const Tracer::Trace & a, const Tracer::Trace & b, double pitch)
{
  for (long m = std::max(a.First, b.First); m <= std::min(a.Last(), b.Last()); ++m)
  {
    if (std::abs(a.At(m) - b.At(m)) > 0.5 * pitch)
    {
      return m;
    }
  }
  return -1;
}

// A trace that stopped short of its prior's ends (a touch it could not pass, a faint
// stretch, a streak) would lose the rest of the roll for every slice after it. It is traced
// again from the prior's stretch beyond each end it stopped at more than half a turn short
// of; a second piece that agrees with the prior is joined to it, the stretch between the
// two (at most a turn) on the prior's curve, offset linearly from one piece's end to the
// other's.
void
ResumeBeyondStops(Tracer::Trace &        trace,
                  const Tracer::Trace &  prior,
                  const Tracer &         tracer,
                  const SliceCrossings & crossings,
                  size_t                 slice)
{
  const long   half = tracer.Frame().Rays / 2;
  const double pitch = tracer.Pitch();
  for (int end : { 0, 1 })
  {
    if (trace.Empty())
    {
      return;
    }
    const long from = end == 0 ? prior.First : trace.Last() + half / 4;
    const long to = end == 0 ? trace.First - half / 4 : prior.Last();
    if ((end == 0 ? trace.First - prior.First : prior.Last() - trace.Last()) <= half || to - from < half / 2)
    {
      continue;
    }
    Tracer::Trace piece = tracer.TraceNear(crossings, slice, prior, from, to);
    if (piece.Empty() || FirstDisagreement(prior, piece, pitch) >= 0 || FirstDisagreement(trace, piece, pitch) >= 0)
    {
      continue;
    }
    const Tracer::Trace & inner = end == 0 ? piece : trace;
    const Tracer::Trace & outer = end == 0 ? trace : piece;
    if (piece.First <= trace.First && piece.Last() >= trace.Last())
    {
      trace = std::move(piece); // passed the hard place from the other side
      continue;
    }
    if (outer.Last() <= inner.Last() || outer.First <= inner.First)
    {
      continue; // the trace holds the piece
    }
    Tracer::Trace joined;
    joined.First = inner.First;
    joined.Rho.assign(static_cast<size_t>(outer.Last() - inner.First + 1), 0.0);
    joined.Confirmed.assign(joined.Rho.size(), 0);
    const long gapFrom = inner.Last() + 1, gapTo = outer.First - 1;
    if (gapFrom <= gapTo &&
        (!(prior.Covers(gapFrom - 1) && prior.Covers(gapTo + 1)) || gapTo - gapFrom >= tracer.Frame().Rays))
    {
      continue; // a trace started away from the prior, or more than a turn to bridge
    }
    const double before = gapFrom <= gapTo ? inner.At(inner.Last()) - prior.At(inner.Last()) : 0.0;
    const double after = gapFrom <= gapTo ? outer.At(outer.First) - prior.At(outer.First) : 0.0;
    for (long m = joined.First; m <= joined.Last(); ++m)
    {
      const auto i = static_cast<size_t>(m - joined.First);
      if (inner.Covers(m))
      {
        joined.Rho[i] = inner.At(m);
        joined.Confirmed[i] = inner.Confirmed[static_cast<size_t>(m - inner.First)];
      }
      else if (outer.Covers(m))
      {
        joined.Rho[i] = outer.At(m);
        joined.Confirmed[i] = outer.Confirmed[static_cast<size_t>(m - outer.First)];
      }
      else
      {
        const double t = static_cast<double>(m - gapFrom + 1) / static_cast<double>(gapTo - gapFrom + 2);
        joined.Rho[i] = prior.At(m) + (1.0 - t) * before + t * after;
      }
    }
    trace = std::move(joined);
  }
}
} // namespace

void
ExtendEnds(Polyline & line, const std::function<bool(double, double)> & inside, double voxel, double maximum)
{
  for (int end = 0; end < 2; ++end)
  {
    const size_t n = line.size() / 2;
    if (n < 2)
    {
      return;
    }
    // Tangent over about one voxel, away from the end.
    const size_t last = end == 0 ? 0 : n - 1;
    size_t       inner = last;
    const double x0 = line[2 * last], y0 = line[2 * last + 1];
    while (true)
    {
      inner = end == 0 ? inner + 1 : inner - 1;
      if (std::hypot(line[2 * inner] - x0, line[2 * inner + 1] - y0) >= voxel || inner == 0 || inner == n - 1)
      {
        break;
      }
    }
    double       tx = x0 - line[2 * inner], ty = y0 - line[2 * inner + 1];
    const double norm = std::hypot(tx, ty);
    if (norm <= 0.0)
    {
      continue;
    }
    tx /= norm;
    ty /= norm;
    const double step = 0.25 * voxel;
    double       reach = 0.0;
    while (reach + step <= maximum && inside(x0 + (reach + step) * tx, y0 + (reach + step) * ty))
    {
      reach += step;
    }
    if (reach > 0.0)
    {
      const double x = x0 + reach * tx, y = y0 + reach * ty;
      line.insert(end == 0 ? line.begin() : line.end(), { x, y });
    }
  }
}

Result
TraceRoll(const SheetVolumeView &             volume,
          const float *                       values,
          const Settings &                    settings,
          const std::function<void(double)> & progress)
{
  Result              result;
  const size_t        nx = volume.Size[0], ny = volume.Size[1], nz = volume.Size[2];
  std::vector<size_t> material;
  for (size_t k = 0; k < nz; ++k)
  {
    const uint8_t * mask = volume.Mask + k * nx * ny;
    if (std::any_of(mask, mask + nx * ny, [](uint8_t v) { return v != 0; }))
    {
      material.push_back(k);
    }
  }
  result.Slices.resize(nz);
  if (material.empty() || !(settings.SheetLevel > settings.AirLevel))
  {
    return result;
  }
  // Seed: a slice in the middle part of the sheet, traced on the mean profile of its
  // neighbours. Two turns that touch in the seed slice would carry its trace onto the next
  // turn, and every slice after it; a touch covers only part of the width, so three slices
  // (at 50, 30 and 70 % of the sheet's width) are tried and the middle one is kept unless
  // another's trace passes through clearly more of its crossings. Each is traced by a
  // tracer of its own (its centre, frame and turn spacing), at the same time given two
  // threads or more.
  struct Seed
  {
    Tracer         SeedTracer;
    SliceCrossings Crossings;
    Tracer::Trace  Trace;
  };
  auto traceSeed = [&](size_t seed) {
    Seed                result{ Tracer(volume, values, settings), {}, {} };
    Tracer &            tracer = result.SeedTracer;
    std::vector<size_t> around;
    for (size_t k : material)
    {
      if (std::abs(static_cast<long>(k) - static_cast<long>(seed)) <= SeedHalfWidth)
      {
        around.push_back(k);
      }
    }
    auto traceAtOffset = [&](double x, double y) {
      tracer.SetOffset(x, y);
      tracer.BuildFrame(material);
      const PolarSlice polar = tracer.Sample(seed, around, true, true);
      result.Crossings = tracer.FindCrossings(polar, true);
      tracer.MeasurePitch(result.Crossings);
      // Again, with touching turns split now that the typical width is known.
      result.Crossings = tracer.FindCrossings(polar, true);
      result.Trace = tracer.TraceAlone(result.Crossings, seed);
      // The same slice turn by turn as minimal paths (TracePaths), kept where it passes
      // through clearly more of the crossings: where the follower crossed onto the next turn
      // at a touch and lost the rest of the one it was on.
      Tracer::Trace paths = tracer.TracePaths(polar, result.Trace, result.Crossings);
      if (!paths.Empty() && tracer.Explained(result.Crossings, paths) >
                              tracer.Explained(result.Crossings, result.Trace) + PathsPreference)
      {
        result.Trace = std::move(paths);
      }
    };
    traceAtOffset(0.0, 0.0);
    // The centroid line need not pass through the spiral's centre (an irregular roll, a field
    // of view that cuts it): re-centre on the innermost turn and trace again.
    for (int pass = 0; pass < 2 && !result.Trace.Empty(); ++pass)
    {
      const Tracer::Trace & trace = result.Trace;
      const long            rays = tracer.Frame().Rays;
      if (trace.Last() - trace.First < 3 * rays / 2)
      {
        break;
      }
      double mean[2] = { 0.0, 0.0 };
      for (long m = trace.First; m < trace.First + rays; ++m)
      {
        const double angle = static_cast<double>(m) * tracer.Frame().Step;
        mean[0] += trace.At(m) * std::cos(angle) / static_cast<double>(rays);
        mean[1] += trace.At(m) * std::sin(angle) / static_cast<double>(rays);
      }
      if (std::hypot(mean[0], mean[1]) < 0.5 * settings.Voxel)
      {
        break;
      }
      traceAtOffset(tracer.GetOffset()[0] + mean[0], tracer.GetOffset()[1] + mean[1]);
    }
    return result;
  };
  std::vector<long> candidates;
  for (const double fraction : { 0.5, 0.3, 0.7 })
  {
    const auto index = static_cast<long>(fraction * static_cast<double>(material.size() - 1) + 0.5);
    if (std::find(candidates.begin(), candidates.end(), index) == candidates.end())
    {
      candidates.push_back(index);
    }
  }
  std::vector<std::optional<Seed>>   traced(candidates.size());
  std::vector<std::function<void()>> seedTasks;
  for (size_t c = 0; c < candidates.size(); ++c)
  {
    seedTasks.emplace_back([&, c]() { traced[c].emplace(traceSeed(material[static_cast<size_t>(candidates[c])])); });
  }
  RunTogether(seedTasks);
  std::vector<Seed> seeds;
  for (auto & seed : traced)
  {
    seeds.push_back(std::move(*seed));
  }
  size_t chosen = 0;
  double bestExplained = -1.0;
  for (size_t c = 0; c < seeds.size(); ++c)
  {
    const double explained =
      seeds[c].Trace.Empty() ? -1.0 : seeds[c].SeedTracer.Explained(seeds[c].Crossings, seeds[c].Trace);
    if (c == 0 || explained > bestExplained + SeedPreference)
    {
      chosen = c;
      bestExplained = explained;
    }
  }
  const long             seedIndex = candidates[chosen];
  const Tracer &         tracer = seeds[chosen].SeedTracer;
  const SliceCrossings & crossings = seeds[chosen].Crossings;
  const Tracer::Trace &  seedTrace = seeds[chosen].Trace;
  result.Pitch = tracer.Pitch();
  result.RayThickness = tracer.Width();
  result.CentreOffset[0] = tracer.GetOffset()[0];
  result.CentreOffset[1] = tracer.GetOffset()[1];
  if (seedTrace.Empty())
  {
    return result;
  }
  const double turns =
    static_cast<double>(seedTrace.Last() - seedTrace.First) / static_cast<double>(tracer.Frame().Rays);
  result.Explained = tracer.Explained(crossings, seedTrace);
  // A spiral moves outwards by about a turn spacing per turn; a curve circling the centre
  // (a flat or folded sheet through it) does not. Noise adds crossings no trace explains: a
  // trace of two turns or more that grows by the turn spacing every turn is a spiral with
  // fewer of them explained.
  const double medianGrowth = tracer.MedianGrowth(seedTrace);
  const bool   growsByPitch = tracer.GrowsByPitch(medianGrowth);
  result.Rolled = turns >= 1.0 && medianGrowth >= std::max(settings.Voxel, 0.5 * tracer.Width()) &&
                  (result.Explained >= 0.6 || (turns >= 2.0 && growsByPitch && result.Explained >= 0.4));
  progress(0.1);

  // Every slice, outwards from the seed, with the previous slice's trace as prior. The
  // crossings of a batch of slices are found in parallel; the two directions are independent
  // and, given two threads or more, traced at the same time (the progress from the calling
  // thread's).
  std::vector<Tracer::Trace> traces(nz);
  std::atomic<size_t>        done{ 0 };
  const std::thread::id      caller = std::this_thread::get_id();
  auto                       traceOutwards = [&](int dir) {
    const size_t  batch = 16;
    Tracer::Trace prior = seedTrace;
    long          rejected = 0;
    for (long q = dir > 0 ? seedIndex : seedIndex - 1; q >= 0 && q < static_cast<long>(material.size());)
    {
      std::vector<size_t> slices;
      for (long r = q; r >= 0 && r < static_cast<long>(material.size()) && slices.size() < batch; r += dir)
      {
        slices.push_back(material[static_cast<size_t>(r)]);
      }
      std::vector<SliceCrossings> found(slices.size());
      MultiThreaderBase::New()->ParallelizeArray(
        0,
        slices.size(),
        [&](SizeValueType i) { found[i] = tracer.FindCrossings(tracer.Sample(slices[i], { slices[i] }, false)); },
        nullptr);
      for (size_t i = 0; i < slices.size(); ++i)
      {
        traces[slices[i]] = tracer.TraceGuided(found[i], slices[i], prior);
        if (traces[slices[i]].Empty())
        {
          continue;
        }
        ResumeBeyondStops(traces[slices[i]], prior, tracer, found[i], slices[i]);
        // A trace that leaves its prior by half a turn spacing somewhere has lost or jumped
        // a turn (noise, a streak, a faint stretch): it is dropped (the slice is then
        // interpolated from its neighbours) and the prior carried on, unless the slices
        // keep disagreeing with it for longer than a few slices (the sheet itself changed).
        if (FirstDisagreement(prior, traces[slices[i]], tracer.Pitch()) >= 0 && rejected < MaximumRejected)
        {
          traces[slices[i]] = Tracer::Trace{};
          ++rejected;
          continue;
        }
        rejected = 0;
        prior = traces[slices[i]];
      }
      q += dir * static_cast<long>(slices.size());
      done += slices.size();
      if (std::this_thread::get_id() == caller)
      {
        progress(0.1 + 0.85 * static_cast<double>(done) / static_cast<double>(material.size()));
      }
    }
  };
  RunTogether({ [&]() { traceOutwards(+1); }, [&]() { traceOutwards(-1); } });

  MatchEndsToNeighbours(traces, material, tracer.Frame(), settings.Voxel);
  result.Incomplete = DropIncompleteTraces(traces, material, tracer.Frame(), settings.Voxel);

  // Neighbouring traces that disagree by half a turn spacing at the same angle: a turn
  // was lost or jumped between them.
  for (size_t i = 1; i < material.size(); ++i)
  {
    const auto & a = traces[material[i - 1]];
    const auto & b = traces[material[i]];
    if (a.Empty() || b.Empty())
    {
      continue;
    }
    const long m = FirstDisagreement(a, b, result.Pitch);
    if (m >= 0)
    {
      result.Disagreements.emplace_back(material[i],
                                        static_cast<double>(m - b.First) / static_cast<double>(tracer.Frame().Rays));
    }
  }
  for (size_t k : material)
  {
    const auto & trace = traces[k];
    if (trace.Rho.size() < 4)
    {
      continue;
    }
    SliceTrace & out = result.Slices[k];
    out.Line = tracer.ToPolyline(trace, k);
    out.Confirmed = static_cast<double>(std::count(trace.Confirmed.begin(), trace.Confirmed.end(), 1)) /
                    static_cast<double>(trace.Confirmed.size());
    out.Turns = static_cast<double>(trace.Last() - trace.First) / static_cast<double>(tracer.Frame().Rays);
  }
  progress(1.0);
  return result;
}
} // namespace RollTracing
} // end namespace itk

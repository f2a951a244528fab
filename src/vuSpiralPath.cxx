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
#include "vuSpiralPath.h"
#include "vuMedian.h"

#include <algorithm>
#include <deque>
#include <iterator>
#include <limits>

namespace itk {
namespace RollTracing {
namespace {
constexpr double Pi = 3.14159265358979323846;
// Intensity (fraction of the contrast) above which the path is taken to run on the sheet.
constexpr double MaterialLevel = 0.5;
// Where the path is pressed against its bound it may run on the flank of the turn before:
// it counts as on the sheet only this bright (a touch), not on a flank.
constexpr double PressedLevel = 0.75;
// ... and stand out of the gaps beside it by this fraction of the sheet measure's median on
// the reference turn: noise and streaks near the axis, brighter than air but not a sheet,
// do not count.
constexpr double RidgeLevel = 0.4;
// Cost of moving one radial sample sideways of the shape of the turn before.
constexpr double MovePenalty = 1.0;
// Samples the path may move per angular step beyond the move of the turn before.
constexpr long MaximumMove = 4;
// Cost of a sample where the scan holds no data: neither sheet nor air.
constexpr double NoDataCost = 0.5;
// Voxels of arc in air (without a sheet sample between them) that end the sheet, where the
// path beyond finds the sheet on less than TailOnSheet of its steps.
constexpr double EndArc = 3.0;
constexpr double TailOnSheet = 0.3;
// The path keeps this fraction of the sheet's thickness away from the turn before, and
// lies at most MostApart turn spacings (the median spacing of the slice) from it; where
// the turn before that is known too, at most LocalApart times the spacing between the two
// (along a quarter turn) from that one (the turn after next lies three spacings from
// it), and where it is not, at most NearApart spacings from the turn before (the turn after
// next lies two spacings from it).
constexpr double LeastApart = 0.5;
constexpr double MostApart = 2.5;
constexpr double LocalApart = 2.5;
constexpr double NearApart = 1.6;
// The reference turn is traced again within this fraction of the turn spacing of itself.
constexpr double Window = 0.4;

struct TurnPath
{
  std::vector<double> Rho;
  std::vector<char>   Confirmed;
  // The sheet measure along the path.
  std::vector<double> Measure;
  bool                Ended{ false };
};

// A sheet measure along each ray: the mean over a sheet's thickness about a sample minus
// the mean over the middle of the gaps on both sides, half a turn spacing away (the samples
// without data left out). It peaks at the middle of a sheet, also of a sharp or saturated
// one (where the intensity is flat across the sheet), and where two turns touch (one band
// of twice the thickness) at the middle of each of them, not of the band.
PolarSlice
SheetMeasure(const PolarSlice & slice, long half, long flankOffset, long flankHalf)
{
  PolarSlice measure = slice;
  measure.Known.clear();
  const long          n = slice.Samples;
  std::vector<double> sum(static_cast<size_t>(n + 1)), count(sum.size());
  auto                mean = [&](long centre, long h) {
    const auto   lo = static_cast<size_t>(std::clamp(centre - h, 0L, n));
    const auto   hi = static_cast<size_t>(std::clamp(centre + h + 1, 0L, n));
    const double c = count[hi] - count[lo];
    return c > 0.0 ? (sum[hi] - sum[lo]) / c : 0.0;
  };
  for (long a = 0; a < slice.Rays; ++a)
  {
    for (long j = 0; j < n; ++j)
    {
      const double v = slice.At(a, j);
      const bool   known = std::isfinite(v);
      sum[static_cast<size_t>(j + 1)] = sum[static_cast<size_t>(j)] + (known ? v : 0.0);
      count[static_cast<size_t>(j + 1)] = count[static_cast<size_t>(j)] + (known ? 1.0 : 0.0);
    }
    float * out = measure.Values.data() + a * n;
    for (long j = 0; j < n; ++j)
    {
      const double flanks = 0.5 * (mean(j - flankOffset, flankHalf) + mean(j + flankOffset, flankHalf));
      out[j] = std::isfinite(slice.At(a, j)) ? static_cast<float>(mean(j, half) - flanks)
                                             : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return measure;
}

// The minimal-path table of one turn: per step i, the admissible samples lo[i]..hi[i], the
// least total cost of reaching each, and the sample of step i - 1 it came from. `bound`
// holds the neighbouring turn's radius at each step, on the side -side of the path (side
// +1: the path lies outside it), `beyond` the turn past it.
struct PathTable
{
  std::vector<long>                lo, hi;
  std::vector<std::vector<double>> total;
  std::vector<std::vector<long>>   from;
};

PathTable
FillPathTable(const PolarSlice &          slice,
              const PolarSlice &          measure,
              long                        m0,
              int                         dir,
              const std::vector<double> & bound,
              const std::vector<double> & beyond,
              int                         side,
              double                      startRho,
              const SpiralPathSettings &  settings)
{
  const double dr = slice.Dr;
  const double least = LeastApart * std::max(settings.Width, settings.Voxel);
  const double most = std::max(MostApart * settings.Pitch, least + 2.0 * settings.Voxel);
  const double near = std::max(NearApart * settings.Pitch, least + 2.0 * settings.Voxel);
  const double window = std::max(Window * settings.Pitch, settings.Voxel);
  const long   centre = static_cast<long>(std::ceil(settings.Voxel / dr));
  const auto   n = static_cast<long>(bound.size());
  const auto   shape = RunningMedian(bound, std::max(8L, slice.Rays / 32));
  // `beyond`: the turn on the far side of `bound`, and the spacing between the two.
  std::vector<double> localSpacing;
  for (size_t i = 0; i < beyond.size(); ++i)
  {
    localSpacing.push_back(std::abs(bound[i] - beyond[i]));
  }
  localSpacing = RunningMedian(localSpacing, std::max(8L, slice.Rays / 8));
  auto cost = [&](long i, long j) {
    const double v = measure.At(m0 + dir * i, j);
    return std::isnan(v) ? NoDataCost : 1.0 - std::clamp(v, 0.0, 1.0);
  };

  PathTable                          table;
  std::vector<long> &                lo = table.lo;
  std::vector<long> &                hi = table.hi;
  std::vector<std::vector<double>> & total = table.total;
  std::vector<std::vector<long>> &   from = table.from;
  const double                       infinite = std::numeric_limits<double>::infinity();
  long                               previousShapeSample = n > 0 ? std::lround(shape[0] / dr) : 0;
  for (long i = 0; i < n; ++i)
  {
    const double b = bound[static_cast<size_t>(i)];
    // side 0: the path keeps within a window about `bound` itself. Without the turn beyond
    // the bound, at most NearApart spacings from it.
    const double far = beyond.empty() ? near : most;
    double       low = side > 0 ? b + least : side < 0 ? b - far : b - window;
    double       high = side > 0 ? b + far : side < 0 ? b - least : b + window;
    if (!beyond.empty() && side != 0)
    {
      const double reach = LocalApart * localSpacing[static_cast<size_t>(i)];
      const double limit = beyond[static_cast<size_t>(i)] + static_cast<double>(side) * reach;
      low = side < 0 ? std::max(low, limit) : low;
      high = side > 0 ? std::min(high, limit) : high;
    }
    long l = static_cast<long>(std::ceil(low / dr));
    long h = static_cast<long>(std::floor(high / dr));
    l = std::max(l, centre);
    h = std::min(h, slice.Samples - 2);
    if (l > h)
    {
      break;
    }
    // The move the shape asks for, in whole samples without rounding bias: a path that
    // keeps its distance to the shape pays nothing.
    const long shapeSample = std::lround(shape[static_cast<size_t>(i)] / dr);
    const long shiftSamples = shapeSample - previousShapeSample;
    previousShapeSample = shapeSample;
    std::vector<double> row(static_cast<size_t>(h - l + 1), infinite);
    std::vector<long>   back(row.size(), -1);
    for (long j = l; j <= h; ++j)
    {
      double best = infinite;
      long   arg = -1;
      if (i == 0)
      {
        best = MovePenalty * static_cast<double>(std::abs(j - std::lround(startRho / dr) - shiftSamples));
      }
      else
      {
        const long pl = std::max(lo.back(), j - shiftSamples - MaximumMove);
        const long ph = std::min(hi.back(), j - shiftSamples + MaximumMove);
        for (long p = pl; p <= ph; ++p)
        {
          const double c = total.back()[static_cast<size_t>(p - lo.back())] +
                           MovePenalty * static_cast<double>(std::abs(j - p - shiftSamples));
          if (c < best)
          {
            best = c;
            arg = p;
          }
        }
      }
      if (best < infinite)
      {
        row[static_cast<size_t>(j - l)] = best + cost(i, j);
        back[static_cast<size_t>(j - l)] = arg;
      }
    }
    if (std::none_of(row.begin(), row.end(), [&](double c) { return c < infinite; }))
    {
      break;
    }
    lo.push_back(l);
    hi.push_back(h);
    total.push_back(std::move(row));
    from.push_back(std::move(back));
  }
  return table;
}

// The path through a filled table, moved up the measure to the sheet's peak and centred to
// a sub-sample radius, each step marked on the sheet (1), in air (0) or without data (2).
TurnPath
CentrePath(const PolarSlice &         slice,
           const PolarSlice &         measure,
           const PathTable &          table,
           long                       m0,
           int                        dir,
           int                        side,
           double                     ridgeLevel,
           const SpiralPathSettings & settings)
{
  const double              dr = slice.Dr;
  const double              infinite = std::numeric_limits<double>::infinity();
  const std::vector<long> & lo = table.lo;
  const std::vector<long> & hi = table.hi;
  const auto &              total = table.total;
  const auto &              from = table.from;
  const auto                steps = static_cast<long>(total.size());
  TurnPath                  path;
  std::vector<long>         j(static_cast<size_t>(steps));
  const auto &              lastRow = total.back();
  j.back() = lo.back() + static_cast<long>(std::min_element(lastRow.begin(), lastRow.end()) - lastRow.begin());
  for (long i = steps - 1; i > 0; --i)
  {
    j[static_cast<size_t>(i - 1)] =
      from[static_cast<size_t>(i)][static_cast<size_t>(j[static_cast<size_t>(i)] - lo[static_cast<size_t>(i)])];
  }

  // Sub-sample radius at the peak of the profile.
  const auto reach = static_cast<long>(std::ceil(0.5 * settings.Width / dr));
  for (long i = 0; i < steps; ++i)
  {
    const long m = m0 + dir * i;
    // The path is stiff (it pays for every bend): it is moved up the profile to the peak of
    // the sheet, within half a thickness and its bounds, before the sub-sample fit.
    long ji = j[static_cast<size_t>(i)];
    for (long climb = 0; climb < reach; ++climb)
    {
      const double here = measure.At(m, ji);
      const double up = ji + 1 <= hi[static_cast<size_t>(i)] ? measure.At(m, ji + 1) : -infinite;
      const double down = ji - 1 >= lo[static_cast<size_t>(i)] ? measure.At(m, ji - 1) : -infinite;
      if (!(std::max(up, down) > here))
      {
        break;
      }
      ji += up >= down ? 1 : -1;
    }
    const double v = slice.At(m, ji);
    double       rho = static_cast<double>(ji) * dr;
    const double peak = measure.At(m, ji), below = measure.At(m, ji - 1), above = measure.At(m, ji + 1);
    if (std::isfinite(peak) && std::isfinite(below) && std::isfinite(above) && peak >= below && peak >= above)
    {
      const double curvature = below - 2.0 * peak + above;
      if (curvature < 0.0)
      {
        rho += std::clamp(0.5 * (below - above) / curvature, -0.5, 0.5) * dr;
      }
    }
    path.Rho.push_back(rho);
    path.Measure.push_back(peak);
    const bool pressed = side > 0   ? ji <= lo[static_cast<size_t>(i)] + 1
                         : side < 0 ? ji >= hi[static_cast<size_t>(i)] - 1
                                    : false;
    const bool onSheet = std::isfinite(v) && v >= (pressed ? PressedLevel : MaterialLevel) && peak >= ridgeLevel;
    // No data: neither sheet nor air (2).
    path.Confirmed.push_back(onSheet ? 1 : std::isnan(v) ? 2 : 0);
  }
  return path;
}

// Cuts the path where the sheet ends: EndArc of air after which the path finds the sheet
// on less than TailOnSheet of its steps (a faint stretch or a touch is followed by sheet
// again; the end of the sheet by air), or where the table stopped short of all `n` steps.
// The reference turn (side 0) is followed whole.
void
CutAtSheetEnd(TurnPath & path, long n, int side, double step, const SpiralPathSettings & settings)
{
  const auto          steps = static_cast<long>(path.Rho.size());
  std::vector<double> onSheetAfter(static_cast<size_t>(steps + 1), 0.0), countedAfter(onSheetAfter.size(), 0.0);
  for (long i = steps - 1; i >= 0; --i)
  {
    const char c = path.Confirmed[static_cast<size_t>(i)];
    onSheetAfter[static_cast<size_t>(i)] = onSheetAfter[static_cast<size_t>(i + 1)] + (c == 1 ? 1.0 : 0.0);
    countedAfter[static_cast<size_t>(i)] = countedAfter[static_cast<size_t>(i + 1)] + (c != 2 ? 1.0 : 0.0);
  }
  double missed = 0.0;
  long   lastOnSheet = -1, runStart = 0;
  for (long i = 0; i < steps && side != 0; ++i)
  {
    const char c = path.Confirmed[static_cast<size_t>(i)];
    if (c != 0)
    {
      lastOnSheet = c == 1 ? i : lastOnSheet;
      missed = 0.0;
      continue;
    }
    runStart = missed == 0.0 ? i : runStart;
    missed += path.Rho[static_cast<size_t>(i)] * step;
    const auto   tail = static_cast<size_t>(runStart);
    const double fraction = countedAfter[tail] > 0.0 ? onSheetAfter[tail] / countedAfter[tail] : 0.0;
    if (missed > EndArc * settings.Voxel && fraction < TailOnSheet)
    {
      path.Ended = true;
      break;
    }
  }
  if (path.Ended || steps < n)
  {
    path.Ended = true;
    path.Rho.resize(static_cast<size_t>(lastOnSheet + 1));
    path.Confirmed.resize(path.Rho.size());
    path.Measure.resize(path.Rho.size());
  }
}

// One turn: steps i = 0, 1, ... at m = m0 + dir * i; `bound` holds the neighbouring turn's
// radius at each step, on the side -side of the path (side +1: the path lies outside it).
TurnPath
TraceTurn(const PolarSlice &          slice,
          const PolarSlice &          measure,
          long                        m0,
          int                         dir,
          const std::vector<double> & bound,
          const std::vector<double> & beyond,
          int                         side,
          double                      startRho,
          double                      ridgeLevel,
          const SpiralPathSettings &  settings)
{
  const PathTable table = FillPathTable(slice, measure, m0, dir, bound, beyond, side, startRho, settings);
  if (table.total.empty())
  {
    TurnPath path;
    path.Ended = true;
    return path;
  }
  TurnPath path = CentrePath(slice, measure, table, m0, dir, side, ridgeLevel, settings);
  CutAtSheetEnd(path, static_cast<long>(bound.size()), side, 2.0 * Pi / static_cast<double>(slice.Rays), settings);
  for (char & c : path.Confirmed)
  {
    c = c == 1 ? 1 : 0;
  }
  return path;
}
} // namespace

SpiralTrace
TraceSpiralPath(const PolarSlice &         slice,
                const SpiralTrace &        reference,
                long                       centre,
                const SpiralPathSettings & settings)
{
  const long rays = slice.Rays;
  if (rays < 8 || reference.Last() - reference.First + 1 < rays)
  {
    return SpiralTrace{};
  }
  // The sense in which the spiral grows: k = sense * m runs from the inner end outwards.
  std::vector<double> growth;
  for (long m = reference.First; m + rays <= reference.Last(); ++m)
  {
    growth.push_back(reference.At(m + rays) - reference.At(m));
  }
  const long sense = growth.empty() || Median(growth) >= 0.0 ? 1 : -1;
  const long kFirst = sense > 0 ? reference.First : -reference.Last();
  const long kLast = sense > 0 ? reference.Last() : -reference.First;

  // The reference's turn about `centre`, within the reference, traced again on this slice.
  const long         first = std::clamp(sense * centre - rays / 2, kFirst, kLast + 1 - rays);
  std::deque<double> rho;
  std::deque<char>   confirmed;
  double             ridgeLevel = 0.0;
  const double       spacing = settings.Pitch;
  // Windows scaled by the turn spacing (the crossing width of a blurred sheet over a bright
  // background can reach the spacing): a quarter spacing on both sides of the sample, the
  // flanks an eighth of it on both sides of the middle of the gaps.
  const PolarSlice measure = SheetMeasure(slice,
                                          std::max(1L, std::lround(0.25 * spacing / slice.Dr)),
                                          std::max(1L, std::lround(0.5 * spacing / slice.Dr)),
                                          std::max(1L, std::lround(0.125 * spacing / slice.Dr)));
  {
    std::vector<double> bound;
    for (long k = first; k < first + rays; ++k)
    {
      bound.push_back(reference.At(sense * k));
    }
    const TurnPath turn =
      TraceTurn(slice, measure, sense * first, static_cast<int>(sense), bound, {}, 0, bound.front(), 0.0, settings);
    if (turn.Rho.size() < static_cast<size_t>(rays))
    {
      return SpiralTrace{};
    }
    rho.assign(turn.Rho.begin(), turn.Rho.end());
    confirmed.assign(turn.Confirmed.begin(), turn.Confirmed.end());
    std::vector<double> levels;
    std::copy_if(
      turn.Measure.begin(), turn.Measure.end(), std::back_inserter(levels), [](double v) { return std::isfinite(v); });
    ridgeLevel = levels.empty() ? 0.0 : RidgeLevel * std::max(0.0, Median(levels));
  }
  long start = first; // k of rho.front()

  // Inwards, each turn bounded by the one outside it.
  for (;;)
  {
    std::vector<double> bound(static_cast<size_t>(rays)), beyond;
    for (long i = 0; i < rays; ++i)
    {
      bound[static_cast<size_t>(i)] = rho[static_cast<size_t>(rays - 1 - i)];
      if (rho.size() >= static_cast<size_t>(2 * rays))
      {
        beyond.push_back(rho[static_cast<size_t>(2 * rays - 1 - i)]);
      }
    }
    const TurnPath turn = TraceTurn(slice,
                                    measure,
                                    sense * (start - 1),
                                    static_cast<int>(-sense),
                                    bound,
                                    beyond,
                                    -1,
                                    rho.front(),
                                    ridgeLevel,
                                    settings);
    for (size_t i = 0; i < turn.Rho.size(); ++i)
    {
      rho.push_front(turn.Rho[i]);
      confirmed.push_front(turn.Confirmed[i]);
    }
    start -= static_cast<long>(turn.Rho.size());
    if (turn.Ended)
    {
      break;
    }
  }

  // Outwards from the innermost whole turn, each turn bounded by the one inside it.
  const size_t keep = std::min(rho.size(), static_cast<size_t>(rays));
  rho.resize(keep);
  confirmed.resize(keep);
  while (rho.size() >= static_cast<size_t>(rays))
  {
    const std::vector<double> bound(rho.end() - rays, rho.end());
    std::vector<double>       beyond;
    if (rho.size() >= static_cast<size_t>(2 * rays))
    {
      beyond.assign(rho.end() - 2 * rays, rho.end() - rays);
    }
    const TurnPath turn = TraceTurn(slice,
                                    measure,
                                    sense * (start + static_cast<long>(rho.size())),
                                    static_cast<int>(sense),
                                    bound,
                                    beyond,
                                    +1,
                                    rho.back(),
                                    ridgeLevel,
                                    settings);
    rho.insert(rho.end(), turn.Rho.begin(), turn.Rho.end());
    confirmed.insert(confirmed.end(), turn.Confirmed.begin(), turn.Confirmed.end());
    if (turn.Ended)
    {
      break;
    }
  }

  // Back to the angular index m, ascending.
  SpiralTrace trace;
  trace.Rho.assign(rho.begin(), rho.end());
  trace.Confirmed.assign(confirmed.begin(), confirmed.end());
  trace.First = start;
  if (sense < 0)
  {
    std::reverse(trace.Rho.begin(), trace.Rho.end());
    std::reverse(trace.Confirmed.begin(), trace.Confirmed.end());
    trace.First = -(start + static_cast<long>(rho.size()) - 1);
  }
  return trace;
}
} // namespace RollTracing
} // end namespace itk

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
#include "vuPolyline.h"
#include "vuSliceTracer.h"

#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <future>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>
#include <thread>
#include <utility>

namespace itk {
namespace RollTracing {
namespace {
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

// Slices averaged on each side of the seed slice.
constexpr long SeedHalfWidth = 3;
// How much more of its crossings another candidate seed slice's trace must explain than
// the middle one's to be taken instead.
constexpr double SeedPreference = 0.05;
// How much more of the seed slice's crossings its trace turn by turn (minimal paths) must
// explain than the crossing follower's to be taken instead.
constexpr double PathsPreference = 0.02;
// A roll's slices keep traces that turn, at their median, at least this share of the seed
// slice's turns.
constexpr double KeptTurnsShare = 0.5;
// ... and find the sheet, over every slice with material, on at least this share of their
// steps.
constexpr double RollConfirmedShare = 0.5;

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

// `trace` extended at its end `end` (0: inner, 1: outer) to the angular index `target` on
// `guide`'s curve, offset by `offset`; the steps added are unconfirmed.
void
ExtendAlong(Tracer::Trace & trace, const Tracer::Trace & guide, int end, long target, double offset)
{
  if (end == 1)
  {
    for (long m = trace.Last() + 1; m <= target; ++m)
    {
      trace.Rho.push_back(guide.At(m) + offset);
      trace.Confirmed.push_back(0);
    }
    return;
  }
  std::vector<double> rho;
  for (long m = target; m < trace.First; ++m)
  {
    rho.push_back(guide.At(m) + offset);
  }
  trace.Rho.insert(trace.Rho.begin(), rho.begin(), rho.end());
  trace.Confirmed.insert(trace.Confirmed.begin(), rho.size(), 0);
  trace.First = std::min(trace.First, target);
}

// `trace` continued at its end `end` to `target` along `neighbour`'s curve (which covers
// that end), offset by the mean distance between the two over the last quarter turn both
// have.
void
ContinueAlong(Tracer::Trace & trace, const Tracer::Trace & neighbour, int end, long target, const PolarFrame & frame)
{
  double sum = 0.0;
  long   used = 0;
  for (long m = end == 0 ? trace.First : trace.Last(); used < frame.Rays / 4 && trace.Covers(m) && neighbour.Covers(m);
       m += end == 0 ? 1 : -1)
  {
    sum += trace.At(m) - neighbour.At(m);
    ++used;
  }
  ExtendAlong(trace, neighbour, end, target, used > 0 ? sum / static_cast<double>(used) : 0.0);
}

// The trace nearest slices[i] (at most `reach` slices away; at equal distances the one
// before) that `usable` accepts and that covers the angular indices `from` and `to`;
// nullptr if none does.
template <typename Usable>
const Tracer::Trace *
NearestCovering(const std::vector<Tracer::Trace> & traces,
                const std::vector<size_t> &        slices,
                size_t                             i,
                size_t                             reach,
                long                               from,
                long                               to,
                Usable                             usable)
{
  for (size_t d = 1; d <= reach; ++d)
  {
    for (const size_t j : { i - d, i + d }) // i - d wraps past 0 to beyond the slices
    {
      if (j < slices.size() && usable(j) && traces[slices[j]].Covers(from) && traces[slices[j]].Covers(to))
      {
        return &traces[slices[j]];
      }
    }
  }
  return nullptr;
}

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
      const Tracer::Trace * neighbour =
        NearestCovering(original, slices, static_cast<size_t>(i), EndReach, at, target, [](size_t) { return true; });
      if (neighbour != nullptr)
      {
        ContinueAlong(trace, *neighbour, end, target, frame);
      }
    }
  }
}

// A trace ends at the last crossing it found, and in a noisy scan a crossing of noise lies
// near the prediction now and then past the sheet's inner end: the trace runs on into the
// roll's core, towards the next turn, and the slices traced after it are guided along the
// same stretch. The sheet goes on along the roll axis and noise does not, so a trace's
// inner end is cut back to where the slices SupportSlices away on one side or the other
// (beyond the smoothing along the axis) hold material at its points, by at most a turn
// spacing. Within EdgeReach of where the scan holds no data (a field of view that cuts the
// sheet) the end is left as it is.
constexpr long   SupportSlices[2] = { 3, 8 };
constexpr double SupportRun = 1.5; // voxels of arc held in a row

void
TrimUnsupportedInnerEnds(std::vector<Tracer::Trace> & traces,
                         const std::vector<size_t> &  slices,
                         const Tracer &               tracer,
                         const SheetVolumeView &      volume,
                         const float *                values,
                         const Settings &             settings)
{
  const PolarFrame & frame = tracer.Frame();
  const double       voxel = settings.Voxel;
  const double       material = settings.AirLevel + MaterialLevel * (settings.SheetLevel - settings.AirLevel);
  const double       reach = std::max(tracer.Pitch(), 6.0 * voxel);
  const auto         nz = static_cast<long>(volume.Size[2]);
  for (size_t k : slices)
  {
    Tracer::Trace & trace = traces[k];
    if (trace.Empty())
    {
      continue;
    }
    const ValueSlice own(volume, values, k);
    // The slices SupportSlices away on either side, and whether those on one side hold
    // material at a point (the mean of their values).
    std::vector<ValueSlice> sides[2];
    for (long d = SupportSlices[0]; d <= SupportSlices[1]; ++d)
    {
      for (int side = 0; side < 2; ++side)
      {
        const long other = static_cast<long>(k) + (side == 0 ? -d : d);
        if (other >= 0 && other < nz)
        {
          sides[side].emplace_back(volume, values, static_cast<size_t>(other));
        }
      }
    }
    auto supported = [&](const double xy[2]) {
      for (const auto & neighbours : sides)
      {
        double sum = 0.0;
        for (const ValueSlice & slice : neighbours)
        {
          sum += slice.Value(xy[0], xy[1], settings.AirLevel);
        }
        if (!neighbours.empty() && sum / static_cast<double>(neighbours.size()) >= material)
        {
          return true;
        }
      }
      return false;
    };
    double arc = 0.0, run = 0.0;
    long   runStart = trace.First, cutAt = trace.First;
    bool   found = false;
    for (long m = trace.First; m <= trace.Last() && arc <= reach + SupportRun * voxel; ++m)
    {
      const double rho = trace.At(m);
      double       xy[2];
      tracer.PointAt(k, m, rho, xy);
      if (own.NearEdge(xy[0], xy[1], EdgeReach * voxel))
      {
        break;
      }
      const double stepArc = std::max(voxel, rho) * frame.Step;
      arc += stepArc;
      if (supported(xy))
      {
        runStart = run == 0.0 ? m : runStart;
        run += stepArc;
        if (run >= SupportRun * voxel)
        {
          cutAt = runStart;
          found = true;
          break;
        }
      }
      else
      {
        run = 0.0;
      }
    }
    if (found && cutAt > trace.First && cutAt < trace.Last())
    {
      const auto cut = static_cast<std::ptrdiff_t>(cutAt - trace.First);
      trace.Rho.erase(trace.Rho.begin(), trace.Rho.begin() + cut);
      trace.Confirmed.erase(trace.Confirmed.begin(), trace.Confirmed.begin() + cut);
      trace.First = cutAt;
    }
  }
}

// A sheet's cut edges run along the roll axis in a straight or slowly drifting line: the
// ends of the traces, as functions of the slice, are fitted robustly by lines over the
// middle 60 % of the slices, and a trace whose end lies further than DropTolerance of arc
// from its line (a slice that cuts the sheet's edge along the axis, faint and blurred; a
// trace lost before the end) is dropped, unless it stopped less than a turn short and can
// be continued along another slice's curve (below): the mesh interpolates a dropped slice
// from its neighbours, or ends before it. An end within EdgeReach of where the scan holds
// no data is where a field of view that cuts the roll cuts the sheet, not the sheet's end:
// where the edge of the data moves across the roll from slice to slice (a tilted roll
// resampled), the piece of a turn that comes back into view beyond a cut is there in some
// slices and not in others, and the ends step from one place to the other. Such ends
// neither count in the line nor drop their trace.
constexpr double DropTolerance = 8.0; // voxels

size_t
DropIncompleteTraces(std::vector<Tracer::Trace> & traces,
                     const std::vector<size_t> &  slices,
                     const Tracer &               tracer,
                     double                       voxel,
                     size_t &                     continued)
{
  continued = 0;
  const size_t n = slices.size();
  if (n < 5)
  {
    return 0;
  }
  const PolarFrame & frame = tracer.Frame();
  // The angular index of a trace's inner (end 0) or outer (end 1) end, and whether it lies
  // further than the tolerance from a line of (slice, end).
  auto              endOf = [](const Tracer::Trace & t, int end) { return end == 0 ? t.First : t.Last(); };
  std::vector<char> atEdge(2 * n, 0);
  for (size_t i = 0; i < n; ++i)
  {
    const Tracer::Trace & t = traces[slices[i]];
    for (int end = 0; end < 2 && !t.Empty(); ++end)
    {
      const long m = endOf(t, end);
      atEdge[2 * i + static_cast<size_t>(end)] = tracer.NearDataEdge(slices[i], m, t.At(m), EdgeReach * voxel) ? 1 : 0;
    }
  }
  auto lineAt = [](const double line[2], size_t i) { return line[0] + line[1] * static_cast<double>(i); };
  auto offLine = [&](size_t i, int end, const double line[2]) {
    const Tracer::Trace & t = traces[slices[i]];
    const long            m = endOf(t, end);
    const double          tolerance = ArcSteps(DropTolerance * voxel, t.At(m), voxel, frame);
    return std::abs(static_cast<double>(m) - lineAt(line, i)) > tolerance;
  };
  // The line of (slice, end) over the middle traces: fitted robustly first (Theil and Sen:
  // the median of the slopes between every two traces, then the median offset), then by
  // least squares over the traces within the tolerance of it. Where the ends of a group of
  // slices step away from the others' (a trace that lost the last piece of a turn, and
  // every slice after it), least squares alone gives a line between the two groups, off
  // both: the whole ones were dropped with the short ones.
  auto fit = [&](int end, double line[2]) {
    std::vector<size_t> used;
    for (size_t i = n / 5; i < n - n / 5; ++i)
    {
      if (!traces[slices[i]].Empty() && atEdge[2 * i + static_cast<size_t>(end)] == 0)
      {
        used.push_back(i);
      }
    }
    if (used.size() < 3)
    {
      return false;
    }
    auto                at = [&](size_t i) { return static_cast<double>(endOf(traces[slices[i]], end)); };
    const auto          stride = std::max<size_t>(1, used.size() / 200);
    std::vector<double> values;
    for (size_t p = 0; p < used.size(); p += stride)
    {
      for (size_t q = p + stride; q < used.size(); q += stride)
      {
        values.push_back((at(used[q]) - at(used[p])) / static_cast<double>(used[q] - used[p]));
      }
    }
    line[1] = Median(values);
    values.clear();
    for (size_t i : used)
    {
      values.push_back(at(i) - line[1] * static_cast<double>(i));
    }
    line[0] = Median(values);
    LineFit points;
    for (size_t i : used)
    {
      if (!offLine(i, end, line))
      {
        points.Add(static_cast<double>(i), at(i));
      }
    }
    if (points.N >= 3.0)
    {
      points.Solve(line[0], line[1]);
    }
    return true;
  };
  double     lines[2][2];
  const bool fitted[2] = { fit(0, lines[0]), fit(1, lines[1]) };
  auto       dropEnd = [&](size_t i, int end) {
    return fitted[end] && atEdge[2 * i + static_cast<size_t>(end)] == 0 && offLine(i, end, lines[end]);
  };
  // A trace that stops short of its line by less than a turn, at an end where another slice
  // reaches the line, is first continued along the nearest such slice's curve: the turns
  // change slowly along the axis, and a group of slices that lost the last piece of a turn
  // alike (a faint stretch by the sheet's edge along the axis) would otherwise all be
  // left out, and the mesh end before them. It is dropped if it is still off its line.
  std::vector<char> whole(n, 0);
  for (size_t i = 0; i < n; ++i)
  {
    whole[i] = !traces[slices[i]].Empty() && !dropEnd(i, 0) && !dropEnd(i, 1) ? 1 : 0;
  }
  // Only traces that are not whole change below: the guides stay as they were.
  size_t dropped = 0;
  for (size_t i = 0; i < n; ++i)
  {
    Tracer::Trace & trace = traces[slices[i]];
    if (trace.Empty() || whole[i])
    {
      continue;
    }
    for (int end = 0; end < 2; ++end)
    {
      const long at = endOf(trace, end);
      if (!dropEnd(i, end))
      {
        continue;
      }
      const auto target = static_cast<long>(std::lround(lineAt(lines[end], i)));
      if ((end == 0 ? at - target : target - at) <= 0 || std::abs(target - at) > frame.Rays)
      {
        continue; // it runs on past its line, or lost more than a turn
      }
      const Tracer::Trace * guide =
        NearestCovering(traces, slices, i, n, at, target, [&](size_t j) { return whole[j] != 0; });
      if (guide != nullptr)
      {
        ContinueAlong(trace, *guide, end, endOf(*guide, end), frame);
      }
    }
    if (dropEnd(i, 0) || dropEnd(i, 1))
    {
      trace = Tracer::Trace{};
      ++dropped;
    }
    else
    {
      ++continued;
    }
  }
  return dropped;
}

// Slices in a row whose traces may be dropped for disagreeing with the last kept one.
constexpr size_t MaximumRejected = 8;

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

// Last angular index at which two traces differ by more than half the turn spacing, given
// the first (FirstDisagreement, >= 0): scanned back from the end of their overlap.
long
LastDisagreement(const Tracer::Trace & a, const Tracer::Trace & b, double pitch, long first)
{
  long last = std::min(a.Last(), b.Last());
  while (last > first && std::abs(a.At(last) - b.At(last)) <= 0.5 * pitch)
  {
    --last;
  }
  return last;
}

// Whether every place where two traces differ by more than half the turn spacing, the
// first at `first` (FirstDisagreement), lies in one stretch shorter than `longest` angular
// steps, with the traces agreeing for at least as long on both sides of it: a touch that
// begins or ends between the two slices (one turn pushed onto the next over a short arc in
// one slice and not in the other), not a trace that lost its turn, which stays off it from
// there on.
bool
DisagreeLocally(const Tracer::Trace & a, const Tracer::Trace & b, double pitch, long first, long longest)
{
  const long from = std::max(a.First, b.First), to = std::min(a.Last(), b.Last());
  const long last = LastDisagreement(a, b, pitch, first);
  return last - first < longest && first - from >= longest && to - last >= longest;
}

// Whether two traces differ by more than half the turn spacing nowhere, or only locally
// (DisagreeLocally).
bool
AgreeLocally(const Tracer::Trace & a, const Tracer::Trace & b, double pitch, long longest)
{
  const long first = FirstDisagreement(a, b, pitch);
  return first < 0 || DisagreeLocally(a, b, pitch, first, longest);
}

// The part of `trace` that stays within half a turn spacing of `prior`: all of it where it
// leaves the prior nowhere or only locally (DisagreeLocally), else the longer of its
// stretches before the first and after the last place where it leaves it (a trace carried
// onto the neighbouring turn at a touch, or begun on it there, keeps the part on its own).
Tracer::Trace
KeepAgreeing(Tracer::Trace trace, const Tracer::Trace & prior, const Tracer & tracer)
{
  const double pitch = tracer.Pitch();
  const long   first = FirstDisagreement(prior, trace, pitch);
  if (first < 0 || DisagreeLocally(prior, trace, pitch, first, tracer.Frame().Rays / 8))
  {
    return trace;
  }
  const long last = LastDisagreement(prior, trace, pitch, first);
  if (first - trace.First >= trace.Last() - last)
  {
    trace.Rho.resize(static_cast<size_t>(first - trace.First));
    trace.Confirmed.resize(trace.Rho.size());
  }
  else
  {
    const auto cut = static_cast<std::ptrdiff_t>(last + 1 - trace.First);
    trace.Rho.erase(trace.Rho.begin(), trace.Rho.begin() + cut);
    trace.Confirmed.erase(trace.Confirmed.begin(), trace.Confirmed.begin() + cut);
    trace.First = last + 1;
  }
  return trace;
}

// A trace that stopped short of its prior's ends (a touch it could not pass, a faint
// stretch, a streak, the part of a turn outside the field of view) would lose the rest of
// the roll for every slice after it. It is traced again from the prior's stretch beyond
// each end it stopped at more than half a turn short of; a second piece that agrees with the
// prior is joined to it, the stretch between the two (at most a turn) on the prior's curve,
// offset linearly from one piece's end to the other's. Again from the joined trace's end,
// up to MaximumResumptions times: a roll cut by the field of view leaves it once a turn, and
// a piece resumed past one cut stops at the next.
constexpr int MaximumResumptions = 4;

void
ResumeBeyondStops(Tracer::Trace &        trace,
                  const Tracer::Trace &  prior,
                  const Tracer &         tracer,
                  const SliceCrossings & crossings,
                  size_t                 slice)
{
  const long   half = tracer.Frame().Rays / 2;
  const double pitch = tracer.Pitch();
  // One resumption beyond the trace's end `end`; true when the trace grew.
  auto resume = [&](int end) {
    if (trace.Empty())
    {
      return false;
    }
    const long from = end == 0 ? prior.First : trace.Last() + half / 4;
    const long to = end == 0 ? trace.First - half / 4 : prior.Last();
    if ((end == 0 ? trace.First - prior.First : prior.Last() - trace.Last()) <= half || to - from < half / 2)
    {
      return false;
    }
    Tracer::Trace piece = tracer.TraceNear(crossings, slice, prior, from, to);
    piece = piece.Empty() ? piece : KeepAgreeing(std::move(piece), prior, tracer);
    if (piece.Empty() || FirstDisagreement(prior, piece, pitch) >= 0 || FirstDisagreement(trace, piece, pitch) >= 0)
    {
      return false;
    }
    const Tracer::Trace & inner = end == 0 ? piece : trace;
    const Tracer::Trace & outer = end == 0 ? trace : piece;
    if (piece.First <= trace.First && piece.Last() >= trace.Last())
    {
      trace = std::move(piece); // passed the hard place from the other side
      return true;
    }
    if (outer.Last() <= inner.Last() || outer.First <= inner.First)
    {
      return false; // the trace holds the piece
    }
    Tracer::Trace joined;
    joined.First = inner.First;
    joined.Rho.assign(static_cast<size_t>(outer.Last() - inner.First + 1), 0.0);
    joined.Confirmed.assign(joined.Rho.size(), 0);
    const long gapFrom = inner.Last() + 1, gapTo = outer.First - 1;
    if (gapFrom <= gapTo &&
        (!(prior.Covers(gapFrom - 1) && prior.Covers(gapTo + 1)) || gapTo - gapFrom >= tracer.Frame().Rays))
    {
      return false; // a trace started away from the prior, or more than a turn to bridge
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
    return true;
  };
  for (int end : { 0, 1 })
  {
    for (int resumption = 0; resumption < MaximumResumptions && resume(end); ++resumption)
    {}
  }
}
// A seed slice's tracer, crossings and trace.
struct SeedTrace
{
  Tracer         SeedTracer;
  SliceCrossings Crossings;
  Tracer::Trace  Trace;
};

// The seed slice `seed` traced on the mean profile of its neighbours by a tracer of its own
// (its centre, frame and turn spacing).
SeedTrace
TraceSeed(const SheetVolumeView &     volume,
          const float *               values,
          const Settings &            settings,
          const std::vector<size_t> & material,
          size_t                      seed)
{
  SeedTrace           result{ Tracer(volume, values, settings), {}, {} };
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
    // through clearly more of the crossings (where the follower crossed onto the next turn
    // at a touch and lost the rest of the one it was on) without running through air for
    // more than a few voxels (a path cut across a gap, which the follower never does).
    Tracer::Trace paths = tracer.TracePaths(polar, result.Trace, result.Crossings);
    if (!paths.Empty() &&
        tracer.Explained(result.Crossings, paths) >
          tracer.Explained(result.Crossings, result.Trace) + PathsPreference &&
        tracer.LongestAirArc(polar, paths) <= PathAirArc * settings.Voxel)
    {
      result.Trace = std::move(paths);
    }
  };
  traceAtOffset(0.0, 0.0);
  // The centroid line need not pass through the spiral's centre (an irregular roll, a field
  // of view that cuts it): re-centre on the innermost turn and trace again. The innermost
  // turn's own centre can lie off the spiral's (a squashed or irregular inner turn): a
  // re-centred trace that passes through clearly fewer of its crossings is undone.
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
    const double before[2] = { tracer.GetOffset()[0], tracer.GetOffset()[1] };
    const double explained = tracer.Explained(result.Crossings, result.Trace);
    traceAtOffset(before[0] + mean[0], before[1] + mean[1]);
    if (result.Trace.Empty() || tracer.Explained(result.Crossings, result.Trace) < explained - SeedPreference)
    {
      traceAtOffset(before[0], before[1]);
      break;
    }
  }
  return result;
}

// The seed slice among three (at 50, 30 and 70 % of the sheet's width), each traced at the
// same time given two threads or more: the middle one unless another's trace passes
// through clearly more of its crossings, or the one the settings name (then alone traced).
// Returns the index of the chosen one in `seeds`.
size_t
ChooseSeed(const SheetVolumeView &     volume,
           const float *               values,
           const Settings &            settings,
           const std::vector<size_t> & material,
           std::vector<long> &         candidates,
           std::vector<SeedTrace> &    seeds)
{
  auto sliceAt = [&](double fraction) {
    return static_cast<long>(fraction * static_cast<double>(material.size() - 1) + 0.5);
  };
  if (settings.SeedCandidate >= 0)
  {
    // The named fraction's own slice (on a sheet a few slices wide two fractions may share one).
    const size_t named = std::min(std::size(SeedFractions) - 1, static_cast<size_t>(settings.SeedCandidate));
    candidates = { sliceAt(SeedFractions[named]) };
  }
  else
  {
    for (const double fraction : SeedFractions)
    {
      const long index = sliceAt(fraction);
      if (std::find(candidates.begin(), candidates.end(), index) == candidates.end())
      {
        candidates.push_back(index);
      }
    }
  }
  std::vector<std::optional<SeedTrace>> traced(candidates.size());
  std::vector<std::function<void()>>    seedTasks;
  for (size_t c = 0; c < candidates.size(); ++c)
  {
    seedTasks.emplace_back([&, c]() {
      traced[c].emplace(TraceSeed(volume, values, settings, material, material[static_cast<size_t>(candidates[c])]));
    });
  }
  RunTogether(seedTasks);
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
  return chosen;
}

// A slice traced with its neighbour's trace as prior (Tracer::TraceGuided, from the
// prior's middle). A start at a hard place (a touch where two turns merge, a streak) can
// stop the follower within a few steps both ways, and so short a trace would be the next
// slice's prior and lose the roll for every slice after it. Where the trace from the middle
// covers less than half of the prior, the middles of the prior's two halves are tried as
// well, each trace is cut to its part on the prior's turn (KeepAgreeing), and the one that
// stays on it over the most steps is kept; ResumeBeyondStops then takes up the rest of the
// roll. A longer trace that leaves the prior is left to the caller's check (dropped unless
// it leaves it only locally).
Tracer::Trace
TraceGuided(const Tracer & tracer, const SliceCrossings & crossings, size_t slice, const Tracer::Trace & prior)
{
  Tracer::Trace trace = tracer.TraceGuided(crossings, slice, prior);
  if (trace.Empty() || 2 * (trace.Last() - trace.First) >= prior.Last() - prior.First)
  {
    return trace;
  }
  auto agreeing = [&](const Tracer::Trace & t) {
    long count = 0;
    for (long m = std::max(t.First, prior.First); m <= std::min(t.Last(), prior.Last()); ++m)
    {
      count += std::abs(t.At(m) - prior.At(m)) <= 0.5 * tracer.Pitch() ? 1 : 0;
    }
    return count;
  };
  trace = KeepAgreeing(std::move(trace), prior, tracer);
  long       best = agreeing(trace);
  const long middle = (prior.First + prior.Last()) / 2;
  for (const auto & [from, to] : { std::make_pair(prior.First, middle), std::make_pair(middle, prior.Last()) })
  {
    Tracer::Trace other = tracer.TraceNear(crossings, slice, prior, from, to);
    if (other.Empty())
    {
      continue;
    }
    other = KeepAgreeing(std::move(other), prior, tracer);
    const long count = agreeing(other);
    if (count > best)
    {
      trace = std::move(other);
      best = count;
    }
  }
  return trace;
}

// The prior for the slice after one traced as `trace` with `prior`: the trace, and beyond
// an end at which it stopped more than DropTolerance of arc short of its prior, the
// prior's stretch, offset to meet the trace's end. A slice that misses the last piece of a
// turn (noise at the place where a roll cut by the field of view comes back into it, a faint
// stretch) would otherwise take that piece from every slice after it, and they would all be
// dropped as traced only in part. `carried` counts, per end, the slices in a row whose
// prior was carried on so; after MaximumCarried of them the end is taken as the trace's
// (the sheet's edge along the axis cuts the turn there).
constexpr long MaximumCarried = 8;

Tracer::Trace
CarryShortEnds(const Tracer::Trace & trace,
               const Tracer::Trace & prior,
               long                  carried[2],
               const PolarFrame &    frame,
               double                voxel)
{
  Tracer::Trace next = trace;
  for (int end = 0; end < 2; ++end)
  {
    const long   at = end == 0 ? trace.First : trace.Last();
    const long   beyond = end == 0 ? prior.First : prior.Last();
    const bool   shorter = end == 0 ? beyond < at : beyond > at;
    const double tolerance = ArcSteps(DropTolerance * voxel, trace.At(at), voxel, frame);
    if (!shorter || !prior.Covers(at) || static_cast<double>(std::abs(beyond - at)) <= tolerance ||
        carried[end] >= MaximumCarried)
    {
      carried[end] = 0;
      continue;
    }
    ++carried[end];
    const double offset = trace.At(at) - prior.At(at);
    ExtendAlong(next, prior, end, beyond, offset);
  }
  return next;
}

// Traces dropped for disagreeing with their prior are given back where the next trace kept
// vouches for them. A touch that begins between two slices moves a turn by half a spacing
// and more; the prior may be carried beyond its trace's ends on the slice before's curve
// (CarryShortEnds). The slices after either disagree with it and are dropped, until one is
// kept (it agrees again, or it disagrees as well and is kept all the same:
// MaximumRejected). Those dropped that agree with it (nowhere or only locally apart), each
// with the next one given back, from the nearest on, are given back: interpolated across
// the touch instead, they would lie between its turns. A dropped trace that stops short of
// the next one's end by more than `longest` angular steps is not: it lost its turn before
// its end, and where it agrees with the next one says nothing of where it did not.
void
GiveBackAgreeing(std::vector<std::pair<size_t, Tracer::Trace>> & dropped,
                 const Tracer::Trace &                           kept,
                 double                                          pitch,
                 long                                            longest,
                 std::vector<Tracer::Trace> &                    traces)
{
  const Tracer::Trace * after = &kept;
  for (auto it = dropped.rbegin(); it != dropped.rend(); ++it)
  {
    const Tracer::Trace & trace = it->second;
    if (trace.First > after->First + longest || trace.Last() < after->Last() - longest)
    {
      break;
    }
    if (!AgreeLocally(*after, trace, pitch, longest))
    {
      break;
    }
    traces[it->first] = std::move(it->second);
    after = &traces[it->first];
  }
}

// Every slice from the seed outwards in direction `dir` (+1 or -1), each traced with the
// previous slice's trace as prior (CarryShortEnds); the crossings of a batch of slices
// found in parallel. `done` counts the slices traced; `report` is called after each batch.
void
TraceOutwards(const Tracer &                tracer,
              const Tracer::Trace &         seedTrace,
              const std::vector<size_t> &   material,
              long                          seedIndex,
              int                           dir,
              double                        voxel,
              std::vector<Tracer::Trace> &  traces,
              std::atomic<size_t> &         done,
              const std::function<void()> & report)
{
  const size_t  batch = 16;
  Tracer::Trace prior = seedTrace;
  long          carried[2] = { 0, 0 };
  const long    longest = tracer.Frame().Rays / 8;
  // The traces dropped since the last one kept, in the order traced.
  std::vector<std::pair<size_t, Tracer::Trace>> dropped;
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
      traces[slices[i]] = TraceGuided(tracer, found[i], slices[i], prior);
      if (traces[slices[i]].Empty())
      {
        continue;
      }
      ResumeBeyondStops(traces[slices[i]], prior, tracer, found[i], slices[i]);
      // A trace that leaves its prior by half a turn spacing somewhere has lost or jumped
      // a turn (noise, a streak, a faint stretch): it is dropped (the slice is then
      // interpolated from its neighbours) and the prior carried on, unless the slices
      // keep disagreeing with it for longer than a few slices (the sheet itself changed).
      if (dropped.size() < MaximumRejected && !AgreeLocally(prior, traces[slices[i]], tracer.Pitch(), longest))
      {
        dropped.emplace_back(slices[i], std::move(traces[slices[i]]));
        traces[slices[i]] = Tracer::Trace{};
        continue;
      }
      GiveBackAgreeing(dropped, traces[slices[i]], tracer.Pitch(), longest, traces);
      dropped.clear();
      prior = CarryShortEnds(traces[slices[i]], prior, carried, tracer.Frame(), voxel);
    }
    q += dir * static_cast<long>(slices.size());
    done += slices.size();
    report();
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

double
SheetSliceLeast(const std::vector<double> & amounts)
{
  return 0.5 * SheetTracing::Percentile(amounts, 0.9);
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
  std::vector<double> amounts;
  for (size_t k = 0; k < nz; ++k)
  {
    const uint8_t * mask = volume.Mask + k * nx * ny;
    const auto      amount = std::count_if(mask, mask + nx * ny, [](uint8_t v) { return v != 0; });
    if (amount > 0)
    {
      material.push_back(k);
      amounts.push_back(static_cast<double>(amount));
    }
  }
  result.Slices.resize(nz);
  if (material.empty() || !(settings.SheetLevel > settings.AirLevel))
  {
    return result;
  }
  // The sheet's own slices: from the first to the last that holds as much material as a
  // slice of the sheet (SheetSliceLeast).
  const double sheetAmount = SheetSliceLeast(amounts);
  long         sheetFirst = 0, sheetLast = static_cast<long>(material.size()) - 1;
  while (sheetFirst < sheetLast && amounts[static_cast<size_t>(sheetFirst)] < sheetAmount)
  {
    ++sheetFirst;
  }
  while (sheetLast > sheetFirst && amounts[static_cast<size_t>(sheetLast)] < sheetAmount)
  {
    --sheetLast;
  }
  // Seed: a slice in the middle part of the sheet, traced on the mean profile of its
  // neighbours. Two turns that touch in the seed slice would carry its trace onto the next
  // turn, and every slice after it; a touch covers only part of the width, so three slices
  // (at 50, 30 and 70 % of the sheet's width) are tried and the middle one is kept unless
  // another's trace passes through clearly more of its crossings. Each is traced by a
  // tracer of its own (its centre, frame and turn spacing), at the same time given two
  // threads or more.
  std::vector<long>      candidates;
  std::vector<SeedTrace> seeds;
  const size_t           chosen = ChooseSeed(volume, values, settings, material, candidates, seeds);
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
  // fewer of them explained. A roll's turns wind around its axis at a distance; a flat
  // sheet whose centroid line lies in it gives a trace that hugs the centre, within about
  // the sheet's thickness, and may seem to turn and grow around it.
  const double medianGrowth = tracer.MedianGrowth(seedTrace);
  const bool   growsByPitch = tracer.GrowsByPitch(medianGrowth);
  const bool   aroundAxis = Median(seedTrace.Rho) >= 1.2 * std::max(settings.Voxel, tracer.Width());
  result.Rolled = turns >= 1.0 && aroundAxis && medianGrowth >= std::max(settings.Voxel, 0.5 * tracer.Width()) &&
                  (result.Explained >= 0.6 || (turns >= 2.0 && growsByPitch && result.Explained >= 0.4));
  progress(0.1);

  // Every slice, outwards from the seed, with the previous slice's trace as prior. The
  // crossings of a batch of slices are found in parallel; the two directions are independent
  // and, given two threads or more, traced at the same time (the progress from the calling
  // thread's).
  std::vector<Tracer::Trace> traces(nz);
  std::atomic<size_t>        done{ 0 };
  const std::thread::id      caller = std::this_thread::get_id();
  auto                       report = [&]() {
    if (std::this_thread::get_id() == caller)
    {
      progress(0.1 + 0.85 * static_cast<double>(done) / static_cast<double>(material.size()));
    }
  };
  auto outwards = [&](int dir) {
    TraceOutwards(tracer, seedTrace, material, seedIndex, dir, settings.Voxel, traces, done, report);
  };
  RunTogether({ [&]() { outwards(+1); }, [&]() { outwards(-1); } });

  TrimUnsupportedInnerEnds(traces, material, tracer, volume, values, settings);
  MatchEndsToNeighbours(traces, material, tracer.Frame(), settings.Voxel);
  result.Incomplete = DropIncompleteTraces(traces, material, tracer, settings.Voxel, result.Continued);

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
  // A seed slice's trace may turn and grow like a spiral's where a flat sheet bends (a page
  // pressed onto the next, a block of pages fused into one piece) while the slices keep no
  // trace of a roll, or keep only short arcs of one: a roll's slices turn about as often as
  // its seed slice, so the traces kept must turn, at their median, at least half as often.
  // Nor is it a roll when the slices' traces, over every slice of the sheet, find the sheet
  // on fewer than half of their steps (a trace that steps from page to page around a block
  // of fused pages is carried across their ends and gaps). Both over the sheet's own slices
  // (debris beyond its ends along the axis holds no trace of it).
  std::vector<double> keptTurns;
  double              confirmed = 0.0;
  for (long i = sheetFirst; i <= sheetLast; ++i)
  {
    const SliceTrace & slice = result.Slices[material[static_cast<size_t>(i)]];
    if (!slice.Line.empty())
    {
      keptTurns.push_back(slice.Turns);
      confirmed += slice.Confirmed;
    }
  }
  result.Rolled = result.Rolled && !keptTurns.empty() && Median(keptTurns) >= KeptTurnsShare * turns &&
                  confirmed >= RollConfirmedShare * static_cast<double>(sheetLast - sheetFirst + 1);
  progress(1.0);
  return result;
}
} // namespace RollTracing
} // end namespace itk

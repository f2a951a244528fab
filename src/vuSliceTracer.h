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
#ifndef vuSliceTracer_h
#define vuSliceTracer_h

#include "vuMedian.h"
#include "vuRollTracer.h"
#include "vuSpiralPath.h"

#include "itkMultiThreaderBase.h"

#include <cmath>
#include <functional>
#include <utility>
#include <vector>

// The roll tracer's parts: the polar frame, the crossings of the sheet with its rays, and
// the tracer of one slice (the seed slice alone, every other slice guided by its neighbour).
namespace itk {
namespace RollTracing {
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
// A crossing narrower than that but this many typical sheets wide or heavy may hold two
// turns pressed together: where a neighbouring turn lies in it too, each turn takes its half.
constexpr double SharedWidth = 1.25;
constexpr double SharedMass = 1.25;
// The next crossing is accepted within this fraction of the local turn spacing.
constexpr double AcceptWindow = 0.4;
// A seed slice's minimal paths are kept only where they run through air (within the scan's
// data) along no longer an arc than this many voxels: a path does not stop where the sheet
// does, and across a touch or round a turn's end it may cut through the gap between turns.
constexpr double PathAirArc = 4.0;
// Rays on which the seed slice's trace is started (at three depths each).
constexpr long AloneRays = 8;
// Voxels from the edge of the scan's data within which the intensities are not trusted.
constexpr long DataMargin = 3;
// A turn carried through a stretch out of the field of view keeps at least this fraction of
// its learnt distance from the turn before.
constexpr double CarriedDistance = 0.65;
// A distance to a turn before is learnt as a share of that turn's radius (where that explains
// the steps better) only this many such distances from the slice's centre and further out;
// nearer it, a centre a few voxels off the spiral's own makes the share swing.
constexpr double ScaledFromDistances = 6.0;
// Voxels beyond DataMargin within which the scan's data ends: a turn predicted there is
// treated as out of the field of view (carried, not lost where its crossing is missing),
// and a trace's end there is where the field of view cuts the sheet, not the sheet's end.
// The edge of the data moves across the roll from slice to slice (a tilted roll resampled),
// and the sheet next to it is blurred with the air beyond it: a neighbouring slice whose
// trace carried the turn through a few voxels further out would otherwise guide this one
// into a stretch just inside the margin where its crossing is not found, and the trace
// would stop there, with every turn after it lost.
constexpr double EdgeReach = 3.0;
// Voxels within which the edge of the data is too near for a band to be taken as a turn
// pressed onto its neighbour (NearestCrossing): where the edge cuts a turn, the cut end
// and the turn beside it form a band.
constexpr double PressedEdgeReach = 3.0 * EdgeReach;
// Largest separation of a band's two sheets, as a share of the turn spacing, for the band
// to be taken as a turn pressed onto its neighbour.
constexpr double PressedSeparation = 0.5;

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

  // Outside (Inside() false), or within `reach` (mm) of a point outside in one of eight
  // directions.
  bool
  NearEdge(double x, double y, double reach) const
  {
    if (!Inside(x, y))
    {
      return true;
    }
    // Called at every step of a trace: the eight unit directions are constants.
    constexpr double diagonal = 0.70710678118654752440;
    constexpr double directions[8][2] = { { 1.0, 0.0 },  { diagonal, diagonal },
                                          { 0.0, 1.0 },  { -diagonal, diagonal },
                                          { -1.0, 0.0 }, { -diagonal, -diagonal },
                                          { 0.0, -1.0 }, { diagonal, -diagonal } };
    for (const auto & d : directions)
    {
      if (!Inside(x + reach * d[0], y + reach * d[1]))
      {
        return true;
      }
    }
    return false;
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
  // The centroids of the crossing's inner and outer halves: the sheets of two turns pressed
  // together too closely to show as a band (Radius for a crossing too narrow to halve).
  double InnerHalf;
  double OuterHalf;

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
SheetRadii(const std::vector<Crossing> & list);

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
  BuildFrame(const std::vector<size_t> & slices);

  const PolarFrame &
  Frame() const
  {
    return m_Frame;
  }

  // The mean of `slices` on the polar frame about the centre of `centreSlice`, as a fraction
  // of the contrast; with `markNoData`, the samples where the scan holds no data are marked.
  // With `parallel`, the rays are shared among ITK's threads (not from inside a parallel loop).
  PolarSlice
  Sample(size_t centreSlice, const std::vector<size_t> & slices, bool markNoData, bool parallel = false) const;

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
  TracePaths(const PolarSlice & polar, const Trace & reference, const SliceCrossings & crossings) const;

  // Each step of a trace moved to the crossing of its ray nearest it, if that lies within
  // AcceptWindow of the turn spacing and not on the turn before (inwards), which took it
  // already: where two turns touch, the path of the outer one may keep to the least distance
  // from the inner one, between the two sheets, while the split band has a crossing on each.
  void
  SnapToCrossings(Trace & trace, const SliceCrossings & crossings) const;

  // The longest arc (mm) along which a trace runs through air within the scan's data: its
  // radius on a sample of `polar` below MaterialLevel of the contrast.
  double
  LongestAirArc(const PolarSlice & polar, const Trace & trace) const;

  // Local maxima of a profile (fraction of the contrast) that rise above air by PeakLevel of the contrast and stand out
  // of their dips by PeakProminence; each placed at the centroid of its upper half.
  std::vector<Crossing>
  Peaks(const std::vector<double> & p) const;


  // Radial distance to the neighbouring turns of a trace at m (0 where it has none).
  double
  TraceSpacing(const Trace & trace, long m) const;

  // The sheet a ray crosses next beyond the turn before at `below`, in the direction of
  // `next`, when the sheet after it lies within AcceptWindow turn spacings of `next` (the
  // next turn): the turn between them, wherever it lies; NaN otherwise.
  double
  Between(const std::vector<Crossing> & list, double below, double next, double spacing) const;

  struct Step
  {
    long   M;
    double Rho;
    bool   Confirmed;
  };

  struct FollowModel;

  // The crossing of `list` nearest `target` (its index; list.size() for none) if it lies
  // within AcceptWindow of the local turn spacing of it (and, without a `guide` trace
  // covering step m, of the last accepted radius carried to this step) and not on the turn
  // one revolution before (`below`, or its `bump` at a touch): the trace would circle.
  // `sheet`: the radius of its sheet nearest the target (a band of touching turns: its inner
  // or outer sheet; a crossing heavier than one sheet that also holds the turn before or
  // the next turn (`ahead`, predicted; NaN where unknown): its half on this turn's side;
  // a band of two sheets whose sheet nearest the target is the turn before: its other sheet,
  // when it lies beyond the turn before on this turn's `side` of it (> 0 outwards, < 0
  // inwards, 0 unknown)).
  // `pressed`: the crossing is a band whose middle lies further from the target than the
  // window, but whose sheet nearest the target lies within it and whose other sheet is the
  // turn before (`below`, or its `bump`) or the next turn: this turn pressed onto a
  // neighbouring one (only where `pressable`, away from the edge of the data); the step
  // follows the touch as a bump.
  size_t
  NearestCrossing(const std::vector<Crossing> & list,
                  double                        target,
                  const Trace *                 guide,
                  long                          m,
                  double                        lastCarried,
                  double                        below,
                  double                        bump,
                  double                        ahead,
                  double                        side,
                  bool                          pressable,
                  double &                      sheet,
                  bool &                        pressed) const;

  // Updates what Follow() has learnt with a confirmed step at radius r: the distances to the
  // turns before (`below`, and `far`: two and three revolutions before; NaN where unknown),
  // the offset from the `guide` trace, the slope of the radius over the last steps.
  void
  Learn(FollowModel &             model,
        const std::vector<Step> & confirmed,
        double                    r,
        const double              far[2],
        double                    below,
        const Trace *             guide) const;

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
         const std::vector<Step> & opposite = {}) const;

  // Traces one slice from a start crossing both ways; the result runs from the inner end.
  Trace
  TraceFrom(const SliceCrossings & crossings, size_t slice, const Trace * prior, long start, double rho) const;

  // Trace without a prior: from the middle crossing of a ray with the median number of
  // crossings (away from the noise of the centre and the loose outer end).
  Trace
  TraceAlone(const SliceCrossings & crossings, size_t slice) const;

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
  TraceNear(const SliceCrossings & crossings, size_t slice, const Trace & prior, long from, long to) const;

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

  // Least distance a follower learns between a turn and the turn before: a sheet's
  // thickness, however tightly they touch.
  double
  LeastTurnDistance() const
  {
    return 0.8 * std::max(m_Width, m_Settings.Voxel);
  }

  // Median spacing of successive crossings and median crossing width.
  void
  MeasurePitch(const SliceCrossings & crossings);

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
  Explained(const SliceCrossings & crossings, const Trace & trace) const;

  Polyline
  ToPolyline(const Trace & trace, size_t slice) const;

  // Whether the point at angular index `m` and radius `rho` of slice `slice` lies within
  // `reach` (mm) of where the scan holds no data (ValueSlice::Inside): the edge of a field
  // of view that cuts the roll.
  bool
  NearDataEdge(size_t slice, long m, double rho, double reach) const;

  // The point (mm, in the slice) at angular index m and radius rho about the slice's centre.
  void
  PointAt(size_t slice, long m, double rho, double xy[2]) const;

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
} // namespace RollTracing
} // end namespace itk

#endif

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
#include "vuSliceTracer.h"
#include "vuMedian.h"

#include <algorithm>
#include <future>
#include <limits>
#include <numeric>

namespace itk {
namespace RollTracing {
Tracer::Trace
Tracer::TracePaths(const PolarSlice & polar, const Trace & reference, const SliceCrossings & crossings) const
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

void
Tracer::SnapToCrossings(Trace & trace, const SliceCrossings & crossings) const
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

double
Tracer::LongestAirArc(const PolarSlice & polar, const Trace & trace) const
{
  double longest = 0.0, run = 0.0;
  for (long m = trace.First; m <= trace.Last(); ++m)
  {
    const double rho = trace.At(m);
    const long   j = std::lround(rho / polar.Dr);
    const double v = j >= 0 && j < polar.Samples ? polar.At(m, j) : std::numeric_limits<double>::quiet_NaN();
    run = std::isfinite(v) && v < MaterialLevel ? run + rho * m_Frame.Step : 0.0;
    longest = std::max(longest, run);
  }
  return longest;
}

double
Tracer::TraceSpacing(const Trace & trace, long m) const
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

double
Tracer::Between(const std::vector<Crossing> & list, double below, double next, double spacing) const
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

// What Follow() has learnt from its confirmed steps: the distance to the turn one revolution
// before and to those two and three before, the offset from the prior, and the radius's
// slope per step.
struct Tracer::FollowModel
{
  // A distance to a turn before, learnt over the last eighth of a turn (at least a dozen
  // steps) of confirmed steps: their median, so that a short stretch where two turns touch
  // (one merged crossing between them) does not pull the next prediction onto the wrong
  // turn. Either in millimetres or as a share of the turn before's radius, whichever
  // explains those steps better. About an elliptic section's axis every turn's radius
  // scales with the section's shape at that angle, and so does the distance between two
  // turns (half as much again on the long axis of a roll squashed to 0.65): a distance in
  // millimetres lags the shape and predicts the next turn in the gap before it where the
  // section widens. About a centre off the spiral's own (a roll's inner turns, an irregular
  // section) the distance stays and its share changes, so the share is taken only
  // ScaledFromDistances distances from the centre and further out.
  struct Learnt
  {
    std::vector<double> Distances, Radii; // per confirmed step: the distance, the turn before's radius
    double              Absolute{ 0.0 };
    double              Share{ 0.0 };
    bool                Scaled{ false };
    std::vector<double> Scratch; // the window's values, reused from one recomputation to the next

    bool
    Known() const
    {
      return Distances.size() >= 6;
    }

    // Recomputed every fourth step once there are more than 24.
    void
    Add(double distance, double radius, size_t window)
    {
      Distances.push_back(distance);
      Radii.push_back(radius);
      if (Distances.size() > 24 && Distances.size() % 4 != 0)
      {
        return;
      }
      const size_t n = std::min(window, Distances.size());
      const size_t from = Distances.size() - n;
      Scratch.assign(Distances.begin() + static_cast<std::ptrdiff_t>(from), Distances.end());
      Absolute = MedianInPlace(Scratch);
      double meanRadius = 0.0;
      for (size_t i = from; i < Distances.size(); ++i)
      {
        meanRadius += Radii[i] / static_cast<double>(n);
      }
      Scaled = false;
      if (meanRadius < ScaledFromDistances * std::abs(Absolute))
      {
        return;
      }
      for (size_t i = 0; i < n; ++i)
      {
        Scratch[i] = Distances[from + i] / Radii[from + i];
      }
      Share = MedianInPlace(Scratch);
      double absoluteResidual = 0.0, scaledResidual = 0.0;
      for (size_t i = from; i < Distances.size(); ++i)
      {
        absoluteResidual += std::abs(Distances[i] - Absolute);
        scaledResidual += std::abs(Distances[i] - Share * Radii[i]);
      }
      Scaled = scaledResidual < absoluteResidual;
    }

    double
    At(double radius) const
    {
      return Scaled ? Share * radius : Absolute;
    }
  };

  Learnt Turn;
  double TurnOffset{ 0.0 }; // the distance to the turn before at the current step
  Learnt Far[2];
  double FarOffset[2]{ 0.0, 0.0 };
  double Slope{ 0.0 };
  double Offset{ 0.0 };

  // The distances at a step whose turns one, two and three revolutions before lie at
  // `below` and `far` (NaN where unknown: the distances taken last are kept); turns lie at
  // least `least` apart, however tightly they touch.
  void
  ScaleTo(double below, const double far[2], double least)
  {
    if (Turn.Known() && std::isfinite(below) && below > 0.0)
    {
      TurnOffset = Turn.At(below);
      if (std::abs(TurnOffset) < least)
      {
        TurnOffset = std::copysign(least, TurnOffset);
      }
    }
    for (int j = 0; j < 2; ++j)
    {
      if (Far[j].Known() && std::isfinite(far[j]) && far[j] > 0.0)
      {
        FarOffset[j] = Far[j].At(far[j]);
      }
    }
  }

  // The radius predicted from the turn before (`below`), or, once the turns two and three
  // before (`far`) are known, the median of the three predictions: where the turn before
  // bulges onto this one (a touch), it alone would carry the bulge outwards onto the next
  // turn; the median does not.
  double
  FromTurns(double below, const double far[2]) const
  {
    const double fromTurn = below + TurnOffset;
    if (Far[0].Known() && Far[1].Known() && std::isfinite(far[0]) && std::isfinite(far[1]))
    {
      std::vector<double> three{ fromTurn, far[0] + FarOffset[0], far[1] + FarOffset[1] };
      return Median(three);
    }
    return fromTurn;
  }
};

namespace {
// The point at `angle` and radius `rho` about `centre` (mm, in the slice).
void
PointAbout(const double centre[2], double angle, double rho, double xy[2])
{
  xy[0] = centre[0] + rho * std::cos(angle);
  xy[1] = centre[1] + rho * std::sin(angle);
}

// The radius of the turn one revolution before each of the first `rays` steps of a trace
// from `start` in direction `dir`: the steps `opposite` already followed the other way from
// the same start (NaN where they do not reach).
std::vector<double>
TurnBeforeStart(const std::vector<Tracer::Step> & opposite, long start, int dir, long rays)
{
  std::vector<double> before(static_cast<size_t>(rays), std::numeric_limits<double>::quiet_NaN());
  for (const Tracer::Step & o : opposite)
  {
    const long back = dir * (start - o.M); // steps taken the other way
    if (back > 0 && back <= rays)
    {
      before[static_cast<size_t>(rays - back)] = o.Rho;
    }
  }
  return before;
}
} // namespace

size_t
Tracer::NearestCrossing(const std::vector<Crossing> & list,
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
                        bool &                        pressed) const
{
  pressed = false;
  const double voxel = m_Settings.Voxel;
  const auto   it =
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
  if (guide != nullptr)
  {
    const double priorSpacing = TraceSpacing(*guide, m);
    if (priorSpacing > 0.0)
    {
      spacing = std::min(spacing, priorSpacing);
    }
  }
  const double     window = AcceptWindow * std::max(spacing, voxel);
  const double     apart = Apart();
  const Crossing & crossing = list[best];
  sheet = crossing.SheetNear(target);
  if (pressable && crossing.Band() && bestDistance >= window && std::abs(sheet - target) < window &&
      crossing.Outer - crossing.Inner < PressedSeparation * m_Pitch)
  {
    // Where this turn is pressed onto the turn before or the next one, the band's middle
    // lies between the two turns, further from the prediction than the window although
    // the band's sheet on this turn's side lies on it; the step would be refused and the
    // prediction held, unconfirmed, off the sheet along the whole touch. The band's sheet
    // is taken when its other sheet is that neighbouring turn (not where a tight curl or
    // noise widens one sheet into a band: its other sheet lies on no known turn) and the
    // sheet taken lies nearer this turn's prediction than that turn (not the neighbouring
    // turn's own band, where a turn converges on the next one). Two turns pressed together
    // lie about a sheet's thickness apart; two turns blurred into one crossing, a whole
    // turn spacing: only bands narrower than PressedSeparation of it.
    const double other = sheet == crossing.Inner ? crossing.Outer : crossing.Inner;
    const auto   on = [&](double r) {
      return std::isfinite(r) && std::abs(other - r) < window && std::abs(sheet - target) < std::abs(sheet - r);
    };
    if (on(below) || on(bump) || on(ahead))
    {
      pressed = true;
      bestDistance = std::abs(sheet - target);
    }
  }
  if (m_WidthMeasured && !crossing.Band() &&
      (crossing.Width > SharedWidth * m_Width || crossing.Mass > SharedMass * m_Mass))
  {
    // Heavier than one sheet, and the turn before or the next one lies in it too (not on
    // this turn): two turns pressed together; this turn's sheet is the half on its side.
    const auto holds = [&](double r) {
      return std::isfinite(r) && std::abs(r - crossing.Radius) < 0.5 * crossing.Width && std::abs(r - target) > apart;
    };
    const bool before = holds(below), after = holds(ahead);
    if (before != after)
    {
      sheet = (before ? below : ahead) < target ? crossing.OuterHalf : crossing.InnerHalf;
    }
  }
  const auto circlingAt = [&](double r) {
    return (std::isfinite(below) && std::abs(r - below) < apart) || (std::isfinite(bump) && std::abs(r - bump) < apart);
  };
  bool circling = circlingAt(sheet);
  if (circling && crossing.Band() && !std::isfinite(bump) &&
      std::max(crossing.Width / m_Width, crossing.Mass / m_Mass) < 2.5)
  {
    // A band of two sheets (not three), one of them the turn before: where two turns touch,
    // the prediction (from a neighbouring slice's trace, or the turns before) can fall on the
    // turn before, and the step would be refused and the prediction carried through, onto
    // the turn before, in this slice and in every slice it guides. The band's other sheet,
    // beyond the turn before on this turn's side of it, is this turn's, whichever of the two
    // the prediction lies nearer. Pressed together, the two sheets' middles lie closer than
    // Apart(), the test for a step onto the turn before, which cannot tell them apart: the
    // band's own sheets are compared instead (only then: a wider band's sheets are told
    // apart by that test).
    const double other = side > 0.0 ? crossing.Outer : crossing.Inner;
    const double onBelow = side > 0.0 ? crossing.Inner : crossing.Outer;
    const double separation = crossing.Outer - crossing.Inner;
    if (side != 0.0 && (other - below) * side > 0.0 && std::abs(onBelow - below) < 0.25 * separation &&
        separation < apart)
    {
      sheet = other;
      circling = false;
    }
  }
  const bool near = bestDistance < window && (guide != nullptr || std::abs(sheet - lastCarried) < window);
  return near && !circling ? best : list.size();
}

void
Tracer::Learn(FollowModel &             model,
              const std::vector<Step> & confirmed,
              double                    r,
              const double              far[2],
              double                    below,
              const Trace *             guide) const
{
  const double maximumSlope = 0.05 * m_Pitch;
  // The distances to the turns before, over the last eighth of a turn (at least 12 steps).
  const size_t window = std::max<size_t>(12, static_cast<size_t>(m_Frame.Rays / 8));
  const size_t count = std::min<size_t>(12, confirmed.size());
  for (int j = 0; j < 2; ++j)
  {
    if (std::isfinite(far[j]) && far[j] > 0.0)
    {
      model.Far[j].Add(r - far[j], far[j], window);
    }
  }
  if (std::isfinite(below) && below > 0.0)
  {
    model.Turn.Add(r - below, below, window);
  }
  // The distances just learnt, at this step's turns before: the next step scales them to its
  // own, and keeps these where it has none (a turn before not traced there).
  model.ScaleTo(below, far, LeastTurnDistance());
  if (guide != nullptr)
  {
    // Mean offset from the prior over the last confirmed steps it covers.
    double sum = 0.0;
    size_t used = 0;
    for (size_t q = confirmed.size() - count; q < confirmed.size(); ++q)
    {
      if (guide->Covers(confirmed[q].M))
      {
        sum += confirmed[q].Rho - guide->At(confirmed[q].M);
        ++used;
      }
    }
    model.Offset = used > 0 ? sum / static_cast<double>(used) : 0.0;
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
      model.Slope = std::clamp(fitted, -maximumSlope, maximumSlope);
    }
  }
}

std::vector<Tracer::Step>
Tracer::Follow(const SliceCrossings &    crossings,
               const ValueSlice &        slice,
               const double              centre[2],
               const Trace *             prior,
               long                      start,
               double                    rho,
               int                       dir,
               const std::vector<Step> & opposite) const
{
  const double      voxel = m_Settings.Voxel;
  const double      material = m_Settings.AirLevel + MaterialLevel * m_Contrast;
  std::vector<Step> steps;
  std::vector<Step> confirmed{ { start, rho, true } };
  FollowModel       model;
  double &          slope = model.Slope;
  double &          offset = model.Offset;
  double            missedArc = 0.0, heldArc = 0.0;
  // Steps up to the last one on a crossing of the turn's own (not a band's sheet), and
  // whether the follower, going inwards, stopped where no material lies ahead.
  size_t ownEnd = 0;
  bool   ranOut = false;
  // A held stretch (material but no separate crossing: touching turns) may be long where
  // the neighbouring slice vouches for it, short where it does not.
  const double heldWithPrior = std::max(30.0 * voxel, 2.0 * m_Pitch);
  // Length of the run of steps taken along a band as a turn pressed onto its neighbour: a
  // touch is short, a tight stretch of an uneven roll is not (no longer than a held stretch
  // the neighbouring slice vouches for).
  double       pressedArc = 0.0;
  const double heldAlone = std::max(4.0 * voxel, 1.0 * m_Pitch);
  const long   maximumSteps = m_Frame.Rays * (static_cast<long>(std::ceil(m_Frame.RMax / m_Pitch)) + 2);
  // Radius at every step taken so far (NaN where none was found): the turn traced one
  // revolution before is the best predictor of the shape of this one (an ellipse, an
  // irregular section), offset by the distance between the two.
  std::vector<double>       radiusAt{ rho };
  const std::vector<double> oppositeAt = TurnBeforeStart(opposite, start, dir, m_Frame.Rays);
  auto                      turnBefore = [&](long step) {
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
  double & turnOffset = model.TurnOffset;
  // The turns two and three revolutions before, each with its own distance to this one:
  // where the turn before bulges onto this one (a touch), it alone would carry the bulge
  // outwards onto the next turn; the median of the three predictions does not.
  auto turnsBefore = [&](long step, long turns) {
    const long back = step - (turns - 1) * m_Frame.Rays;
    return back >= 0 ? turnBefore(back) : std::numeric_limits<double>::quiet_NaN();
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
    model.ScaleTo(below, far, LeastTurnDistance());
    const bool   turnKnown = model.Turn.Known();
    const double predicted = guided                              ? prior->At(m) + offset
                             : turnKnown && std::isfinite(below) ? model.FromTurns(below, far)
                                                                 : last.Rho + slope * static_cast<double>(m - last.M);
    if (predicted <= 0.0)
    {
      break;
    }
    double xy[2];
    PointAbout(centre, static_cast<double>(m) * m_Frame.Step, predicted, xy);
    const double x = xy[0], y = xy[1];
    const bool   outside = slice.NearEdge(x, y, EdgeReach * voxel);
    // Near the edge of the data a band's sheets may be a turn and its cut end: no touch.
    const bool pressable = !slice.NearEdge(x, y, PressedEdgeReach * voxel);
    // No material lies beyond the frame's reach within the scan's data; outside it (a roll
    // cut by the field of view, or within EdgeReach of where the data ends) the turn is
    // carried on, as below.
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
    // The next turn where the neighbouring slice predicts it.
    const double ahead = guided && prior->Covers(m + dir * m_Frame.Rays) ? prior->At(m + dir * m_Frame.Rays) + offset
                                                                         : std::numeric_limits<double>::quiet_NaN();
    // The side of the turn before on which this turn lies (the sign of the distance learnt
    // from it, or of the next turn's from it; 0 while neither is known).
    const double side = turnKnown ? turnOffset : std::isfinite(ahead) && std::isfinite(below) ? ahead - below : 0.0;
    // The crossing accepted near a prediction (NearestCrossing), and the radius of its sheet.
    double sheet = 0.0;
    bool   pressed = false;
    auto   accept = [&](double target) {
      return NearestCrossing(
        list, target, guided ? prior : nullptr, m, lastCarried, below, bump, ahead, side, pressable, sheet, pressed);
    };
    // A step onto a turn pushed onto its neighbour: it follows the touch but leaves the
    // turn's shape and its distances alone (a touch is a bump, not the turn's course).
    const auto followBump = [&](double r) {
      steps.push_back({ m, r, true });
      radiusAt.back() = predicted;
      bumpAt.back() = r;
      missedArc = heldArc = 0.0;
    };
    size_t best = accept(predicted);
    if (best == list.size() && !guided && turnKnown && std::isfinite(below))
    {
      // The distance to the turn before changes (uneven winding): continue the radius.
      best = accept(last.Rho + slope * static_cast<double>(m - last.M));
    }
    if (pressed && pressedArc > heldWithPrior)
    {
      best = list.size();
      pressed = false;
    }
    if (best == list.size() && !outside && turnKnown && std::isfinite(below))
    {
      // Where a turn is pushed onto its neighbour (a touch) it leaves the prediction, and
      // no crossing is near it; the turn is then the crossing between the turn before and
      // the next turn, where the next turn is the crossing after it and lies where the
      // next turn is expected.
      const double nextTurn = guided && prior->Covers(m + dir * m_Frame.Rays)
                                ? prior->At(m + dir * m_Frame.Rays) + offset
                                : predicted + turnOffset;
      const double from = std::isfinite(bump) && (bump - below) * turnOffset > 0.0 ? bump : below;
      const double between = Between(list, from, nextTurn, std::abs(turnOffset));
      if (std::isfinite(between))
      {
        followBump(between);
        continue;
      }
    }
    if (best < list.size() && pressed)
    {
      followBump(sheet);
      pressedArc += sheet * m_Frame.Step;
      continue;
    }
    if (best < list.size())
    {
      const double r = sheet;
      steps.push_back({ m, r, true });
      confirmed.push_back({ m, r, true });
      ownEnd = steps.size();
      radiusAt.back() = r;
      missedArc = heldArc = pressedArc = 0.0;
      Learn(model, confirmed, r, far, below, guided ? prior : nullptr);
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
      // Out of the field of view the neighbouring slice's trace carries the turn, but no
      // closer to the turn before than CarriedDistance of the distance learnt between them:
      // where the edge of the data cut the turn, the neighbours' traces followed that edge
      // inwards, slice after slice. Turns do not close up where nothing of them is seen;
      // they are not moved further either (the learnt distance need not hold far from
      // where it was learnt).
      double carried = predicted;
      if (outside && guided && turnKnown && std::isfinite(below) && (predicted - below) / turnOffset < CarriedDistance)
      {
        carried = below + CarriedDistance * turnOffset;
      }
      steps.push_back({ m, carried, false });
      radiusAt.back() = carried;
    }
    else
    {
      missedArc += predicted * m_Frame.Step;
      if (missedArc > 2.0 * voxel)
      {
        ranOut = dir < 0;
        break;
      }
    }
  }
  // Where the sheet ran out towards the inner end (no material ahead: the roll's core), the
  // trace ends at its last step on a crossing of its own: steps taken along a band past it
  // (a pressed run that no crossing of the turn's own follows) carried the sheet's end on
  // the next turn out. Elsewhere (a hold too long, a touch, the outer end) only the steps
  // held through are dropped.
  if (ranOut)
  {
    steps.resize(ownEnd);
  }
  while (!steps.empty() && !steps.back().Confirmed)
  {
    steps.pop_back();
  }
  return steps;
}

Tracer::Trace
Tracer::TraceFrom(const SliceCrossings & crossings, size_t slice, const Trace * prior, long start, double rho) const
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

Tracer::Trace
Tracer::TraceAlone(const SliceCrossings & crossings, size_t slice) const
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

Tracer::Trace
Tracer::TraceNear(const SliceCrossings & crossings, size_t slice, const Trace & prior, long from, long to) const
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
        // Not from a band of touching turns: its middle lies between them, and the trace
        // would keep it, off the sheet, as its first step (and the next slice's trace too).
        if (!c.Band() && std::abs(c.Radius - rho) < 0.3 * spacing)
        {
          return TraceFrom(crossings, slice, &prior, m, c.Radius);
        }
      }
    }
  }
  return Trace{};
}

double
Tracer::Explained(const SliceCrossings & crossings, const Trace & trace) const
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

bool
Tracer::NearDataEdge(size_t slice, long m, double rho, double reach) const
{
  const ValueSlice sampler(m_Volume, m_Values, slice);
  double           xy[2];
  PointAt(slice, m, rho, xy);
  return sampler.NearEdge(xy[0], xy[1], reach);
}

void
Tracer::PointAt(size_t slice, long m, double rho, double xy[2]) const
{
  double c[2];
  Centre(slice, c);
  PointAbout(c, static_cast<double>(m) * m_Frame.Step, rho, xy);
}

Polyline
Tracer::ToPolyline(const Trace & trace, size_t slice) const
{
  double c[2];
  Centre(slice, c);
  const auto n = static_cast<long>(trace.Rho.size());
  const long halfWidth = 4;
  Polyline   line(2 * trace.Rho.size());
  // A short run of steps that leaves the trace's course by half a turn spacing or more and
  // comes straight back (onto the neighbouring turn or into the gap at a touch, and back)
  // is no shape of the sheet's: it is put back on the course (the running median over
  // Rays / 64 steps each side). Its length, twice the excursion, would shift every column
  // after it along the sheet (slices 20 and 30 voxels longer than their neighbours on a
  // stress scan), and take the rows fitted across such slices onto the neighbouring turn.
  std::vector<double> kept(trace.Rho);
  if (m_Pitch > 0.0 && n > 2)
  {
    const std::vector<double> course = RunningMedian(trace.Rho, std::max(8L, m_Frame.Rays / 64));
    for (size_t i = 0; i < kept.size(); ++i)
    {
      if (std::abs(kept[i] - course[i]) >= 0.5 * m_Pitch)
      {
        kept[i] = course[i];
      }
    }
  }
  for (long i = 0; i < n; ++i)
  {
    const long h = std::min({ halfWidth, i, n - 1 - i });
    double     sum = 0.0;
    for (long j = i - h; j <= i + h; ++j)
    {
      sum += kept[static_cast<size_t>(j)];
    }
    const double rho = sum / static_cast<double>(2 * h + 1);
    PointAbout(c, static_cast<double>(trace.First + i) * m_Frame.Step, rho, &line[2 * i]);
  }
  return line;
}
} // namespace RollTracing
} // end namespace itk

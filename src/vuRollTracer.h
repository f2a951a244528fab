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
#ifndef vuRollTracer_h
#define vuRollTracer_h

#include "itkSheetMidSurfaceExtractor.h"

#include <functional>
#include <vector>

namespace itk {
namespace RollTracing {
/** A planar curve as x, y pairs (mm, the view's frame). */
using Polyline = std::vector<double>;

/** What the roll tracer needs besides the volume. */
struct Settings
{
  /** In-plane voxel size and slice spacing (mm). */
  double Voxel{ 1.0 };
  double SliceSpacing{ 1.0 };
  /** Intensity of air and of the sheet's material (medians outside and inside the mask). */
  double AirLevel{ 0.0 };
  double SheetLevel{ 1.0 };
  /** Line through the slices' mask centroids: centre (x, y) at slice 0 and drift per mm of z. */
  double AxisCentre[2]{ 0.0, 0.0 };
  double AxisSlope[2]{ 0.0, 0.0 };
  /** The candidate seed slice to trace every slice from (an index into SeedFractions);
   * -1: the one whose trace explains clearly more of its slice's crossings. */
  long SeedCandidate{ -1 };
};

/** Where the candidate seed slices lie, as fractions of the sheet's width along the axis;
 * the first is preferred. */
constexpr double SeedFractions[] = { 0.5, 0.3, 0.7 };
/** The least material (voxels, or area) of a slice of the sheet itself, given the material of
 * every slice that holds some: half the fullest slices' (their 90th percentile). Beyond the
 * sheet's ends along the axis a slice may hold debris only (what is left of a streak or a ring
 * artefact, or specks, once a tilted scan is resampled along the roll's axis), and such
 * slices may be most of those with material. */
double
SheetSliceLeast(const std::vector<double> & amounts);

/** The trace of one slice. */
struct SliceTrace
{
  /** Mid-curve from the sheet's inner end to its outer end; empty when not traced. */
  Polyline Line;
  /** Fraction of the traced angular steps on which a crossing of the sheet was found (the
   * rest were carried over from the neighbouring slice through touching or faint turns). */
  double Confirmed{ 0.0 };
  /** Number of turns of the traced curve about the roll axis. */
  double Turns{ 0.0 };
};

/** What TraceRoll found. */
struct Result
{
  std::vector<SliceTrace> Slices;
  /** True when the middle of the sheet traces as a spiral of at least one turn that passes
   * through most crossings of material with the rays (a rolled sheet), and some slice
   * keeps a trace of it. */
  bool Rolled{ false };
  /** Fraction of the seed slice's crossings that lie on its traced spiral. */
  double Explained{ 0.0 };
  /** Median radial distance between successive turns, and the typical crossing width (mm). */
  double Pitch{ 0.0 };
  double RayThickness{ 0.0 };
  /** Spiral centre relative to the centroid line (mm), applied to every slice. */
  double CentreOffset[2]{ 0.0, 0.0 };
  /** Slices whose trace ended far from the line of the other slices' ends (the sheet's
   * edge along the axis, a trace lost before the end): dropped, to be interpolated. */
  size_t Incomplete{ 0 };
  /** Slices whose trace stopped short of that line by less than a turn: continued to it
   * along the nearest whole slice's curve (unconfirmed steps), not dropped. */
  size_t Continued{ 0 };
  /** Where neighbouring slices' traces disagree by more than half a turn: slice, turn. */
  std::vector<std::pair<size_t, double>> Disagreements;
};

/** Extends both ends of a curve along their tangents while `inside` holds (at most
 * `maximum` mm), so that a traced curve reaches the sheet's cut edges. */
void
ExtendEnds(Polyline & line, const std::function<bool(double, double)> & inside, double voxel, double maximum);

/** Traces a rolled sheet in every slice of `values` (the volume's intensities, denoised,
 * x fastest; the mask of `volume` bounds the search). A seed slice in the middle of the
 * sheet is traced on the mean of its neighbours' profiles; every other slice is traced with
 * the trace of the slice before it (towards the seed) as prior, so a faint or touching
 * stretch is carried over from the neighbours instead of being lost or jumping a turn.
 * `progress` receives 0..1 and may throw to abort. */
Result
TraceRoll(const SheetVolumeView &             volume,
          const float *                       values,
          const Settings &                    settings,
          const std::function<void(double)> & progress);
} // namespace RollTracing
} // end namespace itk

#endif

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
#ifndef itkSheetMidSurfaceExtractor_h
#define itkSheetMidSurfaceExtractor_h

#include "VirtualUnwrappingExport.h"
#include "itkSheetMesh.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace itk {
/** \class SheetMidSurfaceExtractorEnums
 * \brief Enumerations of SheetMidSurfaceExtractor, nested in a class the way ITK wraps them.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetMidSurfaceExtractorEnums
{
public:
  /** How the mid-surface of a sheet is traced in each slice. */
  enum class Method : uint8_t
  {
    /** Roll first; the general tracer when the roll tracer does not explain the mask. */
    Auto,
    /** Spiral tracing in polar coordinates about the roll axis (rolled sheets). */
    Roll,
    /** Skeleton of each slice's mask (folded, wavy or other open sheets). */
    General
  };
};
/** Shorter name used throughout the module. */
using SheetSurfaceMethodEnum = SheetMidSurfaceExtractorEnums::Method;
VirtualUnwrapping_EXPORT const char *
ToString(SheetSurfaceMethodEnum method);
/** "auto", "roll" or "general"; throws itk::ExceptionObject on another name. */
VirtualUnwrapping_EXPORT SheetSurfaceMethodEnum
SheetSurfaceMethodFromString(const std::string & name);

/** A volume as plain arrays, x fastest: Mask (non-zero = sheet material, required) and
 * Intensity (optional, same size, any units in which the sheet is brighter than air). The
 * frame is the voxel grid scaled by Spacing: voxel (i, j, k) sits at (i sx, j sy, k sz) mm.
 * The slices (constant k) must cut across the roll axis. */
struct VirtualUnwrapping_EXPORT SheetVolumeView
{
  const uint8_t * Mask{ nullptr };
  const float *   Intensity{ nullptr };
  /** Voxels that hold data of the scan (non-zero), or nullptr for all of them. Beyond the
   * data (outside a scan cut by its field of view, once resampled along a tilted roll axis)
   * the sheet is unknown, not absent: the roll tracer carries a turn through it. */
  const uint8_t * Data{ nullptr };
  size_t          Size[3]{ 0, 0, 0 };
  double          Spacing[3]{ 1.0, 1.0, 1.0 };
  /** True when the roll axis is known to run along the slice normal (for example estimated
   * from the whole volume and resampled along): the axis is then a line of constant (x, y)
   * through the slices' centroids, not the centroids' least-squares line, which a sheet
   * whose ends or radius change along the axis tilts. */
  bool AxisAlongSlices{ false };
};

/** Parameters of SheetMidSurfaceExtractor (mm). */
struct VirtualUnwrapping_EXPORT SheetMidSurfaceParameters
{
  SheetSurfaceMethodEnum Method{ SheetSurfaceMethodEnum::Auto };
  /** Grid spacing along the sheet (s); 0: automatic (see SheetMidSurfaceExtractor). >= 0. */
  double SpacingAlongSheet{ 0.0 };
  /** Grid spacing across the sheet, along the roll axis (w); 0: automatic. >= 0. */
  double SpacingAlongAxis{ 0.0 };
  /** Automatic spacing: largest chord error h^2 / (8 R), as a fraction of the sheet
   * thickness, at the smallest radius of curvature R. In (0, 1]. */
  double ChordErrorFraction{ 0.1 };
};

/** What SheetMidSurfaceExtractor::Extract found. */
struct VirtualUnwrapping_EXPORT SheetMidSurfaceReport
{
  SheetSurfaceMethodEnum Method{ SheetSurfaceMethodEnum::Roll };
  double                 SpacingAlongSheet{ 0.0 };
  double                 SpacingAlongAxis{ 0.0 };
  /** Estimated from the mask: area of a slice's material over its traced length. */
  double SheetThickness{ 0.0 };
  /** The share of the mask's material the traces follow: in a dozen well-traced slices,
   * the mask's extent across the trace (median over its points) times the traced length
   * over the slice's material area; the median over those slices (at most 1). Below 0.9,
   * the mesh leaves out turns, pages or pieces the mask holds, and a warning says so. */
  double TracedShare{ 1.0 };
  /** Smallest radius of curvature of the traced curves (5th percentile). */
  double MinimumCurvatureRadius{ 0.0 };
  /** Median traced length of the sheet in a slice (mm). */
  double SheetLength{ 0.0 };
  /** Roll method: the roll axis, centre (x, y) at the first slice and its drift per mm of z. */
  double AxisCentre[2]{ 0.0, 0.0 };
  double AxisSlope[2]{ 0.0, 0.0 };
  size_t SlicesWithMaterial{ 0 };
  /** Slices inside the meshed range whose trace failed, interpolated from neighbours. */
  size_t InterpolatedSlices{ 0 };
  /** Roll method: per slice of the view, the fraction of its traced spiral confirmed by a
   * crossing of the sheet (the rest carried over from neighbouring slices through touching
   * or faint stretches); -1 for slices without material, 0 for slices not traced. */
  std::vector<double> SliceConfidence;
  /** Roll method: median radial distance between successive turns (mm) and the number of
   * turns traced in the middle slice. */
  double TurnSpacing{ 0.0 };
  double Turns{ 0.0 };
  /** Roll method: where the traces of neighbouring slices disagree by more than half a turn
   * spacing (a turn lost or jumped between them): the slice and the turn, counted from the
   * inner end. */
  struct LayerJump
  {
    size_t Slice;
    double Turn;
  };
  std::vector<LayerJump> LayerJumps;
  /** Roll method: edges of the finished grid across which the mesh steps sideways (in the
   * slice plane) by more than 0.7 of the turn spacing beyond what the edges
   * around it do: a trace that crossed onto the next turn, or rows averaged from slices
   * traced on different turns. Checked on the mesh itself, so that a layer jump the
   * slice-to-slice check missed is still named. Row and column of the grid point at the
   * step (for a step along the axis, between Row and Row + 1), the slice of the view
   * nearest that row, and the size of the step (mm). */
  struct GridStep
  {
    size_t Row;
    size_t Column;
    bool   AlongAxis;
    double Step;
    size_t Slice{ 0 };
  };
  std::vector<GridStep> GridSteps;
  /** Roll method: grid points put back on their row's curve before the checks (runs of one
   * or two points off it, SheetMidSurfaceExtractor::SmoothRowSpikes; bumps towards a
   * touching turn, SheetMidSurfaceExtractor::SmoothTouchBumps). */
  size_t RowSpikesSmoothed{ 0 };
  /** Roll method: grid points put back on their column's curve along the axis before the
   * checks (SheetMidSurfaceExtractor::SmoothColumnSpikes). */
  size_t ColumnSpikesSmoothed{ 0 };
  /** Roll method, with intensities: runs of grid points along a row that lie in air (the
   * intensity the tracer reads below a quarter of the sheet's contrast above the air's
   * level), at least three points long: a mesh traced between two turns, or stepping from
   * one onto the next across a gap that the sideways-step check does not see (a step of
   * less than 0.7 of the turn spacing into a wide gap). Row, first and last column of the
   * run, the slice of the view nearest that row and the lowest level in the run (fraction
   * of the contrast). Points beyond the scan's data, at the volume's border, in the first
   * and last row and in the six columns at either end of a row are not checked. */
  struct OffSheetRun
  {
    size_t Row;
    size_t FirstColumn;
    size_t LastColumn;
    double Lowest;
    size_t Slice{ 0 };
  };
  std::vector<OffSheetRun> OffSheetRuns;
  std::vector<std::string> Warnings;
};

/** Intensity levels of a scan of a sheet: air and sheet material (medians) and the noise
 * of air (the distance from its median to its 15.9th percentile: one standard deviation for
 * Gaussian noise, measured on the lower half, which partial-volume voxels at the sheet's
 * faces do not reach). Values equal to the smallest air value (padding outside a scanner's
 * field of view) are left out. */
struct VirtualUnwrapping_EXPORT SheetIntensityLevels
{
  double Air{ 0.0 };
  double Sheet{ 0.0 };
  double Noise{ 0.0 };
  /** (Sheet - Air) / Noise; infinite for a noise-free scan. */
  double
  SignalToNoise() const;
  /** Gaussian smoothing (in voxels) that brings the scan's noise well below the sheet's
   * contrast without merging turns two voxels apart: 0 at a signal-to-noise ratio of 12
   * and above, else 3 / SNR clamped to [0.5, 1.0]. */
  double
  DenoisingSigma() const;
};
/** Estimates the levels from samples of air and of material (for example the voxels
 * outside and inside a mask, or below and above a threshold). */
VirtualUnwrapping_EXPORT SheetIntensityLevels
EstimateSheetIntensityLevels(std::vector<float> air, std::vector<float> material);

/** Two-class clustering of a sample of a scan's values, started from `levels`: every value
 * is classed by the midpoint of the air and sheet levels and each level becomes its class's
 * median, until the midpoint settles (Ridler and Calvard's iterative selection, with
 * medians). On a smoothed noisy scan it finds the levels that a threshold near the air's
 * level (Otsu's, when the sheet is a small share of the voxels) hides: the material side of
 * such a threshold is mostly noise. The selection settles on the fixed point nearest its
 * start, which from levels inside the air's noise can split that noise in two; such a split
 * (levels less than three of the lower class's noise widths apart, their midpoint within
 * two noise widths of the sample's median) is replaced by the sample's median as the air's
 * level and the median of what lies four noise widths above it as the sheet's, when that
 * is at least 0.1 % of the sample. Padding (the smallest value, when 1 % of the sample or
 * more holds it) is left out throughout. The noise is kept from `levels`. */
VirtualUnwrapping_EXPORT SheetIntensityLevels
RefineSheetIntensityLevels(const std::vector<float> & values, SheetIntensityLevels levels);

/** \class SheetMidSurfaceExtractor
 * \brief Builds an open, grid-structured triangle mesh on the mid-surface of one rolled or
 * folded sheet from its segmentation mask (and, optionally, the CT intensities), on plain
 * arrays; itk::SheetMidSurfaceMeshFilter is the ITK wrapper.
 *
 * A closed isosurface of a thin sheet has two faces and cannot be unrolled, so the sheet's
 * centre curve is traced in every slice (slices cut across the roll axis) and neighbouring
 * slices are stitched into a grid: rows are positions along the roll axis w (increasing
 * with the slice index), columns arc length s along the sheet, the same column index
 * meaning the same fraction of the slice's traced length (so the grid is nearly
 * isometric), point (row r, column c) at index r * columns + c.
 *
 * Roll method: the roll axis is the least-squares line through the slices' mask
 * centroids. In each slice, rays from the axis are sampled (bilinear, a quarter voxel
 * apart; angular step half a voxel at the outermost material); every run of material on a
 * ray is a crossing of the sheet, placed at the intensity-weighted middle of the run (sub
 * voxel; weights are the intensity above the midpoint between air and material, over the
 * run widened by a voxel; without intensities the interpolated mask) and runs longer than
 * 1.6 typical thicknesses (touching turns) are split evenly. The spiral is followed from
 * the crossing of smallest radius, both ways, step by step in angle: the next crossing is
 * the one closest to the radius predicted by a line fitted to the last accepted steps,
 * accepted only within 0.4 of the local turn spacing of both that prediction and the last
 * accepted radius, so the trace never jumps to the neighbouring turn; it ends after two
 * voxels of arc without a crossing (or after rmax / pitch + 2 turns). The radius is
 * smoothed along the trace, the ends are extended along their tangents to the end of the
 * material, and the innermost end is s = 0.
 *
 * General method: in each slice the largest 2D component of the mask is thinned
 * (itk::BinaryThinningImageFilter), the longest path of the skeleton is traced from end to
 * end, smoothed, moved to the intensity-weighted middle of the sheet along its normal and
 * extended to the ends of the material; the middle slice starts at its end nearer the
 * centroid line (the inner end of a roll) and the others are oriented like it.
 *
 * Auto: the roll tracer is kept when, in at least 80 % of the slices with material, the
 * traced length times the typical run length along the rays is 80-125 % of the slice's
 * material area; otherwise the general tracer runs. A forced Roll that fails this test
 * warns.
 *
 * Slices whose traced length differs from the median by more than
 * min(5 %, max(a quarter of the column spacing, 2 voxels)) + 1 voxel are interpolated
 * from their neighbours (a warning says how many); the meshed rows run from the first to
 * the last slice that agrees. Each good slice is then aligned along the sheet to the mean
 * of its good neighbours within five slices (tangential offsets of its columns fitted by
 * a + b c and taken off its arc lengths), since the jitter of the traced ends would shear
 * the grid and make it slightly non-developable. Rows average the slices within one row
 * spacing (triangular weights), which suppresses the noise of single slices. Automatic spacing along s: h = sqrt(8 R f
 * t), the largest chord error f t at the smallest radius of curvature R (ChordErrorFraction f, thickness t, both
 * measured), but not finer than the in-plane voxel size; along w: h, but not finer than the slice spacing.
 *
 * Normals: triangles are oriented so that their normals point to the roll axis (the
 * inside face) for the roll method; for the general method they are dP/dw x dP/ds. For
 * the phantoms' counter-clockwise spiral both agree with itk::SheetPhantomGeometry's
 * SurfaceNormal. Points are in the view's frame (mm, voxel 0 at the origin).
 *
 * Extract() throws itk::ExceptionObject with a one-line message on an empty mask, a volume
 * smaller than 3 x 3 x 2 voxels, a mask no slice of which can be traced, or bad
 * parameters. The progress callback receives 0..1 and aborts (exception) when it returns
 * false.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetMidSurfaceExtractor
{
public:
  using ProgressCallback = std::function<bool(double)>;

  void
  SetParameters(const SheetMidSurfaceParameters & parameters)
  {
    m_Parameters = parameters;
  }
  const SheetMidSurfaceParameters &
  GetParameters() const
  {
    return m_Parameters;
  }
  void
  SetProgressCallback(ProgressCallback callback)
  {
    m_Progress = std::move(callback);
  }

  SheetMesh
  Extract(const SheetVolumeView & volume);

  const SheetMidSurfaceReport &
  GetReport() const
  {
    return m_Report;
  }

  /** Edges of a grid mesh of a rolled sheet (rows in planes of constant z, the roll axis
   * along z, as Extract makes them) across which the mesh steps sideways in the slice plane
   * by more than `limit` (mm) beyond what the edges around it do: a trace that crossed onto
   * the next turn makes such a step along the sheet, rows averaged from slices traced on
   * different turns make one along the axis. A smooth sheet bends gradually, so each edge
   * is measured against the median of its neighbours, component by component (along the
   * sheet: the second difference of the row's curve over seven columns; along the axis:
   * the difference between neighbouring rows over five rows; the six columns at either end,
   * which follow the trace's bending, jittering end, are left out along the sheet).
   * Consecutive flagged edges of one row (along the sheet) or one column (along the axis)
   * are reported once, at the largest step; Slice is left 0. Extract runs it with 0.7 of
   * the turn spacing. */
  static std::vector<SheetMidSurfaceReport::GridStep>
  FindGridSteps(const SheetMesh & mesh, double limit);

  /** Puts back on its row's curve each run of one or two grid points that leaves it by more
   * than `limit` (mm, in the slice plane) while the points either side of the run lie on one
   * smooth curve without it: a column taken onto the neighbouring turn in one row's slices
   * (the edge of a touch along the axis, an artefact), which returns to its turn at the next
   * column. A run's points are set to the cubic through the two points before it and the two
   * after it; each of the two nearest the run must lie within half the limit of the cubic
   * through its own neighbours (the run left out), so a row that crosses onto another turn
   * and stays there, or bends sharply, is left as it is, for FindGridSteps to name. The three
   * columns at either end are left alone. Returns the number of points moved. Extract runs
   * it on a roll's grid with 0.7 of the turn spacing, before its checks. */
  static size_t
  SmoothRowSpikes(SheetMesh & mesh, double limit);

  /** Puts back on its row's curve each bump where a row is pulled onto a touching turn at
   * one column: the point at column c leaves the cubic through columns c - 3, c - 2, c + 2
   * and c + 3 by more than `limit` (mm, in the slice plane), its neighbours c - 1 and c + 1
   * (pulled part way) by at most half as much as it does (a smooth bend, such as the
   * innermost curl, leaves it by 1.5 times as much at c as at its sides, not twice);
   * columns c - 2 and c + 2 each lie within half the limit of the cubic through their own
   * neighbours (the bump left out); and the point lies nearer the row's nearest other turn
   * (its polyline beyond four columns of c) than three quarters of the cubic's distance to
   * it: the bump leans towards that turn. The three columns are set to the cubic. Where
   * turns press together the next turn lies about a sheet's thickness away, too close for
   * SmoothRowSpikes' limit of a turn spacing; Extract runs it on a roll's grid after
   * SmoothRowSpikes, with the sheet's thickness. Returns the number of points moved; the
   * four columns at either end are left alone. */
  static size_t
  SmoothTouchBumps(SheetMesh & mesh, double limit);

  /** Puts back on its column's curve along the axis each grid point that leaves the cubic
   * through the points two and one rows before it and one and two rows after it by more than
   * `limit` (mm, in the slice plane), where the rows either side each lie within half the
   * limit of the cubic through their own neighbours (that point left out): one row whose
   * window of slices held a trace on the neighbouring turn over part of the sheet, while
   * the rows about it, and the sheet, run smoothly along the axis. The point is set to the
   * cubic; the two rows at either end are left alone. Extract runs it on a roll's grid with
   * 0.7 of the turn spacing, before SmoothRowSpikes (two neighbouring rows pushed alike by
   * a turn spacing leave the row beside them half a turn spacing off its cubic). Returns
   * the number of points moved. */
  static size_t
  SmoothColumnSpikes(SheetMesh & mesh, double limit);

  /** Runs of at least `minimumRun` grid points along a row (points in the view's frame,
   * mm) where the view's intensity, as a fraction of (sheetLevel - airLevel) above airLevel
   * (trilinear), is below `level`: see SheetMidSurfaceReport::OffSheetRun. Empty without
   * intensities, for a mesh that is not a grid, or when sheetLevel <= airLevel. Extract
   * runs it with a quarter of the contrast and runs of three. */
  static std::vector<SheetMidSurfaceReport::OffSheetRun>
  FindOffSheetRuns(const SheetMesh &       mesh,
                   const SheetVolumeView & volume,
                   double                  airLevel,
                   double                  sheetLevel,
                   double                  level = 0.25,
                   size_t                  minimumRun = 3);

private:
  SheetMidSurfaceParameters m_Parameters;
  SheetMidSurfaceReport     m_Report;
  ProgressCallback          m_Progress;
};
} // end namespace itk

#endif

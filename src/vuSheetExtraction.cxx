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
#include "vuSheetExtraction.h"
#include "vuMedian.h"
#include "vuPolyline.h"
#include "vuRollTracer.h"
#include "vuSheetGrid.h"

#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace itk {
namespace SheetTracing {
namespace {
constexpr double Pi = 3.14159265358979323846;
// Sideways step of the finished mesh, as a fraction of the turn spacing, reported as a
// possible layer jump: a jump onto the next turn steps by about a whole turn spacing, while
// the sharpest bend of a correct mesh (the innermost curl, a trace's end) stayed below 0.55
// on the stress family's scans.
constexpr double GridStepFraction = 0.7;

using RollTracing::Median;

// Slices at most by which the mesh reaches past the last well-traced slice along the axis.
constexpr long EdgeSlices = 8;

// The mask's extent across a trace is measured up to this many voxels either side; a
// share of the material followed below TracedShareWarning is warned of.
constexpr double TracedExtentVoxels = 20.0;
constexpr double TracedShareWarning = 0.9;
} // namespace

SheetMesh
Extraction::Run()
{
  CheckInput();
  FitAxis();
  MeasureLevels();
  TraceSlices();
  SelectSlices();
  MeasureSheet();
  ResampleColumns();
  ChooseRowSpacing();
  return BuildMesh();
}

void
Extraction::CheckInput() const
{
  if (volume.Mask == nullptr)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: no mask given");
  }
  if (volume.Size[0] < 3 || volume.Size[1] < 3 || volume.Size[2] < 2)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: volume of " << volume.Size[0] << "x" << volume.Size[1] << "x"
                             << volume.Size[2] << " voxels is too small (at least 3x3x2)");
  }
  for (double spacing : volume.Spacing)
  {
    if (!(spacing > 0.0) || !std::isfinite(spacing))
    {
      itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: voxel spacing must be positive");
    }
  }
  if (!(parameters.SpacingAlongSheet >= 0.0) || !(parameters.SpacingAlongAxis >= 0.0) ||
      !(parameters.ChordErrorFraction > 0.0 && parameters.ChordErrorFraction <= 1.0))
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: mesh spacings must be >= 0 and the chord error fraction "
                                "in (0, 1]");
  }
  if (std::abs(sx - sy) > 1e-6 * voxel)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: in-plane voxels must be square (spacing " << sx << " x "
                             << sy << "); resample the volume first");
  }
}

void
Extraction::report(double fraction) const
{
  if (progress && !progress(fraction))
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: aborted");
  }
}

void
Extraction::FitAxis()
{
  // Per-slice material and centroids; the roll axis is the line through the centroids.
  area.assign(nz, 0.0);
  std::vector<double> centroidX(nz, 0.0), centroidY(nz, 0.0);
  for (size_t k = 0; k < nz; ++k)
  {
    const uint8_t * mask = volume.Mask + k * nx * ny;
    double          count = 0.0, mx = 0.0, my = 0.0;
    for (size_t j = 0; j < ny; ++j)
    {
      for (size_t i = 0; i < nx; ++i)
      {
        if (mask[j * nx + i] != 0)
        {
          count += 1.0;
          mx += static_cast<double>(i) * sx;
          my += static_cast<double>(j) * sy;
        }
      }
    }
    area[k] = count * sx * sy;
    if (count > 0.0)
    {
      centroidX[k] = mx / count;
      centroidY[k] = my / count;
      ++m_Report.SlicesWithMaterial;
    }
  }
  if (m_Report.SlicesWithMaterial == 0)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: the mask is empty");
  }
  {
    double sw = 0, sz1 = 0, szz = 0, sxw = 0, syw = 0, szx = 0, szy = 0;
    for (size_t k = 0; k < nz; ++k)
    {
      const double weight = area[k], z = static_cast<double>(k) * sz;
      sw += weight;
      sz1 += weight * z;
      szz += weight * z * z;
      sxw += weight * centroidX[k];
      syw += weight * centroidY[k];
      szx += weight * z * centroidX[k];
      szy += weight * z * centroidY[k];
    }
    const double denominator = sw * szz - sz1 * sz1;
    if (!volume.AxisAlongSlices && denominator > 1e-12 * sw * sw)
    {
      m_Report.AxisSlope[0] = (sw * szx - sz1 * sxw) / denominator;
      m_Report.AxisSlope[1] = (sw * szy - sz1 * syw) / denominator;
    }
    m_Report.AxisCentre[0] = (sxw - m_Report.AxisSlope[0] * sz1) / sw;
    m_Report.AxisCentre[1] = (syw - m_Report.AxisSlope[1] * sz1) / sw;
  }
}

void
Extraction::MeasureLevels()
{
  context.Voxel = voxel;
  if (volume.Intensity != nullptr)
  {
    // Air and material levels: medians of a sample of the voxels outside and inside the mask.
    // Beyond the scan's data (a tilted roll resampled) the padding, the scan's lowest value,
    // is neither air nor sheet: left out, or it pulls the air's level down.
    std::vector<double> outside, inside;
    const size_t        total = nx * ny * nz;
    const size_t        stride = std::max<size_t>(1, total / 400000);
    for (size_t i = 0; i < total; i += stride)
    {
      if (volume.Data == nullptr || volume.Data[i] != 0)
      {
        (volume.Mask[i] != 0 ? inside : outside).push_back(volume.Intensity[i]);
      }
    }
    context.AirLevel = Median(outside);
    context.SheetLevel = Median(inside);
    context.Base = 0.5 * (context.AirLevel + context.SheetLevel);
  }
}

// Whether a roll's traced points lie on the sheet: at least RollOnSheetShare of those
// inside the slices within RollReach voxels of the slice's material (points beyond the
// slices are not judged: a roll cut by the field of view is traced across the cut). A page
// bent where it is pressed onto the next can pass for a spiral of a turn, whose trace,
// grown like a spiral's, runs off the page into the air (60 % of its points on it, a
// mesh tens of millimetres across from a page of a few); rolls keep 95 % or more (16
// stress scans, 7 cut by the field of view) and the phantoms 100 %.
bool
Extraction::RollOnItsSheet(const std::vector<RollTracing::SliceTrace> & slices) const
{
  constexpr long   RollReach = 2;
  constexpr double RollOnSheetShare = 0.8;
  size_t           inside = 0, near = 0;
  for (size_t k = 0; k < nz && k < slices.size(); ++k)
  {
    const Polyline & line = slices[k].Line;
    const uint8_t *  mask = volume.Mask + k * nx * ny;
    for (size_t p = 0; p + 1 < line.size(); p += 2)
    {
      const long i = std::lround(line[p] / sx), j = std::lround(line[p + 1] / sy);
      if (i < 0 || j < 0 || i >= static_cast<long>(nx) || j >= static_cast<long>(ny))
      {
        continue;
      }
      ++inside;
      bool found = false;
      for (long b = std::max(0L, j - RollReach); !found && b <= std::min<long>(ny - 1, j + RollReach); ++b)
      {
        for (long a = std::max(0L, i - RollReach); !found && a <= std::min<long>(nx - 1, i + RollReach); ++a)
        {
          found = mask[static_cast<size_t>(b) * nx + static_cast<size_t>(a)] != 0;
        }
      }
      near += found ? 1 : 0;
    }
  }
  return inside > 0 && static_cast<double>(near) >= RollOnSheetShare * static_cast<double>(inside);
}

void
Extraction::TraceSlices()
{
  traces.assign(nz, {});
  auto traceGeneral = [&](double progressStart, double progressEnd) {
    // ITK's 2D filters inside run single-threaded; nesting them in the pool could stall it.
    for (size_t k = 0; k < nz; ++k)
    {
      if (area[k] > 0.0)
      {
        traces[k] = TraceGeneralSlice(SliceSampler(volume, k), context, sy);
      }
      report(progressStart + (progressEnd - progressStart) * static_cast<double>(k + 1) / static_cast<double>(nz));
    }
  };

  method = parameters.Method;
  if (method != SheetSurfaceMethodEnum::General)
  {
    // The roll tracer reads intensities; a mask alone serves as a 0/1 intensity.
    std::vector<float>    maskValues;
    RollTracing::Settings settings;
    settings.Voxel = voxel;
    settings.SliceSpacing = sz;
    settings.AirLevel = context.AirLevel;
    settings.SheetLevel = context.SheetLevel;
    if (volume.Intensity == nullptr)
    {
      maskValues.resize(nx * ny * nz);
      std::transform(
        volume.Mask, volume.Mask + nx * ny * nz, maskValues.begin(), [](uint8_t v) { return v != 0 ? 1.0f : 0.0f; });
      settings.AirLevel = 0.0;
      settings.SheetLevel = 1.0;
    }
    for (int d = 0; d < 2; ++d)
    {
      settings.AxisCentre[d] = m_Report.AxisCentre[d];
      settings.AxisSlope[d] = m_Report.AxisSlope[d];
    }
    settings.SeedCandidate = seedCandidate;
    const double rollShare = method == SheetSurfaceMethodEnum::Auto ? 0.4 : 0.8;
    const auto   roll = RollTracing::TraceRoll(volume,
                                             volume.Intensity != nullptr ? volume.Intensity : maskValues.data(),
                                             settings,
                                             [&](double fraction) { report(rollShare * fraction); });
    if (method == SheetSurfaceMethodEnum::Auto)
    {
      method =
        roll.Rolled && RollOnItsSheet(roll.Slices) ? SheetSurfaceMethodEnum::Roll : SheetSurfaceMethodEnum::General;
    }
    else if (!roll.Rolled)
    {
      m_Report.Warnings.emplace_back("the roll tracer does not find a spiral of at least one turn through most of "
                                     "the sheet's crossings: the sheet may not be rolled (try the general method)");
    }
    if (method == SheetSurfaceMethodEnum::Roll)
    {
      m_Report.SliceConfidence.assign(nz, -1.0);
      for (size_t k = 0; k < nz; ++k)
      {
        traces[k] = roll.Slices[k].Line;
        if (area[k] > 0.0)
        {
          m_Report.SliceConfidence[k] = traces[k].empty() ? 0.0 : roll.Slices[k].Confirmed;
        }
      }
      m_Report.TurnSpacing = roll.Pitch;
      rollCentreOffset[0] = roll.CentreOffset[0];
      rollCentreOffset[1] = roll.CentreOffset[1];
      m_Report.Turns = roll.Slices[nz / 2].Turns;
      for (const auto & [count, what] :
           { std::make_pair(
               roll.Incomplete,
               " slice(s) traced only in part (their trace ends far from the other slices' ends: the "
               "sheet's edge along the axis, or a trace lost before the end) were left out or interpolated"),
             std::make_pair(roll.Continued,
                            " slice(s) whose trace stopped short of the other slices' ends by less than a turn were "
                            "continued to them along the nearest whole slice's curve") })
      {
        if (count > 0)
        {
          m_Report.Warnings.push_back(std::to_string(count) + what);
        }
      }
      for (const auto & [slice, turn] : roll.Disagreements)
      {
        m_Report.LayerJumps.push_back({ slice, turn });
      }
      if (!m_Report.LayerJumps.empty())
      {
        std::ostringstream text;
        text << "the traces of " << m_Report.LayerJumps.size()
             << " slice(s) disagree with their neighbour's by more than half a turn (possible layer jumps), first at "
                "slice "
             << m_Report.LayerJumps.front().Slice << ", turn " << m_Report.LayerJumps.front().Turn;
        m_Report.Warnings.push_back(text.str());
      }
    }
  }
  if (method == SheetSurfaceMethodEnum::General)
  {
    traceGeneral(parameters.Method == SheetSurfaceMethodEnum::Auto ? 0.4 : 0.0, 0.8);
  }
  m_Report.Method = method;
}

void
Extraction::SelectSlices()
{
  lengths.assign(nz, 0.0);
  std::vector<double> tracedAreas;
  for (size_t k = 0; k < nz; ++k)
  {
    if (PolylineSize(traces[k]) >= 2)
    {
      lengths[k] = ArcLength(traces[k]);
      tracedAreas.push_back(area[k]);
    }
  }
  if (tracedAreas.empty())
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: no slice of the mask could be traced as a sheet");
  }
  // The reference length and area are the medians of the sheet's own slices
  // (SheetSliceLeast): debris beyond its ends along the axis is traced as short pieces.
  const double        sheetSliceArea = RollTracing::SheetSliceLeast(tracedAreas);
  std::vector<double> traced, areas;
  for (size_t k = 0; k < nz; ++k)
  {
    if (lengths[k] > 0.0 && area[k] >= sheetSliceArea)
    {
      traced.push_back(lengths[k]);
      areas.push_back(area[k]);
    }
  }
  referenceLength = Median(traced);
  if (referenceLength < 2.0 * voxel)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: the traced sheet is only " << referenceLength
                             << " mm long, less than two voxels");
  }
  // Slices whose traced length is close to the median (for a roll: the median of the
  // slices within five of it, since a roll's radius may change along its axis); the others
  // (cut short, or with a wrong turn) are interpolated from their neighbours.
  expectedLength.assign(nz, referenceLength);
  if (method == SheetSurfaceMethodEnum::Roll)
  {
    for (size_t k = 0; k < nz; ++k)
    {
      std::vector<double> around;
      for (size_t j = k > 5 ? k - 5 : 0; j <= std::min(nz - 1, k + 5); ++j)
      {
        if (lengths[j] > 0.0)
        {
          around.push_back(lengths[j]);
        }
      }
      expectedLength[k] = around.empty() ? referenceLength : Median(around);
    }
  }
  // A slice that cuts the sheet's edge along the axis holds only part of it (blurred, half
  // as bright): its trace is neither the sheet's middle nor its texture.
  partialArea = 0.75 * Median(areas);
  good.assign(nz, 0);
  SelectGood(0.05 * referenceLength + 3.0 * voxel);
  if (method == SheetSurfaceMethodEnum::General)
  {
    OrientLikeMiddle();
  }
}

void
Extraction::SelectGood(double tolerance)
{
  firstGood = lastGood = -1;
  for (size_t k = 0; k < nz; ++k)
  {
    good[k] = lengths[k] > 0.0 && std::abs(lengths[k] - expectedLength[k]) <= tolerance && area[k] >= partialArea;
    if (good[k])
    {
      firstGood = firstGood < 0 ? static_cast<long>(k) : firstGood;
      lastGood = static_cast<long>(k);
    }
  }
  if (lastGood <= firstGood)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: the sheet could be traced in one slice only; the volume "
                                "is too small along the roll axis");
  }
}

void
Extraction::OrientLikeMiddle()
{
  // Orient every slice like the middle one: the end nearer its first point comes first.
  std::vector<long> goodSlices;
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (good[k])
    {
      goodSlices.push_back(k);
    }
  }
  // The middle slice starts at its end nearer the axis (the inner end of a roll).
  Polyline &   middle = traces[goodSlices[goodSlices.size() / 2]];
  const size_t count = PolylineSize(middle);
  const double axis[2] = { m_Report.AxisCentre[0] + m_Report.AxisSlope[0] * goodSlices[goodSlices.size() / 2] * sz,
                           m_Report.AxisCentre[1] + m_Report.AxisSlope[1] * goodSlices[goodSlices.size() / 2] * sz };
  if (std::hypot(middle[2 * count - 2] - axis[0], middle[2 * count - 1] - axis[1]) <
      std::hypot(middle[0] - axis[0], middle[1] - axis[1]))
  {
    for (size_t i = 0; i < count / 2; ++i)
    {
      std::swap(middle[2 * i], middle[2 * (count - 1 - i)]);
      std::swap(middle[2 * i + 1], middle[2 * (count - 1 - i) + 1]);
    }
  }
  const Polyline reference = middle;
  for (long k : goodSlices)
  {
    Polyline &   line = traces[k];
    const size_t n = PolylineSize(line);
    const double toFirst = std::hypot(line[0] - reference[0], line[1] - reference[1]);
    const double toLast = std::hypot(line[2 * n - 2] - reference[0], line[2 * n - 1] - reference[1]);
    if (toLast < toFirst)
    {
      for (size_t i = 0; i < n / 2; ++i)
      {
        std::swap(line[2 * i], line[2 * (n - 1 - i)]);
        std::swap(line[2 * i + 1], line[2 * (n - 1 - i) + 1]);
      }
    }
  }
}

void
Extraction::MeasureSheet()
{
  // Thickness and the smallest radius of curvature, from the well-traced slices.
  std::vector<double> thicknesses, radii, tracedShares;
  size_t              goodCount = 0;
  for (long k = firstGood; k <= lastGood; ++k)
  {
    goodCount += good[k] ? 1 : 0;
  }
  const size_t sampleEvery = std::max<size_t>(1, goodCount / 12);
  size_t       index = 0;
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (!good[k])
    {
      continue;
    }
    thicknesses.push_back(area[k] / lengths[k]);
    if (index++ % sampleEvery != 0)
    {
      continue;
    }
    const size_t   points = std::max<size_t>(3, static_cast<size_t>(lengths[k] / (0.5 * voxel)));
    const Polyline even = ResampleEvenly(traces[k], points);
    const double   step = lengths[k] / static_cast<double>(points - 1);
    m_Report.SheetThickness = Median(thicknesses);
    const auto offset =
      std::max<size_t>(1, static_cast<size_t>(std::ceil(2.0 * std::max(m_Report.SheetThickness, voxel) / step)));
    for (size_t i = offset; i + offset < points; ++i)
    {
      radii.push_back(Circumradius(&even[2 * (i - offset)], &even[2 * i], &even[2 * (i + offset)]));
    }
    // The mask's extent across the trace (median over its points) times the trace's length,
    // over the slice's material: the share of the material the trace follows.
    const SliceSampler  sampler(volume, k);
    const double        march = 0.25 * voxel;
    std::vector<double> extents;
    for (size_t i = 1; i + 1 < points; i += 4)
    {
      double       chord[2];
      const double norm = NeighbourChord(even, i, chord);
      const double tx = chord[0], ty = chord[1];
      const double x = even[2 * i], y = even[2 * i + 1];
      if (!(norm > 0.0) || sampler.Mask(x, y) < 0.5)
      {
        continue;
      }
      double extent = march;
      for (const double side : { -1.0, 1.0 })
      {
        const double nx0 = -side * ty / norm, ny0 = side * tx / norm;
        for (double d = march; d <= TracedExtentVoxels * voxel && sampler.Mask(x + d * nx0, y + d * ny0) >= 0.5;
             d += march)
        {
          extent += march;
        }
      }
      extents.push_back(extent);
    }
    if (!extents.empty() && area[k] > 0.0)
    {
      tracedShares.push_back(std::min(1.0, Median(extents) * lengths[k] / area[k]));
    }
  }
  m_Report.SheetThickness = Median(thicknesses);
  m_Report.TracedShare = tracedShares.empty() ? 1.0 : Median(tracedShares);
  if (m_Report.TracedShare < TracedShareWarning)
  {
    std::ostringstream text;
    text << "about " << std::lround(100.0 * (1.0 - m_Report.TracedShare))
         << " % of the material in the mask's slices lies away from the traced sheet (not across it): turns, pages "
            "or pieces of the sheet may be missing from the mesh";
    m_Report.Warnings.push_back(text.str());
  }
  m_Report.SheetLength = referenceLength;
  m_Report.MinimumCurvatureRadius = radii.empty() ? referenceLength : Percentile(radii, 0.05);
  if (!std::isfinite(m_Report.MinimumCurvatureRadius))
  {
    m_Report.MinimumCurvatureRadius = referenceLength;
  }
  const double automatic = std::max(
    voxel, std::sqrt(8.0 * m_Report.MinimumCurvatureRadius * parameters.ChordErrorFraction * m_Report.SheetThickness));
  hs = parameters.SpacingAlongSheet > 0.0 ? parameters.SpacingAlongSheet : automatic;
  hw = parameters.SpacingAlongAxis > 0.0 ? parameters.SpacingAlongAxis : std::max(hs, sz);
}

void
Extraction::RollCentre(double z, double xy[2]) const
{
  for (int d = 0; d < 2; ++d)
  {
    xy[d] = m_Report.AxisCentre[d] + m_Report.AxisSlope[d] * z + rollCentreOffset[d];
  }
}

void
Extraction::ResampleColumns()
{
  // A slice shorter or longer than the median by a sizeable part of a column would shear
  // the grid: the columns sit at the same fraction of every slice's length.
  // (The roll tracer has already matched each slice's ends to its neighbours'.)
  if (method == SheetSurfaceMethodEnum::General)
  {
    SelectGood(std::min(0.05 * referenceLength, std::max(0.25 * hs, 2.0 * voxel)) + voxel);
  }

  columns = static_cast<size_t>(std::max(2.0, std::ceil(referenceLength / hs) + 1.0));
  if (columns * (static_cast<size_t>((lastGood - firstGood) * sz / hw) + 2) > (size_t{ 1 } << 31))
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: mesh spacing " << hs << " x " << hw
                             << " mm gives more than 2^31 points");
  }
  // Columns at the same fraction of each slice's traced length; failed slices in between
  // are interpolated from the nearest good ones.
  columnsOf.assign(nz, {});
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (good[k])
    {
      columnsOf[k] = ResampleEvenly(traces[k], columns);
    }
  }
  AlignColumns();
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (good[k])
    {
      continue;
    }
    long before = k - 1, after = k + 1;
    while (!good[before])
    {
      --before;
    }
    while (!good[after])
    {
      ++after;
    }
    const double t = static_cast<double>(k - before) / static_cast<double>(after - before);
    columnsOf[k].resize(2 * columns);
    if (method == SheetSurfaceMethodEnum::Roll)
    {
      // Along the turns, not on chords (a voxel and more inside the outer turns).
      double c0[2], c1[2];
      RollCentre(static_cast<double>(before) * sz, c0);
      RollCentre(static_cast<double>(after) * sz, c1);
      for (size_t i = 0; i < columns; ++i)
      {
        AlongTheTurn(&columnsOf[before][2 * i], c0, &columnsOf[after][2 * i], c1, t, &columnsOf[k][2 * i]);
      }
    }
    else
    {
      for (size_t i = 0; i < 2 * columns; ++i)
      {
        columnsOf[k][i] = (1.0 - t) * columnsOf[before][i] + t * columnsOf[after][i];
      }
    }
    ++m_Report.InterpolatedSlices;
  }
  if (m_Report.InterpolatedSlices > 0)
  {
    std::ostringstream text;
    text << m_Report.InterpolatedSlices << " slice(s) inside the sheet could not be traced and were interpolated";
    m_Report.Warnings.push_back(text.str());
  }
}

// The traced ends of a slice jitter by a fraction of a voxel, which shifts its columns
// along the sheet and makes the grid slightly non-developable (the flattener then has to
// strain or crease it). Align every good slice along the sheet to the mean of its good
// neighbours within five slices: the tangential offsets of its columns are fitted by
// a + b c and the slice is resampled at the corrected arc lengths.

void
Extraction::AlignColumns()
{
  const long            reach = 5;
  std::vector<Polyline> aligned(columnsOf);
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (!good[k])
    {
      continue;
    }
    Polyline reference(2 * columns, 0.0);
    double   neighbours = 0.0;
    for (long j = std::max(firstGood, k - reach); j <= std::min(lastGood, k + reach); ++j)
    {
      if (good[j] && j != k)
      {
        for (size_t i = 0; i < 2 * columns; ++i)
        {
          reference[i] += columnsOf[j][i];
        }
        neighbours += 1.0;
      }
    }
    if (neighbours == 0.0)
    {
      continue;
    }
    for (double & value : reference)
    {
      value /= neighbours;
    }
    double sc = 0.0, so = 0.0, scc = 0.0, sco = 0.0;
    for (size_t c = 0; c < columns; ++c)
    {
      double       chord[2];
      const double norm = NeighbourChord(reference, c, chord);
      if (norm <= 0.0)
      {
        continue;
      }
      const double offset = ((columnsOf[k][2 * c] - reference[2 * c]) * chord[0] +
                             (columnsOf[k][2 * c + 1] - reference[2 * c + 1]) * chord[1]) /
                            norm;
      const auto x = static_cast<double>(c);
      sc += x;
      so += offset;
      scc += x * x;
      sco += x * offset;
    }
    const auto   n = static_cast<double>(columns);
    const double denominator = n * scc - sc * sc;
    if (denominator <= 0.0)
    {
      continue;
    }
    const double        slope = (n * sco - sc * so) / denominator;
    const double        intercept = (so - slope * sc) / n;
    std::vector<double> arcs(columns);
    for (size_t c = 0; c < columns; ++c)
    {
      arcs[c] = lengths[k] * static_cast<double>(c) / static_cast<double>(columns - 1) - intercept -
                slope * static_cast<double>(c);
    }
    aligned[k] = SampleAtArcLengths(traces[k], KeepWithinTrace(arcs, lengths[k]));
  }
  columnsOf = std::move(aligned);
}

void
Extraction::ChooseRowSpacing()
{
  // Along the axis the sheet bends too (a radius that changes along the roll, a skewed
  // end): rows far apart, joined by straight edges, would cut through the gaps between
  // turns. The automatic row spacing h is the largest (at most the one above) at which the
  // curves of the slices deviate from the chord between slices h apart by no more than the
  // chord error f t, above the deviation the noise of the traces makes between neighbouring
  // slices (95th percentile over columns and slices).
  if (!(parameters.SpacingAlongAxis > 0.0) && lastGood - firstGood >= 4)
  {
    auto deviation = [&](long d) {
      std::vector<double> values;
      const size_t        stride = std::max<size_t>(1, columns / 200);
      for (long k = firstGood + d; k + d <= lastGood; k += std::max(1L, d / 2))
      {
        for (size_t c = 0; c < columns; c += stride)
        {
          const double ex = 0.5 * (columnsOf[k - d][2 * c] + columnsOf[k + d][2 * c]) - columnsOf[k][2 * c];
          const double ey = 0.5 * (columnsOf[k - d][2 * c + 1] + columnsOf[k + d][2 * c + 1]) - columnsOf[k][2 * c + 1];
          values.push_back(std::hypot(ex, ey));
        }
      }
      return values.empty() ? 0.0 : Percentile(values, 0.95);
    };
    const double noise = deviation(1);
    const double tolerance = parameters.ChordErrorFraction * std::max(m_Report.SheetThickness, voxel);
    auto         half = static_cast<long>(std::floor(0.5 * hw / sz));
    while (half >= 2 && 2 * half <= lastGood - firstGood && deviation(half) > noise + tolerance)
    {
      half = static_cast<long>(std::floor(0.75 * static_cast<double>(half)));
    }
    hw = std::max(sz, std::min(hw, 2.0 * static_cast<double>(std::max(half, 1L)) * sz));
  }
  const double tilt = std::atan(std::hypot(m_Report.AxisSlope[0], m_Report.AxisSlope[1])) * 180.0 / Pi;
  if (method == SheetSurfaceMethodEnum::Roll && tilt > 2.0)
  {
    std::ostringstream text;
    text << "the roll axis is tilted by " << tilt << " degrees from the slice normal";
    m_Report.Warnings.push_back(text.str());
  }
}

// Where the sheet ends along the axis beyond the good slice `from` (towards dir), as a
// distance from it (mm). The mask says little there: a noisy scan is smoothed before it is
// thresholded, which dims a blurred edge further, so the mask of a slice that holds the
// whole sheet can be a third of a full slice's. The scan's own intensities along the edge
// slice's trace (moved with the roll axis's drift) do not have that bias: their mean above
// air, as a share of the same along the good slices' own traces next to the edge, is the
// share of the sheet each slice holds, and a blur spreads the edge evenly about where the
// share is a half. The edge is put there, between the last slice with half the sheet or
// more and the next (at most EdgeSlices beyond the good ones).
double
Extraction::EdgeReach(long from, long dir) const
{
  const double air = context.AirLevel;
  // Slice `traced`'s trace at about a voxel's spacing, resampled once and read in every
  // slice k beyond it.
  auto alongTrace = [&](long traced) {
    return ResampleEvenly(traces[traced], std::max<size_t>(2, static_cast<size_t>(lengths[traced] / voxel) + 1));
  };
  auto meanAbove = [&](const Polyline & line, long traced, long k) {
    const size_t n = PolylineSize(line);
    const double shift = static_cast<double>(k - traced) * sz;
    SliceSampler sampler(volume, static_cast<size_t>(k));
    double       sum = 0.0, count = 0.0;
    for (size_t i = 0; i < n; ++i)
    {
      const double x = line[2 * i] + m_Report.AxisSlope[0] * shift, y = line[2 * i + 1] + m_Report.AxisSlope[1] * shift;
      const long   ix = std::lround(x / sx), iy = std::lround(y / sy);
      if (ix < 0 || iy < 0 || ix >= static_cast<long>(nx) || iy >= static_cast<long>(ny))
      {
        continue;
      }
      if (volume.Data != nullptr &&
          volume.Data[(static_cast<size_t>(k) * ny + static_cast<size_t>(iy)) * nx + static_cast<size_t>(ix)] == 0)
      {
        continue;
      }
      sum += sampler.Intensity(x, y, air) - air;
      count += 1.0;
    }
    return count > 0.0 ? sum / count : 0.0;
  };
  const Polyline edgeLine = alongTrace(from);
  double         full = 0.0;
  for (long j = from; std::abs(j - from) <= 3 && j >= firstGood && j <= lastGood; j -= dir)
  {
    if (good[j])
    {
      full = std::max(full, j == from ? meanAbove(edgeLine, j, j) : meanAbove(alongTrace(j), j, j));
    }
  }
  if (!(full > 0.0))
  {
    return 0.5 * sz;
  }
  long   last = from;
  double lastShare = 1.0, nextShare = 0.0;
  for (long k = from + dir; k >= 0 && k < static_cast<long>(nz) && std::abs(k - from) <= EdgeSlices; k += dir)
  {
    const double share = meanAbove(edgeLine, from, k) / full;
    if (share < 0.5)
    {
      nextShare = share;
      break;
    }
    last = k;
    lastShare = share;
  }
  const double beyond = lastShare > nextShare ? std::clamp((lastShare - 0.5) / (lastShare - nextShare), 0.0, 1.0) : 0.0;
  return (static_cast<double>(std::abs(last - from)) + beyond) * sz;
}

SheetMesh
Extraction::BuildMesh()
{
  // Rows: a weighted line fit along the slices within one row spacing (BuildSheetGrid).
  // Where slices beyond the first or last good one hold the sheet (its edge along the axis,
  // traces lost in its faint, blurred slices), the mesh reaches over them to where the sheet
  // ends (EdgeReach), on the trend of the last good slices. Without the scan's intensities:
  // over the slices that hold half a full slice's material, and half a slice further.
  const double fullArea = partialArea / 0.75;
  auto         byArea = [&](long from, long dir) {
    long k = from + dir;
    while (k >= 0 && k < static_cast<long>(nz) && std::abs(k - from) <= EdgeSlices && area[k] >= 0.5 * fullArea)
    {
      k += dir;
    }
    const long covered = std::abs(k - from) - 1;
    const bool edge = k >= 0 && k < static_cast<long>(nz) && area[k] > 0.0;
    return static_cast<double>(covered) * sz + (covered > 0 || edge ? 0.5 * sz : 0.0);
  };
  const double below = volume.Intensity != nullptr ? EdgeReach(firstGood, -1) : byArea(firstGood, -1);
  const double above = volume.Intensity != nullptr ? EdgeReach(lastGood, +1) : byArea(lastGood, +1);
  const double span = static_cast<double>(lastGood - firstGood) * sz + below + above;
  const auto   rows = static_cast<size_t>(std::max(2.0, std::ceil(span / hw) + 1.0));
  const double rowSpacing = span / static_cast<double>(rows - 1);
  // Slices whose point lies farther than this from the row's median point are left out of
  // its mean: where a turn is pushed onto the next one in some slices of a row's window and
  // not in others (a touch's edge along the axis), the mean would lie between the two, in
  // the gap or on the neighbouring turn.
  const double agreement = 0.5 * std::max(m_Report.SheetThickness, voxel);
  RollAxisLine rollAxis{};
  for (int d = 0; d < 2; ++d)
  {
    rollAxis.Centre[d] = m_Report.AxisCentre[d] + rollCentreOffset[d];
    rollAxis.Slope[d] = m_Report.AxisSlope[d];
  }
  SheetMesh mesh = BuildSheetGrid(columnsOf,
                                  firstGood,
                                  lastGood,
                                  sz,
                                  below,
                                  rows,
                                  rowSpacing,
                                  columns,
                                  agreement,
                                  method == SheetSurfaceMethodEnum::Roll ? &rollAxis : nullptr);
  if (method == SheetSurfaceMethodEnum::Roll)
  {
    OrientNormalsToAxis(mesh, m_Report.AxisCentre, m_Report.AxisSlope);
  }
  m_Report.SpacingAlongSheet = referenceLength / static_cast<double>(columns - 1);
  m_Report.SpacingAlongAxis = rowSpacing;
  if (method == SheetSurfaceMethodEnum::Roll && m_Report.TurnSpacing > 0.0)
  {
    // A layer jump the slice-to-slice check missed shows on the mesh as a sideways step
    // of about a turn spacing.
    // The slice of the view nearest grid point (row, column).
    auto sliceAt = [&](size_t row, size_t column) {
      const double z = mesh.Points[3 * (row * columns + column) + 2];
      return static_cast<size_t>(std::clamp(std::lround(z / sz), 0L, static_cast<long>(nz) - 1));
    };
    // A row whose window of slices held a trace on the neighbouring turn over part of the
    // sheet leaves its columns' course along the axis there, where the rows about it agree.
    m_Report.ColumnSpikesSmoothed =
      SheetMidSurfaceExtractor::SmoothColumnSpikes(mesh, GridStepFraction * m_Report.TurnSpacing);
    if (m_Report.ColumnSpikesSmoothed > 0)
    {
      std::ostringstream text;
      text << m_Report.ColumnSpikesSmoothed << " grid point(s) off their column's course along the axis by more than "
           << GridStepFraction << " of the turn spacing, where the rows either side agree (a row partly on the "
           << "neighbouring turn), were put back on it";
      m_Report.Warnings.push_back(text.str());
    }
    // A column taken onto the neighbouring turn in one row's slices only (the row's window
    // holds a touch's edge along the axis) leaves the row's curve for a point or two, by
    // about a turn spacing; where the turns press together, the next turn lies about a
    // sheet's thickness away, and the row bends towards it over three columns.
    m_Report.RowSpikesSmoothed =
      SheetMidSurfaceExtractor::SmoothRowSpikes(mesh, GridStepFraction * m_Report.TurnSpacing);
    const double touchLimit = std::max(m_Report.SheetThickness, voxel);
    if (touchLimit < GridStepFraction * m_Report.TurnSpacing)
    {
      m_Report.RowSpikesSmoothed += SheetMidSurfaceExtractor::SmoothTouchBumps(mesh, touchLimit);
    }
    if (m_Report.RowSpikesSmoothed > 0)
    {
      std::ostringstream text;
      text << m_Report.RowSpikesSmoothed << " grid point(s) off their row's curve for one to three columns (a column "
           << "on the neighbouring turn: by more than " << GridStepFraction << " of the turn spacing, or by more than "
           << "the sheet's thickness towards a touching turn) were put back on it";
      m_Report.Warnings.push_back(text.str());
    }
    m_Report.GridSteps = SheetMidSurfaceExtractor::FindGridSteps(mesh, GridStepFraction * m_Report.TurnSpacing);
    for (auto & step : m_Report.GridSteps)
    {
      step.Slice = sliceAt(step.Row, step.Column);
    }
    m_Report.OffSheetRuns =
      SheetMidSurfaceExtractor::FindOffSheetRuns(mesh, volume, context.AirLevel, context.SheetLevel);
    for (auto & run : m_Report.OffSheetRuns)
    {
      run.Slice = sliceAt(run.Row, run.FirstColumn);
    }
    if (!m_Report.OffSheetRuns.empty())
    {
      const auto &       first = m_Report.OffSheetRuns.front();
      std::ostringstream text;
      text << "the mesh lies in air (below a quarter of the sheet's contrast) along " << m_Report.OffSheetRuns.size()
           << " run(s) of grid points (possible layer jumps: traced between turns), first at grid row " << first.Row
           << ", columns " << first.FirstColumn << "-" << first.LastColumn << " (slice " << first.Slice << ")";
      m_Report.Warnings.push_back(text.str());
    }
    if (!m_Report.GridSteps.empty())
    {
      const auto &       first = m_Report.GridSteps.front();
      std::ostringstream text;
      text << "the mesh steps sideways by more than " << GridStepFraction << " of the turn spacing at "
           << m_Report.GridSteps.size() << " place(s) (possible layer jumps), first at grid row " << first.Row
           << ", column " << first.Column << " (slice " << first.Slice << ")";
      m_Report.Warnings.push_back(text.str());
    }
  }
  report(1.0);
  return mesh;
}
} // namespace SheetTracing
} // end namespace itk

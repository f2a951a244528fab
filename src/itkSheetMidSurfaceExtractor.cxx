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
#include "itkSheetMidSurfaceExtractor.h"

#include "vuRollTracer.h"
#include "vuSheetExtraction.h"

#include "itkImage.h"
#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <sstream>

namespace itk {
const char *
ToString(SheetSurfaceMethodEnum method)
{
  switch (method)
  {
    case SheetSurfaceMethodEnum::Roll:
      return "roll";
    case SheetSurfaceMethodEnum::General:
      return "general";
    case SheetSurfaceMethodEnum::Auto:
      break;
  }
  return "auto";
}

SheetSurfaceMethodEnum
SheetSurfaceMethodFromString(const std::string & name)
{
  for (auto method : { SheetSurfaceMethodEnum::Auto, SheetSurfaceMethodEnum::Roll, SheetSurfaceMethodEnum::General })
  {
    if (name == ToString(method))
    {
      return method;
    }
  }
  itkGenericExceptionMacro(<< "unknown surface method \"" << name << "\" (known: auto, roll, general)");
}

double
SheetIntensityLevels::SignalToNoise() const
{
  return Noise > 0.0 ? (Sheet - Air) / Noise : std::numeric_limits<double>::infinity();
}

double
SheetIntensityLevels::DenoisingSigma() const
{
  const double snr = SignalToNoise();
  return snr >= 12.0 ? 0.0 : std::clamp(3.0 / snr, 0.5, 1.0);
}

namespace {
// The value at `fraction` of the way up `values` (reordered).
double
Quantile(std::vector<float> & values, double fraction)
{
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(fraction * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), at, values.end());
  return static_cast<double>(*at);
}
} // namespace

SheetIntensityLevels
EstimateSheetIntensityLevels(std::vector<float> air, std::vector<float> material)
{
  SheetIntensityLevels levels;
  if (!air.empty())
  {
    const float floor = *std::min_element(air.begin(), air.end());
    air.erase(std::remove(air.begin(), air.end(), floor), air.end());
  }
  if (air.size() >= 16 && !material.empty())
  {
    levels.Air = Quantile(air, 0.5);
    levels.Noise = levels.Air - Quantile(air, 0.1587);
    levels.Sheet = Quantile(material, 0.5);
  }
  return levels;
}

namespace {
// Ridler and Calvard's iterative selection with medians, started from `levels`.
SheetIntensityLevels
IterativeSelection(const std::vector<float> & values, SheetIntensityLevels levels)
{
  std::vector<float> air, sheet;
  for (int pass = 0; pass < 30 && levels.Sheet > levels.Air; ++pass)
  {
    const double midpoint = 0.5 * (levels.Air + levels.Sheet);
    air.clear();
    sheet.clear();
    for (float v : values)
    {
      (v >= midpoint ? sheet : air).push_back(v);
    }
    if (air.empty() || sheet.empty())
    {
      break;
    }
    auto median = [](std::vector<float> & part) {
      const auto middle = part.begin() + static_cast<std::ptrdiff_t>(part.size() / 2);
      std::nth_element(part.begin(), middle, part.end());
      return static_cast<double>(*middle);
    };
    const double airLevel = median(air), sheetLevel = median(sheet);
    const bool   settled = std::abs(0.5 * (airLevel + sheetLevel) - midpoint) <= 1e-3 * (sheetLevel - airLevel);
    levels.Air = airLevel;
    levels.Sheet = sheetLevel;
    if (settled)
    {
      break;
    }
  }
  return levels;
}
} // namespace

SheetIntensityLevels
RefineSheetIntensityLevels(const std::vector<float> & values, SheetIntensityLevels levels)
{
  if (values.empty())
  {
    return levels;
  }
  // Padding outside a scanner's field of view (the smallest value, held by 1 % of the
  // sample or more) is neither air nor sheet: left out.
  const float floor = *std::min_element(values.begin(), values.end());
  const bool  padded = static_cast<size_t>(std::count(values.begin(), values.end(), floor)) * 100 >= values.size();
  std::vector<float> sample;
  std::copy_if(
    values.begin(), values.end(), std::back_inserter(sample), [&](float v) { return !padded || v != floor; });
  levels = IterativeSelection(sample, levels);
  if (sample.size() < 100 || !(levels.Sheet > levels.Air))
  {
    return levels;
  }
  // The selection settles on the fixed point nearest its start. Started inside the air's
  // noise (by a threshold there) on a scan whose sheet is a small share of the voxels, it
  // splits that noise in two: its levels then lie less than three of the lower class's
  // noise widths apart, and their midpoint within two of the sample's noise widths of its
  // median. The sheet being a small share, the sample's median and lower half are the
  // air's, and what lies four noise widths above the median is the sheet's.
  const double       midpoint = 0.5 * (levels.Air + levels.Sheet);
  std::vector<float> lower;
  std::copy_if(sample.begin(), sample.end(), std::back_inserter(lower), [midpoint](float v) { return v < midpoint; });
  const double lowerNoise = lower.empty() ? 0.0 : Quantile(lower, 0.5) - Quantile(lower, 0.1587);
  const double median = Quantile(sample, 0.5);
  const double noise = median - Quantile(sample, 0.1587);
  if (!(levels.Sheet - levels.Air < 3.0 * lowerNoise && midpoint < median + 2.0 * noise))
  {
    return levels;
  }
  std::vector<float> sheet;
  std::copy_if(
    sample.begin(), sample.end(), std::back_inserter(sheet), [&](float v) { return v > median + 4.0 * noise; });
  if (sheet.size() * 1000 < sample.size())
  {
    return levels;
  }
  levels.Air = median;
  levels.Sheet = Quantile(sheet, 0.5);
  return levels;
}

namespace {
// Places where a roll's mesh may jump layers, by its own checks.
size_t
PossibleLayerJumps(const SheetMidSurfaceReport & report)
{
  return report.GridSteps.size() + report.OffSheetRuns.size() + report.LayerJumps.size();
}
// Extent of a grid mesh along the roll axis (mm).
double
SpanAlongAxis(const SheetMesh & mesh, const SheetMidSurfaceReport & report)
{
  return static_cast<double>(std::max(0, mesh.GridRows - 1)) * report.SpacingAlongAxis;
}
// A mesh from another seed slice is taken only when its sheet is as long, and its grid as
// wide along the axis, as the first mesh's to within this fraction: a trace that lost part
// of the sheet, or slices left out, has fewer places to check.
constexpr double SeedExtentTolerance = 0.02;
// ... and only when its checks name clearly fewer places: at most the first count less a
// quarter of it (and less one). The checks also name places of a correct mesh (sharp bends
// of a long roll's inner turns), a few more or less from one trace to the next.
constexpr size_t SeedCheckMargin = 4;
} // namespace

SheetMesh
SheetMidSurfaceExtractor::Extract(const SheetVolumeView & volume)
{
  m_Report = SheetMidSurfaceReport{};
  SheetTracing::Extraction extraction(volume, m_Parameters, m_Report, m_Progress);
  SheetMesh                mesh = extraction.Run();
  // Every slice of a roll is traced from its neighbour, outwards from one seed slice, so a
  // seed slice traced wrongly (the inner end cut across to the next turn, a turn lost over
  // part of a revolution where turns touch) carries its error into every slice. Where the
  // mesh's own checks name possible layer jumps, the sheet is traced again from each of the
  // other candidate seed slices, and the mesh whose checks name the fewest is kept.
  const size_t first = PossibleLayerJumps(m_Report);
  if (m_Report.Method != SheetSurfaceMethodEnum::Roll || first == 0)
  {
    return mesh;
  }
  // The progress stays at its end; a caller's abort still stops the tracing.
  const ProgressCallback again = [this](double) { return !m_Progress || m_Progress(1.0); };
  size_t                 fewest = first;
  long                   chosen = 0;
  const double           middleSpan = SpanAlongAxis(mesh, m_Report);
  for (long candidate = 1; candidate < static_cast<long>(std::size(RollTracing::SeedFractions)); ++candidate)
  {
    SheetMidSurfaceReport    report;
    SheetTracing::Extraction other(volume, m_Parameters, report, again);
    other.seedCandidate = candidate;
    SheetMesh otherMesh;
    try
    {
      otherMesh = other.Run();
    }
    catch (const ExceptionObject &)
    {
      if (m_Progress && !m_Progress(1.0))
      {
        throw; // aborted by the caller
      }
      continue; // that seed slice does not trace: the first mesh stands
    }
    const size_t checks = PossibleLayerJumps(report);
    const double span = SpanAlongAxis(otherMesh, report), chosenSpan = SpanAlongAxis(mesh, m_Report);
    // Clearly fewer places named over as much of the sheet, or no more over clearly more of
    // it (the chosen seed's trace lost slices along the axis that this one keeps).
    const bool fewer = checks + std::max<size_t>(1, fewest / SeedCheckMargin) <= fewest &&
                       span >= (1.0 - SeedExtentTolerance) * chosenSpan;
    const bool longer = checks <= fewest && span > (1.0 + SeedExtentTolerance) * chosenSpan;
    if (report.Method == SheetSurfaceMethodEnum::Roll && (fewer || longer) &&
        std::abs(report.SheetLength - m_Report.SheetLength) <= SeedExtentTolerance * m_Report.SheetLength)
    {
      fewest = checks;
      chosen = candidate;
      std::swap(mesh, otherMesh);
      std::swap(m_Report, report);
    }
  }
  if (chosen > 0)
  {
    std::ostringstream text;
    text << "traced from the seed slice at " << std::lround(100.0 * RollTracing::SeedFractions[chosen])
         << " % of the sheet's width along the axis instead of the middle one: its mesh's own checks name " << fewest
         << " possible layer jump(s), the middle one's " << first;
    if (SpanAlongAxis(mesh, m_Report) > (1.0 + SeedExtentTolerance) * middleSpan)
    {
      text << "; it covers more of the sheet along the axis";
    }
    m_Report.Warnings.push_back(text.str());
  }
  return mesh;
}
} // end namespace itk

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
#include "vuReaderOptions.h"

#include "vuCommands.h"

#include "itkImageDuplicator.h"

#include <algorithm>
#include <cmath>

namespace vu {
void
AddReaderOptions(CLI::App & command, ReaderOptions & options)
{
  command.add_option("--series",
                     options.Series,
                     "DICOM series to read: SeriesInstanceUID or series number; in a volume-cartographer "
                     ".volpkg, the volume's directory name, uuid or name (default: the series or volume with the "
                     "most slices)");
  command
    .add_option("--spacing",
                options.Spacing,
                "voxel size X Y Z in mm, replacing the input's (required for "
                "correct geometry of TIFF stacks, which default to 1 1 1)")
    ->expected(3);
  command
    .add_option("--roi",
                options.RegionOfInterest,
                "read only this box of voxels: X Y Z (first index) SX SY SZ (size), in the full volume")
    ->expected(6);
  command
    .add_option("--roi-mm",
                options.PhysicalRegionOfInterest,
                "read only this box in physical coordinates: X0 Y0 Z0 X1 Y1 Z1 (two opposite corners, mm)")
    ->expected(6);
  command.add_option("--shrink", options.Shrink, "integer downsampling factor (averaging), applied after the ROI")
    ->check(CLI::Range(1u, 64u))
    ->capture_default_str();
  command
    .add_option("--slice-tolerance",
                options.SliceSpacingTolerance,
                "how far a DICOM slice may lie from its place on the regular grid, as a fraction of the slice "
                "spacing, before the series is called irregular (and resampled)")
    ->check(CLI::Range(1e-6, 0.5))
    ->capture_default_str();
  command.add_flag("--no-resample",
                   options.NoResample,
                   "refuse a sheared (gantry tilt) or unevenly spaced DICOM series instead of resampling it onto a "
                   "regular grid");
  command
    .add_option("--interpolator",
                options.Interpolator,
                "interpolation of a resampled DICOM series: nearest, linear or bspline (cubic)")
    ->check(CLI::IsMember({ "nearest", "linear", "bspline" }))
    ->capture_default_str();
  command
    .add_option("--resample-spacing",
                options.ResampleSpacing,
                "slice spacing in mm of a resampled DICOM series (default: its smallest slice spacing)")
    ->check(vu::Positive());
}

void
ConfigureReader(const ReaderOptions & options, const std::string & path, itk::CTVolumeReader & reader)
{
  reader.SetFileName(path);
  reader.SetSeriesIdentifier(options.Series);
  if (!options.Spacing.empty())
  {
    itk::CTVolumeReader::SpacingType spacing;
    for (unsigned d = 0; d < 3; ++d)
    {
      if (!(options.Spacing[d] > 0.0) || !std::isfinite(options.Spacing[d]))
      {
        throw UsageError("--spacing: each voxel size must be a positive number of mm");
      }
      spacing[d] = options.Spacing[d];
    }
    reader.SetSpacingOverride(spacing);
    reader.OverrideSpacingOn();
  }
  if (!options.RegionOfInterest.empty() && !options.PhysicalRegionOfInterest.empty())
  {
    throw UsageError("give either --roi or --roi-mm, not both");
  }
  if (!options.RegionOfInterest.empty())
  {
    itk::CTVolumeReader::RegionType region;
    for (unsigned d = 0; d < 3; ++d)
    {
      if (options.RegionOfInterest[d] < 0 || options.RegionOfInterest[d + 3] <= 0)
      {
        throw UsageError("--roi: the first index must be >= 0 and the size > 0");
      }
      region.SetIndex(d, options.RegionOfInterest[d]);
      region.SetSize(d, static_cast<itk::SizeValueType>(options.RegionOfInterest[d + 3]));
    }
    reader.SetRegionOfInterest(region);
    reader.UseRegionOfInterestOn();
  }
  if (!options.PhysicalRegionOfInterest.empty())
  {
    itk::CTVolumeReader::PointType start, end;
    for (unsigned d = 0; d < 3; ++d)
    {
      start[d] = options.PhysicalRegionOfInterest[d];
      end[d] = options.PhysicalRegionOfInterest[d + 3];
    }
    reader.SetPhysicalRegionOfInterestStart(start);
    reader.SetPhysicalRegionOfInterestEnd(end);
    reader.UsePhysicalRegionOfInterestOn();
  }
  reader.SetShrinkFactor(options.Shrink);
  reader.SetSliceSpacingTolerance(options.SliceSpacingTolerance);
  reader.SetResampleIrregularSeries(!options.NoResample);
  reader.SetSliceInterpolator(itk::SliceInterpolatorFromString(options.Interpolator));
  reader.SetResampledSliceSpacing(options.ResampleSpacing);
}

nlohmann::json
GeometryCorrectionsJson(const itk::CTVolumeReader & reader)
{
  const itk::DicomSeriesGeometry & geometry = reader.GetSeriesGeometry();
  if (!reader.GetResampled())
  {
    return nullptr;
  }
  auto slice = [&geometry](size_t k) {
    const double base = geometry.Stack.Slices.front().Position.GetVectorFromOrigin() * geometry.Normal;
    return nlohmann::json{ { "file", geometry.Stack.Slices[k].File }, { "location_mm", base + geometry.Locations[k] } };
  };
  nlohmann::json json;
  json["sheared"] = geometry.Sheared;
  json["tilt_deg"] = geometry.TiltDegrees;
  json["drift_mm_per_mm"] = { geometry.DriftPerMillimetre[0], geometry.DriftPerMillimetre[1] };
  json["maximum_drift_mm"] = geometry.MaximumDrift;
  json["spacing_runs"] = nlohmann::json::array();
  for (const auto & run : geometry.Runs)
  {
    json["spacing_runs"].push_back(
      { { "spacing_mm", run.Spacing }, { "from", slice(run.First) }, { "to", slice(run.Last) } });
  }
  json["gaps"] = nlohmann::json::array();
  for (const auto & gap : geometry.Gaps)
  {
    json["gaps"].push_back({ { "missing_slices", gap.Missing },
                             { "gap_mm", gap.Size },
                             { "usual_spacing_mm", gap.UsualSpacing },
                             { "after", slice(gap.Before) },
                             { "before", slice(gap.Before + 1) } });
  }
  const itk::RegularGrid & grid = reader.GetResampledGrid();
  json["resampled"] = { { "size", { grid.Size[0], grid.Size[1], grid.Size[2] } },
                        { "spacing_mm", { grid.Spacing[0], grid.Spacing[1], grid.Spacing[2] } },
                        { "origin_mm", { grid.Origin[0], grid.Origin[1], grid.Origin[2] } },
                        { "interpolator", itk::ToString(reader.GetSliceInterpolator()) },
                        { "voxels_without_data", reader.GetVoxelsWithoutData() },
                        { "value_without_data", "NaN" } };
  return json;
}

FilledVolume
FillVoxelsWithoutData(itk::CTVolumeReader::OutputImageType * volume)
{
  FilledVolume result;
  result.Volume = volume;
  const float * values = volume->GetBufferPointer();
  const size_t  count = volume->GetBufferedRegion().GetNumberOfPixels();
  result.Filled =
    static_cast<itk::SizeValueType>(std::count_if(values, values + count, [](float v) { return std::isnan(v); }));
  if (result.Filled == 0 || result.Filled == count)
  {
    return result;
  }
  // The median of about a million voxels with data, evenly spread.
  const size_t       stride = std::max<size_t>(1, count / 1000000);
  std::vector<float> sample;
  for (size_t i = 0; i < count; i += stride)
  {
    if (std::isfinite(values[i]))
    {
      sample.push_back(values[i]);
    }
  }
  if (sample.empty())
  {
    sample.push_back(*std::find_if(values, values + count, [](float v) { return std::isfinite(v); }));
  }
  std::nth_element(sample.begin(), sample.begin() + sample.size() / 2, sample.end());
  result.Value = sample[sample.size() / 2];
  auto duplicator = itk::ImageDuplicator<itk::CTVolumeReader::OutputImageType>::New();
  duplicator->SetInputImage(volume);
  duplicator->Update();
  result.Volume = duplicator->GetOutput();
  float * filled = result.Volume->GetBufferPointer();
  std::replace_if(
    filled, filled + count, [](float v) { return std::isnan(v); }, static_cast<float>(result.Value));
  return result;
}
} // namespace vu

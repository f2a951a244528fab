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
#ifndef vuReaderOptions_h
#define vuReaderOptions_h

#include "itkCTVolumeReader.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vu {
/** The CT reader's command-line options, shared by every subcommand that reads a volume
 * (info, unwrap, ...). */
struct ReaderOptions
{
  std::string         Series;
  std::vector<double> Spacing;
  std::vector<long>   RegionOfInterest;
  std::vector<double> PhysicalRegionOfInterest;
  unsigned int        Shrink{ 1 };
  double              SliceSpacingTolerance{ 0.05 };
  bool                NoResample{ false };
  std::string         Interpolator{ "bspline" };
  double              ResampleSpacing{ 0.0 };
};

/** Adds --series, --spacing, --roi, --roi-mm, --shrink, --slice-tolerance, --no-resample,
 * --interpolator and --resample-spacing to a subcommand; the values land in options,
 * which must outlive the parse. */
void
AddReaderOptions(CLI::App & command, ReaderOptions & options);

/** Sets the input path and the options on a reader; throws vu::UsageError for values
 * that cannot be right whatever the input (e.g. a negative spacing). */
void
ConfigureReader(const ReaderOptions & options, const std::string & path, itk::CTVolumeReader & reader);

/** What the reader found wrong with a DICOM series' geometry and what it did about it, as
 * JSON (null for a regular series or another input): the shear, the spacing runs, the
 * gaps with their positions, and the grid it resampled onto. */
nlohmann::json
GeometryCorrectionsJson(const itk::CTVolumeReader & reader);

/** A volume whose voxels without data (NaN: the corners of a resampled sheared series,
 * the gaps of missing slices) hold a value, for the stages that need one in every voxel
 * (segmentation, meshing, the preview): Volume is a copy with those voxels set to Value,
 * the median of the voxels with data (in a scan of a scroll, the air), or the input itself
 * when Filled is 0. */
struct FilledVolume
{
  itk::CTVolumeReader::OutputImageType::Pointer Volume;
  itk::SizeValueType                            Filled{ 0 };
  double                                        Value{ 0.0 };
};
FilledVolume
FillVoxelsWithoutData(itk::CTVolumeReader::OutputImageType * volume);
} // namespace vu

#endif

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
#ifndef vuSheetsJson_h
#define vuSheetsJson_h

#include "itkSheetMidSurfaceMeshFilter.h"

#include <nlohmann/json.hpp>

namespace vu {
// A sheet's entry in the list of sheets found: size, where it lies, how sure the trace is.
template <typename TSurfaceFilter>
nlohmann::json
SheetEntryJson(const TSurfaceFilter & surfaceFilter, unsigned int sheet)
{
  const itk::SheetSummary & summary = surfaceFilter.GetSheetSummary(sheet);
  return { { "sheet", sheet + 1 },
           { "voxels", summary.Voxels },
           { "area_mm2", summary.Area },
           { "bounds_mm",
             { { summary.BoundsMinimum[0], summary.BoundsMinimum[1], summary.BoundsMinimum[2] },
               { summary.BoundsMaximum[0], summary.BoundsMaximum[1], summary.BoundsMaximum[2] } } },
           { "pieces", summary.Pieces },
           { "confidence", summary.Confidence },
           { "method", itk::ToString(surfaceFilter.GetSheetReport(sheet).Method) } };
}

template <typename TSurfaceFilter>
nlohmann::json
DroppedJson(const TSurfaceFilter & surfaceFilter)
{
  const itk::DroppedSheetPieces & dropped = surfaceFilter.GetDroppedPieces();
  nlohmann::json                  untraceable = nlohmann::json::array();
  for (const auto & piece : dropped.NotTraced)
  {
    untraceable.push_back({ { "voxels", piece.Voxels },
                            { "area_mm2", piece.Area },
                            { "reason", piece.Reason },
                            { "split_from_piece", piece.SplitFromPiece } });
  }
  return { { "too_small",
             { { "pieces", dropped.TooSmall },
               { "voxels", dropped.TooSmallVoxels },
               { "minimum_area_mm2", surfaceFilter.GetMinimumSheetAreaUsed() } } },
           { "untraceable", untraceable } };
}

} // namespace vu

#endif

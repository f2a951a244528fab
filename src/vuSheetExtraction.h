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
#ifndef vuSheetExtraction_h
#define vuSheetExtraction_h

#include "itkSheetMidSurfaceExtractor.h"
#include "vuGeneralSliceTracer.h"
#include "vuRollTracer.h"

#include <vector>

namespace itk {
namespace SheetTracing {
// One run of SheetMidSurfaceExtractor::Extract(), stage by stage: the input checked, the
// roll axis fitted through the slices' centroids, the air and material levels, every slice
// traced, the well-traced slices chosen, the sheet's thickness and curvature measured (and
// from them the grid's spacing), the columns of every slice, the row spacing, the grid.
// Each stage reads what the stages before it left in the members.
struct Extraction
{
  Extraction(const SheetVolumeView &                            view,
             const SheetMidSurfaceParameters &                  runParameters,
             SheetMidSurfaceReport &                            runReport,
             const SheetMidSurfaceExtractor::ProgressCallback & runProgress)
    : volume(view)
    , parameters(runParameters)
    , m_Report(runReport)
    , progress(runProgress)
    , nx(view.Size[0])
    , ny(view.Size[1])
    , nz(view.Size[2])
    , sx(view.Spacing[0])
    , sy(view.Spacing[1])
    , sz(view.Spacing[2])
    , voxel(std::min(view.Spacing[0], view.Spacing[1]))
  {}

  SheetMesh
  Run();

  void
  CheckInput() const;
  void
  report(double fraction) const;
  void
  FitAxis();
  void
  MeasureLevels();
  void
  TraceSlices();
  bool
  RollOnItsSheet(const std::vector<RollTracing::SliceTrace> & slices) const;
  void
  SelectSlices();
  void
  SelectGood(double tolerance);
  void
  OrientLikeMiddle();
  void
  MeasureSheet();
  void
  ResampleColumns();
  void
  AlignColumns();
  void
  ChooseRowSpacing();
  double
  EdgeReach(long from, long dir) const;
  SheetMesh
  BuildMesh();
  // The roll's spiral centre in the slice plane at height z (mm): the centroid line moved by
  // the tracer's offset.
  void
  RollCentre(double z, double xy[2]) const;

  const SheetVolumeView &                            volume;
  const SheetMidSurfaceParameters &                  parameters;
  SheetMidSurfaceReport &                            m_Report;
  const SheetMidSurfaceExtractor::ProgressCallback & progress;
  const size_t                                       nx, ny, nz;
  const double                                       sx, sy, sz;
  const double                                       voxel;
  std::vector<double>                                area;    // material per slice (mm^2)
  TraceContext                                       context; // air and material levels
  SheetSurfaceMethodEnum                             method{ SheetSurfaceMethodEnum::Roll };
  std::vector<Polyline>                              traces;  // per slice
  std::vector<double>                                lengths; // traced length per slice
  double                                             referenceLength{ 0.0 };
  std::vector<double>                                expectedLength;
  double                                             partialArea{ 0.0 };
  std::vector<char>                                  good; // well-traced slices
  long                                               firstGood{ -1 }, lastGood{ -1 };
  double                                             hs{ 0.0 }, hw{ 0.0 }; // grid spacings
  size_t                                             columns{ 0 };
  std::vector<Polyline>                              columnsOf; // per slice
  double rollCentreOffset[2]{ 0.0, 0.0 };                       // spiral centre relative to the centroid line (mm)
  long   seedCandidate{ -1 };                                   // RollTracing::Settings::SeedCandidate
};
} // namespace SheetTracing
} // end namespace itk

#endif

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
#ifndef itkDicomSeriesGeometry_h
#define itkDicomSeriesGeometry_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkProcessObject.h"

#include <string>
#include <vector>

namespace itk {
/** \class DicomSeriesGeometryEnums
 * \brief Enumerations of the DICOM series geometry, nested in a class the way ITK wraps them.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT DicomSeriesGeometryEnums
{
public:
  /** How an irregular series is interpolated onto its regular grid, in the plane of the
   * slices and between the two slices that bracket a voxel. */
  enum class Interpolator : uint8_t
  {
    /** The nearest pixel of the nearest slice. */
    NearestNeighbor,
    /** Bilinear in the slice plane, linear between the bracketing slices. */
    Linear,
    /** Cubic B-spline in the slices' index space: keeps fine detail (ink) that linear
     * interpolation blurs, may overshoot slightly at sharp edges. */
    BSpline
  };
};
/** Shorter name used throughout the module. */
using SliceInterpolatorEnum = DicomSeriesGeometryEnums::Interpolator;
VirtualUnwrapping_EXPORT const char *
ToString(SliceInterpolatorEnum interpolator);
/** "nearest", "linear" or "bspline"; throws itk::ExceptionObject on another name. */
VirtualUnwrapping_EXPORT SliceInterpolatorEnum
SliceInterpolatorFromString(const std::string & name);

/** The slices of one DICOM series as their headers place them: each slice's file and
 * ImagePositionPatient (centre of its first pixel, mm), and what all slices share:
 * ImageOrientationPatient (Row: direction of increasing column index, Column: direction
 * of increasing row index; unit vectors), pixel spacing along Row and Column (mm, > 0)
 * and the slice size in pixels (columns, rows). */
struct VirtualUnwrapping_EXPORT DicomSliceStack
{
  struct Slice
  {
    std::string      File;
    Point<double, 3> Position;
  };
  std::vector<Slice> Slices;
  Vector<double, 3>  Row{ 0.0 };
  Vector<double, 3>  Column{ 0.0 };
  double             PixelSpacing[2]{ 1.0, 1.0 };
  SizeValueType      Size[2]{ 0, 0 };
};

/** Slices [First, Last] (indices in slice order) that follow one another at one Spacing (mm). */
struct VirtualUnwrapping_EXPORT SliceSpacingRun
{
  size_t First{ 0 };
  size_t Last{ 0 };
  double Spacing{ 0.0 };
};

/** Slices missing between slice Before and the next one: a gap of Size mm where the
 * neighbouring slices are UsualSpacing apart, so Missing = round(Size / UsualSpacing) - 1. */
struct VirtualUnwrapping_EXPORT SliceGap
{
  size_t   Before{ 0 };
  double   Size{ 0.0 };
  double   UsualSpacing{ 0.0 };
  unsigned Missing{ 0 };
};

/** A regular voxel grid in the patient frame. */
struct VirtualUnwrapping_EXPORT RegularGrid
{
  using ImageType = Image<float, 3>;
  ImageType::PointType     Origin;
  ImageType::SpacingType   Spacing;
  ImageType::DirectionType Direction;
  ImageType::SizeType      Size{ { 0, 0, 0 } };
};

/** \class DicomSeriesGeometry
 * \brief What the slice positions of a DICOM series say about its geometry, and the
 * regular grid in the patient frame that holds it.
 *
 * AnalyseDicomSliceStack() orders the slices along the slice normal (Row x Column) and
 * measures, from the positions alone (GantryDetectorTilt is only compared with them):
 * - the location of each slice along the normal (Locations, first slice 0) and the shift
 *   of its origin in the slice plane from the first slice's (RowOffsets, ColumnOffsets):
 *   a tilted gantry or detector makes a sheared stack, whose origins drift in the plane;
 * - whether the slices lie on a regular grid: every slice within Tolerance x MeanSpacing
 *   of first + i x MeanSpacing (EvenlySpaced), and drift at most half a pixel (!Sheared);
 * - missing slices (Gaps): a gap of more than MissingSliceGapRatio (1.5) times the usual
 *   spacing, the median of up to two gaps on either side of it;
 * - runs of constant spacing (Runs): consecutive gaps within Tolerance of the run's
 *   spacing, gaps of missing slices excluded;
 * - the shear: least-squares drift of the origins per mm along the normal, as a tilt angle.
 *
 * MakeRegularGrid() and AppendSliceStackResampling() then give the grid that holds every
 * slice and the filter that fills it, with NaN for the voxels no slice covers.
 *
 * \ingroup VirtualUnwrapping
 */
struct VirtualUnwrapping_EXPORT DicomSeriesGeometry
{
  /** A gap of more than this many times the usual slice spacing holds missing slices. */
  static constexpr double MissingSliceGapRatio = 1.5;

  /** The slices, ordered along Normal. */
  DicomSliceStack     Stack;
  Vector<double, 3>   Normal{ 0.0 };
  double              Tolerance{ 0.05 };
  std::vector<double> Locations;
  std::vector<double> RowOffsets;
  std::vector<double> ColumnOffsets;

  /** (last - first location) / (slices - 1), mm. */
  double MeanSpacing{ 0.0 };
  bool   EvenlySpaced{ true };
  /** Largest distance of a slice from its place on the regular grid, mm, and that slice. */
  double                       WorstDeviation{ 0.0 };
  size_t                       WorstDeviationSlice{ 0 };
  std::vector<SliceSpacingRun> Runs;
  std::vector<SliceGap>        Gaps;

  bool Sheared{ false };
  /** Largest in-plane distance of a slice origin from the first one, mm, and that slice. */
  double MaximumDrift{ 0.0 };
  size_t MaximumDriftSlice{ 0 };
  /** Least-squares drift of the slice origins along Row and Column per mm along Normal. */
  double DriftPerMillimetre[2]{ 0.0, 0.0 };
  /** atan of the drift per mm, degrees (>= 0). */
  double TiltDegrees{ 0.0 };

  /** A regular, unsheared stack: it is a volume as it is. */
  bool
  IsRegular() const
  {
    return EvenlySpaced && !Sheared;
  }
  /** The smallest spacing of a run (the regular spacing of an evenly spaced stack). */
  double
  SmallestSpacing() const;
  /** Runs of different spacings (beyond Tolerance): the spacing changes within the series. */
  bool
  HasSpacingChanges() const;
  /** Missing slices in all gaps. */
  size_t
  NumberOfMissingSlices() const;
  /** "761.2 mm (FILE)": a slice's location along the normal (of its position, mm) and file. */
  std::string
  DescribeSlice(size_t slice) const;
  /** "0.1 mm from 12 mm (A) to 17 mm (B), 0.15 mm from ...": the spacing runs. */
  std::string
  DescribeRuns() const;
  /** "2 missing slice(s): a gap of 15 mm between ... and ..., usual spacing 5 mm". */
  std::string
  DescribeGap(const SliceGap & gap) const;
  /** "about 15 degrees, GantryDetectorTilt 15): slice origins drift ...": the shear. */
  std::string
  DescribeShear(const std::string & gantryTilt) const;
  /** The largest gap of missing slices, or nullptr. */
  const SliceGap *
  LargestGap() const;
  /** Why the stack is not a regular grid, on one line: the shear, the largest gap, the
   * spacing runs (whichever apply). gantryTilt: the GantryDetectorTilt value, or "". */
  std::string
  DescribeIrregularities(const std::string & gantryTilt) const;
  /** One warning per finding (shear, spacing change, each gap) and one for what the
   * resampling onto grid did (its size, spacing, interpolator and NaN voxels). */
  std::vector<std::string>
  DescribeCorrections(const std::string &   gantryTilt,
                      const RegularGrid &   grid,
                      SliceInterpolatorEnum interpolator,
                      SizeValueType         voxelsWithoutData) const;
};

/** Orders stack.Slices along the normal and measures the geometry (see
 * DicomSeriesGeometry); tolerance in (0, 0.5] is the fraction of a slice spacing by which
 * a slice may miss its place on a regular grid. Throws itk::ExceptionObject for fewer
 * than two slices, a degenerate orientation or two slices at one position. */
VirtualUnwrapping_EXPORT DicomSeriesGeometry
AnalyseDicomSliceStack(DicomSliceStack stack, double tolerance);


/** The grid that holds every slice of a stack: axes Row, Column, Normal; in the slice
 * plane the first slice's pixel lattice, extended to the smallest box that holds every
 * slice's pixels (the union of the sheared slices, as dcm2niix's tilt correction gives);
 * along the normal from the first slice to the last at sliceSpacing (> 0; the last grid
 * slice lies at most one spacing before the last slice). */
VirtualUnwrapping_EXPORT RegularGrid
MakeRegularGrid(const DicomSeriesGeometry & geometry, double sliceSpacing);

/** Voxels of grid that no slice covers (outside the slices' planes or extent, or in a
 * gap of missing slices): the voxels AppendSliceStackResampling() sets to NaN. */
VirtualUnwrapping_EXPORT SizeValueType
CountVoxelsWithoutData(const DicomSeriesGeometry & geometry, const RegularGrid & grid);

/** Appends to pipeline the filters that resample stack onto grid and returns their
 * output. stack holds the slices of geometry in its order, slice k at index k (as
 * ImageSeriesReader reads them; its origin, spacing and direction are ignored). Each
 * voxel is interpolated between the two slices that bracket it along the normal, at
 * the in-plane position given by their origins (interpolated between the two), so the
 * shear and the spacing come from the slice positions. Voxels no slice covers are NaN;
 * in a gap of missing slices only the grid slices within Tolerance x the usual spacing
 * of an acquired slice get values. itk::ResampleImageFilter does the work, so the
 * output is multithreaded, reports progress and streams (the whole stack is read). */
VirtualUnwrapping_EXPORT Image<float, 3> *
                         AppendSliceStackResampling(Image<float, 3> *                     stack,
                                                    const DicomSeriesGeometry &           geometry,
                                                    const RegularGrid &                   grid,
                                                    SliceInterpolatorEnum                 interpolator,
                                                    std::vector<ProcessObject::Pointer> & pipeline);
} // end namespace itk

#endif

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
#include "itkDicomSeriesGeometry.h"

#include "itkBSplineInterpolateImageFunction.h"
#include "itkChangeInformationImageFilter.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkResampleImageFilter.h"
#include "itkTransform.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace itk {
namespace {
using ImageType = Image<float, 3>;

/** A slice origin may drift this many pixels sideways before the stack is called sheared. */
constexpr double kShearPixels = 0.5;
/** Gaps on either side of a gap that give its usual spacing. */
constexpr size_t kSpacingNeighbours = 2;
/** Grid edges within this fraction of a pixel of a slice edge are not widened for it. */
constexpr double kGridSnap = 0.01;
/** Spacing runs named in a message before the rest are only counted. */
constexpr size_t kRunsNamed = 4;

[[noreturn]] void
Fail(const std::string & message)
{
  throw ExceptionObject(__FILE__, __LINE__, message, "AnalyseDicomSliceStack");
}

std::string
FormatMillimetres(double value)
{
  std::ostringstream text;
  text.precision(4);
  // Sums of spacings leave rounding residue where a slice lies at 0 mm.
  text << (std::abs(value) < 1e-9 ? 0.0 : value);
  return text.str();
}

double
Median(std::vector<double> values)
{
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/** Least-squares slope of y over x. */
double
Slope(const std::vector<double> & x, const std::vector<double> & y)
{
  const double n = static_cast<double>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double       sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < x.size(); ++i)
  {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0.0 ? sxy / sxx : 0.0;
}

/** Maps a point of the patient frame to the continuous index (column, row, slice) of the
 * stack of slices as read, through the slices' own positions: the slice coordinate is
 * interpolated between the two slices that bracket the point along the normal, and the
 * in-plane index is taken from their origins, interpolated the same way. A point no slice
 * covers (before the first, after the last, or in a gap of missing slices) maps to NaN,
 * which every interpolator reports as outside its image. */
class SliceStackTransform : public Transform<double, 3, 3>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(SliceStackTransform);

  using Self = SliceStackTransform;
  using Superclass = Transform<double, 3, 3>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  itkNewMacro(Self);
  itkTypeMacro(SliceStackTransform, Transform);

  void
  SetGeometry(const DicomSeriesGeometry & geometry)
  {
    m_First = geometry.Stack.Slices.front().Position;
    m_Row = geometry.Stack.Row;
    m_Column = geometry.Stack.Column;
    m_Normal = geometry.Normal;
    m_PixelSpacing[0] = geometry.Stack.PixelSpacing[0];
    m_PixelSpacing[1] = geometry.Stack.PixelSpacing[1];
    m_Locations = geometry.Locations;
    m_RowOffsets = geometry.RowOffsets;
    m_ColumnOffsets = geometry.ColumnOffsets;
    const size_t gaps = m_Locations.size() - 1;
    m_Snap.assign(gaps, 0.0);
    m_MissingAfter.assign(gaps, false);
    for (size_t k = 0; k < gaps; ++k)
    {
      m_Snap[k] = geometry.Tolerance * (m_Locations[k + 1] - m_Locations[k]);
    }
    for (const SliceGap & gap : geometry.Gaps)
    {
      m_MissingAfter[gap.Before] = true;
      m_Snap[gap.Before] = geometry.Tolerance * gap.UsualSpacing;
    }
    this->Modified();
  }

  /** The slice coordinate of a location along the normal, or NaN where no slice covers it. */
  double
  SliceCoordinate(double location) const
  {
    const size_t last = m_Locations.size() - 1;
    if (location <= 0.0)
    {
      return location >= -m_Snap.front() ? 0.0 : NaN();
    }
    if (location >= m_Locations.back())
    {
      return location <= m_Locations.back() + m_Snap.back() ? static_cast<double>(last) : NaN();
    }
    const size_t k =
      static_cast<size_t>(std::upper_bound(m_Locations.begin(), m_Locations.end(), location) - m_Locations.begin()) - 1;
    const double before = location - m_Locations[k], after = m_Locations[k + 1] - location;
    if (m_MissingAfter[k])
    {
      return before <= m_Snap[k] ? static_cast<double>(k) : after <= m_Snap[k] ? static_cast<double>(k + 1) : NaN();
    }
    return static_cast<double>(k) + before / (before + after);
  }

  OutputPointType
  TransformPoint(const InputPointType & point) const override
  {
    const Vector<double, 3> offset = point - m_First;
    const double            slice = this->SliceCoordinate(offset * m_Normal);
    OutputPointType         index;
    if (std::isnan(slice))
    {
      index.Fill(NaN());
      return index;
    }
    const size_t k0 = static_cast<size_t>(slice);
    const size_t k1 = std::min(k0 + 1, m_Locations.size() - 1);
    const double f = slice - static_cast<double>(k0);
    const double rowShift = m_RowOffsets[k0] + f * (m_RowOffsets[k1] - m_RowOffsets[k0]);
    const double columnShift = m_ColumnOffsets[k0] + f * (m_ColumnOffsets[k1] - m_ColumnOffsets[k0]);
    index[0] = (offset * m_Row - rowShift) / m_PixelSpacing[0];
    index[1] = (offset * m_Column - columnShift) / m_PixelSpacing[1];
    index[2] = slice;
    return index;
  }

  void
  SetParameters(const ParametersType &) override
  {}
  void
  SetFixedParameters(const FixedParametersType &) override
  {}
  void
  ComputeJacobianWithRespectToParameters(const InputPointType &, JacobianType &) const override
  {
    itkExceptionMacro(<< "a slice stack transform has no parameters");
  }

protected:
  SliceStackTransform()
    : Superclass(0)
  {}
  ~SliceStackTransform() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override
  {
    Superclass::PrintSelf(os, indent);
    os << indent << "First: " << m_First << std::endl;
    os << indent << "Row: " << m_Row << std::endl;
    os << indent << "Column: " << m_Column << std::endl;
    os << indent << "Normal: " << m_Normal << std::endl;
    os << indent << "Slices: " << m_Locations.size() << std::endl;
  }

private:
  static double
  NaN()
  {
    return std::numeric_limits<double>::quiet_NaN();
  }

  Point<double, 3>    m_First;
  Vector<double, 3>   m_Row{ 0.0 };
  Vector<double, 3>   m_Column{ 0.0 };
  Vector<double, 3>   m_Normal{ 0.0 };
  double              m_PixelSpacing[2]{ 1.0, 1.0 };
  std::vector<double> m_Locations;
  std::vector<double> m_RowOffsets;
  std::vector<double> m_ColumnOffsets;
  /** Per gap: how far outside a slice a location still takes that slice's values. */
  std::vector<double> m_Snap;
  std::vector<bool>   m_MissingAfter;
};

/** Gaps of missing slices: more than MissingSliceGapRatio times the median of the gaps
 * around them. */
std::vector<SliceGap>
FindMissingSlices(const std::vector<double> & gaps)
{
  std::vector<SliceGap> found;
  for (size_t i = 0; i < gaps.size(); ++i)
  {
    std::vector<double> neighbours;
    for (size_t j = i >= kSpacingNeighbours ? i - kSpacingNeighbours : 0;
         j <= std::min(i + kSpacingNeighbours, gaps.size() - 1);
         ++j)
    {
      if (j != i)
      {
        neighbours.push_back(gaps[j]);
      }
    }
    const double usual = neighbours.empty() ? gaps[i] : Median(neighbours);
    if (gaps[i] > DicomSeriesGeometry::MissingSliceGapRatio * usual)
    {
      SliceGap gap;
      gap.Before = i;
      gap.Size = gaps[i];
      gap.UsualSpacing = usual;
      gap.Missing = static_cast<unsigned>(std::max(1.0, std::round(gaps[i] / usual) - 1.0));
      found.push_back(gap);
    }
  }
  return found;
}
} // namespace

const char *
ToString(SliceInterpolatorEnum interpolator)
{
  switch (interpolator)
  {
    case SliceInterpolatorEnum::NearestNeighbor:
      return "nearest";
    case SliceInterpolatorEnum::BSpline:
      return "bspline";
    case SliceInterpolatorEnum::Linear:
      break;
  }
  return "linear";
}

SliceInterpolatorEnum
SliceInterpolatorFromString(const std::string & name)
{
  for (auto interpolator :
       { SliceInterpolatorEnum::NearestNeighbor, SliceInterpolatorEnum::Linear, SliceInterpolatorEnum::BSpline })
  {
    if (name == ToString(interpolator))
    {
      return interpolator;
    }
  }
  itkGenericExceptionMacro(<< "unknown slice interpolator \"" << name << "\" (nearest, linear or bspline)");
}

double
DicomSeriesGeometry::SmallestSpacing() const
{
  double smallest = MeanSpacing;
  for (const SliceSpacingRun & run : Runs)
  {
    smallest = std::min(smallest, run.Spacing);
  }
  return smallest;
}

bool
DicomSeriesGeometry::HasSpacingChanges() const
{
  const double smallest = this->SmallestSpacing();
  for (const SliceSpacingRun & run : Runs)
  {
    if (run.Spacing - smallest > Tolerance * smallest)
    {
      return true;
    }
  }
  return false;
}

size_t
DicomSeriesGeometry::NumberOfMissingSlices() const
{
  size_t missing = 0;
  for (const SliceGap & gap : Gaps)
  {
    missing += gap.Missing;
  }
  return missing;
}

std::string
DicomSeriesGeometry::DescribeSlice(size_t slice) const
{
  const double base = Stack.Slices.front().Position.GetVectorFromOrigin() * Normal;
  return FormatMillimetres(base + Locations[slice]) + " mm (" + Stack.Slices[slice].File + ")";
}

std::string
DicomSeriesGeometry::DescribeRuns() const
{
  std::string text;
  for (size_t r = 0; r < Runs.size() && r < kRunsNamed; ++r)
  {
    text += (r ? ", " : "") + FormatMillimetres(Runs[r].Spacing) + " mm from " + this->DescribeSlice(Runs[r].First) +
            " to " + this->DescribeSlice(Runs[r].Last);
  }
  if (Runs.size() > kRunsNamed)
  {
    text += " and " + std::to_string(Runs.size() - kRunsNamed) + " more runs";
  }
  return text;
}

std::string
DicomSeriesGeometry::DescribeGap(const SliceGap & gap) const
{
  return std::to_string(gap.Missing) + " missing slice(s): a gap of " + FormatMillimetres(gap.Size) + " mm between " +
         this->DescribeSlice(gap.Before) + " and " + this->DescribeSlice(gap.Before + 1) + ", usual spacing " +
         FormatMillimetres(gap.UsualSpacing) + " mm";
}

std::string
DicomSeriesGeometry::DescribeShear(const std::string & gantryTilt) const
{
  const char * axis = std::abs(DriftPerMillimetre[0]) > std::abs(DriftPerMillimetre[1]) ? "row" : "column";
  return "gantry/detector tilt of about " + FormatMillimetres(TiltDegrees) + " degrees" +
         (gantryTilt.empty() ? std::string() : ", GantryDetectorTilt " + gantryTilt) +
         "): slice origins drift sideways by up to " + FormatMillimetres(MaximumDrift) + " mm (" +
         Stack.Slices[MaximumDriftSlice].File + "), " +
         FormatMillimetres(std::hypot(DriftPerMillimetre[0], DriftPerMillimetre[1])) +
         " mm per mm along the normal, mostly along the " + axis + " direction";
}

const SliceGap *
DicomSeriesGeometry::LargestGap() const
{
  const SliceGap * largest = nullptr;
  for (const SliceGap & gap : Gaps)
  {
    largest = largest == nullptr || gap.Size > largest->Size ? &gap : largest;
  }
  return largest;
}

std::string
DicomSeriesGeometry::DescribeIrregularities(const std::string & gantryTilt) const
{
  std::vector<std::string> parts;
  if (Sheared)
  {
    parts.push_back("sheared slice stack (" + this->DescribeShear(gantryTilt) +
                    "; resample the series on a regular grid first");
  }
  if (const SliceGap * gap = this->LargestGap())
  {
    parts.push_back(this->DescribeGap(*gap) +
                    (Gaps.size() > 1 ? " (" + std::to_string(Gaps.size()) + " gaps in all)" : std::string()));
  }
  if (this->HasSpacingChanges() || (!EvenlySpaced && parts.empty()))
  {
    parts.push_back("non-uniform slice spacing: " + this->DescribeRuns());
  }
  std::string text;
  for (const std::string & part : parts)
  {
    text += (text.empty() ? "" : "; ") + part;
  }
  return text;
}

std::vector<std::string>
DicomSeriesGeometry::DescribeCorrections(const std::string &   gantryTilt,
                                         const RegularGrid &   grid,
                                         SliceInterpolatorEnum interpolator,
                                         SizeValueType         voxelsWithoutData) const
{
  std::vector<std::string> warnings;
  if (Sheared)
  {
    warnings.push_back("sheared slice stack (" + this->DescribeShear(gantryTilt) +
                       "; corrected: resampled onto a regular grid in the patient frame from the slice positions");
  }
  std::ostringstream text;
  text.precision(4);
  if (this->HasSpacingChanges())
  {
    text << "uneven slice spacing: " << this->DescribeRuns() << "; resampled to " << grid.Spacing[2] << " mm slices";
    warnings.push_back(text.str());
  }
  else if (!EvenlySpaced && Gaps.empty())
  {
    text << "irregular slice positions: " << this->DescribeSlice(WorstDeviationSlice) << " lies " << WorstDeviation
         << " mm from its place on a regular grid; resampled to " << grid.Spacing[2] << " mm slices";
    warnings.push_back(text.str());
  }
  for (const SliceGap & gap : Gaps)
  {
    warnings.push_back(this->DescribeGap(gap) + "; the voxels between them are NaN (no data)");
  }
  const auto &       size = grid.Size;
  std::ostringstream summary;
  summary.precision(4);
  summary << "resampled " << Stack.Slices.size() << " slices onto a regular grid of " << size[0] << " x " << size[1]
          << " x " << size[2] << " voxels of " << grid.Spacing[0] << " x " << grid.Spacing[1] << " x "
          << grid.Spacing[2] << " mm (" << ToString(interpolator) << " interpolation); " << voxelsWithoutData
          << " voxels ("
          << 100.0 * static_cast<double>(voxelsWithoutData) / static_cast<double>(size[0] * size[1] * size[2])
          << "%) that no slice covers are NaN";
  warnings.push_back(summary.str());
  return warnings;
}

DicomSeriesGeometry
AnalyseDicomSliceStack(DicomSliceStack stack, double tolerance)
{
  if (stack.Slices.size() < 2)
  {
    Fail("a stack of fewer than two slices has no slice geometry");
  }
  if (!(stack.PixelSpacing[0] > 0.0) || !(stack.PixelSpacing[1] > 0.0))
  {
    Fail("pixel spacing must be positive");
  }
  DicomSeriesGeometry geometry;
  geometry.Tolerance = tolerance;
  Vector<double, 3> normal = CrossProduct(stack.Row, stack.Column);
  if (normal.GetNorm() < 1e-6)
  {
    Fail(stack.Slices.front().File + " has a degenerate ImageOrientationPatient");
  }
  normal.Normalize();
  stack.Row.Normalize();
  stack.Column.Normalize();
  auto along = [&normal](const DicomSliceStack::Slice & s) { return s.Position.GetVectorFromOrigin() * normal; };
  std::stable_sort(
    stack.Slices.begin(),
    stack.Slices.end(),
    [&along](const DicomSliceStack::Slice & a, const DicomSliceStack::Slice & b) { return along(a) < along(b); });

  const size_t                   n = stack.Slices.size();
  const DicomSliceStack::Slice & first = stack.Slices.front();
  const double                   pixel = std::min(stack.PixelSpacing[0], stack.PixelSpacing[1]);
  std::vector<double>            gaps;
  for (size_t k = 0; k < n; ++k)
  {
    const Vector<double, 3> offset = stack.Slices[k].Position - first.Position;
    geometry.Locations.push_back(offset * normal);
    geometry.RowOffsets.push_back(offset * stack.Row);
    geometry.ColumnOffsets.push_back(offset * stack.Column);
    if (k > 0)
    {
      gaps.push_back(geometry.Locations[k] - geometry.Locations[k - 1]);
      if (gaps.back() <= std::min(1e-3, 0.01 * pixel))
      {
        Fail("duplicate slice position (" + FormatMillimetres(along(stack.Slices[k])) + " mm along the normal) in " +
             stack.Slices[k - 1].File + " and " + stack.Slices[k].File);
      }
    }
    const double drift = (offset - normal * geometry.Locations[k]).GetNorm();
    if (drift > geometry.MaximumDrift)
    {
      geometry.MaximumDrift = drift;
      geometry.MaximumDriftSlice = k;
    }
  }
  geometry.Stack = std::move(stack);
  geometry.Normal = normal;

  // A tilted gantry shifts each slice sideways: the stack is sheared, not a box. Half a
  // pixel of drift over the whole stack is what still reads as one.
  geometry.Sheared = geometry.MaximumDrift > kShearPixels * pixel;
  geometry.DriftPerMillimetre[0] = Slope(geometry.Locations, geometry.RowOffsets);
  geometry.DriftPerMillimetre[1] = Slope(geometry.Locations, geometry.ColumnOffsets);
  geometry.TiltDegrees =
    std::atan(std::hypot(geometry.DriftPerMillimetre[0], geometry.DriftPerMillimetre[1])) * 180.0 / Math::pi;

  // Headers often round positions to 0.1 mm: a slice within the tolerance of its place
  // on the regular grid (first + i x mean spacing) is on it.
  geometry.MeanSpacing = geometry.Locations.back() / static_cast<double>(n - 1);
  for (size_t k = 0; k < n; ++k)
  {
    const double deviation = std::abs(geometry.Locations[k] - static_cast<double>(k) * geometry.MeanSpacing);
    if (deviation > geometry.WorstDeviation)
    {
      geometry.WorstDeviation = deviation;
      geometry.WorstDeviationSlice = k;
    }
  }
  geometry.EvenlySpaced = geometry.WorstDeviation <= tolerance * geometry.MeanSpacing;
  if (geometry.EvenlySpaced)
  {
    geometry.Runs.push_back({ 0, n - 1, geometry.MeanSpacing });
    return geometry;
  }

  geometry.Gaps = FindMissingSlices(gaps);
  std::vector<bool> missingAfter(gaps.size(), false);
  for (const SliceGap & gap : geometry.Gaps)
  {
    missingAfter[gap.Before] = true;
  }
  // Runs of constant spacing: a gap joins the run while it stays within the tolerance of
  // the run's mean spacing so far; a gap of missing slices ends the run.
  size_t runStart = 0;
  auto   closeRun = [&](size_t last) {
    if (last > runStart)
    {
      geometry.Runs.push_back(
        { runStart,
          last,
          (geometry.Locations[last] - geometry.Locations[runStart]) / static_cast<double>(last - runStart) });
    }
  };
  for (size_t i = 0; i < gaps.size(); ++i)
  {
    if (missingAfter[i])
    {
      closeRun(i);
      runStart = i + 1;
      continue;
    }
    if (i > runStart)
    {
      const double runSpacing =
        (geometry.Locations[i] - geometry.Locations[runStart]) / static_cast<double>(i - runStart);
      if (std::abs(gaps[i] - runSpacing) > tolerance * runSpacing)
      {
        closeRun(i);
        runStart = i;
      }
    }
  }
  closeRun(n - 1);
  return geometry;
}

RegularGrid
MakeRegularGrid(const DicomSeriesGeometry & geometry, double sliceSpacing)
{
  if (!(sliceSpacing > 0.0) || !std::isfinite(sliceSpacing))
  {
    itkGenericExceptionMacro(<< "the slice spacing of a regular grid must be positive, not " << sliceSpacing);
  }
  const DicomSliceStack & stack = geometry.Stack;
  RegularGrid             grid;
  double                  first[2], last[2];
  for (unsigned axis = 0; axis < 2; ++axis)
  {
    const std::vector<double> & offsets = axis == 0 ? geometry.RowOffsets : geometry.ColumnOffsets;
    const auto [low, high] = std::minmax_element(offsets.begin(), offsets.end());
    first[axis] = std::floor(*low / stack.PixelSpacing[axis] + kGridSnap);
    last[axis] = std::ceil(*high / stack.PixelSpacing[axis] - kGridSnap) + static_cast<double>(stack.Size[axis]) - 1.0;
    grid.Size[axis] = static_cast<SizeValueType>(last[axis] - first[axis]) + 1;
    grid.Spacing[axis] = stack.PixelSpacing[axis];
  }
  grid.Size[2] = static_cast<SizeValueType>(std::floor(geometry.Locations.back() / sliceSpacing + kGridSnap)) + 1;
  grid.Spacing[2] = sliceSpacing;
  for (unsigned k = 0; k < 3; ++k)
  {
    grid.Origin[k] = stack.Slices.front().Position[k] + first[0] * stack.PixelSpacing[0] * stack.Row[k] +
                     first[1] * stack.PixelSpacing[1] * stack.Column[k];
    grid.Direction[k][0] = stack.Row[k];
    grid.Direction[k][1] = stack.Column[k];
    grid.Direction[k][2] = geometry.Normal[k];
  }
  return grid;
}

SizeValueType
CountVoxelsWithoutData(const DicomSeriesGeometry & geometry, const RegularGrid & grid)
{
  auto transform = SliceStackTransform::New();
  transform->SetGeometry(geometry);
  // The grid's points are computed as ResampleImageFilter computes them, so that a voxel
  // whose centre falls on the edge of a slice counts as the filter decides.
  auto image = ImageType::New();
  image->SetOrigin(grid.Origin);
  image->SetSpacing(grid.Spacing);
  image->SetDirection(grid.Direction);
  const SizeValueType perSlice = grid.Size[0] * grid.Size[1];
  SizeValueType       without = 0;
  for (SizeValueType z = 0; z < grid.Size[2]; ++z)
  {
    // The grid's axes are the slices' axes: whether a voxel has data depends on its
    // column alone in one direction and on its row alone in the other.
    SizeValueType inside[2] = { 0, 0 };
    bool          covered = true;
    for (unsigned axis = 0; axis < 2 && covered; ++axis)
    {
      for (SizeValueType g = 0; g < grid.Size[axis]; ++g)
      {
        ImageType::IndexType index{ { 0, 0, static_cast<IndexValueType>(z) } };
        index[axis] = static_cast<IndexValueType>(g);
        ImageType::PointType point;
        image->TransformIndexToPhysicalPoint(index, point);
        const auto sliceIndex = transform->TransformPoint(point);
        if (std::isnan(sliceIndex[2]))
        {
          covered = false;
          break;
        }
        const double size = static_cast<double>(geometry.Stack.Size[axis]);
        inside[axis] += sliceIndex[axis] >= -0.5 && sliceIndex[axis] < size - 0.5 ? 1 : 0;
      }
    }
    without += covered ? perSlice - inside[0] * inside[1] : perSlice;
  }
  return without;
}

Image<float, 3> *
AppendSliceStackResampling(Image<float, 3> *                     stack,
                           const DicomSeriesGeometry &           geometry,
                           const RegularGrid &                   grid,
                           SliceInterpolatorEnum                 interpolator,
                           std::vector<ProcessObject::Pointer> & pipeline)
{
  // The transform maps to the stack's indices: the stack is given the unit geometry, in
  // which a physical point is its index.
  auto unit = ChangeInformationImageFilter<ImageType>::New();
  unit->SetInput(stack);
  unit->SetOutputOrigin(ImageType::PointType());
  ImageType::SpacingType one;
  one.Fill(1.0);
  unit->SetOutputSpacing(one);
  unit->SetOutputDirection(ImageType::DirectionType::GetIdentity());
  unit->ChangeOriginOn();
  unit->ChangeSpacingOn();
  unit->ChangeDirectionOn();

  auto transform = SliceStackTransform::New();
  transform->SetGeometry(geometry);
  auto resample = ResampleImageFilter<ImageType, ImageType, double, double>::New();
  resample->SetInput(unit->GetOutput());
  resample->SetTransform(transform);
  switch (interpolator)
  {
    case SliceInterpolatorEnum::NearestNeighbor:
      resample->SetInterpolator(NearestNeighborInterpolateImageFunction<ImageType, double>::New());
      break;
    case SliceInterpolatorEnum::Linear:
      resample->SetInterpolator(LinearInterpolateImageFunction<ImageType, double>::New());
      break;
    case SliceInterpolatorEnum::BSpline:
    {
      auto bspline = BSplineInterpolateImageFunction<ImageType, double, float>::New();
      bspline->SetSplineOrder(3);
      resample->SetInterpolator(bspline);
      break;
    }
  }
  resample->SetDefaultPixelValue(std::numeric_limits<float>::quiet_NaN());
  resample->SetOutputOrigin(grid.Origin);
  resample->SetOutputSpacing(grid.Spacing);
  resample->SetOutputDirection(grid.Direction);
  resample->SetSize(grid.Size);
  pipeline.push_back(unit.GetPointer());
  pipeline.push_back(resample.GetPointer());
  return resample->GetOutput();
}
} // end namespace itk

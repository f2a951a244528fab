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

#include "vuMedian.h"
#include "vuRollTracer.h"

#include "itkBinaryThinningImageFilter.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkImage.h"
#include "itkMacro.h"
#include "itkMultiThreaderBase.h"
#include "itkRelabelComponentImageFilter.h"

#include <algorithm>
#include <cmath>
#include <deque>
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

SheetIntensityLevels
EstimateSheetIntensityLevels(std::vector<float> air, std::vector<float> material)
{
  SheetIntensityLevels levels;
  if (!air.empty())
  {
    const float floor = *std::min_element(air.begin(), air.end());
    air.erase(std::remove(air.begin(), air.end(), floor), air.end());
  }
  auto at = [](std::vector<float> & values, double fraction) {
    const auto i = values.begin() + static_cast<std::ptrdiff_t>(fraction * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), i, values.end());
    return static_cast<double>(*i);
  };
  if (air.size() >= 16 && !material.empty())
  {
    levels.Air = at(air, 0.5);
    levels.Noise = levels.Air - at(air, 0.1587);
    levels.Sheet = at(material, 0.5);
  }
  return levels;
}

namespace {
constexpr double Pi = 3.14159265358979323846;
// Sideways step of the finished mesh, as a fraction of the turn spacing, reported as a
// possible layer jump: a jump onto the next turn steps by about a whole turn spacing, while
// the sharpest bend of a correct mesh (the innermost curl, a trace's end) stayed below 0.55
// on the stress family's scans.
constexpr double GridStepFraction = 0.7;

// A planar curve as x, y pairs (mm).
using Polyline = std::vector<double>;

using RollTracing::Median;

double
Percentile(std::vector<double> values, double fraction)
{
  if (values.empty())
  {
    return 0.0;
  }
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(fraction * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

size_t
PolylineSize(const Polyline & line)
{
  return line.size() / 2;
}

double
ArcLength(const Polyline & line)
{
  double length = 0.0;
  for (size_t i = 1; i < PolylineSize(line); ++i)
  {
    length += std::hypot(line[2 * i] - line[2 * i - 2], line[2 * i + 1] - line[2 * i - 1]);
  }
  return length;
}

// Moving average whose window shrinks symmetrically near the ends, so the ends stay put.
Polyline
Smooth(const Polyline & line, int halfWidth)
{
  const auto n = static_cast<int>(PolylineSize(line));
  Polyline   out(line.size());
  for (int i = 0; i < n; ++i)
  {
    const int h = std::min({ halfWidth, i, n - 1 - i });
    double    x = 0.0, y = 0.0;
    for (int j = i - h; j <= i + h; ++j)
    {
      x += line[2 * j];
      y += line[2 * j + 1];
    }
    out[2 * i] = x / (2 * h + 1);
    out[2 * i + 1] = y / (2 * h + 1);
  }
  return out;
}

// n points evenly spaced in arc length from the first to the last point.
Polyline
ResampleEvenly(const Polyline & line, size_t n)
{
  const size_t        m = PolylineSize(line);
  std::vector<double> cumulative(m, 0.0);
  for (size_t i = 1; i < m; ++i)
  {
    cumulative[i] = cumulative[i - 1] + std::hypot(line[2 * i] - line[2 * i - 2], line[2 * i + 1] - line[2 * i - 1]);
  }
  Polyline out(2 * n);
  size_t   segment = 1;
  for (size_t c = 0; c < n; ++c)
  {
    const double s = cumulative.back() * static_cast<double>(c) / static_cast<double>(n - 1);
    while (segment + 1 < m && cumulative[segment] < s)
    {
      ++segment;
    }
    const double length = cumulative[segment] - cumulative[segment - 1];
    const double t = length > 0.0 ? std::clamp((s - cumulative[segment - 1]) / length, 0.0, 1.0) : 0.0;
    for (int d = 0; d < 2; ++d)
    {
      out[2 * c + d] = (1.0 - t) * line[2 * (segment - 1) + d] + t * line[2 * segment + d];
    }
  }
  return out;
}

// Points at the given arc lengths along a polyline; beyond its ends, along the end segments.
Polyline
SampleAtArcLengths(const Polyline & line, const std::vector<double> & arcs)
{
  const size_t        m = PolylineSize(line);
  std::vector<double> cumulative(m, 0.0);
  for (size_t i = 1; i < m; ++i)
  {
    cumulative[i] = cumulative[i - 1] + std::hypot(line[2 * i] - line[2 * i - 2], line[2 * i + 1] - line[2 * i - 1]);
  }
  Polyline out(2 * arcs.size());
  for (size_t c = 0; c < arcs.size(); ++c)
  {
    const double s = arcs[c];
    const size_t segment = std::clamp<size_t>(
      static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), s) - cumulative.begin()), 1, m - 1);
    const double length = cumulative[segment] - cumulative[segment - 1];
    const double t = length > 0.0 ? (s - cumulative[segment - 1]) / length : 0.0;
    for (int d = 0; d < 2; ++d)
    {
      out[2 * c + d] = (1.0 - t) * line[2 * (segment - 1) + d] + t * line[2 * segment + d];
    }
  }
  return out;
}

// Increasing arc lengths brought within [0, length]: the columns that fall beyond an end
// are spread evenly between that end and the first column inside, so that no column is
// placed on the straight continuation of an end segment (off the sheet where it curves,
// as a roll's inner end does) and no two columns coincide.
std::vector<double>
KeepWithinTrace(std::vector<double> arcs, double length)
{
  const size_t n = arcs.size();
  if (n < 2 || !(length > 0.0))
  {
    return arcs;
  }
  // Fewer than two columns inside (a fit far off): the columns at even fractions instead.
  const auto even = [&] {
    for (size_t c = 0; c < n; ++c)
    {
      arcs[c] = length * static_cast<double>(c) / static_cast<double>(n - 1);
    }
    return arcs;
  };
  size_t first = 0;
  while (first < n && arcs[first] < 0.0)
  {
    ++first;
  }
  size_t last = n;
  while (last > first && arcs[last - 1] > length)
  {
    --last;
  }
  if (last - first < 2)
  {
    return even();
  }
  for (size_t c = 0; c < first; ++c)
  {
    arcs[c] = arcs[first] * static_cast<double>(c) / static_cast<double>(first);
  }
  const size_t beyond = n - last;
  for (size_t c = 1; c <= beyond; ++c)
  {
    arcs[last - 1 + c] =
      arcs[last - 1] + (length - arcs[last - 1]) * static_cast<double>(c) / static_cast<double>(beyond);
  }
  return arcs;
}

// Bilinear sampling of one slice of the volume, in mm of the view's frame.
class SliceSampler
{
public:
  SliceSampler(const SheetVolumeView & volume, size_t slice)
    : m_NX(volume.Size[0])
    , m_NY(volume.Size[1])
    , m_SX(volume.Spacing[0])
    , m_SY(volume.Spacing[1])
  {
    const size_t offset = slice * m_NX * m_NY;
    m_Mask = volume.Mask + offset;
    m_Intensity = volume.Intensity != nullptr ? volume.Intensity + offset : nullptr;
  }

  bool
  HasIntensity() const
  {
    return m_Intensity != nullptr;
  }

  // Fraction of material; 0 outside the slice.
  double
  Mask(double x, double y) const
  {
    return Interpolate(
      x, y, [this](size_t i) { return m_Mask[i] != 0 ? 1.0 : 0.0; }, 0.0);
  }

  double
  Intensity(double x, double y, double outside) const
  {
    return Interpolate(
      x, y, [this](size_t i) { return static_cast<double>(m_Intensity[i]); }, outside);
  }

  size_t
  CountMaterial() const
  {
    return static_cast<size_t>(std::count_if(m_Mask, m_Mask + m_NX * m_NY, [](uint8_t v) { return v != 0; }));
  }

  size_t
  NX() const
  {
    return m_NX;
  }
  size_t
  NY() const
  {
    return m_NY;
  }
  const uint8_t *
  MaskPointer() const
  {
    return m_Mask;
  }

private:
  template <typename TValue>
  double
  Interpolate(double x, double y, const TValue & value, double outside) const
  {
    const double u = x / m_SX, v = y / m_SY;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto   i0 = static_cast<long>(fu), j0 = static_cast<long>(fv);
    const double a = u - fu, b = v - fv;
    double       result = 0.0;
    for (int dj = 0; dj < 2; ++dj)
    {
      for (int di = 0; di < 2; ++di)
      {
        const long   i = i0 + di, j = j0 + dj;
        const double weight = (di != 0 ? a : 1.0 - a) * (dj != 0 ? b : 1.0 - b);
        const bool   inside = i >= 0 && j >= 0 && i < static_cast<long>(m_NX) && j < static_cast<long>(m_NY);
        result += weight * (inside ? value(static_cast<size_t>(j) * m_NX + static_cast<size_t>(i)) : outside);
      }
    }
    return result;
  }

  const uint8_t * m_Mask{ nullptr };
  const float *   m_Intensity{ nullptr };
  size_t          m_NX, m_NY;
  double          m_SX, m_SY;
};

// What every slice tracer needs besides its slice.
struct TraceContext
{
  double Voxel{ 1.0 };      // in-plane voxel size
  double Base{ 0.0 };       // intensity halfway between air and material
  double AirLevel{ 0.0 };   // intensity outside the volume
  double SheetLevel{ 1.0 }; // intensity of the sheet's material
  double Centre[2]{ 0, 0 }; // roll axis in this slice
};

// Weighted centroid of the sheet along a line p + u n, u in [lo, hi]: intensity above the
// air/material midpoint when available (sub-voxel middle of the sheet), else the mask.
double
CentreAlongLine(const SliceSampler & sampler,
                const TraceContext & context,
                const double         p[2],
                const double         n[2],
                double               lo,
                double               hi,
                double               step)
{
  double sum = 0.0, moment = 0.0;
  for (double u = lo; u <= hi + 1e-12; u += step)
  {
    const double x = p[0] + u * n[0], y = p[1] + u * n[1];
    const double weight = sampler.HasIntensity()
                            ? std::max(0.0, sampler.Intensity(x, y, context.AirLevel) - context.Base)
                            : sampler.Mask(x, y);
    sum += weight;
    moment += weight * u;
  }
  return sum > 0.0 ? moment / sum : 0.5 * (lo + hi);
}

// General tracer for one slice: longest path of the skeleton of the largest component.
Polyline
TraceGeneralSlice(const SliceSampler & sampler, const TraceContext & context, double spacingY)
{
  using SliceImage = Image<uint8_t, 2>;
  using LabelImage = Image<uint32_t, 2>;
  auto                   slice = SliceImage::New();
  SliceImage::RegionType region;
  region.SetSize({ { sampler.NX(), sampler.NY() } });
  slice->SetRegions(region);
  slice->Allocate();
  std::transform(sampler.MaskPointer(),
                 sampler.MaskPointer() + sampler.NX() * sampler.NY(),
                 slice->GetBufferPointer(),
                 [](uint8_t v) { return static_cast<uint8_t>(v != 0 ? 1 : 0); });
  auto components = ConnectedComponentImageFilter<SliceImage, LabelImage>::New();
  components->SetInput(slice);
  components->FullyConnectedOn();
  components->SetNumberOfWorkUnits(1);
  auto relabel = RelabelComponentImageFilter<LabelImage, LabelImage>::New();
  relabel->SetInput(components->GetOutput());
  relabel->SetNumberOfWorkUnits(1);
  relabel->Update();
  const uint32_t * labels = relabel->GetOutput()->GetBufferPointer();
  uint8_t *        pixels = slice->GetBufferPointer();
  for (size_t i = 0; i < sampler.NX() * sampler.NY(); ++i)
  {
    pixels[i] = labels[i] == 1 ? 1 : 0;
  }
  auto thinning = BinaryThinningImageFilter<SliceImage, SliceImage>::New();
  thinning->SetInput(slice);
  thinning->SetNumberOfWorkUnits(1);
  thinning->Update();
  const uint8_t * skeleton = thinning->GetOutput()->GetBufferPointer();

  const auto nx = static_cast<long>(sampler.NX()), ny = static_cast<long>(sampler.NY());
  // Breadth-first distances over the 8-connected skeleton; the farthest pixel from any
  // pixel is an end of the longest path, and the farthest from that end the other end.
  std::vector<long> parent(static_cast<size_t>(nx * ny), -1);
  auto              farthest = [&](long from) {
    std::vector<int> distance(static_cast<size_t>(nx * ny), -1);
    std::deque<long> queue{ from };
    distance[static_cast<size_t>(from)] = 0;
    parent[static_cast<size_t>(from)] = -1;
    long last = from;
    while (!queue.empty())
    {
      const long p = queue.front();
      queue.pop_front();
      last = p;
      const long px = p % nx, py = p / nx;
      for (long dy = -1; dy <= 1; ++dy)
      {
        for (long dx = -1; dx <= 1; ++dx)
        {
          const long qx = px + dx, qy = py + dy;
          if ((dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= nx || qy >= ny)
          {
            continue;
          }
          const long q = qy * nx + qx;
          if (skeleton[q] != 0 && distance[static_cast<size_t>(q)] < 0)
          {
            distance[static_cast<size_t>(q)] = distance[static_cast<size_t>(p)] + 1;
            parent[static_cast<size_t>(q)] = p;
            queue.push_back(q);
          }
        }
      }
    }
    return last;
  };
  long seed = -1;
  for (long p = 0; p < nx * ny && seed < 0; ++p)
  {
    if (skeleton[p] != 0)
    {
      seed = p;
    }
  }
  if (seed < 0)
  {
    return {};
  }
  const long end = farthest(farthest(seed));
  Polyline   line;
  for (long p = end; p >= 0; p = parent[static_cast<size_t>(p)])
  {
    line.push_back(static_cast<double>(p % nx) * context.Voxel);
    line.push_back(static_cast<double>(p / nx) * spacingY);
  }
  if (PolylineSize(line) < 3)
  {
    return {};
  }
  line = Smooth(line, 3);

  // Move each point to the middle of the sheet along the curve's normal.
  const double thickness = static_cast<double>(sampler.CountMaterial()) * context.Voxel * spacingY / ArcLength(line);
  const double reach = 0.5 * thickness + context.Voxel;
  Polyline     refined(line);
  const size_t n = PolylineSize(line);
  for (size_t i = 0; i < n; ++i)
  {
    const size_t a = i > 0 ? i - 1 : i, b = i + 1 < n ? i + 1 : i;
    double       tx = line[2 * b] - line[2 * a], ty = line[2 * b + 1] - line[2 * a + 1];
    const double norm = std::hypot(tx, ty);
    if (norm <= 0.0)
    {
      continue;
    }
    const double normal[2] = { -ty / norm, tx / norm };
    const double point[2] = { line[2 * i], line[2 * i + 1] };
    const double shift =
      std::clamp(CentreAlongLine(sampler, context, point, normal, -reach, reach, 0.25 * context.Voxel),
                 -0.5 * thickness,
                 0.5 * thickness);
    refined[2 * i] += shift * normal[0];
    refined[2 * i + 1] += shift * normal[1];
  }
  refined = Smooth(refined, 2);
  RollTracing::ExtendEnds(
    refined,
    [&](double x, double y) { return sampler.Mask(x, y) >= 0.5; },
    context.Voxel,
    2.0 * thickness + 2.0 * context.Voxel);
  return refined;
}

// Circumradius of three points.
double
Circumradius(const double a[2], const double b[2], const double c[2])
{
  const double ab = std::hypot(b[0] - a[0], b[1] - a[1]);
  const double bc = std::hypot(c[0] - b[0], c[1] - b[1]);
  const double ca = std::hypot(a[0] - c[0], a[1] - c[1]);
  const double cross = std::abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
  return cross > 0.0 ? ab * bc * ca / (2.0 * cross) : std::numeric_limits<double>::infinity();
}
// Slices at most by which the mesh reaches past the last well-traced slice along the axis.
constexpr long EdgeSlices = 8;

// Weighted median of values (pairs of value and weight; reordered).
double
WeightedMedian(std::vector<std::pair<double, double>> & values)
{
  std::sort(values.begin(), values.end());
  double total = 0.0;
  for (const auto & v : values)
  {
    total += v.second;
  }
  double running = 0.0;
  for (const auto & v : values)
  {
    running += v.second;
    if (running >= 0.5 * total)
    {
      return v.first;
    }
  }
  return values.back().first;
}

// Point of column c of a grid row from the slices of its window (slice, weight): the
// weighted mean of the slices' points within `agreement` of their weighted median point
// (the median alone where none is).
void
RobustRowPoint(const std::vector<std::pair<long, double>> & window,
               const std::vector<Polyline> &                columnsOf,
               size_t                                       c,
               double                                       agreement,
               double                                       point[2])
{
  std::vector<std::pair<double, double>> values;
  values.reserve(window.size());
  double median[2];
  for (int axis = 0; axis < 2; ++axis)
  {
    values.clear();
    for (const auto & [k, weight] : window)
    {
      values.emplace_back(columnsOf[static_cast<size_t>(k)][2 * c + static_cast<size_t>(axis)], weight);
    }
    median[axis] = WeightedMedian(values);
  }
  double sum[2] = { 0.0, 0.0 }, weightSum = 0.0;
  for (const auto & [k, weight] : window)
  {
    const double * p = &columnsOf[static_cast<size_t>(k)][2 * c];
    if (std::hypot(p[0] - median[0], p[1] - median[1]) <= agreement)
    {
      sum[0] += weight * p[0];
      sum[1] += weight * p[1];
      weightSum += weight;
    }
  }
  point[0] = weightSum > 0.0 ? sum[0] / weightSum : median[0];
  point[1] = weightSum > 0.0 ? sum[1] / weightSum : median[1];
}

} // namespace

SheetMesh
SheetMidSurfaceExtractor::Extract(const SheetVolumeView & volume)
{
  m_Report = SheetMidSurfaceReport{};
  const SheetMidSurfaceParameters & parameters = m_Parameters;
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
  const size_t nx = volume.Size[0], ny = volume.Size[1], nz = volume.Size[2];
  const double sx = volume.Spacing[0], sy = volume.Spacing[1], sz = volume.Spacing[2];
  const double voxel = std::min(sx, sy);
  if (std::abs(sx - sy) > 1e-6 * voxel)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: in-plane voxels must be square (spacing " << sx << " x "
                             << sy << "); resample the volume first");
  }
  auto report = [this](double fraction) {
    if (m_Progress && !m_Progress(fraction))
    {
      itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: aborted");
    }
  };

  // Per-slice material and centroids; the roll axis is the line through the centroids.
  std::vector<double> area(nz, 0.0), centroidX(nz, 0.0), centroidY(nz, 0.0);
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

  TraceContext context;
  context.Voxel = voxel;
  if (volume.Intensity != nullptr)
  {
    // Air and material levels: medians of a sample of the voxels outside and inside the mask.
    std::vector<double> outside, inside;
    const size_t        total = nx * ny * nz;
    const size_t        stride = std::max<size_t>(1, total / 400000);
    for (size_t i = 0; i < total; i += stride)
    {
      (volume.Mask[i] != 0 ? inside : outside).push_back(volume.Intensity[i]);
    }
    context.AirLevel = Median(outside);
    context.SheetLevel = Median(inside);
    context.Base = 0.5 * (context.AirLevel + context.SheetLevel);
  }

  std::vector<Polyline> traces(nz);
  auto                  traceGeneral = [&](double progressStart, double progressEnd) {
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

  SheetSurfaceMethodEnum method = parameters.Method;
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
    const double rollShare = method == SheetSurfaceMethodEnum::Auto ? 0.4 : 0.8;
    const auto   roll = RollTracing::TraceRoll(volume,
                                             volume.Intensity != nullptr ? volume.Intensity : maskValues.data(),
                                             settings,
                                             [&](double fraction) { report(rollShare * fraction); });
    if (method == SheetSurfaceMethodEnum::Auto)
    {
      method = roll.Rolled ? SheetSurfaceMethodEnum::Roll : SheetSurfaceMethodEnum::General;
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
      m_Report.Turns = roll.Slices[nz / 2].Turns;
      if (roll.Incomplete > 0)
      {
        std::ostringstream text;
        text << roll.Incomplete
             << " slice(s) traced only in part (their trace ends far from the other slices' ends: the sheet's edge "
                "along the axis, or a trace lost before the end) were left out or interpolated";
        m_Report.Warnings.push_back(text.str());
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

  std::vector<double> lengths(nz, 0.0), traced;
  for (size_t k = 0; k < nz; ++k)
  {
    if (PolylineSize(traces[k]) >= 2)
    {
      lengths[k] = ArcLength(traces[k]);
      traced.push_back(lengths[k]);
    }
  }
  if (traced.empty())
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: no slice of the mask could be traced as a sheet");
  }
  const double referenceLength = Median(traced);
  if (referenceLength < 2.0 * voxel)
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: the traced sheet is only " << referenceLength
                             << " mm long, less than two voxels");
  }
  // Slices whose traced length is close to the median (for a roll: the median of the
  // slices within five of it, since a roll's radius may change along its axis); the others
  // (cut short, or with a wrong turn) are interpolated from their neighbours.
  std::vector<double> expectedLength(nz, referenceLength);
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
  std::vector<double> areas;
  for (size_t k = 0; k < nz; ++k)
  {
    if (lengths[k] > 0.0)
    {
      areas.push_back(area[k]);
    }
  }
  const double      partialArea = 0.75 * Median(areas);
  std::vector<char> good(nz, 0);
  long              firstGood = -1, lastGood = -1;
  auto              selectGood = [&](double tolerance) {
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
  };
  selectGood(0.05 * referenceLength + 3.0 * voxel);
  if (method == SheetSurfaceMethodEnum::General)
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

  // Thickness and the smallest radius of curvature, from the well-traced slices.
  std::vector<double> thicknesses, radii;
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
  }
  m_Report.SheetThickness = Median(thicknesses);
  m_Report.SheetLength = referenceLength;
  m_Report.MinimumCurvatureRadius = radii.empty() ? referenceLength : Percentile(radii, 0.05);
  if (!std::isfinite(m_Report.MinimumCurvatureRadius))
  {
    m_Report.MinimumCurvatureRadius = referenceLength;
  }
  const double automatic = std::max(
    voxel, std::sqrt(8.0 * m_Report.MinimumCurvatureRadius * parameters.ChordErrorFraction * m_Report.SheetThickness));
  const double hs = parameters.SpacingAlongSheet > 0.0 ? parameters.SpacingAlongSheet : automatic;
  double       hw = parameters.SpacingAlongAxis > 0.0 ? parameters.SpacingAlongAxis : std::max(hs, sz);

  // A slice shorter or longer than the median by a sizeable part of a column would shear
  // the grid: the columns sit at the same fraction of every slice's length.
  // (The roll tracer has already matched each slice's ends to its neighbours'.)
  if (method == SheetSurfaceMethodEnum::General)
  {
    selectGood(std::min(0.05 * referenceLength, std::max(0.25 * hs, 2.0 * voxel)) + voxel);
  }

  const auto columns = static_cast<size_t>(std::max(2.0, std::ceil(referenceLength / hs) + 1.0));
  if (columns * (static_cast<size_t>((lastGood - firstGood) * sz / hw) + 2) > (size_t{ 1 } << 31))
  {
    itkGenericExceptionMacro(<< "SheetMidSurfaceExtractor: mesh spacing " << hs << " x " << hw
                             << " mm gives more than 2^31 points");
  }
  // Columns at the same fraction of each slice's traced length; failed slices in between
  // are interpolated from the nearest good ones.
  std::vector<Polyline> columnsOf(nz);
  for (long k = firstGood; k <= lastGood; ++k)
  {
    if (good[k])
    {
      columnsOf[k] = ResampleEvenly(traces[k], columns);
    }
  }
  // The traced ends of a slice jitter by a fraction of a voxel, which shifts its columns
  // along the sheet and makes the grid slightly non-developable (the flattener then has to
  // strain or crease it). Align every good slice along the sheet to the mean of its good
  // neighbours within five slices: the tangential offsets of its columns are fitted by
  // a + b c and the slice is resampled at the corrected arc lengths.
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
        const size_t a = c > 0 ? c - 1 : c, b = c + 1 < columns ? c + 1 : c;
        double       tx = reference[2 * b] - reference[2 * a], ty = reference[2 * b + 1] - reference[2 * a + 1];
        const double norm = std::hypot(tx, ty);
        if (norm <= 0.0)
        {
          continue;
        }
        const double offset =
          ((columnsOf[k][2 * c] - reference[2 * c]) * tx + (columnsOf[k][2 * c + 1] - reference[2 * c + 1]) * ty) /
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
    for (size_t i = 0; i < 2 * columns; ++i)
    {
      columnsOf[k][i] = (1.0 - t) * columnsOf[before][i] + t * columnsOf[after][i];
    }
    ++m_Report.InterpolatedSlices;
  }
  if (m_Report.InterpolatedSlices > 0)
  {
    std::ostringstream text;
    text << m_Report.InterpolatedSlices << " slice(s) inside the sheet could not be traced and were interpolated";
    m_Report.Warnings.push_back(text.str());
  }
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

  // Rows: triangular-weighted average of the slices within one row spacing. Where slices
  // beyond the first or last good one hold the sheet (its edge along the axis), the mesh
  // reaches over them, and half a slice further to the middle of the last one's voxels,
  // on the curve of the last good slice.
  // Slices beyond the good ones that still hold most of a slice's material (traces lost
  // in the faint, blurred slices at the sheet's edge along the axis) are covered too, on
  // the curve of the nearest good slice, up to a few slices.
  const double fullArea = partialArea / 0.75;
  auto         reach = [&](long from, long dir) {
    long k = from + dir;
    while (k >= 0 && k < static_cast<long>(nz) && std::abs(k - from) <= EdgeSlices && area[k] >= 0.5 * fullArea)
    {
      k += dir;
    }
    const long covered = std::abs(k - from) - 1;
    const bool edge = k >= 0 && k < static_cast<long>(nz) && area[k] > 0.0;
    return static_cast<double>(covered) * sz + (covered > 0 || edge ? 0.5 * sz : 0.0);
  };
  const double below = reach(firstGood, -1);
  const double above = reach(lastGood, +1);
  const double span = static_cast<double>(lastGood - firstGood) * sz + below + above;
  const auto   rows = static_cast<size_t>(std::max(2.0, std::ceil(span / hw) + 1.0));
  const double rowSpacing = span / static_cast<double>(rows - 1);
  const double kernel = std::max(rowSpacing, sz);
  // Slices whose point lies farther than this from the row's median point are left out of
  // its mean: where a turn is pushed onto the next one in some slices of a row's window and
  // not in others (a touch's edge along the axis), the mean would lie between the two, in
  // the gap or on the neighbouring turn.
  const double agreement = 0.5 * std::max(m_Report.SheetThickness, voxel);
  SheetMesh    mesh;
  mesh.GridRows = static_cast<int32_t>(rows);
  mesh.GridColumns = static_cast<int32_t>(columns);
  mesh.Points.resize(3 * rows * columns);
  mesh.GridIndex.resize(2 * rows * columns);
  for (size_t r = 0; r < rows; ++r)
  {
    const double z = static_cast<double>(firstGood) * sz - below + static_cast<double>(r) * rowSpacing;
    const double zc = std::clamp(z, static_cast<double>(firstGood) * sz, static_cast<double>(lastGood) * sz);
    std::vector<std::pair<long, double>> window;
    for (long k = firstGood; k <= lastGood; ++k)
    {
      const double weight = 1.0 - std::abs(static_cast<double>(k) * sz - zc) / kernel;
      if (weight > 0.0)
      {
        window.emplace_back(k, weight);
      }
    }
    for (size_t c = 0; c < columns; ++c)
    {
      const size_t p = r * columns + c;
      double       point[2];
      RobustRowPoint(window, columnsOf, c, agreement, point);
      mesh.Points[3 * p] = point[0];
      mesh.Points[3 * p + 1] = point[1];
      mesh.Points[3 * p + 2] = z;
      mesh.GridIndex[2 * p] = static_cast<int32_t>(r);
      mesh.GridIndex[2 * p + 1] = static_cast<int32_t>(c);
    }
  }
  // Triangles with normals dP/dw x dP/ds.
  mesh.Triangles.reserve(6 * (rows - 1) * (columns - 1));
  for (size_t r = 0; r + 1 < rows; ++r)
  {
    for (size_t c = 0; c + 1 < columns; ++c)
    {
      const auto a = static_cast<uint32_t>(r * columns + c);
      const auto b = a + 1;
      const auto d = static_cast<uint32_t>(a + columns);
      const auto e = d + 1;
      mesh.Triangles.insert(mesh.Triangles.end(), { a, d, b, b, d, e });
    }
  }
  if (method == SheetSurfaceMethodEnum::Roll)
  {
    // Make the normals point to the roll axis (the inside face).
    double agreement = 0.0;
    for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
    {
      const double * p[3];
      for (int v = 0; v < 3; ++v)
      {
        p[v] = &mesh.Points[3 * mesh.Triangles[3 * t + v]];
      }
      const double u[3] = { p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2] };
      const double v[3] = { p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2] };
      const double normal[2] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2] };
      const double toAxis[2] = { m_Report.AxisCentre[0] + m_Report.AxisSlope[0] * p[0][2] - p[0][0],
                                 m_Report.AxisCentre[1] + m_Report.AxisSlope[1] * p[0][2] - p[0][1] };
      agreement += normal[0] * toAxis[0] + normal[1] * toAxis[1];
    }
    if (agreement < 0.0)
    {
      for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
      {
        std::swap(mesh.Triangles[3 * t + 1], mesh.Triangles[3 * t + 2]);
      }
    }
  }
  m_Report.SpacingAlongSheet = referenceLength / static_cast<double>(columns - 1);
  m_Report.SpacingAlongAxis = rowSpacing;
  if (method == SheetSurfaceMethodEnum::Roll && m_Report.TurnSpacing > 0.0)
  {
    // A layer jump the slice-to-slice check missed shows on the mesh as a sideways step
    // of about a turn spacing.
    m_Report.GridSteps = FindGridSteps(mesh, GridStepFraction * m_Report.TurnSpacing);
    for (auto & step : m_Report.GridSteps)
    {
      const double z = mesh.Points[3 * (step.Row * columns + step.Column) + 2];
      step.Slice = static_cast<size_t>(std::clamp(std::lround(z / sz), 0L, static_cast<long>(nz) - 1));
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
} // end namespace itk

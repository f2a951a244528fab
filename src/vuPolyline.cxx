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
#include "vuPolyline.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace itk {
namespace SheetTracing {
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

double
NeighbourChord(const Polyline & line, size_t i, double chord[2])
{
  const size_t n = PolylineSize(line);
  const size_t a = i > 0 ? i - 1 : i, b = i + 1 < n ? i + 1 : i;
  chord[0] = line[2 * b] - line[2 * a];
  chord[1] = line[2 * b + 1] - line[2 * a + 1];
  return std::hypot(chord[0], chord[1]);
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
} // namespace SheetTracing
} // end namespace itk

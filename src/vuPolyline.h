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
#ifndef vuPolyline_h
#define vuPolyline_h

#include <cstddef>
#include <vector>

namespace itk {
namespace SheetTracing {
/** A planar curve as x, y pairs (mm). */
using Polyline = std::vector<double>;

/** The value at `fraction` (0 to 1) of the sorted values; 0 for none. */
double
Percentile(std::vector<double> values, double fraction);

size_t
PolylineSize(const Polyline & line);

double
ArcLength(const Polyline & line);

// Moving average whose window shrinks symmetrically near the ends, so the ends stay put.
Polyline
Smooth(const Polyline & line, int halfWidth);

// n points evenly spaced in arc length from the first to the last point.
Polyline
ResampleEvenly(const Polyline & line, size_t n);

// Points at the given arc lengths along a polyline; beyond its ends, along the end segments.
Polyline
SampleAtArcLengths(const Polyline & line, const std::vector<double> & arcs);

// Increasing arc lengths brought within [0, length]: the columns that fall beyond an end
// are spread evenly between that end and the first column inside, so that no column is
// placed on the straight continuation of an end segment (off the sheet where it curves,
// as a roll's inner end does) and no two columns coincide.
std::vector<double>
KeepWithinTrace(std::vector<double> arcs, double length);

// The chord between the neighbours of point i (the point itself at an end) in `chord`, and
// its length.
double
NeighbourChord(const Polyline & line, size_t i, double chord[2]);

// Circumradius of three points.
double
Circumradius(const double a[2], const double b[2], const double c[2]);
} // namespace SheetTracing
} // end namespace itk

#endif

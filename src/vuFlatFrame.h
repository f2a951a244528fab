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
#ifndef vuFlatFrame_h
#define vuFlatFrame_h

#include "itkSheetMesh.h"

#include "itk_eigen.h"
#include ITK_EIGEN(Dense)

#include <cstddef>
#include <vector>

namespace itk {
/** The frame of a sheet's particles (x, y, z per particle): its principal axes, a plane
 * through it, and the final frame of a flat mesh. */
namespace FlatFrame {
/** Particle i of a packed coordinate array. */
inline Eigen::Vector3d
PointOf(const std::vector<double> & x, size_t i)
{
  return { x[3 * i], x[3 * i + 1], x[3 * i + 2] };
}

/** Principal axes of a point cloud, as columns sorted by decreasing variance; its centroid
 * into `centroid`. */
Eigen::Matrix3d
PrincipalAxes(const std::vector<double> & x, Eigen::Vector3d & centroid);

/** The particles laid on the plane through `origin` with in-plane axes u and v: their
 * coordinates along u and v, z = 0. */
std::vector<double>
ToPlane(const std::vector<double> & x,
        const Eigen::Vector3d &     origin,
        const Eigen::Vector3d &     u,
        const Eigen::Vector3d &     v);

/** Lays a flat grid mesh's rows straight (z = 0, before Normalise): a sheet rolled or
 * folded about an axis develops into a strip whose rows (the slices across that axis) are
 * straight lines, but a long strip keeps a slow bend in its plane that its springs barely
 * resist (rows differing in length by some parts in a hundred thousand bend a strip 200
 * times longer than wide by millimetres), and the inner turns of a long roll come out with
 * wiggles of some tenths of a millimetre. The centre line (each column's mean point) is
 * followed by a local weighted quadratic over a Gaussian window of half the strip's
 * width, and each column is carried into that line's frame: bends longer than the strip is
 * wide are taken out, each column keeps its shape. Returns the bend taken out (the
 * followed line's largest distance from its chord, mesh units); 0 and the mesh unchanged
 * for a mesh without a grid, or one bent in its plane by more than a tenth of a radian
 * over half its width along most of its length (not a slightly bent strip: a ring; a
 * short stretch that turns faster, such as a jog where an inner turn's trace curls, does
 * not count). */
double
StraightenRows(SheetMesh & flat);

/** The final frame of a flat mesh (z = 0): x along the sheet, triangles counter-clockwise
 * seen from +z, bounding box from (0, 0). On a grid mesh "along the sheet" is the mean
 * direction of its rows (columns increasing along +x), so that what was written along the
 * sheet (a roll's lines of text, a page's) runs along the image's rows whatever the flat
 * outline's shape; on any other mesh it is the longest extent. */
void
Normalise(SheetMesh & flat);

/** The triangles of a flat mesh in its final frame that are turned over (clockwise seen
 * from +z, against the counter-clockwise majority). */
size_t
TurnedOverTriangles(const SheetMesh & flat);
} // namespace FlatFrame
} // namespace itk

#endif

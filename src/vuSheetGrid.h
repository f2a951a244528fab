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
#ifndef vuSheetGrid_h
#define vuSheetGrid_h

#include "itkSheetMesh.h"
#include "vuPolyline.h"

#include <utility>
#include <vector>

namespace itk {
namespace SheetTracing {
/** A roll's axis in the frame of a sheet's slices: its centre at height z (mm, slice k at
 * k * sz) is Centre + Slope * z. */
struct RollAxisLine
{
  double Centre[2];
  double Slope[2];
};

/** The grid mesh of a sheet from its slices' columns (`columnsOf[k]`: `columns` points of
 * slice k, for every slice from firstGood to lastGood). Row r lies at z = firstGood * sz -
 * below + r * rowSpacing: per column, a straight line along the slices fitted, with
 * triangular weights, to the slices within one row spacing (at least one slice; two where
 * the traced range cuts that window), leaving out the slices whose point lies farther than
 * `agreement` from the row's weighted median point, and taken at z: the weighted mean
 * inside the range, the sheet's trend at its edges (rows past the traced slices included).
 * With `rollAxis` (a roll), the rows at the edges take each column's radius and angle about
 * the axis instead of x and y, robustly fitted along the slices, leaving out the slices
 * that disagree across the sheet or along it; the angle is not carried past the traced
 * slices, the radius by the row's median slope (a taper).
 * Triangles with normals dP/dw x dP/ds. */
SheetMesh
BuildSheetGrid(const std::vector<Polyline> & columnsOf,
               long                          firstGood,
               long                          lastGood,
               double                        sz,
               double                        below,
               size_t                        rows,
               double                        rowSpacing,
               size_t                        columns,
               double                        agreement,
               const RollAxisLine *          rollAxis = nullptr);

/** The point a fraction t of the way from p0 to p1 along a roll's turn: angle (the
 * shorter way round) and radius about the axis, whose centres in the two points' slices are
 * c0 and c1, interpolated (extrapolated for t outside [0, 1]); out gets (x, y). Where a
 * sheet's length changes along the axis, the same fraction of two slices' lengths lies at
 * different angles, and the chord between them cuts inside the turn. */
void
AlongTheTurn(const double p0[2], const double c0[2], const double p1[2], const double c1[2], double t, double out[2]);

/** Turns the mesh's triangles over unless their normals point, on the whole, to the axis
 * through axisCentre (at z = 0) with drift axisSlope per mm of z (the inside face of a roll). */
void
OrientNormalsToAxis(SheetMesh & mesh, const double axisCentre[2], const double axisSlope[2]);
} // namespace SheetTracing
} // end namespace itk

#endif

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
#ifndef itkSheetPhantomGeometry_h
#define itkSheetPhantomGeometry_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkSheetMesh.h"

#include <ostream>
#include <string>
#include <vector>

namespace itk {
/** \class SheetPhantomGeometry
 * \brief Ground truth of a synthetic document: the exact shape of a sheet rolled into a
 * scroll or folded like an accordion, the map from sheet coordinates to the CT volume's
 * physical frame, and the ink image that a perfect unwrapping would produce.
 *
 * Sheet coordinates: s is the arc length along the sheet from its inner end (mm, 0..L),
 * w the position across the sheet along the roll axis (mm, 0..W). The mid-surface is a
 * generalised cylinder, P(s, w) = R * (C(s), w - W/2), where C is a planar curve (the
 * cross-section) parameterised by arc length and R a rotation about the volume's x axis
 * by the tilt angle. The sheet is therefore developable and (s, w, 0) is its exact
 * isometric unrolling. Physical frame: millimetres, the frame of the phantom volume's
 * origin, spacing and direction (identity); the roll axis passes through the origin.
 *
 * Cross-sections (Parameters::Shape):
 * - Rolled: Archimedean spiral r(theta) = InnerRadius + Pitch * theta / (2 pi)
 *   + WaveAmplitude * sin(WavesPerTurn * theta), point (r cos theta, Squash * r sin theta),
 *   winding counter-clockwise about +z from its inner end. Waviness makes ridges that run
 *   parallel to the roll axis, which keeps the sheet developable.
 * - Folded: accordion (Z) fold: FoldCount + 1 equal flat panels joined by circular creases
 *   of radius FoldRadius that turn alternately left and right by 180 - FoldOpeningAngle
 *   degrees.
 *
 * Normal and faces: SurfaceNormal is the unit vector dP/dw x dP/ds, which points out of
 * the inked face (for the rolled shape: towards the roll axis, the writing is inside).
 * Seen from that side with s to the right, w increases downwards, so the ink image below
 * (x = s, y = w, row 0 at w = 0) shows the text upright and unmirrored when displayed
 * with y down, as any image viewer does. The mid-surface mesh's triangles are ordered so
 * that their right-hand normals agree with SurfaceNormal; in the flat mesh (s, w, 0)
 * those same triangles face -z.
 *
 * Parameters (mm unless stated; every one is checked by the constructor, which throws
 * itk::ExceptionObject with a one-line message when the sheet would be impossible):
 * - SheetLength L > 0 (default 50), SheetWidth W > 0 (10), SheetThickness t > 0 (0.25);
 * - InnerRadius > t/2 (1.5), Pitch > t (0.75), radial distance between successive turns;
 *   Squash in (0, 1] (1, circular), WaveAmplitude >= 0 (0), WavesPerTurn >= 0 (0);
 * - FoldCount >= 1 (4), FoldRadius > t/2 (0.5), FoldOpeningAngle in [0, 90) degrees (10);
 * - TiltAngle in (-60, 60) degrees (0), rotation of the roll axis about the x axis;
 * - SheetLength / SheetThickness at most 250000 (the size of the table).
 * Beyond these, any sheet whose layers come closer than its thickness (checked
 * numerically: each face point must project back to its own sheet point) is refused.
 *
 * Project() finds the closest point of the mid-surface in O(1) expected time through a
 * uniform grid of the tabulated cross-section (about 1.4 microseconds per point
 * near the standard phantom's sheet), so
 * mesh-error metrics can call it for every vertex of million-vertex meshes.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetPhantomGeometry
{
public:
  using InkImageType = Image<float, 2>;

  enum class ShapeType
  {
    Rolled,
    Folded
  };

  struct Parameters
  {
    ShapeType Shape{ ShapeType::Rolled };
    double    SheetLength{ 50.0 };
    double    SheetWidth{ 10.0 };
    double    SheetThickness{ 0.25 };
    double    InnerRadius{ 1.5 };
    double    Pitch{ 0.75 };
    double    Squash{ 1.0 };
    double    WaveAmplitude{ 0.0 };
    unsigned  WavesPerTurn{ 0 };
    unsigned  FoldCount{ 4 };
    double    FoldRadius{ 0.5 };
    double    FoldOpeningAngle{ 10.0 };
    double    TiltAngle{ 0.0 };
  };

  /** An empty geometry (no sheet); GetSheetLength() is 0. */
  SheetPhantomGeometry() = default;
  /** Validates the parameters and tabulates the sheet; throws on impossible sheets. */
  explicit SheetPhantomGeometry(const Parameters & parameters);

  /** Arc length of a rolled sheet with the given number of turns (same spiral
   * parameters), so that callers can specify a roll by turns instead of length. */
  static double
  RolledLengthForTurns(const Parameters & parameters, double turns);

  static const char *
  ShapeName(ShapeType shape);

  const Parameters &
  GetParameters() const
  {
    return m_Parameters;
  }
  double
  GetSheetLength() const
  {
    return m_Parameters.SheetLength;
  }
  double
  GetSheetWidth() const
  {
    return m_Parameters.SheetWidth;
  }
  double
  GetSheetThickness() const
  {
    return m_Parameters.SheetThickness;
  }
  /** Turns of the spiral (rolled shape); 0 for folded sheets. */
  double
  GetNumberOfTurns() const
  {
    return m_NumberOfTurns;
  }
  /** Smallest radius of curvature of the mid-surface (mm). */
  double
  GetMinimumCurvatureRadius() const;

  /** Mid-surface point at sheet coordinates (s, w); beyond 0..L the sheet is continued
   * along its end tangents. */
  void
  SurfacePoint(double s, double w, double p[3]) const;
  /** Unit normal out of the inked face, dP/dw x dP/ds (see class description). */
  void
  SurfaceNormal(double s, double w, double n[3]) const;
  /** Signed curvature of the cross-section at s (1/mm), positive when the centre of
   * curvature lies on the inked side: the area element at normal offset d is
   * (1 - curvature * d) ds dw. */
  double
  Curvature(double s) const;

  /** Closest point of the mid-surface to p: s in [0, L], w (not clamped) and the
   * signed distance along SurfaceNormal. Returns false when p lies beyond the sheet's
   * edges (its foot point would fall outside 0..L or 0..W). */
  bool
  Project(const double p[3], double & s, double & w, double & signedDistance) const;

  /** Axis-aligned bounds of the whole sheet (both faces) in the physical frame. */
  void
  GetBoundingBox(double lower[3], double upper[3]) const;

  /** The mid-surface as a grid mesh: columns along s (0..L), rows along w (0..W), point
   * (row r, column c) at index r * columns + c, grid spacing at most `spacing` mm,
   * triangles oriented with SurfaceNormal. If flat is given it receives the same
   * triangles with points (s, w, 0). Throws when spacing <= 0 or the mesh would exceed
   * 2^31 points. */
  SheetMesh
  MakeMidSurfaceMesh(double spacing, SheetMesh * flat = nullptr) const;

  /** Ink coverage (0..1) over the sheet: x = s, y = w (pixel centres, spacing in mm,
   * origin at half a pixel), text upright when shown with row 0 at the top. Set by
   * itk::SheetPhantomSource; null until then. */
  const InkImageType *
  GetInkImage() const
  {
    return m_InkImage.GetPointer();
  }
  /** The text rendered into the ink image, lines separated by '\n'; empty when the ink
   * came from a user image. */
  const std::string &
  GetText() const
  {
    return m_Text;
  }
  void
  SetInk(InkImageType * inkImage, const std::string & text);

private:
  void
  Tabulate();
  void
  BuildSearchGrid();
  void
  CheckLayersDoNotOverlap() const;
  void
  CurvePoint(double s, double c[2], double tangent[2]) const;
  void
  ClosestOnCurve(const double q[2], double & s, double & signedDistance, bool & beyondEnd) const;

  Parameters m_Parameters;
  double     m_NumberOfTurns{ 0.0 };
  double     m_Rotation[3][3]{ { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };

  // The cross-section tabulated at uniform arc length m_Step: exact points and unit
  // tangents of the analytic curve, interpolated by cubic Hermite segments.
  double              m_Step{ 0.0 };
  std::vector<double> m_CurveX;
  std::vector<double> m_CurveY;
  std::vector<double> m_TangentX;
  std::vector<double> m_TangentY;
  std::vector<double> m_Curvature;

  // Uniform grid over the cross-section; each cell lists the table segments that touch it.
  double                m_GridOrigin[2]{ 0.0, 0.0 };
  double                m_CellSize{ 1.0 };
  int                   m_GridSize[2]{ 0, 0 };
  std::vector<uint32_t> m_CellStart;
  std::vector<uint32_t> m_CellSegments;

  InkImageType::Pointer m_InkImage;
  std::string           m_Text;
};

/** Prints "rolled" or "folded". */
VirtualUnwrapping_EXPORT std::ostream &
                         operator<<(std::ostream & os, SheetPhantomGeometry::ShapeType shape);
} // end namespace itk

#endif

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
#include "itkSheetPhantomGeometry.h"

#include "itkMacro.h"
#include "itkMath.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace itk {
namespace {
using CurveFunction = std::function<void(double t, double p[2], double d[2])>;

constexpr double Pi = itk::Math::pi;

double
Norm2(const double d[2])
{
  return std::sqrt(d[0] * d[0] + d[1] * d[1]);
}

// Archimedean spiral with optional squash and ripples; t is the polar angle.
CurveFunction
MakeSpiral(const SheetPhantomGeometry::Parameters & p)
{
  const double b = p.Pitch / (2.0 * Pi);
  const double a = p.WaveAmplitude;
  const double k = p.WavesPerTurn;
  const double q = p.Squash;
  const double r0 = p.InnerRadius;
  return [=](double t, double pt[2], double d[2]) {
    const double r = r0 + b * t + a * std::sin(k * t);
    const double dr = b + a * k * std::cos(k * t);
    const double c = std::cos(t), sn = std::sin(t);
    pt[0] = r * c;
    pt[1] = q * r * sn;
    d[0] = dr * c - r * sn;
    d[1] = q * (dr * sn + r * c);
  };
}

// Accordion fold parameterised by arc length: straight panels and circular creases
// turning alternately left and right.
CurveFunction
MakeFold(const SheetPhantomGeometry::Parameters & p)
{
  struct Piece
  {
    double start, length, x, y, angle, curvature;
  };
  const double       turn = Pi - p.FoldOpeningAngle * Pi / 180.0;
  const double       creaseLength = p.FoldRadius * turn;
  const double       panel = (p.SheetLength - p.FoldCount * creaseLength) / (p.FoldCount + 1);
  std::vector<Piece> pieces;
  double             x = 0.0, y = 0.0, angle = 0.0, start = 0.0;
  for (unsigned k = 0; k <= p.FoldCount; ++k)
  {
    pieces.push_back({ start, panel, x, y, angle, 0.0 });
    x += panel * std::cos(angle);
    y += panel * std::sin(angle);
    start += panel;
    if (k == p.FoldCount)
    {
      break;
    }
    const double kappa = (k % 2 == 0 ? 1.0 : -1.0) / p.FoldRadius;
    pieces.push_back({ start, creaseLength, x, y, angle, kappa });
    const double next = angle + kappa * creaseLength;
    x += (std::sin(next) - std::sin(angle)) / kappa;
    y -= (std::cos(next) - std::cos(angle)) / kappa;
    angle = next;
    start += creaseLength;
  }
  return [pieces](double t, double pt[2], double d[2]) {
    auto it =
      std::upper_bound(pieces.begin(), pieces.end(), t, [](double v, const Piece & piece) { return v < piece.start; });
    const Piece & piece = it == pieces.begin() ? pieces.front() : *(it - 1);
    const double  u = t - piece.start;
    const double  angle = piece.angle + piece.curvature * u;
    if (piece.curvature == 0.0)
    {
      pt[0] = piece.x + u * std::cos(angle);
      pt[1] = piece.y + u * std::sin(angle);
    }
    else
    {
      pt[0] = piece.x + (std::sin(angle) - std::sin(piece.angle)) / piece.curvature;
      pt[1] = piece.y - (std::cos(angle) - std::cos(piece.angle)) / piece.curvature;
    }
    d[0] = std::cos(angle);
    d[1] = std::sin(angle);
  };
}

// Arc length of the curve between t0 and t1 (Simpson's rule on one interval).
double
ArcLength(const CurveFunction & curve, double t0, double t1)
{
  double p[2], d0[2], dm[2], d1[2];
  curve(t0, p, d0);
  curve(0.5 * (t0 + t1), p, dm);
  curve(t1, p, d1);
  return (t1 - t0) / 6.0 * (Norm2(d0) + 4.0 * Norm2(dm) + Norm2(d1));
}

void
CheckPositive(double value, const char * name)
{
  if (!(value > 0.0) || !std::isfinite(value))
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: " << name << " must be positive and finite, got " << value);
  }
}
} // namespace

const char *
SheetPhantomGeometry::ShapeName(ShapeType shape)
{
  return shape == ShapeType::Rolled ? "rolled" : "folded";
}

std::ostream &
operator<<(std::ostream & os, SheetPhantomGeometry::ShapeType shape)
{
  return os << SheetPhantomGeometry::ShapeName(shape);
}

SheetPhantomGeometry::SheetPhantomGeometry(const Parameters & parameters)
  : m_Parameters(parameters)
{
  const Parameters & p = m_Parameters;
  CheckPositive(p.SheetLength, "sheet length");
  CheckPositive(p.SheetWidth, "sheet width");
  CheckPositive(p.SheetThickness, "sheet thickness");
  if (!(std::abs(p.TiltAngle) < 60.0))
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: tilt angle must lie in (-60, 60) degrees, got " << p.TiltAngle);
  }
  if (p.Shape == ShapeType::Rolled)
  {
    CheckPositive(p.InnerRadius, "inner radius");
    CheckPositive(p.Pitch, "pitch");
    if (p.InnerRadius <= 0.5 * p.SheetThickness)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: inner radius " << p.InnerRadius
                               << " mm must exceed half the sheet thickness (" << 0.5 * p.SheetThickness << " mm)");
    }
    if (p.Pitch <= p.SheetThickness)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: pitch " << p.Pitch << " mm must exceed the sheet thickness "
                               << p.SheetThickness << " mm, or the turns overlap");
    }
    if (!(p.Squash > 0.0 && p.Squash <= 1.0))
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: squash must lie in (0, 1], got " << p.Squash);
    }
    if (!(p.WaveAmplitude >= 0.0) || p.WaveAmplitude >= p.InnerRadius)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: wave amplitude must lie in [0, inner radius), got "
                               << p.WaveAmplitude);
    }
    if (p.WavesPerTurn > 1000)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: waves per turn must not exceed 1000, got " << p.WavesPerTurn);
    }
  }
  else
  {
    CheckPositive(p.FoldRadius, "fold radius");
    if (p.FoldCount < 1 || p.FoldCount > 1000)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: fold count must lie in 1..1000, got " << p.FoldCount);
    }
    if (p.FoldRadius <= 0.5 * p.SheetThickness)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: fold radius " << p.FoldRadius
                               << " mm must exceed half the sheet thickness (" << 0.5 * p.SheetThickness
                               << " mm), or the layers at a crease overlap");
    }
    if (!(p.FoldOpeningAngle >= 0.0 && p.FoldOpeningAngle < 90.0))
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: fold opening angle must lie in [0, 90) degrees, got "
                               << p.FoldOpeningAngle);
    }
    const double creases = p.FoldCount * p.FoldRadius * (Pi - p.FoldOpeningAngle * Pi / 180.0);
    if (creases >= p.SheetLength)
    {
      itkGenericExceptionMacro(<< "SheetPhantomGeometry: sheet length " << p.SheetLength << " mm is too short for "
                               << p.FoldCount << " creases of radius " << p.FoldRadius << " mm");
    }
  }
  const double tilt = p.TiltAngle * Pi / 180.0;
  m_Rotation[1][1] = std::cos(tilt);
  m_Rotation[1][2] = -std::sin(tilt);
  m_Rotation[2][1] = std::sin(tilt);
  m_Rotation[2][2] = std::cos(tilt);

  Tabulate();
  BuildSearchGrid();
  CheckLayersDoNotOverlap();
}

double
SheetPhantomGeometry::RolledLengthForTurns(const Parameters & parameters, double turns)
{
  CheckPositive(turns, "number of turns");
  const CurveFunction spiral = MakeSpiral(parameters);
  const double        end = 2.0 * Pi * turns;
  const int           steps = static_cast<int>(std::ceil(turns * 4096.0));
  double              length = 0.0;
  for (int i = 0; i < steps; ++i)
  {
    length += ArcLength(spiral, end * i / steps, end * (i + 1) / steps);
  }
  return length;
}

void
SheetPhantomGeometry::Tabulate()
{
  const Parameters &  p = m_Parameters;
  const CurveFunction curve = p.Shape == ShapeType::Rolled ? MakeSpiral(p) : MakeFold(p);
  // A step of t/16 keeps the chord error of the table's polyline below t/1000 even at
  // the tightest admissible curvature radius (t/2).
  const double requested = std::min(p.SheetThickness / 16.0, p.SheetLength / 64.0);
  const size_t segments = static_cast<size_t>(std::ceil(p.SheetLength / requested));
  if (segments > 50000000)
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: sheet length " << p.SheetLength
                             << " mm is too long for thickness " << p.SheetThickness
                             << " mm (more than 5e7 table segments)");
  }
  m_Step = p.SheetLength / segments;

  // March the curve parameter in steps of about a quarter table step of arc length,
  // accumulating arc length, then invert at uniform arc length.
  std::vector<double> parameter{ 0.0 }, length{ 0.0 };
  while (length.back() < p.SheetLength)
  {
    double pt[2], d[2];
    curve(parameter.back(), pt, d);
    const double dt = 0.25 * m_Step / std::max(Norm2(d), 1e-12);
    length.push_back(length.back() + ArcLength(curve, parameter.back(), parameter.back() + dt));
    parameter.push_back(parameter.back() + dt);
  }
  m_CurveX.resize(segments + 1);
  m_CurveY.resize(segments + 1);
  m_TangentX.resize(segments + 1);
  m_TangentY.resize(segments + 1);
  size_t j = 0;
  for (size_t i = 0; i <= segments; ++i)
  {
    const double target = std::min(i * m_Step, p.SheetLength);
    while (j + 2 < length.size() && length[j + 1] < target)
    {
      ++j;
    }
    const double fraction = (target - length[j]) / (length[j + 1] - length[j]);
    double       t = parameter[j] + fraction * (parameter[j + 1] - parameter[j]);
    double       pt[2], d[2];
    for (int iteration = 0; iteration < 2; ++iteration)
    {
      curve(t, pt, d);
      t += (target - length[j] - ArcLength(curve, parameter[j], t)) / Norm2(d);
    }
    curve(t, pt, d);
    const double speed = Norm2(d);
    m_CurveX[i] = pt[0];
    m_CurveY[i] = pt[1];
    m_TangentX[i] = d[0] / speed;
    m_TangentY[i] = d[1] / speed;
    if (i == segments && p.Shape == ShapeType::Rolled)
    {
      m_NumberOfTurns = t / (2.0 * Pi);
    }
  }
  m_Curvature.resize(segments + 1);
  for (size_t i = 0; i <= segments; ++i)
  {
    const size_t a = i == 0 ? 0 : i - 1;
    const size_t b = std::min(i + 1, segments);
    const double cross = m_TangentX[a] * m_TangentY[b] - m_TangentY[a] * m_TangentX[b];
    const double dot = m_TangentX[a] * m_TangentX[b] + m_TangentY[a] * m_TangentY[b];
    m_Curvature[i] = std::atan2(cross, dot) / ((b - a) * m_Step);
  }
}

void
SheetPhantomGeometry::BuildSearchGrid()
{
  const size_t segments = m_CurveX.size() - 1;
  double       lower[2] = { m_CurveX[0], m_CurveY[0] }, upper[2] = { m_CurveX[0], m_CurveY[0] };
  for (size_t i = 0; i <= segments; ++i)
  {
    lower[0] = std::min(lower[0], m_CurveX[i]);
    lower[1] = std::min(lower[1], m_CurveY[i]);
    upper[0] = std::max(upper[0], m_CurveX[i]);
    upper[1] = std::max(upper[1], m_CurveY[i]);
  }
  // Cells about one thickness wide hold a few dozen segments each; coarser when the
  // cross-section is large, to bound memory.
  const double area = (upper[0] - lower[0] + 1e-9) * (upper[1] - lower[1] + 1e-9);
  m_CellSize = std::max(m_Parameters.SheetThickness, std::sqrt(area / 4.0e6));
  for (int d = 0; d < 2; ++d)
  {
    m_GridOrigin[d] = lower[d] - m_CellSize;
    m_GridSize[d] = static_cast<int>(std::ceil((upper[d] - lower[d]) / m_CellSize)) + 2;
  }
  auto cellRange = [&](double lo, double hi, int d, int & first, int & last) {
    first = std::max(0, static_cast<int>(std::floor((lo - m_GridOrigin[d]) / m_CellSize)));
    last = std::min(m_GridSize[d] - 1, static_cast<int>(std::floor((hi - m_GridOrigin[d]) / m_CellSize)));
  };
  const size_t          cells = static_cast<size_t>(m_GridSize[0]) * m_GridSize[1];
  std::vector<uint32_t> counts(cells + 1, 0);
  for (int pass = 0; pass < 2; ++pass)
  {
    for (size_t i = 0; i < segments; ++i)
    {
      int x0, x1, y0, y1;
      cellRange(std::min(m_CurveX[i], m_CurveX[i + 1]), std::max(m_CurveX[i], m_CurveX[i + 1]), 0, x0, x1);
      cellRange(std::min(m_CurveY[i], m_CurveY[i + 1]), std::max(m_CurveY[i], m_CurveY[i + 1]), 1, y0, y1);
      for (int y = y0; y <= y1; ++y)
      {
        for (int x = x0; x <= x1; ++x)
        {
          const size_t cell = static_cast<size_t>(y) * m_GridSize[0] + x;
          if (pass == 0)
          {
            ++counts[cell + 1];
          }
          else
          {
            m_CellSegments[counts[cell]++] = static_cast<uint32_t>(i);
          }
        }
      }
    }
    if (pass == 0)
    {
      for (size_t c = 0; c < cells; ++c)
      {
        counts[c + 1] += counts[c];
      }
      m_CellStart = counts;
      m_CellSegments.resize(counts[cells]);
    }
  }
}

void
SheetPhantomGeometry::CheckLayersDoNotOverlap() const
{
  // If the sheet's layers keep at least one thickness apart (and no crease is sharper
  // than half a thickness), every point of either face projects back to its own sheet
  // point; any other answer means two layers overlap there.
  const double offset = 0.5 * m_Parameters.SheetThickness * (1.0 + 1e-3);
  for (size_t i = 0; i < m_CurveX.size(); ++i)
  {
    for (double side : { -1.0, 1.0 })
    {
      const double q[2] = { m_CurveX[i] - side * offset * m_TangentY[i], m_CurveY[i] + side * offset * m_TangentX[i] };
      double       s, distance;
      bool         beyond;
      ClosestOnCurve(q, s, distance, beyond);
      if (std::abs(s - i * m_Step) > 4.0 * m_Step + 1e-9)
      {
        itkGenericExceptionMacro(<< "SheetPhantomGeometry: the sheet's layers overlap near s = " << i * m_Step
                                 << " mm (layers closer than the thickness " << m_Parameters.SheetThickness
                                 << " mm: increase the pitch or fold radius, or reduce squash and waviness)");
      }
    }
  }
}

void
SheetPhantomGeometry::CurvePoint(double s, double c[2], double tangent[2]) const
{
  const size_t segments = m_CurveX.size() - 1;
  if (s <= 0.0 || s >= m_Parameters.SheetLength)
  {
    const size_t end = s <= 0.0 ? 0 : segments;
    const double beyond = s <= 0.0 ? s : s - m_Parameters.SheetLength;
    tangent[0] = m_TangentX[end];
    tangent[1] = m_TangentY[end];
    c[0] = m_CurveX[end] + beyond * tangent[0];
    c[1] = m_CurveY[end] + beyond * tangent[1];
    return;
  }
  const size_t i = std::min(static_cast<size_t>(s / m_Step), segments - 1);
  const double u = s / m_Step - i;
  const double u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
  const double d00 = 6 * u2 - 6 * u, d10 = 3 * u2 - 4 * u + 1, d01 = -d00, d11 = 3 * u2 - 2 * u;
  const double h = m_Step;
  c[0] = h00 * m_CurveX[i] + h10 * h * m_TangentX[i] + h01 * m_CurveX[i + 1] + h11 * h * m_TangentX[i + 1];
  c[1] = h00 * m_CurveY[i] + h10 * h * m_TangentY[i] + h01 * m_CurveY[i + 1] + h11 * h * m_TangentY[i + 1];
  tangent[0] = (d00 * m_CurveX[i] + d01 * m_CurveX[i + 1]) / h + d10 * m_TangentX[i] + d11 * m_TangentX[i + 1];
  tangent[1] = (d00 * m_CurveY[i] + d01 * m_CurveY[i + 1]) / h + d10 * m_TangentY[i] + d11 * m_TangentY[i + 1];
  const double norm = Norm2(tangent);
  tangent[0] /= norm;
  tangent[1] /= norm;
}

double
SheetPhantomGeometry::Curvature(double s) const
{
  if (m_Curvature.empty())
  {
    return 0.0;
  }
  const size_t segments = m_Curvature.size() - 1;
  const double x = std::clamp(s / m_Step, 0.0, static_cast<double>(segments));
  const size_t i = std::min(static_cast<size_t>(x), segments - 1);
  const double u = x - i;
  return (1.0 - u) * m_Curvature[i] + u * m_Curvature[i + 1];
}

double
SheetPhantomGeometry::GetMinimumCurvatureRadius() const
{
  double largest = 0.0;
  for (double k : m_Curvature)
  {
    largest = std::max(largest, std::abs(k));
  }
  return largest > 0.0 ? 1.0 / largest : std::numeric_limits<double>::infinity();
}

void
SheetPhantomGeometry::SurfacePoint(double s, double w, double p[3]) const
{
  if (m_CurveX.empty())
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: empty geometry");
  }
  double c[2], t[2];
  CurvePoint(s, c, t);
  const double local[3] = { c[0], c[1], w - 0.5 * m_Parameters.SheetWidth };
  for (int r = 0; r < 3; ++r)
  {
    p[r] = m_Rotation[r][0] * local[0] + m_Rotation[r][1] * local[1] + m_Rotation[r][2] * local[2];
  }
}

void
SheetPhantomGeometry::SurfaceNormal(double s, double, double n[3]) const
{
  if (m_CurveX.empty())
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: empty geometry");
  }
  double c[2], t[2];
  CurvePoint(s, c, t);
  // z x (t, 0): the left normal of the cross-section.
  const double local[2] = { -t[1], t[0] };
  for (int r = 0; r < 3; ++r)
  {
    n[r] = m_Rotation[r][0] * local[0] + m_Rotation[r][1] * local[1];
  }
}

void
SheetPhantomGeometry::ClosestOnCurve(const double q[2], double & s, double & signedDistance, bool & beyondEnd) const
{
  const int nx = m_GridSize[0], ny = m_GridSize[1];
  const int cx = std::clamp(static_cast<int>(std::floor((q[0] - m_GridOrigin[0]) / m_CellSize)), 0, nx - 1);
  const int cy = std::clamp(static_cast<int>(std::floor((q[1] - m_GridOrigin[1]) / m_CellSize)), 0, ny - 1);
  double    best = std::numeric_limits<double>::infinity();
  size_t    bestSegment = 0;
  double    bestU = 0.0;

  auto visitCell = [&](int x, int y) {
    const size_t cell = static_cast<size_t>(y) * nx + x;
    for (uint32_t k = m_CellStart[cell]; k < m_CellStart[cell + 1]; ++k)
    {
      const uint32_t i = m_CellSegments[k];
      const double   ax = m_CurveX[i], ay = m_CurveY[i];
      const double   dx = m_CurveX[i + 1] - ax, dy = m_CurveY[i + 1] - ay;
      const double   u = std::clamp(((q[0] - ax) * dx + (q[1] - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
      const double   ex = q[0] - ax - u * dx, ey = q[1] - ay - u * dy;
      const double   d2 = ex * ex + ey * ey;
      if (d2 < best)
      {
        best = d2;
        bestSegment = i;
        bestU = u;
      }
    }
  };
  // Distance from q to a rectangle of cells (inclusive cell bounds).
  auto distanceToCells = [&](int x0, int x1, int y0, int y1) {
    if (x0 > x1 || y0 > y1)
    {
      return std::numeric_limits<double>::infinity();
    }
    const double lx = m_GridOrigin[0] + x0 * m_CellSize, ux = m_GridOrigin[0] + (x1 + 1) * m_CellSize;
    const double ly = m_GridOrigin[1] + y0 * m_CellSize, uy = m_GridOrigin[1] + (y1 + 1) * m_CellSize;
    const double dx = std::max({ lx - q[0], 0.0, q[0] - ux });
    const double dy = std::max({ ly - q[1], 0.0, q[1] - uy });
    return std::sqrt(dx * dx + dy * dy);
  };
  for (int k = 0;; ++k)
  {
    const int x0 = cx - k, x1 = cx + k, y0 = cy - k, y1 = cy + k;
    for (int y = std::max(y0, 0); y <= std::min(y1, ny - 1); ++y)
    {
      const bool edgeRow = (y == y0 || y == y1);
      for (int x = std::max(x0, 0); x <= std::min(x1, nx - 1); ++x)
      {
        if (edgeRow || x == x0 || x == x1)
        {
          visitCell(x, y);
        }
      }
    }
    const bool covered = x0 <= 0 && y0 <= 0 && x1 >= nx - 1 && y1 >= ny - 1;
    if (covered)
    {
      break;
    }
    // Cells not yet visited: the grid outside the (clipped) box of rings 0..k.
    const int    bx0 = std::max(x0, 0), bx1 = std::min(x1, nx - 1), by0 = std::max(y0, 0), by1 = std::min(y1, ny - 1);
    const double remaining = std::min({ distanceToCells(0, bx0 - 1, 0, ny - 1),
                                        distanceToCells(bx1 + 1, nx - 1, 0, ny - 1),
                                        distanceToCells(bx0, bx1, 0, by0 - 1),
                                        distanceToCells(bx0, bx1, by1 + 1, ny - 1) });
    if (best <= remaining * remaining)
    {
      break;
    }
  }

  // Refine on the smooth (Hermite) curve so that Project and SurfacePoint agree.
  const double length = m_Parameters.SheetLength;
  s = std::clamp((bestSegment + bestU) * m_Step, 0.0, length);
  double c[2], t[2];
  for (int iteration = 0; iteration < 3; ++iteration)
  {
    CurvePoint(s, c, t);
    const double rx = q[0] - c[0], ry = q[1] - c[1];
    const double along = rx * t[0] + ry * t[1];
    const double normal = -rx * t[1] + ry * t[0];
    const double denominator = 1.0 - Curvature(s) * normal;
    s = std::clamp(s + along / (denominator > 0.1 ? denominator : 1.0), 0.0, length);
  }
  CurvePoint(s, c, t);
  const double rx = q[0] - c[0], ry = q[1] - c[1];
  const double along = rx * t[0] + ry * t[1];
  signedDistance = -rx * t[1] + ry * t[0];
  const double tolerance = 1e-6 * (1.0 + m_Parameters.SheetThickness);
  beyondEnd = (s <= 0.0 && along < -tolerance) || (s >= length && along > tolerance);
}

bool
SheetPhantomGeometry::Project(const double p[3], double & s, double & w, double & signedDistance) const
{
  if (m_CurveX.empty())
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: empty geometry");
  }
  double local[3];
  for (int r = 0; r < 3; ++r)
  {
    local[r] = m_Rotation[0][r] * p[0] + m_Rotation[1][r] * p[1] + m_Rotation[2][r] * p[2];
  }
  w = local[2] + 0.5 * m_Parameters.SheetWidth;
  bool beyondEnd;
  ClosestOnCurve(local, s, signedDistance, beyondEnd);
  return !beyondEnd && w >= 0.0 && w <= m_Parameters.SheetWidth;
}

void
SheetPhantomGeometry::GetBoundingBox(double lower[3], double upper[3]) const
{
  if (m_CurveX.empty())
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: empty geometry");
  }
  const double half = 0.5 * m_Parameters.SheetThickness;
  for (int d = 0; d < 3; ++d)
  {
    lower[d] = std::numeric_limits<double>::infinity();
    upper[d] = -std::numeric_limits<double>::infinity();
  }
  for (size_t i = 0; i < m_CurveX.size(); ++i)
  {
    for (double side : { -half, half })
    {
      const double x = m_CurveX[i] - side * m_TangentY[i], y = m_CurveY[i] + side * m_TangentX[i];
      for (double z : { -0.5 * m_Parameters.SheetWidth, 0.5 * m_Parameters.SheetWidth })
      {
        for (int r = 0; r < 3; ++r)
        {
          const double v = m_Rotation[r][0] * x + m_Rotation[r][1] * y + m_Rotation[r][2] * z;
          lower[r] = std::min(lower[r], v);
          upper[r] = std::max(upper[r], v);
        }
      }
    }
  }
}

SheetMesh
SheetPhantomGeometry::MakeMidSurfaceMesh(double spacing, SheetMesh * flat) const
{
  if (m_CurveX.empty())
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: empty geometry");
  }
  if (!(spacing > 0.0) || !std::isfinite(spacing))
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: mesh spacing must be positive, got " << spacing);
  }
  const double length = m_Parameters.SheetLength, width = m_Parameters.SheetWidth;
  const double columnsReal = std::ceil(length / spacing) + 1.0, rowsReal = std::ceil(width / spacing) + 1.0;
  if (columnsReal * rowsReal > static_cast<double>(std::numeric_limits<int32_t>::max()))
  {
    itkGenericExceptionMacro(<< "SheetPhantomGeometry: mesh spacing " << spacing << " mm gives more than 2^31 points");
  }
  const int32_t columns = static_cast<int32_t>(columnsReal), rows = static_cast<int32_t>(rowsReal);
  const size_t  points = static_cast<size_t>(rows) * columns;

  std::vector<double> curve(2 * columns);
  for (int32_t c = 0; c < columns; ++c)
  {
    double t[2];
    CurvePoint(length * c / (columns - 1), &curve[2 * c], t);
  }
  SheetMesh mesh;
  mesh.GridRows = rows;
  mesh.GridColumns = columns;
  mesh.Points.resize(3 * points);
  mesh.GridIndex.resize(2 * points);
  for (int32_t r = 0; r < rows; ++r)
  {
    const double z = width * r / (rows - 1) - 0.5 * width;
    for (int32_t c = 0; c < columns; ++c)
    {
      const size_t i = static_cast<size_t>(r) * columns + c;
      const double x = curve[2 * c], y = curve[2 * c + 1];
      for (int d = 0; d < 3; ++d)
      {
        mesh.Points[3 * i + d] = m_Rotation[d][0] * x + m_Rotation[d][1] * y + m_Rotation[d][2] * z;
      }
      mesh.GridIndex[2 * i] = r;
      mesh.GridIndex[2 * i + 1] = c;
    }
  }
  // Triangles (a, d, b) and (b, d, e) of each grid cell have normal dP/dw x dP/ds.
  mesh.Triangles.resize(6 * static_cast<size_t>(rows - 1) * (columns - 1));
  size_t k = 0;
  for (int32_t r = 0; r + 1 < rows; ++r)
  {
    for (int32_t c = 0; c + 1 < columns; ++c)
    {
      const uint32_t a = static_cast<uint32_t>(r) * columns + c, b = a + 1, d = a + columns, e = d + 1;
      const uint32_t corners[6] = { a, d, b, b, d, e };
      std::copy(corners, corners + 6, mesh.Triangles.begin() + k);
      k += 6;
    }
  }
  if (flat != nullptr)
  {
    flat->Triangles = mesh.Triangles;
    flat->GridIndex = mesh.GridIndex;
    flat->GridRows = rows;
    flat->GridColumns = columns;
    flat->Points.resize(3 * points);
    for (int32_t r = 0; r < rows; ++r)
    {
      for (int32_t c = 0; c < columns; ++c)
      {
        const size_t i = static_cast<size_t>(r) * columns + c;
        flat->Points[3 * i] = length * c / (columns - 1);
        flat->Points[3 * i + 1] = width * r / (rows - 1);
        flat->Points[3 * i + 2] = 0.0;
      }
    }
  }
  return mesh;
}

void
SheetPhantomGeometry::SetInk(InkImageType * inkImage, const std::string & text)
{
  m_InkImage = inkImage;
  m_Text = text;
}
} // end namespace itk

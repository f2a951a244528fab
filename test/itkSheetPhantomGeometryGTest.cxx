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
#include "itkFlatteningDistortionCalculator.h"
#include "itkSheetPhantomGeometry.h"
#include "vuTestHelpers.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

#include <cmath>
#include <random>

namespace {
using Geometry = itk::SheetPhantomGeometry;

Geometry::Parameters
RolledParameters()
{
  Geometry::Parameters p;
  p.SheetLength = 40.0;
  p.SheetWidth = 8.0;
  p.SheetThickness = 0.25;
  p.InnerRadius = 1.5;
  p.Pitch = 0.75;
  return p;
}

double
Dot(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Closed-form arc length of r = r0 + b theta from theta = 0.
double
SpiralArcLength(double r0, double b, double theta)
{
  auto primitive = [b](double r) { return 0.5 / b * (r * std::sqrt(r * r + b * b) + b * b * std::asinh(r / b)); };
  return primitive(r0 + b * theta) - primitive(r0);
}

// Project(SurfacePoint + d * normal) must give back (s, w, d) for points well inside.
void
ExpectRoundTrips(const Geometry & g, double maxOffset)
{
  std::mt19937                           random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double                           length = g.GetSheetLength(), width = g.GetSheetWidth();
  for (int k = 0; k < 2000; ++k)
  {
    const double s = length * (0.01 + 0.98 * unit(random));
    const double w = width * (0.01 + 0.98 * unit(random));
    const double d = maxOffset * (2.0 * unit(random) - 1.0);
    double       p[3], n[3];
    g.SurfacePoint(s, w, p);
    g.SurfaceNormal(s, w, n);
    EXPECT_NEAR(std::sqrt(Dot(n, n)), 1.0, 1e-12);
    const double q[3] = { p[0] + d * n[0], p[1] + d * n[1], p[2] + d * n[2] };
    double       ps, pw, pd;
    ASSERT_TRUE(g.Project(q, ps, pw, pd)) << "s " << s << " w " << w << " d " << d;
    EXPECT_NEAR(ps, s, 1e-6);
    EXPECT_NEAR(pw, w, 1e-9);
    EXPECT_NEAR(pd, d, 1e-6);
  }
}

// Isometry of the true mesh and its flat version, and agreement of triangle normals
// with SurfaceNormal.
void
ExpectIsometricMesh(const Geometry & g, double spacing)
{
  itk::SheetMesh flat;
  itk::SheetMesh mesh = g.MakeMidSurfaceMesh(spacing, &flat);
  mesh.Validate("mesh");
  ASSERT_TRUE(mesh.IsGridStructured());
  ASSERT_TRUE(itk::HaveSameTopology(mesh, flat));
  EXPECT_EQ(mesh.GetNumberOfPoints(), static_cast<size_t>(mesh.GridRows) * mesh.GridColumns);
  auto calculator = vu::MeasureDistortion(mesh, flat);
  // Chords of the curved sheet are shorter than the arcs by about (spacing * curvature)^2 / 24.
  const double k = 1.0 / g.GetMinimumCurvatureRadius();
  EXPECT_LT(calculator->GetEdgeStrainP95(), spacing * spacing * k * k / 24.0 + 1e-9);
  EXPECT_EQ(calculator->GetNumberOfFlippedTriangles(), 0u);

  size_t disagreeing = 0;
  for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
  {
    const double * a = &mesh.Points[3 * mesh.Triangles[3 * t]];
    const double * b = &mesh.Points[3 * mesh.Triangles[3 * t + 1]];
    const double * c = &mesh.Points[3 * mesh.Triangles[3 * t + 2]];
    const double   u[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, v[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    const double   normal[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
    const uint32_t first = mesh.Triangles[3 * t];
    double         truth[3];
    g.SurfaceNormal(flat.Points[3 * first], flat.Points[3 * first + 1], truth);
    disagreeing += Dot(normal, truth) <= 0.0;
    // Flat triangles face -z.
    const double * fa = &flat.Points[3 * mesh.Triangles[3 * t]];
    const double * fb = &flat.Points[3 * mesh.Triangles[3 * t + 1]];
    const double * fc = &flat.Points[3 * mesh.Triangles[3 * t + 2]];
    EXPECT_LT((fb[0] - fa[0]) * (fc[1] - fa[1]) - (fb[1] - fa[1]) * (fc[0] - fa[0]), 0.0);
  }
  EXPECT_EQ(disagreeing, 0u);
}
} // namespace

TEST(SheetPhantomGeometry, RolledSheetFollowsTheAnalyticSpiral)
{
  const auto     p = RolledParameters();
  const Geometry g(p);
  const double   b = p.Pitch / (2.0 * itk::Math::pi);
  for (double theta = 0.0; theta < 2.0 * itk::Math::pi * g.GetNumberOfTurns(); theta += 0.37)
  {
    const double s = SpiralArcLength(p.InnerRadius, b, theta);
    const double r = p.InnerRadius + b * theta;
    double       point[3], normal[3];
    g.SurfacePoint(s, 2.0, point);
    EXPECT_NEAR(point[0], r * std::cos(theta), 1e-6);
    EXPECT_NEAR(point[1], r * std::sin(theta), 1e-6);
    EXPECT_NEAR(point[2], 2.0 - 0.5 * p.SheetWidth, 1e-12);
    // The inked face is the inner one: the normal points towards the roll axis.
    g.SurfaceNormal(s, 2.0, normal);
    EXPECT_LT(normal[0] * std::cos(theta) + normal[1] * std::sin(theta), -0.99);
    EXPECT_NEAR(g.Curvature(s), 1.0 / r, 0.02 / r);
  }
  const double expectedTurns =
    (std::sqrt(p.InnerRadius * p.InnerRadius + 2.0 * b * p.SheetLength) - p.InnerRadius) / (b * 2.0 * itk::Math::pi);
  EXPECT_NEAR(g.GetNumberOfTurns(), expectedTurns, 0.01);
}

TEST(SheetPhantomGeometry, LengthForTurnsGivesThoseTurns)
{
  auto         p = RolledParameters();
  const double length = Geometry::RolledLengthForTurns(p, 3.25);
  const double b = p.Pitch / (2.0 * itk::Math::pi);
  EXPECT_NEAR(length, SpiralArcLength(p.InnerRadius, b, 3.25 * 2.0 * itk::Math::pi), 1e-6);
  p.SheetLength = length;
  EXPECT_NEAR(Geometry(p).GetNumberOfTurns(), 3.25, 1e-6);
}

TEST(SheetPhantomGeometry, ProjectInvertsSurfacePoint)
{
  auto p = RolledParameters();
  // Offsets up to 0.3 mm: beyond the faces, short of the middle of the gap (pitch / 2).
  ExpectRoundTrips(Geometry(p), 0.3);
  p.Squash = 0.7;
  p.Pitch = 1.0;
  p.WaveAmplitude = 0.1;
  p.WavesPerTurn = 5;
  p.TiltAngle = 20.0;
  ExpectRoundTrips(Geometry(p), 0.2);
  p.Shape = Geometry::ShapeType::Folded;
  ExpectRoundTrips(Geometry(p), 0.2);
}

TEST(SheetPhantomGeometry, ProjectReportsPointsBeyondTheEdges)
{
  const Geometry g(RolledParameters());
  double         p[3], n[3], s, w, d;
  g.SurfacePoint(5.0, -0.5, p);
  EXPECT_FALSE(g.Project(p, s, w, d));
  EXPECT_NEAR(w, -0.5, 1e-9);
  g.SurfacePoint(g.GetSheetLength() + 0.4, 3.0, p);
  EXPECT_FALSE(g.Project(p, s, w, d));
  EXPECT_NEAR(s, g.GetSheetLength(), 1e-9);
  g.SurfacePoint(g.GetSheetLength() - 0.4, 3.0, p);
  g.SurfaceNormal(g.GetSheetLength() - 0.4, 3.0, n);
  EXPECT_TRUE(g.Project(p, s, w, d));
  EXPECT_NEAR(d, 0.0, 1e-9);
}

TEST(SheetPhantomGeometry, MidSurfaceMeshIsIsometricToItsFlatMesh)
{
  auto p = RolledParameters();
  ExpectIsometricMesh(Geometry(p), 0.1);
  p.Shape = Geometry::ShapeType::Folded;
  p.TiltAngle = -15.0;
  ExpectIsometricMesh(Geometry(p), 0.1);

  itk::SheetMesh flat;
  itk::SheetMesh mesh = Geometry(RolledParameters()).MakeMidSurfaceMesh(0.5, &flat);
  EXPECT_EQ(mesh.GridColumns, 81);
  EXPECT_EQ(mesh.GridRows, 17);
  // Row r, column c at index r * columns + c, at (s, w) = (c * 0.5, r * 0.5).
  const size_t i = 3 * 81 + 10;
  EXPECT_EQ(mesh.GridIndex[2 * i], 3);
  EXPECT_EQ(mesh.GridIndex[2 * i + 1], 10);
  EXPECT_DOUBLE_EQ(flat.Points[3 * i], 5.0);
  EXPECT_DOUBLE_EQ(flat.Points[3 * i + 1], 1.5);
  double expected[3];
  Geometry(RolledParameters()).SurfacePoint(5.0, 1.5, expected);
  for (int d = 0; d < 3; ++d)
  {
    EXPECT_NEAR(mesh.Points[3 * i + d], expected[d], 1e-12);
  }
}

TEST(SheetPhantomGeometry, FoldedSheetHasParallelPanelsAtZeroOpening)
{
  Geometry::Parameters p;
  p.Shape = Geometry::ShapeType::Folded;
  p.SheetLength = 30.0;
  p.FoldCount = 2;
  p.FoldRadius = 0.5;
  p.FoldOpeningAngle = 0.0;
  const Geometry g(p);
  const double   crease = 0.5 * itk::Math::pi;
  const double   panel = (30.0 - 2.0 * crease) / 3.0;
  double         a[3], b[3], c[3];
  g.SurfacePoint(0.5 * panel, 1.0, a);
  g.SurfacePoint(1.5 * panel + crease, 1.0, b);
  g.SurfacePoint(2.5 * panel + 2.0 * crease, 1.0, c);
  // Panels stacked one crease diameter apart, alternating direction.
  EXPECT_NEAR(b[1] - a[1], 1.0, 1e-9);
  EXPECT_NEAR(c[1] - b[1], 1.0, 1e-9);
  EXPECT_NEAR(a[0], b[0], 1e-9);
  EXPECT_NEAR(a[0], c[0], 1e-9);
  EXPECT_NEAR(g.GetMinimumCurvatureRadius(), 0.5, 0.01);
}

TEST(SheetPhantomGeometry, RefusesImpossibleSheets)
{
  auto bad = [](auto change) {
    auto p = RolledParameters();
    change(p);
    EXPECT_THROW(Geometry{ p }, itk::ExceptionObject);
  };
  bad([](Geometry::Parameters & p) { p.SheetLength = -1.0; });
  bad([](Geometry::Parameters & p) { p.SheetWidth = 0.0; });
  bad([](Geometry::Parameters & p) { p.SheetThickness = std::nan(""); });
  bad([](Geometry::Parameters & p) { p.Pitch = p.SheetThickness; });
  bad([](Geometry::Parameters & p) { p.InnerRadius = 0.1; });
  bad([](Geometry::Parameters & p) { p.Squash = 0.0; });
  bad([](Geometry::Parameters & p) { p.TiltAngle = 75.0; });
  // Allowed one by one, but together the squashed turns come closer than the thickness.
  bad([](Geometry::Parameters & p) {
    p.Pitch = 0.3;
    p.Squash = 0.5;
  });
  bad([](Geometry::Parameters & p) {
    p.WaveAmplitude = 0.2;
    p.WavesPerTurn = 40;
  });
  bad([](Geometry::Parameters & p) {
    p.Shape = Geometry::ShapeType::Folded;
    p.FoldRadius = 0.1;
  });
  bad([](Geometry::Parameters & p) {
    p.Shape = Geometry::ShapeType::Folded;
    p.FoldCount = 40;
  });
  EXPECT_THROW(Geometry(RolledParameters()).MakeMidSurfaceMesh(0.0), itk::ExceptionObject);
  EXPECT_THROW(Geometry::RolledLengthForTurns(RolledParameters(), -2.0), itk::ExceptionObject);
  double p[3];
  EXPECT_THROW(Geometry().SurfacePoint(0.0, 0.0, p), itk::ExceptionObject);
}

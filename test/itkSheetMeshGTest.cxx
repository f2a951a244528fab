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
#include "itkSheetMesh.h"

#include "itkMacro.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

namespace {
itk::SheetMesh
UnitSquare()
{
  itk::SheetMesh mesh;
  mesh.Points = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0 };
  mesh.Triangles = { 0, 1, 2, 0, 2, 3 };
  return mesh;
}
} // namespace

TEST(SheetMesh, CountsEdgesAndAreas)
{
  const itk::SheetMesh mesh = UnitSquare();
  EXPECT_EQ(mesh.GetNumberOfPoints(), 4u);
  EXPECT_EQ(mesh.GetNumberOfTriangles(), 2u);
  const std::vector<uint32_t> edges = mesh.ComputeEdges();
  ASSERT_EQ(edges.size(), 10u); // 4 sides + 1 diagonal
  EXPECT_EQ(edges[0], 0u);
  EXPECT_EQ(edges[1], 1u);
  const std::vector<double> areas = mesh.ComputeTriangleAreas();
  EXPECT_DOUBLE_EQ(areas[0] + areas[1], 1.0);
  EXPECT_NO_THROW(mesh.Validate("square"));
  EXPECT_FALSE(mesh.IsGridStructured());
}

TEST(SheetMesh, ValidateRejectsBadArrays)
{
  itk::SheetMesh bad = UnitSquare();
  bad.Triangles[5] = 7;
  EXPECT_THROW(bad.Validate("bad index"), itk::ExceptionObject);
  bad = UnitSquare();
  bad.Triangles[1] = 0;
  EXPECT_THROW(bad.Validate("repeated point"), itk::ExceptionObject);
  bad = UnitSquare();
  bad.Points[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bad.Validate("nan"), itk::ExceptionObject);
  bad = UnitSquare();
  bad.Triangles.clear();
  EXPECT_THROW(bad.Validate("empty"), itk::ExceptionObject);
  bad = UnitSquare();
  bad.GridIndex = { 0, 0 };
  EXPECT_THROW(bad.Validate("grid"), itk::ExceptionObject);
}

TEST(SheetMesh, TopologyComparison)
{
  const itk::SheetMesh a = UnitSquare();
  itk::SheetMesh       b = UnitSquare();
  b.Points[0] = 5.0;
  EXPECT_TRUE(itk::HaveSameTopology(a, b));
  b.Triangles = { 0, 1, 3, 1, 2, 3 };
  EXPECT_FALSE(itk::HaveSameTopology(a, b));
}

TEST(SheetMesh, VertexNormalsAreAreaWeighted)
{
  // A flat triangle in z = 0 joined along the edge (1, 2) to a larger roof rising at 45
  // degrees: normals of points on the shared edge lean towards the larger roof.
  itk::SheetMesh mesh;
  mesh.Points = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 3, 0, 2, 3, 2, 2 };
  mesh.Triangles = { 0, 1, 2, 1, 3, 4, 1, 4, 2 };
  const std::vector<double> normals = mesh.ComputeVertexNormals();
  ASSERT_EQ(normals.size(), 15u);
  EXPECT_NEAR(normals[0], 0.0, 1e-12);
  EXPECT_NEAR(normals[1], 0.0, 1e-12);
  EXPECT_NEAR(normals[2], 1.0, 1e-12);
  // Point 2 touches the flat triangle (area 0.5, normal +z) and the roof triangle
  // (1, 4, 2) (area sqrt(2), normal (-1, 0, 1) / sqrt(2)): weighted sum (-1, 0, 1.5).
  const double length = std::sqrt(1.0 + 2.25);
  EXPECT_NEAR(normals[6], -1.0 / length, 1e-12);
  EXPECT_NEAR(normals[7], 0.0, 1e-12);
  EXPECT_NEAR(normals[8], 1.5 / length, 1e-12);
  for (size_t i = 0; i < 5; ++i)
  {
    EXPECT_NEAR(normals[3 * i] * normals[3 * i] + normals[3 * i + 1] * normals[3 * i + 1] +
                  normals[3 * i + 2] * normals[3 * i + 2],
                1.0,
                1e-12);
  }
  // Reversing the winding reverses every normal.
  itk::SheetMesh flipped = mesh;
  for (size_t t = 0; t < flipped.GetNumberOfTriangles(); ++t)
  {
    std::swap(flipped.Triangles[3 * t + 1], flipped.Triangles[3 * t + 2]);
  }
  const std::vector<double> reversed = flipped.ComputeVertexNormals();
  for (size_t k = 0; k < normals.size(); ++k)
  {
    EXPECT_NEAR(reversed[k], -normals[k], 1e-12);
  }
}

TEST(SheetMesh, VertexNormalOfUnusedPointIsZero)
{
  itk::SheetMesh mesh = UnitSquare();
  mesh.Points.insert(mesh.Points.end(), { 5, 5, 5 });
  const std::vector<double> normals = mesh.ComputeVertexNormals();
  EXPECT_EQ(normals[12], 0.0);
  EXPECT_EQ(normals[13], 0.0);
  EXPECT_EQ(normals[14], 0.0);
  EXPECT_NEAR(normals[2], 1.0, 1e-12);
}

// A quarter cylinder of radius 10 on a 5 x 9 grid laid out on its grid: rows keep their arc
// length, rows stay the row spacing apart, the triangles and the grid are kept.
TEST(SheetMesh, GridLayoutOfACylinderIsIsometric)
{
  itk::SheetMesh mesh;
  mesh.GridRows = 5;
  mesh.GridColumns = 9;
  const double pi = std::acos(-1.0);
  for (int r = 0; r < mesh.GridRows; ++r)
  {
    for (int c = 0; c < mesh.GridColumns; ++c)
    {
      const double t = 0.5 * pi * c / (mesh.GridColumns - 1);
      mesh.Points.insert(mesh.Points.end(), { 10.0 * std::cos(t), 10.0 * std::sin(t), 1.5 * r });
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
      if (r > 0 && c > 0)
      {
        const uint32_t a = (r - 1) * mesh.GridColumns + c - 1, b = a + 1, d = r * mesh.GridColumns + c - 1, e = d + 1;
        mesh.Triangles.insert(mesh.Triangles.end(), { a, b, e, a, e, d });
      }
    }
  }
  const itk::SheetMesh layout = mesh.ComputeGridLayout();
  ASSERT_TRUE(itk::HaveSameTopology(mesh, layout));
  EXPECT_EQ(layout.GridIndex, mesh.GridIndex);
  const double chord = 2.0 * 10.0 * std::sin(0.25 * pi / (mesh.GridColumns - 1));
  for (int r = 0; r < mesh.GridRows; ++r)
  {
    const size_t last = r * mesh.GridColumns + mesh.GridColumns - 1;
    EXPECT_NEAR(layout.Points[3 * last], chord * (mesh.GridColumns - 1), 1e-9);
    EXPECT_EQ(layout.Points[3 * last + 2], 0.0);
  }
  // Rows 1.5 apart, and every triangle counter-clockwise seen from +z; the same grid with
  // its triangles turned the other way is laid out with its rows numbered downwards.
  for (int r = 0; r + 1 < mesh.GridRows; ++r)
  {
    EXPECT_NEAR(
      std::abs(layout.Points[3 * (r * mesh.GridColumns) + 1] - layout.Points[3 * ((r + 1) * mesh.GridColumns) + 1]),
      1.5,
      1e-9);
  }
  for (size_t t = 0; t < layout.GetNumberOfTriangles(); ++t)
  {
    const double * a = &layout.Points[3 * layout.Triangles[3 * t]];
    const double * b = &layout.Points[3 * layout.Triangles[3 * t + 1]];
    const double * c = &layout.Points[3 * layout.Triangles[3 * t + 2]];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]), 0.0);
  }
  itk::SheetMesh turned = mesh;
  for (size_t t = 0; t < turned.GetNumberOfTriangles(); ++t)
  {
    std::swap(turned.Triangles[3 * t + 1], turned.Triangles[3 * t + 2]);
  }
  const itk::SheetMesh turnedLayout = turned.ComputeGridLayout();
  EXPECT_NEAR(turnedLayout.Points[1], 1.5 * (mesh.GridRows - 1), 1e-9);
  EXPECT_NEAR(layout.Points[1], 0.0, 1e-9);
  itk::SheetMesh noGrid = mesh;
  noGrid.GridIndex.clear();
  EXPECT_THROW(noGrid.ComputeGridLayout(), itk::ExceptionObject);
}

// A skewed grid (each row's columns start further along the arc than the row before, as a
// trace of a skewed roll gives them) on a cylinder: its layout keeps the shear, so that every
// edge, the ones across the rows included, has its length on the cylinder. The radius and
// the skew are drawn at run time; laid with the rows one above the other, the edges across
// the rows would be wrong by a seventh or more.
TEST(SheetMesh, GridLayoutOfASkewedGridKeepsItsShear)
{
  const unsigned seed = vu::RunTimeSeed();
  std::mt19937   random(seed);
  auto uniform = [&](double low, double high) { return std::uniform_real_distribution<double>(low, high)(random); };
  const double radius = uniform(5.0, 15.0);
  const double rowStep = uniform(0.5, 1.5);
  const double skew = uniform(0.8, 1.4) * rowStep / radius; // radians a row
  std::cout << "seed " << seed << ": radius " << radius << ", row step " << rowStep << ", skew " << skew << std::endl;
  itk::SheetMesh mesh;
  mesh.GridRows = 12;
  mesh.GridColumns = 60;
  for (int r = 0; r < mesh.GridRows; ++r)
  {
    for (int c = 0; c < mesh.GridColumns; ++c)
    {
      const double t = 0.05 * c + skew * r;
      mesh.Points.insert(mesh.Points.end(), { radius * std::cos(t), radius * std::sin(t), rowStep * r });
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
      if (r > 0 && c > 0)
      {
        const uint32_t a = (r - 1) * mesh.GridColumns + c - 1, b = a + 1, d = r * mesh.GridColumns + c - 1, e = d + 1;
        mesh.Triangles.insert(mesh.Triangles.end(), { a, b, e, a, e, d });
      }
    }
  }
  const itk::SheetMesh        layout = mesh.ComputeGridLayout();
  const std::vector<uint32_t> edges = mesh.ComputeEdges();
  double                      worst = 0.0;
  for (size_t k = 0; k < edges.size(); k += 2)
  {
    auto length = [&](const itk::SheetMesh & m) {
      double sum = 0.0;
      for (unsigned d = 0; d < 3; ++d)
      {
        const double e = m.Points[3 * edges[k] + d] - m.Points[3 * edges[k + 1] + d];
        sum += e * e;
      }
      return std::sqrt(sum);
    };
    worst = std::max(worst, std::abs(length(layout) / length(mesh) - 1.0));
  }
  std::cout << "largest edge strain of the layout " << worst << std::endl;
  EXPECT_LT(worst, 0.01);
}

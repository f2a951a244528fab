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
#include "itkTexturePixelMap.h"

#include "itkMacro.h"

#include "gtest/gtest.h"

#include <cmath>

namespace {
// A 2 x 1 rectangle split along its diagonal, lifted onto the plane z = x: not an
// isometry, but the map only has to be barycentric, which makes it easy to check.
itk::SheetMesh
LiftedSquare(itk::SheetMesh & flat)
{
  flat.Points = { 0, 0, 0, 2, 0, 0, 2, 1, 0, 0, 1, 0 };
  flat.Triangles = { 0, 1, 2, 0, 2, 3 };
  itk::SheetMesh surface = flat;
  for (size_t i = 0; i < 4; ++i)
  {
    surface.Points[3 * i + 2] = surface.Points[3 * i];
  }
  return surface;
}
} // namespace

TEST(TexturePixelMap, GridCoversTheFlatBoundingBox)
{
  itk::SheetMesh flat;
  LiftedSquare(flat);
  const itk::TexturePixelMap grid = itk::ComputeTextureGrid(flat, 0.25, 0.5);
  EXPECT_DOUBLE_EQ(grid.Origin[0], -0.5);
  EXPECT_DOUBLE_EQ(grid.Origin[1], -0.5);
  EXPECT_EQ(grid.Size[0], 13u); // (2 + 1) / 0.25 + 1
  EXPECT_EQ(grid.Size[1], 9u);  // (1 + 1) / 0.25 + 1
  EXPECT_TRUE(grid.Triangle.empty());
  EXPECT_THROW(itk::ComputeTextureGrid(flat, 0.0, 0.0), itk::ExceptionObject);
  EXPECT_THROW(itk::ComputeTextureGrid(flat, 0.1, -1.0), itk::ExceptionObject);
  EXPECT_THROW(itk::ComputeTextureGrid(flat, 1e-7, 0.0), itk::ExceptionObject); // too many pixels
  EXPECT_THROW(itk::ComputeTextureGrid(itk::SheetMesh(), 0.1, 0.0), itk::ExceptionObject);
}

TEST(TexturePixelMap, MapsPixelsToSurfacePointsAndNormals)
{
  itk::SheetMesh             flat;
  const itk::SheetMesh       surface = LiftedSquare(flat);
  const itk::TexturePixelMap map = itk::ComputeTexturePixelMap(surface, flat, 0.25, 0.25);
  ASSERT_EQ(map.Size[0], 11u);
  ASSERT_EQ(map.Size[1], 7u);
  // Every pixel centre in the square, shared edges included, is on the sheet; the margin
  // is not.
  EXPECT_EQ(map.GetNumberOfSheetPixels(), 9u * 5u);
  const double normal[3] = { -1.0 / std::sqrt(2.0), 0.0, 1.0 / std::sqrt(2.0) };
  for (size_t row = 0; row < map.Size[1]; ++row)
  {
    for (size_t column = 0; column < map.Size[0]; ++column)
    {
      const size_t pixel = row * map.Size[0] + column;
      const double x = map.Origin[0] + column * map.PixelSize;
      const double y = map.Origin[1] + row * map.PixelSize;
      const bool   inside = x >= -1e-9 && x <= 2 + 1e-9 && y >= -1e-9 && y <= 1 + 1e-9;
      ASSERT_EQ(map.Triangle[pixel] >= 0, inside) << x << ", " << y;
      if (!inside)
      {
        continue;
      }
      EXPECT_NEAR(map.Positions[3 * pixel], x, 1e-6);
      EXPECT_NEAR(map.Positions[3 * pixel + 1], y, 1e-6);
      EXPECT_NEAR(map.Positions[3 * pixel + 2], x, 1e-6);
      for (int d = 0; d < 3; ++d)
      {
        EXPECT_NEAR(map.Normals[3 * pixel + d], normal[d], 1e-6);
      }
      EXPECT_EQ(map.Triangle[pixel], y > x / 2 + 1e-9 ? 1 : (y < x / 2 - 1e-9 ? 0 : map.Triangle[pixel]));
    }
  }
  EXPECT_EQ(map.NumberOfDegenerateTriangles, 0u);
  EXPECT_EQ(map.NumberOfZeroNormalPixels, 0u);
}

TEST(TexturePixelMap, RejectsMeshesOfDifferentTopology)
{
  itk::SheetMesh flat;
  itk::SheetMesh surface = LiftedSquare(flat);
  flat.Triangles = { 0, 1, 3, 1, 2, 3 };
  EXPECT_THROW(itk::ComputeTexturePixelMap(surface, flat, 0.25, 0.0), itk::ExceptionObject);
  surface.Points.resize(9);
  EXPECT_THROW(itk::ComputeTexturePixelMap(surface, flat, 0.25, 0.0), itk::ExceptionObject);
}

// A half cylinder of radius R meshed with coarse columns (chords of 30 degrees, as coarse
// as the automatic mesh spacing makes them on a roll's inner turn) and its development:
// placed on the curved sheet, the texture's points lie near the cylinder itself, not on
// the chords, which run inside it by up to R (1 - cos 15 degrees) = 0.034 R.
TEST(TexturePixelMap, PlacesPixelsOnTheCurvedSheetNotOnItsChords)
{
  const double   radius = 10.0, length = 6.0;
  const unsigned columns = 7, rows = 3; // 0 to 180 degrees in steps of 30
  itk::SheetMesh flat, surface;
  for (unsigned r = 0; r < rows; ++r)
  {
    for (unsigned c = 0; c < columns; ++c)
    {
      const double angle = M_PI * c / (columns - 1), z = length * r / (rows - 1);
      surface.Points.insert(surface.Points.end(), { radius * std::cos(angle), radius * std::sin(angle), z });
      flat.Points.insert(flat.Points.end(), { radius * angle, z, 0.0 });
    }
  }
  for (unsigned r = 0; r + 1 < rows; ++r)
  {
    for (unsigned c = 0; c + 1 < columns; ++c)
    {
      const uint32_t a = r * columns + c, b = a + 1, d = a + columns, e = d + 1;
      flat.Triangles.insert(flat.Triangles.end(), { a, b, e, a, e, d });
    }
  }
  surface.Triangles = flat.Triangles;
  // The largest distance of the pixels' points from the cylinder, over all of them and
  // away from the two end columns, whose corner normals lean towards the missing side.
  auto distances = [&](bool curved, double & worst, double & worstMiddle) {
    const itk::TexturePixelMap map = itk::ComputeTexturePixelMap(surface, flat, 0.1, 0.0, nullptr, 0.0f, 1.0f, curved);
    worst = worstMiddle = 0.0;
    for (size_t pixel = 0; pixel < map.GetNumberOfPixels(); ++pixel)
    {
      if (map.Triangle[pixel] < 0)
      {
        continue;
      }
      const double x = map.Positions[3 * pixel], y = map.Positions[3 * pixel + 1];
      const double off = std::abs(std::hypot(x, y) - radius);
      worst = std::max(worst, off);
      const double u = map.Origin[0] + (pixel % map.Size[0]) * map.PixelSize;
      if (u > radius * M_PI / 6.0 && u < radius * 5.0 * M_PI / 6.0)
      {
        worstMiddle = std::max(worstMiddle, off);
      }
    }
  };
  const double sagitta = radius * (1.0 - std::cos(M_PI / 12.0));
  double       worst, worstMiddle;
  distances(false, worst, worstMiddle);
  EXPECT_GT(worstMiddle, 0.95 * sagitta) << "on the chords";
  distances(true, worst, worstMiddle);
  // The corners' normals are area-weighted means of their triangles' (the diagonals make
  // them lean a little along the columns), so the curve is not followed exactly: a fifth
  // of the sagitta at most in the middle (the chords themselves reach the whole of it),
  // two thirds at the end columns.
  EXPECT_LT(worstMiddle, 0.25 * sagitta) << "largest distance from the cylinder " << worstMiddle;
  EXPECT_LT(worst, 0.75 * sagitta) << "at the end columns " << worst;
}

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

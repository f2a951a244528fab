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

#include "gtest/gtest.h"

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

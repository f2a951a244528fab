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
#include "itkSheetMeshErrorCalculator.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

namespace {
itk::SheetPhantomGeometry
StandardGeometry()
{
  itk::SheetPhantomGeometry::Parameters parameters;
  parameters.SheetLength = itk::SheetPhantomGeometry::RolledLengthForTurns(parameters, 3.0);
  return itk::SheetPhantomGeometry(parameters);
}

itk::SheetMeshErrorCalculator::Pointer
Measure(const itk::SheetPhantomGeometry & geometry, const itk::SheetMesh & mesh)
{
  auto calculator = itk::SheetMeshErrorCalculator::New();
  calculator->SetGeometry(geometry);
  calculator->SetMesh(mesh);
  calculator->SetVoxelSize(0.1);
  calculator->Compute();
  return calculator;
}

// Moves every vertex along the true normal by offset (mm).
itk::SheetMesh
Offset(const itk::SheetPhantomGeometry & geometry, itk::SheetMesh mesh, double offset)
{
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    double * p = &mesh.Points[3 * i];
    double   s, w, d, n[3];
    geometry.Project(p, s, w, d);
    geometry.SurfaceNormal(s, w, n);
    for (int k = 0; k < 3; ++k)
    {
      p[k] += offset * n[k];
    }
  }
  return mesh;
}
} // namespace

TEST(SheetMeshErrorCalculator, BasicObjectMethods)
{
  auto calculator = itk::SheetMeshErrorCalculator::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(calculator, SheetMeshErrorCalculator, Object));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(0.05, (calculator->SetVoxelSize(0.05), calculator->GetVoxelSize())));
  VU_EXPECT_ITK_MACROS(
    ITK_TEST_SET_GET_VALUE(2.0, (calculator->SetCoverageTolerance(2.0), calculator->GetCoverageTolerance())));
}

TEST(SheetMeshErrorCalculator, TrueMidSurfaceIsPerfect)
{
  const auto geometry = StandardGeometry();
  const auto calculator = Measure(geometry, geometry.MakeMidSurfaceMesh(0.3));
  EXPECT_LT(calculator->GetMeanVertexDistance(), 0.01);
  EXPECT_LT(calculator->GetMaximumVertexDistance(), 0.05);
  EXPECT_GT(calculator->GetCoverage(), 0.999);
  EXPECT_EQ(calculator->GetNumberOfLayerJumps(), 0u);
  EXPECT_GT(calculator->GetNumberOfEdges(), 0u);
}

TEST(SheetMeshErrorCalculator, OffsetMeshIsMeasuredInVoxels)
{
  const auto geometry = StandardGeometry();
  const auto truth = geometry.MakeMidSurfaceMesh(0.3);
  const auto near = Measure(geometry, Offset(geometry, truth, 0.05));
  EXPECT_NEAR(near->GetMeanVertexDistance(), 0.5, 0.02);
  EXPECT_GT(near->GetCoverage(), 0.999);
  const auto far = Measure(geometry, Offset(geometry, truth, 0.2));
  EXPECT_NEAR(far->GetMeanVertexDistance(), 2.0, 0.05);
  EXPECT_LT(far->GetCoverage(), 0.001);
}

TEST(SheetMeshErrorCalculator, HalfMeshCoversHalf)
{
  const auto     geometry = StandardGeometry();
  const auto     truth = geometry.MakeMidSurfaceMesh(0.3);
  itk::SheetMesh half;
  half.Points = truth.Points;
  // Keep the triangles of the first half of the columns.
  for (size_t t = 0; t < truth.GetNumberOfTriangles(); ++t)
  {
    bool keep = true;
    for (int v = 0; v < 3; ++v)
    {
      keep = keep && truth.GridIndex[2 * truth.Triangles[3 * t + v] + 1] <= truth.GridColumns / 2;
    }
    if (keep)
    {
      half.Triangles.insert(half.Triangles.end(), &truth.Triangles[3 * t], &truth.Triangles[3 * t + 3]);
    }
  }
  const auto calculator = Measure(geometry, half);
  EXPECT_NEAR(calculator->GetCoverage(), 0.5, 0.02);
}

TEST(SheetMeshErrorCalculator, EdgeBetweenTurnsIsALayerJump)
{
  const auto     geometry = StandardGeometry();
  itk::SheetMesh mesh;
  // One triangle on the first turn, one with a vertex on the next turn (one turn later).
  const double turn = geometry.GetSheetLength() / geometry.GetNumberOfTurns();
  const double coordinates[4][2] = { { 5.0, 4.0 }, { 5.3, 4.0 }, { 5.0, 4.3 }, { 5.0 + turn, 4.0 } };
  for (const auto & c : coordinates)
  {
    double p[3];
    geometry.SurfacePoint(c[0], c[1], p);
    mesh.Points.insert(mesh.Points.end(), p, p + 3);
  }
  mesh.Triangles = { 0, 1, 2, 1, 3, 2 };
  const auto calculator = Measure(geometry, mesh);
  EXPECT_EQ(calculator->GetNumberOfLayerJumps(), 2u);
  EXPECT_EQ(calculator->GetNumberOfEdges(), 5u);
}

TEST(SheetMeshErrorCalculator, BadInputThrows)
{
  auto calculator = itk::SheetMeshErrorCalculator::New();
  calculator->SetVoxelSize(0.1);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject); // no geometry
  const auto geometry = StandardGeometry();
  calculator->SetGeometry(geometry);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject); // no mesh
  calculator->SetMesh(geometry.MakeMidSurfaceMesh(0.5));
  calculator->SetVoxelSize(0.0);
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject);
}

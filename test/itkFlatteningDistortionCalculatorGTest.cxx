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
#include "vuTestHelpers.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

#include <cmath>

namespace {
// A grid patch of a cylinder of radius r: rows along the axis, columns along the arc.
// Returns the 3D surface; flat receives its exact unrolling (arc length, axial position).
itk::SheetMesh
CylinderPatch(double radius, double angle, int columns, int rows, double height, itk::SheetMesh & flat)
{
  itk::SheetMesh mesh;
  flat = itk::SheetMesh();
  for (int r = 0; r < rows; ++r)
  {
    for (int c = 0; c < columns; ++c)
    {
      const double theta = angle * c / (columns - 1);
      const double z = height * r / (rows - 1);
      mesh.Points.insert(mesh.Points.end(), { radius * std::cos(theta), radius * std::sin(theta), z });
      flat.Points.insert(flat.Points.end(), { radius * theta, z, 0.0 });
    }
  }
  mesh.Triangles = vu::GridTriangles(rows, columns);
  flat.Triangles = mesh.Triangles;
  return mesh;
}
} // namespace

TEST(FlatteningDistortionCalculator, BasicObjectMethods)
{
  auto calculator = itk::FlatteningDistortionCalculator::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(calculator, FlatteningDistortionCalculator, Object));
}

TEST(FlatteningDistortionCalculator, FlatInputHasNoDistortion)
{
  itk::SheetMesh flat;
  itk::SheetMesh surface = CylinderPatch(10.0, 1.0, 12, 6, 5.0, flat);
  // The flat mesh measured against itself, lifted to z = 3: an isometry.
  itk::SheetMesh lifted = flat;
  for (size_t i = 0; i < lifted.GetNumberOfPoints(); ++i)
  {
    lifted.Points[3 * i + 2] = 3.0;
  }
  auto c = vu::MeasureDistortion(lifted, flat);
  EXPECT_NEAR(c->GetEdgeStrainMax(), 0.0, 1e-12);
  EXPECT_NEAR(c->GetAreaDistortion(), 0.0, 1e-12);
  EXPECT_NEAR(c->GetTotalAreaRatio(), 1.0, 1e-12);
  EXPECT_NEAR(c->GetAngleDistortionDegrees(), 0.0, 1e-9);
  EXPECT_NEAR(c->GetL2Stretch(), 1.0, 1e-12);
  EXPECT_NEAR(c->GetLinfStretch(), 1.0, 1e-12);
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
  EXPECT_EQ(c->GetNumberOfEdges(), 11u * 6u + 12u * 5u + 11u * 5u);
}

TEST(FlatteningDistortionCalculator, CylinderUnrollingIsNearlyIsometric)
{
  itk::SheetMesh flat;
  // Chords of a 10-unit radius over 0.05 rad differ from arcs by about 1e-4 relative.
  itk::SheetMesh surface = CylinderPatch(10.0, 2.0, 41, 5, 4.0, flat);
  auto           c = vu::MeasureDistortion(surface, flat);
  EXPECT_LT(c->GetEdgeStrainP95(), 2e-4);
  EXPECT_LT(c->GetAreaDistortion(), 2e-4);
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
}

TEST(FlatteningDistortionCalculator, UniformScaleGivesKnownStrainAndStretch)
{
  itk::SheetMesh flat;
  CylinderPatch(10.0, 1.0, 8, 4, 3.0, flat);
  const itk::SheetMesh surface = flat; // planar surface
  for (double & v : flat.Points)
  {
    v *= 1.1;
  }
  auto c = vu::MeasureDistortion(surface, flat);
  EXPECT_NEAR(c->GetEdgeStrainMean(), 0.1, 1e-12);
  EXPECT_NEAR(c->GetEdgeStrainP95(), 0.1, 1e-12);
  EXPECT_NEAR(c->GetAreaDistortion(), 0.21, 1e-12);
  EXPECT_NEAR(c->GetTotalAreaRatio(), 1.21, 1e-12);
  EXPECT_NEAR(c->GetAngleDistortionDegrees(), 0.0, 1e-9);
  // The map from flat to 3D shrinks by 1/1.1 in every direction.
  EXPECT_NEAR(c->GetL2Stretch(), 1.0 / 1.1, 1e-12);
  EXPECT_NEAR(c->GetLinfStretch(), 1.0 / 1.1, 1e-12);
}

TEST(FlatteningDistortionCalculator, CountsFlippedTriangles)
{
  itk::SheetMesh flat;
  itk::SheetMesh surface = CylinderPatch(10.0, 1.0, 4, 4, 3.0, flat);
  // Fold one interior vertex across its neighbours: the triangles around it flip.
  const size_t v = 1 * 4 + 1;
  flat.Points[3 * v] = flat.Points[3 * (v + 1)] + 1.0;
  auto c = vu::MeasureDistortion(surface, flat);
  EXPECT_GT(c->GetNumberOfFlippedTriangles(), 0u);
  EXPECT_LT(c->GetNumberOfFlippedTriangles(), surface.GetNumberOfTriangles() / 2);
  EXPECT_GT(c->GetEdgeStrainMax(), 0.1);
}

TEST(FlatteningDistortionCalculator, RejectsMismatchedTopology)
{
  itk::SheetMesh flat;
  itk::SheetMesh surface = CylinderPatch(10.0, 1.0, 4, 4, 3.0, flat);
  flat.Triangles.resize(flat.Triangles.size() - 3);
  auto calculator = itk::FlatteningDistortionCalculator::New();
  calculator->SetSurfaceMesh(surface);
  calculator->SetFlatMesh(flat);
  VU_EXPECT_ITK_MACROS(ITK_TRY_EXPECT_EXCEPTION(calculator->Compute()));
  EXPECT_THROW(calculator->Compute(), itk::ExceptionObject);
}

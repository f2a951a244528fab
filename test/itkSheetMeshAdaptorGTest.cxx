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
#include "itkMesh.h"
#include "itkQuadEdgeMesh.h"
#include "itkQuadrilateralCell.h"
#include "itkSheetMeshAdaptor.h"

#include "gtest/gtest.h"

namespace {
itk::SheetMesh
GridSquare()
{
  itk::SheetMesh mesh;
  mesh.Points = { 0, 0, 0, 1, 0, 0.5, 0, 1, 0, 1, 1, 0.25 };
  mesh.Triangles = { 0, 1, 3, 0, 3, 2 };
  mesh.GridIndex = { 0, 0, 0, 1, 1, 0, 1, 1 };
  mesh.GridRows = 2;
  mesh.GridColumns = 2;
  return mesh;
}

template <typename TMesh>
void
ExpectRoundTrip()
{
  const itk::SheetMesh sheet = GridSquare();
  auto                 mesh = itk::SheetMeshToMesh<TMesh>(sheet);
  EXPECT_EQ(mesh->GetNumberOfPoints(), 4u);
  const itk::SheetMesh back = itk::MeshToSheetMesh(mesh.GetPointer());
  EXPECT_EQ(back.Points, sheet.Points);
  ASSERT_EQ(back.GetNumberOfTriangles(), 2u);
  EXPECT_EQ(back.GridIndex, sheet.GridIndex);
  EXPECT_EQ(back.GridRows, 2);
  EXPECT_EQ(back.GridColumns, 2);
  // Triangles keep their orientation (a QuadEdgeMesh may start a face at another corner).
  for (size_t t = 0; t < 2; ++t)
  {
    std::vector<uint32_t> a(sheet.Triangles.begin() + 3 * t, sheet.Triangles.begin() + 3 * t + 3);
    std::vector<uint32_t> b(back.Triangles.begin() + 3 * t, back.Triangles.begin() + 3 * t + 3);
    while (b[0] != a[0])
    {
      std::rotate(b.begin(), b.begin() + 1, b.end());
    }
    EXPECT_EQ(a, b);
  }
}
} // namespace

TEST(SheetMeshAdaptor, RoundTripThroughMesh)
{
  ExpectRoundTrip<itk::Mesh<float, 3>>();
  ExpectRoundTrip<itk::Mesh<double, 3, itk::DefaultStaticMeshTraits<double, 3, 3, double, double, double>>>();
}

TEST(SheetMeshAdaptor, RoundTripThroughQuadEdgeMesh) { ExpectRoundTrip<itk::QuadEdgeMesh<double, 3>>(); }

TEST(SheetMeshAdaptor, RejectsNonTriangleCells)
{
  using MeshType = itk::Mesh<float, 3>;
  auto mesh = MeshType::New();
  for (unsigned i = 0; i < 4; ++i)
  {
    MeshType::PointType p;
    p[0] = i;
    p[1] = i % 2;
    p[2] = 0;
    mesh->SetPoint(i, p);
  }
  using QuadType = itk::QuadrilateralCell<MeshType::CellType>;
  MeshType::CellAutoPointer cell;
  cell.TakeOwnership(new QuadType);
  for (unsigned i = 0; i < 4; ++i)
  {
    cell->SetPointId(i, i);
  }
  mesh->SetCell(0, cell);
  EXPECT_THROW(itk::MeshToSheetMesh(mesh.GetPointer()), itk::ExceptionObject);
  EXPECT_THROW(itk::MeshToSheetMesh(static_cast<MeshType *>(nullptr)), itk::ExceptionObject);
}

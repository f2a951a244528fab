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
#include "itkMassSpringFlatteningMeshFilter.h"
#include "itkMassSpringSheetFlattener.h"
#include "itkMeshFileWriter.h"
#include "itkQuadEdgeMesh.h"
#include "itkRegionOfInterestImageFilter.h"
#include "itkSheetMeshErrorCalculator.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSheetPhantomSource.h"
#include "itkSheetSegmentationImageFilter.h"
#include "vuTestHelpers.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

namespace {
using VolumeType = itk::Image<float, 3>;
using MaskType = itk::Image<unsigned char, 3>;
using MeshType = itk::Mesh<float, 3>;
using SegmentationType = itk::SheetSegmentationImageFilter<VolumeType, MaskType>;
using SurfaceType = itk::SheetMidSurfaceMeshFilter<MaskType, MeshType>;

struct PhantomResult
{
  itk::SheetMesh              Mesh;
  itk::SheetPhantomGeometry   Geometry;
  double                      Voxel{ 0.0 };
  double                      Threshold{ 0.0 };
  itk::SheetSurfaceMethodEnum Method{ itk::SheetSurfaceMethodEnum::Auto };
  size_t                      Warnings{ 0 };
  std::string                 WarningText;
  size_t                      GridSteps{ 0 };
};

// Segments and meshes a preset phantom with default parameters, as the tool does; with
// `cut`, that fraction of the box's width along x is left out of view.
PhantomResult
SegmentPhantom(const std::string & preset, double tilt = 0.0, double cut = 0.0)
{
  auto source = itk::SheetPhantomSource::New();
  source->ApplyPreset(preset);
  source->SetTiltAngle(tilt);
  source->Update();
  auto       region = source->GetOutput()->GetLargestPossibleRegion();
  const auto left = static_cast<itk::SizeValueType>(cut * static_cast<double>(region.GetSize(0)));
  region.SetIndex(0, region.GetIndex(0) + static_cast<itk::IndexValueType>(left));
  region.SetSize(0, region.GetSize(0) - left);
  auto view = itk::RegionOfInterestImageFilter<VolumeType, VolumeType>::New();
  view->SetInput(source->GetOutput());
  view->SetRegionOfInterest(region);
  auto segmentation = SegmentationType::New();
  segmentation->SetInput(view->GetOutput());
  auto surface = SurfaceType::New();
  surface->SetInput(segmentation->GetOutput());
  surface->SetIntensityImage(view->GetOutput());
  surface->Update();
  PhantomResult result;
  result.Mesh = surface->GetSheetMesh();
  result.Geometry = source->GetGeometry();
  result.Voxel = std::min(source->GetVoxelSize(), source->GetSliceSpacing());
  result.Threshold = segmentation->GetThreshold();
  result.Method = surface->GetReport().Method;
  result.Warnings = surface->GetWarnings().size();
  result.GridSteps = surface->GetReport().GridSteps.size();
  result.WarningText = surface->GetWarnings().empty() ? std::string() : surface->GetWarnings().front();
  for (const std::string & warning : surface->GetWarnings())
  {
    std::printf("[ warning  ] %s: %s\n", preset.c_str(), warning.c_str());
  }
  const std::string directory = std::string(VU_BINARY_DIR) + "/Testing/Segmentation";
  std::filesystem::create_directories(directory);
  auto writer = itk::MeshFileWriter<MeshType>::New();
  writer->SetInput(surface->GetOutput());
  writer->SetFileName(directory + "/" + preset + ".obj");
  writer->Update();
  return result;
}

// Number of connected pieces of a mesh (through shared vertices).
size_t
CountConnectedPieces(const itk::SheetMesh & mesh)
{
  std::vector<uint32_t> parent(mesh.GetNumberOfPoints());
  for (uint32_t i = 0; i < parent.size(); ++i)
  {
    parent[i] = i;
  }
  auto find = [&](uint32_t i) {
    while (parent[i] != i)
    {
      i = parent[i] = parent[parent[i]];
    }
    return i;
  };
  for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
  {
    parent[find(mesh.Triangles[3 * t + 1])] = find(mesh.Triangles[3 * t]);
    parent[find(mesh.Triangles[3 * t + 2])] = find(mesh.Triangles[3 * t]);
  }
  size_t pieces = 0;
  for (uint32_t i = 0; i < parent.size(); ++i)
  {
    pieces += find(i) == i ? 1 : 0;
  }
  return pieces;
}

struct Figures
{
  double MeanDistance, MaximumDistance, Coverage;
  size_t LayerJumps;
};

Figures
Measure(const std::string & preset, const PhantomResult & result)
{
  auto calculator = itk::SheetMeshErrorCalculator::New();
  calculator->SetGeometry(result.Geometry);
  calculator->SetMesh(result.Mesh);
  calculator->SetVoxelSize(result.Voxel);
  calculator->Compute();
  const Figures figures{ calculator->GetMeanVertexDistance(),
                         calculator->GetMaximumVertexDistance(),
                         calculator->GetCoverage(),
                         calculator->GetNumberOfLayerJumps() };
  std::printf("[ figures  ] %s: method %s, threshold %.0f, %zu points (%d x %d grid), %zu triangles, "
              "vertex distance mean %.3f max %.3f voxels, coverage %.2f %%, layer jumps %zu, %zu warning(s)\n",
              preset.c_str(),
              itk::ToString(result.Method),
              result.Threshold,
              result.Mesh.GetNumberOfPoints(),
              result.Mesh.GridRows,
              result.Mesh.GridColumns,
              result.Mesh.GetNumberOfTriangles(),
              figures.MeanDistance,
              figures.MaximumDistance,
              100.0 * figures.Coverage,
              figures.LayerJumps,
              result.Warnings);
  return figures;
}

// The mesh flattened by the mass-spring flattener, with its distortion printed as the
// figures of `name`.
itk::FlatteningDistortionCalculator::Pointer
FlattenAndReport(const itk::SheetMesh & mesh, const char * name)
{
  itk::MassSpringSheetFlattener flattener;
  const itk::SheetMesh          flat = flattener.Flatten(mesh);
  auto                          distortion = vu::MeasureDistortion(mesh, flat);
  std::printf("[ figures  ] %s flattened: edge strain mean %.5f p95 %.5f max %.5f, flipped %lu\n",
              name,
              distortion->GetEdgeStrainMean(),
              distortion->GetEdgeStrainP95(),
              distortion->GetEdgeStrainMax(),
              static_cast<unsigned long>(distortion->GetNumberOfFlippedTriangles()));
  return distortion;
}
} // namespace

TEST(SheetMidSurfaceMeshFilter, BasicObjectMethods)
{
  auto filter = SurfaceType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(filter, SheetMidSurfaceMeshFilter, ImageToMeshFilter));
  VU_EXPECT_ITK_MACROS(
    ITK_TEST_SET_GET_VALUE(0.3, (filter->SetSpacingAlongSheet(0.3), filter->GetSpacingAlongSheet())));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(0.4, (filter->SetSpacingAlongAxis(0.4), filter->GetSpacingAlongAxis())));
  VU_EXPECT_ITK_MACROS(
    ITK_TEST_SET_GET_VALUE(0.2, (filter->SetChordErrorFraction(0.2), filter->GetChordErrorFraction())));
  filter->SetMethod(itk::SheetSurfaceMethodEnum::General);
  EXPECT_EQ(filter->GetMethod(), itk::SheetSurfaceMethodEnum::General);
}

TEST(SheetMidSurfaceMeshFilter, StandardRollIsAccurateAndFlattens)
{
  const PhantomResult result = SegmentPhantom("standard");
  const Figures       figures = Measure("standard", result);
  EXPECT_EQ(result.Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_LE(figures.MeanDistance, 0.5);
  EXPECT_GE(figures.Coverage, 0.97);
  EXPECT_EQ(figures.LayerJumps, 0u);
  // The mesh's own check for layer jumps finds none either.
  EXPECT_EQ(result.GridSteps, 0u);
  EXPECT_EQ(CountConnectedPieces(result.Mesh), 1u);
  ASSERT_TRUE(result.Mesh.IsGridStructured());

  // Normals point to the roll axis, like the phantom's SurfaceNormal (the inked face).
  size_t agreeing = 0;
  for (size_t t = 0; t < result.Mesh.GetNumberOfTriangles(); ++t)
  {
    const double * p[3];
    for (int v = 0; v < 3; ++v)
    {
      p[v] = &result.Mesh.Points[3 * result.Mesh.Triangles[3 * t + v]];
    }
    const double u[3] = { p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2] };
    const double v[3] = { p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2] };
    const double n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
    double       s, w, d, truth[3];
    result.Geometry.Project(p[0], s, w, d);
    result.Geometry.SurfaceNormal(s, w, truth);
    agreeing += n[0] * truth[0] + n[1] * truth[1] + n[2] * truth[2] > 0.0 ? 1 : 0;
  }
  EXPECT_EQ(agreeing, result.Mesh.GetNumberOfTriangles());

  // Columns run from the inner end outwards: column 0 projects near s = 0.
  double s0, w0, d0;
  result.Geometry.Project(&result.Mesh.Points[0], s0, w0, d0);
  EXPECT_LT(s0, 0.1 * result.Geometry.GetSheetLength());

  const auto distortion = FlattenAndReport(result.Mesh, "standard");
  EXPECT_LT(distortion->GetEdgeStrainP95(), 0.01);
  // Slices aligned along the sheet keep the grid developable enough not to crease.
  EXPECT_EQ(distortion->GetNumberOfFlippedTriangles(), 0u);
}

TEST(SheetMidSurfaceMeshFilter, PapyrusMicroCTIsAccurate)
{
  const PhantomResult result = SegmentPhantom("papyrus-microct");
  const Figures       figures = Measure("papyrus-microct", result);
  EXPECT_LE(figures.MeanDistance, 0.5);
  EXPECT_GE(figures.Coverage, 0.97);
  EXPECT_EQ(figures.LayerJumps, 0u);
  EXPECT_EQ(CountConnectedPieces(result.Mesh), 1u);
}

TEST(SheetMidSurfaceMeshFilter, TightAndCanvasAreCoveredWithoutLayerJumps)
{
  for (const char * preset : { "tight", "canvas-medical" })
  {
    const PhantomResult result = SegmentPhantom(preset);
    const Figures       figures = Measure(preset, result);
    EXPECT_GE(figures.Coverage, 0.90) << preset;
    EXPECT_EQ(figures.LayerJumps, 0u) << preset;
    EXPECT_EQ(result.GridSteps, 0u) << preset;
    EXPECT_EQ(CountConnectedPieces(result.Mesh), 1u) << preset;
  }
}

TEST(SheetMidSurfaceMeshFilter, SquashedAndFoldedGiveOneOpenMesh)
{
  for (const char * preset : { "squashed", "folded" })
  {
    const PhantomResult result = SegmentPhantom(preset);
    Measure(preset, result);
    EXPECT_EQ(CountConnectedPieces(result.Mesh), 1u) << preset;
    EXPECT_TRUE(result.Mesh.IsGridStructured()) << preset;
  }
}

namespace {
MaskType::Pointer
MakeMask(unsigned size, unsigned depth)
{
  auto                 mask = MaskType::New();
  MaskType::RegionType region;
  region.SetSize({ { size, size, depth } });
  mask->SetRegions(region);
  mask->Allocate();
  mask->FillBuffer(0);
  return mask;
}

// A flat sheet, three voxels thick, across the slices at rows y0..y0+2, columns x0..x1.
void
AddFlatSheet(MaskType * mask, long x0, long x1, long y0)
{
  const auto size = mask->GetLargestPossibleRegion().GetSize();
  for (long z = 0; z < static_cast<long>(size[2]); ++z)
  {
    for (long y = y0; y < y0 + 3; ++y)
    {
      for (long x = x0; x <= x1; ++x)
      {
        mask->SetPixel({ { x, y, z } }, 1);
      }
    }
  }
}
} // namespace

TEST(SheetMidSurfaceMeshFilter, FlatSheetWithAStrayPieceMeshesTheSheetAndWarns)
{
  auto mask = MakeMask(40, 12);
  mask->SetSpacing(0.5);
  AddFlatSheet(mask, 4, 35, 10);
  // A small separate fragment.
  mask->SetPixel({ { 30, 30, 5 } }, 1);
  mask->SetPixel({ { 30, 31, 5 } }, 1);
  auto filter = SurfaceType::New();
  filter->SetInput(mask);
  filter->SetMethod(itk::SheetSurfaceMethodEnum::General);
  filter->Update();
  const itk::SheetMesh & mesh = filter->GetSheetMesh();
  ASSERT_EQ(filter->GetWarnings().size(), 1u);
  EXPECT_NE(filter->GetWarnings()[0].find("2 disconnected pieces"), std::string::npos) << filter->GetWarnings()[0];
  EXPECT_EQ(CountConnectedPieces(mesh), 1u);
  ASSERT_TRUE(mesh.IsGridStructured());
  // The mid-surface of voxel rows 10..12 is y = 11 voxels = 5.5 mm; x spans the sheet.
  double minimumX = 1e9, maximumX = -1e9;
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    EXPECT_NEAR(mesh.Points[3 * i + 1], 5.5, 0.05);
    minimumX = std::min(minimumX, mesh.Points[3 * i]);
    maximumX = std::max(maximumX, mesh.Points[3 * i]);
  }
  EXPECT_LT(minimumX, 2.0 + 0.5);
  EXPECT_GT(maximumX, 17.5 - 0.5);
  EXPECT_EQ(filter->GetOutput()->GetNumberOfPoints(), mesh.GetNumberOfPoints());
  EXPECT_EQ(filter->GetOutput()->GetNumberOfCells(), mesh.GetNumberOfTriangles());
  EXPECT_EQ(filter->GetReport().Method, itk::SheetSurfaceMethodEnum::General);

  // User spacing: about 2 mm along the sheet.
  filter->SetSpacingAlongSheet(2.0);
  filter->SetSpacingAlongAxis(1.0);
  filter->Update();
  EXPECT_NEAR(filter->GetReport().SpacingAlongSheet, 2.0, 0.3);
  EXPECT_NEAR(filter->GetReport().SpacingAlongAxis, 1.0, 0.15);
}

// Two flat sheets joined by a wall between them, meshed as one piece: the trace follows one
// path through them (measured: 0.61 to 0.81 of the material), and the report says how much
// it leaves away from it. The gap and the wall's place are drawn at run time.
TEST(SheetMidSurfaceMeshFilter, MaterialTheTraceDoesNotFollowIsReported)
{
  std::mt19937 random(vu::RunTimeSeed());
  const long   gap = std::uniform_int_distribution<long>(4, 8)(random);
  const long   wall = std::uniform_int_distribution<long>(12, 20)(random);
  auto         mask = MakeMask(40, 12);
  mask->SetSpacing(0.5);
  AddFlatSheet(mask, 4, 35, 10);
  auto filter = SurfaceType::New();
  filter->SetInput(mask);
  filter->SetMethod(itk::SheetSurfaceMethodEnum::General);
  filter->Update();
  EXPECT_GT(filter->GetReport().TracedShare, 0.95);
  AddFlatSheet(mask, 4, 35, 13 + gap);
  for (long z = 0; z < 12; ++z)
  {
    for (long y = 13; y < 13 + gap; ++y)
    {
      for (long x = wall; x < wall + 3; ++x)
      {
        mask->SetPixel({ { x, y, z } }, 1);
      }
    }
  }
  mask->Modified();
  filter->Update();
  const double share = filter->GetReport().TracedShare;
  std::cout << "gap " << gap << ", wall at " << wall << ": traced share " << share << std::endl;
  EXPECT_LT(share, 0.85);
  EXPECT_GT(share, 0.3);
  const auto & warnings = filter->GetWarnings();
  EXPECT_TRUE(std::any_of(warnings.begin(), warnings.end(), [](const std::string & w) {
    return w.find("lies away from the traced sheet") != std::string::npos;
  }));
}

// Three flat sheets apart and a scatter of specks: with EverySheet each sheet is meshed on
// its own (largest first, output i is sheet i), the specks are counted, not meshed, and a
// seed point picks the sheet it lies on.
TEST(SheetMidSurfaceMeshFilter, EverySheetIsMeshedAndSpecksAreCounted)
{
  auto mask = MakeMask(60, 14);
  mask->SetSpacing(0.5);
  AddFlatSheet(mask, 4, 55, 8);   // 52 voxels long
  AddFlatSheet(mask, 4, 45, 20);  // 42
  AddFlatSheet(mask, 10, 45, 32); // 36
  std::mt19937 random(vu::RunTimeSeed());
  unsigned     specks = 0;
  for (int i = 0; i < 40; ++i)
  {
    // Single voxels and pairs in the air between and below the sheets.
    const long x = 2 + static_cast<long>(random() % 56), y = 42 + static_cast<long>(random() % 16);
    const long z = static_cast<long>(random() % 14);
    if (mask->GetPixel({ { x, y, z } }) == 0 && mask->GetPixel({ { x - 1, y, z } }) == 0 &&
        mask->GetPixel({ { x + 1, y, z } }) == 0 && mask->GetPixel({ { x, y - 1, z } }) == 0 &&
        mask->GetPixel({ { x, y + 1, z } }) == 0 && mask->GetPixel({ { x, y, z - 1 } }) == 0 &&
        mask->GetPixel({ { x, y, z + 1 } }) == 0)
    {
      mask->SetPixel({ { x, y, z } }, 1);
      ++specks;
    }
  }
  auto filter = SurfaceType::New();
  filter->SetInput(mask);
  filter->SetMethod(itk::SheetSurfaceMethodEnum::General);
  filter->EverySheetOn();
  filter->Update();
  ASSERT_EQ(filter->GetNumberOfSheets(), 3u);
  EXPECT_EQ(filter->GetDroppedPieces().TooSmall, specks);
  EXPECT_TRUE(filter->GetDroppedPieces().NotTraced.empty());
  const double rows[3] = { 9.0, 21.0, 33.0 };
  const double lengths[3] = { 52.0, 42.0, 36.0 };
  for (unsigned int sheet = 0; sheet < 3; ++sheet)
  {
    const itk::SheetMesh & mesh = filter->GetSheetMesh(sheet);
    EXPECT_EQ(CountConnectedPieces(mesh), 1u);
    EXPECT_EQ(filter->GetSheetOutput(sheet)->GetNumberOfPoints(), mesh.GetNumberOfPoints());
    for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      ASSERT_NEAR(mesh.Points[3 * i + 1], 0.5 * rows[sheet], 0.05) << "sheet " << sheet << ", point " << i;
    }
    const itk::SheetSummary & summary = filter->GetSheetSummary(sheet);
    EXPECT_EQ(summary.Voxels, static_cast<size_t>(3 * 14 * lengths[sheet]));
    EXPECT_NEAR(summary.Area, 0.25 * 14 * lengths[sheet], 0.1 * 0.25 * 14 * lengths[sheet]);
    EXPECT_NEAR(summary.BoundsMinimum[1], 0.5 * rows[sheet], 0.05);
    EXPECT_GT(summary.Confidence, 0.9);
    itk::Point<double, 3> seed;
    seed[0] = 10.0;
    seed[1] = 0.5 * rows[sheet] + 1.0;
    seed[2] = 3.0;
    EXPECT_EQ(filter->FindSheetNearestTo(seed), sheet);
  }
  EXPECT_EQ(filter->GetOutput()->GetNumberOfPoints(), filter->GetSheetMesh().GetNumberOfPoints());

  // A minimum area above the smaller sheets keeps the largest; above every sheet: an error.
  filter->SetMinimumSheetArea(0.25 * 14 * 50.0);
  filter->Update();
  EXPECT_EQ(filter->GetNumberOfSheets(), 1u);
  EXPECT_EQ(filter->GetDroppedPieces().TooSmall, specks + 2);
  filter->SetMinimumSheetArea(1e6);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject);

  // Without EverySheet: the largest only, as before.
  filter->SetMinimumSheetArea(0.0);
  filter->EverySheetOff();
  filter->Update();
  EXPECT_EQ(filter->GetNumberOfSheets(), 1u);
  EXPECT_NEAR(filter->GetSheetMesh().Points[1], 4.5, 0.05);
}

// The largest piece is no sheet (a ball: no slice of it traces) and a smaller piece is: with
// EverySheet the sheet is meshed and the ball dropped with the reason; for the largest piece
// alone, the error.
TEST(SheetMidSurfaceMeshFilter, AnUntraceableLargestPieceIsDroppedAndTheOthersMeshed)
{
  auto mask = MakeMask(60, 24);
  mask->SetSpacing(0.5);
  AddFlatSheet(mask, 4, 55, 8);
  size_t ball = 0;
  for (long z = 0; z < 24; ++z)
  {
    for (long y = 28; y < 53; ++y)
    {
      for (long x = 18; x < 43; ++x)
      {
        if ((x - 30) * (x - 30) + (y - 40) * (y - 40) + (z - 12) * (z - 12) <= 11 * 11)
        {
          mask->SetPixel({ { x, y, z } }, 1);
          ++ball;
        }
      }
    }
  }
  ASSERT_GT(ball, static_cast<size_t>(3 * 52 * 24));
  auto filter = SurfaceType::New();
  filter->SetInput(mask);
  filter->SetMethod(itk::SheetSurfaceMethodEnum::General);
  filter->EverySheetOn();
  ASSERT_NO_THROW(filter->Update());
  ASSERT_EQ(filter->GetNumberOfSheets(), 1u);
  ASSERT_EQ(filter->GetDroppedPieces().NotTraced.size(), 1u);
  EXPECT_EQ(filter->GetDroppedPieces().NotTraced[0].Voxels, ball);
  EXPECT_GT(filter->GetDroppedPieces().NotTraced[0].Area, 0.0);
  EXPECT_FALSE(filter->GetDroppedPieces().NotTraced[0].Reason.empty());
  EXPECT_FALSE(filter->GetDroppedPieces().NotTraced[0].SplitFromPiece);
  EXPECT_EQ(filter->GetSheetSummary(0).Voxels, static_cast<size_t>(3 * 52 * 24));
  const itk::SheetMesh & mesh = filter->GetSheetMesh();
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    ASSERT_NEAR(mesh.Points[3 * i + 1], 4.5, 0.05) << "point " << i;
  }
  bool noted = false;
  for (const std::string & warning : filter->GetWarnings())
  {
    noted = noted || warning.find("could not be traced") != std::string::npos;
  }
  EXPECT_TRUE(noted);

  filter->EverySheetOff();
  EXPECT_THROW(filter->Update(), itk::ExceptionObject);
}

// Specks alone (noise, no sheet): a clear error, not a mesh of a speck.
TEST(SheetMidSurfaceMeshFilter, SpecksWithoutASheetAreRefused)
{
  auto         mask = MakeMask(60, 14);
  std::mt19937 random(vu::RunTimeSeed());
  for (int i = 0; i < 3000; ++i)
  {
    mask->SetPixel(
      { { static_cast<long>(random() % 60), static_cast<long>(random() % 60), static_cast<long>(random() % 14) } }, 1);
  }
  auto filter = SurfaceType::New();
  filter->SetInput(mask);
  filter->EverySheetOn();
  try
  {
    filter->Update();
    FAIL() << "specks were meshed as " << filter->GetNumberOfSheets() << " sheet(s)";
  }
  catch (const itk::ExceptionObject & e)
  {
    EXPECT_NE(std::string(e.GetDescription()).size(), 0u);
  }
}

TEST(SheetMidSurfaceMeshFilter, BadInputThrows)
{
  auto filter = SurfaceType::New();
  filter->SetInput(MakeMask(20, 10));
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // empty mask

  auto tiny = MakeMask(2, 2);
  tiny->FillBuffer(1);
  filter->SetInput(tiny);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // too small

  auto mask = MakeMask(40, 12);
  AddFlatSheet(mask, 4, 35, 10);
  filter->SetInput(mask);
  auto                   intensity = VolumeType::New();
  VolumeType::RegionType region;
  region.SetSize({ { 10, 10, 10 } });
  intensity->SetRegions(region);
  intensity->Allocate();
  filter->SetIntensityImage(intensity);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // intensity of another size
  filter->SetIntensityImage(nullptr);
  filter->SetChordErrorFraction(0.0);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // bad parameter

  auto single = MakeMask(40, 1);
  AddFlatSheet(single, 4, 35, 10);
  filter->SetChordErrorFraction(0.1);
  filter->SetInput(single);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // one slice only
}

// A field of view that cuts the roll on one side leaves its inner part in one piece and the
// outer turns as arcs around it: the arcs are meshed with it, through the part out of view.
TEST(SheetMidSurfaceMeshFilter, RollCutByTheFieldOfViewIsMeshedWhole)
{
  const PhantomResult result = SegmentPhantom("standard", 0.0, 1.0 / 8.0);
  const Figures       figures = Measure("standard cut by the field of view", result);
  EXPECT_NE(result.WarningText.find("cut by the field of view"), std::string::npos) << result.WarningText;
  EXPECT_EQ(result.Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_LE(figures.MeanDistance, 0.5);
  EXPECT_EQ(figures.LayerJumps, 0u);
  // The outer turns alone are more than a third of the sheet; the turns are carried through
  // the eighth out of view.
  EXPECT_GE(figures.Coverage, 0.97);
}

TEST(SheetMidSurfaceMeshFilter, TiltedRollIsResampledAlongItsAxis)
{
  const PhantomResult result = SegmentPhantom("standard", 20.0);
  const Figures       figures = Measure("standard tilted 20 degrees", result);
  EXPECT_NE(result.WarningText.find("resampled along the roll axis"), std::string::npos) << result.WarningText;
  // The axis is found to a fraction of a degree (a central-difference gradient made it 22).
  const std::string tiltedBy = "tilted by ";
  const size_t      at = result.WarningText.find(tiltedBy);
  ASSERT_NE(at, std::string::npos) << result.WarningText;
  EXPECT_NEAR(std::stod(result.WarningText.substr(at + tiltedBy.size())), 20.0, 0.5) << result.WarningText;
  EXPECT_LE(figures.MeanDistance, 0.5);
  EXPECT_GE(figures.Coverage, 0.97);
  EXPECT_EQ(figures.LayerJumps, 0u);
  EXPECT_EQ(CountConnectedPieces(result.Mesh), 1u);
}

TEST(SheetMidSurfaceMeshFilter, EveryOtherPresetMeshFlattens)
{
  for (const char * preset : { "tight", "squashed", "folded", "canvas-medical", "papyrus-microct" })
  {
    const PhantomResult result = SegmentPhantom(preset);
    const auto          distortion = FlattenAndReport(result.Mesh, preset);
    EXPECT_LT(distortion->GetEdgeStrainP95(), 0.01) << preset;
    EXPECT_EQ(distortion->GetNumberOfFlippedTriangles(), 0u) << preset;
  }
}

// A QuadEdgeMesh deletes its cells when it is destroyed: the filters must build their
// outputs in place, not share containers with a temporary mesh (this crashed in Python).
TEST(SheetMidSurfaceMeshFilter, QuadEdgeMeshOutputFlattensThroughTheFilter)
{
  using VolumeType = itk::Image<float, 3>;
  using MaskType = itk::Image<unsigned char, 3>;
  using QEMesh = itk::QuadEdgeMesh<double, 3>;
  auto source = itk::SheetPhantomSource::New();
  source->SetNumberOfTurns(1.5);
  source->SetSheetWidth(5.0);
  source->SetGlyphHeight(1.0);
  source->SetText("AB");
  auto segmentation = itk::SheetSegmentationImageFilter<VolumeType, MaskType>::New();
  segmentation->SetInput(source->GetOutput());
  auto surfaceFilter = itk::SheetMidSurfaceMeshFilter<MaskType, QEMesh>::New();
  surfaceFilter->SetInput(segmentation->GetOutput());
  surfaceFilter->SetIntensityImage(source->GetOutput());
  auto flattening = itk::MassSpringFlatteningMeshFilter<QEMesh, QEMesh>::New();
  flattening->SetInput(surfaceFilter->GetOutput());
  ASSERT_NO_THROW(flattening->Update());
  const QEMesh * surface = surfaceFilter->GetOutput();
  const QEMesh * flat = flattening->GetOutput();
  ASSERT_GT(surface->GetNumberOfPoints(), 100u);
  EXPECT_EQ(flat->GetNumberOfPoints(), surface->GetNumberOfPoints());
  EXPECT_EQ(flat->GetNumberOfFaces(), surface->GetNumberOfFaces());
  auto distortion = itk::FlatteningDistortionCalculator::New();
  distortion->SetSurfaceMesh(surface);
  distortion->SetFlatMesh(flat);
  distortion->Compute();
  EXPECT_LT(distortion->GetEdgeStrainP95(), 0.01);
  EXPECT_EQ(distortion->GetNumberOfFlippedTriangles(), 0u);
}

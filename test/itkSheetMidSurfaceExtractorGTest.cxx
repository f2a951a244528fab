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
#include "itkSheetMidSurfaceExtractor.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace {
constexpr double Pi = 3.14159265358979323846;

// The pinch (voxels) that pushes the second turn onto the first one at 1 <= theta - 2 pi <= 2
// in slices [from, to), growing over the first four of them and shrinking over the last four.
double
Pinch(double theta, double z, double from, double to)
{
  const double t = theta - 2.0 * Pi - 1.0;
  const double along = std::clamp(std::min(z - from + 1.0, to - z) / 4.0, 0.0, 1.0);
  return t >= 0.0 && t <= 1.0 && z >= from && z < to ? 3.0 * along * std::pow(std::sin(Pi * t), 2.0) : 0.0;
}

// A rasterised Archimedean spiral mask (no intensities): r = 12 + 6 theta / (2 pi) voxels,
// 2.5 turns, 3 voxels thick, 1 voxel spacing, 8 slices (or `slices`); centre at (40, 40).
// From slice `gapFrom` on, the sheet is missing where 2 pi <= theta <= 2 pi + 0.6 (a
// stretch of 11 voxels of the second turn: a faint stretch, a crack). In slices
// [touchFrom, touchTo) the second turn is pinched onto the first (Pinch: in the middle
// slices they touch over about 10 voxels of arc).
struct SpiralVolume
{
  size_t               Size[3]{ 80, 80, 8 };
  std::vector<uint8_t> Mask;
  std::vector<uint8_t> Data;
  std::vector<float>   Intensity;
  // `twist`: the whole spiral turned by that angle (radians) per slice about its centre;
  // `taper`: its radius grown by that many voxels per slice.
  explicit SpiralVolume(size_t slices = 8,
                        size_t gapFrom = 1000,
                        size_t touchFrom = 0,
                        size_t touchTo = 0,
                        double twist = 0.0,
                        double taper = 0.0)
    : Size{ 80, 80, slices }
    , Mask(Size[0] * Size[1] * Size[2], 0)
  {
    for (size_t j = 0; j < Size[1]; ++j)
    {
      for (size_t i = 0; i < Size[0]; ++i)
      {
        const double x = static_cast<double>(i) - 40.0, y = static_cast<double>(j) - 40.0;
        const double r = std::hypot(x, y);
        for (size_t k = 0; k < Size[2]; ++k)
        {
          double phi = std::remainder(std::atan2(y, x) - twist * static_cast<double>(k), 2.0 * Pi);
          phi = phi < 0.0 ? phi + 2.0 * Pi : phi;
          bool inside = false;
          for (int turn = 0; turn < 3; ++turn)
          {
            const double theta = phi + 2.0 * Pi * turn;
            const double mid =
              12.0 + taper * static_cast<double>(k) + 6.0 * theta / (2.0 * Pi) -
              Pinch(theta, static_cast<double>(k), static_cast<double>(touchFrom), static_cast<double>(touchTo));
            if (theta <= 2.5 * 2.0 * Pi && std::abs(r - mid) <= 1.5)
            {
              inside = true;
            }
          }
          const bool inGap =
            inside && phi <= 0.6 && std::abs(r - 18.0) < std::abs(r - 12.0) && std::abs(r - 18.0) < std::abs(r - 24.0);
          Mask[(k * Size[1] + j) * Size[0] + i] = inside && !(inGap && k >= gapFrom) ? 1 : 0;
        }
      }
    }
  }
  itk::SheetVolumeView
  View() const
  {
    itk::SheetVolumeView view;
    view.Mask = Mask.data();
    view.Data = Data.empty() ? nullptr : Data.data();
    view.Intensity = Intensity.empty() ? nullptr : Intensity.data();
    for (int d = 0; d < 3; ++d)
    {
      view.Size[d] = Size[d];
    }
    return view;
  }
};
// Every vertex of a mesh of SpiralVolume lies within `tolerance` of the spiral's mid-line
// (pinched in slices [touchFrom, touchTo)); the end columns within 1.5 voxels of its ends,
// (12, 0) inside and (-27, 0) outside.
void
ExpectOnTheSpiral(const itk::SheetMesh & mesh, double tolerance, double touchFrom = 0.0, double touchTo = 0.0)
{
  for (size_t p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    const double x = mesh.Points[3 * p] - 40.0, y = mesh.Points[3 * p + 1] - 40.0;
    const int    column = mesh.GridIndex[2 * p + 1];
    if (column == 0 || column == mesh.GridColumns - 1)
    {
      EXPECT_LT(column == 0 ? std::hypot(x - 12.0, y) : std::hypot(x + 27.0, y), 1.5) << "point " << p;
      continue;
    }
    const double r = std::hypot(x, y);
    double       phi = std::atan2(y, x);
    phi = phi < 0.0 ? phi + 2.0 * Pi : phi;
    double       nearest = 1e9;
    const double z = mesh.Points[3 * p + 2];
    for (int turn = 0; turn < 3; ++turn)
    {
      const double theta = phi + 2.0 * Pi * turn;
      nearest =
        std::min(nearest, std::abs(r - (12.0 + 6.0 * theta / (2.0 * Pi) - Pinch(theta, z, touchFrom, touchTo))));
    }
    EXPECT_LT(nearest, tolerance) << "point " << p << " at (" << x << ", " << y << ", " << z << ")";
  }
}

// Distance (voxels) of a point (x, y relative to the centre, in slice z) from the mid-line
// of SpiralVolume turned by `twist` radian and grown by `taper` voxels per slice.
double
FromTheSpiral(double x, double y, double z, double twist = 0.0, double taper = 0.0)
{
  double phi = std::remainder(std::atan2(y, x) - twist * z, 2.0 * Pi);
  phi = phi < 0.0 ? phi + 2.0 * Pi : phi;
  double nearest = 1e9;
  for (int turn = 0; turn < 3; ++turn)
  {
    nearest =
      std::min(nearest, std::abs(std::hypot(x, y) - (12.0 + taper * z + 6.0 * (phi + 2.0 * Pi * turn) / (2.0 * Pi))));
  }
  return nearest;
}

// How many of a mesh's points satisfy keep(z, column), and the farthest of them from the
// mid-line of SpiralVolume turned by `twist` and grown by `taper` per slice (FromTheSpiral).
template <typename Keep>
std::pair<size_t, double>
FarthestFromTheSpiral(const itk::SheetMesh & mesh, double twist, double taper, Keep keep)
{
  size_t count = 0;
  double largest = 0.0;
  for (size_t p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    const double z = mesh.Points[3 * p + 2];
    if (keep(z, mesh.GridIndex[2 * p + 1]))
    {
      ++count;
      largest =
        std::max(largest, FromTheSpiral(mesh.Points[3 * p] - 40.0, mesh.Points[3 * p + 1] - 40.0, z, twist, taper));
    }
  }
  return { count, largest };
}
} // namespace

TEST(SheetMidSurfaceExtractor, MethodNames)
{
  EXPECT_STREQ(itk::ToString(itk::SheetSurfaceMethodEnum::Roll), "roll");
  EXPECT_EQ(itk::SheetSurfaceMethodFromString("general"), itk::SheetSurfaceMethodEnum::General);
  EXPECT_EQ(itk::SheetSurfaceMethodFromString("auto"), itk::SheetSurfaceMethodEnum::Auto);
  EXPECT_THROW(itk::SheetSurfaceMethodFromString("spiral"), itk::ExceptionObject);
}

TEST(SheetMidSurfaceExtractor, SpiralMaskGivesTheSpiralFromItsInnerEnd)
{
  const SpiralVolume            volume;
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  const auto &                  report = extractor.GetReport();
  EXPECT_EQ(report.Method, itk::SheetSurfaceMethodEnum::Roll);
  ASSERT_TRUE(mesh.IsGridStructured());
  EXPECT_EQ(mesh.GetNumberOfPoints(), static_cast<size_t>(mesh.GridRows) * mesh.GridColumns);
  EXPECT_EQ(mesh.GetNumberOfTriangles(), 2u * (mesh.GridRows - 1) * (mesh.GridColumns - 1));
  // Every vertex lies on the spiral (within half a voxel), the end columns at its ends.
  ExpectOnTheSpiral(mesh, 0.5);
  // Arc length of 2.5 turns: integral of sqrt(r^2 + (dr/dtheta)^2), about 306 voxels.
  EXPECT_NEAR(report.SheetLength, 306.0, 6.0);
  EXPECT_NEAR(report.SheetThickness, 3.0, 0.5);
  EXPECT_TRUE(report.Warnings.empty());

  // The general tracer follows the same sheet.
  itk::SheetMidSurfaceParameters parameters;
  parameters.Method = itk::SheetSurfaceMethodEnum::General;
  extractor.SetParameters(parameters);
  const itk::SheetMesh general = extractor.Extract(volume.View());
  EXPECT_NEAR(extractor.GetReport().SheetLength, 306.0, 10.0);
  // It too starts at the end nearer the axis, the inner end (12, 0).
  EXPECT_LT(std::hypot(general.Points[0] - 52.0, general.Points[1] - 40.0), 1.5);

  // User spacing.
  parameters.Method = itk::SheetSurfaceMethodEnum::Roll;
  parameters.SpacingAlongSheet = 10.0;
  parameters.SpacingAlongAxis = 7.0;
  extractor.SetParameters(parameters);
  const itk::SheetMesh coarse = extractor.Extract(volume.View());
  EXPECT_EQ(coarse.GridRows, 2);
  EXPECT_NEAR(extractor.GetReport().SpacingAlongSheet, 10.0, 0.5);
}

TEST(SheetMidSurfaceExtractor, TraceResumesBeyondAStretchItCannotFollow)
{
  // The seed is the middle slice (12); from slice 16 on, 11 voxels of the second turn are
  // missing. A trace that stopped there would lose the outer turn and a half for every
  // slice after it; it is resumed beyond the stretch and joined across it on the curve of
  // the slice before.
  const SpiralVolume            volume(24, 16);
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  const auto &                  report = extractor.GetReport();
  EXPECT_EQ(report.Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_EQ(report.InterpolatedSlices, 0u);
  EXPECT_NEAR(report.SheetLength, 306.0, 6.0);
  ExpectOnTheSpiral(mesh, 1.0);
  double zMin = 1e9, zMax = -1e9;
  for (size_t p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    zMin = std::min(zMin, mesh.Points[3 * p + 2]);
    zMax = std::max(zMax, mesh.Points[3 * p + 2]);
  }
  // Every slice meshed, the whole turn and a half beyond the stretch included.
  EXPECT_LE(zMin, 0.5);
  EXPECT_GE(zMax, 22.5);
  // No slice left out, interpolated or jumping (the missing stretch shifts the slices'
  // centroids, which may read as a slight tilt of the axis).
  for (const std::string & warning : report.Warnings)
  {
    EXPECT_EQ(warning.find("slice(s)"), std::string::npos) << warning;
  }
}

TEST(SheetMidSurfaceExtractor, TurnsBeyondTheScansDataAreCarriedAcross)
{
  // A field of view that cuts the roll: from x = 62 on (an arc of the outer turn, where the
  // second and a half turns pass x = 64) the volume holds no data of the scan. The trace
  // carries the turn across on the shape of the turn before and picks it up beyond; a
  // tracer that took the missing data for air would end the sheet there.
  SpiralVolume volume(8);
  volume.Data.assign(volume.Mask.size(), 1);
  for (size_t k = 0; k < volume.Size[2]; ++k)
  {
    for (size_t j = 0; j < volume.Size[1]; ++j)
    {
      for (size_t i = 62; i < volume.Size[0]; ++i)
      {
        volume.Mask[(k * volume.Size[1] + j) * volume.Size[0] + i] = 0;
        volume.Data[(k * volume.Size[1] + j) * volume.Size[0] + i] = 0;
      }
    }
  }
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  EXPECT_EQ(extractor.GetReport().Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_NEAR(extractor.GetReport().SheetLength, 306.0, 8.0);
  ExpectOnTheSpiral(mesh, 1.0);

  // Without the data mask the same volume reads as a sheet that ends at the cut.
  volume.Data.clear();
  extractor.Extract(volume.View());
  EXPECT_LT(extractor.GetReport().SheetLength, 290.0);
}

TEST(SheetMidSurfaceExtractor, TouchingTurnsAreNotJumped)
{
  // In slices 5 to 18 of 24 (every candidate seed slice among them) the second turn is
  // pinched onto the first over about 10 voxels of arc (less in the slices 2 to 4 and 19 to
  // 21 on both sides): the two read as one thick sheet there. A trace that takes the merged sheet for the next turn
  // loses a turn or crosses between turns; the mesh must stay on the sheet, one turn after the other.
  const SpiralVolume            volume(24, 1000, 2, 22);
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  const auto &                  report = extractor.GetReport();
  EXPECT_EQ(report.Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_NEAR(report.SheetLength, 306.0, 8.0);
  // Every vertex on its own turn (the turns lie 6 voxels apart); the pinch bends the second
  // turn by 3 voxels over 3 mesh columns, which the mesh follows to within 1.6 voxels.
  ExpectOnTheSpiral(mesh, 1.6, 2.0, 22.0);
}

TEST(SheetMidSurfaceExtractor, SlicesThatCannotBeTracedAreInterpolatedAlongTheTurns)
{
  // The spiral turns by 0.05 radian per slice, and slices 10 to 21 of 32 hold no sheet
  // (untraceable): they are interpolated from slices 9 and 22, whose points at the same
  // fraction of the sheet lie 0.65 radian apart. On the chords between them the mesh lay up
  // to 3 voxels inside the turns; along the turns it stays on the sheet.
  constexpr double twist = 0.05;
  SpiralVolume     volume(32, 1000, 0, 0, twist);
  const size_t     sliceSize = volume.Size[0] * volume.Size[1];
  std::fill(volume.Mask.begin() + 10 * sliceSize, volume.Mask.begin() + 22 * sliceSize, 0);
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  const auto &                  report = extractor.GetReport();
  EXPECT_EQ(report.Method, itk::SheetSurfaceMethodEnum::Roll);
  EXPECT_GE(report.InterpolatedSlices, 12u);
  const auto [interpolatedPoints, largest] = FarthestFromTheSpiral(mesh, twist, 0.0, [&](double z, int column) {
    return column != 0 && column != mesh.GridColumns - 1 && z >= 9.5 && z <= 21.5;
  });
  EXPECT_GT(interpolatedPoints, 0u);
  EXPECT_LT(largest, 0.75); // 0.67; the traced slices' points reach as far
}

TEST(SheetMidSurfaceExtractor, ColumnsSlidingAlongTheirTurnKeepTheRowsOnTheSheet)
{
  // The spiral turns by 0.25 radian per slice, so a column (a fixed fraction of the sheet's
  // length) slides along its turn by 3 to 7 voxels from one slice to the next, as where a
  // roll's sheet is longer in some slices than in others. A row's window then holds no
  // majority of points near their median point taken coordinate by coordinate, which lies
  // between two slices' points, off the sheet (2.7 voxels); the column's radius and angle
  // about the axis, fitted along the window, keep the row on its turn (0.76).
  constexpr double               twist = 0.25;
  SpiralVolume                   volume(16, 1000, 0, 0, twist);
  itk::SheetMidSurfaceExtractor  extractor;
  itk::SheetMidSurfaceParameters parameters;
  parameters.SpacingAlongAxis = 0.5; // every other row halfway between two slices
  extractor.SetParameters(parameters);
  const itk::SheetMesh mesh = extractor.Extract(volume.View());
  EXPECT_EQ(extractor.GetReport().Method, itk::SheetSurfaceMethodEnum::Roll);
  // Inner rows only: the edge rows, past the traced slices, are fitted differently.
  const auto [inner, largest] = FarthestFromTheSpiral(mesh, twist, 0.0, [&](double z, int column) {
    return column >= 2 && column <= mesh.GridColumns - 3 && z >= 2.0 && z <= 13.0;
  });
  std::cout << "inner rows: " << inner << " points, farthest " << largest << " voxel from the sheet" << std::endl;
  EXPECT_GT(inner, 0u);
  EXPECT_LT(largest, 1.0);
}

TEST(SheetMidSurfaceExtractor, RowsPastTheTracedSlicesFollowTheRollsTaper)
{
  // The spiral's radius grows by 0.4 voxel per slice; the first and last three of its 24
  // slices hold only part of the sheet (theta mod 2 pi beyond 1.2 pi missing: the faint,
  // broken edge of a sheet along the axis), so they are not traced and the mesh reaches
  // over them from the traced ones, half a slice past the last. On the curve of the nearest
  // traced slices the edge rows lay up to 2.1 voxels off the sheet; extrapolated from the
  // rows inside along the roll's angle and radius 1.2; on the last slices' own trend 0.94.
  constexpr double taper = 0.4;
  SpiralVolume     volume(24, 1000, 0, 0, 0.0, taper);
  for (size_t k : { 0, 1, 2, 21, 22, 23 })
  {
    for (size_t j = 0; j < volume.Size[1]; ++j)
    {
      for (size_t i = 0; i < volume.Size[0]; ++i)
      {
        double phi = std::atan2(static_cast<double>(j) - 40.0, static_cast<double>(i) - 40.0);
        phi = phi < 0.0 ? phi + 2.0 * Pi : phi;
        if (phi > 1.2 * Pi)
        {
          volume.Mask[(k * volume.Size[1] + j) * volume.Size[0] + i] = 0;
        }
      }
    }
  }
  itk::SheetMidSurfaceExtractor extractor;
  const itk::SheetMesh          mesh = extractor.Extract(volume.View());
  EXPECT_EQ(extractor.GetReport().Method, itk::SheetSurfaceMethodEnum::Roll);
  const auto [edgePoints, largest] = FarthestFromTheSpiral(mesh, 0.0, taper, [&](double z, int column) {
    return column != 0 && column != mesh.GridColumns - 1 && (z <= 2.5 || z >= 20.5);
  });
  std::cout << "edge rows: " << edgePoints << " points, farthest " << largest << " voxel from the sheet" << std::endl;
  EXPECT_GT(edgePoints, 0u);
  EXPECT_LT(largest, 1.0); // 0.94
}

TEST(SheetMidSurfaceExtractor, TheMeshReachesTheSheetsEdgeWhereTheScanShowsIt)
{
  // The sheet fills slices 3 to 20 of 24 (its intensity a Gaussian across it, 1 at its
  // middle, 0 in the air), but the mask of its first and last four slices holds only a
  // quarter of it (theta mod 2 pi below pi / 2: the mask of a noisy scan smoothed before
  // thresholding, which dims a blurred edge further). The scan's intensities show the whole
  // sheet there: the mesh reaches half a slice past slices 3 and 20, where the sheet ends.
  // By the mask's material alone it ran from 6.5 to 16.5 only.
  SpiralVolume volume(24);
  volume.Intensity.assign(volume.Mask.size(), 0.0f);
  const size_t plane = volume.Size[0] * volume.Size[1];
  for (size_t k = 0; k < volume.Size[2]; ++k)
  {
    for (size_t j = 0; j < volume.Size[1]; ++j)
    {
      for (size_t i = 0; i < volume.Size[0]; ++i)
      {
        const size_t index = k * plane + j * volume.Size[0] + i;
        double       phi = std::atan2(static_cast<double>(j) - 40.0, static_cast<double>(i) - 40.0);
        phi = phi < 0.0 ? phi + 2.0 * Pi : phi;
        const bool   sheet = k >= 3 && k <= 20;
        const bool   edge = k <= 6 || k >= 17;
        const double d = FromTheSpiral(static_cast<double>(i) - 40.0, static_cast<double>(j) - 40.0, 0.0);
        const double turns =
          phi / (2.0 * Pi) + std::round((std::hypot(static_cast<double>(i) - 40.0, static_cast<double>(j) - 40.0) -
                                         12.0 - 6.0 * phi / (2.0 * Pi)) /
                                        6.0);
        volume.Intensity[index] =
          sheet && turns >= 0.0 && turns <= 2.5 ? static_cast<float>(std::exp(-0.5 * d * d / 1.21)) : 0.0f;
        volume.Mask[index] = sheet && (!edge || phi < 0.5 * Pi) ? volume.Mask[index] : 0;
      }
    }
  }
  itk::SheetMidSurfaceExtractor  extractor;
  itk::SheetMidSurfaceParameters parameters;
  parameters.Method = itk::SheetSurfaceMethodEnum::Roll;
  extractor.SetParameters(parameters);
  const itk::SheetMesh mesh = extractor.Extract(volume.View());
  double               lowest = 1e9, highest = -1e9;
  for (size_t p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    lowest = std::min(lowest, mesh.Points[3 * p + 2]);
    highest = std::max(highest, mesh.Points[3 * p + 2]);
  }
  EXPECT_NEAR(lowest, 2.5, 0.25);
  EXPECT_NEAR(highest, 20.5, 0.25);
  ExpectOnTheSpiral(mesh, 0.5);
}

TEST(SheetMidSurfaceExtractor, GridStepsNameAMeshThatJumpsATurn)
{
  // A grid on the spiral r = 12 + 6 theta / (2 pi) (turn spacing 6), 10 rows one apart,
  // columns a voxel apart along 2.5 turns: it bends everywhere, and steps nowhere.
  itk::SheetMesh      mesh;
  const int           rows = 10;
  std::vector<double> theta{ 0.0 };
  while (theta.back() < 5.0 * Pi)
  {
    theta.push_back(theta.back() + 1.0 / (12.0 + 6.0 * theta.back() / (2.0 * Pi)));
  }
  const auto columns = static_cast<int>(theta.size());
  mesh.GridRows = rows;
  mesh.GridColumns = columns;
  for (int r = 0; r < rows; ++r)
  {
    for (int c = 0; c < columns; ++c)
    {
      const double radius = 12.0 + 6.0 * theta[c] / (2.0 * Pi);
      mesh.Points.insert(mesh.Points.end(),
                         { radius * std::cos(theta[c]), radius * std::sin(theta[c]), static_cast<double>(r) });
      mesh.GridIndex.insert(mesh.GridIndex.end(), { r, c });
    }
  }
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindGridSteps(mesh, 0.7 * 6.0).empty());

  // Row 5 crosses onto the next turn at column 100 (its radius a turn spacing larger from
  // there on): one step along the sheet in row 5, and steps along the axis on either side
  // of that row, none elsewhere.
  for (int c = 100; c < columns; ++c)
  {
    const size_t p = 5 * static_cast<size_t>(columns) + static_cast<size_t>(c);
    mesh.Points[3 * p] += 6.0 * std::cos(theta[c]);
    mesh.Points[3 * p + 1] += 6.0 * std::sin(theta[c]);
  }
  const auto steps = itk::SheetMidSurfaceExtractor::FindGridSteps(mesh, 0.7 * 6.0);
  size_t     alongSheet = 0, alongAxis = 0;
  for (const auto & step : steps)
  {
    EXPECT_TRUE(step.Row == 4 || step.Row == 5) << step.Row;
    if (step.AlongAxis)
    {
      EXPECT_GE(step.Column, 100u);
      ++alongAxis;
    }
    else
    {
      EXPECT_EQ(step.Row, 5u);
      EXPECT_NEAR(static_cast<double>(step.Column), 100.0, 1.0);
      EXPECT_GT(step.Step, 0.7 * 6.0);
      ++alongSheet;
    }
  }
  EXPECT_EQ(alongSheet, 1u);
  EXPECT_GT(alongAxis, 0u);
}

// A grid on the spiral r = 12 + 6 theta / (2 pi) (turn spacing 6), 8 rows one apart,
// columns three voxels apart along 2.5 turns; Theta holds each column's angle.
struct SpiralGrid
{
  std::vector<double> Theta{ 0.0 };
  itk::SheetMesh      Mesh;
  int                 Columns = 0;

  SpiralGrid()
  {
    auto radius = [](double theta) { return 12.0 + 6.0 * theta / (2.0 * Pi); };
    while (Theta.back() < 5.0 * Pi)
    {
      Theta.push_back(Theta.back() + 3.0 / radius(Theta.back()));
    }
    Columns = static_cast<int>(Theta.size());
    Mesh.GridRows = 8;
    Mesh.GridColumns = Columns;
    for (int r = 0; r < Mesh.GridRows; ++r)
    {
      for (int c = 0; c < Columns; ++c)
      {
        Mesh.Points.insert(Mesh.Points.end(),
                           { radius(Theta[c]) * std::cos(Theta[c]), radius(Theta[c]) * std::sin(Theta[c]), 1.0 * r });
        Mesh.GridIndex.insert(Mesh.GridIndex.end(), { r, c });
      }
    }
  }
};

TEST(SheetMidSurfaceExtractor, RowSpikesArePutBackButARowOnAnotherTurnIsNot)
{
  SpiralGrid                spiral;
  itk::SheetMesh &          mesh = spiral.Mesh;
  const std::vector<double> theta = spiral.Theta;
  const int                 columns = spiral.Columns;
  const std::vector<double> truth = mesh.Points;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothRowSpikes(mesh, 0.7 * 6.0), 0u);
  EXPECT_EQ(mesh.Points, truth);

  // Points pushed a turn spacing outwards, onto the next turn: one in row 1, two side by side
  // in row 3, three side by side in row 4 (a stretch, not a spike), and from column 20 to the
  // end of row 6 (a row that crossed onto the next turn and stays there).
  auto push = [&](int r, int from, int to) {
    for (int c = from; c <= to; ++c)
    {
      const size_t p = static_cast<size_t>(r * columns + c);
      mesh.Points[3 * p] += 6.0 * std::cos(theta[c]);
      mesh.Points[3 * p + 1] += 6.0 * std::sin(theta[c]);
    }
  };
  push(1, 12, 12);
  push(3, 25, 26);
  push(4, 30, 32);
  push(6, 20, columns - 1);
  const std::vector<double> pushed = mesh.Points;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothRowSpikes(mesh, 0.7 * 6.0), 3u);
  double farthest = 0.0;
  for (const auto & [r, c] : { std::pair{ 1, 12 }, { 3, 25 }, { 3, 26 } })
  {
    const size_t p = static_cast<size_t>(r * columns + c);
    farthest =
      std::max(farthest, std::hypot(mesh.Points[3 * p] - truth[3 * p], mesh.Points[3 * p + 1] - truth[3 * p + 1]));
    mesh.Points[3 * p] = pushed[3 * p];
    mesh.Points[3 * p + 1] = pushed[3 * p + 1];
    mesh.Points[3 * p + 2] = pushed[3 * p + 2];
  }
  std::cout << "spikes put back within " << farthest << " voxel of the spiral" << std::endl;
  EXPECT_LT(farthest, 0.1);
  // Nothing else moved: the three-point stretch and the row on the next turn are left for
  // FindGridSteps to name.
  EXPECT_EQ(mesh.Points, pushed);
  EXPECT_FALSE(itk::SheetMidSurfaceExtractor::FindGridSteps(mesh, 0.7 * 6.0).empty());
}

// Where turns press together, a row pulled onto the touching turn at one column bends
// towards it over three: the point there leaves the row's curve by more than a sheet's
// thickness, its neighbours by part of that. Such a bump is put back; a smaller one, one
// leaning away from every other turn, a stretch of three columns pushed alike, and the
// spiral's own bending are left as they are. Rows, columns and directions drawn at run time.
TEST(SheetMidSurfaceExtractor, BumpsTowardsATouchingTurnArePutBack)
{
  std::mt19937              random(vu::RunTimeSeed());
  SpiralGrid                spiral;
  itk::SheetMesh &          mesh = spiral.Mesh;
  const std::vector<double> theta = spiral.Theta;
  const int                 columns = spiral.Columns;
  const std::vector<double> truth = mesh.Points;
  const double              thickness = 2.0;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothTouchBumps(mesh, thickness), 0u);
  EXPECT_EQ(mesh.Points, truth);

  // Radial pushes (outwards for positive sizes) of column c and of its two neighbours.
  auto push = [&](int r, int c, double peak, double side) {
    for (int k = -1; k <= 1; ++k)
    {
      const size_t p = static_cast<size_t>(r * columns + c + k);
      const double size = k == 0 ? peak : side;
      mesh.Points[3 * p] += size * std::cos(theta[c + k]);
      mesh.Points[3 * p + 1] += size * std::sin(theta[c + k]);
    }
  };
  // One bump in each of rows 0 to 3, in the middle of the row, towards a turn inside or
  // outside (the outer one where there is one, half the time): 1.3 to 1.8 thicknesses at
  // c, a quarter to 0.4 of that at its sides.
  std::uniform_real_distribution<double> peakSize(1.3 * thickness, 1.8 * thickness), sideShare(0.25, 0.4);
  std::uniform_int_distribution<int>     middleTurn(columns / 3, 2 * columns / 3);
  std::bernoulli_distribution            outwards(0.5);
  std::vector<int>                       bumped;
  for (int r = 0; r < 4; ++r)
  {
    bumped.push_back(middleTurn(random));
    const bool   outerTurn = theta[static_cast<size_t>(bumped.back())] + 2.0 * Pi <= theta.back();
    const double peak = (outerTurn && outwards(random) ? 1.0 : -1.0) * peakSize(random);
    push(r, bumped.back(), peak, sideShare(random) * peak);
  }
  // Left alone: in row 4 a bump of 0.8 thickness; in row 5 one pushing the outermost turn
  // outwards (no turn there); in row 6 a stretch of three columns pushed alike.
  push(4, middleTurn(random), 0.8 * thickness, 0.25 * thickness);
  push(5, columns - 8, 1.5 * thickness, 0.4 * thickness);
  push(6, middleTurn(random), 1.5 * thickness, 1.5 * thickness);
  const std::vector<double> pushed = mesh.Points;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothTouchBumps(mesh, thickness), 12u);
  double farthest = 0.0;
  for (int r = 0; r < 4; ++r)
  {
    for (int k = -1; k <= 1; ++k)
    {
      const size_t p = static_cast<size_t>(r * columns + bumped[static_cast<size_t>(r)] + k);
      farthest =
        std::max(farthest, std::hypot(mesh.Points[3 * p] - truth[3 * p], mesh.Points[3 * p + 1] - truth[3 * p + 1]));
      std::copy(pushed.begin() + 3 * p, pushed.begin() + 3 * p + 3, mesh.Points.begin() + 3 * p);
    }
  }
  std::cout << "bumps put back within " << farthest << " voxel of the spiral" << std::endl;
  EXPECT_LT(farthest, 0.1);
  EXPECT_EQ(mesh.Points, pushed);
}

// One row whose window of slices held a trace on the neighbouring turn over part of the
// sheet: its points there leave their columns' course along the axis by a turn spacing
// while the rows about them agree. They are put back; two neighbouring rows pushed alike
// (the sheet's own course), a push below 0.7 of a turn spacing and a push in an end row are
// left as they are. Rows, columns and directions drawn at run time.
TEST(SheetMidSurfaceExtractor, ARowOnTheNextTurnOverAFewColumnsIsPutBack)
{
  std::mt19937              random(vu::RunTimeSeed());
  SpiralGrid                spiral;
  itk::SheetMesh &          mesh = spiral.Mesh;
  const std::vector<double> theta = spiral.Theta;
  const int                 columns = spiral.Columns;
  const std::vector<double> truth = mesh.Points;
  const double              spacing = 6.0;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothColumnSpikes(mesh, 0.7 * spacing), 0u);
  EXPECT_EQ(mesh.Points, truth);

  // Radial pushes (outwards for positive sizes) of columns [from, to] of row r.
  auto push = [&](int r, int from, int to, double size) {
    for (int c = from; c <= to; ++c)
    {
      const size_t p = static_cast<size_t>(r * columns + c);
      mesh.Points[3 * p] += size * std::cos(theta[c]);
      mesh.Points[3 * p + 1] += size * std::sin(theta[c]);
    }
  };
  // Each case in its own quarter of the columns, so that none lies in another's rows.
  const int                          quarter = columns / 4;
  std::uniform_int_distribution<int> middleRow(2, 5), start(0, quarter - 6);
  std::bernoulli_distribution        outwards(0.5);
  const int                          row = middleRow(random), from = start(random);
  push(row, from, from + 4, (outwards(random) ? 1.0 : -1.0) * spacing);
  const int pair = std::uniform_int_distribution<int>(2, 4)(random);
  const int pairFrom = quarter + start(random);
  push(pair, pairFrom, pairFrom + 2, spacing);
  push(pair + 1, pairFrom, pairFrom + 2, spacing);
  const int smallFrom = 2 * quarter + start(random);
  push(middleRow(random), smallFrom, smallFrom + 5, 0.6 * spacing);
  push(outwards(random) ? 0 : 7, 3 * quarter + start(random), 3 * quarter + quarter - 2, spacing);
  const std::vector<double> pushed = mesh.Points;
  EXPECT_EQ(itk::SheetMidSurfaceExtractor::SmoothColumnSpikes(mesh, 0.7 * spacing), 5u);
  double farthest = 0.0;
  for (int c = from; c <= from + 4; ++c)
  {
    const size_t p = static_cast<size_t>(row * columns + c);
    farthest =
      std::max(farthest, std::hypot(mesh.Points[3 * p] - truth[3 * p], mesh.Points[3 * p + 1] - truth[3 * p + 1]));
    std::copy(pushed.begin() + 3 * p, pushed.begin() + 3 * p + 3, mesh.Points.begin() + 3 * p);
  }
  std::cout << "row put back within " << farthest << " voxel of the spiral" << std::endl;
  EXPECT_LT(farthest, 1e-9);
  EXPECT_EQ(mesh.Points, pushed);
}

TEST(SheetMidSurfaceExtractor, OffSheetRunsNameAMeshTracedBetweenTurns)
{
  // The spiral's mask as intensities (air 0, sheet 1): the mesh traced on it lies on the
  // sheet everywhere, so no run of it is in air.
  const SpiralVolume volume(12);
  std::vector<float> values(volume.Mask.begin(), volume.Mask.end());
  auto               view = volume.View();
  view.Intensity = values.data();
  itk::SheetMidSurfaceExtractor extractor;
  itk::SheetMesh                mesh = extractor.Extract(view);
  EXPECT_TRUE(extractor.GetReport().OffSheetRuns.empty());
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindOffSheetRuns(mesh, view, 0.0, 1.0).empty());

  // Five points of one row, in the middle of the sheet, moved outwards by half a turn
  // spacing (into the middle of the gap, 3 voxels from both turns): one run, exactly
  // those points. Moved by a whole turn spacing instead (onto the next turn) they are on a
  // sheet again: that is the sideways-step check's to see.
  const auto columns = static_cast<size_t>(mesh.GridColumns);
  ASSERT_GE(mesh.GridRows, 3);
  const size_t row = static_cast<size_t>(mesh.GridRows) / 2, from = columns / 2 - 2, to = columns / 2 + 2;
  auto         moved = [&](double distance) {
    itk::SheetMesh copy = mesh;
    for (size_t c = from; c <= to; ++c)
    {
      double *     p = &copy.Points[3 * (row * columns + c)];
      const double x = p[0] - 40.0, y = p[1] - 40.0, r = std::hypot(x, y);
      p[0] += distance * x / r;
      p[1] += distance * y / r;
    }
    return copy;
  };
  const auto runs = itk::SheetMidSurfaceExtractor::FindOffSheetRuns(moved(3.0), view, 0.0, 1.0);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].Row, row);
  EXPECT_EQ(runs[0].FirstColumn, from);
  EXPECT_EQ(runs[0].LastColumn, to);
  EXPECT_LT(runs[0].Lowest, 0.25);
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindOffSheetRuns(moved(6.0), view, 0.0, 1.0).empty());
  // A run shorter than the minimum is not named; without intensities, or where the scan
  // holds no data, nothing is checked.
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindOffSheetRuns(moved(3.0), view, 0.0, 1.0, 0.25, 6).empty());
  auto maskOnly = view;
  maskOnly.Intensity = nullptr;
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindOffSheetRuns(moved(3.0), maskOnly, 0.0, 1.0).empty());
  const std::vector<uint8_t> noData(volume.Mask.size(), 0);
  auto                       beyondTheScan = view;
  beyondTheScan.Data = noData.data();
  EXPECT_TRUE(itk::SheetMidSurfaceExtractor::FindOffSheetRuns(moved(3.0), beyondTheScan, 0.0, 1.0).empty());
}

// A smoothed noisy scan whose sheet is a small share of the voxels, its levels estimated
// on either side of a threshold inside the air's noise (where Otsu's falls): the refined
// levels put their midpoint between the air's noise and the sheet, where the iterative
// selection alone settles on a split of the air's noise (midpoint within 0.1 noise widths
// of the air). Shares, contrasts and noise drawn each run, half of the samples with padding
// (a constant far below the air, as outside a scanner's field of view, which would make
// the air's noise seem wide); with a larger share, from a good start, the levels stay apart
// (midpoint 1.5 to 4 noise widths above the air).
TEST(SheetMidSurfaceExtractor, IntensityLevelsOfASmallSheetAreNotASplitOfTheAirsNoise)
{
  const unsigned int seed = vu::RunTimeSeed();
  std::mt19937       random(seed);
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (int trial = 0; trial < 8; ++trial)
  {
    const bool                             small = trial % 2 == 0;
    const double                           share = small ? std::uniform_real_distribution<double>(0.015, 0.08)(random)
                                                         : std::uniform_real_distribution<double>(0.1, 0.45)(random);
    const double                           noise = std::uniform_real_distribution<double>(20.0, 80.0)(random);
    const double                           contrast = noise * std::uniform_real_distribution<double>(5.0, 10.0)(random);
    const double                           air = -1000.0;
    std::normal_distribution<double>       gauss(0.0, noise);
    std::uniform_real_distribution<double> partial(0.3, 1.0);
    // From the fifth trial on, a fifth to a third of the voxels are padding outside the
    // scanner's field of view, well below the air.
    const double       padding = trial < 4 ? 0.0 : std::uniform_real_distribution<double>(0.2, 0.33)(random);
    std::vector<float> values(200000);
    for (size_t i = 0; i < values.size(); ++i)
    {
      const double place = static_cast<double>(i) / static_cast<double>(values.size());
      const bool   onSheet = place < share * (1.0 - padding);
      values[i] = place >= 1.0 - padding
                    ? static_cast<float>(air - 12.0 * noise)
                    : static_cast<float>(air + (onSheet ? contrast * partial(random) : 0.0) + gauss(random));
    }
    itk::SheetIntensityLevels start;
    start.Air = air - 0.6 * noise;
    start.Sheet = small ? air + 0.7 * noise : air + 0.6 * contrast;
    start.Noise = 3.0 * noise;
    const itk::SheetIntensityLevels found = itk::RefineSheetIntensityLevels(values, start);
    const double                    midpoint = 0.5 * (found.Air + found.Sheet);
    SCOPED_TRACE("trial " + std::to_string(trial) + ": share " + std::to_string(share) + ", contrast " +
                 std::to_string(contrast / noise) + " noise widths");
    EXPECT_GT(midpoint, air + (small ? 2.0 : 1.2) * noise);
    EXPECT_LT(midpoint, air + 0.8 * contrast);
    EXPECT_NEAR(found.Air, air, small ? 0.5 * noise : 1.5 * noise);
    EXPECT_EQ(found.Noise, start.Noise);
  }
}

TEST(SheetMidSurfaceExtractor, ProgressCallbackAborts)
{
  const SpiralVolume            volume;
  itk::SheetMidSurfaceExtractor extractor;
  double                        last = -1.0;
  extractor.SetProgressCallback([&last](double fraction) {
    last = fraction;
    return false;
  });
  EXPECT_THROW(extractor.Extract(volume.View()), itk::ExceptionObject);
  EXPECT_GE(last, 0.0);
}

TEST(SheetMidSurfaceExtractor, BadInputThrows)
{
  itk::SheetMidSurfaceExtractor extractor;
  itk::SheetVolumeView          view;
  EXPECT_THROW(extractor.Extract(view), itk::ExceptionObject); // no mask
  SpiralVolume volume;
  std::fill(volume.Mask.begin(), volume.Mask.end(), 0);
  EXPECT_THROW(extractor.Extract(volume.View()), itk::ExceptionObject); // empty
  const SpiralVolume good;
  view = good.View();
  view.Spacing[1] = 2.0;
  EXPECT_THROW(extractor.Extract(view), itk::ExceptionObject); // non-square voxels
  view = good.View();
  view.Size[2] = 1;
  EXPECT_THROW(extractor.Extract(view), itk::ExceptionObject); // too small
  itk::SheetMidSurfaceParameters parameters;
  parameters.ChordErrorFraction = 2.0;
  extractor.SetParameters(parameters);
  EXPECT_THROW(extractor.Extract(good.View()), itk::ExceptionObject);
}

TEST(SheetMidSurfaceExtractor, RollMethodOnAFlatSheetWarns)
{
  // A flat sheet, 3 voxels thick, 50 voxels wide, across 6 slices.
  const size_t         size[3] = { 60, 30, 6 };
  std::vector<uint8_t> mask(size[0] * size[1] * size[2], 0);
  for (size_t k = 0; k < size[2]; ++k)
  {
    for (size_t j = 14; j < 17; ++j)
    {
      for (size_t i = 5; i < 55; ++i)
      {
        mask[(k * size[1] + j) * size[0] + i] = 1;
      }
    }
  }
  itk::SheetVolumeView view;
  view.Mask = mask.data();
  for (int d = 0; d < 3; ++d)
  {
    view.Size[d] = size[d];
  }
  itk::SheetMidSurfaceExtractor  extractor;
  itk::SheetMidSurfaceParameters parameters;
  parameters.Method = itk::SheetSurfaceMethodEnum::Roll;
  extractor.SetParameters(parameters);
  extractor.Extract(view);
  ASSERT_FALSE(extractor.GetReport().Warnings.empty());
  EXPECT_NE(extractor.GetReport().Warnings[0].find("may not be rolled"), std::string::npos);

  // Auto picks the general tracer, which follows the sheet from end to end.
  parameters.Method = itk::SheetSurfaceMethodEnum::Auto;
  extractor.SetParameters(parameters);
  const itk::SheetMesh mesh = extractor.Extract(view);
  EXPECT_EQ(extractor.GetReport().Method, itk::SheetSurfaceMethodEnum::General);
  EXPECT_NEAR(extractor.GetReport().SheetLength, 49.0, 1.5);
  for (size_t p = 0; p < mesh.GetNumberOfPoints(); ++p)
  {
    EXPECT_NEAR(mesh.Points[3 * p + 1], 15.0, 0.1);
  }
}

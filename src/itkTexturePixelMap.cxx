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
#include "itkMultiThreaderBase.h"
#include "itkProcessObject.h"
#include "itkProgressTransformer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

namespace itk {
namespace {
constexpr SizeValueType RowsPerBand = 16;
// Marks, while rasterising, a pixel covered only where the normal vanishes.
constexpr int32_t ZeroNormal = -2;

// Bounding box of the flat mesh's x, y; throws on an empty mesh.
std::array<double, 4>
FlatBounds(const SheetMesh & flat)
{
  if (flat.GetNumberOfPoints() == 0)
  {
    itkGenericExceptionMacro(<< "ComputeTextureGrid: the flat mesh has no points");
  }
  std::array<double, 4> b{ { std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::lowest(),
                             std::numeric_limits<double>::lowest() } };
  for (size_t i = 0; i < flat.GetNumberOfPoints(); ++i)
  {
    const double x = flat.Points[3 * i], y = flat.Points[3 * i + 1];
    if (!std::isfinite(x) || !std::isfinite(y))
    {
      itkGenericExceptionMacro(<< "ComputeTextureGrid: flat point " << i << " is not finite");
    }
    b[0] = std::min(b[0], x);
    b[1] = std::min(b[1], y);
    b[2] = std::max(b[2], x);
    b[3] = std::max(b[3], y);
  }
  return b;
}

double
Cross2(double ax, double ay, double bx, double by)
{
  return ax * by - ay * bx;
}
} // namespace

SizeValueType
TexturePixelMap::GetNumberOfSheetPixels() const
{
  return static_cast<SizeValueType>(std::count_if(Triangle.begin(), Triangle.end(), [](int32_t t) { return t >= 0; }));
}

TexturePixelMap
ComputeTextureGrid(const SheetMesh & flat, double pixelSize, double margin)
{
  if (!(pixelSize > 0.0) || !std::isfinite(pixelSize))
  {
    itkGenericExceptionMacro(<< "ComputeTextureGrid: pixel size must be positive and finite, got " << pixelSize);
  }
  if (!(margin >= 0.0) || !std::isfinite(margin))
  {
    itkGenericExceptionMacro(<< "ComputeTextureGrid: margin must be non-negative and finite, got " << margin);
  }
  const std::array<double, 4> b = FlatBounds(flat);
  TexturePixelMap             map;
  map.PixelSize = pixelSize;
  map.Origin = { { b[0] - margin, b[1] - margin } };
  const double columns = std::floor((b[2] - b[0] + 2.0 * margin) / pixelSize) + 1.0;
  const double rows = std::floor((b[3] - b[1] + 2.0 * margin) / pixelSize) + 1.0;
  if (columns * rows > static_cast<double>(std::numeric_limits<int32_t>::max()))
  {
    itkGenericExceptionMacro(<< "ComputeTextureGrid: a " << columns << " x " << rows
                             << " pixel texture is too large; increase the pixel size " << pixelSize);
  }
  map.Size = { { static_cast<SizeValueType>(columns), static_cast<SizeValueType>(rows) } };
  return map;
}

namespace {
// Phong tessellation's shape factor: 1/2 reproduces a circle's arc between two points
// from their tangents to second order (the chord's midpoint moved by the sagitta).
constexpr double PhongShape = 0.5;

// Rasterises flat triangle t into the rows bandFirst..bandLast of `map`: every pixel centre
// inside it gets the barycentric 3D point and interpolated unit normal (ZeroNormal where
// the normals cancel).
void
RasteriseTriangle(TexturePixelMap &           map,
                  const SheetMesh &           surface,
                  const SheetMesh &           flat,
                  const std::vector<double> & normals,
                  uint32_t                    t,
                  SizeValueType               bandFirst,
                  SizeValueType               bandLast,
                  double                      pixelSize,
                  double                      shape)
{
  const SizeValueType columns = map.Size[0];
  const double        inverse = 1.0 / pixelSize;
  const uint32_t *    tri = &flat.Triangles[3 * t];
  const double *      a = &flat.Points[3 * tri[0]];
  const double *      p = &flat.Points[3 * tri[1]];
  const double *      c = &flat.Points[3 * tri[2]];
  const double        e1x = p[0] - a[0], e1y = p[1] - a[1], e2x = c[0] - a[0], e2y = c[1] - a[1];
  const double        inverseDet = 1.0 / Cross2(e1x, e1y, e2x, e2y);
  // Barycentric coordinates tolerate a sliver so that pixel centres on shared edges
  // are covered whatever the rounding.
  constexpr double tolerance = -1e-9;
  const double     xmin = std::min({ a[0], p[0], c[0] }), xmax = std::max({ a[0], p[0], c[0] });
  const double     ymin = std::min({ a[1], p[1], c[1] }), ymax = std::max({ a[1], p[1], c[1] });
  const auto       c0 = static_cast<SizeValueType>(std::max(0.0, std::ceil((xmin - map.Origin[0]) * inverse - 1e-9)));
  const double     c1 = std::min(static_cast<double>(columns - 1), std::floor((xmax - map.Origin[0]) * inverse + 1e-9));
  const double     r0 = std::max(static_cast<double>(bandFirst), std::ceil((ymin - map.Origin[1]) * inverse - 1e-9));
  const double     r1 = std::min(static_cast<double>(bandLast), std::floor((ymax - map.Origin[1]) * inverse + 1e-9));
  const double *   sa = &surface.Points[3 * tri[0]];
  const double *   sb = &surface.Points[3 * tri[1]];
  const double *   sc = &surface.Points[3 * tri[2]];
  const double *   na = &normals[3 * tri[0]];
  const double *   nb = &normals[3 * tri[1]];
  const double *   nc = &normals[3 * tri[2]];
  for (auto row = static_cast<SizeValueType>(std::max(0.0, r0)); static_cast<double>(row) <= r1; ++row)
  {
    const double y = map.Origin[1] + row * pixelSize;
    // The row's line crosses the triangle between the crossings of its edges; only the
    // columns there, widened by a pixel each side for rounding, can pass the barycentric
    // test below (which still decides, so the covered pixels are exactly those of the
    // whole bounding box).
    double         xl = std::numeric_limits<double>::infinity(), xr = -xl;
    const double * corner[3] = { a, p, c };
    for (int e = 0; e < 3; ++e)
    {
      const double * u = corner[e];
      const double * w = corner[(e + 1) % 3];
      if ((u[1] <= y && y <= w[1]) || (w[1] <= y && y <= u[1]))
      {
        const double dy = w[1] - u[1];
        const double x = dy != 0.0 ? u[0] + (y - u[1]) * (w[0] - u[0]) / dy : u[0];
        xl = std::min({ xl, x, dy != 0.0 ? x : w[0] });
        xr = std::max({ xr, x, dy != 0.0 ? x : w[0] });
      }
    }
    SizeValueType first = c0;
    double        last = c1;
    if (xl <= xr)
    {
      first = std::max(c0, static_cast<SizeValueType>(std::max(0.0, std::floor((xl - map.Origin[0]) * inverse) - 1.0)));
      last = std::min(c1, std::ceil((xr - map.Origin[0]) * inverse) + 1.0);
    }
    for (SizeValueType column = first; static_cast<double>(column) <= last; ++column)
    {
      const double x = map.Origin[0] + column * pixelSize;
      const double vx = x - a[0], vy = y - a[1];
      const double lb = Cross2(vx, vy, e2x, e2y) * inverseDet;
      const double lc = Cross2(e1x, e1y, vx, vy) * inverseDet;
      const double la = 1.0 - lb - lc;
      if (la < tolerance || lb < tolerance || lc < tolerance)
      {
        continue;
      }
      const SizeValueType pixel = row * columns + column;
      double              n[3];
      for (int d = 0; d < 3; ++d)
      {
        n[d] = la * na[d] + lb * nb[d] + lc * nc[d];
      }
      const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (!(length > 1e-6))
      {
        if (map.Triangle[pixel] < 0)
        {
          map.Triangle[pixel] = ZeroNormal;
        }
        continue;
      }
      // With a shape factor (curved), the point on the curved sheet, not on the
      // triangle's chord: Phong tessellation (Boubekeur and Alexa 2008), the barycentric
      // blend of the point's projections onto the corners' tangent planes, `shape` of the
      // way from the flat triangle. With 1/2, on a cylinder or sphere this is exact to
      // second order in the edge length, where the flat triangle lies inside the sheet by
      // up to its sagitta (edge^2 / 8R); on a plane it is the barycentric point.
      double point[3];
      for (int d = 0; d < 3; ++d)
      {
        point[d] = la * sa[d] + lb * sb[d] + lc * sc[d];
      }
      const double * corners[3] = { sa, sb, sc };
      const double * cornerNormals[3] = { na, nb, nc };
      const double   weights[3] = { la, lb, lc };
      double         bent[3] = { point[0], point[1], point[2] };
      for (int v = 0; v < 3; ++v)
      {
        const double * q = corners[v];
        const double * m = cornerNormals[v];
        const double   away = (point[0] - q[0]) * m[0] + (point[1] - q[1]) * m[1] + (point[2] - q[2]) * m[2];
        for (int d = 0; d < 3; ++d)
        {
          bent[d] -= shape * weights[v] * away * m[d];
        }
      }
      for (int d = 0; d < 3; ++d)
      {
        map.Positions[3 * pixel + d] = static_cast<float>(bent[d]);
        map.Normals[3 * pixel + d] = static_cast<float>(n[d] / length);
      }
      map.Triangle[pixel] = static_cast<int32_t>(t);
    }
  }
}
} // namespace

TexturePixelMap
ComputeTexturePixelMap(const SheetMesh & surface,
                       const SheetMesh & flat,
                       double            pixelSize,
                       double            margin,
                       ProcessObject *   filter,
                       float             progressStart,
                       float             progressEnd,
                       bool              curved)
{
  surface.Validate("ComputeTexturePixelMap: surface mesh");
  flat.Validate("ComputeTexturePixelMap: flat mesh");
  if (!HaveSameTopology(surface, flat))
  {
    itkGenericExceptionMacro(<< "ComputeTexturePixelMap: the surface mesh (" << surface.GetNumberOfPoints()
                             << " points, " << surface.GetNumberOfTriangles() << " triangles) and the flat mesh ("
                             << flat.GetNumberOfPoints() << " points, " << flat.GetNumberOfTriangles()
                             << " triangles) differ in topology");
  }
  TexturePixelMap     map = ComputeTextureGrid(flat, pixelSize, margin);
  const SizeValueType rows = map.Size[1];
  // Left uninitialised here: each band's work unit fills its rows before it rasterises them.
  map.Positions.resize(3 * map.GetNumberOfPixels());
  map.Normals.resize(3 * map.GetNumberOfPixels());
  map.Triangle.resize(map.GetNumberOfPixels());

  const std::vector<double>   normals = surface.ComputeVertexNormals();
  const std::array<double, 4> b = FlatBounds(flat);
  const double                flatScale2 = (b[2] - b[0]) * (b[2] - b[0]) + (b[3] - b[1]) * (b[3] - b[1]);
  double                      surfaceScale2 = 0.0;
  for (size_t d = 0; d < 3; ++d)
  {
    double lo = surface.Points[d], hi = surface.Points[d];
    for (size_t i = 1; i < surface.GetNumberOfPoints(); ++i)
    {
      lo = std::min(lo, surface.Points[3 * i + d]);
      hi = std::max(hi, surface.Points[3 * i + d]);
    }
    surfaceScale2 += (hi - lo) * (hi - lo);
  }
  const std::vector<double> surfaceAreas = surface.ComputeTriangleAreas();

  // Bin triangles into bands of rows so that each band is written by one work unit only.
  const SizeValueType                bands = (rows + RowsPerBand - 1) / RowsPerBand;
  std::vector<std::vector<uint32_t>> bandTriangles(bands);
  const double                       inverse = 1.0 / pixelSize;
  for (size_t t = 0; t < flat.GetNumberOfTriangles(); ++t)
  {
    const double * a = &flat.Points[3 * flat.Triangles[3 * t]];
    const double * p = &flat.Points[3 * flat.Triangles[3 * t + 1]];
    const double * c = &flat.Points[3 * flat.Triangles[3 * t + 2]];
    const double   flatArea2 = std::abs(Cross2(p[0] - a[0], p[1] - a[1], c[0] - a[0], c[1] - a[1]));
    // Relative thresholds: a triangle this small holds no pixel centre worth a normal.
    if (flatArea2 <= 1e-14 * flatScale2 || 2.0 * surfaceAreas[t] <= 1e-14 * surfaceScale2)
    {
      ++map.NumberOfDegenerateTriangles;
      continue;
    }
    const double ymin = std::min({ a[1], p[1], c[1] }), ymax = std::max({ a[1], p[1], c[1] });
    const auto   r0 = static_cast<SizeValueType>(std::max(0.0, std::ceil((ymin - map.Origin[1]) * inverse - 1e-9)));
    const auto   r1 = static_cast<SizeValueType>(
      std::min(static_cast<double>(rows - 1), std::floor((ymax - map.Origin[1]) * inverse + 1e-9)));
    for (SizeValueType band = r0 / RowsPerBand; band <= r1 / RowsPerBand; ++band)
    {
      bandTriangles[band].push_back(static_cast<uint32_t>(t));
    }
  }

  std::atomic<bool>                    aborted{ false };
  std::unique_ptr<ProgressTransformer> progress;
  if (filter != nullptr)
  {
    progress = std::make_unique<ProgressTransformer>(progressStart, progressEnd, filter);
  }
  MultiThreaderBase::Pointer threader =
    filter != nullptr ? MultiThreaderBase::Pointer(filter->GetMultiThreader()) : MultiThreaderBase::New();
  threader->ParallelizeArray(
    0,
    bands,
    [&](SizeValueType band) {
      if (aborted || (filter != nullptr && filter->GetAbortGenerateData()))
      {
        aborted = true;
        return;
      }
      const SizeValueType bandFirst = band * RowsPerBand;
      const SizeValueType bandLast = std::min(rows, bandFirst + RowsPerBand) - 1;
      const SizeValueType first = bandFirst * map.Size[0], end = (bandLast + 1) * map.Size[0];
      std::fill(map.Positions.begin() + 3 * first, map.Positions.begin() + 3 * end, 0.0f);
      std::fill(map.Normals.begin() + 3 * first, map.Normals.begin() + 3 * end, 0.0f);
      std::fill(map.Triangle.begin() + first, map.Triangle.begin() + end, -1);
      for (const uint32_t t : bandTriangles[band])
      {
        RasteriseTriangle(map, surface, flat, normals, t, bandFirst, bandLast, pixelSize, curved ? PhongShape : 0.0);
      }
    },
    progress ? progress->GetProcessObject() : nullptr);
  if (aborted)
  {
    ProcessAborted e(__FILE__, __LINE__);
    e.SetDescription("ComputeTexturePixelMap: aborted");
    throw e;
  }
  for (int32_t & t : map.Triangle)
  {
    if (t == ZeroNormal)
    {
      ++map.NumberOfZeroNormalPixels;
      t = -1;
    }
  }
  return map;
}
} // end namespace itk

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
#ifndef vuTexturePhantom_h
#define vuTexturePhantom_h

#include "itkImage.h"
#include "itkMesh.h"
#include "itkSheetMesh.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"
#include "vuTestMeshes.h"

#include <cmath>
#include <functional>
#include <random>
#include <vector>

/** Synthetic scans of a sheet with a known ink pattern, for the texturing tests and
 * benchmarks: the sheet's mid-surface and its exact flattening are known analytically. */
namespace vu {
using VolumeType = itk::Image<float, 3>;
using TextureType = itk::Image<float, 2>;
using MeshType = itk::Mesh<float, 3>;

/** A 12 x 10 x 20 volume of 0.5 mm voxels whose value is its z coordinate (0 to 9.5 mm):
 * every layer of a horizontal sheet with normal +z samples its own height. */
inline VolumeType::Pointer
RampVolume()
{
  auto         volume = VolumeType::New();
  itk::Size<3> size{ { 12, 10, 20 } };
  volume->SetRegions(size);
  VolumeType::SpacingType spacing;
  spacing.Fill(0.5);
  volume->SetSpacing(spacing);
  volume->Allocate();
  float * buffer = volume->GetBufferPointer();
  for (itk::SizeValueType n = 0; n < 12 * 10 * 20; ++n)
  {
    buffer[n] = static_cast<float>(0.5 * (n / (12 * 10)));
  }
  return volume;
}

/** A horizontal square at height z inside RampVolume(), corners (1, 1) and (4, 3.5),
 * normal +z. */
inline itk::SheetMesh
HorizontalSquare(double z)
{
  itk::SheetMesh mesh;
  mesh.Points = { 1, 1, z, 4, 1, z, 4, 3.5, z, 1, 3.5, z };
  mesh.Triangles = { 0, 1, 2, 0, 2, 3 };
  return mesh;
}

/** Ink of the test sheet, in sheet coordinates (u, v) in mm on a 40 x 24 mm sheet: bars
 * of several widths, two blocks and an "F" and an "L" (asymmetric, so that a mirrored or
 * turned texture is told apart). */
inline bool
InkAt(double u, double v)
{
  struct Box
  {
    double u0, v0, u1, v1;
  };
  static const Box boxes[] = {
    { 2, 2, 5, 22 },     // bar, 3 mm
    { 7, 2, 9, 22 },     // bar, 2 mm
    { 11, 2, 12.5, 14 }, // bar, 1.5 mm
    { 15, 3, 21, 9 },    // block
    { 15, 12, 18, 21 },  // small block
    { 23, 4, 25, 21 },   // F: stem
    { 25, 19, 31, 21 },  // F: top arm
    { 25, 12, 29, 14 },  // F: middle arm
    { 33, 4, 35, 21 },   // L: stem
    { 35, 4, 39, 6 },    // L: foot
  };
  for (const Box & b : boxes)
  {
    if (u >= b.u0 && u <= b.u1 && v >= b.v0 && v <= b.v1)
    {
      return true;
    }
  }
  return false;
}
constexpr double SheetLength = 40.0;
constexpr double SheetHeight = 24.0;
/** The scanned sheet extends this far beyond the inked, meshed region (mm), so that the
 * texture of the meshed region has no sheet edge in it. */
constexpr double SheetBorder = 1.0;

/** The true ink image: ink area fraction per pixel of side pixelSize, pixel centres at
 * (i * pixelSize, j * pixelSize) for u in [0, SheetLength], v in [0, SheetHeight]. */
inline TextureType::Pointer
MakeInkImage(double pixelSize)
{
  auto                  image = TextureType::New();
  TextureType::SizeType size;
  size[0] = static_cast<itk::SizeValueType>(std::floor(SheetLength / pixelSize)) + 1;
  size[1] = static_cast<itk::SizeValueType>(std::floor(SheetHeight / pixelSize)) + 1;
  image->SetRegions(size);
  TextureType::SpacingType spacing;
  spacing.Fill(pixelSize);
  image->SetSpacing(spacing);
  image->Allocate();
  constexpr int sub = 4;
  for (itk::SizeValueType j = 0; j < size[1]; ++j)
  {
    for (itk::SizeValueType i = 0; i < size[0]; ++i)
    {
      int count = 0;
      for (int a = 0; a < sub; ++a)
      {
        for (int b = 0; b < sub; ++b)
        {
          count += InkAt((i + (a + 0.5) / sub - 0.5) * pixelSize, (j + (b + 0.5) / sub - 0.5) * pixelSize) ? 1 : 0;
        }
      }
      image->SetPixel({ { static_cast<itk::IndexValueType>(i), static_cast<itk::IndexValueType>(j) } },
                      static_cast<float>(count) / (sub * sub));
    }
  }
  return image;
}

/** Where a point lies relative to the sheet: signed distance d along the sheet normal
 * from the mid-surface and sheet coordinates (u, v); false when (u, v) is off the sheet. */
using SheetCoordinates = std::function<bool(const double x[3], double & d, double & u, double & v)>;

struct PhantomSettings
{
  double Thickness{ 2.0 }; // sheet thickness, mm
  double InkFrom{ -1.0 };  // ink occupies d in [InkFrom, InkTo]
  double InkTo{ 1.0 };
  double Paper{ 0.3 };       // attenuation of bare sheet
  double Ink{ 1.0 };         // attenuation of inked sheet
  double BlurSigma{ 0.25 };  // scanner blur, mm
  double NoiseSigma{ 0.03 }; // additive Gaussian noise
  int    Subsamples{ 3 };    // partial volume: Subsamples^3 points averaged per voxel
};

/** Ink in the outer voxel of a 2.5 mm sheet (d in [0.75, 1.25] mm, 1.5 to 2.5 voxels
 * from the mid-surface): a single layer on the mid-surface misses it. */
inline PhantomSettings
FaceInkSettings()
{
  PhantomSettings settings;
  settings.Thickness = 2.5;
  settings.InkFrom = 0.75;
  settings.InkTo = 1.25;
  return settings;
}

/** A scan of the sheet: each voxel averages Subsamples^3 points (partial volume), then
 * Gaussian blur and noise with a fixed seed. */
inline VolumeType::Pointer
MakeVolume(const double             origin[3],
           const itk::Size<3> &     size,
           double                   voxel,
           const SheetCoordinates & sheet,
           const PhantomSettings &  settings)
{
  auto volume = VolumeType::New();
  volume->SetRegions(size);
  VolumeType::SpacingType spacing;
  spacing.Fill(voxel);
  volume->SetSpacing(spacing);
  VolumeType::PointType o;
  for (int d = 0; d < 3; ++d)
  {
    o[d] = origin[d];
  }
  volume->SetOrigin(o);
  volume->Allocate();
  float *   buffer = volume->GetBufferPointer();
  const int sub = settings.Subsamples;
  for (itk::SizeValueType k = 0; k < size[2]; ++k)
  {
    for (itk::SizeValueType j = 0; j < size[1]; ++j)
    {
      for (itk::SizeValueType i = 0; i < size[0]; ++i)
      {
        double sum = 0.0;
        for (int c = 0; c < sub * sub * sub; ++c)
        {
          const double x[3] = { origin[0] + (i + (c % sub + 0.5) / sub - 0.5) * voxel,
                                origin[1] + (j + (c / sub % sub + 0.5) / sub - 0.5) * voxel,
                                origin[2] + (k + (c / (sub * sub) + 0.5) / sub - 0.5) * voxel };
          double       d, u, v;
          if (!sheet(x, d, u, v) || std::abs(d) > 0.5 * settings.Thickness)
          {
            continue;
          }
          const bool ink = d >= settings.InkFrom && d <= settings.InkTo && InkAt(u, v);
          sum += ink ? settings.Ink : settings.Paper;
        }
        buffer[(k * size[1] + j) * size[0] + i] = static_cast<float>(sum / (sub * sub * sub));
      }
    }
  }
  auto blur = itk::SmoothingRecursiveGaussianImageFilter<VolumeType, VolumeType>::New();
  blur->SetInput(volume);
  blur->SetSigma(settings.BlurSigma);
  blur->Update();
  VolumeType::Pointer             scan = blur->GetOutput();
  std::mt19937                    generator(42);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(settings.NoiseSigma));
  float *                         out = scan->GetBufferPointer();
  for (itk::SizeValueType n = 0; n < scan->GetBufferedRegion().GetNumberOfPixels(); ++n)
  {
    out[n] += noise(generator);
  }
  return scan;
}

/** A grid mesh of a sheet parametrised by (u, v) in [0, SheetLength] x [0, SheetHeight]:
 * surface(u, v) gives the 3D point; flat receives (u, v, 0). Triangles are wound so that
 * the normal is du x dv. */
inline itk::SheetMesh
MakeSheetMesh(int                                                          columns,
              int                                                          rows,
              const std::function<std::array<double, 3>(double, double)> & surface,
              itk::SheetMesh &                                             flat)
{
  itk::SheetMesh mesh;
  flat = itk::SheetMesh();
  for (int r = 0; r < rows; ++r)
  {
    for (int c = 0; c < columns; ++c)
    {
      const double                u = SheetLength * c / (columns - 1);
      const double                v = SheetHeight * r / (rows - 1);
      const std::array<double, 3> p = surface(u, v);
      mesh.Points.insert(mesh.Points.end(), { p[0], p[1], p[2] });
      flat.Points.insert(flat.Points.end(), { u, v, 0.0 });
    }
  }
  mesh.Triangles = GridTriangles(rows, columns);
  flat.Triangles = mesh.Triangles;
  return mesh;
}

/** A flat sheet in a tilted plane: mid-surface P0 + u e1 + v e2, normal e1 x e2. */
struct TiltedPlane
{
  double P0[3]{ 6.0, 5.0, 9.0 };
  double E1[3];
  double E2[3];
  double N[3];
  TiltedPlane()
  {
    // Rotated about two axes so that no volume axis is aligned with the sheet.
    const double a = 0.35, b = -0.25;
    const double e1[3] = { std::cos(a), 0.0, std::sin(a) };
    const double e2[3] = { -std::sin(a) * std::sin(b), std::cos(b), std::cos(a) * std::sin(b) };
    for (int d = 0; d < 3; ++d)
    {
      E1[d] = e1[d];
      E2[d] = e2[d];
    }
    N[0] = E1[1] * E2[2] - E1[2] * E2[1];
    N[1] = E1[2] * E2[0] - E1[0] * E2[2];
    N[2] = E1[0] * E2[1] - E1[1] * E2[0];
  }
  std::array<double, 3>
  At(double u, double v) const
  {
    return { P0[0] + u * E1[0] + v * E2[0], P0[1] + u * E1[1] + v * E2[1], P0[2] + u * E1[2] + v * E2[2] };
  }
  bool
  Coordinates(const double x[3], double & d, double & u, double & v) const
  {
    const double r[3] = { x[0] - P0[0], x[1] - P0[1], x[2] - P0[2] };
    d = r[0] * N[0] + r[1] * N[1] + r[2] * N[2];
    u = r[0] * E1[0] + r[1] * E1[1] + r[2] * E1[2];
    v = r[0] * E2[0] + r[1] * E2[1] + r[2] * E2[2];
    return u >= -SheetBorder && u <= SheetLength + SheetBorder && v >= -SheetBorder && v <= SheetHeight + SheetBorder;
  }
};

/** A cylinder-shell sheet around the z axis: mid-surface radius Radius, u = Radius * theta
 * (theta in [0, SheetLength / Radius]), v = z; normal pointing outwards. */
struct CylinderShell
{
  double Radius{ 12.0 };
  std::array<double, 3>
  At(double u, double v) const
  {
    const double theta = u / Radius;
    return { Radius * std::cos(theta), Radius * std::sin(theta), v };
  }
  bool
  Coordinates(const double x[3], double & d, double & u, double & v) const
  {
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1]);
    double       theta = std::atan2(x[1], x[0]);
    if (theta < -0.5)
    {
      theta += 2.0 * M_PI;
    }
    d = r - Radius;
    u = Radius * theta;
    v = x[2];
    return u >= -SheetBorder && u <= SheetLength + SheetBorder && v >= -SheetBorder && v <= SheetHeight + SheetBorder;
  }
};

/** The flat-sheet phantom: volume of 0.5 mm voxels around the tilted plane. */
inline VolumeType::Pointer
MakeTiltedPlaneVolume(const TiltedPlane & plane, const PhantomSettings & settings)
{
  double lo[3] = { 1e9, 1e9, 1e9 }, hi[3] = { -1e9, -1e9, -1e9 };
  for (double u : { 0.0, SheetLength })
  {
    for (double v : { 0.0, SheetHeight })
    {
      const auto p = plane.At(u, v);
      for (int d = 0; d < 3; ++d)
      {
        lo[d] = std::min(lo[d], p[d]);
        hi[d] = std::max(hi[d], p[d]);
      }
    }
  }
  constexpr double voxel = 0.5;
  double           origin[3];
  itk::Size<3>     size;
  for (int d = 0; d < 3; ++d)
  {
    origin[d] = lo[d] - 3.0;
    size[d] = static_cast<itk::SizeValueType>((hi[d] - lo[d] + 6.0) / voxel) + 1;
  }
  return MakeVolume(
    origin,
    size,
    voxel,
    [&plane](const double x[3], double & d, double & u, double & v) { return plane.Coordinates(x, d, u, v); },
    settings);
}

/** The cylinder-shell phantom: a volume of voxels of side voxel (mm) around the shell. */
inline VolumeType::Pointer
MakeCylinderShellVolume(const CylinderShell & shell, const PhantomSettings & settings, double voxel = 0.5)
{
  const double extent = shell.Radius + 3.0;
  const double origin[3] = { -extent, -extent, -3.0 };
  itk::Size<3> size;
  size[0] = size[1] = static_cast<itk::SizeValueType>(2.0 * extent / voxel) + 1;
  size[2] = static_cast<itk::SizeValueType>((SheetHeight + 6.0) / voxel) + 1;
  return MakeVolume(
    origin,
    size,
    voxel,
    [&shell](const double x[3], double & d, double & u, double & v) { return shell.Coordinates(x, d, u, v); },
    settings);
}

/** The grid mesh (columns x rows) of a phantom sheet's mid-surface (TiltedPlane,
 * CylinderShell: anything with At(u, v)); flat receives its exact flattening. */
template <typename TSheet>
inline itk::SheetMesh
MakeSheetMesh(const TSheet & sheet, int columns, int rows, itk::SheetMesh & flat)
{
  return MakeSheetMesh(
    columns, rows, [&sheet](double u, double v) { return sheet.At(u, v); }, flat);
}
} // namespace vu

#endif

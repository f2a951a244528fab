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
#ifndef vuGeneralSliceTracer_h
#define vuGeneralSliceTracer_h

#include "itkSheetMidSurfaceExtractor.h"
#include "vuPolyline.h"

#include <cmath>

namespace itk {
namespace SheetTracing {
// Bilinear sampling of one slice of the volume, in mm of the view's frame.
class SliceSampler
{
public:
  SliceSampler(const SheetVolumeView & volume, size_t slice)
    : m_NX(volume.Size[0])
    , m_NY(volume.Size[1])
    , m_SX(volume.Spacing[0])
    , m_SY(volume.Spacing[1])
  {
    const size_t offset = slice * m_NX * m_NY;
    m_Mask = volume.Mask + offset;
    m_Intensity = volume.Intensity != nullptr ? volume.Intensity + offset : nullptr;
  }

  bool
  HasIntensity() const
  {
    return m_Intensity != nullptr;
  }

  // Fraction of material; 0 outside the slice.
  double
  Mask(double x, double y) const
  {
    return Interpolate(
      x, y, [this](size_t i) { return m_Mask[i] != 0 ? 1.0 : 0.0; }, 0.0);
  }

  double
  Intensity(double x, double y, double outside) const
  {
    return Interpolate(
      x, y, [this](size_t i) { return static_cast<double>(m_Intensity[i]); }, outside);
  }

  size_t
  CountMaterial() const
  {
    return static_cast<size_t>(std::count_if(m_Mask, m_Mask + m_NX * m_NY, [](uint8_t v) { return v != 0; }));
  }

  size_t
  NX() const
  {
    return m_NX;
  }
  size_t
  NY() const
  {
    return m_NY;
  }
  const uint8_t *
  MaskPointer() const
  {
    return m_Mask;
  }

private:
  template <typename TValue>
  double
  Interpolate(double x, double y, const TValue & value, double outside) const
  {
    const double u = x / m_SX, v = y / m_SY;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto   i0 = static_cast<long>(fu), j0 = static_cast<long>(fv);
    const double a = u - fu, b = v - fv;
    double       result = 0.0;
    for (int dj = 0; dj < 2; ++dj)
    {
      for (int di = 0; di < 2; ++di)
      {
        const long   i = i0 + di, j = j0 + dj;
        const double weight = (di != 0 ? a : 1.0 - a) * (dj != 0 ? b : 1.0 - b);
        const bool   inside = i >= 0 && j >= 0 && i < static_cast<long>(m_NX) && j < static_cast<long>(m_NY);
        result += weight * (inside ? value(static_cast<size_t>(j) * m_NX + static_cast<size_t>(i)) : outside);
      }
    }
    return result;
  }

  const uint8_t * m_Mask{ nullptr };
  const float *   m_Intensity{ nullptr };
  size_t          m_NX, m_NY;
  double          m_SX, m_SY;
};

// What every slice tracer needs besides its slice.
struct TraceContext
{
  double Voxel{ 1.0 };      // in-plane voxel size
  double Base{ 0.0 };       // intensity halfway between air and material
  double AirLevel{ 0.0 };   // intensity outside the volume
  double SheetLevel{ 1.0 }; // intensity of the sheet's material
  double Centre[2]{ 0, 0 }; // roll axis in this slice
};

// General tracer for one slice: longest path of the skeleton of the largest component.
Polyline
TraceGeneralSlice(const SliceSampler & sampler, const TraceContext & context, double spacingY);
} // namespace SheetTracing
} // end namespace itk

#endif

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
#ifndef itkLayeredVolumeSampler_hxx
#define itkLayeredVolumeSampler_hxx

#include "itkLayeredVolumeSampler.h"

#include <algorithm>
#include <type_traits>
#include <typeinfo>

namespace itk {
template <typename TImage>
LayeredVolumeSampler<TImage>::LayeredVolumeSampler(const TImage *           volume,
                                                   const InterpolatorType * interpolator,
                                                   const TextureLayers &    layers)
  : m_Interpolator(interpolator)
  , m_Offsets(layers.GetOffsets())
{
  if (volume == nullptr || interpolator == nullptr)
  {
    itkGenericExceptionMacro(<< "LayeredVolumeSampler: no volume or no interpolator");
  }
  const auto & region = volume->GetBufferedRegion();
  if (region.GetNumberOfPixels() == 0)
  {
    itkGenericExceptionMacro(<< "LayeredVolumeSampler: the volume is empty");
  }
  const auto inverseDirection = volume->GetInverseDirection();
  const auto spacing = volume->GetSpacing();
  for (unsigned int i = 0; i < 3; ++i)
  {
    for (unsigned int j = 0; j < 3; ++j)
    {
      m_PhysicalToIndex[i][j] = inverseDirection[i][j] / spacing[i];
    }
    m_Origin[i] = volume->GetOrigin()[i];
    m_Lower[i] = static_cast<double>(region.GetIndex(i));
    m_Upper[i] = static_cast<double>(region.GetIndex(i) + static_cast<IndexValueType>(region.GetSize(i)) - 1);
    m_Last[i] = static_cast<IndexValueType>(region.GetSize(i)) - 1;
  }
  m_Cells = m_Last[0] > 0 && m_Last[1] > 0 && m_Last[2] > 0;
  if (!m_Offsets.empty())
  {
    m_OffsetRange[0] = *std::min_element(m_Offsets.begin(), m_Offsets.end());
    m_OffsetRange[1] = *std::max_element(m_Offsets.begin(), m_Offsets.end());
  }
  m_Stride[0] = 1;
  m_Stride[1] = region.GetSize(0);
  m_Stride[2] = region.GetSize(0) * region.GetSize(1);
  if (typeid(*interpolator) == typeid(LinearInterpolateImageFunction<TImage, double>) &&
      std::is_arithmetic<typename TImage::PixelType>::value)
  {
    m_Buffer = volume->GetBufferPointer();
  }
}

template <typename TImage>
void
LayeredVolumeSampler<TImage>::ConnectInterpolator(InterpolatorType * interpolator, const TImage * volume)
{
  if (interpolator->GetInputImage() != volume || interpolator->GetMTime() < volume->GetMTime())
  {
    interpolator->SetInputImage(volume);
  }
}

template <typename TImage>
inline float
LayeredVolumeSampler<TImage>::Interpolate(const typename TImage::PixelType * p,
                                          const float                        f[3],
                                          const SizeValueType                step[3])
{
  // Single precision: the voxels are floats, and the weights need no more.
  const auto  at = [p](SizeValueType o) { return static_cast<float>(p[o]); };
  const float c00 = at(0) + f[0] * (at(step[0]) - at(0));
  const float c10 = at(step[1]) + f[0] * (at(step[1] + step[0]) - at(step[1]));
  const float c01 = at(step[2]) + f[0] * (at(step[2] + step[0]) - at(step[2]));
  const float c11 = at(step[2] + step[1]) + f[0] * (at(step[2] + step[1] + step[0]) - at(step[2] + step[1]));
  const float c0 = c00 + f[1] * (c10 - c00);
  const float c1 = c01 + f[1] * (c11 - c01);
  return c0 + f[2] * (c1 - c0);
}

template <typename TImage>
inline float
LayeredVolumeSampler<TImage>::Trilinear(const double index[3]) const
{
  SizeValueType offset = 0;
  float         f[3];
  SizeValueType step[3];
  for (unsigned int i = 0; i < 3; ++i)
  {
    const double c = index[i] - m_Lower[i];
    // The last voxel is reached as the far corner of the cell before it (weight 1).
    const IndexValueType base = std::min(static_cast<IndexValueType>(c), std::max<IndexValueType>(m_Last[i] - 1, 0));
    f[i] = m_Last[i] > 0 ? static_cast<float>(c - base) : 0.0f;
    step[i] = m_Last[i] > 0 ? m_Stride[i] : 0;
    offset += base * m_Stride[i];
  }
  return Interpolate(m_Buffer + offset, f, step);
}

template <typename TImage>
inline float
LayeredVolumeSampler<TImage>::TrilinearInside(const double index[3]) const
{
  SizeValueType offset = 0;
  float         f[3];
  for (unsigned int i = 0; i < 3; ++i)
  {
    const double         c = index[i] - m_Lower[i];
    const IndexValueType base = static_cast<IndexValueType>(c);
    f[i] = static_cast<float>(c - base);
    offset += base * m_Stride[i];
  }
  return Interpolate(m_Buffer + offset, f, m_Stride);
}

template <typename TImage>
unsigned int
LayeredVolumeSampler<TImage>::Sample(const double point[3], const double normal[3], float * samples) const
{
  double base[3];
  double step[3];
  for (unsigned int i = 0; i < 3; ++i)
  {
    base[i] = m_PhysicalToIndex[i][0] * (point[0] - m_Origin[0]) + m_PhysicalToIndex[i][1] * (point[1] - m_Origin[1]) +
              m_PhysicalToIndex[i][2] * (point[2] - m_Origin[2]);
    step[i] =
      m_PhysicalToIndex[i][0] * normal[0] + m_PhysicalToIndex[i][1] * normal[1] + m_PhysicalToIndex[i][2] * normal[2];
  }
  // Where the nearest and the farthest layer lie inside the cells on every axis, so do the
  // layers between them (each coordinate is monotonic along the normal, and so is its
  // rounding): no clamp, and none counted.
  if (m_Buffer != nullptr && m_Cells && !m_Offsets.empty())
  {
    bool inside = true;
    for (unsigned int i = 0; i < 3; ++i)
    {
      const double a = base[i] + m_OffsetRange[0] * step[i], b = base[i] + m_OffsetRange[1] * step[i];
      inside = inside && a >= m_Lower[i] && a < m_Upper[i] && b >= m_Lower[i] && b < m_Upper[i];
    }
    if (inside)
    {
      for (size_t k = 0; k < m_Offsets.size(); ++k)
      {
        const double c[3] = { base[0] + m_Offsets[k] * step[0],
                              base[1] + m_Offsets[k] * step[1],
                              base[2] + m_Offsets[k] * step[2] };
        samples[k] = TrilinearInside(c);
      }
      return 0;
    }
  }
  unsigned int                                   clamped = 0;
  typename InterpolatorType::ContinuousIndexType index;
  for (size_t k = 0; k < m_Offsets.size(); ++k)
  {
    bool outside = false;
    for (unsigned int i = 0; i < 3; ++i)
    {
      const double c = base[i] + m_Offsets[k] * step[i];
      // Half a voxel beyond the boundary voxel centres is still inside the scanned volume.
      outside = outside || !(c >= m_Lower[i] - 0.5 && c <= m_Upper[i] + 0.5);
      index[i] = c >= m_Lower[i] ? (c <= m_Upper[i] ? c : m_Upper[i]) : m_Lower[i];
    }
    clamped += outside ? 1 : 0;
    samples[k] = m_Buffer != nullptr ? Trilinear(index.GetDataPointer())
                                     : static_cast<float>(m_Interpolator->EvaluateAtContinuousIndex(index));
  }
  return clamped;
}
} // end namespace itk

#endif

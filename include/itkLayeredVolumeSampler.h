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
#ifndef itkLayeredVolumeSampler_h
#define itkLayeredVolumeSampler_h

#include "itkInterpolateImageFunction.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkTextureLayers.h"

#include <vector>

namespace itk {
/** \class LayeredVolumeSampler
 * \brief Samples a 3D volume at every layer along a surface normal: the sampling engine
 * shared by LayeredTextureMeshFilter and FlattenedTextureImageFilter.
 *
 * For a point p and unit normal n (physical units), layer k is sampled at
 * p + offset_k * n with the offsets of a TextureLayers. The physical-to-index map is
 * precomputed once, so a sample costs one interpolation. Samples outside the volume
 * (beyond the outer faces of its boundary voxels) are clamped onto the boundary and
 * counted, never read out of bounds. The interpolator must already have the volume as
 * its input; its Evaluate methods are thread-safe, so one sampler serves all threads.
 *
 * With ITK's LinearInterpolateImageFunction (the default of the texture filters) the
 * sampler computes the same trilinear weights itself, straight from the voxel buffer:
 * the virtual call and the per-sample bounds logic of the generic interpolator cost more
 * than the interpolation, and the texture filters must sample tens of millions of points
 * per second. Any other interpolator is called as it is.
 *
 * \ingroup VirtualUnwrapping
 */
template <typename TImage>
class ITK_TEMPLATE_EXPORT LayeredVolumeSampler
{
public:
  static_assert(TImage::ImageDimension == 3, "the volume must be 3D");
  using InterpolatorType = InterpolateImageFunction<TImage, double>;

  LayeredVolumeSampler(const TImage * volume, const InterpolatorType * interpolator, const TextureLayers & layers);

  /** Gives interpolator the volume before a sampler is made of them, only when it holds
   * another image or the volume changed since: some interpolators precompute from their
   * image (B-spline coefficients). */
  static void
  ConnectInterpolator(InterpolatorType * interpolator, const TImage * volume);

  /** Writes one sample per layer into samples (GetNumberOfLayers() floats) and returns
   * how many of them fell outside the volume and were clamped. */
  unsigned int
  Sample(const double point[3], const double normal[3], float * samples) const;

  unsigned int
  GetNumberOfLayers() const
  {
    return static_cast<unsigned int>(m_Offsets.size());
  }

private:
  /** The trilinear blend of the cell at p (its corners `step` apart along each axis) at
   * fractions f. */
  static float
  Interpolate(const typename TImage::PixelType * p, const float f[3], const SizeValueType step[3]);
  float
  Trilinear(const double index[3]) const;
  /** Trilinear() at an index inside the cells (each coordinate in [lower, upper) of a volume
   * at least 2 voxels long on every axis), without its clamps: the same value. */
  float
  TrilinearInside(const double index[3]) const;

  const InterpolatorType *           m_Interpolator;
  const typename TImage::PixelType * m_Buffer{ nullptr };
  SizeValueType                      m_Stride[3];
  IndexValueType                     m_Last[3];
  std::vector<double>                m_Offsets;
  double                             m_PhysicalToIndex[3][3];
  double                             m_Origin[3];
  double                             m_Lower[3];
  double                             m_Upper[3];
  /** At least 2 voxels on every axis (the clamp-free path applies). */
  bool m_Cells{ false };
  /** The least and the greatest layer offset. */
  double m_OffsetRange[2]{ 0.0, 0.0 };
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkLayeredVolumeSampler.hxx"
#endif

#endif

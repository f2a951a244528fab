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
#include "itkLayeredVolumeSampler.h"

#include "itkBSplineInterpolateImageFunction.h"
#include "itkImage.h"

#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <random>

namespace {
using VolumeType = itk::Image<float, 3>;
using SamplerType = itk::LayeredVolumeSampler<VolumeType>;
using Side = itk::TextureLayersEnums::Side;
using Filter = itk::TextureLayersEnums::Filter;

// Random values on a rotated, anisotropic grid with an offset buffered region, so that
// every part of the index arithmetic matters.
VolumeType::Pointer
RandomVolume()
{
  auto                   volume = VolumeType::New();
  VolumeType::RegionType region({ { 3, -2, 5 } }, { { 9, 7, 6 } });
  volume->SetRegions(region);
  volume->SetSpacing(vu::Triple<VolumeType::SpacingType>(0.5, 0.75, 1.25));
  volume->SetOrigin(vu::Triple<VolumeType::PointType>(1.0, -2.0, 0.5));
  VolumeType::DirectionType direction;
  const double              c = std::cos(0.4), s = std::sin(0.4);
  direction.SetIdentity();
  direction[0][0] = c;
  direction[0][1] = -s;
  direction[1][0] = s;
  direction[1][1] = c;
  volume->SetDirection(direction);
  volume->Allocate();
  std::mt19937                          generator(3);
  std::uniform_real_distribution<float> uniform(0.0f, 10.0f);
  for (itk::SizeValueType n = 0; n < region.GetNumberOfPixels(); ++n)
  {
    volume->GetBufferPointer()[n] = uniform(generator);
  }
  return volume;
}
} // namespace

TEST(LayeredVolumeSampler, LinearSamplesEqualITKsLinearInterpolator)
{
  const auto volume = RandomVolume();
  auto       interpolator = itk::LinearInterpolateImageFunction<VolumeType, double>::New();
  interpolator->SetInputImage(volume);
  const itk::TextureLayers layers(5, 0.3, 0.1, Side::Both, Filter::Mean, 1.0);
  const SamplerType        sampler(volume, interpolator, layers);

  std::mt19937                           generator(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto &                           region = volume->GetBufferedRegion();
  int                                    compared = 0;
  for (int trial = 0; trial < 2000; ++trial)
  {
    // A point anywhere in the index box, up to its very faces, and a random unit normal.
    itk::ContinuousIndex<double, 3> index;
    for (unsigned int d = 0; d < 3; ++d)
    {
      index[d] = region.GetIndex(d) - 0.5 + unit(generator) * region.GetSize(d);
    }
    VolumeType::PointType point;
    volume->TransformContinuousIndexToPhysicalPoint(index, point);
    double       normal[3] = { unit(generator) - 0.5, unit(generator) - 0.5, unit(generator) - 0.5 };
    const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (double & n : normal)
    {
      n /= length;
    }
    float              samples[5];
    const double       p[3] = { point[0], point[1], point[2] };
    const unsigned int clamped = sampler.Sample(p, normal, samples);
    unsigned int       outside = 0;
    for (unsigned int k = 0; k < 5; ++k)
    {
      VolumeType::PointType q;
      for (unsigned int d = 0; d < 3; ++d)
      {
        q[d] = p[d] + layers.GetOffsets()[k] * normal[d];
      }
      itk::ContinuousIndex<double, 3> qi;
      volume->TransformPhysicalPointToContinuousIndex(q, qi);
      bool inside = true;
      for (unsigned int d = 0; d < 3; ++d)
      {
        const double lo = region.GetIndex(d), hi = region.GetIndex(d) + region.GetSize(d) - 1.0;
        inside = inside && qi[d] >= lo - 0.5 && qi[d] <= hi + 0.5;
        qi[d] = std::min(std::max(qi[d], lo), hi);
      }
      outside += inside ? 0 : 1;
      EXPECT_NEAR(samples[k], interpolator->EvaluateAtContinuousIndex(qi), 1e-4);
      ++compared;
    }
    EXPECT_EQ(clamped, outside);
  }
  EXPECT_EQ(compared, 10000);
}

TEST(LayeredVolumeSampler, OtherInterpolatorsAreCalledAsTheyAre)
{
  const auto volume = RandomVolume();
  auto       interpolator = itk::BSplineInterpolateImageFunction<VolumeType, double>::New();
  interpolator->SetInputImage(volume);
  const itk::TextureLayers        layers(1, 1.0, 0.0, Side::Both, Filter::Mean, 1.0);
  const SamplerType               sampler(volume, interpolator, layers);
  itk::ContinuousIndex<double, 3> index;
  index[0] = 6.3;
  index[1] = 1.7;
  index[2] = 7.2;
  VolumeType::PointType point;
  volume->TransformContinuousIndexToPhysicalPoint(index, point);
  const double p[3] = { point[0], point[1], point[2] };
  const double normal[3] = { 0.0, 0.0, 1.0 };
  float        sample;
  EXPECT_EQ(sampler.Sample(p, normal, &sample), 0u);
  EXPECT_NEAR(sample, interpolator->EvaluateAtContinuousIndex(index), 1e-4);
}

TEST(LayeredVolumeSampler, MissingInputsThrow)
{
  const itk::TextureLayers layers(1, 1.0, 0.0, Side::Both, Filter::Mean, 1.0);
  auto                     interpolator = itk::LinearInterpolateImageFunction<VolumeType, double>::New();
  EXPECT_THROW(SamplerType(nullptr, interpolator, layers), itk::ExceptionObject);
  EXPECT_THROW(SamplerType(RandomVolume(), nullptr, layers), itk::ExceptionObject);
}

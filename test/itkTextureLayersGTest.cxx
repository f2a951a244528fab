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
#include "itkTextureLayers.h"

#include "itkMacro.h"

#include "gtest/gtest.h"

#include <cmath>
#include <sstream>
#include <vector>

namespace {
using Side = itk::TextureLayersEnums::Side;
using Filter = itk::TextureLayersEnums::Filter;

float
Combine(const itk::TextureLayers & layers, std::vector<float> samples)
{
  return layers.Combine(samples.data());
}
} // namespace

TEST(TextureLayers, OffsetsFollowSideFocusAndSpacing)
{
  const itk::TextureLayers both(4, 0.5, 1.0, Side::Both, Filter::Mean, 1.0);
  EXPECT_EQ(both.GetOffsets(), (std::vector<double>{ 0.25, 0.75, 1.25, 1.75 }));
  EXPECT_EQ(both.GetCentralLayer(), 1u); // 0.75 and 1.25 tie: the lower index
  const itk::TextureLayers positive(3, 0.5, -1.0, Side::Positive, Filter::Mean, 1.0);
  EXPECT_EQ(positive.GetOffsets(), (std::vector<double>{ -1.0, -0.5, 0.0 }));
  EXPECT_EQ(positive.GetCentralLayer(), 0u);
  const itk::TextureLayers negative(3, 0.25, 0.0, Side::Negative, Filter::Mean, 1.0);
  EXPECT_EQ(negative.GetOffsets(), (std::vector<double>{ 0.0, -0.25, -0.5 }));
  const itk::TextureLayers single(1, 1.0, 0.3, Side::Both, Filter::Mean, 1.0);
  EXPECT_EQ(single.GetOffsets(), (std::vector<double>{ 0.3 }));
}

TEST(TextureLayers, FiltersCombineSamples)
{
  const std::vector<float> samples{ 4.0f, 1.0f, 9.0f, 2.0f, 3.0f };
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::Mean, 1.0), samples), 3.8f);
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::Max, 1.0), samples), 9.0f);
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::Min, 1.0), samples), 1.0f);
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::Median, 1.0), samples), 3.0f);
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::SingleLayer, 1.0), samples), 9.0f);
  EXPECT_FLOAT_EQ(Combine(itk::TextureLayers(4, 1.0, 0.0, Side::Both, Filter::Median, 1.0), { 4, 1, 9, 2 }), 3.0f);
  // Gaussian weights of offsets -2 .. 2 with sigma 1.
  double weighted = 0.0, weights = 0.0;
  for (int k = 0; k < 5; ++k)
  {
    const double w = std::exp(-0.5 * (k - 2) * (k - 2));
    weighted += w * samples[k];
    weights += w;
  }
  EXPECT_NEAR(
    Combine(itk::TextureLayers(5, 1.0, 0.0, Side::Both, Filter::GaussianMean, 1.0), samples), weighted / weights, 1e-5);
}

TEST(TextureLayers, ImpossibleParametersThrow)
{
  EXPECT_THROW(itk::TextureLayers(0, 1.0, 0.0, Side::Both, Filter::Mean, 1.0), itk::ExceptionObject);
  EXPECT_THROW(itk::TextureLayers(3, 0.0, 0.0, Side::Both, Filter::Mean, 1.0), itk::ExceptionObject);
  EXPECT_THROW(itk::TextureLayers(3, -1.0, 0.0, Side::Both, Filter::Mean, 1.0), itk::ExceptionObject);
  EXPECT_THROW(itk::TextureLayers(3, 1.0, std::nan(""), Side::Both, Filter::Mean, 1.0), itk::ExceptionObject);
  EXPECT_THROW(itk::TextureLayers(3, 1.0, 0.0, Side::Both, Filter::GaussianMean, 0.0), itk::ExceptionObject);
  EXPECT_NO_THROW(itk::TextureLayers(3, 1.0, 0.0, Side::Both, Filter::Mean, 0.0)); // sigma unused
}

TEST(TextureLayers, EnumsPrint)
{
  std::ostringstream out;
  out << Side::Negative << " " << Filter::GaussianMean;
  EXPECT_EQ(out.str(), "Negative GaussianMean");
}

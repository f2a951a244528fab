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
#include "vuTextureOutput.h"

#include "vuCommands.h"

#include "itkImageRegionConstIterator.h"
#include "itkImageRegionIterator.h"
#include "itkLayerStackTexture.h"

#include <algorithm>
#include <cmath>

namespace vu {
itk::TextureLayersEnums::Filter
FilterFromName(const std::string & name)
{
  using F = itk::TextureLayersEnums::Filter;
  if (name == "mean")
    return F::Mean;
  if (name == "gaussian")
    return F::GaussianMean;
  if (name == "max")
    return F::Max;
  if (name == "min")
    return F::Min;
  if (name == "median")
    return F::Median;
  return F::SingleLayer;
}

itk::Image<unsigned char, 2>::Pointer
EightBit(const itk::Image<float, 2> * texture)
{
  using TextureType = itk::Image<float, 2>;
  const std::vector<double> window = itk::LayerStackTexture::DisplayWindow(texture);
  if (window.empty())
  {
    throw UsageError("the texture has no pixel on the sheet");
  }
  const auto lo = static_cast<float>(window[0]), hi = std::max(static_cast<float>(window[1]), lo + 1e-6f);
  // The background's noise cleared, shown in the window of the texture as it was.
  const auto shown = itk::LayerStackTexture::ClearBackground(texture);
  auto       out = itk::Image<unsigned char, 2>::New();
  out->CopyInformation(texture);
  out->SetRegions(texture->GetBufferedRegion());
  out->Allocate();
  itk::ImageRegionConstIterator<TextureType>             in(shown, shown->GetBufferedRegion());
  itk::ImageRegionIterator<itk::Image<unsigned char, 2>> o(out, out->GetBufferedRegion());
  for (; !in.IsAtEnd(); ++in, ++o)
  {
    const float v = in.Get();
    o.Set(std::isfinite(v) ? static_cast<unsigned char>(std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f) * 255.0f + 0.5f)
                           : 0);
  }
  return out;
}

std::vector<double>
FlatTextureCoordinates(const itk::SheetMesh & flat,
                       const double           origin[2],
                       double                 pixelSize,
                       size_t                 width,
                       size_t                 height)
{
  const double        w = static_cast<double>(width) * pixelSize, h = static_cast<double>(height) * pixelSize;
  std::vector<double> uv(2 * flat.GetNumberOfPoints());
  for (size_t i = 0; i < flat.GetNumberOfPoints(); ++i)
  {
    uv[2 * i] = (flat.Points[3 * i] - (origin[0] - 0.5 * pixelSize)) / w;
    uv[2 * i + 1] = (flat.Points[3 * i + 1] - (origin[1] - 0.5 * pixelSize)) / h;
  }
  return uv;
}
} // namespace vu

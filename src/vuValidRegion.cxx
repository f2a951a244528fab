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
#include "vuValidRegion.h"

#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>

namespace itk {
namespace detail {
std::vector<float>
DistanceInsideValidRegion(const Image<unsigned char, 2> * valid)
{
  using MaskType = Image<unsigned char, 2>;
  const auto size = valid->GetBufferedRegion().GetSize();
  // One ring of invalid pixels around the image, so that its border counts as an edge.
  auto               invalid = MaskType::New();
  MaskType::SizeType paddedSize = { { size[0] + 2, size[1] + 2 } };
  invalid->SetRegions(paddedSize);
  invalid->SetSpacing(valid->GetSpacing());
  invalid->Allocate();
  invalid->FillBuffer(1);
  const unsigned char * in = valid->GetBufferPointer();
  unsigned char *       mask = invalid->GetBufferPointer();
  for (SizeValueType y = 0; y < size[1]; ++y)
  {
    for (SizeValueType x = 0; x < size[0]; ++x)
    {
      mask[(y + 1) * paddedSize[0] + x + 1] = in[y * size[0] + x] != 0 ? 0 : 1;
    }
  }
  auto distance = SignedMaurerDistanceMapImageFilter<MaskType, Image<float, 2>>::New();
  distance->SetInput(invalid);
  distance->SetBackgroundValue(0);
  distance->SetUseImageSpacing(true);
  distance->SetSquaredDistance(false);
  distance->SetInsideIsPositive(false);
  distance->Update();
  const float *      d = distance->GetOutput()->GetBufferPointer();
  const float        halfPixel = 0.5f * static_cast<float>(std::min(valid->GetSpacing()[0], valid->GetSpacing()[1]));
  std::vector<float> inside(size[0] * size[1]);
  for (SizeValueType y = 0; y < size[1]; ++y)
  {
    for (SizeValueType x = 0; x < size[0]; ++x)
    {
      inside[y * size[0] + x] = d[(y + 1) * paddedSize[0] + x + 1] - halfPixel;
    }
  }
  return inside;
}
} // namespace detail
} // namespace itk

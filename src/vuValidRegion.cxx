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

#include "itkMultiThreaderBase.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

std::vector<char>
WithinOfValidRegionEdge(const Image<unsigned char, 2> * valid, double width)
{
  const auto            size = valid->GetBufferedRegion().GetSize();
  const auto            columns = static_cast<long>(size[0]), rows = static_cast<long>(size[1]);
  const double          sx = valid->GetSpacing()[0], sy = valid->GetSpacing()[1];
  const float           halfPixel = 0.5f * static_cast<float>(std::min(sx, sy));
  const unsigned char * in = valid->GetBufferPointer();
  // A pixel is within when its distance to the nearest invalid centre is below
  // width + half a pixel: only invalid pixels that near, and rows that near, matter.
  const double reach = width + halfPixel;
  const long   cap = static_cast<long>(std::ceil(reach / sx)) + 1;
  const long   rowReach = static_cast<long>(std::ceil(reach / sy)) + 1;
  // Along each row, the number of pixels to the nearest invalid one (outside the row's ends
  // counts as invalid), capped where it no longer matters.
  std::vector<int> along(size[0] * size[1]);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      const unsigned char * line = in + row * columns;
      int *                 h = &along[row * columns];
      long                  last = -1;
      for (long x = 0; x < columns; ++x)
      {
        last = line[x] != 0 ? last : x;
        h[x] = static_cast<int>(std::min(cap, x - last));
      }
      long next = columns;
      for (long x = columns - 1; x >= 0; --x)
      {
        next = line[x] != 0 ? next : x;
        h[x] = std::min(h[x], static_cast<int>(std::min(cap, next - x)));
      }
    },
    nullptr);
  std::vector<char> within(size[0] * size[1]);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      const auto          y = static_cast<long>(row);
      std::vector<double> nearest(columns, std::numeric_limits<double>::infinity());
      for (long dy = -rowReach; dy <= rowReach; ++dy)
      {
        const double across = (dy * sy) * (dy * sy);
        if (y + dy < 0 || y + dy >= rows)
        {
          // The ring of invalid pixels around the image.
          if (y + dy == -1 || y + dy == rows)
          {
            for (long x = 0; x < columns; ++x)
            {
              nearest[x] = std::min(nearest[x], across);
            }
          }
          continue;
        }
        const int * h = &along[(y + dy) * columns];
        for (long x = 0; x < columns; ++x)
        {
          const double a = h[x] * sx;
          nearest[x] = std::min(nearest[x], a * a + across);
        }
      }
      char * target = &within[y * columns];
      for (long x = 0; x < columns; ++x)
      {
        target[x] = static_cast<float>(std::sqrt(nearest[x])) - halfPixel < width;
      }
    },
    nullptr);
  return within;
}
} // namespace detail
} // namespace itk

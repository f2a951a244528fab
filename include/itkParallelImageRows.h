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
#ifndef itkParallelImageRows_h
#define itkParallelImageRows_h

#include "itkImageRegion.h"
#include "itkMultiThreaderBase.h"

#include <algorithm>
#include <vector>

namespace itk {
/** Calls `visit(k, j, row)` for every row of `region` (a part of a 3D image's buffered
 * region): k and j count the region's slices and rows from 0, `row` points at the row's
 * first voxel in the buffer. The slices are shared among ITK's threads; a slice's rows are
 * visited in order by one thread, so state kept per slice (indexed by k) needs no lock and
 * sums over the slices taken in slice order are the same on any number of threads. */
template <typename TImage, typename TVisit>
void
ForEachImageRow(TImage * image, const ImageRegion<3> & region, TVisit visit)
{
  static_assert(TImage::ImageDimension == 3, "a 3D image");
  const auto size = region.GetSize();
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[2],
    [&](SizeValueType k) {
      for (SizeValueType j = 0; j < size[1]; ++j)
      {
        auto index = region.GetIndex();
        index[1] += static_cast<IndexValueType>(j);
        index[2] += static_cast<IndexValueType>(k);
        visit(k, j, image->GetBufferPointer() + image->ComputeOffset(index));
      }
    },
    nullptr);
}

/** The smallest region of a 3D image's buffered region holding every voxel whose value
 * satisfies `inside`, grown by `margin` voxels on every side and cropped to the buffered
 * region; a region of size 0 when no voxel does. Rows are examined from both ends, the
 * slices in parallel (ForEachImageRow). */
template <typename TImage, typename TPredicate>
ImageRegion<3>
BoundingRegionWhere(const TImage * image, TPredicate inside, long margin)
{
  const ImageRegion<3> region = image->GetBufferedRegion();
  const auto           size = region.GetSize();
  const long           nx = static_cast<long>(size[0]);
  struct SliceBox
  {
    bool Any{ false };
    long Lower[2]{ 0, 0 };
    long Upper[2]{ 0, 0 };
  };
  std::vector<SliceBox> slices(size[2]);
  ForEachImageRow(image, region, [&](SizeValueType k, SizeValueType j, const auto * row) {
    long first = 0;
    while (first < nx && !inside(row[first]))
    {
      ++first;
    }
    if (first == nx)
    {
      return;
    }
    long last = nx - 1;
    while (!inside(row[last]))
    {
      --last;
    }
    SliceBox & box = slices[k];
    box.Lower[0] = box.Any ? std::min(box.Lower[0], first) : first;
    box.Upper[0] = box.Any ? std::max(box.Upper[0], last) : last;
    box.Lower[1] = box.Any ? box.Lower[1] : static_cast<long>(j);
    box.Upper[1] = static_cast<long>(j);
    box.Any = true;
  });
  Index<3> lower, upper;
  bool     any = false;
  for (SizeValueType k = 0; k < size[2]; ++k)
  {
    const SliceBox & box = slices[k];
    if (!box.Any)
    {
      continue;
    }
    const long slice = static_cast<long>(k);
    lower[0] = any ? std::min(lower[0], box.Lower[0]) : box.Lower[0];
    upper[0] = any ? std::max(upper[0], box.Upper[0]) : box.Upper[0];
    lower[1] = any ? std::min(lower[1], box.Lower[1]) : box.Lower[1];
    upper[1] = any ? std::max(upper[1], box.Upper[1]) : box.Upper[1];
    lower[2] = any ? lower[2] : slice;
    upper[2] = slice;
    any = true;
  }
  ImageRegion<3> result;
  if (!any)
  {
    result.SetIndex(region.GetIndex());
    return result;
  }
  for (unsigned d = 0; d < 3; ++d)
  {
    lower[d] += region.GetIndex()[d] - margin;
    upper[d] += region.GetIndex()[d] + margin;
  }
  result.SetIndex(lower);
  result.SetUpperIndex(upper);
  result.Crop(region);
  return result;
}
} // end namespace itk

#endif

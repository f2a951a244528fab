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
#ifndef vuVoxelCount_h
#define vuVoxelCount_h

#include "itkImageRegionConstIteratorWithIndex.h"

#include <cstddef>

namespace vu {
/** How many voxels of the image's largest region fail `holds(value, index)`: the voxels of
 * a read volume that do not hold what was written. */
template <typename TImage, typename THolds>
size_t
CountVoxelsNotHolding(const TImage * image, THolds holds)
{
  size_t bad = 0;
  for (itk::ImageRegionConstIteratorWithIndex<TImage> it(image, image->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    bad += holds(it.Get(), it.GetIndex()) ? 0 : 1;
  }
  return bad;
}
} // namespace vu

#endif

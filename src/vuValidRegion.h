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
#ifndef vuValidRegion_h
#define vuValidRegion_h

#include "itkImage.h"

#include <vector>

namespace itk {
namespace detail {
/** For every pixel of a 2D mask (non-zero = valid), how far its centre lies inside the
 * edge of the valid region, in physical units: the distance to the nearest invalid pixel
 * centre less half a pixel, so that the edge sits half a pixel beyond the centres of the
 * outermost valid pixels. Outside the image counts as invalid. Invalid pixels get values
 * <= 0. Shared by LayerStackTexture::TrimBorder and TextureFidelityCalculator's border. */
std::vector<float>
DistanceInsideValidRegion(const Image<unsigned char, 2> * valid);

/** Whether each pixel lies less than `width` (physical units, > 0) inside the edge of the
 * valid region, as DistanceInsideValidRegion measures it (invalid pixels always do), found
 * without a whole distance map: each row's distance to its nearest invalid pixel, then the
 * nearest over the rows within `width`. */
std::vector<char>
WithinOfValidRegionEdge(const Image<unsigned char, 2> * valid, double width);
} // namespace detail
} // namespace itk

#endif

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
#ifndef vuCombineLayers_h
#define vuCombineLayers_h

#include "itkImage.h"
#include "itkTextureLayers.h"

#include <vector>

namespace itk {
namespace detail {
/** One texture of CombineLayers(): the layers on Side, less the mean of their core when
 * CoreWidth > 0 (as LayerStackTexture::Combine() takes them). */
struct LayerCombination
{
  TextureLayersEnums::Side Side;
  double                   CoreWidth;
};

/** Several combinations of the same stack in one pass over it (each pixel's samples read
 * once): the same textures as one LayerStackTexture::Combine() each. */
std::vector<Image<float, 2>::Pointer>
CombineLayers(const Image<float, 3> *               stack,
              unsigned int                          numberOfLayers,
              double                                layerSpacing,
              double                                focus,
              TextureLayersEnums::Side              stackSide,
              TextureLayersEnums::Filter            filter,
              double                                gaussianSigma,
              const std::vector<LayerCombination> & combinations);

/** An empty texture with the geometry of the stack's first two axes. */
Image<float, 2>::Pointer
NewLayerTexture(const Image<float, 3> * stack);

/** Throws unless `value` is finite and >= 0 (> 0 when not `zeroAllowed`), naming
 * LayerStackTexture::`function` and `what`. */
void
CheckLayerParameter(double value, bool zeroAllowed, const char * function, const char * what);
} // namespace detail
} // end namespace itk

#endif

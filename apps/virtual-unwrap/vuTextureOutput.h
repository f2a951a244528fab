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
#ifndef vuTextureOutput_h
#define vuTextureOutput_h

#include "itkImage.h"
#include "itkSheetMesh.h"
#include "itkTextureLayers.h"

#include <string>
#include <vector>

namespace vu {
/** The layer filter named as the tool's --filter spells it: mean, gaussian, max, min,
 * median; anything else is the single central layer. */
itk::TextureLayersEnums::Filter
FilterFromName(const std::string & name);

/** 8-bit view of a texture: the background's noise cleared (LayerStackTexture::
 * ClearBackground()), contrast stretched over LayerStackTexture::DisplayWindow() of the
 * sheet's pixels (the finite ones: the background dark, the ink bright); off the sheet
 * black. Throws vu::UsageError when no pixel is on the sheet. */
itk::Image<unsigned char, 2>::Pointer
EightBit(const itk::Image<float, 2> * texture);

/** Texture coordinates (u, v per point) of a flat mesh in a texture of width x height
 * pixels of pixelSize whose first pixel's centre is at origin: (0, 0) is the texture's
 * bottom left corner, (1, 1) its top right, as OBJ and VTK take them. */
std::vector<double>
FlatTextureCoordinates(const itk::SheetMesh & flat,
                       const double           origin[2],
                       double                 pixelSize,
                       size_t                 width,
                       size_t                 height);
} // namespace vu

#endif

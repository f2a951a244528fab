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
#ifndef itkTextureLayers_h
#define itkTextureLayers_h

#include "VirtualUnwrappingExport.h"

#include <cstdint>
#include <ostream>
#include <vector>

namespace itk {
/** \class TextureLayersEnums
 * \brief Choices of the layered texture: on which side of the sheet the layers lie and
 * how their samples combine into one value.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT TextureLayersEnums
{
public:
  /** Layers centred on the focus (Both), or starting at the focus and stepping along the
   * normal (Positive) or against it (Negative). */
  enum class Side : uint8_t
  {
    Both,
    Positive,
    Negative
  };
  /** Mean, Gaussian-weighted mean (weights exp(-d^2 / (2 sigma^2)) of the distance d from
   * the focus), Max, Min, Median of the layers, or SingleLayer: the layer nearest the
   * focus alone (the other layers are only in the layer stack). */
  enum class Filter : uint8_t
  {
    Mean,
    GaussianMean,
    Max,
    Min,
    Median,
    SingleLayer
  };
  /** Whether a one-sided texture has the sheet's core (the layers within half a voxel of
   * the mid-surface) subtracted: always, never, or whichever shows the higher ink contrast. */
  enum class CoreSubtraction : uint8_t
  {
    Auto,
    Yes,
    No
  };
};
VirtualUnwrapping_EXPORT std::ostream &
                         operator<<(std::ostream & out, const TextureLayersEnums::Side value);
VirtualUnwrapping_EXPORT std::ostream &
                         operator<<(std::ostream & out, const TextureLayersEnums::Filter value);
VirtualUnwrapping_EXPORT std::ostream &
                         operator<<(std::ostream & out, const TextureLayersEnums::CoreSubtraction value);

/** \class TextureLayers
 * \brief How to sample along a surface normal and combine the samples: the layer offsets
 * and the combining filter shared by the layered texture filters.
 *
 * Parameters (checked by the constructor, which throws itk::ExceptionObject with a
 * one-line message when one is out of range):
 * - numberOfLayers: >= 1;
 * - layerSpacing: distance between neighbouring layers, physical units, > 0;
 * - focus: signed offset of the central layer along the normal, physical units, any
 *   finite value ("focusing" through the sheet);
 * - side: Both (layers at focus + (k - (n - 1) / 2) * spacing), Positive
 *   (focus + k * spacing) or Negative (focus - k * spacing), k = 0 .. n - 1;
 * - filter: see TextureLayersEnums::Filter;
 * - gaussianSigma: width of the Gaussian weights, physical units, > 0 (used by
 *   GaussianMean only).
 *
 * Reference: W. B. Seales and Y. Lin, "Digital Restoration Using Volumetric Scanning",
 * JCDL 2004 (layered texture: number of layers, distance between layers, filter).
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT TextureLayers
{
public:
  using SideType = TextureLayersEnums::Side;
  using FilterType = TextureLayersEnums::Filter;

  TextureLayers(unsigned int numberOfLayers,
                double       layerSpacing,
                double       focus,
                SideType     side,
                FilterType   filter,
                double       gaussianSigma);

  unsigned int
  GetNumberOfLayers() const
  {
    return static_cast<unsigned int>(m_Offsets.size());
  }

  /** Signed distance of each layer from the surface along the normal, physical units,
   * in increasing layer index. */
  const std::vector<double> &
  GetOffsets() const
  {
    return m_Offsets;
  }

  /** The layer nearest the focus (the lower index on a tie): the SingleLayer value. */
  unsigned int
  GetCentralLayer() const
  {
    return m_CentralLayer;
  }

  /** Combines one sample per layer (in layer order) with the filter. May reorder the
   * samples (Median). */
  float
  Combine(float * samples) const;

private:
  std::vector<double> m_Offsets;
  std::vector<double> m_Weights;
  FilterType          m_Filter;
  unsigned int        m_CentralLayer{ 0 };
};
} // end namespace itk

#endif

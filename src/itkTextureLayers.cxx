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

#include <algorithm>
#include <cmath>

namespace itk {
std::ostream &
operator<<(std::ostream & out, const TextureLayersEnums::Side value)
{
  switch (value)
  {
    case TextureLayersEnums::Side::Both:
      return out << "Both";
    case TextureLayersEnums::Side::Positive:
      return out << "Positive";
    case TextureLayersEnums::Side::Negative:
      return out << "Negative";
  }
  return out << "INVALID Side " << static_cast<int>(value);
}

std::ostream &
operator<<(std::ostream & out, const TextureLayersEnums::Filter value)
{
  switch (value)
  {
    case TextureLayersEnums::Filter::Mean:
      return out << "Mean";
    case TextureLayersEnums::Filter::GaussianMean:
      return out << "GaussianMean";
    case TextureLayersEnums::Filter::Max:
      return out << "Max";
    case TextureLayersEnums::Filter::Min:
      return out << "Min";
    case TextureLayersEnums::Filter::Median:
      return out << "Median";
    case TextureLayersEnums::Filter::SingleLayer:
      return out << "SingleLayer";
  }
  return out << "INVALID Filter " << static_cast<int>(value);
}

std::ostream &
operator<<(std::ostream & out, const TextureLayersEnums::CoreSubtraction value)
{
  switch (value)
  {
    case TextureLayersEnums::CoreSubtraction::Auto:
      return out << "Auto";
    case TextureLayersEnums::CoreSubtraction::Yes:
      return out << "Yes";
    case TextureLayersEnums::CoreSubtraction::No:
      return out << "No";
  }
  return out << "INVALID CoreSubtraction " << static_cast<int>(value);
}

TextureLayers::TextureLayers(unsigned int numberOfLayers,
                             double       layerSpacing,
                             double       focus,
                             SideType     side,
                             FilterType   filter,
                             double       gaussianSigma)
  : m_Filter(filter)
{
  if (numberOfLayers == 0)
  {
    itkGenericExceptionMacro(<< "TextureLayers: the number of layers must be at least 1");
  }
  if (!(layerSpacing > 0.0) || !std::isfinite(layerSpacing))
  {
    itkGenericExceptionMacro(<< "TextureLayers: layer spacing must be positive and finite, got " << layerSpacing);
  }
  if (!std::isfinite(focus))
  {
    itkGenericExceptionMacro(<< "TextureLayers: focus must be finite, got " << focus);
  }
  if (filter == FilterType::GaussianMean && (!(gaussianSigma > 0.0) || !std::isfinite(gaussianSigma)))
  {
    itkGenericExceptionMacro(<< "TextureLayers: Gaussian sigma must be positive and finite, got " << gaussianSigma);
  }
  m_Offsets.resize(numberOfLayers);
  for (unsigned int k = 0; k < numberOfLayers; ++k)
  {
    switch (side)
    {
      case SideType::Both:
        m_Offsets[k] = focus + (k - 0.5 * (numberOfLayers - 1)) * layerSpacing;
        break;
      case SideType::Positive:
        m_Offsets[k] = focus + k * layerSpacing;
        break;
      case SideType::Negative:
        m_Offsets[k] = focus - k * layerSpacing;
        break;
      default:
        itkGenericExceptionMacro(<< "TextureLayers: unknown side " << side);
    }
  }
  for (unsigned int k = 1; k < numberOfLayers; ++k)
  {
    if (std::abs(m_Offsets[k] - focus) < std::abs(m_Offsets[m_CentralLayer] - focus) - 1e-12 * layerSpacing)
    {
      m_CentralLayer = k;
    }
  }
  m_Weights.assign(numberOfLayers, 1.0 / numberOfLayers);
  if (filter == FilterType::GaussianMean)
  {
    double sum = 0.0;
    for (unsigned int k = 0; k < numberOfLayers; ++k)
    {
      const double d = m_Offsets[k] - focus;
      m_Weights[k] = std::exp(-d * d / (2.0 * gaussianSigma * gaussianSigma));
      sum += m_Weights[k];
    }
    for (double & w : m_Weights)
    {
      w /= sum;
    }
  }
  else if (filter != FilterType::Mean && filter != FilterType::Max && filter != FilterType::Min &&
           filter != FilterType::Median && filter != FilterType::SingleLayer)
  {
    itkGenericExceptionMacro(<< "TextureLayers: unknown filter " << filter);
  }
}

float
TextureLayers::Combine(float * samples) const
{
  const unsigned int n = GetNumberOfLayers();
  switch (m_Filter)
  {
    case FilterType::Mean:
    case FilterType::GaussianMean:
    {
      double sum = 0.0;
      for (unsigned int k = 0; k < n; ++k)
      {
        sum += m_Weights[k] * samples[k];
      }
      return static_cast<float>(sum);
    }
    case FilterType::Max:
      return *std::max_element(samples, samples + n);
    case FilterType::Min:
      return *std::min_element(samples, samples + n);
    case FilterType::Median:
    {
      // Even counts average the two middle samples, as the usual median does.
      float * middle = samples + n / 2;
      std::nth_element(samples, middle, samples + n);
      if (n % 2 == 1)
      {
        return *middle;
      }
      const float below = *std::max_element(samples, middle);
      return 0.5f * (below + *middle);
    }
    case FilterType::SingleLayer:
      return samples[m_CentralLayer];
  }
  return samples[m_CentralLayer];
}
} // end namespace itk

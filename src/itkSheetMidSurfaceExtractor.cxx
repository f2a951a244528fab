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
#include "itkSheetMidSurfaceExtractor.h"

#include "vuSheetExtraction.h"

#include "itkImage.h"
#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace itk {
const char *
ToString(SheetSurfaceMethodEnum method)
{
  switch (method)
  {
    case SheetSurfaceMethodEnum::Roll:
      return "roll";
    case SheetSurfaceMethodEnum::General:
      return "general";
    case SheetSurfaceMethodEnum::Auto:
      break;
  }
  return "auto";
}

SheetSurfaceMethodEnum
SheetSurfaceMethodFromString(const std::string & name)
{
  for (auto method : { SheetSurfaceMethodEnum::Auto, SheetSurfaceMethodEnum::Roll, SheetSurfaceMethodEnum::General })
  {
    if (name == ToString(method))
    {
      return method;
    }
  }
  itkGenericExceptionMacro(<< "unknown surface method \"" << name << "\" (known: auto, roll, general)");
}

double
SheetIntensityLevels::SignalToNoise() const
{
  return Noise > 0.0 ? (Sheet - Air) / Noise : std::numeric_limits<double>::infinity();
}

double
SheetIntensityLevels::DenoisingSigma() const
{
  const double snr = SignalToNoise();
  return snr >= 12.0 ? 0.0 : std::clamp(3.0 / snr, 0.5, 1.0);
}

SheetIntensityLevels
EstimateSheetIntensityLevels(std::vector<float> air, std::vector<float> material)
{
  SheetIntensityLevels levels;
  if (!air.empty())
  {
    const float floor = *std::min_element(air.begin(), air.end());
    air.erase(std::remove(air.begin(), air.end(), floor), air.end());
  }
  auto at = [](std::vector<float> & values, double fraction) {
    const auto i = values.begin() + static_cast<std::ptrdiff_t>(fraction * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), i, values.end());
    return static_cast<double>(*i);
  };
  if (air.size() >= 16 && !material.empty())
  {
    levels.Air = at(air, 0.5);
    levels.Noise = levels.Air - at(air, 0.1587);
    levels.Sheet = at(material, 0.5);
  }
  return levels;
}

SheetIntensityLevels
RefineSheetIntensityLevels(const std::vector<float> & values, SheetIntensityLevels levels)
{
  std::vector<float> air, sheet;
  for (int pass = 0; pass < 30 && levels.Sheet > levels.Air; ++pass)
  {
    const double midpoint = 0.5 * (levels.Air + levels.Sheet);
    air.clear();
    sheet.clear();
    for (float v : values)
    {
      (v >= midpoint ? sheet : air).push_back(v);
    }
    if (air.empty() || sheet.empty())
    {
      break;
    }
    auto median = [](std::vector<float> & part) {
      const auto middle = part.begin() + static_cast<std::ptrdiff_t>(part.size() / 2);
      std::nth_element(part.begin(), middle, part.end());
      return static_cast<double>(*middle);
    };
    const double airLevel = median(air), sheetLevel = median(sheet);
    const bool   settled = std::abs(0.5 * (airLevel + sheetLevel) - midpoint) <= 1e-3 * (sheetLevel - airLevel);
    levels.Air = airLevel;
    levels.Sheet = sheetLevel;
    if (settled)
    {
      break;
    }
  }
  return levels;
}

SheetMesh
SheetMidSurfaceExtractor::Extract(const SheetVolumeView & volume)
{
  m_Report = SheetMidSurfaceReport{};
  SheetTracing::Extraction extraction(volume, m_Parameters, m_Report, m_Progress);
  return extraction.Run();
}
} // end namespace itk

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
#ifndef vuMedian_h
#define vuMedian_h

#include <algorithm>
#include <cstddef>
#include <vector>

namespace itk {
namespace RollTracing {
/** The median of the values (the upper one of an even count; 0 when there are none),
 * reordering them in place: no copy, for a buffer reused from one call to the next. */
inline double
MedianInPlace(std::vector<double> & values)
{
  if (values.empty())
  {
    return 0.0;
  }
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/** The median of the values (the upper one of an even count; 0 when there are none). */
inline double
Median(std::vector<double> values)
{
  return MedianInPlace(values);
}

/** The median of the values within `half` entries of each (fewer at the ends): a curve's
 * course without its short bumps. The window is kept sorted as it slides (one insertion and
 * one removal a step), the same figure as Median of each window. */
inline std::vector<double>
RunningMedian(const std::vector<double> & values, long half)
{
  const auto          n = static_cast<long>(values.size());
  std::vector<double> median(values.size(), 0.0);
  std::vector<double> window;
  long                first = 0, last = -1; // the window holds values[first..last]
  for (long i = 0; i < n; ++i)
  {
    for (; last < std::min(n - 1, i + half); ++last)
    {
      const double v = values[static_cast<size_t>(last + 1)];
      window.insert(std::upper_bound(window.begin(), window.end(), v), v);
    }
    for (; first < std::max(0L, i - half); ++first)
    {
      window.erase(std::lower_bound(window.begin(), window.end(), values[static_cast<size_t>(first)]));
    }
    median[static_cast<size_t>(i)] = window[window.size() / 2];
  }
  return median;
}
} // namespace RollTracing
} // end namespace itk

#endif

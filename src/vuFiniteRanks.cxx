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
#include "vuFiniteRanks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace itk {
namespace detail {
namespace {
// About this many values are sampled; a rank's window holds the sample's values within
// WindowSpread standard deviations of the rank's expected place in the sample.
constexpr size_t SampleSize = 8192;
constexpr double WindowSpread = 4.0;

bool
Finite(float v)
{
  return std::abs(v) <= std::numeric_limits<float>::max(); // false for NaN and infinities
}
} // namespace

FiniteRanks::FiniteRanks(const float * values, size_t count)
  : m_Values(values)
  , m_Size(count)
{
  m_Finite = static_cast<size_t>(std::count_if(values, values + count, Finite));
  Sample();
}

FiniteRanks::FiniteRanks(const float * values, size_t count, size_t finite, float centre)
  : m_Values(values)
  , m_Size(count)
  , m_Deviation(true)
  , m_Centre(centre)
  , m_Finite(finite)
{
  Sample();
}

FiniteRanks
FiniteRanks::Deviations(float centre) const
{
  return FiniteRanks(m_Values, m_Size, m_Finite, centre);
}

template <typename TBody>
void
FiniteRanks::Transformed(TBody && body) const
{
  if (m_Deviation)
  {
    body([c = m_Centre](float v) { return std::abs(v - c); });
  }
  else
  {
    body([](float v) { return v; });
  }
}

void
FiniteRanks::Sample()
{
  const size_t stride = std::max<size_t>(1, m_Size / SampleSize);
  Transformed([&](auto transform) {
    for (size_t i = 0; i < m_Size; i += stride)
    {
      if (Finite(m_Values[i]))
      {
        m_Sample.push_back(transform(m_Values[i]));
      }
    }
  });
  std::sort(m_Sample.begin(), m_Sample.end());
}

std::vector<float>
FiniteRanks::Quantiles(const std::vector<double> & q) const
{
  constexpr float Infinity = std::numeric_limits<float>::infinity();
  if (m_Finite == 0)
  {
    throw std::out_of_range("FiniteRanks: no finite value");
  }
  const auto         s = static_cast<double>(m_Sample.size());
  std::vector<float> result;
  for (const double p : q)
  {
    const size_t rank = std::min(m_Finite - 1, static_cast<size_t>(p * static_cast<double>(m_Finite - 1) + 0.5));
    // The rank's window of values from the sample (the whole line where the sample is too
    // small to say).
    float lo = -Infinity, hi = Infinity;
    if (m_Sample.size() >= 64)
    {
      const double place = p * (s - 1.0), reach = WindowSpread * std::sqrt(s * p * (1.0 - p) + 1.0) + 1.0;
      if (place - reach >= 0.0)
      {
        lo = m_Sample[static_cast<size_t>(place - reach)];
      }
      if (place + reach <= s - 1.0)
      {
        hi = m_Sample[static_cast<size_t>(place + reach)];
      }
    }
    // One pass that counts the values below the window and keeps those in it, without a
    // data-dependent branch (half the values lie below a median, and a mispredicted branch
    // costs more than the rest of the loop): each value is written to a block and kept by
    // advancing the block's end when it lies in the window.
    size_t             below = 0;
    std::vector<float> kept;
    Transformed([&](auto transform) {
      constexpr size_t Block = 1024;
      float            block[Block];
      size_t           k = 0;
      for (size_t i = 0; i < m_Size; ++i)
      {
        const float    v = transform(m_Values[i]);
        const unsigned finite = Finite(v) ? 1u : 0u;
        const unsigned under = v < lo ? 1u : 0u, over = v > hi ? 1u : 0u;
        below += finite & under;
        block[k] = v;
        k += finite & (1u - (under | over));
        if (k == Block)
        {
          kept.insert(kept.end(), block, block + Block);
          k = 0;
        }
      }
      kept.insert(kept.end(), block, block + k);
    });
    if (rank < below || rank >= below + kept.size())
    {
      // The sample misled (values crowded or ordered against the sampling stride): all of them.
      kept.clear();
      below = 0;
      Transformed([&](auto transform) {
        for (size_t i = 0; i < m_Size; ++i)
        {
          if (Finite(m_Values[i]))
          {
            kept.push_back(transform(m_Values[i]));
          }
        }
      });
    }
    const auto at = kept.begin() + static_cast<std::ptrdiff_t>(rank - below);
    std::nth_element(kept.begin(), at, kept.end());
    result.push_back(*at);
  }
  return result;
}
} // namespace detail
} // end namespace itk

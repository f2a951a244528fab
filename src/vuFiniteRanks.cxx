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
} // namespace

FiniteRanks::FiniteRanks(const float * values, size_t count)
  : m_Values(values)
  , m_Size(count)
{
  Count();
}

FiniteRanks::FiniteRanks(const float * values, size_t count, float centre)
  : m_Values(values)
  , m_Size(count)
  , m_Deviation(true)
  , m_Centre(centre)
{
  Count();
}

template <typename TVisit>
void
FiniteRanks::ForEachFinite(TVisit && visit) const
{
  if (m_Deviation)
  {
    for (size_t i = 0; i < m_Size; ++i)
    {
      if (std::isfinite(m_Values[i]))
      {
        visit(i, std::abs(m_Values[i] - m_Centre));
      }
    }
  }
  else
  {
    for (size_t i = 0; i < m_Size; ++i)
    {
      if (std::isfinite(m_Values[i]))
      {
        visit(i, m_Values[i]);
      }
    }
  }
}

void
FiniteRanks::Count()
{
  ForEachFinite([this](size_t, float) { ++m_Finite; });
  const size_t stride = std::max<size_t>(1, m_Size / SampleSize);
  for (size_t i = 0; i < m_Size; i += stride)
  {
    if (std::isfinite(m_Values[i]))
    {
      m_Sample.push_back(m_Deviation ? std::abs(m_Values[i] - m_Centre) : m_Values[i]);
    }
  }
  std::sort(m_Sample.begin(), m_Sample.end());
}

std::vector<float>
FiniteRanks::Values(const std::vector<size_t> & ranks) const
{
  constexpr float Infinity = std::numeric_limits<float>::infinity();
  // Each rank's window of values from the sample (the whole line where the sample is too
  // small to say), then one pass that counts the values below each window and keeps those in it.
  const size_t        windows = ranks.size();
  std::vector<float>  low(windows, -Infinity), high(windows, Infinity);
  std::vector<size_t> below(windows, 0);
  const auto          s = static_cast<double>(m_Sample.size());
  for (size_t r = 0; r < windows; ++r)
  {
    if (ranks[r] >= m_Finite)
    {
      throw std::out_of_range("FiniteRanks: rank beyond the finite values");
    }
    if (m_Sample.size() >= 64)
    {
      const double q = static_cast<double>(ranks[r]) / std::max<double>(1.0, static_cast<double>(m_Finite - 1));
      const double place = q * (s - 1.0), reach = WindowSpread * std::sqrt(s * q * (1.0 - q) + 1.0) + 1.0;
      if (place - reach >= 0.0)
      {
        low[r] = m_Sample[static_cast<size_t>(place - reach)];
      }
      if (place + reach <= s - 1.0)
      {
        high[r] = m_Sample[static_cast<size_t>(place + reach)];
      }
    }
  }
  // One pass per window, without a data-dependent branch (half the values lie below a
  // median, and a mispredicted branch costs more than the rest of the loop): each value is
  // written to a block and kept by advancing the block's end when it lies in the window.
  std::vector<std::vector<float>> inside(windows);
  for (size_t r = 0; r < windows; ++r)
  {
    const float          lo = low[r], hi = high[r];
    size_t               count = 0, k = 0;
    std::vector<float> & kept = inside[r];
    constexpr size_t     Block = 1024;
    float                block[Block];
    const auto           pass = [&](auto transform) {
      for (size_t i = 0; i < m_Size; ++i)
      {
        const float    v = transform(m_Values[i]);
        const unsigned finite = std::abs(v) <= std::numeric_limits<float>::max() ? 1u : 0u;
        const unsigned under = v < lo ? 1u : 0u, over = v > hi ? 1u : 0u; // NaN: neither
        count += finite & under;
        block[k] = v;
        k += finite & (1u - (under | over));
        if (k == Block)
        {
          kept.insert(kept.end(), block, block + Block);
          k = 0;
        }
      }
    };
    if (m_Deviation)
    {
      pass([c = m_Centre](float v) { return std::abs(v - c); });
    }
    else
    {
      pass([](float v) { return v; });
    }
    kept.insert(kept.end(), block, block + k);
    below[r] = count;
  }
  std::vector<float> result(windows);
  for (size_t r = 0; r < windows; ++r)
  {
    std::vector<float> & values = inside[r];
    if (ranks[r] < below[r] || ranks[r] >= below[r] + values.size())
    {
      // The sample misled (values crowded or ordered against the sampling stride): the
      // whole line.
      values.clear();
      below[r] = 0;
      ForEachFinite([&](size_t, float v) { values.push_back(v); });
    }
    const auto at = values.begin() + static_cast<std::ptrdiff_t>(ranks[r] - below[r]);
    std::nth_element(values.begin(), at, values.end());
    result[r] = *at;
  }
  return result;
}

float
FiniteRanks::Quantile(double q) const
{
  const size_t k = std::min(m_Finite - 1, static_cast<size_t>(q * static_cast<double>(m_Finite - 1) + 0.5));
  return Value(k);
}
} // namespace detail
} // end namespace itk

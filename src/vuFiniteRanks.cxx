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
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace itk {
namespace detail {
namespace {
// About this many values are sampled; a rank's window holds the sample's values within
// WindowSpread standard deviations of the rank's expected place in the sample.
constexpr size_t SampleSize = 8192;
constexpr double WindowSpread = 4.0;
// Counts kept in 32-bit lanes of four are added up every this many values.
constexpr size_t LaneCountLimit = size_t{ 1 } << 30;

bool
Finite(float v)
{
  return std::abs(v) <= std::numeric_limits<float>::max(); // false for NaN and infinities
}

// Four floats and four 32-bit masks (the compiler's vector extension).
using Vector = float __attribute__((vector_size(16)));
using Mask = int32_t __attribute__((vector_size(16)));

float
Magnitude(float v)
{
  return std::abs(v);
}

Vector
Magnitude(Vector v)
{
  return reinterpret_cast<Vector>(reinterpret_cast<Mask>(v) & 0x7fffffff);
}
} // namespace

FiniteRanks::FiniteRanks(const float * values, size_t count)
  : m_Values(values)
  , m_Size(count)
{
  // Four at a time: |v| <= largest is false for NaN and infinities.
  const float  largest = std::numeric_limits<float>::max();
  const Vector top = { largest, largest, largest, largest };
  size_t       i = 0;
  while (i + 4 <= count)
  {
    // Lane counts added up every LaneCountLimit values, before a 32-bit lane can overflow.
    const size_t end = std::min(count, i + LaneCountLimit) / 4 * 4;
    Mask         finite = { 0, 0, 0, 0 };
    for (; i < end; i += 4)
    {
      Vector v;
      std::memcpy(&v, values + i, sizeof(v));
      finite -= Magnitude(v) <= top;
    }
    for (size_t l = 0; l < 4; ++l)
    {
      m_Finite += static_cast<size_t>(finite[l]);
    }
  }
  m_Finite += static_cast<size_t>(std::count_if(values + i, values + count, Finite));
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
    body([c = m_Centre](auto v) { return Magnitude(v - c); });
  }
  else
  {
    body([](auto v) { return v; });
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
  // Each rank's window of values from the sample (the whole line where the sample is too
  // small to say).
  const auto          s = static_cast<double>(m_Sample.size());
  std::vector<Window> windows(q.size(), Window{ -Infinity, Infinity, 0, {} });
  for (size_t j = 0; j < q.size(); ++j)
  {
    const double p = q[j];
    if (m_Sample.size() >= 64)
    {
      const double place = p * (s - 1.0), reach = WindowSpread * std::sqrt(s * p * (1.0 - p) + 1.0) + 1.0;
      if (place - reach >= 0.0)
      {
        windows[j].Low = m_Sample[static_cast<size_t>(place - reach)];
      }
      if (place + reach <= s - 1.0)
      {
        windows[j].High = m_Sample[static_cast<size_t>(place + reach)];
      }
    }
  }
  // One pass for every two ranks: counts the values below each window and keeps those in it.
  Transformed([&](auto transform) {
    for (size_t j = 0; j < windows.size(); j += 2)
    {
      if (j + 1 < windows.size())
      {
        CountAndKeep<2>(transform, &windows[j]);
      }
      else
      {
        CountAndKeep<1>(transform, &windows[j]);
      }
    }
  });
  std::vector<float> result;
  for (size_t j = 0; j < q.size(); ++j)
  {
    const size_t rank = std::min(m_Finite - 1, static_cast<size_t>(q[j] * static_cast<double>(m_Finite - 1) + 0.5));
    size_t       below = windows[j].Below;
    std::vector<float> & kept = windows[j].Kept;
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

template <size_t TWindows, typename TTransform>
void
FiniteRanks::CountAndKeep(TTransform transform, Window * windows) const
{
  // Four values at a time (SSE2 or the target's equivalent, through the compiler's vector
  // extension), without a data-dependent branch (the values in a window are scattered, and
  // a mispredicted branch costs more than the rest of the loop): the values below a window
  // counted lane by lane; each value is written to the window's block, whose end advances
  // when it lies in the window.
  constexpr size_t Lanes = 4;
  constexpr size_t Block = 1024;
  const float      largest = std::numeric_limits<float>::max();
  const Vector     top = { largest, largest, largest, largest };
  Vector           low[TWindows], high[TWindows];
  Mask             below[TWindows];
  float            block[TWindows][Block + Lanes];
  size_t           k[TWindows];
  for (size_t j = 0; j < TWindows; ++j)
  {
    const float lo = windows[j].Low, hi = windows[j].High;
    low[j] = Vector{ lo, lo, lo, lo };
    high[j] = Vector{ hi, hi, hi, hi };
    below[j] = Mask{ 0, 0, 0, 0 };
    k[j] = 0;
  }
  size_t i = 0;
  while (i + Lanes <= m_Size)
  {
    // Lane counts added up every LaneCountLimit values, before a 32-bit lane can overflow.
    const size_t end = std::min(m_Size, i + LaneCountLimit) / Lanes * Lanes;
    for (; i < end; i += Lanes)
    {
      Vector raw;
      std::memcpy(&raw, m_Values + i, sizeof(raw));
      const Vector v = transform(raw);
      const Mask   finite = Magnitude(v) <= top; // false for NaN and infinities
      for (size_t j = 0; j < TWindows; ++j)
      {
        const Mask under = v < low[j];
        below[j] -= finite & under;
        const Mask inside = finite & ~under & (v <= high[j]);
        for (size_t l = 0; l < Lanes; ++l)
        {
          block[j][k[j]] = v[l];
          k[j] += static_cast<size_t>(inside[l] & 1);
        }
        if (k[j] >= Block)
        {
          windows[j].Kept.insert(windows[j].Kept.end(), block[j], block[j] + k[j]);
          k[j] = 0;
        }
      }
    }
    for (size_t j = 0; j < TWindows; ++j)
    {
      for (size_t l = 0; l < Lanes; ++l)
      {
        windows[j].Below += static_cast<size_t>(below[j][l]);
      }
      below[j] = Mask{ 0, 0, 0, 0 };
    }
  }
  for (size_t j = 0; j < TWindows; ++j)
  {
    windows[j].Kept.insert(windows[j].Kept.end(), block[j], block[j] + k[j]);
  }
  for (; i < m_Size; ++i)
  {
    const float v = transform(m_Values[i]);
    for (size_t j = 0; j < TWindows; ++j)
    {
      if (Finite(v) && v < windows[j].Low)
      {
        ++windows[j].Below;
      }
      else if (Finite(v) && v <= windows[j].High)
      {
        windows[j].Kept.push_back(v);
      }
    }
  }
}
} // namespace detail
} // end namespace itk

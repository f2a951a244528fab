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
#ifndef vuFiniteRanks_h
#define vuFiniteRanks_h

#include <cstddef>
#include <vector>

namespace itk {
namespace detail {
/** Exact order statistics of the finite values of a float array (NaN and infinities are
 * left out), or of their absolute deviations |v - centre|, by sampled selection (Floyd and
 * Rivest, "Expected time bounds for selection", CACM 18(3), 1975): a regular sample of
 * about 8192 values, sorted, brackets each rank asked for between two of its values; one
 * pass over the data for every two ranks asked counts the values below each bracket and
 * keeps those inside it, and each rank is selected among those few. Where the bracket misses (the sample
 * misled), the rank is selected among all values. Exactly the values std::nth_element over
 * a copy gives, whatever the data's order, without copying it. The data must outlive the
 * object. */
class FiniteRanks
{
public:
  FiniteRanks(const float * values, size_t count);

  /** The ranks of the same values' absolute deviations from `centre` (their count known). */
  FiniteRanks
  Deviations(float centre) const;

  /** The number of finite values. */
  size_t
  GetCount() const
  {
    return m_Finite;
  }

  /** The values of ranks round(q (count - 1)) for each q in 0..1 (count above 0). */
  std::vector<float>
  Quantiles(const std::vector<double> & q) const;

  float
  Quantile(double q) const
  {
    return Quantiles({ q })[0];
  }

private:
  /** A rank's window of values (from the sample), the count of finite values below it and
   * the values in it. */
  struct Window
  {
    float              Low;
    float              High;
    size_t             Below;
    std::vector<float> Kept;
  };

  FiniteRanks(const float * values, size_t count, size_t finite, float centre);
  void
  Sample();
  /** Calls body(transform) with the map from a stored value to the value ranked. */
  template <typename TBody>
  void
  Transformed(TBody && body) const;
  /** One pass over the values, mapped by `transform`, for TWindows windows. */
  template <size_t TWindows, typename TTransform>
  void
  CountAndKeep(TTransform transform, Window * windows) const;

  const float *      m_Values;
  size_t             m_Size;
  bool               m_Deviation{ false };
  float              m_Centre{ 0.0f };
  size_t             m_Finite{ 0 };
  std::vector<float> m_Sample;
};
} // namespace detail
} // end namespace itk

#endif

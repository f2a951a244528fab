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
#include "vuBandedSprings.h"
#include "vuVectorClones.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

namespace vu {
namespace {
// Adds sign * source[0..count) to the ring slots of particles first, first + 1, ...,
// in contiguous runs (the ring wraps at most once per call).
VU_VECTOR_CLONES void
AddToRing(float * __restrict ring, size_t mask, size_t first, const float * __restrict source, size_t count, float sign)
{
  size_t slot = first & mask;
  while (count > 0)
  {
    const size_t run = std::min(count, mask + 1 - slot);
    float * __restrict to = ring + slot;
    const float * __restrict from = source;
    for (size_t k = 0; k < run; ++k)
    {
      to[k] += sign * from[k];
    }
    source += run;
    count -= run;
    slot = 0;
  }
}

// Moves the ring slots of particles first .. first + count - 1 to destination and clears
// them.
void
TakeFromRing(float * ring, size_t mask, size_t first, float * destination, size_t count)
{
  size_t slot = first & mask;
  while (count > 0)
  {
    const size_t run = std::min(count, mask + 1 - slot);
    std::copy(ring + slot, ring + slot + run, destination);
    std::fill(ring + slot, ring + slot + run, 0.0F);
    destination += run;
    count -= run;
    slot = 0;
  }
}

// The Euler update of count particles from their forces, every particle the same
// arithmetic so that it vectorises: a = F / m + g - c v; symplectic: v' = v + h a,
// x' = x + h v'; explicit: x' = x + h v, v' = v + h a. Locked particles keep x, at rest.
template <bool Symplectic>
VU_VECTOR_CLONES void
IntegrateBlock(const float * __restrict x0,
               const float * __restrict x1,
               const float * __restrict x2,
               float * __restrict xn0,
               float * __restrict xn1,
               float * __restrict xn2,
               float * __restrict v0,
               float * __restrict v1,
               float * __restrict v2,
               const float * __restrict f0,
               const float * __restrict f1,
               const float * __restrict f2,
               const float * __restrict inverseMass,
               const uint8_t * __restrict locked,
               size_t count,
               float  h,
               float  c,
               float  g0,
               float  g1,
               float  g2)
{
  for (size_t k = 0; k < count; ++k)
  {
    // A locked particle moves with a time step of 0 and keeps a velocity of 0 (factors,
    // not a branch, so that the loop vectorises; exact for every other particle).
    const float keep = 1.0F - static_cast<float>(locked[k]); // locked is 0 or 1
    const float hk = keep * h;
    const float w = inverseMass[k];
    const float a0 = f0[k] * w + g0 - c * v0[k];
    const float a1 = f1[k] * w + g1 - c * v1[k];
    const float a2 = f2[k] * w + g2 - c * v2[k];
    const float u0 = v0[k] + h * a0, u1 = v1[k] + h * a1, u2 = v2[k] + h * a2;
    xn0[k] = x0[k] + hk * (Symplectic ? u0 : v0[k]);
    xn1[k] = x1[k] + hk * (Symplectic ? u1 : v1[k]);
    xn2[k] = x2[k] + hk * (Symplectic ? u2 : v2[k]);
    v0[k] = keep * u0;
    v1[k] = keep * u1;
    v2[k] = keep * u2;
  }
}

// Hooke forces of count springs, lower ends at a, upper ends at b (coordinates as three
// arrays each): the force on the lower end, k (|d| - L) / |d| d with d = b - a, into f.
VU_VECTOR_CLONES void
BandForces(const float * __restrict a0,
           const float * __restrict a1,
           const float * __restrict a2,
           const float * __restrict b0,
           const float * __restrict b1,
           const float * __restrict b2,
           const float * __restrict restLength,
           const float * __restrict stiffness,
           size_t count,
           float * __restrict f0,
           float * __restrict f1,
           float * __restrict f2)
{
  for (size_t k = 0; k < count; ++k)
  {
    const float d0 = b0[k] - a0[k], d1 = b1[k] - a1[k], d2 = b2[k] - a2[k];
    // No branch, so that the loop vectorises: for coincident ends the tiny length keeps the
    // scale finite and d = 0 makes the force 0; for any other it is below float's
    // resolution of the length.
    const float len = std::sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-20F;
    const float scale = stiffness[k] * (1.0F - restLength[k] / len);
    f0[k] = scale * d0;
    f1[k] = scale * d1;
    f2[k] = scale * d2;
  }
}
} // namespace

void
BandedSprings::Build(size_t                        particles,
                     const std::vector<uint32_t> & springI,
                     const std::vector<uint32_t> & springJ,
                     const std::vector<double> &   restLength,
                     const std::vector<double> &   stiffness)
{
  m_Particles = particles;
  m_Bands.clear();
  m_Extra.clear();
  m_MaxOffset = 0;
  // Bands: the distances that at least an eighth of the particles have a spring across.
  std::unordered_map<uint32_t, size_t> count;
  for (size_t s = 0; s < springI.size(); ++s)
  {
    const uint32_t offset = springI[s] > springJ[s] ? springI[s] - springJ[s] : springJ[s] - springI[s];
    if (offset > 0 && offset <= MaximumBandOffset)
    {
      ++count[offset];
    }
  }
  std::vector<uint32_t> offsets;
  for (const auto & [offset, springs] : count)
  {
    if (springs >= std::max<size_t>(1, particles / 8))
    {
      offsets.push_back(offset);
    }
  }
  std::sort(offsets.begin(), offsets.end(), [&](uint32_t a, uint32_t b) { return count[a] > count[b]; });
  offsets.resize(std::min<size_t>(offsets.size(), 8));
  std::sort(offsets.begin(), offsets.end());
  std::unordered_map<uint32_t, size_t> bandOf;
  for (uint32_t offset : offsets)
  {
    bandOf[offset] = m_Bands.size();
    Band band;
    band.offset = offset;
    band.restLength.assign(particles, 0.0F);
    band.stiffness.assign(particles, 0.0F);
    m_Bands.push_back(std::move(band));
    m_MaxOffset = std::max(m_MaxOffset, offset);
  }
  // Every spring into its band, or (no band, or a second spring between the same two
  // particles) into the gathered list, stored from both ends.
  std::vector<size_t> extra;
  for (size_t s = 0; s < springI.size(); ++s)
  {
    const uint32_t lower = std::min(springI[s], springJ[s]);
    const uint32_t offset = std::max(springI[s], springJ[s]) - lower;
    const auto     found = bandOf.find(offset);
    if (found != bandOf.end() && m_Bands[found->second].stiffness[lower] == 0.0F)
    {
      m_Bands[found->second].restLength[lower] = static_cast<float>(restLength[s]);
      m_Bands[found->second].stiffness[lower] = static_cast<float>(stiffness[s]);
    }
    else
    {
      extra.push_back(s);
    }
  }
  m_ExtraStart.assign(particles + 1, 0);
  for (size_t s : extra)
  {
    ++m_ExtraStart[springI[s] + 1];
    ++m_ExtraStart[springJ[s] + 1];
  }
  std::partial_sum(m_ExtraStart.begin(), m_ExtraStart.end(), m_ExtraStart.begin());
  m_Extra.resize(2 * extra.size());
  std::vector<uint64_t> fill(m_ExtraStart.begin(), m_ExtraStart.end() - 1);
  for (size_t s : extra)
  {
    const auto L = static_cast<float>(restLength[s]);
    const auto k = static_cast<float>(stiffness[s]);
    m_Extra[fill[springI[s]]++] = { springJ[s], L, k };
    m_Extra[fill[springJ[s]]++] = { springI[s], L, k };
  }
}

void
BandedSprings::StepRange(const float * const x[3],
                         float * const       xNext[3],
                         float * const       v[3],
                         const float *       inverseMass,
                         const uint8_t *     locked,
                         const Settings &    settings,
                         size_t              begin,
                         size_t              end) const
{
  // Pending forces of particles [s, s + BlockSize + m_MaxOffset) while block s is worked.
  size_t ringSize = 1;
  while (ringSize < 2 * BlockSize + m_MaxOffset)
  {
    ringSize *= 2;
  }
  const size_t                    mask = ringSize - 1;
  thread_local std::vector<float> scratch;
  scratch.assign(3 * ringSize + 3 * BlockSize, 0.0F);
  float * ring[3] = { scratch.data(), scratch.data() + ringSize, scratch.data() + 2 * ringSize };
  float * f[3] = { ring[2] + ringSize, ring[2] + ringSize + BlockSize, ring[2] + ringSize + 2 * BlockSize };

  const float h = settings.timeStep;
  const float c = settings.damping;
  // Blocks start a whole number of blocks before the range, far enough back to reach every
  // spring whose upper end lies in it (blocks before particle 0 are cut off).
  const auto blocksBack = static_cast<int64_t>((m_MaxOffset + BlockSize - 1) / BlockSize);
  for (int64_t start = static_cast<int64_t>(begin) - blocksBack * static_cast<int64_t>(BlockSize);
       start < static_cast<int64_t>(end);
       start += static_cast<int64_t>(BlockSize))
  {
    const int64_t stop = start + static_cast<int64_t>(BlockSize);
    if (stop <= 0)
    {
      continue;
    }
    const bool   inRange = start >= static_cast<int64_t>(begin);
    const size_t s = start > 0 ? static_cast<size_t>(start) : 0;
    const size_t blockEnd = std::min(static_cast<size_t>(stop), end);
    for (const Band & band : m_Bands)
    {
      const size_t o = band.offset;
      if (s + o >= m_Particles)
      {
        continue;
      }
      const size_t iEnd = std::min(blockEnd, m_Particles - o);
      BandForces(x[0] + s,
                 x[1] + s,
                 x[2] + s,
                 x[0] + s + o,
                 x[1] + s + o,
                 x[2] + s + o,
                 band.restLength.data() + s,
                 band.stiffness.data() + s,
                 iEnd - s,
                 f[0],
                 f[1],
                 f[2]);
      // Lower ends in the range: the whole block once it has reached the range.
      if (inRange)
      {
        for (int d = 0; d < 3; ++d)
        {
          AddToRing(ring[d], mask, s, f[d], iEnd - s, 1.0F);
        }
      }
      // Upper ends in the range.
      const size_t first = std::max(s, begin > o ? begin - o : size_t{ 0 });
      const size_t last = std::min(iEnd, end > o ? end - o : size_t{ 0 });
      if (first < last)
      {
        for (int d = 0; d < 3; ++d)
        {
          AddToRing(ring[d], mask, first + o, f[d] + (first - s), last - first, -1.0F);
        }
      }
    }
    if (!inRange)
    {
      continue;
    }
    // Every spring of the block's particles is in: integrate them.
    const size_t count = blockEnd - s;
    for (int d = 0; d < 3; ++d)
    {
      TakeFromRing(ring[d], mask, s, f[d], count);
    }
    for (size_t p = s; p < blockEnd; ++p)
    {
      for (uint64_t e = m_ExtraStart[p]; e < m_ExtraStart[p + 1]; ++e)
      {
        const Extra & nb = m_Extra[e];
        const float   d[3] = { x[0][nb.other] - x[0][p], x[1][nb.other] - x[1][p], x[2][nb.other] - x[2][p] };
        const float   len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const float   scale = len > 0.0F ? nb.stiffness * (1.0F - nb.restLength / len) : 0.0F;
        for (int k = 0; k < 3; ++k)
        {
          f[k][p - s] += scale * d[k];
        }
      }
    }
    (settings.symplectic ? IntegrateBlock<true> : IntegrateBlock<false>)(x[0] + s,
                                                                         x[1] + s,
                                                                         x[2] + s,
                                                                         xNext[0] + s,
                                                                         xNext[1] + s,
                                                                         xNext[2] + s,
                                                                         v[0] + s,
                                                                         v[1] + s,
                                                                         v[2] + s,
                                                                         f[0],
                                                                         f[1],
                                                                         f[2],
                                                                         inverseMass + s,
                                                                         locked + s,
                                                                         count,
                                                                         h,
                                                                         c,
                                                                         settings.gravity[0],
                                                                         settings.gravity[1],
                                                                         settings.gravity[2]);
    if (!settings.hasPlane)
    {
      continue;
    }
    // The collision plane as in the double-precision step: pushed back onto it, and
    // V - (1 + k_r)(V . N) N, or at rest below the resting speed.
    const float * N = settings.planeNormal;
    for (size_t p = s; p < blockEnd; ++p)
    {
      if (locked[p])
      {
        continue;
      }
      const float depth = (xNext[0][p] - settings.planePoint[0]) * N[0] +
                          (xNext[1][p] - settings.planePoint[1]) * N[1] + (xNext[2][p] - settings.planePoint[2]) * N[2];
      if (depth < 0.0F)
      {
        const float vNormal = v[0][p] * N[0] + v[1][p] * N[1] + v[2][p] * N[2];
        const float rebound = -settings.restitution * vNormal <= settings.restingSpeed ? 0.0F : settings.restitution;
        for (int d = 0; d < 3; ++d)
        {
          xNext[d][p] -= depth * N[d];
          if (vNormal < 0.0F)
          {
            v[d][p] -= (1.0F + rebound) * vNormal * N[d];
          }
        }
      }
    }
  }
}
} // namespace vu

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
#ifndef vuBandedSprings_h
#define vuBandedSprings_h

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vu {
/** The springs of a mass-spring system for a single-precision explicit Euler step that
 * computes each spring once.
 *
 * A sheet mesh numbers its particles along a grid, so most springs join particles a fixed
 * distance apart in that numbering (1 along a row, a row's length and that +-1 across
 * rows). Springs are grouped by that distance into bands, each stored as contiguous
 * arrays indexed by the spring's lower particle (rest length, stiffness; stiffness 0 where
 * a particle has no spring of that band), so the force loop reads positions, rest lengths
 * and stiffnesses as streams and vectorises. Each thread steps a contiguous range of
 * particles: it walks the range in blocks, computes every band's springs whose lower end
 * lies in the block once, adds the force to both ends in a small ring buffer of pending
 * forces (the upper end lies at most the largest band distance ahead), and integrates a
 * block as soon as all its springs are in: no thread writes another's particles, no force
 * array goes through memory. Springs whose lower end belongs to the previous thread's range
 * are computed by both threads (a band's distance per range and band). Springs that fit no
 * band (a few, on an irregular mesh) are gathered from both ends at integration.
 *
 * State is float, structure of arrays: a third of the memory traffic of the
 * double-precision loop, which is what bounds it. Positions in float carry an absolute
 * error of about 6e-8 of the sheet's extent, which is a relative error of the spring
 * lengths of 6e-8 times the extent over the spring length (docs/flattening.md). */
class BandedSprings
{
public:
  /** Particles are stepped in blocks of this many, aligned to multiples of it; ranges
   * that start on such a multiple sum every force in the same order, so any split of the
   * particles among threads gives the same state, bit for bit. */
  static constexpr size_t BlockSize = 256;
  /** Largest distance in the numbering stored as a band; longer springs are gathered. */
  static constexpr uint32_t MaximumBandOffset = 1u << 16;

  void
  Build(size_t                        particles,
        const std::vector<uint32_t> & springI,
        const std::vector<uint32_t> & springJ,
        const std::vector<double> &   restLength,
        const std::vector<double> &   stiffness);

  struct Settings
  {
    float timeStep{ 0.0F };
    float damping{ 0.0F };
    float gravity[3]{ 0.0F, 0.0F, 0.0F };
    bool  symplectic{ true };
    bool  hasPlane{ false };
    float planePoint[3]{ 0.0F, 0.0F, 0.0F };
    float planeNormal[3]{ 0.0F, 0.0F, 1.0F };
    float restitution{ 0.0F };
    float restingSpeed{ 0.0F };
  };

  /** One explicit (symplectic) Euler step of particles [begin, end): reads the positions
   * x of all particles, writes the new positions of the range to xNext and updates the
   * range's velocities v in place. Locked particles (locked 1, others 0) keep their
   * position, at rest. begin is a multiple of BlockSize. */
  void
  StepRange(const float * const x[3],
            float * const       xNext[3],
            float * const       v[3],
            const float *       inverseMass,
            const uint8_t *     locked,
            const Settings &    settings,
            size_t              begin,
            size_t              end) const;

  /** Ranges shorter than this are not worth a thread of their own. */
  size_t
  GetMinimumRange() const
  {
    return 4 * (static_cast<size_t>(m_MaxOffset) + BlockSize);
  }

private:
  struct Band
  {
    uint32_t           offset{ 0 };
    std::vector<float> restLength;
    std::vector<float> stiffness;
  };
  struct Extra
  {
    uint32_t other;
    float    restLength;
    float    stiffness;
  };
  size_t                m_Particles{ 0 };
  uint32_t              m_MaxOffset{ 0 };
  std::vector<Band>     m_Bands;
  std::vector<uint64_t> m_ExtraStart;
  std::vector<Extra>    m_Extra;
};
} // namespace vu

#endif

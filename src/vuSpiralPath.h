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
#ifndef vuSpiralPath_h
#define vuSpiralPath_h

#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace itk {
namespace RollTracing {
/** One slice of a scan resampled on a polar grid about the roll's axis: ray a at angle
 * a * 2 pi / Rays, sample j at radius j * Dr. An angular index m = a + turn * Rays runs
 * along a spiral; At() wraps it. */
struct PolarSlice
{
  long   Rays{ 0 };
  long   Samples{ 0 };
  double Dr{ 1.0 };
  /** Intensity as a fraction of the sheet's contrast above air (0 air, 1 sheet), ray by ray. */
  std::vector<float> Values;
  /** Zero where the scan holds no data (beyond a field of view that cuts the roll); empty
   * when it holds data everywhere. */
  std::vector<char> Known;

  /** The intensity at angular index m, sample j; NaN where the scan holds no data. */
  double
  At(long m, long j) const
  {
    const auto i = static_cast<size_t>((((m % Rays) + Rays) % Rays) * Samples + j);
    return Known.empty() || Known[i] != 0 ? static_cast<double>(Values[i]) : std::numeric_limits<double>::quiet_NaN();
  }
};

/** A curve about the axis, dense in the angular index: Rho[i] is its radius at
 * m = First + i; Confirmed[i] is set where the sheet was seen there. */
struct SpiralTrace
{
  long                First{ 0 };
  std::vector<double> Rho;
  std::vector<char>   Confirmed;

  bool
  Empty() const
  {
    return Rho.empty();
  }
  long
  Last() const
  {
    return First + static_cast<long>(Rho.size()) - 1;
  }
  bool
  Covers(long m) const
  {
    return !Rho.empty() && m >= First && m <= Last();
  }
  double
  At(long m) const
  {
    return Rho[static_cast<size_t>(m - First)];
  }
};

/** What the turn-by-turn path search needs to know about the sheet (mm). */
struct SpiralPathSettings
{
  /** Typical sheet thickness across a ray and radial distance between turns. */
  double Width{ 1.0 };
  double Pitch{ 1.0 };
  double Voxel{ 1.0 };
};

/** Traces a rolled sheet in one slice turn by turn, each turn as the minimal path through
 * the slice's polar image (dark costs, bright is free) that keeps at least most of a sheet's
 * thickness outside the turn before it and follows that turn's shape (a path that leaves it
 * pays for every sample it moves sideways); the turn before is a hard bound, so where two
 * turns touch the path cannot step onto the next one, and a whole turn is decided at once,
 * so a short touch or faint stretch cannot carry it off.
 * The turn of `reference` centred on m = `centre` (a neighbouring slice's trace, or a first
 * trace of this one) is traced again within a fraction of a turn spacing of it and starts
 * the search; the turns inwards of it are traced with the turn outside as bound, then every
 * turn outwards again from the innermost. Each end stops where the path runs through more than a few voxels of air.
 * Empty when `reference` does not cover a whole turn or that turn is not found on the slice. */
SpiralTrace
TraceSpiralPath(const PolarSlice &         slice,
                const SpiralTrace &        reference,
                long                       centre,
                const SpiralPathSettings & settings);
} // namespace RollTracing
} // end namespace itk

#endif

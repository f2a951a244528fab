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
#ifndef vuCgalParameterize_h
#define vuCgalParameterize_h

// CGAL's surface parameterisations behind a plain interface: CGAL brings the system Eigen,
// which must not meet ITK's internal Eigen in one translation unit.
#include <cstdint>
#include <string>
#include <vector>

namespace vu {
/** Parameterises a triangle mesh (x, y, z per point; three indices per triangle) with
 * CGAL 5.5: method "lscm" (least squares conformal maps, two pinned vertices) or "arap"
 * (as-rigid-as-possible, Liu et al. 2008, CGAL defaults). uv receives x, y, 0 per point.
 * Returns CGAL's error text, empty on success. */
std::string
CgalParameterize(const std::vector<double> &   points,
                 const std::vector<uint32_t> & triangles,
                 const std::string &           method,
                 std::vector<double> &         uv);
} // namespace vu

#endif

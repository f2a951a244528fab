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
#ifndef vuSinglePrecisionState_h
#define vuSinglePrecisionState_h

#include "itkMassSpringSystem.h"
#include "vuBandedSprings.h"

#include <vector>

namespace itk {
/** The float state and banded springs of MassSpringSystem's single-precision Euler step. */
struct MassSpringSystem::SinglePrecisionState
{
  vu::BandedSprings  springs;
  bool               springsValid{ false }; // built from the current springs
  std::vector<float> x[3], xNext[3], v[3];
  std::vector<float> inverseMass;
  bool               loaded{ false }; // x and v hold the system's state
  bool               ahead{ false };  // ... and the double-precision state is older
};
} // end namespace itk

#endif

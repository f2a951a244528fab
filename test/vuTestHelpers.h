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
#ifndef vuTestHelpers_h
#define vuTestHelpers_h

#include "itkTestingMacros.h"

#include "gtest/gtest.h"

#include <cstdlib>
#include <iostream>
#include <random>
#include <string>

/** ITK's testing macros (ITK_EXERCISE_BASIC_OBJECT_METHODS, ITK_TEST_SET_GET_VALUE,
 * ITK_TRY_EXPECT_EXCEPTION, ...) report failure by returning EXIT_FAILURE from the
 * enclosing function; a GoogleTest body returns void, so run them in a lambda. */
#define VU_EXPECT_ITK_MACROS(...)                                                                                      \
  EXPECT_EQ(                                                                                                           \
    [&]() -> int {                                                                                                     \
      __VA_ARGS__;                                                                                                     \
      return EXIT_SUCCESS;                                                                                             \
    }(),                                                                                                               \
    EXIT_SUCCESS)

namespace vu {
/** An ITK spacing, point or vector of three coordinates (TTriple: its type). */
template <typename TTriple>
TTriple
Triple(double x, double y, double z)
{
  TTriple t;
  t[0] = x;
  t[1] = y;
  t[2] = z;
  return t;
}

/** A seed for a test that draws its scene at run time: VU_TEST_SEED when set (to replay a
 * run that failed), otherwise drawn from std::random_device. It is printed either way. */
inline unsigned int
RunTimeSeed()
{
  unsigned int seed = 0;
  if (const char * given = std::getenv("VU_TEST_SEED"))
  {
    seed = static_cast<unsigned int>(std::stoul(given));
  }
  else
  {
    seed = std::random_device{}();
  }
  std::cout << "seed " << seed << " (replay: VU_TEST_SEED=" << seed << ")" << std::endl;
  return seed;
}
} // namespace vu

#endif

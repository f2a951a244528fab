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
#ifndef vuExpectRefusal_h
#define vuExpectRefusal_h

#include "itkMacro.h"

#include "gtest/gtest.h"

#include <string>

namespace vu {
/** Runs `run`, which must refuse with an itk::ExceptionObject whose description holds
 * `reason`; `accepted` says what was wrongly accepted when it does not throw. */
template <typename TRun>
void
ExpectRefusal(TRun && run, const std::string & reason, const std::string & accepted)
{
  try
  {
    run();
    ADD_FAILURE() << accepted;
  }
  catch (const itk::ExceptionObject & e)
  {
    EXPECT_NE(std::string(e.GetDescription()).find(reason), std::string::npos) << e.GetDescription();
  }
}
} // namespace vu

#endif

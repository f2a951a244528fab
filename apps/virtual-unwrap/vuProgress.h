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
#ifndef vuProgress_h
#define vuProgress_h

#include "itkProcessObject.h"

#include <nlohmann/json.hpp>

#include <string>

namespace vu {
/** Progress of a multi-stage command on standard error: a bar per stage on a terminal,
 * plain lines otherwise, JSON lines with --json, nothing with --quiet. */
class Progress
{
public:
  Progress(bool quiet, bool json);

  void
  Start(const std::string & stage, const std::string & message);
  /** Shows an ITK filter's ProgressEvents as the current stage's bar. */
  void
  Observe(itk::ProcessObject * filter);
  /** A simulation step: shown (on a terminal) every 50 steps. */
  void
  Tick(const std::string & phase, uint64_t step);
  void
  Done(const std::string & stage, double seconds);
  /** Final lines on standard output: where the results are and, when measured, the
   * legibility. */
  void
  Finish(const std::string & outputDirectory, const nlohmann::json & report);

private:
  void
  Bar(double fraction);

  bool        m_Quiet;
  bool        m_Json;
  bool        m_Terminal;
  std::string m_Stage;
  int         m_LastPercent{ -1 };
};
} // namespace vu

#endif

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
#ifndef vuWorkbenchSession_h
#define vuWorkbenchSession_h

#include "vuSimulationRunner.h"
#include "vuWorkbenchScene.h"

#include <array>
#include <string>
#include <vector>

namespace vu {
/** Everything a session file holds to reopen the workbench where it was left: the sheet
 * (meshes and where they came from; the scan is read again from its path), the
 * simulation's controls, locks and state, the focal plane, the object's transform and the
 * camera. JSON, written atomically. */
struct Session
{
  Scene                 Source; // Volume not stored
  SimulationControls    Controls;
  FocalPlane            Plane;
  std::vector<uint32_t> Locked;
  bool                  HasState{ false };
  SimulationState       State;
  /** Translation (mm), rotation about x, y, z (degrees), scale. */
  std::array<double, 7> ObjectTransform{ { 0, 0, 0, 0, 0, 0, 1 } };
  bool                  HasCamera{ false };
  /** Position, focal point, view up. */
  std::array<double, 9> Camera{};
};

void
WriteSession(const std::string & path, const Session & session);
/** Throws std::runtime_error naming what is wrong with the file. */
Session
ReadSession(const std::string & path);
} // namespace vu

#endif

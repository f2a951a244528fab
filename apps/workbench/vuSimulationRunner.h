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
#ifndef vuSimulationRunner_h
#define vuSimulationRunner_h

#include "itkMassSpringSheetFlattener.h"
#include "itkSheetMesh.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vu {
/** What a person changes while the sheet unrolls; applied between two steps. */
struct SimulationControls
{
  itk::MassSpringIntegratorEnum Integrator{ itk::MassSpringIntegratorEnum::ImplicitEuler };
  /** Time step in s; 0: the flattener's automatic step for the integrator. */
  double TimeStep{ 0.0 };
  /** Velocity damping in 1/s; < 0: automatic (two over the fall time). */
  double Damping{ -1.0 };
  /** Factors on the springs' stiffness and on the automatic gravity. */
  double StiffnessScale{ 1.0 };
  double GravityScale{ 1.0 };
  /** Restitution k_r of the collision plane, in [0, 1]. */
  double Restitution{ 0.1 };
  /** The unroll ends when the hanging sheet comes to rest (as the command-line tool does);
   * off, it hangs until Flatten is asked for. */
  bool AutoAdvance{ true };

  bool
  operator==(const SimulationControls & o) const
  {
    return Integrator == o.Integrator && TimeStep == o.TimeStep && Damping == o.Damping &&
           StiffnessScale == o.StiffnessScale && GravityScale == o.GravityScale && Restitution == o.Restitution &&
           AutoAdvance == o.AutoAdvance;
  }
  bool
  operator!=(const SimulationControls & o) const
  {
    return !(*this == o);
  }
};

/** A state the simulation can go back to (after a divergence) or a session can reopen. */
struct SimulationState
{
  itk::SheetFlatteningPhaseEnum Phase{ itk::SheetFlatteningPhaseEnum::Unroll };
  uint64_t                      Step{ 0 };
  std::vector<double>           Positions, Velocities;
  std::vector<uint8_t>          Locked;
  SimulationControls            Controls;
  double                        AppliedTimeStep{ 0.0 };
};

/** What the viewer shows: the latest published state of the running simulation. */
struct SimulationSnapshot
{
  enum class Status
  {
    Idle,
    Running,
    Paused,
    Diverged,
    Finished,
    Failed
  };
  uint64_t                      Version{ 0 };
  Status                        State{ Status::Idle };
  itk::SheetFlatteningPhaseEnum Phase{ itk::SheetFlatteningPhaseEnum::Unroll };
  uint64_t                      Step{ 0 };
  double                        KineticEnergy{ 0.0 }, SpringEnergy{ 0.0 }, StepsPerSecond{ 0.0 };
  double                        TimeStep{ 0.0 };
  itk::MassSpringIntegratorEnum Integrator{ itk::MassSpringIntegratorEnum::ImplicitEuler };
  std::vector<double>           Positions;
  std::vector<uint8_t>          Locked;
  std::string                   Message;
};

const char *
ToString(SimulationSnapshot::Status status);

/** Runs itk::MassSpringSheetFlattener on a thread of its own, the way a viewer needs it:
 * the step callback applies the controls, locks, releases and impulses asked for since
 * the last step, publishes the positions for display, keeps the last stable state, and
 * waits while paused. A divergence (itk::MassSpringDivergenceError) stops the run, which
 * can then resume from the last stable state with the controls it had. Every method is
 * called from one thread (the viewer's); the simulation never blocks it. */
class SimulationRunner
{
public:
  SimulationRunner() = default;
  ~SimulationRunner();
  SimulationRunner(const SimulationRunner &) = delete;
  SimulationRunner &
  operator=(const SimulationRunner &) = delete;

  /** Starts a flattening of `surface` holding `locked` (one flag per point) during the
   * unroll, from `resume` when given. Stops a run in progress first. */
  void
  Start(const itk::SheetMesh &                      surface,
        const itk::MassSpringFlatteningParameters & parameters,
        const std::vector<uint8_t> &                locked,
        const SimulationControls &                  controls,
        bool                                        paused,
        const SimulationState *                     resume = nullptr);
  /** Stops the run (at the next step) and waits for its thread. */
  void
  Stop();
  void
  SetPaused(bool paused);
  /** One step, then paused. */
  void
  StepOnce();
  void
  SetControls(const SimulationControls & controls);
  /** The controls asked for last (after ResumeFromStableState: the ones it resumed with). */
  SimulationControls
  GetControls() const
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    return m_Controls;
  }
  /** Locks (lock = true) or releases the given particles. */
  void
  SetLocked(const std::vector<uint32_t> & particles, bool lock);
  /** Ends the unroll phase now: the sheet is dropped onto the plane and flattened. */
  void
  RequestFlatten();
  /** Makes the hanging sheet wave: its free end gets `strength` times g t_fall, the speed
   * of a body after the sheet's fall time under the simulation's gravity (0.3 gives a wave
   * one sees, whatever the sheet's size and units). */
  void
  Wave(double strength);

  /** The latest snapshot when it is newer than `version` (returns false otherwise). */
  bool
  GetSnapshot(uint64_t version, SimulationSnapshot & snapshot) const;
  /** After a divergence: restarts from the last stable state, paused. False without one. */
  bool
  ResumeFromStableState();
  bool
  HasStableState() const;
  SimulationState
  GetStableState() const;
  /** The flat mesh of a finished run and the flattener's report. */
  bool
  GetResult(itk::SheetMesh & flat, itk::MassSpringFlatteningReport * report = nullptr) const;
  /** The state of the run as the last callback saw it (for a session file). */
  SimulationState
  GetCurrentState() const;
  bool
  IsRunning() const
  {
    return m_Thread.joinable() && !m_Done;
  }

private:
  void
  Run(itk::SheetMesh surface, itk::MassSpringFlatteningParameters parameters, std::vector<uint8_t> locked);
  bool
  Callback(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase, uint64_t step);
  /** Applies what the viewer asked for since the last step; false when asked to stop. */
  bool
  TakeRequests(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase);
  void
  KeepStableState(const itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase);
  void
  ApplyControls(itk::MassSpringSystem & system, const SimulationControls & controls);
  void
  Publish(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase, bool force);

  mutable std::mutex      m_Mutex;
  std::condition_variable m_Wake;
  std::thread             m_Thread;
  std::atomic<bool>       m_Done{ true };

  // Requests from the viewer (under m_Mutex).
  bool                                                m_StopRequested{ false };
  bool                                                m_Paused{ false };
  unsigned int                                        m_StepsAllowed{ 0 };
  bool                                                m_FlattenRequested{ false };
  SimulationControls                                  m_Controls;
  bool                                                m_ControlsChanged{ false };
  std::vector<std::pair<std::vector<uint32_t>, bool>> m_LockRequests;
  double                                              m_WaveSpeed{ 0.0 };

  // The run's own state (simulation thread; copied out under m_Mutex).
  SimulationControls                  m_Applied;
  SimulationState                     m_Stable, m_Current;
  bool                                m_HasStable{ false };
  uint64_t                            m_StepsSinceChange{ 0 };
  itk::MassSpringSheetFlattener       m_Flattener;
  itk::SheetMesh                      m_Surface, m_Flat;
  itk::MassSpringFlatteningParameters m_Parameters;
  itk::MassSpringFlatteningReport     m_Report;
  std::vector<uint8_t>                m_InitialLocks;
  bool                                m_PhaseSeen{ false };
  uint64_t                            m_TotalSteps{ 0 };
  double                              m_LastPublish{ -1.0 };
  double                              m_RateClock{ 0.0 };
  uint64_t                            m_RateSteps{ 0 };
  double                              m_Rate{ 0.0 };

  SimulationSnapshot m_Snapshot;
};
} // namespace vu

#endif

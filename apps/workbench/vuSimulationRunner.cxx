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
#include "vuSimulationRunner.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>

namespace vu {
namespace {
double
Now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool
Finite(const std::vector<double> & values)
{
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      return false;
    }
  }
  return true;
}

std::vector<uint8_t>
LockFlags(const itk::MassSpringSystem & system)
{
  std::vector<uint8_t> flags(system.GetNumberOfParticles());
  for (size_t i = 0; i < flags.size(); ++i)
  {
    flags[i] = system.IsLocked(static_cast<uint32_t>(i)) ? 1 : 0;
  }
  return flags;
}
} // namespace

const char *
ToString(SimulationSnapshot::Status status)
{
  switch (status)
  {
    case SimulationSnapshot::Status::Idle:
      return "idle";
    case SimulationSnapshot::Status::Running:
      return "running";
    case SimulationSnapshot::Status::Paused:
      return "paused";
    case SimulationSnapshot::Status::Diverged:
      return "diverged";
    case SimulationSnapshot::Status::Finished:
      return "finished";
    case SimulationSnapshot::Status::Failed:
      return "failed";
  }
  return "unknown";
}

SimulationRunner::~SimulationRunner() { Stop(); }

void
SimulationRunner::Start(const itk::SheetMesh &                      surface,
                        const itk::MassSpringFlatteningParameters & parameters,
                        const std::vector<uint8_t> &                locked,
                        const SimulationControls &                  controls,
                        bool                                        paused,
                        const SimulationState *                     resume)
{
  Stop();
  std::lock_guard<std::mutex> lock(m_Mutex);
  m_StopRequested = false;
  m_Paused = paused;
  m_StepsAllowed = 0;
  m_FlattenRequested = false;
  m_Controls = controls;
  m_ControlsChanged = false;
  m_LockRequests.clear();
  m_WaveSpeed = 0.0;
  m_Applied = controls;
  m_HasStable = false;
  m_StepsSinceChange = 0;
  m_TotalSteps = resume != nullptr ? resume->Step : 0;
  m_LastPublish = -1.0;
  m_RateClock = Now();
  m_RateSteps = m_TotalSteps;
  m_Rate = 0.0;
  m_Flat = itk::SheetMesh();
  m_Report = itk::MassSpringFlatteningReport();
  m_Snapshot.State = paused ? SimulationSnapshot::Status::Paused : SimulationSnapshot::Status::Running;
  m_Snapshot.Message.clear();
  ++m_Snapshot.Version;
  m_Flattener = itk::MassSpringSheetFlattener();
  if (resume != nullptr)
  {
    const auto phase = resume->Phase == itk::SheetFlatteningPhaseEnum::Unroll ? itk::SheetFlatteningPhaseEnum::Unroll
                                                                              : itk::SheetFlatteningPhaseEnum::Flatten;
    m_Flattener.SetInitialState(phase, resume->Positions, resume->Velocities);
  }
  m_Done = false;
  m_Thread = std::thread(&SimulationRunner::Run, this, surface, parameters, locked);
}

void
SimulationRunner::Stop()
{
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    m_StopRequested = true;
  }
  m_Wake.notify_all();
  if (m_Thread.joinable())
  {
    m_Thread.join();
  }
}

void
SimulationRunner::SetPaused(bool paused)
{
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    m_Paused = paused;
    m_StepsAllowed = 0;
  }
  m_Wake.notify_all();
}

void
SimulationRunner::StepOnce()
{
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    m_Paused = true;
    m_StepsAllowed = 1;
  }
  m_Wake.notify_all();
}

void
SimulationRunner::SetControls(const SimulationControls & controls)
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  if (controls != m_Controls)
  {
    m_Controls = controls;
    m_ControlsChanged = true;
    m_Wake.notify_all();
  }
}

void
SimulationRunner::SetLocked(const std::vector<uint32_t> & particles, bool lock)
{
  std::lock_guard<std::mutex> guard(m_Mutex);
  m_LockRequests.emplace_back(particles, lock);
  m_Wake.notify_all();
}

void
SimulationRunner::RequestFlatten()
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  m_FlattenRequested = true;
  m_Wake.notify_all();
}

void
SimulationRunner::Wave(double strength)
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  m_WaveSpeed += strength;
  m_Wake.notify_all();
}

bool
SimulationRunner::GetSnapshot(uint64_t version, SimulationSnapshot & snapshot) const
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  if (m_Snapshot.Version == version)
  {
    return false;
  }
  snapshot = m_Snapshot;
  return true;
}

bool
SimulationRunner::HasStableState() const
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  return m_HasStable;
}

SimulationState
SimulationRunner::GetStableState() const
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  return m_Stable;
}

SimulationState
SimulationRunner::GetCurrentState() const
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  return m_Current;
}

bool
SimulationRunner::GetResult(itk::SheetMesh & flat, itk::MassSpringFlatteningReport * report) const
{
  std::lock_guard<std::mutex> lock(m_Mutex);
  if (m_Snapshot.State != SimulationSnapshot::Status::Finished)
  {
    return false;
  }
  flat = m_Flat;
  if (report != nullptr)
  {
    *report = m_Report;
  }
  return true;
}

bool
SimulationRunner::ResumeFromStableState()
{
  SimulationState                     stable;
  SimulationControls                  failing;
  itk::SheetMesh                      surface;
  itk::MassSpringFlatteningParameters parameters;
  std::vector<uint8_t>                locks;
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    if (!m_HasStable)
    {
      return false;
    }
    stable = m_Stable;
    failing = m_Applied;
    surface = m_Surface;
    parameters = m_Parameters;
    locks = m_InitialLocks;
  }
  Stop();
  // The stable state's controls; if they are the ones that diverged (an unstable step set
  // before the start), the automatic step, which keeps within the integrator's bound.
  SimulationControls controls = stable.Controls;
  if (controls == failing)
  {
    controls.TimeStep = 0.0;
  }
  Start(surface, parameters, stable.Locked.empty() ? locks : stable.Locked, controls, true, &stable);
  return true;
}

void
SimulationRunner::ApplyControls(itk::MassSpringSystem & system, const SimulationControls & controls)
{
  if (controls.StiffnessScale != m_Applied.StiffnessScale && controls.StiffnessScale > 0.0)
  {
    system.ScaleStiffnesses(controls.StiffnessScale / m_Applied.StiffnessScale);
  }
  system.SetIntegrator(controls.Integrator);
  itk::MassSpringFlatteningParameters p = m_Parameters;
  p.Stiffness *= controls.StiffnessScale;
  const double h = controls.TimeStep > 0.0 ? controls.TimeStep
                                           : itk::MassSpringSheetFlattener::AutomaticTimeStep(
                                               system, controls.Integrator, p, m_Flattener.GetReport().FallTime);
  system.SetTimeStep(h);
  system.SetDamping(controls.Damping >= 0.0 ? controls.Damping : m_Flattener.GetReport().Damping);
  if (system.HasCollisionPlane())
  {
    system.SetRestitution(controls.Restitution);
  }
  const double s = controls.GravityScale / std::max(1e-300, m_Applied.GravityScale);
  const auto   now = system.GetGravity();
  system.SetGravity({ now[0] * s, now[1] * s, now[2] * s });
  m_Applied = controls;
}

void
SimulationRunner::Publish(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase, bool force)
{
  const double now = Now();
  if (now - m_RateClock >= 0.5)
  {
    m_Rate = static_cast<double>(m_TotalSteps - m_RateSteps) / (now - m_RateClock);
    m_RateClock = now;
    m_RateSteps = m_TotalSteps;
  }
  if (!force && now - m_LastPublish < 1.0 / 30.0)
  {
    return;
  }
  m_LastPublish = now;
  const double                kinetic = system.ComputeKineticEnergy();
  const double                spring = system.ComputeSpringEnergy();
  std::vector<uint8_t>        locks = LockFlags(system);
  std::lock_guard<std::mutex> lock(m_Mutex);
  m_Snapshot.Phase = phase;
  m_Snapshot.Step = m_TotalSteps;
  m_Snapshot.KineticEnergy = kinetic;
  m_Snapshot.SpringEnergy = spring;
  m_Snapshot.StepsPerSecond = m_Rate;
  m_Snapshot.TimeStep = system.GetTimeStep();
  m_Snapshot.Integrator = system.GetIntegrator();
  m_Snapshot.Positions = system.GetPositions();
  m_Snapshot.Locked = locks;
  m_Snapshot.State =
    m_Paused && m_StepsAllowed == 0 ? SimulationSnapshot::Status::Paused : SimulationSnapshot::Status::Running;
  ++m_Snapshot.Version;
  m_Current.Phase = phase;
  m_Current.Step = m_TotalSteps;
  m_Current.Positions = m_Snapshot.Positions;
  m_Current.Velocities = system.GetVelocities();
  m_Current.Locked = std::move(locks);
  m_Current.Controls = m_Applied;
  m_Current.AppliedTimeStep = system.GetTimeStep();
}

bool
SimulationRunner::TakeRequests(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase)
{
  SimulationControls                                  controls;
  bool                                                controlsChanged = false;
  std::vector<std::pair<std::vector<uint32_t>, bool>> lockRequests;
  double                                              wave = 0.0;
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    if (m_StopRequested)
    {
      return false;
    }
    controlsChanged = m_ControlsChanged;
    controls = m_Controls;
    m_ControlsChanged = false;
    lockRequests.swap(m_LockRequests);
    wave = m_WaveSpeed;
    m_WaveSpeed = 0.0;
  }
  const bool dynamic =
    phase == itk::SheetFlatteningPhaseEnum::Unroll || phase == itk::SheetFlatteningPhaseEnum::Flatten;
  if (controlsChanged || (dynamic && (!lockRequests.empty() || wave != 0.0)))
  {
    // The state before a change is the one to go back to if the change diverges.
    if (dynamic && Finite(system.GetPositions()) && Finite(system.GetVelocities()))
    {
      KeepStableState(system, phase);
    }
    m_StepsSinceChange = 0;
  }
  if (controlsChanged)
  {
    if (dynamic)
    {
      ApplyControls(system, controls);
    }
    else
    {
      m_Applied = controls; // the quasi-static relaxation has its own step and no gravity
    }
  }
  if (dynamic)
  {
    for (const auto & request : lockRequests)
    {
      for (uint32_t id : request.first)
      {
        if (id < system.GetNumberOfParticles())
        {
          system.SetLocked(id, request.second);
        }
      }
    }
    if (wave != 0.0)
    {
      const auto & report = m_Flattener.GetReport();
      itk::MassSpringSheetFlattener::ApplyWave(system, wave * report.Gravity * report.FallTime);
    }
  }
  return true;
}

void
SimulationRunner::KeepStableState(const itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase)
{
  SimulationState stable;
  stable.Phase = phase;
  stable.Step = m_TotalSteps;
  stable.Positions = system.GetPositions();
  stable.Velocities = system.GetVelocities();
  stable.Locked = LockFlags(system);
  stable.Controls = m_Applied;
  stable.AppliedTimeStep = system.GetTimeStep();
  std::lock_guard<std::mutex> lock(m_Mutex);
  m_Stable = std::move(stable);
  m_HasStable = true;
}

bool
SimulationRunner::Callback(itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase, uint64_t)
{
  ++m_TotalSteps;
  ++m_StepsSinceChange;
  const bool dynamic =
    phase == itk::SheetFlatteningPhaseEnum::Unroll || phase == itk::SheetFlatteningPhaseEnum::Flatten;
  if (!m_PhaseSeen || phase != m_Current.Phase)
  {
    m_PhaseSeen = true;
    m_Current.Phase = phase;
    // The flattener sets gravity at each phase's start: the controls go on top of it.
    if (dynamic)
    {
      const SimulationControls wanted = m_Applied;
      m_Applied.GravityScale = 1.0;
      ApplyControls(system, wanted);
    }
  }
  // A state that has run 200 steps on its controls is stable.
  if (dynamic && m_StepsSinceChange >= 200 && m_StepsSinceChange % 50 == 0 && Finite(system.GetPositions()))
  {
    KeepStableState(system, phase);
  }
  bool first = true;
  for (;;)
  {
    if (!TakeRequests(system, phase))
    {
      return false;
    }
    Publish(system, phase, !first);
    std::unique_lock<std::mutex> lock(m_Mutex);
    if (first && m_Paused && m_StepsAllowed > 0)
    {
      --m_StepsAllowed; // this step was the one allowed
    }
    first = false;
    if (m_StopRequested)
    {
      return false;
    }
    if (!m_Paused || m_StepsAllowed > 0 || m_FlattenRequested)
    {
      return true;
    }
    // Paused: shown as such; changes asked for meanwhile are applied without a step.
    lock.unlock();
    Publish(system, phase, true);
    lock.lock();
    m_Wake.wait(lock, [this] {
      return !m_Paused || m_StepsAllowed > 0 || m_StopRequested || m_ControlsChanged || !m_LockRequests.empty() ||
             m_WaveSpeed != 0.0 || m_FlattenRequested;
    });
  }
}

void
SimulationRunner::Run(itk::SheetMesh                      surface,
                      itk::MassSpringFlatteningParameters parameters,
                      std::vector<uint8_t>                locked)
{
  std::vector<uint32_t> ids;
  for (size_t i = 0; i < locked.size(); ++i)
  {
    if (locked[i])
    {
      ids.push_back(static_cast<uint32_t>(i));
    }
  }
  SimulationControls controls;
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    controls = m_Applied;
  }
  parameters.LockedEdge = ids.empty() ? itk::SheetLockedEdgeEnum::None : itk::SheetLockedEdgeEnum::Custom;
  parameters.LockedParticles = ids;
  parameters.CoarseningFactor = 1; // the viewer shows and locks every particle of the mesh
  // One thread for the simulation, the other cores for drawing it (software OpenGL draws
  // on the CPU): an interactive program must stay fluid while it simulates.
  if (parameters.NumberOfWorkUnits == 0)
  {
    parameters.NumberOfWorkUnits = std::max(1u, std::thread::hardware_concurrency() / 2);
  }
  parameters.MaximumStepsPerPhase = UINT_MAX;
  parameters.Integrator = controls.Integrator;
  parameters.TimeStep = controls.TimeStep;
  parameters.Damping = controls.Damping;
  parameters.Restitution = controls.Restitution;
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    m_Surface = surface;
    m_Parameters = parameters;
    m_InitialLocks = locked;
    m_Current = SimulationState();
    m_PhaseSeen = false;
    // The system starts unscaled; the scales are applied as a change at the first step.
    m_Applied = controls;
    m_Applied.StiffnessScale = 1.0;
    m_Applied.GravityScale = 1.0;
    m_Controls = controls;
    m_ControlsChanged = controls.StiffnessScale != 1.0 || controls.GravityScale != 1.0;
  }
  m_Flattener.SetParameters(parameters);
  m_Flattener.SetStepCallback([this](itk::MassSpringSystem &       system,
                                     itk::SheetFlatteningPhaseEnum phase,
                                     uint64_t                      step) { return Callback(system, phase, step); });
  m_Flattener.SetPhaseEndCallback([this](itk::SheetFlatteningPhaseEnum phase, bool converged) {
    std::lock_guard<std::mutex> lock(m_Mutex);
    if (phase == itk::SheetFlatteningPhaseEnum::Unroll)
    {
      if (m_FlattenRequested)
      {
        m_FlattenRequested = false;
        return true;
      }
      return converged && m_Controls.AutoAdvance;
    }
    return converged;
  });
  SimulationSnapshot::Status status = SimulationSnapshot::Status::Finished;
  std::string                message;
  itk::SheetMesh             flat;
  try
  {
    flat = m_Flattener.Flatten(surface);
  }
  catch (const itk::MassSpringDivergenceError & e)
  {
    status = SimulationSnapshot::Status::Diverged;
    message = e.what();
  }
  catch (const itk::ExceptionObject & e)
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    status = m_StopRequested ? SimulationSnapshot::Status::Idle : SimulationSnapshot::Status::Failed;
    message = m_StopRequested ? "stopped" : e.GetDescription();
  }
  catch (const std::exception & e)
  {
    status = SimulationSnapshot::Status::Failed;
    message = e.what();
  }
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    if (status == SimulationSnapshot::Status::Finished)
    {
      m_Flat = flat;
      m_Report = m_Flattener.GetReport();
      m_Snapshot.Positions = flat.Points;
      m_Snapshot.Phase = itk::SheetFlatteningPhaseEnum::Relax;
    }
    m_Snapshot.State = status;
    m_Snapshot.Message = message;
    ++m_Snapshot.Version;
  }
  m_Done = true;
}
} // namespace vu

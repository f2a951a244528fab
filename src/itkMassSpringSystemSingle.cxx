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
// MassSpringSystem's single-precision Euler step and the state it keeps in float.
#include "itkMassSpringSystem.h"
#include "vuImplicitSolver.h"
#include "vuSinglePrecisionState.h"

#include <algorithm>

namespace itk {
void
MassSpringSystem::SetSinglePrecision(bool on)
{
  SyncState();
  DoubleStateChanged();
  m_SinglePrecision = on;
}

bool
MassSpringSystem::UsesSinglePrecisionStep() const
{
  return m_SinglePrecision && m_SpringDamping <= 0.0 &&
         (m_Integrator == MassSpringIntegratorEnum::ExplicitEuler ||
          m_Integrator == MassSpringIntegratorEnum::SymplecticEuler);
}

void
MassSpringSystem::SyncState() const
{
  SinglePrecisionState & single = *m_Single;
  if (!single.ahead)
  {
    return;
  }
  const size_t n = m_Masses.size();
  for (size_t i = 0; i < n; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      m_X[3 * i + d] = single.x[d][i];
      m_V[3 * i + d] = single.v[d][i];
    }
  }
  single.ahead = false;
}

void
MassSpringSystem::DoubleStateChanged()
{
  m_Single->loaded = false;
  m_Single->ahead = false;
}

void
MassSpringSystem::StepEulerSingle(bool symplectic)
{
  SinglePrecisionState & single = *m_Single;
  const size_t           n = m_Masses.size();
  if (!single.springsValid)
  {
    single.springs.Build(n, m_SpringI, m_SpringJ, m_RestLength, m_Stiffness);
    single.springsValid = true;
  }
  if (!single.loaded)
  {
    for (int d = 0; d < 3; ++d)
    {
      single.x[d].resize(n);
      single.xNext[d].resize(n);
      single.v[d].resize(n);
    }
    single.inverseMass.resize(n);
    for (size_t i = 0; i < n; ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        single.x[d][i] = static_cast<float>(m_X[3 * i + d]);
        single.v[d][i] = static_cast<float>(m_V[3 * i + d]);
      }
      single.inverseMass[i] = static_cast<float>(1.0 / m_Masses[i]);
    }
    single.loaded = true;
  }
  vu::BandedSprings::Settings settings;
  settings.timeStep = static_cast<float>(m_TimeStep);
  settings.damping = static_cast<float>(m_Damping);
  settings.symplectic = symplectic;
  settings.hasPlane = m_HasPlane;
  settings.restitution = static_cast<float>(m_Restitution);
  settings.restingSpeed = static_cast<float>(RestingSpeed());
  for (int d = 0; d < 3; ++d)
  {
    settings.gravity[d] = static_cast<float>(m_Gravity[d]);
    settings.planePoint[d] = static_cast<float>(m_PlanePoint[d]);
    settings.planeNormal[d] = static_cast<float>(m_PlaneNormal[d]);
  }
  const float * const x[3] = { single.x[0].data(), single.x[1].data(), single.x[2].data() };
  float * const       xNext[3] = { single.xNext[0].data(), single.xNext[1].data(), single.xNext[2].data() };
  float * const       v[3] = { single.v[0].data(), single.v[1].data(), single.v[2].data() };
  // One contiguous range per work unit: a range shorter than a few band widths would spend
  // more on the springs it shares with its neighbours than it saves.
  const size_t ranges =
    std::max<size_t>(1,
                     std::min<size_t>(n / single.springs.GetMinimumRange(),
                                      m_NumberOfWorkUnits > 0 ? m_NumberOfWorkUnits
                                                              : MultiThreaderBase::GetGlobalDefaultNumberOfThreads()));
  // Ranges start on a block boundary: the state does not depend on the number of threads.
  const auto boundary = [&](size_t r) {
    constexpr size_t block = vu::BandedSprings::BlockSize;
    return r == ranges ? n : (n * r / ranges) / block * block;
  };
  const auto stepRange = [&](size_t r) {
    single.springs.StepRange(
      x, xNext, v, single.inverseMass.data(), m_Locked.data(), settings, boundary(r), boundary(r + 1));
  };
  if (ranges == 1)
  {
    stepRange(0);
  }
  else
  {
    m_Solver->Threader(m_NumberOfWorkUnits)
      ->ParallelizeArray(
        0, ranges, [&](SizeValueType r) { stepRange(r); }, nullptr);
  }
  for (int d = 0; d < 3; ++d)
  {
    single.x[d].swap(single.xNext[d]);
  }
  single.ahead = true;
  ++m_ForceEvaluations;
}
} // end namespace itk

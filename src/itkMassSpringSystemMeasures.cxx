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
// MassSpringSystem's energies, scales, residuals and divergence check.
#include "itkMassSpringSystem.h"

#include "itkMacro.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace itk {
double
MassSpringSystem::ComputeKineticEnergy() const
{
  SyncState();
  double e = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    const double * v = &m_V[3 * i];
    e += 0.5 * m_Masses[i] * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
  return e;
}

double
MassSpringSystem::ComputeSpringEnergy() const
{
  SyncState();
  double e = 0.0;
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    const double * a = &m_X[3 * m_SpringI[s]];
    const double * b = &m_X[3 * m_SpringJ[s]];
    const double   len =
      std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    const double stretch = len - m_RestLength[s];
    e += 0.5 * m_Stiffness[s] * stretch * stretch;
  }
  return e;
}

double
MassSpringSystem::ComputeGravityEnergy() const
{
  SyncState();
  double e = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    const double * x = &m_X[3 * i];
    e -= m_Masses[i] * (m_Gravity[0] * x[0] + m_Gravity[1] * x[1] + m_Gravity[2] * x[2]);
  }
  return e;
}

double
MassSpringSystem::TotalEnergy() const
{
  return ComputeKineticEnergy() + ComputeSpringEnergy() + ComputeGravityEnergy();
}

double
MassSpringSystem::GetMeanStiffness() const
{
  return m_Stiffness.empty() ? 0.0 : std::accumulate(m_Stiffness.begin(), m_Stiffness.end(), 0.0) / m_Stiffness.size();
}

double
MassSpringSystem::GetMeanRestLength() const
{
  return m_RestLength.empty() ? 0.0
                              : std::accumulate(m_RestLength.begin(), m_RestLength.end(), 0.0) / m_RestLength.size();
}

double
MassSpringSystem::GetMeanMass() const
{
  return m_Masses.empty() ? 0.0 : std::accumulate(m_Masses.begin(), m_Masses.end(), 0.0) / m_Masses.size();
}

double
MassSpringSystem::EstimateMaximumAngularFrequency() const
{
  std::vector<double> rowSum(m_Masses.size(), 0.0);
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    rowSum[m_SpringI[s]] += 2.0 * m_Stiffness[s];
    rowSum[m_SpringJ[s]] += 2.0 * m_Stiffness[s];
  }
  double w2 = 0.0;
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    w2 = std::max(w2, rowSum[i] / m_Masses[i]);
  }
  return std::sqrt(w2);
}

double
MassSpringSystem::ComputeRelativeResidualForce()
{
  SyncState();
  std::vector<double> zero(m_V.size(), 0.0), a(m_V.size());
  Accelerations(m_X.data(), zero.data(), a.data());
  --m_ForceEvaluations; // an analysis, not a simulation step
  double       sum = 0.0;
  size_t       count = 0;
  const double contactDepth = 1e-9 * GetMeanRestLength();
  for (size_t i = 0; i < m_Masses.size(); ++i)
  {
    if (m_Locked[i])
    {
      continue;
    }
    double f[3] = { a[3 * i] * m_Masses[i], a[3 * i + 1] * m_Masses[i], a[3 * i + 2] * m_Masses[i] };
    if (m_HasPlane)
    {
      const double * x = &m_X[3 * i];
      const double   depth = (x[0] - m_PlanePoint[0]) * m_PlaneNormal[0] + (x[1] - m_PlanePoint[1]) * m_PlaneNormal[1] +
                           (x[2] - m_PlanePoint[2]) * m_PlaneNormal[2];
      const double fn = f[0] * m_PlaneNormal[0] + f[1] * m_PlaneNormal[1] + f[2] * m_PlaneNormal[2];
      // The plane carries what pushes a resting particle into it.
      if (depth <= contactDepth && fn < 0.0)
      {
        for (int d = 0; d < 3; ++d)
        {
          f[d] -= fn * m_PlaneNormal[d];
        }
      }
    }
    sum += f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    ++count;
  }
  const double scale = GetMeanStiffness() * GetMeanRestLength();
  return count > 0 && scale > 0.0 ? std::sqrt(sum / count) / scale : 0.0;
}

double
MassSpringSystem::ComputeRelativeKineticEnergy() const
{
  double scale = 0.0;
  for (size_t s = 0; s < m_SpringI.size(); ++s)
  {
    scale += 0.5 * m_Stiffness[s] * m_RestLength[s] * m_RestLength[s];
  }
  return scale > 0.0 ? ComputeKineticEnergy() / scale : 0.0;
}

std::string
MassSpringSystem::Describe() const
{
  std::ostringstream os;
  os << "integrator " << ToString(m_Integrator) << ", step " << m_Steps << ", time step " << m_TimeStep;
  const double w = EstimateMaximumAngularFrequency();
  os << " (w_max h = " << w * m_TimeStep << ")";
  return os.str();
}

void
MassSpringSystem::CheckDivergence()
{
  SyncState();
  for (size_t k = 0; k < m_X.size(); ++k)
  {
    if (!std::isfinite(m_X[k]) || !std::isfinite(m_V[k]))
    {
      throw MassSpringDivergenceError("mass-spring simulation diverged (non-finite state) with " + Describe());
    }
  }
  const double energy = TotalEnergy();
  if (energy - m_InitialEnergy > m_EnergyGrowthLimit * m_EnergyReference)
  {
    std::ostringstream os;
    os << "mass-spring simulation diverged (energy grew from " << m_InitialEnergy << " to " << energy << ", beyond "
       << m_EnergyGrowthLimit << " times the energy scale " << m_EnergyReference << ") with " << Describe();
    throw MassSpringDivergenceError(os.str());
  }
}

} // end namespace itk

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
// The single-precision Euler step against the double-precision one.
#include "itkMassSpringSheetFlattener.h"
#include "itkMassSpringSystem.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <cmath>

namespace {
using itk::MassSpringIntegratorEnum;
using itk::MassSpringSystem;

// A 2-turn roll (about 10000 particles, grid-numbered, structural and shear springs)
// falling under gravity, with springs across the numbering that fit no band. (Neither a
// collision plane nor locks: contacts and a sheet buckling under its own weight make the
// motion chaotic, and two runs whose states differ by one part in 1e7 part after a few
// hundred steps in any precision.)
void
MakeRoll(MassSpringSystem & system, MassSpringIntegratorEnum integrator, unsigned int workUnits)
{
  const itk::SheetMesh                mesh = vu::SpiralRollMesh(2.0, 0.5, 2.0, 0.1, 3.0, nullptr);
  itk::MassSpringFlatteningParameters parameters;
  parameters.NumberOfWorkUnits = workUnits;
  itk::MassSpringSheetFlattener::BuildSystem(mesh, parameters, system);
  const uint32_t n = system.GetNumberOfParticles();
  for (uint32_t i = 0; i < 40; ++i)
  {
    const uint32_t a = (i * 7919U) % n, b = (i * 104729U + n / 2) % n;
    if (a != b)
    {
      const std::vector<double> & x = system.GetPositions();
      const double                d = std::sqrt((x[3 * a] - x[3 * b]) * (x[3 * a] - x[3 * b]) +
                                 (x[3 * a + 1] - x[3 * b + 1]) * (x[3 * a + 1] - x[3 * b + 1]) +
                                 (x[3 * a + 2] - x[3 * b + 2]) * (x[3 * a + 2] - x[3 * b + 2]));
      system.AddSpring(a, b, d, 0.01 * system.GetMeanStiffness());
    }
  }
  system.SetIntegrator(integrator);
  system.SetGravity({ 0.0, -1.0, 0.0 });
  system.SetDamping(integrator == MassSpringIntegratorEnum::ExplicitEuler ? 5.0 : 0.5);
  const double bound = 2.0 / system.EstimateMaximumAngularFrequency();
  system.SetTimeStep((integrator == MassSpringIntegratorEnum::ExplicitEuler ? 0.02 : 0.5) * bound);
  system.SetDivergenceCheckInterval(50);
}

// Largest distance between the two states' particles, in mean rest lengths.
double
LargestDifference(const std::vector<double> & a, const std::vector<double> & b, double scale)
{
  double largest = 0.0;
  for (size_t i = 0; i < a.size(); i += 3)
  {
    largest = std::max(largest,
                       std::sqrt((a[i] - b[i]) * (a[i] - b[i]) + (a[i + 1] - b[i + 1]) * (a[i + 1] - b[i + 1]) +
                                 (a[i + 2] - b[i + 2]) * (a[i + 2] - b[i + 2])));
  }
  return largest / scale;
}
} // namespace

TEST(MassSpringSinglePrecision, FollowsTheDoublePrecisionTrajectory)
{
  for (MassSpringIntegratorEnum integrator :
       { MassSpringIntegratorEnum::SymplecticEuler, MassSpringIntegratorEnum::ExplicitEuler })
  {
    MassSpringSystem reference, single;
    MakeRoll(reference, integrator, 2);
    MakeRoll(single, integrator, 2);
    single.SetSinglePrecision(true);
    const std::vector<double> start = reference.GetPositions();
    const double              scale = reference.GetMeanRestLength();
    for (int s = 0; s < 400; ++s)
    {
      reference.Step();
      single.Step();
    }
    // The sheet has fallen by a good part of a rest length or more; the two stay within a
    // thousandth of a rest length of each other.
    EXPECT_GT(LargestDifference(reference.GetPositions(), start, scale), 0.1) << itk::ToString(integrator);
    const double difference = LargestDifference(reference.GetPositions(), single.GetPositions(), scale);
    EXPECT_LT(difference, 1e-3) << itk::ToString(integrator);
    EXPECT_GT(difference, 0.0) << "the single-precision step did not run";
    EXPECT_NEAR(
      single.ComputeKineticEnergy(), reference.ComputeKineticEnergy(), 1e-4 * reference.ComputeKineticEnergy());
    EXPECT_EQ(single.GetNumberOfSteps(), 400U);
  }
}

TEST(MassSpringSinglePrecision, SameStateWithAnyNumberOfThreads)
{
  MassSpringSystem one, two;
  MakeRoll(one, MassSpringIntegratorEnum::SymplecticEuler, 1);
  MakeRoll(two, MassSpringIntegratorEnum::SymplecticEuler, 2);
  one.SetSinglePrecision(true);
  two.SetSinglePrecision(true);
  for (int s = 0; s < 100; ++s)
  {
    one.Step();
    two.Step();
  }
  EXPECT_EQ(one.GetPositions(), two.GetPositions());
  EXPECT_EQ(one.GetVelocities(), two.GetVelocities());
}

TEST(MassSpringSinglePrecision, StateHandsOverBetweenPrecisions)
{
  // Single steps, a read, double steps, a change of positions, single steps again: every
  // hand-over carries the state, the same as all in double precision within float error.
  MassSpringSystem reference, mixed;
  MakeRoll(reference, MassSpringIntegratorEnum::SymplecticEuler, 2);
  MakeRoll(mixed, MassSpringIntegratorEnum::SymplecticEuler, 2);
  const double scale = reference.GetMeanRestLength();
  for (int phase = 0; phase < 4; ++phase)
  {
    mixed.SetSinglePrecision(phase % 2 == 0);
    for (int s = 0; s < 50; ++s)
    {
      reference.Step();
      mixed.Step();
    }
    if (phase == 1)
    {
      std::vector<double> x = reference.GetPositions();
      for (double & c : x)
      {
        c += 0.5;
      }
      reference.SetPositions(x);
      mixed.SetPositions(x);
    }
    EXPECT_LT(LargestDifference(reference.GetPositions(), mixed.GetPositions(), scale), 1e-3) << "phase " << phase;
  }
  EXPECT_EQ(mixed.GetNumberOfSteps(), 200U);
}

TEST(MassSpringSinglePrecision, DivergenceIsStillDetected)
{
  MassSpringSystem system;
  MakeRoll(system, MassSpringIntegratorEnum::SymplecticEuler, 2);
  system.SetSinglePrecision(true);
  system.SetTimeStep(20.0 / system.EstimateMaximumAngularFrequency());
  EXPECT_THROW(
    {
      for (int s = 0; s < 500; ++s)
      {
        system.Step();
      }
    },
    itk::MassSpringDivergenceError);
}

TEST(MassSpringSinglePrecision, BouncesOnTheCollisionPlaneAsInDoublePrecision)
{
  // Two particles on a spring dropped onto a plane with restitution (bounces, then rest),
  // tied by a soft spring to a locked third.
  std::vector<double> heights[2];
  for (bool single : { false, true })
  {
    MassSpringSystem system;
    system.SetParticles({ 0.0, 1.0, 0.0, 1.0, 1.5, 0.0, 5.0, 3.0, 0.0 }, { 1.0, 2.0, 1.0 });
    system.AddSpring(0, 1, 1.2, 50.0);
    system.AddSpring(1, 2, 4.0, 1.0);
    system.SetLocked(2, true);
    system.SetIntegrator(MassSpringIntegratorEnum::SymplecticEuler);
    system.SetGravity({ 0.0, -9.81, 0.0 });
    system.SetCollisionPlane({ 0.0, 0.0, 0.0 }, { 0.0, 1.0, 0.0 }, 0.5);
    system.SetTimeStep(1e-3);
    system.SetSinglePrecision(single);
    for (int s = 0; s < 3000; ++s)
    {
      system.Step();
      if (s % 100 == 99)
      {
        heights[single].push_back(system.GetPositions()[1]);
        EXPECT_EQ(system.GetPositions()[7], 3.0) << "a locked particle moved";
      }
    }
  }
  ASSERT_EQ(heights[0].size(), heights[1].size());
  EXPECT_NE(heights[0], heights[1]) << "the single-precision step did not run";
  double lowest = 1.0;
  for (size_t k = 0; k < heights[0].size(); ++k)
  {
    EXPECT_NEAR(heights[1][k], heights[0][k], 1e-4) << "sample " << k;
    lowest = std::min(lowest, heights[0][k]);
  }
  EXPECT_GE(lowest, -1e-9); // on the plane, never through it
}

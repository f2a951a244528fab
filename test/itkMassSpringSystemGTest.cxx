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
#include "itkMassSpringSystem.h"

#include "itkMacro.h"

#include "gtest/gtest.h"

#include <cmath>

namespace {
using itk::MassSpringIntegratorEnum;
using itk::MassSpringSystem;

// A unit mass on a spring of stiffness k anchored to a locked particle: one undamped mode
// of angular frequency w = sqrt(k / m). Starts stretched by 10% of the rest length.
void
MakeOscillator(MassSpringSystem & system, double k, double damping)
{
  system.SetParticles({ 0, 0, 0, 1.1, 0, 0 }, { 1.0, 1.0 });
  system.AddSpring(0, 1, 1.0, k);
  system.SetLocked(0, true);
  system.SetDamping(damping);
}

// Runs the oscillator for a given number of periods; true when it stayed bounded.
bool
RunsStably(MassSpringIntegratorEnum integrator, double wh, double damping, int steps = 2000)
{
  MassSpringSystem system;
  const double     k = 4.0; // w = 2
  MakeOscillator(system, k, damping);
  system.SetIntegrator(integrator);
  system.SetTimeStep(wh / 2.0);
  try
  {
    for (int s = 0; s < steps; ++s)
    {
      system.Step();
    }
  }
  catch (const itk::MassSpringDivergenceError & e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find(itk::ToString(integrator)), std::string::npos) << message;
    EXPECT_NE(message.find("time step"), std::string::npos) << message;
    return false;
  }
  return true;
}
} // namespace

TEST(MassSpringSystem, IntegratorNames)
{
  for (auto e : { MassSpringIntegratorEnum::ExplicitEuler,
                  MassSpringIntegratorEnum::Midpoint,
                  MassSpringIntegratorEnum::RungeKutta4,
                  MassSpringIntegratorEnum::SymplecticEuler,
                  MassSpringIntegratorEnum::ImplicitEuler })
  {
    EXPECT_EQ(itk::MassSpringIntegratorFromString(itk::ToString(e)), e);
  }
  EXPECT_THROW(itk::MassSpringIntegratorFromString("verlet"), itk::ExceptionObject);
}

TEST(MassSpringSystem, RejectsImpossibleParameters)
{
  MassSpringSystem system;
  EXPECT_THROW(system.SetParticles({ 0, 0, 0 }, { 0.0 }), itk::ExceptionObject);
  EXPECT_THROW(system.SetParticles({ 0, 0 }, { 1.0 }), itk::ExceptionObject);
  system.SetParticles({ 0, 0, 0, 1, 0, 0 }, { 1.0, 1.0 });
  EXPECT_THROW(system.AddSpring(0, 0, 1.0, 1.0), itk::ExceptionObject);
  EXPECT_THROW(system.AddSpring(0, 2, 1.0, 1.0), itk::ExceptionObject);
  EXPECT_THROW(system.AddSpring(0, 1, 1.0, -1.0), itk::ExceptionObject);
  EXPECT_THROW(system.SetTimeStep(0.0), itk::ExceptionObject);
  EXPECT_THROW(system.SetDamping(-1.0), itk::ExceptionObject);
  EXPECT_THROW(system.SetCollisionPlane({ 0, 0, 0 }, { 0, 0, 0 }, 0.1), itk::ExceptionObject);
  EXPECT_THROW(system.SetCollisionPlane({ 0, 0, 0 }, { 0, 0, 1 }, 1.5), itk::ExceptionObject);
  EXPECT_THROW(system.SetImplicitIterations(0), itk::ExceptionObject);
}

TEST(MassSpringSystem, SpringForceFollowsHookesLaw)
{
  MassSpringSystem system;
  system.SetParticles({ 0, 0, 0, 1.5, 0, 0 }, { 1.0, 2.0 });
  system.AddSpring(0, 1, 1.0, 10.0);
  system.SetGravity({ 0, 0, -9.81 });
  std::vector<double> a;
  system.ComputeAccelerations(system.GetPositions(), system.GetVelocities(), a);
  // Stretched by 0.5: force 5 pulls the particles together.
  EXPECT_NEAR(a[0], 5.0, 1e-12);
  EXPECT_NEAR(a[3], -2.5, 1e-12);
  EXPECT_NEAR(a[2], -9.81, 1e-12);
  EXPECT_NEAR(system.ComputeSpringEnergy(), 0.5 * 10.0 * 0.25, 1e-12);
  EXPECT_NEAR(system.EstimateMaximumAngularFrequency(), std::sqrt(20.0), 1e-12);
}

// Stiffness and restitution changed between steps, as an interactive program does.
TEST(MassSpringSystem, StiffnessScaledAndRestitutionChangedBetweenSteps)
{
  MassSpringSystem system;
  system.SetParticles({ 0, 0, 0, 1.5, 0, 0 }, { 1.0, 2.0 });
  system.AddSpring(0, 1, 1.0, 10.0);
  system.ScaleStiffnesses(3.0);
  EXPECT_NEAR(system.ComputeSpringEnergy(), 3.0 * 0.5 * 10.0 * 0.25, 1e-12);
  EXPECT_NEAR(system.GetSpringStiffnesses()[0], 30.0, 1e-12);
  // The implicit solver sees the new stiffness: a step of the stiffer spring moves more.
  system.SetIntegrator(itk::MassSpringIntegratorEnum::ImplicitEuler);
  system.SetTimeStep(0.01);
  system.Step();
  const double stiffMove = system.GetPositions()[3] - 1.5;
  system.SetPositions({ 0, 0, 0, 1.5, 0, 0 });
  system.SetVelocities(std::vector<double>(6, 0.0));
  system.ScaleStiffnesses(1.0 / 3.0);
  system.Step();
  EXPECT_LT(stiffMove, 1.5 * (system.GetPositions()[3] - 1.5));
  EXPECT_THROW(system.ScaleStiffnesses(0.0), itk::ExceptionObject);
  EXPECT_THROW(system.ScaleStiffnesses(std::nan("")), itk::ExceptionObject);
  system.SetRestitution(0.7);
  EXPECT_EQ(system.GetRestitution(), 0.7);
  EXPECT_THROW(system.SetRestitution(1.5), itk::ExceptionObject);
}

// Linear analysis of x'' = -w^2 x: symplectic Euler is stable for w h < 2.
TEST(MassSpringSystem, SymplecticEulerStableBelowItsBoundDivergesAbove)
{
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::SymplecticEuler, 1.9, 0.0));
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::SymplecticEuler, 2.1, 0.0));
}

// Classical RK4 is stable for w h < 2 sqrt(2) = 2.83.
TEST(MassSpringSystem, RungeKutta4StableBelowItsBoundDivergesAbove)
{
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::RungeKutta4, 2.7, 0.0));
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::RungeKutta4, 2.95, 0.0));
}

// Forward Euler grows at every time step without damping; with damping c it is stable while
// |1 + h lambda| <= 1 for lambda = -c/2 +- i sqrt(w^2 - c^2/4).
TEST(MassSpringSystem, ExplicitEulerNeedsDampingAndASmallStep)
{
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::ExplicitEuler, 0.2, 0.0, 20000));
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::ExplicitEuler, 0.5, 1.0));  // |1 + h lambda| = 0.90
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::ExplicitEuler, 1.5, 1.0)); // |1 + h lambda| = 1.23
}

// Explicit midpoint: |1 + z + z^2/2| > 1 on the imaginary axis, so it too grows undamped.
TEST(MassSpringSystem, MidpointNeedsDampingAndASmallStep)
{
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::Midpoint, 0.5, 0.0, 20000));
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::Midpoint, 1.0, 1.0));
  EXPECT_FALSE(RunsStably(MassSpringIntegratorEnum::Midpoint, 2.5, 1.0));
}

TEST(MassSpringSystem, ImplicitEulerSurvivesWhereExplicitMethodsFail)
{
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::ImplicitEuler, 2.95, 0.0));
  EXPECT_TRUE(RunsStably(MassSpringIntegratorEnum::ImplicitEuler, 200.0, 0.0, 200));
  // And it relaxes the stretched spring to its rest length.
  MassSpringSystem system;
  MakeOscillator(system, 4.0, 0.0);
  system.SetIntegrator(MassSpringIntegratorEnum::ImplicitEuler);
  system.SetTimeStep(1.0);
  system.SetImplicitIterations(20);
  for (int s = 0; s < 200; ++s)
  {
    system.Step();
  }
  EXPECT_NEAR(system.GetPositions()[3], 1.0, 1e-6);
  EXPECT_LT(system.ComputeRelativeKineticEnergy(), 1e-10);
}

TEST(MassSpringSystem, SymplecticEulerConservesEnergyOfAnOscillator)
{
  MassSpringSystem system;
  MakeOscillator(system, 4.0, 0.0);
  system.SetIntegrator(MassSpringIntegratorEnum::SymplecticEuler);
  system.SetTimeStep(0.01);
  const double initial = system.ComputeSpringEnergy();
  double       maxEnergy = 0.0;
  for (int s = 0; s < 5000; ++s)
  {
    system.Step();
    maxEnergy = std::max(maxEnergy, system.ComputeSpringEnergy() + system.ComputeKineticEnergy());
  }
  EXPECT_NEAR(maxEnergy / initial, 1.0, 0.02);
}

TEST(MassSpringSystem, GravityAndCollisionPlaneFollowThePaper)
{
  MassSpringSystem system;
  system.SetParticles({ 0, 0, 1.0 }, { 2.0 });
  system.SetGravity({ 0, 0, -10.0 });
  system.SetCollisionPlane({ 0, 0, 0 }, { 0, 0, 2.0 }, 0.1);
  system.SetIntegrator(MassSpringIntegratorEnum::RungeKutta4);
  const double h = 1e-3;
  system.SetTimeStep(h);
  // Free fall: x(t) = 1 - 5 t^2 until t = sqrt(0.2).
  for (int s = 0; s < 300; ++s)
  {
    system.Step();
  }
  EXPECT_NEAR(system.GetPositions()[2], 1.0 - 5.0 * 0.09, 1e-9);
  double impactSpeed = 0.0;
  while (system.GetVelocities()[2] < 0.0)
  {
    impactSpeed = -system.GetVelocities()[2];
    system.Step();
  }
  // Bounce: V_new = V_old - (1 + k_r)(V_old . N) N, so the particle leaves at k_r times its speed.
  EXPECT_NEAR(system.GetVelocities()[2], 0.1 * impactSpeed, 0.02 * impactSpeed);
  EXPECT_GE(system.GetPositions()[2], 0.0);
}

TEST(MassSpringSystem, LockedParticlesStayPut)
{
  MassSpringSystem system;
  system.SetParticles({ 0, 0, 0, 1, 0, 0, 2, 0, 0 }, { 1.0, 1.0, 1.0 });
  system.AddSpring(0, 1, 1.0, 100.0);
  system.AddSpring(1, 2, 1.0, 100.0);
  system.SetLockedParticles({ 0 });
  system.SetGravity({ 0, -9.81, 0 });
  system.SetDamping(2.0);
  for (auto integrator : { MassSpringIntegratorEnum::SymplecticEuler, MassSpringIntegratorEnum::ImplicitEuler })
  {
    system.SetIntegrator(integrator);
    system.SetTimeStep(integrator == MassSpringIntegratorEnum::ImplicitEuler ? 0.05 : 0.005);
    for (int s = 0; s < 4000; ++s)
    {
      system.Step();
    }
    EXPECT_EQ(system.GetPositions()[0], 0.0);
    EXPECT_EQ(system.GetPositions()[1], 0.0);
    // The chain hangs straight down from the locked particle.
    EXPECT_NEAR(system.GetPositions()[3], 0.0, 1e-3);
    EXPECT_LT(system.GetPositions()[7], system.GetPositions()[4]);
  }
  EXPECT_EQ(system.GetNumberOfLockedParticles(), 1u);
  system.UnlockAll();
  EXPECT_EQ(system.GetNumberOfLockedParticles(), 0u);
}

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
#include "itkFlatteningDistortionCalculator.h"
#include "itkMassSpringSheetFlattener.h"
#include "vuTestHelpers.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <set>

namespace {
void
PrintReport(const itk::MassSpringSheetFlattener & flattener, const itk::FlatteningDistortionCalculator * c)
{
  const auto & report = flattener.GetReport();
  std::cout << "particles " << report.Particles << " simulated " << report.SimulatedParticles << " springs "
            << report.Springs << " factor " << report.CoarseningFactor << " seconds " << report.Seconds << std::endl;
  for (const auto & phase : report.Phases)
  {
    std::cout << "  " << itk::ToString(phase.Name) << " " << phase.Integrator << " h=" << phase.TimeStep << " steps "
              << phase.Steps << " " << phase.StopReason << " KE " << phase.RelativeKineticEnergy << " F "
              << phase.RelativeResidualForce << " " << phase.Seconds << " s" << std::endl;
  }
  std::cout << "  strain p95 " << c->GetEdgeStrainP95() << " max " << c->GetEdgeStrainMax() << " area "
            << c->GetAreaDistortion() << " flipped " << c->GetNumberOfFlippedTriangles() << std::endl;
}

// Flattens `surface` with `parameters`, measures the flat mesh (into `flat` when given) and
// prints the report and the measures.
itk::FlatteningDistortionCalculator::Pointer
FlattenAndMeasure(itk::MassSpringSheetFlattener &             flattener,
                  const itk::SheetMesh &                      surface,
                  const itk::MassSpringFlatteningParameters & parameters,
                  itk::SheetMesh *                            flat = nullptr)
{
  flattener.SetParameters(parameters);
  const itk::SheetMesh result = flattener.Flatten(surface);
  auto                 c = vu::MeasureDistortion(surface, result);
  PrintReport(flattener, c);
  if (flat != nullptr)
  {
    *flat = result;
  }
  return c;
}

void
ExpectDevelopableFlattening(const itk::SheetMesh & surface, const itk::MassSpringFlatteningParameters & parameters)
{
  itk::MassSpringSheetFlattener flattener;
  itk::SheetMesh                flat;
  auto                          c = FlattenAndMeasure(flattener, surface, parameters, &flat);
  ASSERT_TRUE(itk::HaveSameTopology(surface, flat));
  EXPECT_LE(c->GetEdgeStrainP95(), 0.005);
  EXPECT_LE(c->GetAreaDistortion(), 0.005);
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
  for (size_t i = 0; i < flat.GetNumberOfPoints(); ++i)
  {
    ASSERT_EQ(flat.Points[3 * i + 2], 0.0);
  }
}
} // namespace

TEST(MassSpringSheetFlattener, CylinderPatchWithTheStableSolver)
{
  const itk::SheetMesh surface = vu::ExtrudedCurveMesh(
    [](double t, double & x, double & y) {
      x = 20.0 * std::cos(t);
      y = 20.0 * std::sin(t);
    },
    3.0,
    2.0,
    30.0,
    nullptr);
  itk::MassSpringFlatteningParameters parameters;
  parameters.LockedEdge = itk::SheetLockedEdgeEnum::None;
  ExpectDevelopableFlattening(surface, parameters);
}

TEST(MassSpringSheetFlattener, SpiralRollUnrollThenFlattenWithTheStableSolver)
{
  const itk::SheetMesh                surface = vu::SpiralRollMesh(10.0, 4.0, 3.0, 2.0, 30.0, nullptr);
  itk::MassSpringFlatteningParameters parameters;
  ExpectDevelopableFlattening(surface, parameters);
}

TEST(MassSpringSheetFlattener, SpiralRollUnrollThenFlattenWithRungeKutta4)
{
  const itk::SheetMesh                surface = vu::SpiralRollMesh(10.0, 4.0, 2.0, 4.0, 20.0, nullptr);
  itk::MassSpringFlatteningParameters parameters;
  parameters.Integrator = itk::MassSpringIntegratorEnum::RungeKutta4;
  parameters.MaximumStepsPerPhase = 20000;
  ExpectDevelopableFlattening(surface, parameters);
}

TEST(MassSpringSheetFlattener, CoarseToFineOnALargerRoll)
{
  itk::SheetMesh                      truth;
  const itk::SheetMesh                surface = vu::SpiralRollMesh(20.0, 5.0, 3.0, 0.5, 25.0, &truth);
  itk::MassSpringFlatteningParameters parameters;
  parameters.CoarseParticles = 3000;
  itk::MassSpringSheetFlattener flattener;
  auto                          c = FlattenAndMeasure(flattener, surface, parameters);
  EXPECT_GT(flattener.GetReport().CoarseningFactor, 1u);
  EXPECT_LT(flattener.GetReport().SimulatedParticles, surface.GetNumberOfPoints() / 4);
  EXPECT_LE(c->GetEdgeStrainP95(), 0.005);
  EXPECT_LE(c->GetAreaDistortion(), 0.005);
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
}

// A 10-turn roll (5 mm inner radius, 1 mm pitch, 10 mm wide) whose radius grows by a
// part in ten thousand per millimetre along its axis: its rows differ in length by a
// thousandth from one edge to the other, so the flat strip is an arc (sagitta about
// epsilon L^2 / 8 = 4.9 mm over its 628 mm). Its rows come out straight and the bend taken
// out is reported; with StraightenRows off the arc stays. A strip lying in a plane, bent
// there into a ring (20 mm radius), keeps its shape: it is not a slightly bent strip.
namespace {
// The largest distance of a flat grid mesh's middle row from the straight line through
// its ends.
double
MiddleRowBend(const itk::SheetMesh & flat)
{
  const int      columns = flat.GridColumns;
  const size_t   row = static_cast<size_t>(flat.GridRows / 2) * columns;
  const double * a = &flat.Points[3 * row];
  const double * b = &flat.Points[3 * (row + columns - 1)];
  const double   length = std::hypot(b[0] - a[0], b[1] - a[1]);
  double         bend = 0.0;
  for (int c = 0; c < columns; ++c)
  {
    const double * p = &flat.Points[3 * (row + c)];
    bend = std::max(bend, std::abs((p[0] - a[0]) * (b[1] - a[1]) - (p[1] - a[1]) * (b[0] - a[0])) / length);
  }
  return bend;
}

// A grid mesh flattened without straightening its rows and with it: the middle row's
// bend each time, the bend each report gives, and the straightened flat mesh's flipped
// triangles and edge strain p95.
struct Straightening
{
  double BendWithout{ 0.0 }, ReportedWithout{ 0.0 };
  double BendWith{ 0.0 }, ReportedWith{ 0.0 };
  size_t Flipped{ 0 };
  double StrainP95{ 0.0 };
};

Straightening
FlattenWithoutAndWithStraightening(const itk::SheetMesh & surface)
{
  itk::MassSpringFlatteningParameters parameters;
  itk::MassSpringSheetFlattener       flattener;
  itk::SheetMesh                      flat;
  Straightening                       result;
  parameters.StraightenRows = 0;
  FlattenAndMeasure(flattener, surface, parameters, &flat);
  result.BendWithout = MiddleRowBend(flat);
  result.ReportedWithout = flattener.GetReport().RowBend;
  parameters.StraightenRows = 1;
  const auto c = FlattenAndMeasure(flattener, surface, parameters, &flat);
  result.BendWith = MiddleRowBend(flat);
  result.ReportedWith = flattener.GetReport().RowBend;
  result.Flipped = c->GetNumberOfFlippedTriangles();
  result.StrainP95 = c->GetEdgeStrainP95();
  return result;
}
} // namespace

TEST(MassSpringSheetFlattener, ALongStripBentInItsPlaneComesOutWithStraightRows)
{
  itk::SheetMesh surface = vu::SpiralRollMesh(5.0, 1.0, 10.0, 0.8, 10.0, nullptr);
  for (size_t i = 0; i < surface.GetNumberOfPoints(); ++i)
  {
    const double grow = 1.0 + 1e-4 * surface.Points[3 * i + 2];
    surface.Points[3 * i] *= grow;
    surface.Points[3 * i + 1] *= grow;
  }
  const Straightening strip = FlattenWithoutAndWithStraightening(surface);
  const double        arc = strip.BendWithout;
  EXPECT_NEAR(arc, 4.9, 1.0);
  EXPECT_EQ(strip.ReportedWithout, 0.0);
  EXPECT_LT(strip.BendWith, 0.05 * arc);
  EXPECT_NEAR(strip.ReportedWith, arc, 0.2 * arc);
  EXPECT_EQ(strip.Flipped, 0u);
  EXPECT_LE(strip.StrainP95, 0.005);

  const itk::SheetMesh ring = vu::SquareGridMesh(25, [](int r, int c) {
    const double angle = 0.1 * c - 1.2, rho = 20.0 + 0.5 * r - 6.0;
    return std::array<double, 3>{ rho * std::sin(angle), rho * std::cos(angle), 0.0 };
  });
  const Straightening  laid = FlattenWithoutAndWithStraightening(ring);
  EXPECT_LT(laid.ReportedWith, 0.5);
  EXPECT_GT(laid.BendWith, 5.0);
}

// A strip bent into a gentle arc in its plane, as a tapered roll develops, with a short
// jog near one end (where the trace of an inner turn curls): the jog turns the strip's
// frame fast over a few columns, but the strip is a slightly bent one and its rows come
// out straight (the arc's radius, the jog's place and size drawn at run time).
TEST(MassSpringSheetFlattener, AGentleArcWithAShortJogIsStraightened)
{
  const unsigned seed = vu::RunTimeSeed();
  std::mt19937   random(seed);
  const double   radius = std::uniform_real_distribution<double>(350.0, 700.0)(random);
  const int      jogAt = std::uniform_int_distribution<int>(10, 20)(random);
  const double   jog = std::uniform_real_distribution<double>(2.5, 3.5)(random);
  std::cout << "seed " << seed << ": arc radius " << radius << ", jog of " << jog << " at column " << jogAt
            << std::endl;
  constexpr int        Rows = 6, Columns = 151;
  constexpr double     Spacing = 2.0;
  const itk::SheetMesh strip = vu::GridMesh(Rows, Columns, [&](int r, int c) {
    // Columns along the arc; the first columns shifted across it, the shift fading over 3.
    const double shift = jog * std::clamp((jogAt - c) / 3.0, 0.0, 1.0);
    const double rho = radius + Spacing * (r - 0.5 * (Rows - 1)) + shift;
    const double angle = Spacing * (c - 0.5 * (Columns - 1)) / radius;
    return std::array<double, 3>{ rho * std::sin(angle), rho * std::cos(angle), 0.0 };
  });
  const Straightening  laid = FlattenWithoutAndWithStraightening(strip);
  std::cout << "bend " << laid.BendWithout << " -> " << laid.BendWith << ", reported " << laid.ReportedWith
            << std::endl;
  EXPECT_GT(laid.BendWithout, 10.0);
  EXPECT_LT(laid.BendWith, 0.2 * laid.BendWithout);
  EXPECT_GT(laid.ReportedWith, 0.5 * laid.BendWithout);
  EXPECT_EQ(laid.Flipped, 0u);
}

// A 10-turn roll with a tight inner curl (2.5 mm radius, 0.75 mm pitch, 0.74 mm spacing):
// the curl at the free end is small against the whole sheet and would pass a planarity
// test on the whole; the unroll phase waits until it is out, so nothing folds over when
// the sheet is dropped onto the plane.
TEST(MassSpringSheetFlattener, TightInnerCurlOfALongRollDoesNotFoldOver)
{
  const itk::SheetMesh                surface = vu::SpiralRollMesh(2.5, 0.75, 10.0, 0.74, 10.4, nullptr);
  itk::MassSpringFlatteningParameters parameters;
  parameters.CoarseParticles = 100000;
  ExpectDevelopableFlattening(surface, parameters);
}

// A flattening that did not finish says so: a roll whose unroll phase is stopped after a
// few steps is dropped onto the plane still rolled, and the report names the phases that
// stopped at their step limit and counts the triangles turned over, as the distortion
// measure does; a converged flattening has nothing to say.
// A roll whose unrolling stops long before it hangs flat is pressed onto the plane as it
// hangs, folded; the flattener says so, and starts again from the roll's rows developed
// onto the plane. The roll's size and the step limit are drawn at run time.
TEST(MassSpringSheetFlattener, AnUnfinishedUnrollIsReportedAndStartsAgainFromItsRows)
{
  const unsigned seed = vu::RunTimeSeed();
  std::mt19937   random(seed);
  auto uniform = [&](double low, double high) { return std::uniform_real_distribution<double>(low, high)(random); };
  const double       turns = uniform(2.5, 4.0);
  const double       width = uniform(2.0, 4.0);
  const unsigned int steps = std::uniform_int_distribution<unsigned int>(2, 9)(random);
  std::cout << "seed " << seed << ": " << turns << " turns, width " << width << ", " << steps << " steps a phase"
            << std::endl;
  const itk::SheetMesh          surface = vu::SpiralRollMesh(10.0, 4.0, turns, width, 30.0, nullptr);
  itk::MassSpringSheetFlattener converged;
  const itk::SheetMesh          good = converged.Flatten(surface);
  EXPECT_TRUE(converged.GetReport().Warnings.empty());
  EXPECT_EQ(converged.GetReport().FlippedBeforeRestart, 0u);
  EXPECT_EQ(converged.GetReport().FlippedTriangles,
            vu::MeasureDistortion(surface, good)->GetNumberOfFlippedTriangles());

  itk::MassSpringFlatteningParameters parameters;
  parameters.MaximumStepsPerPhase = steps;
  parameters.RestartFromDevelopedRows = 0;
  itk::MassSpringSheetFlattener folded;
  auto                          f = FlattenAndMeasure(folded, surface, parameters);
  EXPECT_GT(f->GetNumberOfFlippedTriangles(), 0u);
  EXPECT_EQ(folded.GetReport().FlippedTriangles, f->GetNumberOfFlippedTriangles());

  parameters.RestartFromDevelopedRows = 1;
  itk::MassSpringSheetFlattener unfinished;
  auto                          c = FlattenAndMeasure(unfinished, surface, parameters);
  const auto &                  report = unfinished.GetReport();
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
  EXPECT_EQ(report.FlippedTriangles, 0u);
  EXPECT_LT(c->GetEdgeStrainP95(), 1e-3);
  EXPECT_EQ(report.FlippedBeforeRestart, folded.GetReport().FlippedTriangles);
  EXPECT_TRUE(report.RestartKept);
  auto named = [](const itk::MassSpringFlatteningReport & r, const std::string & text) {
    bool found = false;
    for (const std::string & w : r.Warnings)
    {
      std::cout << "warning: " << w << std::endl;
      found |= w.find(text) != std::string::npos;
    }
    return found;
  };
  EXPECT_TRUE(named(report, "unroll phase stopped at its step limit"));
  EXPECT_TRUE(named(report, "with " + std::to_string(report.FlippedBeforeRestart) + " triangles turned over"));
  EXPECT_TRUE(named(folded.GetReport(),
                    std::to_string(folded.GetReport().FlippedTriangles) + " of " +
                      std::to_string(surface.GetNumberOfTriangles()) + " triangles"));
}

TEST(MassSpringSheetFlattener, DomeIsFlattenedWithoutFlipsAndItsDistortionReported)
{
  const itk::SheetMesh                surface = vu::DomeMesh(30.0, 0.6, 25);
  itk::MassSpringFlatteningParameters parameters;
  parameters.LockedEdge = itk::SheetLockedEdgeEnum::None;
  itk::MassSpringSheetFlattener flattener;
  auto                          c = FlattenAndMeasure(flattener, surface, parameters);
  EXPECT_EQ(c->GetNumberOfFlippedTriangles(), 0u);
  // A sphere cannot be flattened isometrically: the distortion shows.
  EXPECT_GT(c->GetEdgeStrainMax(), 0.005);
  EXPECT_LT(c->GetEdgeStrainP95(), 0.2);
}

TEST(MassSpringSheetFlattener, ExplicitStepAboveTheBoundIsReportedAsDivergence)
{
  const itk::SheetMesh                surface = vu::SpiralRollMesh(10.0, 4.0, 1.0, 4.0, 12.0, nullptr);
  itk::MassSpringFlatteningParameters parameters;
  parameters.Integrator = itk::MassSpringIntegratorEnum::SymplecticEuler;
  parameters.TimeStepSafety = 3.0; // w_max h up to 6: beyond the bound of 2
  parameters.Damping = 0.0;
  itk::MassSpringSheetFlattener flattener;
  flattener.SetParameters(parameters);
  try
  {
    flattener.Flatten(surface);
    FAIL() << "a symplectic Euler step of three times the stability bound did not diverge";
  }
  catch (const itk::MassSpringDivergenceError & e)
  {
    EXPECT_NE(std::string(e.what()).find("symplectic-euler"), std::string::npos) << e.what();
  }
  // The stable solver survives the same stiffness and mass at a far larger step.
  parameters.Integrator = itk::MassSpringIntegratorEnum::ImplicitEuler;
  flattener.SetParameters(parameters);
  const itk::SheetMesh flat = flattener.Flatten(surface);
  EXPECT_LE(vu::MeasureDistortion(surface, flat)->GetEdgeStrainP95(), 0.005);
}

TEST(MassSpringSheetFlattener, CallbackSeesEveryPhaseAndCanAbort)
{
  const itk::SheetMesh                    surface = vu::SpiralRollMesh(10.0, 4.0, 1.0, 4.0, 12.0, nullptr);
  itk::MassSpringSheetFlattener           flattener;
  std::set<itk::SheetFlatteningPhaseEnum> phases;
  flattener.SetStepCallback([&](itk::MassSpringSystem & system, itk::SheetFlatteningPhaseEnum phase, uint64_t) {
    phases.insert(phase);
    EXPECT_EQ(system.GetNumberOfParticles(), surface.GetNumberOfPoints());
    return true;
  });
  flattener.Flatten(surface);
  using Phase = itk::SheetFlatteningPhaseEnum;
  EXPECT_EQ(phases, (std::set<Phase>{ Phase::Unroll, Phase::Flatten, Phase::Relax }));
  // The callback and the report name the same phases.
  for (const auto & phase : flattener.GetReport().Phases)
  {
    EXPECT_EQ(phases.count(phase.Name), 1u) << itk::ToString(phase.Name);
  }
  EXPECT_STREQ(itk::ToString(Phase::RelaxFull), "relax-full");
  flattener.SetStepCallback([](itk::MassSpringSystem &, Phase, uint64_t step) { return step < 5; });
  EXPECT_THROW(flattener.Flatten(surface), itk::ExceptionObject);
}

// The default edge, Auto: a grid mesh (a rolled sheet's mid-surface) is unrolled from its
// outer edge, any other mesh only dropped onto the plane.
TEST(MassSpringSheetFlattener, AutomaticLockedEdge)
{
  itk::MassSpringSheetFlattener flattener;
  EXPECT_EQ(flattener.GetParameters().LockedEdge, itk::SheetLockedEdgeEnum::Auto);
  itk::SheetMesh triangle;
  triangle.Points = { 0, 0, 0, 1, 0, 0, 0, 1, 0.2 };
  triangle.Triangles = { 0, 1, 2 };
  flattener.Flatten(triangle);
  EXPECT_EQ(flattener.GetReport().LockedEdge, itk::SheetLockedEdgeEnum::None);
  flattener.Flatten(vu::SpiralRollMesh(10.0, 4.0, 2.0, 4.0, 20.0, nullptr));
  EXPECT_EQ(flattener.GetReport().LockedEdge, itk::SheetLockedEdgeEnum::OuterEdge);
  EXPECT_EQ(flattener.GetParameters().LockedEdge, itk::SheetLockedEdgeEnum::Auto);
  EXPECT_EQ(itk::SheetLockedEdgeFromString("auto"), itk::SheetLockedEdgeEnum::Auto);
}

TEST(MassSpringSheetFlattener, RejectsBadInput)
{
  itk::MassSpringSheetFlattener flattener;
  itk::SheetMesh                degenerate;
  degenerate.Points = { 0, 0, 0, 1, 0, 0, 2, 0, 0 }; // collinear: zero area
  degenerate.Triangles = { 0, 1, 2 };
  EXPECT_THROW(flattener.Flatten(degenerate), itk::ExceptionObject);

  itk::SheetMesh triangle;
  triangle.Points = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
  triangle.Triangles = { 0, 1, 2 };
  // An outer edge needs a grid.
  itk::MassSpringFlatteningParameters parameters;
  parameters.LockedEdge = itk::SheetLockedEdgeEnum::OuterEdge;
  flattener.SetParameters(parameters);
  EXPECT_THROW(flattener.Flatten(triangle), itk::ExceptionObject);
  parameters.LockedEdge = itk::SheetLockedEdgeEnum::Custom;
  parameters.LockedParticles = { 7 };
  flattener.SetParameters(parameters);
  EXPECT_THROW(flattener.Flatten(triangle), itk::ExceptionObject);
  parameters = itk::MassSpringFlatteningParameters();
  parameters.Restitution = 2.0;
  flattener.SetParameters(parameters);
  EXPECT_THROW(flattener.Flatten(triangle), itk::ExceptionObject);
  EXPECT_THROW(itk::SheetLockedEdgeFromString("middle"), itk::ExceptionObject);
  EXPECT_EQ(itk::SheetLockedEdgeFromString("outer"), itk::SheetLockedEdgeEnum::OuterEdge);
}

// What an interactive program needs: a phase that ends when the caller says, the held
// edge found in one call, a wave, and a run resumed from a saved state.
TEST(MassSpringSheetFlattener, CallerEndsThePhasesAndResumesASavedState)
{
  using Phase = itk::SheetFlatteningPhaseEnum;
  const itk::SheetMesh surface = vu::SpiralRollMesh(10.0, 4.0, 2.0, 4.0, 20.0, nullptr);
  const auto outer = itk::MassSpringSheetFlattener::EdgeParticles(surface, itk::SheetLockedEdgeEnum::OuterEdge);
  const auto inner = itk::MassSpringSheetFlattener::EdgeParticles(surface, itk::SheetLockedEdgeEnum::InnerEdge);
  ASSERT_EQ(outer.size(), static_cast<size_t>(surface.GridRows));
  ASSERT_EQ(inner.size(), outer.size());
  EXPECT_NE(outer, inner);
  EXPECT_THROW(itk::MassSpringSheetFlattener::EdgeParticles(surface, itk::SheetLockedEdgeEnum::Auto),
               itk::ExceptionObject);

  itk::MassSpringFlatteningParameters parameters;
  parameters.LockedEdge = itk::SheetLockedEdgeEnum::Custom;
  parameters.LockedParticles = outer;
  parameters.MaximumStepsPerPhase = 100000;
  itk::MassSpringSheetFlattener flattener;
  flattener.SetParameters(parameters);
  // The unroll phase lasts exactly 400 steps although it converges earlier; the state at
  // step 200 is saved.
  uint64_t            unrollSteps = 0;
  std::vector<double> saved, savedVelocities;
  flattener.SetStepCallback([&](itk::MassSpringSystem & system, Phase phase, uint64_t step) {
    if (phase == Phase::Unroll)
    {
      unrollSteps = step;
      if (step == 200)
      {
        saved = system.GetPositions();
        savedVelocities = system.GetVelocities();
      }
    }
    return true;
  });
  flattener.SetPhaseEndCallback(
    [&](Phase phase, bool converged) { return phase == Phase::Unroll ? unrollSteps >= 400 : converged; });
  const itk::SheetMesh flat = flattener.Flatten(surface);
  EXPECT_EQ(unrollSteps, 400u);
  EXPECT_EQ(flattener.GetReport().Phases.front().Steps, 400u);
  const double p95 = vu::MeasureDistortion(surface, flat)->GetEdgeStrainP95();
  EXPECT_LE(p95, 0.005);

  // Resumed from step 200 of the unroll: the unroll restarts there (its first step moves
  // the saved state, not the rolled sheet), and the result is as good.
  flattener.SetInitialState(Phase::Unroll, saved, savedVelocities);
  bool firstStepChecked = false;
  flattener.SetStepCallback([&](itk::MassSpringSystem & system, Phase phase, uint64_t step) {
    if (phase == Phase::Unroll && step == 1)
    {
      double moved = 0.0;
      for (size_t k = 0; k < saved.size(); ++k)
      {
        moved = std::max(moved, std::abs(system.GetPositions()[k] - saved[k]));
      }
      EXPECT_LT(moved, 0.5) << "the run did not start from the saved state";
      firstStepChecked = true;
    }
    unrollSteps = phase == Phase::Unroll ? step : unrollSteps;
    return true;
  });
  // Ended after ten steps, before three checks in a row could find it at rest.
  flattener.SetPhaseEndCallback(
    [&](Phase phase, bool converged) { return phase == Phase::Unroll ? unrollSteps >= 10 : converged; });
  const itk::SheetMesh resumed = flattener.Flatten(surface);
  EXPECT_TRUE(firstStepChecked);
  EXPECT_EQ(flattener.GetReport().Phases.front().StopReason, "ended by the caller");
  EXPECT_LE(vu::MeasureDistortion(surface, resumed)->GetEdgeStrainP95(), 0.005);
  // A flatten-phase resume skips the unroll.
  flattener.SetInitialState(Phase::Flatten, saved, {});
  flattener.Flatten(surface);
  EXPECT_EQ(flattener.GetReport().Phases.front().Name, Phase::Flatten);
  flattener.ClearInitialState();
  EXPECT_THROW(flattener.SetInitialState(Phase::Relax, saved, {}), itk::ExceptionObject);
  flattener.SetInitialState(Phase::Unroll, std::vector<double>(9, 0.0), {});
  EXPECT_THROW(flattener.Flatten(surface), itk::ExceptionObject);
}

TEST(MassSpringSheetFlattener, WaveMovesOnlyFreeParticlesAlongTheNormal)
{
  const itk::SheetMesh                surface = vu::SquareGridMesh(6, [](int r, int c) {
    return std::array<double, 3>{ { 2.0 * c, 2.0 * r, 0.0 } };
  });
  itk::MassSpringSystem               system;
  itk::MassSpringFlatteningParameters parameters;
  itk::MassSpringSheetFlattener::BuildSystem(surface, parameters, system);
  system.SetLocked(0, true);
  itk::MassSpringSheetFlattener::ApplyWave(system, 3.0);
  const auto & v = system.GetVelocities();
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[2], 0.0);
  double fastest = 0.0;
  for (size_t i = 1; i < system.GetNumberOfParticles(); ++i)
  {
    EXPECT_NEAR(v[3 * i], 0.0, 1e-12);
    EXPECT_NEAR(v[3 * i + 1], 0.0, 1e-12);
    fastest = std::max(fastest, std::abs(v[3 * i + 2]));
  }
  EXPECT_NEAR(fastest, 3.0, 1e-9);
}

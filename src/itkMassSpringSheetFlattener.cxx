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
#include "itkMassSpringSheetFlattener.h"
#include "vuCoarseGrid.h"
#include "vuFlatFrame.h"

#include "itkMacro.h"
#include "itk_eigen.h"
#include ITK_EIGEN(Dense)
#include ITK_EIGEN(Sparse)
#include ITK_EIGEN(SparseCholesky)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>
#include <unordered_set>

namespace itk {
const char *
ToString(SheetLockedEdgeEnum edge)
{
  switch (edge)
  {
    case SheetLockedEdgeEnum::None:
      return "none";
    case SheetLockedEdgeEnum::OuterEdge:
      return "outer";
    case SheetLockedEdgeEnum::InnerEdge:
      return "inner";
    case SheetLockedEdgeEnum::Custom:
      return "custom";
    case SheetLockedEdgeEnum::Auto:
      return "auto";
  }
  return "unknown";
}

const char *
ToString(SheetFlatteningPhaseEnum phase)
{
  switch (phase)
  {
    case SheetFlatteningPhaseEnum::Unroll:
      return "unroll";
    case SheetFlatteningPhaseEnum::Flatten:
      return "flatten";
    case SheetFlatteningPhaseEnum::Relax:
      return "relax";
    case SheetFlatteningPhaseEnum::RelaxFull:
      return "relax-full";
  }
  return "unknown";
}

SheetLockedEdgeEnum
SheetLockedEdgeFromString(const std::string & name)
{
  for (auto e : { SheetLockedEdgeEnum::None,
                  SheetLockedEdgeEnum::OuterEdge,
                  SheetLockedEdgeEnum::InnerEdge,
                  SheetLockedEdgeEnum::Custom,
                  SheetLockedEdgeEnum::Auto })
  {
    if (name == ToString(e))
    {
      return e;
    }
  }
  itkGenericExceptionMacro(<< "unknown locked edge '" << name << "' (none, outer, inner, custom, auto)");
}

namespace {
using Clock = std::chrono::steady_clock;
using Vec3 = Eigen::Vector3d;
using FlatFrame::PointOf;
using FlatFrame::PrincipalAxes;
using FlatFrame::ToPlane;

double
Seconds(Clock::time_point since)
{
  return std::chrono::duration<double>(Clock::now() - since).count();
}

uint64_t
EdgeKey(uint32_t a, uint32_t b)
{
  return a < b ? (uint64_t{ a } << 32) | b : (uint64_t{ b } << 32) | a;
}

} // namespace

void
MassSpringSheetFlattener::BuildSystem(const SheetMesh &                      mesh,
                                      const MassSpringFlatteningParameters & parameters,
                                      MassSpringSystem &                     system)
{
  mesh.Validate("mass-spring sheet");
  if (!(parameters.Stiffness > 0.0) || !(parameters.Density > 0.0) || parameters.ShearStiffnessRatio < 0.0 ||
      parameters.BendingStiffnessRatio < 0.0)
  {
    itkGenericExceptionMacro(<< "mass-spring sheet: stiffness and density must be positive and stiffness ratios "
                             << "non-negative");
  }
  const size_t              n = mesh.GetNumberOfPoints();
  const std::vector<double> areas = mesh.ComputeTriangleAreas();
  std::vector<double>       masses(n, 0.0);
  for (size_t t = 0; t < areas.size(); ++t)
  {
    for (int c = 0; c < 3; ++c)
    {
      masses[mesh.Triangles[3 * t + c]] += parameters.Density * areas[t] / 3.0;
    }
  }
  for (size_t i = 0; i < n; ++i)
  {
    if (!(masses[i] > 0.0))
    {
      itkGenericExceptionMacro(<< "mass-spring sheet: point " << i
                               << " belongs to no triangle of non-zero area (degenerate mesh)");
    }
  }
  system.SetParticles(mesh.Points, masses);

  const std::vector<uint32_t> edges = mesh.ComputeEdges();
  auto   length = [&](uint32_t a, uint32_t b) { return (PointOf(mesh.Points, a) - PointOf(mesh.Points, b)).norm(); };
  double meanLength = 0.0;
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    const double L = length(edges[e], edges[e + 1]);
    if (!(L > 0.0))
    {
      itkGenericExceptionMacro(<< "mass-spring sheet: edge (" << edges[e] << ", " << edges[e + 1]
                               << ") has zero length (degenerate mesh)");
    }
    meanLength += L;
  }
  meanLength /= static_cast<double>(edges.size() / 2);
  auto addSpring = [&](uint32_t a, uint32_t b, double ratio) {
    const double L = length(a, b);
    if (L > 0.0)
    {
      system.AddSpring(a, b, L, ratio * parameters.Stiffness * meanLength / L);
    }
  };
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    addSpring(edges[e], edges[e + 1], 1.0);
  }

  // The mesh's edges as sorted keys (ComputeEdges lists them in key order): a binary search
  // is faster than a hash set of millions of edges to build.
  std::vector<uint64_t> edgeKeys(edges.size() / 2);
  for (size_t e = 0; e < edges.size(); e += 2)
  {
    edgeKeys[e / 2] = EdgeKey(edges[e], edges[e + 1]);
  }
  const auto isEdge = [&edgeKeys](uint64_t key) { return std::binary_search(edgeKeys.begin(), edgeKeys.end(), key); };
  if (mesh.IsGridStructured())
  {
    const std::vector<int64_t> lookup = CoarseToFine::GridLookup(mesh);
    auto                       at = [&](int32_t r, int32_t c) -> int64_t {
      return r < mesh.GridRows && c < mesh.GridColumns ? lookup[static_cast<size_t>(r) * mesh.GridColumns + c] : -1;
    };
    for (int32_t r = 0; r < mesh.GridRows; ++r)
    {
      for (int32_t c = 0; c < mesh.GridColumns; ++c)
      {
        const int64_t p00 = at(r, c), p01 = at(r, c + 1), p10 = at(r + 1, c), p11 = at(r + 1, c + 1);
        if (parameters.ShearStiffnessRatio > 0.0 && p00 >= 0 && p01 >= 0 && p10 >= 0 && p11 >= 0)
        {
          // Shear: whichever quad diagonal the triangulation did not use.
          for (auto [a, b] : { std::pair<int64_t, int64_t>{ p00, p11 }, { p01, p10 } })
          {
            if (!isEdge(EdgeKey(static_cast<uint32_t>(a), static_cast<uint32_t>(b))))
            {
              addSpring(static_cast<uint32_t>(a), static_cast<uint32_t>(b), parameters.ShearStiffnessRatio);
            }
          }
        }
        if (parameters.BendingStiffnessRatio > 0.0 && p00 >= 0)
        {
          for (int64_t q : { at(r, c + 2), at(r + 2, c) })
          {
            if (q >= 0)
            {
              addSpring(static_cast<uint32_t>(p00), static_cast<uint32_t>(q), parameters.BendingStiffnessRatio);
            }
          }
        }
      }
    }
  }
  else if (parameters.ShearStiffnessRatio > 0.0)
  {
    // Shear: join the two points opposite each interior edge.
    std::vector<std::pair<uint64_t, uint32_t>> opposite;
    opposite.reserve(mesh.Triangles.size());
    for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
    {
      for (int e = 0; e < 3; ++e)
      {
        opposite.emplace_back(EdgeKey(mesh.Triangles[3 * t + e], mesh.Triangles[3 * t + (e + 1) % 3]),
                              mesh.Triangles[3 * t + (e + 2) % 3]);
      }
    }
    std::sort(opposite.begin(), opposite.end());
    std::unordered_set<uint64_t> added;
    for (size_t k = 0; k + 1 < opposite.size(); ++k)
    {
      if (opposite[k].first == opposite[k + 1].first && opposite[k].second != opposite[k + 1].second)
      {
        const uint64_t key = EdgeKey(opposite[k].second, opposite[k + 1].second);
        if (!isEdge(key) && added.insert(key).second)
        {
          addSpring(opposite[k].second, opposite[k + 1].second, parameters.ShearStiffnessRatio);
        }
      }
    }
  }
  system.SetNumberOfWorkUnits(parameters.NumberOfWorkUnits);
}

namespace {
// Runs one phase until converged or at the step limit; records it in the report.
MassSpringFlatteningReport::Phase
RunPhase(MassSpringSystem &                                 system,
         SheetFlatteningPhaseEnum                           name,
         const MassSpringFlatteningParameters &             parameters,
         const MassSpringSheetFlattener::StepCallback &     callback,
         const MassSpringSheetFlattener::PhaseEndCallback & phaseEnd,
         const std::function<bool()> &                      settled = {})
{
  MassSpringFlatteningReport::Phase phase;
  phase.Name = name;
  phase.Integrator = ToString(system.GetIntegrator());
  phase.TimeStep = system.GetTimeStep();
  phase.StopReason = "step limit";
  const auto   start = Clock::now();
  const size_t checkEvery = 10;
  // A swinging sheet is momentarily still at the ends of its swing: rest counts only when
  // it lasts for several checks in a row.
  const unsigned int restingChecksNeeded = 3;
  unsigned int       restingChecks = 0;
  for (uint64_t step = 1; step <= parameters.MaximumStepsPerPhase; ++step)
  {
    system.Step();
    phase.Steps = step;
    if (callback && !callback(system, name, step))
    {
      itkGenericExceptionMacro(<< "mass-spring flattening aborted during the " << ToString(name) << " phase at step "
                               << step);
    }
    if (step % checkEvery == 0)
    {
      phase.RelativeKineticEnergy = system.ComputeRelativeKineticEnergy();
      restingChecks = phase.RelativeKineticEnergy < parameters.KineticEnergyTolerance ? restingChecks + 1 : 0;
      bool converged = false;
      if (restingChecks >= restingChecksNeeded && (!settled || settled()))
      {
        phase.RelativeResidualForce = system.ComputeRelativeResidualForce();
        converged = phase.RelativeResidualForce < parameters.ResidualForceTolerance;
      }
      if (phaseEnd ? phaseEnd(name, converged) : converged)
      {
        phase.StopReason = converged ? "converged" : "ended by the caller";
        break;
      }
    }
  }
  phase.RelativeKineticEnergy = system.ComputeRelativeKineticEnergy();
  phase.RelativeResidualForce = system.ComputeRelativeResidualForce();
  phase.Seconds = Seconds(start);
  return phase;
}

// Quasi-static relaxation on the plane z = 0 until the residual force is small.
MassSpringFlatteningReport::Phase
RunRelaxation(MassSpringSystem &                             system,
              SheetFlatteningPhaseEnum                       name,
              const MassSpringFlatteningParameters &         parameters,
              const MassSpringSheetFlattener::StepCallback & callback)
{
  MassSpringFlatteningReport::Phase phase;
  phase.Name = name;
  phase.Integrator = "quasi-static";
  phase.StopReason = "step limit";
  const auto start = Clock::now();
  system.SetGravity({ 0.0, 0.0, 0.0 });
  system.UnlockAll();
  system.SetCollisionPlane({ 0.0, 0.0, 0.0 }, { 0.0, 0.0, 1.0 }, parameters.Restitution);
  // Regularise the singular spring Laplacian by M / h^2 at (w h) = 1e3: 1e-6 of the springs.
  const double w = std::sqrt(system.GetMeanStiffness() / system.GetMeanMass());
  system.SetTimeStep(1e3 / w);
  phase.TimeStep = system.GetTimeStep();
  const unsigned int batch = 5;
  for (uint64_t done = 0; done < parameters.RelaxationIterations; done += batch)
  {
    system.Relax(batch);
    phase.Steps = done + batch;
    if (callback && !callback(system, name, phase.Steps))
    {
      itkGenericExceptionMacro(<< "mass-spring flattening aborted during the " << ToString(name) << " phase");
    }
    phase.RelativeResidualForce = system.ComputeRelativeResidualForce();
    if (phase.RelativeResidualForce < parameters.RelaxationTolerance)
    {
      phase.StopReason = "converged";
      break;
    }
  }
  phase.Seconds = Seconds(start);
  return phase;
}

// The particles of a grid mesh held by the unroll phase: the end column of each row.
std::vector<uint32_t>
GridEdgeParticles(const SheetMesh & mesh, SheetLockedEdgeEnum edge)
{
  if (!mesh.IsGridStructured())
  {
    itkGenericExceptionMacro(<< "mass-spring flattening: locked edge '" << ToString(edge)
                             << "' needs a grid-structured mesh; give the particles to lock instead");
  }
  // The first and last point of each row (increasing column).
  std::vector<int64_t> first(mesh.GridRows, -1), last(mesh.GridRows, -1);
  std::vector<int32_t> firstColumn(mesh.GridRows, std::numeric_limits<int32_t>::max()), lastColumn(mesh.GridRows, -1);
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    const int32_t r = mesh.GridIndex[2 * i], c = mesh.GridIndex[2 * i + 1];
    if (c < firstColumn[r])
    {
      firstColumn[r] = c;
      first[r] = static_cast<int64_t>(i);
    }
    if (c > lastColumn[r])
    {
      lastColumn[r] = c;
      last[r] = static_cast<int64_t>(i);
    }
  }
  std::vector<uint32_t> starts, ends;
  for (int32_t r = 0; r < mesh.GridRows; ++r)
  {
    if (first[r] >= 0)
    {
      starts.push_back(static_cast<uint32_t>(first[r]));
      ends.push_back(static_cast<uint32_t>(last[r]));
    }
  }
  // Outer: the end farther from the roll's axis, i.e. from the sheet's centroid line.
  Vec3 centroid = Vec3::Zero();
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    centroid += PointOf(mesh.Points, i);
  }
  centroid /= static_cast<double>(mesh.GetNumberOfPoints());
  Vec3 axis = Vec3::Zero();
  for (size_t k = 0; k + 1 < starts.size(); ++k)
  {
    axis += PointOf(mesh.Points, starts[k + 1]) - PointOf(mesh.Points, starts[k]);
  }
  axis = axis.norm() > 0.0 ? axis.normalized() : Vec3::UnitZ();
  auto radial = [&](const std::vector<uint32_t> & ids) {
    double sum = 0.0;
    for (uint32_t id : ids)
    {
      const Vec3 d = PointOf(mesh.Points, id) - centroid;
      sum += (d - d.dot(axis) * axis).norm();
    }
    return sum / static_cast<double>(ids.size());
  };
  const bool endIsOuter = radial(ends) >= radial(starts);
  if (edge == SheetLockedEdgeEnum::OuterEdge)
  {
    return endIsOuter ? ends : starts;
  }
  return endIsOuter ? starts : ends;
}


// The parameters as run: the automatic locked edge resolved for this mesh, every numeric
// parameter checked against its range (a NaN in none).
MassSpringFlatteningParameters
ResolvedParameters(MassSpringFlatteningParameters p, const SheetMesh & surface)
{
  if (p.LockedEdge == SheetLockedEdgeEnum::Auto)
  {
    p.LockedEdge = surface.IsGridStructured() ? SheetLockedEdgeEnum::OuterEdge : SheetLockedEdgeEnum::None;
  }
#define VU_MASS_SPRING_CHECK_RANGE(type, name, value, lowest, highest, option, key, meaning)                           \
  if (!(static_cast<double>(p.name) >= static_cast<double>(lowest) &&                                                  \
        static_cast<double>(p.name) <= static_cast<double>(highest)))                                                  \
  {                                                                                                                    \
    itkGenericExceptionMacro(<< "mass-spring flattening: impossible parameter " #name " = " << p.name                  \
                             << " (its range: " << static_cast<type>(lowest) << " to " << static_cast<type>(highest)   \
                             << ")");                                                                                  \
  }
  VU_MASS_SPRING_PARAMETERS(VU_MASS_SPRING_CHECK_RANGE)
#undef VU_MASS_SPRING_CHECK_RANGE
  return p;
}

// The particles the unroll phase holds, numbered in the simulated level (`fineIds`: each
// simulated particle's id in the full mesh of `n` points, when `factor` > 1).
std::vector<uint32_t>
HeldParticles(const MassSpringFlatteningParameters & p,
              const SheetMesh &                      simulated,
              size_t                                 n,
              unsigned int                           factor,
              const std::vector<uint32_t> &          fineIds)
{
  std::vector<uint32_t> locked;
  if (p.LockedEdge == SheetLockedEdgeEnum::Custom)
  {
    for (uint32_t id : p.LockedParticles)
    {
      if (id >= n)
      {
        itkGenericExceptionMacro(<< "mass-spring flattening: locked particle " << id << " does not exist");
      }
      if (factor == 1)
      {
        locked.push_back(id);
      }
      else
      {
        auto found = std::find(fineIds.begin(), fineIds.end(), id);
        if (found != fineIds.end())
        {
          locked.push_back(static_cast<uint32_t>(found - fineIds.begin()));
        }
      }
    }
    if (!p.LockedParticles.empty() && locked.empty())
    {
      itkGenericExceptionMacro(<< "mass-spring flattening: none of the locked particles is on the simulated grid; "
                               << "use CoarseningFactor 1");
    }
  }
  else if (p.LockedEdge != SheetLockedEdgeEnum::None)
  {
    locked = GridEdgeParticles(simulated, p.LockedEdge);
  }
  return locked;
}

// Unroll: gravity across the held edge, from it towards the sheet's centroid (a unit vector).
Vec3
HangingDirection(const MassSpringSystem & system, const std::vector<uint32_t> & locked, double extent)
{
  Vec3 heldCentroid = Vec3::Zero(), centroid = Vec3::Zero();
  for (uint32_t id : locked)
  {
    heldCentroid += PointOf(system.GetPositions(), id);
  }
  heldCentroid /= static_cast<double>(locked.size());
  for (size_t i = 0; i < system.GetNumberOfParticles(); ++i)
  {
    centroid += PointOf(system.GetPositions(), i);
  }
  centroid /= static_cast<double>(system.GetNumberOfParticles());
  std::vector<double> heldPositions;
  for (uint32_t id : locked)
  {
    const Vec3 x = PointOf(system.GetPositions(), id);
    heldPositions.insert(heldPositions.end(), { x.x(), x.y(), x.z() });
  }
  Vec3       heldMean;
  const Vec3 axis = locked.size() > 1 ? Vec3(PrincipalAxes(heldPositions, heldMean).col(0)) : Vec3::UnitZ();
  Vec3       down = centroid - heldCentroid;
  down -= down.dot(axis) * axis;
  if (down.norm() < 1e-9 * extent)
  {
    down = axis.unitOrthogonal();
  }
  return down.normalized();
}

// Unrolled: hanging in a plane. A sheet creeping out of its curl can be slow enough to pass
// for resting, so planarity is part of convergence: close to its plane on the whole
// (`tolerance` of the mean spring length, root mean square), and no triangle seen from the
// plane's normal turned over. A small curl left at the free end (the inner turns of a long
// roll) passes the first and would fold over when the sheet is dropped onto the plane; it
// fails the second.
bool
HangsFlat(const MassSpringSystem & system, const SheetMesh & simulated, double tolerance)
{
  Vec3                  centroid;
  const Eigen::Matrix3d axes = PrincipalAxes(system.GetPositions(), centroid);
  const auto &          x = system.GetPositions();
  double                sum = 0.0;
  for (size_t i = 0; i < system.GetNumberOfParticles(); ++i)
  {
    const double d = (PointOf(x, i) - centroid).dot(axes.col(2));
    sum += d * d;
  }
  if (std::sqrt(sum / system.GetNumberOfParticles()) >= tolerance * system.GetMeanRestLength())
  {
    return false;
  }
  size_t positive = 0, negative = 0;
  for (size_t t = 0; t < simulated.GetNumberOfTriangles(); ++t)
  {
    const uint32_t * tri = &simulated.Triangles[3 * t];
    const Vec3       e1 = PointOf(x, tri[1]) - PointOf(x, tri[0]);
    const Vec3       e2 = PointOf(x, tri[2]) - PointOf(x, tri[0]);
    const double     side = e1.cross(e2).dot(axes.col(2));
    positive += side > 0.0 ? 1 : 0;
    negative += side < 0.0 ? 1 : 0;
  }
  return std::min(positive, negative) == 0;
}
} // namespace

namespace {
// What a caller should not miss: every phase that stopped at its step limit, and the
// triangles of the flat mesh turned over.
void
AddWarnings(MassSpringFlatteningReport & report, size_t triangles)
{
  for (const auto & phase : report.Phases)
  {
    if (phase.StopReason != "converged")
    {
      std::ostringstream text;
      text << "the " << ToString(phase.Name) << " phase stopped at its " << phase.StopReason << " (" << phase.Steps
           << " steps) before it converged";
      report.Warnings.push_back(text.str());
    }
  }
  if (report.FlippedBeforeRestart > 0)
  {
    std::ostringstream text;
    text << "the sheet came out of the unroll and flatten phases with " << report.FlippedBeforeRestart
         << " triangles turned over; relaxed again from its rows developed onto the plane, "
         << (report.RestartKept ? "which is kept" : "which did no better and is not kept");
    report.Warnings.push_back(text.str());
  }
  if (report.FlippedTriangles > 0)
  {
    std::ostringstream text;
    text << report.FlippedTriangles << " of " << triangles
         << " triangles of the flat mesh are turned over: the sheet lies folded onto itself there, and its "
            "texture does not read there";
    report.Warnings.push_back(text.str());
  }
}
} // namespace

SheetMesh
MassSpringSheetFlattener::Flatten(const SheetMesh & surface)
{
  const auto start = Clock::now();
  surface.Validate("mass-spring flattening input");
  m_Report = MassSpringFlatteningReport();
  const MassSpringFlatteningParameters p = ResolvedParameters(m_Parameters, surface);
  m_Report.LockedEdge = p.LockedEdge;
  const size_t n = surface.GetNumberOfPoints();
  m_Report.Particles = n;

  // The level that is simulated: the full mesh or a coarser grid.
  unsigned int factor = 1;
  if (surface.IsGridStructured())
  {
    factor =
      p.CoarseningFactor > 0
        ? p.CoarseningFactor
        : std::max(1u, static_cast<unsigned int>(std::ceil(std::sqrt(double(n) / std::max(1u, p.CoarseParticles)))));
  }
  std::vector<uint32_t> fineIds;
  SheetMesh             simulated = factor > 1 ? CoarseToFine::CoarseGrid(surface, factor, fineIds) : surface;
  if (factor > 1 && simulated.GetNumberOfTriangles() == 0)
  {
    factor = 1;
    simulated = surface;
  }
  m_Report.CoarseningFactor = factor;
  m_Report.SimulatedParticles = simulated.GetNumberOfPoints();
  // Held particles, in the simulated level's numbering.
  const std::vector<uint32_t> locked = HeldParticles(p, simulated, n, factor, fineIds);

  MassSpringSystem system;
  BuildSystem(simulated, p, system);
  m_Report.Springs = system.GetNumberOfSprings();

  // Scales: weight per row, hanging length, fall time.
  const double totalMass = std::accumulate(system.GetMasses().begin(), system.GetMasses().end(), 0.0);
  const double rows =
    simulated.IsGridStructured() ? std::max(1, simulated.GridRows) : std::sqrt(double(simulated.GetNumberOfPoints()));
  const double meanLength = system.GetMeanRestLength();
  double       extent = 0.0;
  {
    const std::vector<double> areas = simulated.ComputeTriangleAreas();
    const double              area = std::accumulate(areas.begin(), areas.end(), 0.0);
    // A sheet of this area and this many rows, rows meanLength apart, is this long.
    extent = std::max(meanLength, area / std::max(meanLength, meanLength * (rows - 1.0)));
  }
  const double gravity = p.Gravity > 0.0 ? p.Gravity : p.HangingStrain * p.Stiffness * meanLength / (totalMass / rows);
  const double fallTime = std::sqrt(2.0 * extent / gravity);
  const double damping = p.Damping >= 0.0 ? p.Damping : 2.0 / fallTime;
  m_Report.Gravity = gravity;
  m_Report.Damping = damping;
  system.SetDamping(damping);
  system.SetSpringDamping(p.SpringDamping);
  system.SetIntegrator(p.Integrator);
  m_Report.FallTime = fallTime;
  system.SetTimeStep(p.TimeStep > 0.0 ? p.TimeStep : AutomaticTimeStep(system, p.Integrator, p, fallTime));

  // A run resumed from a saved state.
  bool resumedAfterUnroll = false;
  if (!m_InitialPositions.empty())
  {
    if (m_InitialPositions.size() != 3 * system.GetNumberOfParticles() ||
        (!m_InitialVelocities.empty() && m_InitialVelocities.size() != m_InitialPositions.size()))
    {
      itkGenericExceptionMacro(<< "mass-spring flattening: the initial state holds " << m_InitialPositions.size() / 3
                               << " particles, the simulated sheet " << system.GetNumberOfParticles());
    }
    system.SetPositions(m_InitialPositions);
    if (!m_InitialVelocities.empty())
    {
      system.SetVelocities(m_InitialVelocities);
    }
    resumedAfterUnroll = m_InitialPhase != SheetFlatteningPhaseEnum::Unroll;
  }

  // 1. Unroll: hold the edge, gravity across it towards the sheet.
  if (!locked.empty() && !resumedAfterUnroll)
  {
    system.SetLockedParticles(locked);
    const Vec3 down = HangingDirection(system, locked, extent);
    system.SetGravity({ gravity * down.x(), gravity * down.y(), gravity * down.z() });
    auto planar = [&system, &p, &simulated]() { return HangsFlat(system, simulated, p.PlanarityTolerance); };
    m_Report.Phases.push_back(RunPhase(system, SheetFlatteningPhaseEnum::Unroll, p, m_Callback, m_PhaseEnd, planar));
  }

  // 2. Flatten: a plane under the sheet, gravity towards it, nothing held.
  {
    Vec3                  centroid;
    const Eigen::Matrix3d axes = PrincipalAxes(system.GetPositions(), centroid);
    const Vec3            normal = axes.col(2);
    double                lowest = 0.0;
    for (size_t i = 0; i < system.GetNumberOfParticles(); ++i)
    {
      lowest = std::min(lowest, (PointOf(system.GetPositions(), i) - centroid).dot(normal));
    }
    const Vec3 planePoint = centroid + lowest * normal;
    system.UnlockAll();
    system.SetCollisionPlane(
      { planePoint.x(), planePoint.y(), planePoint.z() }, { normal.x(), normal.y(), normal.z() }, p.Restitution);
    system.SetGravity({ -gravity * normal.x(), -gravity * normal.y(), -gravity * normal.z() });
    m_Report.Phases.push_back(RunPhase(system, SheetFlatteningPhaseEnum::Flatten, p, m_Callback, m_PhaseEnd));

    // 3. Relax on the plane, expressed in its own coordinates.
    system.SetPositions(ToPlane(system.GetPositions(), planePoint, axes.col(0), axes.col(1)));
    system.SetVelocities(std::vector<double>(3 * system.GetNumberOfParticles(), 0.0));
    m_Report.Phases.push_back(RunRelaxation(system, SheetFlatteningPhaseEnum::Relax, p, m_Callback));
  }
  m_Report.SpringEvaluations += system.GetNumberOfForceEvaluations() * system.GetNumberOfSprings();

  // The simulated level's flat positions carried to the whole sheet, relaxed there, its
  // rows straightened, in the final frame.
  auto finish = [&](const std::vector<double> & simulatedFlat, double & rowBend) {
    SheetMesh whole = surface;
    if (factor == 1)
    {
      whole.Points = simulatedFlat;
    }
    else
    {
      const std::vector<double> prolonged = CoarseToFine::Prolong(surface, simulated, factor, simulatedFlat);
      MassSpringSystem          fine;
      BuildSystem(surface, p, fine);
      fine.SetPositions(prolonged);
      m_Report.Springs = fine.GetNumberOfSprings();
      m_Report.Phases.push_back(RunRelaxation(fine, SheetFlatteningPhaseEnum::RelaxFull, p, m_Callback));
      m_Report.SpringEvaluations += fine.GetNumberOfForceEvaluations() * fine.GetNumberOfSprings();
      whole.Points = fine.GetPositions();
    }
    rowBend = p.StraightenRows != 0 ? FlatFrame::StraightenRows(whole) : 0.0;
    FlatFrame::Normalise(whole);
    return whole;
  };
  SheetMesh flat = finish(system.GetPositions(), m_Report.RowBend);
  m_Report.FlippedTriangles = FlatFrame::TurnedOverTriangles(flat);

  // 5. A sheet that came out folded (a long roll whose unrolling stopped at its step
  // limit, pressed onto the plane as it hung) starts again from its rows developed onto
  // the plane, fold-free, and is relaxed from there; the flat mesh with fewer triangles
  // turned over is kept.
  if (p.RestartFromDevelopedRows != 0 && m_Report.FlippedTriangles > 0 && simulated.IsGridStructured())
  {
    MassSpringSystem restart;
    BuildSystem(simulated, p, restart);
    restart.SetPositions(simulated.ComputeGridLayout().Points);
    m_Report.Phases.push_back(RunRelaxation(restart, SheetFlatteningPhaseEnum::Relax, p, m_Callback));
    m_Report.SpringEvaluations += restart.GetNumberOfForceEvaluations() * restart.GetNumberOfSprings();
    double          bend = 0.0;
    const SheetMesh again = finish(restart.GetPositions(), bend);
    const size_t    flipped = FlatFrame::TurnedOverTriangles(again);
    m_Report.FlippedBeforeRestart = m_Report.FlippedTriangles;
    m_Report.RestartKept = flipped < m_Report.FlippedTriangles;
    if (m_Report.RestartKept)
    {
      flat = again;
      m_Report.RowBend = bend;
      m_Report.FlippedTriangles = flipped;
    }
  }
  AddWarnings(m_Report, flat.GetNumberOfTriangles());
  m_Report.Seconds = Seconds(start);
  return flat;
}

double
MassSpringSheetFlattener::AutomaticTimeStep(const MassSpringSystem &               system,
                                            MassSpringIntegratorEnum               integrator,
                                            const MassSpringFlatteningParameters & parameters,
                                            double                                 fallTime)
{
  if (integrator == MassSpringIntegratorEnum::ImplicitEuler)
  {
    return fallTime / parameters.StepsPerFallTime;
  }
  const double bound = integrator == MassSpringIntegratorEnum::RungeKutta4 ? 2.83 : 2.0;
  return parameters.TimeStepSafety * bound / system.EstimateMaximumAngularFrequency();
}

std::vector<uint32_t>
MassSpringSheetFlattener::EdgeParticles(const SheetMesh & mesh, SheetLockedEdgeEnum edge)
{
  if (edge != SheetLockedEdgeEnum::OuterEdge && edge != SheetLockedEdgeEnum::InnerEdge)
  {
    itkGenericExceptionMacro(<< "EdgeParticles: the edge must be outer or inner, not " << ToString(edge));
  }
  return GridEdgeParticles(mesh, edge);
}

void
MassSpringSheetFlattener::SetInitialState(SheetFlatteningPhaseEnum    phase,
                                          const std::vector<double> & positions,
                                          const std::vector<double> & velocities)
{
  if (phase != SheetFlatteningPhaseEnum::Unroll && phase != SheetFlatteningPhaseEnum::Flatten)
  {
    itkGenericExceptionMacro(<< "mass-spring flattening: a run resumes in the unroll or flatten phase, not "
                             << ToString(phase));
  }
  if (positions.empty() || positions.size() % 3 != 0 ||
      !std::all_of(positions.begin(), positions.end(), [](double c) { return std::isfinite(c); }))
  {
    itkGenericExceptionMacro(<< "mass-spring flattening: an initial state needs 3 finite coordinates per particle");
  }
  m_InitialPhase = phase;
  m_InitialPositions = positions;
  m_InitialVelocities = velocities;
}

void
MassSpringSheetFlattener::ApplyWave(MassSpringSystem & system, double speed)
{
  const size_t n = system.GetNumberOfParticles();
  if (n == 0 || !std::isfinite(speed))
  {
    return;
  }
  Vec3                  centroid;
  const Eigen::Matrix3d axes = PrincipalAxes(system.GetPositions(), centroid);
  const Vec3            normal = axes.col(2);
  // Distances from the held particles' centroid (the sheet's, when nothing is held).
  Vec3   anchor = Vec3::Zero();
  size_t held = 0;
  for (size_t i = 0; i < n; ++i)
  {
    if (system.IsLocked(static_cast<uint32_t>(i)))
    {
      anchor += PointOf(system.GetPositions(), i);
      ++held;
    }
  }
  anchor = held > 0 ? Vec3(anchor / static_cast<double>(held)) : centroid;
  std::vector<double> distance(n);
  double              farthest = 0.0;
  for (size_t i = 0; i < n; ++i)
  {
    distance[i] = (PointOf(system.GetPositions(), i) - anchor).norm();
    farthest = std::max(farthest, distance[i]);
  }
  std::vector<double> v = system.GetVelocities();
  for (size_t i = 0; i < n; ++i)
  {
    if (system.IsLocked(static_cast<uint32_t>(i)))
    {
      continue;
    }
    const double s = held > 0 && farthest > 0.0 ? speed * distance[i] / farthest : speed;
    for (unsigned d = 0; d < 3; ++d)
    {
      v[3 * i + d] += s * normal[d];
    }
  }
  system.SetVelocities(v);
}

} // end namespace itk

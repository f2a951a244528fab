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
#include "vuWorkbenchSession.h"

#include "vuOutput.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <stdexcept>

namespace vu {
namespace {
constexpr const char * Format = "virtual-unwrap-workbench-session";

nlohmann::json
MeshJson(const itk::SheetMesh & mesh)
{
  return { { "points", mesh.Points },
           { "triangles", mesh.Triangles },
           { "grid_index", mesh.GridIndex },
           { "grid_rows", mesh.GridRows },
           { "grid_columns", mesh.GridColumns } };
}

itk::SheetMesh
MeshFromJson(const nlohmann::json & json, const std::string & what)
{
  itk::SheetMesh mesh;
  json.at("points").get_to(mesh.Points);
  json.at("triangles").get_to(mesh.Triangles);
  json.at("grid_index").get_to(mesh.GridIndex);
  json.at("grid_rows").get_to(mesh.GridRows);
  json.at("grid_columns").get_to(mesh.GridColumns);
  mesh.Validate(what);
  return mesh;
}

nlohmann::json
ControlsJson(const SimulationControls & c)
{
  return { { "integrator", itk::ToString(c.Integrator) },
           { "time_step", c.TimeStep },
           { "damping", c.Damping },
           { "stiffness_scale", c.StiffnessScale },
           { "gravity_scale", c.GravityScale },
           { "restitution", c.Restitution },
           { "auto_advance", c.AutoAdvance } };
}

SimulationControls
ControlsFromJson(const nlohmann::json & json)
{
  SimulationControls c;
  c.Integrator = itk::MassSpringIntegratorFromString(json.at("integrator").get<std::string>());
  json.at("time_step").get_to(c.TimeStep);
  json.at("damping").get_to(c.Damping);
  json.at("stiffness_scale").get_to(c.StiffnessScale);
  json.at("gravity_scale").get_to(c.GravityScale);
  json.at("restitution").get_to(c.Restitution);
  json.at("auto_advance").get_to(c.AutoAdvance);
  if (!(c.TimeStep >= 0.0) || !(c.StiffnessScale > 0.0) || !(c.GravityScale >= 0.0) ||
      !(c.Restitution >= 0.0 && c.Restitution <= 1.0))
  {
    throw std::runtime_error("impossible simulation controls");
  }
  return c;
}
} // namespace

void
WriteSession(const std::string & path, const Session & s)
{
  nlohmann::json json;
  json["format"] = Format;
  json["version"] = 1;
  json["source"] = { { "kind", s.Source.Kind },
                     { "scan", s.Source.ScanPath },
                     { "mesh", s.Source.MeshPath },
                     { "output_folder", s.Source.OutputFolder } };
  json["surface"] = MeshJson(s.Source.Surface);
  if (s.Source.Flat.GetNumberOfPoints() > 0)
  {
    json["flat_points"] = s.Source.Flat.Points;
  }
  json["controls"] = ControlsJson(s.Controls);
  json["focal_plane"] = { { "offset", s.Plane.Offset },
                          { "layers", s.Plane.Layers },
                          { "spacing", s.Plane.Spacing },
                          { "filter", s.Plane.Filter } };
  json["locked"] = s.Locked;
  if (s.HasState)
  {
    json["state"] = { { "phase", itk::ToString(s.State.Phase) },
                      { "step", s.State.Step },
                      { "positions", s.State.Positions },
                      { "velocities", s.State.Velocities },
                      { "locked", s.State.Locked },
                      { "controls", ControlsJson(s.State.Controls) } };
  }
  json["object_transform"] = s.ObjectTransform;
  if (s.HasCamera)
  {
    json["camera"] = s.Camera;
  }
  WriteTextFileAtomically(path, json.dump());
}

Session
ReadSession(const std::string & path)
{
  std::ifstream in(path);
  if (!in)
  {
    throw std::runtime_error("cannot open the session file " + path);
  }
  Session s;
  try
  {
    const nlohmann::json json = nlohmann::json::parse(in);
    if (json.value("format", std::string()) != Format)
    {
      throw std::runtime_error("not a workbench session file");
    }
    const auto & source = json.at("source");
    source.at("kind").get_to(s.Source.Kind);
    source.at("scan").get_to(s.Source.ScanPath);
    source.at("mesh").get_to(s.Source.MeshPath);
    source.at("output_folder").get_to(s.Source.OutputFolder);
    s.Source.Surface = MeshFromJson(json.at("surface"), "the session's sheet mesh");
    const size_t coordinates = s.Source.Surface.Points.size();
    if (json.contains("flat_points"))
    {
      s.Source.Flat = s.Source.Surface;
      json.at("flat_points").get_to(s.Source.Flat.Points);
      if (s.Source.Flat.Points.size() != coordinates)
      {
        throw std::runtime_error("the flat mesh does not match the sheet");
      }
    }
    s.Controls = ControlsFromJson(json.at("controls"));
    const auto & plane = json.at("focal_plane");
    plane.at("offset").get_to(s.Plane.Offset);
    plane.at("layers").get_to(s.Plane.Layers);
    plane.at("spacing").get_to(s.Plane.Spacing);
    plane.at("filter").get_to(s.Plane.Filter);
    json.at("locked").get_to(s.Locked);
    for (uint32_t id : s.Locked)
    {
      if (id >= coordinates / 3)
      {
        throw std::runtime_error("a locked particle does not exist");
      }
    }
    if (json.contains("state"))
    {
      const auto & state = json.at("state");
      s.HasState = true;
      const std::string phase = state.at("phase").get<std::string>();
      s.State.Phase =
        phase == "unroll" ? itk::SheetFlatteningPhaseEnum::Unroll : itk::SheetFlatteningPhaseEnum::Flatten;
      state.at("step").get_to(s.State.Step);
      state.at("positions").get_to(s.State.Positions);
      state.at("velocities").get_to(s.State.Velocities);
      state.at("locked").get_to(s.State.Locked);
      s.State.Controls = ControlsFromJson(state.at("controls"));
      if (s.State.Positions.size() != coordinates ||
          (!s.State.Velocities.empty() && s.State.Velocities.size() != coordinates) ||
          (!s.State.Locked.empty() && s.State.Locked.size() != coordinates / 3))
      {
        throw std::runtime_error("the simulation state does not match the sheet");
      }
    }
    json.at("object_transform").get_to(s.ObjectTransform);
    if (json.contains("camera"))
    {
      s.HasCamera = true;
      json.at("camera").get_to(s.Camera);
    }
  }
  catch (const nlohmann::json::exception & e)
  {
    throw std::runtime_error("the session file " + path + " is damaged: " + e.what());
  }
  catch (const itk::ExceptionObject & e)
  {
    throw std::runtime_error("the session file " + path + " is damaged: " + e.GetDescription());
  }
  catch (const std::runtime_error & e)
  {
    throw std::runtime_error("the session file " + path + ": " + e.what());
  }
  return s;
}
} // namespace vu

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
#include "vuCgalParameterize.h"

#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

namespace vu {
std::string
CgalParameterize(const std::vector<double> &   points,
                 const std::vector<uint32_t> & triangles,
                 const std::string &           method,
                 std::vector<double> &         uv)
{
  using Kernel = CGAL::Simple_cartesian<double>;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  using Vertex = Mesh::Vertex_index;
  namespace SMP = CGAL::Surface_mesh_parameterization;

  Mesh                mesh;
  std::vector<Vertex> vertices;
  vertices.reserve(points.size() / 3);
  for (size_t i = 0; i < points.size() / 3; ++i)
  {
    vertices.push_back(mesh.add_vertex(Kernel::Point_3(points[3 * i], points[3 * i + 1], points[3 * i + 2])));
  }
  for (size_t t = 0; t < triangles.size() / 3; ++t)
  {
    if (mesh.add_face(vertices[triangles[3 * t]], vertices[triangles[3 * t + 1]], vertices[triangles[3 * t + 2]]) ==
        Mesh::null_face())
    {
      return "CGAL refused triangle " + std::to_string(t);
    }
  }
  const auto      border = CGAL::Polygon_mesh_processing::longest_border(mesh).first;
  auto            uvMap = mesh.add_property_map<Vertex, Kernel::Point_2>("v:uv").first;
  SMP::Error_code error = SMP::OK;
  if (method == "lscm")
  {
    error = SMP::parameterize(mesh, SMP::LSCM_parameterizer_3<Mesh>(), border, uvMap);
  }
  else if (method == "arap")
  {
    error = SMP::parameterize(mesh, SMP::ARAP_parameterizer_3<Mesh>(), border, uvMap);
  }
  else
  {
    return "unknown CGAL method " + method;
  }
  if (error != SMP::OK)
  {
    return SMP::get_error_message(error);
  }
  uv.assign(points.size(), 0.0);
  for (size_t i = 0; i < vertices.size(); ++i)
  {
    uv[3 * i] = uvMap[vertices[i]].x();
    uv[3 * i + 1] = uvMap[vertices[i]].y();
  }
  return {};
}
} // namespace vu

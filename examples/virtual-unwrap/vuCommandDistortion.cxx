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
// virtual-unwrap distortion SURFACE FLAT: distortion of a flattening, as JSON.
#include "vuCommands.h"

#include "itkFlatteningDistortionCalculator.h"
#include "itkMesh.h"
#include "itkMeshFileReader.h"
#include "itkSheetMeshAdaptor.h"

#include <filesystem>

namespace vu {
namespace {
itk::SheetMesh
ReadSheetMesh(const std::string & path)
{
  if (!std::filesystem::is_regular_file(path))
  {
    throw UsageError("mesh file not found: " + path);
  }
  using MeshType = itk::Mesh<float, 3>;
  auto reader = itk::MeshFileReader<MeshType>::New();
  reader->SetFileName(path);
  reader->Update();
  itk::SheetMesh sheet = itk::MeshToSheetMesh(reader->GetOutput());
  sheet.Validate(path);
  return sheet;
}
} // namespace

void
RegisterDistortionCommand(CLI::App & app)
{
  auto *             command = app.add_subcommand("distortion",
                                      "Distortion of a flattening: compare a 3D sheet mesh with its flat "
                                                  "version (same points and triangles), print JSON.");
  static std::string surfacePath, flatPath, outputPath;
  command->add_option("SURFACE", surfacePath, "3D sheet mesh (OBJ, VTK, OFF, ...)")->required();
  command->add_option("FLAT", flatPath, "flattened mesh with the same points and triangles; z is ignored")->required();
  command->add_option("-o,--output", outputPath, "write the JSON to this file instead of standard output");
  command->callback([] {
    auto calculator = itk::FlatteningDistortionCalculator::New();
    calculator->SetSurfaceMesh(ReadSheetMesh(surfacePath));
    calculator->SetFlatMesh(ReadSheetMesh(flatPath));
    calculator->Compute();
    nlohmann::json json;
    json["edge_strain"] = { { "mean", calculator->GetEdgeStrainMean() },
                            { "p95", calculator->GetEdgeStrainP95() },
                            { "max", calculator->GetEdgeStrainMax() } };
    json["area_distortion"] = calculator->GetAreaDistortion();
    json["total_area_ratio"] = calculator->GetTotalAreaRatio();
    json["angle_distortion_degrees"] = calculator->GetAngleDistortionDegrees();
    json["l2_stretch"] = calculator->GetL2Stretch();
    json["linf_stretch"] = calculator->GetLinfStretch();
    json["flipped_triangles"] = calculator->GetNumberOfFlippedTriangles();
    json["degenerate_flat_triangles"] = calculator->GetNumberOfDegenerateFlatTriangles();
    json["edges"] = calculator->GetNumberOfEdges();
    EmitJson(json, outputPath);
  });
}
} // namespace vu

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
#include "vuWorkbenchScene.h"

#include "itkCTVolumeReader.h"
#include "itkFlattenedTextureImageFilter.h"
#include "itkMesh.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSheetSegmentationImageFilter.h"
#include "vuReaderOptions.h"
#include "vuSheetMeshIO.h"
#include "vuTextureOutput.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace vu {
namespace fs = std::filesystem;
namespace {
using MaskType = itk::Image<unsigned char, 3>;
using MeshType = itk::Mesh<double, 3>;

// Reports a filter's progress as the part [from, to] of the job and aborts it when the job
// is cancelled (the filter then throws itk::ProcessAborted).
void
Observe(itk::ProcessObject * filter, Job & job, double from, double to)
{
  filter->AddObserver(itk::ProgressEvent(), [filter, &job, from, to](const itk::EventObject &) {
    job.Progress = from + (to - from) * filter->GetProgress();
    if (job.Cancel)
    {
      filter->AbortGenerateDataOn();
    }
  });
}

void
ThrowIfCancelled(const Job & job)
{
  if (job.Cancel)
  {
    throw std::runtime_error("cancelled");
  }
}

WorkbenchVolume::Pointer
ReadVolume(const std::string & path, Job & job, double from, double to, std::vector<std::string> & warnings)
{
  job.SetStage("reading " + path);
  auto reader = itk::CTVolumeReader::New();
  ConfigureReader(ReaderOptions(), path, *reader);
  Observe(reader, job, from, to);
  reader->Update();
  for (const auto & w : reader->GetWarnings())
  {
    warnings.push_back("read: " + w);
  }
  WorkbenchVolume::Pointer volume = reader->GetOutput();
  volume->DisconnectPipeline();
  return volume;
}
} // namespace

WorkbenchVolume::Pointer
ReadScanVolume(const std::string & path, Job & job, std::vector<std::string> & warnings)
{
  return ReadVolume(path, job, 0.0, 1.0, warnings);
}

Scene
OpenScan(const std::string & path, Job & job)
{
  Scene scene;
  scene.Kind = "scan";
  scene.ScanPath = path;
  scene.Volume = ReadVolume(path, job, 0.0, 0.3, scene.Warnings);
  ThrowIfCancelled(job);
  // Segmentation and meshing need a value in every voxel (as in the command-line tool).
  const FilledVolume filled = FillVoxelsWithoutData(scene.Volume);
  job.SetStage("segmenting the sheet");
  auto segmentation = itk::SheetSegmentationImageFilter<WorkbenchVolume, MaskType>::New();
  segmentation->SetInput(filled.Volume);
  Observe(segmentation, job, 0.3, 0.6);
  segmentation->Update();
  ThrowIfCancelled(job);
  job.SetStage("meshing the sheet's mid-surface");
  auto surface = itk::SheetMidSurfaceMeshFilter<MaskType, MeshType>::New();
  surface->SetInput(segmentation->GetOutput());
  surface->SetIntensityImage(filled.Volume);
  Observe(surface, job, 0.6, 1.0);
  surface->Update();
  ThrowIfCancelled(job);
  scene.Surface = surface->GetSheetMesh();
  for (const auto & w : surface->GetWarnings())
  {
    scene.Warnings.push_back("mesh: " + w);
  }
  job.Progress = 1.0;
  return scene;
}

Scene
OpenUnwrapOutput(const std::string & folder, Job & job)
{
  const fs::path dir(folder);
  if (!fs::is_directory(dir) || !fs::exists(dir / "surface.vtp"))
  {
    throw std::runtime_error("not an output folder of virtual-unwrap unwrap (no surface.vtp): " + folder);
  }
  Scene scene;
  scene.Kind = "unwrap-output";
  scene.OutputFolder = folder;
  scene.MeshPath = (dir / "surface.vtp").string();
  job.SetStage("reading " + scene.MeshPath);
  scene.Surface = ReadSheetMesh(scene.MeshPath);
  if (fs::exists(dir / "flat.obj"))
  {
    itk::SheetMesh flat = ReadSheetMesh((dir / "flat.obj").string());
    if (itk::HaveSameTopology(flat, scene.Surface))
    {
      scene.Flat = flat;
      scene.Flat.GridIndex = scene.Surface.GridIndex;
      scene.Flat.GridRows = scene.Surface.GridRows;
      scene.Flat.GridColumns = scene.Surface.GridColumns;
    }
    else
    {
      scene.Warnings.push_back("flat.obj does not match surface.vtp; not shown");
    }
  }
  job.Progress = 0.2;
  // The scan named in the report, when it is still there.
  std::ifstream report(dir / "report.json");
  if (report)
  {
    try
    {
      const nlohmann::json json = nlohmann::json::parse(report);
      const std::string    input = json.at("input").at("path").get<std::string>();
      if (fs::exists(input))
      {
        scene.ScanPath = input;
        scene.Volume = ReadVolume(input, job, 0.2, 1.0, scene.Warnings);
      }
      else
      {
        scene.Warnings.push_back("the scan " + input + " named in report.json is not there: no slices, no texture");
      }
    }
    catch (const nlohmann::json::exception & e)
    {
      scene.Warnings.push_back(std::string("report.json unreadable: ") + e.what());
    }
  }
  job.Progress = 1.0;
  return scene;
}

Scene
OpenMeshAndVolume(const std::string & mesh, const std::string & volume, Job & job)
{
  Scene scene;
  scene.Kind = "mesh+volume";
  scene.MeshPath = mesh;
  job.SetStage("reading " + mesh);
  scene.Surface = ReadSheetMesh(mesh);
  scene.Surface.Validate("the sheet mesh " + mesh);
  if (!volume.empty())
  {
    scene.ScanPath = volume;
    scene.Volume = ReadVolume(volume, job, 0.1, 1.0, scene.Warnings);
  }
  job.Progress = 1.0;
  return scene;
}

TextureImage
RenderTexture(const Scene & scene, const itk::SheetMesh & domain, const FocalPlane & plane, Job & job)
{
  if (!scene.Volume)
  {
    throw std::runtime_error("no scan: a texture needs the volume the sheet was traced in");
  }
  if (!itk::HaveSameTopology(domain, scene.Surface))
  {
    throw std::runtime_error("the flat domain does not match the sheet");
  }
  using TextureType = itk::Image<float, 2>;
  using FilterType = itk::FlattenedTextureImageFilter<WorkbenchVolume, TextureType, MeshType>;
  const auto layerFilter = FilterFromName(plane.Filter);
  if (layerFilter == itk::TextureLayersEnums::Filter::SingleLayer && plane.Filter != "single")
  {
    throw std::runtime_error("unknown layer filter: " + plane.Filter);
  }
  auto         filter = FilterType::New();
  const auto   spacing = scene.Volume->GetSpacing();
  const double voxel = std::min({ spacing[0], spacing[1], spacing[2] });
  filter->SetSurfaceMesh(itk::SheetMeshToMesh<MeshType>(scene.Surface));
  filter->SetFlatMesh(itk::SheetMeshToMesh<MeshType>(domain));
  filter->SetVolume(scene.Volume);
  filter->SetPixelSize(voxel); // one voxel: fast enough to follow a slider
  filter->SetNumberOfLayers(std::max(1u, plane.Layers));
  filter->SetLayerSpacing(plane.Spacing > 0.0 ? plane.Spacing : 0.5 * voxel);
  filter->SetFocus(plane.Offset);
  filter->SetLayerFilter(layerFilter);
  Observe(filter, job, 0.0, 1.0);
  job.SetStage("sampling the texture");
  filter->Update();
  const TextureType * texture = filter->GetOutput();
  const auto          size = texture->GetLargestPossibleRegion().GetSize();
  TextureImage        image;
  image.Width = static_cast<unsigned int>(size[0]);
  image.Height = static_cast<unsigned int>(size[1]);
  // The contrast stretch of the tool's texture.png; ITK's index (0, 0) is the lowest x and
  // y, the texture's bottom left in VTK's frame too.
  const auto            eightBit = EightBit(texture);
  const unsigned char * pixels = eightBit->GetBufferPointer();
  image.Pixels.assign(pixels, pixels + static_cast<size_t>(image.Width) * image.Height);
  const auto   origin = texture->GetOrigin();
  const double corner[2] = { origin[0], origin[1] };
  const auto   uv = FlatTextureCoordinates(domain, corner, filter->GetPixelSize(), image.Width, image.Height);
  image.TextureCoordinates.assign(uv.begin(), uv.end());
  job.Progress = 1.0;
  return image;
}
} // namespace vu

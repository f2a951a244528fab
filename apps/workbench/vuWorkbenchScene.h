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
#ifndef vuWorkbenchScene_h
#define vuWorkbenchScene_h

#include "itkImage.h"
#include "itkSheetMesh.h"

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

namespace vu {
/** Progress and cancellation of a long piece of work on another thread. */
class Job
{
public:
  std::atomic<double> Progress{ 0.0 };
  std::atomic<bool>   Cancel{ false };

  void
  SetStage(const std::string & stage)
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    m_Stage = stage;
  }
  std::string
  GetStage() const
  {
    std::lock_guard<std::mutex> lock(m_Mutex);
    return m_Stage;
  }

private:
  mutable std::mutex m_Mutex;
  std::string        m_Stage;
};

using WorkbenchVolume = itk::Image<float, 3>;

/** What the workbench works on: the sheet's mesh and, when known, the scan it was traced
 * in (for the slice view, the texture and the export). */
struct Scene
{
  /** "scan", "unwrap-output" or "mesh+volume". */
  std::string Kind;
  /** The scan (a path the reader takes), the mesh file, the unwrap output folder. */
  std::string              ScanPath, MeshPath, OutputFolder;
  WorkbenchVolume::Pointer Volume;
  itk::SheetMesh           Surface;
  itk::SheetMesh           Flat;
  std::vector<std::string> Warnings;
};

/** Reads a CT scan (anything the command-line tool reads) and traces its sheet with the
 * module's filters and their defaults, as `virtual-unwrap unwrap` does. */
Scene
OpenScan(const std::string & path, Job & job);
/** An output folder of `virtual-unwrap unwrap`: its surface and flat meshes, and the scan
 * named in its report.json when it can still be read. */
Scene
OpenUnwrapOutput(const std::string & folder, Job & job);
/** A sheet mesh (.vtp, .obj, .vtk, ...) and optionally the scan it lies in. */
Scene
OpenMeshAndVolume(const std::string & mesh, const std::string & volume, Job & job);

/** Reads a scan as the command-line tool does (the reader's defaults). */
WorkbenchVolume::Pointer
ReadScanVolume(const std::string & path, Job & job, std::vector<std::string> & warnings);

/** The focal plane of the layered texture: layers about the sheet, offset along its normal. */
struct FocalPlane
{
  double       Offset{ 0.0 };  // mm along the normal
  unsigned int Layers{ 5 };    // samples along the normal
  double       Spacing{ 0.0 }; // mm between them; 0: half the voxel size
  std::string  Filter{ "max" };

  bool
  operator==(const FocalPlane & o) const
  {
    return Offset == o.Offset && Layers == o.Layers && Spacing == o.Spacing && Filter == o.Filter;
  }
};

/** An 8-bit texture over a flat domain (the flat mesh, or the grid's layout before
 * flattening) and the texture coordinates of the domain's points in it. */
struct TextureImage
{
  unsigned int               Width{ 0 }, Height{ 0 };
  std::vector<unsigned char> Pixels;             // row 0 at the bottom (y up), as VTK stores images
  std::vector<float>         TextureCoordinates; // (u, v) per point of the domain
};

/** Samples the scan about `scene.Surface` into an image laid out like `domain` (same
 * points and triangles) with itk::FlattenedTextureImageFilter. */
TextureImage
RenderTexture(const Scene & scene, const itk::SheetMesh & domain, const FocalPlane & plane, Job & job);
} // namespace vu

#endif

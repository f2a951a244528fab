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
#ifndef itkTexturePixelMap_h
#define itkTexturePixelMap_h

#include "VirtualUnwrappingExport.h"
#include "itkIntTypes.h"
#include "itkSheetMesh.h"

#include <array>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace itk {
class ProcessObject;

namespace detail {
/** A std::allocator whose value-initialisation of a new element leaves it uninitialised:
 * the pixel map's buffers are filled by the threads that then write them, each its own band
 * of rows, instead of zeroed by one thread first. */
template <typename T>
struct DefaultInitAllocator : std::allocator<T>
{
  template <typename U>
  struct rebind
  {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U> &) noexcept
  {}
  template <typename U>
  void
  construct(U * p) noexcept(std::is_nothrow_default_constructible<U>::value)
  {
    ::new (static_cast<void *>(p)) U;
  }
  template <typename U, typename... TArguments>
  void
  construct(U * p, TArguments &&... arguments)
  {
    ::new (static_cast<void *>(p)) U(std::forward<TArguments>(arguments)...);
  }
};
} // namespace detail

/** \class TexturePixelMap
 * \brief Where to sample the volume for each pixel of a flattened texture: the 3D point on
 * the sheet and the unit surface normal there, or "off the sheet".
 *
 * The texture grid lies in the flat mesh's x-y plane: pixel (i, j) (column i, row j) has
 * its centre at (Origin[0] + i * PixelSize, Origin[1] + j * PixelSize). Arrays are
 * stored row by row (x fastest). Positions and Normals hold three floats per pixel,
 * meaningful only where Triangle >= 0; Triangle is the index of the flat triangle that
 * covers the pixel centre, or -1 off the sheet. The map depends only on the two meshes and
 * the grid, so one map serves any number of layer settings and filters.
 *
 * Built by ComputeTexturePixelMap().
 *
 * \ingroup VirtualUnwrapping
 */
struct VirtualUnwrapping_EXPORT TexturePixelMap
{
  std::array<SizeValueType, 2>                                Size{ { 0, 0 } };
  std::array<double, 2>                                       Origin{ { 0.0, 0.0 } };
  double                                                      PixelSize{ 1.0 };
  std::vector<float, detail::DefaultInitAllocator<float>>     Positions;
  std::vector<float, detail::DefaultInitAllocator<float>>     Normals;
  std::vector<int32_t, detail::DefaultInitAllocator<int32_t>> Triangle;
  /** Triangles skipped because their 3D or flat area is (numerically) zero. */
  SizeValueType NumberOfDegenerateTriangles{ 0 };
  /** Pixels inside a triangle whose interpolated vertex normal vanishes: left off the
   * sheet. */
  SizeValueType NumberOfZeroNormalPixels{ 0 };

  SizeValueType
  GetNumberOfPixels() const
  {
    return Size[0] * Size[1];
  }
  SizeValueType
  GetNumberOfSheetPixels() const;
};

/** The texture grid that covers the flat mesh's bounding box (x, y) grown by margin on
 * every side, with square pixels of side pixelSize: fills Size, Origin and PixelSize of
 * the returned map and leaves its arrays empty. Throws itk::ExceptionObject when
 * pixelSize is not positive, margin is negative, the mesh is empty or non-finite, or the
 * grid would exceed 2^31 pixels. */
VirtualUnwrapping_EXPORT TexturePixelMap
ComputeTextureGrid(const SheetMesh & flat, double pixelSize, double margin);

/** Rasterises the flat mesh onto the grid of ComputeTextureGrid(flat, pixelSize, margin):
 * each flat triangle visits the pixel centres in its bounding box, keeps those inside it
 * (barycentric test, shared edges covered), and maps them by the same barycentric
 * coordinates to a point of the 3D surface and to the normalised interpolation of the
 * surface's area-weighted vertex normals. With `curved`, the point is placed on the
 * curved sheet the vertices and their normals describe rather than on the flat triangle
 * (Phong tessellation, Boubekeur and Alexa 2008, shape factor 1/2: the barycentric blend
 * of the point's projections onto the corners' tangent planes, halfway from the
 * triangle), which on a roll meshed with the automatic spacing lies inside the sheet by
 * up to its sagitta; on a plane the two coincide.
 *
 * surface and flat must share topology (same point count, same triangles): otherwise,
 * or when either mesh is invalid (SheetMesh::Validate), throws itk::ExceptionObject.
 * Runs in parallel over bands of rows with MultiThreaderBase::ParallelizeArray. When
 * filter is given, its progress moves from progressStart to progressEnd and its
 * AbortGenerateData flag stops the work with itk::ProcessAborted. */
VirtualUnwrapping_EXPORT TexturePixelMap
ComputeTexturePixelMap(const SheetMesh & surface,
                       const SheetMesh & flat,
                       double            pixelSize,
                       double            margin,
                       ProcessObject *   filter = nullptr,
                       float             progressStart = 0.0f,
                       float             progressEnd = 1.0f,
                       bool              curved = false);
} // end namespace itk

#endif

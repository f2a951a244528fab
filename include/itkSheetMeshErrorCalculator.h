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
#ifndef itkSheetMeshErrorCalculator_h
#define itkSheetMeshErrorCalculator_h

#include "VirtualUnwrappingExport.h"
#include "itkObject.h"
#include "itkObjectFactory.h"
#include "itkSheetMesh.h"
#include "itkSheetPhantomGeometry.h"
#include "itkSheetPhantomSource.h"

namespace itk {
/** \class SheetMeshErrorCalculator
 * \brief Measures a sheet mesh against the ground truth of a phantom: how far its
 * vertices lie from the true mid-surface, how much of the true sheet it covers, and how
 * many of its edges jump between turns (the module's "mesh error" measures).
 *
 * - vertex distance: distance of each vertex to the true mid-surface
 *   (SheetPhantomGeometry::Project; beyond the sheet's edges, the distance to the nearest
 *   edge point), in voxels: mean and max;
 * - coverage: the true mid-surface is sampled at cell centres of a grid of half a voxel in
 *   (s, w); coverage is the fraction of samples (of area, the sheet being isometric to
 *   (s, w)) whose distance to the mesh (exact point-to-triangle distance, triangles binned
 *   in a uniform grid) is at most CoverageTolerance voxels;
 * - layer jumps: edges whose two vertices project to arc lengths that differ by more than
 *   twice the edge's 3D length plus four voxels: such an edge joins two different turns
 *   (or panels) of the sheet.
 *
 * Parameters: VoxelSize (mm per voxel, the unit of the reported distances; default 0 must
 * be set, > 0), CoverageTolerance (voxels, default 1, > 0). The geometry is copied.
 * Compute() throws itk::ExceptionObject on an empty geometry, an invalid or empty mesh or
 * a non-positive voxel size or tolerance.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetMeshErrorCalculator : public Object
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(SheetMeshErrorCalculator);

  using Self = SheetMeshErrorCalculator;
  using Superclass = Object;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(SheetMeshErrorCalculator, Object);

  void
  SetGeometry(const SheetPhantomGeometry & geometry);
  void
  SetMesh(const SheetMesh & mesh);
  /** The ground truth of a phantom source (updated or with its output information
   * generated) and a mesh of the wrapped types (see DataObjectToSheetMesh): the setters
   * Python uses. */
  void
  SetPhantom(const SheetPhantomSource * phantom);
  void
  SetMesh(const DataObject * mesh);
  itkSetMacro(VoxelSize, double);
  itkGetConstMacro(VoxelSize, double);
  itkSetMacro(CoverageTolerance, double);
  itkGetConstMacro(CoverageTolerance, double);

  void
  Compute();

  /** Vertex distances to the true mid-surface, voxels. */
  itkGetConstMacro(MeanVertexDistance, double);
  itkGetConstMacro(MaximumVertexDistance, double);
  /** Fraction (0..1) of the true sheet area within CoverageTolerance of the mesh. */
  itkGetConstMacro(Coverage, double);
  itkGetConstMacro(NumberOfLayerJumps, SizeValueType);
  itkGetConstMacro(NumberOfEdges, SizeValueType);
  /** Vertices whose closest true point lies beyond the sheet's edges. */
  itkGetConstMacro(NumberOfVerticesBeyondSheet, SizeValueType);

protected:
  SheetMeshErrorCalculator() = default;
  ~SheetMeshErrorCalculator() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  SheetPhantomGeometry m_Geometry;
  SheetMesh            m_Mesh;
  double               m_VoxelSize{ 0.0 };
  double               m_CoverageTolerance{ 1.0 };

  double        m_MeanVertexDistance{ 0.0 };
  double        m_MaximumVertexDistance{ 0.0 };
  double        m_Coverage{ 0.0 };
  SizeValueType m_NumberOfLayerJumps{ 0 };
  SizeValueType m_NumberOfEdges{ 0 };
  SizeValueType m_NumberOfVerticesBeyondSheet{ 0 };
};
} // end namespace itk

#endif

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
#ifndef itkFlatteningDistortionCalculator_h
#define itkFlatteningDistortionCalculator_h

#include "VirtualUnwrappingExport.h"
#include "itkDataObject.h"
#include "itkObject.h"
#include "itkObjectFactory.h"
#include "itkSheetMesh.h"

namespace itk {
/** \class FlatteningDistortionCalculator
 * \brief Measures how much a flattening distorts a sheet: compares a 3D mesh with its
 * flattened version (same points, same triangles; only x and y of the flat mesh count).
 *
 * Measures, named as in the module's design document:
 * - edge strain |l_flat - l_3d| / l_3d over unique edges: mean, 95th percentile, max;
 * - area distortion |A_flat / A_3d - 1|, mean weighted by 3D area, and the total area
 *   ratio sum(A_flat) / sum(A_3d);
 * - angle distortion: mean absolute difference of triangle corner angles, in degrees;
 * - L2 and Linf stretch of Sander, Snyder, Gortler and Hoppe, "Texture mapping progressive
 *   meshes" (SIGGRAPH 2001), of the map from the flat mesh to the 3D mesh, without area
 *   renormalisation (the flat mesh is in physical units, so an isometry gives 1 and 1);
 * - flipped triangles: those whose 2D orientation disagrees with the majority; triangles
 *   of zero flat area are counted as degenerate.
 *
 * Triangles of zero 3D area are skipped and counted (GetNumberOfDegenerate3DTriangles).
 * Compute() throws itk::ExceptionObject when the meshes do not share topology or contain
 * invalid indices or non-finite coordinates.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT FlatteningDistortionCalculator : public Object
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(FlatteningDistortionCalculator);

  using Self = FlatteningDistortionCalculator;
  using Superclass = Object;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(FlatteningDistortionCalculator, Object);

  /** The sheet as a 3D surface (rest shape). */
  void
  SetSurfaceMesh(const SheetMesh & mesh);
  /** The flattened sheet; z is ignored. */
  void
  SetFlatMesh(const SheetMesh & mesh);
  /** The same from itk::Mesh<float, 3>, itk::Mesh<double, 3> or itk::QuadEdgeMesh<double, 3>
   * (see DataObjectToSheetMesh); these are the setters Python uses. */
  void
  SetSurfaceMesh(const DataObject * mesh);
  void
  SetFlatMesh(const DataObject * mesh);

  void
  Compute();

  itkGetConstMacro(EdgeStrainMean, double);
  itkGetConstMacro(EdgeStrainP95, double);
  itkGetConstMacro(EdgeStrainMax, double);
  itkGetConstMacro(AreaDistortion, double);
  itkGetConstMacro(TotalAreaRatio, double);
  itkGetConstMacro(AngleDistortionDegrees, double);
  itkGetConstMacro(L2Stretch, double);
  itkGetConstMacro(LinfStretch, double);
  itkGetConstMacro(NumberOfFlippedTriangles, SizeValueType);
  itkGetConstMacro(NumberOfDegenerateFlatTriangles, SizeValueType);
  itkGetConstMacro(NumberOfDegenerate3DTriangles, SizeValueType);
  itkGetConstMacro(NumberOfEdges, SizeValueType);

protected:
  FlatteningDistortionCalculator() = default;
  ~FlatteningDistortionCalculator() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  SheetMesh m_SurfaceMesh;
  SheetMesh m_FlatMesh;

  double        m_EdgeStrainMean{ 0.0 };
  double        m_EdgeStrainP95{ 0.0 };
  double        m_EdgeStrainMax{ 0.0 };
  double        m_AreaDistortion{ 0.0 };
  double        m_TotalAreaRatio{ 1.0 };
  double        m_AngleDistortionDegrees{ 0.0 };
  double        m_L2Stretch{ 1.0 };
  double        m_LinfStretch{ 1.0 };
  SizeValueType m_NumberOfFlippedTriangles{ 0 };
  SizeValueType m_NumberOfDegenerateFlatTriangles{ 0 };
  SizeValueType m_NumberOfDegenerate3DTriangles{ 0 };
  SizeValueType m_NumberOfEdges{ 0 };
};
} // end namespace itk

#endif

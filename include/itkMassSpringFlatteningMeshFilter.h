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
#ifndef itkMassSpringFlatteningMeshFilter_h
#define itkMassSpringFlatteningMeshFilter_h

#include "itkMassSpringSheetFlattener.h"
#include "itkMesh.h"
#include "itkMeshToMeshFilter.h"

#include <ostream>

namespace itk {
/** \class MassSpringFlatteningMeshFilter
 * \brief Unrolls and flattens a sheet mesh by the physically based mass-spring simulation
 * of Seales and Lin (2004): Mesh -> Mesh of the same points and triangles, flat.
 *
 * The input is a triangle mesh of one sheet (itk::Mesh or itk::QuadEdgeMesh, 3D), for
 * instance the mid-surface mesh of a rolled sheet; when its meta-data carries the sheet
 * grid (see itkSheetMeshAdaptor.h), the grid's end column can be held to unroll it and the
 * simulation can run on a coarser grid. The output has the same points (same order) and
 * the same triangles, with z = 0: its x and y are the flattened sheet coordinates in the
 * input's units (mm), i.e. the UV coordinates that FlattenedTextureImageFilter reads. The
 * input's point data and sheet grid are carried over.
 *
 * The work is done by MassSpringSheetFlattener (see it for the model, the phases and every
 * parameter); this filter exposes its parameters, with the same names, defaults and ranges:
 * Integrator (ImplicitEuler), TimeStep (0: automatic), StepsPerFallTime (40),
 * TimeStepSafety (0.5), Stiffness (1),
 * ShearStiffnessRatio (0.5), BendingStiffnessRatio (0: off), Density (1), Gravity
 * (0: automatic), HangingStrain (0.01), Damping (-1: automatic), SpringDamping (0),
 * Restitution (0.1, in [0, 1]), LockedEdge (OuterEdge), LockedParticles,
 * MaximumStepsPerPhase (3000), KineticEnergyTolerance (1e-9), ResidualForceTolerance
 * (1e-3), PlanarityTolerance (0.25), RelaxationIterations (300), RelaxationTolerance (1e-5), CoarseningFactor
 * (0: automatic), CoarseParticles (3000).
 *
 * Events: an IterationEvent after every simulation step (observers may read
 * GetCurrentSystem() positions, GetCurrentPhase(), GetCurrentStep(), and may lock or unlock
 * particles or change damping, time step or integrator through GetCurrentSystem()),
 * ProgressEvent, and abort through AbortGenerateData (throws ProcessAborted). A diverging
 * run throws an ExceptionObject naming the integrator, the step and the time step; no
 * output is produced. GetReport() tells what each phase did.
 *
 * \ingroup VirtualUnwrapping
 */
template <typename TInputMesh, typename TOutputMesh = TInputMesh>
class ITK_TEMPLATE_EXPORT MassSpringFlatteningMeshFilter : public MeshToMeshFilter<TInputMesh, TOutputMesh>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(MassSpringFlatteningMeshFilter);

  using Self = MassSpringFlatteningMeshFilter;
  using Superclass = MeshToMeshFilter<TInputMesh, TOutputMesh>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  itkNewMacro(Self);
  itkTypeMacro(MassSpringFlatteningMeshFilter, MeshToMeshFilter);

  using InputMeshType = TInputMesh;
  using OutputMeshType = TOutputMesh;
  using IntegratorEnum = MassSpringIntegratorEnum;
  using LockedEdgeEnum = SheetLockedEdgeEnum;

  itkSetEnumMacro(Integrator, IntegratorEnum);
  itkGetEnumMacro(Integrator, IntegratorEnum);
  itkSetClampMacro(TimeStep, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(TimeStep, double);
  itkSetClampMacro(StepsPerFallTime, double, 1e-3, NumericTraits<double>::max());
  itkGetConstMacro(StepsPerFallTime, double);
  itkSetClampMacro(TimeStepSafety, double, 1e-6, 100.0);
  itkGetConstMacro(TimeStepSafety, double);
  itkSetClampMacro(Stiffness, double, 1e-12, NumericTraits<double>::max());
  itkGetConstMacro(Stiffness, double);
  itkSetClampMacro(ShearStiffnessRatio, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(ShearStiffnessRatio, double);
  itkSetClampMacro(BendingStiffnessRatio, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(BendingStiffnessRatio, double);
  itkSetClampMacro(Density, double, 1e-12, NumericTraits<double>::max());
  itkGetConstMacro(Density, double);
  itkSetClampMacro(Gravity, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(Gravity, double);
  itkSetClampMacro(HangingStrain, double, 1e-9, 1.0);
  itkGetConstMacro(HangingStrain, double);
  itkSetMacro(Damping, double);
  itkGetConstMacro(Damping, double);
  itkSetClampMacro(SpringDamping, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(SpringDamping, double);
  itkSetClampMacro(Restitution, double, 0.0, 1.0);
  itkGetConstMacro(Restitution, double);
  itkSetEnumMacro(LockedEdge, LockedEdgeEnum);
  itkGetEnumMacro(LockedEdge, LockedEdgeEnum);
  itkSetClampMacro(MaximumStepsPerPhase, unsigned int, 1, NumericTraits<unsigned int>::max());
  itkGetConstMacro(MaximumStepsPerPhase, unsigned int);
  itkSetClampMacro(KineticEnergyTolerance, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(KineticEnergyTolerance, double);
  itkSetClampMacro(ResidualForceTolerance, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(ResidualForceTolerance, double);
  itkSetClampMacro(PlanarityTolerance, double, 1e-9, NumericTraits<double>::max());
  itkGetConstMacro(PlanarityTolerance, double);
  itkSetClampMacro(RelaxationIterations, unsigned int, 1, NumericTraits<unsigned int>::max());
  itkGetConstMacro(RelaxationIterations, unsigned int);
  itkSetClampMacro(RelaxationTolerance, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(RelaxationTolerance, double);
  itkSetMacro(CoarseningFactor, unsigned int);
  itkGetConstMacro(CoarseningFactor, unsigned int);
  itkSetClampMacro(CoarseParticles, unsigned int, 4, NumericTraits<unsigned int>::max());
  itkGetConstMacro(CoarseParticles, unsigned int);

  /** Particles held during the unroll phase when LockedEdge is Custom. */
  void
  SetLockedParticles(const std::vector<uint32_t> & particles)
  {
    if (particles != m_LockedParticles)
    {
      m_LockedParticles = particles;
      this->Modified();
    }
  }
  const std::vector<uint32_t> &
  GetLockedParticles() const
  {
    return m_LockedParticles;
  }

  /** The parameters as MassSpringSheetFlattener takes them. */
  MassSpringFlatteningParameters
  GetParameters() const;

  /** During an update (from an IterationEvent observer): the running system, its phase
   * ("unroll", "flatten", "relax", "relax-full") and the step within the phase. */
  MassSpringSystem *
  GetCurrentSystem() const
  {
    return m_CurrentSystem;
  }
  const std::string &
  GetCurrentPhase() const
  {
    return m_CurrentPhase;
  }
  uint64_t
  GetCurrentStep() const
  {
    return m_CurrentStep;
  }

  /** What the last update did. */
  const MassSpringFlatteningReport &
  GetReport() const
  {
    return m_Report;
  }

protected:
  MassSpringFlatteningMeshFilter() = default;
  ~MassSpringFlatteningMeshFilter() override = default;

  void
  GenerateData() override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  IntegratorEnum        m_Integrator{ IntegratorEnum::ImplicitEuler };
  double                m_TimeStep{ 0.0 };
  double                m_TimeStepSafety{ 0.5 };
  double                m_StepsPerFallTime{ 40.0 };
  double                m_Stiffness{ 1.0 };
  double                m_ShearStiffnessRatio{ 0.5 };
  double                m_BendingStiffnessRatio{ 0.0 };
  double                m_Density{ 1.0 };
  double                m_Gravity{ 0.0 };
  double                m_HangingStrain{ 0.01 };
  double                m_Damping{ -1.0 };
  double                m_SpringDamping{ 0.0 };
  double                m_Restitution{ 0.1 };
  LockedEdgeEnum        m_LockedEdge{ LockedEdgeEnum::OuterEdge };
  std::vector<uint32_t> m_LockedParticles;
  unsigned int          m_MaximumStepsPerPhase{ 3000 };
  double                m_KineticEnergyTolerance{ 1e-9 };
  double                m_ResidualForceTolerance{ 1e-3 };
  double                m_PlanarityTolerance{ 0.25 };
  unsigned int          m_RelaxationIterations{ 300 };
  double                m_RelaxationTolerance{ 1e-5 };
  unsigned int          m_CoarseningFactor{ 0 };
  unsigned int          m_CoarseParticles{ 3000 };

  MassSpringFlatteningReport m_Report;
  MassSpringSystem *         m_CurrentSystem{ nullptr };
  std::string                m_CurrentPhase;
  uint64_t                   m_CurrentStep{ 0 };
};

/** Printing for ITK's Set/Get debug output and PrintSelf. */
inline std::ostream &
operator<<(std::ostream & os, MassSpringIntegratorEnum e)
{
  return os << ToString(e);
}
inline std::ostream &
operator<<(std::ostream & os, SheetLockedEdgeEnum e)
{
  return os << ToString(e);
}
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkMassSpringFlatteningMeshFilter.hxx"
#endif

#endif

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
 * The work is done by MassSpringSheetFlattener (see it for the model and the phases); this
 * filter exposes its parameters with the same names, defaults and ranges: Integrator
 * (ImplicitEuler), LockedEdge (OuterEdge), LockedParticles, and the numeric parameters
 * listed, with their meanings, in VU_MASS_SPRING_PARAMETERS (itkMassSpringSheetFlattener.h).
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

  /** Integrator of the unroll and flatten phases (ImplicitEuler). */
  virtual void
  SetIntegrator(const IntegratorEnum integrator)
  {
    if (m_Parameters.Integrator != integrator)
    {
      m_Parameters.Integrator = integrator;
      this->Modified();
    }
  }
  virtual IntegratorEnum
  GetIntegrator() const
  {
    return m_Parameters.Integrator;
  }
  /** What the unroll phase holds (OuterEdge). */
  virtual void
  SetLockedEdge(const LockedEdgeEnum edge)
  {
    if (m_Parameters.LockedEdge != edge)
    {
      m_Parameters.LockedEdge = edge;
      this->Modified();
    }
  }
  virtual LockedEdgeEnum
  GetLockedEdge() const
  {
    return m_Parameters.LockedEdge;
  }

  /** Set/Get of every numeric parameter of VU_MASS_SPRING_PARAMETERS (see there for
   * meanings and defaults); a Set clamps to the parameter's range. */
#define VU_MASS_SPRING_FILTER_SET_GET(type, name, value, lowest, highest, option, key, meaning)                        \
  virtual void Set##name(const type _arg)                                                                              \
  {                                                                                                                    \
    const type clamped = std::min<type>(std::max<type>(_arg, lowest), highest);                                        \
    if (m_Parameters.name != clamped)                                                                                  \
    {                                                                                                                  \
      m_Parameters.name = clamped;                                                                                     \
      this->Modified();                                                                                                \
    }                                                                                                                  \
  }                                                                                                                    \
  virtual type Get##name() const { return m_Parameters.name; }
  VU_MASS_SPRING_PARAMETERS(VU_MASS_SPRING_FILTER_SET_GET)
#undef VU_MASS_SPRING_FILTER_SET_GET

  /** Particles held during the unroll phase when LockedEdge is Custom. */
  void
  SetLockedParticles(const std::vector<uint32_t> & particles)
  {
    if (particles != m_Parameters.LockedParticles)
    {
      m_Parameters.LockedParticles = particles;
      this->Modified();
    }
  }
  const std::vector<uint32_t> &
  GetLockedParticles() const
  {
    return m_Parameters.LockedParticles;
  }

  /** The parameters as MassSpringSheetFlattener takes them; Set takes all of them at once
   * (the number of work units stays the filter's own). */
  MassSpringFlatteningParameters
  GetParameters() const;
  void
  SetParameters(const MassSpringFlatteningParameters & parameters);

  /** During an update (from an IterationEvent observer): the running system, its phase
   * and the step within the phase. */
  MassSpringSystem *
  GetCurrentSystem() const
  {
    return m_CurrentSystem;
  }
  SheetFlatteningPhaseEnum
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
  /** Every parameter but the number of work units, which is the filter's own. */
  MassSpringFlatteningParameters m_Parameters;

  MassSpringFlatteningReport m_Report;
  MassSpringSystem *         m_CurrentSystem{ nullptr };
  SheetFlatteningPhaseEnum   m_CurrentPhase{ SheetFlatteningPhaseEnum::Unroll };
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
inline std::ostream &
operator<<(std::ostream & os, SheetFlatteningPhaseEnum e)
{
  return os << ToString(e);
}
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkMassSpringFlatteningMeshFilter.hxx"
#endif

#endif

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
#ifndef itkMassSpringFlatteningMeshFilter_hxx
#define itkMassSpringFlatteningMeshFilter_hxx

#include "itkMassSpringFlatteningMeshFilter.h"
#include "itkSheetMeshAdaptor.h"

namespace itk {
template <typename TInputMesh, typename TOutputMesh>
MassSpringFlatteningParameters
MassSpringFlatteningMeshFilter<TInputMesh, TOutputMesh>::GetParameters() const
{
  MassSpringFlatteningParameters p = m_Parameters;
  p.NumberOfWorkUnits = this->GetNumberOfWorkUnits();
  return p;
}

template <typename TInputMesh, typename TOutputMesh>
void
MassSpringFlatteningMeshFilter<TInputMesh, TOutputMesh>::SetParameters(
  const MassSpringFlatteningParameters & parameters)
{
  const unsigned int workUnits = m_Parameters.NumberOfWorkUnits;
  m_Parameters = parameters;
  m_Parameters.NumberOfWorkUnits = workUnits;
  this->Modified();
}

template <typename TInputMesh, typename TOutputMesh>
void
MassSpringFlatteningMeshFilter<TInputMesh, TOutputMesh>::GenerateData()
{
  const InputMeshType * input = this->GetInput();
  const SheetMesh       surface = MeshToSheetMesh(input);

  MassSpringSheetFlattener flattener;
  flattener.SetParameters(this->GetParameters());
  // Progress: each phase advances a share of the bar as its steps approach the limit.
  const double stepLimit = m_Parameters.MaximumStepsPerPhase;
  using Phase = SheetFlatteningPhaseEnum;
  flattener.SetStepCallback([this, stepLimit](MassSpringSystem & system, Phase phase, uint64_t step) {
    m_CurrentSystem = &system;
    m_CurrentPhase = phase;
    m_CurrentStep = step;
    this->InvokeEvent(IterationEvent());
    double base = 0.0, share = 0.4;
    if (phase == Phase::Flatten)
    {
      base = 0.4;
      share = 0.3;
    }
    else if (phase != Phase::Unroll)
    {
      base = 0.7;
      share = 0.3;
    }
    const double limit =
      phase == Phase::Relax || phase == Phase::RelaxFull ? m_Parameters.RelaxationIterations : stepLimit;
    this->UpdateProgress(static_cast<float>(base + share * std::min(1.0, step / limit)));
    return !this->GetAbortGenerateData();
  });
  SheetMesh flat;
  try
  {
    flat = flattener.Flatten(surface);
  }
  catch (const MassSpringDivergenceError & e)
  {
    m_CurrentSystem = nullptr;
    itkExceptionMacro(<< e.GetDescription());
  }
  catch (...)
  {
    m_CurrentSystem = nullptr;
    if (this->GetAbortGenerateData())
    {
      ProcessAborted aborted(__FILE__, __LINE__);
      aborted.SetDescription("MassSpringFlatteningMeshFilter: aborted by the user");
      throw aborted;
    }
    throw;
  }
  m_CurrentSystem = nullptr;
  m_Report = flattener.GetReport();

  // Built in place (a QuadEdgeMesh must not share its cells with a temporary mesh); the
  // sheet grid (and whatever else the input carries) describes the flat mesh as well.
  OutputMeshType * output = this->GetOutput();
  SheetMeshIntoMesh(flat, output);
  output->SetMetaDataDictionary(input->GetMetaDataDictionary());
  // Point data travels with the points, which keep their order.
  if (input->GetPointData() != nullptr && input->GetPointData()->Size() == input->GetNumberOfPoints())
  {
    typename OutputMeshType::PointIdentifier id = 0;
    for (auto it = input->GetPointData()->Begin(); it != input->GetPointData()->End(); ++it, ++id)
    {
      output->SetPointData(id, static_cast<typename OutputMeshType::PixelType>(it.Value()));
    }
  }
  MarkMeshWhole(output);
  this->UpdateProgress(1.0f);
}

template <typename TInputMesh, typename TOutputMesh>
void
MassSpringFlatteningMeshFilter<TInputMesh, TOutputMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Integrator: " << m_Parameters.Integrator << std::endl;
  os << indent << "LockedEdge: " << m_Parameters.LockedEdge << std::endl;
  os << indent << "LockedParticles: " << m_Parameters.LockedParticles.size() << std::endl;
#define VU_MASS_SPRING_FILTER_PRINT(type, name, value, lowest, highest, option, key, meaning)                          \
  os << indent << #name ": " << m_Parameters.name << std::endl;
  VU_MASS_SPRING_PARAMETERS(VU_MASS_SPRING_FILTER_PRINT)
#undef VU_MASS_SPRING_FILTER_PRINT
  os << indent << "CurrentPhase: " << m_CurrentPhase << std::endl;
  os << indent << "CurrentStep: " << m_CurrentStep << std::endl;
}
} // end namespace itk

#endif

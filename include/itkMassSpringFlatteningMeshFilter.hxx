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
  MassSpringFlatteningParameters p;
  p.Integrator = m_Integrator;
  p.TimeStep = m_TimeStep;
  p.TimeStepSafety = m_TimeStepSafety;
  p.StepsPerFallTime = m_StepsPerFallTime;
  p.Stiffness = m_Stiffness;
  p.ShearStiffnessRatio = m_ShearStiffnessRatio;
  p.BendingStiffnessRatio = m_BendingStiffnessRatio;
  p.Density = m_Density;
  p.Gravity = m_Gravity;
  p.HangingStrain = m_HangingStrain;
  p.Damping = m_Damping;
  p.SpringDamping = m_SpringDamping;
  p.Restitution = m_Restitution;
  p.LockedEdge = m_LockedEdge;
  p.LockedParticles = m_LockedParticles;
  p.MaximumStepsPerPhase = m_MaximumStepsPerPhase;
  p.KineticEnergyTolerance = m_KineticEnergyTolerance;
  p.ResidualForceTolerance = m_ResidualForceTolerance;
  p.PlanarityTolerance = m_PlanarityTolerance;
  p.RelaxationIterations = m_RelaxationIterations;
  p.RelaxationTolerance = m_RelaxationTolerance;
  p.CoarseningFactor = m_CoarseningFactor;
  p.CoarseParticles = m_CoarseParticles;
  p.NumberOfWorkUnits = this->GetNumberOfWorkUnits();
  return p;
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
  const double stepLimit = m_MaximumStepsPerPhase;
  flattener.SetStepCallback([this, stepLimit](MassSpringSystem & system, const std::string & phase, uint64_t step) {
    m_CurrentSystem = &system;
    m_CurrentPhase = phase;
    m_CurrentStep = step;
    this->InvokeEvent(IterationEvent());
    double base = 0.0, share = 0.4;
    if (phase == "flatten")
    {
      base = 0.4;
      share = 0.3;
    }
    else if (phase != "unroll")
    {
      base = 0.7;
      share = 0.3;
    }
    const double limit = phase.rfind("relax", 0) == 0 ? m_RelaxationIterations : stepLimit;
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
    itkExceptionMacro(<< e.what());
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
  this->UpdateProgress(1.0f);
}

template <typename TInputMesh, typename TOutputMesh>
void
MassSpringFlatteningMeshFilter<TInputMesh, TOutputMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Integrator: " << m_Integrator << std::endl;
  os << indent << "TimeStep: " << m_TimeStep << std::endl;
  os << indent << "TimeStepSafety: " << m_TimeStepSafety << std::endl;
  os << indent << "StepsPerFallTime: " << m_StepsPerFallTime << std::endl;
  os << indent << "Stiffness: " << m_Stiffness << std::endl;
  os << indent << "ShearStiffnessRatio: " << m_ShearStiffnessRatio << std::endl;
  os << indent << "BendingStiffnessRatio: " << m_BendingStiffnessRatio << std::endl;
  os << indent << "Density: " << m_Density << std::endl;
  os << indent << "Gravity: " << m_Gravity << std::endl;
  os << indent << "HangingStrain: " << m_HangingStrain << std::endl;
  os << indent << "Damping: " << m_Damping << std::endl;
  os << indent << "SpringDamping: " << m_SpringDamping << std::endl;
  os << indent << "Restitution: " << m_Restitution << std::endl;
  os << indent << "LockedEdge: " << m_LockedEdge << std::endl;
  os << indent << "LockedParticles: " << m_LockedParticles.size() << std::endl;
  os << indent << "MaximumStepsPerPhase: " << m_MaximumStepsPerPhase << std::endl;
  os << indent << "KineticEnergyTolerance: " << m_KineticEnergyTolerance << std::endl;
  os << indent << "ResidualForceTolerance: " << m_ResidualForceTolerance << std::endl;
  os << indent << "PlanarityTolerance: " << m_PlanarityTolerance << std::endl;
  os << indent << "RelaxationIterations: " << m_RelaxationIterations << std::endl;
  os << indent << "RelaxationTolerance: " << m_RelaxationTolerance << std::endl;
  os << indent << "CoarseningFactor: " << m_CoarseningFactor << std::endl;
  os << indent << "CoarseParticles: " << m_CoarseParticles << std::endl;
  os << indent << "CurrentPhase: " << m_CurrentPhase << std::endl;
  os << indent << "CurrentStep: " << m_CurrentStep << std::endl;
}
} // end namespace itk

#endif

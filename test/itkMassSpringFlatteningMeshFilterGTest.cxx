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
#include "itkCommand.h"
#include "itkFlatteningDistortionCalculator.h"
#include "itkMassSpringFlatteningMeshFilter.h"
#include "itkQuadEdgeMesh.h"
#include "itkSheetMeshAdaptor.h"
#include "vuTestHelpers.h"
#include "vuTestMeshes.h"

#include "gtest/gtest.h"

namespace {
using MeshType = itk::Mesh<float, 3>;
using FilterType = itk::MassSpringFlatteningMeshFilter<MeshType>;

MeshType::Pointer
RollWithPointData(itk::SheetMesh & sheet)
{
  sheet = vu::SpiralRollMesh(10.0, 4.0, 2.0, 2.0, 16.0, nullptr);
  auto mesh = itk::SheetMeshToMesh<MeshType>(sheet);
  for (size_t i = 0; i < sheet.GetNumberOfPoints(); ++i)
  {
    mesh->SetPointData(i, static_cast<float>(i % 7));
  }
  return mesh;
}
} // namespace

TEST(MassSpringFlatteningMeshFilter, BasicObjectMethodsAndParameters)
{
  auto filter = FilterType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(filter, MassSpringFlatteningMeshFilter, MeshToMeshFilter));
  filter->SetIntegrator(itk::MassSpringIntegratorEnum::RungeKutta4);
  filter->SetRestitution(0.3);
  filter->SetStiffness(2.0);
  filter->SetLockedEdge(itk::SheetLockedEdgeEnum::InnerEdge);
  filter->SetRestitution(5.0); // clamped to [0, 1]
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(1.0, filter->GetRestitution()));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(2.0, filter->GetStiffness()));
  const itk::MassSpringFlatteningParameters p = filter->GetParameters();
  EXPECT_EQ(p.Integrator, itk::MassSpringIntegratorEnum::RungeKutta4);
  EXPECT_EQ(p.LockedEdge, itk::SheetLockedEdgeEnum::InnerEdge);
  EXPECT_EQ(p.Stiffness, 2.0);
}

TEST(MassSpringFlatteningMeshFilter, FlattensARollWithEventsAndCarriesPointData)
{
  itk::SheetMesh sheet;
  auto           input = RollWithPointData(sheet);
  auto           filter = FilterType::New();
  filter->SetInput(input);
  size_t iterations = 0, withSystem = 0;
  float  lastProgress = 0.0f;
  struct Counter : public itk::Command
  {
    size_t * iterations{};
    size_t * withSystem{};
    float *  progress{};
    void
    Execute(itk::Object * caller, const itk::EventObject & event) override
    {
      Execute(static_cast<const itk::Object *>(caller), event);
    }
    void
    Execute(const itk::Object * caller, const itk::EventObject & event) override
    {
      const auto * f = static_cast<const FilterType *>(caller);
      if (itk::IterationEvent().CheckEvent(&event))
      {
        ++*iterations;
        if (f->GetCurrentSystem() != nullptr && f->GetCurrentSystem()->GetNumberOfParticles() > 0)
        {
          ++*withSystem;
        }
      }
      else if (itk::ProgressEvent().CheckEvent(&event))
      {
        *progress = f->GetProgress();
      }
    }
  };
  itk::SmartPointer<Counter> counter = new Counter;
  counter->UnRegister();
  counter->iterations = &iterations;
  counter->withSystem = &withSystem;
  counter->progress = &lastProgress;
  filter->AddObserver(itk::IterationEvent(), counter);
  filter->AddObserver(itk::ProgressEvent(), counter);
  filter->Update();
  MeshType * output = filter->GetOutput();
  ASSERT_EQ(output->GetNumberOfPoints(), input->GetNumberOfPoints());
  ASSERT_EQ(output->GetNumberOfCells(), input->GetNumberOfCells());
  EXPECT_GT(iterations, 10u);
  EXPECT_EQ(withSystem, iterations);
  EXPECT_FLOAT_EQ(lastProgress, 1.0f);
  for (size_t i = 0; i < sheet.GetNumberOfPoints(); ++i)
  {
    EXPECT_EQ(output->GetPoint(i)[2], 0.0f);
    EXPECT_EQ(output->GetPointData()->ElementAt(i), static_cast<float>(i % 7));
  }
  const itk::SheetMesh flat = itk::MeshToSheetMesh(output);
  EXPECT_EQ(flat.GridIndex, sheet.GridIndex);
  auto calculator = itk::FlatteningDistortionCalculator::New();
  calculator->SetSurfaceMesh(sheet);
  calculator->SetFlatMesh(flat);
  calculator->Compute();
  EXPECT_LE(calculator->GetEdgeStrainP95(), 0.005);
  EXPECT_EQ(calculator->GetNumberOfFlippedTriangles(), 0u);
  ASSERT_FALSE(filter->GetReport().Phases.empty());
  EXPECT_EQ(filter->GetReport().Phases.front().Name, itk::SheetFlatteningPhaseEnum::Unroll);

  // Up to date after its update: a downstream filter's update does not run it again.
  const auto before = iterations;
  output->Update();
  filter->Update();
  EXPECT_EQ(iterations, before);
}

TEST(MassSpringFlatteningMeshFilter, WorksOnQuadEdgeMeshes)
{
  using QEMesh = itk::QuadEdgeMesh<double, 3>;
  const itk::SheetMesh sheet = vu::SpiralRollMesh(10.0, 4.0, 1.5, 2.0, 10.0, nullptr);
  auto                 filter = itk::MassSpringFlatteningMeshFilter<QEMesh>::New();
  filter->SetInput(itk::SheetMeshToMesh<QEMesh>(sheet));
  filter->Update();
  const itk::SheetMesh flat = itk::MeshToSheetMesh(filter->GetOutput());
  EXPECT_EQ(flat.GetNumberOfPoints(), sheet.GetNumberOfPoints());
  EXPECT_EQ(flat.GetNumberOfTriangles(), sheet.GetNumberOfTriangles());
}

TEST(MassSpringFlatteningMeshFilter, AbortAndDivergenceAreReported)
{
  itk::SheetMesh sheet;
  auto           input = RollWithPointData(sheet);
  auto           filter = FilterType::New();
  filter->SetInput(input);
  struct Aborter : public itk::Command
  {
    void
    Execute(itk::Object * caller, const itk::EventObject &) override
    {
      auto * f = static_cast<FilterType *>(caller);
      if (f->GetCurrentStep() >= 10)
      {
        f->AbortGenerateDataOn();
      }
    }
    void
    Execute(const itk::Object *, const itk::EventObject &) override
    {}
  };
  itk::SmartPointer<Aborter> aborter = new Aborter;
  aborter->UnRegister();
  const unsigned long tag = filter->AddObserver(itk::IterationEvent(), aborter);
  EXPECT_THROW(filter->Update(), itk::ProcessAborted);
  filter->RemoveObserver(tag);
  filter->AbortGenerateDataOff();

  filter->SetIntegrator(itk::MassSpringIntegratorEnum::SymplecticEuler);
  filter->SetTimeStepSafety(3.0);
  filter->SetDamping(0.0);
  try
  {
    filter->Update();
    FAIL() << "a time step three times the stability bound did not diverge";
  }
  catch (const itk::ExceptionObject & e)
  {
    EXPECT_NE(std::string(e.GetDescription()).find("symplectic-euler"), std::string::npos) << e.GetDescription();
  }
}

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
#include "itkLayeredTextureMeshFilter.h"

#include "itkCommand.h"
#include "vuTestHelpers.h"
#include "vuTexturePhantom.h"

#include "gtest/gtest.h"

#include <cmath>

namespace {
using FilterType = itk::LayeredTextureMeshFilter<vu::MeshType, vu::VolumeType>;
using Filter = itk::TextureLayersEnums::Filter;
using Side = itk::TextureLayersEnums::Side;

// vu::HorizontalSquare(z) as the filter's input mesh.
vu::MeshType::Pointer
SquareMesh(double z)
{
  return itk::SheetMeshToMesh<vu::MeshType>(vu::HorizontalSquare(z));
}

std::vector<float>
Values(FilterType * filter)
{
  filter->Update();
  std::vector<float> values;
  const auto *       data = filter->GetOutput()->GetPointData();
  for (auto it = data->Begin(); it != data->End(); ++it)
  {
    values.push_back(it.Value());
  }
  return values;
}

double
Correlation(const std::vector<double> & a, const std::vector<double> & b)
{
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (size_t k = 0; k < a.size(); ++k)
  {
    sa += a[k];
    sb += b[k];
    saa += a[k] * a[k];
    sbb += b[k] * b[k];
    sab += a[k] * b[k];
  }
  const double n = static_cast<double>(a.size());
  return (sab - sa * sb / n) / std::sqrt((saa - sa * sa / n) * (sbb - sb * sb / n));
}
} // namespace

TEST(LayeredTextureMeshFilter, BasicObjectMethods)
{
  auto filter = FilterType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(filter, LayeredTextureMeshFilter, MeshToMeshFilter));
  filter->SetNumberOfLayers(5);
  filter->SetLayerSpacing(0.25);
  filter->SetFocus(0.5);
  filter->SetLayerSide(Side::Positive);
  filter->SetLayerFilter(Filter::GaussianMean);
  filter->SetGaussianSigma(0.75);
  EXPECT_EQ(filter->GetNumberOfLayers(), 5u);
  EXPECT_EQ(filter->GetLayerSpacing(), 0.25);
  EXPECT_EQ(filter->GetFocus(), 0.5);
  EXPECT_EQ(filter->GetLayerSide(), Side::Positive);
  EXPECT_EQ(filter->GetLayerFilter(), Filter::GaussianMean);
  EXPECT_EQ(filter->GetGaussianSigma(), 0.75);
  EXPECT_NE(filter->GetInterpolator(), nullptr);
}

TEST(LayeredTextureMeshFilter, VertexValuesFollowTheLayers)
{
  auto filter = FilterType::New();
  filter->SetInput(SquareMesh(5.0));
  filter->SetVolume(vu::RampVolume());
  filter->SetNumberOfLayers(5);
  filter->SetLayerSpacing(0.5);
  filter->SetFocus(-0.25);
  for (const auto & [filterType, expected] : std::vector<std::pair<Filter, double>>{
         { Filter::Mean, 4.75 }, { Filter::Max, 5.75 }, { Filter::Min, 3.75 }, { Filter::SingleLayer, 4.75 } })
  {
    filter->SetLayerFilter(filterType);
    const std::vector<float> values = Values(filter);
    ASSERT_EQ(values.size(), 4u);
    for (const float value : values)
    {
      EXPECT_NEAR(value, expected, 1e-5) << filterType;
    }
  }
  EXPECT_EQ(filter->GetOutput()->GetNumberOfCells(), 2u);
  EXPECT_EQ(filter->GetNumberOfClampedSamples(), 0u);
  EXPECT_EQ(filter->GetNumberOfZeroNormalPoints(), 0u);
}

TEST(LayeredTextureMeshFilter, MaxFilterRecoversInkOffTheMidSurface)
{
  const vu::TiltedPlane     plane;
  const vu::PhantomSettings settings = vu::FaceInkSettings();
  const auto                volume = vu::MakeTiltedPlaneVolume(plane, settings);
  itk::SheetMesh            flat;
  const itk::SheetMesh      sheet = vu::MakeSheetMesh(plane, 81, 49, flat);
  std::vector<double>       ink;
  for (size_t i = 0; i < flat.GetNumberOfPoints(); ++i)
  {
    ink.push_back(vu::InkAt(flat.Points[3 * i], flat.Points[3 * i + 1]) ? 1.0 : 0.0);
  }
  auto filter = FilterType::New();
  filter->SetInput(itk::SheetMeshToMesh<vu::MeshType>(sheet));
  filter->SetVolume(volume);
  const std::vector<float> single = Values(filter);
  filter->SetNumberOfLayers(5);
  filter->SetLayerSpacing(0.5);
  filter->SetLayerFilter(Filter::Max);
  const std::vector<float> max = Values(filter);
  const double             singleCorrelation = Correlation(std::vector<double>(single.begin(), single.end()), ink);
  const double             maxCorrelation = Correlation(std::vector<double>(max.begin(), max.end()), ink);
  std::cout << "per vertex, ink on one face: single layer correlation " << singleCorrelation << ", max of 5 "
            << maxCorrelation << std::endl;
  EXPECT_LT(singleCorrelation, 0.5);
  EXPECT_GE(maxCorrelation, 0.8); // against binary ink at the vertices: edges blur
}

TEST(LayeredTextureMeshFilter, ZeroNormalsAndSamplesOutsideAreCounted)
{
  // The same triangle twice with opposite windings: every vertex normal cancels.
  itk::SheetMesh folded;
  folded.Points = { 1, 1, 5, 4, 1, 5, 4, 3.5, 5 };
  folded.Triangles = { 0, 1, 2, 0, 2, 1 };
  auto filter = FilterType::New();
  filter->SetInput(itk::SheetMeshToMesh<vu::MeshType>(folded));
  filter->SetVolume(vu::RampVolume());
  for (const float value : Values(filter))
  {
    EXPECT_TRUE(std::isnan(value));
  }
  EXPECT_EQ(filter->GetNumberOfZeroNormalPoints(), 3u);

  // Above the volume: clamped onto its top face, counted.
  filter->SetInput(SquareMesh(20.0));
  for (const float value : Values(filter))
  {
    EXPECT_NEAR(value, 9.5, 1e-5);
  }
  EXPECT_EQ(filter->GetNumberOfClampedSamples(), 4u);
}

TEST(LayeredTextureMeshFilter, BadInputThrows)
{
  auto filter = FilterType::New();
  filter->SetInput(SquareMesh(5.0));
  EXPECT_THROW(filter->Update(), itk::ExceptionObject); // no volume
  filter->SetVolume(vu::RampVolume());
  filter->SetNumberOfLayers(0);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject);
  filter->SetNumberOfLayers(3);
  filter->SetLayerSpacing(-1.0);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject);
  filter->SetLayerSpacing(1.0);
  filter->SetLayerFilter(Filter::GaussianMean);
  filter->SetGaussianSigma(0.0);
  EXPECT_THROW(filter->Update(), itk::ExceptionObject);
}

TEST(LayeredTextureMeshFilter, AbortStopsTheFilter)
{
  // Enough points for several work units, so that progress is reported on the way.
  itk::SheetMesh flat;
  const auto     sheet = vu::MakeSheetMesh(
    200,
    50,
    [](double u, double v) {
      return std::array<double, 3>{ 0.1 * u, 0.1 * v, 5.0 };
    },
    flat);
  auto filter = FilterType::New();
  filter->SetInput(itk::SheetMeshToMesh<vu::MeshType>(sheet));
  filter->SetVolume(vu::RampVolume());
  auto abort = itk::CStyleCommand::New();
  abort->SetCallback([](itk::Object * caller, const itk::EventObject &, void *) {
    static_cast<itk::ProcessObject *>(caller)->AbortGenerateDataOn();
  });
  filter->AddObserver(itk::ProgressEvent(), abort);
  EXPECT_THROW(filter->Update(), itk::ProcessAborted);
}

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
#include "itkReadableTextureImageFilter.h"

#include "itkSheetMeshAdaptor.h"
#include "itkTextureFidelityCalculator.h"
#include "vuTestHelpers.h"
#include "vuTexturePhantom.h"

#include "gtest/gtest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

namespace {
using FilterType = itk::ReadableTextureImageFilter<vu::VolumeType>;
using Side = itk::TextureLayersEnums::Side;
using Core = itk::TextureLayersEnums::CoreSubtraction;

// The cylinder shell phantom: 0.5 mm voxels, a 2.5 mm sheet with ink in its outer face.
constexpr double Voxel = 0.5;
constexpr double Thickness = 2.5;

struct Shell
{
  vu::VolumeType::Pointer Volume;
  itk::SheetMesh          Surface, Flat;
};

const Shell &
InkedShell()
{
  static const Shell shell = [] {
    const vu::CylinderShell cylinder;
    Shell                   s;
    s.Volume = vu::MakeCylinderShellVolume(cylinder, vu::FaceInkSettings(), Voxel);
    s.Surface = vu::MakeSheetMesh(cylinder, 61, 7, s.Flat);
    return s;
  }();
  return shell;
}

FilterType::Pointer
MakeFilter(const Shell & shell)
{
  auto filter = FilterType::New();
  filter->SetSurfaceMesh(itk::SheetMeshToMesh<vu::MeshType>(shell.Surface));
  filter->SetFlatMesh(itk::SheetMeshToMesh<vu::MeshType>(shell.Flat));
  filter->SetVolume(shell.Volume);
  filter->SetSheetThickness(Thickness);
  return filter;
}

double
Fidelity(FilterType * filter)
{
  auto calculator = itk::TextureFidelityCalculator::New();
  calculator->SetReference(vu::MakeInkImage(filter->GetAppliedPixelSize()));
  calculator->SetTexture(filter->GetOutput());
  calculator->SetTextureMask(filter->GetMaskOutput());
  calculator->Compute();
  return calculator->GetNormalizedCrossCorrelation();
}

bool
SamePixels(const vu::TextureType * a, const vu::TextureType * b)
{
  const size_t n = a->GetLargestPossibleRegion().GetNumberOfPixels();
  if (n != b->GetLargestPossibleRegion().GetNumberOfPixels())
  {
    return false;
  }
  return std::equal(a->GetBufferPointer(), a->GetBufferPointer() + n, b->GetBufferPointer(), [](float x, float y) {
    return (std::isnan(x) && std::isnan(y)) || x == y;
  });
}
} // namespace

TEST(ReadableTextureImageFilter, BasicObjectMethods)
{
  auto filter = FilterType::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(filter, ReadableTextureImageFilter, ImageSource));
  filter->SetNumberOfLayers(7);
  filter->SetAutomaticSide(false);
  filter->SetLayerSide(Side::Negative);
  filter->SetSubtractCore(Core::Yes);
  filter->SetRestoreFWHM(0.2);
  EXPECT_EQ(filter->GetNumberOfLayers(), 7u);
  EXPECT_FALSE(filter->GetAutomaticSide());
  EXPECT_EQ(filter->GetLayerSide(), Side::Negative);
  EXPECT_EQ(filter->GetSubtractCore(), Core::Yes);
  EXPECT_EQ(filter->GetRestoreFWHM(), 0.2);
  // Automatic by default.
  auto fresh = FilterType::New();
  EXPECT_EQ(fresh->GetPixelSize(), 0.0);
  EXPECT_EQ(fresh->GetNumberOfLayers(), 0u);
  EXPECT_EQ(fresh->GetLayerSpacing(), 0.0);
  EXPECT_TRUE(fresh->GetAutomaticSide());
  EXPECT_EQ(fresh->GetSubtractCore(), Core::Auto);
  EXPECT_LT(fresh->GetMedianRadius(), 0.0);
  EXPECT_LT(fresh->GetRestoreFWHM(), 0.0);
}

// Automatic sampling: pixels and layers half a voxel apart, layers reaching half a voxel
// beyond both faces; the inked face's half is chosen, and the texture is the policy's
// choice from the filter's own layer stack, pixel for pixel.
TEST(ReadableTextureImageFilter, ChoosesTheInkedFaceFromItsOwnStack)
{
  auto filter = MakeFilter(InkedShell());
  filter->Update();
  const unsigned int reach = static_cast<unsigned int>(std::ceil((0.5 * Thickness + 0.5 * Voxel) / (0.5 * Voxel)));
  EXPECT_EQ(filter->GetAppliedPixelSize(), 0.5 * Voxel);
  EXPECT_EQ(filter->GetAppliedLayerSpacing(), 0.5 * Voxel);
  EXPECT_EQ(filter->GetAppliedNumberOfLayers(), 1 + 2 * reach);
  EXPECT_EQ(filter->GetLayerStackOutput()->GetLargestPossibleRegion().GetSize()[2], 1 + 2 * reach);

  const itk::ReadableTextureSelection & selection = filter->GetSelection();
  // Both sides, and each half with and without its core.
  ASSERT_EQ(selection.Candidates.size(), 5u);
  EXPECT_FALSE(selection.FocalSlabs);
  for (const auto & candidate : selection.Candidates)
  {
    EXPECT_LE(candidate.Score, filter->GetChosenScore());
  }
  // The ink lies in the outer face: the normal of this mesh points outwards or inwards, and
  // the half on that side wins.
  EXPECT_NE(selection.ChosenCandidate().Side, Side::Both);
  EXPECT_EQ(selection.VertexSide, selection.ChosenCandidate().Side);
  EXPECT_EQ(selection.VertexLayers, reach + 1);
  const double ncc = Fidelity(filter);
  std::cout << "inked face chosen: side " << selection.ChosenCandidate().Side << ", core subtracted "
            << selection.ChosenCandidate().SubtractCore << ", score " << filter->GetChosenScore() << ", NCC " << ncc
            << std::endl;
  EXPECT_GE(ncc, 0.9);

  itk::ReadableTextureSettings settings;
  settings.NumberOfLayers = filter->GetAppliedNumberOfLayers();
  settings.LayerSpacing = filter->GetAppliedLayerSpacing();
  settings.Voxel = Voxel;
  const auto again = itk::SelectReadableTexture(filter->GetLayerStackOutput(), settings);
  EXPECT_EQ(again.Chosen, selection.Chosen);
  EXPECT_TRUE(SamePixels(again.Texture, filter->GetOutput()));
}

// A noisy scan (the segmentation smoothed it): focal slabs of 3 and 5 layers at every depth,
// denoised as strongly as the scan was.
TEST(ReadableTextureImageFilter, FocalSlabsOnANoisyScan)
{
  auto filter = MakeFilter(InkedShell());
  filter->SetDenoisingSigma(1.0);
  filter->Update();
  const auto &       selection = filter->GetSelection();
  const unsigned int layers = filter->GetAppliedNumberOfLayers();
  EXPECT_TRUE(selection.FocalSlabs);
  EXPECT_EQ(selection.Candidates.size(), static_cast<size_t>((layers - 2) + (layers - 4)));
  EXPECT_EQ(selection.MedianRadius, Voxel);
  EXPECT_EQ(selection.SmoothSigma, Voxel);
  EXPECT_GT(selection.ChosenCandidate().Count, 0u);
  EXPECT_EQ(selection.VertexFilter, itk::TextureLayersEnums::Filter::Mean);
  // The chosen slab's middle lies off the mid-surface on the inked face's side (Positive:
  // this mesh's normal points outwards, see the test above).
  EXPECT_GT(selection.Depth, 0.0);
  const double ncc = Fidelity(filter);
  std::cout << "focal slab layers " << selection.ChosenCandidate().First << " + " << selection.ChosenCandidate().Count
            << ", depth " << selection.Depth << " mm, NCC " << ncc << std::endl;
  EXPECT_GE(ncc, 0.85);
}

// Where another sheet touches this one, its material fills the stack's outermost layers on
// that side over a patch: a bright disc with sharp edges, which the stroke measure would
// take for writing. Those pixels are left out of the focal slabs' scores, and the slab
// holding the strokes is chosen. Stroke positions, the disc, the noise and the ink's side
// are drawn at run time.
TEST(ReadableTextureImageFilter, AnotherSheetTouchingIsNotTakenForWriting)
{
  std::mt19937           random(vu::RunTimeSeed());
  constexpr unsigned int Layers = 9;
  constexpr long         Columns = 160, Rows = 100;
  const bool             inkPositive = std::bernoulli_distribution(0.5)(random);
  // Sheet profile across the layers (0.5-voxel layer spacing, a 2.2-voxel sheet blurred).
  std::array<float, Layers> profile{};
  for (unsigned int k = 0; k < Layers; ++k)
  {
    const double d = 0.5 * (static_cast<double>(k) - 4.0);
    profile[k] = static_cast<float>(0.5 * (std::erf((1.1 - d) / 0.9) + std::erf((1.1 + d) / 0.9)));
  }
  // Ink strokes: vertical and horizontal bars two pixels wide, in letter-sized boxes.
  std::vector<uint8_t>                ink(Columns * Rows, 0);
  std::uniform_int_distribution<long> boxX(10, Columns - 26), boxY(15, Rows - 35);
  for (int letter = 0; letter < 10; ++letter)
  {
    const long x0 = boxX(random), y0 = boxY(random);
    for (long y = y0; y < y0 + 20; ++y)
    {
      for (long x = x0; x < x0 + 14; ++x)
      {
        const bool bar = (x - x0 < 3) || (y - y0 < 3) || (letter % 2 == 0 && y - y0 >= 9 && y - y0 < 12);
        ink[y * Columns + x] |= bar ? 1 : 0;
      }
    }
  }
  // The other sheet's patch: a disc in the three outermost layers of the side away from the ink.
  std::uniform_real_distribution<double> where(0.25, 0.75), radius(8.0, 14.0);
  const double                           cx = where(random) * Columns, cy = where(random) * Rows, r = radius(random);
  auto                                   stack = itk::Image<float, 3>::New();
  itk::Image<float, 3>::SizeType         size{
    { static_cast<itk::SizeValueType>(Columns), static_cast<itk::SizeValueType>(Rows), Layers }
  };
  stack->SetRegions(size);
  const double spacing[3] = { 0.25 * Voxel, 0.25 * Voxel, 0.25 * Voxel };
  stack->SetSpacing(spacing);
  stack->Allocate();
  auto clean = itk::Image<float, 3>::New();
  clean->CopyInformation(stack);
  clean->SetRegions(size);
  clean->Allocate();
  std::normal_distribution<float> noise(0.0f, 0.12f);
  for (unsigned int k = 0; k < Layers; ++k)
  {
    const unsigned int fromInkFace = inkPositive ? Layers - 1 - k : k;
    const bool         inkLayer = fromInkFace >= 2 && fromInkFace <= 3;
    const bool         patchLayer = (inkPositive ? k : Layers - 1 - k) <= 2;
    for (long y = 0; y < Rows; ++y)
    {
      for (long x = 0; x < Columns; ++x)
      {
        const size_t i = (static_cast<size_t>(k) * Rows + y) * Columns + x;
        float        v = profile[k] + (inkLayer && ink[y * Columns + x] ? 0.6f : 0.0f) + noise(random);
        clean->GetBufferPointer()[i] = v;
        if (patchLayer && std::hypot(x - cx, y - cy) < r)
        {
          v = std::max(v, 1.0f + noise(random));
        }
        stack->GetBufferPointer()[i] = v;
      }
    }
  }
  itk::ReadableTextureSettings settings;
  settings.NumberOfLayers = Layers;
  settings.LayerSpacing = 0.5 * Voxel;
  settings.Voxel = Voxel;
  settings.DenoisingSigma = 0.7;
  const auto touched = itk::SelectReadableTexture(stack, settings);
  const auto alone = itk::SelectReadableTexture(clean, settings);
  ASSERT_TRUE(touched.FocalSlabs);
  EXPECT_GT(touched.PixelsLeftOut, 0u);
  EXPECT_LT(touched.PixelsLeftOut, static_cast<size_t>(0.25 * Columns * Rows));
  EXPECT_EQ(alone.PixelsLeftOut, 0u);
  // The chosen slab holds inked layers and its middle does not lie on the other sheet's
  // side, as without the other sheet. (A slab centred on the middle layer may win: five
  // layers holding both inked ones halve the noise.)
  const unsigned int inkFirst = inkPositive ? Layers - 4 : 2;
  const auto         holdsTheInk = [&](const itk::ReadableTextureSelection & selection) {
    const auto & chosen = selection.ChosenCandidate();
    return chosen.First <= inkFirst + 1 && chosen.First + chosen.Count > inkFirst &&
           (inkPositive ? selection.Depth >= 0.0 : selection.Depth <= 0.0);
  };
  const auto & chosen = touched.ChosenCandidate();
  std::cout << "ink on the " << (inkPositive ? "positive" : "negative") << " side; disc r " << r << "; chosen layers "
            << chosen.First << " + " << chosen.Count << " (alone: " << alone.ChosenCandidate().First << " + "
            << alone.ChosenCandidate().Count << "), " << touched.PixelsLeftOut << " pixels left out" << std::endl;
  EXPECT_TRUE(holdsTheInk(touched));
  EXPECT_TRUE(holdsTheInk(alone));
}

// A side given: one candidate per core choice asked for; restoration replaces the Gaussian.
TEST(ReadableTextureImageFilter, GivenSideCoreAndRestoration)
{
  auto filter = MakeFilter(InkedShell());
  filter->SetAutomaticSide(false);
  filter->SetLayerSide(Side::Positive);
  filter->SetSubtractCore(Core::Yes);
  filter->SetRestoreFWHM(0.0);
  filter->Update();
  const auto & selection = filter->GetSelection();
  ASSERT_EQ(selection.Candidates.size(), 1u);
  EXPECT_EQ(selection.ChosenCandidate().Side, Side::Positive);
  EXPECT_TRUE(selection.ChosenCandidate().SubtractCore);
  EXPECT_EQ(selection.SmoothSigma, 0.0);
  EXPECT_GT(selection.PsfSigma, 0.0);
  EXPECT_EQ(filter->GetAppliedNumberOfLayers(),
            1 + static_cast<unsigned int>(std::ceil((0.5 * Thickness + 0.5 * Voxel) / (0.5 * Voxel))));
  EXPECT_EQ(selection.VertexLayers, filter->GetAppliedNumberOfLayers());
}

TEST(ReadableTextureImageFilter, BadInputThrows)
{
  const Shell & shell = InkedShell();
  auto          even = MakeFilter(shell);
  even->SetNumberOfLayers(6); // the automatic side splits the layers at the focus
  EXPECT_THROW(even->Update(), itk::ExceptionObject);
  auto both = MakeFilter(shell);
  both->SetSmoothSigma(0.5);
  both->SetRestoreFWHM(0.2); // restoration replaces the Gaussian
  EXPECT_THROW(both->Update(), itk::ExceptionObject);
  auto negative = MakeFilter(shell);
  negative->SetPixelSize(-1.0);
  EXPECT_THROW(negative->Update(), itk::ExceptionObject);
  auto noVolume = FilterType::New();
  noVolume->SetSurfaceMesh(itk::SheetMeshToMesh<vu::MeshType>(shell.Surface));
  noVolume->SetFlatMesh(itk::SheetMeshToMesh<vu::MeshType>(shell.Flat));
  EXPECT_THROW(noVolume->Update(), itk::ExceptionObject);
  // The policy on its own: a stack that does not hold the layers it is said to.
  itk::ReadableTextureSettings settings;
  settings.NumberOfLayers = 9;
  auto filter = MakeFilter(shell);
  filter->Update();
  EXPECT_THROW(itk::SelectReadableTexture(filter->GetLayerStackOutput(), settings), itk::ExceptionObject);
  EXPECT_THROW(itk::SelectReadableTexture(nullptr, settings), itk::ExceptionObject);
}

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
#include "itkSheetRollAxis.h"
#include "itkBinaryBallStructuringElement.h"
#include "itkBinaryDilateImageFilter.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkParallelImageRows.h"
#include "itkRecursiveGaussianImageFilter.h"
#include "itkResampleImageFilter.h"
#include "itkSheetMidSurfaceExtractor.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "vnl/algo/vnl_determinant.h"
#include "vnl/algo/vnl_symmetric_eigensystem.h"

namespace itk {
namespace {
using IntensityImageType = SheetRollAxis::IntensityImageType;

// The largest tilt of the structure tensor's axis from the slice normal that is taken as a
// roll's axis, in degrees.
constexpr double LargestTilt = 45.0;
// The middle eigenvalue of the structure tensor at or below this many times the smallest:
// no spread of the normals across the tensor's axis (a flat sheet), which then says nothing
// of a roll's axis.
constexpr double SpreadEigenvalueRatio = 1.25;
// Degrees by which the centroids' line may leave the tensor's axis (where that shows some
// spread of the normals) before the tensor's axis is taken.
constexpr double LargestDisagreement = 2.0;
// The middle eigenvalue of the structure tensor below this fraction of the largest: the
// normals all lie near one direction (a flat or gently curved sheet, a page), as a roll's,
// even a squashed one's (0.28 at an axes ratio of 0.3), do not.
constexpr double FlatSheetFraction = 0.15;

IntensityImageType::Pointer
GaussianDerivative(const IntensityImageType * input, const IntensityImageType::SpacingType & sigmas, unsigned int d)
{
  // The derivative along d of itk::GradientRecursiveGaussianImageFilter, value for value
  // (the same recursive filters, sigmas and order: the derivative along d with the last
  // sigma, then smoothing along the other two axes with the first and second), per voxel.
  // Its single-threaded copy of every derivative into a vector image, per physical unit,
  // and pass over it for the direction are left out (the caller divides by the spacing and
  // applies the direction only at the voxels the tensor reads): on a scan of 180 M voxels
  // those took six seconds on one thread.
  using FilterType = RecursiveGaussianImageFilter<IntensityImageType, IntensityImageType>;
  auto derivative = FilterType::New();
  derivative->SetInput(input);
  derivative->SetOrder(GaussianOrderEnum::FirstOrder);
  derivative->SetNormalizeAcrossScale(false);
  derivative->SetSigma(sigmas[2]);
  derivative->SetDirection(d);
  derivative->InPlaceOff();
  // The filters stay referenced until the update: an output keeps no hold on its source.
  std::array<FilterType::Pointer, 3> chain{ derivative, FilterType::New(), FilterType::New() };
  unsigned int                       direction = 0;
  for (unsigned int i = 0; i < 2; ++i, ++direction)
  {
    direction += direction == d ? 1 : 0;
    const FilterType::Pointer & smoothing = chain[i + 1];
    smoothing->SetInput(chain[i]->GetOutput());
    smoothing->SetOrder(GaussianOrderEnum::ZeroOrder);
    smoothing->SetNormalizeAcrossScale(false);
    smoothing->SetSigma(sigmas[i]);
    smoothing->SetDirection(direction);
    smoothing->InPlaceOn();
  }
  const FilterType::Pointer & last = chain[2];
  last->Update();
  IntensityImageType::Pointer result = last->GetOutput();
  result->DisconnectPipeline();
  return result;
}
} // namespace

SheetRollAxis::AxisType
SheetRollAxis::Estimate(const SheetImageType *     sheetMask,
                        const IntensityImageType * sheetIntensity,
                        bool &                     fromTensor,
                        AxisType *                 tensorAxisInReach,
                        double *                   tensorSpread,
                        AxisType *                 flatSheetNormal)
{
  // The sheet does not change along the roll axis: its normals all lie across it, so the
  // axis is the direction of least gradient energy over the sheet (the structure tensor's
  // smallest eigenvector), taken from the lightly smoothed intensities (the mask where
  // there are none). Isotropic noise adds to every eigenvalue alike and moves no
  // eigenvector; the roll's edges add energy along the axis only. A flat or gently curved
  // sheet has two small eigenvalues and no such axis: then the centroids' line decides.
  // The gradient is the Gaussian derivative, not a central difference of the smoothed
  // image: a central difference damps a thin sheet's high in-plane frequencies more than
  // its low ones along the slices, which tips every normal towards the slice normal and
  // overstates a tilt by about a tenth (2 degrees at 17).
  const IntensityImageType *  input = sheetIntensity;
  IntensityImageType::Pointer maskIntensities;
  if (input == nullptr)
  {
    // The mask as 0 / 1 intensities on its own buffered box.
    maskIntensities = IntensityImageType::New();
    maskIntensities->CopyInformation(sheetMask);
    maskIntensities->SetRegions(sheetMask->GetBufferedRegion());
    maskIntensities->Allocate();
    const size_t count = sheetMask->GetBufferedRegion().GetNumberOfPixels();
    for (size_t i = 0; i < count; ++i)
    {
      maskIntensities->GetBufferPointer()[i] = sheetMask->GetBufferPointer()[i] != 0 ? 1.0f : 0.0f;
    }
    input = maskIntensities;
  }
  const auto &    step = input->GetSpacing();
  const uint8_t * mask = sheetMask->GetBufferPointer();
  const auto      size = sheetMask->GetBufferedRegion().GetSize();
  const auto &    direction = sheetMask->GetDirection();
  // Slice by slice in parallel, then summed in slice order (the same sum on any number of
  // threads). The air well away from the sheet (no material within NoiseProbe voxels along
  // any axis) measures the noise's own tensor per voxel, which is taken off the sheet's
  // sum for the axis's direction: noise adds gradient energy in every direction, and
  // projection noise more within the slices than across them, which tips the axis towards
  // the slice normal.
  constexpr long NoiseProbe = 3;
  const long     nx = static_cast<long>(size[0]), ny = static_cast<long>(size[1]), nz = static_cast<long>(size[2]);
  auto           material = [&](long i, long j, long k) {
    return i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz && mask[(k * ny + j) * nx + i] != 0;
  };
  auto farFromSheet = [&](long i, long j, long k) {
    for (long d = 1; d <= NoiseProbe; ++d)
    {
      if (material(i - d, j, k) || material(i + d, j, k) || material(i, j - d, k) || material(i, j + d, k) ||
          material(i, j, k - d) || material(i, j, k + d))
      {
        return false;
      }
    }
    return true;
  };
  // The voxels the tensor reads, per slice in row order (offsets within the slice): the
  // sheet's, and the air's from every other voxel of every other row (a sample is enough
  // for its mean), with their three derivatives. The derivatives are computed one at a
  // time and kept only there: three float images of the sheet's box held at once were the
  // largest part of the mesh stage's memory.
  struct SliceReads
  {
    std::vector<uint32_t>             Offsets[2]; // 0: sheet, 1: air
    std::vector<std::array<float, 3>> Values[2];
  };
  if (size[0] * size[1] > std::numeric_limits<uint32_t>::max())
  {
    itkGenericExceptionMacro(<< "roll axis: slices of " << size[0] << " x " << size[1] << " voxels are too large");
  }
  std::vector<SliceReads> reads(size[2]);
  ForEachImageRow(
    sheetMask, sheetMask->GetBufferedRegion(), [&](SizeValueType k, SizeValueType j, const uint8_t * row) {
      for (size_t i = 0; i < size[0]; ++i)
      {
        const bool onSheet = row[i] != 0;
        if (!onSheet && (sheetIntensity == nullptr || i % 2 != 0 || j % 2 != 0 ||
                         !farFromSheet(static_cast<long>(i), static_cast<long>(j), static_cast<long>(k))))
        {
          continue;
        }
        reads[k].Offsets[onSheet ? 0 : 1].push_back(static_cast<uint32_t>(j * size[0] + i));
      }
    });
  for (auto & slice : reads)
  {
    for (unsigned which = 0; which < 2; ++which)
    {
      slice.Offsets[which].shrink_to_fit();
      slice.Values[which].resize(slice.Offsets[which].size());
    }
  }
  // Sigma: one voxel along each axis (as ITK's gradient filter assigns a sigma array).
  const SizeValueType sliceVoxels = size[0] * size[1];
  for (unsigned int d = 0; d < 3; ++d)
  {
    const IntensityImageType::Pointer derivative = GaussianDerivative(input, sheetMask->GetSpacing(), d);
    const float *                     values = derivative->GetBufferPointer();
    MultiThreaderBase::New()->ParallelizeArray(
      0,
      size[2],
      [&](SizeValueType k) {
        for (unsigned which = 0; which < 2; ++which)
        {
          const std::vector<uint32_t> & offsets = reads[k].Offsets[which];
          for (size_t n = 0; n < offsets.size(); ++n)
          {
            reads[k].Values[which][n][d] = values[k * sliceVoxels + offsets[n]];
          }
        }
      },
      nullptr);
  }
  // Per slice: the sheet's and the air's tensor sums (entries 0-8) and voxel counts (9).
  std::vector<std::array<double, 10>> sheetSums(size[2], std::array<double, 10>{});
  std::vector<std::array<double, 10>> airSums(size[2], std::array<double, 10>{});
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[2],
    [&](SizeValueType k) {
      for (unsigned which = 0; which < 2; ++which)
      {
        std::array<double, 10> & sum = which == 0 ? sheetSums[k] : airSums[k];
        for (const auto & derivative : reads[k].Values[which])
        {
          // The gradient in the physical frame: per physical unit, as the gradient filter
          // gives it (divided in double, then float), then the image's direction applied.
          float perUnit[3];
          for (unsigned d = 0; d < 3; ++d)
          {
            perUnit[d] = static_cast<float>(static_cast<double>(derivative[d]) / step[d]);
          }
          const CovariantVector<float, 3> local(perUnit);
          CovariantVector<float, 3>       physical;
          input->TransformLocalVectorToPhysicalVector(local, physical);
          for (unsigned r = 0; r < 3; ++r)
          {
            for (unsigned c = 0; c < 3; ++c)
            {
              sum[3 * r + c] += static_cast<double>(physical[r]) * static_cast<double>(physical[c]);
            }
          }
          sum[9] += 1.0;
        }
      }
      reads[k] = SliceReads{};
    },
    nullptr);
  vnl_matrix<double> tensor(3, 3, 0.0), air(3, 3, 0.0);
  double             sheetCount = 0.0, airCount = 0.0;
  for (size_t k = 0; k < size[2]; ++k)
  {
    sheetCount += sheetSums[k][9];
    airCount += airSums[k][9];
    for (unsigned r = 0; r < 3; ++r)
    {
      for (unsigned c = 0; c < 3; ++c)
      {
        tensor(r, c) += sheetSums[k][3 * r + c];
        air(r, c) += airSums[k][3 * r + c];
      }
    }
  }
  // Whether the sheet is a roll is decided on the whole tensor, noise and all (the same
  // test for a clean and a noisy scan of one object); the axis's direction is taken with
  // the noise's share off, given enough air for a mean (a box the sheet fills leaves
  // little).
  constexpr double                        LeastAirVoxels = 1000.0;
  const vnl_symmetric_eigensystem<double> eigen(tensor);
  const vnl_symmetric_eigensystem<double> withoutNoise(
    airCount >= LeastAirVoxels ? tensor - (sheetCount / airCount) * air : tensor);
  // Eigenvalues ascending. A roll spreads its normals across the axis: the two large
  // eigenvalues are far above the axis's, or (an elliptic roll whose radius changes along
  // the axis, whose normals tilt towards it) still clearly above it and comparable with
  // each other, as a flat or gently curved sheet's are not.
  constexpr double rolledEigenvalueRatio = 2.5;
  constexpr double tiltedEigenvalueRatio = 1.5;
  constexpr double comparableEigenvalues = 0.25;
  AxisType         tensorAxis, sliceNormal;
  for (unsigned r = 0; r < 3; ++r)
  {
    tensorAxis[r] = withoutNoise.get_eigenvector(0)[r];
    sliceNormal[r] = direction[r][2];
  }
  const double cosine = tensorAxis * sliceNormal;
  if (cosine < 0.0)
  {
    tensorAxis = -tensorAxis;
  }
  const bool   tensorInReach = std::abs(cosine) >= std::cos(LargestTilt * Math::pi / 180.0);
  const double smallest = std::max(eigen.get_eigenvalue(0), 0.0), middle = eigen.get_eigenvalue(1);
  if (tensorInReach && tensorAxisInReach != nullptr)
  {
    *tensorAxisInReach = tensorAxis;
  }
  if (tensorSpread != nullptr)
  {
    *tensorSpread = smallest > 0.0 ? middle / smallest : std::numeric_limits<double>::infinity();
  }
  if (flatSheetNormal != nullptr)
  {
    flatSheetNormal->Fill(0.0);
    if (middle < FlatSheetFraction * eigen.get_eigenvalue(2))
    {
      for (unsigned r = 0; r < 3; ++r)
      {
        (*flatSheetNormal)[r] = withoutNoise.get_eigenvector(2)[r];
      }
    }
  }
  if (tensorInReach && middle > 0.0 &&
      (middle > rolledEigenvalueRatio * smallest ||
       (middle > tiltedEigenvalueRatio * smallest && middle > comparableEigenvalues * eigen.get_eigenvalue(2))))
  {
    fromTensor = true;
    return tensorAxis;
  }
  fromTensor = false;
  return EstimateFromCentroids(sheetMask);
}

SheetRollAxis::AxisType
SheetRollAxis::EstimateFromCentroids(const SheetImageType * sheetMask)
{
  // Least-squares line i(k), j(k) through the centroids of the middle 60 % of the slices
  // with material: slices near the ends of a tilted roll cut it partly, which biases them.
  const auto          size = sheetMask->GetBufferedRegion().GetSize();
  std::vector<double> count(size[2], 0.0), sumI(size[2], 0.0), sumJ(size[2], 0.0);
  ForEachImageRow(
    sheetMask, sheetMask->GetBufferedRegion(), [&](SizeValueType k, SizeValueType j, const uint8_t * row) {
      for (size_t i = 0; i < size[0]; ++i)
      {
        if (row[i] != 0)
        {
          count[k] += 1.0;
          sumI[k] += static_cast<double>(i);
          sumJ[k] += static_cast<double>(j);
        }
      }
    });
  long first = -1, last = -1;
  for (size_t k = 0; k < size[2]; ++k)
  {
    if (count[k] > 0.0)
    {
      first = first < 0 ? static_cast<long>(k) : first;
      last = static_cast<long>(k);
    }
  }
  const long margin = (last - first) / 5;
  double     sw = 0, sk = 0, skk = 0, si = 0, sj = 0, ski = 0, skj = 0;
  for (long k = first + margin; k <= last - margin && k >= 0; ++k)
  {
    const auto kk = static_cast<double>(k);
    sw += count[k];
    sk += count[k] * kk;
    skk += count[k] * kk * kk;
    si += sumI[k];
    sj += sumJ[k];
    ski += kk * sumI[k];
    skj += kk * sumJ[k];
  }
  const double denominator = sw * skk - sk * sk;
  double       slope[2] = { 0.0, 0.0 };
  if (denominator > 1e-9 * sw * sw)
  {
    slope[0] = (sw * ski - sk * si) / denominator;
    slope[1] = (sw * skj - sk * sj) / denominator;
  }
  const auto & spacing = sheetMask->GetSpacing();
  const auto & direction = sheetMask->GetDirection();
  AxisType     axis;
  for (unsigned r = 0; r < 3; ++r)
  {
    axis[r] =
      direction[r][0] * spacing[0] * slope[0] + direction[r][1] * spacing[1] * slope[1] + direction[r][2] * spacing[2];
  }
  axis.Normalize();
  return axis;
}

bool
SheetRollAxis::Align(SheetImageType::Pointer &     sheetMask,
                     IntensityImageType::Pointer & sheetIntensity,
                     SheetImageType::Pointer &     sheetData,
                     double                        tiltTolerance,
                     std::vector<std::string> &    warnings)
{
  const SheetImageType::Pointer     originalMask = sheetMask;
  const IntensityImageType::Pointer originalIntensity = sheetIntensity;
  const auto &                      spacing = originalMask->GetSpacing();
  const auto &                      direction = originalMask->GetDirection();
  const auto                        size = originalMask->GetBufferedRegion().GetSize();
  const double                      inPlane = std::min(spacing[0], spacing[1]);
  const bool                        square = std::abs(spacing[0] - spacing[1]) <= 1e-6 * inPlane;
  auto                              angle = [](const AxisType & a, const AxisType & b) {
    return std::acos(std::clamp(a * b, -1.0, 1.0)) * 180.0 / Math::pi;
  };
  auto sliceNormal = [](const SheetImageType * image) {
    AxisType normal;
    for (unsigned r = 0; r < 3; ++r)
    {
      normal[r] = image->GetDirection()[r][2];
    }
    return normal;
  };
  const AxisType originalNormal = sliceNormal(originalMask);
  bool           fromTensor = false;
  AxisType       tensorAxis{ 0.0 };
  double         spread = 0.0;
  AxisType       flatNormal{ 0.0 };
  AxisType       axis = Estimate(originalMask, originalIntensity, fromTensor, &tensorAxis, &spread, &flatNormal);
  // A flat or gently curved sheet has no roll axis: the tensor's least direction is the
  // noise's and the edges', and the centroids of slices that cut it aslant move along it, so
  // that each refinement tilts the slices further (a page went from 8 to 88 degrees in four).
  // Any direction in its plane lets the slices cut across it; the one nearest the slice
  // normal resamples least (not at all where the slices already do).
  bool flat = false;
  if (!fromTensor && flatNormal.GetNorm() > 0.0)
  {
    AxisType inPlane = originalNormal - (originalNormal * flatNormal) * flatNormal;
    if (inPlane.GetNorm() >= std::sin(LargestTilt * Math::pi / 180.0))
    {
      inPlane.Normalize();
      axis = inPlane;
      flat = true;
    }
  }
  // The centroids of a short roll's slices (a disc-like roll, cut across its faces by the
  // slices of a tilt) move across it, not along it: where their line leaves the slice normal
  // by more than the tensor's reach while the tensor's axis lies within it, or leaves the
  // tensor's axis by more than a few degrees (its eigenvalues were too close for a roll only
  // because the radius changes along the axis or the section is squashed, but show a spread
  // of the normals across it), the tensor's axis is the roll's. Refined on the resampled
  // grids, a short roll's centroids' line can also drift away from a good first estimate.
  auto preferTensor = [&]() {
    // Between the two lines, whichever way each points.
    const double between = angle(axis, tensorAxis);
    const double apart = std::min(between, 180.0 - between);
    if (!fromTensor && !flat && tensorAxis.GetNorm() > 0.0 &&
        (angle(axis, originalNormal) > LargestTilt || (spread > SpreadEigenvalueRatio && apart > LargestDisagreement)))
    {
      axis = tensorAxis;
      fromTensor = true;
    }
  };
  preferTensor();
  if (angle(axis, originalNormal) <= tiltTolerance && square)
  {
    return fromTensor;
  }
  // Each pass resamples the original box along the current estimate. The structure tensor's
  // estimate is global and needs one (the last, where it replaces the centroids'); the
  // centroids' is better from a better aligned grid (partial slices bias it less), so it
  // converges in a few.
  for (int pass = 0; pass < 4 || fromTensor || flat; ++pass)
  {
    AxisType firstAxis;
    for (unsigned r = 0; r < 3; ++r)
    {
      firstAxis[r] = direction[r][0];
    }
    firstAxis -= (firstAxis * axis) * axis;
    firstAxis.Normalize();
    const AxisType                secondAxis = CrossProduct(axis, firstAxis);
    SheetImageType::DirectionType newDirection;
    for (unsigned r = 0; r < 3; ++r)
    {
      newDirection[r][0] = firstAxis[r];
      newDirection[r][1] = secondAxis[r];
      newDirection[r][2] = axis[r];
    }
    SheetImageType::SpacingType newSpacing;
    newSpacing[0] = newSpacing[1] = inPlane;
    newSpacing[2] = spacing[2];
    // Bounds of the original box's corners in the new frame.
    double       lower[3] = { 1e300, 1e300, 1e300 }, upper[3] = { -1e300, -1e300, -1e300 };
    const auto & origin = originalMask->GetOrigin();
    for (unsigned corner = 0; corner < 8; ++corner)
    {
      SheetImageType::IndexType index;
      for (unsigned d = 0; d < 3; ++d)
      {
        index[d] = (corner >> d) & 1U ? static_cast<IndexValueType>(size[d]) - 1 : 0;
      }
      SheetImageType::PointType point;
      originalMask->TransformIndexToPhysicalPoint(index, point);
      for (unsigned d = 0; d < 3; ++d)
      {
        double coordinate = 0.0;
        for (unsigned r = 0; r < 3; ++r)
        {
          coordinate += newDirection[r][d] * (point[r] - origin[r]);
        }
        lower[d] = std::min(lower[d], coordinate);
        upper[d] = std::max(upper[d], coordinate);
      }
    }
    SheetImageType::PointType newOrigin;
    SheetImageType::SizeType  newSize;
    for (unsigned r = 0; r < 3; ++r)
    {
      newOrigin[r] =
        origin[r] + newDirection[r][0] * lower[0] + newDirection[r][1] * lower[1] + newDirection[r][2] * lower[2];
      newSize[r] = static_cast<SizeValueType>(std::ceil((upper[r] - lower[r]) / newSpacing[r])) + 1;
    }
    // Binary images are resampled by nearest neighbour, 0 beyond the original box.
    auto resampleBinary = [&](const SheetImageType * image) {
      auto resampler = ResampleImageFilter<SheetImageType, SheetImageType>::New();
      resampler->SetInput(image);
      resampler->SetInterpolator(NearestNeighborInterpolateImageFunction<SheetImageType>::New());
      resampler->SetOutputOrigin(newOrigin);
      resampler->SetOutputSpacing(newSpacing);
      resampler->SetOutputDirection(newDirection);
      resampler->SetSize(newSize);
      resampler->SetDefaultPixelValue(0);
      resampler->Update();
      return SheetImageType::Pointer(resampler->GetOutput());
    };
    sheetMask = resampleBinary(originalMask);
    // Where the resampled box reaches beyond the original one there is no data of the scan:
    // a sheet cut there by the field of view is unknown, not absent.
    auto inside = SheetImageType::New();
    inside->CopyInformation(originalMask);
    inside->SetRegions(originalMask->GetBufferedRegion());
    inside->Allocate();
    inside->FillBuffer(1);
    sheetData = resampleBinary(inside);
    if (originalIntensity)
    {
      const float * values = originalIntensity->GetBufferPointer();
      const float air = *std::min_element(values, values + originalIntensity->GetBufferedRegion().GetNumberOfPixels());
      auto        resampler = ResampleImageFilter<IntensityImageType, IntensityImageType>::New();
      resampler->SetInput(originalIntensity);
      resampler->SetOutputOrigin(newOrigin);
      resampler->SetOutputSpacing(newSpacing);
      resampler->SetOutputDirection(newDirection);
      resampler->SetSize(newSize);
      resampler->SetDefaultPixelValue(air);
      resampler->Update();
      sheetIntensity = resampler->GetOutput();
    }
    if (fromTensor || flat)
    {
      break;
    }
    const AxisType refined = EstimateFromCentroids(sheetMask);
    if (angle(refined, sliceNormal(sheetMask)) <= 0.25 * tiltTolerance)
    {
      break;
    }
    axis = refined;
    preferTensor();
  }
  std::ostringstream text;
  text << "the volume was resampled along the roll axis";
  if (angle(axis, originalNormal) > tiltTolerance)
  {
    text << ", which is tilted by " << angle(axis, originalNormal) << " degrees from the slice normal";
  }
  else
  {
    text << " to square in-plane voxels of " << inPlane;
  }
  warnings.push_back(text.str());
  return fromTensor;
}

void
SheetRollAxis::HideOtherSheets(SheetImageType * sheetMask, IntensityImageType * sheetIntensity)
{
  uint8_t *    mask = sheetMask->GetBufferPointer();
  const size_t count = sheetMask->GetBufferedRegion().GetNumberOfPixels();
  if (std::none_of(mask, mask + count, [](uint8_t v) { return v == 2; }))
  {
    return;
  }
  if (sheetIntensity == nullptr)
  {
    std::replace(mask, mask + count, uint8_t{ 2 }, uint8_t{ 0 });
    return;
  }
  // The zone within two voxels of each kind of material (a blurred sheet's rim reaches
  // about that far).
  auto within = [sheetMask](uint8_t value) {
    using KernelType = BinaryBallStructuringElement<uint8_t, 3>;
    KernelType kernel;
    kernel.SetRadius(2);
    kernel.CreateStructuringElement();
    auto dilate = BinaryDilateImageFilter<SheetImageType, SheetImageType, KernelType>::New();
    dilate->SetInput(sheetMask);
    dilate->SetKernel(kernel);
    dilate->SetForegroundValue(value);
    dilate->SetBackgroundValue(0);
    dilate->Update();
    SheetImageType::Pointer zone = dilate->GetOutput();
    zone->DisconnectPipeline();
    return zone;
  };
  const SheetImageType::Pointer nearOther = within(2);
  const SheetImageType::Pointer nearSheet = within(1);
  const uint8_t *               other = nearOther->GetBufferPointer();
  const uint8_t *               sheet = nearSheet->GetBufferPointer();
  float *                       values = sheetIntensity->GetBufferPointer();
  // Air: the voxels near no material at all; where the box holds too few, its median.
  std::vector<float> air;
  for (size_t i = 0; i < count; ++i)
  {
    if (other[i] != 2 && sheet[i] != 1)
    {
      air.push_back(values[i]);
    }
  }
  if (air.size() < 64)
  {
    air.clear();
    for (size_t i = 0; i < count; ++i)
    {
      if (mask[i] == 0)
      {
        air.push_back(values[i]);
      }
    }
    if (air.empty())
    {
      air.push_back(*std::min_element(values, values + count));
    }
    std::nth_element(air.begin(), air.begin() + air.size() / 2, air.end());
    air = { air[air.size() / 2] };
  }
  std::minstd_rand                      draw(20040601);
  std::uniform_int_distribution<size_t> pick(0, air.size() - 1);
  for (size_t i = 0; i < count; ++i)
  {
    if (mask[i] == 2 || (mask[i] == 0 && other[i] == 2 && sheet[i] != 1))
    {
      values[i] = air[pick(draw)];
    }
  }
  std::replace(mask, mask + count, uint8_t{ 2 }, uint8_t{ 0 });
}

void
SheetRollAxis::Denoise(const SheetImageType *        sheetMask,
                       IntensityImageType::Pointer & sheetIntensity,
                       std::vector<std::string> &    warnings)
{
  const size_t       count = sheetMask->GetBufferedRegion().GetNumberOfPixels();
  const size_t       stride = std::max<size_t>(1, count / 400000);
  std::vector<float> air, material;
  const uint8_t *    mask = sheetMask->GetBufferPointer();
  const float *      values = sheetIntensity->GetBufferPointer();
  for (size_t i = 0; i < count; i += stride)
  {
    (mask[i] != 0 ? material : air).push_back(values[i]);
  }
  const SheetIntensityLevels levels = EstimateSheetIntensityLevels(std::move(air), std::move(material));
  const double               sigma = levels.DenoisingSigma();
  if (!(sigma > 0.0))
  {
    return;
  }
  // The slices now cut across the roll axis, along which the sheet does not change: smooth
  // twice as much along it as across the sheet.
  const auto & spacing = sheetIntensity->GetSpacing();
  SmoothingRecursiveGaussianImageFilter<IntensityImageType, IntensityImageType>::SigmaArrayType sigmas;
  sigmas[0] = sigma * spacing[0];
  sigmas[1] = sigma * spacing[1];
  sigmas[2] = 2.0 * sigma * spacing[2];
  auto smoothing = SmoothingRecursiveGaussianImageFilter<IntensityImageType, IntensityImageType>::New();
  smoothing->SetInput(sheetIntensity);
  smoothing->SetSigmaArray(sigmas);
  smoothing->Update();
  sheetIntensity = smoothing->GetOutput();
  std::ostringstream text;
  text << "noisy scan (sheet contrast " << levels.SignalToNoise()
       << " times the noise): intensities smoothed for tracing, Gaussian sigma " << sigma << " voxel across and "
       << 2.0 * sigma << " along the roll axis";
  warnings.push_back(text.str());
}
} // end namespace itk

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
#include "itkTouchingSheetSplitter.h"

#include "itkConnectedComponentImageFilter.h"
#include "itkDanielssonDistanceMapImageFilter.h"
#include "itkHessianRecursiveGaussianImageFilter.h"
#include "itkImageRegionConstIterator.h"
#include "itkRelabelComponentImageFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <unordered_set>
#include <utility>
#include <vector>

#include "vnl/algo/vnl_symmetric_eigensystem.h"

namespace itk {
namespace {
using PieceImage = Image<uint8_t, 3>;
using LabelImage = Image<uint32_t, 3>;

// The fractions of the median plate measure at which cores are taken, lowest first. Where a
// page bulges onto the next and fuses with it, the fused slab's middle keeps about 0.8 of a
// sheet's measure (blur and the sheets' overlap), near the median: its cores part only
// above it.
constexpr double CoreFractions[] = { 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3 };
// Parts of a core whose footprints on its mean plane overlap by at least this share of the
// smaller one lie one on the other.
constexpr double StackedOverlap = 0.5;
// Where the parts met (the core's voxels left out of them within ContactReach voxels of two
// of them) must lie inside every part's footprint: by this share of its extent along each
// direction of the plane, and a voxel more. Pages fuse where one bulges onto the next,
// within both; a fold's panels meet at its crease, on the edge of both.
constexpr long   ContactReach = 2;
constexpr double ContactInset = 0.05;
// The other two eigenvalues must stay below this share of the plate's.
constexpr double PlateDominance = 0.5;
// A plate voxel's normal (the Hessian's eigenvector across the sheet, in the image's axes)
// packed in a byte a component, of length NormalScale.
using PackedNormal = std::array<int8_t, 3>;
constexpr double NormalScale = 127.0;
// A voxel lies on another sheet when it is further across its nearest core than half the
// sheet's thickness less half the core's by more than this many voxels (the sheets' blurred
// faces, the mask's staircase, the normal's error). On three clear books, voxels given to
// the wrong page: 651, 715 and 122 by the nearest core alone; 147, 720 and 96 with 1.5;
// with 0.5 a page's own face voxels went to the page it touches (1175, 738, 333); with 2 the
// tips stayed with the page below (651, 704, 111).
constexpr double StackedMargin = 1.5;
// The measure's scale per sheet thickness (a 2.5-voxel sheet: one voxel).
constexpr double ScalePerThickness = 0.4;
// The piece is split again at the scale its thinnest part asks for when that is below this
// share of the piece's own.
constexpr double FinerScaleShare = 0.85;
// The finer split is kept where every two of its sheets meet over less than FusedShare of the
// smaller one's footprint, or the intensity where they meet dips at least FinerSplitGap of
// the way from the sheets' level to the air's (SheetsLieApart).
constexpr double FusedShare = 0.5;
constexpr double FinerSplitGap = 0.25;
// A core that falls apart is split only into parts of at least this share of it.
constexpr double SliverFraction = 0.05;

// Face-connected components of the voxels where `inside` holds, largest first.
template <typename TInside>
LabelImage::Pointer
Components(const PieceImage * like, TInside inside, std::vector<SizeValueType> & sizes)
{
  auto mask = PieceImage::New();
  mask->CopyInformation(like);
  mask->SetRegions(like->GetBufferedRegion());
  mask->Allocate();
  const SizeValueType n = like->GetBufferedRegion().GetNumberOfPixels();
  for (SizeValueType v = 0; v < n; ++v)
  {
    mask->GetBufferPointer()[v] = inside(v) ? 1 : 0;
  }
  auto components = ConnectedComponentImageFilter<PieceImage, LabelImage>::New();
  components->SetInput(mask);
  components->FullyConnectedOff();
  auto relabel = RelabelComponentImageFilter<LabelImage, LabelImage>::New();
  relabel->SetInput(components->GetOutput());
  relabel->Update();
  sizes = relabel->GetSizeOfObjectsInPixels();
  LabelImage::Pointer labels = relabel->GetOutput();
  labels->DisconnectPipeline();
  return labels;
}

// The scale of the plate measure for a piece's sheets: at least `sigma`, and at least
// ScalePerThickness times their thickness, twice the piece's volume over its surface (faces
// between its voxels and the others; a staircase overstates an oblique sheet's surface, so
// this errs thin). At a scale well below a thick sheet's half thickness, each face would
// make a ridge of its own.
double
MeasureScale(const PieceImage * piece, double sigma)
{
  return std::max(
    sigma, ScalePerThickness * PlateThickness(piece, piece->GetBufferedRegion(), [](uint8_t v) { return v != 0; }));
}

// The plate measure (minus the across-sheet eigenvalue of the Hessian where it dominates)
// on the piece's voxels, 0 elsewhere; `measured` receives its non-zero values.
std::vector<float>
PlateMeasure(const Image<float, 3> *     values,
             const PieceImage *          piece,
             double                      sigma,
             std::vector<double> &       measured,
             std::vector<PackedNormal> & normals)
{
  const SizeValueType n = piece->GetBufferedRegion().GetNumberOfPixels();
  const uint8_t *     in = piece->GetBufferPointer();
  using HessianFilter = HessianRecursiveGaussianImageFilter<Image<float, 3>>;
  auto hessian = HessianFilter::New();
  hessian->SetInput(values);
  hessian->SetSigma(sigma);
  hessian->SetNormalizeAcrossScale(false);
  hessian->Update();
  const auto *       tensors = hessian->GetOutput()->GetBufferPointer();
  std::vector<float> plate(n, 0.0f);
  normals.assign(n, PackedNormal{ 0, 0, 0 });
  for (SizeValueType v = 0; v < n; ++v)
  {
    if (in[v] == 0)
    {
      continue;
    }
    typename HessianFilter::OutputPixelType::EigenValuesArrayType   e;
    typename HessianFilter::OutputPixelType::EigenVectorsMatrixType vectors;
    tensors[v].ComputeEigenAnalysis(e, vectors);
    unsigned order[3] = { 0, 1, 2 };
    std::sort(std::begin(order), std::end(order), [&e](unsigned a, unsigned b) { return e[a] < e[b]; });
    const double across = e[order[0]];
    if (across < 0.0 && std::max(std::abs(e[order[1]]), std::abs(e[order[2]])) < PlateDominance * -across)
    {
      plate[v] = static_cast<float>(-across);
      measured.push_back(-across);
      for (unsigned d = 0; d < 3; ++d)
      {
        normals[v][d] = static_cast<int8_t>(std::lround(NormalScale * vectors[order[0]][d]));
      }
    }
  }
  return plate;
}

struct Core
{
  std::vector<SizeValueType> Voxels;
};

// Whether `parts` (labelled 1 to parts.size() in `partOf`) are sheets that touch within
// `core`: every two lie one on the other, their footprints on the plane of their voxels'
// two largest principal directions (one-voxel bins) overlapping by at least StackedOverlap
// of the smaller, and where they met lies inside every footprint (ContactInset). The
// parts into which noise or ink breaks one sheet's core lie side by side; the panels of a
// fold lie one on the other but meet at the crease, on their edges.
bool
Stacked(const PieceImage * piece, const Core & core, const std::vector<Core> & parts, const uint32_t * partOf)
{
  const auto   size = piece->GetBufferedRegion().GetSize();
  const auto & spacing = piece->GetSpacing();
  auto         at = [&](SizeValueType v, double * p) {
    p[0] = static_cast<double>(v % size[0]) * spacing[0];
    p[1] = static_cast<double>((v / size[0]) % size[1]) * spacing[1];
    p[2] = static_cast<double>(v / (size[0] * size[1])) * spacing[2];
  };
  double mean[3] = { 0.0, 0.0, 0.0 };
  double count = 0.0;
  for (const Core & part : parts)
  {
    for (SizeValueType v : part.Voxels)
    {
      double p[3];
      at(v, p);
      for (unsigned d = 0; d < 3; ++d)
      {
        mean[d] += p[d];
      }
      count += 1.0;
    }
  }
  for (double & m : mean)
  {
    m /= count;
  }
  vnl_matrix<double> covariance(3, 3, 0.0);
  for (const Core & part : parts)
  {
    for (SizeValueType v : part.Voxels)
    {
      double p[3];
      at(v, p);
      for (unsigned r = 0; r < 3; ++r)
      {
        for (unsigned c = 0; c < 3; ++c)
        {
          covariance(r, c) += (p[r] - mean[r]) * (p[c] - mean[c]);
        }
      }
    }
  }
  const vnl_symmetric_eigensystem<double> eigen(covariance);
  // A voxel's place on the plane of the two largest principal directions.
  auto project = [&](SizeValueType v, double * q) {
    double p[3];
    at(v, p);
    q[0] = 0.0;
    q[1] = 0.0;
    for (unsigned d = 0; d < 3; ++d)
    {
      q[0] += (p[d] - mean[d]) * eigen.get_eigenvector(2)[d];
      q[1] += (p[d] - mean[d]) * eigen.get_eigenvector(1)[d];
    }
  };
  // Each part's footprint (one-voxel bins) and extent on the plane.
  const double                             bin = std::min({ spacing[0], spacing[1], spacing[2] });
  std::vector<std::unordered_set<int64_t>> footprints(parts.size());
  std::vector<std::array<double, 4>>       extents(parts.size(), { 1e300, 1e300, -1e300, -1e300 });
  for (size_t i = 0; i < parts.size(); ++i)
  {
    for (SizeValueType v : parts[i].Voxels)
    {
      double q[2];
      project(v, q);
      const auto iu = static_cast<int64_t>(std::lround(q[0] / bin)), iw = static_cast<int64_t>(std::lround(q[1] / bin));
      footprints[i].insert(iu * (int64_t{ 1 } << 32) + iw);
      for (unsigned d = 0; d < 2; ++d)
      {
        extents[i][d] = std::min(extents[i][d], q[d]);
        extents[i][2 + d] = std::max(extents[i][2 + d], q[d]);
      }
    }
  }
  // The contact: the core's voxels in no part with two parts within ContactReach.
  const auto label = [&](long x, long y, long z) -> uint32_t {
    if (x < 0 || y < 0 || z < 0 || x >= static_cast<long>(size[0]) || y >= static_cast<long>(size[1]) ||
        z >= static_cast<long>(size[2]))
    {
      return 0;
    }
    const uint32_t l = partOf[(static_cast<SizeValueType>(z) * size[1] + static_cast<SizeValueType>(y)) * size[0] +
                              static_cast<SizeValueType>(x)];
    return l <= parts.size() ? l : 0;
  };
  double contact[2] = { 0.0, 0.0 };
  double contacts = 0.0;
  for (SizeValueType v : core.Voxels)
  {
    const uint32_t own = partOf[v];
    if (own > 0 && own <= parts.size())
    {
      continue;
    }
    const long x = static_cast<long>(v % size[0]), y = static_cast<long>((v / size[0]) % size[1]),
               z = static_cast<long>(v / (size[0] * size[1]));
    uint32_t first = 0;
    bool     two = false;
    for (long dz = -ContactReach; dz <= ContactReach && !two; ++dz)
    {
      for (long dy = -ContactReach; dy <= ContactReach && !two; ++dy)
      {
        for (long dx = -ContactReach; dx <= ContactReach && !two; ++dx)
        {
          const uint32_t l = label(x + dx, y + dy, z + dz);
          two = l != 0 && first != 0 && l != first;
          first = first == 0 ? l : first;
        }
      }
    }
    if (two)
    {
      double q[2];
      project(v, q);
      contact[0] += q[0];
      contact[1] += q[1];
      contacts += 1.0;
    }
  }
  if (contacts == 0.0)
  {
    return false;
  }
  contact[0] /= contacts;
  contact[1] /= contacts;
  for (const auto & extent : extents)
  {
    for (unsigned d = 0; d < 2; ++d)
    {
      const double inset = ContactInset * (extent[2 + d] - extent[d]) + bin;
      if (contact[d] < extent[d] + inset || contact[d] > extent[2 + d] - inset)
      {
        return false;
      }
    }
  }
  for (size_t i = 0; i < parts.size(); ++i)
  {
    for (size_t j = i + 1; j < parts.size(); ++j)
    {
      const auto & small = footprints[i].size() <= footprints[j].size() ? footprints[i] : footprints[j];
      const auto & large = footprints[i].size() <= footprints[j].size() ? footprints[j] : footprints[i];
      const auto   shared = std::count_if(small.begin(), small.end(), [&](int64_t b) { return large.count(b) != 0; });
      if (static_cast<double>(shared) < StackedOverlap * static_cast<double>(small.size()))
      {
        return false;
      }
    }
  }
  return true;
}

// Cores: the components of the plate measure above the first fraction of its median, each
// kept whole unless it falls apart into two or more large cores at the next fraction.
std::vector<Core>
FindCores(const PieceImage * piece, const std::vector<float> & plate, double median, SizeValueType minimumCoreVoxels)
{
  const SizeValueType        n = piece->GetBufferedRegion().GetNumberOfPixels();
  std::vector<Core>          cores;
  std::vector<SizeValueType> sizes;
  auto                       first = Components(
    piece, [&](SizeValueType v) { return plate[v] > CoreFractions[0] * median; }, sizes);
  {
    std::vector<Core> found(sizes.size());
    for (SizeValueType v = 0; v < n; ++v)
    {
      const uint32_t l = first->GetBufferPointer()[v];
      if (l > 0 && sizes[l - 1] >= minimumCoreVoxels)
      {
        found[l - 1].Voxels.push_back(v);
      }
    }
    for (auto & core : found)
    {
      if (!core.Voxels.empty())
      {
        cores.push_back(std::move(core));
      }
    }
  }
  std::vector<uint8_t> inCore(n, 0);
  for (size_t step = 1; step < std::size(CoreFractions); ++step)
  {
    std::vector<Core> next;
    for (auto & core : cores)
    {
      std::fill(inCore.begin(), inCore.end(), 0);
      for (SizeValueType v : core.Voxels)
      {
        inCore[v] = plate[v] > CoreFractions[step] * median ? 1 : 0;
      }
      auto parts = Components(
        piece, [&](SizeValueType v) { return inCore[v] != 0; }, sizes);
      // Large: a sheet's core, not a speck of noise (and not a sliver of this core).
      const SizeValueType least =
        std::max<SizeValueType>(minimumCoreVoxels, static_cast<SizeValueType>(SliverFraction * core.Voxels.size()));
      const SizeValueType large =
        std::count_if(sizes.begin(), sizes.end(), [&](SizeValueType s) { return s >= least; });
      if (large < 2)
      {
        next.push_back(std::move(core));
        continue;
      }
      std::vector<Core> split(large);
      for (SizeValueType v : core.Voxels)
      {
        const uint32_t l = parts->GetBufferPointer()[v];
        if (l > 0 && l <= large)
        {
          split[l - 1].Voxels.push_back(v);
        }
      }
      // Sheets that touch lie one on the other; a core that breaks into parts side by side
      // is one sheet's, broken by noise or its ink, and stays whole.
      if (!Stacked(piece, core, split, parts->GetBufferPointer()))
      {
        next.push_back(std::move(core));
        continue;
      }
      for (auto & part : split)
      {
        next.push_back(std::move(part));
      }
    }
    cores = std::move(next);
  }
  return cores;
}

// Every voxel of the piece labelled with its nearest core (1-based, in the order of `cores`);
// `toCore` receives each voxel's offset to its nearest core voxel (index units) and
// `seedsOut` the cores' labels.
void
LabelByNearestCore(const PieceImage *             piece,
                   const std::vector<Core> &      cores,
                   uint16_t *                     out,
                   Image<Offset<3>, 3>::Pointer & toCore,
                   LabelImage::Pointer &          seedsOut)
{
  const SizeValueType n = piece->GetBufferedRegion().GetNumberOfPixels();
  const uint8_t *     in = piece->GetBufferPointer();
  auto                seeds = LabelImage::New();
  seeds->CopyInformation(piece);
  seeds->SetRegions(piece->GetBufferedRegion());
  seeds->Allocate();
  seeds->FillBuffer(0);
  for (size_t c = 0; c < cores.size(); ++c)
  {
    for (SizeValueType v : cores[c].Voxels)
    {
      seeds->GetBufferPointer()[v] = static_cast<uint32_t>(c + 1);
    }
  }
  auto nearest = DanielssonDistanceMapImageFilter<LabelImage, Image<float, 3>, LabelImage>::New();
  nearest->SetInput(seeds);
  nearest->InputIsBinaryOff();
  nearest->UseImageSpacingOn();
  nearest->Update();
  const uint32_t * voronoi = nearest->GetVoronoiMap()->GetBufferPointer();
  for (SizeValueType v = 0; v < n; ++v)
  {
    out[v] = in[v] != 0 ? static_cast<uint16_t>(voronoi[v]) : 0;
  }
  toCore = nearest->GetVectorDistanceMap();
  toCore->DisconnectPipeline();
  seedsOut = seeds;
}

// Gives the voxels that lie on another sheet back to it. Where two pages lie a voxel or so
// apart, or fuse where one bulges onto the next, a face of one page (denser where it is
// inked) can lie nearer to the other page's core than to its own, which runs off-centre or
// ends short of it; the nearest core then gives that face to the other page, whose texture
// shows this page's writing. A sheet's voxels lie within half its thickness of its middle:
// a voxel further than that across its nearest core (along the core's normal, beyond half
// the sheet's thickness less half the core's, by StackedMargin) lies on another sheet, and
// goes to the nearest core of another sheet within whose reach it lies. Voxels no other
// core takes keep their label.
void
GiveStackedVoxelsTheirSheet(const PieceImage *                piece,
                            const std::vector<Core> &         cores,
                            const std::vector<PackedNormal> & normals,
                            const Image<Offset<3>, 3> *       toCore,
                            const LabelImage *                seeds,
                            Image<uint16_t, 3> *              labelImage)
{
  const auto          region = piece->GetBufferedRegion();
  const auto          size = region.GetSize();
  const SizeValueType n = region.GetNumberOfPixels();
  const uint8_t *     in = piece->GetBufferPointer();
  const auto &        spacing = piece->GetSpacing();
  const uint32_t *    coreOf = seeds->GetBufferPointer();
  const auto *        offsets = toCore->GetBufferPointer();
  uint16_t *          labels = labelImage->GetBufferPointer();
  const double        voxel = std::cbrt(spacing[0] * spacing[1] * spacing[2]);
  const double        margin = StackedMargin * voxel;
  // Each sheet's reach across its core: half its thickness less half its core's.
  std::vector<double>       reach(cores.size() + 1, 0.0);
  double                    thickest = 0.0;
  const std::vector<double> sheets = PlateThicknessPerLabel(labelImage, region, cores.size());
  const std::vector<double> coreThickness = PlateThicknessPerLabel(seeds, region, cores.size());
  for (size_t c = 1; c <= cores.size(); ++c)
  {
    reach[c] = std::max(0.0, 0.5 * (sheets[c] - coreThickness[c])) + margin;
    thickest = std::max(thickest, sheets[c]);
  }
  long reachOut[3];
  for (unsigned d = 0; d < 3; ++d)
  {
    reachOut[d] = static_cast<long>(std::ceil((thickest + voxel) / spacing[d]));
  }
  const SizeValueType stride[3] = { 1, size[0], size[0] * size[1] };
  const auto          across = [&](SizeValueType site, const double * o) {
    const PackedNormal & normal = normals[site];
    return std::abs(o[0] * normal[0] + o[1] * normal[1] + o[2] * normal[2]) / NormalScale;
  };
  std::vector<std::pair<SizeValueType, uint16_t>> moved;
  for (SizeValueType v = 0; v < n; ++v)
  {
    if (in[v] == 0 || coreOf[v] != 0 || labels[v] == 0)
    {
      continue;
    }
    const long    at[3] = { static_cast<long>(v % size[0]),
                            static_cast<long>((v / size[0]) % size[1]),
                            static_cast<long>(v / stride[2]) };
    const auto &  o = offsets[v];
    double        own[3];
    SizeValueType site = v;
    for (unsigned d = 0; d < 3; ++d)
    {
      own[d] = static_cast<double>(o[d]) * spacing[d];
      site = static_cast<SizeValueType>(static_cast<long>(site) + o[d] * static_cast<long>(stride[d]));
    }
    if (across(site, own) <= reach[labels[v]])
    {
      continue;
    }
    double   best = std::numeric_limits<double>::infinity();
    uint16_t to = 0;
    for (long z = std::max(0L, at[2] - reachOut[2]); z <= std::min<long>(size[2] - 1, at[2] + reachOut[2]); ++z)
    {
      for (long y = std::max(0L, at[1] - reachOut[1]); y <= std::min<long>(size[1] - 1, at[1] + reachOut[1]); ++y)
      {
        for (long x = std::max(0L, at[0] - reachOut[0]); x <= std::min<long>(size[0] - 1, at[0] + reachOut[0]); ++x)
        {
          const SizeValueType u = static_cast<SizeValueType>(x) + static_cast<SizeValueType>(y) * stride[1] +
                                  static_cast<SizeValueType>(z) * stride[2];
          const uint32_t c = coreOf[u];
          if (c == 0 || c == labels[v])
          {
            continue;
          }
          const double w[3] = { static_cast<double>(x - at[0]) * spacing[0],
                                static_cast<double>(y - at[1]) * spacing[1],
                                static_cast<double>(z - at[2]) * spacing[2] };
          const double d2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
          if (d2 < best && across(u, w) <= reach[c])
          {
            best = d2;
            to = static_cast<uint16_t>(c);
          }
        }
      }
    }
    if (to != 0)
    {
      moved.emplace_back(v, to);
    }
  }
  for (auto & [v, to] : moved)
  {
    labels[v] = to;
  }
}

// `visit` on each face-neighbour of voxel v (an offset in a region of `size`) inside the
// region, until it returns false; whether it never did.
template <typename TVisit>
bool
EveryFaceNeighbour(const Size<3> & size, SizeValueType v, TVisit visit)
{
  const SizeValueType strides[3] = { 1, size[0], size[0] * size[1] };
  SizeValueType       rest = v;
  for (int d = 2; d >= 0; --d)
  {
    const SizeValueType at = rest / strides[d];
    rest %= strides[d];
    if ((at > 0 && !visit(v - strides[d])) || (at + 1 < size[d] && !visit(v + strides[d])))
    {
      return false;
    }
  }
  return true;
}

// Whether every two of the sheets labelled in `labels` that meet (the piece's voxels with a
// face-neighbour in the piece labelled with the other) lie apart: they meet over less than
// FusedShare of the smaller one's footprint (its voxels over `thickness` voxels: pages with
// a gap between them, fused where one bulges onto the other), or the intensity where they
// meet dips at least FinerSplitGap of the way from the cores' level towards the air's (the
// region's voxels outside the piece: pages whose gap the mask fills). A thick sheet's two
// faces, which a scale well below its thickness sees as two plates, meet all over across
// its dense middle.
bool
SheetsLieApart(const Image<float, 3> *       values,
               const PieceImage *            piece,
               const std::vector<Core> &     cores,
               const std::vector<uint16_t> & labels,
               double                        thickness)
{
  const auto                                                  size = piece->GetBufferedRegion().GetSize();
  const SizeValueType                                         n = piece->GetBufferedRegion().GetNumberOfPixels();
  const uint8_t *                                             in = piece->GetBufferPointer();
  const float *                                               value = values->GetBufferPointer();
  std::vector<float>                                          core, air;
  std::vector<SizeValueType>                                  voxels(cores.size() + 1, 0);
  std::map<std::pair<uint16_t, uint16_t>, std::vector<float>> meet;
  for (const Core & c : cores)
  {
    for (SizeValueType v : c.Voxels)
    {
      core.push_back(value[v]);
    }
  }
  for (SizeValueType v = 0; v < n; ++v)
  {
    if (in[v] == 0)
    {
      air.push_back(value[v]);
      continue;
    }
    ++voxels[std::min<size_t>(labels[v], cores.size())];
    uint16_t other = 0;
    EveryFaceNeighbour(size, v, [&](SizeValueType u) {
      other = in[u] != 0 && labels[u] != labels[v] ? labels[u] : 0;
      return other == 0;
    });
    if (other != 0)
    {
      meet[{ std::min(other, labels[v]), std::max(other, labels[v]) }].push_back(value[v]);
    }
  }
  const auto median = [](std::vector<float> & x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return static_cast<double>(x[x.size() / 2]);
  };
  if (core.empty() || air.empty())
  {
    return false;
  }
  const double sheet = median(core), background = median(air);
  for (auto & [pair, between] : meet)
  {
    const double footprint =
      static_cast<double>(std::min(voxels[pair.first], voxels[pair.second])) / std::max(1.0, thickness);
    // Both sides of where they meet count: half of them is the area.
    if (0.5 * static_cast<double>(between.size()) < FusedShare * footprint)
    {
      continue;
    }
    if (!(sheet > background) || (sheet - median(between)) / (sheet - background) < FinerSplitGap)
    {
      return false;
    }
  }
  return true;
}
} // namespace

TouchingSheetSplit
SplitTouchingSheets(const Image<float, 3> * values,
                    const PieceImage *      piece,
                    double                  sigma,
                    SizeValueType           minimumCoreVoxels,
                    double                  sheetThickness)
{
  if (values == nullptr || piece == nullptr || values->GetBufferedRegion() != piece->GetBufferedRegion())
  {
    itkGenericExceptionMacro(<< "SplitTouchingSheets: the values and the piece must cover the same region");
  }
  const SizeValueType n = piece->GetBufferedRegion().GetNumberOfPixels();
  const uint8_t *     in = piece->GetBufferPointer();
  const double        scale = MeasureScale(piece, sigma);
  TouchingSheetSplit  result;
  result.Labels = Image<uint16_t, 3>::New();
  result.Labels->CopyInformation(piece);
  result.Labels->SetRegions(piece->GetBufferedRegion());
  result.Labels->Allocate();
  result.Labels->FillBuffer(0);
  uint16_t * out = result.Labels->GetBufferPointer();
  auto       whole = [&]() {
    for (SizeValueType v = 0; v < n; ++v)
    {
      out[v] = in[v] != 0 ? 1 : 0;
    }
    result.Sheets = 1;
    return result;
  };
  // The cores at a scale, largest first (none when too little of the piece is plate-like).
  const auto coresAt = [&](double at, std::vector<PackedNormal> & normals) {
    std::vector<double>      measured;
    const std::vector<float> plate = PlateMeasure(values, piece, at, measured, normals);
    std::vector<Core>        cores;
    if (measured.size() >= 2 * minimumCoreVoxels)
    {
      std::nth_element(measured.begin(), measured.begin() + measured.size() / 2, measured.end());
      cores = FindCores(piece, plate, measured[measured.size() / 2], minimumCoreVoxels);
    }
    std::sort(
      cores.begin(), cores.end(), [](const Core & a, const Core & b) { return a.Voxels.size() > b.Voxels.size(); });
    return cores;
  };
  std::vector<PackedNormal>    normals;
  std::vector<Core>            cores = coresAt(scale, normals);
  Image<Offset<3>, 3>::Pointer toCore;
  LabelImage::Pointer          seeds;
  // Pages fused into one piece make it thicker than a page, and the scale its thickness sets
  // coarser than a page's: where a part split off, or the scan's thinnest sheet, asks for a
  // clearly finer scale, the piece is split again at it, and that split is kept when it
  // finds more sheets.
  double thinnest = sheetThickness > 0.0 ? sheetThickness : std::numeric_limits<double>::infinity();
  if (cores.size() >= 2)
  {
    LabelByNearestCore(piece, cores, out, toCore, seeds);
    const std::vector<double> thickness =
      PlateThicknessPerLabel(result.Labels.GetPointer(), piece->GetBufferedRegion(), cores.size());
    for (size_t c = 1; c <= cores.size(); ++c)
    {
      thinnest = thickness[c] > 0.0 ? std::min(thinnest, thickness[c]) : thinnest;
    }
  }
  const double finer = std::max(sigma, ScalePerThickness * thinnest);
  if (std::isfinite(thinnest) && finer < FinerScaleShare * scale)
  {
    std::vector<PackedNormal> finerNormals;
    std::vector<Core>         more = coresAt(finer, finerNormals);
    if (more.size() > std::max<size_t>(1, cores.size()))
    {
      std::vector<uint16_t>        finerLabels(n, 0);
      Image<Offset<3>, 3>::Pointer finerToCore;
      LabelImage::Pointer          finerSeeds;
      LabelByNearestCore(piece, more, finerLabels.data(), finerToCore, finerSeeds);
      if (SheetsLieApart(values, piece, more, finerLabels, thinnest / sigma))
      {
        cores = std::move(more);
        normals = std::move(finerNormals);
        toCore = finerToCore;
        seeds = finerSeeds;
        std::copy(finerLabels.begin(), finerLabels.end(), out);
      }
    }
  }
  if (cores.size() < 2)
  {
    return whole();
  }
  GiveStackedVoxelsTheirSheet(
    piece, cores, normals, toCore.GetPointer(), seeds.GetPointer(), result.Labels.GetPointer());
  result.Sheets = static_cast<unsigned int>(cores.size());
  return result;
}

Image<float, 3>::Pointer
BlankOtherSheets(const Image<float, 3> * volume, const Image<uint16_t, 3> * sheets, uint16_t sheet)
{
  if (volume == nullptr || sheets == nullptr || volume->GetBufferedRegion() != sheets->GetBufferedRegion())
  {
    itkGenericExceptionMacro(<< "BlankOtherSheets: the sheets' labels must cover the volume's region");
  }
  const auto          size = volume->GetBufferedRegion().GetSize();
  const SizeValueType n = volume->GetBufferedRegion().GetNumberOfPixels();
  const float *       in = volume->GetBufferPointer();
  const uint16_t *    label = sheets->GetBufferPointer();
  // The background: values of unlabelled voxels none of whose face-neighbours is labelled
  // (air, away from the sheets' blurred faces), a sample of them, drawn in a fixed order
  // so that a blanked region has the scan's own noise. A constant would be a patch without
  // noise, whose zero spread a texture's contrast measures take for signal.
  const auto everyFaceNeighbour = [&size](SizeValueType v, auto visit) { return EveryFaceNeighbour(size, v, visit); };
  std::vector<float>  air;
  const SizeValueType stride = std::max<SizeValueType>(1, n / 200000);
  for (SizeValueType v = 0; v < n; v += stride)
  {
    if (label[v] == 0 && std::isfinite(in[v]) && everyFaceNeighbour(v, [&](SizeValueType u) { return label[u] == 0; }))
    {
      air.push_back(in[v]);
    }
  }
  if (air.empty())
  {
    air.push_back(0.0f);
  }
  std::minstd_rand                      draw(20040601);
  std::uniform_int_distribution<size_t> pick(0, air.size() - 1);
  auto                                  out = Image<float, 3>::New();
  out->CopyInformation(volume);
  out->SetRegions(volume->GetBufferedRegion());
  out->Allocate();
  float * o = out->GetBufferPointer();
  std::copy_n(in, n, o);
  for (SizeValueType v = 0; v < n; ++v)
  {
    if (label[v] == 0 || label[v] == sheet)
    {
      continue;
    }
    o[v] = air[pick(draw)];
    // Its unlabelled face-neighbours.
    everyFaceNeighbour(v, [&](SizeValueType u) {
      if (label[u] == 0)
      {
        o[u] = air[pick(draw)];
      }
      return true;
    });
  }
  return out;
}
} // end namespace itk

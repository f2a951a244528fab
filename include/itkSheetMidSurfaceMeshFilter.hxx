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
#ifndef itkSheetMidSurfaceMeshFilter_hxx
#define itkSheetMidSurfaceMeshFilter_hxx

#include "itkConnectedComponentImageFilter.h"
#include "itkGradientRecursiveGaussianImageFilter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkLabelStatisticsImageFilter.h"
#include "itkNearestNeighborInterpolateImageFunction.h"
#include "itkParallelImageRows.h"
#include "itkRelabelComponentImageFilter.h"
#include "itkResampleImageFilter.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"
#include "itkTouchingSheetSplitter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

#include "vnl/algo/vnl_determinant.h"
#include "vnl/algo/vnl_symmetric_eigensystem.h"

namespace itk {
template <typename TMaskImage, typename TOutputMesh>
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::SheetMidSurfaceMeshFilter()
{
  this->SetNumberOfRequiredInputs(1);
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::SetIntensityImage(const IntensityImageType * image)
{
  this->ProcessObject::SetNthInput(1, const_cast<IntensityImageType *>(image));
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::GetIntensityImage() const -> const IntensityImageType *
{
  return dynamic_cast<const IntensityImageType *>(this->ProcessObject::GetInput(1));
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::GenerateData()
{
  const MaskImageType *      mask = this->GetInput(0);
  const IntensityImageType * intensity = this->GetIntensityImage();
  if (mask == nullptr || mask->GetBufferedRegion().GetNumberOfPixels() == 0)
  {
    itkExceptionMacro(<< "the mask is empty");
  }
  const auto region = mask->GetBufferedRegion();
  if (intensity != nullptr && intensity->GetBufferedRegion() != region)
  {
    itkExceptionMacro(<< "the intensity image (" << intensity->GetBufferedRegion().GetSize()
                      << ") does not cover the mask (" << region.GetSize() << ")");
  }
  this->UpdateProgress(0.0f);

  // One sheet = one connected mesh: keep the largest face-connected component.
  using LabelImageType = Image<SizeValueType, 3>;
  auto components = ConnectedComponentImageFilter<MaskImageType, LabelImageType>::New();
  components->SetInput(mask);
  components->FullyConnectedOff();
  auto relabel = RelabelComponentImageFilter<LabelImageType, LabelImageType>::New();
  relabel->SetInput(components->GetOutput());
  relabel->Update();
  const LabelImageType * labels = relabel->GetOutput();
  m_Report = SheetMidSurfaceReport{};
  if (relabel->GetNumberOfObjects() == 0)
  {
    itkExceptionMacro(<< "the mask is empty");
  }
  // A roll cut by the field of view falls apart into its inner part and the arcs of its
  // outer turns, which wrap around it: smaller pieces whose boxes overlap a sheet's box are
  // meshed with it when they trace as one roll (the roll tracer carries its turns through
  // the part out of view). Otherwise, and for pieces apart from it, the piece alone.
  const SizeValueType objects = relabel->GetNumberOfObjects();
  // The pieces' bounding boxes (the labels serve as their own values).
  auto pieces = LabelStatisticsImageFilter<LabelImageType, LabelImageType>::New();
  pieces->SetInput(labels);
  pieces->SetLabelInput(labels);
  pieces->Update();
  const auto & pieceSizes = relabel->GetSizeOfObjectsInPixels();
  const auto & spacing = mask->GetSpacing();
  const double voxelVolume = spacing[0] * spacing[1] * spacing[2];
  // Pieces meshed as part of a sheet, dropped or counted as too small.
  std::vector<uint8_t> done(objects + 1, 0);
  // The sheet made of the pieces of `source` (the labels, or a piece split into the sheets
  // that touch in it) whose labels are kept.
  auto meshLabels = [&](const auto * source, const std::vector<uint8_t> & keep, std::vector<std::string> & warnings) {
    auto kept = [&keep](auto label) { return static_cast<size_t>(label) < keep.size() && keep[label] != 0; };
    // Read only the bounding box of the sheet, plus two voxels.
    const typename MaskImageType::RegionType box = BoundingRegionWhere(source, kept, 2);

    // The sheet's box as images of their own (index 0 at the box corner).
    typename SheetImageType::RegionType boxRegion;
    boxRegion.SetSize(box.GetSize());
    typename SheetImageType::PointType boxOrigin;
    mask->TransformIndexToPhysicalPoint(box.GetIndex(), boxOrigin);
    typename SheetImageType::Pointer sheetMask = SheetImageType::New();
    sheetMask->SetRegions(boxRegion);
    sheetMask->SetOrigin(boxOrigin);
    sheetMask->SetSpacing(mask->GetSpacing());
    sheetMask->SetDirection(mask->GetDirection());
    sheetMask->Allocate();
    typename IntensityImageType::Pointer sheetIntensity;
    if (intensity != nullptr)
    {
      sheetIntensity = IntensityImageType::New();
      sheetIntensity->CopyInformation(sheetMask);
      sheetIntensity->SetRegions(boxRegion);
      sheetIntensity->Allocate();
    }
    {
      // Row by row, the slices in parallel; the intensities lie where the labels do.
      const auto boxSize = box.GetSize();
      ForEachImageRow(source, box, [&](SizeValueType k, SizeValueType j, const auto * label) {
        const SizeValueType to = (k * boxSize[1] + j) * boxSize[0];
        uint8_t *           out = sheetMask->GetBufferPointer() + to;
        for (SizeValueType i = 0; i < boxSize[0]; ++i)
        {
          out[i] = kept(label[i]) ? 1 : 0;
        }
        if (intensity != nullptr)
        {
          std::copy_n(intensity->GetBufferPointer() + (label - source->GetBufferPointer()),
                      boxSize[0],
                      sheetIntensity->GetBufferPointer() + to);
        }
      });
    }
    typename SheetImageType::Pointer sheetData;
    const bool axisKnown = this->AlignWithRollAxis(sheetMask, sheetIntensity, sheetData, warnings);
    if (sheetIntensity)
    {
      this->Denoise(sheetMask, sheetIntensity, warnings);
    }

    SheetVolumeView view;
    view.Mask = sheetMask->GetBufferPointer();
    view.Intensity = sheetIntensity ? sheetIntensity->GetBufferPointer() : nullptr;
    view.Data = sheetData ? sheetData->GetBufferPointer() : nullptr;
    view.AxisAlongSlices = axisKnown;
    for (unsigned d = 0; d < 3; ++d)
    {
      view.Size[d] = sheetMask->GetBufferedRegion().GetSize()[d];
      view.Spacing[d] = sheetMask->GetSpacing()[d];
    }

    SheetMidSurfaceExtractor  extractor;
    SheetMidSurfaceParameters parameters;
    parameters.Method = m_Method;
    parameters.SpacingAlongSheet = m_SpacingAlongSheet;
    parameters.SpacingAlongAxis = m_SpacingAlongAxis;
    parameters.ChordErrorFraction = m_ChordErrorFraction;
    extractor.SetParameters(parameters);
    const double progressFrom = 0.1 + 0.9 * static_cast<double>(m_Sheets.size()) / (m_EverySheet ? 4.0 : 1.0);
    extractor.SetProgressCallback([this, progressFrom](double fraction) {
      const double span = m_EverySheet ? 0.9 / 4.0 : 0.9;
      this->UpdateProgress(static_cast<float>(std::min(0.99, progressFrom + span * fraction)));
      return !this->GetAbortGenerateData();
    });
    Sheet sheet;
    sheet.Mesh = extractor.Extract(view);
    sheet.Report = extractor.GetReport();
    // From the (possibly resampled) box's scaled voxel frame to the physical frame.
    ToPhysicalFrame(sheetMask->GetOrigin(), sheetMask->GetDirection(), sheet.Mesh);
    return sheet;
  };
  auto meshPieces = [&](const std::vector<uint8_t> & keep, std::vector<std::string> & warnings) {
    return meshLabels(labels, keep, warnings);
  };

  // The sheet made from a piece: with the smaller pieces in its box that trace with it as
  // one roll, or alone.
  auto meshSheetFrom = [&](SizeValueType first, std::vector<std::string> & warnings) {
    auto                 firstBox = pieces->GetRegion(first);
    std::vector<uint8_t> group(objects + 1, 0);
    group[first] = 1;
    SizeValueType grouped = 1;
    for (SizeValueType l = first + 1; l <= objects; ++l)
    {
      // An arc of a cut turn, not a speck of noise within the roll's box.
      auto       box = pieces->GetRegion(l);
      const bool arc =
        static_cast<double>(pieceSizes[l - 1]) >= CutArcFraction * static_cast<double>(pieceSizes[first - 1]);
      group[l] = done[l] == 0 && arc && box.Crop(firstBox) ? 1 : 0;
      grouped += group[l];
    }
    if (grouped > 1 && m_Method != SheetSurfaceMethodEnum::General)
    {
      try
      {
        std::vector<std::string> groupWarnings;
        Sheet                    sheet = meshPieces(group, groupWarnings);
        // Every piece meshed with it must lie on the roll's mesh: a loose fragment in the
        // roll's box is a sheet of its own.
        if (sheet.Report.Method == SheetSurfaceMethodEnum::Roll && PiecesOnMesh(labels, group, sheet.Mesh))
        {
          warnings.insert(warnings.end(), groupWarnings.begin(), groupWarnings.end());
          sheet.Summary.Pieces = grouped;
          sheet.Pieces = group;
          for (SizeValueType l = first; l <= objects; ++l)
          {
            done[l] |= group[l];
            sheet.Summary.Voxels += group[l] != 0 ? pieceSizes[l - 1] : 0;
          }
          return sheet;
        }
      }
      catch (const ExceptionObject &)
      {
        if (this->GetAbortGenerateData())
        {
          throw;
        }
      }
    }
    std::vector<uint8_t> alone(first + 1, 0);
    alone[first] = 1;
    done[first] = 1;
    Sheet sheet = meshPieces(alone, warnings);
    sheet.Pieces = alone;
    sheet.Summary.Voxels = pieceSizes[first - 1];
    return sheet;
  };

  m_Sheets.clear();
  m_Dropped = DroppedSheetPieces{};
  std::vector<std::string> warnings;
  m_Sheets.push_back(meshSheetFrom(1, warnings));
  const double thickness = std::max(m_Sheets.front().Report.SheetThickness, std::cbrt(voxelVolume));
  auto         areaOf = [&](SizeValueType voxels) { return static_cast<double>(voxels) * voxelVolume / thickness; };
  m_MinimumSheetAreaUsed = m_MinimumSheetArea > 0.0
                             ? m_MinimumSheetArea
                             : std::max(AutomaticMinimumAreaFraction * areaOf(m_Sheets.front().Summary.Voxels),
                                        AutomaticMinimumAreaVoxels * spacing[0] * spacing[1]);
  if ((m_EverySheet || m_MinimumSheetArea > 0.0) && areaOf(m_Sheets.front().Summary.Voxels) < m_MinimumSheetAreaUsed)
  {
    const double largest = areaOf(m_Sheets.front().Summary.Voxels);
    m_Sheets.clear();
    itkExceptionMacro(<< "no sheet: the largest piece of material covers " << largest
                      << " mm^2, less than the minimum sheet area of " << m_MinimumSheetAreaUsed << " mm^2");
  }
  // A piece that is not a roll may hold sheets that touch (pages stuck together): split
  // along the dip of the plate measure between them and mesh each.
  const double minimumCoreVoxels = 0.5 * m_MinimumSheetAreaUsed / (spacing[0] * spacing[1]);
  auto         splitSheet = [&](SizeValueType piece, Sheet & whole, std::vector<std::string> & warnings) {
    std::vector<Sheet> sheets;
    if (!m_EverySheet || whole.Report.Method == SheetSurfaceMethodEnum::Roll || whole.Summary.Pieces != 1)
    {
      sheets.push_back(std::move(whole));
      return sheets;
    }
    auto box = pieces->GetRegion(piece);
    box.PadByRadius(3);
    box.Crop(labels->GetBufferedRegion());
    using PieceImageType = Image<uint8_t, 3>;
    auto pieceMask = PieceImageType::New();
    pieceMask->CopyInformation(labels);
    pieceMask->SetRegions(box);
    pieceMask->Allocate();
    auto values = IntensityImageType::New();
    values->CopyInformation(labels);
    values->SetRegions(box);
    values->Allocate();
    for (ImageRegionConstIteratorWithIndex<LabelImageType> it(labels, box); !it.IsAtEnd(); ++it)
    {
      const bool on = it.Get() == piece;
      pieceMask->SetPixel(it.GetIndex(), on ? 1 : 0);
      values->SetPixel(it.GetIndex(), intensity != nullptr ? intensity->GetPixel(it.GetIndex()) : (on ? 1.0f : 0.0f));
    }
    const double             sigma = std::min({ spacing[0], spacing[1], spacing[2] });
    const TouchingSheetSplit split =
      SplitTouchingSheets(values, pieceMask, sigma, static_cast<SizeValueType>(std::max(1.0, minimumCoreVoxels)));
    if (split.Sheets < 2)
    {
      sheets.push_back(std::move(whole));
      return sheets;
    }
    // The split labels over the whole mask, so that each sheet is read like a piece.
    auto splitLabels = Image<uint16_t, 3>::New();
    splitLabels->CopyInformation(labels);
    splitLabels->SetRegions(labels->GetBufferedRegion());
    splitLabels->Allocate();
    splitLabels->FillBuffer(0);
    for (ImageRegionConstIteratorWithIndex<Image<uint16_t, 3>> it(split.Labels, box); !it.IsAtEnd(); ++it)
    {
      splitLabels->SetPixel(it.GetIndex(), it.Get());
    }
    std::ostringstream text;
    text << "a piece of " << whole.Summary.Voxels << " voxels holds " << split.Sheets
         << " sheets that touch: split between them";
    warnings.push_back(text.str());
    // Each split sheet's voxels, counted in one pass over the box.
    std::vector<SizeValueType> splitVoxels(split.Sheets + 1, 0);
    for (ImageRegionConstIterator<Image<uint16_t, 3>> it(split.Labels, box); !it.IsAtEnd(); ++it)
    {
      ++splitVoxels[std::min<size_t>(it.Get(), split.Sheets)];
    }
    for (unsigned int k = 1; k <= split.Sheets; ++k)
    {
      std::vector<uint8_t> keep(k + 1, 0);
      keep[k] = 1;
      std::vector<std::string> sheetWarnings;
      Sheet                    sheet = meshLabels(splitLabels.GetPointer(), keep, sheetWarnings);
      sheet.Split = splitLabels.GetPointer();
      sheet.SplitLabel = static_cast<uint16_t>(k);
      sheet.Summary.Voxels = splitVoxels[k];
      sheet.Report.Warnings.insert(sheet.Report.Warnings.begin(), sheetWarnings.begin(), sheetWarnings.end());
      sheets.push_back(std::move(sheet));
    }
    return sheets;
  };
  {
    Sheet first = std::move(m_Sheets.front());
    m_Sheets = splitSheet(1, first, warnings);
  }
  for (SizeValueType l = 2; m_EverySheet && l <= objects; ++l)
  {
    if (done[l] != 0)
    {
      continue;
    }
    if (areaOf(pieceSizes[l - 1]) < m_MinimumSheetAreaUsed)
    {
      done[l] = 1;
      ++m_Dropped.TooSmall;
      m_Dropped.TooSmallVoxels += pieceSizes[l - 1];
      continue;
    }
    std::vector<std::string> sheetWarnings;
    try
    {
      Sheet sheet = meshSheetFrom(l, sheetWarnings);
      for (Sheet & part : splitSheet(l, sheet, sheetWarnings))
      {
        part.Report.Warnings.insert(part.Report.Warnings.begin(), sheetWarnings.begin(), sheetWarnings.end());
        m_Sheets.push_back(std::move(part));
      }
    }
    catch (const ExceptionObject & e)
    {
      if (this->GetAbortGenerateData())
      {
        throw;
      }
      done[l] = 1;
      m_Dropped.NotTraced.push_back({ pieceSizes[l - 1], areaOf(pieceSizes[l - 1]), e.GetDescription() });
    }
  }
  const SizeValueType meshedPieces = std::count(done.begin() + 1, done.end(), uint8_t{ 1 });
  if (!m_EverySheet && objects > 1)
  {
    const SizeValueType meshed = m_Sheets.front().Summary.Pieces;
    std::ostringstream  text;
    text << "the mask holds " << objects << " disconnected pieces; ";
    if (meshed == 1)
    {
      text << "only the largest (" << pieceSizes[0];
    }
    else
    {
      text << "the largest and the " << meshed - 1 << " around it, cut by the field of view ("
           << m_Sheets.front().Summary.Voxels;
    }
    text << " of " << std::accumulate(pieceSizes.begin(), pieceSizes.end(), SizeValueType{ 0 })
         << " voxels) was meshed";
    warnings.insert(warnings.begin(), text.str());
  }
  else if (m_EverySheet && (m_Dropped.TooSmall > 0 || !m_Dropped.NotTraced.empty()))
  {
    std::ostringstream text;
    text << m_Sheets.size() << " sheet(s) meshed from "
         << meshedPieces - m_Dropped.TooSmall - m_Dropped.NotTraced.size() << " of " << objects << " pieces";
    if (m_Dropped.TooSmall > 0)
    {
      text << "; " << m_Dropped.TooSmall << " piece(s) below the minimum sheet area of " << m_MinimumSheetAreaUsed
           << " mm^2 ignored (" << m_Dropped.TooSmallVoxels << " voxels)";
    }
    if (!m_Dropped.NotTraced.empty())
    {
      text << "; " << m_Dropped.NotTraced.size() << " piece(s) could not be traced";
    }
    warnings.insert(warnings.begin(), text.str());
  }
  // Sheets numbered by size.
  std::stable_sort(m_Sheets.begin(), m_Sheets.end(), [](const Sheet & a, const Sheet & b) {
    return a.Summary.Voxels > b.Summary.Voxels;
  });
  Sheet & first = m_Sheets.front();
  first.Report.Warnings.insert(first.Report.Warnings.begin(), warnings.begin(), warnings.end());
  m_Report = first.Report;

  // The output is the first sheet, built in place (a QuadEdgeMesh must not share its cells
  // with a temporary mesh: it deletes them when it is destroyed); the others are built on
  // request by GetSheetOutput (outputs added here would mark the filter modified, and the
  // next downstream update would run it again).
  m_SheetOutputs.assign(m_Sheets.size(), nullptr);
  m_SheetLabels = nullptr;
  if (m_EverySheet)
  {
    m_SheetLabels = SheetLabelImageType::New();
    m_SheetLabels->CopyInformation(mask);
    m_SheetLabels->SetRegions(region);
    m_SheetLabels->Allocate();
    m_SheetLabels->FillBuffer(0);
    uint16_t *            out = m_SheetLabels->GetBufferPointer();
    const SizeValueType * in = labels->GetBufferPointer();
    const SizeValueType   n = region.GetNumberOfPixels();
    for (size_t i = 0; i < m_Sheets.size(); ++i)
    {
      const Sheet & sheet = m_Sheets[i];
      const auto    label = static_cast<uint16_t>(std::min<size_t>(i + 1, NumericTraits<uint16_t>::max()));
      for (SizeValueType v = 0; v < n; ++v)
      {
        const bool mine = sheet.Split ? sheet.Split->GetBufferPointer()[v] == sheet.SplitLabel
                                      : in[v] < sheet.Pieces.size() && sheet.Pieces[in[v]] != 0;
        out[v] = mine ? label : out[v];
      }
    }
  }
  for (Sheet & sheet : m_Sheets)
  {
    Summarise(sheet, areaOf(sheet.Summary.Voxels));
  }
  SheetMeshIntoMesh(m_Sheets.front().Mesh, this->GetOutput());
  MarkMeshWhole(this->GetOutput());
  this->UpdateProgress(1.0f);
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::ToPhysicalFrame(
  const typename SheetImageType::PointType &     origin,
  const typename SheetImageType::DirectionType & direction,
  SheetMesh &                                    sheet)
{
  for (size_t i = 0; i < sheet.GetNumberOfPoints(); ++i)
  {
    double q[3] = { sheet.Points[3 * i], sheet.Points[3 * i + 1], sheet.Points[3 * i + 2] };
    for (unsigned r = 0; r < 3; ++r)
    {
      sheet.Points[3 * i + r] = origin[r] + direction[r][0] * q[0] + direction[r][1] * q[1] + direction[r][2] * q[2];
    }
  }
  if (vnl_determinant(direction.GetVnlMatrix()) < 0.0)
  {
    for (size_t t = 0; t < sheet.GetNumberOfTriangles(); ++t)
    {
      std::swap(sheet.Triangles[3 * t + 1], sheet.Triangles[3 * t + 2]);
    }
  }
}

template <typename TMaskImage, typename TOutputMesh>
template <typename TLabelImage>
bool
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::PiecesOnMesh(const TLabelImage *          labels,
                                                                 const std::vector<uint8_t> & group,
                                                                 const SheetMesh &            mesh)
{
  // The voxels within PieceOnMeshReach voxels of a mesh point, then each piece's share of
  // them.
  const auto        region = labels->GetBufferedRegion();
  const auto        size = region.GetSize();
  std::vector<bool> nearMesh(region.GetNumberOfPixels(), false);
  const long        reach = PieceOnMeshReach;
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    typename TLabelImage::PointType p;
    for (unsigned d = 0; d < 3; ++d)
    {
      p[d] = mesh.Points[3 * i + d];
    }
    typename TLabelImage::IndexType index;
    labels->TransformPhysicalPointToIndex(p, index);
    for (long z = std::max<long>(0, index[2] - reach); z <= std::min<long>(size[2] - 1, index[2] + reach); ++z)
    {
      for (long y = std::max<long>(0, index[1] - reach); y <= std::min<long>(size[1] - 1, index[1] + reach); ++y)
      {
        for (long x = std::max<long>(0, index[0] - reach); x <= std::min<long>(size[0] - 1, index[0] + reach); ++x)
        {
          nearMesh[(z * size[1] + y) * size[0] + x] = true;
        }
      }
    }
  }
  std::vector<SizeValueType> on(group.size(), 0), all(group.size(), 0);
  const SizeValueType *      label = labels->GetBufferPointer();
  for (SizeValueType v = 0; v < nearMesh.size(); ++v)
  {
    if (label[v] < group.size() && group[label[v]] != 0)
    {
      ++all[label[v]];
      on[label[v]] += nearMesh[v] ? 1 : 0;
    }
  }
  for (size_t l = 0; l < group.size(); ++l)
  {
    if (all[l] > 0 && static_cast<double>(on[l]) < PieceOnMeshFraction * static_cast<double>(all[l]))
    {
      return false;
    }
  }
  return true;
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::Summarise(Sheet & sheet, double area)
{
  SheetSummary & summary = sheet.Summary;
  summary.Area = area;
  const SheetMesh & mesh = sheet.Mesh;
  for (unsigned d = 0; d < 3; ++d)
  {
    summary.BoundsMinimum[d] = NumericTraits<double>::max();
    summary.BoundsMaximum[d] = NumericTraits<double>::NonpositiveMin();
  }
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      summary.BoundsMinimum[d] = std::min(summary.BoundsMinimum[d], mesh.Points[3 * i + d]);
      summary.BoundsMaximum[d] = std::max(summary.BoundsMaximum[d], mesh.Points[3 * i + d]);
    }
  }
  const SheetMidSurfaceReport & report = sheet.Report;
  const double                  traced = report.SlicesWithMaterial == 0 ? 0.0
                                                                        : 1.0 - static_cast<double>(report.InterpolatedSlices) /
                                                                 static_cast<double>(report.SlicesWithMaterial);
  double                        confirmed = 0.0;
  size_t                        counted = 0;
  for (double c : report.SliceConfidence)
  {
    if (c > 0.0)
    {
      confirmed += c;
      ++counted;
    }
  }
  summary.Confidence = std::max(0.0, traced) * (counted > 0 ? confirmed / static_cast<double>(counted) : 1.0);
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::GetSheetOutput(unsigned int sheet) -> OutputMeshType *
{
  if (sheet >= m_Sheets.size())
  {
    itkExceptionMacro(<< "sheet " << sheet << " requested of " << m_Sheets.size());
  }
  if (sheet == 0)
  {
    return this->GetOutput();
  }
  if (!m_SheetOutputs[sheet])
  {
    m_SheetOutputs[sheet] = SheetMeshToMesh<OutputMeshType>(m_Sheets[sheet].Mesh);
  }
  return m_SheetOutputs[sheet].GetPointer();
}

template <typename TMaskImage, typename TOutputMesh>
unsigned int
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::FindSheetNearestTo(
  const typename MaskImageType::PointType & point) const
{
  if (m_Sheets.empty())
  {
    itkExceptionMacro(<< "no sheet has been meshed");
  }
  unsigned int nearest = 0;
  double       best = NumericTraits<double>::max();
  for (unsigned int i = 0; i < m_Sheets.size(); ++i)
  {
    const auto & points = m_Sheets[i].Mesh.Points;
    for (size_t p = 0; p + 2 < points.size(); p += 3)
    {
      const double d = (points[p] - point[0]) * (points[p] - point[0]) +
                       (points[p + 1] - point[1]) * (points[p + 1] - point[1]) +
                       (points[p + 2] - point[2]) * (points[p + 2] - point[2]);
      if (d < best)
      {
        best = d;
        nearest = i;
      }
    }
  }
  return nearest;
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::EstimateRollAxis(const SheetImageType *     sheetMask,
                                                                     const IntensityImageType * sheetIntensity,
                                                                     bool &                     fromTensor) -> AxisType
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
  using GradientImageType = Image<CovariantVector<float, 3>, 3>;
  using GradientType = GradientRecursiveGaussianImageFilter<IntensityImageType, GradientImageType>;
  auto gradientFilter = GradientType::New();
  if (sheetIntensity != nullptr)
  {
    gradientFilter->SetInput(sheetIntensity);
  }
  else
  {
    // The mask as 0 / 1 intensities on its own buffered box.
    auto source = IntensityImageType::New();
    source->CopyInformation(sheetMask);
    source->SetRegions(sheetMask->GetBufferedRegion());
    source->Allocate();
    const size_t count = sheetMask->GetBufferedRegion().GetNumberOfPixels();
    for (size_t i = 0; i < count; ++i)
    {
      source->GetBufferPointer()[i] = sheetMask->GetBufferPointer()[i] != 0 ? 1.0f : 0.0f;
    }
    gradientFilter->SetInput(source);
  }
  typename GradientType::SigmaArrayType sigmas;
  for (unsigned d = 0; d < 3; ++d)
  {
    sigmas[d] = sheetMask->GetSpacing()[d];
  }
  gradientFilter->SetSigmaArray(sigmas);
  gradientFilter->SetUseImageDirection(true);
  gradientFilter->Update();
  const auto *    gradients = gradientFilter->GetOutput()->GetBufferPointer();
  const uint8_t * mask = sheetMask->GetBufferPointer();
  const auto      size = sheetMask->GetBufferedRegion().GetSize();
  const auto &    direction = sheetMask->GetDirection();
  // Slice by slice in parallel, then summed in slice order (the same sum on any number of
  // threads).
  std::vector<std::array<double, 9>> sliceTensors(size[2], std::array<double, 9>{});
  ForEachImageRow(sheetMask, sheetMask->GetBufferedRegion(), [&](SizeValueType k, SizeValueType, const uint8_t * row) {
    std::array<double, 9> & sum = sliceTensors[k];
    const auto *            gradientRow = gradients + (row - mask);
    for (size_t i = 0; i < size[0]; ++i)
    {
      if (row[i] == 0)
      {
        continue;
      }
      const auto & physical = gradientRow[i];
      for (unsigned r = 0; r < 3; ++r)
      {
        for (unsigned c = 0; c < 3; ++c)
        {
          sum[3 * r + c] += static_cast<double>(physical[r]) * static_cast<double>(physical[c]);
        }
      }
    }
  });
  vnl_matrix<double> tensor(3, 3, 0.0);
  for (const auto & sum : sliceTensors)
  {
    for (unsigned r = 0; r < 3; ++r)
    {
      for (unsigned c = 0; c < 3; ++c)
      {
        tensor(r, c) += sum[3 * r + c];
      }
    }
  }
  const vnl_symmetric_eigensystem<double> eigen(tensor);
  // Eigenvalues ascending. A roll spreads its normals evenly across the axis: the two
  // large eigenvalues are comparable and far above the axis's.
  constexpr double rolledEigenvalueRatio = 2.5;
  constexpr double largestTilt = 45.0;
  if (eigen.get_eigenvalue(1) > rolledEigenvalueRatio * std::max(eigen.get_eigenvalue(0), 0.0) &&
      eigen.get_eigenvalue(1) > 0.0)
  {
    AxisType axis;
    for (unsigned r = 0; r < 3; ++r)
    {
      axis[r] = eigen.get_eigenvector(0)[r];
    }
    const double cosine = axis[0] * direction[0][2] + axis[1] * direction[1][2] + axis[2] * direction[2][2];
    if (std::abs(cosine) >= std::cos(largestTilt * Math::pi / 180.0))
    {
      fromTensor = true;
      return cosine < 0.0 ? AxisType(-axis) : axis;
    }
  }
  fromTensor = false;
  return EstimateRollAxisFromCentroids(sheetMask);
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::EstimateRollAxisFromCentroids(const SheetImageType * sheetMask)
  -> AxisType
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

template <typename TMaskImage, typename TOutputMesh>
bool
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::AlignWithRollAxis(
  typename SheetImageType::Pointer &     sheetMask,
  typename IntensityImageType::Pointer & sheetIntensity,
  typename SheetImageType::Pointer &     sheetData,
  std::vector<std::string> &             warnings) const
{
  const typename SheetImageType::Pointer     originalMask = sheetMask;
  const typename IntensityImageType::Pointer originalIntensity = sheetIntensity;
  const auto &                               spacing = originalMask->GetSpacing();
  const auto &                               direction = originalMask->GetDirection();
  const auto                                 size = originalMask->GetBufferedRegion().GetSize();
  const double                               inPlane = std::min(spacing[0], spacing[1]);
  const bool                                 square = std::abs(spacing[0] - spacing[1]) <= 1e-6 * inPlane;
  auto                                       angle = [](const AxisType & a, const AxisType & b) {
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
  AxisType       axis = EstimateRollAxis(originalMask, originalIntensity, fromTensor);
  if (angle(axis, originalNormal) <= m_AxisTiltTolerance && square)
  {
    return fromTensor;
  }
  // Each pass resamples the original box along the current estimate. The structure tensor's
  // estimate is global and needs one; the centroids' is better from a better aligned grid
  // (partial slices bias it less), so it converges in a few.
  for (int pass = 0; pass < 4; ++pass)
  {
    AxisType firstAxis;
    for (unsigned r = 0; r < 3; ++r)
    {
      firstAxis[r] = direction[r][0];
    }
    firstAxis -= (firstAxis * axis) * axis;
    firstAxis.Normalize();
    const AxisType                         secondAxis = CrossProduct(axis, firstAxis);
    typename SheetImageType::DirectionType newDirection;
    for (unsigned r = 0; r < 3; ++r)
    {
      newDirection[r][0] = firstAxis[r];
      newDirection[r][1] = secondAxis[r];
      newDirection[r][2] = axis[r];
    }
    typename SheetImageType::SpacingType newSpacing;
    newSpacing[0] = newSpacing[1] = inPlane;
    newSpacing[2] = spacing[2];
    // Bounds of the original box's corners in the new frame.
    double       lower[3] = { 1e300, 1e300, 1e300 }, upper[3] = { -1e300, -1e300, -1e300 };
    const auto & origin = originalMask->GetOrigin();
    for (unsigned corner = 0; corner < 8; ++corner)
    {
      typename SheetImageType::IndexType index;
      for (unsigned d = 0; d < 3; ++d)
      {
        index[d] = (corner >> d) & 1U ? static_cast<IndexValueType>(size[d]) - 1 : 0;
      }
      typename SheetImageType::PointType point;
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
    typename SheetImageType::PointType newOrigin;
    typename SheetImageType::SizeType  newSize;
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
      return typename SheetImageType::Pointer(resampler->GetOutput());
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
    if (fromTensor)
    {
      break;
    }
    const AxisType refined = EstimateRollAxisFromCentroids(sheetMask);
    if (angle(refined, sliceNormal(sheetMask)) <= 0.25 * m_AxisTiltTolerance)
    {
      break;
    }
    axis = refined;
  }
  std::ostringstream text;
  text << "the volume was resampled along the roll axis";
  if (angle(axis, originalNormal) > m_AxisTiltTolerance)
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

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::Denoise(const SheetImageType *                 sheetMask,
                                                            typename IntensityImageType::Pointer & sheetIntensity,
                                                            std::vector<std::string> &             warnings) const
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
  typename SmoothingRecursiveGaussianImageFilter<IntensityImageType, IntensityImageType>::SigmaArrayType sigmas;
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

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Method: " << ToString(m_Method) << std::endl;
  os << indent << "SpacingAlongSheet: " << m_SpacingAlongSheet << std::endl;
  os << indent << "SpacingAlongAxis: " << m_SpacingAlongAxis << std::endl;
  os << indent << "ChordErrorFraction: " << m_ChordErrorFraction << std::endl;
  os << indent << "AxisTiltTolerance: " << m_AxisTiltTolerance << std::endl;
  os << indent << "EverySheet: " << m_EverySheet << std::endl;
  os << indent << "MinimumSheetArea: " << m_MinimumSheetArea << std::endl;
  os << indent << "Sheets: " << m_Sheets.size() << std::endl;
  os << indent << "SheetMesh: " << this->GetSheetMesh().GetNumberOfPoints() << " points, "
     << this->GetSheetMesh().GetNumberOfTriangles() << " triangles" << std::endl;
  os << indent << "Report: method " << ToString(m_Report.Method) << ", spacing " << m_Report.SpacingAlongSheet << " x "
     << m_Report.SpacingAlongAxis << " mm, thickness " << m_Report.SheetThickness << " mm, " << m_Report.Warnings.size()
     << " warning(s)" << std::endl;
}
} // end namespace itk

#endif

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
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkLabelStatisticsImageFilter.h"
#include "itkParallelImageRows.h"
#include "itkRelabelComponentImageFilter.h"
#include "itkSheetMeshAdaptor.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkTouchingSheetSplitter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <numeric>
#include <sstream>


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
  auto components = ConnectedComponentImageFilter<MaskImageType, LabelImageType>::New();
  components->SetInput(mask);
  components->FullyConnectedOff();
  auto relabel = RelabelComponentImageFilter<LabelImageType, LabelImageType>::New();
  relabel->SetInput(components->GetOutput());
  relabel->InPlaceOn();
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
  Pieces pieces;
  pieces.Labels = labels;
  pieces.Intensity = intensity;
  pieces.Objects = relabel->GetNumberOfObjects();
  pieces.Sizes = relabel->GetSizeOfObjectsInPixels();
  pieces.Done.assign(pieces.Objects + 1, 0);
  {
    // The pieces' bounding boxes (the labels serve as their own values).
    auto statistics = LabelStatisticsImageFilter<LabelImageType, LabelImageType>::New();
    statistics->SetInput(labels);
    statistics->SetLabelInput(labels);
    statistics->Update();
    pieces.Boxes.resize(pieces.Objects + 1);
    for (SizeValueType l = 1; l <= pieces.Objects; ++l)
    {
      pieces.Boxes[l] = statistics->GetRegion(l);
    }
  }
  const auto & spacing = mask->GetSpacing();
  const double voxelVolume = spacing[0] * spacing[1] * spacing[2];

  m_Sheets.clear();
  m_Dropped = DroppedSheetPieces{};
  std::vector<std::string> warnings;
  // With every sheet, the largest piece may not trace whole because it holds pages that
  // touch (its slices cross several of them): it is then split into its sheets, or dropped
  // as untraceable, and the run fails only when no piece traces.
  std::exception_ptr firstError;
  std::string        firstReason;
  try
  {
    m_Sheets.push_back(MeshSheetFrom(pieces, 1, warnings));
  }
  catch (const ExceptionObject & e)
  {
    if (!m_EverySheet || this->GetAbortGenerateData())
    {
      throw;
    }
    firstError = std::current_exception();
    firstReason = e.GetDescription();
    Sheet untraced;
    untraced.Report.Method = SheetSurfaceMethodEnum::General;
    untraced.Report.SheetThickness =
      PlateThickness(labels, pieces.Boxes[1], [](LabelPixelType label) { return label == 1; });
    untraced.Summary.Voxels = pieces.Sizes[0];
    m_Sheets.push_back(std::move(untraced));
  }
  m_VoxelArea = voxelVolume / std::max(m_Sheets.front().Report.SheetThickness, std::cbrt(voxelVolume));
  m_MinimumSheetAreaUsed = m_MinimumSheetArea > 0.0
                             ? m_MinimumSheetArea
                             : std::max(AutomaticMinimumAreaFraction * AreaOf(m_Sheets.front().Summary.Voxels),
                                        AutomaticMinimumAreaVoxels * spacing[0] * spacing[1]);
  if ((m_EverySheet || m_MinimumSheetArea > 0.0) && AreaOf(m_Sheets.front().Summary.Voxels) < m_MinimumSheetAreaUsed)
  {
    const double largest = AreaOf(m_Sheets.front().Summary.Voxels);
    m_Sheets.clear();
    itkExceptionMacro(<< "no sheet: the largest piece of material covers " << largest
                      << " mm^2, less than the minimum sheet area of " << m_MinimumSheetAreaUsed << " mm^2");
  }
  // A piece that is not a roll may hold sheets that touch (pages stuck together): split
  // along the dip of the plate measure between them and mesh each.
  const double minimumCoreVoxels = 0.5 * m_MinimumSheetAreaUsed / (spacing[0] * spacing[1]);
  {
    Sheet first = std::move(m_Sheets.front());
    m_Sheets = SplitSheet(pieces, 1, first, minimumCoreVoxels, warnings);
    if (firstError && m_Sheets.size() == 1 && m_Sheets.front().Mesh.Points.empty())
    {
      m_Dropped.NotTraced.push_back({ pieces.Sizes[0], AreaOf(pieces.Sizes[0]), firstReason });
      m_Sheets.clear();
    }
  }
  for (SizeValueType l = 2; m_EverySheet && l <= pieces.Objects; ++l)
  {
    if (pieces.Done[l] != 0)
    {
      continue;
    }
    if (AreaOf(pieces.Sizes[l - 1]) < m_MinimumSheetAreaUsed)
    {
      pieces.Done[l] = 1;
      ++m_Dropped.TooSmall;
      m_Dropped.TooSmallVoxels += pieces.Sizes[l - 1];
      continue;
    }
    std::vector<std::string> sheetWarnings;
    try
    {
      Sheet sheet = MeshSheetFrom(pieces, l, sheetWarnings);
      for (Sheet & part : SplitSheet(pieces, l, sheet, minimumCoreVoxels, sheetWarnings))
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
      pieces.Done[l] = 1;
      m_Dropped.NotTraced.push_back({ pieces.Sizes[l - 1], AreaOf(pieces.Sizes[l - 1]), e.GetDescription() });
    }
  }
  if (m_Sheets.empty())
  {
    std::rethrow_exception(firstError ? firstError
                                      : std::make_exception_ptr(ExceptionObject(
                                          __FILE__, __LINE__, "no piece of the mask could be traced as a sheet")));
  }
  const std::string piecesNote = PiecesNote(pieces);
  if (!piecesNote.empty())
  {
    warnings.insert(warnings.begin(), piecesNote);
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
    LabelSheets(labels);
  }
  for (Sheet & sheet : m_Sheets)
  {
    Summarise(sheet, AreaOf(sheet.Summary.Voxels));
  }
  SheetMeshIntoMesh(m_Sheets.front().Mesh, this->GetOutput());
  MarkMeshWhole(this->GetOutput());
  this->UpdateProgress(1.0f);
}

template <typename TMaskImage, typename TOutputMesh>
template <typename TLabelImage>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::MeshLabels(const TLabelImage *          source,
                                                               const IntensityImageType *   intensity,
                                                               const std::vector<uint8_t> & keep,
                                                               std::vector<std::string> &   warnings) -> Sheet
{
  auto kept = [&keep](auto label) { return static_cast<size_t>(label) < keep.size() && keep[label] != 0; };
  // Read only the bounding box of the sheet, plus two voxels.
  const ImageRegion<3> box = BoundingRegionWhere(source, kept, 2);

  // The sheet's box as images of their own (index 0 at the box corner).
  typename SheetImageType::RegionType boxRegion;
  boxRegion.SetSize(box.GetSize());
  typename SheetImageType::PointType boxOrigin;
  source->TransformIndexToPhysicalPoint(box.GetIndex(), boxOrigin);
  typename SheetImageType::Pointer sheetMask = SheetImageType::New();
  sheetMask->SetRegions(boxRegion);
  sheetMask->SetOrigin(boxOrigin);
  sheetMask->SetSpacing(source->GetSpacing());
  sheetMask->SetDirection(source->GetDirection());
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
    // Row by row, the slices in parallel; the intensities lie where the labels do. When
    // every sheet is meshed, the other pieces and split sheets are sheets of their own (or
    // too small to be one): their material is marked 2 and hidden from the tracers. For the
    // largest sheet alone, pieces not meshed with it (arcs of turns the tracer did not
    // take as its own, specks) stay as they are in the scan.
    const auto boxSize = box.GetSize();
    ForEachImageRow(source, box, [&](SizeValueType k, SizeValueType j, const auto * label) {
      const SizeValueType to = (k * boxSize[1] + j) * boxSize[0];
      uint8_t *           out = sheetMask->GetBufferPointer() + to;
      for (SizeValueType i = 0; i < boxSize[0]; ++i)
      {
        out[i] = kept(label[i]) ? 1 : (m_EverySheet && label[i] != 0 ? 2 : 0);
      }
      if (intensity != nullptr)
      {
        std::copy_n(intensity->GetBufferPointer() + (label - source->GetBufferPointer()),
                    boxSize[0],
                    sheetIntensity->GetBufferPointer() + to);
      }
    });
  }
  SheetRollAxis::HideOtherSheets(sheetMask, sheetIntensity);
  typename SheetImageType::Pointer sheetData;
  const bool axisKnown = SheetRollAxis::Align(sheetMask, sheetIntensity, sheetData, m_AxisTiltTolerance, warnings);
  if (sheetIntensity)
  {
    SheetRollAxis::Denoise(sheetMask, sheetIntensity, warnings);
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
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::MeshSheetFrom(Pieces &                   pieces,
                                                                  SizeValueType              first,
                                                                  std::vector<std::string> & warnings) -> Sheet
{
  auto                 firstBox = pieces.Boxes[first];
  std::vector<uint8_t> group(pieces.Objects + 1, 0);
  group[first] = 1;
  SizeValueType grouped = 1;
  // The field of view cuts a roll's turns where they leave the scan, so every piece of a cut
  // roll (its inner part too) reaches the scan's edge. Pages that lie apart within the scan
  // do not: two parallel sheets, around the middle of the gap between them, can otherwise
  // trace as a turn of a roll.
  const ImageRegion<3> scan = pieces.Labels->GetBufferedRegion();
  const auto           reachesEdge = [&scan](const ImageRegion<3> & box) {
    for (unsigned d = 0; d < 3; ++d)
    {
      if (box.GetIndex(d) <= scan.GetIndex(d) + CutEdgeReach ||
          box.GetUpperIndex()[d] >= scan.GetUpperIndex()[d] - CutEdgeReach)
      {
        return true;
      }
    }
    return false;
  };
  const bool cut = reachesEdge(firstBox);
  for (SizeValueType l = first + 1; cut && l <= pieces.Objects; ++l)
  {
    // An arc of a cut turn, not a speck of noise within the roll's box.
    auto       box = pieces.Boxes[l];
    const bool arc =
      static_cast<double>(pieces.Sizes[l - 1]) >= CutArcFraction * static_cast<double>(pieces.Sizes[first - 1]);
    group[l] = pieces.Done[l] == 0 && arc && reachesEdge(box) && box.Crop(firstBox) ? 1 : 0;
    grouped += group[l];
  }
  if (grouped > 1 && m_Method != SheetSurfaceMethodEnum::General)
  {
    try
    {
      std::vector<std::string> groupWarnings;
      Sheet                    sheet = MeshLabels(pieces.Labels, pieces.Intensity, group, groupWarnings);
      // Every piece meshed with it must lie on the roll's mesh, or wholly off it (a loose
      // fragment in the roll's box, or an arc the trace did not reach, is then a sheet of
      // its own); a piece the mesh only grazes refuses the group.
      if (sheet.Report.Method == SheetSurfaceMethodEnum::Roll && PiecesOnMesh(pieces.Labels, first, group, sheet.Mesh))
      {
        warnings.insert(warnings.end(), groupWarnings.begin(), groupWarnings.end());
        grouped = static_cast<SizeValueType>(std::count(group.begin(), group.end(), uint8_t{ 1 }));
        sheet.Summary.Pieces = grouped;
        sheet.Pieces = group;
        for (SizeValueType l = first; l <= pieces.Objects; ++l)
        {
          pieces.Done[l] |= group[l];
          sheet.Summary.Voxels += group[l] != 0 ? pieces.Sizes[l - 1] : 0;
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
  pieces.Done[first] = 1;
  Sheet sheet = MeshLabels(pieces.Labels, pieces.Intensity, alone, warnings);
  sheet.Pieces = alone;
  sheet.Summary.Voxels = pieces.Sizes[first - 1];
  return sheet;
}

template <typename TMaskImage, typename TOutputMesh>
auto
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::SplitSheet(Pieces &                   pieces,
                                                               SizeValueType              piece,
                                                               Sheet &                    whole,
                                                               double                     minimumCoreVoxels,
                                                               std::vector<std::string> & warnings)
  -> std::vector<Sheet>
{
  std::vector<Sheet> sheets;
  if (!m_EverySheet || whole.Report.Method == SheetSurfaceMethodEnum::Roll || whole.Summary.Pieces != 1)
  {
    sheets.push_back(std::move(whole));
    return sheets;
  }
  auto box = pieces.Boxes[piece];
  box.PadByRadius(3);
  box.Crop(pieces.Labels->GetBufferedRegion());
  using PieceImageType = Image<uint8_t, 3>;
  auto pieceMask = PieceImageType::New();
  pieceMask->CopyInformation(pieces.Labels);
  pieceMask->SetRegions(box);
  pieceMask->Allocate();
  auto values = IntensityImageType::New();
  values->CopyInformation(pieces.Labels);
  values->SetRegions(box);
  values->Allocate();
  for (ImageRegionConstIteratorWithIndex<LabelImageType> it(pieces.Labels, box); !it.IsAtEnd(); ++it)
  {
    const bool on = it.Get() == piece;
    pieceMask->SetPixel(it.GetIndex(), on ? 1 : 0);
    values->SetPixel(it.GetIndex(),
                     pieces.Intensity != nullptr ? pieces.Intensity->GetPixel(it.GetIndex()) : (on ? 1.0f : 0.0f));
  }
  // The scan's thinnest sheet, measured once, when a piece is first split.
  if (pieces.ThinnestSheet < 0.0)
  {
    double thinnest = 0.0;
    for (SizeValueType l = 1; l <= std::min<SizeValueType>(pieces.Objects, ThicknessPieces); ++l)
    {
      if (static_cast<double>(pieces.Sizes[l - 1]) >= ThicknessPieceShare * static_cast<double>(pieces.Sizes[0]))
      {
        const double t =
          PlateThickness(pieces.Labels, pieces.Boxes[l], [l](LabelPixelType label) { return label == l; });
        thinnest = thinnest > 0.0 ? std::min(thinnest, t) : t;
      }
    }
    pieces.ThinnestSheet = thinnest;
  }
  const auto &             spacing = pieces.Labels->GetSpacing();
  const double             sigma = std::min({ spacing[0], spacing[1], spacing[2] });
  const TouchingSheetSplit split = SplitTouchingSheets(
    values, pieceMask, sigma, static_cast<SizeValueType>(std::max(1.0, minimumCoreVoxels)), pieces.ThinnestSheet);
  if (split.Sheets < 2)
  {
    sheets.push_back(std::move(whole));
    return sheets;
  }
  // The split labels over the whole mask, so that each sheet is read like a piece.
  auto splitLabels = Image<uint16_t, 3>::New();
  splitLabels->CopyInformation(pieces.Labels);
  splitLabels->SetRegions(pieces.Labels->GetBufferedRegion());
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
    Sheet                    sheet;
    try
    {
      sheet = MeshLabels(splitLabels.GetPointer(), pieces.Intensity, keep, sheetWarnings);
    }
    catch (const ExceptionObject & e)
    {
      if (this->GetAbortGenerateData())
      {
        throw;
      }
      // One sheet of the split that does not trace is dropped; the others are kept.
      m_Dropped.NotTraced.push_back({ splitVoxels[k], AreaOf(splitVoxels[k]), e.GetDescription(), true });
      continue;
    }
    sheet.Split = splitLabels.GetPointer();
    sheet.SplitLabel = static_cast<uint16_t>(k);
    sheet.Summary.Voxels = splitVoxels[k];
    sheet.Report.Warnings.insert(sheet.Report.Warnings.begin(), sheetWarnings.begin(), sheetWarnings.end());
    sheets.push_back(std::move(sheet));
  }
  return sheets;
}

template <typename TMaskImage, typename TOutputMesh>
double
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::AreaOf(SizeValueType voxels) const
{
  return static_cast<double>(voxels) * m_VoxelArea;
}

template <typename TMaskImage, typename TOutputMesh>
std::string
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::PiecesNote(const Pieces & pieces) const
{
  const SizeValueType meshedPieces = std::count(pieces.Done.begin() + 1, pieces.Done.end(), uint8_t{ 1 });
  if (!m_EverySheet && pieces.Objects > 1)
  {
    const SizeValueType meshed = m_Sheets.front().Summary.Pieces;
    std::ostringstream  text;
    text << "the mask holds " << pieces.Objects << " disconnected pieces; ";
    if (meshed == 1)
    {
      text << "only the largest (" << pieces.Sizes[0];
    }
    else
    {
      text << "the largest and the " << meshed - 1 << " around it, cut by the field of view ("
           << m_Sheets.front().Summary.Voxels;
    }
    text << " of " << std::accumulate(pieces.Sizes.begin(), pieces.Sizes.end(), SizeValueType{ 0 })
         << " voxels) was meshed";
    return text.str();
  }
  else if (m_EverySheet && (m_Dropped.TooSmall > 0 || !m_Dropped.NotTraced.empty()))
  {
    const auto splitSheets = static_cast<SizeValueType>(
      std::count_if(m_Dropped.NotTraced.begin(), m_Dropped.NotTraced.end(), [](const auto & dropped) {
        return dropped.SplitFromPiece;
      }));
    const SizeValueType wholePieces = m_Dropped.NotTraced.size() - splitSheets;
    std::ostringstream  text;
    text << m_Sheets.size() << " sheet(s) meshed from " << meshedPieces - m_Dropped.TooSmall - wholePieces << " of "
         << pieces.Objects << " pieces";
    if (m_Dropped.TooSmall > 0)
    {
      text << "; " << m_Dropped.TooSmall << " piece(s) below the minimum sheet area of " << m_MinimumSheetAreaUsed
           << " mm^2 ignored (" << m_Dropped.TooSmallVoxels << " voxels)";
    }
    if (wholePieces > 0)
    {
      text << "; " << wholePieces << " piece(s) could not be traced";
    }
    if (splitSheets > 0)
    {
      text << "; " << splitSheets << " sheet(s) split from a piece could not be traced";
    }
    return text.str();
  }
  return {};
}

template <typename TMaskImage, typename TOutputMesh>
void
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::LabelSheets(const LabelImageType * labels)
{
  m_SheetLabels = SheetLabelImageType::New();
  m_SheetLabels->CopyInformation(labels);
  m_SheetLabels->SetRegions(labels->GetBufferedRegion());
  m_SheetLabels->Allocate();
  m_SheetLabels->FillBuffer(0);
  uint16_t *             out = m_SheetLabels->GetBufferPointer();
  const LabelPixelType * in = labels->GetBufferPointer();
  const SizeValueType    n = labels->GetBufferedRegion().GetNumberOfPixels();
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
SheetMidSurfaceMeshFilter<TMaskImage, TOutputMesh>::PiecesOnMesh(const TLabelImage *    labels,
                                                                 SizeValueType          first,
                                                                 std::vector<uint8_t> & group,
                                                                 const SheetMesh &      mesh)
{
  // The voxels within PieceOnMeshReach voxels of the mesh's surface (each triangle sampled
  // at most a voxel apart: a roll's mesh points can lie several voxels apart), then each
  // piece's share of them.
  const auto        region = labels->GetBufferedRegion();
  const auto        size = region.GetSize();
  std::vector<bool> nearMesh(region.GetNumberOfPixels(), false);
  const long        reach = PieceOnMeshReach;
  const auto        spacing = labels->GetSpacing();
  const double      voxel = std::min({ spacing[0], spacing[1], spacing[2] });
  const auto        mark = [&](const double * at) {
    typename TLabelImage::PointType p;
    for (unsigned d = 0; d < 3; ++d)
    {
      p[d] = at[d];
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
  };
  const double * points = mesh.Points.data();
  for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
  {
    const double * a = points + 3 * static_cast<size_t>(mesh.Triangles[3 * t]);
    const double * b = points + 3 * static_cast<size_t>(mesh.Triangles[3 * t + 1]);
    const double * c = points + 3 * static_cast<size_t>(mesh.Triangles[3 * t + 2]);
    double         longest = 0.0;
    for (const auto & edge : { std::make_pair(a, b), std::make_pair(b, c), std::make_pair(c, a) })
    {
      double length2 = 0.0;
      for (unsigned d = 0; d < 3; ++d)
      {
        length2 += (edge.first[d] - edge.second[d]) * (edge.first[d] - edge.second[d]);
      }
      longest = std::max(longest, std::sqrt(length2));
    }
    const auto steps = static_cast<unsigned>(std::max(1.0, std::ceil(longest / voxel)));
    for (unsigned i = 0; i <= steps; ++i)
    {
      for (unsigned j = 0; i + j <= steps; ++j)
      {
        const double u = static_cast<double>(i) / steps, v = static_cast<double>(j) / steps, w = 1.0 - u - v;
        double       at[3];
        for (unsigned d = 0; d < 3; ++d)
        {
          at[d] = u * a[d] + v * b[d] + w * c[d];
        }
        mark(at);
      }
    }
  }
  std::vector<SizeValueType> on(group.size(), 0), all(group.size(), 0);
  const LabelPixelType *     label = labels->GetBufferPointer();
  for (SizeValueType v = 0; v < nearMesh.size(); ++v)
  {
    if (label[v] < group.size() && group[label[v]] != 0)
    {
      ++all[label[v]];
      on[label[v]] += nearMesh[v] ? 1 : 0;
    }
  }
  // Every piece on the mesh or wholly off it (then left out of the group), the first on it.
  std::vector<uint8_t> kept = group;
  for (size_t l = 0; l < group.size(); ++l)
  {
    if (group[l] == 0 || all[l] == 0)
    {
      continue;
    }
    const double share = static_cast<double>(on[l]) / static_cast<double>(all[l]);
    if (share < PieceOnMeshFraction && (l == first || share > PieceOffMeshFraction))
    {
      return false;
    }
    kept[l] = share >= PieceOnMeshFraction ? 1 : 0;
  }
  group = kept;
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

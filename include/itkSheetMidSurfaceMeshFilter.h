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
#ifndef itkSheetMidSurfaceMeshFilter_h
#define itkSheetMidSurfaceMeshFilter_h

#include "itkImage.h"
#include "itkImageToMeshFilter.h"
#include "itkMesh.h"
#include "itkSheetMesh.h"
#include "itkSheetMidSurfaceExtractor.h"
#include "itkSheetRollAxis.h"

#include <string>
#include <vector>

namespace itk {
/** \class SheetMidSurfaceMeshFilter
 * \brief Image -> Mesh: an open triangle mesh on the mid-surface of the sheet in a
 * segmentation mask (e.g. from itk::SheetSegmentationImageFilter), optionally refined with
 * the CT intensities; a thin ITK wrapper over itk::SheetMidSurfaceExtractor, whose
 * documentation describes the algorithm, the grid and the normals.
 *
 * The mask's face-connected components are labelled; the largest is meshed (one sheet =
 * one connected mesh) and, when there are several, a warning says so; with EverySheet on,
 * every piece whose area reaches MinimumSheetArea is meshed as a sheet of its own (see
 * below). Only the bounding box of a sheet's component (plus two voxels) is read. The roll axis is estimated as the
 * direction of least gradient energy over the sheet (the smallest eigenvector of the
 * structure tensor of the lightly smoothed intensities, or of the mask), since a rolled
 * sheet does not change along its axis; for a sheet without such a direction (flat or
 * gently curved: two small eigenvalues) as the least-squares line through the slices'
 * centroids of the sheet. When the axis is tilted from
 * the slice normal (third image axis) by more than AxisTiltTolerance degrees, or the
 * in-plane voxels are not square, the box is resampled (itk::ResampleImageFilter: nearest
 * neighbour for the mask, linear for the intensities) onto a grid whose third axis is the
 * roll axis and whose in-plane voxels are square, and a warning says so. The physical
 * frame (origin, spacing, direction) is respected, and triangle winding is preserved under
 * a mirroring direction matrix.
 *
 * Inputs: 0, the mask (non-zero = sheet; required); IntensityImage (optional, same
 * geometry as the mask, Image<float, 3>, e.g. HU): crossings are centred on the
 * intensity-weighted middle of the sheet (sub-voxel).
 * Parameters: Method (Auto; Roll, General), SpacingAlongSheet (mm, 0 = automatic,
 * >= 0), SpacingAlongAxis (mm, 0 = automatic, >= 0), ChordErrorFraction (0.1, in (0, 1]),
 * AxisTiltTolerance (degrees, 2, >= 0; the slices must still cut the roll, so tilts up to
 * about 45 degrees are handled).
 * Every sheet (EverySheet, off by default): the pieces are taken from the largest down.
 * Each becomes a sheet, together with the smaller pieces in its box that trace with it as
 * one roll (the arcs of its turns cut by the field of view: it and they reach the scan's
 * edge); a piece whose area (voxels
 * times voxel volume over the first sheet's measured thickness) is below
 * MinimumSheetArea (mm^2; 0: automatic, 1 % of the first sheet's area and at least 400
 * in-plane voxels) is counted as too small, one that cannot be traced is dropped with the
 * reason (GetDroppedPieces()). A piece that is not a roll is split into the sheets that
 * touch in it (pages stuck together; itk::SplitTouchingSheets), each meshed on its own.
 * Sheets are numbered from 0 by size: GetSheetOutput(i) (an itk::Mesh),
 * GetSheetMesh(i), GetSheetReport(i) and GetSheetSummary(i) (voxels, area, physical
 * bounds, pieces, confidence). The output and GetSheetMesh() are the first, largest sheet
 * either way. FindSheetNearestTo(point) picks a sheet by a seed point.
 * Outputs: the itk::Mesh (triangles; grid rows, columns and per-point (row, column) in its
 * meta-data dictionary, keys of itkSheetMeshAdaptor.h), GetSheetMesh() (the same as plain
 * arrays, GridIndex set), GetReport() (method used, spacings, thickness, smallest radius
 * of curvature, axis) and GetWarnings().
 *
 * Errors (itk::ExceptionObject, one line): empty mask, intensity image of another size,
 * too small a volume, nothing traceable (see SheetMidSurfaceExtractor).
 *
 * \ingroup VirtualUnwrapping
 */
/** One sheet found by SheetMidSurfaceMeshFilter with EverySheet on: its size, where it
 * lies (physical bounds of its mesh, mm) and how sure the trace is (the share of its
 * slices traced, not interpolated, times their mean confirmed fraction). */
struct VirtualUnwrapping_EXPORT SheetSummary
{
  size_t Voxels{ 0 };
  /** Voxels times voxel volume over the sheet's measured thickness (mm^2). */
  double Area{ 0.0 };
  double BoundsMinimum[3]{ 0.0, 0.0, 0.0 };
  double BoundsMaximum[3]{ 0.0, 0.0, 0.0 };
  /** Face-connected pieces of the mask meshed as this sheet (more than one: a roll cut by
   * the field of view). */
  size_t Pieces{ 1 };
  double Confidence{ 0.0 };
};

/** The pieces of the mask that SheetMidSurfaceMeshFilter did not mesh, and why. */
struct VirtualUnwrapping_EXPORT DroppedSheetPieces
{
  /** Below MinimumSheetArea: counted, not meshed. */
  size_t TooSmall{ 0 };
  size_t TooSmallVoxels{ 0 };
  /** Large enough but not traceable: voxels, area (mm^2) and the extractor's reason. */
  struct Untraceable
  {
    size_t      Voxels;
    double      Area;
    std::string Reason;
    /** One of the sheets split from a piece (the piece's other sheets were meshed). */
    bool SplitFromPiece{ false };
  };
  std::vector<Untraceable> NotTraced;
};

template <typename TMaskImage, typename TOutputMesh = Mesh<float, 3>>
class ITK_TEMPLATE_EXPORT SheetMidSurfaceMeshFilter : public ImageToMeshFilter<TMaskImage, TOutputMesh>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(SheetMidSurfaceMeshFilter);

  using Self = SheetMidSurfaceMeshFilter;
  using Superclass = ImageToMeshFilter<TMaskImage, TOutputMesh>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using MaskImageType = TMaskImage;
  using OutputMeshType = TOutputMesh;
  using IntensityImageType = Image<float, 3>;
  static_assert(TMaskImage::ImageDimension == 3, "the mask must be a 3D image");

  itkNewMacro(Self);
  itkTypeMacro(SheetMidSurfaceMeshFilter, ImageToMeshFilter);

  void
  SetIntensityImage(const IntensityImageType * image);
  const IntensityImageType *
  GetIntensityImage() const;

  itkSetEnumMacro(Method, SheetSurfaceMethodEnum);
  itkGetEnumMacro(Method, SheetSurfaceMethodEnum);
  itkSetMacro(SpacingAlongSheet, double);
  itkGetConstMacro(SpacingAlongSheet, double);
  itkSetMacro(SpacingAlongAxis, double);
  itkGetConstMacro(SpacingAlongAxis, double);
  itkSetMacro(ChordErrorFraction, double);
  itkGetConstMacro(ChordErrorFraction, double);
  itkSetMacro(AxisTiltTolerance, double);
  itkGetConstMacro(AxisTiltTolerance, double);
  itkSetMacro(EverySheet, bool);
  itkGetConstMacro(EverySheet, bool);
  itkBooleanMacro(EverySheet);
  itkSetClampMacro(MinimumSheetArea, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(MinimumSheetArea, double);

  /** Sheet i's mesh as the output mesh type: the output itself for sheet 0, a mesh of its
   * own (built on the first request after an Update, not connected to the pipeline) for
   * the others. */
  OutputMeshType *
  GetSheetOutput(unsigned int sheet);

  /** Sheets meshed by the last Update(): 1 unless EverySheet is on. */
  unsigned int
  GetNumberOfSheets() const
  {
    return static_cast<unsigned int>(m_Sheets.size());
  }
  const SheetMesh &
  GetSheetMesh(unsigned int sheet) const
  {
    return m_Sheets.at(sheet).Mesh;
  }
  const SheetMidSurfaceReport &
  GetSheetReport(unsigned int sheet) const
  {
    return m_Sheets.at(sheet).Report;
  }
  const SheetSummary &
  GetSheetSummary(unsigned int sheet) const
  {
    return m_Sheets.at(sheet).Summary;
  }
  const DroppedSheetPieces &
  GetDroppedPieces() const
  {
    return m_Dropped;
  }
  /** Which sheet each voxel of the mask belongs to (sheet i: i + 1, 0: none), over the
   * mask's region; built with EverySheet on, null otherwise. */
  using SheetLabelImageType = Image<uint16_t, 3>;
  const SheetLabelImageType *
  GetSheetLabelImage() const
  {
    return m_SheetLabels.GetPointer();
  }
  /** The minimum sheet area applied by the last Update() (mm^2). */
  double
  GetMinimumSheetAreaUsed() const
  {
    return m_MinimumSheetAreaUsed;
  }
  /** The sheet with a mesh point nearest to a physical point (a seed point picking one
   * sheet of several); throws when there is no sheet. */
  unsigned int
  FindSheetNearestTo(const typename MaskImageType::PointType & point) const;

  const SheetMesh &
  GetSheetMesh() const
  {
    return m_Sheets.empty() ? m_Empty.Mesh : m_Sheets.front().Mesh;
  }
  const SheetMidSurfaceReport &
  GetReport() const
  {
    return m_Report;
  }
  const std::vector<std::string> &
  GetWarnings() const
  {
    return m_Report.Warnings;
  }
  /** Figures of the report as plain values (for wrapped languages): the measured sheet
   * thickness, the smallest radius of curvature and the sheet's length along the
   * mid-surface, in mm, and the spacings actually used. */
  double
  GetSheetThickness() const
  {
    return m_Report.SheetThickness;
  }
  double
  GetMinimumCurvatureRadius() const
  {
    return m_Report.MinimumCurvatureRadius;
  }
  double
  GetSheetLength() const
  {
    return m_Report.SheetLength;
  }
  double
  GetSpacingAlongSheetUsed() const
  {
    return m_Report.SpacingAlongSheet;
  }
  double
  GetSpacingAlongAxisUsed() const
  {
    return m_Report.SpacingAlongAxis;
  }

protected:
  SheetMidSurfaceMeshFilter();
  ~SheetMidSurfaceMeshFilter() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;
  void
  GenerateData() override;

private:
  /** Least size of a piece meshed with the largest when their boxes overlap (a roll cut by
   * the field of view), as a fraction of the largest piece: the arc of a cut turn, not a
   * speck of noise. */
  static constexpr double CutArcFraction = 0.002;
  /** A piece whose box comes within this many voxels of a face of the scan reaches its edge
   * (may be cut by the field of view). */
  static constexpr IndexValueType CutEdgeReach = 2;
  /** Automatic minimum sheet area: this fraction of the first sheet's area, and at least
   * this many in-plane voxels. */
  static constexpr double AutomaticMinimumAreaFraction = 0.01;
  static constexpr double AutomaticMinimumAreaVoxels = 400.0;
  /** Pieces whose thickness is measured for the splitter's scale (Pieces::ThinnestSheet): the
   * largest ones, up to this many, of at least this share of the largest's voxels. */
  static constexpr SizeValueType ThicknessPieces = 32;
  static constexpr double        ThicknessPieceShare = 0.05;
  struct Sheet
  {
    SheetMesh             Mesh;
    SheetMidSurfaceReport Report;
    SheetSummary          Summary;
    /** Its voxels: the pieces' labels kept, or one label of a split piece. */
    std::vector<uint8_t>                   Pieces;
    SmartPointer<const Image<uint16_t, 3>> Split;
    uint16_t                               SplitLabel{ 0 };
  };
  using SheetImageType = Image<uint8_t, 3>;
  /** The pieces' labels: 4 bytes a voxel (a scan of 4 G voxels holds fewer pieces). */
  using LabelPixelType = uint32_t;
  using LabelImageType = Image<LabelPixelType, 3>;
  /** The mask's pieces (face-connected components, largest first): their labels, the
   * intensities (or null), their bounding boxes and sizes (by label), and which are done
   * (meshed as part of a sheet, dropped or counted as too small). */
  struct Pieces
  {
    const LabelImageType *      Labels{ nullptr };
    const IntensityImageType *  Intensity{ nullptr };
    SizeValueType               Objects{ 0 };
    std::vector<ImageRegion<3>> Boxes;
    std::vector<SizeValueType>  Sizes;
    std::vector<uint8_t>        Done;
    /** The thinnest of the large pieces' thicknesses (mm; 0: none measured), a page's where a
     * book's pages lie apart in places, which the splitter's scale heeds where pages fused
     * into one piece make it thicker. Measured when a piece is first split (negative until
     * then): a roll never needs it. */
    double ThinnestSheet{ -1.0 };
  };
  /** The sheet made of the pieces of `source` (the labels, or a piece split into the sheets
   * that touch in it) whose labels are kept: their box read, aligned with the roll axis,
   * denoised and traced. */
  template <typename TLabelImage>
  Sheet
  MeshLabels(const TLabelImage *          source,
             const IntensityImageType *   intensity,
             const std::vector<uint8_t> & keep,
             std::vector<std::string> &   warnings);
  /** The sheet made from piece `first`: with the smaller pieces in its box that trace with it
   * as one roll (CutArcFraction of its size at least; it and they reaching the scan's edge,
   * where the field of view cut them apart), or alone. */
  Sheet
  MeshSheetFrom(Pieces & pieces, SizeValueType first, std::vector<std::string> & warnings);
  /** A piece that is not a roll may hold sheets that touch (pages stuck together): split
   * along the dip of the plate measure between them (SplitTouchingSheets) and mesh each;
   * otherwise `whole` alone. */
  std::vector<Sheet>
  SplitSheet(Pieces &                   pieces,
             SizeValueType              piece,
             Sheet &                    whole,
             double                     minimumCoreVoxels,
             std::vector<std::string> & warnings);
  /** Voxels times voxel volume over the first sheet's thickness (mm^2). */
  double
  AreaOf(SizeValueType voxels) const;
  /** What was meshed of how many pieces, when that is not everything; empty otherwise. */
  std::string
  PiecesNote(const Pieces & pieces) const;
  /** m_SheetLabels: every voxel labelled with its sheet's number (from 1). */
  void
  LabelSheets(const LabelImageType * labels);
  static void
  ToPhysicalFrame(const typename SheetImageType::PointType &     origin,
                  const typename SheetImageType::DirectionType & direction,
                  SheetMesh &                                    sheet);
  static void
  Summarise(Sheet & sheet, double area);
  /** Whether the group's mesh (physical frame) holds its pieces: each piece has at least
   * PieceOnMeshFraction of its voxels within PieceOnMeshReach voxels of the mesh's surface,
   * or at most PieceOffMeshFraction (then it is left out of `group`); the first piece must
   * be on the mesh. */
  template <typename TLabelImage>
  static bool
  PiecesOnMesh(const TLabelImage * labels, SizeValueType first, std::vector<uint8_t> & group, const SheetMesh & mesh);
  static constexpr long   PieceOnMeshReach = 2;
  static constexpr double PieceOnMeshFraction = 0.5;
  static constexpr double PieceOffMeshFraction = 0.05;

  SheetSurfaceMethodEnum m_Method{ SheetSurfaceMethodEnum::Auto };
  double                 m_SpacingAlongSheet{ 0.0 };
  double                 m_SpacingAlongAxis{ 0.0 };
  double                 m_ChordErrorFraction{ 0.1 };
  double                 m_AxisTiltTolerance{ 2.0 };
  bool                   m_EverySheet{ false };
  double                 m_MinimumSheetArea{ 0.0 };
  double                 m_MinimumSheetAreaUsed{ 0.0 };
  /** A voxel's share of a sheet's area: its volume over the first sheet's thickness. */
  double                                        m_VoxelArea{ 0.0 };
  std::vector<Sheet>                            m_Sheets;
  std::vector<typename OutputMeshType::Pointer> m_SheetOutputs;
  typename SheetLabelImageType::Pointer         m_SheetLabels;
  Sheet                                         m_Empty;
  DroppedSheetPieces                            m_Dropped;
  SheetMidSurfaceReport                         m_Report;
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkSheetMidSurfaceMeshFilter.hxx"
#endif

#endif

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
#ifndef itkCTVolumeReader_h
#define itkCTVolumeReader_h

#include "VirtualUnwrappingExport.h"
#include "itkDicomSeriesGeometry.h"
#include "itkImage.h"
#include "itkImageSource.h"

#include <cstdint>
#include <string>
#include <vector>

namespace itk {
/** \class CTVolumeReader
 * \brief Reads a CT scan (DICOM series, stack of 2D slices, or a single volume file) into
 * an Image<float, 3> with its physical geometry and calibrated values, or refuses it with
 * a one-line message that names the file and the problem.
 *
 * FileName may be:
 * - a directory holding DICOM files (searched recursively). The files are grouped into
 *   series by SeriesInstanceUID (GDCM scanner); SeriesIdentifier chooses one by UID or
 *   by series number, otherwise the series with the most slices is read (a tie is refused)
 *   and a warning names the choice and the alternatives. Slices are ordered by their
 *   position along the slice normal (ImagePositionPatient . (row x column)), never by
 *   file name or instance number. Rescale Slope/Intercept is applied to each slice (CT
 *   gives Hounsfield units). Every transfer syntax GDCM decodes is accepted (JPEG
 *   lossless, JPEG 2000, JPEG-LS, RLE, deflate, big endian, implicit VR).
 * - a single DICOM file: read when it holds several frames that step through space
 *   (multi-frame); a single frame is a 2D image and is refused, as are a series of one
 *   slice and a cine loop (Frame Increment Pointer = Frame Time).
 * - a directory or a glob pattern (e.g. "scan/slice_*.tif") of 2D slices (8, 16 or 32 bit
 *   TIFF, or any 2D format ITK reads): ordered by natural sort of the file names
 *   (slice2 before slice10). TIFF resolution tags are not trusted: spacing is SpacingOverride
 *   or 1 x 1 x 1 with a warning, origin 0, identity direction.
 * - a single volume file: NRRD, MetaImage (.mha/.mhd), NIfTI, multi-page TIFF (geometry
 *   from the file, except TIFF which is treated like a stack).
 * - a volume-cartographer volume package (`NAME.volpkg`: config.json, volumes/ID/) or one
 *   of its volume directories (meta.json beside the TIFF slices): the slices as a stack,
 *   the voxel size from meta.json's `voxelsize` (micrometres). In a package with several
 *   volumes SeriesIdentifier chooses one by directory name, uuid or name, otherwise the one
 *   with the most slices is read and a warning names the others. A slice count that
 *   differs from meta.json's is refused.
 * - a Zarr v2 array or an OME-Zarr image (a directory, read by itk::ZarrImageIO chunk by
 *   chunk: a region of interest opens only the chunks it overlaps). OME-Zarr gives the
 *   voxel size and origin; a bare array has none (1 x 1 x 1 mm unless SpacingOverride, with
 *   a warning).
 *
 * Geometry of a DICOM series, measured on the headers before any pixel is read
 * (itk::DicomSeriesGeometry): mixed image sizes, pixel spacings or orientations, duplicate
 * slice positions and truncated files among the slices to be read are refused. A regular
 * stack (every slice within SliceSpacingTolerance of first + i x mean spacing, slice
 * origins drifting sideways by at most half a pixel) takes the header geometry: origin of
 * the first slice, PixelSpacing, mean slice spacing, direction (row, column, normal).
 * An irregular stack, as hospital CT delivers with a tilted gantry and protocols that
 * change the slice spacing, is resampled by default onto a regular grid in the patient
 * frame (ResampleIrregularSeries):
 * - a sheared stack (gantry or detector tilt: slice origins drifting sideways) is
 *   corrected from the slice positions themselves, GantryDetectorTilt being only reported;
 * - uneven spacing (runs of different spacing) is equalised to ResampledSliceSpacing;
 * - missing slices (a gap of more than 1.5 times the spacing around it) are named with
 *   their positions, and the voxels between the slices around the gap are NaN;
 * - voxels no slice covers (the corners a sheared stack leaves) are NaN, never invented.
 * The grid's axes are the slices' row, column and normal; in the slice plane it holds
 * every slice (the first slice's pixel lattice, widened to the sheared slices, as
 * dcm2niix's tilt correction does), along the normal it runs from the first slice to the
 * last. Each finding and the correction are one warning each (GetWarnings); the
 * measurements are in GetSeriesGeometry(). A series with more missing slices than
 * acquired ones is refused. Without resampling an irregular stack is refused, naming on
 * one line every irregularity found: the tilt, the largest gap and its files, the spacing
 * runs with their positions.
 *
 * Parameters (all optional):
 * - SeriesIdentifier: SeriesInstanceUID or series number (a volume package: the volume's
 *   directory name, uuid or name); default "" (most slices).
 * - SpacingOverride, OverrideSpacing: voxel size in mm (each > 0) that replaces the
 *   spacing of any input; default off.
 * - RegionOfInterest, UseRegionOfInterest: a box in voxel indices of the full volume,
 *   which must lie inside it; default off.
 * - PhysicalRegionOfInterestStart/End, UsePhysicalRegionOfInterest: two opposite corners
 *   in physical coordinates (mm); the smallest voxel box that holds the voxels whose
 *   centres lie between them (exactly those voxels for an axis-aligned volume), clipped
 *   to the volume (with a warning) and refused when empty; default off.
 * - ShrinkFactor: integer downsampling by averaging (BinShrinkImageFilter) after the
 *   region of interest (the spacing grows by the factor), >= 1; default 1.
 * - SliceSpacingTolerance: how far a DICOM slice may lie from its place on the regular
 *   grid (first position + i x mean spacing), as a fraction of the slice spacing, before
 *   the stack is called irregular (headers often round positions to 0.1 mm); also how
 *   close two spacings must be to form one run, and how far from an acquired slice a grid
 *   slice in a gap may lie and still take its values; (0, 0.5], default 0.05.
 * - ResampleIrregularSeries: resample a sheared or unevenly spaced DICOM series onto a
 *   regular grid (true, default), or refuse it (false).
 * - SliceInterpolator: NearestNeighbor, Linear or BSpline (cubic, default), used in the
 *   slice plane and between the slices around a voxel. Linear interpolation blurs: on the
 *   standard phantom written with a 15 degree tilt it costs 0.03-0.045 of texture NCC,
 *   the cubic B-spline 0.01 or less (docs/ct-reading.md).
 * - ResampledSliceSpacing: slice spacing of the regular grid, mm, >= 0; default 0: the
 *   smallest slice spacing of the series (the spacing of its most finely spaced run).
 *
 * The output streams: a downstream filter that requests a sub-region (for example a few
 * slices, or StatisticsImageFilter with several stream divisions) makes the reader read
 * only the slices it needs (ImageSeriesReader, ExtractImageFilter), so a stack larger
 * than memory can be cropped or summarised. A region of interest is indexed from 0 and
 * its origin is its first voxel. Progress is reported and AbortGenerateData honoured
 * slice by slice. A resampled series is read whole (its slices bracket the grid's).
 *
 * References: DICOM PS3.3 C.7.6.2 (Image Plane Module: ImagePositionPatient,
 * ImageOrientationPatient, PixelSpacing) and C.11.1 (Modality LUT: Rescale
 * Slope/Intercept).
 *
 * What was read is reported after UpdateOutputInformation(): InputKind, Modality,
 * PixelType (stored component type), RescaleSlope/Intercept, ChosenSeries,
 * AlternativeSeries, Warnings, FullSize (before the region of interest and shrinking),
 * SliceFileNames (in slice order), SeriesGeometry (DICOM series), Resampled,
 * ResampledGrid and VoxelsWithoutData (voxels of the resampled grid that are NaN).
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT CTVolumeReader : public ImageSource<Image<float, 3>>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(CTVolumeReader);

  using Self = CTVolumeReader;
  using OutputImageType = Image<float, 3>;
  using Superclass = ImageSource<OutputImageType>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  using RegionType = OutputImageType::RegionType;
  using SizeType = OutputImageType::SizeType;
  using SpacingType = OutputImageType::SpacingType;
  using PointType = OutputImageType::PointType;

  itkNewMacro(Self);
  itkTypeMacro(CTVolumeReader, ImageSource);

  /** One DICOM series found in the input. */
  struct SeriesInfo
  {
    std::string   UID;
    std::string   Number;
    std::string   Description;
    std::string   Modality;
    SizeValueType NumberOfSlices{ 0 };
  };

  itkSetStringMacro(FileName);
  itkGetStringMacro(FileName);
  itkSetStringMacro(SeriesIdentifier);
  itkGetStringMacro(SeriesIdentifier);

  itkSetMacro(SpacingOverride, SpacingType);
  itkGetConstMacro(SpacingOverride, SpacingType);
  itkSetMacro(OverrideSpacing, bool);
  itkGetConstMacro(OverrideSpacing, bool);
  itkBooleanMacro(OverrideSpacing);

  itkSetMacro(RegionOfInterest, RegionType);
  itkGetConstMacro(RegionOfInterest, RegionType);
  itkSetMacro(UseRegionOfInterest, bool);
  itkGetConstMacro(UseRegionOfInterest, bool);
  itkBooleanMacro(UseRegionOfInterest);

  itkSetMacro(PhysicalRegionOfInterestStart, PointType);
  itkGetConstMacro(PhysicalRegionOfInterestStart, PointType);
  itkSetMacro(PhysicalRegionOfInterestEnd, PointType);
  itkGetConstMacro(PhysicalRegionOfInterestEnd, PointType);
  itkSetMacro(UsePhysicalRegionOfInterest, bool);
  itkGetConstMacro(UsePhysicalRegionOfInterest, bool);
  itkBooleanMacro(UsePhysicalRegionOfInterest);

  itkSetClampMacro(ShrinkFactor, unsigned int, 1, NumericTraits<unsigned int>::max());
  itkGetConstMacro(ShrinkFactor, unsigned int);

  itkSetClampMacro(SliceSpacingTolerance, double, 1e-6, 0.5);
  itkGetConstMacro(SliceSpacingTolerance, double);

  itkSetMacro(ResampleIrregularSeries, bool);
  itkGetConstMacro(ResampleIrregularSeries, bool);
  itkBooleanMacro(ResampleIrregularSeries);
  /** Whether finding the volume's information (UpdateOutputInformation) also inflates the
   * compressed data of a MetaImage file to find damage, as a file check does; off by default:
   * reading the voxels inflates them once and stops on damage anyway. */
  itkSetMacro(VerifyCompressedData, bool);
  itkGetConstMacro(VerifyCompressedData, bool);
  itkBooleanMacro(VerifyCompressedData);
  itkSetEnumMacro(SliceInterpolator, SliceInterpolatorEnum);
  itkGetEnumMacro(SliceInterpolator, SliceInterpolatorEnum);
  itkSetClampMacro(ResampledSliceSpacing, double, 0.0, NumericTraits<double>::max());
  itkGetConstMacro(ResampledSliceSpacing, double);

  /** "DICOM series", "DICOM multi-frame file", "image stack" or "image file". */
  itkGetStringMacro(InputKind);
  /** DICOM Modality (CT, MR, ...); empty for other formats. */
  itkGetStringMacro(Modality);
  /** Stored pixel component type before calibration: uint8, int16, uint16, float... */
  itkGetStringMacro(PixelType);
  itkGetConstMacro(RescaleSlope, double);
  itkGetConstMacro(RescaleIntercept, double);
  itkGetConstMacro(FullSize, SizeType);
  /** True when an irregular DICOM series was resampled onto ResampledGrid. */
  itkGetConstMacro(Resampled, bool);
  itkGetConstMacro(VoxelsWithoutData, SizeValueType);
  const RegularGrid &
  GetResampledGrid() const
  {
    return m_ResampledGrid;
  }
  /** Slice positions, spacing runs, gaps and shear of the DICOM series read (empty for
   * other inputs and multi-frame files). */
  const DicomSeriesGeometry &
  GetSeriesGeometry() const
  {
    return m_SeriesGeometry;
  }

  const SeriesInfo &
  GetChosenSeries() const
  {
    return m_ChosenSeries;
  }
  const std::vector<SeriesInfo> &
  GetAlternativeSeries() const
  {
    return m_AlternativeSeries;
  }
  const std::vector<std::string> &
  GetWarnings() const
  {
    return m_Warnings;
  }
  const std::vector<std::string> &
  GetSliceFileNames() const
  {
    return m_SliceFileNames;
  }

protected:
  CTVolumeReader() = default;
  ~CTVolumeReader() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

  /** Examines the input (headers only), checks its geometry and builds the internal
   * reading pipeline; throws ExceptionObject when the input cannot be read as a volume. */
  void
  GenerateOutputInformation() override;

  /** Reads the requested region through the internal pipeline. */
  void
  GenerateData() override;

private:
  void
  ResetFacts();
  /** Reads a list of files (a directory's, or a glob's matches): a TIFF stack, a DICOM
   * series found among dicomSearch, or a stack of other 2D images. */
  void
  ExamineFiles(const std::vector<std::string> & listed, const std::vector<std::string> & dicomSearch);
  /** Returns false when none of the files is DICOM; throws when the DICOM input cannot
   * be read as a volume. */
  bool
  ExamineDicom(const std::vector<std::string> & files, bool singleFile);
  /** Measures a DICOM series' slice geometry and chooses: header geometry, resampling, or
   * refusal. */
  void
  ExamineSliceGeometry(DicomSliceStack stack, const std::string & gantryTilt);
  void
  ExamineSliceStack(std::vector<std::string> files);
  void
  ExamineVolumeFile(const std::string & file);
  void
  ExamineZarrStore();
  /** A volume-cartographer package or volume directory: false when the directory is not one. */
  bool
  ExamineVolumePackage();
  void
  BuildPipeline();
  /** After a failed read: the first file of the region of interest that cannot be read. */
  std::string
  FindUnreadableFile() const;

  std::string           m_FileName;
  std::string           m_SeriesIdentifier;
  SpacingType           m_SpacingOverride{ 1.0 };
  bool                  m_OverrideSpacing{ false };
  RegionType            m_RegionOfInterest;
  bool                  m_UseRegionOfInterest{ false };
  PointType             m_PhysicalRegionOfInterestStart{ 0.0 };
  PointType             m_PhysicalRegionOfInterestEnd{ 0.0 };
  bool                  m_UsePhysicalRegionOfInterest{ false };
  unsigned              m_ShrinkFactor{ 1 };
  double                m_SliceSpacingTolerance{ 0.05 };
  bool                  m_ResampleIrregularSeries{ true };
  bool                  m_VerifyCompressedData{ false };
  SliceInterpolatorEnum m_SliceInterpolator{ SliceInterpolatorEnum::BSpline };
  double                m_ResampledSliceSpacing{ 0.0 };

  std::string              m_InputKind;
  std::string              m_Modality;
  std::string              m_PixelType;
  double                   m_RescaleSlope{ 1.0 };
  double                   m_RescaleIntercept{ 0.0 };
  SizeType                 m_FullSize{ { 0, 0, 0 } };
  SeriesInfo               m_ChosenSeries;
  std::vector<SeriesInfo>  m_AlternativeSeries;
  std::vector<std::string> m_Warnings;
  std::vector<std::string> m_SliceFileNames;
  DicomSeriesGeometry      m_SeriesGeometry;
  bool                     m_Resampled{ false };
  RegularGrid              m_ResampledGrid;
  SizeValueType            m_VoxelsWithoutData{ 0 };

  /** The internal pipeline (reader, geometry, region of interest, shrinking), kept alive
   * here because a filter's output holds only a weak reference to its source. */
  std::vector<ProcessObject::Pointer> m_Pipeline;
  /** The geometry given to the volume instead of the one ITK's image IO reports: checked
   * DICOM header geometry, or for stacks and TIFF files (no trustworthy geometry) origin
   * 0, 1 mm spacing, identity direction. */
  bool                           m_ReplaceGeometry{ false };
  PointType                      m_GeometryOrigin{ 0.0 };
  SpacingType                    m_GeometrySpacing{ 1.0 };
  OutputImageType::DirectionType m_GeometryDirection{ OutputImageType::DirectionType::GetIdentity() };
  OutputImageType::Pointer       m_PipelineOutput;
  bool                           m_IsDicom{ false };
  /** Size of the pixel data of one DICOM file, to detect truncated files. */
  uintmax_t m_DicomPixelBytes{ 0 };
  /** Files of the region of interest: [first, end) of SliceFileNames. */
  size_t m_FirstSliceToRead{ 0 };
  size_t m_EndSliceToRead{ 0 };
};
} // end namespace itk

#endif

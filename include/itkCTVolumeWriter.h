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
#ifndef itkCTVolumeWriter_h
#define itkCTVolumeWriter_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkObject.h"
#include "itkObjectFactory.h"

#include <string>
#include <vector>

namespace itk {
/** \class CTVolumeWriter
 * \brief Writes a CT volume in Hounsfield units the way scanners and archives deliver
 * them: a DICOM CT series, a 16-bit TIFF stack, a single MetaImage / NRRD file, or an
 * OME-Zarr store.
 *
 * Formats (Format):
 * - Dicom: FileName is a directory; one CT Image Storage file per slice, IMnnnnn.dcm,
 *   numbered in a shuffled order (seeded by Seed) so that readers must sort by position.
 *   Pixels are int16 stored values with RescaleSlope 1 and RescaleIntercept -1024 (HU =
 *   stored - 1024); every file carries ImagePositionPatient of its slice,
 *   ImageOrientationPatient from the direction, PixelSpacing, SliceThickness and
 *   SpacingBetweenSlices, InstanceNumber, one StudyInstanceUID, SeriesInstanceUID and
 *   FrameOfReferenceUID, and SeriesDescription;
 * - Tiff: FileName is a directory; slice_0000.tif, slice_0001.tif ... in slice order,
 *   unsigned 16-bit, value = HU + 1024 (so HU below -1024, air noise, is clipped to
 *   -1024 as scanners do). TIFF keeps no 3D geometry: give the spacing to
 *   the reader (the phantom tool records it in its JSON);
 * - MetaImage (.mha) and Nrrd (.nrrd): FileName is the file; int16 HU, zlib-compressed,
 *   with origin, spacing and direction.
 * - Zarr (.zarr): FileName is the store; an OME-Zarr image (itk::ZarrImageIO), int16 HU
 *   in 64^3 chunks compressed by blosc (zstd), with origin and spacing (the direction must
 *   be the identity).
 *
 * A DICOM series can be written the way a hospital CT delivers head and spine scans, so
 * that readers are tested against a known volume:
 * - GantryTilt (degrees, in (-60, 60), default 0): the slices are acquired in a gantry
 *   tilted about the row axis. Every slice keeps the input's orientation, and its origin
 *   moves along the column axis by -tan(GantryTilt) times its distance from the first
 *   slice along the slice normal (the sheared stack GE scanners write; dcm2niix reads a
 *   positive GantryDetectorTilt from it); GantryDetectorTilt (0018,1120) holds the angle.
 *   The slices get rows enough that each holds the whole input (OutsideValue beyond it).
 * - SliceLocations (mm, default empty: one slice per input slice): where along the input's
 *   third axis, from its first slice, the slices are taken; increasing, within the input.
 *   SliceLocationsWithSpacingChange() gives a series whose spacing changes mid-way.
 * Such slices are sampled from the input by Lanczos-windowed sinc interpolation of radius
 * 4 (itk::WindowedSincInterpolateImageFunction): the closest ITK comes to sampling the
 * scanned object itself, and it gives back the input's values at its own voxels;
 * SliceThickness is then the distance to the next slice, SpacingBetweenSlices is written
 * only for evenly spaced slices. Both are refused for the other formats.
 * - OutsideValue (HU, default -1000, air): written where a sheared slice reaches beyond
 *   the input.
 *
 * Values are rounded to whole HU and clamped to the range of the stored type. Directories
 * are created when missing. Throws itk::ExceptionObject without an input, file name, or
 * when writing fails.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT CTVolumeWriter : public Object
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(CTVolumeWriter);

  using Self = CTVolumeWriter;
  using Superclass = Object;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using ImageType = Image<float, 3>;

  enum class FormatType
  {
    Dicom,
    Tiff,
    MetaImage,
    Nrrd,
    Zarr
  };

  itkNewMacro(Self);
  itkTypeMacro(CTVolumeWriter, Object);

  /** "dicom", "tiff", "mha", "nrrd" or "zarr"; throws on anything else. */
  static FormatType
  FormatFromString(const std::string & name);
  static const char *
  FormatName(FormatType format);

  itkSetConstObjectMacro(Input, ImageType);
  itkGetConstObjectMacro(Input, ImageType);
  itkSetStringMacro(FileName);
  itkGetStringMacro(FileName);
  itkSetEnumMacro(Format, FormatType);
  itkGetEnumMacro(Format, FormatType);
  itkSetStringMacro(SeriesDescription);
  itkGetStringMacro(SeriesDescription);
  itkSetMacro(Seed, uint32_t);
  itkGetConstMacro(Seed, uint32_t);
  itkSetMacro(GantryTilt, double);
  itkGetConstMacro(GantryTilt, double);
  itkSetMacro(OutsideValue, double);
  itkGetConstMacro(OutsideValue, double);
  void
  SetSliceLocations(const std::vector<double> & locations)
  {
    m_SliceLocations = locations;
    this->Modified();
  }
  const std::vector<double> &
  GetSliceLocations() const
  {
    return m_SliceLocations;
  }

  /** Slice locations from 0 to extent (mm): firstSpacing up to half the extent, then
   * secondSpacing (both > 0); the last slice lies at most one spacing before extent. */
  static std::vector<double>
  SliceLocationsWithSpacingChange(double extent, double firstSpacing, double secondSpacing);

  void
  Write();

protected:
  CTVolumeWriter() = default;
  ~CTVolumeWriter() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  void
  WriteDicom() const;
  /** The input sampled on the tilted or relocated slices: a stack holding slice k at
   * index k, and each slice's origin. */
  ImageType::Pointer
  SampleSlices(const std::vector<double> & locations, std::vector<ImageType::PointType> & origins) const;
  void
  WriteTiff() const;
  void
  WriteSingleFile() const;

  ImageType::ConstPointer m_Input;
  std::string             m_FileName;
  FormatType              m_Format{ FormatType::Dicom };
  std::string             m_SeriesDescription{ "VirtualUnwrapping sheet phantom" };
  uint32_t                m_Seed{ 1 };
  double                  m_GantryTilt{ 0.0 };
  double                  m_OutsideValue{ -1000.0 };
  std::vector<double>     m_SliceLocations;
};
} // end namespace itk

#endif

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
 * one connected mesh) and, when there are several, a warning says so. Only the bounding
 * box of that component (plus two voxels) is read. The roll axis is estimated as the
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

  const SheetMesh &
  GetSheetMesh() const
  {
    return m_SheetMesh;
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
  using SheetImageType = Image<uint8_t, 3>;
  using AxisType = Vector<double, 3>;
  static AxisType
  EstimateRollAxis(const SheetImageType * sheetMask, const IntensityImageType * sheetIntensity, bool & fromTensor);
  static AxisType
  EstimateRollAxisFromCentroids(const SheetImageType * sheetMask);
  /** Returns true when the axis came from the structure tensor (so the slices now cut
   * straight across it). After a resampling, sheetData marks the voxels that lie inside the
   * original box (1; the others hold no data of the scan); otherwise it is left null. */
  bool
  AlignWithRollAxis(typename SheetImageType::Pointer &     sheetMask,
                    typename IntensityImageType::Pointer & sheetIntensity,
                    typename SheetImageType::Pointer &     sheetData,
                    std::vector<std::string> &             warnings) const;
  /** Smooths the intensities of a noisy scan for tracing (SheetIntensityLevels::DenoisingSigma
   * across the sheet, twice that along the roll axis); a clean scan is left as it is. */
  void
  Denoise(const SheetImageType *                 sheetMask,
          typename IntensityImageType::Pointer & sheetIntensity,
          std::vector<std::string> &             warnings) const;

  SheetSurfaceMethodEnum m_Method{ SheetSurfaceMethodEnum::Auto };
  double                 m_SpacingAlongSheet{ 0.0 };
  double                 m_SpacingAlongAxis{ 0.0 };
  double                 m_ChordErrorFraction{ 0.1 };
  double                 m_AxisTiltTolerance{ 2.0 };
  SheetMesh              m_SheetMesh;
  SheetMidSurfaceReport  m_Report;
};
} // end namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkSheetMidSurfaceMeshFilter.hxx"
#endif

#endif

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
#ifndef itkSheetRollAxis_h
#define itkSheetRollAxis_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkVector.h"

#include <string>
#include <vector>

namespace itk {
/** \brief The roll axis of a sheet's box, the box resampled across it, and its intensities
 * smoothed for tracing: the steps of SheetMidSurfaceMeshFilter that do not depend on its
 * image and mesh types (compiled once, in the library).
 *
 * Estimate(): the direction of least gradient energy over the sheet (the structure
 * tensor's smallest eigenvector, from Gaussian derivatives at one voxel, less the noise's
 * own tensor measured in the air three voxels or more from the sheet), where the middle
 * eigenvalue stands well above the smallest, or above it and comparable with the largest
 * (a roll spreads its normals across its axis), and the axis lies within 45 degrees of the
 * slice normal; otherwise EstimateFromCentroids(),
 * the least-squares line through the centroids of the middle 60 % of the slices
 * (`tensorAxisInReach`, when given, receives the tensor's axis wherever it lies within 45
 * degrees of the slice normal; `tensorSpread` the ratio of the middle eigenvalue to the
 * smallest: how far the normals spread across that axis; `flatSheetNormal` the tensor's
 * largest eigenvector where the middle eigenvalue is below 0.15 of it (the normals all
 * near one direction: a flat or gently curved sheet), else zero).
 * Align(): when the axis is tilted from the slice normal by more than `tiltTolerance`
 * degrees, or the in-plane voxels are not square, resamples the box onto a grid whose third
 * axis is the roll axis and whose in-plane voxels are square; the centroids' line, refined on
 * each resampled grid, gives way to the tensor's axis within reach wherever it leaves the
 * slice normal by more than 45 degrees, or that axis by more than 2 where the tensor shows a
 * spread of the normals across it (the centroids of a short roll's tilted slices move across
 * it). A flat or gently curved sheet whose axis is not the tensor's takes the direction in
 * its plane nearest the slice normal, where that lies within 45 degrees of it. Returns true
 * when the axis came from the structure tensor (so the slices now cut straight across it).
 * After a resampling, sheetData marks the voxels that lie inside the original box (1; the
 * others hold no data of the scan); otherwise it is left null.
 * Denoise(): smooths the intensities of a noisy scan for tracing
 * (SheetIntensityLevels::DenoisingSigma across the sheet, twice that along the roll axis);
 * a clean scan is left as it is.
 * HideOtherSheets(): in a box whose mask marks the sheet 1 and the material of other sheets
 * 2, the other sheets' voxels and their rims (the voxels within two voxels of them and not
 * of this sheet) take values of the box's own air, drawn from it in a fixed order, so that no
 * tracer follows a neighbouring page or fragment; the mask is left 0 / 1.
 * Align() and Denoise() each add a line to `warnings` for what they changed.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetRollAxis
{
public:
  using SheetImageType = Image<uint8_t, 3>;
  using IntensityImageType = Image<float, 3>;
  using AxisType = Vector<double, 3>;

  static AxisType
  Estimate(const SheetImageType *     sheetMask,
           const IntensityImageType * sheetIntensity,
           bool &                     fromTensor,
           AxisType *                 tensorAxisInReach = nullptr,
           double *                   tensorSpread = nullptr,
           AxisType *                 flatSheetNormal = nullptr);
  static AxisType
  EstimateFromCentroids(const SheetImageType * sheetMask);
  static bool
  Align(SheetImageType::Pointer &     sheetMask,
        IntensityImageType::Pointer & sheetIntensity,
        SheetImageType::Pointer &     sheetData,
        double                        tiltTolerance,
        std::vector<std::string> &    warnings);
  static void
  HideOtherSheets(SheetImageType * sheetMask, IntensityImageType * sheetIntensity);
  static void
  Denoise(const SheetImageType *        sheetMask,
          IntensityImageType::Pointer & sheetIntensity,
          std::vector<std::string> &    warnings);
};
} // end namespace itk

#endif

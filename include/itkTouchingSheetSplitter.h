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
#ifndef itkTouchingSheetSplitter_h
#define itkTouchingSheetSplitter_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"

namespace itk {
/** \brief Splits one piece of a sheet mask into the sheets that touch within it: pages
 * stuck together over part of their area, which thresholding joins into one piece.
 *
 * A sheet is a bright plate: across it the intensity's second derivative is strongly
 * negative, along it small. The plate measure P = -lambda1 where the Hessian's most
 * negative eigenvalue lambda1 dominates (both others below half its size), 0 elsewhere
 * (itk::HessianRecursiveGaussianImageFilter at a scale of 0.4 times the sheets' thickness,
 * twice the piece's volume over its surface, and at least Sigma, mm), is
 * high along each sheet's
 * middle and dips where two sheets meet, even where they fuse with no gap left (two
 * sheets side by side make a slab twice as thick, whose middle bends less). The cores,
 * the piece's voxels where P exceeds a fraction of its median over the piece, are taken
 * from a fraction of 0.6 upwards in steps of 0.1 (to 1.3: a fused slab's middle keeps
 * about 0.8 of a sheet's measure, near the median): a core that falls apart at the next
 * step into two or more cores of at least MinimumCoreVoxels each is replaced by them when
 * they lie one on the other (their footprints on the core's mean plane overlapping by half
 * the smaller or more) and met inside every footprint (a page bulging onto the next), the
 * others stay whole, so a sheet that noise or ink breaks into parts side by side, or a
 * fold whose panels meet at a crease on their edges, is not split. Every voxel of the
 * piece then goes to its nearest core (itk::DanielssonDistanceMapImageFilter's Voronoi
 * map): across a fused contact, the middle of the slab.
 *
 * Inputs over one region: Values (intensities, or the mask itself as 0/1), Piece (non-zero
 * = the piece). Output: labels 1..Sheets on the piece's voxels (0 elsewhere), largest
 * first; Sheets is 1 (and the labels all 1) when the piece holds one sheet.
 * \ingroup VirtualUnwrapping
 */
struct VirtualUnwrapping_EXPORT TouchingSheetSplit
{
  Image<uint16_t, 3>::Pointer Labels;
  unsigned int                Sheets{ 0 };
};

VirtualUnwrapping_EXPORT TouchingSheetSplit
SplitTouchingSheets(const Image<float, 3> *   values,
                    const Image<uint8_t, 3> * piece,
                    double                    sigma,
                    SizeValueType             minimumCoreVoxels);
/** A copy of `volume` in which the voxels of the other sheets (labels of `sheets` other
 * than 0 and `sheet`), and the unlabelled voxels next to them (their blurred faces), hold
 * the background: values of the unlabelled voxels away from every sheet (air as scanned,
 * noise and all), drawn in a fixed order. A sheet's texture sampled from it
 * does not show the sheets that touch it. `sheets` covers the volume's region (as
 * SheetMidSurfaceMeshFilter::GetSheetLabelImage does). */
VirtualUnwrapping_EXPORT Image<float, 3>::Pointer
BlankOtherSheets(const Image<float, 3> * volume, const Image<uint16_t, 3> * sheets, uint16_t sheet);
} // end namespace itk

#endif

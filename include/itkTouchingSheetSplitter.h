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

#include <cmath>
#include <vector>

namespace itk {

/** The thickness of the plate made by the voxels of each class 1 .. `classes` of `image`
 * within `region` (element k; `classOf(value)` gives a voxel's class, 0 for none): twice
 * the class's volume over the area of its faces to the other voxels (a staircase overstates
 * an oblique sheet's area, so this errs thin), in physical units (a voxel's cube root of
 * volume per voxel); 0 for a class without voxels. One pass over the region. */
template <typename TImage, typename TClassOf>
std::vector<double>
PlateThicknessOfClasses(const TImage * image, const ImageRegion<3> & region, size_t classes, TClassOf classOf)
{
  const auto                 size = region.GetSize();
  const auto                 full = image->GetBufferedRegion().GetSize();
  const auto                 start = image->ComputeOffset(region.GetIndex());
  const auto *               in = image->GetBufferPointer();
  const auto &               spacing = image->GetSpacing();
  std::vector<SizeValueType> voxels(classes + 1, 0), faces(classes + 1, 0);
  const OffsetValueType      step[3] = { 1,
                                         static_cast<OffsetValueType>(full[0]),
                                         static_cast<OffsetValueType>(full[0] * full[1]) };
  for (SizeValueType z = 0; z < size[2]; ++z)
  {
    for (SizeValueType y = 0; y < size[1]; ++y)
    {
      for (SizeValueType x = 0; x < size[0]; ++x)
      {
        const auto   v = start + static_cast<OffsetValueType>((z * full[1] + y) * full[0] + x);
        const size_t k = classOf(in[v]);
        if (k == 0)
        {
          continue;
        }
        ++voxels[k];
        const SizeValueType at[3] = { x, y, z };
        for (unsigned d = 0; d < 3; ++d)
        {
          faces[k] +=
            (at[d] == 0 || classOf(in[v - step[d]]) != k) + (at[d] + 1 == size[d] || classOf(in[v + step[d]]) != k);
        }
      }
    }
  }
  std::vector<double> thickness(classes + 1, 0.0);
  const double        voxel = std::cbrt(spacing[0] * spacing[1] * spacing[2]);
  for (size_t k = 1; k <= classes; ++k)
  {
    thickness[k] = faces[k] > 0 ? 2.0 * voxel * static_cast<double>(voxels[k]) / static_cast<double>(faces[k]) : 0.0;
  }
  return thickness;
}

/** The thickness of the plate made by the voxels of `image` within `region` for which
 * `inside(value)` holds (PlateThicknessOfClasses with one class). */
template <typename TImage, typename TInside>
double
PlateThickness(const TImage * image, const ImageRegion<3> & region, TInside inside)
{
  return PlateThicknessOfClasses(
    image, region, 1, [&inside](auto value) { return inside(value) ? size_t{ 1 } : size_t{ 0 }; })[1];
}

/** PlateThickness of each label 1 .. `labels` of a label image within `region` at once
 * (element l; element 0 is not measured): one pass instead of one per label. Labels above
 * `labels` count as other voxels. */
template <typename TImage>
std::vector<double>
PlateThicknessPerLabel(const TImage * image, const ImageRegion<3> & region, size_t labels)
{
  return PlateThicknessOfClasses(image, region, labels, [labels](auto value) {
    const auto l = static_cast<size_t>(value);
    return l <= labels ? l : size_t{ 0 };
  });
}
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
 * map): across a fused contact, the middle of the slab. Where pages lie a voxel or so
 * apart or fuse, a page's face (denser where inked) can lie nearer to the other page's core
 * than to its own: a voxel that lies across its nearest core (along the core's normal, the
 * Hessian's eigenvector across the sheet) further than half the sheet's thickness less half
 * the core's, and a voxel and a half more, goes to the nearest core of another sheet within
 * whose reach it lies.
 *
 * Pages fused into one piece make it thicker than a page, and the scale its thickness
 * sets coarser than a page's: where a part split off, or SheetThickness (mm: the scan's
 * thinnest sheet where known, 0 otherwise), asks for a scale below 0.85 of the first, the
 * piece is split again at that finer scale, and the finer split is kept when it finds
 * more sheets that lie apart: every two that meet do so over less than half the smaller
 * one's footprint (pages with a gap between them, fused where one bulges onto the next), or
 * the intensity where they meet dips a quarter of the way from the sheets' level to the
 * air's (pages whose gap the mask fills). A thick sheet's two faces, which a scale well
 * below its thickness sees as two plates, meet all over across its dense middle.
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
                    SizeValueType             minimumCoreVoxels,
                    double                    sheetThickness = 0.0);
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

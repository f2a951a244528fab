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
#ifndef itkLayerStackTexture_h
#define itkLayerStackTexture_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkTextureLayers.h"

#include <vector>

namespace itk {
/** \class LayerStackTexture
 * \brief Textures made after sampling, from a layer stack (FlattenedTextureImageFilter's
 * output 2): one side of the sheet, the sheet's core subtracted, an ink-contrast score to
 * choose between such textures, NaN-aware smoothing and trimming of the sheet's border.
 *
 * All images are float; NaN marks pixels off the sheet and stays NaN. Every function
 * throws itk::ExceptionObject with a one-line message on a missing image or a parameter
 * out of range.
 *
 * - Combine(): the layers of a stack sampled with (numberOfLayers, layerSpacing, focus,
 *   stackSide) that lie on `side` of the focus, combined with `filter` exactly as
 *   TextureLayers combines them. A stack sampled on Both sides (an odd number of layers)
 *   splits into its Positive half (the focus layer and the layers along the normal) and
 *   its Negative half; otherwise `side` must be the stack's side. With coreWidth > 0 the
 *   mean of the chosen layers within coreWidth of the focus (the sheet's core when the
 *   focus is the mid-surface) is subtracted: ink is dense matter added near a face, while
 *   the sheet's own structure (fibres, density changes) runs through its depth, so the
 *   difference keeps the ink and cancels most of the structure.
 * - InkContrast(): (99th percentile - median) / (1.4826 median absolute deviation) of the
 *   finite pixels: how far the brightest percent stands above the spread of the bulk.
 *   Ink is denser than the sheet and covers a small part of it, so the texture that shows
 *   it best scores highest; structure and noise raise the spread and lower the score.
 *   Returns 0 when fewer than 2 pixels are finite or the spread is 0.
 * - LayerWindow(): the mean of layers first .. first + count - 1 of a stack, pixel by
 *   pixel over the finite samples (NaN where none is): a focal slab through the sheet. On a
 *   noisy scan the mean of the few layers that hold the ink keeps it and averages the
 *   noise, where the maximum over many noisy layers can pick the noise's extremes.
 * - StrokeContrast(): the ink contrast of the band-pass Smooth(strokeSigma) -
 *   Smooth(6 strokeSigma): letters' strokes are kept, the sheet's slow changes of
 *   brightness (a slab drifting towards a face, the sheet's edges) and pixel noise are not,
 *   so among focal slabs of a noisy scan the one that shows the writing scores highest.
 *   The band's 96th percentile is taken block by block along the texture's longer side
 *   (blocks as long as the shorter side, at least 64 pixels, overlapping by half, scored
 *   when a quarter of their pixels is on the sheet), and the highest, less the whole
 *   band's median, over its spread (1.4826 median absolute deviation) is the score: a
 *   few lines of writing on a long sheet fill the top 4 % of their blocks but not of the
 *   whole texture, and a compact blot (a bulge's flank, a blanked patch's rim) fills the
 *   top percent of its block but not the top 4 %. Pixels within 6 strokeSigma of the
 *   sheet's border, where the band rings, are not scored. With `leaveOut` (a texture of
 *   the same size), the pixels where it is not finite are left out of the score (not of
 *   the filtering): where the sheet is off the surface the stack was sampled about, or
 *   another sheet touches it.
 * - Quantiles(): the values of the finite pixels at the given ranks q (0..1; the value
 *   of rank round(q (n - 1)) of the n finite pixels sorted), exactly, by sampled selection
 *   in a few passes without copying the texture (a display window, a noise level). An
 *   empty list when no pixel is finite.
 * - DisplayWindow(): the values {low, high} shown as black and white: the 99.5th
 *   percentile of the finite pixels and the larger of their 0.5th percentile and the
 *   median plus half NoiseSpread() (with inkIsBright false, mirrored: the 0.5th
 *   percentile, and the smaller of the 99.5th and the median less half the spread). The
 *   sheet's background, most of a texture, is then dark, its noise mostly below the
 *   black point, and the ink stands out alone: a person and OCR read it without the
 *   background's speckle, which on a noisy scan reads as letters. Where that leaves no
 *   range, the plain percentile window. Empty when no pixel is finite.
 * - ClearBackground(): a copy in which every finite pixel that is not ink takes the
 *   median of the finite pixels (the sheet's background). Ink is made of the components
 *   (8 neighbours, ITK's ConnectedComponentImageFilter) of the pixels more than one
 *   NoiseSpread() beyond the median in the ink's direction (brighter when inkIsBright)
 *   that reach a pixel more than 4.5 spreads beyond it, or whose mass (the sum of their
 *   pixels' excess over one spread) exceeds that of every component on the other side of
 *   the median that stays within 4.5 spreads of it (a blot beyond that is no measure of
 *   the noise) while their box is at most 1.5 times the median height, and width, of the
 *   components of the first kind, or while they are faint letters run together along a
 *   line (the lines run along the texture's longer side: 0.5 to 1.5 times those
 *   components' height across it, at most 4 times it along it). A letter's faint parts
 *   are kept with its strong ones; a faint letter that nowhere reaches 4.5 spreads but
 *   outweighs every blob of the noise is kept whole (the noise makes blobs on both sides
 *   alike, the ink on one side only, so
 *   the other side measures the noise's largest blob in this very texture: high over a
 *   long sheet, low over a small page), and a faint band across a sheet, larger than any
 *   letter, is not. The background's noise, which passes one spread in a sixth of
 *   the pixels and 4.5 about 3 times in a million, is cleared: over a long sheet that
 *   speckle is what OCR reads as letters. A texture with no pixel 4.5 spreads beyond its
 *   median, or without spread, is returned unchanged; NaN stays NaN.
 *   Display the result in DisplayWindow() of the texture before clearing.
 * - NoiseSpread(): 1.4826 x the median absolute deviation of the finite pixels (the
 *   standard deviation for Gaussian noise): the spread of the sheet's background, which
 *   covers most of a texture; 0 when fewer than 2 pixels are finite.
 * - EdgePreservingSmooth(): ITK's BilateralImageFilter, a Gaussian of standard deviation
 *   domainSigma (physical units; 0 returns a copy) weighted by a Gaussian of the
 *   difference in value of standard deviation rangeSigma (> 0): averages the noise of the
 *   background and of the ink and keeps the edges between them, where differences are
 *   large. A range sigma of about twice NoiseSpread() suits textures with sharp ink.
 *   NaN pixels neither contribute nor change.
 * - Deconvolve(): undoes a Gaussian blur of standard deviation psfSigma (physical units;
 *   0 returns a copy) with ITK's TikhonovDeconvolutionImageFilter and the given
 *   regularization (> 0; relative to the PSF's unit gain: larger is smoother), scaled
 *   by 1 + regularization so that flat regions keep their value. NaN pixels are filled
 *   with the median of the finite ones for the transform and stay NaN.
 * - ScanBlurSigma(): the standard deviation of the blur a texture sampled from a scan
 *   carries, for Deconvolve(): the scanner's Gaussian PSF of full width at half maximum
 *   psfFWHM combined with the partial volume of voxels of size voxelSize,
 *   sqrt((psfFWHM / 2.3548)^2 + voxelSize^2 / 12) (both >= 0, physical units).
 * - RegisterToSheet(): the stack resampled along its depth so that the sheet lies at the
 *   same layers in every pixel. A mesh is never exactly on the sheet: its flat triangles
 *   cut inside a curved sheet between their corners, a bulge it does not follow leaves it
 *   off, and across a sheet's faces the scan changes steeply with depth, so a layer at a
 *   fixed depth from the mesh shows these depth errors as stripes and blotches as strong
 *   as the ink. In each pixel the sheet's centre is the centroid, over the layers, of the
 *   stack's excess over the midpoint between air (the darkest layer's median) and sheet
 *   (the middle layer's median), the stack first smoothed across the texture with a
 *   Gaussian of `sigma` (physical units: wider than a stroke, so the ink, dense matter
 *   near one face, hardly moves it); the centres are smoothed with a quarter of that and
 *   each pixel's layers are read again, by linear interpolation along the depth (the end
 *   layers repeated beyond the stack), shifted by its centre's offset from the median
 *   centre. A stack of fewer than three layers, or without a sheet brighter than the air,
 *   is returned as a copy; NaN stays NaN, and a pixel without material keeps its layers.
 *   With `shift`, it receives each pixel's shift along the depth (the stack's third
 *   spacing times the layers; NaN where nothing was shifted): a map of where, and how
 *   far, the mesh lies off the sheet.
 * - Smooth(): Gaussian of standard deviation sigma (physical units, 0 returns a copy) by
 *   normalised convolution: NaN pixels neither contribute nor change.
 * - Median(): median of the finite pixels in the square of half-side `radius` (physical
 *   units, rounded to whole pixels per axis; less than half a pixel returns a copy) around
 *   each finite pixel; NaN pixels stay NaN. Removes specks smaller than about the radius
 *   and keeps edges.
 * - TrimBorder(): pixels whose centre lies less than `width` (physical units) inside the
 *   edge of the finite region (taken half a pixel beyond the centres of its outermost
 *   pixels; the image border counts as an edge) become NaN; 0 returns a copy.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT LayerStackTexture
{
public:
  using TextureType = Image<float, 2>;
  using LayerStackType = Image<float, 3>;
  using SideType = TextureLayersEnums::Side;
  using FilterType = TextureLayersEnums::Filter;

  static TextureType::Pointer
  Combine(const LayerStackType * stack,
          unsigned int           numberOfLayers,
          double                 layerSpacing,
          double                 focus,
          SideType               stackSide,
          SideType               side,
          FilterType             filter,
          double                 gaussianSigma,
          double                 coreWidth);

  static TextureType::Pointer
  LayerWindow(const LayerStackType * stack, unsigned int first, unsigned int count);

  static double
  InkContrast(const TextureType * texture);

  static double
  StrokeContrast(const TextureType * texture, double strokeSigma, const TextureType * leaveOut = nullptr);

  static TextureType::Pointer
  ClearBackground(const TextureType * texture, bool inkIsBright = true);

  static double
  NoiseSpread(const TextureType * texture);

  static std::vector<double>
  Quantiles(const TextureType * texture, const std::vector<double> & q);

  static std::vector<double>
  DisplayWindow(const TextureType * texture, bool inkIsBright = true);

  static TextureType::Pointer
  EdgePreservingSmooth(const TextureType * texture, double domainSigma, double rangeSigma);

  static TextureType::Pointer
  Deconvolve(const TextureType * texture, double psfSigma, double regularization);

  static double
  ScanBlurSigma(double psfFWHM, double voxelSize);

  static LayerStackType::Pointer
  RegisterToSheet(const LayerStackType * stack, double sigma, TextureType::Pointer * shift = nullptr);

  static TextureType::Pointer
  Smooth(const TextureType * texture, double sigma);

  static TextureType::Pointer
  Median(const TextureType * texture, double radius);

  static TextureType::Pointer
  TrimBorder(const TextureType * texture, double width);
};
} // end namespace itk

#endif

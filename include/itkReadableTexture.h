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
#ifndef itkReadableTexture_h
#define itkReadableTexture_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkTextureLayers.h"

#include <vector>

namespace itk {
/** How a readable texture is chosen from a layer stack (ReadableTextureImageFilter's policy,
 * also callable on any stack): see SelectReadableTexture(). Lengths in physical units. */
struct ReadableTextureSettings
{
  /** The stack's sampling: layers, their spacing, the central layer's offset (focus), and
   * the side of the focus they lie on. */
  unsigned int             NumberOfLayers{ 1 };
  double                   LayerSpacing{ 1.0 };
  double                   Focus{ 0.0 };
  TextureLayersEnums::Side StackSide{ TextureLayersEnums::Side::Both };
  /** The stack was sampled on both sides to choose the side: both halves are candidates too
   * (the stack must be Both, with an odd number of layers). */
  bool                                AutomaticSide{ true };
  TextureLayersEnums::CoreSubtraction SubtractCore{ TextureLayersEnums::CoreSubtraction::Auto };
  TextureLayersEnums::Filter          Filter{ TextureLayersEnums::Filter::Max };
  double                              GaussianSigma{ 1.0 };
  /** The scan's smallest voxel side, and the Gaussian smoothing (in voxels) the
   * segmentation applied to a noisy scan (0: none, the scan was clean enough). */
  double Voxel{ 1.0 };
  double DenoisingSigma{ 0.0 };
  /** Median half-side and Gaussian sigma of the denoising; negative: automatic (half a
   * voxel, or the segmentation's smoothing width on a noisy scan). */
  double MedianRadius{ -1.0 };
  double SmoothSigma{ -1.0 };
  /** Restoration instead of the Gaussian: the full width at half maximum of the scanner's
   * PSF (0: the voxels' partial volume only); negative: no restoration. */
  double RestoreFWHM{ -1.0 };
};

/** One candidate texture and its score. A side candidate has Count 0; a focal slab is the
 * mean of layers First .. First + Count - 1. */
struct ReadableTextureCandidate
{
  TextureLayersEnums::Side Side{ TextureLayersEnums::Side::Both };
  bool                     SubtractCore{ false };
  double                   Score{ 0.0 };
  unsigned int             First{ 0 };
  unsigned int             Count{ 0 };
};

/** What SelectReadableTexture() chose, and how the per-vertex texture of the same choice
 * is sampled (LayeredTextureMeshFilter: layers, focus, side, filter). */
struct ReadableTextureSelection
{
  Image<float, 2>::Pointer              Texture;
  std::vector<ReadableTextureCandidate> Candidates;
  size_t                                Chosen{ 0 };
  /** Noisy scan with automatic side: the candidates are focal slabs scored by stroke contrast. */
  bool FocalSlabs{ false };
  /** Focal slabs: the pixels left out of their scores, where the sheet is off the
   * mid-surface (the middle layer holds air: a bulge the mesh does not follow; an
   * outermost layer holds material: another sheet touching this one) or near it. */
  size_t PixelsLeftOut{ 0 };
  /** Focal slabs: the stack is registered to the sheet first
   * (LayerStackTexture::RegisterToSheet); the median and 95th percentile of the shifts'
   * size (physical units): how far the mesh lies off the sheet. */
  double SheetShiftMedian{ 0.0 };
  double SheetShiftP95{ 0.0 };
  double MedianRadius{ 0.0 };
  double SmoothSigma{ 0.0 };
  double CoreWidth{ 0.0 };
  /** Restoration's PSF sigma, bilateral domain sigma, range factor and regularization (0
   * without restoration). */
  double PsfSigma{ 0.0 };
  double RestoreDomainSigma{ 0.0 };
  double RestoreRangeFactor{ 0.0 };
  double RestoreRegularization{ 0.0 };
  /** The chosen texture's depth: a focal slab's middle layer's offset, else the focus. */
  double                     Depth{ 0.0 };
  unsigned int               VertexLayers{ 1 };
  TextureLayersEnums::Side   VertexSide{ TextureLayersEnums::Side::Both };
  TextureLayersEnums::Filter VertexFilter{ TextureLayersEnums::Filter::Max };

  const ReadableTextureCandidate &
  ChosenCandidate() const
  {
    return Candidates[Chosen];
  }
};

/** Chooses the texture in which the writing reads best from a layer stack
 * (FlattenedTextureImageFilter's output 2):
 * - candidates: with AutomaticSide, the whole stack and each half (the Positive half: the
 *   focus layer and the layers along the normal; the Negative half), each half with and
 *   without the sheet's core (the layers within half a voxel of the focus) subtracted
 *   (SubtractCore Auto; Yes or No: one of them); else the stack's own side. Each candidate
 *   is combined with Filter (LayerStackTexture::Combine), then denoised: a median of
 *   MedianRadius, then a Gaussian of SmoothSigma, or with RestoreFWHM an edge-preserving
 *   smoothing over one voxel (range twice the background's spread) and a deconvolution of
 *   the scan's blur. The highest ink contrast (LayerStackTexture::InkContrast) wins.
 * - On a noisy scan (DenoisingSigma > 0) with AutomaticSide the candidates are focal slabs
 *   instead: the mean of 3 or 5 neighbouring layers at every depth, denoised the same way,
 *   scored by stroke contrast (letters' strokes, half a voxel wide): neither the maximum
 *   over noisy layers nor the plain ink contrast holds under noise.
 * Throws itk::ExceptionObject on a missing stack, a stack that does not hold
 * NumberOfLayers layers, AutomaticSide on a stack that is not Both with an odd number of
 * layers, or restoration together with a Gaussian (SmoothSigma > 0). */
VirtualUnwrapping_EXPORT ReadableTextureSelection
SelectReadableTexture(const Image<float, 3> * stack, const ReadableTextureSettings & settings);

/** The automatic number of layers: from the focus to half a voxel beyond the sheet's
 * faces (sheet thickness), on both sides or on one, `layerSpacing` apart. */
VirtualUnwrapping_EXPORT unsigned int
ReadableTextureLayers(double sheetThickness, double voxel, double layerSpacing, TextureLayersEnums::Side side);
} // end namespace itk

#endif

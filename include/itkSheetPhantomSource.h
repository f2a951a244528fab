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
#ifndef itkSheetPhantomSource_h
#define itkSheetPhantomSource_h

#include "VirtualUnwrappingExport.h"
#include "itkImageSource.h"
#include "itkSheetPhantomGeometry.h"

#include <string>
#include <vector>

namespace itk {
/** \class SheetPhantomSource
 * \brief Synthesises a CT scan (Hounsfield units) of a written sheet rolled into a scroll
 * or folded like an accordion, together with its ground truth (GetGeometry()).
 *
 * The sheet (air AirValue, material SheetValue) carries ink: either text rendered with
 * FreeType from Text in the font FontFile, or a user image (SetInkPattern). Ink adds
 * InkContrast to the material within InkDepth of the inked face (InkDepth >= thickness:
 * the ink soaks through). The scan is simulated in three steps:
 * 1. partial volume: the sheet is cut into sub-voxel cells (Supersampling per voxel along
 *    each axis, in sheet coordinates s, w and depth), and each cell's material, weighted by
 *    its exact volume (area element (1 - curvature * depth)), is splatted into the eight
 *    nearest voxels with trilinear weights;
 * 2. the scanner's point spread function: Gaussian of full width at half maximum BlurFWHM
 *    (itk::DiscreteGaussianImageFilter);
 * 3. noise: additive Gaussian noise of NoiseStandardDeviation HU, seeded by Seed
 *    (itk::AdditiveGaussianNoiseImageFilter), identical for identical parameters.
 * Papyrus-like fibres (FibreContrast > 0) modulate the material by smoothed, seeded noise
 * elongated along s on the inked half of the sheet and along w on the other half.
 *
 * The volume covers the sheet's bounding box plus Margin on every side; its voxels are
 * VoxelSize in x and y and SliceSpacing along z (the roll axis before tilting), direction
 * identity, origin on the grid of voxel multiples. The ground-truth ink image has pixels
 * of min(VoxelSize, SliceSpacing) / InkOversampling.
 *
 * Parameters (mm, HU or degrees; default = the "standard" preset; ranges checked, with a
 * one-line itk::ExceptionObject, by UpdateOutputInformation()):
 * - sheet and shape: see itk::SheetPhantomGeometry (Shape Rolled, SheetLength 49.53 from
 *   3 turns, SheetWidth 10, SheetThickness 0.25, InnerRadius 1.5, Pitch 0.75, Squash 1,
 *   WaveAmplitude 0, WavesPerTurn 0, FoldCount 4, FoldRadius 0.5, FoldOpeningAngle 10,
 *   TiltAngle 0);
 * - Text (three lines of capitals; '\n' separates lines, longer lines are word-wrapped),
 *   FontFile (DejaVuSans-Bold.ttf), GlyphHeight 1.6 > 0: height of capitals; text that
 *   does not fit inside margins of half a glyph height is refused;
 * - InkPattern (none): dark pixels are ink; fitted inside the sheet keeping its aspect;
 * - InkContrast 1200 (any sign), InkDepth 0.08 in (0, inf);
 * - AirValue -1000, SheetValue 400 (> AirValue), FibreContrast 0 >= 0 (standard
 *   deviation, HU), FibreLength 1.0 > 0;
 * - VoxelSize 0.1 > 0, SliceSpacing 0.1 > 0, Margin 0.5 >= 0, Supersampling 3 in 1..8,
 *   InkOversampling 4 in 1..16, BlurFWHM 0.12 >= 0, NoiseStandardDeviation 40 >= 0,
 *   Seed 1; volumes over 256 M voxels are refused.
 * Presets (ApplyPreset, GetPresetNames): standard, tight, squashed, folded,
 * canvas-medical, papyrus-microct; docs/phantoms.md describes them.
 *
 * Reference: W. B. Seales and Y. Lin, "Digital Restoration Using Volumetric Scanning",
 * JCDL 2004 (its canvas and papyrus experiments are the models of two presets).
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT SheetPhantomSource : public ImageSource<Image<float, 3>>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(SheetPhantomSource);

  using Self = SheetPhantomSource;
  using Superclass = ImageSource<Image<float, 3>>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using OutputImageType = Image<float, 3>;
  using InkImageType = SheetPhantomGeometry::InkImageType;
  using ShapeType = SheetPhantomGeometry::ShapeType;

  itkNewMacro(Self);
  itkTypeMacro(SheetPhantomSource, ImageSource);

  /** Sets every shape, ink, material and scan parameter to those of a named preset
   * (Seed, FontFile, Supersampling, InkOversampling and InkPattern are kept); throws on
   * an unknown name. */
  void
  ApplyPreset(const std::string & name);
  static std::vector<std::string>
  GetPresetNames();
  /** One-line description of a preset; throws on an unknown name. */
  static std::string
  GetPresetDescription(const std::string & name);
  /** Name of the last preset applied, or empty. */
  itkGetStringMacro(PresetName);

  itkSetMacro(Shape, ShapeType);
  itkGetConstMacro(Shape, ShapeType);
  itkSetMacro(SheetLength, double);
  itkGetConstMacro(SheetLength, double);
  itkSetMacro(SheetWidth, double);
  itkGetConstMacro(SheetWidth, double);
  itkSetMacro(SheetThickness, double);
  itkGetConstMacro(SheetThickness, double);
  itkSetMacro(InnerRadius, double);
  itkGetConstMacro(InnerRadius, double);
  itkSetMacro(Pitch, double);
  itkGetConstMacro(Pitch, double);
  itkSetMacro(Squash, double);
  itkGetConstMacro(Squash, double);
  itkSetMacro(WaveAmplitude, double);
  itkGetConstMacro(WaveAmplitude, double);
  itkSetMacro(WavesPerTurn, unsigned int);
  itkGetConstMacro(WavesPerTurn, unsigned int);
  itkSetMacro(FoldCount, unsigned int);
  itkGetConstMacro(FoldCount, unsigned int);
  itkSetMacro(FoldRadius, double);
  itkGetConstMacro(FoldRadius, double);
  itkSetMacro(FoldOpeningAngle, double);
  itkGetConstMacro(FoldOpeningAngle, double);
  itkSetMacro(TiltAngle, double);
  itkGetConstMacro(TiltAngle, double);
  /** Sets SheetLength so that a rolled sheet makes this many turns. */
  void
  SetNumberOfTurns(double turns);

  itkSetStringMacro(Text);
  itkGetStringMacro(Text);
  itkSetStringMacro(FontFile);
  itkGetStringMacro(FontFile);
  itkSetMacro(GlyphHeight, double);
  itkGetConstMacro(GlyphHeight, double);
  itkSetObjectMacro(InkPattern, InkImageType);
  itkGetConstObjectMacro(InkPattern, InkImageType);
  itkSetMacro(InkContrast, double);
  itkGetConstMacro(InkContrast, double);
  itkSetMacro(InkDepth, double);
  itkGetConstMacro(InkDepth, double);

  itkSetMacro(AirValue, double);
  itkGetConstMacro(AirValue, double);
  itkSetMacro(SheetValue, double);
  itkGetConstMacro(SheetValue, double);
  itkSetMacro(FibreContrast, double);
  itkGetConstMacro(FibreContrast, double);
  itkSetMacro(FibreLength, double);
  itkGetConstMacro(FibreLength, double);

  itkSetMacro(VoxelSize, double);
  itkGetConstMacro(VoxelSize, double);
  itkSetMacro(SliceSpacing, double);
  itkGetConstMacro(SliceSpacing, double);
  itkSetMacro(Margin, double);
  itkGetConstMacro(Margin, double);
  itkSetMacro(Supersampling, unsigned int);
  itkGetConstMacro(Supersampling, unsigned int);
  itkSetMacro(InkOversampling, unsigned int);
  itkGetConstMacro(InkOversampling, unsigned int);
  itkSetMacro(BlurFWHM, double);
  itkGetConstMacro(BlurFWHM, double);
  itkSetMacro(NoiseStandardDeviation, double);
  itkGetConstMacro(NoiseStandardDeviation, double);
  itkSetMacro(Seed, uint32_t);
  itkGetConstMacro(Seed, uint32_t);

  /** The ground truth, valid after UpdateOutputInformation() or Update(). */
  const SheetPhantomGeometry &
  GetGeometry() const
  {
    return m_Geometry;
  }
  /** The ground-truth ink image of the geometry (x along the sheet, y along its width,
   * 0..1 coverage, spacing in mm); valid after Update(). */
  const InkImageType *
  GetInkImage() const
  {
    return m_Geometry.GetInkImage();
  }

protected:
  SheetPhantomSource() = default;
  ~SheetPhantomSource() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;
  void
  GenerateOutputInformation() override;
  void
  GenerateData() override;
  void
  EnlargeOutputRequestedRegion(DataObject * output) override;

private:
  void
  CheckParameters() const;
  InkImageType::Pointer
  MakeInkImage(std::string & renderedText) const;
  InkImageType::Pointer
  MakeFibreTexture(bool alongSheet, uint32_t seed) const;
  void
  Splat(OutputImageType * volume);

  std::string  m_PresetName{ "standard" };
  ShapeType    m_Shape{ ShapeType::Rolled };
  double       m_SheetLength{ SheetPhantomGeometry::RolledLengthForTurns(SheetPhantomGeometry::Parameters{}, 3.0) };
  double       m_SheetWidth{ 10.0 };
  double       m_SheetThickness{ 0.25 };
  double       m_InnerRadius{ 1.5 };
  double       m_Pitch{ 0.75 };
  double       m_Squash{ 1.0 };
  double       m_WaveAmplitude{ 0.0 };
  unsigned int m_WavesPerTurn{ 0 };
  unsigned int m_FoldCount{ 4 };
  double       m_FoldRadius{ 0.5 };
  double       m_FoldOpeningAngle{ 10.0 };
  double       m_TiltAngle{ 0.0 };

  std::string           m_Text{ "DIGITAL RESTORATION USING\nVOLUMETRIC SCANNING\nSEALES AND LIN 2004" };
  std::string           m_FontFile{ "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf" };
  double                m_GlyphHeight{ 1.6 };
  InkImageType::Pointer m_InkPattern;
  double                m_InkContrast{ 1200.0 };
  double                m_InkDepth{ 0.08 };

  double m_AirValue{ -1000.0 };
  double m_SheetValue{ 400.0 };
  double m_FibreContrast{ 0.0 };
  double m_FibreLength{ 1.0 };

  double       m_VoxelSize{ 0.1 };
  double       m_SliceSpacing{ 0.1 };
  double       m_Margin{ 0.5 };
  unsigned int m_Supersampling{ 3 };
  unsigned int m_InkOversampling{ 4 };
  double       m_BlurFWHM{ 0.12 };
  double       m_NoiseStandardDeviation{ 40.0 };
  uint32_t     m_Seed{ 1 };

  SheetPhantomGeometry m_Geometry;
};
} // end namespace itk

#endif

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
#ifndef itkTextLegibility_h
#define itkTextLegibility_h

#include "VirtualUnwrappingExport.h"
#include "itkImage.h"
#include "itkObject.h"
#include "itkObjectFactory.h"

#include <string>

namespace itk {
/** \class TextLegibility
 * \brief Legibility of a flat image of text: what tesseract OCR reads in it and the
 * character error rate (CER) against the known text.
 *
 * Compute() shows the image as texture.png does: the background's noise cleared
 * (LayerStackTexture::ClearBackground()) and windowed (LayerStackTexture::DisplayWindow()
 * of its finite pixels: the background's median and speckle below the ink's side of the
 * window, the 0.5th or 99.5th percentile at the other; non-finite pixels, e.g. NaN off an
 * unwrapped sheet, take the median of the finite ones, the background where ink covers a
 * minority), inverts it when
 * InkIsBright (CT ink is denser, hence brighter, than the sheet) so that the text is dark
 * on white, enlarges it by UpscaleFactor (linear interpolation; less when the enlarged
 * image would exceed tesseract's largest side, 32767 pixels with the border: a long roll's
 * texture is scaled to fit, GetAppliedScale()), pads a white border of
 * 16 pixels, writes a temporary 8-bit PNG and runs
 * `tesseract PNG stdout --psm PageSegmentationMode -l Language`.
 * Pixel spacing is ignored: image column = x to the right, row = y downwards.
 *
 * CER = Levenshtein distance (insertions, deletions, substitutions of Unicode code
 * points) between the normalised recognised text and the normalised truth, divided by
 * the number of code points of the normalised truth. Normalisation: every run of
 * whitespace (space, tab, newline, carriage return, form feed, vertical tab) becomes a
 * single space and leading and trailing whitespace is removed; case and punctuation are
 * kept. The CER can exceed 1 when the OCR invents text.
 *
 * Parameters: InkIsBright (true), UpscaleFactor (2, range [0.25, 8]),
 * PageSegmentationMode (6: a single uniform block of text; 0..13), Language ("eng"),
 * TesseractExecutable ("tesseract", looked up on PATH unless it contains a '/'),
 * TruthText ("": when empty Compute() only recognises).
 * Compute() throws itk::ExceptionObject when there is no image or no finite pixel, when tesseract is not
 * installed (naming the Debian packages to install) or when it fails.
 *
 * Reference: R. Smith, "An overview of the Tesseract OCR engine", ICDAR 2007.
 *
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT TextLegibility : public Object
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(TextLegibility);

  using Self = TextLegibility;
  using Superclass = Object;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;
  using ImageType = Image<float, 2>;

  itkNewMacro(Self);
  itkTypeMacro(TextLegibility, Object);

  itkSetConstObjectMacro(Image, ImageType);
  itkGetConstObjectMacro(Image, ImageType);
  itkSetStringMacro(TruthText);
  itkGetStringMacro(TruthText);
  itkSetMacro(InkIsBright, bool);
  itkGetConstMacro(InkIsBright, bool);
  itkBooleanMacro(InkIsBright);
  itkSetClampMacro(UpscaleFactor, double, 0.25, 8.0);
  itkGetConstMacro(UpscaleFactor, double);
  itkSetClampMacro(PageSegmentationMode, int, 0, 13);
  itkGetConstMacro(PageSegmentationMode, int);
  itkSetStringMacro(Language);
  itkGetStringMacro(Language);
  itkSetStringMacro(TesseractExecutable);
  itkGetStringMacro(TesseractExecutable);

  /** Runs OCR on the image and, when TruthText is set, measures the CER. */
  void
  Compute();

  /** Raw tesseract output of the last Compute(). */
  itkGetStringMacro(RecognizedText);
  /** CER of the last Compute() (0 when no truth was given). */
  itkGetConstMacro(CharacterErrorRate, double);
  itkGetConstMacro(EditDistance, SizeValueType);
  /** The scale of the image tesseract read in the last Compute(): UpscaleFactor, or less
   * for an image too long for tesseract. */
  itkGetConstMacro(AppliedScale, double);

  /** The longest side, in pixels, of an image tesseract reads. */
  static constexpr SizeValueType TesseractLargestSide = 32767;

  /** True when the tesseract executable can be found. */
  bool
  IsTesseractAvailable() const;

  /** Whitespace normalisation used by the CER (see class description). */
  static std::string
  NormalizeText(const std::string & text);
  /** Levenshtein distance between two UTF-8 strings, counted in code points. */
  static SizeValueType
  ComputeEditDistance(const std::string & a, const std::string & b);
  /** CER of recognised against truth after normalisation; throws when the normalised
   * truth is empty. */
  static double
  ComputeCharacterErrorRate(const std::string & recognized, const std::string & truth);

protected:
  TextLegibility() = default;
  ~TextLegibility() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  std::string
  FindTesseract() const;

  ImageType::ConstPointer m_Image;
  std::string             m_TruthText;
  bool                    m_InkIsBright{ true };
  double                  m_UpscaleFactor{ 2.0 };
  double                  m_AppliedScale{ 0.0 };
  int                     m_PageSegmentationMode{ 6 };
  std::string             m_Language{ "eng" };
  std::string             m_TesseractExecutable{ "tesseract" };

  std::string   m_RecognizedText;
  double        m_CharacterErrorRate{ 0.0 };
  SizeValueType m_EditDistance{ 0 };
};
} // end namespace itk

#endif

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
#include "itkSheetPhantomSource.h"
#include "itkTextLegibility.h"
#include "vuExpectRefusal.h"
#include "vuTestHelpers.h"

#include "gtest/gtest.h"

#include <limits>

namespace {
using Legibility = itk::TextLegibility;

using InkType = itk::SheetPhantomGeometry::InkImageType;

// The sentence the reading tests render and read.
const std::string Sentence = "THE QUICK BROWN FOX";

// Ink image of a short sentence rendered by the phantom source (no volume is made).
const InkType *
RenderInk(itk::SheetPhantomSource * source, const std::string & text)
{
  source->SetText(text);
  source->UpdateOutputInformation();
  return source->GetGeometry().GetInkImage();
}

// The ink image of Sentence, and its size.
struct SentenceInk
{
  itk::SheetPhantomSource::Pointer Source = itk::SheetPhantomSource::New();
  const InkType *                  Image = RenderInk(Source, Sentence);
  const InkType::SizeType          Size = Image->GetLargestPossibleRegion().GetSize();
};

// Reads image with the truth text `text` and expects tesseract to read that text.
void
ExpectReadBack(Legibility * legibility, const InkType * image, const std::string & text)
{
  legibility->SetImage(image);
  legibility->SetTruthText(text);
  legibility->Compute();
  EXPECT_EQ(Legibility::NormalizeText(legibility->GetRecognizedText()), text);
}

// The ink image placed at `offset` on an image of `size` filled with `fill`.
InkType::Pointer
Placed(const InkType * ink, const InkType::SizeType & size, const long offset[2], float fill)
{
  const auto inner = ink->GetLargestPossibleRegion().GetSize();
  auto       placed = InkType::New();
  placed->SetRegions(size);
  placed->Allocate();
  placed->FillBuffer(fill);
  for (long y = 0; y < static_cast<long>(inner[1]); ++y)
  {
    for (long x = 0; x < static_cast<long>(inner[0]); ++x)
    {
      placed->SetPixel({ { x + offset[0], y + offset[1] } }, ink->GetPixel({ { x, y } }));
    }
  }
  return placed;
}
} // namespace

TEST(TextLegibility, BasicObjectMethods)
{
  auto legibility = Legibility::New();
  VU_EXPECT_ITK_MACROS(ITK_EXERCISE_BASIC_OBJECT_METHODS(legibility, TextLegibility, Object));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_BOOLEAN(legibility, InkIsBright, false));
  VU_EXPECT_ITK_MACROS(ITK_TEST_SET_GET_VALUE(2.0, legibility->GetUpscaleFactor()); legibility->SetUpscaleFactor(3.0);
                       ITK_TEST_SET_GET_VALUE(3.0, legibility->GetUpscaleFactor()));
  legibility->SetUpscaleFactor(100.0);
  EXPECT_EQ(legibility->GetUpscaleFactor(), 8.0);
  legibility->SetPageSegmentationMode(4);
  EXPECT_EQ(legibility->GetPageSegmentationMode(), 4);
}

TEST(TextLegibility, NormalizesWhitespace)
{
  EXPECT_EQ(Legibility::NormalizeText("  THE\tQUICK \n\n BROWN\r\nFOX \f"), "THE QUICK BROWN FOX");
  EXPECT_EQ(Legibility::NormalizeText("\n \t"), "");
  EXPECT_EQ(Legibility::NormalizeText("Case, kept."), "Case, kept.");
}

TEST(TextLegibility, EditDistanceOfKnownPairs)
{
  EXPECT_EQ(Legibility::ComputeEditDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(Legibility::ComputeEditDistance("", "abc"), 3u);
  EXPECT_EQ(Legibility::ComputeEditDistance("abc", ""), 3u);
  EXPECT_EQ(Legibility::ComputeEditDistance("flaw", "lawn"), 2u);
  EXPECT_EQ(Legibility::ComputeEditDistance("same", "same"), 0u);
  // Code points, not bytes: one substitution of a two-byte character.
  EXPECT_EQ(Legibility::ComputeEditDistance("caf\xC3\xA9", "cafe"), 1u);
  EXPECT_THROW(Legibility::ComputeEditDistance("\xC3", "a"), itk::ExceptionObject);
}

TEST(TextLegibility, CharacterErrorRateOfKnownCases)
{
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("HELLO WORLD", "HELLO WORLD"), 0.0);
  // Line breaks and repeated spaces are not errors.
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("HELLO\n  WORLD\n\f", "HELLO WORLD"), 0.0);
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("HELL0 WORLD", "HELLO WORLD"), 1.0 / 11.0);
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("HELLO", "HELLO WORLD"), 6.0 / 11.0);
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("", "ABCD"), 1.0);
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("ABCD EFGH", "AB"), 3.5);
  EXPECT_DOUBLE_EQ(Legibility::ComputeCharacterErrorRate("hello world", "HELLO WORLD"), 10.0 / 11.0);
  EXPECT_THROW(Legibility::ComputeCharacterErrorRate("ABC", " \n "), itk::ExceptionObject);
}

TEST(TextLegibility, ReadsRenderedText)
{
  auto legibility = Legibility::New();
  if (!legibility->IsTesseractAvailable())
  {
    GTEST_SKIP() << "tesseract is not installed";
  }
  const SentenceInk sentence;
  ExpectReadBack(legibility, sentence.Image, Sentence);
  EXPECT_EQ(legibility->GetCharacterErrorRate(), 0.0);

  // Dark ink on a bright sheet reads the same with InkIsBright off.
  const InkType * ink = sentence.Image;
  auto            dark = InkType::New();
  dark->CopyInformation(ink);
  dark->SetRegions(ink->GetLargestPossibleRegion());
  dark->Allocate();
  for (size_t i = 0; i < dark->GetLargestPossibleRegion().GetNumberOfPixels(); ++i)
  {
    dark->GetBufferPointer()[i] = 1.0f - ink->GetBufferPointer()[i];
  }
  legibility->InkIsBrightOff();
  ExpectReadBack(legibility, dark, Sentence);
}

// An unwrapped texture is NaN off the sheet: those pixels are background, not ink, and
// do not shift the window; an image without a finite pixel cannot be read.
TEST(TextLegibility, NaNPixelsAreBackground)
{
  auto legibility = Legibility::New();
  if (!legibility->IsTesseractAvailable())
  {
    GTEST_SKIP() << "tesseract is not installed";
  }
  const SentenceInk ink;
  const long        frame[2] = { 40, 40 };
  InkType::SizeType size = { { ink.Size[0] + 2 * frame[0], ink.Size[1] + 2 * frame[1] } };
  auto              framed = Placed(ink.Image, size, frame, std::numeric_limits<float>::quiet_NaN());
  ExpectReadBack(legibility, framed, Sentence);
  EXPECT_EQ(legibility->GetCharacterErrorRate(), 0.0);

  framed->FillBuffer(std::numeric_limits<float>::quiet_NaN());
  EXPECT_THROW(legibility->Compute(), itk::ExceptionObject);
}

// A long roll's texture is tens of thousands of pixels long, longer than tesseract reads
// once enlarged: it is enlarged less, to fit, and still read.
TEST(TextLegibility, ImageTooLongForTesseractIsScaledToFit)
{
  auto legibility = Legibility::New();
  if (!legibility->IsTesseractAvailable())
  {
    GTEST_SKIP() << "tesseract is not installed";
  }
  const SentenceInk ink;
  const long        length = 20000;
  ASSERT_LT(static_cast<long>(ink.Size[0]), length);
  InkType::SizeType size = { { static_cast<itk::SizeValueType>(length), ink.Size[1] } };
  const long        middle[2] = { length / 2, 0 };
  ExpectReadBack(legibility, Placed(ink.Image, size, middle, 0.0f), Sentence);
  EXPECT_NEAR(legibility->GetAppliedScale(),
              static_cast<double>(Legibility::TesseractLargestSide - 32) / static_cast<double>(length),
              1e-9);

  // An image that fits keeps the upscale factor.
  legibility->SetImage(ink.Image);
  legibility->Compute();
  EXPECT_EQ(legibility->GetAppliedScale(), legibility->GetUpscaleFactor());
}

TEST(TextLegibility, ReportsMissingTesseractAndMissingImage)
{
  auto legibility = Legibility::New();
  EXPECT_THROW(legibility->Compute(), itk::ExceptionObject);
  auto source = itk::SheetPhantomSource::New();
  legibility->SetImage(RenderInk(source, "ABC"));
  legibility->SetTesseractExecutable("/nonexistent/tesseract");
  EXPECT_FALSE(legibility->IsTesseractAvailable());
  vu::ExpectRefusal([&] { legibility->Compute(); }, "tesseract-ocr", "a missing tesseract was not reported");
  legibility->SetTesseractExecutable("vu-no-such-tesseract-program");
  EXPECT_THROW(legibility->Compute(), itk::ExceptionObject);
}

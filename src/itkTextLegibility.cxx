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
#include "itkTextLegibility.h"
#include "itkLayerStackTexture.h"

#include "itkConstantPadImageFilter.h"
#include "itkIdentityTransform.h"
#include "itkImageFileWriter.h"
#include "itkIntensityWindowingImageFilter.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkPNGImageIO.h"
#include "itkResampleImageFilter.h"
#include "vuUtf8.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <unistd.h>

namespace itk {
namespace {
bool
IsWhitespace(char c)
{
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

std::string
ShellQuote(const std::string & text)
{
  std::string quoted = "'";
  for (char c : text)
  {
    quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  }
  return quoted + "'";
}

// Removes the temporary PNG however Compute() leaves.
struct TemporaryFile
{
  std::string Path;
  ~TemporaryFile()
  {
    if (!Path.empty())
    {
      std::remove(Path.c_str());
    }
  }
};
} // namespace

std::string
TextLegibility::NormalizeText(const std::string & text)
{
  std::string normalized;
  bool        pendingSpace = false;
  for (char c : text)
  {
    if (IsWhitespace(c))
    {
      pendingSpace = !normalized.empty();
      continue;
    }
    if (pendingSpace)
    {
      normalized += ' ';
      pendingSpace = false;
    }
    normalized += c;
  }
  return normalized;
}

SizeValueType
TextLegibility::ComputeEditDistance(const std::string & a, const std::string & b)
{
  const std::vector<uint32_t> x = vu::DecodeUtf8(a, "TextLegibility: text");
  const std::vector<uint32_t> y = vu::DecodeUtf8(b, "TextLegibility: text");
  std::vector<SizeValueType>  previous(y.size() + 1), current(y.size() + 1);
  for (size_t j = 0; j <= y.size(); ++j)
  {
    previous[j] = j;
  }
  for (size_t i = 1; i <= x.size(); ++i)
  {
    current[0] = i;
    for (size_t j = 1; j <= y.size(); ++j)
    {
      current[j] = std::min({ previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (x[i - 1] == y[j - 1] ? 0 : 1) });
    }
    std::swap(previous, current);
  }
  return previous[y.size()];
}

double
TextLegibility::ComputeCharacterErrorRate(const std::string & recognized, const std::string & truth)
{
  const std::string normalizedTruth = NormalizeText(truth);
  const size_t      length = vu::DecodeUtf8(normalizedTruth, "TextLegibility: truth text").size();
  if (length == 0)
  {
    itkGenericExceptionMacro(<< "TextLegibility: the truth text is empty, the character error rate is undefined");
  }
  return static_cast<double>(ComputeEditDistance(NormalizeText(recognized), normalizedTruth)) / length;
}

std::string
TextLegibility::FindTesseract() const
{
  namespace fs = std::filesystem;
  const auto executable = [](const fs::path & path) {
    std::error_code error;
    return fs::is_regular_file(path, error) && access(path.c_str(), X_OK) == 0;
  };
  if (m_TesseractExecutable.find('/') != std::string::npos)
  {
    return executable(m_TesseractExecutable) ? m_TesseractExecutable : std::string();
  }
  const char *       path = std::getenv("PATH");
  std::istringstream directories(path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string        directory;
  while (std::getline(directories, directory, ':'))
  {
    const fs::path candidate = fs::path(directory.empty() ? "." : directory) / m_TesseractExecutable;
    if (executable(candidate))
    {
      return candidate.string();
    }
  }
  return std::string();
}

bool
TextLegibility::IsTesseractAvailable() const
{
  return !FindTesseract().empty();
}

void
TextLegibility::Compute()
{
  if (!m_Image)
  {
    itkExceptionMacro(<< "no image to read");
  }
  const std::string tesseract = FindTesseract();
  if (tesseract.empty())
  {
    itkExceptionMacro(<< "tesseract OCR not found (\"" << m_TesseractExecutable
                      << "\"): install the Debian packages tesseract-ocr and tesseract-ocr-eng");
  }
  const auto region = m_Image->GetBufferedRegion();
  if (region.GetNumberOfPixels() == 0)
  {
    itkExceptionMacro(<< "the image is empty");
  }

  // A robust window keeps a few bright outliers (noise, metal) from washing out the text.
  // Non-finite pixels (NaN off an unwrapped sheet) take no part in it and take the median
  // of the finite ones: the sheet's background, ink covering a minority of it, so that the
  // sheet's outline does not read as a stroke.
  // What texture.png shows: the background's noise cleared, in the window of the image.
  const auto                cleared = LayerStackTexture::ClearBackground(m_Image, m_InkIsBright);
  const float *             buffer = cleared->GetBufferPointer();
  const std::vector<double> median = LayerStackTexture::Quantiles(m_Image, { 0.5 });
  if (median.empty())
  {
    itkExceptionMacro(<< "the image has no finite pixel");
  }
  const auto background = static_cast<float>(median.front());
  // The window of the image a person looks at (texture.png): the background dark, its
  // speckle below the black point, which tesseract would otherwise read as letters.
  const std::vector<double> shown = LayerStackTexture::DisplayWindow(m_Image, m_InkIsBright);
  const auto                low = static_cast<float>(shown[0]);
  const float               high = std::max(static_cast<float>(shown[1]), low + 1e-6f);
  auto                      finite = ImageType::New();
  finite->CopyInformation(m_Image);
  finite->SetRegions(region);
  finite->Allocate();
  std::transform(buffer, buffer + region.GetNumberOfPixels(), finite->GetBufferPointer(), [background](float v) {
    return std::isfinite(v) ? v : background;
  });

  using OutputImageType = Image<unsigned char, 2>;
  using WindowType = IntensityWindowingImageFilter<ImageType, ImageType>;
  auto window = WindowType::New();
  window->SetInput(finite);
  window->SetWindowMinimum(low);
  window->SetWindowMaximum(high);
  window->SetOutputMinimum(m_InkIsBright ? 255.0f : 0.0f);
  window->SetOutputMaximum(m_InkIsBright ? 0.0f : 255.0f);

  // Resample on the pixel grid (spacing and origin do not matter to OCR), within the
  // largest image tesseract reads.
  constexpr SizeValueType border = 16;
  const auto              size = region.GetSize();
  const double            longest = static_cast<double>(std::max(size[0], size[1]));
  m_AppliedScale = std::min(m_UpscaleFactor, static_cast<double>(TesseractLargestSide - 2 * border) / longest);
  ImageType::SizeType        upSize;
  ImageType::SpacingType     upSpacing;
  ImageType::PointType       upOrigin;
  const ImageType::PointType inputOrigin = m_Image->GetOrigin();
  for (unsigned d = 0; d < 2; ++d)
  {
    upSize[d] = std::clamp<SizeValueType>(
      static_cast<SizeValueType>(std::floor(size[d] * m_AppliedScale + 0.5)), 1, TesseractLargestSide - 2 * border);
    upSpacing[d] = m_Image->GetSpacing()[d] * size[d] / upSize[d];
    upOrigin[d] = inputOrigin[d] - 0.5 * m_Image->GetSpacing()[d] + 0.5 * upSpacing[d];
  }
  auto resample = ResampleImageFilter<ImageType, OutputImageType>::New();
  resample->SetInput(window->GetOutput());
  resample->SetSize(upSize);
  resample->SetOutputSpacing(upSpacing);
  resample->SetOutputOrigin(upOrigin);
  resample->SetOutputDirection(m_Image->GetDirection());
  resample->SetDefaultPixelValue(255);
  auto pad = ConstantPadImageFilter<OutputImageType, OutputImageType>::New();
  pad->SetInput(resample->GetOutput());
  OutputImageType::SizeType padding;
  padding.Fill(border);
  pad->SetPadLowerBound(padding);
  pad->SetPadUpperBound(padding);
  pad->SetConstant(255);

  TemporaryFile png;
  {
    std::string pattern = (std::filesystem::temp_directory_path() / "vu-ocr-XXXXXX.png").string();
    const int   descriptor = mkstemps(pattern.data(), 4);
    if (descriptor < 0)
    {
      itkExceptionMacro(<< "cannot create a temporary file in " << std::filesystem::temp_directory_path());
    }
    close(descriptor);
    png.Path = pattern;
  }
  auto writer = ImageFileWriter<OutputImageType>::New();
  writer->SetInput(pad->GetOutput());
  writer->SetImageIO(PNGImageIO::New());
  writer->SetFileName(png.Path);
  writer->Update();

  const std::string command = ShellQuote(tesseract) + " " + ShellQuote(png.Path) + " stdout --psm " +
                              std::to_string(m_PageSegmentationMode) + " -l " + ShellQuote(m_Language) + " 2>/dev/null";
  FILE * pipe = popen(command.c_str(), "r");
  if (pipe == nullptr)
  {
    itkExceptionMacro(<< "cannot run " << tesseract);
  }
  std::string text;
  char        chunk[4096];
  size_t      read;
  while ((read = fread(chunk, 1, sizeof(chunk), pipe)) > 0)
  {
    text.append(chunk, read);
  }
  const int status = pclose(pipe);
  if (status != 0)
  {
    itkExceptionMacro(<< "tesseract failed (exit status " << status << ") on " << png.Path << " with language \""
                      << m_Language << "\"");
  }
  m_RecognizedText = text;
  m_EditDistance = 0;
  m_CharacterErrorRate = 0.0;
  if (!NormalizeText(m_TruthText).empty())
  {
    m_EditDistance = ComputeEditDistance(NormalizeText(m_RecognizedText), NormalizeText(m_TruthText));
    m_CharacterErrorRate = ComputeCharacterErrorRate(m_RecognizedText, m_TruthText);
  }
}

void
TextLegibility::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "Image: " << m_Image.GetPointer() << std::endl;
  os << indent << "TruthText: " << m_TruthText << std::endl;
  os << indent << "InkIsBright: " << m_InkIsBright << std::endl;
  os << indent << "UpscaleFactor: " << m_UpscaleFactor << std::endl;
  os << indent << "AppliedScale: " << m_AppliedScale << std::endl;
  os << indent << "PageSegmentationMode: " << m_PageSegmentationMode << std::endl;
  os << indent << "Language: " << m_Language << std::endl;
  os << indent << "TesseractExecutable: " << m_TesseractExecutable << std::endl;
  os << indent << "RecognizedText: " << m_RecognizedText << std::endl;
  os << indent << "CharacterErrorRate: " << m_CharacterErrorRate << std::endl;
  os << indent << "EditDistance: " << m_EditDistance << std::endl;
}
} // end namespace itk

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

#include "itkAdditiveGaussianNoiseImageFilter.h"
#include "itkChangeInformationImageFilter.h"
#include "itkDiscreteGaussianImageFilter.h"
#include "itkInvertIntensityImageFilter.h"
#include "itkLinearInterpolateImageFunction.h"
#include "itkMultiThreaderBase.h"
#include "itkResampleImageFilter.h"
#include "itkRescaleIntensityImageFilter.h"
#include "itkShiftScaleImageFilter.h"
#include "itkSmoothingRecursiveGaussianImageFilter.h"
#include "itkStatisticsImageFilter.h"
#include "vuFontFace.h"
#include "vuUtf8.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace itk {
namespace {
using InkImageType = SheetPhantomSource::InkImageType;
using ShapeType = SheetPhantomSource::ShapeType;

struct Preset
{
  const char * Name;
  const char * Description;
  ShapeType    Shape;
  double       TurnsOrLength; // turns when rolled, length (mm) when folded
  double       Width, Thickness, InnerRadius, Pitch, Squash, WaveAmplitude;
  unsigned     WavesPerTurn, FoldCount;
  double       FoldRadius, FoldOpeningAngle, TiltAngle;
  const char * Text;
  double       GlyphHeight, InkContrast, InkDepth, AirValue, SheetValue, FibreContrast, FibreLength;
  double       VoxelSize, SliceSpacing, Margin, BlurFWHM, NoiseStandardDeviation;
};

constexpr const char * StandardText = "DIGITAL RESTORATION USING\nVOLUMETRIC SCANNING\nSEALES AND LIN 2004";

// clang-format off
const Preset Presets[] = {
  { "standard", "3-turn scroll, 0.1 mm voxels: sheet 2.5 voxels thick, 5-voxel gaps, three lines of 16-voxel capitals",
    ShapeType::Rolled, 3.0, 10.0, 0.25, 1.5, 0.75, 1.0, 0.0, 0, 4, 0.5, 10.0, 0.0,
    StandardText, 1.6, 1200.0, 0.08, -1000.0, 400.0, 0.0, 1.0,
    0.1, 0.1, 0.5, 0.12, 40.0 },
  { "tight", "4-turn scroll with turns 1.5 voxels apart (0.1 mm voxels), the standard text",
    ShapeType::Rolled, 4.0, 10.0, 0.25, 1.5, 0.4, 1.0, 0.0, 0, 4, 0.5, 10.0, 0.0,
    StandardText, 1.6, 1200.0, 0.08, -1000.0, 400.0, 0.0, 1.0,
    0.1, 0.1, 0.5, 0.12, 40.0 },
  { "squashed", "3-turn scroll flattened to an elliptic cross-section (axes ratio 0.55), 0.1 mm voxels",
    ShapeType::Rolled, 3.0, 10.0, 0.25, 2.0, 1.0, 0.55, 0.0, 0, 4, 0.5, 10.0, 0.0,
    StandardText, 1.6, 1200.0, 0.08, -1000.0, 400.0, 0.0, 1.0,
    0.1, 0.1, 0.5, 0.12, 40.0 },
  { "folded", "accordion (Z) fold, 4 rounded creases, panels opening by 8 degrees, 0.1 mm voxels",
    ShapeType::Folded, 42.0, 10.0, 0.25, 1.5, 0.75, 1.0, 0.0, 0, 4, 0.4, 8.0, 0.0,
    StandardText, 1.6, 1200.0, 0.08, -1000.0, 400.0, 0.0, 1.0,
    0.1, 0.1, 0.5, 0.12, 40.0 },
  { "canvas-medical", "painted canvas rolled 2.5 turns in a medical CT: 1 mm pixels, 1.5 mm slices, 20 mm letters",
    ShapeType::Rolled, 2.5, 100.0, 1.5, 20.0, 5.0, 1.0, 0.0, 0, 4, 0.5, 10.0, 0.0,
    "PAINTED CANVAS\nMEDICAL CT", 20.0, 2500.0, 0.5, -1000.0, 200.0, 0.0, 1.0,
    1.0, 1.5, 3.0, 1.5, 25.0 },
  { "papyrus-microct", "papyrus replica rolled 3 turns in a micro-CT: 30 um voxels, sheet 6.7 voxels thick, fibres",
    ShapeType::Rolled, 3.0, 3.0, 0.2, 0.8, 0.35, 1.0, 0.0, 0, 4, 0.5, 10.0, 0.0,
    "PAPYRUS REPLICA\nMICRO CT 2004", 0.6, 1000.0, 0.03, -1000.0, 250.0, 60.0, 1.0,
    0.03, 0.03, 0.3, 0.04, 60.0 },
};
// clang-format on

const Preset &
FindPreset(const std::string & name)
{
  for (const Preset & preset : Presets)
  {
    if (name == preset.Name)
    {
      return preset;
    }
  }
  std::ostringstream names;
  for (const Preset & preset : Presets)
  {
    names << (&preset == Presets ? "" : ", ") << preset.Name;
  }
  itkGenericExceptionMacro(<< "SheetPhantomSource: unknown preset \"" << name << "\" (known: " << names.str() << ")");
}

} // namespace

std::vector<std::string>
SheetPhantomSource::GetPresetNames()
{
  std::vector<std::string> names;
  for (const Preset & preset : Presets)
  {
    names.emplace_back(preset.Name);
  }
  return names;
}

std::string
SheetPhantomSource::GetPresetDescription(const std::string & name)
{
  return FindPreset(name).Description;
}

void
SheetPhantomSource::ApplyPreset(const std::string & name)
{
  const Preset & p = FindPreset(name);
  m_PresetName = p.Name;
  m_Shape = p.Shape;
  m_SheetWidth = p.Width;
  m_SheetThickness = p.Thickness;
  m_InnerRadius = p.InnerRadius;
  m_Pitch = p.Pitch;
  m_Squash = p.Squash;
  m_WaveAmplitude = p.WaveAmplitude;
  m_WavesPerTurn = p.WavesPerTurn;
  m_FoldCount = p.FoldCount;
  m_FoldRadius = p.FoldRadius;
  m_FoldOpeningAngle = p.FoldOpeningAngle;
  m_TiltAngle = p.TiltAngle;
  if (p.Shape == ShapeType::Rolled)
  {
    SetNumberOfTurns(p.TurnsOrLength);
  }
  else
  {
    m_SheetLength = p.TurnsOrLength;
  }
  m_Text = p.Text;
  m_GlyphHeight = p.GlyphHeight;
  m_InkContrast = p.InkContrast;
  m_InkDepth = p.InkDepth;
  m_AirValue = p.AirValue;
  m_SheetValue = p.SheetValue;
  m_FibreContrast = p.FibreContrast;
  m_FibreLength = p.FibreLength;
  m_VoxelSize = p.VoxelSize;
  m_SliceSpacing = p.SliceSpacing;
  m_Margin = p.Margin;
  m_BlurFWHM = p.BlurFWHM;
  m_NoiseStandardDeviation = p.NoiseStandardDeviation;
  this->Modified();
}

void
SheetPhantomSource::SetNumberOfTurns(double turns)
{
  SheetPhantomGeometry::Parameters p;
  p.InnerRadius = m_InnerRadius;
  p.Pitch = m_Pitch;
  p.Squash = m_Squash;
  p.WaveAmplitude = m_WaveAmplitude;
  p.WavesPerTurn = m_WavesPerTurn;
  this->SetSheetLength(SheetPhantomGeometry::RolledLengthForTurns(p, turns));
}

void
SheetPhantomSource::CheckParameters() const
{
  auto positive = [](double value, const char * name) {
    if (!(value > 0.0) || !std::isfinite(value))
    {
      itkGenericExceptionMacro(<< "SheetPhantomSource: " << name << " must be positive and finite, got " << value);
    }
  };
  auto nonNegative = [](double value, const char * name) {
    if (!(value >= 0.0) || !std::isfinite(value))
    {
      itkGenericExceptionMacro(<< "SheetPhantomSource: " << name << " must be zero or positive, got " << value);
    }
  };
  positive(m_VoxelSize, "voxel size");
  positive(m_SliceSpacing, "slice spacing");
  positive(m_GlyphHeight, "glyph height");
  positive(m_InkDepth, "ink depth");
  positive(m_FibreLength, "fibre length");
  nonNegative(m_Margin, "margin");
  nonNegative(m_BlurFWHM, "blur FWHM");
  nonNegative(m_NoiseStandardDeviation, "noise standard deviation");
  nonNegative(m_FibreContrast, "fibre contrast");
  if (!std::isfinite(m_AirValue) || !std::isfinite(m_SheetValue) || !std::isfinite(m_InkContrast))
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: air, sheet and ink values must be finite");
  }
  if (!(m_SheetValue > m_AirValue))
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: sheet value " << m_SheetValue << " HU must exceed the air value "
                             << m_AirValue << " HU");
  }
  if (m_Supersampling < 1 || m_Supersampling > 8)
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: supersampling must lie in 1..8, got " << m_Supersampling);
  }
  if (m_InkOversampling < 1 || m_InkOversampling > 16)
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: ink oversampling must lie in 1..16, got " << m_InkOversampling);
  }
}

SheetPhantomSource::InkImageType::Pointer
SheetPhantomSource::MakeInkImage(std::string & renderedText) const
{
  const double pixel = std::min(m_VoxelSize, m_SliceSpacing) / m_InkOversampling;
  const double columnsReal = std::ceil(m_SheetLength / pixel), rowsReal = std::ceil(m_SheetWidth / pixel);
  if (columnsReal * rowsReal > 2.0e8)
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: ink image of " << columnsReal << " x " << rowsReal
                             << " pixels is too large: reduce the ink oversampling or the sheet size");
  }
  auto                   ink = InkImageType::New();
  InkImageType::SizeType size = { { static_cast<SizeValueType>(columnsReal), static_cast<SizeValueType>(rowsReal) } };
  ink->SetRegions(size);
  const double spacing[2] = { m_SheetLength / size[0], m_SheetWidth / size[1] };
  const double origin[2] = { 0.5 * spacing[0], 0.5 * spacing[1] };
  ink->SetSpacing(spacing);
  ink->SetOrigin(origin);
  ink->Allocate(true);
  renderedText.clear();

  const double margin = 0.5 * m_GlyphHeight;
  if (m_InkPattern)
  {
    // Dark is ink: rescale the pattern to 0..1, invert, and fit it inside the margins.
    using RescaleType = RescaleIntensityImageFilter<InkImageType, InkImageType>;
    auto rescale = RescaleType::New();
    rescale->SetInput(m_InkPattern);
    rescale->SetOutputMinimum(0.0);
    rescale->SetOutputMaximum(1.0);
    auto invert = InvertIntensityImageFilter<InkImageType, InkImageType>::New();
    invert->SetInput(rescale->GetOutput());
    invert->SetMaximum(1.0);
    const auto   patternSize = m_InkPattern->GetLargestPossibleRegion().GetSize();
    const double scale =
      std::min((m_SheetLength - 2.0 * margin) / patternSize[0], (m_SheetWidth - 2.0 * margin) / patternSize[1]);
    if (!(scale > 0.0))
    {
      itkGenericExceptionMacro(<< "SheetPhantomSource: the sheet is too small for an ink image inside margins of "
                               << margin << " mm");
    }
    auto place = ChangeInformationImageFilter<InkImageType>::New();
    place->SetInput(invert->GetOutput());
    const double                placedSpacing[2] = { scale, scale };
    const double                placedOrigin[2] = { 0.5 * (m_SheetLength - patternSize[0] * scale) + 0.5 * scale,
                                                    0.5 * (m_SheetWidth - patternSize[1] * scale) + 0.5 * scale };
    InkImageType::DirectionType identity;
    identity.SetIdentity();
    place->SetOutputSpacing(placedSpacing);
    place->SetOutputOrigin(placedOrigin);
    place->SetOutputDirection(identity);
    place->ChangeSpacingOn();
    place->ChangeOriginOn();
    place->ChangeDirectionOn();
    auto resample = ResampleImageFilter<InkImageType, InkImageType>::New();
    resample->SetInput(place->GetOutput());
    resample->SetReferenceImage(ink);
    resample->UseReferenceImageOn();
    resample->SetDefaultPixelValue(0.0);
    resample->Update();
    return resample->GetOutput();
  }

  const std::vector<uint32_t> codes = vu::DecodeUtf8(m_Text, "SheetPhantomSource: text");
  const PhantomText::FontFace font(m_FontFile, m_GlyphHeight / pixel);
  const long                  marginPixels = std::lround(margin / pixel * 64.0);
  const long                  available = static_cast<long>(size[0]) * 64 - 2 * marginPixels;
  const auto                  lines = PhantomText::LayOutLines(font, codes, available);
  if (lines.empty())
  {
    return ink;
  }
  const FT_Face face = font.Face();
  const long    ascender = face->size->metrics.ascender, descender = face->size->metrics.descender;
  const long    lineHeight = face->size->metrics.height;
  const long    blockHeight = static_cast<long>(lines.size() - 1) * lineHeight + ascender - descender;
  long          blockWidth = 0;
  for (const auto & line : lines)
  {
    blockWidth = std::max(blockWidth, font.Width(line));
  }
  const long heightAvailable = static_cast<long>(size[1]) * 64 - 2 * marginPixels;
  if (blockWidth > available || blockHeight > heightAvailable)
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: text does not fit on the sheet: it needs "
                             << (blockWidth / 64.0 + 2 * margin / pixel) * pixel << " x "
                             << (blockHeight / 64.0 + 2 * margin / pixel) * pixel << " mm, the sheet is "
                             << m_SheetLength << " x " << m_SheetWidth << " mm (reduce the glyph height or the text)");
  }
  float * buffer = ink->GetBufferPointer();
  long    baseline = (static_cast<long>(size[1]) * 64 - blockHeight) / 2 + ascender;
  for (const auto & line : lines)
  {
    long    pen = (static_cast<long>(size[0]) * 64 - blockWidth) / 2;
    FT_UInt previous = 0;
    for (uint32_t code : line)
    {
      const FT_UInt index = font.GlyphIndex(code);
      pen += font.Kerning(previous, index);
      previous = index;
      if (FT_Load_Glyph(face, index, FT_LOAD_RENDER) != 0)
      {
        itkGenericExceptionMacro(<< "SheetPhantomSource: FreeType cannot render character U+" << std::hex << code);
      }
      const FT_Bitmap & bitmap = face->glyph->bitmap;
      const long        left = (pen >> 6) + face->glyph->bitmap_left;
      const long        top = (baseline >> 6) - face->glyph->bitmap_top;
      for (unsigned r = 0; r < bitmap.rows; ++r)
      {
        const long y = top + r;
        for (unsigned c = 0; c < bitmap.width; ++c)
        {
          const long x = left + c;
          if (x >= 0 && y >= 0 && x < static_cast<long>(size[0]) && y < static_cast<long>(size[1]))
          {
            float & value = buffer[y * size[0] + x];
            value = std::max(value, bitmap.buffer[r * bitmap.pitch + c] / 255.0f);
          }
        }
      }
      pen += face->glyph->advance.x;
    }
    baseline += lineHeight;
    renderedText += (renderedText.empty() ? "" : "\n") + vu::EncodeUtf8(line);
  }
  return ink;
}

SheetPhantomSource::InkImageType::Pointer
SheetPhantomSource::MakeFibreTexture(bool alongSheet, uint32_t seed) const
{
  // White noise smoothed much longer along the fibres than across them, scaled to a
  // standard deviation of FibreContrast. The noise reaches four sigmas beyond the sheet on
  // every side and is cropped after smoothing: the recursive Gaussian extends an image by
  // its edge values, which near the edges would weigh a few noise samples heavily and
  // raise the fibre contrast there several-fold (bands of false density at the sheet's
  // ends).
  const double pixel = 0.5 * std::min(m_VoxelSize, m_SliceSpacing);
  double       sigma[2];
  sigma[alongSheet ? 0 : 1] = 0.5 * m_FibreLength;
  sigma[alongSheet ? 1 : 0] = 1.5 * pixel;
  const SizeValueType sheet[2] = { static_cast<SizeValueType>(std::ceil(m_SheetLength / pixel)) + 1,
                                   static_cast<SizeValueType>(std::ceil(m_SheetWidth / pixel)) + 1 };
  SizeValueType       pad[2];
  for (int d = 0; d < 2; ++d)
  {
    pad[d] = static_cast<SizeValueType>(std::ceil(4.0 * sigma[d] / pixel));
  }
  auto                         noise = InkImageType::New();
  const InkImageType::SizeType size = { { sheet[0] + 2 * pad[0], sheet[1] + 2 * pad[1] } };
  noise->SetRegions(size);
  noise->SetSpacing(pixel);
  noise->Allocate(true);
  auto random = AdditiveGaussianNoiseImageFilter<InkImageType, InkImageType>::New();
  random->SetInput(noise);
  random->SetStandardDeviation(1.0);
  random->SetSeed(seed);
  random->SetNumberOfWorkUnits(16);
  auto smooth = SmoothingRecursiveGaussianImageFilter<InkImageType, InkImageType>::New();
  SmoothingRecursiveGaussianImageFilter<InkImageType>::SigmaArrayType sigmas;
  sigmas[0] = sigma[0];
  sigmas[1] = sigma[1];
  smooth->SetInput(random->GetOutput());
  smooth->SetSigmaArray(sigmas);
  smooth->Update();
  // The sheet's part, with pixel (0, 0) at s = w = 0 again.
  auto cropped = InkImageType::New();
  cropped->SetRegions(InkImageType::SizeType{ { sheet[0], sheet[1] } });
  cropped->SetSpacing(pixel);
  cropped->Allocate();
  for (SizeValueType y = 0; y < sheet[1]; ++y)
  {
    const float * from = smooth->GetOutput()->GetBufferPointer() + (y + pad[1]) * size[0] + pad[0];
    std::copy(from, from + sheet[0], cropped->GetBufferPointer() + y * sheet[0]);
  }
  auto statistics = StatisticsImageFilter<InkImageType>::New();
  statistics->SetInput(cropped);
  statistics->Update();
  auto scale = ShiftScaleImageFilter<InkImageType, InkImageType>::New();
  scale->SetInput(cropped);
  scale->SetShift(-statistics->GetMean());
  scale->SetScale(m_FibreContrast / std::max(statistics->GetSigma(), 1e-12));
  scale->Update();
  return scale->GetOutput();
}

void
SheetPhantomSource::GenerateOutputInformation()
{
  CheckParameters();
  SheetPhantomGeometry::Parameters p;
  p.Shape = m_Shape;
  p.SheetLength = m_SheetLength;
  p.SheetWidth = m_SheetWidth;
  p.SheetThickness = m_SheetThickness;
  p.InnerRadius = m_InnerRadius;
  p.Pitch = m_Pitch;
  p.Squash = m_Squash;
  p.WaveAmplitude = m_WaveAmplitude;
  p.WavesPerTurn = m_WavesPerTurn;
  p.FoldCount = m_FoldCount;
  p.FoldRadius = m_FoldRadius;
  p.FoldOpeningAngle = m_FoldOpeningAngle;
  p.TiltAngle = m_TiltAngle;
  SheetPhantomGeometry geometry(p);

  const double spacing[3] = { m_VoxelSize, m_VoxelSize, m_SliceSpacing };
  double       lower[3], upper[3];
  geometry.GetBoundingBox(lower, upper);
  OutputImageType::PointType   origin;
  OutputImageType::SizeType    size;
  OutputImageType::IndexType   start = { { 0, 0, 0 } };
  OutputImageType::SpacingType outputSpacing;
  double                       voxels = 1.0;
  for (int d = 0; d < 3; ++d)
  {
    origin[d] = std::floor((lower[d] - m_Margin) / spacing[d]) * spacing[d];
    const double extent = std::ceil((upper[d] + m_Margin - origin[d]) / spacing[d]) + 1.0;
    voxels *= extent;
    size[d] = static_cast<SizeValueType>(extent);
    outputSpacing[d] = spacing[d];
  }
  if (voxels > 256.0e6)
  {
    itkGenericExceptionMacro(<< "SheetPhantomSource: the volume would have " << voxels / 1e6
                             << " M voxels (limit 256 M): increase the voxel size or reduce the sheet");
  }
  std::string                 text;
  const InkImageType::Pointer ink = MakeInkImage(text);
  geometry.SetInk(ink, text);
  m_Geometry = std::move(geometry);

  OutputImageType * output = this->GetOutput();
  output->SetLargestPossibleRegion(OutputImageType::RegionType(start, size));
  output->SetSpacing(outputSpacing);
  output->SetOrigin(origin);
  OutputImageType::DirectionType direction;
  direction.SetIdentity();
  output->SetDirection(direction);
}

void
SheetPhantomSource::EnlargeOutputRequestedRegion(DataObject * output)
{
  output->SetRequestedRegionToLargestPossibleRegion();
}

void
SheetPhantomSource::Splat(OutputImageType * volume)
{
  const SheetPhantomGeometry & g = m_Geometry;
  const double length = g.GetSheetLength(), width = g.GetSheetWidth(), thickness = g.GetSheetThickness();
  const auto   spacing = volume->GetSpacing();
  const auto   origin = volume->GetOrigin();
  const auto   size = volume->GetLargestPossibleRegion().GetSize();
  const double step = std::min({ spacing[0], spacing[1], spacing[2] }) / m_Supersampling;
  const size_t ns = static_cast<size_t>(std::ceil(length / step));
  const size_t nw = static_cast<size_t>(std::ceil(width / step));
  const size_t nd = std::max<size_t>(1, static_cast<size_t>(std::ceil(thickness / step)));
  const double ds = length / ns, dw = width / nw, dd = thickness / nd;
  const double cellVolume = ds * dw * dd / (spacing[0] * spacing[1] * spacing[2]);

  // Per column of samples: the mid-surface point at w = 0, the normal and the curvature.
  std::vector<double> base(3 * ns), normal(3 * ns), curvature(ns);
  for (size_t i = 0; i < ns; ++i)
  {
    const double s = (i + 0.5) * ds;
    g.SurfacePoint(s, 0.0, &base[3 * i]);
    g.SurfaceNormal(s, 0.0, &normal[3 * i]);
    curvature[i] = g.Curvature(s);
  }
  double axis[3], p0[3];
  g.SurfacePoint(0.0, 1.0, axis);
  g.SurfacePoint(0.0, 0.0, p0);
  for (int d = 0; d < 3; ++d)
  {
    axis[d] -= p0[d];
  }

  using InterpolatorType = LinearInterpolateImageFunction<InkImageType, double>;
  auto inkInterpolator = InterpolatorType::New();
  inkInterpolator->SetInputImage(g.GetInkImage());
  InterpolatorType::Pointer fibreInterpolator[2];
  InkImageType::Pointer     fibres[2];
  if (m_FibreContrast > 0.0)
  {
    for (int k = 0; k < 2; ++k)
    {
      fibres[k] = MakeFibreTexture(k == 0, m_Seed * 2654435761u + k + 1);
      fibreInterpolator[k] = InterpolatorType::New();
      fibreInterpolator[k]->SetInputImage(fibres[k]);
    }
  }
  auto sample = [](const InterpolatorType * interpolator, double s, double w) {
    const auto &                          image = *interpolator->GetInputImage();
    const auto                            sp = image.GetSpacing();
    const auto                            o = image.GetOrigin();
    const auto                            sz = image.GetLargestPossibleRegion().GetSize();
    InterpolatorType::ContinuousIndexType index;
    index[0] = std::clamp((s - o[0]) / sp[0], 0.0, sz[0] - 1.0);
    index[1] = std::clamp((w - o[1]) / sp[1], 0.0, sz[1] - 1.0);
    return interpolator->EvaluateAtContinuousIndex(index);
  };

  const double material = m_SheetValue - m_AirValue;
  const double inkStart = 0.5 * thickness - m_InkDepth;
  float *      buffer = volume->GetBufferPointer();
  const double inverseSpacing[3] = { 1.0 / spacing[0], 1.0 / spacing[1], 1.0 / spacing[2] };

  // Samples whose w differ by more than twice the voxel diagonal never touch the same
  // voxel, so bands of w that wide, taken every other band, can be splatted in parallel.
  const double diagonal = std::sqrt(spacing[0] * spacing[0] + spacing[1] * spacing[1] + spacing[2] * spacing[2]);
  const size_t bandRows = static_cast<size_t>(std::ceil(2.01 * diagonal / dw));
  const size_t bands = (nw + bandRows - 1) / bandRows;

  auto splatBand = [&](size_t band) {
    const size_t        j0 = band * bandRows, j1 = std::min(nw, j0 + bandRows);
    std::vector<double> values(nd);
    for (size_t i = 0; i < ns; ++i)
    {
      const double s = (i + 0.5) * ds;
      for (size_t j = j0; j < j1; ++j)
      {
        const double w = (j + 0.5) * dw;
        const double ink = m_InkContrast * sample(inkInterpolator, s, w);
        double       fibre[2] = { 0.0, 0.0 };
        if (m_FibreContrast > 0.0)
        {
          fibre[0] = sample(fibreInterpolator[0], s, w);
          fibre[1] = sample(fibreInterpolator[1], s, w);
        }
        for (size_t k = 0; k < nd; ++k)
        {
          const double depth = -0.5 * thickness + (k + 0.5) * dd;
          const double value = (material + (depth >= 0.0 ? fibre[0] : fibre[1]) + (depth >= inkStart ? ink : 0.0)) *
                               cellVolume * (1.0 - curvature[i] * depth);
          double index[3];
          int    corner[3];
          double fraction[3];
          bool   inside = true;
          for (int d = 0; d < 3; ++d)
          {
            const double x = base[3 * i + d] + w * axis[d] + depth * normal[3 * i + d];
            index[d] = (x - origin[d]) * inverseSpacing[d];
            corner[d] = static_cast<int>(std::floor(index[d]));
            fraction[d] = index[d] - corner[d];
            inside = inside && corner[d] >= 0 && corner[d] + 1 < static_cast<int>(size[d]);
          }
          if (!inside)
          {
            continue;
          }
          const size_t first = corner[0] + size[0] * (corner[1] + size[1] * static_cast<size_t>(corner[2]));
          for (int c = 0; c < 8; ++c)
          {
            const int    bx = c & 1, by = (c >> 1) & 1, bz = (c >> 2) & 1;
            const double weight = (bx ? fraction[0] : 1.0 - fraction[0]) * (by ? fraction[1] : 1.0 - fraction[1]) *
                                  (bz ? fraction[2] : 1.0 - fraction[2]);
            buffer[first + bx + size[0] * (by + size[1] * bz)] += static_cast<float>(weight * value);
          }
        }
      }
    }
  };

  // Bands go in chunks so that progress is reported and an abort honoured in between.
  const size_t chunk = 2 * std::max<size_t>(1, this->GetMultiThreader()->GetMaximumNumberOfThreads());
  size_t       done = 0;
  for (size_t parity = 0; parity < 2; ++parity)
  {
    std::vector<size_t> phase;
    for (size_t b = parity; b < bands; b += 2)
    {
      phase.push_back(b);
    }
    for (size_t first = 0; first < phase.size(); first += chunk)
    {
      const size_t last = std::min(phase.size(), first + chunk);
      this->GetMultiThreader()->ParallelizeArray(
        first, last, [&](SizeValueType k) { splatBand(phase[k]); }, nullptr);
      done += last - first;
      this->UpdateProgress(0.7f * done / bands);
      if (this->GetAbortGenerateData())
      {
        ProcessAborted aborted(__FILE__, __LINE__);
        aborted.SetDescription("SheetPhantomSource: aborted");
        throw aborted;
      }
    }
  }
}

void
SheetPhantomSource::GenerateData()
{
  OutputImageType * output = this->GetOutput();
  auto              volume = OutputImageType::New();
  volume->CopyInformation(output);
  volume->SetRegions(output->GetLargestPossibleRegion());
  volume->Allocate(true);
  this->UpdateProgress(0.0f);
  Splat(volume);

  // The splat accumulated material above air.
  const size_t count = volume->GetLargestPossibleRegion().GetNumberOfPixels();
  float *      buffer = volume->GetBufferPointer();
  const float  air = static_cast<float>(m_AirValue);
  for (size_t i = 0; i < count; ++i)
  {
    buffer[i] += air;
  }

  OutputImageType::Pointer result = volume;
  if (m_BlurFWHM > 0.0)
  {
    const double sigma = m_BlurFWHM / (2.0 * std::sqrt(2.0 * std::log(2.0)));
    auto         blur = DiscreteGaussianImageFilter<OutputImageType, OutputImageType>::New();
    blur->SetInput(result);
    blur->SetVariance(sigma * sigma);
    blur->SetUseImageSpacing(true);
    blur->SetMaximumKernelWidth(64);
    blur->AddObserver(ProgressEvent(),
                      [this, &blur](const EventObject &) { this->UpdateProgress(0.7f + 0.15f * blur->GetProgress()); });
    blur->Update();
    result = blur->GetOutput();
    result->DisconnectPipeline();
  }
  if (m_NoiseStandardDeviation > 0.0)
  {
    auto noise = AdditiveGaussianNoiseImageFilter<OutputImageType, OutputImageType>::New();
    noise->SetInput(result);
    noise->SetStandardDeviation(m_NoiseStandardDeviation);
    noise->SetSeed(m_Seed);
    // A fixed split makes the noise independent of the number of threads.
    noise->SetNumberOfWorkUnits(16);
    noise->Update();
    result = noise->GetOutput();
  }
  this->UpdateProgress(1.0f);
  this->GraftOutput(result);
}

void
SheetPhantomSource::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "PresetName: " << m_PresetName << std::endl;
  os << indent << "Shape: " << m_Shape << std::endl;
  os << indent << "SheetLength: " << m_SheetLength << std::endl;
  os << indent << "SheetWidth: " << m_SheetWidth << std::endl;
  os << indent << "SheetThickness: " << m_SheetThickness << std::endl;
  os << indent << "InnerRadius: " << m_InnerRadius << std::endl;
  os << indent << "Pitch: " << m_Pitch << std::endl;
  os << indent << "Squash: " << m_Squash << std::endl;
  os << indent << "WaveAmplitude: " << m_WaveAmplitude << std::endl;
  os << indent << "WavesPerTurn: " << m_WavesPerTurn << std::endl;
  os << indent << "FoldCount: " << m_FoldCount << std::endl;
  os << indent << "FoldRadius: " << m_FoldRadius << std::endl;
  os << indent << "FoldOpeningAngle: " << m_FoldOpeningAngle << std::endl;
  os << indent << "TiltAngle: " << m_TiltAngle << std::endl;
  os << indent << "Text: " << m_Text << std::endl;
  os << indent << "FontFile: " << m_FontFile << std::endl;
  os << indent << "GlyphHeight: " << m_GlyphHeight << std::endl;
  os << indent << "InkPattern: " << m_InkPattern.GetPointer() << std::endl;
  os << indent << "InkContrast: " << m_InkContrast << std::endl;
  os << indent << "InkDepth: " << m_InkDepth << std::endl;
  os << indent << "AirValue: " << m_AirValue << std::endl;
  os << indent << "SheetValue: " << m_SheetValue << std::endl;
  os << indent << "FibreContrast: " << m_FibreContrast << std::endl;
  os << indent << "FibreLength: " << m_FibreLength << std::endl;
  os << indent << "VoxelSize: " << m_VoxelSize << std::endl;
  os << indent << "SliceSpacing: " << m_SliceSpacing << std::endl;
  os << indent << "Margin: " << m_Margin << std::endl;
  os << indent << "Supersampling: " << m_Supersampling << std::endl;
  os << indent << "InkOversampling: " << m_InkOversampling << std::endl;
  os << indent << "BlurFWHM: " << m_BlurFWHM << std::endl;
  os << indent << "NoiseStandardDeviation: " << m_NoiseStandardDeviation << std::endl;
  os << indent << "Seed: " << m_Seed << std::endl;
  os << indent << "Geometry: sheet " << m_Geometry.GetSheetLength() << " x " << m_Geometry.GetSheetWidth() << " x "
     << m_Geometry.GetSheetThickness() << " mm, " << m_Geometry.GetNumberOfTurns() << " turns" << std::endl;
}
} // end namespace itk

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
#ifndef vuFontFace_h
#define vuFontFace_h

#include "itkMacro.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace itk {
/** The phantom's text rendering with FreeType (validation kit only). */
namespace PhantomText {
// Owns a FreeType library and face for the duration of one rendering.
class FontFace
{
public:
  FontFace(const std::string & file, double capHeightPixels)
  {
    if (FT_Init_FreeType(&m_Library) != 0)
    {
      itkGenericExceptionMacro(<< "SheetPhantomSource: cannot initialise FreeType");
    }
    if (FT_New_Face(m_Library, file.c_str(), 0, &m_Face) != 0)
    {
      FT_Done_FreeType(m_Library);
      itkGenericExceptionMacro(<< "SheetPhantomSource: cannot load font file \"" << file << "\"");
    }
    // Scale the em so that capitals (the height of 'H') are capHeightPixels tall.
    if (FT_Load_Char(m_Face, 'H', FT_LOAD_NO_SCALE) != 0 || m_Face->glyph->metrics.height <= 0)
    {
      Release();
      itkGenericExceptionMacro(<< "SheetPhantomSource: font \"" << file << "\" has no capital H to measure");
    }
    const double em = capHeightPixels * m_Face->units_per_EM / m_Face->glyph->metrics.height;
    FT_Set_Char_Size(m_Face, 0, static_cast<FT_F26Dot6>(std::lround(em * 64.0)), 72, 72);
  }
  ~FontFace() { Release(); }
  void
  Release()
  {
    if (m_Face != nullptr)
    {
      FT_Done_Face(m_Face);
      m_Face = nullptr;
    }
    if (m_Library != nullptr)
    {
      FT_Done_FreeType(m_Library);
      m_Library = nullptr;
    }
  }
  FontFace(const FontFace &) = delete;
  FontFace &
  operator=(const FontFace &) = delete;

  FT_UInt
  GlyphIndex(uint32_t code) const
  {
    const FT_UInt index = FT_Get_Char_Index(m_Face, code);
    if (index == 0)
    {
      itkGenericExceptionMacro(<< "SheetPhantomSource: character U+" << std::hex << std::uppercase << code
                               << " is not in the font");
    }
    return index;
  }
  // Advance widths with kerning, in pixels (26.6 fixed point).
  long
  Width(const std::vector<uint32_t> & line) const
  {
    long    width = 0;
    FT_UInt previous = 0;
    for (uint32_t code : line)
    {
      const FT_UInt index = GlyphIndex(code);
      width += Kerning(previous, index);
      FT_Load_Glyph(m_Face, index, FT_LOAD_DEFAULT);
      width += m_Face->glyph->advance.x;
      previous = index;
    }
    return width;
  }
  long
  Kerning(FT_UInt previous, FT_UInt index) const
  {
    if (previous == 0 || !FT_HAS_KERNING(m_Face))
    {
      return 0;
    }
    FT_Vector delta;
    FT_Get_Kerning(m_Face, previous, index, FT_KERNING_DEFAULT, &delta);
    return delta.x;
  }
  FT_Face
  Face() const
  {
    return m_Face;
  }

private:
  FT_Library m_Library{ nullptr };
  FT_Face    m_Face{ nullptr };
};

// Greedy word wrap of each paragraph to maxWidth (26.6 pixels).
std::vector<std::vector<uint32_t>>
LayOutLines(const FontFace & font, const std::vector<uint32_t> & text, long maxWidth);
} // namespace PhantomText
} // end namespace itk

#endif

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
// Internal to the library (not installed): UTF-8 <-> code points, shared by the text
// renderer of the phantom source and the OCR error measure.
#ifndef vuUtf8_h
#define vuUtf8_h

#include "itkMacro.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vu {
/** Code points of a UTF-8 string; throws itk::ExceptionObject, naming `what`, on
 * malformed input. */
inline std::vector<uint32_t>
DecodeUtf8(const std::string & text, const char * what)
{
  std::vector<uint32_t> codes;
  for (size_t i = 0; i < text.size();)
  {
    const auto byte = static_cast<unsigned char>(text[i]);
    const int  extra = byte < 0x80 ? 0 : (byte >> 5) == 0x6 ? 1 : (byte >> 4) == 0xE ? 2 : (byte >> 3) == 0x1E ? 3 : -1;
    if (extra < 0 || i + extra >= text.size())
    {
      itkGenericExceptionMacro(<< what << " is not valid UTF-8 at byte " << i);
    }
    uint32_t code = extra == 0 ? byte : (byte & (0x3F >> extra));
    for (int k = 1; k <= extra; ++k)
    {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xC0) != 0x80)
      {
        itkGenericExceptionMacro(<< what << " is not valid UTF-8 at byte " << i + k);
      }
      code = (code << 6) | (next & 0x3F);
    }
    codes.push_back(code);
    i += extra + 1;
  }
  return codes;
}

inline std::string
EncodeUtf8(const std::vector<uint32_t> & codes)
{
  std::string text;
  for (uint32_t c : codes)
  {
    if (c < 0x80)
    {
      text += static_cast<char>(c);
    }
    else if (c < 0x800)
    {
      text += static_cast<char>(0xC0 | (c >> 6));
      text += static_cast<char>(0x80 | (c & 0x3F));
    }
    else if (c < 0x10000)
    {
      text += static_cast<char>(0xE0 | (c >> 12));
      text += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      text += static_cast<char>(0x80 | (c & 0x3F));
    }
    else
    {
      text += static_cast<char>(0xF0 | (c >> 18));
      text += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      text += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      text += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return text;
}
} // namespace vu

#endif

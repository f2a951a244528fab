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
#include "vuFontFace.h"

#include <algorithm>

namespace itk {
namespace PhantomText {
// Greedy word wrap of each paragraph to maxWidth (26.6 pixels).
std::vector<std::vector<uint32_t>>
LayOutLines(const FontFace & font, const std::vector<uint32_t> & text, long maxWidth)
{
  std::vector<std::vector<uint32_t>> paragraphs(1);
  for (uint32_t c : text)
  {
    if (c == '\n')
    {
      paragraphs.emplace_back();
    }
    else
    {
      paragraphs.back().push_back(c == '\t' ? ' ' : c);
    }
  }
  std::vector<std::vector<uint32_t>> lines;
  for (const auto & paragraph : paragraphs)
  {
    std::vector<std::vector<uint32_t>> words(1);
    for (uint32_t c : paragraph)
    {
      if (c == ' ')
      {
        if (!words.back().empty())
        {
          words.emplace_back();
        }
      }
      else
      {
        words.back().push_back(c);
      }
    }
    if (words.back().empty())
    {
      words.pop_back();
    }
    std::vector<uint32_t> line;
    for (const auto & word : words)
    {
      std::vector<uint32_t> candidate = line;
      if (!candidate.empty())
      {
        candidate.push_back(' ');
      }
      candidate.insert(candidate.end(), word.begin(), word.end());
      if (!line.empty() && font.Width(candidate) > maxWidth)
      {
        lines.push_back(line);
        line = word;
      }
      else
      {
        line = candidate;
      }
    }
    if (!line.empty())
    {
      lines.push_back(line);
    }
  }
  return lines;
}
} // namespace PhantomText
} // end namespace itk

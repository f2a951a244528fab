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
#ifndef vuCTReaderRefusal_h
#define vuCTReaderRefusal_h

#include "itkCTVolumeReader.h"
#include "vuCTInputFiles.h"

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>

namespace itk {
/** What CTVolumeReader's parts share: the input-file helpers, the refusal with a one-line
 * message, and a series' description in messages. */
namespace CTReading {
namespace fs = std::filesystem;
using namespace detail;
using OutputImageType = CTVolumeReader::OutputImageType;

/** Throws the message alone (no class name or address in the description) on one line,
 * so that the tool can print it as one readable line. */
template <typename... TParts>
[[noreturn]] void
Refuse(const TParts &... parts)
{
  std::ostringstream text;
  (text << ... << parts);
  std::string message = text.str();
  std::replace_if(
    message.begin(), message.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  throw ExceptionObject(__FILE__, __LINE__, message, "CTVolumeReader");
}

inline std::string
DescribeSeries(const CTVolumeReader::SeriesInfo & s)
{
  return "series " + (s.Number.empty() ? std::string("?") : s.Number) +
         (s.Description.empty() ? std::string() : " '" + s.Description + "'") + " (" + s.UID + ", " +
         std::to_string(s.NumberOfSlices) + " slices)";
}
} // namespace CTReading
} // end namespace itk

#endif

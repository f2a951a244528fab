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
#include "vuCTInputFiles.h"
#include "vuIsolatedParse.h"

#include "itkImageIOFactory.h"
#include "itkMetaImageIO.h"
#include "itk_zlib.h"

#include "gdcmImageReader.h"
#include "gdcmReader.h"


#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace itk {
namespace detail {
namespace fs = std::filesystem;


std::string
Trim(const char * text)
{
  if (text == nullptr)
  {
    return {};
  }
  std::string s(text);
  const auto  first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos)
  {
    return {};
  }
  // DICOM pads odd-length values with a space (text) or a NUL (UIDs).
  const auto last = s.find_last_not_of(std::string(" \t\r\n\0", 5));
  return s.substr(first, last - first + 1);
}

std::vector<double>
ParseDecimals(const std::string & text)
{
  std::vector<double> values;
  std::stringstream   stream(text);
  std::string         part;
  while (std::getline(stream, part, '\\'))
  {
    try
    {
      values.push_back(std::stod(part));
    }
    catch (const std::exception &)
    {
      return {};
    }
  }
  return values;
}

double
ParseDecimal(const std::string & text, double fallback)
{
  const std::vector<double> values = ParseDecimals(text);
  return values.size() == 1 && std::isfinite(values[0]) ? values[0] : fallback;
}

bool
NaturalLess(const std::string & a, const std::string & b)
{
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size())
  {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j])))
    {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie])))
      {
        ++ie;
      }
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je])))
      {
        ++je;
      }
      // Compare digit runs by value: strip leading zeros, then longer means larger.
      size_t iz = i, jz = j;
      while (iz + 1 < ie && a[iz] == '0')
      {
        ++iz;
      }
      while (jz + 1 < je && b[jz] == '0')
      {
        ++jz;
      }
      if (ie - iz != je - jz)
      {
        return ie - iz < je - jz;
      }
      const int order = a.compare(iz, ie - iz, b, jz, je - jz);
      if (order != 0)
      {
        return order < 0;
      }
      i = ie;
      j = je;
    }
    else
    {
      if (a[i] != b[j])
      {
        return a[i] < b[j];
      }
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

bool
HasTiffExtension(const fs::path & path)
{
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return extension == ".tif" || extension == ".tiff";
}

bool
HasNonDicomImageExtension(const fs::path & path)
{
  std::string name = path.filename().string();
  std::transform(
    name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char * extension : { ".tif",
                                  ".tiff",
                                  ".nrrd",
                                  ".nhdr",
                                  ".mha",
                                  ".mhd",
                                  ".raw",
                                  ".nii",
                                  ".nii.gz",
                                  ".hdr",
                                  ".img",
                                  ".png",
                                  ".jpg",
                                  ".jpeg",
                                  ".bmp",
                                  ".vtk",
                                  ".h5",
                                  ".hdf5",
                                  ".hdf" })
  {
    const std::string e(extension);
    if (name.size() > e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0)
    {
      return true;
    }
  }
  return false;
}

std::string
ComponentTypeName(IOComponentEnum type, size_t bytes)
{
  const std::string bits = std::to_string(8 * bytes);
  switch (type)
  {
    case IOComponentEnum::FLOAT:
    case IOComponentEnum::DOUBLE:
    case IOComponentEnum::LDOUBLE:
      return "float" + bits;
    case IOComponentEnum::CHAR:
    case IOComponentEnum::SHORT:
    case IOComponentEnum::INT:
    case IOComponentEnum::LONG:
    case IOComponentEnum::LONGLONG:
      return "int" + bits;
    case IOComponentEnum::UNKNOWNCOMPONENTTYPE:
      return "unknown";
    default:
      return "uint" + bits;
  }
}

std::string
SizeText(const ImageIOBase * io)
{
  std::ostringstream text;
  for (unsigned d = 0; d < io->GetNumberOfDimensions(); ++d)
  {
    text << (d ? "x" : "") << io->GetDimensions(d);
  }
  return text.str();
}

std::string
MetaImageHeaderProblem(const std::string & file)
{
  std::ifstream in(file, std::ios::binary);
  std::string   line;
  long          dimensions = -1;
  std::string   compressedSize;
  // MetaIO reads as many numbers per field as NDims says, whatever the file holds: a
  // negative or huge NDims makes it read for hours. The header ends at ElementDataFile.
  for (size_t read = 0; read < (1u << 20) && std::getline(in, line); read += line.size() + 1)
  {
    // MetaIO copies each field name into 255 bytes without checking (a line without '='
    // runs on into the next name).
    const auto equals = line.find('=');
    if ((equals == std::string::npos ? line.size() : equals) >= 255)
    {
      return "cannot read " + file + ": a header line of " + std::to_string(line.size()) +
             " characters is not a MetaImage field";
    }
    if (equals == std::string::npos)
    {
      // MetaIO would read it as the start of the next field's name and so find its
      // header, and the data after it, elsewhere than this check does.
      const std::string text = Trim(line.c_str());
      if (!text.empty())
      {
        return "cannot read " + file + ": the header line '" + text.substr(0, 40) +
               "' is not a MetaImage field (NAME = VALUE)";
      }
      continue;
    }
    const std::string key = Trim(line.substr(0, equals).c_str());
    const std::string value = Trim(line.substr(equals + 1).c_str());
    // MetaIO copies a text value into 255 bytes as well (only lists of numbers, such as
    // a TransformMatrix, are read otherwise).
    if (value.size() >= 255)
    {
      std::istringstream tokens(value);
      std::string        token;
      bool               numbers = true;
      while (numbers && tokens >> token)
      {
        char * end = nullptr;
        std::strtod(token.c_str(), &end);
        numbers = end != token.c_str() && *end == '\0';
      }
      if (!numbers || key == "ObjectType" || key == "ObjectSubType" || key == "Name" || key == "Comment" ||
          key == "ElementDataFile" || key == "ElementType" || key == "AnatomicalOrientation")
      {
        return "cannot read " + file + ": the value of " + key.substr(0, 40) + " has " + std::to_string(value.size()) +
               " characters, more than a MetaImage field holds";
      }
    }
    if (key == "NDims")
    {
      char * end = nullptr;
      dimensions = std::strtol(value.c_str(), &end, 10);
      if (end == value.c_str() || Trim(end) != "" || dimensions < 1 || dimensions > 10)
      {
        return "cannot read " + file + ": NDims must be a whole number from 1 to 10, not '" + value + "'";
      }
    }
    else if (key == "DimSize" || key == "ElementNumberOfChannels" || key == "HeaderSize")
    {
      std::istringstream numbers(value);
      std::string        number;
      long               count = 0;
      while (numbers >> number)
      {
        char *     end = nullptr;
        const long n = std::strtol(number.c_str(), &end, 10);
        if (*end != '\0' || n < (key == "HeaderSize" ? -1 : 1) || n > (1L << 31))
        {
          return "cannot read " + file + ": " + key + " must hold whole numbers, not '" + value + "'";
        }
        ++count;
      }
      if (key == "DimSize" && dimensions > 0 && count != dimensions)
      {
        return "cannot read " + file + ": DimSize holds " + std::to_string(count) + " sizes for NDims " +
               std::to_string(dimensions);
      }
    }
    else if (key == "CompressedDataSize")
    {
      compressedSize = value;
    }
    else if (key == "ElementDataFile")
    {
      // MetaIO allocates what CompressedDataSize says before reading the data file.
      if (!compressedSize.empty() && value.find('%') == std::string::npos && value.find(' ') == std::string::npos &&
          value != "LIST")
      {
        const fs::path  data = value == "LOCAL" ? fs::path(file) : fs::path(file).parent_path() / value;
        std::error_code error;
        const uintmax_t size = fs::file_size(data, error);
        char *          end = nullptr;
        const double    claimed = std::strtod(compressedSize.c_str(), &end);
        if (end == compressedSize.c_str() || Trim(end) != "" || !(claimed >= 0.0) ||
            claimed > static_cast<double>(error ? 0 : size))
        {
          return "cannot read " + file + ": CompressedDataSize '" + compressedSize + "' is more than the " +
                 std::to_string(error ? 0 : size) + " bytes of its data file";
        }
      }
      // A file-name pattern (name%03d.raw first last step) goes to printf with one int:
      // one %d it may have, any other conversion would read what is not there.
      static const std::regex pattern("[^%]*(%0?[0-9]*d[^%]*)?( .*)?");
      if (!std::regex_match(value, pattern))
      {
        return "cannot read " + file + ": ElementDataFile '" + value +
               "' is neither a file name nor a pattern with one %d";
      }
      break;
    }
  }
  return {};
}

std::string
TiffDirectoryProblem(const std::string & file)
{
  std::ifstream in(file, std::ios::binary);
  unsigned char header[8] = {};
  if (!in.read(reinterpret_cast<char *>(header), 8))
  {
    return {};
  }
  const bool little = header[0] == 'I' && header[1] == 'I' && header[2] == 42 && header[3] == 0;
  const bool big = header[0] == 'M' && header[1] == 'M' && header[2] == 0 && header[3] == 42;
  if (!little && !big)
  {
    return {}; // not a classic TIFF
  }
  auto u16 = [little](const unsigned char * p) -> uint32_t { return little ? p[0] | p[1] << 8 : p[1] | p[0] << 8; };
  auto u32 = [little](const unsigned char * p) -> uint64_t {
    return little ? uint64_t(p[0]) | uint64_t(p[1]) << 8 | uint64_t(p[2]) << 16 | uint64_t(p[3]) << 24
                  : uint64_t(p[3]) | uint64_t(p[2]) << 8 | uint64_t(p[1]) << 16 | uint64_t(p[0]) << 24;
  };
  std::error_code error;
  const uint64_t  size = fs::file_size(file, error);
  // libtiff allocates and clears what a directory entry claims before reading it.
  uint64_t           offset = u32(header + 4);
  std::set<uint64_t> visited;
  while (offset != 0)
  {
    // libtiff counts directories by following the chain; a chain back to a directory it
    // has passed, by an offset it does not recognise, never ends.
    if (!visited.insert(offset).second || visited.size() > 65535)
    {
      return "cannot read " + file + ": its TIFF directories form a loop";
    }
    unsigned char count[2];
    in.seekg(static_cast<std::streamoff>(offset));
    if (offset + 2 > size || !in.read(reinterpret_cast<char *>(count), 2))
    {
      return "cannot read " + file + ": a TIFF directory lies beyond the end of the file";
    }
    const uint32_t             entries = u16(count);
    std::vector<unsigned char> table(12u * entries + 4u);
    if (offset + 2 + table.size() > size || !in.read(reinterpret_cast<char *>(table.data()), table.size()))
    {
      return "cannot read " + file + ": a TIFF directory runs past the end of the file";
    }
    // Width, length, bits per sample, compression, samples per pixel (TIFF's defaults).
    uint64_t width = 0, length = 0, bits = 1, compression = 1, samples = 1, rowsPerStrip = 0, planar = 1;
    uint64_t tileWidth = 0, tileLength = 0;
    // libtiff keeps the first of a tag given twice and the check here would judge another:
    // an image's geometry is given once.
    std::set<uint32_t> geometryTags;
    for (uint32_t e = 0; e < entries; ++e)
    {
      const unsigned char * entry = &table[12u * e];
      static const unsigned typeSize[] = { 1, 1, 1, 2, 4, 8, 1, 1, 2, 4, 8, 4, 8, 4, 1, 1, 8, 8, 8 };
      const uint32_t        type = u16(entry + 2);
      const uint64_t        count = u32(entry + 4);
      const uint64_t        bytes = count * (type < 19 ? typeSize[type] : 1);
      if (bytes > size)
      {
        return "cannot read " + file + ": TIFF tag " + std::to_string(u16(entry)) + " claims " + std::to_string(bytes) +
               " bytes, the file has " + std::to_string(size);
      }
      // The first value of a SHORT or LONG entry; BitsPerSample of several samples lies
      // elsewhere in the file, but its samples share one depth in any image ITK reads.
      uint64_t first = type == 3 ? u16(entry + 8) : type == 4 ? u32(entry + 8) : 0;
      if (type == 3 && bytes > 4)
      {
        unsigned char value[2] = {};
        in.seekg(static_cast<std::streamoff>(u32(entry + 8)));
        first = in.read(reinterpret_cast<char *>(value), 2) ? u16(value) : 0;
        in.clear();
      }
      static const std::set<uint32_t> geometry = { 256, 257, 258, 259, 277, 278, 284, 322, 323 };
      if (geometry.count(u16(entry)) != 0 && !geometryTags.insert(u16(entry)).second)
      {
        return "cannot read " + file + ": its TIFF directory gives tag " + std::to_string(u16(entry)) +
               " (image geometry) more than once";
      }
      switch (u16(entry))
      {
        case 256:
          width = first;
          break;
        case 257:
          length = first;
          break;
        case 258:
          bits = first;
          break;
        case 259:
          compression = first;
          break;
        case 277:
          samples = first;
          break;
        case 278:
          rowsPerStrip = first;
          break;
        case 284:
          planar = first;
          break;
        case 322:
          tileWidth = first;
          break;
        case 323:
          tileLength = first;
          break;
        default:
          break;
      }
    }
    // libtiff and ITK size their buffers from the image's claimed size: an uncompressed
    // image cannot be larger than its file, a compressed one not more than the best ratio
    // of TIFF's lossless codecs (deflate, about 1000:1) times it.
    const double pixelBytes = static_cast<double>(std::max<uint64_t>(width, 1)) *
                              static_cast<double>(std::max<uint64_t>(length, 1)) * static_cast<double>(samples) *
                              static_cast<double>(bits) / 8.0;
    const double holds = compression == 1 ? static_cast<double>(size) : DeflateCanHold(static_cast<double>(size));
    if (pixelBytes > holds)
    {
      return "cannot read " + file + ": its TIFF image claims " + std::to_string(width) + " x " +
             std::to_string(length) + " pixels (" + std::to_string(static_cast<uint64_t>(pixelBytes)) +
             " bytes), more than its " + std::to_string(size) + " bytes can hold" +
             (compression == 1 ? "" : " even compressed");
    }
    // libtiff allocates and clears a table entry for every strip or tile the image's size
    // implies, whatever the file holds: each takes at least one byte of the file.
    const double parts =
      (tileWidth > 0 && tileLength > 0
         ? std::ceil(static_cast<double>(width) / static_cast<double>(tileWidth)) *
             std::ceil(static_cast<double>(length) / static_cast<double>(tileLength))
         : std::ceil(static_cast<double>(length) /
                     static_cast<double>(std::max<uint64_t>(1, rowsPerStrip == 0 ? length : rowsPerStrip)))) *
      static_cast<double>(planar == 2 ? samples : 1);
    if (parts > static_cast<double>(size))
    {
      return "cannot read " + file + ": its TIFF image of " + std::to_string(width) + " x " + std::to_string(length) +
             " pixels claims " + std::to_string(static_cast<uint64_t>(parts)) + " strips or tiles, more than its " +
             std::to_string(size) + " bytes can hold";
    }
    offset = u32(&table[12u * entries]);
  }
  return {};
}

std::vector<std::string>
ProbeHeaders(const std::vector<std::string> & files)
{
  const IsolatedParse run = ParseInChildProcess(files, [](const std::string & file) {
    try
    {
      ReadImageHeader(file);
    }
    catch (const std::exception & e)
    {
      return std::string(e.what()).empty() ? std::string("cannot read ") + file : std::string(e.what());
    }
    return std::string();
  });
  if (!run.FailedFile.empty())
  {
    throw std::runtime_error(run.FailedFile + " is damaged: the image reader " + run.Failure + " on its header");
  }
  return run.Results;
}

ImageIOBase::Pointer
ReadImageHeader(const std::string & file)
{
  const std::string tiffProblem = TiffDirectoryProblem(file);
  if (!tiffProblem.empty())
  {
    throw std::runtime_error(tiffProblem);
  }
  std::string extension = fs::path(file).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  if (extension == ".mha" || extension == ".mhd")
  {
    const std::string problem = MetaImageHeaderProblem(file);
    if (!problem.empty())
    {
      throw std::runtime_error(problem);
    }
  }
  ImageIOBase::Pointer io = ImageIOFactory::CreateImageIO(file.c_str(), ImageIOFactory::IOFileModeEnum::ReadMode);
  if (io.IsNull())
  {
    throw std::runtime_error("cannot read " + file + ": not an image file in a format ITK reads");
  }
  io->SetFileName(file);
  try
  {
    io->ReadImageInformation();
  }
  catch (const ExceptionObject & e)
  {
    throw std::runtime_error("cannot read " + file + ": " + e.GetDescription());
  }
  // The reader inverts the direction matrix by a singular value decomposition, which
  // never ends on entries near the largest double; a direction is a rotation.
  for (unsigned i = 0; i < io->GetNumberOfDimensions(); ++i)
  {
    double length = 0.0;
    for (const double d : io->GetDirection(i))
    {
      if (!std::isfinite(d) || std::abs(d) > 1e3)
      {
        throw std::runtime_error("cannot read " + file + ": its direction matrix holds " + std::to_string(d) +
                                 ", not a rotation");
      }
      length += d * d;
    }
    if (!(length > 1e-12))
    {
      throw std::runtime_error("cannot read " + file + ": its direction matrix has a zero column, not a rotation");
    }
    if (!std::isfinite(io->GetOrigin(i)))
    {
      throw std::runtime_error("cannot read " + file + ": its origin is not finite");
    }
  }
  return io;
}

} // namespace detail
} // namespace itk

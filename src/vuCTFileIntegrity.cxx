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
// Whether an input file holds the data its header promises: truncated MetaImage, NRRD and
// DICOM files, damaged compressed streams.
#include "vuCTInputFiles.h"
#include "vuIsolatedParse.h"

#include "itkByteSwapper.h"
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

namespace {
// Where the data of a MetaImage with ElementDataFile = LOCAL begins: after that line.
uintmax_t
LocalDataOffset(const std::string & file)
{
  std::ifstream in(file, std::ios::binary);
  std::string   line;
  while (std::getline(in, line))
  {
    if (Trim(line.c_str()).rfind("ElementDataFile", 0) == 0)
    {
      return static_cast<uintmax_t>(in.tellg());
    }
  }
  return 0;
}

// Why a zlib or gzip stream from `offset` of `file` does not inflate to `bytes` ("its
// compressed data ..."), or "": inflated into `output` (`bytes` long), or into a small
// buffer thrown away when it is null.
std::string
InflateStream(const std::string & file, uintmax_t offset, uintmax_t bytes, unsigned char * output)
{
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  z_stream stream{};
  if (!in || inflateInit2(&stream, 15 + 32) != Z_OK)
  {
    return "its compressed data cannot be opened";
  }
  std::vector<unsigned char> input(1u << 20), scratch(output == nullptr ? 1u << 16 : 0);
  int                        status = Z_OK;
  while (stream.total_out < bytes && status == Z_OK)
  {
    if (stream.avail_in == 0)
    {
      in.read(reinterpret_cast<char *>(input.data()), static_cast<std::streamsize>(input.size()));
      stream.next_in = input.data();
      stream.avail_in = static_cast<uInt>(in.gcount());
      if (stream.avail_in == 0)
      {
        break;
      }
    }
    // Never beyond the image: a stream that holds more stops there.
    const uintmax_t room = output == nullptr ? scratch.size() : bytes - stream.total_out;
    stream.next_out = output == nullptr ? scratch.data() : output + stream.total_out;
    stream.avail_out = static_cast<uInt>(std::min<uintmax_t>(room, uintmax_t{ 1 } << 30));
    status = inflate(&stream, Z_NO_FLUSH);
    if (status == Z_BUF_ERROR)
    {
      status = Z_OK; // no progress possible with this input: more is read
    }
  }
  const uintmax_t inflated = stream.total_out;
  inflateEnd(&stream);
  if (inflated < bytes)
  {
    return "its compressed data is damaged (it inflates to " + std::to_string(inflated) + " of the " +
           std::to_string(bytes) + " bytes of the image)";
  }
  return {};
}

// Where the voxels of a MetaImage lie: its data file and the offset in it; false when they
// are not in one file (a list of files, a file name pattern).
bool
MetaImageDataFile(const std::string & file, MetaImageIO * meta, std::string & data, uintmax_t & offset)
{
  const std::string dataName = meta->GetMetaImagePointer()->ElementDataFileName();
  if (dataName == "LIST" || dataName.find('%') != std::string::npos || dataName.find(' ') != std::string::npos)
  {
    return false;
  }
  data = dataName == "LOCAL" ? file : (fs::path(file).parent_path() / dataName).string();
  offset = dataName == "LOCAL" ? LocalDataOffset(file) : 0;
  return true;
}

// MetaImageDataFile of a MetaImage whose voxels MetaIO would inflate as one stream.
bool
CompressedMetaImageData(const std::string & file, MetaImageIO * meta, std::string & data, uintmax_t & offset)
{
  return meta != nullptr && meta->GetMetaImagePointer()->CompressedData() &&
         MetaImageDataFile(file, meta, data, offset);
}

template <typename T>
void
SwapFrom(IOByteOrderEnum order, void * buffer, SizeValueType count)
{
  if (order == IOByteOrderEnum::BigEndian)
  {
    ByteSwapper<T>::SwapRangeFromSystemToBigEndian(static_cast<T *>(buffer), count);
  }
  else if (order == IOByteOrderEnum::LittleEndian)
  {
    ByteSwapper<T>::SwapRangeFromSystemToLittleEndian(static_cast<T *>(buffer), count);
  }
}
} // namespace

std::string
MetaImageTruncation(const std::string & file, ImageIOBase * io)
{
  auto * meta = dynamic_cast<MetaImageIO *>(io);
  if (meta == nullptr)
  {
    return {};
  }
  std::string dataFile;
  uintmax_t   offset = 0;
  if (!MetaImageDataFile(file, meta, dataFile, offset))
  {
    return {};
  }
  const fs::path  data = dataFile;
  std::error_code error;
  const uintmax_t size = fs::file_size(data, error);
  if (meta->GetMetaImagePointer()->CompressedData())
  {
    // zlib compresses at best about 1000 to 1: a larger image is not in the file. The
    // stream itself is checked as it is read (CheckedMetaImageIO).
    if (!error && static_cast<double>(io->GetImageSizeInBytes()) > DeflateCanHold(static_cast<double>(size)))
    {
      return "cannot read " + file + ": its compressed data file " + data.string() + " of " + std::to_string(size) +
             " bytes cannot hold an image of " + std::to_string(io->GetImageSizeInBytes()) + " bytes";
    }
    return error ? "cannot read " + file + ": its compressed data file " + data.string() + " cannot be opened"
                 : std::string();
  }
  if (error || size < static_cast<uintmax_t>(io->GetImageSizeInBytes()))
  {
    return "cannot read " + file + ": its data file " + data.string() + " holds " + std::to_string(error ? 0 : size) +
           " bytes, the image needs " + std::to_string(io->GetImageSizeInBytes());
  }
  return {};
}

std::string
MetaImageStreamProblem(const std::string & file, ImageIOBase * io)
{
  std::string data;
  uintmax_t   offset = 0;
  if (!CompressedMetaImageData(file, dynamic_cast<MetaImageIO *>(io), data, offset))
  {
    return {};
  }
  const std::string problem = InflateStream(data, offset, static_cast<uintmax_t>(io->GetImageSizeInBytes()), nullptr);
  return problem.empty() ? problem : "cannot read " + file + ": " + problem;
}

std::string
NrrdTruncation(const std::string & file, ImageIOBase * io)
{
  std::ifstream in(file, std::ios::binary);
  std::string   line;
  if (!std::getline(in, line) || line.rfind("NRRD", 0) != 0)
  {
    return {};
  }
  std::string encoding = "raw", dataFile;
  bool        attached = false;
  while (std::getline(in, line))
  {
    if (!line.empty() && line.back() == '\r')
    {
      line.pop_back();
    }
    if (line.empty())
    {
      attached = true; // the data follow the blank line
      break;
    }
    const size_t colon = line.find(':');
    if (line[0] == '#' || colon == std::string::npos)
    {
      continue;
    }
    const std::string key = Trim(line.substr(0, colon).c_str());
    const std::string value = Trim(line.substr(colon + 1).c_str());
    if (key == "encoding")
    {
      encoding = value;
    }
    else if (key == "data file" || key == "datafile")
    {
      dataFile = value;
    }
  }
  std::error_code error;
  uintmax_t       available = 0;
  fs::path        data = file;
  if (!dataFile.empty())
  {
    // A list of files or a numbered pattern: NrrdIO checks each file as it reads it.
    if (dataFile.rfind("LIST", 0) == 0 || dataFile.find(' ') != std::string::npos)
    {
      return {};
    }
    data = fs::path(file).parent_path() / dataFile;
    available = fs::file_size(data, error);
  }
  else if (attached)
  {
    const std::streamoff offset = in.tellg();
    const uintmax_t      size = fs::file_size(file, error);
    available = offset > 0 && static_cast<uintmax_t>(offset) < size ? size - static_cast<uintmax_t>(offset) : 0;
  }
  if (error)
  {
    return {}; // NrrdIO says what is missing
  }
  // What the data can hold at most, as bytes of the image, by encoding: raw bytes as
  // they are, hex two characters a byte, text at least one character a value, gzip about
  // 1000 to 1 at best, bzip2 (long runs coded as runs) far more.
  const double bytes = static_cast<double>(available);
  const double values = static_cast<double>(io->GetImageSizeInComponents());
  const double needed = static_cast<double>(io->GetImageSizeInBytes());
  bool         holds = true;
  if (encoding == "raw")
  {
    holds = bytes >= needed;
  }
  else if (encoding == "hex")
  {
    holds = bytes >= 2.0 * needed;
  }
  else if (encoding == "txt" || encoding == "text" || encoding == "ascii")
  {
    holds = bytes >= values;
  }
  else if (encoding == "gz" || encoding == "gzip")
  {
    holds = DeflateCanHold(bytes) >= needed;
  }
  else if (encoding == "bz2" || encoding == "bzip2")
  {
    holds = 1e6 * bytes + 65536.0 >= needed;
  }
  if (holds)
  {
    return {};
  }
  return "cannot read " + file + ": its NRRD data (" + encoding + ", " + std::to_string(available) + " bytes" +
         (dataFile.empty() ? "" : " in " + data.string()) + ") cannot hold an image of " + SizeText(io) + " voxels (" +
         std::to_string(static_cast<uintmax_t>(needed)) + " bytes)";
}

bool
IsDicomDirectoryFile(const std::string & file)
{
  gdcm::Reader reader;
  reader.SetFileName(file.c_str());
  if (!reader.ReadUpToTag(gdcm::Tag(0x0003, 0x0000)))
  {
    return false;
  }
  return reader.GetFile().GetHeader().GetMediaStorage() == gdcm::MediaStorage::MediaStorageDirectoryStorage;
}

std::string
DicomFilesProblem(const std::vector<std::string> & files, uintmax_t pixelBytes)
{
  const IsolatedParse run = ParseInChildProcess(files, [pixelBytes](const std::string & file) {
    QuietGdcm         quiet;
    gdcm::ImageReader reader;
    reader.SetFileName(file.c_str());
    if (!reader.Read())
    {
      return "cannot read " + file + ": the DICOM parser does not recognise it";
    }
    return TruncationProblem(file, pixelBytes);
  });
  for (const std::string & result : run.Results)
  {
    if (!result.empty())
    {
      return result;
    }
  }
  if (!run.FailedFile.empty())
  {
    return run.FailedFile + " is damaged: the DICOM parser " + run.Failure + " on it";
  }
  return {};
}

std::string
TruncationProblem(const std::string & file, uintmax_t pixelBytes)
{
  gdcm::Reader reader;
  reader.SetFileName(file.c_str());
  const gdcm::Tag pixelData(0x7fe0, 0x0010);
  if (!reader.ReadUpToTag(pixelData, { pixelData }))
  {
    return "cannot read the header of " + file;
  }
  const gdcm::TransferSyntax syntax = reader.GetFile().GetHeader().GetDataSetTransferSyntax();
  if (syntax.IsEncapsulated() || syntax == gdcm::TransferSyntax::DeflatedExplicitVRLittleEndian)
  {
    return {};
  }
  std::error_code error;
  const uintmax_t size = fs::file_size(file, error);
  const uintmax_t needed = reader.GetStreamCurrentPosition() + pixelBytes;
  if (error || size < needed)
  {
    return file + " is truncated: its pixel data needs " + std::to_string(needed) + " bytes, the file has " +
           std::to_string(size);
  }
  return {};
}
void
CheckedMetaImageIO::Read(void * buffer)
{
  std::string data;
  uintmax_t   offset = 0;
  if (!CompressedMetaImageData(m_FileName, this, data, offset))
  {
    Superclass::Read(buffer);
    return;
  }
  const auto     bytes = static_cast<uintmax_t>(this->GetImageSizeInBytes());
  const unsigned dimensions = this->GetNumberOfDimensions();
  ImageIORegion  whole(dimensions);
  for (unsigned d = 0; d < dimensions; ++d)
  {
    whole.SetIndex(d, 0);
    whole.SetSize(d, this->GetDimensions(d));
  }
  if (!(whole == m_IORegion))
  {
    const std::string problem = InflateStream(data, offset, bytes, nullptr);
    if (!problem.empty())
    {
      itkExceptionMacro(<< problem);
    }
    Superclass::Read(buffer);
    return;
  }
  const std::string problem = InflateStream(data, offset, bytes, static_cast<unsigned char *>(buffer));
  if (!problem.empty())
  {
    itkExceptionMacro(<< problem);
  }
  // MetaIO's own byte order fix (ITK's byte order states the system's), by the components'
  // size.
  const SizeValueType   count = this->GetImageSizeInComponents();
  const IOByteOrderEnum order =
    this->GetMetaImagePointer()->BinaryDataByteOrderMSB() ? IOByteOrderEnum::BigEndian : IOByteOrderEnum::LittleEndian;
  switch (this->GetComponentSize())
  {
    case 1:
      break;
    case 2:
      SwapFrom<uint16_t>(order, buffer, count);
      break;
    case 4:
      SwapFrom<uint32_t>(order, buffer, count);
      break;
    case 8:
      SwapFrom<uint64_t>(order, buffer, count);
      break;
    default:
      itkExceptionMacro(<< "components of " << this->GetComponentSize() << " bytes are not read");
  }
}

} // namespace detail
} // namespace itk

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
#include "itkZarrImageIO.h"

#include "itkVersion.h"

#include <blosc.h>
#include <nlohmann/json.hpp>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

namespace itk {
namespace {
namespace fs = std::filesystem;
using Json = nlohmann::json;

bool
ReadJson(const fs::path & file, Json & json)
{
  std::ifstream in(file);
  if (!in)
  {
    return false;
  }
  json = Json::parse(in, nullptr, false);
  return !json.is_discarded();
}

bool
IsOmeGroup(const fs::path & directory)
{
  Json attributes;
  return fs::is_regular_file(directory / ".zattrs") && ReadJson(directory / ".zattrs", attributes) &&
         attributes.is_object() && attributes.contains("multiscales") && attributes["multiscales"].is_array() &&
         !attributes["multiscales"].empty();
}

// Millimetres per unit of an OME-NGFF space axis.
double
MillimetresPer(const std::string & unit)
{
  if (unit.empty() || unit == "millimeter")
  {
    return 1.0;
  }
  if (unit == "micrometer")
  {
    return 1e-3;
  }
  if (unit == "nanometer")
  {
    return 1e-6;
  }
  if (unit == "centimeter")
  {
    return 10.0;
  }
  if (unit == "meter")
  {
    return 1e3;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// The values of a transformation of the given type ("scale", "translation") in a list of
// coordinateTransformations, or `fallback` when there is none.
std::vector<double>
Transformation(const Json & list, const char * type, std::vector<double> fallback)
{
  if (!list.is_array())
  {
    return fallback;
  }
  for (const Json & t : list)
  {
    if (t.is_object() && t.value("type", "") == type && t.contains(type) && t[type].is_array())
    {
      return t[type].get<std::vector<double>>();
    }
  }
  return fallback;
}

// One element of the stored type holding a .zarray's fill value (a number, "NaN",
// "Infinity" or "-Infinity"; 0 when absent).
std::vector<char>
FillValueBytes(const Json & fill, IOComponentEnum type, size_t componentSize)
{
  std::vector<char> bytes(componentSize, 0);
  double            value = 0.0;
  if (fill.is_number())
  {
    value = fill.get<double>();
  }
  else if (fill.is_string())
  {
    const std::string text = fill.get<std::string>();
    value = text == "NaN" ? std::numeric_limits<double>::quiet_NaN()
                          : (text == "-Infinity" ? -1.0 : 1.0) * std::numeric_limits<double>::infinity();
  }
  auto store = [&](auto typed) {
    using T = decltype(typed);
    const T v = static_cast<T>(value);
    std::memcpy(bytes.data(), &v, sizeof(T));
  };
  switch (type)
  {
    case IOComponentEnum::UCHAR:
      store(uint8_t{});
      break;
    case IOComponentEnum::CHAR:
      store(int8_t{});
      break;
    case IOComponentEnum::USHORT:
      store(uint16_t{});
      break;
    case IOComponentEnum::SHORT:
      store(int16_t{});
      break;
    case IOComponentEnum::UINT:
      store(uint32_t{});
      break;
    case IOComponentEnum::INT:
      store(int32_t{});
      break;
    case IOComponentEnum::FLOAT:
      store(float{});
      break;
    default:
      store(double{});
      break;
  }
  return bytes;
}
} // namespace

ZarrImageIO::ZarrImageIO()
{
  this->SetNumberOfDimensions(3);
  this->SetNumberOfComponents(1);
  this->SetPixelType(IOPixelEnum::SCALAR);
}

bool
ZarrImageIO::CanReadFile(const char * fileName)
{
  try
  {
    const fs::path path(fileName);
    return fs::is_directory(path) && (fs::is_regular_file(path / ".zarray") || IsOmeGroup(path));
  }
  catch (const std::exception &)
  {
    return false;
  }
}

void
ZarrImageIO::ReadImageInformation()
{
  if (!fs::is_directory(fs::path(m_FileName)))
  {
    itkExceptionMacro(<< m_FileName << " is not a Zarr store (not a directory)");
  }
  // The array, and for an OME-Zarr image the scale and translation of its axes (Zarr order).
  std::string         array = m_FileName;
  std::vector<double> scale, translation;
  m_HasGeometry = false;
  if (!fs::is_regular_file(fs::path(m_FileName) / ".zarray"))
  {
    ReadOmeMultiscales(array, scale, translation);
    m_HasGeometry = !scale.empty();
  }
  m_ArrayPath = array;
  ReadArrayMetadata();
  SetAxes(scale, translation);
}

void
ZarrImageIO::ReadOmeMultiscales(std::string & arrayPath, std::vector<double> & scale, std::vector<double> & translation)
{
  const fs::path      root(m_FileName);
  std::vector<double> unitScale;
  Json                attributes;
  if (!IsOmeGroup(root) || !ReadJson(root / ".zattrs", attributes))
  {
    itkExceptionMacro(<< m_FileName << " holds neither .zarray nor OME-Zarr multiscales metadata in .zattrs");
  }
  const Json & image = attributes["multiscales"][0];
  if (!image.contains("datasets") || !image["datasets"].is_array() || image["datasets"].empty() ||
      !image["datasets"][0].contains("path"))
  {
    itkExceptionMacro(<< m_FileName << ": OME-Zarr multiscales without datasets");
  }
  const Json & dataset = image["datasets"][0];
  arrayPath = (root / dataset["path"].get<std::string>()).string();
  if (image.contains("axes") && image["axes"].is_array())
  {
    for (const Json & axis : image["axes"])
    {
      const std::string unit = axis.is_object() ? axis.value("unit", "") : "";
      const std::string type = axis.is_object() ? axis.value("type", "space") : "space";
      const double      factor = type == "space" ? MillimetresPer(unit) : 1.0;
      if (!std::isfinite(factor))
      {
        itkExceptionMacro(<< m_FileName << ": OME-Zarr axis unit \"" << unit << "\" is not a length unit");
      }
      unitScale.push_back(factor);
    }
  }
  scale = Transformation(dataset.value("coordinateTransformations", Json()), "scale", {});
  translation = Transformation(dataset.value("coordinateTransformations", Json()), "translation", {});
  // Transformations of the whole multiscale apply after the dataset's.
  const Json          global = image.value("coordinateTransformations", Json());
  std::vector<double> globalScale = Transformation(global, "scale", {});
  std::vector<double> globalTranslation = Transformation(global, "translation", {});
  const size_t        n = std::max({ scale.size(), translation.size(), globalScale.size(), unitScale.size() });
  scale.resize(n, 1.0);
  translation.resize(n, 0.0);
  globalScale.resize(n, 1.0);
  globalTranslation.resize(n, 0.0);
  unitScale.resize(n, 1.0);
  for (size_t a = 0; a < n; ++a)
  {
    translation[a] = (globalScale[a] * translation[a] + globalTranslation[a]) * unitScale[a];
    scale[a] = globalScale[a] * scale[a] * unitScale[a];
  }
}

void
ZarrImageIO::ReadArrayMetadata()
{
  const fs::path array(m_ArrayPath);
  Json           meta;
  if (!ReadJson(array / ".zarray", meta) || !meta.is_object())
  {
    itkExceptionMacro(<< "cannot read the Zarr array metadata " << (array / ".zarray").string());
  }
  try
  {
    if (meta.value("zarr_format", 0) != 2)
    {
      itkExceptionMacro(<< m_ArrayPath << ": only Zarr format 2 is read (zarr_format " << meta.value("zarr_format", 0)
                        << ")");
    }
    m_Shape = meta.at("shape").get<std::vector<SizeValueType>>();
    m_Chunks = meta.at("chunks").get<std::vector<SizeValueType>>();
    if (m_Shape.size() != m_Chunks.size() || m_Shape.size() < 2)
    {
      itkExceptionMacro(<< m_ArrayPath << ": shape and chunks must have the same length, at least 2");
    }
    if (meta.value("order", "C") != "C")
    {
      itkExceptionMacro(<< m_ArrayPath << ": Fortran-ordered arrays are not read");
    }
    if (meta.contains("filters") && !meta["filters"].is_null() && !meta["filters"].empty())
    {
      itkExceptionMacro(<< m_ArrayPath << ": arrays with filters are not read");
    }
    m_Separator = meta.value("dimension_separator", ".");
    if (m_Separator != "." && m_Separator != "/")
    {
      itkExceptionMacro(<< m_ArrayPath << ": unknown dimension_separator \"" << m_Separator << "\"");
    }
    const Json &      compressor = meta.value("compressor", Json());
    const std::string codec = compressor.is_object() ? compressor.value("id", "") : "";
    if (compressor.is_null())
    {
      m_Codec = Codec::None;
    }
    else if (codec == "blosc")
    {
      m_Codec = Codec::Blosc;
    }
    else if (codec == "zlib" || codec == "gzip")
    {
      m_Codec = Codec::Zlib;
    }
    else
    {
      itkExceptionMacro(<< m_ArrayPath << ": compressor \"" << codec << "\" is not read (blosc, zlib, gzip or none)");
    }
    const std::string dtype = meta.at("dtype").get<std::string>();
    if (dtype.size() < 3 || (dtype[0] != '<' && dtype[0] != '|' && !(dtype[0] == '>' && dtype.substr(1) == "u1") &&
                             !(dtype[0] == '>' && dtype.substr(1) == "i1")))
    {
      itkExceptionMacro(<< m_ArrayPath << ": data type \"" << dtype << "\" is not read (little-endian only)");
    }
    static const std::map<std::string, IOComponentEnum> types = {
      { "u1", IOComponentEnum::UCHAR }, { "i1", IOComponentEnum::CHAR },  { "u2", IOComponentEnum::USHORT },
      { "i2", IOComponentEnum::SHORT }, { "u4", IOComponentEnum::UINT },  { "i4", IOComponentEnum::INT },
      { "f4", IOComponentEnum::FLOAT }, { "f8", IOComponentEnum::DOUBLE }
    };
    const auto type = types.find(dtype.substr(1));
    if (type == types.end())
    {
      itkExceptionMacro(<< m_ArrayPath << ": data type \"" << dtype << "\" is not read");
    }
    this->SetComponentType(type->second);
    // The fill value of absent chunks, converted to the stored type.
    m_FillValue = FillValueBytes(meta.value("fill_value", Json()), this->GetComponentType(), this->GetComponentSize());
  }
  catch (const Json::exception & e)
  {
    itkExceptionMacro(<< m_ArrayPath << ": malformed .zarray (" << e.what() << ")");
  }
}

void
ZarrImageIO::SetAxes(const std::vector<double> & scale, const std::vector<double> & translation)
{
  // Leading axes (time, channel) of length 1 are dropped; the rest become ITK's axes in
  // reverse order (Zarr's last axis varies fastest, as ITK's first).
  const size_t total = m_Shape.size();
  const size_t spatial = std::min<size_t>(3, total);
  m_LeadingAxes = static_cast<unsigned int>(total - spatial);
  for (size_t a = 0; a < m_LeadingAxes; ++a)
  {
    if (m_Shape[a] != 1)
    {
      itkExceptionMacro(<< m_ArrayPath << ": " << total << "-dimensional array with " << m_Shape[a]
                        << " entries along axis " << a << ": only volumes (leading axes of length 1) are read");
    }
  }
  for (size_t a = 0; a < total; ++a)
  {
    if (m_Shape[a] == 0 || m_Chunks[a] == 0)
    {
      itkExceptionMacro(<< m_ArrayPath << ": empty shape or chunk along axis " << a);
    }
  }
  this->SetNumberOfDimensions(static_cast<unsigned int>(spatial));
  for (unsigned int d = 0; d < spatial; ++d)
  {
    const size_t a = total - 1 - d;
    this->SetDimensions(d, m_Shape[a]);
    const double s = a < scale.size() ? scale[a] : 1.0;
    if (!(s > 0.0) || !std::isfinite(s))
    {
      itkExceptionMacro(<< m_FileName << ": OME-Zarr scale " << s << " along axis " << a << " is not positive");
    }
    this->SetSpacing(d, s);
    this->SetOrigin(d, a < translation.size() ? translation[a] : 0.0);
    std::vector<double> axis(spatial, 0.0);
    axis[d] = 1.0;
    this->SetDirection(d, axis);
  }
}

ImageIORegion
ZarrImageIO::GenerateStreamableReadRegionFromRequestedRegion(const ImageIORegion & requested) const
{
  const unsigned int n = this->GetNumberOfDimensions();
  ImageIORegion      region(n);
  for (unsigned int d = 0; d < n; ++d)
  {
    const bool inside = m_UseStreamedReading && d < requested.GetImageDimension();
    region.SetIndex(d, inside ? requested.GetIndex(d) : 0);
    region.SetSize(d, inside ? requested.GetSize(d) : this->GetDimensions(d));
  }
  return region;
}

std::string
ZarrImageIO::ChunkKey(const std::vector<SizeValueType> & chunkIndex) const
{
  std::string key;
  for (size_t a = 0; a < chunkIndex.size(); ++a)
  {
    key += (a > 0 ? m_Separator : std::string()) + std::to_string(chunkIndex[a]);
  }
  return key;
}

void
ZarrImageIO::ReadChunk(const std::vector<SizeValueType> & chunkIndex, std::vector<char> & data) const
{
  const size_t  component = this->GetComponentSize();
  SizeValueType elements = 1;
  for (SizeValueType c : m_Chunks)
  {
    elements *= c;
  }
  const size_t   bytes = elements * component;
  const fs::path file = fs::path(m_ArrayPath) / this->ChunkKey(chunkIndex);
  data.resize(bytes);
  std::ifstream in(file, std::ios::binary);
  if (!in)
  {
    // An absent chunk holds the fill value everywhere.
    for (size_t i = 0; i < elements; ++i)
    {
      std::memcpy(data.data() + i * component, m_FillValue.data(), component);
    }
    return;
  }
  std::vector<char> stored((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto              refuse = [&](const std::string & why) {
    itkExceptionMacro(<< "cannot read the Zarr chunk " << file.string() << ": " << why);
  };
  switch (m_Codec)
  {
    case Codec::None:
      if (stored.size() != bytes)
      {
        refuse("it holds " + std::to_string(stored.size()) + " bytes, the chunk needs " + std::to_string(bytes));
      }
      data.swap(stored);
      break;
    case Codec::Blosc:
    {
      size_t decompressed = 0, compressed = 0, block = 0;
      if (stored.size() < BLOSC_MIN_HEADER_LENGTH)
      {
        refuse("too short for a blosc header");
      }
      blosc_cbuffer_sizes(stored.data(), &decompressed, &compressed, &block);
      if (decompressed != bytes || compressed > stored.size())
      {
        refuse("blosc header gives " + std::to_string(decompressed) + " bytes, the chunk needs " +
               std::to_string(bytes));
      }
      const int n = blosc_decompress_ctx(stored.data(), data.data(), data.size(), 1);
      if (n < 0 || static_cast<size_t>(n) != bytes)
      {
        refuse("blosc decompression failed");
      }
      break;
    }
    case Codec::Zlib:
    {
      z_stream stream{};
      // 15 window bits + 32: a zlib or a gzip header, detected.
      if (inflateInit2(&stream, 15 + 32) != Z_OK)
      {
        refuse("zlib could not start");
      }
      stream.next_in = reinterpret_cast<Bytef *>(stored.data());
      stream.avail_in = static_cast<uInt>(stored.size());
      stream.next_out = reinterpret_cast<Bytef *>(data.data());
      stream.avail_out = static_cast<uInt>(data.size());
      const int  status = inflate(&stream, Z_FINISH);
      const auto produced = static_cast<size_t>(stream.total_out);
      inflateEnd(&stream);
      if (status != Z_STREAM_END || produced != bytes)
      {
        refuse("it does not inflate to the chunk's " + std::to_string(bytes) + " bytes");
      }
      break;
    }
  }
}

template <typename TVisit>
void
ZarrImageIO::ForEachChunkInRegion(TVisit visit) const
{
  const unsigned int spatial = this->GetNumberOfDimensions();
  const size_t       total = m_Shape.size();
  const size_t       component = this->GetComponentSize();
  // The region along each Zarr axis [first, end), and the chunks it touches.
  std::vector<SizeValueType> first(total, 0), end(total, 1), chunkFirst(total, 0), chunkEnd(total, 1);
  for (unsigned int d = 0; d < spatial; ++d)
  {
    const size_t a = total - 1 - d;
    first[a] = static_cast<SizeValueType>(m_IORegion.GetIndex(d));
    end[a] = first[a] + m_IORegion.GetSize(d);
    if (end[a] > m_Shape[a] || end[a] <= first[a])
    {
      itkExceptionMacro(<< m_ArrayPath << ": the region lies outside the array");
    }
    chunkFirst[a] = first[a] / m_Chunks[a];
    chunkEnd[a] = (end[a] - 1) / m_Chunks[a] + 1;
  }
  // Strides of the buffer (ITK order: x fastest) and of a chunk along each Zarr axis.
  std::vector<SizeValueType> bufferStride(total, 0), chunkStride(total, 1);
  SizeValueType              stride = 1;
  for (unsigned int d = 0; d < spatial; ++d)
  {
    bufferStride[total - 1 - d] = stride;
    stride *= m_IORegion.GetSize(d);
  }
  for (size_t a = total - 1; a-- > 0;)
  {
    chunkStride[a] = chunkStride[a + 1] * m_Chunks[a + 1];
  }
  const size_t               last = total - 1;
  std::vector<SizeValueType> chunk(chunkFirst);
  std::vector<ChunkRun>      runs;
  for (;;)
  {
    // The part of this chunk inside the region, as runs along the last axis; whether it
    // is all of the chunk's part inside the array.
    std::vector<SizeValueType> low(total), high(total);
    bool                       covered = true;
    for (size_t a = 0; a < total; ++a)
    {
      low[a] = std::max(first[a], chunk[a] * m_Chunks[a]);
      high[a] = std::min(end[a], (chunk[a] + 1) * m_Chunks[a]);
      covered =
        covered && low[a] == chunk[a] * m_Chunks[a] && high[a] == std::min(m_Shape[a], (chunk[a] + 1) * m_Chunks[a]);
    }
    runs.clear();
    std::vector<SizeValueType> at(low);
    for (;;)
    {
      SizeValueType inChunk = 0, inBuffer = 0;
      for (size_t a = 0; a < total; ++a)
      {
        inChunk += (at[a] - chunk[a] * m_Chunks[a]) * chunkStride[a];
        inBuffer += (at[a] - first[a]) * bufferStride[a];
      }
      runs.push_back({ inChunk * component, inBuffer * component, (high[last] - low[last]) * component });
      size_t a = last;
      while (a-- > 0)
      {
        if (++at[a] < high[a])
        {
          break;
        }
        at[a] = low[a];
      }
      if (a == static_cast<size_t>(-1))
      {
        break;
      }
    }
    visit(chunk, runs, covered);
    size_t a = total;
    while (a-- > 0)
    {
      if (++chunk[a] < chunkEnd[a])
      {
        break;
      }
      chunk[a] = chunkFirst[a];
    }
    if (a == static_cast<size_t>(-1))
    {
      break;
    }
  }
}

void
ZarrImageIO::Read(void * buffer)
{
  m_NumberOfChunksRead = 0;
  auto *            out = static_cast<char *>(buffer);
  std::vector<char> data;
  this->ForEachChunkInRegion([&](const std::vector<SizeValueType> & chunk, const std::vector<ChunkRun> & runs, bool) {
    this->ReadChunk(chunk, data);
    ++m_NumberOfChunksRead;
    for (const ChunkRun & run : runs)
    {
      std::memcpy(out + run.Buffer, data.data() + run.Chunk, run.Bytes);
    }
  });
}

bool
ZarrImageIO::CanWriteFile(const char * fileName)
{
  const std::string name(fileName);
  return name.size() > 5 && name.compare(name.size() - 5, 5, ".zarr") == 0;
}

void
ZarrImageIO::PrepareStore()
{
  const unsigned int n = this->GetNumberOfDimensions();
  if (n < 2 || n > 3 || this->GetNumberOfComponents() != 1)
  {
    itkExceptionMacro(<< "ZarrImageIO writes 2D or 3D scalar images, not " << n << "D with "
                      << this->GetNumberOfComponents() << " components");
  }
  for (unsigned int d = 0; d < n; ++d)
  {
    for (unsigned int e = 0; e < n; ++e)
    {
      if (std::abs(this->GetDirection(d)[e] - (d == e ? 1.0 : 0.0)) > 1e-9)
      {
        itkExceptionMacro(<< m_FileName << ": OME-Zarr stores no rotation; the image's direction must be the identity");
      }
    }
  }
  static const std::map<IOComponentEnum, std::string> types = {
    { IOComponentEnum::UCHAR, "|u1" }, { IOComponentEnum::CHAR, "|i1" },  { IOComponentEnum::USHORT, "<u2" },
    { IOComponentEnum::SHORT, "<i2" }, { IOComponentEnum::UINT, "<u4" },  { IOComponentEnum::INT, "<i4" },
    { IOComponentEnum::FLOAT, "<f4" }, { IOComponentEnum::DOUBLE, "<f8" }
  };
  const auto type = types.find(this->GetComponentType());
  if (type == types.end())
  {
    itkExceptionMacro(<< "ZarrImageIO does not write "
                      << ImageIOBase::GetComponentTypeAsString(this->GetComponentType()) << " voxels");
  }
  m_Shape.assign(n, 0);
  m_Chunks.assign(n, 0);
  std::vector<double> scale(n), translation(n);
  for (unsigned int d = 0; d < n; ++d)
  {
    const size_t a = n - 1 - d;
    m_Shape[a] = this->GetDimensions(d);
    m_Chunks[a] = std::min<SizeValueType>(m_ChunkEdge, m_Shape[a]);
    scale[a] = this->GetSpacing(d);
    translation[a] = this->GetOrigin(d);
  }
  m_LeadingAxes = 0;
  m_Separator = ".";
  m_Codec = this->GetUseCompression() ? Codec::Blosc : Codec::None;
  m_FillValue.assign(this->GetComponentSize(), 0);
  const fs::path root(m_FileName);
  m_ArrayPath = (root / "0").string();
  m_HasGeometry = true;

  Json array = { { "zarr_format", 2 }, { "shape", m_Shape }, { "chunks", m_Chunks }, { "dtype", type->second },
                 { "fill_value", 0 },  { "order", "C" },     { "filters", nullptr }, { "dimension_separator", "." } };
  array["compressor"] =
    m_Codec == Codec::Blosc
      ? Json{ { "id", "blosc" }, { "cname", "zstd" }, { "clevel", 3 }, { "shuffle", 1 }, { "blocksize", 0 } }
      : Json(nullptr);
  Json axes = Json::array();
  for (size_t a = 0; a < n; ++a)
  {
    axes.push_back({ { "name", std::string(1, "zyx"[3 - n + a]) }, { "type", "space" }, { "unit", "millimeter" } });
  }
  Json attributes;
  attributes["multiscales"] = Json::array(
    { { { "version", "0.4" },
        { "axes", axes },
        { "datasets",
          Json::array(
            { { { "path", "0" },
                { "coordinateTransformations",
                  Json::array({ { { "type", "scale" }, { "scale", scale } },
                                { { "type", "translation" }, { "translation", translation } } }) } } }) } } });
  auto writeJson = [&](const fs::path & file, const Json & json) {
    const fs::path partial = file.string() + ".partial";
    std::ofstream(partial) << json.dump(1) << "\n";
    fs::rename(partial, file);
  };
  // A store that already holds this array (an earlier region of the same image) is
  // continued, its geometry written again; another store at the path is replaced;
  // anything else there is refused.
  Json existing;
  if (fs::is_regular_file(root / "0" / ".zarray") && ReadJson(root / "0" / ".zarray", existing) && existing == array)
  {
    writeJson(root / ".zattrs", attributes);
    return;
  }
  std::error_code error;
  if (fs::exists(root, error))
  {
    const bool store = fs::is_directory(root) && (fs::exists(root / ".zgroup") || fs::exists(root / ".zarray"));
    if (!store && !(fs::is_directory(root) && fs::is_empty(root)))
    {
      itkExceptionMacro(<< m_FileName << " exists and is not a Zarr store: not overwritten");
    }
    fs::remove_all(root);
  }
  fs::create_directories(root / "0");
  writeJson(root / ".zgroup", { { "zarr_format", 2 } });
  writeJson(root / ".zattrs", attributes);
  writeJson(root / "0" / ".zarray", array);
}

void
ZarrImageIO::WriteChunk(const std::vector<SizeValueType> & chunkIndex, const std::vector<char> & data) const
{
  const fs::path    file = fs::path(m_ArrayPath) / this->ChunkKey(chunkIndex);
  std::vector<char> stored;
  if (m_Codec == Codec::Blosc)
  {
    stored.resize(data.size() + BLOSC_MAX_OVERHEAD);
    const int bytes = blosc_compress_ctx(
      3, BLOSC_SHUFFLE, this->GetComponentSize(), data.size(), data.data(), stored.data(), stored.size(), "zstd", 0, 1);
    if (bytes <= 0)
    {
      itkExceptionMacro(<< "blosc could not compress the chunk " << file.string());
    }
    stored.resize(static_cast<size_t>(bytes));
  }
  const std::vector<char> & out = m_Codec == Codec::Blosc ? stored : data;
  const fs::path            partial = file.string() + ".partial";
  {
    std::ofstream stream(partial, std::ios::binary);
    stream.write(out.data(), static_cast<std::streamsize>(out.size()));
    if (!stream)
    {
      itkExceptionMacro(<< "cannot write the chunk " << partial.string());
    }
  }
  fs::rename(partial, file);
}

void
ZarrImageIO::Write(const void * buffer)
{
  this->PrepareStore();
  const auto *      in = static_cast<const char *>(buffer);
  std::vector<char> data;
  this->ForEachChunkInRegion(
    [&](const std::vector<SizeValueType> & chunk, const std::vector<ChunkRun> & runs, bool covered) {
      if (covered)
      {
        data.assign(
          this->GetComponentSize() *
            std::accumulate(m_Chunks.begin(), m_Chunks.end(), SizeValueType{ 1 }, std::multiplies<SizeValueType>()),
          0);
      }
      else
      {
        this->ReadChunk(chunk, data); // the parts other regions wrote, or the fill value
      }
      for (const ChunkRun & run : runs)
      {
        std::memcpy(data.data() + run.Chunk, in + run.Buffer, run.Bytes);
      }
      this->WriteChunk(chunk, data);
    });
}

void
ZarrImageIO::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "ArrayPath: " << m_ArrayPath << std::endl;
  os << indent << "HasGeometry: " << m_HasGeometry << std::endl;
  os << indent << "NumberOfChunksRead: " << m_NumberOfChunksRead << std::endl;
}

ZarrImageIOFactory::ZarrImageIOFactory()
{
  this->RegisterOverride(
    "itkImageIOBase", "itkZarrImageIO", "Zarr v2 / OME-Zarr image IO", true, CreateObjectFunction<ZarrImageIO>::New());
}

const char *
ZarrImageIOFactory::GetITKSourceVersion() const
{
  return ITK_SOURCE_VERSION;
}

const char *
ZarrImageIOFactory::GetDescription() const
{
  return "Zarr v2 / OME-Zarr image IO";
}
} // namespace itk

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
// TIFF stack discovery of the CT reader: a folder of files whose names the fuzzer
// chooses, found by listing the folder or by a glob pattern it chooses too, one of them
// with the fuzzer's bytes, the others a valid 8 x 6 slice, then read as `unwrap` reads a
// stack (natural order of names, slice sizes and types checked, voxels stacked).
//
// Input: one byte (even: the folder, odd: a pattern), then lines up to a NUL byte (with a
// pattern, its first line is the pattern; the others name files, at most 8, '/' made
// '_'), then the bytes of the first file.
#include "vuFuzzCommon.h"

#include "itkImageFileWriter.h"

#include <algorithm>
#include <exception>
#include <vector>

namespace {
// A valid TIFF slice, made once.
const std::vector<char> &
ValidSlice()
{
  static const std::vector<char> bytes = [] {
    using SliceType = itk::Image<unsigned short, 2>;
    auto                slice = SliceType::New();
    SliceType::SizeType size = { { 8, 6 } };
    slice->SetRegions(size);
    slice->Allocate();
    unsigned short value = 0;
    for (auto * p = slice->GetBufferPointer(); p != slice->GetBufferPointer() + 48; ++p)
    {
      *p = value += 997;
    }
    const std::filesystem::path path = vu::fuzz::ScratchFolder() / "valid.tif";
    itk::WriteImage(slice, path.string());
    std::ifstream in(path, std::ios::binary);
    return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }();
  return bytes;
}

std::string
SafeName(std::string name)
{
  std::replace(name.begin(), name.end(), '/', '_');
  if (name.size() > 64)
  {
    name.resize(64);
  }
  return name;
}
} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const uint8_t * data, size_t size)
{
  using namespace vu::fuzz;
  Quiet();
  if (size < 1)
  {
    return 0;
  }
  const std::vector<char> & valid = ValidSlice();
  const bool                glob = (data[0] & 1) != 0;
  const uint8_t *           end = std::find(data + 1, data + size, uint8_t(0));
  std::vector<std::string>  lines;
  std::string               line;
  for (const uint8_t * p = data + 1; p != end; ++p)
  {
    if (*p == '\n')
    {
      lines.push_back(line);
      line.clear();
    }
    else
    {
      line.push_back(static_cast<char>(*p));
    }
  }
  lines.push_back(line);
  std::string pattern;
  if (glob)
  {
    pattern = SafeName(lines.front());
    lines.erase(lines.begin());
  }
  const std::filesystem::path folder = FreshFolder("stack");
  size_t                      files = 0;
  for (const std::string & name : lines)
  {
    const std::string safe = SafeName(name);
    if (safe.empty() || safe == "." || safe == ".." || files == 8)
    {
      continue;
    }
    if (files == 0)
    {
      const uint8_t * first = end == data + size ? end : end + 1;
      WriteFile(folder / safe, first, static_cast<size_t>(data + size - first));
    }
    else
    {
      WriteFile(folder / safe, reinterpret_cast<const uint8_t *>(valid.data()), valid.size());
    }
    ++files;
  }
  ReadVolume(glob ? (folder / pattern).string() : folder.string());
  return 0;
}

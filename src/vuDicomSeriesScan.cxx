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
#include "vuDicomSeriesScan.h"
#include "vuCTInputFiles.h"
#include "vuIsolatedParse.h"

#include "gdcmScanner.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>

namespace itk {
namespace detail {
namespace {
const gdcm::Tag kSeriesUID(0x0020, 0x000e);
const gdcm::Tag kSeriesNumber(0x0020, 0x0011);
const gdcm::Tag kSeriesDescription(0x0008, 0x103e);
const gdcm::Tag kModality(0x0008, 0x0060);
const gdcm::Tag kPosition(0x0020, 0x0032);
const gdcm::Tag kOrientation(0x0020, 0x0037);
const gdcm::Tag kRows(0x0028, 0x0010);
const gdcm::Tag kColumns(0x0028, 0x0011);
const gdcm::Tag kPixelSpacing(0x0028, 0x0030);
const gdcm::Tag kNumberOfFrames(0x0028, 0x0008);
const gdcm::Tag kRescaleIntercept(0x0028, 0x1052);
const gdcm::Tag kRescaleSlope(0x0028, 0x1053);
const gdcm::Tag kBitsAllocated(0x0028, 0x0100);
const gdcm::Tag kPixelRepresentation(0x0028, 0x0103);
const gdcm::Tag kGantryTilt(0x0018, 0x1120);
const gdcm::Tag kFrameIncrementPointer(0x0028, 0x0009);
const gdcm::Tag kSamplesPerPixel(0x0028, 0x0002);
} // namespace

namespace {
const gdcm::Tag  kScannedTags[] = { kSeriesUID,
                                    kSeriesNumber,
                                    kSeriesDescription,
                                    kModality,
                                    kPosition,
                                    kOrientation,
                                    kRows,
                                    kColumns,
                                    kPixelSpacing,
                                    kNumberOfFrames,
                                    kRescaleIntercept,
                                    kRescaleSlope,
                                    kBitsAllocated,
                                    kPixelRepresentation,
                                    kGantryTilt,
                                    kFrameIncrementPointer,
                                    kSamplesPerPixel };
constexpr size_t kScannedTagCount = sizeof(kScannedTags) / sizeof(kScannedTags[0]);

// One file's header as the child process sends it: "D" for a DICOMDIR, "N" for a file
// that is not DICOM, or "S" and the values of kScannedTags, each after its length.
std::string
ScanOneFile(const std::string & file)
{
  QuietGdcm quiet;
  if (IsDicomDirectoryFile(file))
  {
    return "D";
  }
  gdcm::Scanner scanner;
  for (const gdcm::Tag & tag : kScannedTags)
  {
    scanner.AddTag(tag);
  }
  scanner.Scan({ file });
  if (!scanner.IsKey(file.c_str()))
  {
    return "N";
  }
  std::string record = "S";
  for (const gdcm::Tag & tag : kScannedTags)
  {
    const char *      value = scanner.GetValue(file.c_str(), tag);
    const std::string text = value != nullptr ? value : "";
    const uint32_t    length = static_cast<uint32_t>(text.size());
    record.append(reinterpret_cast<const char *>(&length), sizeof(length));
    record += text;
  }
  return record;
}

// The values of a record of ScanOneFile, or none when it is not an image's record.
std::vector<std::string>
RecordValues(const std::string & record)
{
  std::vector<std::string> values;
  if (record.empty() || record[0] != 'S')
  {
    return values;
  }
  size_t at = 1;
  while (values.size() < kScannedTagCount && at + sizeof(uint32_t) <= record.size())
  {
    uint32_t length = 0;
    std::copy_n(record.data() + at, sizeof(length), reinterpret_cast<char *>(&length));
    at += sizeof(length);
    if (length > record.size() - at)
    {
      return {};
    }
    values.push_back(record.substr(at, length));
    at += length;
  }
  return values.size() == kScannedTagCount ? values : std::vector<std::string>{};
}
} // namespace

DicomScan
ScanDicomFiles(const std::vector<std::string> & files)
{
  // GDCM's scanner aborts the process on some damaged headers: the files are scanned in a
  // child process, which starts again after the file it died on.
  DicomScan                scan;
  std::vector<std::string> records;
  for (size_t next = 0; next < files.size();)
  {
    const std::vector<std::string> rest(files.begin() + static_cast<std::ptrdiff_t>(next), files.end());
    IsolatedParse                  run = ParseInChildProcess(rest, ScanOneFile);
    records.insert(records.end(), run.Results.begin(), run.Results.end());
    next += run.Results.size();
    if (!run.FailedFile.empty())
    {
      ++scan.DicomFiles;
      scan.Damaged.push_back(run.FailedFile + " (the DICOM parser " + run.Failure + " on it)");
      records.emplace_back();
      ++next;
    }
  }
  for (size_t i = 0; i < files.size(); ++i)
  {
    if (records[i] == "D")
    {
      ++scan.DicomFiles;
      continue;
    }
    const std::vector<std::string> v = RecordValues(records[i]);
    if (v.empty())
    {
      continue;
    }
    ++scan.DicomFiles;
    auto value = [&v](const gdcm::Tag & tag) {
      const size_t k = static_cast<size_t>(std::find(std::begin(kScannedTags), std::end(kScannedTags), tag) -
                                           std::begin(kScannedTags));
      return Trim(v[k].c_str());
    };
    DicomSlice s;
    s.File = files[i];
    s.Rows = value(kRows);
    s.Columns = value(kColumns);
    if (s.Rows.empty() || s.Columns.empty())
    {
      continue;
    }
    s.SeriesUID = value(kSeriesUID);
    s.SeriesNumber = value(kSeriesNumber);
    s.SeriesDescription = value(kSeriesDescription);
    s.Modality = value(kModality);
    s.Position = ParseDecimals(value(kPosition));
    s.Orientation = ParseDecimals(value(kOrientation));
    s.PixelSpacing = ParseDecimals(value(kPixelSpacing));
    const double frames = ParseDecimal(value(kNumberOfFrames), 1.0);
    s.Frames = frames >= 1.0 ? static_cast<SizeValueType>(frames) : SizeValueType{ 1 };
    s.Slope = ParseDecimal(value(kRescaleSlope), 1.0);
    s.Intercept = ParseDecimal(value(kRescaleIntercept), 0.0);
    s.BitsAllocated = ParseDecimal(value(kBitsAllocated), 16.0);
    s.Signed = value(kPixelRepresentation) == "1";
    s.SamplesPerPixel = ParseDecimal(value(kSamplesPerPixel), 1.0);
    for (const char c : value(kFrameIncrementPointer))
    {
      if (std::isxdigit(static_cast<unsigned char>(c)))
      {
        s.FrameIncrementPointer += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      }
    }
    s.GantryTilt = value(kGantryTilt);
    scan.Series[s.SeriesUID].push_back(s);
  }
  return scan;
}

std::string
MakeSliceStack(const std::vector<DicomSlice> & slices, DicomSliceStack & stack)
{
  for (const DicomSlice & s : slices)
  {
    if (s.Position.size() != 3 || s.Orientation.size() != 6)
    {
      return s.File + " has no valid ImagePositionPatient/ImageOrientationPatient: the slices cannot be ordered";
    }
  }
  const DicomSlice & first = slices.front();
  for (const DicomSlice & s : slices)
  {
    if (s.Rows != first.Rows || s.Columns != first.Columns)
    {
      return "mixed image sizes in one series: " + first.File + " is " + first.Columns + "x" + first.Rows + ", " +
             s.File + " is " + s.Columns + "x" + s.Rows;
    }
    for (unsigned k = 0; k < 6; ++k)
    {
      if (std::abs(s.Orientation[k] - first.Orientation[k]) > 1e-4)
      {
        return "mixed orientations in one series: " + first.File + " and " + s.File +
               " have different ImageOrientationPatient";
      }
    }
    if (s.PixelSpacing.size() != first.PixelSpacing.size() ||
        (s.PixelSpacing.size() == 2 &&
         (std::abs(s.PixelSpacing[0] - first.PixelSpacing[0]) > 1e-4 * first.PixelSpacing[0] ||
          std::abs(s.PixelSpacing[1] - first.PixelSpacing[1]) > 1e-4 * first.PixelSpacing[1])))
    {
      return "mixed pixel spacing in one series: " + first.File + " and " + s.File;
    }
  }
  for (unsigned k = 0; k < 3; ++k)
  {
    stack.Row[k] = first.Orientation[k];
    stack.Column[k] = first.Orientation[k + 3];
  }
  // DICOM PixelSpacing is (between rows, between columns), that is (y, x).
  const bool hasSpacing = first.PixelSpacing.size() == 2 && first.PixelSpacing[0] > 0.0 && first.PixelSpacing[1] > 0.0;
  stack.PixelSpacing[0] = hasSpacing ? first.PixelSpacing[1] : 1.0;
  stack.PixelSpacing[1] = hasSpacing ? first.PixelSpacing[0] : 1.0;
  stack.Size[0] = static_cast<SizeValueType>(ParseDecimal(first.Columns, 0.0));
  stack.Size[1] = static_cast<SizeValueType>(ParseDecimal(first.Rows, 0.0));
  for (const DicomSlice & s : slices)
  {
    stack.Slices.push_back({ s.File, Image<float, 3>::PointType(s.Position.data()) });
  }
  return {};
}

} // namespace detail
} // namespace itk

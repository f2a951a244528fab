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

#include "gdcmScanner.h"

#include <cctype>
#include <cmath>

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

DicomScan
ScanDicomFiles(const std::vector<std::string> & files)
{
  DicomScan                scan;
  std::vector<std::string> candidates;
  for (const std::string & f : files)
  {
    if (IsDicomDirectoryFile(f))
    {
      ++scan.DicomFiles;
    }
    else
    {
      candidates.push_back(f);
    }
  }
  gdcm::Scanner scanner;
  for (const gdcm::Tag & tag : { kSeriesUID,
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
                                 kSamplesPerPixel })
  {
    scanner.AddTag(tag);
  }
  scanner.Scan(candidates);
  for (const std::string & file : candidates)
  {
    const char * f = file.c_str();
    if (!scanner.IsKey(f))
    {
      continue;
    }
    ++scan.DicomFiles;
    DicomSlice s;
    s.File = file;
    s.Rows = Trim(scanner.GetValue(f, kRows));
    s.Columns = Trim(scanner.GetValue(f, kColumns));
    if (s.Rows.empty() || s.Columns.empty())
    {
      continue;
    }
    s.SeriesUID = Trim(scanner.GetValue(f, kSeriesUID));
    s.SeriesNumber = Trim(scanner.GetValue(f, kSeriesNumber));
    s.SeriesDescription = Trim(scanner.GetValue(f, kSeriesDescription));
    s.Modality = Trim(scanner.GetValue(f, kModality));
    s.Position = ParseDecimals(Trim(scanner.GetValue(f, kPosition)));
    s.Orientation = ParseDecimals(Trim(scanner.GetValue(f, kOrientation)));
    s.PixelSpacing = ParseDecimals(Trim(scanner.GetValue(f, kPixelSpacing)));
    const double frames = ParseDecimal(Trim(scanner.GetValue(f, kNumberOfFrames)), 1.0);
    s.Frames = frames >= 1.0 ? static_cast<SizeValueType>(frames) : SizeValueType{ 1 };
    s.Slope = ParseDecimal(Trim(scanner.GetValue(f, kRescaleSlope)), 1.0);
    s.Intercept = ParseDecimal(Trim(scanner.GetValue(f, kRescaleIntercept)), 0.0);
    s.BitsAllocated = ParseDecimal(Trim(scanner.GetValue(f, kBitsAllocated)), 16.0);
    s.Signed = Trim(scanner.GetValue(f, kPixelRepresentation)) == "1";
    s.SamplesPerPixel = ParseDecimal(Trim(scanner.GetValue(f, kSamplesPerPixel)), 1.0);
    for (const char c : Trim(scanner.GetValue(f, kFrameIncrementPointer)))
    {
      if (std::isxdigit(static_cast<unsigned char>(c)))
      {
        s.FrameIncrementPointer += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      }
    }
    s.GantryTilt = Trim(scanner.GetValue(f, kGantryTilt));
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

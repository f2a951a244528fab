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
#ifndef vuDicomSeriesScan_h
#define vuDicomSeriesScan_h

#include "itkDicomSeriesGeometry.h"

#include <map>
#include <string>
#include <vector>

namespace itk {
namespace detail {
/** Header facts of one DICOM image file, as the GDCM scanner finds them (text values
 * without their padding). */
struct DicomSlice
{
  std::string         File;
  std::string         SeriesUID;
  std::string         SeriesNumber;
  std::string         SeriesDescription;
  std::string         Modality;
  std::vector<double> Position;
  std::vector<double> Orientation;
  std::vector<double> PixelSpacing;
  std::string         Rows;
  std::string         Columns;
  SizeValueType       Frames{ 1 };
  double              Slope{ 1.0 };
  double              Intercept{ 0.0 };
  double              BitsAllocated{ 16.0 };
  bool                Signed{ false };
  double              SamplesPerPixel{ 1.0 };
  /** Frame Increment Pointer as 8 lower-case hex digits (e.g. "00181063", Frame Time). */
  std::string FrameIncrementPointer;
  /** GantryDetectorTilt as written, or "". */
  std::string GantryTilt;
};

/** The DICOM files among some files: how many there are (DICOMDIRs and objects without
 * pixels included) and the image files by SeriesInstanceUID. */
struct DicomScan
{
  size_t                                         DicomFiles{ 0 };
  std::map<std::string, std::vector<DicomSlice>> Series;
  /** Files on which the DICOM parser died, each with how, e.g. "a.dcm (the DICOM parser
   * aborted on it)". They are counted among the DICOM files. */
  std::vector<std::string> Damaged;
};

/** Scans the headers of files (DICOMDIRs are told apart from their file meta header
 * alone, before GDCM parses their data set) in a child process, so that a file on which
 * the parser aborts is only reported (ParseInChildProcess). */
DicomScan
ScanDicomFiles(const std::vector<std::string> & files);

/** The slices of one series as a stack to be measured (itk::DicomSeriesGeometry), or the
 * reason their headers cannot make one volume: no position or orientation, mixed image
 * sizes, orientations or pixel spacings. */
std::string
MakeSliceStack(const std::vector<DicomSlice> & slices, DicomSliceStack & stack);
} // namespace detail
} // namespace itk

#endif

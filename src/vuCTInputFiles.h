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
#ifndef vuCTInputFiles_h
#define vuCTInputFiles_h

#include "itkImageIOBase.h"
#include "itkMetaImageIO.h"

#include "gdcmTrace.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace itk {
namespace detail {
/** Facts about the files CTVolumeReader is given, found without reading their pixels: names,
 * formats, headers, DICOM values and truncation. */

/** Turns GDCM's own warnings and errors off while it works for the reader: it reports
 * every odd private tag on standard error, and the reader says itself, in one line, what
 * went wrong. */
class QuietGdcm
{
public:
  QuietGdcm()
    : m_Warning(gdcm::Trace::GetWarningFlag())
    , m_Error(gdcm::Trace::GetErrorFlag())
  {
    gdcm::Trace::WarningOff();
    gdcm::Trace::ErrorOff();
  }
  ~QuietGdcm()
  {
    gdcm::Trace::SetWarning(m_Warning);
    gdcm::Trace::SetError(m_Error);
  }
  QuietGdcm(const QuietGdcm &) = delete;
  QuietGdcm &
  operator=(const QuietGdcm &) = delete;

private:
  bool m_Warning;
  bool m_Error;
};
/** A DICOM text value without its padding (spaces, or the NUL of an odd-length UID). */
std::string
Trim(const char * text);

/** Backslash-separated decimal string (DICOM DS multi-value) to numbers; empty when any
 * part does not parse. */
std::vector<double>
ParseDecimals(const std::string & text);

/** One decimal (DICOM DS), or fallback when text is not exactly one finite number. */
double
ParseDecimal(const std::string & text, double fallback);

/** Orders file names as a person would: digit runs compare by value, so slice2 comes
 * before slice10 (slice numbers are seldom zero-padded to the same width). */
bool
NaturalLess(const std::string & a, const std::string & b);

/** .tif or .tiff, in any case. */
bool
HasTiffExtension(const std::filesystem::path & path);

/** Formats ITK reads that are never DICOM (a DICOM file may have any name or none). */
bool
HasNonDicomImageExtension(const std::filesystem::path & path);

/** "uint16", "int16", "float32"...: a stored pixel component type and its size in bytes. */
std::string
ComponentTypeName(IOComponentEnum type, size_t bytes);

/** "512x512x28": the size an image IO reports. */
std::string
SizeText(const ImageIOBase * io);

/** The most image bytes `bytes` of deflate (zlib, gzip) data can hold: about 1000 to 1 at
 * best, with room for a small image. */
inline double
DeflateCanHold(double bytes)
{
  return 1100.0 * bytes + 65536.0;
}

/** Why the text header of a MetaImage (.mha, .mhd) cannot be handed to MetaIO, or "":
 * NDims not a whole number from 1 to 10, DimSize not NDims positive whole numbers. */
std::string
MetaImageHeaderProblem(const std::string & file);

/** Why a TIFF file's directories cannot be handed to libtiff, or "" (also for a file
 * that is not a TIFF): a directory beyond the end of the file, or an entry that claims
 * more bytes than the file holds (libtiff allocates and clears them first). */
std::string
TiffDirectoryProblem(const std::string & file);

/** Reads the headers of image files first in a child process with limits
 * (ParseInChildProcess): for each file, "" when ReadImageHeader reads it there, or why not.
 * Throws, naming the file and how the child died, when a format's library aborts or never
 * ends on a header (libtiff's directory reading has done both); a header that asks for
 * more memory than the child may take fails there with an error instead, so the caller
 * must not read a file with an error again in its own process. */
std::vector<std::string>
ProbeHeaders(const std::vector<std::string> & files);

/** Reads the header of an image file (a MetaImage or a TIFF checked first), or says why
 * it cannot. */
ImageIOBase::Pointer
ReadImageHeader(const std::string & file);

/** Why a MetaImage cannot hold its voxels, or "": MetaIO reads a short uncompressed data
 * file without failing (it only prints a notice) and leaves the rest of the buffer as it
 * was, so the size of the data file is checked against the header. A compressed data file
 * is checked here only for its size; its stream is inflated and checked by
 * CheckedMetaImageIO as it is read. */
std::string
MetaImageTruncation(const std::string & file, ImageIOBase * io);

/** Why the compressed data of a MetaImage does not inflate to its image, or "" (also when
 * its data is not compressed): the whole stream is inflated into a small scratch buffer. */
std::string
MetaImageStreamProblem(const std::string & file, ImageIOBase * io);

/** MetaImageIO whose compressed voxels are inflated by zlib's own loop, which stops on a
 * damaged stream with an error naming the file (MetaIO's inflation loop never ends on some
 * damaged streams). A whole image is inflated straight into the output buffer, once; a
 * region of it is read by MetaIO after its stream was inflated here and found whole. */
class CheckedMetaImageIO : public MetaImageIO
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(CheckedMetaImageIO);
  using Self = CheckedMetaImageIO;
  using Superclass = MetaImageIO;
  using Pointer = SmartPointer<Self>;
  itkNewMacro(Self);
  itkTypeMacro(CheckedMetaImageIO, MetaImageIO);

  void
  Read(void * buffer) override;

protected:
  CheckedMetaImageIO() = default;
  ~CheckedMetaImageIO() override = default;
};

/** Why a NRRD file's data cannot hold the image its header describes, or "": NrrdIO
 * allocates the whole image its header claims before reading a byte of the data. */
std::string
NrrdTruncation(const std::string & file, ImageIOBase * io);

/** True for a DICOMDIR (a media directory, never an image). GDCM's full parse aborts on
 * some malformed DICOMDIR files (an assertion in its fallback reader), so they are told
 * apart from their file meta header alone, before the scanner reads their data set. */
bool
IsDicomDirectoryFile(const std::string & file);

/** Why DICOM image files cannot be read, or "": the first file on which GDCM's parser
 * aborts the process (Debian's GDCM keeps its assertions, and damaged headers trip them),
 * asks for far more memory or time than the file can justify (a length of gigabytes
 * claimed in a small file), does not find an image, or that is truncated
 * (TruncationProblem). The files are parsed in a child process with limits, so that only
 * the child fails (ParseInChildProcess). */
std::string
DicomFilesProblem(const std::vector<std::string> & files, uintmax_t pixelBytes);

/** Why a file cannot hold all its pixels, or "": the file must reach past the start of
 * its Pixel Data value by the size of the image. GDCM fills the missing part of a
 * truncated native (uncompressed) file silently, so this is checked from the header.
 * Compressed data has no known size and fails in its decoder instead. */
std::string
TruncationProblem(const std::string & file, uintmax_t pixelBytes);
} // namespace detail
} // namespace itk

#endif

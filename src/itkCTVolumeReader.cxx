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
#include "itkCTVolumeReader.h"
#include "vuCTInputFiles.h"
#include "vuDicomSeriesScan.h"

#include "itkBinShrinkImageFilter.h"
#include "itkChangeInformationImageFilter.h"
#include "itkExtractImageFilter.h"
#include "itkGDCMImageIO.h"
#include "itkImageFileReader.h"
#include "itkImageIOFactory.h"
#include "itkImageSeriesReader.h"
#include "itkProgressAccumulator.h"
#include "itksys/Glob.hxx"

#include "gdcmDirectory.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace itk {
namespace {
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

std::string
DescribeSeries(const CTVolumeReader::SeriesInfo & s)
{
  return "series " + (s.Number.empty() ? std::string("?") : s.Number) +
         (s.Description.empty() ? std::string() : " '" + s.Description + "'") + " (" + s.UID + ", " +
         std::to_string(s.NumberOfSlices) + " slices)";
}
} // namespace

void
CTVolumeReader::ResetFacts()
{
  m_InputKind.clear();
  m_Modality.clear();
  m_PixelType.clear();
  m_RescaleSlope = 1.0;
  m_RescaleIntercept = 0.0;
  m_FullSize.Fill(0);
  m_ChosenSeries = SeriesInfo();
  m_AlternativeSeries.clear();
  m_Warnings.clear();
  m_SliceFileNames.clear();
  m_SeriesGeometry = DicomSeriesGeometry();
  m_Resampled = false;
  m_ResampledGrid = RegularGrid();
  m_VoxelsWithoutData = 0;
  m_Pipeline.clear();
  m_PipelineOutput = nullptr;
  m_ReplaceGeometry = false;
  m_GeometryOrigin.Fill(0.0);
  m_GeometrySpacing.Fill(1.0);
  m_GeometryDirection.SetIdentity();
  m_IsDicom = false;
  m_DicomPixelBytes = 0;
  m_FirstSliceToRead = 0;
  m_EndSliceToRead = 0;
}

void
CTVolumeReader::GenerateOutputInformation()
{
  this->ResetFacts();
  const QuietGdcm quiet;
  if (m_FileName.empty())
  {
    Refuse("no input: the file name is empty");
  }
  if (m_OverrideSpacing)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      if (!(m_SpacingOverride[d] > 0.0) || !std::isfinite(m_SpacingOverride[d]))
      {
        Refuse("spacing must be positive and finite, got ", m_SpacingOverride);
      }
    }
  }
  if (m_UseRegionOfInterest && m_UsePhysicalRegionOfInterest)
  {
    Refuse("give a region of interest either in voxel indices or in physical coordinates, not both");
  }

  try
  {
    std::error_code error;
    const bool      exists = fs::exists(m_FileName, error);
    if (!exists && m_FileName.find_first_of("*?[") != std::string::npos)
    {
      itksys::Glob glob;
      glob.FindFiles(m_FileName);
      std::vector<std::string> files;
      for (const std::string & f : glob.GetFiles())
      {
        if (fs::is_regular_file(f, error))
        {
          files.push_back(f);
        }
      }
      if (files.empty())
      {
        throw std::runtime_error("no file matches " + m_FileName);
      }
      this->ExamineFiles(files, files);
    }
    else if (!exists)
    {
      throw std::runtime_error("no such file or directory: " + m_FileName);
    }
    else if (fs::is_directory(m_FileName, error))
    {
      std::vector<std::string> listed;
      for (const auto & entry : fs::directory_iterator(m_FileName))
      {
        if (entry.is_regular_file())
        {
          listed.push_back(entry.path().string());
        }
      }
      gdcm::Directory directory;
      directory.Load(m_FileName, true);
      if (directory.GetFilenames().empty())
      {
        throw std::runtime_error("directory is empty: " + m_FileName);
      }
      this->ExamineFiles(listed, directory.GetFilenames());
    }
    else if (HasNonDicomImageExtension(m_FileName) || !this->ExamineDicom({ m_FileName }, true))
    {
      this->ExamineVolumeFile(m_FileName);
    }
  }
  catch (const std::runtime_error & e)
  {
    Refuse(e.what());
  }
  this->BuildPipeline();
}

void
CTVolumeReader::ExamineFiles(const std::vector<std::string> & listed, const std::vector<std::string> & dicomSearch)
{
  // TIFF stacks hold thousands of large slices, and GDCM's parser can abort on foreign
  // binary data: files named as another image format never go to the DICOM scanner.
  std::vector<std::string> tiffs, images, dicomCandidates;
  for (const std::string & f : listed)
  {
    if (HasTiffExtension(f))
    {
      tiffs.push_back(f);
    }
    else if (HasNonDicomImageExtension(f))
    {
      images.push_back(f);
    }
  }
  for (const std::string & f : dicomSearch)
  {
    if (!HasNonDicomImageExtension(f))
    {
      dicomCandidates.push_back(f);
    }
  }
  if (!tiffs.empty())
  {
    images = tiffs;
  }
  else if (!dicomCandidates.empty() && this->ExamineDicom(dicomCandidates, false))
  {
    return;
  }
  else if (images.empty())
  {
    // Asking ITK's image formats whether they read a file hands it to libtiff and others:
    // they are asked in a child process, and a damaged TIFF is refused by name.
    const std::vector<std::string> problems = ProbeHeaders(listed);
    for (size_t i = 0; i < listed.size(); ++i)
    {
      const std::string tiffProblem = TiffDirectoryProblem(listed[i]);
      if (!tiffProblem.empty())
      {
        throw std::runtime_error(tiffProblem);
      }
      if (problems[i].empty())
      {
        images.push_back(listed[i]);
      }
    }
  }
  if (images.empty())
  {
    throw std::runtime_error("no DICOM, TIFF or other image files in " + m_FileName);
  }
  if (images.size() == 1)
  {
    this->ExamineVolumeFile(images.front());
  }
  else
  {
    this->ExamineSliceStack(images);
  }
}

bool
CTVolumeReader::ExamineDicom(const std::vector<std::string> & files, bool singleFile)
{
  DicomScan scan = ScanDicomFiles(files);
  if (scan.DicomFiles == 0)
  {
    return false;
  }
  if (scan.Series.empty() && !scan.Damaged.empty())
  {
    throw std::runtime_error(scan.Damaged.front() + ": it is damaged");
  }
  for (const std::string & damaged : scan.Damaged)
  {
    m_Warnings.push_back("skipped the damaged file " + damaged);
  }
  if (scan.Series.empty())
  {
    throw std::runtime_error(singleFile ? m_FileName + " is a DICOM file without an image (a DICOMDIR or another "
                                                       "non-image object)"
                                        : m_FileName + " holds " + std::to_string(scan.DicomFiles) +
                                            " DICOM file(s) but no image");
  }
  m_IsDicom = true;

  std::vector<SeriesInfo> series;
  for (const auto & [uid, seriesSlices] : scan.Series)
  {
    SeriesInfo info;
    info.UID = uid;
    info.Number = seriesSlices.front().SeriesNumber;
    info.Description = seriesSlices.front().SeriesDescription;
    info.Modality = seriesSlices.front().Modality;
    for (const DicomSlice & s : seriesSlices)
    {
      info.NumberOfSlices += s.Frames;
    }
    series.push_back(info);
  }
  std::stable_sort(series.begin(), series.end(), [](const SeriesInfo & a, const SeriesInfo & b) {
    return a.NumberOfSlices > b.NumberOfSlices;
  });
  auto listAll = [&series]() {
    std::string text;
    for (const SeriesInfo & s : series)
    {
      text += (text.empty() ? "" : "; ") + DescribeSeries(s);
    }
    return text;
  };

  size_t chosen = 0;
  if (!m_SeriesIdentifier.empty())
  {
    std::vector<size_t> matches;
    for (size_t i = 0; i < series.size(); ++i)
    {
      if (series[i].UID == m_SeriesIdentifier)
      {
        matches = { i };
        break;
      }
      if (series[i].Number == m_SeriesIdentifier)
      {
        matches.push_back(i);
      }
    }
    if (matches.empty())
    {
      throw std::runtime_error("no series '" + m_SeriesIdentifier + "' in " + m_FileName +
                               "; series found: " + listAll());
    }
    if (matches.size() > 1)
    {
      throw std::runtime_error("series number " + m_SeriesIdentifier + " is not unique in " + m_FileName +
                               ": choose by SeriesInstanceUID among " + listAll());
    }
    chosen = matches.front();
  }
  else if (series.size() > 1 && series[0].NumberOfSlices == series[1].NumberOfSlices)
  {
    throw std::runtime_error(m_FileName + " holds several series with " + std::to_string(series[0].NumberOfSlices) +
                             " slices; choose one by series number or SeriesInstanceUID: " + listAll());
  }
  m_ChosenSeries = series[chosen];
  for (size_t i = 0; i < series.size(); ++i)
  {
    if (i != chosen)
    {
      m_AlternativeSeries.push_back(series[i]);
    }
  }
  if (!m_AlternativeSeries.empty())
  {
    std::string others;
    for (const SeriesInfo & s : m_AlternativeSeries)
    {
      others += (others.empty() ? "" : "; ") + DescribeSeries(s);
    }
    m_Warnings.push_back("read " + DescribeSeries(m_ChosenSeries) + "; other series: " + others);
  }

  const std::vector<DicomSlice> & slices = scan.Series[m_ChosenSeries.UID];
  const DicomSlice &              first = slices.front();
  m_Modality = m_ChosenSeries.Modality;
  m_RescaleSlope = first.Slope;
  m_RescaleIntercept = first.Intercept;
  m_PixelType = (first.Signed ? "int" : "uint") + std::to_string(static_cast<int>(first.BitsAllocated));
  m_DicomPixelBytes =
    static_cast<uintmax_t>(ParseDecimal(first.Rows, 0.0) * ParseDecimal(first.Columns, 0.0) *
                           static_cast<double>(first.Frames) * first.SamplesPerPixel * first.BitsAllocated / 8.0);
  for (const DicomSlice & s : slices)
  {
    if (s.Slope != first.Slope || s.Intercept != first.Intercept)
    {
      m_Warnings.push_back("rescale slope/intercept differ between slices (" + first.File + ", " + s.File +
                           "): each slice is calibrated with its own");
      break;
    }
  }

  if (slices.size() == 1)
  {
    if (first.Frames < 2)
    {
      throw std::runtime_error(singleFile ? m_FileName + " is a single 2D image (" + first.Columns + "x" + first.Rows +
                                              "), not a volume; give the directory of its series"
                                          : DescribeSeries(m_ChosenSeries) + " has only one slice (" + first.File +
                                              "): a single 2D image is not a volume");
    }
    // Frames indexed by Frame Time (Vector) are a cine loop taken in one place, not slices.
    if (first.FrameIncrementPointer == "00181063" || first.FrameIncrementPointer == "00181065")
    {
      throw std::runtime_error(first.File + " holds " + std::to_string(first.Frames) +
                               " frames of a time series (Frame Increment Pointer is Frame Time), not a volume");
    }
    m_InputKind = "DICOM multi-frame file";
    if (first.PixelSpacing.empty())
    {
      m_Warnings.push_back(first.File + " has no top-level PixelSpacing: the spacing comes from its functional "
                                        "groups if any, else 1 mm");
    }
    m_SliceFileNames = { first.File };
    return true;
  }
  for (const DicomSlice & s : slices)
  {
    if (s.Frames > 1)
    {
      throw std::runtime_error(DescribeSeries(m_ChosenSeries) + " mixes " + std::to_string(slices.size()) +
                               " files of which " + s.File + " has several frames: read each multi-frame file alone");
    }
  }
  // GDCM ignores the position of some image kinds (secondary capture, ...): the checked
  // header geometry is given to the volume explicitly.
  DicomSliceStack   stack;
  const std::string problem = MakeSliceStack(slices, stack);
  if (!problem.empty())
  {
    throw std::runtime_error(DescribeSeries(m_ChosenSeries) + ": " + problem);
  }
  this->ExamineSliceGeometry(std::move(stack), first.GantryTilt);
  if (first.PixelSpacing.size() != 2)
  {
    m_Warnings.push_back(first.File + " has no PixelSpacing: 1 mm pixels assumed");
  }
  m_InputKind = "DICOM series";
  return true;
}

void
CTVolumeReader::ExamineSliceGeometry(DicomSliceStack stack, const std::string & gantryTilt)
{
  try
  {
    m_SeriesGeometry = AnalyseDicomSliceStack(std::move(stack), m_SliceSpacingTolerance);
  }
  catch (const ExceptionObject & e)
  {
    throw std::runtime_error(DescribeSeries(m_ChosenSeries) + ": " + e.GetDescription());
  }
  const DicomSeriesGeometry & geometry = m_SeriesGeometry;
  for (const DicomSliceStack::Slice & s : geometry.Stack.Slices)
  {
    m_SliceFileNames.push_back(s.File);
  }
  const std::string series = DescribeSeries(m_ChosenSeries) + ": ";
  if (geometry.IsRegular())
  {
    m_ReplaceGeometry = true;
    m_GeometrySpacing[0] = geometry.Stack.PixelSpacing[0];
    m_GeometrySpacing[1] = geometry.Stack.PixelSpacing[1];
    m_GeometrySpacing[2] = geometry.MeanSpacing;
    m_GeometryOrigin = geometry.Stack.Slices.front().Position;
    for (unsigned k = 0; k < 3; ++k)
    {
      m_GeometryDirection[k][0] = geometry.Stack.Row[k];
      m_GeometryDirection[k][1] = geometry.Stack.Column[k];
      m_GeometryDirection[k][2] = geometry.Normal[k];
    }
    return;
  }

  if (!m_ResampleIrregularSeries)
  {
    throw std::runtime_error(series + geometry.DescribeIrregularities(gantryTilt));
  }
  const size_t acquired = geometry.Stack.Slices.size();
  if (geometry.NumberOfMissingSlices() > acquired)
  {
    // A grid mostly made of gaps would be a volume of NaN with a few slices in it.
    throw std::runtime_error(series + geometry.DescribeGap(*geometry.LargestGap()) + ": more slices are missing (" +
                             std::to_string(geometry.NumberOfMissingSlices()) + ") than were acquired (" +
                             std::to_string(acquired) + "), the series is not resampled");
  }
  m_ResampledGrid =
    MakeRegularGrid(geometry, m_ResampledSliceSpacing > 0.0 ? m_ResampledSliceSpacing : geometry.SmallestSpacing());
  m_Resampled = true;
  m_VoxelsWithoutData = CountVoxelsWithoutData(geometry, m_ResampledGrid);
  for (const std::string & warning :
       geometry.DescribeCorrections(gantryTilt, m_ResampledGrid, m_SliceInterpolator, m_VoxelsWithoutData))
  {
    m_Warnings.push_back(warning);
  }
}

void
CTVolumeReader::ExamineSliceStack(std::vector<std::string> files)
{
  std::sort(files.begin(), files.end(), NaturalLess);
  if (files.size() == 1)
  {
    this->ExamineVolumeFile(files.front());
    return;
  }
  for (const std::string & problem : ProbeHeaders(files))
  {
    if (!problem.empty())
    {
      throw std::runtime_error(problem);
    }
  }
  ImageIOBase::Pointer reference = ReadImageHeader(files.front());
  for (const std::string & file : files)
  {
    ImageIOBase::Pointer io = file == files.front() ? reference : ReadImageHeader(file);
    if (io->GetNumberOfDimensions() > 2 && io->GetDimensions(2) > 1)
    {
      throw std::runtime_error(file + " holds " + SizeText(io) + " voxels: a stack must be made of 2D slices");
    }
    if (io->GetDimensions(0) != reference->GetDimensions(0) || io->GetDimensions(1) != reference->GetDimensions(1))
    {
      throw std::runtime_error("mixed image sizes in the stack: " + files.front() + " is " + SizeText(reference) +
                               ", " + file + " is " + SizeText(io));
    }
  }
  m_PixelType = ComponentTypeName(reference->GetComponentType(), reference->GetComponentSize());
  if (reference->GetNumberOfComponents() > 1)
  {
    m_Warnings.push_back("slices have " + std::to_string(reference->GetNumberOfComponents()) +
                         " components per pixel: converted to luminance");
  }
  m_InputKind = "image stack";
  m_ReplaceGeometry = true;
  if (!m_OverrideSpacing)
  {
    m_Warnings.push_back("no voxel size given for an image stack (its files do not store one reliably): using 1 x 1 "
                         "x 1 mm");
  }
  m_SliceFileNames = std::move(files);
}

void
CTVolumeReader::ExamineVolumeFile(const std::string & file)
{
  const std::string problem = ProbeHeaders({ file }).front();
  if (!problem.empty())
  {
    throw std::runtime_error(problem);
  }
  ImageIOBase::Pointer io = ReadImageHeader(file);
  const unsigned       dimensions = io->GetNumberOfDimensions();
  if (dimensions < 3 || io->GetDimensions(2) < 2)
  {
    throw std::runtime_error(file + " is a 2D image (" + SizeText(io) + "), not a volume");
  }
  for (unsigned d = 3; d < dimensions; ++d)
  {
    if (io->GetDimensions(d) > 1)
    {
      throw std::runtime_error(file + " has " + std::to_string(dimensions) + " dimensions (" + SizeText(io) +
                               "): only 3D volumes are read");
    }
  }
  std::string truncation = MetaImageTruncation(file, io);
  if (truncation.empty())
  {
    truncation = NrrdTruncation(file, io);
  }
  if (!truncation.empty())
  {
    throw std::runtime_error(truncation);
  }
  m_PixelType = ComponentTypeName(io->GetComponentType(), io->GetComponentSize());
  m_InputKind = "image file";
  if (std::string(io->GetNameOfClass()) == "TIFFImageIO")
  {
    m_ReplaceGeometry = true;
    if (!m_OverrideSpacing)
    {
      m_Warnings.push_back("no voxel size given for a TIFF volume (TIFF resolution tags are not trusted): using 1 x 1 "
                           "x 1 mm");
    }
  }
  m_SliceFileNames = { file };
}

void
CTVolumeReader::BuildPipeline()
{
  // The first and last files' headers are parsed by ITK's series reader just below; the
  // slices to read, once the region of interest is known.
  if (m_IsDicom)
  {
    const std::string problem =
      DicomFilesProblem({ m_SliceFileNames.front(), m_SliceFileNames.back() }, m_DicomPixelBytes);
    if (!problem.empty())
    {
      Refuse(problem);
    }
  }
  OutputImageType * tail = nullptr;
  if (m_SliceFileNames.size() > 1)
  {
    auto reader = ImageSeriesReader<OutputImageType>::New();
    reader->SetFileNames(m_SliceFileNames);
    if (m_IsDicom)
    {
      reader->SetImageIO(GDCMImageIO::New());
      // The slice geometry was measured from the headers, against SliceSpacingTolerance.
      reader->SetSpacingWarningRelThreshold(NumericTraits<double>::max());
    }
    // Reading every slice header on the first update would defeat a small region of
    // interest on a stack of thousands of slices.
    reader->MetaDataDictionaryArrayUpdateOff();
    reader->UseStreamingOn();
    tail = reader->GetOutput();
    m_Pipeline.push_back(reader.GetPointer());
    if (m_Resampled)
    {
      tail = AppendSliceStackResampling(tail, m_SeriesGeometry, m_ResampledGrid, m_SliceInterpolator, m_Pipeline);
    }
  }
  else
  {
    auto reader = ImageFileReader<OutputImageType>::New();
    reader->SetFileName(m_SliceFileNames.front());
    if (m_IsDicom)
    {
      reader->SetImageIO(GDCMImageIO::New());
    }
    tail = reader->GetOutput();
    m_Pipeline.push_back(reader.GetPointer());
  }

  if (m_ReplaceGeometry || m_OverrideSpacing)
  {
    auto change = ChangeInformationImageFilter<OutputImageType>::New();
    change->SetInput(tail);
    change->SetOutputSpacing(m_OverrideSpacing ? m_SpacingOverride : m_GeometrySpacing);
    change->ChangeSpacingOn();
    if (m_ReplaceGeometry)
    {
      change->SetOutputOrigin(m_GeometryOrigin);
      change->SetOutputDirection(m_GeometryDirection);
      change->ChangeOriginOn();
      change->ChangeDirectionOn();
    }
    tail = change->GetOutput();
    m_Pipeline.push_back(change.GetPointer());
  }

  try
  {
    const QuietGdcm quiet;
    tail->UpdateOutputInformation();
  }
  catch (const ProcessAborted &)
  {
    throw;
  }
  catch (const ExceptionObject & e)
  {
    Refuse("cannot read ", m_FileName, ": ", e.GetDescription());
  }
  const RegionType full = tail->GetLargestPossibleRegion();
  m_FullSize = full.GetSize();

  RegionType roi = full;
  if (m_UseRegionOfInterest)
  {
    roi = m_RegionOfInterest;
    if (roi.GetNumberOfPixels() == 0 || !full.IsInside(roi))
    {
      Refuse("region of interest (index ",
             roi.GetIndex(),
             ", size ",
             roi.GetSize(),
             ") is not inside the volume of size ",
             m_FullSize);
    }
  }
  else if (m_UsePhysicalRegionOfInterest)
  {
    // The box between the two corners, mapped to continuous indices through its eight
    // corners: for an oblique volume this is the index box that encloses it.
    ContinuousIndex<double, 3> low, high;
    for (unsigned corner = 0; corner < 8; ++corner)
    {
      PointType p;
      for (unsigned d = 0; d < 3; ++d)
      {
        p[d] = (corner >> d) & 1 ? m_PhysicalRegionOfInterestEnd[d] : m_PhysicalRegionOfInterestStart[d];
      }
      ContinuousIndex<double, 3> c;
      tail->TransformPhysicalPointToContinuousIndex(p, c);
      for (unsigned d = 0; d < 3; ++d)
      {
        low[d] = corner ? std::min(low[d], c[d]) : c[d];
        high[d] = corner ? std::max(high[d], c[d]) : c[d];
      }
    }
    bool clipped = false;
    for (unsigned d = 0; d < 3; ++d)
    {
      const double first = std::ceil(low[d] - 1e-6), last = std::floor(high[d] + 1e-6);
      const double fullLast = static_cast<double>(m_FullSize[d]) - 1.0;
      if (last < 0.0 || first > fullLast || last < first)
      {
        Refuse("physical region of interest ",
               m_PhysicalRegionOfInterestStart,
               " - ",
               m_PhysicalRegionOfInterestEnd,
               " mm does not overlap the volume (axis ",
               d,
               ")");
      }
      clipped = clipped || first < 0.0 || last > fullLast;
      roi.SetIndex(d, static_cast<IndexValueType>(std::max(first, 0.0)));
      roi.SetSize(d, static_cast<SizeValueType>(std::min(last, fullLast) - std::max(first, 0.0)) + 1);
    }
    if (clipped)
    {
      m_Warnings.push_back("physical region of interest clipped to the volume");
    }
  }
  // A resampled grid slice needs the acquired slices around it: all are read.
  const bool series = m_SliceFileNames.size() > 1 && !m_Resampled;
  m_FirstSliceToRead = series ? static_cast<size_t>(roi.GetIndex(2)) : 0;
  m_EndSliceToRead = series ? m_FirstSliceToRead + roi.GetSize(2) : m_SliceFileNames.size();
  // Only the slices to be read are checked, so that a damaged slice outside the region
  // of interest does not stop the rest of the stack from being read.
  if (m_IsDicom)
  {
    const std::vector<std::string> toRead(m_SliceFileNames.begin() + static_cast<std::ptrdiff_t>(m_FirstSliceToRead),
                                          m_SliceFileNames.begin() + static_cast<std::ptrdiff_t>(m_EndSliceToRead));
    const std::string              problem = DicomFilesProblem(toRead, m_DicomPixelBytes);
    if (!problem.empty())
    {
      Refuse(problem);
    }
  }
  if (m_UseRegionOfInterest || m_UsePhysicalRegionOfInterest)
  {
    // ExtractImageFilter passes a downstream request for a few slices on upstream
    // (RegionOfInterestImageFilter asks for the whole box); the box is then re-indexed
    // from 0 with its corner as origin.
    auto extract = ExtractImageFilter<OutputImageType, OutputImageType>::New();
    extract->SetInput(tail);
    extract->SetExtractionRegion(roi);
    extract->SetDirectionCollapseToSubmatrix();
    PointType corner;
    tail->TransformIndexToPhysicalPoint(roi.GetIndex(), corner);
    auto reindex = ChangeInformationImageFilter<OutputImageType>::New();
    reindex->SetInput(extract->GetOutput());
    OutputImageType::OffsetType offset;
    for (unsigned d = 0; d < 3; ++d)
    {
      offset[d] = -roi.GetIndex(d);
    }
    reindex->SetOutputOffset(offset);
    reindex->ChangeRegionOn();
    reindex->SetOutputOrigin(corner);
    reindex->ChangeOriginOn();
    tail = reindex->GetOutput();
    m_Pipeline.push_back(extract.GetPointer());
    m_Pipeline.push_back(reindex.GetPointer());
  }

  if (m_ShrinkFactor > 1)
  {
    for (unsigned d = 0; d < 3; ++d)
    {
      if (roi.GetSize(d) < m_ShrinkFactor)
      {
        Refuse("shrink factor ", m_ShrinkFactor, " is larger than the region to read (", roi.GetSize(), ")");
      }
    }
    auto shrink = BinShrinkImageFilter<OutputImageType, OutputImageType>::New();
    shrink->SetInput(tail);
    shrink->SetShrinkFactors(m_ShrinkFactor);
    tail = shrink->GetOutput();
    m_Pipeline.push_back(shrink.GetPointer());
  }
  tail->UpdateOutputInformation();
  m_PipelineOutput = tail;
  this->GetOutput()->CopyInformation(tail);
}

void
CTVolumeReader::GenerateData()
{
  OutputImageType * output = this->GetOutput();
  OutputImageType * tail = m_PipelineOutput;

  auto progress = ProgressAccumulator::New();
  progress->SetMiniPipelineFilter(this);
  for (const ProcessObject::Pointer & filter : m_Pipeline)
  {
    progress->RegisterInternalFilter(filter, 1.0f / static_cast<float>(m_Pipeline.size()));
  }

  tail->SetRequestedRegion(output->GetRequestedRegion());
  const QuietGdcm quiet;
  try
  {
    tail->Update();
  }
  catch (const ProcessAborted &)
  {
    throw;
  }
  catch (const ExceptionObject & e)
  {
    Refuse("cannot read ", this->FindUnreadableFile(), ": ", e.GetDescription());
  }
  this->GraftOutput(tail);
}

std::string
CTVolumeReader::FindUnreadableFile() const
{
  // The series reader does not say which slice failed: read them one by one to find it.
  for (size_t i = m_FirstSliceToRead; i < m_EndSliceToRead; ++i)
  {
    auto reader = ImageFileReader<OutputImageType>::New();
    reader->SetFileName(m_SliceFileNames[i]);
    if (m_IsDicom)
    {
      reader->SetImageIO(GDCMImageIO::New());
    }
    try
    {
      reader->Update();
    }
    catch (const ExceptionObject &)
    {
      return m_SliceFileNames[i];
    }
  }
  return m_FileName;
}

void
CTVolumeReader::PrintSelf(std::ostream & os, Indent indent) const
{
  Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << m_FileName << std::endl;
  os << indent << "SeriesIdentifier: " << m_SeriesIdentifier << std::endl;
  os << indent << "SpacingOverride: " << m_SpacingOverride << std::endl;
  os << indent << "OverrideSpacing: " << m_OverrideSpacing << std::endl;
  os << indent << "RegionOfInterest: " << m_RegionOfInterest << std::endl;
  os << indent << "UseRegionOfInterest: " << m_UseRegionOfInterest << std::endl;
  os << indent << "PhysicalRegionOfInterestStart: " << m_PhysicalRegionOfInterestStart << std::endl;
  os << indent << "PhysicalRegionOfInterestEnd: " << m_PhysicalRegionOfInterestEnd << std::endl;
  os << indent << "UsePhysicalRegionOfInterest: " << m_UsePhysicalRegionOfInterest << std::endl;
  os << indent << "ShrinkFactor: " << m_ShrinkFactor << std::endl;
  os << indent << "SliceSpacingTolerance: " << m_SliceSpacingTolerance << std::endl;
  os << indent << "ResampleIrregularSeries: " << m_ResampleIrregularSeries << std::endl;
  os << indent << "SliceInterpolator: " << ToString(m_SliceInterpolator) << std::endl;
  os << indent << "ResampledSliceSpacing: " << m_ResampledSliceSpacing << std::endl;
  os << indent << "InputKind: " << m_InputKind << std::endl;
  os << indent << "Modality: " << m_Modality << std::endl;
  os << indent << "PixelType: " << m_PixelType << std::endl;
  os << indent << "RescaleSlope: " << m_RescaleSlope << std::endl;
  os << indent << "RescaleIntercept: " << m_RescaleIntercept << std::endl;
  os << indent << "FullSize: " << m_FullSize << std::endl;
  os << indent << "ChosenSeries: " << (m_ChosenSeries.UID.empty() ? "(none)" : DescribeSeries(m_ChosenSeries))
     << std::endl;
  os << indent << "AlternativeSeries: " << m_AlternativeSeries.size() << std::endl;
  for (const SeriesInfo & s : m_AlternativeSeries)
  {
    os << indent.GetNextIndent() << DescribeSeries(s) << std::endl;
  }
  os << indent << "Warnings: " << m_Warnings.size() << std::endl;
  for (const std::string & w : m_Warnings)
  {
    os << indent.GetNextIndent() << w << std::endl;
  }
  os << indent << "SliceFileNames: " << m_SliceFileNames.size() << std::endl;
  os << indent << "SeriesGeometry: " << m_SeriesGeometry.Locations.size() << " slices"
     << (m_SeriesGeometry.Sheared ? ", sheared" : "") << ", " << m_SeriesGeometry.Runs.size() << " spacing runs, "
     << m_SeriesGeometry.Gaps.size() << " gaps" << std::endl;
  os << indent << "Resampled: " << m_Resampled << std::endl;
  os << indent << "ResampledGrid: size " << m_ResampledGrid.Size << ", spacing " << m_ResampledGrid.Spacing
     << ", origin " << m_ResampledGrid.Origin << std::endl;
  os << indent << "VoxelsWithoutData: " << m_VoxelsWithoutData << std::endl;
  os << indent << "Pipeline: " << m_Pipeline.size() << " internal filters" << std::endl;
  os << indent << "PipelineOutput: " << m_PipelineOutput.GetPointer() << std::endl;
  os << indent << "ReplaceGeometry: " << m_ReplaceGeometry << std::endl;
  os << indent << "GeometryOrigin: " << m_GeometryOrigin << std::endl;
  os << indent << "GeometrySpacing: " << m_GeometrySpacing << std::endl;
  os << indent << "GeometryDirection: " << m_GeometryDirection << std::endl;
  os << indent << "IsDicom: " << m_IsDicom << std::endl;
  os << indent << "DicomPixelBytes: " << m_DicomPixelBytes << std::endl;
  os << indent << "SlicesToRead: [" << m_FirstSliceToRead << ", " << m_EndSliceToRead << ")" << std::endl;
}
} // end namespace itk

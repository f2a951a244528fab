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
// CTVolumeReader's inspection of its input before reading: which files, DICOM series and
// their slice geometry, image stacks, single volume files.
#include "itkCTVolumeReader.h"
#include "vuCTInputFiles.h"
#include "vuCTReaderRefusal.h"
#include "vuDicomSeriesScan.h"

#include "itkBinShrinkImageFilter.h"
#include "itkChangeInformationImageFilter.h"
#include "itkExtractImageFilter.h"
#include "itkGDCMImageIO.h"
#include "itkImageFileReader.h"
#include "itkImageIOFactory.h"
#include "itkImageSeriesReader.h"
#include "itkProgressAccumulator.h"
#include "itkZarrImageIO.h"
#include "itksys/Glob.hxx"

#include "gdcmDirectory.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace itk {
namespace {
using namespace CTReading;

// The series to read among `series` (sorted by decreasing number of slices): the one whose
// SeriesInstanceUID or unique series number is `identifier`, or without one the one with
// the most slices; refused when that is not one series.
size_t
ChooseSeries(const std::vector<CTVolumeReader::SeriesInfo> & series,
             const std::string &                             identifier,
             const std::string &                             fileName)
{
  auto listAll = [&series]() {
    std::string text;
    for (const CTVolumeReader::SeriesInfo & s : series)
    {
      text += (text.empty() ? "" : "; ") + DescribeSeries(s);
    }
    return text;
  };

  size_t chosen = 0;
  if (!identifier.empty())
  {
    std::vector<size_t> matches;
    for (size_t i = 0; i < series.size(); ++i)
    {
      if (series[i].UID == identifier)
      {
        matches = { i };
        break;
      }
      if (series[i].Number == identifier)
      {
        matches.push_back(i);
      }
    }
    if (matches.empty())
    {
      throw std::runtime_error("no series '" + identifier + "' in " + fileName + "; series found: " + listAll());
    }
    if (matches.size() > 1)
    {
      throw std::runtime_error("series number " + identifier + " is not unique in " + fileName +
                               ": choose by SeriesInstanceUID among " + listAll());
    }
    chosen = matches.front();
  }
  else if (series.size() > 1 && series[0].NumberOfSlices == series[1].NumberOfSlices)
  {
    throw std::runtime_error(fileName + " holds several series with " + std::to_string(series[0].NumberOfSlices) +
                             " slices; choose one by series number or SeriesInstanceUID: " + listAll());
  }
  return chosen;
}
} // namespace

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
  const size_t chosen = ChooseSeries(series, m_SeriesIdentifier, m_FileName);
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
  if (truncation.empty() && m_VerifyCompressedData)
  {
    truncation = MetaImageStreamProblem(file, io);
  }
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

bool
CTVolumeReader::ExamineVolumePackage()
{
  namespace fs = std::filesystem;
  using Json = nlohmann::json;
  const fs::path given(m_FileName);
  auto           readMeta = [](const fs::path & directory, Json & meta) {
    std::ifstream in(directory / "meta.json");
    meta = in ? Json::parse(in, nullptr, false) : Json();
    return !meta.is_discarded() && meta.is_object() && meta.contains("voxelsize");
  };
  // The volume directory: the one given, or in a package the one asked for by
  // SeriesIdentifier (directory name, uuid or name), else the one with the most slices.
  fs::path volume;
  Json     meta;
  if (readMeta(given, meta))
  {
    volume = given;
  }
  else if (fs::is_regular_file(given / "config.json") && fs::is_directory(given / "volumes"))
  {
    std::vector<std::pair<fs::path, Json>> volumes;
    for (const auto & entry : fs::directory_iterator(given / "volumes"))
    {
      Json candidate;
      if (entry.is_directory() && readMeta(entry.path(), candidate))
      {
        volumes.emplace_back(entry.path(), candidate);
      }
    }
    if (volumes.empty())
    {
      throw std::runtime_error(m_FileName + " is a volume package without volumes (no volumes/*/meta.json)");
    }
    std::sort(volumes.begin(), volumes.end(), [](const auto & a, const auto & b) { return a.first < b.first; });
    auto describe = [](const std::pair<fs::path, Json> & v) {
      return v.first.filename().string() + " (" + v.second.value("name", std::string()) + ", " +
             std::to_string(v.second.value("slices", 0)) + " slices)";
    };
    const std::pair<fs::path, Json> * chosen = nullptr;
    if (!m_SeriesIdentifier.empty())
    {
      for (const auto & v : volumes)
      {
        if (v.first.filename() == m_SeriesIdentifier || v.second.value("uuid", std::string()) == m_SeriesIdentifier ||
            v.second.value("name", std::string()) == m_SeriesIdentifier)
        {
          chosen = &v;
        }
      }
      if (chosen == nullptr)
      {
        std::string names;
        for (const auto & v : volumes)
        {
          names += (names.empty() ? "" : ", ") + describe(v);
        }
        throw std::runtime_error("no volume " + m_SeriesIdentifier + " in " + m_FileName + "; it holds " + names);
      }
    }
    else
    {
      chosen = &*std::max_element(volumes.begin(), volumes.end(), [](const auto & a, const auto & b) {
        return a.second.value("slices", 0) < b.second.value("slices", 0);
      });
      if (volumes.size() > 1)
      {
        std::string others;
        for (const auto & v : volumes)
        {
          others += &v == chosen ? "" : (others.empty() ? "" : ", ") + describe(v);
        }
        m_Warnings.push_back("the volume package holds " + std::to_string(volumes.size()) + " volumes: read " +
                             describe(*chosen) + " (the most slices); others: " + others);
      }
    }
    volume = chosen->first;
    meta = chosen->second;
  }
  else
  {
    return false;
  }
  const double voxel = meta["voxelsize"].is_number() ? meta["voxelsize"].get<double>() : 0.0;
  if (!(voxel > 0.0) || !std::isfinite(voxel))
  {
    throw std::runtime_error((volume / "meta.json").string() + ": voxelsize must be a positive number (micrometres)");
  }
  std::vector<std::string> slices;
  for (const auto & entry : fs::directory_iterator(volume))
  {
    if (entry.is_regular_file() && HasTiffExtension(entry.path()))
    {
      slices.push_back(entry.path().string());
    }
  }
  if (slices.empty())
  {
    throw std::runtime_error(volume.string() + " holds meta.json but no TIFF slices");
  }
  const auto expected = meta.value("slices", 0L);
  if (expected > 0 && static_cast<size_t>(expected) != slices.size())
  {
    throw std::runtime_error(volume.string() + " holds " + std::to_string(slices.size()) +
                             " TIFF slices, its meta.json " + std::to_string(expected));
  }
  this->ExamineSliceStack(std::move(slices));
  // The voxel size is the package's (micrometres), not the 1 mm a bare stack gets.
  m_Warnings.erase(std::remove_if(m_Warnings.begin(),
                                  m_Warnings.end(),
                                  [](const std::string & w) { return w.rfind("no voxel size given", 0) == 0; }),
                   m_Warnings.end());
  m_GeometrySpacing.Fill(voxel * 1e-3);
  m_InputKind = "volume-cartographer volume";
  return true;
}

void
CTVolumeReader::ExamineZarrStore()
{
  auto io = ZarrImageIO::New();
  io->SetFileName(m_FileName);
  try
  {
    io->ReadImageInformation();
  }
  catch (const ExceptionObject & e)
  {
    throw std::runtime_error(e.GetDescription());
  }
  if (io->GetNumberOfDimensions() < 3 || io->GetDimensions(2) < 2)
  {
    throw std::runtime_error(m_FileName + " is a 2D image (" + SizeText(io.GetPointer()) + "), not a volume");
  }
  m_PixelType = ComponentTypeName(io->GetComponentType(), io->GetComponentSize());
  m_InputKind = io->GetHasGeometry() ? "OME-Zarr image" : "Zarr array";
  if (!io->GetHasGeometry() && !m_OverrideSpacing)
  {
    m_Warnings.push_back("no voxel size given for a Zarr array without OME-Zarr metadata: using 1 x 1 x 1 mm");
  }
  m_SliceFileNames = { m_FileName };
}

} // end namespace itk

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

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace itk {
namespace {
using namespace CTReading;

// A reader of one file: GDCM for DICOM, the checked MetaIO for a MetaImage (MetaIO's own
// inflation never ends on some damaged streams), otherwise the IO ITK's factories choose.
ImageFileReader<OutputImageType>::Pointer
NewFileReader(const std::string & file, bool dicom)
{
  auto reader = ImageFileReader<OutputImageType>::New();
  reader->SetFileName(file);
  if (dicom)
  {
    reader->SetImageIO(GDCMImageIO::New());
  }
  else if (auto zarr = ZarrImageIO::New(); zarr->CanReadFile(file.c_str()))
  {
    reader->SetImageIO(zarr);
  }
  else if (auto io = detail::CheckedMetaImageIO::New(); io->CanReadFile(file.c_str()))
  {
    reader->SetImageIO(io);
  }
  return reader;
}

// The index box that encloses the physical box between two corners (mm): each of its eight
// corners mapped to a continuous index, the box clipped to the image (`clipped` set then);
// refused when it does not overlap the image.
CTVolumeReader::RegionType
IndexBox(const OutputImageType *           image,
         const CTVolumeReader::PointType & start,
         const CTVolumeReader::PointType & end,
         bool &                            clipped)
{
  const auto                 size = image->GetLargestPossibleRegion().GetSize();
  ContinuousIndex<double, 3> low, high;
  for (unsigned corner = 0; corner < 8; ++corner)
  {
    CTVolumeReader::PointType p;
    for (unsigned d = 0; d < 3; ++d)
    {
      p[d] = (corner >> d) & 1 ? end[d] : start[d];
    }
    ContinuousIndex<double, 3> c;
    image->TransformPhysicalPointToContinuousIndex(p, c);
    for (unsigned d = 0; d < 3; ++d)
    {
      low[d] = corner ? std::min(low[d], c[d]) : c[d];
      high[d] = corner ? std::max(high[d], c[d]) : c[d];
    }
  }
  CTVolumeReader::RegionType box;
  clipped = false;
  for (unsigned d = 0; d < 3; ++d)
  {
    const double first = std::ceil(low[d] - 1e-6), last = std::floor(high[d] + 1e-6);
    const double fullLast = static_cast<double>(size[d]) - 1.0;
    if (last < 0.0 || first > fullLast || last < first)
    {
      Refuse("physical region of interest ", start, " - ", end, " mm does not overlap the volume (axis ", d, ")");
    }
    clipped = clipped || first < 0.0 || last > fullLast;
    box.SetIndex(d, static_cast<IndexValueType>(std::max(first, 0.0)));
    box.SetSize(d, static_cast<SizeValueType>(std::min(last, fullLast) - std::max(first, 0.0)) + 1);
  }
  return box;
}

// Appends the extraction of `region` to the reading pipeline. ExtractImageFilter passes a
// downstream request for a few slices on upstream (RegionOfInterestImageFilter asks for the
// whole box); the box is then re-indexed from 0 with its corner as origin.
OutputImageType *
AppendExtraction(OutputImageType *                     tail,
                 const CTVolumeReader::RegionType &    region,
                 std::vector<ProcessObject::Pointer> & pipeline)
{
  auto extract = ExtractImageFilter<OutputImageType, OutputImageType>::New();
  extract->SetInput(tail);
  extract->SetExtractionRegion(region);
  extract->SetDirectionCollapseToSubmatrix();
  CTVolumeReader::PointType corner;
  tail->TransformIndexToPhysicalPoint(region.GetIndex(), corner);
  auto reindex = ChangeInformationImageFilter<OutputImageType>::New();
  reindex->SetInput(extract->GetOutput());
  OutputImageType::OffsetType offset;
  for (unsigned d = 0; d < 3; ++d)
  {
    offset[d] = -region.GetIndex(d);
  }
  reindex->SetOutputOffset(offset);
  reindex->ChangeRegionOn();
  reindex->SetOutputOrigin(corner);
  reindex->ChangeOriginOn();
  pipeline.push_back(extract.GetPointer());
  pipeline.push_back(reindex.GetPointer());
  return reindex->GetOutput();
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
    else if (ZarrImageIO::New()->CanReadFile(m_FileName.c_str()))
    {
      this->ExamineZarrStore();
    }
    else if (fs::is_directory(m_FileName, error) && this->ExamineVolumePackage())
    {
      // A volume-cartographer package or volume: its TIFF slices with the voxel size.
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
    else if (auto io = detail::CheckedMetaImageIO::New(); io->CanReadFile(m_SliceFileNames.front().c_str()))
    {
      reader->SetImageIO(io);
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
    auto reader = NewFileReader(m_SliceFileNames.front(), m_IsDicom);
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
    bool clipped = false;
    roi = IndexBox(tail, m_PhysicalRegionOfInterestStart, m_PhysicalRegionOfInterestEnd, clipped);
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
    tail = AppendExtraction(tail, roi, m_Pipeline);
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
  if (m_SliceFileNames.size() == 1)
  {
    return m_FileName;
  }
  for (size_t i = m_FirstSliceToRead; i < m_EndSliceToRead; ++i)
  {
    auto reader = NewFileReader(m_SliceFileNames[i], m_IsDicom);
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
  os << indent << "VerifyCompressedData: " << m_VerifyCompressedData << std::endl;
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

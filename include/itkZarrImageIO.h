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
#ifndef itkZarrImageIO_h
#define itkZarrImageIO_h

#include "VirtualUnwrappingExport.h"

#include "itkImageIOBase.h"
#include "itkObjectFactoryBase.h"

#include <cstdint>
#include <string>
#include <vector>

namespace itk {
/** \class ZarrImageIO
 * \brief Reads a volume stored as a Zarr v2 array on disk (a directory of chunk files), as
 * the field stores scroll scans, chunk by chunk: only the chunks that a requested region
 * touches are opened and decompressed, so a volume larger than memory can be read a region
 * at a time (streaming through ImageFileReader or CTVolumeReader).
 *
 * FileName may be:
 * - a Zarr array: a directory holding `.zarray` (and optionally `.zattrs`). Its shape is
 *   read as (z, y, x), the last axis varying fastest, and becomes the ITK image's (x, y, z).
 *   No voxel size is stored in a bare array: spacing 1, origin 0 (CTVolumeReader warns).
 * - an OME-Zarr image (NGFF 0.4): a group whose `.zattrs` holds `multiscales`; the first
 *   (full-resolution) dataset is read, with the voxel size and origin of its `scale` and
 *   `translation` transformations, converted to millimetres from the axes' units
 *   (micrometer, nanometer, millimeter, centimeter, meter; a unitless axis is taken in mm).
 *   Leading time or channel axes must have length 1.
 * The array may have any chunk shape, `dimension_separator` "." or "/", fill value for the
 * chunks that are absent (written by zarr as all fill value), C order, little-endian (or
 * single-byte) integers of 8, 16 or 32 bits or floats of 32 or 64 bits, and chunks stored
 * raw, or compressed by blosc (every codec the Debian blosc library decodes: blosclz, lz4,
 * lz4hc, zlib, zstd, with any shuffle) or by zlib or gzip. Anything else (Fortran order,
 * big-endian data, filters, other compressors) is refused with the reason, as is a chunk
 * file that does not decompress to the chunk's size.
 *
 * GetNumberOfChunksRead() counts the chunk files opened by the last Read(): a region read
 * touches only the chunks it overlaps.
 *
 * Writing (a FileName ending in ".zarr") makes an OME-Zarr image, region by region if the
 * writer streams. References: Zarr storage specification v2
 * (https://zarr.readthedocs.io/en/stable/spec/v2.html); OME-NGFF 0.4
 * (https://ngff.openmicroscopy.org/0.4/).
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT ZarrImageIO : public ImageIOBase
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(ZarrImageIO);

  using Self = ZarrImageIO;
  using Superclass = ImageIOBase;
  using Pointer = SmartPointer<Self>;

  itkNewMacro(Self);
  itkTypeMacro(ZarrImageIO, ImageIOBase);

  /** A directory holding `.zarray`, or an OME-Zarr group (`.zattrs` with multiscales). */
  bool
  CanReadFile(const char * fileName) override;

  bool
  CanStreamRead() override
  {
    return true;
  }

  bool
  SupportsDimension(unsigned long dimension) override
  {
    return dimension >= 2 && dimension <= 3;
  }

  void
  ReadImageInformation() override;

  /** The requested region itself when streamed reading is on (ImageFileReader's
   * UseStreaming, the default), otherwise the whole array. */
  ImageIORegion
  GenerateStreamableReadRegionFromRequestedRegion(const ImageIORegion & requested) const override;

  /** Reads the IORegion into the buffer, chunk by chunk. */
  void
  Read(void * buffer) override;

  /** A name ending in ".zarr": written as an OME-Zarr image (one full-resolution dataset
   * "0", the voxel size and origin as its scale and translation in millimetres). */
  bool
  CanWriteFile(const char * fileName) override;

  /** Regions of the image may be written one after the other (ImageFileWriter's stream
   * divisions): a chunk that a region covers in part is merged with what the store holds. */
  bool
  CanStreamWrite() override
  {
    return true;
  }

  /** Written with the first region by Write(). */
  void
  WriteImageInformation() override
  {}

  /** Writes the IORegion from the buffer, chunk by chunk: blosc (zstd, level 3, byte
   * shuffle) when UseCompression is on, raw chunks otherwise. A direction other than the
   * identity is refused (OME-Zarr has no rotation), as is a path that exists and is not a
   * Zarr store. */
  void
  Write(const void * buffer) override;

  /** Chunk edge in voxels for writing (each axis, clipped to the image); default 64. */
  itkSetClampMacro(ChunkEdge, unsigned int, 1, 4096);
  itkGetConstMacro(ChunkEdge, unsigned int);

  /** Chunk files opened by the last Read(). */
  itkGetConstMacro(NumberOfChunksRead, SizeValueType);

  /** The array directory read (the first dataset of an OME-Zarr group), after
   * ReadImageInformation(). */
  itkGetStringMacro(ArrayPath);

  /** Whether the geometry (voxel size, origin) came from OME-Zarr metadata. */
  itkGetConstMacro(HasGeometry, bool);

protected:
  ZarrImageIO();
  ~ZarrImageIO() override = default;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  struct ChunkRun
  {
    size_t Chunk, Buffer, Bytes; // byte offsets in the chunk and the buffer, length
  };
  enum class Codec
  {
    None,
    Blosc,
    Zlib
  };

  // ReadImageInformation's parts: an OME-Zarr group's first dataset (its array's path, and
  // per Zarr axis the voxel size and origin in mm); the array's .zarray (shape, chunks,
  // codec, type, fill value); the axes (leading ones of length 1 dropped, the rest in ITK's
  // order, with the geometry).
  void
  ReadOmeMultiscales(std::string & arrayPath, std::vector<double> & scale, std::vector<double> & translation);
  void
  ReadArrayMetadata();
  void
  SetAxes(const std::vector<double> & scale, const std::vector<double> & translation);
  void
  ReadChunk(const std::vector<SizeValueType> & chunkIndex, std::vector<char> & data) const;
  void
  WriteChunk(const std::vector<SizeValueType> & chunkIndex, const std::vector<char> & data) const;
  std::string
  ChunkKey(const std::vector<SizeValueType> & chunkIndex) const;
  void
  PrepareStore();
  // The chunks the IORegion overlaps, each visited with its index and the region's part
  // of it (copied between the chunk's data and the buffer by `copy`).
  template <typename TVisit>
  void
  ForEachChunkInRegion(TVisit visit) const;

  std::string                m_ArrayPath;
  std::vector<SizeValueType> m_Shape;  // Zarr order (slowest first)
  std::vector<SizeValueType> m_Chunks; // Zarr order
  unsigned int               m_LeadingAxes{ 0 };
  std::string                m_Separator{ "." };
  Codec                      m_Codec{ Codec::None };
  std::vector<char>          m_FillValue; // one element, in the stored type
  SizeValueType              m_NumberOfChunksRead{ 0 };
  bool                       m_HasGeometry{ false };
  unsigned int               m_ChunkEdge{ 64 };
};

/** \class ZarrImageIOFactory
 * \brief Makes ZarrImageIO available to ImageFileReader:
 * `itk::ObjectFactoryBase::RegisterFactory(itk::ZarrImageIOFactory::New())`.
 * \ingroup VirtualUnwrapping
 */
class VirtualUnwrapping_EXPORT ZarrImageIOFactory : public ObjectFactoryBase
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(ZarrImageIOFactory);

  using Self = ZarrImageIOFactory;
  using Superclass = ObjectFactoryBase;
  using Pointer = SmartPointer<Self>;

  itkFactorylessNewMacro(Self);
  itkTypeMacro(ZarrImageIOFactory, ObjectFactoryBase);

  const char *
  GetITKSourceVersion() const override;
  const char *
  GetDescription() const override;

protected:
  ZarrImageIOFactory();
  ~ZarrImageIOFactory() override = default;
};
} // namespace itk

#endif

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
// Unwraps a CT scan of a rolled sheet into a flat, readable texture with the module's ITK
// filters: the whole job of `virtual-unwrap unwrap`, without its reports and extra files.
//
//   UnwrapScroll INPUT OUTPUT.tif
//
// INPUT: a DICOM series folder, a TIFF stack folder or a volume file (.mha, .nrrd, ...).
#include "itkCTVolumeReader.h"
#include "itkFlipImageFilter.h"
#include "itkImageFileWriter.h"
#include "itkMassSpringFlatteningMeshFilter.h"
#include "itkReadableTextureImageFilter.h"
#include "itkSheetMidSurfaceMeshFilter.h"
#include "itkSheetSegmentationImageFilter.h"

#include <iostream>

int
main(int argc, char * argv[])
{
  if (argc != 3)
  {
    std::cerr << "usage: " << argv[0] << " INPUT OUTPUT.tif" << std::endl;
    return 2;
  }
  using VolumeType = itk::Image<float, 3>;
  using MaskType = itk::Image<unsigned char, 3>;
  using MeshType = itk::Mesh<double, 3>;
  using TextureType = itk::Image<float, 2>;
  try
  {
    // Read the scan, find the sheet and mesh its mid-surface.
    auto reader = itk::CTVolumeReader::New();
    reader->SetFileName(argv[1]);
    auto segmentation = itk::SheetSegmentationImageFilter<VolumeType, MaskType>::New();
    segmentation->SetInput(reader->GetOutput());
    auto surface = itk::SheetMidSurfaceMeshFilter<MaskType, MeshType>::New();
    surface->SetInput(segmentation->GetOutput());
    surface->SetIntensityImage(reader->GetOutput());
    surface->Update();

    // Unroll and flatten it by the mass-spring simulation.
    auto flattening = itk::MassSpringFlatteningMeshFilter<MeshType>::New();
    flattening->SetInput(surface->GetOutput());

    // The texture in which the writing reads best, from layers sampled through the sheet.
    auto texture = itk::ReadableTextureImageFilter<VolumeType, TextureType, MeshType>::New();
    texture->SetSurfaceMesh(surface->GetOutput());
    texture->SetFlatMesh(flattening->GetOutput());
    texture->SetVolume(reader->GetOutput());
    texture->SetSheetThickness(surface->GetSheetThickness());
    texture->SetDenoisingSigma(segmentation->GetAppliedDenoisingSigma());

    // Rows top-down, as an image is read (the flat sheet's y grows upwards).
    auto flip = itk::FlipImageFilter<TextureType>::New();
    flip->SetInput(texture->GetOutput());
    itk::FixedArray<bool, 2> axes;
    axes[0] = false;
    axes[1] = true;
    flip->SetFlipAxes(axes);
    flip->FlipAboutOriginOff();
    itk::WriteImage(flip->GetOutput(), argv[2]);

    std::cout << "sheet " << surface->GetSheetThickness() << " mm thick; texture "
              << texture->GetOutput()->GetLargestPossibleRegion().GetSize() << " pixels of "
              << texture->GetAppliedPixelSize() << " mm in " << argv[2] << std::endl;
  }
  catch (const itk::ExceptionObject & e)
  {
    std::cerr << argv[0] << ": error: " << e.GetDescription() << std::endl;
    return 1;
  }
  return 0;
}

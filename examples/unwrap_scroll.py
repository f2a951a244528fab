#!/usr/bin/env python3
"""Unwraps a CT scan of a rolled sheet into a flat, readable texture with the module's
wrapped ITK filters: the whole job of `virtual-unwrap unwrap`, without its reports and
extra files.

    unwrap_scroll.py INPUT OUTPUT.tif

INPUT: a DICOM series folder, a TIFF stack folder or a volume file (.mha, .nrrd, ...).
"""
import sys

import itk

VolumeType = itk.Image[itk.F, 3]
MaskType = itk.Image[itk.UC, 3]
MeshType = itk.Mesh[itk.D, 3]
TextureType = itk.Image[itk.F, 2]


def unwrap(input_path):
    """The readable texture of the sheet in the scan at `input_path`, rows top-down."""
    # Read the scan, find the sheet and mesh its mid-surface.
    reader = itk.CTVolumeReader.New(FileName=input_path)
    segmentation = itk.SheetSegmentationImageFilter[VolumeType, MaskType].New(Input=reader.GetOutput())
    surface = itk.SheetMidSurfaceMeshFilter[MaskType, MeshType].New(Input=segmentation.GetOutput())
    surface.SetIntensityImage(reader.GetOutput())
    surface.Update()

    # Unroll and flatten it by the mass-spring simulation.
    flattening = itk.MassSpringFlatteningMeshFilter[MeshType, MeshType].New(Input=surface.GetOutput())

    # The texture in which the writing reads best, from layers sampled through the sheet.
    texture = itk.ReadableTextureImageFilter[VolumeType, TextureType, MeshType].New()
    texture.SetSurfaceMesh(surface.GetOutput())
    texture.SetFlatMesh(flattening.GetOutput())
    texture.SetVolume(reader.GetOutput())
    texture.SetSheetThickness(surface.GetSheetThickness())
    texture.SetDenoisingSigma(segmentation.GetAppliedDenoisingSigma())

    # Rows top-down, as an image is read (the flat sheet's y grows upwards).
    flip = itk.FlipImageFilter[TextureType].New(Input=texture.GetOutput())
    flip.SetFlipAxes((False, True))
    flip.FlipAboutOriginOff()
    flip.Update()
    return flip.GetOutput()


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} INPUT OUTPUT.tif")
    try:
        result = unwrap(sys.argv[1])
    except RuntimeError as error:  # ITK's exceptions reach Python as RuntimeError
        sys.exit(f"{sys.argv[0]}: error: {str(error).strip().splitlines()[-1]}")
    itk.imwrite(result, sys.argv[2])
    size = tuple(result.GetLargestPossibleRegion().GetSize())
    print(f"texture {size} pixels in {sys.argv[2]}")

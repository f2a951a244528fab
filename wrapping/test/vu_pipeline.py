"""The unwrapping pipeline of `virtual-unwrap unwrap`, written with the wrapped filters.

Shared by the Python tests; also an example of the module's Python API.
"""
import math

import itk

VolumeType = itk.Image[itk.F, 3]
MaskType = itk.Image[itk.UC, 3]
TextureType = itk.Image[itk.F, 2]
MeshType = itk.Mesh[itk.F, 3]


def enum_value(holder, enum, name):
    """A nested enum value as SWIG exposes it (for example TextureLayersEnums.Filter_Max)."""
    return getattr(holder, f"{enum}_{name}")


def unwrap(volume, layer_filter="Max"):
    """Segment, mesh, unroll and flatten, then texture `volume` with the tool's defaults.

    Returns a dict with the texture (2D float image, rows flipped as the tool writes them),
    its mask, the surface and flat meshes and the filters, for inspection.
    """
    segmentation = itk.SheetSegmentationImageFilter[VolumeType, MaskType].New(Input=volume)
    segmentation.Update()

    surface_filter = itk.SheetMidSurfaceMeshFilter[MaskType, MeshType].New()
    surface_filter.SetInput(segmentation.GetOutput())
    surface_filter.SetIntensityImage(volume)
    surface_filter.Update()
    surface = surface_filter.GetOutput()

    flattening = itk.MassSpringFlatteningMeshFilter[MeshType, MeshType].New(Input=surface)
    flattening.Update()
    flat = flattening.GetOutput()

    # The tool's automatic texture parameters: pixels and layers half a voxel apart, layers
    # on both sides reaching half a voxel beyond the sheet's measured faces.
    voxel = min(volume.GetSpacing())
    pixel_size = voxel / 2.0
    layer_spacing = voxel / 2.0
    thickness = surface_filter.GetSheetThickness()
    reach = int(math.ceil((0.5 * thickness + 0.5 * voxel) / layer_spacing))
    layers = 1 + 2 * reach
    Side = itk.TextureLayersEnums

    texturer = itk.FlattenedTextureImageFilter[VolumeType, TextureType, MeshType].New()
    texturer.SetSurfaceMesh(surface)
    texturer.SetFlatMesh(flat)
    texturer.SetVolume(volume)
    texturer.SetPixelSize(pixel_size)
    texturer.SetMargin(2.0 * pixel_size)
    texturer.SetNumberOfLayers(layers)
    texturer.SetLayerSpacing(layer_spacing)
    texturer.SetLayerSide(enum_value(Side, "Side", "Both"))
    texturer.SetLayerFilter(enum_value(Side, "Filter", layer_filter))
    texturer.Update()

    # The tool's --side auto --subtract-core auto: candidates from the layer stack (both
    # sides; each half with and without the sheet's core subtracted), each denoised by a
    # median and a Gaussian of half a voxel; the one of highest ink contrast is kept.
    stack = texturer.GetLayerStackOutput()
    candidates = []
    for side in ("Both", "Positive", "Negative"):
        for core in ((False,) if side == "Both" else (False, True)):
            combined = itk.LayerStackTexture.Combine(
                stack, layers, layer_spacing, 0.0, enum_value(Side, "Side", "Both"), enum_value(Side, "Side", side),
                enum_value(Side, "Filter", layer_filter), texturer.GetGaussianSigma(), 0.5 * voxel if core else 0.0)
            smoothed = itk.LayerStackTexture.Smooth(itk.LayerStackTexture.Median(combined, 0.5 * voxel), 0.5 * voxel)
            candidates.append((itk.LayerStackTexture.InkContrast(smoothed), side, core, smoothed))
    contrast, side, core, chosen = max(candidates, key=lambda c: c[0])

    # The tool writes rows top-down (y of the flat sheet grows upwards).
    flip = itk.FlipImageFilter[TextureType].New(Input=chosen)
    flip.SetFlipAxes((False, True))
    flip.FlipAboutOriginOff()
    flip.Update()
    return {
        "texture": flip.GetOutput(),
        "mask": texturer.GetMaskOutput(),
        "surface": surface,
        "flat": flat,
        "segmentation": segmentation,
        "surface_filter": surface_filter,
        "flattening": flattening,
        "texturer": texturer,
        "layers": layers,
        "chosen": (side, core, contrast),
    }


def texture_ncc(reference, texture):
    """NCC of the texture against a reference ink image after the best similarity alignment."""
    fidelity = itk.TextureFidelityCalculator.New()
    fidelity.SetReference(reference)
    fidelity.SetTexture(texture)
    fidelity.Compute()
    return fidelity

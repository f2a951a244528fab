"""The unwrapping pipeline of `virtual-unwrap unwrap`, written with the wrapped filters.

Shared by the Python tests; also an example of the module's Python API.
"""
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

    # The texture the tool writes: automatic pixel size, layers and side, core subtraction
    # and denoising chosen by ink contrast (ReadableTextureImageFilter holds that policy).
    Layers = itk.TextureLayersEnums
    texturer = itk.ReadableTextureImageFilter[VolumeType, TextureType, MeshType].New()
    texturer.SetSurfaceMesh(surface)
    texturer.SetFlatMesh(flat)
    texturer.SetVolume(volume)
    texturer.SetSheetThickness(surface_filter.GetSheetThickness())
    texturer.SetLayerFilter(enum_value(Layers, "Filter", layer_filter))
    texturer.SetDenoisingSigma(segmentation.GetAppliedDenoisingSigma())
    texturer.Update()
    chosen = texturer.GetOutput()

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
        "layers": texturer.GetAppliedNumberOfLayers(),
        "chosen": (texturer.GetChosenSide(), texturer.GetChosenSubtractCore(), texturer.GetChosenScore()),
    }


def texture_ncc(reference, texture):
    """NCC of the texture against a reference ink image after the best similarity alignment."""
    fidelity = itk.TextureFidelityCalculator.New()
    fidelity.SetReference(reference)
    fidelity.SetTexture(texture)
    fidelity.Compute()
    return fidelity

#!/usr/bin/env python3
"""Each wrapped filter through ITK's Python conventions: snake_case functions with keyword
arguments, template deduction from the input, numpy views of the outputs.

    functional_api_test.py OUTPUT_DIR
"""
import os
import sys

import numpy as np

import itk

output_dir = sys.argv[1]
os.makedirs(output_dir, exist_ok=True)

# A small rolled phantom, made by the functional form of the source.
volume = itk.sheet_phantom_source(number_of_turns=1.5, sheet_width=5.0, glyph_height=1.0, voxel_size=0.1, text="AB")
assert isinstance(volume, itk.Image[itk.F, 3]), type(volume)
array = itk.array_view_from_image(volume)
assert array.ndim == 3 and np.isfinite(array).all()
print(f"[ figures ] phantom {array.shape[::-1]} voxels, {array.min():.0f}..{array.max():.0f} HU")

# Segmentation: template deduced from the volume; numpy sees a binary mask.
mask = itk.sheet_segmentation_image_filter(volume)
assert isinstance(mask, itk.Image[itk.UC, 3]), type(mask)
mask_array = itk.array_view_from_image(mask)
assert set(np.unique(mask_array)) <= {0, 1} or set(np.unique(mask_array)) <= {0, 255}, np.unique(mask_array)
assert mask_array.any()
# Integer CT (short) is accepted too.
short_volume = itk.cast_image_filter(volume, ttype=(itk.Image[itk.F, 3], itk.Image[itk.SS, 3]))
short_mask = itk.sheet_segmentation_image_filter(short_volume)
assert np.array_equal(itk.array_view_from_image(short_mask) > 0, mask_array > 0) or \
    abs(int((itk.array_view_from_image(short_mask) > 0).sum()) - int((mask_array > 0).sum())) < 0.01 * mask_array.size

# Mid-surface mesh, each wrapped mesh type.
for label, mesh_type in (("Mesh[F,3]", itk.Mesh[itk.F, 3]), ("Mesh[D,3]", itk.Mesh[itk.D, 3]),
                         ("QuadEdgeMesh[D,3]", itk.QuadEdgeMesh[itk.D, 3])):
    surface_filter = itk.SheetMidSurfaceMeshFilter[itk.Image[itk.UC, 3], mesh_type].New(
        Input=mask, IntensityImage=volume)
    surface_filter.Update()
    surface = surface_filter.GetOutput()
    assert surface.GetNumberOfPoints() > 100, surface.GetNumberOfPoints()
    assert surface_filter.GetSheetThickness() > 0.0

    # Flattening: functional form, template deduced from the mesh.
    flat = itk.mass_spring_flattening_mesh_filter(surface)
    assert flat.GetNumberOfPoints() == surface.GetNumberOfPoints()
    points = np.array([flat.GetPoint(i) for i in range(flat.GetNumberOfPoints())])
    assert np.allclose(points[:, 2], 0.0), "the flat mesh lies in z = 0"

    distortion = itk.FlatteningDistortionCalculator.New()
    distortion.SetSurfaceMesh(surface)
    distortion.SetFlatMesh(flat)
    distortion.Compute()
    assert distortion.GetEdgeStrainP95() < 0.01, distortion.GetEdgeStrainP95()
    assert distortion.GetNumberOfFlippedTriangles() == 0

    # Per-vertex texture.
    textured = itk.layered_texture_mesh_filter(surface, volume=volume, number_of_layers=5, layer_spacing=0.05)
    values = np.array([textured.GetPointData().GetElement(i) for i in range(textured.GetNumberOfPoints())])
    assert values.size == surface.GetNumberOfPoints() and np.isfinite(values).all()

    # Per-pixel texture (a source: the template is named).
    texturer = itk.FlattenedTextureImageFilter[itk.Image[itk.F, 3], itk.Image[itk.F, 2], mesh_type].New(
        SurfaceMesh=surface, FlatMesh=flat, Volume=volume, PixelSize=0.05, NumberOfLayers=5, LayerSpacing=0.05,
        LayerFilter=itk.TextureLayersEnums.Filter_Max)
    texturer.Update()
    texture = itk.array_view_from_image(texturer.GetOutput())
    sheet = itk.array_view_from_image(texturer.GetMaskOutput()) > 0
    assert sheet.mean() > 0.5, sheet.mean()
    assert np.isfinite(texture[sheet]).all() and np.isnan(texture[~sheet]).all()
    layers = itk.array_view_from_image(texturer.GetLayerStackOutput())
    assert layers.shape[0] == 5
    # Restoration of the texture (static functions of LayerStackTexture): NaN stays NaN.
    restored = itk.LayerStackTexture.Deconvolve(
        itk.LayerStackTexture.EdgePreservingSmooth(
            texturer.GetOutput(), 0.1, 2.0 * itk.LayerStackTexture.NoiseSpread(texturer.GetOutput())), 0.06, 0.1)
    restored_array = itk.array_view_from_image(restored)
    assert np.isfinite(restored_array[sheet]).all() and np.isnan(restored_array[~sheet]).all()
    assert abs(np.median(restored_array[sheet]) - np.median(texture[sheet])) < 0.2 * np.std(texture[sheet])
    print(f"[ figures ] {label}: "
          f"{surface.GetNumberOfPoints()} points, strain p95 {distortion.GetEdgeStrainP95():.1e}, "
          f"texture {texture.shape[::-1]}, sheet {sheet.mean():.1%}")

# Reader and writer round trip through MetaImage.
path = os.path.join(output_dir, "phantom.mha")
writer = itk.CTVolumeWriter.New(Input=volume, FileName=path)
writer.SetFormat(itk.CTVolumeWriter.FormatType_MetaImage)
writer.Write()
reader = itk.CTVolumeReader.New(FileName=path)
reader.Update()
read_back = itk.array_view_from_image(reader.GetOutput())
assert read_back.shape == array.shape
assert np.abs(read_back - array).max() <= 0.51 + 1e-3, np.abs(read_back - array).max()  # int16 HU

# Legibility of a rendered word (needs tesseract).
ink = itk.SheetPhantomSource.New(Text="HELLO", NumberOfTurns=1.0)
ink.Update()
legibility = itk.TextLegibility.New(Image=ink.GetInkImage(), TruthText="HELLO", InkIsBright=True)
legibility.Compute()
print(f"[ figures ] tesseract read {legibility.GetRecognizedText().strip()!r}, CER {legibility.GetCharacterErrorRate():.2f}")
assert legibility.GetCharacterErrorRate() <= 0.2

#!/usr/bin/env python3
"""The whole pipeline from Python on the standard rolled phantom.

    pipeline_test.py OUTPUT_DIR [VIRTUAL_UNWRAP]

Writes the standard phantom as a DICOM series from Python (SheetPhantomSource +
CTVolumeWriter), reads it back (CTVolumeReader), unwraps it with the wrapped filters and
compares the texture with the ground-truth ink, with TextureFidelityCalculator and with
numpy. With VIRTUAL_UNWRAP (the C++ tool) it runs the tool on the same series and requires
the same texture, pixel for pixel (and so the same NCC).
"""
import json
import os
import subprocess
import sys

import numpy as np

import itk

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vu_pipeline  # noqa: E402

output_dir = sys.argv[1]
tool = sys.argv[2] if len(sys.argv) > 2 else None
os.makedirs(output_dir, exist_ok=True)

# 1. Synthesise the phantom and write it as a DICOM series.
phantom = itk.SheetPhantomSource.New()
phantom.ApplyPreset("standard")
phantom.Update()
series_dir = os.path.join(output_dir, "dicom")
writer = itk.CTVolumeWriter.New()
writer.SetInput(phantom.GetOutput())
writer.SetFileName(series_dir)
writer.Write()
ink = phantom.GetInkImage()
print(f"[ figures ] phantom {tuple(phantom.GetOutput().GetLargestPossibleRegion().GetSize())}, "
      f"ink {tuple(ink.GetLargestPossibleRegion().GetSize())}, text {phantom.GetText()!r}")

# 2. Read it back as a lab would.
reader = itk.CTVolumeReader.New()
reader.SetFileName(series_dir)
reader.Update()
volume = reader.GetOutput()
assert reader.GetModality() == "CT", reader.GetModality()
assert tuple(volume.GetLargestPossibleRegion().GetSize()) == tuple(
    phantom.GetOutput().GetLargestPossibleRegion().GetSize())

# 3. Unwrap.
result = vu_pipeline.unwrap(volume)
surface, flat = result["surface"], result["flat"]
print(f"[ figures ] mesh {surface.GetNumberOfPoints()} points, {surface.GetNumberOfCells()} cells; "
      f"sheet thickness {result['surface_filter'].GetSheetThickness():.3f} mm; {result['layers']} layers; "
      f"chosen texture {result['chosen']}")
assert surface.GetNumberOfPoints() == flat.GetNumberOfPoints()

# Mesh accuracy against the ground truth and distortion of the flattening.
error = itk.SheetMeshErrorCalculator.New()
error.SetPhantom(phantom)
error.SetMesh(surface)
error.SetVoxelSize(min(volume.GetSpacing()))
error.Compute()
distortion = itk.FlatteningDistortionCalculator.New()
distortion.SetSurfaceMesh(surface)
distortion.SetFlatMesh(flat)
distortion.Compute()
print(f"[ figures ] mesh error {error.GetMeanVertexDistance():.3f} voxel, coverage {error.GetCoverage():.4f}; "
      f"edge strain p95 {distortion.GetEdgeStrainP95():.2e}, flipped {distortion.GetNumberOfFlippedTriangles()}")
assert error.GetMeanVertexDistance() < 0.5
assert error.GetCoverage() > 0.98
assert distortion.GetEdgeStrainP95() < 0.01
assert distortion.GetNumberOfFlippedTriangles() == 0

# 4. Texture against the ground truth.
texture = result["texture"]
fidelity = vu_pipeline.texture_ncc(ink, texture)
ncc = fidelity.GetNormalizedCrossCorrelation()
print(f"[ figures ] Python texture NCC {ncc:.4f} (mirrored {fidelity.GetMirrored()}, "
      f"rotation {fidelity.GetRotationDegrees():.1f} deg)")
itk.imwrite(texture, os.path.join(output_dir, "texture.tif"))

# The same figure with numpy, on the aligned texture: Pearson correlation over the pixels
# where both images have values.
aligned = itk.array_from_image(fidelity.GetAlignedTexture())
reference = itk.array_from_image(ink)
assert aligned.shape == reference.shape, (aligned.shape, reference.shape)
valid = np.isfinite(aligned) & np.isfinite(reference)
a = aligned[valid] - aligned[valid].mean()
b = reference[valid] - reference[valid].mean()
numpy_ncc = float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum()))
print(f"[ figures ] numpy NCC on the aligned texture {numpy_ncc:.4f} over {valid.mean():.1%} of the ink image")
assert ncc >= 0.85, ncc
assert numpy_ncc >= 0.85, numpy_ncc

# The Python example (examples/unwrap_scroll.py), the same job in a page, reads as well.
example = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "unwrap_scroll.py")
example_texture = os.path.join(output_dir, "example.tif")
subprocess.run([sys.executable, example, series_dir, example_texture], check=True)
example_ncc = vu_pipeline.texture_ncc(ink, itk.imread(example_texture, itk.F)).GetNormalizedCrossCorrelation()
print(f"[ figures ] examples/unwrap_scroll.py texture NCC {example_ncc:.4f}")
assert abs(example_ncc - ncc) <= 0.01, (example_ncc, ncc)

# 5. The C++ tool on the same series must agree.
if tool:
    # The tool links the system's ITK: run it without the test driver's library path, which
    # points at the Python build's ITK.
    tool_env = {k: v for k, v in os.environ.items() if k not in ("LD_LIBRARY_PATH", "PYTHONPATH")}
    tool_out = os.path.join(output_dir, "tool")
    truth_dir = os.path.join(output_dir, "truth")
    subprocess.run([tool, "phantom", "standard", "-o", truth_dir, "--force"], check=True,
                   stdout=subprocess.DEVNULL, env=tool_env)
    subprocess.run([tool, "unwrap", series_dir, "-o", tool_out, "--ground-truth", truth_dir], check=True,
                   stdout=subprocess.DEVNULL, env=tool_env)
    with open(os.path.join(tool_out, "report.json")) as f:
        tool_ncc = json.load(f)["legibility"]["texture_ncc"]
    print(f"[ figures ] C++ tool texture NCC {tool_ncc:.4f}; difference {abs(tool_ncc - ncc):.4f}")
    assert abs(tool_ncc - ncc) <= 0.01, (tool_ncc, ncc)
    # Pixel for pixel: the tool and the Python pipeline run the same filters with the same
    # defaults, so their textures are the same image (holes as NaN in both).
    tool_pixels = itk.array_from_image(itk.imread(os.path.join(tool_out, "texture.tif"), itk.F))
    python_pixels = itk.array_from_image(texture)
    assert tool_pixels.shape == python_pixels.shape, (tool_pixels.shape, python_pixels.shape)
    same = (tool_pixels == python_pixels) | (np.isnan(tool_pixels) & np.isnan(python_pixels))
    differing = int(np.count_nonzero(~same))
    largest = float(np.nanmax(np.abs(tool_pixels - python_pixels))) if differing else 0.0
    print(f"[ figures ] Python and C++ textures, {python_pixels.shape[1]} x {python_pixels.shape[0]} pixels: "
          f"{differing} differ (largest difference {largest:.3g})")
    assert differing == 0, (differing, largest)
else:
    print("[ skipped ] no virtual-unwrap given: the comparison with the C++ tool did not run")

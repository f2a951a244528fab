#!/usr/bin/env python3
"""Bad input reaches Python as a RuntimeError with a one-line reason, never a crash.

    bad_input_test.py OUTPUT_DIR
"""
import os
import sys

import itk

output_dir = sys.argv[1]
os.makedirs(output_dir, exist_ok=True)


def expect_error(what, function, *words):
    try:
        function()
    except RuntimeError as error:  # itk.ExceptionObject arrives as RuntimeError
        message = str(error)
        assert all(w.lower() in message.lower() for w in words), f"{what}: {message}"
        print(f"[ refused ] {what}: {message.strip().splitlines()[-1]}")
        return
    raise AssertionError(f"{what}: no error")


reader = itk.CTVolumeReader.New(FileName=os.path.join(output_dir, "missing"))
expect_error("missing input", reader.Update, "no such file")

empty = itk.Image[itk.UC, 3].New()
empty.SetRegions([16, 16, 16])
empty.Allocate()
empty.FillBuffer(0)
surface_filter = itk.SheetMidSurfaceMeshFilter[itk.Image[itk.UC, 3], itk.Mesh[itk.F, 3]].New(Input=empty)
expect_error("empty mask", surface_filter.Update, "empty")

distortion = itk.FlatteningDistortionCalculator.New()
expect_error("wrong data object as a mesh", lambda: distortion.SetSurfaceMesh(empty), "unsupported mesh type")

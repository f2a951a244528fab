#!/usr/bin/python3
"""Builds the tilted CT series of this folder from the Philips head CT in ../philips_ct.

Every slice of philips_ct/S2010 (512 x 512, 0.451 mm pixels, 28 slices 5 mm apart) is
binned 8 x 8 (mean of the stored values: 64 x 64, 3.61 mm pixels) and its header is
rewritten into the sheared stack a CT with a tilted gantry writes:
  ImagePositionPatient  y -= tan(tilt) * (z - z of the first slice)   (z: along the normal)
  GantryDetectorTilt    = tilt
with new Study/Series/SOP Instance UIDs. Pixel values, orientation, rescale and the other
tags are the scanner's. Two series are written:
  gantry18/      18.5 degree tilt, 28 slices 5 mm apart (as acquired)
  gantry18_4to7/ 18.5 degree tilt, the first 14 slices 4 mm apart, the rest 7 mm apart
                 (only ImagePositionPatient and SliceLocation change: the pixels stay those
                 of the 5 mm slices)
Run with Debian's python3 (python3-pydicom, python3-numpy) from this folder:
  /usr/bin/python3 make_tilted_series.py
"""
import math
import os

import numpy as np
import pydicom
from pydicom.uid import generate_uid

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "philips_ct", "S2010")
HERE = os.path.dirname(os.path.abspath(__file__))
TILT = 18.5
BIN = 8


def slices():
    files = [os.path.join(SOURCE, f"I{i}") for i in range(10, 290, 10)]
    data = [pydicom.dcmread(f) for f in files]
    return sorted(data, key=lambda d: float(d.ImagePositionPatient[2]))


def write(name, spacings, description):
    out = os.path.join(HERE, name)
    os.makedirs(out, exist_ok=True)
    study, series, frame = generate_uid(), generate_uid(), generate_uid()
    source = slices()
    z0 = float(source[0].ImagePositionPatient[2])
    z = z0
    for k, d in enumerate(source):
        if k > 0:
            z += spacings[k - 1]
        pixels = d.pixel_array.astype(np.float64)
        rows, columns = pixels.shape
        binned = pixels.reshape(rows // BIN, BIN, columns // BIN, BIN).mean(axis=(1, 3))
        d.PixelData = np.round(binned).astype(d.pixel_array.dtype).tobytes()
        d.Rows, d.Columns = rows // BIN, columns // BIN
        spacing = [float(v) for v in d.PixelSpacing]
        x, y, _ = (float(v) for v in d.ImagePositionPatient)
        # The centre of a binned pixel is the mean of the centres it covers.
        x += 0.5 * (BIN - 1) * spacing[1]
        y += 0.5 * (BIN - 1) * spacing[0]
        y -= math.tan(math.radians(TILT)) * (z - z0)
        d.PixelSpacing = [round(s * BIN, 6) for s in spacing]
        d.ImagePositionPatient = [round(x, 4), round(y, 4), round(z, 4)]
        d.SliceLocation = round(z, 4)
        d.GantryDetectorTilt = TILT
        d.StudyInstanceUID, d.SeriesInstanceUID, d.FrameOfReferenceUID = study, series, frame
        d.SOPInstanceUID = generate_uid()
        d.file_meta.MediaStorageSOPInstanceUID = d.SOPInstanceUID
        d.SeriesDescription = description
        for tag in ("SpacingBetweenSlices",):
            if tag in d and len(set(spacings)) > 1:
                delattr(d, tag)
        d.save_as(os.path.join(out, f"IM{k:03d}.dcm"))


write("gantry18", [5.0] * 27, "head CT, gantry tilt 18.5 deg")
write("gantry18_4to7", [4.0] * 13 + [7.0] * 14,
      "head CT, gantry tilt 18.5 deg, spacing 4 then 7 mm")

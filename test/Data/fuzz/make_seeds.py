#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets (test/fuzz/): small valid inputs of every
format a parser reads, from which the fuzzers mutate. Run from anywhere; rewrites the
folders beside this script. The DICOM seeds are slices of the tilted CT series in
test/Data/dicom/tilted_ct (license there). Files named found-* are inputs the fuzzers
found that once crashed or hung a parser, kept so that every replay tries them again
(the DICOM ones are mutations of those slices, under the same license)."""
import gzip
import io
import pathlib
import shutil
import struct

import numpy as np
import tifffile

HERE = pathlib.Path(__file__).resolve().parent


def folder(name):
    """A target's seed folder, emptied but for the inputs the fuzzers found ("found-*":
    kept as regression seeds, each a mutation of a seed written here)."""
    path = HERE / name
    path.mkdir(exist_ok=True)
    for entry in path.iterdir():
        if not entry.name.startswith("found-"):
            shutil.rmtree(entry) if entry.is_dir() else entry.unlink()
    return path


# A 3 x 4 grid sheet: 12 points, 12 triangles.
POINTS = [(0.5 * c, 0.1 * r * r, 0.5 * r) for r in range(3) for c in range(4)]
TRIANGLES = []
for r in range(2):
    for c in range(3):
        a = 4 * r + c
        TRIANGLES += [(a, a + 1, a + 4), (a + 1, a + 5, a + 4)]

mesh = folder("vuFuzzMeshReader")
(mesh / "grid.obj").write_text(
    "# grid\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in POINTS)
    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in TRIANGLES))
(mesh / "grid_uv.obj").write_text(
    "".join(f"v {x} {y} {z}\n" for x, y, z in POINTS)
    + "".join(f"vt {x} {z}\n" for x, y, z in POINTS)
    + "".join(f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}\n" for a, b, c in TRIANGLES))
(mesh / "grid.off").write_text(
    f"OFF\n{len(POINTS)} {len(TRIANGLES)} 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in POINTS)
    + "".join(f"3 {a} {b} {c}\n" for a, b, c in TRIANGLES))
(mesh / "grid.vtk").write_text(
    "# vtk DataFile Version 3.0\ngrid\nASCII\nDATASET POLYDATA\n"
    f"POINTS {len(POINTS)} float\n" + "".join(f"{x} {y} {z}\n" for x, y, z in POINTS)
    + f"POLYGONS {len(TRIANGLES)} {4 * len(TRIANGLES)}\n" + "".join(f"3 {a} {b} {c}\n" for a, b, c in TRIANGLES))
binary = io.BytesIO()
binary.write(b"# vtk DataFile Version 3.0\ngrid\nBINARY\nDATASET POLYDATA\n")
binary.write(f"POINTS {len(POINTS)} float\n".encode())
binary.write(b"".join(struct.pack(">3f", *p) for p in POINTS) + b"\n")
binary.write(f"POLYGONS {len(TRIANGLES)} {4 * len(TRIANGLES)}\n".encode())
binary.write(b"".join(struct.pack(">4i", 3, *t) for t in TRIANGLES) + b"\n")
(mesh / "grid_binary.vtk").write_bytes(binary.getvalue())
rows = " ".join(str(r) for r in range(3) for c in range(4))
columns = " ".join(str(c) for r in range(3) for c in range(4))
(mesh / "grid.vtp").write_text(f"""<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="{len(POINTS)}" NumberOfPolys="{len(TRIANGLES)}">
      <PointData>
        <DataArray type="Int32" Name="GridRow" format="ascii">{rows}</DataArray>
        <DataArray type="Int32" Name="GridColumn" format="ascii">{columns}</DataArray>
      </PointData>
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">{" ".join(f"{x} {y} {z}" for x, y, z in POINTS)}</DataArray>
      </Points>
      <Polys>
        <DataArray type="Int32" Name="connectivity" format="ascii">{" ".join(f"{a} {b} {c}" for a, b, c in TRIANGLES)}</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">{" ".join(str(3 * (i + 1)) for i in range(len(TRIANGLES)))}</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
""")

# Volumes of 6 x 5 x 4 voxels, int16, a bright slab in air.
volume = np.full((4, 5, 6), -1000, dtype="<i2")
volume[:, 2, :] = 300
raw = volume.tobytes()
image = folder("vuFuzzImageFile")
header = ("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
          "TransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = 0 0 0\nElementSpacing = 0.1 0.1 0.2\n"
          "DimSize = 6 5 4\nElementType = MET_SHORT\n")
(image / "raw.mha").write_bytes((header + "ElementDataFile = LOCAL\n").encode() + raw)
import zlib
(image / "compressed.mha").write_bytes(
    (header.replace("BinaryData = True\n", "BinaryData = True\nCompressedData = True\n")
     + f"CompressedDataSize = {len(zlib.compress(raw))}\nElementDataFile = LOCAL\n").encode() + zlib.compress(raw))
nrrd = ("NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: 6 5 4\n"
        "space directions: (0.1,0,0) (0,0.1,0) (0,0,0.2)\nkinds: domain domain domain\nendian: little\n"
        "space origin: (0,0,0)\n")
(image / "raw.nrrd").write_bytes((nrrd + "encoding: raw\n\n").encode() + raw)
(image / "gzip.nrrd").write_bytes((nrrd + "encoding: gzip\n\n").encode() + gzip.compress(raw))
(image / "ascii.nrrd").write_bytes(
    (nrrd + "encoding: ascii\n\n" + " ".join(str(v) for v in volume.ravel()) + "\n").encode())

dicom = folder("vuFuzzDicomSeries")
series = HERE.parent / "dicom" / "tilted_ct" / "gantry18"
for name in ("IM002.dcm", "IM014.dcm"):
    shutil.copy(series / name, dicom / name)

stack = folder("vuFuzzTiffStack")
slice_ = io.BytesIO()
tifffile.imwrite(slice_, (np.arange(48, dtype=np.uint16) * 997).reshape(6, 8))
tiff = slice_.getvalue()
(stack / "folder").write_bytes(b"\x00slice1.tif\nslice2.tif\nslice10.tif\x00" + tiff)
(stack / "glob").write_bytes(b"\x01slice*.tif\nslice1.tif\nslice2.tif\nnotes.txt\x00" + tiff)
(stack / "uppercase").write_bytes(b"\x00A_0001.TIFF\nA_0002.TIFF\x00" + tiff)
float_slice = io.BytesIO()
tifffile.imwrite(float_slice, np.linspace(-1, 1, 48, dtype=np.float32).reshape(6, 8))
(stack / "float").write_bytes(b"\x00s_1.tif\ns_2.tif\x00" + float_slice.getvalue())

options = folder("vuFuzzOptions")
for name, line in {
    "roi": "--roi 0 0 0 10 10 10",
    "roi_mm": "--roi-mm -1.5 0 0 2.5 3 4",
    "spacing": "--spacing 0.1 0.1 0.25",
    "shrink": "--shrink 2 --slice-tolerance 0.1 --interpolator linear",
    "series": "--series 1.2.840.113619 --resample-spacing 0.5 --no-resample",
    "mesh_spacing_pair": "--mesh-spacing 0.5,auto",
    "mesh_spacing": "--mesh-spacing 0.3",
    "lock": "--lock 0 3 11",
    "locked_edge": "--locked-edge inner --integrator rk4 --time-step 0.001",
    "simulation": "--stiffness 200 --restitution 0.5 --max-steps 10 --coarse-particles 8",
}.items():
    (options / name).write_text("\n".join(line.split(" ")))

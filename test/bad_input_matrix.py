#!/usr/bin/env python3
"""Bad-input matrix of virtual-unwrap: malformed inputs and impossible options over every
subcommand. Each case must end with a non-zero exit status (not a signal), exactly one
line "virtual-unwrap: error: ..." on standard error, as its last line, naming the problem
(a pattern), no output left behind, and every input file unchanged.

Usage: bad_input_matrix.py TOOL TEST_DATA_DIR WORK_DIR [CASE_NAME_PART]
Needs only the Python standard library."""

import hashlib
import os
import re
import shutil
import struct
import subprocess
import sys


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)
    return path


def mha(path, size, spacing=(1.0, 1.0, 1.0), values=None, element="MET_FLOAT", claim=None, raw=None):
    """A MetaImage with its data inline; `claim` overrides the DimSize written in the header,
    `raw` the bytes written after it."""
    count = size[0] * size[1] * size[2]
    if raw is None:
        values = values if values is not None else [0.0] * count
        raw = struct.pack("<%df" % count, *values)
    dims = claim if claim is not None else size
    header = ("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
              "DimSize = %d %d %d\nElementSpacing = %g %g %g\nElementType = %s\nElementDataFile = LOCAL\n"
              % (dims[0], dims[1], dims[2], spacing[0], spacing[1], spacing[2], element))
    return write(path, header.encode() + raw)


def sheet_values(n=24):
    """A volume with a bright slab through it: enough for the reader, not a sheet to unwrap."""
    values = []
    for z in range(n):
        for y in range(n):
            for x in range(n):
                values.append(1000.0 if abs(x - n // 2) <= 1 else -1000.0)
    return values


def quad_obj(path, vertices=None, faces=None):
    vertices = vertices if vertices is not None else ["0 0 0", "1 0 0", "0 1 0", "1 1 0"]
    faces = faces if faces is not None else ["1 2 3", "2 4 3"]
    return write(path, "".join("v %s\n" % v for v in vertices) + "".join("f %s\n" % f for f in faces))


def digest(paths):
    result = {}
    for root in paths:
        files = [root] if os.path.isfile(root) else [os.path.join(d, f) for d, _, fs in os.walk(root) for f in fs]
        for f in files:
            with open(f, "rb") as handle:
                result[f] = hashlib.sha256(handle.read()).hexdigest()
    return result


def main():
    tool, data, work = (os.path.abspath(a) for a in sys.argv[1:4])
    only = sys.argv[4] if len(sys.argv) > 4 else ""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    w = lambda *p: os.path.join(work, *p)
    philips = os.path.join(data, "dicom", "philips_ct", "S2010")

    # Inputs.
    ok_volume = mha(w("in", "slab.mha"), (24, 24, 24), values=sheet_values())
    constant = mha(w("in", "constant.mha"), (12, 12, 12), values=[5.0] * 1728)
    nan_volume = mha(w("in", "nan.mha"), (12, 12, 12), values=[float("nan")] * 1728)
    inf_volume = mha(w("in", "inf.mha"), (12, 12, 12), values=[float("inf")] * 4 + [0.0] * 1724)
    zero_spacing = mha(w("in", "zero_spacing.mha"), (12, 12, 12), spacing=(1.0, 0.0, 1.0))
    truncated = mha(w("in", "truncated.mha"), (12, 12, 12), raw=b"\0" * 1000)
    huge = mha(w("in", "huge.mha"), (12, 12, 12), claim=(200000, 200000, 200000), raw=b"\0" * 64)
    garbage = write(w("in", "garbage.mha"), bytes(range(256)) * 8)
    compressed_header = ("ObjectType = Image\nNDims = 3\nDimSize = %s\nElementType = MET_SHORT\n"
                         "CompressedData = True\n%sElementDataFile = LOCAL\n")
    huge_compressed_size = write(w("in", "huge_compressed_size.mha"),
                                 (compressed_header % ("6 5 4", "CompressedDataSize = 9223372036854775808\n"))
                                 .encode() + bytes(64))
    huge_inflation = write(w("in", "huge_inflation.mha"),
                           (compressed_header % ("6000 5000 4000", "")).encode() + bytes(64))
    # Found by fuzzing: a header line without '=' (MetaIO reads it into the next field's name,
    # finds the data elsewhere and inflates it for ever).
    with open(os.path.join(data, "fuzz", "vuFuzzImageFile", "found-line-without-equals"), "rb") as f:
        line_without_equals = write(w("in", "line_without_equals.mha"), f.read())
    nrrd_header = ("NRRD0004\ntype: short\ndimension: 3\nsizes: %s\nendian: little\nencoding: %s\n\n")
    huge_nrrd = write(w("in", "huge.nrrd"), (nrrd_header % ("60000 50000 40000", "raw")).encode() + bytes(64))
    huge_gzip_nrrd = write(w("in", "huge_gzip.nrrd"), (nrrd_header % ("60000 50000 40000", "gzip")).encode() + bytes(64))
    text = write(w("in", "notes.txt"), "not a volume\n")
    empty_file = write(w("in", "empty.nrrd"), b"")
    os.makedirs(w("in", "empty_dir"))
    flat_2d = mha(w("in", "flat.mha"), (12, 12, 1), values=[0.0] * 144)
    # A DICOM series with one slice truncated.
    names = sorted(f for f in os.listdir(philips) if f.startswith("I"))
    os.makedirs(w("in", "dicom_truncated"))
    for f in names:
        shutil.copy(os.path.join(philips, f), w("in", "dicom_truncated", f))
    victim = w("in", "dicom_truncated", names[len(names) // 2])
    with open(victim, "r+b") as handle:
        handle.truncate(os.path.getsize(victim) // 3)
    empty_obj = write(w("in", "empty.obj"), "")
    # Found by fuzzing: a VTK XML mesh claiming 42949672963 components a point.
    with open(os.path.join(data, "fuzz", "vuFuzzMeshReader", "found-vtp-huge-components"), "rb") as f:
        huge_vtp = write(w("in", "huge_components.vtp"), f.read())
    # Found by fuzzing: compressed MetaImage data on which MetaIO's inflation never ends.
    with open(os.path.join(data, "fuzz", "vuFuzzImageFile", "found-inflate-loop"), "rb") as f:
        damaged_stream = write(w("in", "damaged_stream.mha"), f.read())
    # Found by fuzzing: a TIFF directory giving the image length twice (libtiff keeps the
    # first, 2^32 rows, and sizes its strip table from it). The seed holds file names
    # first, then the TIFF's bytes after a NUL byte.
    with open(os.path.join(data, "fuzz", "vuFuzzTiffStack", "found-duplicate-length"), "rb") as f:
        seed = f.read()
        duplicate_length = write(w("in", "duplicate_length.tif"), seed[seed.index(b"\0", 1) + 1:])
    nan_obj = quad_obj(w("in", "nan_vertex.obj"), vertices=["0 0 0", "1 0 0", "nan 1 0", "1 1 0"])
    inf_obj = quad_obj(w("in", "inf_vertex.obj"), vertices=["0 0 0", "1 0 0", "0 inf 0", "1 1 0"])
    short_obj = quad_obj(w("in", "short_vertex.obj"), vertices=["0 0 0", "1 0", "0 1 0", "1 1 0"])
    points_obj = quad_obj(w("in", "points_only.obj"), faces=[])
    beyond_obj = quad_obj(w("in", "beyond.obj"), faces=["1 2 3", "2 4 9"])
    repeat_obj = quad_obj(w("in", "repeat.obj"), faces=["1 2 3", "2 2 3"])
    binary_obj = write(w("in", "binary.obj"), bytes(range(256)) * 4)
    good_obj = quad_obj(w("in", "good.obj"))
    tri_obj = quad_obj(w("in", "one_triangle.obj"), faces=["1 2 3"])
    garbage_vtp = write(w("in", "garbage.vtp"), "<VTKFile type='PolyData'><broken")
    garbage_off = write(w("in", "garbage.off"), "OFF\n4 2 0\n0 0 0\n1 0\n")
    garbage_vtk = write(w("in", "garbage.vtk"), "# vtk DataFile Version 3.0\nbroken\nASCII\nDATASET POLYDATA\nPOINTS 9 float\n1 2\n")

    out = lambda name: w("out", name)
    missing = w("in", "missing.mha")
    cases = [
        # info: the reader, whatever the input.
        ("info missing path", ["info", missing], "no such file or directory"),
        ("info empty directory", ["info", w("in", "empty_dir")], "directory is empty"),
        ("info text file", ["info", text], "(cannot read|not a|no reader|unknown|format)"),
        ("info empty file", ["info", empty_file], "(cannot read|empty|no reader|format)"),
        ("info garbage mha", ["info", garbage], "(cannot read|header|format|MetaImage)"),
        ("info truncated mha", ["info", truncated], "(cannot read|short|truncated|size|bytes)"),
        ("info CompressedDataSize beyond the file", ["info", huge_compressed_size], "CompressedDataSize"),
        ("info compressed data too small for its image", ["info", huge_inflation], "cannot hold an image"),
        ("info damaged compressed data", ["info", damaged_stream], "(compressed data is damaged|cannot read)"),
        ("info header claims 8e15 voxels", ["info", huge], "(too large|voxels|memory|size|cannot read|bytes)"),
        ("info TIFF geometry tag given twice", ["info", duplicate_length], "more than once"),
        ("info NRRD claims 1.2e14 voxels in 64 bytes", ["info", huge_nrrd], "cannot hold an image"),
        ("unwrap gzip NRRD claims 1.2e14 voxels", ["unwrap", huge_gzip_nrrd, "-o", out("uw_huge_nrrd"), "-q"],
         "cannot hold an image"),
        ("info MetaImage header line without =", ["info", line_without_equals], "not a MetaImage field"),
        ("info zero spacing", ["info", zero_spacing], "spacing"),
        ("info 2D image", ["info", flat_2d], "(single 2D|2D|one slice|3D)"),
        ("info negative --spacing", ["info", ok_volume, "--spacing", "1", "-1", "1"], "--spacing"),
        ("info --roi outside", ["info", ok_volume, "--roi", "0", "0", "20", "10", "10", "10"], "not inside"),
        ("info --roi not numbers", ["info", ok_volume, "--roi", "a", "b", "c", "1", "2", "3"], "--roi"),
        ("info --roi-mm outside", ["info", ok_volume, "--roi-mm", "-90", "-90", "-90", "-80", "-80", "-80"], "(--roi-mm|outside|not inside|does not)"),
        ("info --shrink 0", ["info", ok_volume, "--shrink", "0"], "--shrink"),
        ("info --series absent", ["info", philips, "--series", "77"], "no series '77'"),
        ("info DICOM truncated slice", ["info", w("in", "dicom_truncated")], "(truncated|cannot read|slice|I[0-9]+)"),
        ("info -o into a missing folder", ["info", ok_volume, "-o", w("no", "such", "dir", "info.json")],
         "(cannot write|no such|directory)"),
        ("info no input", ["info"], "required"),
        ("unknown subcommand", ["unroll", ok_volume], "(unroll|subcommand|not expected)"),
        # segment and unwrap: volumes with nothing to segment, impossible options.
        ("segment constant volume", ["segment", constant, "-o", out("seg_constant")], "constant"),
        ("segment all-NaN volume", ["segment", nan_volume, "-o", out("seg_nan")], "no finite voxel"),
        ("segment infinite values", ["segment", inf_volume, "-o", out("seg_inf")], "infinite"),
        ("segment threshold above maximum", ["segment", ok_volume, "-o", out("seg_thr"), "--threshold", "5000"],
         "threshold"),
        ("segment missing volume", ["segment", missing, "-o", out("seg_missing")], "no such file or directory"),
        ("unwrap constant volume", ["unwrap", constant, "-o", out("uw_constant"), "-q"], "constant"),
        ("unwrap all-NaN volume", ["unwrap", nan_volume, "-o", out("uw_nan"), "-q"], "no finite voxel"),
        ("unwrap infinite values", ["unwrap", inf_volume, "-o", out("uw_inf"), "-q"], "infinite"),
        ("unwrap garbage volume", ["unwrap", garbage, "-o", out("uw_garbage"), "-q"],
         "(cannot read|header|format|MetaImage)"),
        ("unwrap negative --mesh-spacing", ["unwrap", ok_volume, "-o", out("uw_ms"), "-q", "--mesh-spacing", "-1"],
         "--mesh-spacing"),
        ("unwrap even --layers with --side auto", ["unwrap", ok_volume, "-o", out("uw_layers"), "-q", "--layers", "4"],
         "odd number of --layers"),
        ("unwrap bad --restore", ["unwrap", ok_volume, "-o", out("uw_restore"), "-q", "--restore", "sharp"],
         "--restore"),
        ("unwrap missing --ground-truth", ["unwrap", ok_volume, "-o", out("uw_gt"), "-q", "--ground-truth",
                                            w("in", "no_truth")], "(ground.truth|no such)"),
        ("unwrap unknown --integrator", ["unwrap", ok_volume, "-o", out("uw_int"), "-q", "--integrator", "verlet"],
         "--integrator"),
        ("unwrap negative --time-step", ["unwrap", ok_volume, "-o", out("uw_dt"), "-q", "--time-step", "-1"],
         "--time-step"),
        ("unwrap --restitution above 1", ["unwrap", ok_volume, "-o", out("uw_kr"), "-q", "--restitution", "2"],
         "--restitution"),
        # flatten and distortion: meshes.
        ("flatten empty OBJ", ["flatten", empty_obj, "-o", out("f_empty.obj")], "no points"),
        ("flatten VTK XML claiming 4e10 components", ["flatten", huge_vtp, "-o", out("f_huge.obj")],
         "NumberOfComponents"),
        ("flatten NaN vertex", ["flatten", nan_obj, "-o", out("f_nan.obj")], ":3: vertex 3 has a non-finite"),
        ("flatten infinite vertex", ["flatten", inf_obj, "-o", out("f_inf.obj")], ":3: vertex 3 has a non-finite"),
        ("flatten vertex with two coordinates", ["flatten", short_obj, "-o", out("f_short.obj")],
         ":2: vertex 2 has fewer than three"),
        ("flatten points without triangles", ["flatten", points_obj, "-o", out("f_points.obj")], "no triangles"),
        ("flatten face beyond the points", ["flatten", beyond_obj, "-o", out("f_beyond.obj")],
         "(beyond|missing point|point)"),
        ("flatten face repeating a point", ["flatten", repeat_obj, "-o", out("f_repeat.obj")], "repeats a point"),
        ("flatten binary garbage OBJ", ["flatten", binary_obj, "-o", out("f_binary.obj")],
         "(cannot read|no points|vertex|triangle)"),
        ("flatten garbage VTP", ["flatten", garbage_vtp, "-o", out("f_vtp.obj")], "cannot read a mesh"),
        ("flatten garbage OFF", ["flatten", garbage_off, "-o", out("f_off.obj")], "(cannot read|no points|point)"),
        ("flatten garbage VTK", ["flatten", garbage_vtk, "-o", out("f_vtk.obj")], "(cannot read|no points|point)"),
        ("flatten missing mesh", ["flatten", w("in", "missing.obj"), "-o", out("f_missing.obj")],
         "mesh file not found"),
        ("flatten output not OBJ or VTP", ["flatten", good_obj, "-o", out("f_out.png")], "must end in .obj or .vtp"),
        ("flatten --lock not a number", ["flatten", good_obj, "-o", out("f_lock.obj"), "--lock", "x"], "--lock"),
        ("flatten --lock beyond the points", ["flatten", good_obj, "-o", out("f_lock2.obj"), "--lock", "99"],
         "(99|lock)"),
        ("distortion point counts differ", ["distortion", good_obj, tri_obj], "(points|differ|same)"),
        ("distortion NaN flat vertex", ["distortion", good_obj, nan_obj], ":3: vertex 3 has a non-finite"),
        ("distortion missing flat", ["distortion", good_obj, w("in", "missing.obj")], "mesh file not found"),
        # phantom: impossible parameters.
        ("phantom unknown preset", ["phantom", "spiral", "-o", out("ph_preset")], "(preset|spiral)"),
        ("phantom negative --turns", ["phantom", "standard", "-o", out("ph_turns"), "--turns", "-1"], "number of turns must be positive"),
        ("phantom unknown --format", ["phantom", "standard", "-o", out("ph_format"), "--format", "jpeg"],
         'unknown format "jpeg"'),
    ]
    inputs = digest([w("in"), philips])
    failures = []
    ran = 0
    for name, arguments, pattern in cases:
        if only and only not in name:
            continue
        ran += 1
        os.makedirs(w("out"), exist_ok=True)
        result = subprocess.run([tool] + arguments, capture_output=True, text=True, timeout=300, cwd=work)
        lines = [l for l in result.stderr.splitlines() if l.strip()]
        errors = [l for l in lines if l.startswith("virtual-unwrap: error: ")]
        problems = []
        if result.returncode <= 0:
            problems.append("exit status %d" % result.returncode)
        if len(errors) != 1 or not lines or lines[-1] != errors[0]:
            problems.append("not one error line, last: %r" % result.stderr[-300:])
        elif not re.search(pattern, errors[0]):
            problems.append("message %r does not match %r" % (errors[0], pattern))
        left = os.listdir(w("out"))
        if left:
            problems.append("output left behind: %s" % left)
        shutil.rmtree(w("out"))
        print("%-45s %s" % (name, "ok: " + errors[0][23:] if not problems else "FAILED: " + "; ".join(problems)))
        if problems:
            failures.append(name)
    if digest([w("in"), philips]) != inputs:
        failures.append("inputs changed")
        print("FAILED: an input file changed")
    print("%d cases, %d failed" % (ran, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

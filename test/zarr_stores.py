#!/usr/bin/env python3
"""Writes Zarr stores with python3-zarr (Debian) for ZarrImageIO's test, their shapes,
chunks, data types, compressors and layouts drawn at run time, and a manifest.json that
describes each store so that the reader's output can be checked voxel by voxel.

usage: zarr_stores.py OUTDIR [--seed N]

Every voxel holds value(x, y, z) = (a x + b y + c z + d) mod m (m the type's range for
integers; floats: a x + b y + c z + d with fractional coefficients), the coefficients drawn
per store. Stores:
  array-*      bare Zarr arrays (.zarray): blosc (every codec), zlib, gzip or raw chunks,
               "." or "/" separators, chunks that do not divide the shape, and one chunk
               left unwritten (all fill value) when the layout allows;
  ome          an OME-Zarr image (NGFF 0.4): a group with multiscales, two levels, axes in
               micrometres, a scale and a translation;
  ome-tczyx    OME-Zarr with time and channel axes of length 1;
  flat         a 2D array (not a volume).
"""
import argparse
import json
import os
import shutil
import sys

import numpy as np
import zarr
from numcodecs import Blosc, GZip, Zlib

TYPES = ["<u2", "<i2", "|u1", "<f4", "<u4", "<f8"]


def value_array(shape_zyx, dtype, coeff):
    z, y, x = np.meshgrid(*[np.arange(n) for n in shape_zyx], indexing="ij")
    a, b, c, d = coeff
    if np.dtype(dtype).kind == "f":
        return (a * x + b * y + c * z + d).astype(dtype)
    info = np.iinfo(dtype)
    span = int(info.max) - int(info.min) + 1
    v = (int(a) * x.astype(np.int64) + int(b) * y + int(c) * z + int(d)) % span + int(info.min)
    return v.astype(dtype)


def coefficients(rng, dtype):
    if np.dtype(dtype).kind == "f":
        return [float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)),
                float(rng.uniform(-100, 100))]
    return [int(rng.integers(1, 40)), int(rng.integers(1, 400)), int(rng.integers(1, 4000)),
            int(rng.integers(0, 1000))]


def compressor(rng, kind=None):
    kind = kind or rng.choice(["blosc", "blosc", "zlib", "gzip", "none"])
    if kind == "blosc":
        cname = str(rng.choice(["lz4", "lz4hc", "blosclz", "zstd", "zlib"]))
        shuffle = int(rng.choice([Blosc.NOSHUFFLE, Blosc.SHUFFLE, Blosc.BITSHUFFLE]))
        return Blosc(cname=cname, clevel=int(rng.integers(1, 9)), shuffle=shuffle), f"blosc-{cname}"
    if kind == "zlib":
        return Zlib(level=int(rng.integers(1, 9))), "zlib"
    if kind == "gzip":
        return GZip(level=int(rng.integers(1, 9))), "gzip"
    return None, "none"


def write_array(path, data, chunks, comp, separator, fill, hole):
    store = zarr.DirectoryStore(path, dimension_separator=separator)
    arr = zarr.create(data.shape, chunks=chunks, dtype=data.dtype, compressor=comp, store=store,
                     fill_value=fill, write_empty_chunks=False, overwrite=True)
    arr[...] = data
    if hole is not None:
        # One chunk holds only the fill value: zarr leaves its file out.
        arr[hole] = fill
    return arr


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--seed", type=int, default=None)
    args = p.parse_args()
    seed = args.seed if args.seed is not None else int.from_bytes(os.urandom(4), "little")
    rng = np.random.default_rng(seed)
    print(f"zarr_stores: seed {seed}")
    if os.path.exists(args.out):
        shutil.rmtree(args.out)
    os.makedirs(args.out)
    manifest = {"seed": seed, "stores": []}

    for i in range(6):
        dtype = TYPES[i % len(TYPES)]
        shape = [int(rng.integers(5, 23)) for _ in range(3)]
        chunks = [int(rng.integers(2, n + 1)) for n in shape]
        # Every kind of chunk storage and both separators, the rest drawn.
        comp, codec = compressor(rng, ["blosc", "zlib", "gzip", "none", "blosc", "blosc"][i])
        separator = "." if i % 2 == 0 else "/"
        coeff = coefficients(rng, dtype)
        data = value_array(shape, dtype, coeff)
        fill = 7
        grid = [-(-n // c) for n, c in zip(shape, chunks)]
        hole, hole_chunk = None, None
        if all(g >= 2 for g in grid):
            hole_chunk = [int(rng.integers(0, g - 1)) for g in grid]  # never an edge chunk
            hole = tuple(slice(h * c, (h + 1) * c) for h, c in zip(hole_chunk, chunks))
            data[hole] = fill
        name = f"array-{i}"
        write_array(os.path.join(args.out, name), data, chunks, comp, separator, fill, hole)
        manifest["stores"].append({"name": name, "kind": "array", "dtype": dtype, "shape_zyx": shape,
                                   "chunks_zyx": chunks, "codec": codec, "separator": separator,
                                   "coefficients": coeff, "fill": fill, "hole_chunk_zyx": hole_chunk})

    # OME-Zarr images.
    for name, lead in (("ome", []), ("ome-tczyx", [1, 1])):
        dtype = "<u2"
        shape = [int(rng.integers(8, 25)) for _ in range(3)]
        chunks = [int(rng.integers(3, n + 1)) for n in shape]
        comp, codec = compressor(rng)
        coeff = coefficients(rng, dtype)
        data = value_array(shape, dtype, coeff)
        scale = [float(rng.uniform(2, 40)) for _ in range(3)]        # micrometres
        translation = [float(rng.uniform(-500, 500)) for _ in range(3)]
        root = zarr.open_group(os.path.join(args.out, name), mode="w")
        full = root.create_dataset("0", shape=lead + shape, chunks=[1] * len(lead) + chunks, dtype=dtype,
                                   compressor=comp)
        full[...] = data.reshape(lead + shape)
        half = data[::2, ::2, ::2]
        root.create_dataset("1", data=half.reshape(lead + list(half.shape)), compressor=comp)
        axes = ([{"name": "t", "type": "time", "unit": "second"}, {"name": "c", "type": "channel"}] if lead else [])
        axes += [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
        ones = [1.0] * len(lead)
        zeros = [0.0] * len(lead)
        root.attrs["multiscales"] = [{
            "version": "0.4", "name": name, "axes": axes,
            "datasets": [
                {"path": "0", "coordinateTransformations": [
                    {"type": "scale", "scale": ones + scale},
                    {"type": "translation", "translation": zeros + translation}]},
                {"path": "1", "coordinateTransformations": [
                    {"type": "scale", "scale": ones + [2 * s for s in scale]},
                    {"type": "translation", "translation": zeros + translation}]}]}]
        manifest["stores"].append({"name": name, "kind": "ome", "dtype": dtype, "shape_zyx": shape,
                                   "chunks_zyx": chunks, "codec": codec, "separator": ".",
                                   "coefficients": coeff, "fill": 0, "hole_chunk_zyx": None,
                                   "scale_um_zyx": scale, "translation_um_zyx": translation})

    flat = zarr.open(os.path.join(args.out, "flat"), mode="w", shape=(12, 9), chunks=(5, 5), dtype="<u2")
    flat[...] = np.arange(108, dtype="<u2").reshape(12, 9)
    manifest["stores"].append({"name": "flat", "kind": "flat"})

    with open(os.path.join(args.out, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())

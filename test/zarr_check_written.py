#!/usr/bin/env python3
"""Reads with python3-zarr the OME-Zarr stores ZarrImageIO wrote in its test (listed in
written.json beside them) and checks every voxel, the chunking and the OME-NGFF
multiscales metadata.

usage: zarr_check_written.py STOREDIR
"""
import json
import os
import sys

import numpy as np
import zarr


def main():
    directory = sys.argv[1]
    with open(os.path.join(directory, "written.json")) as f:
        written = json.load(f)
    failures = 0
    for store in written:
        group = zarr.open_group(os.path.join(directory, store["name"]), mode="r")
        array = group["0"]
        nx, ny, nz = store["size_xyz"]
        z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
        expected = (7 * x + 13 * y + 29 * z + store["salt"]) % 3000
        values = array[...]
        edge = store["chunk_edge"]
        checks = {
            "shape": values.shape == (nz, ny, nx),
            "values": values.shape == expected.shape and np.array_equal(values.astype(np.float64), expected),
            "chunks": tuple(array.chunks) == tuple(min(edge, n) for n in (nz, ny, nx)),
            "compressor": (array.compressor is not None) == store["compressed"],
        }
        image = group.attrs["multiscales"][0]
        transforms = {t["type"]: t[t["type"]] for t in image["datasets"][0]["coordinateTransformations"]}
        checks["axes"] = [a["name"] for a in image["axes"]] == ["z", "y", "x"] and all(
            a["unit"] == "millimeter" for a in image["axes"])
        checks["scale"] = np.allclose(transforms["scale"], store["spacing_xyz"][::-1], rtol=0, atol=1e-12)
        checks["translation"] = np.allclose(transforms["translation"], store["origin_xyz"][::-1], rtol=0, atol=1e-12)
        bad = [k for k, ok in checks.items() if not ok]
        print(f"{store['name']}: {'ok' if not bad else 'FAILED ' + ', '.join(bad)} "
              f"({nx} x {ny} x {nz}, chunk edge {edge}, {store['streams']} stream divisions)")
        failures += len(bad)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Picture of a scan with several sheets for docs/segmentation.md: a slice across the
sheets (HU window -1100..1500) with each sheet's mesh cross-section in its own colour and
number, beside each sheet's texture.png, from `virtual-unwrap unwrap VOLUME -o UNWRAP_DIR`
with several sheets found (UNWRAP_DIR/sheet-NN).

Usage: /usr/bin/python3 scripts/sheets-figure.py OUT.png VOLUME.mha UNWRAP_DIR [TITLE]
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vu_mha import read_mha  # noqa: E402


def read_vertices(path):
    points = []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if fields and fields[0] == "v":
                points.append([float(v) for v in fields[1:4]])
    return np.array(points)


def main():
    out, volume_path, unwrap = sys.argv[1:4]
    title = sys.argv[4] if len(sys.argv) > 4 else ""
    volume, spacing, origin = read_mha(volume_path)
    with open(os.path.join(unwrap, "report.json")) as f:
        report = json.load(f)
    sheets = [s for s in report["sheets"] if "folder" in s]
    z = volume.shape[0] // 2
    colours = plt.get_cmap("tab10")
    rows = max(1, len(sheets))
    fig = plt.figure(figsize=(10, 1.3 * rows + 1))
    grid = fig.add_gridspec(rows, 2, width_ratios=[1.1, 1.0])
    ax = fig.add_subplot(grid[:, 0])
    ax.imshow(volume[z], cmap="gray", vmin=-1100, vmax=1500, origin="upper")
    for i, sheet in enumerate(sheets):
        points = read_vertices(os.path.join(unwrap, sheet["folder"], "surface.obj"))
        voxels = (points - np.array(origin)) / np.array(spacing)
        # The mesh row nearest the slice.
        nearest = voxels[np.argmin(np.abs(voxels[:, 2] - z)), 2]
        near = np.abs(voxels[:, 2] - nearest) < 0.25
        ax.plot(voxels[near, 0], voxels[near, 1], ".", ms=2.5, color=colours(i % 10))
        if np.any(near):
            ax.text(voxels[near, 0].max() + 2, np.median(voxels[near, 1]), str(sheet["sheet"]),
                    color=colours(i % 10), fontsize=8, va="center")
        tex = plt.imread(os.path.join(unwrap, sheet["folder"], "texture.png"))
        tax = fig.add_subplot(grid[i, 1])
        tax.imshow(tex, cmap="gray")
        tax.set_xticks([])
        tax.set_yticks([])
        tax.set_ylabel(str(sheet["sheet"]), rotation=0, labelpad=10, color=colours(i % 10))
    ax.set_title(f"slice {z}: each sheet's mesh", fontsize=9)
    if title:
        fig.suptitle(title, fontsize=10)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Pictures of segmentations for docs/segmentation.md: for each pair PHANTOM_DIR SEGMENT_DIR
(from `virtual-unwrap phantom PRESET -o PHANTOM_DIR --format mha` and
`virtual-unwrap segment PHANTOM_DIR/volume.mha -o SEGMENT_DIR`), the axial slice nearest the
middle mesh row (HU window -1100..1500) with the mask outline and that row of the mesh
(the traced mid-surface, vertices as dots, red at the inner end), next to the whole mesh seen
along the roll axis, saved as OUT/segment-<name>.png.

Usage: /usr/bin/python3 scripts/segmentation-overlay.py OUT PHANTOM_DIR SEGMENT_DIR [...]
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



def read_obj(path):
    points = []
    for line in open(path):
        fields = line.split()
        if fields and fields[0] == "v":
            points.append([float(v) for v in fields[1:4]])
    return np.array(points)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for phantom, segment in zip(sys.argv[2::2], sys.argv[3::2]):
        volume, spacing, origin = read_mha(os.path.join(phantom, "volume.mha"))
        mask, _, _ = read_mha(os.path.join(segment, "mask.mha"))
        with open(os.path.join(segment, "segment.json")) as f:
            summary = json.load(f)
        rows, columns = summary["grid"]["rows"], summary["grid"]["columns"]
        points = read_obj(os.path.join(segment, "surface.obj")).reshape(rows, columns, 3)
        row = points[rows // 2]
        k = int(round((row[0, 2] - origin[2]) / spacing[2]))
        extent = [origin[0] - 0.5 * spacing[0], origin[0] + (volume.shape[2] - 0.5) * spacing[0],
                  origin[1] + (volume.shape[1] - 0.5) * spacing[1], origin[1] - 0.5 * spacing[1]]
        figure, axes = plt.subplots(1, 2, figsize=(11, 5.2))
        axes[0].imshow(volume[k], cmap="gray", vmin=-1100, vmax=1500, extent=extent, interpolation="nearest")
        xs = origin[0] + np.arange(volume.shape[2]) * spacing[0]
        ys = origin[1] + np.arange(volume.shape[1]) * spacing[1]
        axes[0].contour(xs, ys, mask[k], levels=[0.5], colors="deepskyblue", linewidths=0.6)
        axes[0].plot(row[:, 0], row[:, 1], "-", color="yellow", linewidth=0.8)
        axes[0].plot(row[:, 0], row[:, 1], ".", color="orange", markersize=3)
        axes[0].plot(row[0, 0], row[0, 1], "o", color="red", markersize=5)
        axes[0].set_title("%s: slice z = %.2f mm, mask outline (blue), mesh row %d (yellow)"
                          % (os.path.basename(phantom.rstrip("/")), row[0, 2], rows // 2), fontsize=8)
        axes[0].tick_params(labelsize=6)
        for r in range(rows):
            axes[1].plot(points[r, :, 0], points[r, :, 1], "-", color="tab:blue", linewidth=0.3)
        for c in range(0, columns, max(1, columns // 40)):
            axes[1].plot(points[:, c, 0], points[:, c, 1], "-", color="tab:gray", linewidth=0.3)
        axes[1].plot(points[:, 0, 0], points[:, 0, 1], "o", color="red", markersize=3)
        axes[1].set_aspect("equal")
        axes[1].set_title("mesh seen along the roll axis: %d x %d grid, %s method, column 0 red"
                          % (rows, columns, summary["method"]), fontsize=8)
        axes[1].tick_params(labelsize=6)
        figure.tight_layout()
        figure.savefig(os.path.join(out, "segment-%s.png" % os.path.basename(phantom.rstrip("/"))), dpi=90)
        plt.close(figure)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Pictures of phantoms for docs/phantoms.md: for each DIR written by
`virtual-unwrap phantom PRESET -o DIR --format mha`, an axial slice (middle of the
roll axis, HU window -1100..1500) and the ground-truth ink image side by side, saved
as OUT/phantom-<preset>.png.

Usage: /usr/bin/python3 scripts/phantom-slices.py OUT DIR [DIR ...]
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vu_mha import read_mha  # noqa: E402



def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for directory in sys.argv[2:]:
        with open(os.path.join(directory, "ground_truth.json")) as f:
            truth = json.load(f)
        volume, spacing, _ = read_mha(os.path.join(directory, truth["volume"]["path"]))
        ink = mpimg.imread(os.path.join(directory, "ground_truth_ink.png"))
        axial = volume[volume.shape[0] // 2]
        figure, axes = plt.subplots(1, 2, figsize=(8.0, 2.6), gridspec_kw={"width_ratios": [1, 2.4]})
        extent = [0, axial.shape[1] * spacing[0], axial.shape[0] * spacing[1], 0]
        axes[0].imshow(axial, cmap="gray", vmin=-1100, vmax=1500, extent=extent, interpolation="nearest")
        axes[0].set_title("axial slice (mm)", fontsize=8)
        axes[0].tick_params(labelsize=6)
        sheet = truth["sheet"]
        axes[1].imshow(ink, cmap="gray_r", extent=[0, sheet["length_mm"], sheet["width_mm"], 0], aspect="equal")
        axes[1].set_title("ground-truth ink (s, w in mm)", fontsize=8)
        axes[1].tick_params(labelsize=6)
        figure.suptitle("%s: %d x %d x %d voxels" % ((truth["preset"],) + tuple(truth["volume"]["size"])), fontsize=9)
        figure.tight_layout()
        path = os.path.join(out, "phantom-%s.png" % truth["preset"])
        figure.savefig(path, dpi=110)
        plt.close(figure)
        print(path)


if __name__ == "__main__":
    main()

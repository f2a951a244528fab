#!/usr/bin/python3
"""Figure of docs/texturing.md: the textures written by itkFlattenedTextureImageFilterGTest.

Usage: /usr/bin/python3 scripts/texturing_figure.py BUILD_DIR OUTPUT_PNG
Reads BUILD_DIR/FlattenedTexture_*.mha (MetaImage, float, uncompressed).
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vu_mha import read_mha  # noqa: E402



def main():
    build, output = sys.argv[1], sys.argv[2]
    panels = [
        ("Ink", "true ink image (area fraction, 0.25 mm pixels)"),
        ("FlatSheet", "flat tilted sheet, ink through the sheet: 3-layer mean"),
        ("FaceInk_SingleLayer", "ink on one face: single layer on the mid-surface"),
        ("FaceInk_Max5", "ink on one face: max of 5 layers (+/- 2 voxels)"),
        ("CylinderShell_Max5", "cylinder shell, ink outside: max of 5 layers"),
        ("CylinderShell_Focus1", "cylinder shell: 3-layer mean, focus +1 mm"),
    ]
    figure, axes = plt.subplots(3, 2, figsize=(10, 9))
    for axis, (name, title) in zip(axes.ravel(), panels):
        image, _, _ = read_mha(f"{build}/FlattenedTexture_{name}.mha")
        # Row index grows with flat y: show y upwards.
        axis.imshow(image, cmap="gray", origin="lower", interpolation="nearest")
        axis.set_title(title, fontsize=9)
        axis.set_xticks([])
        axis.set_yticks([])
    figure.tight_layout()
    figure.savefig(output, dpi=80)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How much model does a scene need? Legibility (tesseract character error rate) and texture
NCC of `virtual-unwrap unwrap` on the standard phantom against the mesh spacing, and against
which physics is on. Writes CSV (one row per run) for scripts/plot-benchmarks.py.

    /usr/bin/python3 benchmarks/enough_model.py [--build build] [--csv FILE] [--quick]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

# Mesh spacings (mm) around the automatic choice (about 0.6 mm on the standard phantom,
# whose voxels are 0.1 mm); 0 is the automatic choice itself.
SPACINGS = [0.1, 0.15, 0.2, 0.3, 0.45, 0, 0.9, 1.2, 1.8, 2.4]
# Physics variants at the automatic spacing: what the default model has, less, and more.
PHYSICS = [
    ("default", []),
    ("no shear springs", ["--shear", "0"]),
    ("no unroll phase", ["--locked-edge", "none"]),
    ("20-step limit per phase", ["--max-steps", "20"]),
    ("+ bending springs", ["--bending", "0.1"]),
    ("symplectic Euler", ["--integrator", "symplectic-euler"]),
    # Coarse-to-fine only acts on meshes above CoarseParticles (3000): a 0.2 mm mesh.
    ("0.2 mm mesh, coarse-to-fine", ["--mesh-spacing", "0.2"]),
    ("0.2 mm mesh, full resolution", ["--mesh-spacing", "0.2", "--coarsening", "1"]),
]


def run(tool, volume, truth, out, extra):
    subprocess.run([tool, "unwrap", volume, "-o", out, "--ground-truth", truth, "--quiet"] + extra,
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    stages = {s["stage"]: s["seconds"] for s in report["stages"]}
    return {
        "mesh_spacing_mm": report["parameters"]["mesh"]["spacing_along_sheet_mm"],
        "points": report["mesh"]["points"],
        "texture_ncc": report["legibility"]["texture_ncc"],
        "character_error_rate": report["legibility"]["character_error_rate"],
        "edge_strain_p95": report["distortion"]["edge_strain"]["p95"],
        "flipped_triangles": report["distortion"]["flipped_triangles"],
        "flatten_seconds": stages["flatten"],
        "unwrap_seconds": sum(v for k, v in stages.items() if k != "score"),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default="build")
    parser.add_argument("--csv", default=None)
    parser.add_argument("--quick", action="store_true", help="two spacings and two physics variants (CI smoke)")
    args = parser.parse_args()
    tool = os.path.join(args.build, "bin", "virtual-unwrap")
    spacings = [0, 1.2] if args.quick else SPACINGS
    physics = PHYSICS[:2] if args.quick else PHYSICS
    fields = ["sweep", "setting", "mesh_spacing_mm", "points", "texture_ncc", "character_error_rate",
              "edge_strain_p95", "flipped_triangles", "flatten_seconds", "unwrap_seconds"]
    out = open(args.csv, "w", newline="") if args.csv else sys.stdout
    writer = csv.DictWriter(out, fieldnames=fields)
    writer.writeheader()
    with tempfile.TemporaryDirectory() as work:
        phantom = os.path.join(work, "phantom")
        subprocess.run([tool, "phantom", "standard", "-o", phantom], check=True, stdout=subprocess.DEVNULL)
        volume = os.path.join(phantom, "volume")
        for spacing in spacings:
            extra = ["--mesh-spacing", str(spacing)] if spacing > 0 else []
            row = run(tool, volume, phantom, os.path.join(work, f"s{spacing}"), extra)
            writer.writerow({"sweep": "mesh spacing", "setting": "auto" if spacing == 0 else spacing, **row})
            out.flush()
        for name, extra in physics:
            row = run(tool, volume, phantom, os.path.join(work, name.replace(" ", "_")), extra)
            writer.writerow({"sweep": "physics", "setting": name, **row})
            out.flush()


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Charts of the benchmark CSVs in docs/benchmarks/ (see docs/benchmarks.md):

  scripts/plot-benchmarks.py [DIR]     (default docs/benchmarks)

flattening*.csv -> docs/images/pareto.png: wall time against edge strain p95 for every
method and setting, one panel per mesh (failed or diverged runs marked on the top edge).
stability.csv   -> docs/images/stability.png: measured largest stable time step of each
explicit integrator against w_max, with the linear-analysis bounds as lines.
"""
import csv
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "docs", "benchmarks")
images = os.path.join(here, "..", "docs", "images")


def rows(pattern):
    out = []
    for path in sorted(glob.glob(os.path.join(data, pattern))):
        with open(path) as f:
            out.extend(csv.DictReader(f))
    return out


def pareto():
    results = rows("flattening*.csv")
    if not results:
        return
    meshes = sorted({r["mesh"] for r in results}, key=lambda m: (m.split("-")[0], float(m.split("-")[1].rstrip("kM")) * (1e6 if m.endswith("M") else 1e3 if m.endswith("k") else 1)))
    fig, axes = plt.subplots(1, len(meshes), figsize=(4.2 * len(meshes), 4.2), squeeze=False)
    markers = {"mass-spring/implicit-euler": "o", "mass-spring/rk4": "s", "mass-spring/symplectic-euler": "^",
               "mass-spring/midpoint": "v", "mass-spring/euler": "x", "itk-parameterization": "D",
               "cgal-lscm": "P", "cgal-arap": "*"}
    unique = {}
    for ax, mesh in zip(axes[0], meshes):
        for r in (r for r in results if r["mesh"] == mesh):
            ok = r["edge_strain_p95"] not in ("", None)
            y = float(r["edge_strain_p95"]) if ok else 1.0
            ax.scatter(float(r["seconds"]) if float(r["seconds"]) > 0 else 1e-3, y,
                       marker=markers.get(r["method"], "o"),
                       color="C%d" % (list(markers).index(r["method"]) if r["method"] in markers else 9),
                       alpha=1.0 if ok else 0.35, label=r["method"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axhline(0.005, color="grey", lw=0.8, ls="--")
        ax.set_title(mesh)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("edge strain p95 (top edge: failed/diverged)")
        handles, labels = ax.get_legend_handles_labels()
        unique.update(zip(labels, handles))
    fig.legend(unique.values(), unique.keys(), loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(os.path.join(images, "pareto.png"), dpi=90)


def stability():
    results = rows("stability.csv")
    if not results:
        return
    integrators = ["euler", "midpoint", "symplectic-euler", "rk4"]
    zetas = sorted({float(r["damping_ratio"]) for r in results})
    fig, axes = plt.subplots(1, len(zetas), figsize=(4.2 * len(zetas), 4.0), squeeze=False)
    for ax, zeta in zip(axes[0], zetas):
        for k, name in enumerate(integrators):
            sel = sorted((r for r in results if r["integrator"] == name and float(r["damping_ratio"]) == zeta),
                         key=lambda r: float(r["w_max"]))
            if not sel:
                continue
            w = [float(r["w_max"]) for r in sel]
            ax.plot(w, [float(r["h_linear_bound"]) or float("nan") for r in sel], color="C%d" % k, lw=1,
                    label="%s bound" % name)
            ax.scatter(w, [float(r["h_measured"]) for r in sel], color="C%d" % k, marker="o", s=18,
                       label="%s measured" % name)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title("damping ratio %.2g" % zeta)
        ax.set_xlabel("w_max = highest angular frequency (rad/s)")
        ax.set_ylabel("largest stable time step (s)")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(images, "stability.png"), dpi=90)


pareto()
stability()

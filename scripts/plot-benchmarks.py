#!/usr/bin/python3
"""Charts of the benchmark CSVs in docs/benchmarks/ (see docs/benchmarks.md):

  scripts/plot-benchmarks.py [DIR]     (default docs/benchmarks)

flattening*.csv -> docs/images/pareto.png: wall time against edge strain p95 for every
method and setting, one panel per mesh (failed or diverged runs marked on the top edge).
stability.csv   -> docs/images/stability.png: measured largest stable time step of each
explicit integrator against w_max, with the linear-analysis bounds as lines.
enough-model.csv -> docs/images/enough-model.png: texture NCC, OCR character error rate
and unwrapping time against mesh spacing, and for each physics variant.
step-throughput.csv, flattening-1M.csv, flattening.csv -> docs/images/scaling.png: time
per explicit step, spring evaluations per second and time to convergence against size.
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



def enough_model():
    results = rows("enough-model.csv")
    if not results:
        return
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 4.6), gridspec_kw={"width_ratios": [1, 1.25]})
    sweep = sorted((r for r in results if r["sweep"] == "mesh spacing"), key=lambda r: float(r["mesh_spacing_mm"]))
    x = [float(r["mesh_spacing_mm"]) for r in sweep]
    left.plot(x, [float(r["texture_ncc"]) for r in sweep], "o-", label="texture NCC")
    left.plot(x, [1.0 - float(r["character_error_rate"]) for r in sweep], "s--", label="1 - OCR character error rate")
    for r in sweep:
        if r["setting"] == "auto":
            left.axvline(float(r["mesh_spacing_mm"]), color="grey", lw=0.8, ls=":")
            left.annotate("automatic", (float(r["mesh_spacing_mm"]), 0.05), rotation=90, color="grey", fontsize=8)
    left.set_xscale("log")
    left.set_ylim(0, 1.02)
    left.set_xlabel("mesh spacing (mm; voxel 0.1 mm)")
    left.set_ylabel("legibility")
    twin = left.twinx()
    twin.plot(x, [float(r["unwrap_seconds"]) for r in sweep], "^:", color="tab:red", label="unwrap time")
    twin.set_ylabel("unwrap time without scoring (s)", color="tab:red")
    left.legend(loc="lower left", fontsize=8)
    left.set_title("standard phantom: legibility against mesh spacing")
    physics = [r for r in results if r["sweep"] == "physics"]
    names = [r["setting"] for r in physics]
    y = range(len(physics))
    right.barh([i + 0.2 for i in y], [float(r["texture_ncc"]) for r in physics], height=0.4, label="texture NCC")
    right.barh([i - 0.2 for i in y], [1.0 - float(r["character_error_rate"]) for r in physics], height=0.4,
               label="1 - OCR character error rate")
    for i, r in enumerate(physics):
        right.annotate(f"{float(r['flatten_seconds']):.1f} s, p95 {float(r['edge_strain_p95']):.1%}, "
                       f"{r['flipped_triangles']} flips", (1.02, i), fontsize=7, va="center",
                       annotation_clip=False)
    right.set_yticks(list(y))
    right.set_yticklabels(names, fontsize=8)
    right.invert_yaxis()
    right.set_xlim(0, 1.6)
    right.set_xticks([0, 0.2, 0.4, 0.6, 0.8, 1.0])
    right.axvline(1.0, color="grey", lw=0.6)
    right.set_xlabel("legibility (annotations: flatten time, edge strain p95, flipped triangles)")
    right.legend(loc="lower right", fontsize=7)
    right.set_title("which physics is needed (automatic spacing)")
    fig.tight_layout()
    fig.savefig(os.path.join(images, "enough-model.png"), dpi=90)



def scaling():
    steps = rows("step-throughput.csv")
    runs = rows("scaling.csv")
    if not steps and not runs:
        return
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(14, 4.2))
    series = sorted({(r.get("precision", "double"), r["threads"]) for r in steps}, key=lambda k: (k[0], int(k[1])))
    for precision, threads in series:
        sel = sorted((r for r in steps if (r.get("precision", "double"), r["threads"]) == (precision, threads)),
                     key=lambda r: int(r["particles"]))
        x = [int(r["particles"]) for r in sel]
        label = f"{precision}, {threads} thread(s)"
        style = "o-" if precision == "double" else "s--"
        a.plot(x, [1e3 * float(r["seconds_per_step"]) for r in sel], style, label=label)
        b.plot(x, [float(r["spring_evaluations_per_second"]) for r in sel], style, label=label)
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("particles")
    a.set_ylabel("ms per explicit step (symplectic Euler)")
    a.set_title("time per step")
    a.legend(fontsize=8)
    b.axhline(5e8, color="grey", ls=":", lw=1)
    b.annotate("target 5e8", (b.get_xlim()[0], 5e8), fontsize=8, color="grey", va="bottom")
    b.set_xscale("log")
    b.set_yscale("log")
    b.set_xlabel("particles")
    b.set_ylabel("spring evaluations per second")
    b.set_title("explicit step throughput")
    b.legend(fontsize=8)
    for threads in sorted({r["threads"] for r in runs}, key=int):
        sel = sorted((r for r in runs if r["threads"] == threads), key=lambda r: int(r["vertices"]))
        x = [int(r["vertices"]) for r in sel]
        c.plot(x, [float(r["seconds"]) for r in sel], "o-", label=f"time, {threads} thread(s)")
    if runs:
        twin = c.twinx()
        sel = sorted((r for r in runs if r["threads"] == "1"), key=lambda r: int(r["vertices"]))
        twin.plot([int(r["vertices"]) for r in sel], [float(r["peak_memory_mib"]) for r in sel], "s:",
                  color="tab:red", label="peak memory")
        twin.set_yscale("log")
        twin.set_ylabel("peak memory (MiB)", color="tab:red")
    c.set_xscale("log")
    c.set_yscale("log")
    c.set_xlabel("vertices")
    c.set_ylabel("seconds to convergence (implicit, default)")
    c.set_title("flattening to convergence")
    c.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(os.path.join(images, "scaling.png"), dpi=90)


pareto()
stability()
enough_model()
scaling()

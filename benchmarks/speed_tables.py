#!/usr/bin/python3
"""Markdown tables of one speed run (benchmarks/speed-run.sh) for docs/benchmarks.md.

  benchmarks/speed_tables.py DIR      (DIR holds the run's CSVs and stage tables)

Prints the targets first (the 1M-vertex roll against CGAL LSCM, the 10M-vertex roll, the
explicit step at 1M particles, the texture stage, the pipeline on two threads), then every
table of the page in its order.
"""
import csv
import json
import os
import re
import sys


def rows(directory, name):
    path = os.path.join(directory, name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def g(value, digits=3):
    if value in ("", None):
        return "-"
    return f"{float(value):.{digits}g}"


def table(header, body):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


def mesh_order(name):
    kind, size = name.split("-")
    scale = 1e6 if size.endswith("M") else 1e3 if size.endswith("k") else 1
    return (kind != "roll", float(size.rstrip("kM")) * scale)


def flattening(directory):
    results = []
    for name in ("flattening.csv", "flattening-100k.csv", "flattening-1M.csv", "flattening-cgal.csv"):
        results += rows(directory, name)
    results.sort(key=lambda r: mesh_order(r["mesh"]))  # stable: methods keep their run order
    body = [[r["mesh"], r["method"], r["setting"], g(r["seconds"]), r["status"], g(r["edge_strain_p95"]),
             g(r["edge_strain_max"]), g(r["area_distortion"]), r["flipped"] or "-"] for r in results]
    return results, table(["mesh", "method", "setting", "seconds", "status", "edge strain p95", "max",
                           "area distortion", "flipped"], body)


def find(results, mesh, method, setting=None):
    for r in results:
        if r["mesh"] == mesh and r["method"] == method and (setting is None or r["setting"] == setting):
            return r
    return None


def stability(directory):
    results = rows(directory, "stability.csv")
    groups = {}
    for r in results:
        groups.setdefault((r["integrator"], r["damping_ratio"]), []).append(r)
    body = []
    order = ["euler", "midpoint", "symplectic-euler", "rk4"]
    keys = sorted(groups, key=lambda k: (order.index(k[0]) if k[0] in order else len(order), float(k[1])))
    for integrator, zeta in keys:
        group = groups[(integrator, zeta)]
        ratios = [float(r["measured_over_bound"]) for r in group if float(r["h_linear_bound"]) > 0]
        at1 = next((r for r in group if float(r["stiffness"]) == 1.0), group[0])
        w = float(at1["w_max"])
        spread = f"{min(ratios):.3f}-{max(ratios):.3f}" if ratios else "bound 0 (grows at every step)"
        body.append([integrator, zeta, spread, g(w * float(at1["h_measured"])), g(w * float(at1["h_linear_bound"]))])
    return table(["integrator", "damping ratio", "measured / bound (every stiffness)", "w_max h measured at stiffness 1",
                  "linear bound w_max h"], body)


def main():
    directory = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks")
    results, flat_table = flattening(directory)
    steps = rows(directory, "step-throughput.csv")
    scaling = rows(directory, "scaling.csv")
    texture = open(os.path.join(directory, "texture-stage.md")).read().strip() \
        if os.path.exists(os.path.join(directory, "texture-stage.md")) else ""
    pipeline = open(os.path.join(directory, "pipeline-threads.md")).read().strip() \
        if os.path.exists(os.path.join(directory, "pipeline-threads.md")) else ""

    print("## Targets")
    ours = find(results, "roll-1M", "mass-spring/implicit-euler", "auto")
    lscm = find(results, "roll-1M", "cgal-lscm")
    if ours and lscm:
        print(f"- roll-1M: mass-spring implicit {float(ours['seconds']):.2f} s at p95 {g(ours['edge_strain_p95'])}, "
              f"CGAL LSCM {float(lscm['seconds']):.1f} s at p95 {g(lscm['edge_strain_p95'])}: "
              f"{float(lscm['seconds']) / float(ours['seconds']):.1f} times faster")
    ten = [r for r in scaling if r["mesh"] == "roll-10M"]
    for r in ten:
        print(f"- roll-10M on {r['threads']} threads: {float(r['seconds']):.0f} s, peak memory "
              f"{float(r['peak_memory_mib']) / 1024:.1f} GiB, p95 {g(r['edge_strain_p95'])}, flipped {r['flipped']}")
    best = [r for r in steps if r["mesh"] == "roll-1M" and r["precision"] == "single"]
    if best:
        top = max(best, key=lambda r: int(r["threads"]))
        print(f"- explicit step at 1M particles, single precision, {top['threads']} threads: "
              f"{float(top['spring_evaluations_per_second']):.3g} spring evaluations/s, "
              f"{g(top['largest_difference_rest_lengths'])} rest lengths from the double-precision state")
    for line in texture.splitlines()[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        print(f"- texture stage, 30 mm phantom ({cells[0]} library): median {cells[1]} s, "
              f"{cells[4]} samples/s")
    match = re.search(r"two threads ([0-9.]+) times faster than one \(rounds: ([^)]*)\)", pipeline)
    if match:
        print(f"- whole pipeline, 182 M-voxel phantom: two threads {match.group(1)} times faster than one "
              f"(rounds {match.group(2)})")
    for line in pipeline.splitlines():
        if line.startswith("| 2 |"):
            print(f"- texture stage of that pipeline on two threads: {line.strip('|').split('|')[8].strip()} samples/s")

    print("\n## 1. Flattening methods\n")
    print(flat_table)
    print("\n## 2. Stability map\n")
    print(stability(directory))
    print("\n## 3. Scaling: mass-spring against CGAL LSCM\n")
    body = []
    for mesh in ("roll-10k", "roll-100k", "roll-1M"):
        a, b = find(results, mesh, "mass-spring/implicit-euler", "auto"), find(results, mesh, "cgal-lscm")
        if a and b:
            body.append([mesh, f"{g(a['seconds'])} s, p95 {g(a['edge_strain_p95'])}",
                         f"{g(b['seconds'])} s, p95 {g(b['edge_strain_p95'])}"])
    print(table(["vertices", "mass-spring implicit (auto)", "CGAL LSCM"], body))
    print("\n### Explicit step throughput\n")
    print(table(["mesh", "particles", "springs", "precision", "threads", "ms per step",
                 "spring evaluations per second", "peak memory (MiB)", "from the double state (rest lengths)"],
                [[r["mesh"], r["particles"], r["springs"], r["precision"], r["threads"],
                  f"{1000 * float(r['seconds_per_step']):.2f}", f"{float(r['spring_evaluations_per_second']):.3g}",
                  f"{float(r['peak_memory_mib']):.0f}", g(r["largest_difference_rest_lengths"], 2)] for r in steps]))
    print("\n### Time to convergence\n")
    print(table(["mesh", "vertices", "threads", "seconds", "steps", "edge strain p95", "flipped", "peak memory (MiB)"],
                [[r["mesh"], r["vertices"], r["threads"], g(r["seconds"]), r["steps"], f"{float(r['edge_strain_p95']):.2e}",
                  r["flipped"], f"{float(r['peak_memory_mib']):.0f}"] for r in scaling]))
    enough = rows(directory, "enough-model.csv")
    if enough:
        print("\n## 4. Enough model\n")
        print(table(["sweep", "setting", "spacing (mm)", "points", "texture NCC", "OCR CER", "edge strain p95",
                     "flipped", "flatten (s)", "unwrap (s)"],
                    [[r["sweep"], r["setting"], f"{float(r['mesh_spacing_mm']):.2f}", r["points"],
                      f"{float(r['texture_ncc']):.3f}", f"{float(r['character_error_rate']):.2f}",
                      f"{100 * float(r['edge_strain_p95']):.2f}%", r["flipped_triangles"],
                      f"{float(r['flatten_seconds']):.2f}", f"{float(r['unwrap_seconds']):.2f}"] for r in enough]))
    demo = os.path.join(directory, "demo-report.json")
    if os.path.exists(demo):
        report = json.load(open(demo))
        print("\n## 5. Pipeline profile of the demo\n")
        print(table(["stage", "seconds", "peak memory (MiB)"],
                    [[x["stage"], f"{x['seconds']:.2f}", f"{x.get('peak_memory_mib', float('nan')):.0f}"]
                     for x in report["stages"]]))
        legibility = report.get("legibility", {})
        print(f"\nOCR CER {legibility.get('character_error_rate', float('nan')):.3f}, "
              f"texture NCC {legibility.get('texture_ncc', float('nan')):.3f}, {report['seconds']:.2f} s in all")
    print("\n## 6. Texture stage of unwrap, 30 mm phantom\n")
    print(texture)
    frames = os.path.join(directory, "workbench-frames.txt")
    if os.path.exists(frames):
        print("\n## 7. Workbench frame rate\n")
        body = []
        for chunk in open(frames).read().split("particles=")[1:]:
            start, end = chunk.find("{"), chunk.rfind("}")
            if start < 0 or end < start:
                body.append([chunk.split()[0], chunk.split()[1].split("=")[1], "failed", "-"])
                continue
            r = json.loads(chunk[start:end + 1])
            body.append([f"{r['particles']} ({r['triangles']})", r["integrator"], f"{r['frames_per_second']:.1f}",
                         f"{r['steps_per_second']:.3g}" if "none" not in r["integrator"] else "-"])
        print(table(["particles (triangles)", "simulation", "rendered frames/s", "simulation steps/s"], body))
    print("\n## 8. Whole pipeline on one and two threads\n")
    print(pipeline)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Benchmark of `virtual-unwrap unwrap` on scans that hold several written sheets.

A generator of CT scans with more than one sheet, written independently of the module's
phantom source (its own geometry, rasteriser and text), and a scorer that runs the tool
with its default options (every sheet) and matches each sheet it finds to a true sheet.
Every parameter of a scene is drawn at run time from its seed.

Scenes (lengths in voxels; the voxel size in mm only scales the file's geometry):
  pair       two flat written sheets, parallel, `separation` voxels apart face to face
             (3 to 20), slightly tilted together;
  book       a book block: 6 to 9 pages, each a cylinder bent along its length (the block's
             common curvature plus a little of its own), gaps of 2 to 6 voxels, and 2 to 4
             places where a page bulges onto the next over a patch of 8 to 16 voxels and
             touches it (the two sheets fuse there: no gap at all);
  fragments  a small roll (2 to 3 turns) beside two loose flat pieces, none touching.
Each sheet's occupancy is clip(t/2 - |d| + 1/2, 0, 1) of its perpendicular distance d to
the mid-surface, ends and edges anti-aliased the same way, the sheets combined by their
maximum; ink is a denser layer over the outer third of the thickness on one face, in the
glyphs of two or three lines of words (DejaVu bold faces); then Gaussian blur and white
noise at SNR 3 to 8 (sheet level over the noise's standard deviation).

Scoring (voxels): the tool's surface.obj files (one per sheet found) are mapped back to
voxels; each mesh vertex goes to the true sheet nearest it and each mesh to the sheet most
of its vertices go to. Per true sheet: found, mean mesh error (point-to-plane distance of
the vertices to the sheet's mid-surface), jumps (vertices of the sheet's mesh that lie on
another sheet: more than one voxel from this one and nearer another), coverage (samples
of the true sheet every half voxel within one voxel of the mesh) and the OCR character
error rate of the sheet's texture.png (tesseract --psm 6, best of the 8 rotations and
mirrors). A sheet succeeds with error <= 0.5, 0 jumps and coverage >= 97 %; it is
legible with CER <= 5 %.

    sheet_pages.py generate --kind book --seed N --out DIR [--param key=value ...]
    sheet_pages.py run --scenes N --seed S --out DIR [--kinds pair,book,fragments]
                       [--jobs 1] [--tool build/bin/virtual-unwrap] [--csv FILE] [--keep failures|all]
                       [--param key=value ...]
        One row per true sheet in the CSV; a summary per kind (markdown) on stdout.
    sheet_pages.py summary --csv FILE
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sheet_stress as stress  # noqa: E402  (words, fonts, OCR, mesh distances, MHA writer)

KINDS = ("pair", "book", "fragments")


# ----------------------------------------------------------------------------------------
# Sheets


class Sheet:
    """A sheet as a map from sheet coordinates (s along its length, w across) to the volume,
    tabulated: mid-surface points P(s, w), unit normals N (out of the inked face when ink
    is +1) and the arc-length grids. Built from a callable surface(u, w) -> (x, y, z)."""

    def __init__(self, points, normals, s, w, thickness, inked_face):
        self.points, self.normals = points, normals  # (nw, ns, 3) voxel (x, y, z)
        self.s, self.w = s, w  # (ns,), (nw,)
        self.thickness, self.inked_face = thickness, inked_face
        self.ink = None
        self.lines = []

    def samples(self):
        return self.points.reshape(-1, 3), self.normals.reshape(-1, 3)


def sheet_from_surface(surface, u, w, thickness, inked_face):
    """Tabulate surface(u, w) on the grid u x w and reparameterise u by arc length (per the
    middle row: the sheets here bend along u only, besides small bumps)."""
    uu, ww = np.meshgrid(u, w)
    pts = surface(uu, ww)  # (nw, nu, 3)
    mid = pts[len(w) // 2]
    seg = np.linalg.norm(np.diff(mid, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    du = np.gradient(pts, axis=1)
    dw = np.gradient(pts, axis=0)
    n = np.cross(du, dw)
    n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-12)
    return Sheet(pts, n * inked_face, s, w - w[0], thickness, inked_face)


def flat_page(origin, e_len, e_wid, length, width, thickness, inked_face, bow=0.0, bumps=(), step=0.5):
    """A page spanned by unit vectors e_len (along its length) and e_wid (across), bent along
    its length by `bow` voxels at the middle (a cylinder), with Gaussian bumps (u, w,
    height, sigma) along its normal."""
    e_len, e_wid = np.asarray(e_len, float), np.asarray(e_wid, float)
    normal = np.cross(e_len, e_wid)
    u = np.arange(0.0, length + 1e-9, step)
    w = np.arange(0.0, width + 1e-9, step)

    def surface(uu, ww):
        h = bow * (1.0 - (2.0 * uu / length - 1.0) ** 2)
        for bu, bw, height, sigma in bumps:
            h = h + height * np.exp(-((uu - bu) ** 2 + (ww - bw) ** 2) / (2.0 * sigma ** 2))
        return (np.asarray(origin, float) + uu[..., None] * e_len + ww[..., None] * e_wid + h[..., None] * normal)

    return sheet_from_surface(surface, u, w, thickness, inked_face)


def spiral_roll(centre, inner_radius, pitch, turns, width, thickness, inked_face, step=0.5):
    """A roll about the z axis through `centre`: r = inner_radius + pitch * phi / (2 pi)."""
    phi_max = 2.0 * math.pi * turns
    # Parameter phi sampled about every `step` voxels of arc.
    arc = inner_radius * phi_max + pitch * phi_max ** 2 / (4.0 * math.pi)
    phi = np.linspace(0.0, phi_max, int(arc / step) + 2)
    w = np.arange(0.0, width + 1e-9, step)

    def surface(pp, ww):
        r = inner_radius + pitch * pp / (2.0 * math.pi)
        return np.stack([centre[0] + r * np.cos(pp), centre[1] + r * np.sin(pp), centre[2] + ww], axis=-1)

    return sheet_from_surface(surface, phi, w, thickness, inked_face)


def write_text(sheet, rng, letter_height):
    """Two or three lines of words laid out inside the sheet with a border; sets sheet.ink
    (an image over (s, w), TEXTURE_PIXEL voxels a pixel) and sheet.lines."""
    from PIL import ImageFont
    font_path = os.path.join(stress.FONT_DIR, str(rng.choice(stress.FONTS)))
    border = max(3.0, 1.25 * sheet.thickness + 2.0)
    length, width = sheet.s[-1] - 2 * border, sheet.w[-1] - 2 * border
    height = letter_height
    lines_wanted = int(rng.integers(2, 4))
    while (lines_wanted - 1) * 1.6 * height + 1.3 * height > width and lines_wanted > 1:
        lines_wanted -= 1
    while (lines_wanted - 1) * 1.6 * height + 1.3 * height > width and height > 6.0:
        height *= 0.9
    px = height / stress.TEXTURE_PIXEL
    font = ImageFont.truetype(font_path, 100)
    cap = font.getbbox("H")
    font = ImageFont.truetype(font_path, max(6, int(round(100 * px / (cap[3] - cap[1])))))
    limit = length / stress.TEXTURE_PIXEL
    lines = []
    for _ in range(lines_wanted):
        words = []
        for _ in range(int(rng.integers(1, 5))):
            candidate = " ".join(words + [str(rng.choice(stress.WORDS))])
            if font.getlength(candidate) <= limit:
                words = candidate.split()
        if not words:
            words = [str(rng.choice(stress.WORDS))]
            while font.getlength(words[0]) > limit and len(words[0]) > 2:
                words[0] = words[0][:-1]
        lines.append(" ".join(words))
    arr = stress.draw_text_block(font, lines, px).astype(np.float32) / 255.0
    block_s, block_wv = arr.shape[1] * stress.TEXTURE_PIXEL, arr.shape[0] * stress.TEXTURE_PIXEL
    s0 = border + rng.uniform(0.0, max(0.0, length - block_s))
    w0 = border + rng.uniform(0.0, max(0.0, width - block_wv))
    sheet.ink = (arr, s0, w0)
    sheet.lines = lines


def ink_at(sheet, s, w):
    if sheet.ink is None:
        return np.zeros_like(s)
    arr, s0, w0 = sheet.ink
    return ndimage.map_coordinates(arr, [(w - w0) / stress.TEXTURE_PIXEL, (s - s0) / stress.TEXTURE_PIXEL],
                                   order=1, cval=0.0)


def rasterise(sheets, dims, ink_contrast):
    """Occupancy plus ink of every sheet, combined by their maximum: for each voxel near a
    sheet, its nearest tabulated point gives (s, w), the normal and the distance."""
    nx, ny, nz = dims
    volume = np.zeros((nz, ny, nx), dtype=np.float32)
    for sheet in sheets:
        pts, nrm = sheet.samples()
        tree = cKDTree(pts)
        reach = 0.5 * sheet.thickness + 1.5
        lo = np.maximum(np.floor(pts.min(axis=0) - reach), 0).astype(int)
        hi = np.minimum(np.ceil(pts.max(axis=0) + reach), [nx - 1, ny - 1, nz - 1]).astype(int)
        zz, yy, xx = np.mgrid[lo[2]:hi[2] + 1, lo[1]:hi[1] + 1, lo[0]:hi[0] + 1]
        q = np.stack([xx.ravel(), yy.ravel(), zz.ravel()], axis=1).astype(np.float64)
        dist, idx = tree.query(q, distance_upper_bound=reach + 0.5)
        near = np.isfinite(dist)
        q, idx = q[near], idx[near]
        offset = q - pts[idx]
        d = np.einsum("ij,ij->i", offset, nrm[idx])
        # In-plane overshoot past the sheet's ends and edges (anti-aliased like the faces).
        tangential = np.linalg.norm(offset - d[:, None] * nrm[idx], axis=1)
        iw, js = np.unravel_index(idx, sheet.points.shape[:2])
        at_rim = (iw == 0) | (iw == len(sheet.w) - 1) | (js == 0) | (js == len(sheet.s) - 1)
        rim = np.where(at_rim, np.clip(0.5 - tangential, 0.0, 1.0), 1.0)
        occupancy = np.clip(0.5 * sheet.thickness - np.abs(d) + 0.5, 0.0, 1.0) * rim
        # Ink: the outer third of the thickness on the inked face (+ normal side).
        layer = np.clip(np.minimum(d - sheet.thickness / 6.0 + 0.5, 0.5 * sheet.thickness - d + 0.5), 0.0, 1.0)
        value = occupancy + ink_contrast * layer * rim * ink_at(sheet, sheet.s[js], sheet.w[iw])
        flat = (q[:, 2].astype(int), q[:, 1].astype(int), q[:, 0].astype(int))
        np.maximum.at(volume, flat, value.astype(np.float32))
    return volume


# ----------------------------------------------------------------------------------------
# Scenes


def draw_scene(kind, seed, overrides=None):
    """Parameters and sheets of one scene, all drawn from the seed."""
    rng = np.random.default_rng([int(seed), KINDS.index(kind)])
    p = {"kind": kind, "seed": int(seed),
         "thickness": float(rng.uniform(2.0, 3.0)),
         "blur": float(rng.uniform(0.4, 0.9)),
         "snr": float(rng.uniform(3.0, 8.0)),
         "ink_contrast": float(rng.uniform(0.5, 1.2)),
         "letter_height": float(rng.uniform(9.0, 15.0)),
         "voxel_mm": float(rng.choice([0.02, 0.05, 0.1])),
         "separation": float(rng.uniform(3.0, 20.0)),
         "pages": int(rng.integers(6, 10)),
         "touches": int(rng.integers(2, 5))}
    p.update(overrides or {})
    t = p["thickness"]
    sheets, margin = [], 8.0
    if kind == "pair":
        length, width = rng.uniform(90, 130), rng.uniform(50, 70)
        tilt = math.radians(rng.uniform(-8, 8))
        e_len, e_wid = np.array([math.cos(tilt), math.sin(tilt), 0.0]), np.array([0.0, 0.0, 1.0])
        up = np.array([-math.sin(tilt), math.cos(tilt), 0.0])  # the second sheet lies above the first
        base = np.array([margin, margin + 4.0 + max(0.0, -length * math.sin(tilt)), margin])
        for k in range(2):
            origin = base + k * (p["separation"] + t) * up
            sheets.append(flat_page(origin, e_len, e_wid, length, width, t, 1 if k == 0 else -1))
    elif kind == "book":
        length, width = rng.uniform(90, 130), rng.uniform(50, 70)
        common_bow = rng.uniform(-6, 6)
        gaps = rng.uniform(2.0, 6.0, p["pages"] - 1)
        touch_pages = rng.choice(p["pages"] - 1, size=min(p["touches"], p["pages"] - 1), replace=False)
        y = margin + abs(common_bow) + 4.0
        for k in range(p["pages"]):
            bumps = []
            if k in touch_pages:
                # Bulges by its gap (and a quarter voxel more: the sheets fuse) onto the next.
                sigma = rng.uniform(4.0, 8.0)
                bumps.append((rng.uniform(0.25, 0.75) * length, rng.uniform(0.25, 0.75) * width,
                              gaps[k] + 0.25, sigma))
            bow = common_bow + rng.uniform(-0.5, 0.5)
            # e_len x e_wid = +y: pages stacked along y.
            sheets.append(flat_page([margin, y, margin + width], [1, 0, 0], [0, 0, -1], length, width, t,
                                    1 if rng.random() < 0.5 else -1, bow=bow, bumps=bumps))
            if k + 1 < p["pages"]:
                y += t + gaps[k]
        p["gaps"] = [round(float(g), 3) for g in gaps]
        p["touching_pages"] = sorted(int(k) + 1 for k in touch_pages)
    else:
        turns = rng.uniform(2.0, 3.0)
        inner = rng.uniform(8.0, 12.0)
        pitch = t + rng.uniform(3.0, 6.0)
        width = rng.uniform(50, 70)
        outer = inner + pitch * turns
        centre = np.array([margin + outer + 2, margin + outer + 2, margin])
        sheets.append(spiral_roll(centre, inner, pitch, turns, width, t, -1))
        x0 = centre[0] + outer + rng.uniform(8, 14)
        for k in range(2):
            length, fw = rng.uniform(45, 70), rng.uniform(35, 50)
            tilt = math.radians(rng.uniform(-20, 20))
            e_len = np.array([math.cos(tilt), math.sin(tilt), 0.0]) if k == 0 else np.array([0.0, 1.0, 0.0])
            e_wid = np.array([0.0, 0.0, 1.0])
            origin = (np.array([x0, margin + 7.0 + max(0.0, -length * math.sin(tilt)), margin + rng.uniform(0, 8)])
                      if k == 0 else
                      np.array([margin + 3.0 + rng.uniform(0, 10), centre[1] + outer + rng.uniform(10, 16), margin]))
            sheets.append(flat_page(origin, e_len, e_wid, length, fw, t, 1 if rng.random() < 0.5 else -1,
                                    bow=rng.uniform(-3, 3)))
        p.update({"turns": turns, "inner_radius": inner, "pitch": pitch})
    for sheet in sheets:
        write_text(sheet, rng, p["letter_height"])
    return p, sheets


def generate(kind, seed, out, overrides=None):
    started = time.time()
    p, sheets = draw_scene(kind, seed, overrides)
    reach = max(s.thickness for s in sheets) + 4.0 * p["blur"] + 4.0
    lowest = np.min([s.points.reshape(-1, 3).min(axis=0) for s in sheets], axis=0)
    if not np.all(lowest >= max(s.thickness for s in sheets) + 2.0 * p["blur"]):
        raise ValueError(f"a sheet of the scene leaves the volume (lowest point {lowest})")
    top = np.max([s.points.reshape(-1, 3).max(axis=0) for s in sheets], axis=0)
    dims = tuple(int(math.ceil(v + reach + 4)) for v in top)
    clean = rasterise(sheets, dims, p["ink_contrast"])
    clean = ndimage.gaussian_filter(clean, p["blur"], mode="nearest")
    noise = np.random.default_rng([int(seed), 99]).standard_normal(clean.shape).astype(np.float32) / p["snr"]
    air, material = -1000.0, 400.0
    hu = air + (material - air) * (clean + noise)
    os.makedirs(out, exist_ok=True)
    spacing = p["voxel_mm"]
    stress.write_mha(os.path.join(out, "volume.mha"), np.round(hu).astype(np.int16), spacing, (0.0, 0.0, 0.0),
                     "MET_SHORT")
    truth = {"parameters": p, "dims": dims, "spacing_mm": spacing, "origin_mm": [0.0, 0.0, 0.0],
             "sheets": [{"lines": s.lines, "text": " ".join(s.lines), "inked_face": s.inked_face,
                         "length": float(s.s[-1]), "width": float(s.w[-1])} for s in sheets],
             "seconds": round(time.time() - started, 2)}
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    np.savez_compressed(os.path.join(out, "truth_sheets.npz"),
                        **{f"points{k}": s.points.astype(np.float32) for k, s in enumerate(sheets)},
                        **{f"normals{k}": s.normals.astype(np.float32) for k, s in enumerate(sheets)})
    return truth


# ----------------------------------------------------------------------------------------
# Scoring


def tool_sheets(out):
    """The tool's sheets: (folder, report) for each, from its report.json."""
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    found = report.get("sheets", [])
    if any("folder" in s for s in found):
        return [(os.path.join(out, s["folder"]), s) for s in found if "folder" in s]
    return [(out, found[0] if found else {})] if os.path.exists(os.path.join(out, "surface.obj")) else []


def score_scene(scene_dir, workdir, ocr=True):
    with open(os.path.join(scene_dir, "truth.json")) as f:
        truth = json.load(f)
    with open(os.path.join(scene_dir, "tool.json")) as f:
        outcome = json.load(f)
    geometry = np.load(os.path.join(scene_dir, "truth_sheets.npz"))
    count = len(truth["sheets"])
    pts = [geometry[f"points{k}"].reshape(-1, 3).astype(np.float64) for k in range(count)]
    nrm = [geometry[f"normals{k}"].reshape(-1, 3).astype(np.float64) for k in range(count)]
    trees = [cKDTree(p) for p in pts]
    p = truth["parameters"]
    rows = [{"kind": p["kind"], "seed": p["seed"], "sheet": k + 1, "sheets_true": count, "found": False,
             "mesh_error": float("nan"), "jumps": -1, "coverage": 0.0, "cer": float("nan"), "success": False,
             "legible": False, "tool_exit": outcome["tool_exit"], "sheets_found": 0,
             "separation": round(p["separation"], 2) if p["kind"] == "pair" else "",
             "touching": (k + 1 in p.get("touching_pages", []) or k in p.get("touching_pages", []))
             if p["kind"] == "book" else "",
             "snr": round(p["snr"], 2), "thickness": round(p["thickness"], 2)} for k in range(count)]
    out = os.path.join(scene_dir, "unwrap")
    if outcome["tool_exit"] != 0 or not os.path.exists(os.path.join(out, "report.json")):
        return rows
    spacing, origin = truth["spacing_mm"], np.array(truth["origin_mm"])
    meshes = []
    for folder, entry in tool_sheets(out):
        verts, faces = stress.read_obj(os.path.join(folder, "surface.obj"))
        verts = (verts - origin) / spacing
        dist = np.stack([np.abs(np.einsum("ij,ij->i", verts - pts[k][trees[k].query(verts)[1]],
                                          nrm[k][trees[k].query(verts)[1]])) for k in range(count)], axis=1)
        near = np.stack([trees[k].query(verts)[0] for k in range(count)], axis=1)
        owner = np.argmin(near, axis=1)
        sheet = int(np.bincount(owner, minlength=count).argmax())
        meshes.append((folder, verts, faces, dist, near, owner, sheet))
    for r in rows:
        r["sheets_found"] = len(meshes)
    for k in range(count):
        mine = [m for m in meshes if m[6] == k]
        if not mine:
            continue
        folder, verts, faces, dist, near, owner, _ = max(mine, key=lambda m: len(m[1]))
        row = rows[k]
        row["found"] = True
        row["mesh_error"] = float(np.mean(np.minimum(dist[:, k], near[:, k])))
        row["jumps"] = int(np.sum((near[:, k] > 1.0) & (owner != k)))
        sample = pts[k][::3]
        d = stress.mesh_to_surface_distance(verts, faces, sample, 0.5)
        row["coverage"] = float(np.mean(d <= 1.0))
        texture = os.path.join(folder, "texture.png")
        if ocr and os.path.exists(texture):
            row.update({"cer": stress.ocr_score(texture, truth["sheets"][k]["text"], workdir)["cer"]})
        row["success"] = bool(row["mesh_error"] <= stress.SUCCESS_ERROR and row["jumps"] == 0
                              and row["coverage"] >= stress.SUCCESS_COVERAGE)
        row["legible"] = bool(row["cer"] <= stress.LEGIBLE_CER)
    return rows


def process(kind, seed, root, tool, keep, timeout=1800, overrides=None, ocr=True):
    scene_dir = os.path.join(root, f"{kind}-{seed}")
    generate(kind, seed, scene_dir, overrides)
    out = os.path.join(scene_dir, "unwrap")
    cmd = [tool, "unwrap", os.path.join(scene_dir, "volume.mha"), "-o", out, "-q"]
    started = time.time()
    try:
        result = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        code, stderr = result.returncode, result.stderr
    except subprocess.TimeoutExpired:
        code, stderr = "timeout", ""
    with open(os.path.join(scene_dir, "tool.json"), "w") as f:
        json.dump({"command": cmd, "tool_exit": code, "stderr": stderr[-4000:],
                   "seconds_tool": round(time.time() - started, 2)}, f, indent=1)
    workdir = os.path.join(scene_dir, "ocr")
    os.makedirs(workdir, exist_ok=True)
    rows = score_scene(scene_dir, workdir, ocr)
    for r in rows:
        r["seconds_tool"] = round(time.time() - started, 2)
    if keep == "none" or (keep == "failures" and all(r["success"] and r["legible"] for r in rows)):
        os.remove(os.path.join(scene_dir, "volume.mha"))
    return rows


def summary(rows):
    lines = ["| kind | scenes | sheets | found | success | legible | mean error (median) | jumps (sheets with any) |",
             "|---|---|---|---|---|---|---|---|"]
    for kind in KINDS + ("all",):
        sel = [r for r in rows if kind == "all" or r["kind"] == kind]
        if not sel:
            continue
        scenes = len({(r["kind"], r["seed"]) for r in sel})
        found = sum(1 for r in sel if str(r["found"]) == "True")
        ok = sum(1 for r in sel if str(r["success"]) == "True")
        legible = sum(1 for r in sel if str(r["legible"]) == "True")
        errors = [float(r["mesh_error"]) for r in sel if str(r["found"]) == "True"]
        jumps = sum(1 for r in sel if str(r["found"]) == "True" and int(r["jumps"]) > 0)
        lines.append(f"| {kind} | {scenes} | {len(sel)} | {found} | {ok} ({100.0 * ok / len(sel):.0f} %) | "
                     f"{legible} ({100.0 * legible / len(sel):.0f} %) | "
                     f"{np.median(errors) if errors else float('nan'):.3f} | {jumps} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate")
    g.add_argument("--kind", choices=KINDS, required=True)
    g.add_argument("--seed", type=int, required=True)
    g.add_argument("--out", required=True)
    g.add_argument("--param", action="append", default=[], help="key=value overriding a drawn parameter")
    r = sub.add_parser("run")
    r.add_argument("--scenes", type=int, default=6)
    r.add_argument("--seed", type=int, required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--kinds", default=",".join(KINDS))
    r.add_argument("--jobs", type=int, default=1)
    r.add_argument("--tool", default="build/bin/virtual-unwrap")
    r.add_argument("--csv", default=None)
    r.add_argument("--keep", choices=("failures", "all", "none"), default="failures")
    r.add_argument("--param", action="append", default=[], help="key=value overriding a drawn parameter of every scene")
    c = sub.add_parser("check", help="one scene through the tool; exit 1 unless every sheet meets --require")
    c.add_argument("--kind", choices=KINDS, required=True)
    c.add_argument("--seed", type=int, default=None, help="default: drawn now (printed)")
    c.add_argument("--out", required=True)
    c.add_argument("--tool", default="build/bin/virtual-unwrap")
    c.add_argument("--param", action="append", default=[], help="key=value overriding a drawn parameter")
    c.add_argument("--require", choices=("found", "mesh"), default="mesh",
                   help="found: every sheet found apart; mesh: and each one's mesh succeeds")
    c.add_argument("--legible", default="",
                   help="true sheets (1-based, comma-separated) whose texture.png must read with CER <= 5 %%")
    s = sub.add_parser("summary")
    s.add_argument("--csv", required=True)
    args = parser.parse_args()
    def parse_overrides(kind, seed):
        overrides = {}
        drawn = draw_scene(kind, seed)[0] if args.param else {}
        for item in args.param:
            key, value = item.split("=", 1)
            if key not in drawn:
                raise SystemExit(f"no parameter {key!r}; the parameters: {', '.join(sorted(drawn))}")
            overrides[key] = type(drawn[key])(value)
        return overrides

    if args.command in ("generate", "check"):
        if args.seed is None:
            args.seed = int(np.random.default_rng().integers(1, 2 ** 31 - 1))
        overrides = parse_overrides(args.kind, args.seed)
        if args.command == "generate":
            truth = generate(args.kind, args.seed, args.out, overrides)
            print(json.dumps(truth["parameters"], indent=1))
            return 0
        shutil.rmtree(args.out, ignore_errors=True)
        legible = {int(k) for k in args.legible.split(",") if k.strip()}
        rows = process(args.kind, args.seed, args.out, args.tool, "all", overrides=overrides, ocr=bool(legible))
        bad = 0
        for row in rows:
            ok = row["found"] and (args.require == "found" or row["success"])
            ok = ok and (row["sheet"] not in legible or row["legible"])
            bad += 0 if ok else 1
            cer = f", CER {row['cer']:.3f}" if row["sheet"] in legible else ""
            print(f"{args.kind} seed {args.seed} sheet {row['sheet']}/{row['sheets_true']}: found {row['found']}, "
                  f"error {row['mesh_error']:.3f}, jumps {row['jumps']}, coverage {row['coverage']:.3f}{cer}"
                  f"{'' if ok else '  FAILED'}")
        return 1 if bad else 0
    if args.command == "summary":
        with open(args.csv) as f:
            print(summary(list(csv.DictReader(f))))
        return 0
    kinds = args.kinds.split(",")
    tasks = [(kinds[i % len(kinds)], args.seed + i) for i in range(args.scenes)]
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with concurrent.futures.ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(process, kind, seed, args.out, args.tool, args.keep,
                               overrides=parse_overrides(kind, seed)) for kind, seed in tasks]
        for future in concurrent.futures.as_completed(futures):
            for row in future.result():
                rows.append(row)
                print(f"{row['kind']} {row['seed']} sheet {row['sheet']}/{row['sheets_true']}: found {row['found']}, "
                      f"error {row['mesh_error']:.3f}, jumps {row['jumps']}, coverage {row['coverage']:.3f}, "
                      f"CER {row['cer']:.3f}", flush=True)
    rows.sort(key=lambda r: (r["kind"], r["seed"], r["sheet"]))
    path = args.csv or os.path.join(args.out, "results.csv")
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    print(summary(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Stress benchmark of `virtual-unwrap unwrap` on randomised CT scans of rolled sheets.

A generator of rolled-sheet CT scans written independently of the module's own phantom
source (its own geometry, rasteriser, noise model, fonts and words), and a scorer that runs
the tool with its default options on each scan and compares the sheet surface it finds,
and the text it renders, with the known truth. Every parameter of a scan is drawn at run
time from its seed; nothing in the family is tuned to the tool.

Subcommands (run with Debian's /usr/bin/python3; numpy, scipy, matplotlib, tifffile,
pydicom, PIL and tesseract are needed):

    sheet_stress.py generate --seed N --out DIR [--region accept|wide] [--small]
                             [--param key=value ...]
        Draw one scan's parameters from the seed (printed, and stored in DIR/truth.json
        with the text), write the volume (DIR/volume.mha, DIR/tiff/ or DIR/dicom/),
        the true ink image DIR/truth_ink.png and the geometry tables DIR/truth_geometry.npz.

    sheet_stress.py run --scans 100 --seed S --out DIR [--jobs 1] [--region accept|wide]
                        [--csv FILE] [--tool build/bin/virtual-unwrap] [--small]
                        [--keep failures|all|none] [--selfcheck] [--strict] [--stage unwrap|mesh]
                        [--require-success]
        Generate scans with seeds S, S+1, ..., run `virtual-unwrap unwrap INPUT -o OUT -q`
        on each with default options (--spacing added for TIFF stacks, which carry no
        geometry), score it, write one CSV row per scan and print a per-factor summary
        (markdown). Failing scans get DIR/scan-SEED/overlay.png: slices with the true
        mid-surface (green) and the mesh's cross-section (red, layer jumps yellow).
        --stage mesh: `virtual-unwrap segment` instead (the same mesh, no flattening or texture),
        scored on the mesh alone: several times faster, for the hundred-scan run and the map.
        --strict: exit 2 if the tool crashed (signal, exit status other than 0 or 1,
        missing outputs) or scoring raised; a refusal (exit 1) is a failed scan, not an error.
        --require-success: exit 3 unless every scan succeeds (for a regression check on a
        scan that once failed, given by its seed).

    sheet_stress.py map --per-cell K --out DIR --csv FILE --png FILE [--seed S]
                        [--snr 8,5,4,3,2.5,2,1.5] [--gaps 1,1.5,2,3,4,6] [--stage unwrap|mesh]
        Stability map of the segmentation: success rate on a grid of SNR x gap between
        turns (voxels), the other parameters drawn from the whole family; heat-map PNG.

    sheet_stress.py rescore --out DIR --csv FILE [--rerun unwrap|mesh] [--jobs N] [--strict]
                                            score a run directory's scans again (after running
                                            the tool on them again)
    sheet_stress.py ceiling --scans 100 --seed S --out DIR --csv FILE [--jobs N] [--require-legible]
        How legible the scans themselves are, without the tool: each scan's ink read from the
        TRUE surface (ink_ceiling; cer_ceiling per scan, the share legible per factor). `run`
        (--stage unwrap) and `rescore` add cer_ceiling to every row as well.
    sheet_stress.py summary --csv FILE      reprint the summary table of a CSV
    sheet_stress.py selfcheck [--tool T]    the scorer against the truth itself (and T reads
                                            every format)
    sheet_stress.py preview --scan DIR --png FILE   slices and true ink of a generated scan

Scan family (all lengths in voxels; the voxel size in mm is drawn separately and only
scales the file's geometry). In the roll's own frame (axis z') the mid-surface's polar
radius at unwrapped angle phi is

    rho(phi, z') = S(alpha) * (r(phi) + a(z') + touches(phi, z')),   alpha = phi mod 2 pi

with dr/dphi = (gap(phi) + thickness(phi)) / (2 pi), gap(phi) = gap * (1 + unevenness * u),
u in [0, 1] smooth, corrected so that the smallest perpendicular gap between neighbouring
turns is exactly `gap`; S is an ellipse (axes ratio `squash`) times a few low-order Fourier
terms (`irregularity`, relative amplitude), normalised so that the perpendicular turn
spacing is smallest (= the pitch) where the shape is tightest; a(z') is a smooth radius
variation along the axis; touches pinch the gap to zero over a short arc and part of the
width. The thickness varies smoothly (+/- 20 %) along the sheet and the axis; the inner and
outer ends sit at any angles and may drift with z' (a skew roll); the axis is tilted about
x and y. Each voxel's value comes from its perpendicular distance d to the nearest sheet
crossing on its ray from the axis: occupancy clip(t/2 - |d| + 0.5, 0, 1), ends and edges
anti-aliased the same way; ink is a denser layer over the outer third of the thickness on
one face (inner or outer), inside the glyphs of text rendered with PIL in DejaVu Serif /
Condensed / Mono bold. Then Gaussian blur (the scanner's PSF), then noise: white in the
image, or projection-domain noise: what filtered back-projection makes of noisy
sinograms (ramp-shaped noise power spectrum), with optional ring artefacts (per-channel
detector offsets, back-projected) and streaks (single bad readings, back-projected),
scaled so that the noise sigma in air is (sheet level - air level) / SNR.

Scoring (in voxels; the tool writes surface.obj in the input's physical mm, mapped back
to voxels with the volume's origin and spacing):
  mesh error  distance of each mesh vertex to the true mid-surface: nearest truth sample
              (cKDTree, samples every 0.25 voxel, coarser on the largest sheets), refined
              point-to-plane with the sample's normal and tangents; mean, p95, max over the
              vertices inside the volume (where a field of view cuts the roll, the mesh bridges
              the sheet outside the scan, which no scan shows; mesh_error_mean_all and
              vertices_outside report that part)
  jumps       mesh edges inside the volume whose ends' true arc lengths s differ by more than twice the
              edge's length plus 4 voxels (an edge between two turns)
  coverage    fraction of the true sheet inside the field of view (samples every half
              voxel in s and w) within 1 voxel of the mesh (exact point-to-triangle
              distance to the triangles of the nearest points of the densified mesh)
  CER         tesseract (--psm 6), Levenshtein distance / length of the true text (capitals,
              letters, digits and single spaces; lines joined by a space), best of the 8
              rotations / mirrors. cer: the whole texture.png; cer_text: the box of texture.png
              where the true text lies, found through the tool's own mesh (vertices whose true
              (s, w) fall in the text block, mapped by flat.obj's texture coordinates). On a long
              sheet the whole texture is mostly noise that tesseract reads as letters, so cer
              counts those insertions; cer_text measures the text. The 8 variants are tried
              on the box and the whole image is read in the best of them (all 8 without a box).
  success     mean mesh error <= 0.5 voxel, 0 jumps, coverage >= 97 %;
              legible: cer <= 5 %, legible_text: cer_text <= 5 %

Formats: MetaImage (float32, or int16 HU), TIFF stack (int16 HU, or uint16 HU + 32768; the
tool gets --spacing), DICOM CT series (int16, Rescale Slope/Intercept, one file per slice,
instance numbers in either order). Each scan directory keeps truth.json (parameters, text,
ink grid, volume frame, measured gap and SNR), truth_ink.png, truth_geometry.npz, tool.json
(command, exit status, stderr), unwrap/ (the tool's outputs) and, for failures,
overlay.png; volumes of successful scans are deleted unless --keep all.
"""
import argparse
import concurrent.futures
import csv
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

# ----------------------------------------------------------------------------------------
# Words and fonts of the ink. Capital English words; the fonts are the bold serif, the
# condensed and the monospaced faces of fonts-dejavu-core.

WORDS = """
ABOUT ABOVE ACROSS AFTER AGAIN AGAINST ALMOST ALONG ALWAYS AMONG ANCIENT ANIMAL ANSWER
APPLE ARMY AROUND AUTUMN BASKET BEFORE BEHIND BELOW BESIDE BETTER BETWEEN BEYOND BIRD
BLACK BORDER BOTTLE BRANCH BREAD BRIDGE BRIGHT BROTHER BUILD BURNING CANDLE CAPTAIN
CARRY CASTLE CATTLE CENTRE CHAIR CHANGE CHAPTER CHILD CIRCLE CITY CLEAR CLOUD COAST
COLD COLOUR COMMON CORNER COUNTRY COURAGE CROWN DANCE DARK DAUGHTER DEEP DESERT DINNER
DISTANT DOCTOR DOOR DREAM DRIVE EARLY EARTH EASTERN EMPTY EVENING FAMILY FARMER FATHER
FEATHER FIELD FINGER FIRE FLOWER FOREST FORGET FRIEND FROZEN GARDEN GATHER GENTLE GLASS
GOLDEN GRAIN GREEN GROUND HARBOUR HARVEST HEAVY HIDDEN HONEY HORSE HOUSE HUNDRED HUNTER
ISLAND JOURNEY KETTLE KING KITCHEN LADDER LAMP LANTERN LETTER LIGHT LITTLE MARKET MEADOW
MERCHANT MIDDLE MIRROR MORNING MOTHER MOUNTAIN NARROW NEEDLE NORTHERN NUMBER OCEAN OFFICE
ORANGE ORCHARD PALACE PAPER PEOPLE PEPPER PILLOW PLANET POCKET POWDER PRINCE QUIET RABBIT
RAILWAY RIVER ROCKET ROUND SADDLE SAILOR SALT SEASON SECOND SHADOW SHEPHERD SHIP SILENT
SILVER SISTER SLOW SMALL SOLDIER SPRING SQUARE STABLE STONE STORM STRANGE STREAM STREET
SUMMER SUNDAY SWEET TABLE TEACHER THUNDER TIMBER TOWER TRAVEL TREASURE VALLEY VELVET
VILLAGE VIOLET VOYAGE WAGON WALNUT WARM WATER WEATHER WESTERN WHEEL WHISPER WINDOW WINTER
WOODEN WORKER YELLOW YESTERDAY YOUNG ZEBRA
""".split()

FONT_DIR = "/usr/share/fonts/truetype/dejavu"
FONTS = ["DejaVuSerif-Bold.ttf", "DejaVuSerifCondensed-Bold.ttf", "DejaVuSansCondensed-Bold.ttf",
         "DejaVuSansMono-Bold.ttf"]

TEXTURE_PIXEL = 0.5  # ink image pixel, voxels (the tool's texture pixel is half a voxel)
SUCCESS_ERROR, SUCCESS_COVERAGE, LEGIBLE_CER = 0.5, 0.97, 0.05

# ----------------------------------------------------------------------------------------
# Parameters


def stream(seed, name):
    """An independent random stream per parameter, so overriding one leaves the others."""
    return np.random.default_rng([int(seed), zlib.crc32(name.encode())])


def log_uniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def draw_parameters(seed, region="wide", small=False, overrides=None):
    """All parameters of one scan, drawn from the seed; `overrides` (name -> value) win."""
    overrides = dict(overrides or {})
    p = {"seed": int(seed), "region": region, "small": bool(small)}
    accept = region == "accept"

    def draw(name, fn):
        if name in overrides:
            value = overrides.pop(name)
            default = fn(stream(seed, name))
            p[name] = type(default)(value) if not isinstance(default, bool) else value in (True, "1", "true", "yes")
        else:
            p[name] = fn(stream(seed, name))
        return p[name]

    def turns(r):
        if small:
            return float(r.uniform(2.0, 3.5))
        u = r.random()
        if u < 0.80:
            return float(r.uniform(2.0, 12.0))
        if u < 0.90:
            return float(r.uniform(12.0, 20.0))
        return float(r.uniform(20.0, 30.0))

    draw("turns", turns)
    draw("thickness", lambda r: float(r.uniform(2.0 if accept else 1.0, 4.0)))
    draw("gap", lambda r: log_uniform(r, 2.0 if accept else 1.0, 8.0))
    draw("snr", lambda r: log_uniform(r, 3.0 if accept else 1.5, 8.0))
    draw("radius_variation", lambda r: float(r.uniform(0.0, 2.0 if small else 4.0)))
    draw("radius_variation_kind", lambda r: str(r.choice(["sine", "taper"])))
    draw("unevenness", lambda r: float(r.uniform(0.0, 1.0)))
    draw("touches", lambda r: int(0 if r.random() < 0.5 else r.integers(1, 5)))
    draw("irregularity", lambda r: float(r.uniform(0.0, 0.10)))
    draw("squash", lambda r: float(r.uniform(0.6, 1.0)))
    draw("thickness_variation", lambda r: float(r.uniform(0.0, 0.2)))
    draw("end_drift_inner", lambda r: float(r.uniform(-8.0, 8.0)))
    draw("end_drift_outer", lambda r: float(r.uniform(-8.0, 8.0)))
    draw("start_angle_deg", lambda r: float(r.uniform(0.0, 360.0)))
    draw("width", lambda r: float(r.uniform(36.0, 44.0) if small else r.uniform(40.0, 140.0)))
    tilt_max = 5.0 if small else 15.0
    draw("tilt_x_deg", lambda r: float(r.uniform(-tilt_max, tilt_max)))
    draw("tilt_y_deg", lambda r: float(r.uniform(-tilt_max, tilt_max)))
    draw("clockwise", lambda r: bool(r.random() < 0.5))
    draw("fov_cut", lambda r: float(r.uniform(0.0, 1.0)) if r.random() < 0.2 else 0.0)  # fraction of 15 % D
    draw("fov_cut_side", lambda r: str(r.choice(["-x", "+x", "-y", "+y"])))
    draw("margin", lambda r: float(r.uniform(2.0, 12.0)))
    draw("voxel_mm", lambda r: round(log_uniform(r, 0.02, 1.0), 5))
    draw("air_hu", lambda r: float(r.uniform(-1024.0, -960.0)))
    draw("sheet_hu", lambda r: float(r.uniform(-200.0, 300.0)))
    draw("ink_face", lambda r: str(r.choice(["inner", "outer"])))
    draw("ink_contrast", lambda r: float(r.uniform(0.3, 1.2)))
    draw("font", lambda r: str(r.choice(FONTS)))
    draw("letter_height", lambda r: float(r.uniform(8.0, 10.0) if small else r.uniform(8.0, 20.0)))
    draw("text_lines", lambda r: int(2 if small else r.integers(2, 5)))
    draw("blur", lambda r: float(r.uniform(0.4, 1.2)))
    draw("noise", lambda r: str(r.choice(["image", "projection"])))
    draw("rings", lambda r: float(r.uniform(0.5, 3.0)) if r.random() < 0.5 else 0.0)
    draw("streaks", lambda r: float(r.uniform(0.1, 0.5)) if r.random() < 0.4 else 0.0)
    draw("format", lambda r: str(r.choice(["mha-float", "mha-int16", "tiff-int16", "tiff-uint16", "dicom"])))
    draw("origin_x_mm", lambda r: float(r.uniform(-100.0, 100.0)))
    draw("origin_y_mm", lambda r: float(r.uniform(-100.0, 100.0)))
    draw("origin_z_mm", lambda r: float(r.uniform(-100.0, 100.0)))
    draw("inner_radius", lambda r: log_uniform(r, 4.0, 10.0) if small else log_uniform(r, 3.0, 30.0))
    if overrides:
        raise SystemExit(f"unknown parameter(s): {', '.join(sorted(overrides))}")
    # Dependent limits (not draws): the innermost turn keeps clear of the axis, and the roll
    # fits the in-plane budget (turns are cut first, unless they were given).
    p["inner_radius"] = max(p["inner_radius"], p["radius_variation"] + p["thickness"] + 2.0)
    budget = 46.0 if small else 210.0
    pitch = p["gap"] * (1.0 + 0.5 * p["unevenness"]) + p["thickness"]
    fit = (budget / (1.0 + p["irregularity"]) / 1.25 - p["inner_radius"] - p["radius_variation"]) / pitch
    if p["turns"] > fit:
        p["turns_drawn"] = p["turns"]
        p["turns"] = max(1.6, float(fit))
    return p


def derived_factors(p):
    """Factor columns for the summary (from the parameters)."""
    tilt = math.degrees(math.acos(math.cos(math.radians(p["tilt_x_deg"])) * math.cos(math.radians(p["tilt_y_deg"]))))
    artefact = "image noise" if p["noise"] == "image" else "projection noise"
    if p["noise"] == "projection":
        extra = [name for name in ("rings", "streaks") if p[name] > 0]
        if extra:
            artefact += " + " + " + ".join(extra)
    return {"tilt_deg": round(tilt, 3), "artefact": artefact,
            "coarse_voxels": bool(p["thickness"] <= 1.5)}


# ----------------------------------------------------------------------------------------
# Geometry


def smooth_profile(rng, x, periods, count=3):
    """Sum of `count` cosines of the given period range over x, scaled to [-1, 1]."""
    y = np.zeros_like(x)
    for _ in range(count):
        period = rng.uniform(*periods)
        y += rng.uniform(0.3, 1.0) * np.cos(2 * np.pi * x / period + rng.uniform(0, 2 * np.pi))
    lo, hi = y.min(), y.max()
    return 2.0 * (y - lo) / max(hi - lo, 1e-9) - 1.0


def rotation(p):
    ax, ay = math.radians(p["tilt_x_deg"]), math.radians(p["tilt_y_deg"])
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    return rx @ ry


def lerp(table, x0, dx, x, periodic=False, outside=None):
    """Linear interpolation in a table sampled at x0 + i dx (np.interp without the search)."""
    f = (np.asarray(x, dtype=np.float64) - x0) / dx
    n = len(table)
    if periodic:
        f = np.mod(f, n)
        i = np.minimum(f.astype(np.intp), n - 1)
        frac = f - i
        return table[i] * (1 - frac) + table[(i + 1) % n] * frac
    i = np.clip(np.floor(f), 0, n - 2).astype(np.intp)
    frac = np.clip(f - i, 0.0, 1.0)
    out = table[i] * (1 - frac) + table[i + 1] * frac
    if outside is not None:
        out = np.where((f < 0) | (f > n - 1), outside, out)
    return out


class Roll:
    """The true mid-surface and sheet of one scan, in the roll's frame (voxels)."""

    def __init__(self, p):
        self.p = p
        seed = p["seed"]
        t0, g, n_turns = p["thickness"], p["gap"], p["turns"]
        self.width = p["width"]
        self.hand = -1.0 if p["clockwise"] else 1.0
        # Cross-section shape S(alpha): ellipse times low-order Fourier terms, normalised so
        # that the smallest perpendicular turn-spacing factor is 1.
        rng = stream(seed, "shape")
        na = 4096
        self.alpha = np.linspace(0, 2 * np.pi, na, endpoint=False)
        q, ae = p["squash"], rng.uniform(0, np.pi)
        ell = q / np.sqrt((q * np.cos(self.alpha - ae)) ** 2 + np.sin(self.alpha - ae) ** 2)
        orders = np.arange(2, 6)
        weights = rng.random(len(orders))
        weights *= p["irregularity"] / max(weights.sum(), 1e-9)
        four = np.ones(na)
        for k, w in zip(orders, weights):
            four += w * np.cos(k * self.alpha + rng.uniform(0, 2 * np.pi))
        shape = ell * four
        dshape = (np.roll(shape, -1) - np.roll(shape, 1)) / (2 * (2 * np.pi / na))
        spacing_factor = shape / np.sqrt(1 + (dshape / shape) ** 2)
        norm = spacing_factor.min()
        self.S, self.dS, self.G = shape / norm, dshape / norm, spacing_factor / norm
        # Profiles along the sheet (turns as the unit of phi).
        self.phi_start = math.radians(p["start_angle_deg"])
        r_guess = p["inner_radius"] + (n_turns + 2) * (g * (1 + p["unevenness"]) + 1.25 * t0)
        lo = self.phi_start - 2 * np.pi * 0.75
        hi = self.phi_start + 2 * np.pi * (n_turns + 1.75)
        n = int(min(2_000_000, max(20000, (hi - lo) * r_guess * self.S.max() / 0.08)))
        self.phi = np.linspace(lo, hi, n)
        turns_axis = (self.phi - self.phi_start) / (2 * np.pi)
        u = 0.5 * (smooth_profile(stream(seed, "uneven"), turns_axis, (0.7, 4.0)) + 1.0)
        self.gap_target = g * (1.0 + p["unevenness"] * u)
        v = smooth_profile(stream(seed, "thick"), turns_axis, (0.3, 3.0))
        self.t_along = t0 * (1.0 + 0.75 * p["thickness_variation"] * v)
        rz = stream(seed, "thick_z")
        self.tz_amp, self.tz_freq, self.tz_phase = 0.25 * p["thickness_variation"], rz.uniform(0.3, 1.5), rz.uniform(0, 2 * np.pi)
        ra = stream(seed, "radius_z")
        self.a_freq, self.a_phase = ra.uniform(0.3, 1.5), ra.uniform(0, 2 * np.pi)
        # Radius by integration of the pitch, corrected until the smallest perpendicular gap
        # between neighbouring turns (over the turns that both exist) is the drawn gap.
        pitch = self.gap_target + self.t_along * (1.0 + self.tz_amp)
        dphi = self.phi[1] - self.phi[0]
        i0 = int(np.searchsorted(self.phi, self.phi_start))
        one_turn = int(round(2 * np.pi / dphi))
        span = slice(i0, i0 + max(1, int((n_turns - 1.0) * 2 * np.pi / dphi)))
        g_at = np.interp(np.mod(self.phi, 2 * np.pi), self.alpha, self.G, period=2 * np.pi)
        for _ in range(6):
            r = np.concatenate([[0.0], np.cumsum(0.5 * (pitch[1:] + pitch[:-1]) * dphi)]) / (2 * np.pi)
            r += p["inner_radius"] - r[i0]
            spacing = np.full(n, np.inf)
            spacing[:-one_turn] = r[one_turn:] - r[:-one_turn]
            tpair = np.full(n, np.inf)
            tpair[:-one_turn] = 0.5 * (self.t_along[one_turn:] + self.t_along[:-one_turn]) * (1 + self.tz_amp)
            with np.errstate(invalid="ignore"):
                gap_perp = g_at * spacing - tpair
            low = np.min(gap_perp[span]) if n_turns > 1.0 else g
            if abs(low - g) < 0.005:
                break
            pitch = pitch + (g - low)
        self.r = np.maximum(r, 0.5)
        self.dr = pitch / (2 * np.pi)
        self.gap_perp = gap_perp
        self.gap_measured_min = float(np.min(gap_perp[span])) if n_turns > 1.0 else float("nan")
        self.gap_measured_median = float(np.median(gap_perp[span])) if n_turns > 1.0 else float("nan")
        # Reference arc length s(phi) on the mean cross-section (no radius variation, no
        # touches): the sheet's own coordinate, s = 0 at the inner end of the middle slice.
        s_al = np.interp(np.mod(self.phi, 2 * np.pi), self.alpha, self.S, period=2 * np.pi)
        ds_al = np.interp(np.mod(self.phi, 2 * np.pi), self.alpha, self.dS, period=2 * np.pi)
        rho = s_al * self.r
        drho = ds_al * self.r + s_al * self.dr
        speed = np.sqrt(rho ** 2 + drho ** 2)
        self.s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * dphi)])
        self.s -= np.interp(self.phi_start, self.phi, self.s)
        # Uniform tables for the hot lookups: phi(s) and phi(r) (both increasing).
        self.dphi = dphi
        self.s_step = (self.s[-1] - self.s[0]) / (n - 1)
        self.phi_of_s = np.interp(self.s[0] + self.s_step * np.arange(n), self.s, self.phi)
        self.r_step = (self.r[-1] - self.r[0]) / (n - 1)
        self.phi_of_r = np.interp(self.r[0] + self.r_step * np.arange(n), self.r, self.phi)
        # Ends: the inner end at phi_start, the outer end `turns` later; both may drift
        # with z' (given as arc length over the width, limited to 0.6 rad).
        r_in = p["inner_radius"]
        r_out = float(np.interp(self.phi_start + 2 * np.pi * n_turns, self.phi, self.r))
        self.drift0 = float(np.clip(p["end_drift_inner"] / (r_in * self.S.mean()), -0.6, 0.6))
        self.drift1 = float(np.clip(p["end_drift_outer"] / (r_out * self.S.mean()), -0.6, 0.6))
        self.phi_end = self.phi_start + 2 * np.pi * n_turns
        # Touches: the gap pinched to zero over a short arc and part of the width (turn k
        # pushed out onto turn k + 1).
        rt = stream(seed, "touches")
        self.touches = []
        for _ in range(p["touches"]):
            if n_turns < 1.3:
                break
            phi_c = self.phi_start + 2 * np.pi * rt.uniform(0.3, max(0.35, n_turns - 1.1))
            rho_c = float(np.interp(phi_c, self.phi, self.r)) * self.S.mean()
            arc = rt.uniform(2.0, 10.0)
            ramp = max(4.0, 3.0 * g)
            half_flat, half_ramp = 0.5 * arc / rho_c, ramp / rho_c
            d = np.abs(self.phi - phi_c)
            win = np.where(d <= half_flat, 1.0,
                           np.where(d <= half_flat + half_ramp,
                                    0.5 * (1 + np.cos(np.pi * (d - half_flat) / half_ramp)), 0.0))
            sel = np.nonzero(win > 0)[0]
            sel = sel[sel + one_turn < n]
            height = (self.r[sel + one_turn] - self.r[sel]) - (self.t_along[sel] + self.t_along[sel + one_turn]) / (2 * g_at[sel])
            zc = rt.uniform(-0.5, 0.5) * self.width
            zh = 0.5 * self.width * rt.uniform(0.3, 1.0)
            self.touches.append({"phi": self.phi[sel].copy(), "phi0": float(self.phi[sel[0]]), "bump": win[sel] * height,
                                 "dbump": np.gradient(win[sel] * height, dphi) if len(sel) > 1 else np.zeros(len(sel)),
                                 "phi_center": float(phi_c), "arc": float(arc), "z_center": float(zc),
                                 "z_half": float(zh)})
        # Frame: roll frame -> volume voxel coordinates (x, y, z index units).
        self.R = rotation(p)
        self.center = np.zeros(3)

    # --- functions of z' --------------------------------------------------------------
    def radius_shift(self, z):
        amp = self.p["radius_variation"]
        if self.p["radius_variation_kind"] == "taper":
            return amp * np.clip(2.0 * z / self.width, -1, 1)
        return amp * np.sin(2 * np.pi * self.a_freq * z / self.width + self.a_phase)

    def thickness_factor(self, z):
        return 1.0 + self.tz_amp * np.sin(2 * np.pi * self.tz_freq * z / self.width + self.tz_phase)

    def end_angles(self, z):
        f = np.clip(z / self.width, -0.5, 0.5)
        return self.phi_start + self.drift0 * f, self.phi_end + self.drift1 * f

    @staticmethod
    def z_window(z, center, half):
        d = np.abs(z - center) - half
        return np.where(d <= 0, 1.0, np.where(d < 4.0, 0.5 * (1 + np.cos(np.pi * d / 4.0)), 0.0))

    # --- the surface ------------------------------------------------------------------
    def touch_windows(self, z):
        return [self.z_window(z, t["z_center"], t["z_half"]) for t in self.touches]

    def radius(self, phi, z, windows=None, shift=None):
        """Normalised radius (before the shape factor) and its derivative along phi."""
        p0, d = self.phi[0], self.dphi
        r = lerp(self.r, p0, d, phi) + (self.radius_shift(z) if shift is None else shift)
        dr = lerp(self.dr, p0, d, phi)
        bump = dbump = 0.0
        if windows is None:
            windows = self.touch_windows(z)
        for t, wz in zip(self.touches, windows):  # overlapping touches: the larger push wins
            if np.any(wz > 0) and len(t["phi"]) > 1:
                b = wz * lerp(t["bump"], t["phi0"], d, phi, outside=0.0)
                db = wz * lerp(t["dbump"], t["phi0"], d, phi, outside=0.0)
                larger = b > bump
                bump, dbump = np.where(larger, b, bump), np.where(larger, db, dbump)
        return r + bump, dr + dbump

    def shape(self, alpha):
        a = np.mod(alpha, 2 * np.pi)
        da = self.alpha[1] - self.alpha[0]
        return lerp(self.S, 0.0, da, a, periodic=True), lerp(self.dS, 0.0, da, a, periodic=True)

    def point(self, phi, z):
        """Roll-frame mid-surface points (..., 3) at unwrapped angles phi and axial z."""
        r, _ = self.radius(phi, z)
        sh, _ = self.shape(phi)
        rho = sh * r
        return np.stack([rho * np.cos(phi), self.hand * rho * np.sin(phi), np.broadcast_to(z, rho.shape)], axis=-1)

    def to_volume(self, pts):
        return pts @ self.R.T + self.center

    def from_volume(self, pts):
        return (pts - self.center) @ self.R

    def arc_to_phi(self, s):
        return lerp(self.phi_of_s, self.s[0], self.s_step, s)

    def frame(self, phi, z):
        """Roll-frame mid-surface points at (phi, z), their derivative along phi and their
        unit normals (outward)."""
        pt = self.point(phi, z)
        eps = 1e-3
        dphi = (self.point(phi + eps, z) - self.point(phi - eps, z)) / (2 * eps)
        dz = (self.point(phi, z + 0.05) - self.point(phi, z - 0.05)) / 0.1
        nrm = np.cross(dphi, dz)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        radial = pt.copy()
        radial[:, 2] = 0
        nrm *= np.sign(np.sum(nrm * radial, axis=1))[:, None]
        return pt, dphi, nrm

    def samples(self, h, phi_limits=True):
        """Mid-surface samples every h along s and w: volume points, unit normals (outward),
        unit tangents along s and along w, s, w and turn index."""
        z = np.linspace(-0.5 * self.width, 0.5 * self.width, int(math.ceil(self.width / h)) + 1)
        p0, p1 = self.end_angles(z)
        s0, s1 = np.interp(p0, self.phi, self.s), np.interp(p1, self.phi, self.s)
        s_grid = np.arange(s0.min(), s1.max() + 1e-9, h)
        out = {k: [] for k in ("points", "normals", "ts", "tw", "s", "w", "turn")}
        chunk = max(1, int(4_000_000 // max(len(s_grid), 1)))
        for i in range(0, len(z), chunk):
            zz, ss = np.meshgrid(z[i:i + chunk], s_grid, indexing="ij")
            keep = (ss >= s0[i:i + chunk, None]) & (ss <= s1[i:i + chunk, None])
            zc = z[i:i + chunk]
            zz = np.concatenate([zz[keep], zc, zc])  # and each row's exact ends
            ss = np.concatenate([ss[keep], s0[i:i + chunk], s1[i:i + chunk]])
            phi = self.arc_to_phi(ss)
            pt, dphi, nrm = self.frame(phi, zz)
            ts = dphi / np.linalg.norm(dphi, axis=1, keepdims=True)
            tw = np.cross(nrm, ts)
            tw *= np.sign(tw[:, 2])[:, None]
            out["points"].append(self.to_volume(pt).astype(np.float32))
            out["normals"].append((nrm @ self.R.T).astype(np.float32))
            out["ts"].append((ts @ self.R.T).astype(np.float32))
            out["tw"].append((tw @ self.R.T).astype(np.float32))
            out["s"].append(ss.astype(np.float32))
            out["w"].append(zz.astype(np.float32))
            out["turn"].append(np.floor((phi - self.phi_start) / (2 * np.pi)).astype(np.int16))
        return {k: np.concatenate(v) for k, v in out.items()}

    def area(self):
        z = np.linspace(-0.5 * self.width, 0.5 * self.width, 21)
        p0, p1 = self.end_angles(z)
        return float(np.mean(np.interp(p1, self.phi, self.s) - np.interp(p0, self.phi, self.s)) * self.width)

    def sheet_length(self):
        return float(np.interp(self.phi_end, self.phi, self.s) - np.interp(self.phi_start, self.phi, self.s))

    # --- rasterisation ----------------------------------------------------------------
    def rasterise(self, xyz_volume, ink=None):
        """Sheet occupancy and ink occupancy x glyph at volume points (N, 3)."""
        x, y, z = self.from_volume(xyz_volume).T
        y = self.hand * y
        rho = np.hypot(x, y)
        alpha = np.mod(np.arctan2(y, x), 2 * np.pi)
        sh, dsh = self.shape(alpha)
        a = self.radius_shift(z)
        u = rho / sh - a
        phi_u = lerp(self.phi_of_r, self.r[0], self.r_step, u)
        windows = self.touch_windows(z)
        k_lo = np.floor((phi_u - alpha) / (2 * np.pi))
        p0, p1 = self.end_angles(z)
        half_w = 0.5 * self.width
        fz = np.clip(half_w - np.abs(z) + 0.5, 0.0, 1.0)
        tz = self.thickness_factor(z)
        occ = np.zeros_like(rho)
        inked = np.zeros_like(rho)
        sign = 1.0 if self.p["ink_face"] == "outer" else -1.0
        for m in (-1, 0, 1):  # the crossings either side of the voxel, and one more inside (touches)
            phi = alpha + 2 * np.pi * (k_lo + m)
            r, dr = self.radius(phi, z, windows, a)
            rho_m = sh * r
            drho = dsh * r + sh * dr
            arc = np.sqrt(rho_m ** 2 + drho ** 2)
            d = (rho - rho_m) * rho_m / arc
            t = lerp(self.t_along, self.phi[0], self.dphi, phi) * tz
            ends = np.clip((phi - p0) * arc + 0.5, 0.0, 1.0) * np.clip((p1 - phi) * arc + 0.5, 0.0, 1.0) * fz
            occ += np.clip(0.5 * t - np.abs(d) + 0.5, 0.0, np.minimum(1.0, t)) * ends
            if ink is not None:
                layer = t / 3.0
                ink_occ = np.clip(0.5 * layer - np.abs(d - sign * t / 3.0) + 0.5, 0.0, np.minimum(1.0, layer)) * ends
                hit = ink_occ > 0
                if np.any(hit):
                    s = lerp(self.s, self.phi[0], self.dphi, phi[hit])
                    inked[hit] += ink_occ[hit] * ink.sample(s, z[hit])
        return np.minimum(occ, 1.0), inked


# ----------------------------------------------------------------------------------------
# Ink


class Ink:
    """Text rendered over the sheet map: x = arc length s, y = axial position w."""

    def __init__(self, image, s_origin, w_top, pixel=TEXTURE_PIXEL):
        self.image = image.astype(np.float32) / 255.0
        self.s_origin, self.w_top, self.pixel = s_origin, w_top, pixel

    def sample(self, s, w):
        col = (s - self.s_origin) / self.pixel
        row = (self.w_top - w) / self.pixel
        return ndimage.map_coordinates(self.image, [row, col], order=1, cval=0.0)


def draw_text_block(font, lines, px):
    """Lines of text drawn white on black (uint8 array), capitals px pixels tall, 1.6 of
    them apart, in a margin of 4 pixels."""
    from PIL import Image, ImageDraw
    cap = font.getbbox("H")
    line_px = 1.6 * px
    block_w = max(font.getlength(line) for line in lines)
    block_h = (len(lines) - 1) * line_px + 1.3 * px
    pad = 4
    img = Image.new("L", (int(math.ceil(block_w)) + 2 * pad, int(math.ceil(block_h)) + 2 * pad), 0)
    draw = ImageDraw.Draw(img)
    for i, line in enumerate(lines):
        draw.text((pad, pad + i * line_px - cap[1] + 0.15 * px), line, font=font, fill=255)
    return np.asarray(img)


def render_text(p, roll, fov_ok):
    """Lay out 2-4 lines of random words in the longest stretch of the sheet inside the field
    of view; returns (Ink, lines, layout facts)."""
    from PIL import ImageFont
    rng = stream(p["seed"], "words")
    font_path = os.path.join(FONT_DIR, p["font"])
    height = p["letter_height"]
    lines_wanted = p["text_lines"]
    half_w = 0.5 * roll.width
    z = np.linspace(-half_w, half_w, 9)
    p0, p1 = roll.end_angles(z)
    s_lo = float(np.max(np.interp(p0, roll.phi, roll.s)))
    s_hi = float(np.min(np.interp(p1, roll.phi, roll.s)))
    border = max(3.0, 1.25 * p["thickness"] + 2.0)
    # The longest run of s inside the field of view (fov_ok: s grid -> bool).
    s_grid, ok = fov_ok
    ok = ok & (s_grid >= s_lo + border) & (s_grid <= s_hi - border)
    best, start = (0.0, s_lo + border, s_lo + border), None
    for i, flag in enumerate(np.append(ok, False)):
        if flag and start is None:
            start = i
        elif not flag and start is not None:
            a, b = s_grid[start], s_grid[i - 1]
            if b - a > best[0]:
                best = (b - a, a, b)
            start = None
    if best[0] < 4 * height:  # nothing usable inside the field of view: the whole sheet
        best = (s_hi - s_lo - 2 * border, s_lo + border, s_hi - border)
    avail_s, s_a, s_b = best
    avail_w = roll.width - 2 * border
    def block(lines, h):
        return (lines - 1) * 1.6 * h + 1.3 * h
    while block(lines_wanted, height) > avail_w and lines_wanted > 2:
        lines_wanted -= 1
    while block(lines_wanted, height) > avail_w and height > 8.0:
        height = max(8.0, 0.9 * height)
    while block(lines_wanted, height) > avail_w and lines_wanted > 1:
        lines_wanted -= 1
    while block(lines_wanted, height) > avail_w and height > 6.0:
        height = max(6.0, 0.9 * height)
    px = height / TEXTURE_PIXEL
    font = ImageFont.truetype(font_path, 100)
    cap = font.getbbox("H")
    font = ImageFont.truetype(font_path, max(6, int(round(100 * px / (cap[3] - cap[1])))))
    max_len_px = min(avail_s, rng.uniform(25.0, 60.0) * height) / TEXTURE_PIXEL
    lines = []
    for _ in range(lines_wanted):
        words = []
        for _ in range(rng.integers(2, 6)):
            candidate = " ".join(words + [str(rng.choice(WORDS))])
            if font.getlength(candidate) <= max_len_px or not words:
                words = candidate.split()
        while words and font.getlength(" ".join(words)) > avail_s / TEXTURE_PIXEL and len(words[-1]) > 1:
            if len(words) > 1:
                words.pop()
            else:
                words[0] = words[0][:-1]
        lines.append(" ".join(words))
    arr = draw_text_block(font, lines, px)
    # Place the block at random inside the usable stretch and width.
    block_s = arr.shape[1] * TEXTURE_PIXEL
    block_wv = arr.shape[0] * TEXTURE_PIXEL
    s_origin = s_a + rng.uniform(0, max(0.0, (s_b - s_a) - block_s))
    w_top = half_w - border - rng.uniform(0, max(0.0, avail_w - block_wv))
    facts = {"letter_height_used": round(height, 3), "text_lines_used": len(lines),
             "ink_s_origin": s_origin, "ink_w_top": w_top, "text_fits_fov": bool(best[0] >= block_s)}
    return Ink(arr, s_origin, w_top), lines, facts


# ----------------------------------------------------------------------------------------
# Volume


def layout_volume(p, roll):
    """Place the roll in the volume: voxel dimensions and the roll centre (voxel coordinates),
    with the air margin and the optional field-of-view cut on one side."""
    h = max(1.0, math.sqrt(roll.area() / 200_000.0))
    pts = roll.samples(h)["points"].astype(np.float64)
    reach = 0.5 * p["thickness"] * 1.25 + 3.0 * p["blur"] + 1.0
    lo, hi = pts.min(axis=0) - reach, pts.max(axis=0) + reach
    margin = p["margin"]
    lo[:2] -= margin
    hi[:2] += margin
    lo[2] -= 2.0
    hi[2] += 2.0
    cut = 0.0
    if p["fov_cut"] > 0:
        diameter = float(np.max(hi[:2] - lo[:2]) - 2 * margin)
        cut = margin + max(3.0, p["fov_cut"] * 0.15 * diameter)
        axis = 0 if p["fov_cut_side"][1] == "x" else 1
        if p["fov_cut_side"][0] == "-":
            lo[axis] += cut
        else:
            hi[axis] -= cut
    dims = np.ceil(hi - lo).astype(int) + 1
    roll.center = -lo
    return dims, cut - margin if cut > 0 else 0.0


def fov_along_sheet(roll, dims, step=1.0):
    """For an s grid, whether the sheet is inside the volume at every w."""
    z = np.linspace(-0.5 * roll.width + 2, 0.5 * roll.width - 2, 9)
    p0, p1 = roll.end_angles(np.zeros(1))
    s_grid = np.arange(roll.s.min(), roll.s.max(), step)
    ok = np.ones(len(s_grid), dtype=bool)
    pad = 0.5 * roll.p["thickness"] + 1.0
    for zz in z:
        pts = roll.to_volume(roll.point(roll.arc_to_phi(s_grid), np.full(len(s_grid), zz)))
        ok &= np.all((pts >= pad) & (pts <= dims - 1 - pad), axis=1)
    return s_grid, ok


def ring_kernel(n):
    """Discrete ramp (Ram-Lak) filter kernel for offsets -n..n (detector channels)."""
    k = np.arange(-n, n + 1)
    h = np.zeros(len(k))
    h[k == 0] = 0.25
    odd = (k % 2) != 0
    h[odd] = -1.0 / (np.pi * k[odd]) ** 2
    return k, h


def projection_noise(p, shape, air_mask):
    """Noise of filtered back-projection for a parallel-beam scanner rotating about z:
    white sinogram noise becomes image noise with a ramp-shaped power spectrum; per-channel
    detector offsets become rings about the rotation centre; single bad readings become
    streaks. Returned with unit standard deviation over the air voxels."""
    nz, ny, nx = shape
    rng = stream(p["seed"], "projection")
    ky = np.fft.fftfreq(ny)[:, None]
    kx = np.fft.rfftfreq(nx)[None, :]
    k = np.sqrt(kx ** 2 + ky ** 2)
    window = np.where(k <= 0.5, 0.5 * (1 + np.cos(np.pi * k / 0.5)), 0.0) ** 0.5  # Hann apodisation
    filt = np.sqrt(k) * window
    noise = np.empty(shape, dtype=np.float32)
    for z0 in range(0, nz, 16):
        white = rng.standard_normal((min(16, nz - z0), ny, nx)).astype(np.float32)
        noise[z0:z0 + 16] = np.fft.irfft2(np.fft.rfft2(white) * filt, s=(ny, nx))
    noise /= noise.std()
    centre = np.array([nx, ny]) / 2.0 + rng.uniform(-5, 5, 2)
    yy, xx = np.mgrid[0:ny, 0:nx].astype(np.float32)
    if p["rings"] > 0:
        # Offsets of a few bad channels (and a little spread on all), back-projected after
        # ramp filtering: a radially symmetric image about the rotation centre.
        n = int(np.hypot(nx, ny) / 2) + 4
        offsets = 0.05 * rng.standard_normal(2 * n + 1)
        bad = rng.choice(2 * n + 1, size=int(rng.integers(3, 12)), replace=False)
        offsets[bad] += rng.choice([-1.0, 1.0], len(bad)) * rng.uniform(0.5, 1.5, len(bad))
        kk, h = ring_kernel(16)
        q = np.convolve(offsets, h, mode="same")
        channels = np.arange(-n, n + 1)
        radii = np.arange(0, n, 0.25)
        theta = np.linspace(0, np.pi, 360, endpoint=False)
        ring_profile = np.mean(np.interp(radii[:, None] * np.cos(theta)[None, :], channels, q), axis=1)
        ring = np.interp(np.hypot(xx - centre[0], yy - centre[1]), radii, ring_profile)
        ring /= max(np.abs(ring).max(), 1e-9)
        drift = 1.0 + 0.2 * np.sin(np.linspace(0, np.pi * rng.uniform(0.5, 2), nz) + rng.uniform(0, 6.3))
        noise += (p["rings"] * ring)[None, :, :] * drift[:, None, None].astype(np.float32)
    if p["streaks"] > 0:
        kk, h = ring_kernel(8)
        for z in range(nz):
            if rng.random() >= p["streaks"]:
                continue
            for _ in range(int(rng.integers(1, 4))):
                th = rng.uniform(0, np.pi)
                c = rng.uniform(-0.4, 0.4) * min(nx, ny)
                t = (xx - centre[0]) * math.cos(th) + (yy - centre[1]) * math.sin(th) - c
                noise[z] += rng.uniform(3.0, 10.0) * np.interp(t, kk, h, left=0.0, right=0.0) / 0.25
    sd = float(noise[air_mask].std()) if np.any(air_mask) else float(noise.std())
    return noise / max(sd, 1e-9)


def make_volume(p, roll, dims, ink):
    """Clean (blurred) relative volume in [0, ~2] (air 0, sheet 1), the noise (unit sd in
    air), and the air mask."""
    nx, ny, nz = (int(v) for v in dims)
    clean = np.zeros((nz, ny, nx), dtype=np.float32)
    yy, xx = np.mgrid[0:ny, 0:nx].astype(np.float64)
    base = np.stack([xx.ravel(), yy.ravel(), np.zeros(nx * ny)], axis=1)
    for z in range(nz):
        base[:, 2] = z
        occ, inked = roll.rasterise(base, ink)
        clean[z] = (occ + p["ink_contrast"] * inked).reshape(ny, nx)
    if p["blur"] > 0:
        clean = ndimage.gaussian_filter(clean, p["blur"], mode="nearest").astype(np.float32)
    air = clean < 0.01
    if p["noise"] == "projection":
        noise = projection_noise(p, clean.shape, air)
    else:
        noise = stream(p["seed"], "noise").standard_normal(clean.shape).astype(np.float32)
    return clean, noise, air


def write_mha(path, volume, spacing, origin, element):
    nz, ny, nx = volume.shape
    header = ("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
              "CompressedData = False\nTransformMatrix = 1 0 0 0 1 0 0 0 1\n"
              f"Offset = {origin[0]:.6f} {origin[1]:.6f} {origin[2]:.6f}\nCenterOfRotation = 0 0 0\n"
              "AnatomicalOrientation = RAI\n"
              f"ElementSpacing = {spacing:.6g} {spacing:.6g} {spacing:.6g}\nDimSize = {nx} {ny} {nz}\n"
              f"ElementType = {element}\nElementDataFile = LOCAL\n")
    dtype = {"MET_FLOAT": "<f4", "MET_SHORT": "<i2"}[element]
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(np.ascontiguousarray(volume.astype(dtype)).tobytes())


def write_tiff_stack(directory, volume, dtype):
    import tifffile
    os.makedirs(directory, exist_ok=True)
    for z in range(volume.shape[0]):
        tifffile.imwrite(os.path.join(directory, f"slice_{z:04d}.tif"), volume[z].astype(dtype))


def write_dicom_series(directory, hu, spacing, origin, seed):
    import pydicom
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
    os.makedirs(directory, exist_ok=True)
    rng = stream(seed, "dicom")
    slope = float(rng.choice([1.0, 0.5]))
    intercept = float(rng.choice([-1024.0, 0.0, -1000.0]))
    stored = np.clip(np.round((hu - intercept) / slope), -32768, 32767).astype(np.int16)
    study, series, frame = (generate_uid(entropy_srcs=[str(seed), name]) for name in ("study", "series", "frame"))
    ct = "1.2.840.10008.5.1.4.1.1.2"
    nz, ny, nx = hu.shape
    order = np.arange(nz) if rng.random() < 0.5 else np.arange(nz)[::-1]
    for z in range(nz):
        sop = generate_uid(entropy_srcs=[str(seed), "slice", str(z)])
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = ct
        meta.MediaStorageSOPInstanceUID = sop
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        meta.ImplementationClassUID = generate_uid(entropy_srcs=["sheet-stress"])
        ds = FileDataset(None, {}, file_meta=meta, preamble=b"\0" * 128)
        ds.is_little_endian, ds.is_implicit_VR = True, False
        ds.SOPClassUID, ds.SOPInstanceUID = ct, sop
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.Modality = "CT"
        ds.PatientName, ds.PatientID = "Stress^Roll", f"ROLL{seed}"
        ds.StudyDate = ds.SeriesDate = "20240101"
        ds.SeriesNumber, ds.InstanceNumber = 1, int(order[z]) + 1
        ds.ImagePositionPatient = [f"{origin[0]:.6f}", f"{origin[1]:.6f}", f"{origin[2] + z * spacing:.6f}"]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.PixelSpacing = [f"{spacing:.6g}", f"{spacing:.6g}"]
        ds.SliceThickness = f"{spacing:.6g}"
        ds.Rows, ds.Columns = ny, nx
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleIntercept, ds.RescaleSlope, ds.RescaleType = f"{intercept:g}", f"{slope:g}", "HU"
        ds.PixelData = np.ascontiguousarray(stored[z]).tobytes()
        ds.save_as(os.path.join(directory, f"IM{z:05d}.dcm"), write_like_original=False)


def build_scan(p):
    """Geometry, layout, text and the clean and noise volumes of one scan (in memory)."""
    roll = Roll(p)
    dims, cut = layout_volume(p, roll)
    fov = fov_along_sheet(roll, dims)
    ink, lines, facts = render_text(p, roll, fov)
    return roll, dims, cut, ink, lines, facts


def generate(p, out, verbose=True):
    """Write one scan and its truth into `out`; returns the truth dict."""
    started = time.time()
    os.makedirs(out, exist_ok=True)
    roll, dims, cut, ink, lines, facts = build_scan(p)
    clean, noise, air = make_volume(p, roll, dims, ink)
    delta = p["sheet_hu"] - p["air_hu"]
    sigma = delta / p["snr"]
    hu = p["air_hu"] + delta * clean + sigma * noise
    v = p["voxel_mm"]
    origin = [p["origin_x_mm"], p["origin_y_mm"], p["origin_z_mm"]]
    fmt = p["format"]
    if fmt.startswith("mha"):
        path = os.path.join(out, "volume.mha")
        if fmt == "mha-float":
            write_mha(path, hu.astype(np.float32), v, origin, "MET_FLOAT")
            stored = hu.astype(np.float32)
        else:
            stored = np.clip(np.round(hu), -32768, 32767)
            write_mha(path, stored, v, origin, "MET_SHORT")
        input_path, tool_args, file_origin = path, [], origin
    elif fmt.startswith("tiff"):
        path = os.path.join(out, "tiff")
        if fmt == "tiff-int16":
            stored = np.clip(np.round(hu), -32768, 32767)
            write_tiff_stack(path, stored, np.int16)
        else:
            stored = np.clip(np.round(hu + 32768.0), 0, 65535) - 32768.0  # unsigned, offset: nothing clipped
            write_tiff_stack(path, stored + 32768.0, np.uint16)
        input_path, tool_args, file_origin = path, ["--spacing", f"{v:g}", f"{v:g}", f"{v:g}"], [0.0, 0.0, 0.0]
    else:
        path = os.path.join(out, "dicom")
        write_dicom_series(path, hu, v, origin, p["seed"])
        stored = hu
        input_path, tool_args, file_origin = path, [], origin
    snr_measured = float(delta / np.std(stored[air])) if np.any(air) else float("nan")
    from PIL import Image
    Image.fromarray((ink.image * 255).astype(np.uint8)).save(os.path.join(out, "truth_ink.png"))
    np.savez_compressed(os.path.join(out, "truth_geometry.npz"), phi=roll.phi, r=roll.r, s=roll.s,
                        thickness=roll.t_along, alpha=roll.alpha, shape=roll.S)
    truth = {
        "parameters": p,
        "factors": derived_factors(p),
        "text": "\n".join(lines),
        "lines": lines,
        "ink": {"image": "truth_ink.png", "pixel_mm": TEXTURE_PIXEL * v, "pixel_voxels": TEXTURE_PIXEL,
                "x": "arc length s along the sheet (from the inner end in the middle slice), increasing to the right",
                "y": "position w along the roll axis, decreasing downwards (row 0 at w_top)",
                "s_origin_mm": facts["ink_s_origin"] * v, "w_top_mm": facts["ink_w_top"] * v,
                "face": p["ink_face"], **facts},
        "volume": {"input": os.path.relpath(input_path, out), "tool_arguments": tool_args,
                   "dimensions": [int(d) for d in dims], "voxel_mm": v, "origin_mm": file_origin,
                   "frame": "physical mm = origin + voxel index * voxel_mm, identity direction (x fastest)",
                   "roll_center_voxels": roll.center.tolist(), "rotation": roll.R.tolist(),
                   "fov_cut_voxels": cut},
        "measured": {"gap_min": roll.gap_measured_min, "gap_median": roll.gap_measured_median,
                     "snr": snr_measured, "sheet_length": roll.sheet_length(), "sheet_area": roll.area(),
                     "outer_radius": float(np.interp(roll.phi_end, roll.phi, roll.r) * roll.S.max())},
        "seconds": time.time() - started,
    }
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    if verbose:
        print(json.dumps({"parameters": p, "text": lines, "volume": truth["volume"]["dimensions"],
                          "measured": truth["measured"], "seconds": round(truth["seconds"], 2)}, indent=1))
    return truth


def load_roll(scan_dir):
    """The Roll of a generated scan, rebuilt from its stored parameters."""
    with open(os.path.join(scan_dir, "truth.json")) as f:
        truth = json.load(f)
    roll = Roll(truth["parameters"])
    roll.center = np.array(truth["volume"]["roll_center_voxels"])
    return roll, truth


def read_volume(scan_dir, truth):
    """The written volume back as HU (z, y, x), for pictures."""
    path = os.path.join(scan_dir, truth["volume"]["input"])
    fmt = truth["parameters"]["format"]
    if fmt.startswith("mha"):
        with open(path, "rb") as f:
            data = f.read()
        end = data.index(b"ElementDataFile = LOCAL\n") + len(b"ElementDataFile = LOCAL\n")
        dtype = "<f4" if b"MET_FLOAT" in data[:end] else "<i2"
        nx, ny, nz = truth["volume"]["dimensions"]
        return np.frombuffer(data[end:], dtype=dtype).reshape(nz, ny, nx).astype(np.float32)
    names = sorted(os.listdir(path))
    if fmt.startswith("tiff"):
        import tifffile
        vol = np.stack([tifffile.imread(os.path.join(path, n)) for n in names]).astype(np.float32)
        return vol - 32768.0 if fmt == "tiff-uint16" else vol
    import pydicom
    slices = [pydicom.dcmread(os.path.join(path, n)) for n in names]
    slices.sort(key=lambda d: float(d.ImagePositionPatient[2]))
    return np.stack([d.pixel_array * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in slices]).astype(np.float32)


# ----------------------------------------------------------------------------------------
# Scoring


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(verts, dtype=np.float64).reshape(-1, 3), np.array(faces, dtype=np.int64).reshape(-1, 3)


def closest_on_triangles(p, a, b, c):
    """Closest points to p on triangles (a, b, c), all arrays (N, 3) (Ericson's method)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = vb / denom
        w = vc / denom
        out = a + ab * v[:, None] + ac * w[:, None]
        # Regions outside the face: vertices and edges.
        m = (d1 <= 0) & (d2 <= 0)
        out[m] = a[m]
        m2 = (d3 >= 0) & (d4 <= d3)
        out[m2 & ~m] = b[m2 & ~m]
        done = m | m2
        m3 = (d6 >= 0) & (d5 <= d6) & ~done
        out[m3] = c[m3]
        done |= m3
        m4 = (vc <= 0) & (d1 >= 0) & (d3 <= 0) & ~done
        t = d1 / (d1 - d3)
        out[m4] = a[m4] + ab[m4] * t[m4, None]
        done |= m4
        m5 = (vb <= 0) & (d2 >= 0) & (d6 <= 0) & ~done
        t = d2 / (d2 - d6)
        out[m5] = a[m5] + ac[m5] * t[m5, None]
        done |= m5
        m6 = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0) & ~done
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        out[m6] = b[m6] + (c - b)[m6] * t[m6, None]
    bad = ~np.isfinite(out).all(axis=1)  # degenerate triangles: nearest vertex
    if np.any(bad):
        cand = np.stack([a[bad], b[bad], c[bad]], axis=1)
        k = np.argmin(np.linalg.norm(cand - p[bad, None, :], axis=2), axis=1)
        out[bad] = cand[np.arange(len(k)), k]
    return out


def densify(verts, faces, h):
    """Points on every triangle no further than about h apart (rows parallel to the longest
    edge, so slivers cost their length, not its square), with their triangle index."""
    tri = verts[faces]
    edges = np.stack([np.linalg.norm(tri[:, 1] - tri[:, 0], axis=1), np.linalg.norm(tri[:, 2] - tri[:, 1], axis=1),
                      np.linalg.norm(tri[:, 0] - tri[:, 2], axis=1)], axis=1)
    k = np.argmax(edges, axis=1)  # longest edge k runs from vertex k to vertex k + 1
    idx = np.arange(len(faces))
    a, b, c = tri[idx, k], tri[idx, (k + 1) % 3], tri[idx, (k + 2) % 3]
    base = np.maximum(edges[idx, k], 1e-12)
    height = np.linalg.norm(np.cross(b - a, c - a), axis=1) / base
    rows = np.ceil(height / h).astype(np.int64) + 1  # rows at t = 0, 1/(rows-1), ..., 1
    row_tri = np.repeat(idx, rows)
    first = np.cumsum(rows) - rows
    j = np.arange(len(row_tri)) - np.repeat(first, rows)
    t = j / np.maximum(np.repeat(rows - 1, rows), 1)
    t = np.where(np.repeat(rows, rows) == 1, 0.0, t)
    p = a[row_tri] + t[:, None] * (c - a)[row_tri]
    q = b[row_tri] + t[:, None] * (c - b)[row_tri]
    count = np.ceil((1 - t) * base[row_tri] / h).astype(np.int64) + 1
    pt_row = np.repeat(np.arange(len(row_tri)), count)
    first = np.cumsum(count) - count
    i = np.arange(len(pt_row)) - np.repeat(first, count)
    u = (i / np.maximum(np.repeat(count - 1, count), 1))[:, None]
    points = p[pt_row] * (1 - u) + q[pt_row] * u
    return points, row_tri[pt_row]


def mesh_to_surface_distance(verts, faces, queries, h, k=4):
    """Distance from each query point to the triangle mesh (exact point-to-triangle over the
    triangles of the k nearest points of the mesh densified at spacing h)."""
    dense, tri = densify(verts, faces, h)
    tree = cKDTree(dense)
    best = np.full(len(queries), np.inf)
    for i0 in range(0, len(queries), 500_000):
        q = queries[i0:i0 + 500_000]
        _, idx = tree.query(q, k=k)
        idx = idx.reshape(len(q), -1)
        for j in range(idx.shape[1]):
            t = faces[tri[idx[:, j]]]
            cp = closest_on_triangles(q, verts[t[:, 0]], verts[t[:, 1]], verts[t[:, 2]])
            best[i0:i0 + len(q)] = np.minimum(best[i0:i0 + len(q)], np.linalg.norm(cp - q, axis=1))
    return best


class TruthSurface:
    """Truth samples of one scan for scoring (volume voxel coordinates)."""

    def __init__(self, roll, dims, max_samples=3_000_000):
        self.roll = roll
        self.dims = np.asarray(dims, dtype=np.float64)
        area = roll.area()
        self.h = max(0.25, math.sqrt(area / max_samples))
        self.samples = roll.samples(self.h)
        self.tree = cKDTree(self.samples["points"])
        hc = 0.5
        cov = roll.samples(hc)
        pts = cov["points"]
        inside = np.all((pts >= -0.5) & (pts <= np.asarray(dims) - 0.5), axis=1)
        self.coverage_points = pts[inside].astype(np.float64)
        self.coverage_total = int(len(pts))
        if len(self.coverage_points) > 2_000_000:
            pick = stream(roll.p["seed"], "coverage").choice(len(self.coverage_points), 2_000_000, replace=False)
            self.coverage_points = self.coverage_points[pick]

    def end_arcs(self, w):
        """True arc lengths of the inner and outer end at axial positions w."""
        p0, p1 = self.roll.end_angles(np.asarray(w, dtype=np.float64))
        return np.interp(p0, self.roll.phi, self.roll.s), np.interp(p1, self.roll.phi, self.roll.s)

    def project(self, pts):
        """Distance of points to the true mid-surface, and their arc length s."""
        _, idx = self.tree.query(pts)
        sm = self.samples
        rel = pts - sm["points"][idx]
        dn = np.einsum("ij,ij->i", rel, sm["normals"][idx])
        ds = np.einsum("ij,ij->i", rel, sm["ts"][idx])
        dw = np.einsum("ij,ij->i", rel, sm["tw"][idx])
        half = 0.5 * self.h
        dist = np.sqrt(dn ** 2 + np.maximum(0, np.abs(ds) - half) ** 2 + np.maximum(0, np.abs(dw) - half) ** 2)
        self.last_w = sm["w"][idx] + dw
        return dist, sm["s"][idx] + ds, sm["turn"][idx], dn


def mesh_edges(faces):
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    e.sort(axis=1)
    return np.unique(e, axis=0)


def score_mesh(truth_surface, verts, faces):
    """Mesh error, layer jumps and coverage of a mesh (volume voxel coordinates)."""
    if len(verts) == 0 or len(faces) == 0:
        return {"mesh_error_mean": float("nan"), "mesh_error_p95": float("nan"), "mesh_error_max": float("nan"),
                "jumps": -1, "coverage": 0.0, "vertices": len(verts), "triangles": len(faces)}
    dist, s, turn, _ = truth_surface.project(verts)
    edges = mesh_edges(faces)
    length = np.linalg.norm(verts[edges[:, 0]] - verts[edges[:, 1]], axis=1)
    # Where a field of view cuts the roll, the mesh bridges the part of the sheet outside the
    # scan, which no scan shows: error and jumps are measured on the mesh inside the volume
    # (as coverage is on the true sheet inside it); the error of all vertices is kept too.
    inside = np.all((verts >= -0.5) & (verts <= truth_surface.dims - 0.5), axis=1)
    if not inside.any():
        inside[:] = True
    jumps = (np.abs(s[edges[:, 0]] - s[edges[:, 1]]) > 2.0 * length + 4.0) & inside[edges[:, 0]] & inside[edges[:, 1]]
    edge_len = float(np.median(length))
    # Jump edges with a vertex within 1.5 mesh spacings of a true end of the sheet (or beyond
    # it): the end of the trace overshooting onto the neighbouring turn.
    s0, s1 = truth_surface.end_arcs(truth_surface.last_w)
    near_end = (s - s0 < 1.5 * edge_len) | (s1 - s < 1.5 * edge_len)
    at_ends = jumps & (near_end[edges[:, 0]] | near_end[edges[:, 1]])
    h = max(0.5, math.sqrt(max(mesh_area(verts, faces), 1.0) / 1_000_000))
    near = mesh_to_surface_distance(verts, faces, truth_surface.coverage_points, h)
    coverage = float(np.mean(near <= 1.0)) if len(near) else 0.0
    return {"mesh_error_mean": float(dist[inside].mean()), "mesh_error_p95": float(np.percentile(dist[inside], 95)),
            "mesh_error_max": float(dist[inside].max()), "mesh_error_mean_all": float(dist.mean()),
            "vertices_outside": int((~inside).sum()), "jumps": int(jumps.sum()), "jumps_at_ends": int(at_ends.sum()),
            "coverage": coverage,
            "vertices": int(len(verts)), "triangles": int(len(faces)), "median_edge": edge_len,
            "turns_touched": int(len(np.unique(turn))), "_jump_edges": edges[jumps],
            "_projected": {"distance": dist, "s": s, "w": truth_surface.last_w}}


def mesh_area(verts, faces):
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def normalise_text(text):
    text = re.sub(r"[^A-Z0-9 ]", " ", text.upper().replace("\n", " "))
    return re.sub(r"\s+", " ", text).strip()


def levenshtein(a, b):
    if len(a) < len(b):
        a, b = b, a
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb)))
        previous = current
    return previous[-1]


OCR_VARIANTS = [("as is", None), ("mirrored", "FLIP_LEFT_RIGHT"), ("rotated 180", "ROTATE_180"),
                ("rotated 180, mirrored", "TRANSVERSE_180"), ("rotated 90", "ROTATE_90"),
                ("rotated 270", "ROTATE_270"), ("rotated 90, mirrored", "TRANSPOSE"),
                ("rotated 270, mirrored", "TRANSVERSE")]


def _tesseract(image, workdir):
    path = os.path.join(workdir, "ocr-variant.png")
    image.save(path)
    try:
        env = dict(os.environ, OMP_THREAD_LIMIT="1")  # its threads only spin on a busy machine
        result = subprocess.run(["tesseract", path, "stdout", "--psm", "6"], capture_output=True, text=True,
                                timeout=120, env=env)
        text = result.stdout
    except subprocess.TimeoutExpired:
        text = ""
    os.remove(path)
    return normalise_text(text)


def _variant(image, op):
    from PIL import Image
    if op is None:
        return image
    if op == "TRANSVERSE_180":
        return image.transpose(Image.Transpose.ROTATE_180).transpose(Image.Transpose.FLIP_LEFT_RIGHT)
    return image.transpose(getattr(Image.Transpose, op))


def ocr_score(texture_png, truth_text, workdir, box=None):
    """Character error rates of tesseract (--psm 6), best over the 8 rotations / mirrors:
    cer on the whole texture.png; cer_text on the box where the true text lies (when known).
    The 8 variants are tried on the box (small, fast) and the whole image is read in the
    variant found best there; without a box all 8 are tried on the whole image."""
    from PIL import Image
    truth = normalise_text(truth_text)
    image = Image.open(texture_png).convert("L")
    result = {"cer": float("nan"), "cer_text": float("nan"), "ocr_variant": "", "ocr_text": "", "ocr_text_region": ""}

    def best_of(img, variants):
        best = (float("inf"), "", "")
        for name, op in variants:
            got = _tesseract(_variant(img, op), workdir)
            cer = levenshtein(got, truth) / max(1, len(truth))
            if cer < best[0]:
                best = (cer, name, got)
            if cer <= 0.01:
                break
        return best

    if box is not None:
        cer, name, got = best_of(image.crop(box), OCR_VARIANTS)
        result.update({"cer_text": cer, "ocr_variant": name, "ocr_text_region": got,
                       "ocr_box": "%d,%d,%d,%d" % box})
        cer, name, got = best_of(image, [v for v in OCR_VARIANTS if v[0] == name])
    else:
        cer, name, got = best_of(image, OCR_VARIANTS)
        result["ocr_variant"] = name
    result.update({"cer": cer, "ocr_text": got[:500]})
    return result


# ----------------------------------------------------------------------------------------
# Pictures


def mesh_slice_segments(verts, faces, z):
    """Segments where the mesh crosses the plane z (volume voxel coordinates)."""
    tri = verts[faces]
    d = tri[:, :, 2] - z
    crossing = (np.min(d, axis=1) < 0) & (np.max(d, axis=1) > 0)
    segs = []
    for t, dd in zip(tri[crossing], d[crossing]):
        pts = []
        for i, j in ((0, 1), (1, 2), (2, 0)):
            if (dd[i] < 0) != (dd[j] < 0):
                f = dd[i] / (dd[i] - dd[j])
                pts.append(t[i] + f * (t[j] - t[i]))
        if len(pts) == 2:
            segs.append([pts[0][:2], pts[1][:2]])
    return np.array(segs).reshape(-1, 2, 2)


def overlay_png(path, volume, truth_surface, verts, faces, jump_edges, title, slices=None):
    """Slices of the scan with the true mid-surface (green dots), the mesh's cross-section (red)
    and the ends of layer-jump edges within a voxel of the slice (yellow)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    nz = volume.shape[0]
    if slices is None:
        slices = [int(nz * f) for f in (0.3, 0.5, 0.7)]
    fig, axes = plt.subplots(1, len(slices), figsize=(6.5 * len(slices), 6.8), squeeze=False)
    lo, hi = np.percentile(volume, [1, 99.7])
    pts = truth_surface.samples["points"]
    for ax, z in zip(axes[0], slices):
        ax.imshow(volume[z], cmap="gray", vmin=lo, vmax=hi, origin="upper", interpolation="nearest")
        near = np.abs(pts[:, 2] - z) < 0.5 * truth_surface.h + 0.01
        ax.plot(pts[near, 0], pts[near, 1], ".", color="lime", markersize=1.5, alpha=0.7, linestyle="none")
        if len(verts) and len(faces):
            segs = mesh_slice_segments(verts, faces, z + 1e-4)
            ax.add_collection(LineCollection(segs, colors="red", linewidths=1.0))
            if len(jump_edges):  # ends of the layer-jump edges near this slice
                ends = verts[np.unique(jump_edges.ravel())]
                close = np.abs(ends[:, 2] - z) < 1.0
                ax.plot(ends[close, 0], ends[close, 1], "o", color="yellow", markersize=2.5, linestyle="none")
        ax.set_title(f"slice z = {z}")
        ax.set_xlim(-0.5, volume.shape[2] - 0.5)
        ax.set_ylim(volume.shape[1] - 0.5, -0.5)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ----------------------------------------------------------------------------------------
# One scan through the tool


PARAMETER_KEYS = [k for k in draw_parameters(0) if k != "seed"] + ["turns_drawn"]
FACTOR_KEYS = ["tilt_deg", "artefact", "coarse_voxels"]
MEASURED_KEYS = ["tilt_reach", "gap_min", "gap_median", "snr_measured", "sheet_length", "outer_radius", "dimensions",
                 "fov_cut_voxels", "text", "text_fits_fov"]
FIGURE_KEYS = ["success", "legible", "legible_text", "mesh_error_mean", "mesh_error_p95", "mesh_error_max",
               "mesh_error_mean_all", "vertices_outside", "jumps",
               "jumps_at_ends",
               "coverage", "cer", "cer_text", "cer_ceiling", "legible_ceiling", "ceiling_filter", "ocr_variant", "ocr_text", "ocr_text_region", "ocr_box", "vertices",
               "triangles", "median_edge", "turns_touched"]
TOOL_KEYS = ["tool_exit", "tool_error", "crash", "score_error", "method", "threshold", "grid", "sheet_thickness_mm",
             "flipped_triangles", "edge_strain_p95",
             "texture_side", "warnings", "seconds_generate", "seconds_tool", "seconds_score"]
CSV_KEYS = ["seed"] + PARAMETER_KEYS + FACTOR_KEYS + MEASURED_KEYS + FIGURE_KEYS + TOOL_KEYS


def truth_grid_mesh(roll, spacing=1.0):
    """A grid mesh on the true mid-surface (rows along w, columns along s), volume voxels."""
    w = np.linspace(-0.5 * roll.width, 0.5 * roll.width, max(2, int(math.ceil(roll.width / spacing)) + 1))
    p0, p1 = roll.end_angles(w)
    s0, s1 = np.interp(p0, roll.phi, roll.s), np.interp(p1, roll.phi, roll.s)
    cols = max(2, int(math.ceil(np.max(s1 - s0) / spacing)) + 1)
    frac = np.linspace(0, 1, cols)
    s = s0[:, None] + frac[None, :] * (s1 - s0)[:, None]
    ww = np.broadcast_to(w[:, None], s.shape)
    pts = roll.to_volume(roll.point(roll.arc_to_phi(s), ww)).reshape(-1, 3)
    r, c = np.meshgrid(np.arange(len(w) - 1), np.arange(cols - 1), indexing="ij")
    i = (r * cols + c).ravel()
    faces = np.concatenate([np.stack([i, i + 1, i + cols + 1], 1), np.stack([i, i + cols + 1, i + cols], 1)])
    return pts, faces, s, ww


def truth_row(truth):
    """CSV fields of a scan's parameters and measured facts."""
    row = {"seed": truth["parameters"]["seed"]}
    row.update(truth["parameters"])
    row.update(truth["factors"])
    m = truth["measured"]
    row.update({"gap_min": m["gap_min"], "gap_median": m["gap_median"], "snr_measured": m["snr"],
                "sheet_length": m["sheet_length"], "outer_radius": m["outer_radius"],
                "dimensions": "x".join(str(d) for d in truth["volume"]["dimensions"]),
                "fov_cut_voxels": truth["volume"]["fov_cut_voxels"], "text": " / ".join(truth["lines"]),
                "text_fits_fov": truth["ink"]["text_fits_fov"]})
    # How far the tilt carries the roll's cross-section along the slice normal, against its
    # width: above about 0.5 most slices cut the roll partly.
    row["tilt_reach"] = round(2.0 * m["outer_radius"] * math.sin(math.radians(truth["factors"]["tilt_deg"]))
                              / truth["parameters"]["width"], 4)
    return row


def run_tool(tool, scan_dir, truth, timeout, stage="unwrap"):
    """`virtual-unwrap unwrap INPUT -o OUT -q` (stage "mesh": `virtual-unwrap segment INPUT -o OUT`,
    the same mesh without flattening and texturing) with default options; the outcome is also
    stored in scan_dir/tool.json so that the scan can be scored again later."""
    out = os.path.join(scan_dir, "unwrap")
    if stage == "mesh":
        cmd = [tool, "segment", os.path.join(scan_dir, truth["volume"]["input"]), "-o", out]
    else:
        cmd = [tool, "unwrap", os.path.join(scan_dir, truth["volume"]["input"]), "-o", out, "-q"]
    cmd += truth["volume"]["tool_arguments"]
    started = time.time()
    try:
        result = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        code, stderr = result.returncode, result.stderr
    except subprocess.TimeoutExpired as e:
        code, stderr = "timeout", (e.stderr.decode() if isinstance(e.stderr, bytes) else (e.stderr or ""))
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    errors = [line for line in lines if "error" in line.lower()] or lines
    outcome = {"command": cmd, "tool_exit": code, "seconds_tool": round(time.time() - started, 2),
               "tool_error": (errors[0] if errors else "")[:300] if code != 0 else "", "stderr": stderr[-4000:]}
    with open(os.path.join(scan_dir, "tool.json"), "w") as f:
        json.dump(outcome, f, indent=1)
    return outcome


def text_region(truth, scan_dir, projected, texture_png, flat_obj):
    """The box of texture.png where the true text lies, found through the tool's own mesh: the
    vertices whose true (s, w) fall in the text block, mapped by their texture coordinates."""
    from PIL import Image
    if not os.path.exists(flat_obj):
        return None
    uv = []
    with open(flat_obj) as f:
        for line in f:
            if line.startswith("vt "):
                uv.append([float(x) for x in line.split()[1:3]])
    uv = np.array(uv).reshape(-1, 2)
    if len(uv) != len(projected["s"]):
        return None
    ink = truth["ink"]
    with Image.open(os.path.join(scan_dir, "truth_ink.png")) as im:
        block_w, block_h = im.size[0] * TEXTURE_PIXEL, im.size[1] * TEXTURE_PIXEL
    margin = ink["letter_height_used"]
    s0, s1 = ink["ink_s_origin"] - margin, ink["ink_s_origin"] + block_w + margin
    w1, w0 = ink["ink_w_top"] + margin, ink["ink_w_top"] - block_h - margin
    dist, s, w = projected["distance"], projected["s"], projected["w"]
    sel = (dist < 2.0) & (s >= s0) & (s <= s1) & (w >= w0) & (w <= w1)
    if sel.sum() < 4:
        return None
    with Image.open(texture_png) as im:
        width, height = im.size
    x, y = uv[sel, 0] * width, (1.0 - uv[sel, 1]) * height
    pad = 2.0 * margin / TEXTURE_PIXEL * 0.5
    box = (int(max(0, x.min() - pad)), int(max(0, y.min() - pad)), int(min(width, x.max() + pad + 1)),
           int(min(height, y.max() + pad + 1)))
    return box if box[2] - box[0] > 8 and box[3] - box[1] > 8 else None


CEILING_SIGMAS = (1.0, 2.0, 3.0, 4.0)  # Gaussian smoothing of the ideal texture, pixels (half a voxel)
CEILING_BACKGROUND = (0.0, 20.0)      # and its slow background taken out (Gaussian, pixels; 0: none)


def ink_ceiling(scan_dir):
    """How legible the scan itself is: the volume sampled on the TRUE mid-surface, over the
    ink layer's true depth (three samples across it, along the true normal), at the ink
    image's pixels (half a voxel); then smoothed (CEILING_SIGMAS) with or without its slow
    background taken out (CEILING_BACKGROUND), shown with the median as white and the 99.5th
    percentile as black (dense ink dark on a white page), read by tesseract. cer_ceiling is
    the best of these; a texture found by any method that samples the scan cannot be expected
    to read better than this, so a scan with cer_ceiling > 5 % is illegible in the scan, not
    by the tool's fault. ceiling.png keeps the best image."""
    from PIL import Image
    roll, truth = load_roll(scan_dir)
    p, ink = truth["parameters"], truth["ink"]
    volume = read_volume(scan_dir, truth)
    with Image.open(os.path.join(scan_dir, "truth_ink.png")) as im:
        width, height = im.size
    pad = 16
    s = ink["ink_s_origin"] + np.arange(-pad, width + pad) * TEXTURE_PIXEL
    w = ink["ink_w_top"] - np.arange(-pad, height + pad) * TEXTURE_PIXEL
    ss_, ww = np.meshgrid(s, w)
    z = ww.ravel()
    pt, _, normal = roll.frame(roll.arc_to_phi(ss_.ravel()), z)
    t = p["thickness"] * roll.thickness_factor(z)[:, None]
    sign = 1.0 if p["ink_face"] == "outer" else -1.0
    total = np.zeros(len(z))
    for f in (-1.0, 0.0, 1.0):  # the ink layer: the outer third of the thickness, t / 3 deep
        q = roll.to_volume(pt + (sign * t / 3.0 + f * t / 6.0) * normal)
        total += ndimage.map_coordinates(volume, [q[:, 2], q[:, 1], q[:, 0]], order=1, mode="nearest")
    ideal = (total / 3.0).reshape(ss_.shape)
    text = normalise_text(truth["text"])
    best = (float("inf"), "", None)
    for sigma in CEILING_SIGMAS:
        smooth = ndimage.gaussian_filter(ideal, sigma)
        for background in CEILING_BACKGROUND:
            img = smooth - ndimage.gaussian_filter(smooth, background) if background else smooth
            white, black = np.median(img), np.percentile(img, 99.5)
            grey = 1.0 - np.clip((img - white) / max(black - white, 1e-9), 0.0, 1.0)
            image = Image.fromarray((255 * grey).astype(np.uint8))
            cer = levenshtein(_tesseract(image, scan_dir), text) / max(1, len(text))
            if cer < best[0]:
                best = (cer, f"sigma {sigma:g} px" + (f", background {background:g} px" if background else ""), image)
            if cer <= 0.01:
                break
        if best[0] <= 0.01:
            break
    best[2].save(os.path.join(scan_dir, "ceiling.png"))
    return {"cer_ceiling": best[0], "ceiling_filter": best[1], "legible_ceiling": bool(best[0] <= LEGIBLE_CER)}


def remove_volume(scan_dir):
    """Delete a scan's volume (whichever format it was written in); truth and outputs stay."""
    for name in ("volume.mha", "tiff", "dicom"):
        target = os.path.join(scan_dir, name)
        if os.path.isdir(target):
            shutil.rmtree(target)
        elif os.path.exists(target):
            os.remove(target)


def score_scan(scan_dir, keep="failures", overlay=True, ceiling=False):
    """Score the tool's outputs in scan_dir against the truth; returns the CSV row."""
    with open(os.path.join(scan_dir, "truth.json")) as f:
        truth = json.load(f)
    row = truth_row(truth)
    row["seconds_generate"] = round(truth["seconds"], 2)
    with open(os.path.join(scan_dir, "tool.json")) as f:
        outcome = json.load(f)
    row.update({k: outcome[k] for k in ("tool_exit", "tool_error", "seconds_tool")})
    code = outcome["tool_exit"]
    out = os.path.join(scan_dir, "unwrap")
    if not os.path.exists(os.path.join(out, "surface.obj")) and os.path.isdir(os.path.join(out, "sheet-01")):
        out = os.path.join(out, "sheet-01")  # several sheets found: the largest is the roll
    surface = os.path.join(out, "surface.obj")
    row["crash"] = bool(code not in (0, 1) or (code == 0 and not os.path.exists(surface)))
    if code == 0 and os.path.exists(os.path.join(out, "segment.json")):
        with open(os.path.join(out, "segment.json")) as f:
            report = json.load(f)
        row["warnings"] = " | ".join(report.get("warnings", []))[:1000]
        row["method"] = report.get("method", "")
        row["threshold"] = report.get("threshold", {}).get("value", "") if isinstance(report.get("threshold"), dict) \
            else report.get("threshold", "")
    if code == 0 and os.path.exists(os.path.join(out, "report.json")):
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        row["warnings"] = " | ".join(report.get("warnings", []))[:1000]
        par = report.get("parameters", {})
        row["method"] = par.get("mesh", {}).get("method", "")
        row["threshold"] = par.get("threshold", {}).get("value", "")
        row["texture_side"] = par.get("texture", {}).get("side", "")
        row["grid"] = "x".join(str(g) for g in report.get("mesh", {}).get("grid", []))
        row["sheet_thickness_mm"] = report.get("mesh", {}).get("sheet_thickness_mm", "")
        distortion = report.get("distortion", {})
        row["flipped_triangles"] = distortion.get("flipped_triangles", "")
        row["edge_strain_p95"] = distortion.get("edge_strain", {}).get("p95", "")
    p = truth["parameters"]
    started = time.time()
    figures = {}
    try:
        roll = Roll(p)
        roll.center = np.array(truth["volume"]["roll_center_voxels"])
        surface_truth = TruthSurface(roll, truth["volume"]["dimensions"])
        verts, faces = np.zeros((0, 3)), np.zeros((0, 3), dtype=int)
        if code == 0 and os.path.exists(surface):
            verts_mm, faces = read_obj(surface)
            verts = (verts_mm - np.array(truth["volume"]["origin_mm"])) / truth["volume"]["voxel_mm"]
            figures = score_mesh(surface_truth, verts, faces)
            texture = os.path.join(out, "texture.png")
            if os.path.exists(texture):
                box = text_region(truth, scan_dir, figures["_projected"], texture, os.path.join(out, "flat.obj"))
                figures.update(ocr_score(texture, truth["text"], scan_dir, box))
        else:
            figures = {"mesh_error_mean": float("nan"), "jumps": -1, "coverage": 0.0, "cer": float("nan"),
                       "cer_text": float("nan")}
        figures["success"] = bool(figures.get("mesh_error_mean", float("nan")) <= SUCCESS_ERROR
                                  and figures.get("jumps", -1) == 0
                                  and figures.get("coverage", 0.0) >= SUCCESS_COVERAGE)
        figures["legible"] = bool(figures.get("cer", float("inf")) <= LEGIBLE_CER)
        figures["legible_text"] = bool(figures.get("cer_text", float("inf")) <= LEGIBLE_CER)
        if ceiling and os.path.exists(os.path.join(scan_dir, truth["volume"]["input"])):
            figures.update(ink_ceiling(scan_dir))
        if overlay and not figures["success"] and os.path.exists(os.path.join(scan_dir, truth["volume"]["input"])):
            volume = read_volume(scan_dir, truth)
            title = (f"seed {p['seed']}: turns {p['turns']:.1f}, gap {p['gap']:.2f}, t {p['thickness']:.2f}, "
                     f"SNR {p['snr']:.2f}, {truth['factors']['artefact']}, tilt {truth['factors']['tilt_deg']:.1f}, "
                     f"squash {p['squash']:.2f}, touches {p['touches']}; exit {code}"
                     + (f" ({outcome['tool_error'][:80]})" if code != 0 else "")
                     + f"; error {figures.get('mesh_error_mean', float('nan')):.2f}, "
                     f"jumps {figures.get('jumps')}, coverage {figures.get('coverage', 0):.3f}")
            overlay_png(os.path.join(scan_dir, "overlay.png"), volume, surface_truth, verts, faces,
                        figures.get("_jump_edges", np.zeros((0, 2), dtype=int)), title)
    except Exception as e:  # a scoring failure is reported, not hidden
        import traceback
        row["score_error"] = f"{type(e).__name__}: {e}"
        traceback.print_exc()
    row["seconds_score"] = round(time.time() - started, 2)
    for k, v in figures.items():
        if not k.startswith("_"):
            row[k] = round(v, 5) if isinstance(v, float) else v
    if keep == "none" or (keep == "failures" and row.get("success") and not row.get("crash")):
        remove_volume(scan_dir)
        layers = os.path.join(out, "layers.tif")
        if os.path.exists(layers):
            os.remove(layers)
    return row


def process_scan(seed, out_root, region="accept", small=False, tool="build/bin/virtual-unwrap", keep="failures",
                 overrides=None, timeout=1800, extra=None, stage="unwrap"):
    """Generate, run and score one scan; returns its CSV row."""
    scan_dir = os.path.join(out_root, f"scan-{seed}")
    if os.path.isdir(scan_dir):
        shutil.rmtree(scan_dir)
    p = draw_parameters(seed, region, small, overrides)
    truth = generate(p, scan_dir, verbose=False)
    run_tool(tool, scan_dir, truth, timeout, stage)
    row = score_scan(scan_dir, keep, ceiling=stage == "unwrap")
    row.update(extra or {})
    return row


def ceiling_scan(seed, out_root, region="accept", small=False, keep="none", overrides=None):
    """Generate one scan and read its ink from the true surface (ink_ceiling): no tool run."""
    scan_dir = os.path.join(out_root, f"scan-{seed}")
    if os.path.isdir(scan_dir):
        shutil.rmtree(scan_dir)
    truth = generate(draw_parameters(seed, region, small, overrides), scan_dir, verbose=False)
    row = truth_row(truth)
    try:
        row.update(ink_ceiling(scan_dir))
    except Exception as e:  # a scoring failure is reported, not hidden
        row["score_error"] = f"{type(e).__name__}: {e}"
    if keep != "all":
        remove_volume(scan_dir)
    return row


def _ceiling_scan_star(kwargs):
    return ceiling_scan(**kwargs)


def _rescore_star(kwargs):
    """Score one kept scan again, after running the tool on it again if asked."""
    if kwargs["rerun"]:
        with open(os.path.join(kwargs["scan_dir"], "truth.json")) as f:
            truth = json.load(f)
        out = os.path.join(kwargs["scan_dir"], "unwrap")
        if os.path.isdir(out):
            shutil.rmtree(out)
        run_tool(kwargs["tool"], kwargs["scan_dir"], truth, 1800, kwargs["rerun"])
    return score_scan(kwargs["scan_dir"], keep="all", ceiling=kwargs["rerun"] != "mesh")


def _process_scan_star(kwargs):
    return process_scan(**kwargs)


def run_scans(tasks, csv_path, jobs=1, verbose=True):
    """Run scan tasks (process_scan keyword dicts), writing CSV rows as they finish."""
    rows = []
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=CSV_KEYS + [k for k in tasks[0].get("extra", {}) if k not in CSV_KEYS],
                                extrasaction="ignore", restval="")
        writer.writeheader()

        def done(row):
            rows.append(row)
            writer.writerow(row)
            f.flush()
            if verbose:
                print(f"seed {row['seed']}: exit {row.get('tool_exit')} "
                      f"success {row.get('success')} error {row.get('mesh_error_mean', '')} "
                      f"jumps {row.get('jumps', '')} coverage {row.get('coverage', '')} cer {row.get('cer', '')} "
                      f"cer_text {row.get('cer_text', '')} "
                      f"[{row.get('seconds_generate')} + {row.get('seconds_tool')} + {row.get('seconds_score')} s]"
                      + (f" {row.get('tool_error')}" if row.get("tool_error") else "")
                      + (f" SCORE ERROR {row['score_error']}" if row.get("score_error") else ""), flush=True)

        if jobs <= 1:
            for task in tasks:
                done(process_scan(**task))
        else:
            with concurrent.futures.ProcessPoolExecutor(max_workers=jobs) as pool:
                for row in pool.map(_process_scan_star, tasks):
                    done(row)
    return rows


# ----------------------------------------------------------------------------------------
# Summary


def _num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def _bins(edges, fmt="{:g}"):
    return [(f"{fmt.format(a)}-{fmt.format(b)}", (lambda x, a=a, b=b: a <= _num(x) < b)) for a, b in edges]


FACTORS = [
    ("turns", "turns", _bins([(1.5, 4), (4, 8), (8, 12), (12, 20), (20, 31)])),
    ("gap (voxels)", "gap", _bins([(1, 1.5), (1.5, 2), (2, 3), (3, 4), (4, 6), (6, 8.01)])),
    ("SNR", "snr", _bins([(1.5, 2), (2, 3), (3, 4), (4, 6), (6, 8.01)])),
    ("thickness (voxels)", "thickness", _bins([(1, 1.5), (1.5, 2), (2, 3), (3, 4.01)])),
    ("radius variation along axis (voxels)", "radius_variation", _bins([(0, 1), (1, 2), (2, 4.01)])),
    ("winding unevenness", "unevenness", _bins([(0, 0.33), (0.33, 0.67), (0.67, 1.01)])),
    ("touching turns", "touches", [("none", lambda x: _num(x) == 0), ("1-4 touches", lambda x: _num(x) > 0)]),
    ("irregularity (Fourier amplitude)", "irregularity", _bins([(0, 0.033), (0.033, 0.067), (0.067, 0.101)])),
    ("squash (axes ratio)", "squash", _bins([(0.6, 0.73), (0.73, 0.87), (0.87, 1.01)])),
    ("tilt (degrees)", "tilt_deg", _bins([(0, 5), (5, 10), (10, 22)])),
    ("tilt reach: diameter x sin(tilt) / width", "tilt_reach", _bins([(0, 0.25), (0.25, 0.45), (0.45, 10)])),
    ("winding direction (in the slices)", "clockwise", [("counter-clockwise", lambda x: str(x) == "False"),
                                                        ("clockwise", lambda x: str(x) == "True")]),
    ("FOV cut", "fov_cut_voxels", [("none", lambda x: _num(x) == 0), ("cut", lambda x: _num(x) > 0)]),
    ("artefact type", "artefact", None),
    ("blur sigma (voxels)", "blur", _bins([(0.4, 0.67), (0.67, 0.94), (0.94, 1.21)])),
    ("ink contrast (of the sheet's)", "ink_contrast", _bins([(0.3, 0.6), (0.6, 0.9), (0.9, 1.21)])),
    ("letter height (voxels)", "letter_height", _bins([(6, 11), (11, 15.5), (15.5, 20.01)])),
    ("voxel coarseness", "coarse_voxels", [("coarse (t <= 1.5)", lambda x: str(x) == "True"),
                                            ("fine (t > 1.5)", lambda x: str(x) == "False")]),
    ("file format", "format", None),
]


def _median(values):
    v = [x for x in values if math.isfinite(x)]
    return float(np.median(v)) if v else float("nan")


def summary_table(rows):
    """Markdown table: per factor bin, the success rate and the medians of the figures."""
    def stats(sel):
        n = len(sel)
        ok = sum(str(r.get("success")) == "True" for r in sel)
        leg = sum(str(r.get("legible")) == "True" for r in sel)
        leg_text = sum(str(r.get("legible_text")) == "True" for r in sel)
        refused = sum(str(r.get("tool_exit")) != "0" for r in sel)
        err = _median([_num(r.get("mesh_error_mean")) for r in sel])
        jumps = _median([_num(r.get("jumps")) for r in sel if _num(r.get("jumps")) >= 0])
        cov = _median([_num(r.get("coverage")) for r in sel])
        cer = _median([_num(r.get("cer")) for r in sel])
        cer_text = _median([_num(r.get("cer_text")) for r in sel])
        f = lambda x, d=2: "-" if not math.isfinite(x) else f"{x:.{d}f}"
        in_scan = [r for r in sel if str(r.get("legible_ceiling")) in ("True", "False")]
        ceiling = "-" if not in_scan else \
            f"{100.0 * sum(str(r.get('legible_ceiling')) == 'True' for r in in_scan) / len(in_scan):.0f} %"
        return (f"{n} | {100.0 * ok / n:.0f} % | {f(err)} | {f(jumps, 0)} | {f(100 * cov, 1)} % | {f(cer)} | "
                f"{f(cer_text)} | {100.0 * leg / n:.0f} % / {100.0 * leg_text / n:.0f} % / {ceiling} | {refused}")
    out = ["| factor | bin | scans | success | median mesh error (voxels) | median jumps | median coverage | "
           "median CER (texture) | median CER (text region) | legible (texture / text region / in the scan) | "
           "tool exit != 0 |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    out += _factor_rows(rows, stats)
    out.append("")
    out.append("success: mean mesh error <= 0.5 voxel, 0 layer jumps, coverage >= 97 %; legible: CER <= 5 %; "
               "in the scan: the ink read from the true surface (ink_ceiling). "
               "Medians over the scans the tool meshed (jumps, error, CER); coverage counts a refused scan as 0.")
    return "\n".join(out)


def _factor_rows(rows, stats):
    """The table's rows: all scans, then each factor's bins, each with stats(selected rows)."""
    out = [f"| all | | {stats(rows)} |"]
    for name, key, bins in FACTORS:
        if bins is None:
            values = sorted({str(r.get(key)) for r in rows})
            bins = [(v, (lambda x, v=v: str(x) == v)) for v in values]
        for label, pred in bins:
            sel = [r for r in rows if pred(r.get(key))]
            if sel:
                out.append(f"| {name} | {label} | {stats(sel)} |")
    return out


def ceiling_table(rows):
    """Markdown table of a ceiling run: per factor bin, how many scans read from the true
    surface (the scan's own legibility, no tool involved)."""
    def stats(sel):
        cers = [_num(r.get("cer_ceiling")) for r in sel]
        legible = sum(str(r.get("legible_ceiling")) == "True" for r in sel)
        med = _median(cers)
        return f"{len(sel)} | {100.0 * legible / len(sel):.0f} % | " + ("-" if not math.isfinite(med) else f"{med:.2f}")
    out = ["| factor | bin | scans | legible in the scan (CER <= 5 %) | median CER from the true surface |",
           "|---|---|---|---|---|"]
    out += _factor_rows(rows, stats)
    return "\n".join(out)


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# ----------------------------------------------------------------------------------------
# Stability map


def stability_map(rows, snrs, gaps, png, family="the whole family"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    frac = np.full((len(snrs), len(gaps)), np.nan)
    text = [["" for _ in gaps] for _ in snrs]
    for i, snr in enumerate(snrs):
        for j, gap in enumerate(gaps):
            sel = [r for r in rows if abs(_num(r.get("map_snr")) - snr) < 1e-6 and abs(_num(r.get("map_gap")) - gap) < 1e-6]
            if sel:
                ok = sum(str(r.get("success")) == "True" for r in sel)
                frac[i, j] = ok / len(sel)
                text[i][j] = f"{ok}/{len(sel)}"
    fig, ax = plt.subplots(figsize=(1.3 * len(gaps) + 2.5, 0.8 * len(snrs) + 1.8))
    im = ax.imshow(frac, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    for i in range(len(snrs)):
        for j in range(len(gaps)):
            if text[i][j]:
                ax.text(j, i, f"{frac[i, j]:.2f}\n{text[i][j]}", ha="center", va="center", fontsize=9)
    ax.set_xticks(range(len(gaps)), [f"{g:g}" for g in gaps])
    ax.set_yticks(range(len(snrs)), [f"{s:g}" for s in snrs])
    ax.set_xlabel("gap between turns (voxels)")
    ax.set_ylabel("SNR (sheet - air) / noise sigma")
    ax.set_title("virtual-unwrap segmentation: success rate on " + family +
                 "\n(mesh error <= 0.5 voxel, 0 jumps, coverage >= 97 %)", fontsize=10)
    fig.colorbar(im, ax=ax, label="success fraction")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------------------
# Self-check of the generator and the scorer


def selfcheck(tool=None, verbose=True):
    """The scorer against the truth itself, the rasteriser against the truth, the writers
    against their read-back, the OCR against the rendered ink. Raises on failure."""
    failures = []

    def check(name, ok, detail):
        if verbose:
            print(f"{'ok  ' if ok else 'FAIL'} {name}: {detail}", flush=True)
        if not ok:
            failures.append(name)

    p = draw_parameters(11, "accept", small=True, overrides={"touches": 2, "tilt_x_deg": 4.0, "tilt_y_deg": -3.0,
                                                              "radius_variation": 1.5, "squash": 0.75})
    roll, dims, cut, ink, lines, facts = build_scan(p)
    truth = TruthSurface(roll, dims)
    sm = truth.samples
    t = p["thickness"]
    # Interior samples (away from the sheet's ends and edges and from the touches).
    w = sm["w"].astype(np.float64)
    p0, p1 = roll.end_angles(w)
    s0, s1 = np.interp(p0, roll.phi, roll.s), np.interp(p1, roll.phi, roll.s)
    phi = roll.arc_to_phi(sm["s"].astype(np.float64))
    bumped = np.zeros(len(phi))
    for shift in (0.0, -2 * np.pi):  # this turn or the one inside it pushed out by a touch
        bumped += np.abs(roll.radius(phi + shift, w)[0] - np.interp(phi + shift, roll.phi, roll.r)
                         - roll.radius_shift(w))
    interior = ((np.abs(w) < 0.5 * roll.width - 1.5) & (sm["s"] > s0 + 1.5) & (sm["s"] < s1 - 1.5)
                & (np.abs(bumped) < 1e-6))
    pick = np.nonzero(interior)[0][::7]
    occ, _ = roll.rasterise(sm["points"][pick].astype(np.float64))
    check("rasteriser: sheet on the true mid-surface", np.mean(occ > 0.99) > 0.999,
          f"{100 * np.mean(occ > 0.99):.2f} % of interior samples fully sheet")
    for side in (1, -1):
        off = sm["points"][pick] + side * (0.5 * t * 1.25 + 1.0) * sm["normals"][pick]
        occ, _ = roll.rasterise(off.astype(np.float64))
        check(f"rasteriser: air {'outside' if side > 0 else 'inside'} the sheet", np.mean(occ < 0.01) > 0.999,
              f"{100 * np.mean(occ < 0.01):.2f} % of points {0.5 * t * 1.25 + 1.0:.2f} voxels beside the sheet in air")
    verts, faces, s_grid, w_grid = truth_grid_mesh(roll, 1.0)
    f0 = score_mesh(truth, verts, faces)
    check("scorer: true mesh", f0["mesh_error_mean"] < 0.05 and f0["jumps"] == 0 and f0["coverage"] > 0.995,
          f"error {f0['mesh_error_mean']:.3f} (max {f0['mesh_error_max']:.3f}), jumps {f0['jumps']}, "
          f"coverage {f0['coverage']:.4f}")
    normals_at = truth.samples["normals"][truth.tree.query(verts)[1]]
    f1 = score_mesh(truth, verts + normals_at, faces)
    ok1 = 0.9 < f1["mesh_error_mean"] < 1.1 and not f1["mesh_error_mean"] <= SUCCESS_ERROR
    check("scorer: mesh shifted 1 voxel along the normal", ok1,
          f"error {f1['mesh_error_mean']:.3f}, coverage {f1['coverage']:.3f} -> fails")
    rows, cols = s_grid.shape
    moved = verts.reshape(rows, cols, 3).copy()
    band = slice(int(0.4 * rows), int(0.6 * rows))
    phi = roll.arc_to_phi(s_grid[band]) + 2 * np.pi
    moved[band] = roll.to_volume(roll.point(phi, w_grid[band]))
    keep_cols = np.nonzero(np.all(phi <= roll.end_angles(w_grid[band])[1], axis=0))[0]
    moved = moved[:, keep_cols].reshape(-1, 3)
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(len(keep_cols) - 1), indexing="ij")
    i = (r * len(keep_cols) + c).ravel()
    k = len(keep_cols)
    faces2 = np.concatenate([np.stack([i, i + 1, i + k + 1], 1), np.stack([i, i + k + 1, i + k], 1)])
    f2 = score_mesh(truth, moved, faces2)
    check("scorer: rows moved to the next turn", f2["jumps"] > 0 and f2["mesh_error_mean"] < 0.05,
          f"jumps {f2['jumps']}, error {f2['mesh_error_mean']:.3f} (on the sheet, wrong turn) -> fails")
    # Writers: read back every format.
    with tempfile.TemporaryDirectory() as work:
        for fmt in ("mha-float", "mha-int16", "tiff-int16", "tiff-uint16", "dicom"):
            q = dict(p, format=fmt, width=12.0, turns=1.8)
            d = os.path.join(work, fmt)
            tr = generate(q, d, verbose=False)
            vol = read_volume(d, tr)
            ok = list(vol.shape[::-1]) == tr["volume"]["dimensions"] and np.ptp(vol) > 100
            detail = f"read back {vol.shape[::-1]}, range {vol.min():.0f}..{vol.max():.0f} HU"
            if tool and os.path.exists(tool):
                res = subprocess.run([tool, "info", os.path.join(d, tr["volume"]["input"])]
                                     + tr["volume"]["tool_arguments"], capture_output=True, text=True)
                try:
                    info = json.loads(res.stdout)
                    size, origin, spacing = info["size"], info["origin"], info["spacing"]
                    ok &= (size == tr["volume"]["dimensions"]
                           and np.allclose(origin, tr["volume"]["origin_mm"], atol=1e-3)
                           and np.allclose(spacing, tr["volume"]["voxel_mm"], rtol=1e-4))
                    detail += f"; tool info size {size}, origin {origin}, spacing {spacing}"
                except Exception as e:
                    ok = False
                    detail += f"; tool info unreadable ({e}): {res.stderr.strip()[:200]}"
            check(f"writer {fmt}", ok, detail)
        # OCR on the rendered ink itself.
        from PIL import Image
        img = os.path.join(work, "ink.png")
        Image.fromarray((255 - ink.image * 255).astype(np.uint8)).save(img)
        best = ocr_score(img, "\n".join(lines), work)
        check("OCR on the true ink image", best["cer"] <= 0.05,
              f"CER {best['cer']:.3f} ({best['ocr_variant']}: '{best['ocr_text']}' vs '{normalise_text(' '.join(lines))}')")
    if failures:
        raise SystemExit(f"selfcheck failed: {', '.join(failures)}")
    return True


def preview_png(scan_dir, png):
    """A look at one generated scan: the middle slice, a zoom into it, a cut along the axis and
    the true ink image."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image
    with open(os.path.join(scan_dir, "truth.json")) as f:
        truth = json.load(f)
    vol = read_volume(scan_dir, truth)
    nz, ny, nx = vol.shape
    lo, hi = np.percentile(vol, [1, 99.7])
    p = truth["parameters"]
    fig, axes = plt.subplots(2, 2, figsize=(13, 12))
    axes[0, 0].imshow(vol[nz // 2], cmap="gray", vmin=lo, vmax=hi)
    axes[0, 0].set_title(f"slice z = {nz // 2} of {nz} ({nx} x {ny})")
    c = [int(v) for v in truth["volume"]["roll_center_voxels"]]
    cy, cx = min(max(c[1], 0), ny - 1), min(max(c[0], 0), nx - 1)
    half = max(20, min(nx, ny) // 6)
    zoom = vol[nz // 2, max(0, cy - half):cy + half, max(0, cx):cx + 2 * half]
    axes[0, 1].imshow(zoom, cmap="gray", vmin=lo, vmax=hi, interpolation="nearest")
    axes[0, 1].set_title("zoom: from the axis outwards")
    axes[1, 0].imshow(vol[:, cy, :], cmap="gray", vmin=lo, vmax=hi, aspect="auto")
    axes[1, 0].set_title(f"cut along the axis at y = {cy}")
    axes[1, 1].imshow(np.asarray(Image.open(os.path.join(scan_dir, "truth_ink.png"))), cmap="gray")
    axes[1, 1].set_title("true ink: " + " / ".join(truth["lines"]), fontsize=8)
    fig.suptitle(f"seed {p['seed']}: turns {p['turns']:.1f}, gap {p['gap']:.2f}, thickness {p['thickness']:.2f}, "
                 f"SNR {p['snr']:.2f} ({truth['factors']['artefact']}), blur {p['blur']:.2f}, squash {p['squash']:.2f}, "
                 f"irregularity {p['irregularity']:.3f}, touches {p['touches']}, tilt {truth['factors']['tilt_deg']:.1f} deg, "
                 f"ink {p['ink_face']} x{p['ink_contrast']:.2f}, {p['format']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)


# ----------------------------------------------------------------------------------------
# Command line


def parse_overrides(items):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SystemExit(f"--param wants key=value, not '{item}'")
        k, v = item.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    g = sub.add_parser("generate", help="write one scan and its truth")
    g.add_argument("--seed", type=int, required=True)
    g.add_argument("--out", required=True)
    g.add_argument("--region", choices=["accept", "wide"], default="wide")
    g.add_argument("--small", action="store_true", help="small scans (about 100 x 100 x 40 voxels)")
    g.add_argument("--param", action="append", metavar="KEY=VALUE", help="override a drawn parameter")
    r = sub.add_parser("run", help="generate scans, run the tool, score, summarise")
    r.add_argument("--scans", type=int, default=100)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--out", required=True)
    r.add_argument("--jobs", type=int, default=1, help="scans in parallel (the tool itself is multithreaded)")
    r.add_argument("--region", choices=["accept", "wide"], default="accept")
    r.add_argument("--csv", default=None, help="default OUT/results.csv")
    r.add_argument("--tool", default="build/bin/virtual-unwrap")
    r.add_argument("--small", action="store_true")
    r.add_argument("--keep", choices=["failures", "all", "none"], default="failures",
                   help="which scans keep their volume (outputs and truth are always kept)")
    r.add_argument("--param", action="append", metavar="KEY=VALUE", help="fix a parameter for every scan")
    r.add_argument("--stage", choices=["unwrap", "mesh"], default="unwrap",
                   help="unwrap: the whole tool, scored on mesh and text; mesh: `segment` only, scored on the mesh")
    r.add_argument("--timeout", type=float, default=1800.0, help="seconds per tool run")
    r.add_argument("--selfcheck", action="store_true", help="run the self-check first")
    r.add_argument("--strict", action="store_true", help="exit 2 if the tool crashed or scoring failed")
    r.add_argument("--require-success", action="store_true",
                   help="exit 3 unless every scan succeeds (mesh error, jumps, coverage): a regression check")
    m = sub.add_parser("map", help="stability map: success rate over SNR x gap")
    m.add_argument("--per-cell", type=int, default=5)
    m.add_argument("--seed", type=int, default=100000)
    m.add_argument("--out", required=True)
    m.add_argument("--csv", required=True)
    m.add_argument("--png", required=True)
    m.add_argument("--snr", default="8,5,4,3,2.5,2,1.5")
    m.add_argument("--gaps", default="1,1.5,2,3,4,6")
    m.add_argument("--jobs", type=int, default=1)
    m.add_argument("--tool", default="build/bin/virtual-unwrap")
    m.add_argument("--small", action="store_true")
    m.add_argument("--keep", choices=["failures", "all", "none"], default="none")
    m.add_argument("--stage", choices=["unwrap", "mesh"], default="unwrap",
                   help="unwrap: the whole tool, scored on mesh and text; mesh: `segment` only, scored on the mesh")
    m.add_argument("--timeout", type=float, default=1800.0)
    q = sub.add_parser("rescore", help="score the scans of a run directory again (no generation, no tool run)")
    q.add_argument("--out", required=True)
    q.add_argument("--csv", required=True)
    q.add_argument("--rerun", choices=["unwrap", "mesh"], default=None,
                   help="run the tool again on the kept scans first (after a change to the tool)")
    q.add_argument("--tool", default="build/bin/virtual-unwrap")
    q.add_argument("--jobs", type=int, default=1)
    q.add_argument("--strict", action="store_true", help="exit 2 if the tool crashed or scoring failed")
    e = sub.add_parser("ceiling", help="how legible the scans themselves are: the ink read from the true surface")
    e.add_argument("--scans", type=int, default=100)
    e.add_argument("--seed", type=int, default=1)
    e.add_argument("--out", required=True)
    e.add_argument("--csv", required=True)
    e.add_argument("--jobs", type=int, default=1)
    e.add_argument("--region", choices=["accept", "wide"], default="accept")
    e.add_argument("--small", action="store_true")
    e.add_argument("--keep", choices=["all", "none"], default="none", help="keep the volumes")
    e.add_argument("--param", action="append", metavar="KEY=VALUE", help="fix a parameter for every scan")
    e.add_argument("--require-legible", action="store_true",
                   help="exit 3 unless every scan reads from the true surface (a check of the generator's ink)")
    s = sub.add_parser("summary", help="reprint the summary table of a CSV")
    s.add_argument("--csv", required=True)
    v = sub.add_parser("preview", help="PNG of a generated scan: slices and the true ink")
    v.add_argument("--scan", required=True)
    v.add_argument("--png", required=True)
    c = sub.add_parser("selfcheck", help="check the generator and the scorer against the truth")
    c.add_argument("--tool", default=None, help="also check that the tool reads every format")
    args = parser.parse_args()

    if args.command == "generate":
        generate(draw_parameters(args.seed, args.region, args.small, parse_overrides(args.param)), args.out)
    elif args.command == "preview":
        preview_png(args.scan, args.png)
    elif args.command == "selfcheck":
        selfcheck(args.tool)
    elif args.command == "rescore":
        dirs = sorted((d for d in os.listdir(args.out) if d.startswith("scan-")
                       and os.path.exists(os.path.join(args.out, d, "truth.json" if args.rerun else "tool.json"))),
                      key=lambda d: int(d[5:]))
        tasks = [dict(scan_dir=os.path.join(args.out, d), rerun=args.rerun, tool=os.path.abspath(args.tool))
                 for d in dirs]
        rows = []
        with open(args.csv, "w", newline="") as f, \
                concurrent.futures.ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            writer = csv.DictWriter(f, fieldnames=CSV_KEYS, extrasaction="ignore", restval="")
            writer.writeheader()
            for d, row in zip(dirs, pool.map(_rescore_star, tasks)):
                writer.writerow(row)
                f.flush()
                rows.append({k: str(v) for k, v in row.items()})
                print(f"{d}: success {row.get('success')} error {row.get('mesh_error_mean')} jumps {row.get('jumps')} "
                      f"coverage {row.get('coverage')} cer {row.get('cer')} cer_text {row.get('cer_text')}", flush=True)
        print(summary_table(read_csv(args.csv)))
        bad = [r for r in rows if r.get("crash") == "True" or r.get("score_error")]
        if args.strict and (bad or not rows):
            print(f"{len(bad)} scan(s) with a tool crash or a scoring error, {len(rows)} scored", file=sys.stderr)
            sys.exit(2)
    elif args.command == "summary":
        print(summary_table(read_csv(args.csv)))
    elif args.command == "ceiling":
        os.makedirs(args.out, exist_ok=True)
        overrides = parse_overrides(args.param)
        tasks = [dict(seed=args.seed + i, out_root=args.out, region=args.region, small=args.small, keep=args.keep,
                      overrides=overrides) for i in range(args.scans)]
        with open(args.csv, "w", newline="") as f, \
                concurrent.futures.ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            writer = csv.DictWriter(f, fieldnames=CSV_KEYS, extrasaction="ignore", restval="")
            writer.writeheader()
            for row in pool.map(_ceiling_scan_star, tasks):
                writer.writerow(row)
                f.flush()
                print(f"seed {row['seed']}: cer_ceiling {row.get('cer_ceiling', '')} ({row.get('ceiling_filter', '')})"
                      + (f" SCORE ERROR {row['score_error']}" if row.get("score_error") else ""), flush=True)
        rows = read_csv(args.csv)
        print()
        print(ceiling_table(rows))
        if any(r.get("score_error") for r in rows):
            sys.exit(2)
        illegible = [r["seed"] for r in rows if r.get("legible_ceiling") != "True"]
        if args.require_legible and (illegible or not rows):
            print(f"\n{len(illegible)} of {len(rows)} scan(s) illegible from the true surface: " + ", ".join(illegible),
                  file=sys.stderr)
            sys.exit(3)
    elif args.command == "run":
        if args.selfcheck:
            selfcheck(args.tool)
        if not os.path.exists(args.tool):
            raise SystemExit(f"no tool at {args.tool}")
        os.makedirs(args.out, exist_ok=True)
        csv_path = args.csv or os.path.join(args.out, "results.csv")
        overrides = parse_overrides(args.param)
        tasks = [dict(seed=args.seed + i, out_root=args.out, region=args.region, small=args.small,
                      tool=os.path.abspath(args.tool), keep=args.keep, overrides=overrides, timeout=args.timeout,
                      stage=args.stage)
                 for i in range(args.scans)]
        rows = run_scans(tasks, csv_path, args.jobs)
        rows = read_csv(csv_path)
        print()
        print(summary_table(rows))
        bad = [r for r in rows if r.get("crash") == "True" or r.get("score_error")]
        if bad:
            print(f"\n{len(bad)} scan(s) with a tool crash (signal, exit status other than 0 or 1, timeout, "
                  "missing outputs) or a scoring error: " + ", ".join(r["seed"] for r in bad), file=sys.stderr)
        incomplete = len(rows) != args.scans or any(r.get("tool_exit") in ("", None) or r.get("success") in ("", None)
                                                     for r in rows)
        if incomplete:
            print(f"\n{csv_path}: {len(rows)} complete row(s) for {args.scans} scan(s)", file=sys.stderr)
        if args.strict and (bad or incomplete):
            sys.exit(2)
        failed = [r["seed"] for r in rows if r.get("success") != "True"]
        if args.require_success and (failed or not rows):
            print(f"\n{len(failed)} of {len(rows)} scan(s) did not succeed: " + ", ".join(failed), file=sys.stderr)
            sys.exit(3)
    elif args.command == "map":
        snrs = [float(x) for x in args.snr.split(",")]
        gaps = [float(x) for x in args.gaps.split(",")]
        os.makedirs(args.out, exist_ok=True)
        tasks = []
        for i, snr in enumerate(snrs):
            for j, gap in enumerate(gaps):
                for k in range(args.per_cell):
                    tasks.append(dict(seed=args.seed + 1000 * (i * len(gaps) + j) + k, out_root=args.out,
                                      region="wide", small=args.small, tool=os.path.abspath(args.tool),
                                      keep=args.keep, overrides={"snr": snr, "gap": gap}, timeout=args.timeout,
                                      stage=args.stage,
                                      extra={"map_snr": snr, "map_gap": gap}))
        run_scans(tasks, args.csv, args.jobs)
        rows = read_csv(args.csv)
        stability_map(rows, snrs, gaps, args.png,
                      "small scans (2-3.5 turns)" if args.small else "the whole family")
        print(summary_table(rows))
        print(f"\nstability map: {args.png}")


if __name__ == "__main__":
    main()

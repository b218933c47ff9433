#!/usr/bin/env python3
"""Independent procedural height-field texture generator (23 model families).

usage: python3 gen.py OUT_DIR --per-model N --seed S [--size 256] [--jobs 2]

Every model builds a HEIGHT FIELD (either a periodic raster or an analytic
function of the plane); a shared randomised renderer then resamples it
(scale 0.5-2x, any rotation), shades it and quantises it to 8-bit grey.
Only NumPy / SciPy / Pillow are used.
"""
import os
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
import argparse
import csv
import math
import sys
import time

import numpy as np
from scipy import ndimage
from scipy import fft as sfft
from scipy.spatial import cKDTree
from PIL import Image

MODELS = [
    "CA (Excitable media model)",
    "CA (Forest fire model)",
    "CA (Surface tension model)",
    "Cellular",
    "Folding of Cellular",
    "Folding of Fractal",
    "Folding of Perlin noise",
    "Folding of Texton Placement",
    "Fractal (Fourier spectral synthesis)",
    "Fractal (midpoint displacement)",
    "Fractal (one-over-f-beta noise)",
    "Fusion of Cellular and Texton",
    "Fusion of Perlin and Cellular",
    "Fusion of Perlin and Texton",
    "Islamic Patterns",
    "Matrix Transformation",
    "Perlin noise",
    "Reaction Diffusion",
    "Texton Addition",
    "Texton probability map",
    "Texton random grid",
    "Texton random walk",
    "Texton regular",
]

TAU = 2.0 * np.pi
SQ3 = math.sqrt(3.0)


# ----------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------
def loguni(rng, a, b):
    return float(np.exp(rng.uniform(np.log(a), np.log(b))))


def pick(rng, items, p=None):
    if p is not None:
        p = np.asarray(p, float)
        p = p / p.sum()
    return items[int(rng.choice(len(items), p=p))]


def mm01(h):
    a, b = float(np.min(h)), float(np.max(h))
    if b - a < 1e-12:
        return np.zeros_like(h, dtype=float)
    return (h - a) / (b - a)


def pct01(h, lo=0.5, hi=99.5):
    a, b = np.percentile(h, [lo, hi])
    if b - a < 1e-12:
        return np.zeros_like(h, dtype=float)
    return np.clip((h - a) / (b - a), 0.0, 1.0)


def zs(h):
    s = float(np.std(h))
    if s < 1e-12:
        return np.zeros_like(h, dtype=float)
    return (h - float(np.mean(h))) / s


def smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def fast_len(n):
    return int(sfft.next_fast_len(int(n)))


def tile_op(a, fn):
    """Apply a non-periodic operator to a periodic array via 3x3 tiling."""
    n0, n1 = a.shape
    t = np.tile(a, (3, 3))
    r = fn(t)
    return r[n0:2 * n0, n1:2 * n1]


def warp(a, dx, dy, order=1):
    n0, n1 = a.shape
    yy, xx = np.mgrid[0:n0, 0:n1].astype(float)
    return ndimage.map_coordinates(a, [yy + dy, xx + dx], order=order, mode="grid-wrap")


class Raster:
    """Periodic raster height field; px = nominal output pixels per cell."""

    def __init__(self, a, px=1.0):
        self.a = np.asarray(a, dtype=float)
        self.px = float(px)


class Func:
    """Analytic height field h = f(X, Y) with X, Y in nominal output pixels."""

    def __init__(self, f):
        self.f = f


# ----------------------------------------------------------------------------
# spectral / fractal noise
# ----------------------------------------------------------------------------
def _fgrid(N):
    fy = np.fft.fftfreq(N)[:, None]
    fx = np.fft.rfftfreq(N)[None, :]
    return fx, fy


def filtered_white(rng, N, filt):
    w = rng.standard_normal((N, N))
    W = np.fft.rfft2(w)
    fx, fy = _fgrid(N)
    W *= filt(fx, fy)
    return np.fft.irfft2(W, s=(N, N))


def one_over_f(rng, N, beta, stretch=1.0, sdir=0.0, fmin=0.0, fmax=None):
    """White noise filtered by |A f|^(-beta/2) (A = anisotropic scaling)."""
    c, s = math.cos(sdir), math.sin(sdir)

    def filt(fx, fy):
        a = fx * c + fy * s
        b = -fx * s + fy * c
        r = np.sqrt((a * stretch) ** 2 + (b / stretch) ** 2)
        r0 = 1.0 / N
        amp = np.maximum(r, r0) ** (-beta / 2.0)
        amp[0, 0] = 0.0
        rr = np.hypot(fx, fy)
        if fmin > 0:
            amp *= smoothstep(fmin * 0.5, fmin, rr)
        if fmax is not None:
            amp *= np.exp(-(rr / fmax) ** 2)
        return amp

    return filtered_white(rng, N, filt)


def spectral_synthesis(rng, N, beta, ddir=None, avar=None, fmin=0.0, fpeak=None, bw=None):
    """Saupe style Fourier synthesis: random amplitudes & phases, power ~ f^-beta,
    optional dominant direction (DDir) with angular spread (avar, radians)."""
    fy = np.fft.fftfreq(N)[:, None]
    fx = np.fft.rfftfreq(N)[None, :]
    r = np.hypot(fx, fy)
    r[0, 0] = 1.0
    amp = r ** (-beta / 2.0)
    if fpeak is not None:
        amp = amp * np.exp(-0.5 * (np.log(r / fpeak) / bw) ** 2)
    if ddir is not None:
        th = np.arctan2(fy, fx) + np.zeros_like(fx)
        d = np.angle(np.exp(2j * (th - ddir))) / 2.0
        amp = amp * np.exp(-0.5 * (d / avar) ** 2)
    if fmin > 0:
        amp = amp * smoothstep(fmin * 0.5, fmin, r)
    amp[0, 0] = 0.0
    mag = amp * np.sqrt(rng.exponential(1.0, amp.shape))
    ph = rng.uniform(0, TAU, amp.shape)
    return np.fft.irfft2(mag * np.exp(1j * ph), s=(N, N))


def sum_of_sines(rng, N, beta, nwaves, ddir, avar, kmin, kmax):
    """Sparse spectral synthesis: few plane waves with power-law amplitudes.
    Integer wave vectors keep the field periodic on the N x N torus."""
    yy, xx = np.mgrid[0:N, 0:N].astype(float)
    h = np.zeros((N, N))
    for _ in range(nwaves):
        k = loguni(rng, kmin, kmax)
        if ddir is None:
            a = rng.uniform(0, np.pi)
        else:
            a = ddir + rng.normal(0, avar)
        kx, ky = round(k * math.cos(a)), round(k * math.sin(a))
        if kx == 0 and ky == 0:
            continue
        kk = math.hypot(kx, ky)
        h += kk ** (-beta / 2.0) * rng.normal() * np.cos(TAU * (kx * xx + ky * yy) / N + rng.uniform(0, TAU))
    return h


def diamond_square(rng, N, H, start_level=1, variant="diamond-square"):
    """Periodic midpoint displacement on a 2^k torus; roughness H."""
    a = np.zeros((N, N))
    step = N >> start_level
    if step < 2:
        step = 2
    m = N // step
    a[::step, ::step] = rng.standard_normal((m, m))
    scale = 0.5 ** H
    while step > 1:
        half = step // 2
        G = a[::step, ::step]
        if variant == "diamond-square":
            C = 0.25 * (G + np.roll(G, -1, 0) + np.roll(G, -1, 1) + np.roll(np.roll(G, -1, 0), -1, 1))
            C = C + scale * rng.standard_normal(C.shape)
            a[half::step, half::step] = C
            # edge points between vertical neighbours (y = i*step+half, x = j*step)
            E1 = 0.25 * (G + np.roll(G, -1, 0) + C + np.roll(C, 1, 1))
            E2 = 0.25 * (G + np.roll(G, -1, 1) + C + np.roll(C, 1, 0))
        else:  # Fournier square midpoint: edges from their two end points
            E1 = 0.5 * (G + np.roll(G, -1, 0))
            E2 = 0.5 * (G + np.roll(G, -1, 1))
            C = 0.25 * (G + np.roll(G, -1, 0) + np.roll(G, -1, 1) + np.roll(np.roll(G, -1, 0), -1, 1))
            C = C + scale * rng.standard_normal(C.shape)
            a[half::step, half::step] = C
        a[half::step, ::step] = E1 + scale * rng.standard_normal(E1.shape)
        a[::step, half::step] = E2 + scale * rng.standard_normal(E2.shape)
        step = half
        scale *= 0.5 ** H
    return a


def fractal_field(rng, N, u, allow=("spectral", "oneoverf", "midpoint"), smooth=False):
    kind = pick(rng, list(allow))
    if kind == "spectral":
        beta = rng.uniform(3.0, 4.2) if smooth else rng.uniform(1.6, 3.6)
        if rng.random() < 0.6:
            ddir, avar = rng.uniform(0, np.pi), math.radians(loguni(rng, 4, 60))
        else:
            ddir, avar = None, None
        h = spectral_synthesis(rng, N, beta, ddir, avar, fmin=(1.0 / (200 * u)) * rng.random())
        d = "spectral b=%.2f%s" % (beta, "" if ddir is None else " dir=%.0f var=%.0f" % (math.degrees(ddir), math.degrees(avar)))
    elif kind == "oneoverf":
        beta = rng.uniform(3.0, 4.0) if smooth else rng.uniform(1.2, 3.5)
        st = 1.0 if rng.random() < 0.4 else loguni(rng, 1.5, 6)
        h = one_over_f(rng, N, beta, st, rng.uniform(0, np.pi))
        d = "1/f b=%.2f stretch=%.1f" % (beta, st)
    else:
        M = 1 << int(math.ceil(math.log2(max(N, 16))))
        H = rng.uniform(0.7, 1.0) if smooth else rng.uniform(0.25, 0.95)
        sl = int(rng.integers(1, 5))
        h = diamond_square(rng, M, H, sl + max(0, int(math.log2(M / (256 * u)))))
        d = "midpoint H=%.2f" % H
    return h, d


# ----------------------------------------------------------------------------
# Perlin gradient noise / value noise (periodic)
# ----------------------------------------------------------------------------
def _fade(t):
    return t * t * t * (t * (t * 6 - 15) + 10)


def lattice_noise(rng, N, P, value=False):
    """One octave on an N x N torus with P lattice cells per period."""
    P = max(1, int(P))
    x = (np.arange(N) + 0.5) * P / N
    i0 = np.floor(x).astype(np.int64)
    f = x - i0
    i0 %= P
    i1 = (i0 + 1) % P
    w = _fade(f)
    wy, wx = w[:, None], w[None, :]
    fy, fx = f[:, None], f[None, :]
    if value:
        V = rng.uniform(-1, 1, (P, P))
        c00 = V[i0[:, None], i0[None, :]]
        c01 = V[i0[:, None], i1[None, :]]
        c10 = V[i1[:, None], i0[None, :]]
        c11 = V[i1[:, None], i1[None, :]]
    else:
        ang = rng.uniform(0, TAU, (P, P))
        gx, gy = np.cos(ang), np.sin(ang)

        def dot(iy, ix, oy, ox):
            return gx[iy[:, None], ix[None, :]] * (fx - ox) + gy[iy[:, None], ix[None, :]] * (fy - oy)

        c00 = dot(i0, i0, 0, 0)
        c01 = dot(i0, i1, 0, 1)
        c10 = dot(i1, i0, 1, 0)
        c11 = dot(i1, i1, 1, 1)
        # scale gradient noise to roughly [-1, 1]
        c00, c01, c10, c11 = [c * 1.41 for c in (c00, c01, c10, c11)]
    top = c00 + wx * (c01 - c00)
    bot = c10 + wx * (c11 - c10)
    return top + wy * (bot - top)


def perlin_fbm(rng, N, feat, octaves, persistence, lacunarity, mode="fbm", value=False):
    total = np.zeros((N, N))
    amp = 1.0
    cells = N / feat
    weight = np.ones((N, N))
    norm = 0.0
    for o in range(octaves):
        P = max(1, int(round(cells)))
        if P > N / 2.5:
            break
        n = lattice_noise(rng, N, P, value)
        if mode == "fbm":
            s = n
        elif mode == "turbulence":
            s = np.abs(n)
        else:  # ridged multifractal (Musgrave style)
            s = (1.0 - np.abs(n)) ** 2
            s = s * weight
            weight = np.clip(s * 2.0, 0, 1)
        total += amp * s
        norm += amp
        amp *= persistence
        cells *= lacunarity
    return total / max(norm, 1e-9)


def perlin_field(rng, N, u, modes=("fbm", "fbm", "turbulence", "ridged"), max_oct=8, feat_lo=16):
    value = rng.random() < 0.25
    mode = pick(rng, list(modes))
    octaves = int(rng.integers(1, max_oct + 1))
    pers = rng.uniform(0.3, 0.7)
    lac = rng.uniform(1.8, 2.3)
    feat = loguni(rng, feat_lo * u, 160 * u)
    h = perlin_fbm(rng, N, feat, octaves, pers, lac, mode, value)
    d = "%s %s oct=%d pers=%.2f lac=%.2f feat=%.0f" % ("value" if value else "perlin", mode, octaves, pers, lac, feat)
    return h, d


# ----------------------------------------------------------------------------
# Worley cellular noise (periodic, via periodic kd-tree)
# ----------------------------------------------------------------------------
def worley_points(rng, N, cell, layout, jitter):
    if layout in ("grid", "hex"):
        m = max(2, int(round(N / cell)))
        c = N / m
        gy, gx = np.mgrid[0:m, 0:m].astype(float)
        if layout == "hex":
            if m % 2:
                m += 1
                c = N / m
                gy, gx = np.mgrid[0:m, 0:m].astype(float)
            gx = gx + 0.5 * (gy % 2)
        x = (gx + 0.5 + jitter * rng.uniform(-0.5, 0.5, gx.shape)) * c
        y = (gy + 0.5 + jitter * rng.uniform(-0.5, 0.5, gy.shape)) * c
        pts = np.stack([x.ravel(), y.ravel()], -1)
    else:
        n = max(4, int(rng.poisson(N * N / (cell * cell))))
        pts = rng.uniform(0, N, (n, 2))
    pts = np.mod(pts, N)
    pts[pts >= N] = 0.0
    return pts


def worley_query(pts, N, p, k=3):
    tree = cKDTree(pts, boxsize=N)
    ys, xs = np.mgrid[0:N, 0:N].astype(float) + 0.5
    q = np.stack([xs.ravel(), ys.ravel()], -1)
    d, idx = tree.query(q, k=k, p=p)
    return d.reshape(N, N, k), idx.reshape(N, N, k)


METRICS = {"euclid": 2.0, "manhattan": 1.0, "chebyshev": np.inf, "minkowski3": 3.0}


def cellular_field(rng, N, u, styles=None, cell=None):
    if cell is None:
        cell = loguni(rng, 14 * u, 90 * u)
    layout = pick(rng, ["grid", "grid", "poisson", "hex"])
    jitter = rng.uniform(0.3, 1.0) if layout == "grid" else rng.uniform(0.0, 0.6)
    metric = pick(rng, ["euclid", "manhattan", "chebyshev", "minkowski3"], [0.55, 0.15, 0.15, 0.15])
    pts = worley_points(rng, N, cell, layout, jitter)
    d, idx = worley_query(pts, N, METRICS[metric], 3)
    F1, F2, F3 = d[..., 0], d[..., 1], d[..., 2]
    if styles is None:
        styles = ["F1", "F2", "F2-F1", "F3-F1", "F1*F2", "combo", "mosaic", "stones", "dome", "cone",
                  "pyramid", "crackle"]
    style = pick(rng, styles)
    if style == "F1":
        h = F1
    elif style == "F2":
        h = F2
    elif style == "F2-F1":
        h = F2 - F1
    elif style == "F3-F1":
        h = F3 - F1
    elif style == "F1*F2":
        h = F1 * F2
    elif style == "combo":
        c = rng.uniform(-1, 1, 3)
        c[0] = abs(c[0]) + 0.2
        h = c[0] * F1 + c[1] * F2 + c[2] * F3
    elif style == "mosaic":
        vals = rng.uniform(0, 1, len(pts))
        g = rng.uniform(0.7, 3.0)
        h = vals[idx[..., 0]] * (0.3 + 0.7 * smoothstep(0, g, F2 - F1)) if rng.random() < 0.7 else vals[idx[..., 0]]
    elif style == "stones":
        w = cell * rng.uniform(0.05, 0.4)
        h = smoothstep(0, w, F2 - F1)
        if rng.random() < 0.5:
            h = h * rng.uniform(0.5, 1.0, len(pts))[idx[..., 0]]
    elif style in ("dome", "cone"):
        r = np.clip(2 * F1 / np.maximum(F1 + F2, 1e-9), 0, 1)
        h = np.sqrt(1 - r * r) if style == "dome" else 1 - r
    elif style == "pyramid":
        if metric == "euclid":
            p0 = pts[idx[..., 0]]
            e = []
            for j in (1, 2):
                dv = pts[idx[..., j]] - p0
                dv -= N * np.round(dv / N)
                e.append((d[..., j] ** 2 - F1 ** 2) / (2 * np.maximum(np.hypot(dv[..., 0], dv[..., 1]), 1e-9)))
            h = np.minimum(e[0], e[1])
        else:
            h = F2 - F1
    else:  # crackle
        w = rng.uniform(1.0, 4.0) * u
        h = smoothstep(0, w, F2 - F1)
        if rng.random() < 0.5:
            h = h + 0.5 * (1 - np.clip(F1 / cell, 0, 1))
    gam = 1.0
    if style in ("F1", "F2", "F2-F1", "F3-F1") and rng.random() < 0.4:
        gam = loguni(rng, 0.5, 2.0)
        h = mm01(h) ** gam
    desc = "worley %s %s %s cell=%.0f jit=%.2f" % (style, metric, layout, cell, jitter)
    return h, desc, pts, idx


# ----------------------------------------------------------------------------
# textons (stamps)
# ----------------------------------------------------------------------------
SHAPES = ["disc", "ellipse", "square", "rsquare", "diamond", "triangle", "hexagon", "star",
          "cross", "bar", "ring", "pentagon"]
PROFILES = ["flat", "dome", "cone", "gauss", "bevel"]


def texton_spec(rng, graded=False, shapes=None):
    shape = pick(rng, shapes or SHAPES)
    sp = {"shape": shape}
    if shape == "ellipse":
        sp["aspect"] = rng.uniform(0.3, 0.75)
    elif shape == "bar":
        sp["aspect"] = rng.uniform(0.1, 0.35)
    elif shape == "cross":
        sp["w"] = rng.uniform(0.15, 0.45)
    elif shape == "star":
        sp["m"] = int(rng.integers(4, 9))
        sp["rin"] = rng.uniform(0.3, 0.65)
        sp["q"] = rng.uniform(1.0, 3.0)
    elif shape == "ring":
        sp["r0"] = rng.uniform(0.5, 0.8)
        sp["wr"] = rng.uniform(0.1, 0.3)
        sp["base"] = pick(rng, ["disc", "disc", "square", "hexagon"])
    if graded:
        sp["profile"] = pick(rng, ["dome", "cone", "gauss", "cone"])
    else:
        sp["profile"] = pick(rng, PROFILES, [0.3, 0.25, 0.2, 0.1, 0.15])
    sp["bevel"] = rng.uniform(0.15, 0.45)
    return sp


def _poly_gauge(U, V, n, rot=0.0):
    r = np.hypot(U, V)
    th = np.arctan2(V, U) - rot
    seg = TAU / n
    phi = np.mod(th, seg) - seg / 2
    return r * np.cos(phi) / math.cos(math.pi / n)


def texton_gauge(sp, U, V):
    s = sp["shape"]
    if s == "ring":
        s = sp["base"]
    if s == "disc":
        return np.hypot(U, V)
    if s == "ellipse":
        return np.hypot(U, V / sp["aspect"])
    if s == "square":
        return np.maximum(np.abs(U), np.abs(V)) * 1.3
    if s == "rsquare":
        return ((np.abs(U) ** 4 + np.abs(V) ** 4) ** 0.25) * 1.2
    if s == "diamond":
        return np.abs(U) + np.abs(V)
    if s == "triangle":
        return _poly_gauge(U, V, 3, math.pi / 2) * 0.9
    if s == "pentagon":
        return _poly_gauge(U, V, 5, math.pi / 2)
    if s == "hexagon":
        return _poly_gauge(U, V, 6)
    if s == "star":
        th = np.arctan2(V, U)
        R = sp["rin"] + (1 - sp["rin"]) * ((1 + np.cos(sp["m"] * th)) / 2) ** sp["q"]
        return np.hypot(U, V) / R
    if s == "cross":
        w = sp["w"]
        a = np.maximum(np.abs(U), np.abs(V) / w)
        b = np.maximum(np.abs(U) / w, np.abs(V))
        return np.minimum(a, b) * 1.15
    if s == "bar":
        return np.maximum(np.abs(U), np.abs(V) / sp["aspect"]) * 1.1
    return np.hypot(U, V)


def texton_height(sp, U, V, R):
    g = texton_gauge(sp, U, V)
    prof = sp["profile"]
    if sp["shape"] == "ring":
        t = 1 - np.abs(g - sp["r0"]) / sp["wr"]
        if prof == "flat":
            return np.clip(t * sp["wr"] * R / 1.2 + 0.5, 0, 1)
        if prof == "dome":
            return np.sqrt(np.clip(1 - (1 - np.clip(t, 0, 1)) ** 2, 0, 1))
        return np.clip(t, 0, 1)
    if prof == "flat":
        return np.clip((1 - g) * R / 1.2 + 0.5, 0, 1)
    if prof == "dome":
        return np.sqrt(np.clip(1 - g * g, 0, 1))
    if prof == "cone":
        return np.clip(1 - g, 0, 1)
    if prof == "gauss":
        return np.clip((np.exp(-3 * g * g) - 0.02) / 0.98, 0, 1)
    # bevel / plateau
    return np.clip((1 - g) / sp["bevel"], 0, 1)


def draw_textons(N, items, combine="max", canvas=None):
    """items: (x, y, R, angle, spec, amp). Periodic canvas N x N."""
    if canvas is None:
        canvas = np.zeros((N, N))
    for (x, y, R, ang, sp, amp) in items:
        R = min(R, N / 4.0)
        ext = R * 1.5 + 2
        x0 = int(math.floor(x - ext))
        y0 = int(math.floor(y - ext))
        x1 = int(math.ceil(x + ext)) + 1
        y1 = int(math.ceil(y + ext)) + 1
        xs = np.arange(x0, x1) + 0.5 - x
        ys = np.arange(y0, y1) + 0.5 - y
        c, s = math.cos(ang), math.sin(ang)
        U = (xs[None, :] * c + ys[:, None] * s) / R
        V = (-xs[None, :] * s + ys[:, None] * c) / R
        h = texton_height(sp, U, V, R)
        ix = np.arange(x0, x1) % N
        iy = np.arange(y0, y1) % N
        sub = canvas[np.ix_(iy, ix)]
        if combine == "max":
            sub = np.maximum(sub, amp * h)
        elif combine == "add":
            sub = sub + amp * h
        elif combine == "min":
            sub = np.minimum(sub, amp * h)
        else:  # "over": opaque stamping, later textons cover earlier ones
            cov = np.clip(h * 8, 0, 1) if sp["profile"] != "flat" else h
            sub = sub * (1 - cov) + amp * h * cov
        canvas[np.ix_(iy, ix)] = sub
    return canvas


def tex_regular(rng, N, u, graded=False):
    spacing = loguni(rng, 14 * u, 80 * u)
    lattice = pick(rng, ["square", "hex", "brick", "rect", "oblique"])
    alt = pick(rng, ["none", "none", "rot", "shape"])
    nx = max(2, int(round(N / spacing)))
    if alt != "none" and nx % 2:
        nx += 1
    dx = N / nx
    shift = 0.0
    if lattice == "square":
        ny, dy = nx, dx
    elif lattice == "hex":
        ny = max(2, 2 * int(round(N / (dx * SQ3 / 2) / 2)))
        dy = N / ny
        shift = 0.5
    elif lattice == "brick":
        asp = rng.uniform(0.45, 0.8)
        ny = max(2, 2 * int(round(N / (dx * asp) / 2)))
        dy = N / ny
        shift = 0.5
    elif lattice == "rect":
        asp = rng.uniform(0.4, 0.8) if rng.random() < 0.5 else rng.uniform(1.25, 2.0)
        ny = max(2, int(round(N / (dx * asp))))
        if alt != "none" and ny % 2:
            ny += 1
        dy = N / ny
    else:
        ny = max(2, int(round(N / dx)))
        if alt != "none" and ny % 2:
            ny += 1
        dy = N / ny
        q = int(rng.integers(1, ny))
        shift = -1.0 - q / ny  # marker: cumulative shift
    sp1 = texton_spec(rng, graded)
    sp2 = texton_spec(rng, graded) if alt == "shape" else sp1
    fill = rng.uniform(0.35, 0.98)
    R = fill * min(dx, dy) / 2
    if lattice in ("brick", "rect") and sp1["shape"] in ("ellipse", "bar") and dx > dy:
        R = fill * dx / 2
    ang = rng.uniform(0, TAU) if rng.random() < 0.3 else (0.0 if rng.random() < 0.6 else math.pi / 4)
    ang2 = ang + (math.pi / 2 if rng.random() < 0.5 else math.pi / 4)
    items = []
    for j in range(ny):
        for i in range(nx):
            if shift >= 0:
                x = (i + 0.5 + shift * (j % 2)) * dx
            else:
                x = (i + 0.5 + j * (-shift - 1.0) * 1.0) * dx
            y = (j + 0.5) * dy
            odd = (i + j) % 2 == 1
            sp = sp2 if (alt == "shape" and odd) else sp1
            a = ang2 if (alt == "rot" and odd) else ang
            items.append((x % N, y, R, a, sp, 1.0))
    h = draw_textons(N, items, "max")
    d = "regular %s %s/%s prof=%s sp=%.0f fill=%.2f alt=%s" % (lattice, sp1["shape"], sp2["shape"], sp1["profile"], dx, fill, alt)
    return h, d


def tex_random_grid(rng, N, u, graded=False):
    spacing = loguni(rng, 12 * u, 70 * u)
    m = max(2, int(round(N / spacing)))
    c = N / m
    specs = [texton_spec(rng, graded) for _ in range(int(rng.integers(1, 3)))]
    fill = rng.uniform(0.3, 0.9)
    sizevar = rng.uniform(0, 0.45)
    jitter = rng.uniform(0.2, 1.0)
    rot = pick(rng, ["random", "random", "fixed", "small"])
    a0 = rng.uniform(0, TAU)
    empty = rng.uniform(0, 0.25) if rng.random() < 0.3 else 0.0
    items = []
    for j in range(m):
        for i in range(m):
            if rng.random() < empty:
                continue
            R = c / 2 * fill * (1 + sizevar * rng.uniform(-1, 1))
            free = max(0.0, c / 2 - R * 0.7)
            x = (i + 0.5) * c + jitter * rng.uniform(-1, 1) * free
            y = (j + 0.5) * c + jitter * rng.uniform(-1, 1) * free
            a = {"random": rng.uniform(0, TAU), "fixed": a0, "small": a0 + rng.normal(0, 0.2)}[rot]
            items.append((x, y, R, a, specs[int(rng.integers(len(specs)))], rng.uniform(0.6, 1.0) if rng.random() < 0.5 else 1.0))
    h = draw_textons(N, items, pick(rng, ["max", "max", "over"]))
    d = "randgrid %s prof=%s cell=%.0f fill=%.2f jit=%.2f rot=%s" % ("+".join(s["shape"] for s in specs), specs[0]["profile"], c, fill, jitter, rot)
    return h, d


def tex_random_walk(rng, N, u, graded=False):
    sp = texton_spec(rng, graded)
    R0 = loguni(rng, 3 * u, 12 * u)
    steplen = R0 * rng.uniform(0.5, 2.2)
    walkers = int(rng.integers(1, 14))
    cover = rng.uniform(0.15, 0.6)
    total = int(cover * N * N / (math.pi * R0 * R0) * (steplen / (2 * R0)) * 1.5) + 20
    total = min(total, 9000)
    nsteps = max(10, total // walkers)
    sigma = loguni(rng, 0.05, 0.9)
    lattice_walk = rng.random() < 0.2
    align = rng.random() < 0.6
    sizevar = rng.uniform(0, 0.4)
    items = []
    for w in range(walkers):
        x, y = rng.uniform(0, N, 2)
        a = rng.uniform(0, TAU)
        if lattice_walk:
            a = int(rng.integers(4)) * math.pi / 2
        for t in range(nsteps):
            if lattice_walk:
                if rng.random() < 0.3:
                    a += pick(rng, [-1, 1]) * math.pi / 2
            else:
                a += rng.normal(0, sigma)
            x = (x + steplen * math.cos(a)) % N
            y = (y + steplen * math.sin(a)) % N
            R = R0 * (1 + sizevar * rng.uniform(-1, 1))
            items.append((x, y, R, a if align else rng.uniform(0, TAU), sp, 1.0))
    h = draw_textons(N, items, pick(rng, ["max", "max", "add", "over"]))
    d = "randwalk %s prof=%s R=%.1f step=%.1f walkers=%d turn=%.2f%s" % (sp["shape"], sp["profile"], R0, steplen, walkers, sigma, " lattice" if lattice_walk else "")
    return h, d


def density_map(rng, N, u):
    kind = pick(rng, ["fft", "perlin"])
    if kind == "fft":
        m = one_over_f(rng, N, rng.uniform(3.0, 4.5), fmin=1.0 / N)
    else:
        m = perlin_fbm(rng, N, loguni(rng, 60 * u, 200 * u), 2, 0.4, 2.0)
    m = zs(m)
    style = pick(rng, ["sigmoid", "power", "threshold"])
    if style == "sigmoid":
        m = 1 / (1 + np.exp(-rng.uniform(1.5, 5) * (m - rng.uniform(-0.7, 0.7))))
    elif style == "power":
        m = mm01(m) ** rng.uniform(1.0, 3.5)
    else:
        m = smoothstep(-0.2, 0.2, m - rng.uniform(-0.8, 0.8)) * 0.97 + 0.03
    return m, style


def tex_probmap(rng, N, u, graded=False):
    dens, style = density_map(rng, N, u)
    sp = texton_spec(rng, graded)
    R0 = loguni(rng, 3 * u, 14 * u)
    cover = rng.uniform(0.3, 1.2)
    n_max = int(cover * N * N / (math.pi * R0 * R0))
    n_max = min(n_max, 12000)
    cand = rng.uniform(0, N, (n_max, 2))
    dv = dens[cand[:, 1].astype(int) % N, cand[:, 0].astype(int) % N]
    keep = rng.random(n_max) < dv / dens.max()
    cand = cand[keep]
    sizemod = rng.random() < 0.4
    rot = pick(rng, ["random", "fixed"])
    a0 = rng.uniform(0, TAU)
    items = []
    for (x, y) in cand:
        R = R0 * rng.uniform(0.75, 1.25)
        if sizemod:
            R *= 0.5 + dens[int(y) % N, int(x) % N]
        items.append((x, y, R, rng.uniform(0, TAU) if rot == "random" else a0, sp, 1.0))
    h = draw_textons(N, items, pick(rng, ["max", "over"]))
    d = "probmap(%s) %s prof=%s R=%.1f n=%d%s" % (style, sp["shape"], sp["profile"], R0, len(items), " sizemod" if sizemod else "")
    return h, d


def tex_addition(rng, N, u, graded=False):
    nspec = int(rng.integers(1, 4))
    specs = [texton_spec(rng, graded) for _ in range(nspec)]
    Rlo = loguni(rng, 3 * u, 16 * u)
    Rhi = Rlo * loguni(rng, 1.0, 4.0)
    overlap = rng.uniform(0.8, 4.0)
    meanA = math.pi * Rlo * Rhi
    n = min(int(overlap * N * N / meanA), 12000)
    signs = rng.random() < 0.25
    items = []
    for _ in range(n):
        x, y = rng.uniform(0, N, 2)
        R = loguni(rng, Rlo, Rhi)
        amp = rng.uniform(0.3, 1.0)
        if signs and rng.random() < 0.4:
            amp = -amp
        items.append((x, y, R, rng.uniform(0, TAU), specs[int(rng.integers(nspec))], amp))
    h = draw_textons(N, items, "add")
    d = "addition %s prof=%s R=%.0f-%.0f n=%d%s" % ("+".join(s["shape"] for s in specs), specs[0]["profile"], Rlo, Rhi, n, " signed" if signs else "")
    return h, d


def texton_field(rng, N, u, graded=False, kinds=("regular", "grid", "walk", "prob", "add")):
    k = pick(rng, list(kinds))
    f = {"regular": tex_regular, "grid": tex_random_grid, "walk": tex_random_walk,
         "prob": tex_probmap, "add": tex_addition}[k]
    return f(rng, N, u, graded)


# ----------------------------------------------------------------------------
# folding
# ----------------------------------------------------------------------------
def fold(rng, h):
    h = mm01(h)
    kind = pick(rng, ["triangle", "triangle", "sine", "abs", "powtri"])
    k = rng.uniform(1.5, 7.0)
    ph = rng.uniform(0, 2)
    if kind == "triangle":
        y = 1 - np.abs(np.mod(h * k + ph, 2.0) - 1)
        d = "tri k=%.1f" % k
    elif kind == "powtri":
        g = loguni(rng, 0.4, 2.5)
        y = 1 - np.abs(np.mod((h ** g) * k + ph, 2.0) - 1)
        d = "tri(h^%.2f) k=%.1f" % (g, k)
    elif kind == "sine":
        y = 0.5 + 0.5 * np.cos(np.pi * (k * h + ph))
        d = "sine k=%.1f" % k
    else:
        m = int(rng.integers(2, 6))
        y = h
        for _ in range(m):
            c = rng.uniform(0.3, 0.7)
            y = mm01(np.abs(y - c))
        d = "abs-fold x%d" % m
    return y, d


# ----------------------------------------------------------------------------
# fusion
# ----------------------------------------------------------------------------
def fuse(rng, A, B, ops):
    op = pick(rng, ops)
    a, b = zs(A), zs(B)
    if op == "sum":
        w = rng.uniform(0.25, 0.75)
        h = w * a + (1 - w) * b
        op = "sum w=%.2f" % w
    elif op == "product":
        bias = rng.uniform(0.0, 0.5)
        h = (bias + (1 - bias) * mm01(A)) * mm01(B)
        op = "product bias=%.2f" % bias
    elif op == "max":
        h = np.maximum(a, b * rng.uniform(0.6, 1.4))
    elif op == "min":
        h = np.minimum(a, b * rng.uniform(0.6, 1.4))
    elif op == "diff":
        h = np.abs(a - b)
    elif op == "mask":
        t = rng.uniform(-0.5, 0.5)
        m = smoothstep(t - 0.3, t + 0.3, a)
        h = m * b + (1 - m) * a * rng.uniform(0.2, 1.0)
    elif op == "screen":
        x, y = mm01(A), mm01(B)
        h = 1 - (1 - x) * (1 - y)
    else:
        raise ValueError(op)
    return h, op


def warp_by(rng, B, A, u):
    """Domain-warp field B by displacement derived from field A."""
    amp = loguni(rng, 3 * u, 25 * u)
    if rng.random() < 0.5:
        gy, gx = np.gradient(ndimage.gaussian_filter(zs(A), 2, mode="wrap"))
        s = max(np.percentile(np.hypot(gx, gy), 95), 1e-9)
        dx, dy = -gy / s * amp, gx / s * amp  # curl-like flow
        how = "curl"
    else:
        a = zs(A)
        ang = rng.uniform(0, TAU)
        dx, dy = a * amp * math.cos(ang), a * amp * math.sin(ang)
        how = "shift"
    return warp(B, dx, dy), "warp(%s %.0fpx)" % (how, amp)


# ----------------------------------------------------------------------------
# model generators: gen(rng, ext, u) -> (field, description)
# ext = nominal pixels the renderer needs to cover, u = size / 256
# ----------------------------------------------------------------------------
def g_perlin(rng, ext, u):
    N = int(ext)
    h, d = perlin_field(rng, N, u)
    return Raster(h), d


def g_fractal_spectral(rng, ext, u):
    N = fast_len(ext)
    beta = rng.uniform(1.6, 3.8)
    rms = loguni(rng, 0.3, 3.0)
    directional = rng.random() < 0.65
    ddir = rng.uniform(0, np.pi) if directional else None
    avar = math.radians(loguni(rng, 3, 50)) if directional else None
    variant = pick(rng, ["fft", "fft", "fft", "sines"])
    if variant == "fft":
        fpeak = bw = None
        if rng.random() < 0.25:
            fpeak, bw = 1.0 / loguni(rng, 8 * u, 60 * u), rng.uniform(0.3, 0.8)
        h = spectral_synthesis(rng, N, beta, ddir, avar, fmin=(1.0 / (loguni(rng, 60, 400) * u)) if rng.random() < 0.5 else 0.0,
                               fpeak=fpeak, bw=bw)
    else:
        nw = int(rng.integers(12, 120))
        h = sum_of_sines(rng, N, beta, nw, ddir, avar if avar else 0.5, N / (120 * u), N / (6 * u))
    h = zs(h) * rms
    d = "spectral(%s) beta=%.2f RMS=%.2f %s" % (variant, beta, rms,
                                              "DDir=%.0f Avar=%.0f" % (math.degrees(ddir), math.degrees(avar)) if directional else "isotropic")
    return Raster(h), d


def g_fractal_oneoverf(rng, ext, u):
    N = fast_len(ext)
    beta = rng.uniform(1.0, 3.5)
    stretch = 1.0 if rng.random() < 0.35 else loguni(rng, 1.5, 8.0)
    sdir = rng.uniform(0, np.pi)
    variant = pick(rng, ["fft", "fft", "octaves"])
    if variant == "fft":
        h = one_over_f(rng, N, beta, stretch, sdir, fmax=(1.0 / (loguni(rng, 1.0, 4.0) * u)) if rng.random() < 0.4 else None)
    else:
        # spatial-domain 1/f^beta: sum of octaves of smoothed white noise,
        # each octave weighted by sigma^((beta-2)/2)*sigma (2D scaling)
        h = np.zeros((N, N))
        sig = 0.7 * u
        c, s = math.cos(sdir), math.sin(sdir)
        while sig < N / 6:
            w = rng.standard_normal((N, N))
            if stretch > 1.01:
                # anisotropic gaussian via rotate-free separable approx in FFT
                fx, fy = _fgrid(N)
                a = fx * c + fy * s
                b = -fx * s + fy * c
                G = np.exp(-2 * (np.pi * sig) ** 2 * ((a * stretch) ** 2 + (b / stretch) ** 2))
                o = np.fft.irfft2(np.fft.rfft2(w) * G, s=(N, N))
            else:
                o = ndimage.gaussian_filter(w, sig, mode="wrap")
            o /= max(o.std(), 1e-12)
            h += o * sig ** ((beta - 2.0) / 2.0)
            sig *= 2.0
    d = "1/f^beta(%s) beta=%.2f stretch=%.1f dir=%.0f" % (variant, beta, stretch, math.degrees(sdir))
    return Raster(h), d


def g_fractal_midpoint(rng, ext, u):
    px = 1.0 if rng.random() < 0.7 else rng.uniform(1.0, 2.0)
    need = ext / px
    M = 1 << int(math.ceil(math.log2(max(need, 16))))
    H = rng.uniform(0.2, 0.95)
    variant = pick(rng, ["diamond-square", "diamond-square", "square-midpoint"])
    sl = int(rng.integers(1, 5)) + max(0, int(math.log2(M / (256 * u))))
    h = diamond_square(rng, M, H, sl, variant)
    d = "%s H=%.2f start=%d px=%.2f" % (variant, H, sl, px)
    return Raster(h, px), d


def g_cellular(rng, ext, u):
    N = int(ext)
    h, d, _, _ = cellular_field(rng, N, u)
    return Raster(h), d


def g_fold_cellular(rng, ext, u):
    N = int(ext)
    h, d, _, _ = cellular_field(rng, N, u, styles=["F1", "F2", "F2-F1", "F3-F1", "F1*F2", "combo", "dome", "cone", "pyramid"],
                                cell=loguni(rng, 24 * u, 110 * u))
    y, fd = fold(rng, h)
    return Raster(y), "fold[%s] of %s" % (fd, d)


def g_fold_fractal(rng, ext, u):
    N = fast_len(ext)
    h, d = fractal_field(rng, N, u, smooth=rng.random() < 0.85)
    if rng.random() < 0.5:
        sg = rng.uniform(0.8, 3.0) * u
        h = ndimage.gaussian_filter(h, sg, mode="wrap")
        d += " blur=%.1f" % sg
    if h.shape[0] != N:
        N = h.shape[0]
    y, fd = fold(rng, h)
    return Raster(y), "fold[%s] of %s" % (fd, d)


def g_fold_perlin(rng, ext, u):
    N = int(ext)
    h, d = perlin_field(rng, N, u, max_oct=5, feat_lo=32)
    y, fd = fold(rng, h)
    return Raster(y), "fold[%s] of %s" % (fd, d)


def g_fold_texton(rng, ext, u):
    # textons drawn on a coarser canvas (px > 1) so that the folded contours
    # inside each texton stay visible
    px = rng.uniform(1.0, 2.5)
    N = int(math.ceil(ext / px))
    h, d = texton_field(rng, N, u, graded=True, kinds=("regular", "grid", "grid", "prob", "add", "add", "walk"))
    if rng.random() < 0.35:
        h = ndimage.gaussian_filter(h, rng.uniform(1, 3) * u, mode="wrap")
    y, fd = fold(rng, h)
    return Raster(y, px), "fold[%s] of %s px=%.2f" % (fd, d, px)


def g_fuse_perlin_cellular(rng, ext, u):
    N = int(ext)
    A, da = perlin_field(rng, N, u)
    B, db, _, _ = cellular_field(rng, N, u)
    op = pick(rng, ["sum", "product", "max", "min", "mask", "warp", "warp", "warp+sum", "diff"])
    if op.startswith("warp"):
        h, wd = warp_by(rng, B, A, u)
        if op == "warp+sum":
            w = rng.uniform(0.15, 0.5)
            h = (1 - w) * zs(h) + w * zs(A)
            wd += "+sum w=%.2f" % w
    else:
        h, wd = fuse(rng, A, B, [op])
    return Raster(h), "%s | A=%s | B=%s" % (wd, da, db)


def g_fuse_perlin_texton(rng, ext, u):
    N = int(ext)
    A, da = perlin_field(rng, N, u)
    op = pick(rng, ["sum", "product", "max", "mask", "warp", "warp", "amp", "screen"])
    if op == "amp":
        # per-texton amplitude / size taken from the Perlin field at its centre
        B, db = texton_field(rng, N, u, kinds=("grid", "prob", "add"))
        h = zs(B) * (0.2 + mm01(A)) + 0.3 * zs(A)
        wd = "texton-amplitude-by-perlin"
    else:
        B, db = texton_field(rng, N, u)
        if op == "warp":
            h, wd = warp_by(rng, B, A, u)
            if rng.random() < 0.5:
                h = zs(h) + rng.uniform(0.1, 0.6) * zs(A)
                wd += "+sum"
        else:
            h, wd = fuse(rng, A, B, [op])
    return Raster(h), "%s | A=%s | B=%s" % (wd, da, db)


def g_fuse_cellular_texton(rng, ext, u):
    N = int(ext)
    A, da, pts, idx = cellular_field(rng, N, u)
    op = pick(rng, ["sum", "product", "max", "min", "mask", "sites", "sites", "cellmask", "warp"])
    if op == "sites":
        # one texton on every Worley feature point, over the cellular relief
        sp = texton_spec(rng)
        cell = math.sqrt(N * N / len(pts))
        R = cell * rng.uniform(0.15, 0.45)
        a0 = rng.uniform(0, TAU)
        rnd = rng.random() < 0.6
        items = [(x, y, R * rng.uniform(0.8, 1.2), rng.uniform(0, TAU) if rnd else a0, sp, 1.0) for (x, y) in pts]
        B = draw_textons(N, items, "max")
        w = rng.uniform(0.3, 0.8)
        h = w * mm01(A) + (1 - w) * B if rng.random() < 0.5 else np.maximum(mm01(A) * w, B)
        wd = "textons-at-sites %s R=%.0f" % (sp["shape"], R)
        db = ""
    elif op == "cellmask":
        B, db = texton_field(rng, N, u, kinds=("grid", "prob", "add", "walk"))
        occ = rng.random(len(pts)) < rng.uniform(0.3, 0.7)
        m = occ[idx[..., 0]].astype(float)
        m = ndimage.gaussian_filter(m, 1.0 * u, mode="wrap")
        h = zs(B) * m + 0.5 * zs(A) * (1 - m)
        wd = "textons-in-random-cells"
    elif op == "warp":
        B, db = texton_field(rng, N, u)
        h, wd = warp_by(rng, B, A, u)
        h = zs(h) + rng.uniform(0.1, 0.6) * zs(A)
    else:
        B, db = texton_field(rng, N, u)
        h, wd = fuse(rng, A, B, [op])
    return Raster(h), "%s | A=%s | B=%s" % (wd, da, db)


def g_texton_regular(rng, ext, u):
    N = int(ext)
    h, d = tex_regular(rng, N, u)
    return Raster(h), d


def g_texton_grid(rng, ext, u):
    N = int(ext)
    h, d = tex_random_grid(rng, N, u)
    return Raster(h), d


def g_texton_walk(rng, ext, u):
    N = int(ext)
    h, d = tex_random_walk(rng, N, u)
    return Raster(h), d


def g_texton_prob(rng, ext, u):
    N = int(ext)
    h, d = tex_probmap(rng, N, u)
    return Raster(h), d


def g_texton_add(rng, ext, u):
    N = int(ext)
    h, d = tex_addition(rng, N, u)
    return Raster(h), d


# ----------------------------------------------------------------------------
# cellular automata
# ----------------------------------------------------------------------------
MOORE = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]
VONN = [(-1, 0), (1, 0), (0, -1), (0, 1)]


def nb_offsets(r, kind):
    out = []
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dx == 0 and dy == 0:
                continue
            if kind == "vn" and abs(dx) + abs(dy) > r:
                continue
            out.append((dy, dx))
    return out


def sim_size(rng, ext, lo, hi, cap):
    px = rng.uniform(lo, hi)
    L = int(math.ceil(ext / px))
    if L > cap:
        L = cap
    return max(L, 32), px


def g_ca_forest(rng, ext, u):
    L, px = sim_size(rng, ext, 1.5 * u, 4.0 * u, 240)
    p = loguni(rng, 0.004, 0.05)
    f = p * loguni(rng, 1e-3, 3e-2)
    nbk = pick(rng, ["vn", "moore"])
    offs = VONN if nbk == "vn" else MOORE
    state = (rng.random((L, L)) < 0.5).astype(np.int8)
    last_burn = -rng.integers(0, int(1 / p) + 1, (L, L)).astype(np.int32)
    grow_t = last_burn.copy()
    steps = int(np.clip(10 / p, 500, 2500))
    for t in range(steps):
        fire = state == 2
        trees = state == 1
        nbf = np.zeros_like(fire)
        if fire.any():
            for dy, dx in offs:
                nbf |= np.roll(np.roll(fire, dy, 0), dx, 1)
        r = rng.random((L, L))
        ign = trees & (nbf | (r < f))
        grow = (state == 0) & (r < p)
        state[fire] = 0
        last_burn[fire] = t
        state[ign] = 2
        state[grow] = 1
        grow_t[grow] = t
    render = pick(rng, ["burn-age", "density", "state", "state", "tree-age"])
    if render == "burn-age":
        h = np.minimum(steps - last_burn, np.percentile(steps - last_burn, 98)).astype(float)
        h = ndimage.gaussian_filter(h, rng.uniform(0.8, 2.0), mode="wrap")
    elif render == "density":
        h = ndimage.gaussian_filter((state == 1).astype(float), rng.uniform(1.2, 3.5), mode="wrap")
    elif render == "state":
        h = np.choose(state, [0.0, 1.0, 0.5])
        h = ndimage.gaussian_filter(h, rng.uniform(0.3, 0.7), mode="wrap")
    else:
        age = np.where(state == 1, steps - grow_t, 0).astype(float)
        h = ndimage.gaussian_filter(np.sqrt(age), rng.uniform(0.6, 1.5), mode="wrap")
    d = "forest-fire p=%.4f f/p=%.1e nb=%s steps=%d L=%d render=%s" % (p, f / p, nbk, steps, L, render)
    return Raster(h, px), d


def g_ca_surface(rng, ext, u):
    L, px = sim_size(rng, ext, 1.0 * u, 3.0 * u, 288)
    for attempt in range(4):
        rule = pick(rng, ["anneal", "anneal", "majority", "vote5x5", "glauber"])
        if rule == "anneal":
            rho = rng.uniform(0.46, 0.54)
        else:
            rho = rng.uniform(0.42, 0.58) if rng.random() < 0.8 else rng.uniform(0.35, 0.65)
        s = (rng.random((L, L)) < rho).astype(np.float32)
        if rule == "anneal":
            steps = int(rng.integers(20, 400))
        elif rule == "majority":
            steps = int(rng.integers(5, 60))
        elif rule == "vote5x5":
            steps = int(rng.integers(5, 80))
        else:
            steps = int(rng.integers(30, 250))
            beta = rng.uniform(0.8, 3.0)
        for t in range(steps):
            if rule == "vote5x5":
                n = np.rint(ndimage.uniform_filter(s, 5, mode="wrap") * 25)
                s = (n >= 13).astype(np.float32)
            else:
                n = np.rint(ndimage.uniform_filter(s, 3, mode="wrap") * 9)
                if rule == "anneal":
                    s = ((n == 4) | (n >= 6)).astype(np.float32)
                elif rule == "majority":
                    s = (n >= 5).astype(np.float32)
                else:
                    pr = 1 / (1 + np.exp(-beta * (n - 4.5)))
                    s = (rng.random((L, L)) < pr).astype(np.float32)
        if 0.12 < s.mean() < 0.88:
            break
    render = pick(rng, ["smooth", "smooth", "distance", "binary"])
    if render == "smooth":
        h = ndimage.gaussian_filter(s.astype(float), rng.uniform(0.7, 2.5), mode="wrap")
    elif render == "distance":
        c = rng.uniform(2, 8)

        def sdt(a):
            return ndimage.distance_transform_edt(a) - ndimage.distance_transform_edt(1 - a)

        h = tile_op(s.astype(float), sdt)
        h = np.clip(h, -c, c)
        h = ndimage.gaussian_filter(h, 0.6, mode="wrap")
    else:
        h = ndimage.gaussian_filter(s.astype(float), 0.5, mode="wrap")
    d = "surface-tension %s rho=%.2f steps=%d L=%d render=%s" % (rule, rho, steps, L, render)
    return Raster(h, px), d


def g_ca_excitable(rng, ext, u):
    L, px = sim_size(rng, ext, 1.2 * u, 2.6 * u, 200)
    kind = pick(rng, ["cyclic", "cyclic", "gh"])
    for attempt in range(3):
        if kind == "cyclic":
            # (range, neighbourhood, threshold, states, steps) chosen from settings that
            # self-organise into spirals / travelling waves (Griffeath's cyclic CA)
            setting = pick(rng, [(1, "vn", 1, (9, 13), (450, 900)), (1, "moore", 3, (3, 3), (220, 500)),
                                 (1, "moore", 3, (4, 4), (300, 600)), (2, "moore", 7, (3, 3), (250, 500)),
                                 (2, "moore", 9, (3, 4), (250, 500)), (2, "vn", 4, (5, 5), (300, 500))])
            r, nbk, thr, (nlo, nhi), (slo, shi) = setting
            n = int(rng.integers(nlo, nhi + 1))
            offs = nb_offsets(r, nbk)
            s = rng.integers(0, n, (L, L)).astype(np.int16)
            steps = int(rng.integers(slo, shi + 1))
            for t in range(steps):
                nxt = (s + 1) % n
                cnt = np.zeros((L, L), np.int16)
                for dy, dx in offs:
                    cnt += np.roll(np.roll(s, dy, 0), dx, 1) == nxt
                s = np.where(cnt >= thr, nxt, s)
            desc = "cyclic-CA n=%d r=%d %s thr=%d steps=%d" % (n, r, nbk, thr, steps)
        else:
            # Greenberg-Hastings: 0 rest, 1 excited, 2..n-1 refractory
            setting = pick(rng, [(2, 3, (5, 8)), (2, 4, (5, 8)), (3, 6, (5, 7)), (2, 2, (5, 6))])
            r, thr, (nlo, nhi) = setting
            n = int(rng.integers(nlo, nhi + 1))
            s = np.where(rng.random((L, L)) < rng.uniform(0.2, 0.45), rng.integers(1, n, (L, L)), 0).astype(np.int16)
            steps = int(rng.integers(150, 400))
            for t in range(steps):
                exc = (s == 1).astype(np.float32)
                cnt = np.rint(ndimage.uniform_filter(exc, 2 * r + 1, mode="wrap") * (2 * r + 1) ** 2 - exc)
                new = np.where(s > 0, (s + 1) % n, np.where(cnt >= thr, 1, 0))
                s = new.astype(np.int16)
            desc = "Greenberg-Hastings n=%d r=%d thr=%d steps=%d" % (n, r, thr, steps)
        if np.std(s) > 0.2 and len(np.unique(s)) > 2:
            break
        kind = "cyclic"
    render = pick(rng, ["phase", "cos", "cos", "state"])
    ph = s.astype(float) / n
    if render == "phase":
        h = ndimage.gaussian_filter(ph, rng.uniform(0.5, 1.2), mode="wrap")
    elif render == "cos":
        c = ndimage.gaussian_filter(np.cos(TAU * ph), rng.uniform(0.5, 1.5), mode="wrap")
        sn = ndimage.gaussian_filter(np.sin(TAU * ph), rng.uniform(0.5, 1.5), mode="wrap")
        h = c if rng.random() < 0.7 else np.arctan2(sn, c)
    else:
        h = ndimage.gaussian_filter((s == 1).astype(float) + 0.3 * ph, 0.7, mode="wrap")
    return Raster(h, px), "%s L=%d render=%s" % (desc, L, render)


# ----------------------------------------------------------------------------
# reaction diffusion (Gray-Scott, Pearson regimes) and Schnakenberg Turing model
# ----------------------------------------------------------------------------
GS_REGIMES = {
    "spots": (0.035, 0.065), "mitosis": (0.0367, 0.0649), "solitons": (0.030, 0.062),
    "coral": (0.0545, 0.062), "maze": (0.029, 0.057), "holes": (0.039, 0.058),
    "worms": (0.046, 0.063), "stripes": (0.042, 0.059), "mixed": (0.022, 0.051),
    "chaotic-spots": (0.018, 0.051), "network": (0.062, 0.0609), "spot-worms": (0.034, 0.0618),
}


def _lap(a):
    return np.roll(a, 1, 0) + np.roll(a, -1, 0) + np.roll(a, 1, 1) + np.roll(a, -1, 1) - 4 * a


def gray_scott(rng, L, F, k, Du, Dv, steps):
    U = np.ones((L, L), np.float32)
    V = np.zeros((L, L), np.float32)
    nseed = max(3, int(L * L / rng.uniform(150, 900)))
    for _ in range(nseed):
        y, x = rng.integers(0, L, 2)
        r = int(rng.integers(2, 5))
        ys = np.arange(y - r, y + r) % L
        xs = np.arange(x - r, x + r) % L
        U[np.ix_(ys, xs)] = 0.5
        V[np.ix_(ys, xs)] = 0.25
    U += (0.02 * rng.standard_normal((L, L))).astype(np.float32)
    V += (0.02 * rng.standard_normal((L, L))).astype(np.float32)
    F = np.float32(F)
    k = np.float32(k)
    for t in range(steps):
        uvv = U * V * V
        U += Du * _lap(U) - uvv + F * (1 - U)
        V += Dv * _lap(V) + uvv - (F + k) * V
    return U, V


def schnakenberg(rng, L, a, b, d, steps, dt, scale):
    """u_t = lap u + g(a - u + u^2 v), v_t = d lap v + g(b - u^2 v); semi-implicit FFT."""
    u0 = a + b
    v0 = b / (a + b) ** 2
    U = u0 + 0.05 * rng.standard_normal((L, L))
    V = v0 + 0.05 * rng.standard_normal((L, L))
    fy = np.fft.fftfreq(L)[:, None]
    fx = np.fft.rfftfreq(L)[None, :]
    k2 = (TAU ** 2) * (fx ** 2 + fy ** 2) / scale ** 2
    du = 1.0 / (1 + dt * k2)
    dv = 1.0 / (1 + dt * d * k2)
    g = 1.0
    for t in range(steps):
        f = a - U + U * U * V
        gg = b - U * U * V
        U = np.fft.irfft2(np.fft.rfft2(U + dt * g * f) * du, s=(L, L))
        V = np.fft.irfft2(np.fft.rfft2(V + dt * g * gg) * dv, s=(L, L))
    return U, V


def g_reaction_diffusion(rng, ext, u):
    system = pick(rng, ["gray-scott"] * 5 + ["schnakenberg"])
    if system == "gray-scott":
        for attempt in range(3):
            L, px = sim_size(rng, ext, 1.2 * u, 3.2 * u, 150)
            name = pick(rng, list(GS_REGIMES))
            F, k = GS_REGIMES[name]
            F *= rng.uniform(0.97, 1.03)
            k *= rng.uniform(0.99, 1.01)
            Du = rng.uniform(0.16, 0.22)
            Dv = Du * rng.uniform(0.45, 0.55)
            steps = int(rng.integers(3000, 6000))
            U, V = gray_scott(rng, L, F, k, np.float32(Du), np.float32(Dv), steps)
            if V.std() > 0.02 and np.isfinite(V).all():
                break
        field = V if rng.random() < 0.6 else -U
        h = field.astype(float)
        if rng.random() < 0.3:
            h = ndimage.gaussian_filter(h, 0.7, mode="wrap")
        d = "gray-scott %s F=%.4f k=%.4f Du=%.2f steps=%d L=%d" % (name, F, k, Du, steps, L)
    else:
        L, px = sim_size(rng, ext, 1.0 * u, 2.5 * u, 144)
        a, b = rng.uniform(0.03, 0.1), 0.9
        dd = rng.uniform(12, 30)
        scale = rng.uniform(0.5, 0.9)
        U, V = schnakenberg(rng, L, a, b, dd, int(rng.integers(1300, 2000)), 0.08, scale)
        h = U if rng.random() < 0.65 else -U
        d = "schnakenberg spots a=%.2f b=%.2f d=%.0f scale=%.2f L=%d" % (a, b, dd, scale, L)
    return Raster(h, px), d


# ----------------------------------------------------------------------------
# Islamic star patterns (Hankin polygons-in-contact on Archimedean tilings)
# ----------------------------------------------------------------------------
def reg_poly(c, n, side, mid_angle):
    R = side / (2 * math.sin(math.pi / n))
    return [(c[0] + R * math.cos(mid_angle + (2 * k - 1) * math.pi / n),
             c[1] + R * math.sin(mid_angle + (2 * k - 1) * math.pi / n)) for k in range(n)]


def tiling(name):
    if name == "4.4.4.4":
        a1, a2 = (1.0, 0.0), (0.0, 1.0)
        polys = [reg_poly((0.5, 0.5), 4, 1, 0)]
    elif name == "6.6.6":
        a1, a2 = (SQ3, 0.0), (SQ3 / 2, 1.5)
        polys = [reg_poly((0, 0), 6, 1, 0)]
    elif name == "3.3.3.3.3.3":
        a1, a2 = (1.0, 0.0), (0.5, SQ3 / 2)
        polys = [reg_poly((0.5, SQ3 / 6), 3, 1, -math.pi / 2), reg_poly((1.0, SQ3 / 3), 3, 1, math.pi / 2)]
    elif name == "4.8.8":
        w = 1 + math.sqrt(2)
        a1, a2 = (w, 0.0), (0.0, w)
        polys = [reg_poly((0, 0), 8, 1, 0), reg_poly((w / 2, w / 2), 4, 1, math.pi / 4)]
    elif name == "3.6.3.6":
        a1, a2 = (2.0, 0.0), (1.0, SQ3)
        polys = [reg_poly((0, 0), 6, 1, math.pi / 6), reg_poly((1.0, SQ3 / 3), 3, 1, math.pi / 2),
                 reg_poly((2.0, 2 * SQ3 / 3), 3, 1, -math.pi / 2)]
    elif name == "3.12.12":
        L = 2 + SQ3
        a1, a2 = (L, 0.0), (L / 2, L * SQ3 / 2)
        polys = [reg_poly((0, 0), 12, 1, 0), reg_poly((L / 2, L / (2 * SQ3)), 3, 1, 7 * math.pi / 6),
                 reg_poly((L, L / SQ3), 3, 1, -math.pi / 2)]
    elif name == "4.6.12":
        L = 3 + SQ3
        a1, a2 = (L, 0.0), (L / 2, L * SQ3 / 2)
        polys = [reg_poly((0, 0), 12, 1, 0),
                 reg_poly((L / 2, 0), 4, 1, 0), reg_poly((L / 4, L * SQ3 / 4), 4, 1, math.pi / 3),
                 reg_poly((-L / 4, L * SQ3 / 4), 4, 1, 2 * math.pi / 3),
                 reg_poly((L / 2, L / (2 * SQ3)), 6, 1, math.pi / 6),
                 reg_poly((L, L / SQ3), 6, 1, math.pi / 6)]
    else:
        raise ValueError(name)
    return np.array([a1, a2]).T, polys


def hankin_segments(polys, theta, delta):
    segs = []
    for V in polys:
        V = np.array(V)
        n = len(V)
        C = V.mean(0)
        Rm = np.max(np.hypot(*(V - C).T))
        E = [V[(i + 1) % n] - V[i] for i in range(n)]
        for i in range(n):
            j = (i + 1) % n
            e1 = E[i] / np.linalg.norm(E[i])
            e2 = E[j] / np.linalg.norm(E[j])
            m1 = 0.5 * (V[i] + V[j]) + delta * e1
            m2 = 0.5 * (V[j] + V[(j + 1) % n]) - delta * e2
            n1 = np.array([-e1[1], e1[0]])
            if np.dot(n1, C - m1) < 0:
                n1 = -n1
            n2 = np.array([-e2[1], e2[0]])
            if np.dot(n2, C - m2) < 0:
                n2 = -n2
            d1 = math.cos(theta) * e1 + math.sin(theta) * n1
            d2 = -math.cos(theta) * e2 + math.sin(theta) * n2
            M = np.array([d1, -d2]).T
            if abs(np.linalg.det(M)) < 1e-9:
                continue
            t, s = np.linalg.solve(M, m2 - m1)
            P = m1 + t * d1
            if t <= 0 or s <= 0 or np.hypot(*(P - C)) > Rm * 1.05:
                P = C.copy()
            segs.append((m1, P))
            segs.append((m2, P))
    return segs


def seg_distance(Wx, Wy, segs, Lm):
    """min distance from points to all segments and their lattice images."""
    Linv = np.linalg.inv(Lm)
    fx = Linv[0, 0] * Wx + Linv[0, 1] * Wy
    fy = Linv[1, 0] * Wx + Linv[1, 1] * Wy
    fx -= np.floor(fx)
    fy -= np.floor(fy)
    X = Lm[0, 0] * fx + Lm[0, 1] * fy
    Y = Lm[1, 0] * fx + Lm[1, 1] * fy
    d2 = np.full(X.shape, np.inf)
    for (A, B) in segs:
        for i in (-1, 0, 1):
            for j in (-1, 0, 1):
                off = Lm[:, 0] * i + Lm[:, 1] * j
                ax, ay = A[0] + off[0], A[1] + off[1]
                bx, by = B[0] + off[0], B[1] + off[1]
                vx, vy = bx - ax, by - ay
                ll = vx * vx + vy * vy
                px_, py_ = X - ax, Y - ay
                if ll < 1e-12:
                    dd = px_ * px_ + py_ * py_
                else:
                    t = np.clip((px_ * vx + py_ * vy) / ll, 0, 1)
                    qx, qy = px_ - t * vx, py_ - t * vy
                    dd = qx * qx + qy * qy
                np.minimum(d2, dd, out=d2)
    return np.sqrt(d2)


def g_islamic(rng, ext, u):
    name = pick(rng, ["4.4.4.4", "6.6.6", "3.3.3.3.3.3", "4.8.8", "3.6.3.6", "3.12.12", "4.6.12"],
                [0.18, 0.18, 0.1, 0.18, 0.12, 0.1, 0.14])
    Lm, polys = tiling(name)
    theta = math.radians(pick(rng, [30, 36, 45, 54, 60, 67.5, 72]) + rng.uniform(-4, 4)) \
        if rng.random() < 0.7 else math.radians(rng.uniform(25, 78))
    delta = 0.0 if rng.random() < 0.65 else rng.uniform(0.03, 0.2)
    segs = hankin_segments(polys, theta, delta)
    # drop duplicate-ish segments
    cell_len = math.sqrt(abs(np.linalg.det(Lm)))
    unit = loguni(rng, 40 * u, 140 * u) / cell_len  # px per tiling unit
    w = loguni(rng, 1.2 * u, 7 * u)  # band half width in px
    style = pick(rng, ["band", "round", "outline", "groove", "cushion", "regions"], [0.2, 0.2, 0.18, 0.12, 0.15, 0.15])
    extra_lines = rng.random() < 0.2  # also show underlying tiling edges faintly

    edge_segs = []
    if extra_lines:
        for V in polys:
            for i in range(len(V)):
                edge_segs.append((np.array(V[i]), np.array(V[(i + 1) % len(V)])))

    def f(X, Y):
        d = seg_distance(X / unit, Y / unit, segs, Lm) * unit
        if style == "band":
            h = smoothstep(w + 0.7, w - 0.7, d)
        elif style == "round":
            h = np.sqrt(np.clip(1 - (d / w) ** 2, 0, 1))
        elif style == "outline":
            w2 = max(0.8, w * rng.uniform(0.25, 0.5))
            h = smoothstep(w + w2 + 0.7, w + w2 - 0.7, d) - smoothstep(w - w2 + 0.7, w - w2 - 0.7, d) * 0.8
        elif style == "groove":
            h = -np.sqrt(np.clip(1 - (d / w) ** 2, 0, 1))
        elif style == "cushion":
            c = w * rng.uniform(2, 5)
            h = np.sqrt(np.clip(d, 0, c) / c)
        else:
            inside = d > w
            lab, nl = ndimage.label(inside)
            areas = ndimage.sum(np.ones_like(d), lab, index=np.arange(1, nl + 1))
            q = np.log1p(areas)
            q = (q - q.min()) / max(q.max() - q.min(), 1e-9)
            lvl = rng.uniform(0.3, 1.0, 6)
            val = np.concatenate([[0.0], lvl[np.minimum((q * 5.99).astype(int), 5)]])
            h = val[lab] * smoothstep(w, w + 1.5, d)
            h = ndimage.gaussian_filter(h, 0.6)
        if extra_lines:
            de = seg_distance(X / unit, Y / unit, edge_segs, Lm) * unit
            h = h - 0.35 * smoothstep(1.5, 0.3, de)
        return h

    return Func(f), "islamic %s contact=%.1f delta=%.2f cell=%.0fpx width=%.1f style=%s%s" % (
        name, math.degrees(theta), delta, unit * cell_len, w, style, " +tiling" if extra_lines else "")


# ----------------------------------------------------------------------------
# Matrix transformation: motif repeated by the matrices of a wallpaper group
# ----------------------------------------------------------------------------
def _rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


MX = np.array([[-1.0, 0.0], [0.0, 1.0]])  # x -> -x
MY = np.array([[1.0, 0.0], [0.0, -1.0]])  # y -> -y


def wallpaper(name, rng):
    """Return lattice matrix (columns a1,a2) and generators (A, b) in cartesian coords."""
    I = np.eye(2)
    z = np.zeros(2)
    if name in ("p1", "p2"):
        r = rng.uniform(0.7, 1.4)
        ang = rng.uniform(math.radians(62), math.radians(88))
        Lm = np.array([[1.0, r * math.cos(ang)], [0.0, r * math.sin(ang)]])
        gens = [] if name == "p1" else [(-I, z)]
    elif name in ("pm", "pg", "pmm", "pmg", "pgg"):
        a, b = 1.0, rng.uniform(0.6, 1.6)
        Lm = np.array([[a, 0.0], [0.0, b]])
        gens = {"pm": [(MX, z)], "pg": [(MX, np.array([0, b / 2]))],
                "pmm": [(MX, z), (MY, z)], "pmg": [(-I, z), (MX, np.array([a / 2, 0]))],
                "pgg": [(-I, z), (MX, np.array([a / 2, b / 2]))]}[name]
    elif name in ("cm", "cmm"):
        a, b = 1.0, rng.uniform(1.2, 2.6)
        Lm = np.array([[a, a / 2], [0.0, b / 2]])
        gens = [(MX, z)] if name == "cm" else [(MX, z), (MY, z)]
    elif name in ("p4", "p4m", "p4g"):
        Lm = np.eye(2)
        R4 = _rot(math.pi / 2)
        gens = {"p4": [(R4, z)], "p4m": [(R4, z), (MX, z)], "p4g": [(R4, z), (MX, np.array([0.5, 0.5]))]}[name]
    else:
        Lm = np.array([[1.0, 0.5], [0.0, SQ3 / 2]])
        R3, R6 = _rot(TAU / 3), _rot(TAU / 6)
        gens = {"p3": [(R3, z)], "p3m1": [(R3, z), (MX, z)], "p31m": [(R3, z), (MY, z)],
                "p6": [(R6, z)], "p6m": [(R6, z), (MX, z)]}[name]
    return Lm, gens


def group_closure(Lm, gens):
    Linv = np.linalg.inv(Lm)

    def red(A, b):
        f = Linv @ b
        f -= np.floor(f + 1e-9)
        return A, Lm @ f

    def key(A, b):
        f = Linv @ b
        f -= np.floor(f + 1e-6)
        return tuple(np.round(A, 4).ravel()) + tuple(np.round(f, 4) % 1.0)

    elems = {key(np.eye(2), np.zeros(2)): (np.eye(2), np.zeros(2))}
    frontier = list(elems.values())
    while frontier:
        new = []
        for (A, b) in frontier:
            for (G, c) in gens:
                A2, b2 = red(G @ A, G @ b + c)
                k = key(A2, b2)
                if k not in elems:
                    elems[k] = (A2, b2)
                    new.append((A2, b2))
        frontier = new
        if len(elems) > 48:
            break
    return list(elems.values())


def g_matrix(rng, ext, u):
    name = pick(rng, ["p1", "p2", "pm", "pg", "cm", "pmm", "pmg", "pgg", "cmm", "p4", "p4m", "p4g",
                      "p3", "p3m1", "p31m", "p6", "p6m"])
    Lm, gens = wallpaper(name, rng)
    ops = group_closure(Lm, gens)
    cell_px = loguni(rng, 40 * u, 130 * u)
    unit = cell_px / math.sqrt(abs(np.linalg.det(Lm)))
    K = int(rng.integers(1, 5))
    prims = []
    for _ in range(K):
        typ = pick(rng, ["blob", "blob", "stroke", "ring"])
        c = Lm @ rng.uniform(0, 1, 2)
        amp = rng.uniform(0.4, 1.0) * (1 if rng.random() < 0.85 else -1)
        if typ == "blob":
            s1 = rng.uniform(0.03, 0.14)
            s2 = s1 * rng.uniform(0.25, 1.0)
            ang = rng.uniform(0, np.pi)
            Rm = _rot(ang)
            Cov = Rm @ np.diag([s1 * s1, s2 * s2]) @ Rm.T
            prims.append(("blob", c, Cov, amp))
        elif typ == "stroke":
            ln = rng.uniform(0.1, 0.45)
            ang = rng.uniform(0, np.pi)
            dvec = 0.5 * ln * np.array([math.cos(ang), math.sin(ang)])
            wdt = rng.uniform(0.012, 0.05)
            prims.append(("stroke", c - dvec, c + dvec, wdt, amp))
        else:
            prims.append(("ring", c, rng.uniform(0.05, 0.18), rng.uniform(0.01, 0.04), amp))
    # orbit of the motif under the group
    orbit = []
    for (A, b) in ops:
        for p in prims:
            if p[0] == "blob":
                orbit.append(("blob", A @ p[1] + b, A @ p[2] @ A.T, p[3]))
            elif p[0] == "stroke":
                orbit.append(("stroke", A @ p[1] + b, A @ p[2] + b, p[3], p[4]))
            else:
                orbit.append(("ring", A @ p[1] + b, p[2], p[3], p[4]))
    combine = pick(rng, ["sum", "sum", "max"])
    Linv = np.linalg.inv(Lm)

    def f(X, Y):
        Wx, Wy = X / unit, Y / unit
        h = np.zeros(X.shape) if combine == "sum" else np.full(X.shape, -1e9)
        for p in orbit:
            c = p[1]
            fx = Linv[0, 0] * (Wx - c[0]) + Linv[0, 1] * (Wy - c[1])
            fy = Linv[1, 0] * (Wx - c[0]) + Linv[1, 1] * (Wy - c[1])
            fx -= np.floor(fx)
            fy -= np.floor(fy)
            acc = None
            for i in (0, -1):
                for j in (0, -1):
                    dx = Lm[0, 0] * (fx + i) + Lm[0, 1] * (fy + j)
                    dy = Lm[1, 0] * (fx + i) + Lm[1, 1] * (fy + j)
                    if p[0] == "blob":
                        Ci = np.linalg.inv(p[2])
                        q = Ci[0, 0] * dx * dx + 2 * Ci[0, 1] * dx * dy + Ci[1, 1] * dy * dy
                        v = p[3] * np.exp(-0.5 * q)
                    elif p[0] == "stroke":
                        a, b_ = p[1] - c, p[2] - c
                        vx, vy = b_[0] - a[0], b_[1] - a[1]
                        t = np.clip(((dx - a[0]) * vx + (dy - a[1]) * vy) / (vx * vx + vy * vy), 0, 1)
                        qx, qy = dx - a[0] - t * vx, dy - a[1] - t * vy
                        v = p[4] * np.sqrt(np.clip(1 - (qx * qx + qy * qy) / p[3] ** 2, 0, 1))
                    else:
                        r = np.hypot(dx, dy)
                        v = p[4] * np.exp(-0.5 * ((r - p[2]) / p[3]) ** 2)
                    acc = v if acc is None else (acc + v if combine == "sum" else np.maximum(acc, v))
            h = h + acc if combine == "sum" else np.maximum(h, acc)
        return h

    return Func(f), "wallpaper %s |G|=%d motif=%s cell=%.0fpx combine=%s" % (
        name, len(ops), "+".join(p[0] for p in prims), cell_px, combine)


GENERATORS = {
    "CA (Excitable media model)": g_ca_excitable,
    "CA (Forest fire model)": g_ca_forest,
    "CA (Surface tension model)": g_ca_surface,
    "Cellular": g_cellular,
    "Folding of Cellular": g_fold_cellular,
    "Folding of Fractal": g_fold_fractal,
    "Folding of Perlin noise": g_fold_perlin,
    "Folding of Texton Placement": g_fold_texton,
    "Fractal (Fourier spectral synthesis)": g_fractal_spectral,
    "Fractal (midpoint displacement)": g_fractal_midpoint,
    "Fractal (one-over-f-beta noise)": g_fractal_oneoverf,
    "Fusion of Cellular and Texton": g_fuse_cellular_texton,
    "Fusion of Perlin and Cellular": g_fuse_perlin_cellular,
    "Fusion of Perlin and Texton": g_fuse_perlin_texton,
    "Islamic Patterns": g_islamic,
    "Matrix Transformation": g_matrix,
    "Perlin noise": g_perlin,
    "Reaction Diffusion": g_reaction_diffusion,
    "Texton Addition": g_texton_add,
    "Texton probability map": g_texton_prob,
    "Texton random grid": g_texton_grid,
    "Texton random walk": g_texton_walk,
    "Texton regular": g_texton_regular,
}


# ----------------------------------------------------------------------------
# renderer
# ----------------------------------------------------------------------------
def sample_field(field, rng, S, scale, theta):
    c = np.arange(S) - S / 2 + 0.5
    yy, xx = np.meshgrid(c, c, indexing="ij")
    ct, st = math.cos(theta), math.sin(theta)
    X = (ct * xx - st * yy) / scale
    Y = (st * xx + ct * yy) / scale
    if isinstance(field, Raster):
        a = field.a
        px = field.px
        eff = scale * px  # output pixels per raster cell
        if eff < 1.0:
            a = ndimage.gaussian_filter(a, 0.5 * math.sqrt(1.0 / eff ** 2 - 1.0), mode="wrap")
        oy, ox = rng.uniform(0, a.shape[0]), rng.uniform(0, a.shape[1])
        return ndimage.map_coordinates(a, [Y / px + oy, X / px + ox], order=3, mode="grid-wrap")
    ox, oy = rng.uniform(-500, 500, 2)
    return field.f(X + ox, Y + oy)


def render(field, rng, S, scale, theta):
    H = sample_field(field, rng, S, scale, theta)
    h = pct01(H, 0.2, 99.8)
    inv = rng.random() < 0.2
    if inv:
        h = 1 - h
    mode = pick(rng, ["lambert", "halflambert", "phong", "ao", "height", "mixed"], [0.3, 0.15, 0.15, 0.12, 0.16, 0.12])
    az = rng.uniform(0, TAU)
    el = math.radians(rng.uniform(15, 75))
    slope_deg = rng.uniform(20, 70)
    desc = "render=%s" % mode
    if mode != "height":
        gy, gx = np.gradient(h)
        g = np.hypot(gx, gy)
        g90 = float(np.percentile(g, 90))
        if g90 < 1e-9:
            g90 = float(g.max()) + 1e-9
        k = math.tan(math.radians(slope_deg)) / g90
        nx, ny, nz = -k * gx, -k * gy, np.ones_like(h)
        nn = np.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / nn, ny / nn, nz / nn
        lx, ly, lz = math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)
        ndl = nx * lx + ny * ly + nz * lz
        amb = rng.uniform(0.0, 0.35)
        if mode == "halflambert":
            wrap_ = rng.uniform(0.3, 1.0)
            I = np.clip((ndl + wrap_) / (1 + wrap_), 0, 1) ** rng.uniform(1.0, 2.0)
        else:
            I = amb + (1 - amb) * np.clip(ndl, 0, 1)
        if mode == "phong":
            hx, hy, hz = lx, ly, lz + 1.0
            hn = math.sqrt(hx * hx + hy * hy + hz * hz)
            ndh = np.clip((nx * hx + ny * hy + nz * hz) / hn, 0, 1)
            I = I + rng.uniform(0.1, 0.5) * ndh ** rng.uniform(8, 60)
        elif mode == "ao":
            ao = rng.uniform(0.2, 0.6)
            I = I * (1 - ao + ao * h)
        elif mode == "mixed":
            w = rng.uniform(0.25, 0.6)
            I = (1 - w) * I + w * h
        desc += " az=%.0f el=%.0f slope=%.0f" % (math.degrees(az), math.degrees(el), slope_deg)
    else:
        I = h
    if inv:
        desc += " inverted"
    lo, hi = rng.uniform(0, 1.5), 100 - rng.uniform(0, 1.5)
    I = pct01(I, lo, hi)
    gamma = loguni(rng, 0.6, 1.7)
    I = I ** gamma
    o0, o1 = rng.uniform(0, 0.12), rng.uniform(0.88, 1.0)
    I = o0 + (o1 - o0) * I
    hist = np.histogram(I, bins=64, range=(0, 1))[0]
    flat_frac = hist.max() / I.size
    if rng.random() < 0.5:
        I = ndimage.gaussian_filter(I, rng.uniform(0.3, 1.0))
    if rng.random() < 0.6:
        I = I + rng.normal(0, rng.uniform(0.003, 0.025), I.shape)
    img = np.clip(np.rint(I * 255), 0, 255).astype(np.uint8)
    desc += " gamma=%.2f scale=%.2f rot=%.0f" % (gamma, scale, math.degrees(theta))
    return img, desc, flat_frac


def image_ok(img):
    f = img.astype(float)
    if f.std() < 10:
        return False
    sat = np.mean((img <= 1) | (img >= 254))
    if sat > 0.3:
        return False
    # not dominated by a single grey value
    hist = np.bincount(img.ravel(), minlength=256)
    if hist.max() > 0.6 * img.size:
        return False
    return True


def make_image(seed, mi, ii, S):
    rng = np.random.default_rng([int(seed), int(mi), int(ii)])
    gen = GENERATORS[MODELS[mi]]
    u = S / 256.0
    img, desc = None, ""
    for attempt in range(6):
        scale = loguni(rng, 0.5, 2.0)
        theta = rng.uniform(0, TAU)
        ext = int(math.ceil(S * (abs(math.cos(theta)) + abs(math.sin(theta))) / scale)) + 6
        field, fdesc = gen(rng, ext, u)
        img, rdesc, flat_frac = render(field, rng, S, scale, theta)
        desc = "%s; %s" % (fdesc, rdesc)
        if image_ok(img) and flat_frac < 0.93:
            break
        desc += "; (retry %d)" % (attempt + 1)
    return img, desc


def slug(s):
    out = "".join(ch.lower() if ch.isalnum() else "_" for ch in s)
    while "__" in out:
        out = out.replace("__", "_")
    return out.strip("_")


def _work(args):
    seed, mi, ii, S, outdir = args
    t0 = time.time()
    img, desc = make_image(seed, mi, ii, S)
    fn = "%02d_%s_%03d.png" % (mi, slug(MODELS[mi]), ii)
    Image.fromarray(img, mode="L").save(os.path.join(outdir, fn))
    return fn, MODELS[mi], desc, time.time() - t0


# rough relative costs: start slow jobs first for better load balance
SLOW = {"Reaction Diffusion": 5, "CA (Forest fire model)": 4, "CA (Excitable media model)": 3,
        "Islamic Patterns": 2, "Matrix Transformation": 2, "Texton Addition": 2,
        "Folding of Texton Placement": 2, "Fusion of Cellular and Texton": 2, "Fusion of Perlin and Texton": 2}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--per-model", type=int, required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--models", type=str, default=None, help="comma separated model indices (debug)")
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)
    mids = range(len(MODELS)) if a.models is None else [int(x) for x in a.models.split(",")]
    tasks = [(a.seed, mi, ii, a.size, a.out_dir) for mi in mids for ii in range(a.per_model)]
    tasks.sort(key=lambda t: -SLOW.get(MODELS[t[1]], 1))
    t0 = time.time()
    rows = []
    times = {}
    if a.jobs <= 1:
        it = map(_work, tasks)
        for r in it:
            rows.append(r)
    else:
        import multiprocessing as mp
        ctx = mp.get_context("fork")
        with ctx.Pool(a.jobs) as pool:
            for r in pool.imap_unordered(_work, tasks, chunksize=1):
                rows.append(r)
    rows.sort(key=lambda r: r[0])
    with open(os.path.join(a.out_dir, "labels.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["file", "model", "split", "variant"])
        for fn, model, desc, dt in rows:
            w.writerow([fn, model, "validation", desc])
            times.setdefault(model, []).append(dt)
    el = time.time() - t0
    print("wrote %d images to %s in %.1f s" % (len(rows), a.out_dir, el))
    for m in sorted(times, key=lambda m: -np.mean(times[m])):
        print("  %-40s mean %.2f s  max %.2f s" % (m, np.mean(times[m]), np.max(times[m])))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Independent cross-implementation test set of procedural textures.

Writes 368 images (23 models x 16: 8 validation + 8 test), 256x256 8-bit
greyscale PNG, plus labels.csv (file,model,split,variant) and render.csv
(the per-image shading parameters) into an output folder.

Every generator here was written from the PCN paper's model list and from
general literature knowledge of each procedural family, NOT from Filigree's
own generators.  Each generator makes a HEIGHT FIELD; render() then turns it
into a grey image with its own randomised shading / scale / rotation.

Usage:  python3 bench/texture-xset/make_set.py [OUT_DIR] [--jobs N]
        (default OUT_DIR: target/texture-xset relative to the repo root)

Deterministic: every image uses its own numpy Generator seeded from
(BASE_SEED, model index, split, image index), so the output does not depend
on the number of worker processes or on the order of work.
Dependencies: numpy, scipy, Pillow only.
"""

import argparse
import csv
import math
import os
import sys
import time

import numpy as np
from PIL import Image
from scipy import ndimage
from scipy.spatial import cKDTree

SIZE = 256
BASE_SEED = 0x7E57_5E7  # "test set"
PER_SPLIT = 8
SPLITS = ("validation", "test")

MODELS = [
    "CA (Forest fire model)",
    "CA (Surface tension model)",
    "CA (Excitable media model)",
    "Cellular",
    "Folding of Texton Placement",
    "Folding of Cellular",
    "Folding of Fractal",
    "Folding of Perlin noise",
    "Fusion of Cellular and Texton",
    "Fusion of Perlin and Cellular",
    "Fusion of Perlin and Texton",
    "Fractal (one-over-f-beta noise)",
    "Fractal (Fourier spectral synthesis)",
    "Fractal (midpoint displacement)",
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


# ---------------------------------------------------------------------------
# small helpers
# ---------------------------------------------------------------------------

def loguniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def norm01(h, lo_pct=0.5, hi_pct=99.5):
    """Robustly rescale to [0, 1] (percentile based, clipped)."""
    h = np.asarray(h, dtype=np.float64)
    lo, hi = np.percentile(h, [lo_pct, hi_pct])
    if hi - lo < 1e-12:
        lo, hi = h.min(), h.max()
        if hi - lo < 1e-12:
            return np.zeros_like(h)
    return np.clip((h - lo) / (hi - lo), 0.0, 1.0)


def grid_size(need, lo=64, hi=512, mult=16):
    g = int(math.ceil(need / mult) * mult)
    return int(min(hi, max(lo, g)))


def pow2_at_least(n, lo=64, hi=512):
    p = lo
    while p < n and p < hi:
        p *= 2
    return p


def ca_cells(h, c):
    """CA lattice -> height field: cells become c x c blocks, lightly
    smoothed so that resampling does not alias the block edges."""
    return ndimage.gaussian_filter(upsample_nearest(h, c), 0.3 + 0.25 * c,
                                   mode="wrap")


def upsample_nearest(a, c):
    if c == 1:
        return a
    return np.kron(a, np.ones((c, c), dtype=a.dtype))


def fold(h, nfold, offset):
    """Triangle-wave folding of a normalised height: the height axis is
    folded back on itself nfold times (nfold=1, offset=.5 -> |h-.5|)."""
    x = norm01(h, 1.0, 99.0) * nfold + offset
    return np.abs(np.mod(x, 2.0) - 1.0)


# ---------------------------------------------------------------------------
# Perlin gradient noise (periodic, permutation-hashed gradients, quintic fade)
# ---------------------------------------------------------------------------

_GRAD8 = np.array([[1, 0], [-1, 0], [0, 1], [0, -1],
                   [1, 1], [-1, 1], [1, -1], [-1, -1]], dtype=np.float64)
_GRAD8[4:] /= math.sqrt(2.0)


def _fade(t):
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def perlin_layer(G, period, perm):
    """One octave of 2-D Perlin noise on a GxG grid with `period` lattice
    cells across the image (tiles seamlessly)."""
    c = (np.arange(G) + 0.5) * period / G
    i0 = np.floor(c).astype(np.int64)
    f = c - i0
    i1 = (i0 + 1) % period
    i0 = i0 % period
    fy = f[:, None]
    fx = f[None, :]

    def corner(iy, ix, oy, ox):
        g = _GRAD8[perm[(perm[ix & 255] + iy) & 255] & 7]
        return g[..., 0] * (fx - ox) + g[..., 1] * (fy - oy)

    n00 = corner(i0[:, None], i0[None, :], 0, 0)
    n01 = corner(i0[:, None], i1[None, :], 0, 1)
    n10 = corner(i1[:, None], i0[None, :], 1, 0)
    n11 = corner(i1[:, None], i1[None, :], 1, 1)
    u = _fade(fx)
    v = _fade(fy)
    a = n00 + u * (n01 - n00)
    b = n10 + u * (n11 - n10)
    return (a + v * (b - a)) * math.sqrt(2.0)


def perlin_fbm(rng, G, cell_px, octaves, persistence, turbulence=False,
               lacunarity=2):
    base = max(1, int(round(G / cell_px)))
    total = np.zeros((G, G))
    amp, norm = 1.0, 0.0
    used = 0
    for o in range(octaves):
        period = base * lacunarity ** o
        if period > G // 2 or period > 256:
            break
        n = perlin_layer(G, period, rng.permutation(256))
        total += amp * (np.abs(n) if turbulence else n)
        norm += amp
        amp *= persistence
        used += 1
    return total / max(norm, 1e-9), used


# ---------------------------------------------------------------------------
# Worley / cellular noise (periodic feature points, KD-tree)
# ---------------------------------------------------------------------------

def worley(rng, G, cell_px, k=3, metric=2.0, jitter_grid=False):
    n = max(3, int(round((G / cell_px) ** 2)))
    if jitter_grid:
        m = max(2, int(round(math.sqrt(n))))
        n = m * m
        gy, gx = np.mgrid[0:m, 0:m]
        pts = (np.stack([gy.ravel(), gx.ravel()], 1)
               + rng.uniform(0, 1, (n, 2))) * (G / m)
    else:
        pts = rng.uniform(0, G, (n, 2))
    offs = np.array([(dy, dx) for dy in (-G, 0, G) for dx in (-G, 0, G)],
                    dtype=np.float64)
    allp = (pts[None, :, :] + offs[:, None, :]).reshape(-1, 2)
    ids = np.tile(np.arange(n), 9)
    tree = cKDTree(allp)
    yy, xx = np.mgrid[0:G, 0:G] + 0.5
    q = np.stack([yy.ravel(), xx.ravel()], 1)
    d, idx = tree.query(q, k=k, p=metric)
    return d.reshape(G, G, k), ids[idx].reshape(G, G, k), n


def cellular_height(rng, G, kind, cell_px, metric):
    d, ids, n = worley(rng, G, cell_px, k=3, metric=metric,
                       jitter_grid=(rng.random() < 0.25))
    F1, F2 = d[..., 0], d[..., 1]
    if kind == "F1 faceted":
        h = F1 if rng.random() < 0.5 else -F1
    elif kind == "F1 domed":
        rho = F1 / (0.5 * (F1 + F2) + 1e-9)
        h = np.sqrt(np.clip(1 - rho ** 2, 0, 1))
        if rng.random() < 0.3:
            h = -h
    elif kind == "F2 faceted":
        h = F2 if rng.random() < 0.6 else -F2
    elif kind == "F2 domed":
        h = (F2 / F2.max()) ** 2
    elif kind == "F2-F1 faceted":
        h = F2 - F1
    elif kind == "F2-F1 flat":
        bw = rng.uniform(1.5, 0.25 * cell_px)
        h = np.clip((F2 - F1) / bw, 0, 1)
    elif kind == "flat mosaic":
        bw = rng.uniform(1.0, 4.0)
        cellh = rng.uniform(0.2, 1.0, n)
        h = cellh[ids[..., 0]] * np.clip((F2 - F1) / bw, 0, 1)
    elif kind == "F3-F1 faceted":
        h = d[..., 2] - F1
    else:
        raise ValueError(kind)
    return h, n


CELL_KINDS = ["F1 faceted", "F1 domed", "F2 faceted", "F2 domed",
              "F2-F1 faceted", "F2-F1 flat", "flat mosaic", "F3-F1 faceted"]
METRICS = {2.0: "euclidean", 1.0: "manhattan", np.inf: "chebyshev"}


def draw_metric(rng):
    r = rng.random()
    return 2.0 if r < 0.65 else (1.0 if r < 0.85 else np.inf)


# ---------------------------------------------------------------------------
# spectral fractals and midpoint displacement
# ---------------------------------------------------------------------------

def _freqs(G):
    fy = np.fft.fftfreq(G)[:, None]
    fx = np.fft.rfftfreq(G)[None, :]
    return fy, fx


def one_over_f(rng, G, beta, aspect=1.0, angle=0.0):
    """White Gaussian noise filtered by |f|^-beta/2 (power ~ 1/f^beta);
    anisotropy through an elliptic frequency metric."""
    fy, fx = _freqs(G)
    c, s = math.cos(angle), math.sin(angle)
    fu = c * fx + s * fy
    fv = -s * fx + c * fy
    f = np.sqrt((fu * aspect) ** 2 + (fv / aspect) ** 2)
    f[0, 0] = np.inf
    f = np.maximum(f, 1.0 / G)
    amp = f ** (-beta / 2.0)
    amp[0, 0] = 0.0
    W = np.fft.rfft2(rng.standard_normal((G, G)))
    return np.fft.irfft2(W * amp, s=(G, G))


def spectral_synthesis(rng, G, beta, ddir, avar_deg, rms=1.0,
                       second_dir=None):
    """Fourier spectral synthesis: deterministic power-law amplitude with a
    Gaussian angular (directional) weighting, uniformly random phases.
    Parameters follow the directional-fractal surface description
    (RMS, dominant direction DDir, angular variance)."""
    fy, fx = _freqs(G)
    f = np.sqrt(fx ** 2 + fy ** 2)
    f[0, 0] = 1.0
    theta = np.arctan2(fy, fx)

    def dirw(d0):
        if avar_deg is None:
            return np.ones_like(f)
        dt = np.angle(np.exp(2j * (theta - d0))) / 2.0  # wrap to +-pi/2
        sig = math.radians(avar_deg)
        return np.exp(-0.5 * (dt / sig) ** 2)

    w = dirw(ddir)
    if second_dir is not None:
        w = w + dirw(second_dir)
    amp = f ** (-beta / 2.0) * (0.02 + w)
    amp[0, 0] = 0.0
    phase = rng.uniform(0, 2 * np.pi, amp.shape)
    h = np.fft.irfft2(amp * np.exp(1j * phase), s=(G, G))
    return h / (h.std() + 1e-12) * rms


def diamond_square(rng, N, H, coarse):
    """Periodic diamond-square midpoint displacement on an NxN torus
    (N power of two).  `coarse` random points per side start the recursion,
    roughness H in (0,1)."""
    a = np.zeros((N, N))
    step = N // coarse
    a[::step, ::step] = rng.standard_normal((coarse, coarse))
    scale = 1.0 * 2.0 ** (-H)
    while step > 1:
        half = step // 2
        C = a[::step, ::step]
        cen = (C + np.roll(C, -1, 0) + np.roll(C, -1, 1)
               + np.roll(np.roll(C, -1, 0), -1, 1)) / 4.0
        a[half::step, half::step] = cen + scale * rng.standard_normal(C.shape)
        M = a[half::step, half::step]
        s2 = scale * 2.0 ** (-H / 2.0)
        p1 = (C + np.roll(C, -1, 1) + np.roll(M, 1, 0) + M) / 4.0
        p2 = (C + np.roll(C, -1, 0) + np.roll(M, 1, 1) + M) / 4.0
        a[::step, half::step] = p1 + s2 * rng.standard_normal(C.shape)
        a[half::step, ::step] = p2 + s2 * rng.standard_normal(C.shape)
        scale *= 2.0 ** (-H)
        step = half
    return a


# ---------------------------------------------------------------------------
# textons
# ---------------------------------------------------------------------------

TEXTON_SHAPES = ["disc", "ring", "star", "cross", "square", "triangle",
                 "hexagon", "ellipse"]


def draw_texton(rng, shape=None, profile=None):
    shape = shape or TEXTON_SHAPES[rng.integers(len(TEXTON_SHAPES))]
    prof = profile or ["flat", "dome", "cone"][rng.integers(3)]
    prm = {"shape": shape, "profile": prof,
           "n": int(rng.integers(4, 9)), "q": float(rng.uniform(0.35, 0.6)),
           "w": float(rng.uniform(0.22, 0.42)),
           "aspect": float(rng.uniform(2.0, 4.0)),
           "edge": float(rng.uniform(0.08, 0.25))}
    if shape == "ring":
        prm["w"] = float(rng.uniform(0.15, 0.32))
    return prm


def texton_desc(t):
    s = t["shape"]
    if s == "star":
        s = "%d-point star" % t["n"]
    return "%s %s" % (t["profile"], s)


def _shape_t(t, u, v):
    s = t["shape"]
    if s == "disc":
        return np.hypot(u, v)
    if s == "ellipse":
        return np.hypot(u, v * t["aspect"])
    if s == "square":
        return np.maximum(np.abs(u), np.abs(v))
    if s == "ring":
        w = t["w"]
        return np.abs(np.hypot(u, v) - (1.0 - w)) / w
    if s == "cross":
        w = t["w"]
        return np.minimum(np.maximum(np.abs(u), np.abs(v) / w),
                          np.maximum(np.abs(u) / w, np.abs(v)))
    rho = np.hypot(u, v)
    phi = np.arctan2(v, u)
    if s in ("triangle", "hexagon"):
        n = 3 if s == "triangle" else 6
        sec = 2 * np.pi / n
        pm = np.mod(phi, sec) - sec / 2
        return rho * np.cos(pm) / math.cos(np.pi / n)
    if s == "star":
        n, q = t["n"], t["q"]
        sec = 2 * np.pi / n
        a = np.mod(phi, sec)
        a = np.where(a > sec / 2, sec - a, a)
        b = sec / 2
        r = q * math.sin(b) / (np.sin(a) + q * np.sin(b - a))
        return rho / r
    raise ValueError(s)


def _profile(t, tt):
    p = t["profile"]
    if p == "flat":
        return np.clip((1.0 - tt) / t["edge"], 0, 1)
    if p == "dome":
        return np.sqrt(np.clip(1.0 - tt * tt, 0, 1))
    return np.clip(1.0 - tt, 0, 1)


def stamp(canvas, t, cy, cx, r, ang, hgt=1.0, mode="max"):
    G = canvas.shape[0]
    r = float(min(r, G / 2 - 4))
    R = int(math.ceil(r)) + 2
    iy, ix = int(math.floor(cy)), int(math.floor(cx))
    oy = np.arange(iy - R, iy + R + 1)
    ox = np.arange(ix - R, ix + R + 1)
    y = (oy + 0.5 - cy)[:, None]
    x = (ox + 0.5 - cx)[None, :]
    ca, sa = math.cos(ang), math.sin(ang)
    u = (x * ca + y * sa) / r
    v = (-x * sa + y * ca) / r
    h = hgt * _profile(t, _shape_t(t, u, v))
    sel = np.ix_(oy % G, ox % G)
    if mode == "max":
        canvas[sel] = np.maximum(canvas[sel], h)
    else:
        canvas[sel] = canvas[sel] + h


def place_regular(rng, G, r, spacing):
    kind = ["square", "hex", "brick", "rect"][rng.integers(4)]
    nx = max(2, int(round(G / spacing)))
    dx = G / nx
    if kind == "hex":
        ny = max(2, 2 * int(round(G / (dx * math.sqrt(3) / 2) / 2)))
    elif kind == "rect":
        ny = max(2, int(round(G / (dx * rng.uniform(0.6, 1.6)))))
    else:
        ny = nx if kind == "square" else max(2, 2 * int(round(nx / 2 * 1.3)))
    dy = G / ny
    ang = rng.uniform(0, 2 * np.pi)
    oy0, ox0 = rng.uniform(0, dy), rng.uniform(0, dx)
    pos = []
    for j in range(ny):
        shift = 0.5 * dx if (kind in ("hex", "brick") and j % 2) else 0.0
        for i in range(nx):
            pos.append((oy0 + j * dy, ox0 + i * dx + shift, ang, 1.0, 1.0))
    return pos, "%s lattice %dx%d" % (kind, nx, ny)


def place_random_grid(rng, G, r, spacing):
    nx = max(2, int(round(G / spacing)))
    d = G / nx
    jit = rng.uniform(0.3, 1.0)
    rot = rng.random() < 0.6
    sj = rng.uniform(0.0, 0.3)
    a0 = rng.uniform(0, 2 * np.pi)
    pos = []
    for j in range(nx):
        for i in range(nx):
            pos.append(((j + 0.5 + jit * rng.uniform(-.5, .5)) * d,
                        (i + 0.5 + jit * rng.uniform(-.5, .5)) * d,
                        rng.uniform(0, 2 * np.pi) if rot else a0,
                        1.0 + sj * rng.uniform(-1, 1), 1.0))
    return pos, "grid %dx%d jitter %.2f%s" % (nx, nx, jit,
                                               ", random rotation" if rot else "")


def place_random_walk(rng, G, r, coverage):
    W = int(rng.integers(1, 6))
    ntot = int(coverage * G * G / (np.pi * r * r))
    ntot = max(20, min(ntot, 2500))
    step = 2 * r * rng.uniform(0.6, 1.3)
    turn = rng.uniform(0.1, 0.8)
    per = max(ntot // W, int(1.5 * G / step))   # every walk crosses the tile
    ntot = per * W
    pos = []
    for w in range(W):
        y, x = rng.uniform(0, G, 2)
        hd = rng.uniform(0, 2 * np.pi)
        for _ in range(per):
            pos.append((y % G, x % G, hd, 1.0, 1.0))
            hd += rng.normal(0, turn)
            y += step * math.sin(hd)
            x += step * math.cos(hd)
    return pos, "%d walkers, %d steps, turn sd %.2f" % (W, ntot, turn)


def prob_map(rng, G):
    sig = G / rng.uniform(3, 9)
    f = ndimage.gaussian_filter(rng.standard_normal((G, G)), sig, mode="wrap")
    f = norm01(f, 0, 100)
    return f


def place_prob_map(rng, G, r, coverage):
    f = prob_map(rng, G)
    if rng.random() < 0.5:
        gam = rng.uniform(1.5, 4)
        p = f ** gam
        mdesc = "power %.1f" % gam
    else:
        th = rng.uniform(0.3, 0.55)
        p = np.clip(f - th, 0, None) ** 1.0
        mdesc = "threshold %.2f" % th
    p = p.ravel() / p.sum()
    n = max(15, min(2500, int(coverage * G * G / (np.pi * r * r))))
    idx = rng.choice(G * G, n, p=p)
    ys, xs = np.divmod(idx, G)
    rot = rng.random() < 0.7
    a0 = rng.uniform(0, 2 * np.pi)
    pos = [(ys[i] + rng.random(), xs[i] + rng.random(),
            rng.uniform(0, 2 * np.pi) if rot else a0, 1.0, 1.0)
           for i in range(n)]
    return pos, "%d textons, map %s" % (n, mdesc)


def place_uniform(rng, G, r, coverage):
    n = max(10, min(2500, int(coverage * G * G / (np.pi * r * r))))
    pos = [(rng.uniform(0, G), rng.uniform(0, G), rng.uniform(0, 2 * np.pi),
            1.0, 1.0) for _ in range(n)]
    return pos, "%d uniform random textons" % n


def render_textons(G, t, pos, r, mode="max"):
    canvas = np.zeros((G, G))
    for (y, x, a, sc, hg) in pos:
        stamp(canvas, t, y, x, r * sc, a, hg, mode)
    return canvas


def texton_field(rng, G, kind, shape=None):
    """Returns (height, description) for one texton placement model."""
    t = draw_texton(rng, shape)
    r = loguniform(rng, 6.0, 20.0) if kind == "regular" else loguniform(rng, 4.0, 18.0)
    if kind == "regular":
        pos, pd = place_regular(rng, G, r, r * rng.uniform(2.1, 3.2))
        h = render_textons(G, t, pos, r)
    elif kind == "random grid":
        pos, pd = place_random_grid(rng, G, r, r * rng.uniform(2.1, 3.5))
        h = render_textons(G, t, pos, r)
    elif kind == "random walk":
        pos, pd = place_random_walk(rng, G, r, rng.uniform(0.25, 0.7))
        h = render_textons(G, t, pos, r)
    elif kind == "probability map":
        pos, pd = place_prob_map(rng, G, r, rng.uniform(0.3, 0.9))
        h = render_textons(G, t, pos, r)
    elif kind == "addition":
        cov = rng.uniform(0.6, 2.5)
        n = max(20, min(2500, int(cov * G * G / (np.pi * (1.5 * r) ** 2))))
        h = np.zeros((G, G))
        for _ in range(n):
            stamp(h, t, rng.uniform(0, G), rng.uniform(0, G),
                  r * rng.uniform(0.6, 2.0), rng.uniform(0, 2 * np.pi),
                  rng.uniform(0.3, 1.0), mode="add")
        pd = "%d textons summed, coverage %.1f" % (n, cov)
    elif kind == "uniform":
        pos, pd = place_uniform(rng, G, r, rng.uniform(0.3, 0.9))
        h = render_textons(G, t, pos, r)
    else:
        raise ValueError(kind)
    return h, "%s r=%.0fpx, %s" % (texton_desc(t), r, pd)


# ---------------------------------------------------------------------------
# cellular automata
# ---------------------------------------------------------------------------

OFF4 = [(-1, 0), (1, 0), (0, -1), (0, 1)]
OFF8 = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]
OFF_R2 = [(dy, dx) for dy in range(-2, 3) for dx in range(-2, 3)
          if (dy, dx) != (0, 0)]


def ca_forest_fire(rng, n, steps, p, f, offs, mode):
    s = (rng.random((n, n)) < rng.uniform(0.3, 0.7)).astype(np.uint8)
    age = np.zeros((n, n), dtype=np.float32)
    for _ in range(steps):
        fire = s == 2
        nb = np.zeros_like(fire)
        for o in offs:
            nb |= np.roll(fire, o, (0, 1))
        r = rng.random((n, n))
        tree = s == 1
        ign = tree & (nb | (r < f))
        grow = (s == 0) & (r < p)
        s = s.copy()
        s[fire] = 0
        s[ign] = 2
        s[grow] = 1
        age[s == 1] += 1
        age[s != 1] = 0
    if mode == "state":
        h = np.where(s == 1, 1.0, np.where(s == 2, 0.45, 0.0))
    elif mode == "tree age":
        tau = 1.0 / p
        h = np.where(s == 1, 0.25 + 0.75 * np.minimum(age / tau, 1.0),
                     np.where(s == 2, 0.1, 0.0))
    else:
        h = ndimage.gaussian_filter((s == 1).astype(float),
                                    rng.uniform(0.7, 1.5), mode="wrap")
    return h


def ca_surface_tension(rng, n, steps, dens, radius, twist):
    s = (rng.random((n, n)) < dens).astype(np.uint8)
    k = 2 * radius + 1
    tot = k * k
    half = tot // 2
    w = np.ones((k, k), dtype=np.uint8)
    for _ in range(steps):
        c = ndimage.correlate(s, w, mode="wrap")
        if twist:   # Vichniac "anneal": swap the outcomes of half and half+1
            s = ((c > half + 1) | (c == half)).astype(np.uint8)
        else:       # plain majority vote
            s = (c > half).astype(np.uint8)
    return s.astype(float)


def ca_greenberg_hastings(rng, n, steps, ns, thr, offs, pex, spont=0.0):
    """Greenberg-Hastings excitable medium: 0 rest, 1 excited, 2..ns-1
    refractory.  A resting cell fires when >= thr neighbours are excited
    (or spontaneously with probability `spont`)."""
    for attempt in range(4):
        s = np.where(rng.random((n, n)) < pex, rng.integers(1, ns, (n, n)), 0)
        for _ in range(steps):
            ex = (s == 1).astype(np.uint8)
            cnt = sum(np.roll(ex, o, (0, 1)) for o in offs)
            fire = cnt >= thr
            if spont > 0:
                fire |= rng.random((n, n)) < spont
            s = np.where(s == 0, fire.astype(s.dtype), (s + 1) % ns)
        if np.mean(s != 0) > 0.05:
            break
        # the waves died out: retry with a denser start and a little
        # spontaneous firing (keeps the medium excitable)
        pex = min(0.5, pex * 1.5)
        spont = max(spont, 2e-5)
    return s, ns


def ca_cyclic(rng, n, steps, ns, thr, offs):
    s = rng.integers(0, ns, (n, n))
    for _ in range(steps):
        nx = (s + 1) % ns
        cnt = sum((np.roll(s, o, (0, 1)) == nx).astype(np.uint8) for o in offs)
        s = np.where(cnt >= thr, nx, s)
    return s, ns


# ---------------------------------------------------------------------------
# reaction diffusion (Gray-Scott, batched, periodic)
# ---------------------------------------------------------------------------

RD_REGIMES = [  # (name, F, k) -- Pearson (1993) / well known Gray-Scott map
    ("spots (lambda)", 0.026, 0.061),
    ("spots", 0.030, 0.062),
    ("mitosis spots (kappa/mu edge)", 0.0367, 0.0649),
    ("mixed spots and stripes", 0.034, 0.0618),
    ("labyrinth (theta)", 0.029, 0.057),
    ("labyrinth", 0.037, 0.060),
    ("holes / negative spots (iota)", 0.039, 0.058),
    ("stripes / coral (kappa)", 0.0545, 0.062),
    ("worms (mu)", 0.058, 0.065),
    ("worms and loops", 0.050, 0.065),
    ("stripes (eta)", 0.046, 0.063),
    ("chaotic stripes (gamma)", 0.022, 0.051),
    ("chaotic spots (epsilon)", 0.018, 0.051),
    ("holes and stripes (delta)", 0.030, 0.055),
]


def gray_scott_batch(rng_list, params, N=128, steps=6000):
    """params: list of (F, k, dscale).  One independent sim per entry."""
    B = len(params)
    F = np.array([p[0] for p in params], np.float32)[:, None, None]
    K = np.array([p[1] for p in params], np.float32)[:, None, None]
    ds = np.array([p[2] for p in params], np.float32)[:, None, None]
    Du = (0.2 * ds * ds).astype(np.float32)
    Dv = (0.1 * ds * ds).astype(np.float32)
    U = np.ones((B, N, N), np.float32)
    V = np.zeros((B, N, N), np.float32)
    yy, xx = np.mgrid[0:N, 0:N]
    for b, rng in enumerate(rng_list):
        for _ in range(int(rng.integers(18, 36))):
            cy, cx = rng.uniform(0, N, 2)
            rr = rng.uniform(3, 7) * float(ds[b, 0, 0]) + 1.5
            dy = (yy - cy + N / 2) % N - N / 2
            dx = (xx - cx + N / 2) % N - N / 2
            m = dy * dy + dx * dx < rr * rr
            U[b][m] = 0.5
            V[b][m] = 0.25
        U[b] += rng.normal(0, 0.05, (N, N)).astype(np.float32)
        V[b] += rng.normal(0, 0.05, (N, N)).astype(np.float32)
    np.clip(V, 0, 1, out=V)
    P = np.empty((B, N + 2, N + 2), np.float32)

    def lap(a):
        P[:, 1:-1, 1:-1] = a
        P[:, 0, 1:-1] = a[:, -1]
        P[:, -1, 1:-1] = a[:, 0]
        P[:, :, 0] = P[:, :, -2]
        P[:, :, -1] = P[:, :, 1]
        return P[:, :-2, 1:-1] + P[:, 2:, 1:-1] + P[:, 1:-1, :-2] + P[:, 1:-1, 2:] - 4 * a

    for _ in range(steps):
        uvv = U * V * V
        U += Du * lap(U) - uvv + F * (1 - U)
        V += Dv * lap(V) + uvv - (F + K) * V
    return V


# ---------------------------------------------------------------------------
# lattice patterns: Islamic star patterns (Hankin polygons-in-contact) and
# matrix-transformation (point-group) patterns.  Both are analytic and are
# evaluated directly at the renderer's sample coordinates.
# ---------------------------------------------------------------------------

def _ccw(poly):
    poly = np.asarray(poly, float)
    c = poly.mean(0)
    ang = np.arctan2(poly[:, 1] - c[1], poly[:, 0] - c[0])
    return poly[np.argsort(ang)]


def _regular(center, n, R, a0):
    return _ccw([(center[0] + R * math.cos(a0 + 2 * np.pi * k / n),
                  center[1] + R * math.sin(a0 + 2 * np.pi * k / n))
                 for k in range(n)])


def tiling(name):
    """(a1, a2, polygons) with unit edge length."""
    s3 = math.sqrt(3.0)
    if name == "square 4.4.4.4":
        return (1, 0), (0, 1), [_ccw([(0, 0), (1, 0), (1, 1), (0, 1)])]
    if name == "hexagonal 6.6.6":
        return (s3, 0), (s3 / 2, 1.5), [_regular((0, 0), 6, 1.0, np.pi / 6)]
    if name == "octagon-square 4.8.8":
        a = 1 + math.sqrt(2)
        R8 = 1 / (2 * math.sin(np.pi / 8))
        return (a, 0), (0, a), [_regular((0, 0), 8, R8, np.pi / 8),
                                _regular((a / 2, a / 2), 4, math.sqrt(.5), 0)]
    if name == "trihexagonal 3.6.3.6":
        return (2, 0), (1, s3), [
            _regular((0, 0), 6, 1.0, 0.0),
            _ccw([(1, 0), (1.5, s3 / 2), (0.5, s3 / 2)]),
            _ccw([(1.5, s3 / 2), (2.5, s3 / 2), (2, s3)])]
    raise ValueError(name)


def hankin_segments(poly, theta, delta):
    n = len(poly)
    segs = []
    ct, st = math.cos(theta), math.sin(theta)
    for i in range(n):
        A, B, C = poly[i], poly[(i + 1) % n], poly[(i + 2) % n]
        L1 = np.linalg.norm(B - A)
        L2 = np.linalg.norm(C - B)
        e1 = (B - A) / L1
        e2 = (C - B) / L2
        n1 = np.array([-e1[1], e1[0]])
        n2 = np.array([-e2[1], e2[0]])
        M1 = (A + B) / 2 + delta * L1 * e1
        M2 = (B + C) / 2 - delta * L2 * e2
        d1 = ct * e1 + st * n1
        d2 = -ct * e2 + st * n2
        Mx = np.array([d1, -d2]).T
        det = np.linalg.det(Mx)
        if abs(det) < 1e-9:
            segs.append((M1, M2))
            continue
        t, s = np.linalg.solve(Mx, M2 - M1)
        if t <= 0 or s <= 0:
            segs.append((M1, M2))
            continue
        P = M1 + t * d1
        segs.append((M1, P))
        segs.append((M2, P))
    return segs


class LatticeField:
    """Periodic analytic field on a 2-D lattice.  `elements` is a list of
    callables e(py, px) -> partial height evaluated on coordinates already
    reduced to the centred unit cell, for every nearby lattice translate."""

    def __init__(self, a1, a2, scale):
        self.a1 = np.array(a1, float) * scale
        self.a2 = np.array(a2, float) * scale
        B = np.array([self.a1, self.a2]).T
        self.Binv = np.linalg.inv(B)
        corners = [0.5 * (sx * self.a1 + sy * self.a2)
                   for sx in (-1, 1) for sy in (-1, 1)]
        self.rcell = max(np.linalg.norm(c) for c in corners)

    def reduce(self, ys, xs):
        u = self.Binv[0, 0] * xs + self.Binv[0, 1] * ys
        v = self.Binv[1, 0] * xs + self.Binv[1, 1] * ys
        u = u - np.round(u)
        v = v - np.round(v)
        qx = self.a1[0] * u + self.a2[0] * v
        qy = self.a1[1] * u + self.a2[1] * v
        return qy, qx

    def translates(self, reach):
        out = []
        m = int(math.ceil((reach + self.rcell) /
                          min(np.linalg.norm(self.a1), np.linalg.norm(self.a2)))) + 1
        for i in range(-m, m + 1):
            for j in range(-m, m + 1):
                out.append(i * self.a1 + j * self.a2)
        return out


def _seg_point_dist0(a, b):
    ab = b - a
    t = np.clip(-(a @ ab) / max(ab @ ab, 1e-12), 0, 1)
    return np.linalg.norm(a + t * ab)


def islamic_field(rng, key):
    tname, th_lo, th_hi, use_delta = key
    a1, a2, polys = tiling(tname)
    theta = math.radians(rng.uniform(th_lo, th_hi))
    delta = rng.uniform(0.06, 0.16) if use_delta else 0.0
    edge_px = loguniform(rng, 14, 44)
    if tname == "square 4.4.4.4":
        edge_px *= 1.5
    lat = LatticeField(a1, a2, edge_px)
    w = rng.uniform(1.6, 0.09 * edge_px + 2.0)
    prof = ["strap", "round", "grooved strap", "engraved"][rng.integers(4)]
    base = []
    for poly in polys:
        for (p, q) in hankin_segments(poly, theta, delta):
            base.append((p * edge_px, q * edge_px))
    segs = []
    for t in lat.translates(3 * w):
        for (p, q) in base:
            a, b = p + t, q + t
            if _seg_point_dist0(a, b) <= lat.rcell + 2 * w + 1:
                segs.append((a, b))
    segs = np.array(segs)  # (n, 2, 2) in (x, y)
    bev = rng.uniform(0.6, 1.5)

    def f(ys, xs):
        qy, qx = lat.reduce(ys, xs)
        d = np.full(qx.shape, np.inf)
        for (a, b) in segs:
            ab = b - a
            L2 = ab @ ab
            if L2 < 1e-12:
                continue
            tt = np.clip(((qx - a[0]) * ab[0] + (qy - a[1]) * ab[1]) / L2, 0, 1)
            dd = np.hypot(qx - a[0] - tt * ab[0], qy - a[1] - tt * ab[1])
            np.minimum(d, dd, out=d)
        strap = np.clip((w - d) / bev, 0, 1)
        if prof == "strap":
            return strap
        if prof == "round":
            return np.sqrt(np.clip(1 - (d / w) ** 2, 0, 1))
        if prof == "grooved strap":
            return strap - 0.6 * np.clip((0.3 * w - d) / 0.6, 0, 1)
        return 1.0 - strap

    desc = "%s, contact angle %.1f deg%s, edge %.0fpx, band %.1fpx %s" % (
        tname, math.degrees(theta),
        (", offset %.2f" % delta) if use_delta else "", edge_px, w, prof)
    return f, desc


def _rot(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def point_group(name):
    I = np.eye(2)
    mx = np.array([[1, 0], [0, -1]], float)
    if name == "p2":
        return [I, -I]
    if name == "pmm":
        return [I, -I, mx, -mx]
    if name == "p4":
        return [_rot(k * np.pi / 2) for k in range(4)]
    if name == "p4m":
        r = [_rot(k * np.pi / 2) for k in range(4)]
        return r + [m @ mx for m in r]
    if name == "p3":
        return [_rot(k * 2 * np.pi / 3) for k in range(3)]
    if name == "p6":
        return [_rot(k * np.pi / 3) for k in range(6)]
    if name == "p6m":
        r = [_rot(k * np.pi / 3) for k in range(6)]
        return r + [m @ mx for m in r]
    if name == "p3m1":
        r = [_rot(k * 2 * np.pi / 3) for k in range(3)]
        my = np.array([[-1, 0], [0, 1]], float)
        return r + [m @ my for m in r]
    raise ValueError(name)


GROUP_LATTICE = {"p2": "oblique", "pmm": "rect", "p4": "square",
                 "p4m": "square", "p3": "hex", "p6": "hex", "p6m": "hex",
                 "p3m1": "hex"}


def matrix_field(rng, group):
    """A motif of a few strokes/blobs is copied by every 2x2 matrix of a
    crystallographic point group and by lattice translations
    (h(p) = sum_t sum_M motif(M^-1 (p - t)))."""
    lname = GROUP_LATTICE[group]
    if lname == "square":
        a1, a2 = (1, 0), (0, 1)
    elif lname == "hex":
        a1, a2 = (1, 0), (0.5, math.sqrt(3) / 2)
    elif lname == "rect":
        a1, a2 = (1, 0), (0, rng.uniform(0.55, 0.85))
    else:
        ang = rng.uniform(np.radians(65), np.radians(80))
        rr = rng.uniform(0.7, 1.0)
        a1, a2 = (1, 0), (rr * math.cos(ang), rr * math.sin(ang))
    cell = loguniform(rng, 28, 80)
    lat = LatticeField(a1, a2, cell)
    ops = point_group(group)
    K = int(rng.integers(1, 4))
    elems = []
    for _ in range(K):
        c = rng.uniform(0.1, 0.42) * cell * np.array(
            [math.cos(rng.uniform(0, 2 * np.pi)), math.sin(rng.uniform(0, 2 * np.pi))])
        if rng.random() < 0.55:  # stroke (capsule)
            L = rng.uniform(0.12, 0.35) * cell
            a = rng.uniform(0, np.pi)
            d = L * np.array([math.cos(a), math.sin(a)])
            wdt = rng.uniform(0.025, 0.07) * cell
            elems.append(("stroke", c - d / 2, c + d / 2, wdt,
                          rng.uniform(0.6, 1.0)))
        else:  # anisotropic blob
            s1 = rng.uniform(0.04, 0.12) * cell
            s2 = s1 * rng.uniform(1.0, 2.5)
            a = rng.uniform(0, np.pi)
            elems.append(("blob", c, None, (s1, s2, a), rng.uniform(0.6, 1.0)))
    reach = 0.5 * cell
    inst = []
    trs = lat.translates(reach)
    for M in ops:
        for (typ, p0, p1, prm, amp) in elems:
            for t in trs:
                q0 = M @ p0 + t
                if typ == "stroke":
                    q1 = M @ p1 + t
                    if _seg_point_dist0(q0, q1) > lat.rcell + 4 * prm:
                        continue
                    inst.append((0, q0, q1, prm, amp))
                else:
                    s1, s2, a = prm
                    if np.linalg.norm(q0) > lat.rcell + 4 * s2:
                        continue
                    R = M @ _rot(a)
                    Sinv = R @ np.diag([1 / s1 ** 2, 1 / s2 ** 2]) @ R.T
                    inst.append((1, q0, Sinv, None, amp))
    prof = ["sum", "clipped", "soft max"][rng.integers(3)]

    def f(ys, xs):
        qy, qx = lat.reduce(ys, xs)
        h = np.zeros(qx.shape)
        for (typ, q0, X, wdt, amp) in inst:
            dx = qx - q0[0]
            dy = qy - q0[1]
            if typ == 0:
                ab = X - q0
                t = np.clip((dx * ab[0] + dy * ab[1]) / (ab @ ab), 0, 1)
                d2 = (dx - t * ab[0]) ** 2 + (dy - t * ab[1]) ** 2
                g = amp * np.exp(-0.5 * d2 / (wdt * wdt))
            else:
                g = amp * np.exp(-0.5 * (X[0, 0] * dx * dx + 2 * X[0, 1] * dx * dy
                                         + X[1, 1] * dy * dy))
            if prof == "soft max":
                np.maximum(h, g, out=h)
            else:
                h += g
        if prof == "clipped":
            h = np.clip(h / 0.6, 0, 1)
        return h

    desc = "%s on %s lattice, %d motif elements (%s), cell %.0fpx, %s" % (
        group, lname, K, ",".join(e[0] for e in elems), cell, prof)
    return f, desc


# ---------------------------------------------------------------------------
# per-model generators.  gen(rng, need, key) -> (field, description)
# field is either a periodic 2-D array (native pixels) or a callable
# f(ys, xs) evaluated at native-pixel coordinates.
# ---------------------------------------------------------------------------

def g_forest_fire(rng, need, key):
    nb, mode = key
    c = int(rng.integers(1, 4))
    n = int(min(256, math.ceil(need / c)))
    p = loguniform(rng, 0.006, 0.05)
    f = p * loguniform(rng, 2e-4, 1e-2)
    steps = int(rng.integers(250, 500))
    offs = OFF4 if nb == "von Neumann" else OFF8
    h = ca_forest_fire(rng, n, steps, p, f, offs, mode)
    return ca_cells(h, c), \
        "%s, p=%.3f f=%.1e, %d steps, cell %dpx, height=%s" % (
            nb, p, f, steps, c, mode)


def g_surface_tension(rng, need, key):
    rule, radius, steps_rng, dens_rng = key
    c = int(rng.integers(1, 4))
    n = int(min(256, math.ceil(need / c)))
    dens = rng.uniform(*dens_rng)
    steps = int(rng.integers(*steps_rng))
    h = ca_surface_tension(rng, n, steps, dens, radius, rule == "anneal")
    if rng.random() < 0.4:
        h = ndimage.gaussian_filter(h, rng.uniform(0.5, 1.2), mode="wrap")
    return ca_cells(h, c), \
        "%s rule, %dx%d neighbourhood, density %.2f, %d steps, cell %dpx" % (
            "twisted-majority anneal" if rule == "anneal" else "majority vote",
            2 * radius + 1, 2 * radius + 1, dens, steps, c)


def g_excitable(rng, need, key):
    kind = key[0]
    c = int(rng.integers(2, 4))
    n = int(min(192, math.ceil(need / c)))
    if kind == "GH":
        _, ns_rng, thr, nbname, pex_rng, spont = key
        ns = int(rng.integers(*ns_rng))
        pex = rng.uniform(*pex_rng)
        offs = {"vN": OFF4, "Moore": OFF8, "R2 Moore": OFF_R2}[nbname]
        steps = int(rng.integers(180, 320))
        s, ns = ca_greenberg_hastings(rng, n, steps, ns, thr, offs, pex, spont)
        desc = "Greenberg-Hastings %d states, threshold %d, %s, %d steps%s" % (
            ns, thr, nbname, steps,
            (", spontaneous firing %.0e" % spont) if spont else "")
    else:
        _, ns_rng, thr, nbname = key
        ns = int(rng.integers(*ns_rng))
        offs = {"vN": OFF4, "Moore": OFF8, "R2 Moore": OFF_R2}[nbname]
        steps = int(rng.integers(200, 350))
        s, ns = ca_cyclic(rng, n, steps, ns, thr, offs)
        desc = "cyclic CA %d states, threshold %d, %s, %d steps" % (
            ns, thr, nbname, steps)
    if rng.random() < 0.5:
        h = s / ns
        hm = "sawtooth"
    else:
        h = np.cos(2 * np.pi * s / ns)
        hm = "cosine"
    return ca_cells(h.astype(float), c), desc + ", cell %dpx, %s" % (c, hm)


def g_cellular(rng, need, key):
    G = grid_size(need)
    cell = loguniform(rng, 12, 64)
    metric = draw_metric(rng)
    h, n = cellular_height(rng, G, key, cell, metric)
    return h, "worley %s, %s, ~%.0fpx cells (%d points)" % (
        key, METRICS[metric], cell, n)


def g_fold_texton(rng, need, key):
    G = grid_size(need)
    shape, placement = key
    t = draw_texton(rng, shape, ["dome", "cone"][rng.integers(2)])
    r = loguniform(rng, 6.0, 22.0)
    if placement == "uniform":
        pos, pd = place_uniform(rng, G, r, rng.uniform(0.3, 0.8))
    elif placement == "random grid":
        pos, pd = place_random_grid(rng, G, r, r * rng.uniform(2.0, 3.0))
    else:
        pos, pd = place_prob_map(rng, G, r, rng.uniform(0.4, 0.9))
    h = render_textons(G, t, pos, r, "max" if rng.random() < 0.6 else "add")
    if rng.random() < 0.5:
        h = ndimage.gaussian_filter(h, rng.uniform(1, 3), mode="wrap")
    nf, off = rng.uniform(1.5, 4.0), rng.uniform(0, 1)
    return fold(h, nf, off), "fold x%.1f (offset %.2f) of %s r=%.0fpx, %s" % (
        nf, off, texton_desc(t), r, pd)


def g_fold_cellular(rng, need, key):
    G = grid_size(need)
    cell = loguniform(rng, 16, 72)
    metric = draw_metric(rng)
    h, n = cellular_height(rng, G, key, cell, metric)
    if rng.random() < 0.4:
        h = ndimage.gaussian_filter(h, rng.uniform(0.7, 2), mode="wrap")
    nf, off = rng.uniform(1.5, 4.5), rng.uniform(0, 1)
    return fold(h, nf, off), "fold x%.1f (offset %.2f) of worley %s, %s, %d points" % (
        nf, off, key, METRICS[metric], n)


def fractal_base(rng, G, key):
    if key == "1/f":
        beta = rng.uniform(2.4, 3.6)
        asp = loguniform(rng, 1.0, 4.0)
        return one_over_f(rng, G, beta, asp, rng.uniform(0, np.pi)), \
            "1/f^%.2f noise, aspect %.1f" % (beta, asp)
    if key == "spectral":
        beta = rng.uniform(2.6, 3.8)
        av = None if rng.random() < 0.5 else rng.uniform(8, 40)
        return spectral_synthesis(rng, G, beta, rng.uniform(0, np.pi), av), \
            "spectral synthesis beta %.2f, %s" % (
                beta, "isotropic" if av is None else "angular sd %.0f deg" % av)
    H = rng.uniform(0.6, 0.95)
    N = pow2_at_least(G)
    return diamond_square(rng, N, H, int(rng.choice([1, 2, 4]))), \
        "diamond-square H=%.2f" % H


def g_fold_fractal(rng, need, key):
    G = grid_size(need)
    h, d = fractal_base(rng, G, key)
    nf, off = rng.uniform(1.5, 5.0), rng.uniform(0, 1)
    return fold(h, nf, off), "fold x%.1f (offset %.2f) of %s" % (nf, off, d)


def g_fold_perlin(rng, need, key):
    G = grid_size(need)
    oct_lo, oct_hi = key
    octv = int(rng.integers(oct_lo, oct_hi + 1))
    pers = rng.uniform(0.3, 0.7)
    cell = loguniform(rng, 24, 160)
    h, used = perlin_fbm(rng, G, cell, octv, pers)
    nf, off = rng.uniform(1.5, 5.0), rng.uniform(0, 1)
    return fold(h, nf, off), \
        "fold x%.1f (offset %.2f) of perlin fbm %d oct, persistence %.2f, %.0fpx" % (
            nf, off, used, pers, cell)


def blend(rng, A, B, mode):
    A = norm01(A)
    B = norm01(B)
    if mode == "linear":
        w = rng.uniform(0.3, 0.7)
        return w * A + (1 - w) * B, "linear blend w=%.2f" % w
    if mode == "multiply":
        k = rng.uniform(0.3, 1.0)
        return A * ((1 - k) + k * B), "A x (%.2f + %.2f B)" % (1 - k, k)
    if mode == "max":
        w = rng.uniform(0.6, 1.0)
        return np.maximum(A, w * B), "max(A, %.2f B)" % w
    if mode == "screen":
        return 1 - (1 - A) * (1 - B), "screen"
    raise ValueError(mode)


def g_fusion_ct(rng, need, key):
    G = grid_size(need)
    ckind, tkind, mode = key
    A, n = cellular_height(rng, G, ckind, loguniform(rng, 18, 70), draw_metric(rng))
    B, td = texton_field(rng, G, tkind)
    h, bd = blend(rng, A, B, mode)
    return h, "%s of worley %s (%d pts) + textons %s" % (bd, ckind, n, td)


def g_fusion_pc(rng, need, key):
    G = grid_size(need)
    ckind, mode = key
    cell = loguniform(rng, 18, 70)
    pcell = loguniform(rng, 24, 160)
    octv = int(rng.integers(1, 8))
    pers = rng.uniform(0.3, 0.7)
    turb = rng.random() < 0.4
    P, used = perlin_fbm(rng, G, pcell, octv, pers, turb)
    if mode == "warp":
        amp = rng.uniform(0.15, 0.5) * cell
        d, ids, n = worley(rng, G, cell, 2, draw_metric(rng))
        # domain-distorted worley: evaluate F on perlin-displaced coordinates
        P2, _ = perlin_fbm(rng, G, pcell, octv, pers)
        dy = amp * P / (np.abs(P).max() + 1e-9)
        dx = amp * P2 / (np.abs(P2).max() + 1e-9)
        yy, xx = np.mgrid[0:G, 0:G].astype(float)
        F = d[..., 1] - d[..., 0] if ckind.startswith("F2-F1") else d[..., 0]
        h = ndimage.map_coordinates(F, [yy + dy, xx + dx], order=1, mode="grid-wrap")
        bd = "perlin domain warp (amp %.0fpx)" % amp
    else:
        C, n = cellular_height(rng, G, ckind, cell, draw_metric(rng))
        h, bd = blend(rng, C, P, mode)
    return h, "%s of worley %s (%d pts) and perlin %s%d oct p=%.2f" % (
        bd, ckind, n, "turbulence " if turb else "", used, pers)


def g_fusion_pt(rng, need, key):
    G = grid_size(need)
    tkind, mode = key
    octv = int(rng.integers(1, 8))
    pers = rng.uniform(0.3, 0.7)
    turb = rng.random() < 0.4
    P, used = perlin_fbm(rng, G, loguniform(rng, 24, 160), octv, pers, turb)
    T, td = texton_field(rng, G, tkind)
    h, bd = blend(rng, T, P, mode)
    return h, "%s of textons %s and perlin %s%d oct p=%.2f" % (
        bd, td, "turbulence " if turb else "", used, pers)


def g_one_over_f(rng, need, key):
    G = grid_size(need)
    (blo, bhi), (alo, ahi) = key
    beta = rng.uniform(blo, bhi)
    asp = loguniform(rng, alo, ahi) if ahi > 1 else 1.0
    ang = rng.uniform(0, np.pi)
    h = one_over_f(rng, G, beta, asp, ang)
    return h, "white noise filtered to 1/f^%.2f, aspect %.1f at %.0f deg" % (
        beta, asp, math.degrees(ang))


def g_spectral(rng, need, key):
    G = grid_size(need)
    (blo, bhi), av_rng, bimodal = key
    beta = rng.uniform(blo, bhi)
    ddir = rng.uniform(0, np.pi)
    av = None if av_rng is None else rng.uniform(*av_rng)
    d2 = ddir + rng.uniform(np.pi / 4, np.pi / 2) if bimodal else None
    rms = rng.uniform(0.5, 2.0)
    h = spectral_synthesis(rng, G, beta, ddir, av, rms, d2)
    desc = "power-law amplitude beta %.2f, random phase, " % beta
    if av is None:
        desc += "isotropic"
    else:
        desc += "DDir %.0f deg, angular sd %.0f deg" % (math.degrees(ddir), av)
        if bimodal:
            desc += ", second lobe %.0f deg" % math.degrees(d2)
    return h, desc + ", RMS %.2f" % rms


def g_midpoint(rng, need, key):
    (hlo, hhi), coarse = key
    N = pow2_at_least(need)
    H = rng.uniform(hlo, hhi)
    h = diamond_square(rng, N, H, coarse)
    return h, "periodic diamond-square, H=%.2f, %d start points/side, %dpx" % (
        H, coarse, N)


def g_islamic(rng, need, key):
    return islamic_field(rng, key)


def g_matrix(rng, need, key):
    return matrix_field(rng, key)


def g_perlin(rng, need, key):
    G = grid_size(need)
    mode, (olo, ohi) = key
    octv = int(rng.integers(olo, ohi + 1))
    pers = rng.uniform(0.3, 0.7)
    cell = loguniform(rng, 16, 128)
    h, used = perlin_fbm(rng, G, cell, octv, pers, mode == "turbulence")
    return h, "perlin gradient noise %s, %d octaves, persistence %.2f, base cell %.0fpx" % (
        mode, used, pers, cell)


def g_texton(kind):
    def g(rng, need, key):
        G = grid_size(need)
        return texton_field(rng, G, kind, key)
    return g


# variant keys: 8 per model; both splits use the same 8 keys with
# independent seeds and continuous parameter draws.
TEX8 = TEXTON_SHAPES
SPEC = {
    "CA (Forest fire model)": (g_forest_fire, [
        ("von Neumann", "state"), ("Moore", "state"), ("von Neumann", "tree age"),
        ("Moore", "tree age"), ("von Neumann", "smoothed density"),
        ("Moore", "smoothed density"), ("von Neumann", "state"), ("Moore", "tree age")]),
    "CA (Surface tension model)": (g_surface_tension, [
        ("anneal", 1, (10, 40), (0.48, 0.52)), ("anneal", 1, (60, 150), (0.48, 0.52)),
        ("anneal", 1, (150, 300), (0.49, 0.51)), ("anneal", 2, (10, 30), (0.48, 0.52)),
        ("anneal", 2, (40, 100), (0.49, 0.51)), ("majority", 1, (5, 15), (0.45, 0.55)),
        ("majority", 2, (5, 15), (0.45, 0.55)), ("anneal", 1, (20, 50), (0.455, 0.47))]),
    "CA (Excitable media model)": (g_excitable, [
        ("GH", (5, 8), 1, "vN", (0.1, 0.25), 0.0),
        ("GH", (11, 15), 3, "R2 Moore", (0.25, 0.35), 0.0),
        ("GH", (9, 13), 3, "R2 Moore", (0.2, 0.3), 3e-5),
        ("GH", (6, 9), 1, "vN", (0.1, 0.2), 2e-5),
        ("CCA", (12, 16), 1, "vN"), ("CCA", (7, 9), 3, "R2 Moore"),
        ("CCA", (9, 11), 3, "R2 Moore"), ("CCA", (6, 8), 3, "R2 Moore")]),
    "Cellular": (g_cellular, CELL_KINDS),
    "Folding of Texton Placement": (g_fold_texton, [
        ("disc", "uniform"), ("ring", "random grid"), ("star", "probability map"),
        ("cross", "uniform"), ("square", "random grid"), ("hexagon", "uniform"),
        ("ellipse", "probability map"), ("triangle", "random grid")]),
    "Folding of Cellular": (g_fold_cellular, CELL_KINDS),
    "Folding of Fractal": (g_fold_fractal, [
        "1/f", "spectral", "midpoint", "1/f", "spectral", "midpoint", "1/f", "spectral"]),
    "Folding of Perlin noise": (g_fold_perlin, [
        (1, 1), (2, 3), (3, 5), (5, 8), (1, 2), (2, 4), (4, 6), (6, 8)]),
    "Fusion of Cellular and Texton": (g_fusion_ct, [
        ("F1 domed", "uniform", "linear"), ("F2-F1 faceted", "random grid", "linear"),
        ("F1 faceted", "regular", "max"), ("flat mosaic", "uniform", "multiply"),
        ("F2-F1 flat", "probability map", "linear"), ("F2 faceted", "random walk", "max"),
        ("F1 domed", "random grid", "screen"), ("F2-F1 faceted", "uniform", "multiply")]),
    "Fusion of Perlin and Cellular": (g_fusion_pc, [
        ("F1 domed", "linear"), ("F2-F1 faceted", "linear"), ("F1 faceted", "multiply"),
        ("F2-F1 faceted", "warp"), ("flat mosaic", "linear"), ("F2 faceted", "screen"),
        ("F1 faceted", "warp"), ("F2-F1 flat", "multiply")]),
    "Fusion of Perlin and Texton": (g_fusion_pt, [
        ("uniform", "linear"), ("random grid", "linear"), ("regular", "multiply"),
        ("probability map", "max"), ("random walk", "linear"), ("uniform", "multiply"),
        ("regular", "screen"), ("random grid", "max")]),
    "Fractal (one-over-f-beta noise)": (g_one_over_f, [
        ((1.4, 2.2), (1, 1)), ((2.2, 3.4), (1, 1)), ((1.6, 2.6), (1.5, 3)),
        ((2.4, 3.4), (1.5, 3)), ((1.6, 2.6), (3, 8)), ((2.4, 3.4), (3, 8)),
        ((1.2, 3.0), (2, 6)), ((1.8, 3.2), (4, 10))]),
    "Fractal (Fourier spectral synthesis)": (g_spectral, [
        ((2.0, 2.8), None, False), ((2.8, 3.8), None, False),
        ((2.0, 3.0), (4, 12), False), ((2.8, 3.8), (4, 12), False),
        ((2.0, 3.4), (12, 30), False), ((2.4, 3.6), (25, 45), False),
        ((2.2, 3.4), (5, 15), True), ((2.0, 3.6), (8, 25), False)]),
    "Fractal (midpoint displacement)": (g_midpoint, [
        ((0.15, 0.35), 1), ((0.35, 0.55), 1), ((0.55, 0.75), 1), ((0.75, 0.95), 1),
        ((0.2, 0.5), 2), ((0.5, 0.9), 2), ((0.3, 0.7), 4), ((0.5, 0.9), 8)]),
    "Islamic Patterns": (g_islamic, [
        ("octagon-square 4.8.8", 60, 75, False), ("octagon-square 4.8.8", 50, 72, True),
        ("square 4.4.4.4", 55, 75, False), ("square 4.4.4.4", 25, 40, True),
        ("hexagonal 6.6.6", 55, 70, False), ("hexagonal 6.6.6", 30, 50, True),
        ("trihexagonal 3.6.3.6", 45, 70, False), ("trihexagonal 3.6.3.6", 55, 75, True)]),
    "Matrix Transformation": (g_matrix, [
        "p4", "p4m", "p6", "p6m", "p3", "p2", "pmm", "p3m1"]),
    "Perlin noise": (g_perlin, [
        ("fbm", (1, 1)), ("fbm", (2, 3)), ("fbm", (4, 5)), ("fbm", (6, 8)),
        ("turbulence", (1, 2)), ("turbulence", (3, 4)), ("turbulence", (5, 8)),
        ("fbm", (2, 8))]),
    "Reaction Diffusion": (None, None),  # batched, see rd_task
    "Texton Addition": (g_texton("addition"), TEX8),
    "Texton probability map": (g_texton("probability map"), TEX8[3:] + TEX8[:3]),
    "Texton random grid": (g_texton("random grid"), TEX8[5:] + TEX8[:5]),
    "Texton random walk": (g_texton("random walk"), TEX8[2:] + TEX8[:2]),
    "Texton regular": (g_texton("regular"), TEX8[6:] + TEX8[:6]),
}

# render zoom range per model: the expensive simulations (CA, RD) are made
# on bounded grids, so they get a narrower minification range.
ZOOM = {m: (0.5, 2.0) for m in MODELS}
for m in ("CA (Forest fire model)", "CA (Surface tension model)",
          "CA (Excitable media model)"):
    ZOOM[m] = (0.75, 2.0)
ZOOM["Reaction Diffusion"] = (1.0, 2.0)


# ---------------------------------------------------------------------------
# renderer
# ---------------------------------------------------------------------------

def draw_render(rng, model):
    zlo, zhi = ZOOM[model]
    p = {
        "zoom": loguniform(rng, zlo, zhi),
        "rotation": float(rng.uniform(0, 360)),
        "plain": bool(rng.random() < 0.2),
        "azimuth": float(rng.uniform(0, 360)),
        "elevation": float(rng.uniform(20, 70)),
        "relief": loguniform(rng, 0.35, 2.0),
        "ambient": float(rng.uniform(0.0, 0.15)),
        "gamma": float(rng.uniform(0.7, 1.4)),
        "blur": float(rng.uniform(0.0, 1.0)),
        "noise": float(rng.uniform(0.0, 3.0)),
        "invert": bool(rng.random() < 0.5),
    }
    th = math.radians(p["rotation"])
    p["need"] = SIZE * (abs(math.cos(th)) + abs(math.sin(th))) / p["zoom"] + 8
    return p


def render(field, p, rng):
    th = math.radians(p["rotation"])
    z = p["zoom"]
    yy, xx = np.mgrid[0:SIZE, 0:SIZE].astype(np.float64) - (SIZE - 1) / 2.0
    c, s = math.cos(th), math.sin(th)
    sy = (c * yy - s * xx) / z
    sx = (s * yy + c * xx) / z
    if callable(field):
        cy, cx = rng.uniform(-500, 500, 2)
        if z < 0.9:   # 2x2 supersampling against aliasing
            acc = 0.0
            for oy in (-0.25, 0.25):
                for ox in (-0.25, 0.25):
                    acc = acc + field((c * (yy + oy) - s * (xx + ox)) / z + cy,
                                      (s * (yy + oy) + c * (xx + ox)) / z + cx)
            h = acc / 4.0
        else:
            h = field(sy + cy, sx + cx)
    else:
        G = field.shape[0]
        cy, cx = rng.uniform(0, G, 2)
        src = np.asarray(field, np.float64)
        if z < 0.9:   # low-pass before minifying
            src = ndimage.gaussian_filter(src, 0.5 * math.sqrt(1 / z ** 2 - 1),
                                          mode="wrap")
        h = ndimage.map_coordinates(src, [sy + cy - 0.5, sx + cx - 0.5],
                                    order=3, mode="grid-wrap")
    h = np.asarray(h, np.float64)
    if p["plain"]:
        img = norm01(h)
        if p["invert"]:
            img = 1 - img
    else:
        h = h - h.mean()
        if p["invert"]:           # the sign of a height field is arbitrary
            h = -h
        gy, gx = np.gradient(h)
        grms = math.sqrt(float(np.mean(gx * gx + gy * gy))) + 1e-12
        k = p["relief"] / grms
        nx, ny, nz = -k * gx, -k * gy, np.ones_like(h)
        nn = np.sqrt(nx * nx + ny * ny + nz * nz)
        az, el = math.radians(p["azimuth"]), math.radians(p["elevation"])
        L = (math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))
        I = np.clip((nx * L[0] + ny * L[1] + nz * L[2]) / nn, 0, 1)
        a = p["ambient"]
        I = a + (1 - a) * I
        hi = np.percentile(I, 99.7)
        img = np.clip(I / max(hi, 1e-6) * rng.uniform(0.85, 1.0), 0, 1)
    img = img ** p["gamma"] * 255.0
    if p["blur"] > 0.05:
        img = ndimage.gaussian_filter(img, p["blur"], mode="reflect")
    img = img + rng.normal(0, p["noise"], img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


# ---------------------------------------------------------------------------
# driver
# ---------------------------------------------------------------------------

def image_rngs(mi, si, i):
    g = np.random.default_rng([BASE_SEED, mi, si, i, 0])   # generator
    r = np.random.default_rng([BASE_SEED, mi, si, i, 1])   # render params
    n = np.random.default_rng([BASE_SEED, mi, si, i, 2])   # render noise
    return g, r, n


def file_names():
    """Neutral, label-free file names: a seeded permutation of all items."""
    items = [(mi, si, i) for mi in range(len(MODELS))
             for si in range(len(SPLITS)) for i in range(PER_SPLIT)]
    perm = np.random.default_rng([BASE_SEED, 99]).permutation(len(items))
    return {items[k]: "xset_%03d.png" % (perm[k] + 1) for k in range(len(items))}


def save(out, name, img):
    Image.fromarray(img, mode="L").save(os.path.join(out, name), optimize=False)


def model_task(args):
    mi, out, names = args
    model = MODELS[mi]
    rows = []
    if model == "Reaction Diffusion":
        return rd_task(mi, out, names)
    gen, keys = SPEC[model]
    for si in range(len(SPLITS)):
        for i in range(PER_SPLIT):
            rg, rr, rn = image_rngs(mi, si, i)
            p = draw_render(rr, model)
            field, desc = gen(rg, p["need"], keys[i])
            img = render(field, p, rn)
            name = names[(mi, si, i)]
            save(out, name, img)
            rows.append((name, model, SPLITS[si], desc, p))
    return rows


def rd_task(mi, out, names):
    model = MODELS[mi]
    jobs, params, rngs = [], [], []
    for si in range(len(SPLITS)):
        for i in range(PER_SPLIT):
            rg, rr, rn = image_rngs(mi, si, i)
            p = draw_render(rr, model)
            # 8 variants: spread over the regime list, split-dependent choice
            pool = RD_REGIMES[:]
            j = (i * len(pool)) // PER_SPLIT + int(rg.integers(0, 2))
            name_r, F, k = pool[min(j, len(pool) - 1)]
            F *= rg.uniform(0.98, 1.02)
            k *= rg.uniform(0.995, 1.005)
            ds = rg.uniform(0.55, 1.0)
            jobs.append((si, i, p, rn, name_r, F, k, ds, bool(rg.random() < 0.5)))
            params.append((F, k, ds))
            rngs.append(rg)
    V = gray_scott_batch(rngs, params)
    rows = []
    for b, (si, i, p, rn, name_r, F, k, ds, useU) in enumerate(jobs):
        h = ndimage.zoom(V[b].astype(np.float64), 2, order=3, mode="grid-wrap",
                         grid_mode=True)
        img = render(h, p, rn)
        name = names[(mi, si, i)]
        save(out, name, img)
        desc = "gray-scott %s F=%.4f k=%.4f, diffusion scale %.2f, 128^2 sim x2" % (
            name_r, F, k, ds)
        rows.append((name, model, SPLITS[si], desc, p))
    return rows


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    repo = os.path.abspath(os.path.join(here, "..", ".."))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", default=os.path.join(repo, "target", "texture-xset"))
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--models", default="", help="comma separated model indices (debug)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    names = file_names()
    todo = list(range(len(MODELS)))
    if a.models:
        todo = [int(x) for x in a.models.split(",")]
    # the slowest tasks first so two workers balance well
    order = sorted(todo, key=lambda m: 0 if MODELS[m] in (
        "Reaction Diffusion", "Islamic Patterns", "Matrix Transformation") else 1)
    t0 = time.time()
    tasks = [(m, a.out, names) for m in order]
    results = []
    if a.jobs > 1:
        import multiprocessing as mp
        with mp.get_context("fork").Pool(a.jobs) as pool:
            for rows in pool.imap_unordered(model_task, tasks):
                results.extend(rows)
                print("  %-40s done (%.1fs)" % (rows[0][1], time.time() - t0), flush=True)
    else:
        for t in tasks:
            rows = model_task(t)
            results.extend(rows)
            print("  %-40s done (%.1fs)" % (rows[0][1], time.time() - t0), flush=True)
    results.sort(key=lambda r: r[0])
    with open(os.path.join(a.out, "labels.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["file", "model", "split", "variant"])
        for (name, model, split, desc, p) in results:
            w.writerow([name, model, split, desc])
    with open(os.path.join(a.out, "render.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        keys = ["zoom", "rotation", "plain", "invert", "azimuth", "elevation",
                "relief", "ambient", "gamma", "blur", "noise"]
        w.writerow(["file"] + keys)
        for (name, model, split, desc, p) in results:
            w.writerow([name] + [("%.3f" % p[k]) if isinstance(p[k], float)
                                 else int(p[k]) for k in keys])
    print("wrote %d images to %s in %.1fs" % (len(results), a.out, time.time() - t0))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""JAX-on-CPU reference of Fit's SDF loss (issue 9 item 6).

The same loss as src/pattern/loss.rs, `L = L_S + α_N·L_N` with
`L_S = 1/|C| Σ_c mean (S_c − T_c)²` and `L_N = 1/|C| Σ_c mean (1 − ⟨n_S, n_T⟩²)`
(central-difference normals, pixels where either gradient vanishes count 0),
on the same scene (the shipped generators `circles-grid` and `stripes-dots`,
written out below from their .flg programs), the same parameters and the same
target fields, which `filigree bench fit --speed-only --export-jax DIR`
writes as DIR/<generator>-<grid>.json together with our loss and gradient.
The pattern fields follow src/pattern/field: per colour, the "on top"
operator over the shapes in drawing order (union = min, difference =
max(B, −X)), strokes |d| − w/2, the magnitude clamped to the distance to the
canvas edge (and to CAP = 2), times the field scale (pixels of the grid).

Run (one core, XLA single-threaded; bench/fit_vs_jax.sh does all of it):

    python3 -m venv target/jax-venv && target/jax-venv/bin/pip install jax jaxlib
    target/release/filigree bench fit --speed-only --only circles-grid,stripes-dots \\
        --export-jax target/jax-cases
    XLA_FLAGS="--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1" \\
        taskset -c 0 target/jax-venv/bin/python bench/jax_fit_reference.py target/jax-cases/*.json

Prints one JSON object: per case, both loss values (ours from the export,
JAX's), their relative difference, the largest relative gradient difference,
and loss/s and loss+gradient/s (best and median of three timed windows after
jit compilation and warm-up, as `bench fit` measures ours), in float64 (our
precision) and float32; `jax_loss_evals_per_s` and `jax_loss_grad_evals_per_s`
are the faster of the two, the figure ratios are taken against.
"""
import json
import os
import sys
import time

os.environ.setdefault(
    "XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
)
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_platforms", "cpu")
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

CAP = 2.0


def circle_d(px, py, cx, cy, r):
    return jnp.sqrt((px - cx) ** 2 + (py - cy) ** 2) - r


def segment_d(px, py, ax, ay, bx, by):
    ex, ey = bx - ax, by - ay
    wx, wy = px - ax, py - ay
    t = jnp.clip((wx * ex + wy * ey) / (ex * ex + ey * ey), 0.0, 1.0)
    return jnp.sqrt((wx - ex * t) ** 2 + (wy - ey * t) ** 2)


def circles_grid(p, px, py):
    """assets/patterns/circles-grid.flg: one colour, 25 filled circles."""
    dx, dy, ox, oy, r = p[0], p[1], p[2], p[3], p[4]
    k = jnp.arange(5.0)
    cx = (ox + k * dx)[:, None] * jnp.ones(5)[None, :]
    cy = jnp.ones(5)[:, None] * (oy + k * dy)[None, :]
    cx, cy = cx.reshape(-1), cy.reshape(-1)
    d = circle_d(px[None], py[None], cx[:, None, None], cy[:, None, None], r)
    blue = jnp.minimum(CAP, jnp.min(d, axis=0))
    return [blue]


def stripes_dots(p, px, py):
    """assets/patterns/stripes-dots.flg: six stroked stripes (red), then a
    4×3 grid of dots (dark) on top. Channels in palette order: red, dark."""
    spacing, angle, width, offset = p[0], p[1], p[2], p[3]
    dot_r, dot_spacing, dot_x, dot_y = p[4], p[5], p[6], p[7]
    c, s = jnp.cos(angle), jnp.sin(angle)
    k = jnp.arange(6.0)
    d = offset + (k - 2.5) * spacing
    mx, my = 0.5 - s * d, 0.5 + c * d
    sd = segment_d(
        px[None], py[None],
        (mx - c)[:, None, None], (my - s)[:, None, None],
        (mx + c)[:, None, None], (my + s)[:, None, None],
    )
    w = jnp.maximum(width, 0.0)
    stripes = jnp.min(jnp.abs(sd) - 0.5 * w, axis=0)
    i, j = jnp.arange(4.0), jnp.arange(3.0)
    cx = ((dot_x + i * dot_spacing)[:, None] * jnp.ones(3)[None, :]).reshape(-1)
    cy = (jnp.ones(4)[:, None] * (dot_y + j * dot_spacing)[None, :]).reshape(-1)
    dots = jnp.min(circle_d(px[None], py[None], cx[:, None, None], cy[:, None, None], dot_r), axis=0)
    red = jnp.maximum(jnp.minimum(CAP, stripes), -dots)
    dark = jnp.minimum(CAP, dots)
    return [red, dark]


PROGRAMS = {"circles-grid": circles_grid, "stripes-dots": stripes_dots}


def stencil(n):
    i = np.arange(n)
    m, p = np.maximum(i - 1, 0), np.minimum(i + 1, n - 1)
    return m, p, 1.0 / np.maximum(p - m, 1)


def target_normals(t, n):
    m, p, ih = stencil(n)
    gx = (t[:, :, p] - t[:, :, m]) * ih[None, None, :]
    gy = (t[:, p, :] - t[:, m, :]) * ih[None, :, None]
    l = np.sqrt(gx * gx + gy * gy)
    ok = l > 1e-12
    ls = np.where(ok, l, 1.0)
    return np.where(ok, gx / ls, 0.0), np.where(ok, gy / ls, 0.0)


def central_x(f):
    """Central differences along the last axis, one-sided at the borders
    (slices, not gathers: XLA's CPU gathers are slow)."""
    return jnp.concatenate(
        [f[..., 1:2] - f[..., 0:1], (f[..., 2:] - f[..., :-2]) * 0.5, f[..., -1:] - f[..., -2:-1]],
        axis=-1,
    )


def central_y(f):
    return jnp.concatenate(
        [f[:, 1:2] - f[:, 0:1], (f[:, 2:] - f[:, :-2]) * 0.5, f[:, -1:] - f[:, -2:-1]], axis=1
    )


def make_loss(case, dtype):
    n = case["grid"]
    scale = case["scale"]
    alpha = case["normal_weight"]
    prog = PROGRAMS[case["generator"]]
    t = np.array(case["target_sdf"], dtype=np.float64).reshape(-1, n, n)
    channels = t.shape[0]
    tx, ty = target_normals(t, n)
    tmask = (tx != 0.0) | (ty != 0.0)
    xs = (np.arange(n) + 0.5) / n
    px, py = np.meshgrid(xs, xs)  # [y, x]
    ix = np.arange(n)
    edge_px = np.minimum(np.minimum(ix, n - 1 - ix)[None, :], np.minimum(ix, n - 1 - ix)[:, None])
    cap = np.minimum(CAP, (edge_px + 0.5) / n)
    norm = 1.0 / (channels * n * n)
    t, tx, ty, cap, px, py = (jnp.asarray(a, dtype=dtype) for a in (t, tx, ty, cap, px, py))
    tmask = jnp.asarray(tmask)
    tiny = 1e-24 if dtype == jnp.float64 else 1e-30

    def loss(params):
        s = jnp.stack([jnp.clip(f, -cap, cap) for f in prog(params, px, py)]) * scale
        ls = jnp.sum((s - t) ** 2) * norm
        gx, gy = central_x(s), central_y(s)
        l2 = gx * gx + gy * gy
        ok = tmask & (l2 > tiny)
        dot = (gx * tx + gy * ty) / jnp.sqrt(jnp.where(ok, l2, 1.0))
        ln = jnp.sum(jnp.where(ok, 1.0 - dot * dot, 0.0)) * norm
        return ls + alpha * ln

    return loss


def rate(f, x):
    jax.block_until_ready(f(x))  # compile
    for _ in range(3):
        jax.block_until_ready(f(x))  # warm up
    rates = []
    for _ in range(3):
        t0 = time.perf_counter()
        k = 0
        while time.perf_counter() - t0 < 0.3 or k < 3:
            jax.block_until_ready(f(x))
            k += 1
        rates.append(k / (time.perf_counter() - t0))
    rates.sort()
    return rates[2], rates[1]


def main(paths):
    out = []
    for path in paths:
        with open(path) as fh:
            case = json.load(fh)
        if case["generator"] not in PROGRAMS:
            print(f"{path}: no JAX version of {case['generator']}; skipped", file=sys.stderr)
            continue
        row = {"generator": case["generator"], "grid": case["grid"], "loss_filigree": case["loss"]}
        g = np.asarray(case["grad"])
        gscale = max(np.max(np.abs(g)), 1e-300)
        for dtype, key in [(jnp.float64, "f64"), (jnp.float32, "f32")]:
            x = jnp.asarray(case["params"], dtype=dtype)
            loss = jax.jit(make_loss(case, dtype))
            loss_grad = jax.jit(jax.value_and_grad(make_loss(case, dtype)))
            lj = float(loss(x))
            _, gj = loss_grad(x)
            gj = np.asarray(gj, dtype=np.float64)
            lo, lg = rate(loss, x), rate(loss_grad, x)
            row[key] = {
                "loss_jax": lj,
                "loss_rel_diff": abs(lj - case["loss"]) / max(abs(case["loss"]), 1e-300),
                "grad_max_rel_diff": float(np.max(np.abs(gj - g)) / gscale),
                "loss_evals_per_s": round(lo[0]), "loss_grad_evals_per_s": round(lg[0]),
                "median_loss_evals_per_s": round(lo[1]),
                "median_loss_grad_evals_per_s": round(lg[1]),
            }
        # The reference figure: the faster precision (a conservative ratio).
        row["jax_loss_evals_per_s"] = max(row["f64"]["loss_evals_per_s"], row["f32"]["loss_evals_per_s"])
        row["jax_loss_grad_evals_per_s"] = max(
            row["f64"]["loss_grad_evals_per_s"], row["f32"]["loss_grad_evals_per_s"])
        out.append(row)
    print(json.dumps({"bench": "jax_fit_reference", "jax": jax.__version__, "cases": out}, indent=2))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])

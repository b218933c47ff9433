"""Issue 36 probe: a small convolutional network learnt from renders of two
implementations, read on the cross-implementation validation set.

python3 src/bench/examples/texture_cnn_probe.py OURS_DIR XVAL_DIR INDOMAIN_DIR TRAIN_DIR...

OURS_DIR: our dataset as PNGs with labels.csv (texture_xset_dump
--write-images; its `variant` column marks the bases `bench texture` holds
out, which are read, never learnt); XVAL_DIR: the VALIDATION part of the
cross-implementation set (labels.csv); INDOMAIN_DIR: one bench/texture-train
set never learnt (the ceiling inside that implementation); TRAIN_DIR:
bench/texture-train sets (file names start with the model's index in
gen.py's MODELS).

Each image is halved (256² -> 128², area mean) and standardised (zero mean,
unit deviation). Training takes random 64² windows with a random dihedral
symmetry, gamma and Gaussian noise; reading takes the whole 128² picture
(the network is convolutional with a global mean and deviation pooling, so
any size reads). Six 3×3 convolutions (the first 5×5), three of stride 2,
ReLU, channels 16-128: ~7 M multiply-adds a 64² window, ~29 M a 128²
picture. Adam, cosine schedule, label smoothing 0.1. Prints after each
epoch: cross-implementation top-1 / top-3 / ECE, in-domain top-1, and
our held-out bases' top-1. Needs numpy, pillow, jax (CPU).
Environment: EPOCHS (12), SEED (0), WIDTH (1.0: channel multiplier).
"""
import csv
import math
import os
import sys
import time

import numpy as np
from PIL import Image

import jax
import jax.numpy as jnp

EPOCHS = int(os.environ.get("EPOCHS", "12"))
SEED = int(os.environ.get("SEED", "0"))
WIDTH = float(os.environ.get("WIDTH", "1.0"))
CROP = 64
BATCH = 64


def halve(path):
    a = np.asarray(Image.open(path).convert("L"), dtype=np.float32)
    h, w = a.shape[0] // 2 * 2, a.shape[1] // 2 * 2
    a = a[:h, :w].reshape(h // 2, 2, w // 2, 2).mean((1, 3))
    if a.shape != (128, 128):
        a = np.asarray(Image.fromarray(a).resize((128, 128), Image.BILINEAR), dtype=np.float32)
    return a


def load_labelled(d):
    rows = list(csv.DictReader(open(os.path.join(d, "labels.csv"))))
    X = np.stack([halve(os.path.join(d, r["file"])) for r in rows])
    return X, np.array([r["model"] for r in rows]), rows


# The models in bench/texture-train/gen.py's order (its file names' prefix).
def gen_models():
    here = os.path.dirname(os.path.abspath(__file__))
    src = open(os.path.join(here, "../../../bench/texture-train/gen.py")).read()
    start = src.index("MODELS = [")
    return [s.strip().strip('",') for s in src[start:src.index("]", start)].splitlines()[1:] if s.strip()]


def load_gen(d, models):
    files = sorted(f for f in os.listdir(d) if f.endswith(".png"))
    X = np.stack([halve(os.path.join(d, f)) for f in files])
    return X, np.array([models[int(f[:2])] for f in files])


def standardise(X):
    m = X.mean((1, 2), keepdims=True)
    s = X.std((1, 2), keepdims=True) + 1e-3
    return ((X - m) / s).astype(np.float32)


t0 = time.time()
models = gen_models()
O, yo, orows = load_labelled(sys.argv[1])
held = np.array([int(r["variant"]) for r in orows]) == 1
V, yv, _ = load_labelled(sys.argv[2])
T, yt = load_gen(sys.argv[3], models)
gens = [load_gen(d, models) for d in sys.argv[4:]]
classes = sorted(set(yo))
assert set(models) == set(classes), "the two implementations name the same 23 models"
idx = {m: i for i, m in enumerate(classes)}
Xtr = np.concatenate([O[~held]] + [g[0] for g in gens])
ytr = np.array([idx[m] for m in np.concatenate([yo[~held]] + [g[1] for g in gens])])
# Both implementations weigh alike in the loss, whatever their counts.
n_ours = int((~held).sum())
wtr = np.concatenate([np.full(n_ours, 0.5 / n_ours), np.full(len(ytr) - n_ours, 0.5 / (len(ytr) - n_ours))])
wtr = (wtr / wtr.mean()).astype(np.float32)
print(f"loaded in {time.time() - t0:.0f} s: train {len(ytr)} ({n_ours} ours), xval {len(yv)}, "
      f"in-domain {len(yt)}, ours held-out {held.sum()}", flush=True)

CH = [max(4, int(round(c * WIDTH))) for c in (16, 32, 48, 64, 96, 128)]
LAYERS = [(5, 1, CH[0], 2), (3, CH[0], CH[1], 1), (3, CH[1], CH[2], 2),
          (3, CH[2], CH[3], 1), (3, CH[3], CH[4], 2), (3, CH[4], CH[5], 1)]


def init(key):
    params = []
    for k, cin, cout, _ in LAYERS:
        key, sub = jax.random.split(key)
        params.append((jax.random.normal(sub, (k, k, cin, cout)) * math.sqrt(2.0 / (k * k * cin)),
                       jnp.zeros(cout)))
    key, sub = jax.random.split(key)
    params.append((jax.random.normal(sub, (2 * CH[5], len(classes))) * math.sqrt(1.0 / (2 * CH[5])),
                   jnp.zeros(len(classes))))
    return params


def forward(params, x):
    h = x[..., None]
    for (w, b), (_, _, _, s) in zip(params[:-1], LAYERS):
        h = jax.lax.conv_general_dilated(h, w, (s, s), "SAME", dimension_numbers=("NHWC", "HWIO", "NHWC"))
        h = jax.nn.relu(h + b)
    m = h.mean((1, 2))
    sd = jnp.sqrt(((h - m[:, None, None, :]) ** 2).mean((1, 2)) + 1e-6)
    w, b = params[-1]
    return jnp.concatenate([m, sd], 1) @ w + b


def loss_fn(params, x, y, wt):
    logits = forward(params, x)
    n = len(classes)
    target = jax.nn.one_hot(y, n) * 0.9 + 0.1 / n
    return (-(target * jax.nn.log_softmax(logits)).sum(1) * wt).mean()


@jax.jit
def train_step(params, m, v, t, lr, x, y, wt):
    g = jax.grad(loss_fn)(params, x, y, wt)
    b1, b2 = 0.9, 0.999
    m = jax.tree_util.tree_map(lambda a, b: b1 * a + (1 - b1) * b, m, g)
    v = jax.tree_util.tree_map(lambda a, b: b2 * a + (1 - b2) * b * b, v, g)
    c1, c2 = 1 - b1 ** t, 1 - b2 ** t
    params = jax.tree_util.tree_map(
        lambda p, a, b: p - lr * ((a / c1) / (jnp.sqrt(b / c2) + 1e-8) + 1e-4 * p), params, m, v)
    return params, m, v


predict = jax.jit(lambda p, x: jax.nn.softmax(forward(p, x)))


def augment(rng, X):
    n = len(X)
    out = np.empty((n, CROP, CROP), np.float32)
    for i in range(n):
        y0, x0 = rng.integers(0, 128 - CROP + 1, 2)
        a = X[i, y0:y0 + CROP, x0:x0 + CROP]
        a = np.rot90(a, rng.integers(4))
        if rng.random() < 0.5:
            a = a[:, ::-1]
        # gamma on the 0..255 picture, then noise, then standardise
        g = math.exp(rng.normal(0, 0.25))
        a = 255.0 * (np.clip(a, 0, 255) / 255.0) ** g
        a = a + rng.normal(0, rng.uniform(0, 4), a.shape)
        out[i] = a
    return standardise(out)


def read(params, X):
    Xs = standardise(X)
    return np.concatenate([np.asarray(predict(params, Xs[i:i + 128])) for i in range(0, len(Xs), 128)])


def scores(P, y):
    top = np.argsort(-P, 1)
    yi = np.array([idx[m] for m in y])
    right = top[:, 0] == yi
    conf = P.max(1)
    bins = np.minimum((conf * 10).astype(int), 9)
    ece = sum(abs(right[bins == b].mean() - conf[bins == b].mean()) * (bins == b).mean()
              for b in range(10) if (bins == b).any())
    return right.mean(), (top[:, :3] == yi[:, None]).any(1).mean(), ece


rng = np.random.default_rng(SEED)
params = init(jax.random.PRNGKey(SEED))
m = jax.tree_util.tree_map(jnp.zeros_like, params)
v = jax.tree_util.tree_map(jnp.zeros_like, params)
steps_per_epoch = len(ytr) // BATCH
total = EPOCHS * steps_per_epoch
t = 0
print(f"channels {CH}, {steps_per_epoch} steps an epoch", flush=True)
for epoch in range(EPOCHS):
    t1 = time.time()
    order = rng.permutation(len(ytr))
    for s in range(steps_per_epoch):
        b = order[s * BATCH:(s + 1) * BATCH]
        t += 1
        lr = 2e-3 * 0.5 * (1 + math.cos(math.pi * t / total))
        params, m, v = train_step(params, m, v, t, lr, augment(rng, Xtr[b]), ytr[b], wtr[b])
    xs = scores(read(params, V), yv)
    ind = scores(read(params, T), yt)
    oh = scores(read(params, O[held]), yo[held])
    print(f"epoch {epoch + 1}: xval top1/top3/ECE {xs[0]:.3f}/{xs[1]:.3f}/{xs[2]:.3f} | in-domain top1 {ind[0]:.3f}"
          f" | ours held-out top1 {oh[0]:.3f} | {time.time() - t1:.0f} s", flush=True)
if os.environ.get("SAVE"):
    np.savez(os.environ["SAVE"], *[np.asarray(a) for layer in params for a in layer])

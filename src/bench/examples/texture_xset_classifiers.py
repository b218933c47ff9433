"""Issue 36 classifier experiments on cached features (see
src/bench/examples/texture_xset_dump.rs):
python3 src/bench/examples/texture_xset_classifiers.py DIR KIND...

Judged on the held-out bases, the paper's split and the cross-implementation
set's VALIDATION part only (the dump holds no test image).
KIND: lin:C (one-vs-rest squared hinge, balanced, L-BFGS: a stand-in for
the Rust linear SVM), ens:C:D:G (lin:C and rff:D:G:C, scores summed), soft:L2 (multinomial logistic), rff:D:G:C (random Fourier
features of an RBF kernel, gamma = G / mean squared distance, then lin:C),
mlp:H:L2 (one hidden ReLU layer of H, softmax, L-BFGS, ITER iterations).
A prefix h- reads the square-rooted histograms as they are (no chi2 map);
a suffix ! skips the paper's split (a second training). Environment: GW
(weight of the standardised global values, 1), LBPW / PCNW (weights of the
LBP and PCN histograms, h- only), LOOKDUP=k (look rows k times in training),
NOLIGHT1=1 (drop the second light's clean images from training).
EXTRA=PREFIX,... (more training rows: another implementation's images,
dumped with texture_xset_dump --views-only; EXTRAT, EXTRADUP below),
ONLYPAPER=1 (only the paper's split), XSET=xset-scales (the dump's
--scales reads; PER=1 prints each model's validation counts).
Prints held-out bases (first images, their looks), the paper's split and
the validation images' top-1/top-3 as read (transform 0), and with their
scores summed over 2 (identity, mirror) and all 8 rotations and mirrors.
"""
import sys, time
import numpy as np
from scipy.optimize import minimize

D = sys.argv[1]
meta = np.genfromtxt(f"{D}/rows.csv", delimiter=",", skip_header=1, dtype=np.int64)
dim = int(meta[0, 7])
X = np.fromfile(f"{D}/rows.f32", dtype="<f4").reshape(len(meta), -1)
XT = __import__("os").environ.get("XSET", "xset")
xm = np.genfromtxt(f"{D}/{XT}.csv", delimiter=",", skip_header=1, dtype=np.int64)
XS = np.fromfile(f"{D}/{XT}.f32", dtype="<f4").reshape(len(xm), -1)
model, base, held, look, light, crop, ptest = (meta[:, i] for i in range(7))
# EXTRA=PREFIX[,PREFIX...]: more training rows, another implementation's
# images as `--views-only` dumped them (PREFIX.f32 / PREFIX.csv: image,
# model, transform, view); EXTRAT=t keeps transforms < t (8: all).
EXTRA = [e for e in __import__("os").environ.get("EXTRA", "").split(",") if e]
if EXTRA:
    _t = int(__import__("os").environ.get("EXTRAT", "8"))
    _xs, _ys = [], []
    for e in EXTRA:
        em = np.genfromtxt(f"{e}.csv", delimiter=",", skip_header=1, dtype=np.int64)
        ex = np.fromfile(f"{e}.f32", dtype="<f4").reshape(len(em), -1)
        keep = em[:, 2] < _t
        _xs.append(ex[keep]); _ys.append(em[keep, 1])
    EX, EY = np.vstack(_xs), np.concatenate(_ys)
    print(f"extra training rows: {len(EX)}", flush=True)
K = 23
import os
GW = float(os.environ.get('GW', '1'))
LBPW = float(os.environ.get('LBPW', '1'))
PCNW = float(os.environ.get('PCNW', '1'))


def chi2(h):
    h = h.astype(np.float64) ** 2
    L = 0.5
    a0, a1 = L * 1.0, 2 * L / np.cosh(np.pi * L)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = L * np.log(h)
        r = np.sqrt(a1 * h)
        out = np.stack([np.sqrt(a0 * h), r * np.cos(t), r * np.sin(t)], -1)
    out[h <= 0] = 0
    return out.reshape(len(h), -1).astype(np.float32)


class Rows:
    def __init__(self, Xtr, hell=False):
        self.hell = hell
        g = Xtr[:, dim:].astype(np.float64)
        self.m = g.mean(0)
        sd = g.std(0)
        self.s = np.where(sd > 1e-6, sd, 1.0)

    def __call__(self, X):
        z = np.clip((X[:, dim:] - self.m) / self.s, -5, 5) * GW
        z = np.nan_to_num(z)
        h = X[:, :dim].astype(np.float32) if self.hell else chi2(X[:, :dim])
        if self.hell and (LBPW != 1 or PCNW != 1):
            h = h.copy()
            h[:, dim - 162:] *= LBPW
            h[:, :dim - 178] *= PCNW
        return np.hstack([h, z.astype(np.float32)])


def ovr_sqhinge(R, y, C):
    n, d = R.shape
    Y = -np.ones((n, K))
    Y[np.arange(n), y] = 1
    npos = np.bincount(y, minlength=K)
    wpos = n / (2.0 * np.maximum(npos, 1))
    wneg = n / (2.0 * np.maximum(n - npos, 1))
    Wt = np.where(Y > 0, wpos[None, :], wneg[None, :])
    mu = R.mean(0)
    Rc = np.hstack([R - mu, np.ones((n, 1))])

    def f(w):
        W = w.reshape(d + 1, K)
        m = np.maximum(0, 1 - Y * (Rc @ W))
        loss = 0.5 * (W * W).sum() + C * (Wt * m * m).sum()
        G = W - 2 * C * Rc.T @ (Wt * m * Y)
        return loss, G.ravel()

    r = minimize(f, np.zeros((d + 1) * K), jac=True, method="L-BFGS-B", options={"maxiter": 300})
    W = r.x.reshape(d + 1, K)
    return lambda Q: np.hstack([Q - mu, np.ones((len(Q), 1))]) @ W


def softmax_reg(R, y, l2):
    n, d = R.shape
    mu, sd = R.mean(0), R.std(0) + 1e-6
    Rc = np.hstack([(R - mu) / sd, np.ones((n, 1))])
    Y = np.eye(K)[y]

    def f(w):
        W = w.reshape(d + 1, K)
        S = Rc @ W
        S -= S.max(1, keepdims=True)
        P = np.exp(S)
        P /= P.sum(1, keepdims=True)
        loss = -np.log(P[np.arange(n), y] + 1e-300).mean() + 0.5 * l2 * (W[:-1] ** 2).sum()
        G = Rc.T @ (P - Y) / n
        G[:-1] += l2 * W[:-1]
        return loss, G.ravel()

    r = minimize(f, np.zeros((d + 1) * K), jac=True, method="L-BFGS-B", options={"maxiter": 500})
    W = r.x.reshape(d + 1, K)
    return lambda Q: np.hstack([(Q - mu) / sd, np.ones((len(Q), 1))]) @ W


def mlp(R, y, H, l2, seed=1):
    n, d = R.shape
    mu, sd = R.mean(0), R.std(0) + 1e-6
    Rc = (R - mu) / sd
    rng = np.random.default_rng(seed)
    W1 = rng.normal(0, np.sqrt(2.0 / d), (d, H))
    W2 = rng.normal(0, np.sqrt(1.0 / H), (H, K))
    shapes = [(d, H), (H,), (H, K), (K,)]
    x0 = np.concatenate([W1.ravel(), np.zeros(H), W2.ravel(), np.zeros(K)])
    Y = np.eye(K)[y]

    def unpack(w):
        out, o = [], 0
        for s in shapes:
            k = int(np.prod(s))
            out.append(w[o:o + k].reshape(s))
            o += k
        return out

    def f(w):
        A, b, B, c = unpack(w)
        Z = Rc @ A + b
        Hh = np.maximum(Z, 0)
        S = Hh @ B + c
        S -= S.max(1, keepdims=True)
        P = np.exp(S)
        P /= P.sum(1, keepdims=True)
        loss = -np.log(P[np.arange(n), y] + 1e-300).mean() + 0.5 * l2 * ((A ** 2).sum() + (B ** 2).sum())
        dS = (P - Y) / n
        gB = Hh.T @ dS + l2 * B
        gc = dS.sum(0)
        dH = dS @ B.T * (Z > 0)
        gA = Rc.T @ dH + l2 * A
        gb = dH.sum(0)
        return loss, np.concatenate([gA.ravel(), gb, gB.ravel(), gc])

    r = minimize(f, x0, jac=True, method="L-BFGS-B", options={"maxiter": int(os.environ.get("ITER", "150"))})
    A, b, B, c = unpack(r.x)
    return lambda Q: np.maximum(((Q - mu) / sd) @ A + b, 0) @ B + c


def rff(Rtr, Dn, G, seed=3):
    rng = np.random.default_rng(seed)
    idx = rng.choice(len(Rtr), min(2000, len(Rtr)), replace=False)
    S = Rtr[idx]
    # mean squared distance over random pairs (all columns)
    a, b = S[: len(S) // 2], S[len(S) // 2: 2 * (len(S) // 2)]
    msd = ((a - b) ** 2).sum(1).mean()
    gamma = G / msd
    Wf = rng.normal(0, np.sqrt(2 * gamma), (Rtr.shape[1], Dn))
    bf = rng.uniform(0, 2 * np.pi, Dn)
    return lambda Q: np.sqrt(2.0 / Dn) * np.cos(Q @ Wf + bf)


def make(kind, R, y):
    p = kind.split(":")
    if p[0] == "lin":
        return ovr_sqhinge(R, y, float(p[1]))
    if p[0] == "soft":
        return softmax_reg(R, y, float(p[1]))
    if p[0] == "mlp":
        return mlp(R, y, int(p[1]), float(p[2]))
    if p[0] == "rff":
        phi = rff(R, int(p[1]), float(p[2]))
        inner = ovr_sqhinge(phi(R), y, float(p[3]))
        return lambda Q: inner(phi(Q))
    if p[0] == "ens":
        # ens:C:D:G: lin:C and rff:D:G:C, each one's scores over their
        # spread on the training rows, summed.
        a = ovr_sqhinge(R, y, float(p[1]))
        phi = rff(R, int(p[2]), float(p[3]))
        PR = phi(R)
        b = ovr_sqhinge(PR, y, float(p[1]))
        sa, sb = a(R).std(), b(PR).std()
        return lambda Q: a(Q) / sa + b(phi(Q)) / sb
    raise SystemExit(kind)


def run(kind, paper=True):
    t = time.time()
    hell = kind.startswith("h-")
    label = kind
    kind = kind[2:] if hell else kind
    tr = held == 0
    rows = Rows(np.vstack([X[tr]] + ([EX] if EXTRA else [])), hell)
    R = rows(X)
    ti = np.nonzero(tr)[0]
    dup = int(os.environ.get("LOOKDUP", "1"))
    if dup > 1:
        ti = np.concatenate([ti] + [ti[look[ti] == 1]] * (dup - 1))
    if os.environ.get("NOLIGHT1"):
        ti = ti[(look[ti] == 1) | (light[ti] == 0)]
    if os.environ.get("ONLYPAPER"):
        clf = lambda Q: np.zeros((len(Q), K))
    elif EXTRA:
        dupx = int(os.environ.get("EXTRADUP", "1"))
        ER = rows(EX)
        clf = make(kind, np.vstack([R[ti]] + [ER] * dupx), np.concatenate([model[ti]] + [EY] * dupx))
    else:
        clf = make(kind, R[ti], model[ti])
    # held-out bases: first image (light 0, first crop seen), and their looks
    first = {}
    for i in np.nonzero((held == 1) & (look == 0) & (light == 0))[0]:
        first.setdefault(base[i], i)
    fi = np.array(sorted(first.values()))
    ho = (clf(R[fi]).argmax(1) == model[fi]).mean()
    li = np.nonzero((held == 1) & (look == 1))[0]
    lo = (clf(R[li]).argmax(1) == model[li]).mean()
    # xset validation
    RS = rows(XS)
    sc = clf(RS)
    img = xm[:, 0]
    n = img.max() + 1
    res = {}
    reads = (("x", xm[:, 2] == 0), ("tta8", np.ones(len(xm), bool)), ("tta2", xm[:, 2] <= 1))
    if XT == "xset-scales":
        # 1x both windows / 1x first window + the halved image / all three / halved alone
        reads = (("x", xm[:, 2] == 0), ("tta2", ((xm[:, 2] == 0) & (xm[:, 3] == 0)) | (xm[:, 2] == 1)),
                 ("tta8", np.ones(len(xm), bool)), ("half", xm[:, 2] == 1))
    for name, sel in reads:
        S = np.zeros((n, K))
        np.add.at(S, img[sel], sc[sel])
        want = np.zeros(n, int)
        want[img] = xm[:, 1]
        top1 = (S.argmax(1) == want).mean()
        rank = (S > S[np.arange(n), want][:, None]).sum(1)
        top3 = (rank < 3).mean()
        res[name] = (top1, top3)
        if os.environ.get("PER") and name == "x":
            names = open("src/texture/models/mod.rs").read()
            for m in range(K):
                k = want == m
                print(f"   model {m:2d}: {(S.argmax(1)[k] == m).sum()}/{k.sum()}  top3 {(rank[k] < 3).sum()}")
    pp = float("nan")
    if os.environ.get("ONLYPAPER"):
        res = {k: (float("nan"), float("nan")) for k in ("x", "tta2", "tta8")}
    if paper:
        ptr = ptest == 0
        prow = Rows(X[ptr], hell)
        PR = prow(X)
        pclf = make(kind, PR[ptr], model[ptr])
        te = ptest == 1
        pp = (pclf(PR[te]).argmax(1) == model[te]).mean()
    if XT == "xset-scales":
        print("   (xset-scales: x = 1x two windows, tta2 = 1x first window + halved image, tta8 = all three, half = halved alone: ", {k: v for k, v in res.items()}, ")")
    print(f"{label:22s} held {ho:.3f} looks {lo:.3f} paper {pp:.3f} | xset top1/top3 {res['x'][0]:.3f}/{res['x'][1]:.3f}"
          f" tta2 {res['tta2'][0]:.3f}/{res['tta2'][1]:.3f} tta8 {res['tta8'][0]:.3f}/{res['tta8'][1]:.3f} ({time.time()-t:.0f}s)",
          flush=True)


for k in sys.argv[2:]:
    nop = k.endswith("!")
    run(k.rstrip("!"), paper=not nop)

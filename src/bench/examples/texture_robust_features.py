"""Issue 36 probe: shading-, rotation- and scale-robust texture descriptors
computed in Python on labelled PNG directories (any `labels.csv` with
`file,model,...`), to judge a feature family before it is written in Rust.
python3 src/bench/examples/texture_robust_features.py DIR OUT.npz [--half]

Per 128² window (a 128² image is one window; a 256² image is its two
diagonal quadrants, averaged, as the index's `Pcn::views` reads a query):
- wavelet scattering (Kymatio's numpy frontend, J = 4, L = 8, order 2),
  spatially averaged, first order averaged over the 8 angles, second order
  averaged over theta1 keeping theta2 - theta1 (rotation invariance), logs;
- rotation-invariant uniform LBP histograms, (P, R) = (8, 1), (16, 2),
  (24, 3), at the window's scale and halved, square-rooted;
- the log power spectrum in 12 log-spaced radial bands (mean removed) and
  12 orientation bins sorted (anisotropy without a direction);
- intensity skew and kurtosis, the share of flat pixels, gradient skew
  and kurtosis.
With --half a 256² image is read whole instead: scattering and spectrum
on it halved to 128² (its 2 × 2 means), LBP on it and on it halved,
moments on it; the variant that read the cross-implementation set
better (the report). 189 values. Needs numpy, scipy, pillow, scikit-image, kymatio (pip).
Findings: docs/bench/texture-xset-2026-12-07b.md.
"""
import sys, csv, numpy as np
from PIL import Image
from multiprocessing import Pool
from scipy import ndimage, stats
from skimage.feature import local_binary_pattern
from kymatio.scattering2d.frontend.numpy_frontend import ScatteringNumPy2D as Scattering2D

NAMES = None
S128 = None
def init():
    global S128
    S128 = Scattering2D(J=4, shape=(128, 128), L=8, max_order=2)

def scat(img):
    x = img.astype(np.float32)
    x = (x - x.mean()) / (x.std() + 1e-6)
    S = S128.scattering(x)  # (C, 8, 8)
    s = S.mean(axis=(-1, -2))
    # orders: 0: 1; 1: J*L = 32; 2: L*L*J*(J-1)/2 = 384
    J, L = 4, 8
    o0 = s[:1]
    o1 = s[1:1 + J * L].reshape(J, L)
    o2 = s[1 + J * L:]
    # rotation average of first order; second order averaged over theta1, keeping (theta2 - theta1)
    f1 = np.log(o1.mean(1) + 1e-6)
    # second order index layout in kymatio: for j1, for theta1, for j2>j1, for theta2
    rows = []
    k = 0
    acc = {}
    for j1 in range(J):
        for t1 in range(L):
            for j2 in range(j1 + 1, J):
                for t2 in range(L):
                    key = (j1, j2, (t2 - t1) % L)
                    acc.setdefault(key, []).append(o2[k]); k += 1
    f2 = np.log(np.array([np.mean(acc[kk]) for kk in sorted(acc)]) + 1e-6)
    # normalise second order by first (scale-ish invariance)
    return np.concatenate([f1, f2])

def lbp(img):
    out = []
    for im in (img, ndimage.zoom(img, 0.5, order=1)):
        for P, R in ((8, 1), (16, 2), (24, 3)):
            c = local_binary_pattern(im, P, R, method="uniform")
            h = np.bincount(c.astype(int).ravel(), minlength=P + 2).astype(float)
            out.append(np.sqrt(h / h.sum()))
    return np.concatenate(out)

def spectral(img):
    x = img - img.mean()
    w = np.hanning(x.shape[0])[:, None] * np.hanning(x.shape[1])[None, :]
    F = np.abs(np.fft.fftshift(np.fft.fft2(x * w))) ** 2
    n = x.shape[0]
    yy, xx = np.mgrid[:n, :n] - n // 2
    r = np.hypot(xx, yy); th = np.arctan2(yy, xx) % np.pi
    edges = np.geomspace(1, n / 2, 13)
    band = [F[(r >= a) & (r < b)].mean() for a, b in zip(edges[:-1], edges[1:])]
    band = np.log(np.array(band) + 1e-9); band -= band.mean()
    m = (r >= 2) & (r < n / 2)
    ang = np.bincount((th[m] / np.pi * 12).astype(int) % 12, weights=F[m], minlength=12)
    ang = np.sort(ang / ang.sum())
    return np.concatenate([band, np.log(ang + 1e-9)])

def inten(img):
    x = (img - img.mean()) / (img.std() + 1e-6)
    g = np.hypot(ndimage.sobel(img, 0), ndimage.sobel(img, 1))
    g = g / (g.mean() + 1e-6)
    flat = (g < 0.1).mean()
    return np.array([stats.skew(x.ravel()), stats.kurtosis(x.ravel()), flat,
                     stats.skew(g.ravel()), np.log(stats.kurtosis(g.ravel()) + 3)])

def feat(w):
    return np.concatenate([scat(w), lbp(w), spectral(w), inten(w)])

def one(path):
    img = np.asarray(Image.open(path).convert("L"), dtype=np.float64)
    if img.shape == (128, 128):
        return feat(img)
    assert img.shape == (256, 256), img.shape
    if HALF:
        small = img.reshape(128, 2, 128, 2).mean((1, 3))
        return np.concatenate([scat(small), lbp(img), spectral(small), inten(img)])
    return (feat(img[:128, :128]) + feat(img[128:, 128:])) / 2

HALF = "--half" in sys.argv

if __name__ == "__main__":
    d, out = sys.argv[1], sys.argv[2]
    rows = list(csv.DictReader(open(f"{d}/labels.csv")))
    paths = [f"{d}/{r['file']}" for r in rows]
    with Pool(2, initializer=init) as p:
        X = np.array(p.map(one, paths, chunksize=8))
    np.savez(out, X=X, model=np.array([r["model"] for r in rows]), files=np.array([r["file"] for r in rows]))
    print(out, X.shape)

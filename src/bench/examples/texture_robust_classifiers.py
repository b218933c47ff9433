"""Issue 36 probe: classifiers on texture_robust_features.py's descriptors.
python3 src/bench/examples/texture_robust_classifiers.py OURS.npz OURS_LABELS.csv XVAL.npz TRAIN.npz...

OURS.npz: our dataset's images (texture_xset_dump --write-images, whose
labels.csv says in its last column whether the image's base is one that
`bench texture` holds out); XVAL.npz: the cross-implementation set's
VALIDATION images only; TRAIN.npz: bench/texture-train sets. Standardised
features, an RBF SVM (C from the environment, 10) with Platt
probabilities; the first 2, 4, ... TRAIN sets with their images
weighted 2W/n (n sets; W in 2, 4, 8), so that together they weigh as
much as two sets at weight W, whatever n. Prints cross-implementation top-1, top-3 and the
expected calibration error (10 bins), and the same on our held-out bases.
Also: bench/texture-train alone, and our training bases alone. PER=1:
only ours + all TRAIN sets at weight 2, with each model's validation
counts (top-1, top-3, the two commonest wrong answers) and per family.
INDOMAIN=1: the ceiling inside one implementation: the last TRAIN set
is held out, and the first 2, 4, ... of the others train (no Platt
step; C 10 and 100); top-1 on the held-out set, then the commonest
confusions of the largest training.
Needs numpy, scikit-learn. Findings: docs/bench/texture-xset-2026-12-07b.md.
"""
import csv
import os
import sys
import warnings

import numpy as np
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

warnings.filterwarnings("ignore")


def load(p):
    z = np.load(p)
    return np.nan_to_num(z["X"], nan=0.0, posinf=0.0, neginf=0.0), z["model"]


O, yo = load(sys.argv[1])
held = np.array([int(r["variant"]) for r in csv.DictReader(open(sys.argv[2]))]) == 1
V, yv = load(sys.argv[3])
D3 = [load(p) for p in sys.argv[4:]]
C = float(os.environ.get("C", "10"))


def evaluate(clf, sc, X, y):
    P = clf.predict_proba(sc.transform(X))
    top = clf.classes_[np.argsort(-P, 1)]
    conf, right = P.max(1), top[:, 0] == y
    bins = np.minimum((conf * 10).astype(int), 9)
    ece = sum(abs(right[bins == b].mean() - conf[bins == b].mean()) * (bins == b).mean()
              for b in range(10) if (bins == b).any())
    return f"{right.mean():.3f} / {(top[:, :3] == y[:, None]).any(1).mean():.3f} / {ece:.3f}"


def per_model(clf, sc):
    import collections
    P = clf.predict_proba(sc.transform(V))
    top = clf.classes_[np.argsort(-P, 1)]
    for m in sorted(set(yv)):
        k = yv == m
        wrong = collections.Counter(top[k, 0][top[k, 0] != m]).most_common(2)
        print(f"| {m} | {(top[k, 0] == m).sum()}/{k.sum()} | {(top[k, :3] == m).any(1).sum()}/{k.sum()} | "
              + ", ".join(f"{a} {b}" for a, b in wrong) + " |")
    prefixes = ("Folding", "Fusion", "Texton", "Fractal", "CA")
    fam = np.vectorize(lambda m: next((p for p in prefixes if m.startswith(p)), m))
    ff, pf = fam(yv), fam(top[:, 0])
    print(f"family right {(ff == pf).mean():.3f}")
    for f in sorted(set(ff)):
        k = ff == f
        print(f"| {f} | {(top[k, 0] == yv[k]).sum()} / {(pf[k] == f).sum()} of {k.sum()} |")


def run(label, parts):
    X = np.vstack([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    w = np.concatenate([np.full(len(p[1]), p[2]) for p in parts])
    sc = StandardScaler().fit(X)
    clf = SVC(C=C, probability=True, random_state=0).fit(sc.transform(X), y, sample_weight=w)
    print(f"{label:44s} xval top1/top3/ECE {evaluate(clf, sc, V, yv)}"
          f" | ours held-out {evaluate(clf, sc, O[held], yo[held])}", flush=True)
    return clf, sc


if os.environ.get("INDOMAIN"):
    import collections
    (T, yt), train = D3[-1], D3[:-1]
    n = 2
    while True:
        n = min(n, len(train))
        X = np.vstack([d[0] for d in train[:n]])
        y = np.concatenate([d[1] for d in train[:n]])
        sc = StandardScaler().fit(X)
        for c in (10.0, 100.0):
            p = SVC(C=c, random_state=0).fit(sc.transform(X), y).predict(sc.transform(T))
            print(f"in-domain: {n} texture-train sets, C {c:g}: top-1 {(p == yt).mean():.3f}", flush=True)
        if n == len(train):
            break
        n *= 2
    print(collections.Counter((t, q) for t, q in zip(yt, p) if t != q).most_common(10))
    sys.exit()


if os.environ.get("PER"):
    per_model(*run(f"ours + {len(D3)} texture-train sets, weight 2",
                   [(O[~held], yo[~held], 1.0)] + [(X, y, 4 / len(D3)) for X, y in D3]))
    sys.exit()


run("texture-train only (all sets)", [(X, y, 1.0) for X, y in D3])
run("our training bases only", [(O[~held], yo[~held], 1.0)])
n = 2
while n <= len(D3):
    for W in (2, 4, 8):
        run(f"ours + {n} texture-train sets, weight {W}",
            [(O[~held], yo[~held], 1.0)] + [(X, y, W * 2 / n) for X, y in D3[:n]])
    n *= 2

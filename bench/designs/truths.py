"""Write <name>.truth.json for every design: the parameter values of
<name>.flg that reproduce the design, from the design's own numbers (the
constants in make-own.mjs / make-geopattern.mjs and geopattern's formulas),
converted to canvas units (256 px = 1, y down). For reference only.

Phases (ox, oy, offsets) are reduced into the .flg's range by whole lattice
periods, so each truth lies inside its parameter's range.

Usage: python3 truths.py
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
S = 256.0


def gp_map(v, d0, d1):  # geopattern's map(v, 0, 15, d0, d1)
    return d0 + v * (d1 - d0) / 15.0


def reduce(x, p, lo=0.0):
    """x shifted by whole periods p into [lo, lo + p)."""
    return lo + (x - lo) % p


def reduce2(x, y, a, b, xlo=0.0, ylo=0.0):
    """(x, y) shifted by the lattice a = (ax, 0), b = (bx, by) (bx = shear)
    so that y is in [ylo, ylo + by) and then x is in [xlo, xlo + ax)."""
    n = math.floor((y - ylo) / b[1])
    x, y = x - n * b[0], y - n * b[1]
    return reduce(x, a[0], xlo), y


T = {}

# ---------------------------------------------------------------- own designs
# diagonal-stripes: rect rows in a frame rotated by -45° about (128, 128);
# stripe centre line at k*P + phase + w/2 px from the centre, along the
# normal (sin 45°, cos 45°), i.e. the stripe() convention of the .flg.
P, w, phase = 34, 13, 9
T["diagonal-stripes"] = dict(angle=-math.pi / 4, spacing=P / S, width=w / S,
                             offset=reduce((phase + w / 2) / S, P / S))

# cross-hatch: family 1 at -45° (phase 6 px), family 2 at +45° (phase 13 px).
P, w = 20, 3
T["cross-hatch"] = dict(a1=-math.pi / 4, a2=math.pi / 4, sp1=P / S, sp2=P / S,
                        o1=reduce(6 / S, P / S), o2=reduce(13 / S, P / S), w=w / S)

# polka-dots: cell 46 px, dots at (ox, oy) and (ox + d/2, oy + d/2).
d, r, ox, oy = 46, 10.5, 14, 9
T["polka-dots"] = dict(d=d / S, r=r / S, ox=ox / S, oy=oy / S)

# seigaiha: outer radius R, rows R/2 apart shifted by R, rings width w.
R, ox, oy, w = 30, 21, 4, 3.2
x, y = reduce2(ox / S, oy / S, (2 * R / S, 0), (R / S, R / 2 / S))
T["seigaiha"] = dict(R=R / S, dy=R / 2 / S, ox=x, oy=y, w=w / S)

# honeycomb-outline: flat-topped hexagons, circumradius a, a centre (7, 12).
a, ox, oy, w = 19, 7, 12, 4
T["honeycomb-outline"] = dict(a=a / S, w=w / S, ox=ox / S, oy=oy / S)

# graph-paper-major: minor pitch 17, majors every 4, crossing at (11.4, 23.7).
d, ox, oy = 17, 11.4, 23.7
T["graph-paper-major"] = dict(d=d / S, wm=2 / S, wM=4 / S, ox=ox / S, oy=oy / S)

# tartan: period 72, bands 24 from (17.6, 30.3) (so centres +12), lines 3 px
# at 36 px from a band centre.
P, b, t, lo = 72, 24, 3, 36
T["tartan"] = dict(P=P / S, b=b / S, t=t / S, lo=lo / S,
                   cx=(17.6 + b / 2) / S, cy=(30.3 + b / 2) / S)

# brick-wall: course 56 x 25 px, mortar 4, a brick centred at (19.3, 8.6).
L, H, g = 56, 25, 4
T["brick-wall"] = dict(L=L / S, H=H / S, g=g / S, ox=19.3 / S, oy=8.6 / S)

# shippo: circles r = 28 on the lattice (2r, 0), (r, r), a centre (9, 17).
r = 28
T["shippo"] = dict(d=r / S, r=r / S, w=3 / S, ox=9 / S, oy=17 / S)

# ---------------------------------------------------------- geopattern designs
# Canvas point of geopattern tile point (X, Y): ((off_x + k X) / S, (off_y + k Y) / S).


def cv(X, Y, k, off):
    return (off[0] + k * X) / S, (off[1] + k * Y) / S


# gp-octogons: square size s = map(12, 10, 60); octagon (x s, y s), corners cut 0.33 s.
k, off = 0.83, (-9, -40)
s = gp_map(12, 10, 60)
cx, cy = cv(s / 2, s / 2, k, off)
T["gp-octogons"] = dict(d=k * s / S, size=k * s / S, cut=k * 0.33 * s / S,
                        ox=reduce(cx, k * s / S), oy=reduce(cy, k * s / S))

# gp-hexagons: side s = map(14, 8, 60); hexagon centres (1.5 s x, sqrt3 s (y + x%2/2));
# the three shades follow (q - r) mod 3; the hexagon at (0, 0) has shade 0.
k, off = 0.34, (-5, -12)
s = gp_map(14, 8, 60)
sc = k * s / S
x, y = cv(0, 0, k, off)
x, y = reduce2(x, y, (3 * sc, 0), (1.5 * sc, 1.5 * math.sqrt(3) * sc))
T["gp-hexagons"] = dict(s=sc, ox=x, oy=y)

# gp-sine-waves: period 380, amplitude A = 81, wave width 28 (hash "eb…");
# wave i: cubic, mid line at y = 28 i - A/2, crest (0.75 A above) at x = 0,
# so it crosses its mid line going up at x = -P/4; even i light, odd dark.
k, off = 0.45, (-30, 6)
Pw, A, ww = 380, 81, 28
x, y = cv(-Pw / 4, -A / 2, k, off)
T["gp-sine-waves"] = dict(len=k * Pw / S, amp=0.75 * k * A / S, pitch=2 * k * ww / S,
                          w=k * ww / S, ox=reduce(x, k * Pw / S), oy=reduce(y, 2 * k * ww / S))

# gp-triangles: side s = map(12, 15, 80), height s sqrt3/2; light triangles
# point down, row y: x from (x s/2 - s/2), the one at x = 0, y = 0 has its top
# edge's centre at (0, 0).
k, off = 0.74, (-14, -10)
s = gp_map(12, 15, 80)
h = s * math.sqrt(3) / 2
x, y = cv(0, 0, k, off)
x, y = reduce2(x, y, (k * s / S, 0), (k * s / 2 / S, k * h / S))
T["gp-triangles"] = dict(s=k * s / S, h=k * h / S, ox=x, oy=y)

# gp-diamonds: w = h = map(11, 10, 50); dark diamonds (even rows) centred at (x w, m h).
k, off = 1.18, (-17, -9)
w = gp_map(11, 10, 50)
x, y = cv(0, 0, k, off)
T["gp-diamonds"] = dict(dw=k * w / S, dh=k * w / S, ox=reduce(x, k * w / S), oy=reduce(y, k * w / S))

# gp-nested-squares: block b = map(14, 4, 12), cell 9 b, outer square 7 b
# (stroke b), inner 3 b (stroke b), cell (0, 0) centred at (4 b, 4 b).
k, off = 0.78, (-23, -14)
b = gp_map(14, 4, 12)
x, y = cv(4 * b, 4 * b, k, off)
T["gp-nested-squares"] = dict(pitch=k * 9 * b / S, outer=k * 7 * b / S, inner=k * 3 * b / S,
                              lw=k * b / S, ox=reduce(x, k * 9 * b / S), oy=reduce(y, k * 9 * b / S))

# gp-concentric-circles: ring size rs = map(13, 10, 60), stroke rs/5, pitch
# 1.2 rs, ring radius rs/2, dot radius rs/4, first centre (0.6 rs, 0.6 rs).
k, off = 0.71, (-6, -31)
rs = gp_map(13, 10, 60)
x, y = cv(0.6 * rs, 0.6 * rs, k, off)
T["gp-concentric-circles"] = dict(d=k * 1.2 * rs / S, R=k * rs / 2 / S, w=k * rs / 5 / S,
                                  r=k * rs / 4 / S, ox=reduce(x, k * 1.2 * rs / S),
                                  oy=reduce(y, k * 1.2 * rs / S))

# gp-tessellation (3.4.6.4): side s = 40; tile TW = (3 + sqrt3) s, TH = (2 + 2 sqrt3) s;
# hexagonal holes (circumradius s, flat top) at (TW/2, TH/2) on the triangular
# lattice (0, TH/2), (TW/2, TH/4), i.e. rows TH/4 apart, TW along, shifted TW/2.
k, off = 0.5, (-37, -18)
s = gp_map(15, 5, 40)
TW, TH = (3 + math.sqrt(3)) * s, (2 + 2 * math.sqrt(3)) * s
x, y = cv(TW / 2, TH / 2, k, off)
x, y = reduce2(x, y, (k * TW / S, 0), (k * TW / 2 / S, k * TH / 4 / S))
T["gp-tessellation"] = dict(px=k * TW / S, py=k * TH / 4 / S, r=k * s / S, ox=x, oy=y)

# gp-squares: s = map(8, 10, 60); light squares where x + y is even, (0, 0) light.
k, off = 0.93, (-12, -25)
s = gp_map(8, 10, 60)
x, y = cv(s / 2, s / 2, k, off)
x, y = reduce2(x, y, (2 * k * s / S, 0), (k * s / S, k * s / S))
T["gp-squares"] = dict(s=k * s / S, ox=x, oy=y)

# gp-chevrons: w = h = map(10, 30, 80), band e = 0.66 h, rows e apart (light
# on even rows), V depth h - e; row 0's chevron at x = 0 has its top-left
# corner at (0, -h/2).
k, off = 0.61, (-11, -4)
wc = gp_map(10, 30, 80)
e = 0.66 * wc
x, y = cv(0, -wc / 2, k, off)
T["gp-chevrons"] = dict(w=k * wc / S, pitch=2 * k * e / S, depth=k * (wc - e) / S,
                        t=k * e / S, ox=reduce(x, k * wc / S), oy=reduce(y, 2 * k * e / S))

if __name__ == "__main__":
    for name, t in sorted(T.items()):
        t = {key: round(v, 5) for key, v in t.items()}
        with open(os.path.join(HERE, f"{name}.truth.json"), "w") as f:
            json.dump(t, f, indent=1)
            f.write("\n")
        print(name, json.dumps(t))

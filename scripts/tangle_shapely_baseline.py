#!/usr/bin/env python3
"""Baseline for `filigree bench tangle`: the work of its BASELINE_GRAMMAR
(`bench/tangle-baseline.tangle`: a 1200x1200 sheet split into a grid of
20-unit cells, each cell outlined four times by 2 units: 18,000 final
shapes) done with shapely/GEOS.
Prints JSON {"shapes", "vertices", "seconds": {"min", "median"}}.
Exits 1 if shapely is not installed (the bench then reports it missing)."""
import json
import sys
import time

try:
    from shapely.geometry import LineString, MultiLineString, box
    from shapely.ops import split
except ImportError:
    sys.exit(1)


def run():
    sheet = box(0, 0, 1200, 1200)
    cuts = [LineString([(x, -1), (x, 1201)]) for x in range(20, 1200, 20)]
    cuts += [LineString([(-1, y), (1201, y)]) for y in range(20, 1200, 20)]
    # All cut lines at once (GEOS polygonizes the noded arrangement).
    cells = list(split(sheet, MultiLineString(cuts)).geoms)
    final = []
    for cell in cells:
        cur = cell
        for _ in range(4):
            inner = cur.buffer(-2, join_style="round")
            final.append(cur.difference(inner))
            cur = inner
        final.append(cur)
    return final


def vertices(g):
    if g.geom_type == "Polygon":
        return len(g.exterior.coords) + sum(len(r.coords) for r in g.interiors)
    return sum(vertices(p) for p in getattr(g, "geoms", []))


repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 3
secs = []
for _ in range(repeats):
    t = time.perf_counter()
    shapes = run()
    secs.append(time.perf_counter() - t)
secs.sort()
print(json.dumps({
    "shapes": len(shapes),
    "vertices": sum(vertices(s) for s in shapes),
    "seconds": {"min": secs[0], "median": secs[len(secs) // 2]},
}))

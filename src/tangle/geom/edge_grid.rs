//! A polygon's edges bucketed on a uniform grid, for many point queries
//! against one polygon ([`Polygon::contains`] and
//! [`Polygon::boundary_distance`] read every edge; a placement asks them
//! for every dart, centroid and disc, so on a region with thousands of
//! holes that was the whole cost of the step).
//!
//! Answers are the same bits as the polygon's own: every candidate edge is
//! tested with the same arithmetic, in the same orientation, and the
//! buckets only decide which edges can be skipped:
//! - `contains` counts crossings of the edges whose row band holds the
//!   point's height (the parity of all rings' crossings together is the
//!   parity of the number of rings that contain the point, which is
//!   `Polygon::contains`' even-odd rule);
//! - `boundary_distance` visits cells in square rings around the point and
//!   stops once the nearest edge found is nearer than any cell not yet
//!   visited (an edge is listed in every cell its segment passes through,
//!   so an edge not seen lies outside the visited square).
use super::polygon::Polygon;
use glam::DVec2;

/// Cells the grid may have per edge (cells are about two edges long, but
/// never so small that an empty bounding box costs more than the edges).
const CELLS_PER_EDGE: f64 = 4.0;

/// The most cells along a side.
const MAX_SIDE: usize = 4096;

/// Edges per row band the grid aims at, and the most bands.
const EDGES_PER_BAND: usize = 2;
const MAX_BANDS: usize = 1 << 16;

/// Ids in buckets, compressed: bucket `k` holds `ids[starts[k]..starts[k + 1]]`.
struct Buckets {
    starts: Vec<u32>,
    ids: Vec<u32>,
}

impl Buckets {
    /// Buckets `0..n` from `(bucket, id)` pairs, ids in the order given.
    fn new(n: usize, pairs: impl Fn(&mut dyn FnMut(usize, u32))) -> Buckets {
        let mut starts = vec![0u32; n + 1];
        pairs(&mut |k, _| starts[k + 1] += 1);
        for k in 0..n {
            starts[k + 1] += starts[k];
        }
        let mut next = starts.clone();
        let mut ids = vec![0u32; starts[n] as usize];
        pairs(&mut |k, id| {
            ids[next[k] as usize] = id;
            next[k] += 1;
        });
        Buckets { starts, ids }
    }

    fn get(&self, k: usize) -> &[u32] {
        &self.ids[self.starts[k] as usize..self.starts[k + 1] as usize]
    }
}

/// A polygon's edges on a grid (see the module docs).
pub struct EdgeGrid {
    /// Edges `(r[i], r[i + 1])` of every ring.
    edges: Vec<(DVec2, DVec2)>,
    lo: DVec2,
    cell: f64,
    w: usize,
    h: usize,
    /// Rounding allowance in coordinates: the cells an edge is listed in
    /// reach this far beyond it.
    pad: f64,
    /// Edge ids by cell (row-major): every cell the segment passes through.
    cells: Buckets,
    /// Edge ids by row band (bands `band` tall: a band holds the edges a
    /// horizontal line through it may cross): every band the edge's
    /// height spans, once.
    bands: Buckets,
    band: f64,
    n_bands: usize,
}

impl EdgeGrid {
    /// The grid of `poly`'s edges: about O(points + cells crossed) to build.
    pub fn new(poly: &Polygon) -> EdgeGrid {
        let mut edges = Vec::with_capacity(poly.vertices());
        for r in &poly.rings {
            let n = r.len();
            edges.extend((0..n).map(|i| (r[i], r[(i + 1) % n])));
        }
        let (lo, hi) = poly.bbox();
        let size = hi - lo;
        let n = edges.len() as f64;
        let mean_length = edges.iter().map(|(a, b)| a.distance(*b)).sum::<f64>() / n.max(1.0);
        let cell = (2.0 * mean_length)
            .max((size.x.max(0.0) * size.y.max(0.0) / (CELLS_PER_EDGE * n + 16.0)).sqrt())
            .max(size.max_element() / MAX_SIDE as f64);
        if edges.is_empty() || !(cell.is_finite() && cell > 0.0) {
            // Nothing to bucket (or a point-sized polygon): one cell.
            let m = edges.len();
            let all = || Buckets {
                starts: vec![0, m as u32],
                ids: (0..m as u32).collect(),
            };
            return EdgeGrid {
                edges,
                lo,
                cell: f64::INFINITY,
                w: 1,
                h: 1,
                pad: 0.0,
                cells: all(),
                bands: all(),
                band: f64::INFINITY,
                n_bands: 1,
            };
        }
        let dim = |len: f64| ((len / cell).floor() as usize + 1).min(MAX_SIDE + 1);
        let (w, h) = (dim(size.x), dim(size.y));
        let wanted = (edges.len() / EDGES_PER_BAND).clamp(1, MAX_BANDS);
        // Bands no thinner than an edge's mean height, so that an edge
        // spans about two (thinner bands multiply the lists, not speed).
        let mean_height = edges.iter().map(|(a, b)| (b.y - a.y).abs()).sum::<f64>() / n;
        let band = (size.y / wanted as f64)
            .max(mean_height)
            .max(cell / MAX_BANDS as f64);
        let n_bands = ((size.y / band).floor() as usize + 1).min(MAX_BANDS);
        let pad = 1e-6 * cell + 1e-12 * lo.abs().max(hi.abs()).max_element();
        let mut grid = EdgeGrid {
            edges,
            lo,
            cell,
            w,
            h,
            pad,
            cells: Buckets {
                starts: vec![],
                ids: vec![],
            },
            bands: Buckets {
                starts: vec![],
                ids: vec![],
            },
            band,
            n_bands,
        };
        let g = &grid;
        // Bands: a point's band lies between its edge's ends' bands
        // (rounding is monotone), so no allowance is needed.
        let bands = Buckets::new(n_bands, |put| {
            for (id, &(a, b)) in g.edges.iter().enumerate() {
                for k in g.band_of(a.y.min(b.y))..=g.band_of(a.y.max(b.y)) {
                    put(k, id as u32);
                }
            }
        });
        let cells = Buckets::new(w * h, |put| {
            for (id, &(a, b)) in g.edges.iter().enumerate() {
                let (r0, r1) = (g.row(a.y.min(b.y) - pad), g.row(a.y.max(b.y) + pad));
                for row in r0..=r1 {
                    // The segment's x range within this row.
                    let y0 = lo.y + row as f64 * cell;
                    let (t0, t1) = if a.y == b.y {
                        (0.0, 1.0)
                    } else {
                        let ta = ((y0 - pad - a.y) / (b.y - a.y)).clamp(0.0, 1.0);
                        let tb = ((y0 + cell + pad - a.y) / (b.y - a.y)).clamp(0.0, 1.0);
                        (ta.min(tb), ta.max(tb))
                    };
                    let (xa, xb) = (a.x + (b.x - a.x) * t0, a.x + (b.x - a.x) * t1);
                    for c in g.col(xa.min(xb) - pad)..=g.col(xa.max(xb) + pad) {
                        put(row * w + c, id as u32);
                    }
                }
            }
        });
        grid.bands = bands;
        grid.cells = cells;
        grid
    }

    fn row(&self, y: f64) -> usize {
        (((y - self.lo.y) / self.cell).floor().max(0.0) as usize).min(self.h - 1)
    }

    fn col(&self, x: f64) -> usize {
        (((x - self.lo.x) / self.cell).floor().max(0.0) as usize).min(self.w - 1)
    }

    fn band_of(&self, y: f64) -> usize {
        (((y - self.lo.y) / self.band).floor().max(0.0) as usize).min(self.n_bands - 1)
    }

    /// [`Polygon::contains`] of the polygon the grid was made from.
    pub fn contains(&self, p: DVec2) -> bool {
        let mut inside = false;
        for &id in self.bands.get(self.band_of(p.y)) {
            // `ring_contains` pairs a point with the one before it.
            let (b, a) = self.edges[id as usize];
            if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
                inside = !inside;
            }
        }
        inside
    }

    /// Squared distance from `p` to edge `id`, as `Polygon::boundary_distance` computes it.
    fn d2(&self, p: DVec2, id: u32) -> f64 {
        let (a, b) = self.edges[id as usize];
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
        p.distance_squared(a + ab * t)
    }

    /// The cell holding `p`, if it is on the grid.
    fn cell_of(&self, p: DVec2) -> Option<(usize, usize)> {
        let q = (p - self.lo) / self.cell;
        let on = q.x >= 0.0 && q.y >= 0.0 && q.x < self.w as f64 && q.y < self.h as f64;
        on.then_some((q.x as usize, q.y as usize))
    }

    fn brute_d2(&self, p: DVec2) -> f64 {
        (0..self.edges.len() as u32)
            .map(|id| self.d2(p, id))
            .fold(f64::INFINITY, f64::min)
    }

    /// [`Polygon::boundary_distance`] of the polygon the grid was made from.
    pub fn boundary_distance(&self, p: DVec2) -> f64 {
        let Some((cx, cy)) = self.cell_of(p) else {
            // Off the grid (or one cell): every edge, as the polygon does.
            return self.brute_d2(p).sqrt();
        };
        let mut d2 = f64::INFINITY;
        for k in 0.. {
            let (x0, x1) = (cx.saturating_sub(k), (cx + k).min(self.w - 1));
            let (y0, y1) = (cy.saturating_sub(k), (cy + k).min(self.h - 1));
            for y in y0..=y1 {
                let edge_row = y + k == cy || y == cy + k;
                for x in x0..=x1 {
                    // Only the ring at Chebyshev distance k.
                    if edge_row || x + k == cx || x == cx + k {
                        for &id in self.cells.get(y * self.w + x) {
                            d2 = d2.min(self.d2(p, id));
                        }
                    }
                }
            }
            // Edges not seen lie outside the visited square: at least k
            // cells away (less the rounding allowance).
            let reach = (k as f64 * self.cell - 2.0 * self.pad).max(0.0);
            let everything = x0 == 0 && y0 == 0 && x1 == self.w - 1 && y1 == self.h - 1;
            if everything || d2 <= reach * reach {
                break;
            }
        }
        d2.sqrt()
    }

    /// `boundary_distance(p) >= r`, the same answer, reading only the
    /// edges within `r` of `p`.
    pub fn boundary_distance_at_least(&self, p: DVec2, r: f64) -> bool {
        if self.cell_of(p).is_none() || !r.is_finite() {
            return self.brute_d2(p).sqrt() >= r;
        }
        // Edges nearer than `r` pass through a cell of the box around p.
        let reach = r.max(0.0) + 2.0 * self.pad;
        let (x0, x1) = (self.col(p.x - reach), self.col(p.x + reach));
        let (y0, y1) = (self.row(p.y - reach), self.row(p.y + reach));
        let mut d2 = f64::INFINITY;
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &id in self.cells.get(y * self.w + x) {
                    d2 = d2.min(self.d2(p, id));
                }
            }
        }
        // A nearer edge outside the box would be further than `r`.
        d2.sqrt() >= r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ring(c: DVec2, r: f64, n: usize, phase: f64) -> Vec<DVec2> {
        (0..n)
            .map(|i| {
                let t = phase + i as f64 / n as f64 * std::f64::consts::TAU;
                c + DVec2::new(t.cos(), t.sin()) * r * (1.0 + 0.3 * (5.0 * t).sin())
            })
            .collect()
    }

    /// A wobbly outline with wobbly holes, like a placement's remainder.
    fn holey(seed: u64, holes: usize) -> Polygon {
        let mut rng = crate::core::rng::Rng::new(seed);
        let mut rings = vec![ring(DVec2::new(50.0, 40.0), 45.0, 200, 0.0)];
        for _ in 0..holes {
            let c = DVec2::new(20.0 + 60.0 * rng.f64(), 15.0 + 50.0 * rng.f64());
            let mut h = ring(c, 1.0 + 3.0 * rng.f64(), 16, rng.f64());
            h.reverse();
            rings.push(h);
        }
        Polygon { rings }
    }

    /// The grid answers exactly what the polygon answers (bit for bit),
    /// on the grid, off it, on vertices and on edges.
    #[test]
    fn answers_are_the_polygons_bit_for_bit() {
        for (seed, holes) in [(1, 0), (2, 5), (3, 60)] {
            let poly = holey(seed, holes);
            let grid = EdgeGrid::new(&poly);
            let mut rng = crate::core::rng::Rng::new(seed + 100);
            let mut probes: Vec<DVec2> = (0..3000)
                .map(|_| DVec2::new(-20.0 + 140.0 * rng.f64(), -20.0 + 120.0 * rng.f64()))
                .collect();
            probes.extend(poly.rings.iter().flatten().copied());
            probes.extend(poly.rings[0].windows(2).map(|w| (w[0] + w[1]) * 0.5));
            for p in probes {
                assert_eq!(grid.contains(p), poly.contains(p), "contains at {p}");
                let d = poly.boundary_distance(p);
                assert_eq!(
                    grid.boundary_distance(p).to_bits(),
                    d.to_bits(),
                    "distance at {p}"
                );
                for r in [0.0, 0.5 * d, d, d + 1e-12, 2.0 * d + 0.1, 3.0] {
                    assert_eq!(grid.boundary_distance_at_least(p, r), d >= r, "{p} {r}");
                }
            }
        }
    }

    #[test]
    fn degenerate_polygons_answer_like_the_polygon() {
        let empty = Polygon::default();
        let g = EdgeGrid::new(&empty);
        assert!(!g.contains(DVec2::ZERO));
        assert_eq!(g.boundary_distance(DVec2::ZERO), f64::INFINITY);
        // A flat (zero-height) ring: a grid one row tall.
        let flat = Polygon {
            rings: vec![vec![
                DVec2::ZERO,
                DVec2::new(10.0, 0.0),
                DVec2::new(5.0, 0.0),
            ]],
        };
        let g = EdgeGrid::new(&flat);
        for p in [
            DVec2::new(3.0, 0.0),
            DVec2::new(3.0, 2.0),
            DVec2::new(-4.0, -1.0),
        ] {
            assert_eq!(g.contains(p), flat.contains(p));
            assert_eq!(
                g.boundary_distance(p).to_bits(),
                flat.boundary_distance(p).to_bits()
            );
        }
    }

    proptest! {
        #[test]
        fn any_rings_answer_like_the_polygon(
            pts in prop::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 3..40),
            cut in 0usize..40,
            probes in prop::collection::vec((-70.0f64..70.0, -70.0f64..70.0), 1..30),
        ) {
            let pts: Vec<DVec2> = pts.into_iter().map(|(x, y)| DVec2::new(x, y)).collect();
            let cut = cut.min(pts.len());
            let rings: Vec<Vec<DVec2>> = [&pts[..cut], &pts[cut..]]
                .into_iter()
                .filter(|r| !r.is_empty())
                .map(<[DVec2]>::to_vec)
                .collect();
            let poly = Polygon { rings };
            let grid = EdgeGrid::new(&poly);
            for (x, y) in probes {
                let p = DVec2::new(x, y);
                prop_assert_eq!(grid.contains(p), poly.contains(p));
                let d = poly.boundary_distance(p);
                prop_assert_eq!(grid.boundary_distance(p).to_bits(), d.to_bits());
                prop_assert_eq!(grid.boundary_distance_at_least(p, d), true);
                prop_assert_eq!(grid.boundary_distance_at_least(p, 0.7 * d + 0.01), d >= 0.7 * d + 0.01);
            }
        }
    }
}

//! Streamline split (paper §4.2, "Streamline Split"): a shape cut along
//! equally spaced streamlines of a vector field interpolated from vectors
//! on its boundary.
//!
//! 1. **Boundary vectors.** The boundary is resampled by arc length at
//!    most [`MAX_BOUNDARY_SAMPLES`] points per polygon (never closer than
//!    half the offset), and each sample `P_i` gets a unit vector by kind:
//!    - smooth outline: `v_i = P_{i+1} − P_i`, averaged with the previous
//!      edge's `P_i − P_{i−1}` (so `P_{i+1} − P_{i−1}`, the tangent at
//!      `P_i`): on our coarse samples the forward difference alone leans
//!      outwards by half the angle between samples, and closed streamlines
//!      become spirals. Every ring is taken counter-clockwise so that the
//!      flow around a hole turns the same way as around the outside
//!      (opposite turns would cancel between them);
//!    - strip: `v_i = (P_{i+1} − P_i) + (P_{i−1} − P_i)`, inverted if it
//!      points outside. On a straight run of a tessellated boundary this
//!      vector vanishes; we take its limit direction for a slightly curved
//!      run, the inward normal;
//!    - circular from a point `P′` (default the centroid):
//!      `v_i = ((P′ − P_i)/|P′ − P_i|)^⊥`.
//! 2. **Field.** `v(p) = Σ w_i(p) v_i`, normalised, with mean value
//!    coordinates `w_i` ([`crate::tangle::geom::mvc`]; the paper's Meyer et al.
//!    coordinates need convex shapes). Strip vectors point inwards from
//!    every side, so opposite sides cancel in that sum: for the strip kind
//!    the vectors are interpolated as orientations (doubled angles,
//!    `(x² − y², 2xy)`) and streamlines cross the shape from side to side.
//!    The field is evaluated lazily on a grid of at most [`MAX_GRID`]²
//!    nodes and looked up bilinearly, so tracing costs no mean value sums.
//! 3. **Streamlines** (Jobard & Lefer 1997): the first seed is the point
//!    farthest from the boundary (or the centroid; `P′` shifted by the
//!    offset for the circular kind, whose field vanishes at `P′`); each
//!    line is traced both ways with improved Euler (midpoint) steps of
//!    [`STEP`] × offset, stopping where it leaves the shape (and extended
//!    a little past the boundary so the cut is clean), where it comes
//!    closer than half the offset to another line (it is joined to that
//!    line, so the cut closes a piece), where it returns to its start (a
//!    closed loop ends on its first point), at a singular point or a sharp
//!    turn, or at a budget. New seeds are tried at one offset on either
//!    side of every line, in order.
//! 4. **Cut.** The shape is sliced along the lines
//!    ([`Polygon::slice`]); the pieces tile it.
//!
//! Everything is bounded ([`MAX_LINES`], [`MAX_LINE_POINTS`],
//! [`MAX_STEPS`]; the offset is raised to at least the shape's extent /
//! [`MAX_ACROSS`]), sequential and uses only `+ − × ÷ sqrt`, so the cuts
//! are the same bytes natively and in wasm.
use super::ast::StreamKind;
use crate::tangle::geom::mvc::mean_value_weights;
use crate::tangle::geom::order;
use crate::tangle::geom::polygon::{ring_area2, ring_length, Polygon, Ring, SLIVER_AREA};
use glam::DVec2;

/// Boundary samples carrying vectors, per polygon (all rings together).
pub const MAX_BOUNDARY_SAMPLES: usize = 256;
/// Field grid nodes per axis, at most.
pub const MAX_GRID: usize = 128;
/// Streamlines per shape, at most.
pub const MAX_LINES: usize = 4096;
/// Points per streamline, at most.
pub const MAX_LINE_POINTS: usize = 8192;
/// Integration steps per shape (all lines together), at most.
pub const MAX_STEPS: usize = 1_000_000;
/// The offset is at least the shape's larger extent divided by this (so a
/// tiny offset cannot ask for millions of lines).
pub const MAX_ACROSS: f64 = 256.0;
/// Integration step, as a fraction of the offset.
pub const STEP: f64 = 0.2;
/// A line stops when it comes this close (× offset) to another one.
const D_TEST: f64 = 0.5;
/// A seed is refused this close (× offset) to an existing line.
const D_SEED: f64 = 0.9;
/// Open ends are extended this far (× offset) past the boundary.
const EXTEND: f64 = 0.02;
/// A step turning by more than 60° stops the line (a singular point).
const MAX_TURN_COS: f64 = 0.5;

/// The cuts of a streamline split of `poly` with lines `offset` apart:
/// open polylines reaching slightly past the boundary (or ending on
/// another line), and closed loops given as polylines that return to
/// their first point. Empty when the shape is degenerate (no area,
/// smaller than the offset) or the offset is not a positive number.
pub fn streamline_cuts(poly: &Polygon, kind: StreamKind, offset: f64) -> Vec<Vec<DVec2>> {
    streamline_cuts_at(poly, kind, offset, None)
}

/// [`streamline_cuts`] with the circular kind's centre `P′` given
/// (`None` or a non-finite point: the centroid). Other kinds ignore it.
pub fn streamline_cuts_at(
    poly: &Polygon,
    kind: StreamKind,
    offset: f64,
    centre: Option<DVec2>,
) -> Vec<Vec<DVec2>> {
    if !(offset.is_finite() && offset > 0.0) || poly.rings.is_empty() {
        return vec![];
    }
    if poly.area() < SLIVER_AREA || poly.rings.iter().flatten().any(|p| !p.is_finite()) {
        return vec![];
    }
    let (lo, hi) = poly.bbox();
    let extent = (hi - lo).max_element();
    if offset >= extent {
        return vec![];
    }
    let offset = offset.max(extent / MAX_ACROSS);
    let centre = centre
        .filter(|c| c.is_finite())
        .unwrap_or_else(|| poly.centroid());
    let Some(field) = Field::new(poly, kind, offset, centre) else {
        return vec![];
    };
    let mut tracer = Tracer::new(poly, field, offset);
    tracer.run(kind, centre);
    tracer.lines
}

/// The pieces of `poly` cut along its streamlines ([`streamline_cuts`]);
/// the shape itself, unsplit, when there are no cuts.
pub fn streamline_split(poly: &Polygon, kind: StreamKind, offset: f64) -> Vec<Polygon> {
    poly.slice(&streamline_cuts(poly, kind, offset))
}

/// [`streamline_split`] with the circular kind's centre given.
pub fn streamline_split_at(
    poly: &Polygon,
    kind: StreamKind,
    offset: f64,
    centre: Option<DVec2>,
) -> Vec<Polygon> {
    poly.slice(&streamline_cuts_at(poly, kind, offset, centre))
}

/// A ring resampled at `n` points equally spaced by arc length.
fn resample_by_length(ring: &[DVec2], n: usize) -> Ring {
    let len = ring_length(ring);
    let m = ring.len();
    let mut out = Vec::with_capacity(n);
    let (mut edge, mut at) = (0usize, 0.0f64); // current edge, its start's arc length
    for k in 0..n {
        let s = len * k as f64 / n as f64;
        while edge + 1 < m && at + ring[edge].distance(ring[(edge + 1) % m]) < s {
            at += ring[edge].distance(ring[(edge + 1) % m]);
            edge += 1;
        }
        let (a, b) = (ring[edge], ring[(edge + 1) % m]);
        let l = a.distance(b);
        let t = if l > 0.0 {
            ((s - at) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(a.lerp(b, t));
    }
    out
}

/// The vector field over a shape: boundary samples and vectors, and a
/// lazily filled grid of interpolated (not yet normalised) vectors.
struct Field {
    /// Orientation field (doubled angles) rather than a direction field.
    doubled: bool,
    rings: Vec<Ring>,
    vecs: Vec<DVec2>,
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    nodes: Vec<DVec2>,
    known: Vec<bool>,
    /// Grid cells the boundary passes through: there the field is summed
    /// exactly (bilinear lookups would mix in nodes outside the shape,
    /// where the field is extrapolated).
    exact: Vec<bool>,
    scratch: Vec<f64>,
}

impl Field {
    fn new(poly: &Polygon, kind: StreamKind, offset: f64, centre: DVec2) -> Option<Field> {
        let total: f64 = poly.rings.iter().map(|r| ring_length(r)).sum();
        let spacing = (total / MAX_BOUNDARY_SAMPLES as f64).max(0.5 * offset);
        let mut rings = Vec::new();
        let mut vecs = Vec::new();
        for (k, ring) in poly.rings.iter().enumerate() {
            let n = (ring_length(ring) / spacing).floor() as usize;
            // Holes smaller than three samples carry no vectors (the
            // outer ring always does).
            let n = if k == 0 { n.max(3) } else { n };
            if n < 3 || ring.len() < 3 {
                continue;
            }
            // Region on the left: outer ring counter-clockwise, holes
            // clockwise (the even-odd rule of `Polygon` decides which is
            // which, so a ring's role is its index).
            let mut r = resample_by_length(ring, n);
            let ccw = ring_area2(&r) > 0.0;
            if ccw != (k == 0) {
                r.reverse();
            }
            let m = r.len();
            for i in 0..m {
                let (prev, p, next) = (r[(i + m - 1) % m], r[i], r[(i + 1) % m]);
                let inward = (next - prev).perp().normalize_or_zero();
                let v = match kind {
                    // The tangent at P_i (see the module doc); every ring
                    // counter-clockwise: holes turned round.
                    StreamKind::Smooth if k == 0 => next - prev,
                    StreamKind::Smooth => prev - next,
                    StreamKind::Strip => {
                        let d = (next - p) + (prev - p);
                        let scale = (next - p).length() + (prev - p).length();
                        if d.length() <= 1e-6 * scale {
                            inward
                        } else if d.dot(inward) < 0.0 {
                            -d
                        } else {
                            d
                        }
                    }
                    StreamKind::Circular => (centre - p).normalize_or_zero().perp(),
                };
                let v = v.normalize_or_zero();
                vecs.push(if kind == StreamKind::Strip {
                    DVec2::new(v.x * v.x - v.y * v.y, 2.0 * v.x * v.y)
                } else {
                    v
                });
            }
            rings.push(r);
        }
        if rings.is_empty() {
            return None;
        }
        let (lo, hi) = poly.bbox();
        let extent = (hi - lo).max_element();
        let cell = offset.max(extent / (MAX_GRID - 3) as f64);
        let lo = lo - DVec2::splat(cell);
        let nx = (((hi.x - lo.x) / cell).ceil() as usize + 2).min(MAX_GRID);
        let ny = (((hi.y - lo.y) / cell).ceil() as usize + 2).min(MAX_GRID);
        let mut exact = vec![false; nx * ny];
        let at = |p: DVec2| {
            let g = (p - lo) / cell;
            (
                (g.x.clamp(0.0, (nx - 1) as f64) as usize).min(nx - 2),
                (g.y.clamp(0.0, (ny - 1) as f64) as usize).min(ny - 2),
            )
        };
        for ring in &poly.rings {
            let r = crate::tangle::geom::polygon::resample_ring(ring, cell);
            for (k, &a) in r.iter().enumerate() {
                let b = r[(k + 1) % r.len()];
                let ((i0, j0), (i1, j1)) = (at(a.min(b)), at(a.max(b)));
                for j in j0..=j1 {
                    exact[j * nx + i0..=j * nx + i1].fill(true);
                }
            }
        }
        Some(Field {
            doubled: kind == StreamKind::Strip,
            rings,
            vecs,
            lo,
            cell,
            nx,
            ny,
            nodes: vec![DVec2::ZERO; nx * ny],
            known: vec![false; nx * ny],
            exact,
            scratch: Vec::new(),
        })
    }

    /// `Σ w_i(p) v_i`.
    fn sum(&mut self, p: DVec2) -> DVec2 {
        mean_value_weights(&self.rings, p, &mut self.scratch);
        let v = self
            .scratch
            .iter()
            .zip(&self.vecs)
            .fold(DVec2::ZERO, |acc, (&w, &v)| acc + v * w);
        if v.is_finite() {
            v
        } else {
            DVec2::ZERO
        }
    }

    fn node(&mut self, i: usize, j: usize) -> DVec2 {
        let k = j * self.nx + i;
        if !self.known[k] {
            let p = self.lo + DVec2::new(i as f64, j as f64) * self.cell;
            self.nodes[k] = self.sum(p);
            self.known[k] = true;
        }
        self.nodes[k]
    }

    /// The interpolated vector at `p` (bilinear over the grid, exact
    /// next to the boundary).
    fn raw(&mut self, p: DVec2) -> DVec2 {
        let g = (p - self.lo) / self.cell;
        let gx = g.x.clamp(0.0, (self.nx - 1) as f64);
        let gy = g.y.clamp(0.0, (self.ny - 1) as f64);
        let i = (gx.floor() as usize).min(self.nx - 2);
        let j = (gy.floor() as usize).min(self.ny - 2);
        if self.exact[j * self.nx + i] {
            return self.sum(p);
        }
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        let a = self.node(i, j);
        let b = self.node(i + 1, j);
        let c = self.node(i, j + 1);
        let d = self.node(i + 1, j + 1);
        a.lerp(b, fx).lerp(c.lerp(d, fx), fy)
    }

    /// The unit field direction at `p` (for an orientation field, one of
    /// its two directions), `None` where the field vanishes.
    fn dir(&mut self, p: DVec2) -> Option<DVec2> {
        let v = self.raw(p);
        let r = v.length();
        if r.is_nan() || r <= 1e-9 {
            return None;
        }
        if !self.doubled {
            return Some(v / r);
        }
        // Half the angle of (cos 2θ, sin 2θ), without trigonometry.
        let c = (v.x / r).clamp(-1.0, 1.0);
        let x = (0.5 * (1.0 + c)).sqrt();
        let y = (0.5 * (1.0 - c)).sqrt();
        Some(DVec2::new(x, if v.y < 0.0 { -y } else { y }))
    }
}

/// A uniform grid of buckets over the shape's box (cell = offset).
struct Buckets {
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    items: Vec<Vec<u32>>,
}

impl Buckets {
    fn new(lo: DVec2, hi: DVec2, cell: f64) -> Buckets {
        let lo = lo - DVec2::splat(cell);
        let nx = ((hi.x - lo.x) / cell).ceil() as usize + 2;
        let ny = ((hi.y - lo.y) / cell).ceil() as usize + 2;
        Buckets {
            lo,
            cell,
            nx,
            ny,
            items: vec![Vec::new(); nx * ny],
        }
    }

    /// Cell coordinates of `p`, clamped into the grid.
    fn at(&self, p: DVec2) -> (usize, usize) {
        let g = (p - self.lo) / self.cell;
        let i = g.x.clamp(0.0, (self.nx - 1) as f64) as usize;
        let j = g.y.clamp(0.0, (self.ny - 1) as f64) as usize;
        (i, j)
    }

    fn push(&mut self, p: DVec2, id: u32) {
        let (i, j) = self.at(p);
        self.items[j * self.nx + i].push(id);
    }

    /// Cells of the box `a`..`b` (inclusive).
    fn cells(&self, a: DVec2, b: DVec2) -> impl Iterator<Item = usize> + '_ {
        let (i0, j0) = self.at(a.min(b));
        let (i1, j1) = self.at(a.max(b));
        (j0..=j1).flat_map(move |j| (i0..=i1).map(move |i| j * self.nx + i))
    }
}

/// The shape's exact boundary, bucketed for segment crossings and
/// point-in-shape tests.
struct Boundary<'a> {
    poly: &'a Polygon,
    edges: Vec<(DVec2, DVec2)>,
    grid: Buckets,
    /// Per cell: whether its centre is inside (valid for the whole cell
    /// when no edge touches it).
    inside: Vec<bool>,
}

impl<'a> Boundary<'a> {
    fn new(poly: &'a Polygon, cell: f64) -> Boundary<'a> {
        let (lo, hi) = poly.bbox();
        let mut grid = Buckets::new(lo, hi, cell);
        let mut edges = Vec::new();
        for ring in &poly.rings {
            // Pieces no longer than a cell: each touches at most 2×2 cells.
            let r = crate::tangle::geom::polygon::resample_ring(ring, cell);
            let n = r.len();
            for i in 0..n {
                let (a, b) = (r[i], r[(i + 1) % n]);
                let id = edges.len() as u32;
                edges.push((a, b));
                let cells: Vec<usize> = grid.cells(a, b).collect();
                for c in cells {
                    grid.items[c].push(id);
                }
            }
        }
        // Centres inside, row by row (crossings to the right, as
        // `Polygon::contains` counts them). Edges are at most a cell long,
        // so each crosses the centre lines of at most two rows.
        let mut inside = vec![false; grid.nx * grid.ny];
        // (row, crossing as an order::key, 0), sorted by row then x.
        let mut xs: Vec<order::Key> = Vec::new();
        for &(a, b) in &edges {
            let (y0, y1) = (a.y.min(b.y), a.y.max(b.y));
            let j0 = ((y0 - grid.lo.y) / grid.cell - 0.5).floor().max(0.0) as usize;
            let j1 =
                (((y1 - grid.lo.y) / grid.cell - 0.5).ceil().max(0.0) as usize).min(grid.ny - 1);
            for j in j0..=j1 {
                let y = grid.lo.y + (j as f64 + 0.5) * grid.cell;
                if (a.y > y) != (b.y > y) {
                    let x = (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x;
                    xs.push((j as u64, order::key(x), 0));
                }
            }
        }
        order::sort(&mut xs);
        let mut at = 0;
        for j in 0..grid.ny {
            let start = at;
            while at < xs.len() && xs[at].0 == j as u64 {
                at += 1;
            }
            let row = &xs[start..at];
            for i in 0..grid.nx {
                let x = grid.lo.x + (i as f64 + 0.5) * grid.cell;
                let right = row.len() - row.partition_point(|&(_, c, _)| order::from_key(c) <= x);
                inside[j * grid.nx + i] = right % 2 == 1;
            }
        }
        Boundary {
            poly,
            edges,
            grid,
            inside,
        }
    }

    /// Whether `p` is inside: its cell centre's side, flipped by every
    /// edge (all of them are in the cell's bucket) that the segment from
    /// the centre to `p` crosses. Sides are half-open (on a line counts as
    /// left), so a segment through a vertex crosses exactly one of its two
    /// edges.
    fn contains(&self, p: DVec2) -> bool {
        let (i, j) = self.grid.at(p);
        let k = j * self.grid.nx + i;
        let c = self.grid.lo + (DVec2::new(i as f64, j as f64) + 0.5) * self.grid.cell;
        // Clamped points (outside the grid) are outside the shape.
        if (p - c).abs().max_element() > 0.5 * self.grid.cell {
            return false;
        }
        let left = |o: DVec2, d: DVec2, x: DVec2| d.perp_dot(x - o) >= 0.0;
        let mut inside = self.inside[k];
        for &e in &self.grid.items[k] {
            let (a, b) = self.edges[e as usize];
            if left(c, p - c, a) != left(c, p - c, b) && left(a, b - a, c) != left(a, b - a, p) {
                inside = !inside;
            }
        }
        inside
    }

    /// The first crossing of the segment `p → q` with the boundary, as a
    /// parameter in `[0, 1]`.
    fn exit(&self, p: DVec2, q: DVec2) -> Option<f64> {
        let d = q - p;
        let mut best: Option<f64> = None;
        for c in self.grid.cells(p, q) {
            for &e in &self.grid.items[c] {
                let (a, b) = self.edges[e as usize];
                let f = b - a;
                let den = d.perp_dot(f);
                if den == 0.0 {
                    continue;
                }
                let t = (a - p).perp_dot(f) / den;
                let u = (a - p).perp_dot(d) / den;
                if (0.0..=1.0).contains(&t)
                    && (0.0..=1.0).contains(&u)
                    && best.is_none_or(|b| t < b)
                {
                    best = Some(t);
                }
            }
        }
        best
    }
}

/// Distance from `p` to the nearest edge of closed rings.
fn ring_distance(rings: &[Ring], p: DVec2) -> f64 {
    let mut d2 = f64::INFINITY;
    for r in rings {
        let n = r.len();
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            let ab = b - a;
            let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
            d2 = d2.min(p.distance_squared(a + ab * t));
        }
    }
    d2.sqrt()
}

/// A traced point: position, line and signed arc length from the seed.
#[derive(Clone, Copy)]
struct Pt {
    pos: DVec2,
    line: u32,
    s: f64,
}

/// How one direction of a trace ended.
#[derive(PartialEq)]
enum End {
    /// Returned to its seed: a closed loop.
    Loop,
    Other,
}

struct Tracer<'a> {
    field: Field,
    boundary: Boundary<'a>,
    offset: f64,
    h: f64,
    pts: Vec<Pt>,
    near: Buckets,
    /// Accepted lines (the cuts), in seeding order.
    lines: Vec<Vec<DVec2>>,
    steps: usize,
}

impl<'a> Tracer<'a> {
    fn new(poly: &'a Polygon, field: Field, offset: f64) -> Tracer<'a> {
        let (lo, hi) = poly.bbox();
        Tracer {
            field,
            boundary: Boundary::new(poly, offset),
            offset,
            h: STEP * offset,
            pts: Vec::new(),
            near: Buckets::new(lo, hi, offset),
            lines: Vec::new(),
            steps: 0,
        }
    }

    fn run(&mut self, kind: StreamKind, centre: DVec2) {
        // First line: a long one from the first seed that gives one.
        let o = self.offset;
        let shifts = [
            DVec2::ZERO,
            DVec2::new(o, 0.0),
            DVec2::new(0.0, o),
            DVec2::new(-o, 0.0),
            DVec2::new(0.0, -o),
        ];
        let bases: Vec<DVec2> = if kind == StreamKind::Circular {
            vec![centre + DVec2::new(o, 0.0), centre]
        } else {
            vec![self.farthest_inside(), self.boundary.poly.centroid()]
        };
        'first: for base in bases {
            for s in shifts {
                let seed = base + s;
                if self.boundary.contains(seed) && self.trace(seed, 2.0 * o) {
                    break 'first;
                }
            }
        }
        // Jobard–Lefer: seeds one offset beside every line, in order.
        let stride = ((0.5 / STEP).round() as usize).max(1);
        let mut k = 0;
        while k < self.lines.len() {
            let n = self.lines[k].len();
            let mut i = 0;
            while i < n {
                if self.lines.len() >= MAX_LINES || self.steps >= MAX_STEPS {
                    return;
                }
                let line = &self.lines[k];
                let (a, b) = (line[i.saturating_sub(1)], line[(i + 1).min(n - 1)]);
                let normal = (b - a).perp().normalize_or_zero();
                let p = line[i];
                if normal != DVec2::ZERO {
                    for side in [normal, -normal] {
                        let seed = p + side * o;
                        if self.boundary.contains(seed) && !self.any_within(seed, D_SEED * o) {
                            self.trace(seed, 0.5 * o);
                        }
                    }
                }
                i += stride;
            }
            k += 1;
        }
    }

    /// The inside point farthest from the boundary (measured to the
    /// field's boundary samples), on a coarse grid.
    fn farthest_inside(&self) -> DVec2 {
        let (lo, hi) = self.boundary.poly.bbox();
        let n = 32;
        let step = (hi - lo) / n as f64;
        let mut best = (self.boundary.poly.centroid(), -1.0);
        for j in 0..n {
            for i in 0..n {
                let p = lo + (DVec2::new(i as f64, j as f64) + 0.5) * step;
                if self.boundary.contains(p) {
                    let d = ring_distance(&self.field.rings, p);
                    if d > best.1 {
                        best = (p, d);
                    }
                }
            }
        }
        best.0
    }

    /// The nearest traced point within `r` of `p`, skipping points of
    /// `line` within `skip` arc length of `s`.
    fn nearest(&self, p: DVec2, r: f64, line: u32, s: f64) -> Option<DVec2> {
        let r2 = r * r;
        let mut best: Option<(f64, DVec2)> = None;
        let d = DVec2::splat(r);
        for c in self.near.cells(p - d, p + d) {
            for &id in &self.near.items[c] {
                let q = self.pts[id as usize];
                if q.line == line && (q.s - s).abs() < self.offset {
                    continue;
                }
                let d2 = q.pos.distance_squared(p);
                if d2 < r2 && best.is_none_or(|(b, _)| d2 < b) {
                    best = Some((d2, q.pos));
                }
            }
        }
        best.map(|(_, q)| q)
    }

    /// Whether any traced point lies within `r` of `p`.
    fn any_within(&self, p: DVec2, r: f64) -> bool {
        let d = DVec2::splat(r);
        self.near.cells(p - d, p + d).any(|c| {
            self.near.items[c]
                .iter()
                .any(|&id| self.pts[id as usize].pos.distance_squared(p) < r * r)
        })
    }

    fn add_point(&mut self, pos: DVec2, line: u32, s: f64) {
        let id = self.pts.len() as u32;
        self.pts.push(Pt { pos, line, s });
        self.near.push(pos, id);
    }

    /// Traces a line from `seed` and keeps it if it spans at least
    /// `min_size` (its box's diagonal); a refused line leaves no trace.
    fn trace(&mut self, seed: DVec2, min_size: f64) -> bool {
        let Some(d0) = self.field.dir(seed) else {
            return false;
        };
        let line = self.lines.len() as u32;
        let first = self.pts.len();
        self.add_point(seed, line, 0.0);
        let mut fwd = Vec::new();
        let end = self.trace_one(seed, d0, 1.0, line, &mut fwd);
        let mut bwd = Vec::new();
        if end != End::Loop {
            self.trace_one(seed, d0, -1.0, line, &mut bwd);
        }
        let mut pts: Vec<DVec2> = bwd.into_iter().rev().collect();
        pts.push(seed);
        pts.extend(fwd);
        let (lo, hi) = pts
            .iter()
            .fold((seed, seed), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        if pts.len() < 2 || lo.distance(hi) < min_size {
            // Undo: this line's points are the newest in every bucket.
            for k in (first..self.pts.len()).rev() {
                let (i, j) = self.near.at(self.pts[k].pos);
                let cell = &mut self.near.items[j * self.near.nx + i];
                if cell.last() == Some(&(k as u32)) {
                    cell.pop();
                }
            }
            self.pts.truncate(first);
            return false;
        }
        self.lines.push(pts);
        true
    }

    /// One direction of a trace (`sign` +1: along the seed's field
    /// direction `d0`, −1: against it); points after the seed go to `out`.
    fn trace_one(
        &mut self,
        seed: DVec2,
        d0: DVec2,
        sign: f64,
        line: u32,
        out: &mut Vec<DVec2>,
    ) -> End {
        let (h, o) = (self.h, self.offset);
        let mut p = seed;
        let mut prev = d0 * sign;
        let mut s = 0.0;
        while out.len() + 1 < MAX_LINE_POINTS / 2 && self.steps < MAX_STEPS {
            self.steps += 1;
            let Some(d1) = self.step_dir(p, prev, sign) else {
                break;
            };
            let Some(d2) = self.step_dir(p + d1 * (0.5 * h), d1, sign) else {
                break;
            };
            if d2.dot(prev) < MAX_TURN_COS {
                break;
            }
            let q = p + d2 * h;
            if let Some(t) = self.boundary.exit(p, q) {
                out.push(p + (q - p) * t + d2 * (EXTEND * o));
                return End::Other;
            }
            s += h;
            if sign > 0.0 && s > 2.0 * o && q.distance(seed) < D_TEST * o {
                out.push(seed);
                return End::Loop;
            }
            if let Some(x) = self.nearest(q, D_TEST * o, line, s * sign) {
                out.push(x);
                return End::Other;
            }
            out.push(q);
            self.add_point(q, line, s * sign);
            p = q;
            prev = d2;
        }
        End::Other
    }

    /// The field direction at `p` for a step following `prev`: aligned
    /// with it for an orientation field, `sign` times the field for a
    /// direction field.
    fn step_dir(&mut self, p: DVec2, prev: DVec2, sign: f64) -> Option<DVec2> {
        let d = self.field.dir(p)?;
        Some(if self.field.doubled {
            if d.dot(prev) < 0.0 {
                -d
            } else {
                d
            }
        } else {
            d * sign
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn l_shape() -> Polygon {
        Polygon {
            rings: vec![vec![
                v(0.0, 0.0),
                v(300.0, 0.0),
                v(300.0, 120.0),
                v(120.0, 120.0),
                v(120.0, 300.0),
                v(0.0, 300.0),
            ]],
        }
    }

    fn square_with_hole() -> Polygon {
        Polygon::new(vec![
            Polygon::rect(v(0.0, 0.0), v(200.0, 200.0)).rings[0].clone(),
            Polygon::circle(v(70.0, 110.0), 30.0, 48).rings[0].clone(),
        ])
        .unwrap()
        .remove(0)
    }

    /// Pieces tile the parent: areas sum to its area (1e-3 relative) and
    /// their union has the same area (no overlaps).
    fn assert_tiles(parent: &Polygon, pieces: &[Polygon]) {
        let sum: f64 = pieces.iter().map(Polygon::area).sum();
        let a = parent.area();
        assert!((sum - a).abs() <= 1e-3 * a, "area {sum} vs parent {a}");
        let union: f64 = Polygon::union_all(pieces).iter().map(Polygon::area).sum();
        assert!(
            (union - sum).abs() <= 1e-3 * a,
            "overlap: union {union} vs sum {sum}"
        );
    }

    #[test]
    fn every_kind_conserves_area_without_overlaps() {
        let shapes = [
            Polygon::rect(v(0.0, 0.0), v(200.0, 200.0)),
            Polygon::circle(v(0.0, 0.0), 100.0, 200),
            l_shape(),
            square_with_hole(),
            Polygon::rect(v(0.0, 0.0), v(400.0, 100.0)),
        ];
        for (k, shape) in shapes.iter().enumerate() {
            for kind in [StreamKind::Smooth, StreamKind::Strip, StreamKind::Circular] {
                let pieces = streamline_split(shape, kind, 20.0);
                assert!(
                    pieces.len() >= 3,
                    "shape {k} {kind:?}: {} pieces",
                    pieces.len()
                );
                assert_tiles(shape, &pieces);
            }
        }
    }

    #[test]
    fn circular_split_of_a_disc_gives_concentric_rings() {
        let c = v(50.0, -20.0);
        let disc = Polygon::circle(c, 100.0, 256);
        let cuts = streamline_cuts(&disc, StreamKind::Circular, 20.0);
        let closed = cuts.iter().filter(|l| l.first() == l.last()).count();
        assert!(closed >= 3, "{closed} closed loops of {}", cuts.len());
        let pieces = disc.slice(&cuts);
        assert_tiles(&disc, &pieces);
        let rings: Vec<&Polygon> = pieces.iter().filter(|p| p.rings.len() == 2).collect();
        assert!(
            rings.len() >= 3,
            "{} rings of {} pieces",
            rings.len(),
            pieces.len()
        );
        for p in &pieces {
            assert!(
                p.centroid().distance(c) < 5.0,
                "piece centred at {}",
                p.centroid()
            );
        }
        // Concentric: each ring's inner and outer boundaries are circles
        // about the centre (radii vary by less than a fifth of the offset).
        for p in &rings {
            for ring in &p.rings {
                let (lo, hi) = ring.iter().fold((f64::MAX, 0.0f64), |(lo, hi), q| {
                    (lo.min(q.distance(c)), hi.max(q.distance(c)))
                });
                assert!(hi - lo < 4.0, "ring radii {lo}..{hi}");
            }
        }
    }

    #[test]
    fn circular_split_of_a_square_nests_pieces_around_the_centre() {
        let sq = Polygon::rect(v(0.0, 0.0), v(200.0, 200.0));
        let pieces = streamline_split(&sq, StreamKind::Circular, 20.0);
        assert_tiles(&sq, &pieces);
        let centre = v(100.0, 100.0);
        let nested: Vec<&Polygon> = pieces
            .iter()
            .filter(|p| p.rings.len() == 2 && p.centroid().distance(centre) < 5.0)
            .collect();
        assert!(
            nested.len() >= 3,
            "{} nested rings of {}",
            nested.len(),
            pieces.len()
        );
        // And a piece holds the centre itself.
        assert!(pieces.iter().any(|p| p.contains(centre)));
    }

    #[test]
    fn circular_split_turns_around_the_given_point() {
        // Boundary vectors are normalised (paper), so the field's centre is
        // near P′ but not exactly on it for a point off the centroid.
        let sq = Polygon::rect(v(0.0, 0.0), v(200.0, 200.0));
        let at = v(60.0, 140.0);
        let pieces = streamline_split_at(&sq, StreamKind::Circular, 15.0, Some(at));
        assert_tiles(&sq, &pieces);
        let core = pieces
            .iter()
            .filter(|p| p.rings.len() == 1 && p.contains(p.centroid()))
            .min_by(|a, b| {
                a.centroid()
                    .distance(at)
                    .total_cmp(&b.centroid().distance(at))
            })
            .unwrap();
        let d = core.centroid().distance(at);
        assert!(d < 25.0, "core piece at {} ({d} from P′)", core.centroid());
        assert!(
            core.area() < 0.08 * sq.area(),
            "core piece area {}",
            core.area()
        );
        let rings = pieces
            .iter()
            .filter(|p| p.rings.len() == 2 && p.centroid().distance(at) < 30.0)
            .count();
        assert!(rings >= 3, "{rings} rings around P′");
    }

    #[test]
    fn strip_split_of_a_long_rectangle_cuts_across_it() {
        let r = Polygon::rect(v(0.0, 0.0), v(400.0, 100.0));
        let offset = 20.0;
        let pieces = streamline_split(&r, StreamKind::Strip, offset);
        assert_tiles(&r, &pieces);
        let n = pieces.len() as f64;
        let expect = 400.0 / offset;
        assert!(
            n >= 0.6 * expect && n <= 2.0 * expect,
            "{n} pieces, expected about {expect}"
        );
        // Strips cross the rectangle: most of its area is in pieces taller
        // than wide that reach from the bottom side to the top side.
        let across: f64 = pieces
            .iter()
            .filter(|p| {
                let (lo, hi) = p.bbox();
                hi.y - lo.y > 2.0 * (hi.x - lo.x) && lo.y < 1.0 && hi.y > 99.0
            })
            .map(Polygon::area)
            .sum();
        assert!(across > 0.5 * r.area(), "{across} of {}", r.area());
    }

    #[test]
    fn smooth_split_of_an_l_shape_follows_its_outline() {
        let l = l_shape();
        let pieces = streamline_split(&l, StreamKind::Smooth, 20.0);
        assert_tiles(&l, &pieces);
        // Ring-like: a ring runs round inside the L, and the pieces are
        // bands about one offset wide (2·area/perimeter), not blobs.
        let rings = pieces.iter().filter(|p| p.rings.len() >= 2).count();
        assert!(rings >= 1, "no ring among {} pieces", pieces.len());
        let widths: Vec<f64> = pieces
            .iter()
            .map(|p| {
                let per: f64 = p.rings.iter().map(|r| ring_length(r)).sum();
                2.0 * p.area() / per
            })
            .collect();
        let bands = widths.iter().filter(|&&w| w < 1.5 * 20.0).count();
        assert!(bands * 5 >= pieces.len() * 4, "band widths {widths:?}");
        let largest = pieces.iter().map(Polygon::area).fold(0.0, f64::max);
        assert!(largest < 0.35 * l.area(), "a blob of {largest}");
    }

    #[test]
    fn splits_are_deterministic() {
        for kind in [StreamKind::Smooth, StreamKind::Strip, StreamKind::Circular] {
            let a = streamline_cuts(&square_with_hole(), kind, 12.0);
            let b = streamline_cuts(&square_with_hole(), kind, 12.0);
            assert!(!a.is_empty());
            assert_eq!(a, b);
        }
    }

    #[test]
    fn degenerate_input_is_returned_unsplit() {
        let tiny = Polygon::rect(v(0.0, 0.0), v(1e-4, 1e-4));
        let sq = Polygon::rect(v(0.0, 0.0), v(10.0, 10.0));
        let flat = Polygon {
            rings: vec![vec![v(0.0, 0.0), v(5.0, 0.0), v(10.0, 0.0)]],
        };
        for kind in [StreamKind::Smooth, StreamKind::Strip, StreamKind::Circular] {
            assert_eq!(streamline_split(&tiny, kind, 1.0), vec![tiny.clone()]);
            for offset in [10.0, 50.0, 0.0, -1.0, f64::NAN, f64::INFINITY] {
                assert_eq!(streamline_split(&sq, kind, offset), vec![sq.clone()]);
            }
            assert!(streamline_cuts(&flat, kind, 1.0).is_empty());
            assert!(streamline_cuts(&Polygon::default(), kind, 1.0).is_empty());
            // A tiny offset is raised to the extent / MAX_ACROSS: still
            // bounded, still a tiling.
            let pieces = streamline_split(&sq, kind, 1e-9);
            assert_tiles(&sq, &pieces);
        }
    }

    fn arb_poly() -> impl Strategy<Value = Polygon> {
        proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 3..10).prop_filter_map(
            "degenerate",
            |pts| {
                let ring = pts.into_iter().map(|(x, y)| DVec2::new(x, y)).collect();
                Polygon::new(vec![ring])?.into_iter().next()
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Any shape, any kind: the pieces tile it.
        #[test]
        fn streamline_pieces_tile_any_polygon(p in arb_poly(), kind in 0..3usize, offset in 2.0f64..20.0) {
            let kind = [StreamKind::Smooth, StreamKind::Strip, StreamKind::Circular][kind];
            let pieces = streamline_split(&p, kind, offset);
            let sum: f64 = pieces.iter().map(Polygon::area).sum();
            prop_assert!((sum - p.area()).abs() <= 1e-3 * p.area().max(1.0), "{sum} vs {}", p.area());
            let union: f64 = Polygon::union_all(&pieces).iter().map(Polygon::area).sum();
            prop_assert!((union - sum).abs() <= 1e-3 * sum.max(1.0), "overlap: {union} vs {sum}");
        }
    }
}

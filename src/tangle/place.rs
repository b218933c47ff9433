//! Shape placement, paper §4.2 "Shape placement": `place(s, d)` packs
//! copies of a motif inside a region and keeps what is left over.
//!
//! The paper's four steps, each bounded:
//!
//! 1. **Poisson disc centres by dart throwing** inside the region: darts
//!    land uniformly on the region's raster (below), a dart is kept when it
//!    lies in the region, at least `e + MIN_SCALE·s/2` from its boundary
//!    and at least `s + d` from every kept centre. At most
//!    [`MAX_DARTS`] darts, stopping after [`MAX_MISSES`] misses in a row or
//!    at [`MAX_PLACEMENTS`] centres.
//! 2. **Lloyd relaxation of a geodesic centroidal Voronoi diagram** on a
//!    raster: the region is rasterised with cells `(s + d)/8` wide (finer
//!    than the sampling), but never more than [`MAX_RASTER`] cells along
//!    either side whatever the region's size (a region more than 64 sample
//!    spacings across gets coarser cells than that). A multi-source Dijkstra
//!    (8 neighbours, Euclidean step costs, no corner cutting) from the
//!    centres through inside cells gives every cell its geodesically nearest
//!    centre; each centre moves to its cell's centroid, and a centroid that
//!    falls outside the region or outside its own cell (a non-convex cell:
//!    a ring's cell has its centroid in the hole) is snapped to the closest
//!    raster cell of its own cell. [`LLOYD_ITERATIONS`] rounds at most,
//!    fewer once no centre moves more than a quarter of a raster cell.
//! 3. **The motif at each centre**, scaled to diameter `s`, unrotated (the
//!    motif's own orientation is kept; a rule that wants rotation rotates
//!    the motif), shrunk until it fits: its bounding disc (the motif lies
//!    in the unit disc) keeps `e` from the region's boundary, measured
//!    exactly with [`Polygon::boundary_distance`].
//! 4. **Shrinking until nothing overlaps**: while two placed shapes'
//!    bounding discs are closer than `d`, the larger of the pair is scaled
//!    by 0.9 (never below `MIN_SCALE·s/2`), [`MAX_SHRINK_ROUNDS`] rounds at
//!    most. Centres too close for even two minimum-size shapes (possible
//!    after relaxation) drop the later one first, and any pair still
//!    offending after the rounds drops its later shape, so the result holds
//!    by construction: placed shapes lie inside the region, keep `e` from
//!    its boundary and `d` from each other (on their bounding discs, so
//!    the polygons themselves keep at least that).
//!
//! Parameters: `s` (size) is a placed shape's diameter — the diameter of
//! the disc it is scaled into; `d` (distance) is the desired gap between
//! two placed shapes, so full-size centres are `s + d` apart; a shape
//! keeps `e = min(d/2, s/10)` from the region's edge. (Not `d/2`: the
//! paper's own Fig. 9 grammar places blobs of `s = 20` with `d = 25` in
//! the 25-wide ring of an `outline(25)`, which only works if the edge
//! margin is small; `s/10` keeps shapes off the edge line.) Shapes that
//! would be smaller than
//! [`MIN_SCALE`]` · s` are dropped rather than placed as specks.
//!
//! Degenerate input (an empty or sliver region, a non-finite or
//! non-positive size, a negative or non-finite distance, an empty motif)
//! places nothing and gives the whole region back as the remainder.
use crate::core::rng::Rng;
use crate::tangle::geom::edge_grid::EdgeGrid;
use crate::tangle::geom::order;
use crate::tangle::geom::polygon::{Polygon, SLIVER_AREA};
use glam::DVec2;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// At most this many shapes are placed into one region. A region that
/// could hold more gets this many, spread over all of it by the
/// relaxation (they are then further apart than `s + d`).
pub const MAX_PLACEMENTS: usize = 2000;

/// Raster cells along the longer side of the region at most (so the raster
/// has at most `(MAX_RASTER + 2)²` cells, border included, whatever the
/// region's size).
pub const MAX_RASTER: usize = 512;

/// Raster cells per sample spacing `s + d` (when the cap allows).
const CELLS_PER_SPACING: f64 = 8.0;

/// Darts thrown in step 1 at most.
pub const MAX_DARTS: usize = 100_000;

/// Step 1 stops after this many rejected darts in a row.
pub const MAX_MISSES: usize = 1_000;

/// Lloyd rounds in step 2 at most.
pub const LLOYD_ITERATIONS: usize = 10;

/// Overlap-shrinking rounds in step 4 at most.
pub const MAX_SHRINK_ROUNDS: usize = 64;

/// Step 4's shrink factor.
const SHRINK: f64 = 0.9;

/// A placed shape is at least this fraction of the size `s` across;
/// anything that would be smaller is dropped.
pub const MIN_SCALE: f64 = 0.25;

/// What [`place`] gives: the placed copies and the region minus them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Placement {
    /// The placed motifs, in a deterministic order (by their centre's
    /// dart). Pairwise disjoint, each inside the region.
    pub placed: Vec<Polygon>,
    /// `region − ⋃ placed` (the whole region when nothing was placed).
    pub remainder: Vec<Polygon>,
}

/// `p` centred at its area centroid and scaled so that its farthest point
/// is at distance 1: the form [`place`] expects. `None` for an empty,
/// zero-area or non-finite polygon.
pub fn normalise_motif(p: &Polygon) -> Option<Polygon> {
    if !solid(p) {
        return None;
    }
    let c = p.centroid();
    let far = p
        .rings
        .iter()
        .flatten()
        .map(|v| v.distance(c))
        .fold(0.0, f64::max);
    if !(c.is_finite() && far.is_finite() && far > 0.0) {
        return None;
    }
    let rings = p
        .rings
        .iter()
        .map(|r| r.iter().map(|&v| (v - c) / far).collect())
        .collect();
    Some(Polygon { rings })
}

/// Places copies of `motif` (inside the unit disc at the origin, see
/// [`normalise_motif`]; a motif reaching further is scaled down into it)
/// of diameter `size` into `region`, keeping gaps of `distance` (module
/// docs for the exact meaning), with randomness only from `rng`.
///
/// Never panics; at most [`MAX_PLACEMENTS`] shapes; the same `rng` state
/// gives the same result bit for bit.
pub fn place(
    region: &Polygon,
    motif: &Polygon,
    size: f64,
    distance: f64,
    rng: &mut Rng,
) -> Placement {
    let nothing = || Placement {
        placed: vec![],
        remainder: if region.rings.is_empty() {
            vec![]
        } else {
            vec![region.clone()]
        },
    };
    let Some(params) = Params::new(region, motif, size, distance) else {
        return nothing();
    };
    let raster = Raster::new(region, params.spacing);
    if raster.inside_cells.is_empty() {
        return nothing();
    }
    // Every dart, centroid and disc asks the region where a point is: the
    // edge grid answers from the edges nearby (the same answers).
    let edges = EdgeGrid::new(region);
    let mut centres = dart_throw(region, &edges, &raster, &params, rng);
    if centres.is_empty() {
        return nothing();
    }
    lloyd(&edges, &raster, &mut centres);
    let discs = fit_discs(region, &edges, &centres, &params);
    let placed: Vec<Polygon> = discs
        .into_iter()
        .map(|(c, r)| Polygon {
            rings: params
                .motif
                .rings
                .iter()
                .map(|ring| ring.iter().map(|&v| c + v * r).collect())
                .collect(),
        })
        .filter(|p| p.area() >= SLIVER_AREA)
        .collect();
    if placed.is_empty() {
        return nothing();
    }
    let remainder = region.difference_all(&placed);
    Placement { placed, remainder }
}

/// Finite points and at least a sliver's area.
fn solid(p: &Polygon) -> bool {
    p.rings.iter().flatten().all(|v| v.is_finite()) && p.area() >= SLIVER_AREA
}

/// Checked parameters.
struct Params {
    /// The motif inside the unit disc.
    motif: Polygon,
    /// Full radius `s/2`.
    radius: f64,
    /// Smallest radius kept, `MIN_SCALE · s/2`.
    min_radius: f64,
    /// Desired gap `d`.
    gap: f64,
    /// Gap kept from the region's edge, `min(d/2, s/10)`.
    edge: f64,
    /// Poisson radius `s + d`.
    spacing: f64,
}

impl Params {
    fn new(region: &Polygon, motif: &Polygon, size: f64, distance: f64) -> Option<Params> {
        let size_ok = size.is_finite() && size > 0.0;
        let gap_ok = distance.is_finite() && distance >= 0.0;
        if !(solid(region) && solid(motif) && size_ok && gap_ok) {
            return None;
        }
        let reach = motif
            .rings
            .iter()
            .flatten()
            .map(|v| v.length())
            .fold(0.0, f64::max);
        if !(reach.is_finite() && reach > 0.0) {
            return None;
        }
        let motif = if reach > 1.0 {
            Polygon {
                rings: motif
                    .rings
                    .iter()
                    .map(|r| r.iter().map(|&v| v / reach).collect())
                    .collect(),
            }
        } else {
            motif.clone()
        };
        let spacing = size + distance;
        if !spacing.is_finite() {
            return None;
        }
        Some(Params {
            motif,
            radius: size * 0.5,
            min_radius: MIN_SCALE * size * 0.5,
            gap: distance,
            edge: (0.5 * distance).min(0.1 * size),
            spacing,
        })
    }
}

/// The region on a grid: which cell centres lie inside (even-odd, the
/// same rule as [`Polygon::contains`]).
struct Raster {
    origin: DVec2,
    cell: f64,
    w: usize,
    h: usize,
    inside: Vec<bool>,
    /// Indices of inside cells, ascending.
    inside_cells: Vec<usize>,
}

impl Raster {
    fn new(region: &Polygon, spacing: f64) -> Raster {
        let (lo, hi) = region.bbox();
        let extent = (hi - lo).max_element();
        let cell = (spacing / CELLS_PER_SPACING).max(extent / MAX_RASTER as f64);
        let empty = Raster {
            origin: lo,
            cell: 1.0,
            w: 0,
            h: 0,
            inside: vec![],
            inside_cells: vec![],
        };
        if !(cell.is_finite() && cell > 0.0) {
            return empty;
        }
        // The region's cells plus a border of outside cells all round, so
        // that a cell's 8 neighbours need no bounds checks.
        let dims = |len: f64| ((len / cell).ceil() as usize).clamp(1, MAX_RASTER) + 2;
        let (w, h) = (dims(hi.x - lo.x), dims(hi.y - lo.y));
        let origin = lo - DVec2::splat(cell);
        // Crossings of each row's centre line, edge by edge (each edge
        // only visits the rows it spans).
        let mut rows: Vec<Vec<f64>> = vec![vec![]; h];
        let inner = |v: f64, n: usize| v.clamp(1.0, (n - 1) as f64) as usize;
        for ring in &region.rings {
            let n = ring.len();
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + n - 1) % n]);
                let (y0, y1) = (a.y.min(b.y), a.y.max(b.y));
                // Rows whose centre y is in [y0, y1), one more each side
                // against rounding (the exact test below decides).
                let first = inner(((y0 - origin.y) / cell - 1.5).ceil(), h);
                let last = inner(((y1 - origin.y) / cell + 0.5).ceil(), h);
                for (row, xs) in rows.iter_mut().enumerate().take(last).skip(first) {
                    let y = origin.y + (row as f64 + 0.5) * cell;
                    // The test `contains` makes, so a cell centre is inside
                    // here exactly when `contains` says so.
                    if (a.y > y) != (b.y > y) {
                        xs.push((b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x);
                    }
                }
            }
        }
        let mut inside = vec![false; w * h];
        for (row, xs) in rows.iter_mut().enumerate() {
            order::sort_f64(xs);
            for pair in xs.chunks_exact(2) {
                // Centres x with pair[0] <= x < pair[1], border excluded.
                let first = inner(((pair[0] - origin.x) / cell - 0.5).ceil(), w);
                let last = inner(((pair[1] - origin.x) / cell - 0.5).ceil(), w);
                for i in first..last {
                    inside[row * w + i] = true;
                }
            }
        }
        let inside_cells = (0..w * h).filter(|&i| inside[i]).collect();
        Raster {
            origin,
            cell,
            w,
            h,
            inside,
            inside_cells,
        }
    }

    fn centre(&self, idx: usize) -> DVec2 {
        let (x, y) = (idx % self.w, idx / self.w);
        self.origin + DVec2::new(x as f64 + 0.5, y as f64 + 0.5) * self.cell
    }

    /// The cell containing `p`, if on the grid.
    fn index(&self, p: DVec2) -> Option<usize> {
        let q = (p - self.origin) / self.cell;
        if !(q.x >= 0.0 && q.y >= 0.0) {
            return None;
        }
        let (x, y) = (q.x.floor() as usize, q.y.floor() as usize);
        (x < self.w && y < self.h).then_some(y * self.w + x)
    }
}

/// A uniform grid of points for neighbour queries within `reach`: cells
/// are at least `reach` wide (and at most `GRID_CELLS` along a side), so
/// a query looks at the 3×3 cells around a point.
struct PointGrid {
    origin: DVec2,
    cell: f64,
    w: usize,
    h: usize,
    cells: Vec<Vec<usize>>,
}

const GRID_CELLS: usize = 256;

impl PointGrid {
    fn new(lo: DVec2, hi: DVec2, reach: f64) -> PointGrid {
        let extent = (hi - lo).max_element();
        let cell = reach.max(extent / GRID_CELLS as f64).max(1e-300);
        let dims = |len: f64| ((len / cell).floor() as usize + 1).clamp(1, GRID_CELLS + 1);
        let (w, h) = (dims(hi.x - lo.x), dims(hi.y - lo.y));
        PointGrid {
            origin: lo,
            cell,
            w,
            h,
            cells: vec![vec![]; w * h],
        }
    }

    fn coords(&self, p: DVec2) -> (usize, usize) {
        let q = ((p - self.origin) / self.cell).max(DVec2::ZERO);
        (
            (q.x as usize).min(self.w - 1),
            (q.y as usize).min(self.h - 1),
        )
    }

    fn insert(&mut self, p: DVec2, id: usize) {
        let (x, y) = self.coords(p);
        self.cells[y * self.w + x].push(id);
    }

    /// Ids stored in the 3×3 cells around `p` (a superset of those within
    /// `reach`).
    fn near(&self, p: DVec2) -> impl Iterator<Item = usize> + '_ {
        let (x, y) = self.coords(p);
        let xs = x.saturating_sub(1)..(x + 2).min(self.w);
        (y.saturating_sub(1)..(y + 2).min(self.h)).flat_map(move |yy| {
            xs.clone()
                .flat_map(move |xx| self.cells[yy * self.w + xx].iter().copied())
        })
    }
}

/// Step 1: Poisson disc centres by dart throwing.
fn dart_throw(
    region: &Polygon,
    edges: &EdgeGrid,
    raster: &Raster,
    params: &Params,
    rng: &mut Rng,
) -> Vec<DVec2> {
    let (lo, hi) = region.bbox();
    let mut grid = PointGrid::new(lo, hi, params.spacing);
    let spacing2 = params.spacing * params.spacing;
    let margin = params.edge + params.min_radius;
    let mut centres: Vec<DVec2> = vec![];
    let mut misses = 0;
    for _ in 0..MAX_DARTS {
        if misses >= MAX_MISSES || centres.len() >= MAX_PLACEMENTS {
            break;
        }
        let cell = raster.inside_cells[rng.below(raster.inside_cells.len())];
        let jitter = DVec2::new(rng.f64() - 0.5, rng.f64() - 0.5) * raster.cell;
        let p = raster.centre(cell) + jitter;
        let ok = grid
            .near(p)
            .all(|j| centres[j].distance_squared(p) >= spacing2)
            && edges.contains(p)
            && edges.boundary_distance_at_least(p, margin);
        if ok {
            grid.insert(p, centres.len());
            centres.push(p);
            misses = 0;
        } else {
            misses += 1;
        }
    }
    centres
}

const NO_SITE: u32 = u32::MAX;

/// The geodesic Voronoi labelling: for every raster cell, the index of
/// its nearest centre through inside cells ([`NO_SITE`] outside or out of
/// reach). Centres whose raster cell is outside (or taken by a nearer
/// centre) seed nothing.
fn geodesic_cells(raster: &Raster, centres: &[DVec2]) -> Vec<u32> {
    let n = raster.w * raster.h;
    let mut dist = vec![f64::INFINITY; n];
    let mut label = vec![NO_SITE; n];
    let mut heap: BinaryHeap<Reverse<u64>> = BinaryHeap::new();
    for (k, &c) in centres.iter().enumerate() {
        let Some(idx) = raster.index(c) else { continue };
        if !raster.inside[idx] {
            continue;
        }
        let d = c.distance(raster.centre(idx));
        if d < dist[idx] {
            dist[idx] = d;
            label[idx] = k as u32;
            heap.push(Reverse(dist_key(d) << 32 | idx as u64));
        }
    }
    let w = raster.w;
    let diag = raster.cell * std::f64::consts::SQRT_2;
    let inside = &raster.inside;
    while let Some(Reverse(key)) = heap.pop() {
        let idx = (key & 0xFFFF_FFFF) as usize;
        if key >> 32 != dist_key(dist[idx]) {
            continue; // superseded by a shorter path
        }
        let d = dist[idx];
        let site = label[idx];
        // Inside cells are never on the border, so all 8 neighbours exist.
        let (e, wst, n, s) = (idx + 1, idx - 1, idx + w, idx - w);
        let orth = [e, wst, n, s].map(|j| inside[j]);
        let mut relax = |j: usize, step: f64| {
            let nd = d + step;
            if nd < dist[j] {
                dist[j] = nd;
                label[j] = site;
                heap.push(Reverse(dist_key(nd) << 32 | j as u64));
            }
        };
        for (k, &j) in [e, wst, n, s].iter().enumerate() {
            if orth[k] {
                relax(j, raster.cell);
            }
        }
        // No corner cutting: a diagonal step needs both cells it passes
        // between.
        for (dx, dy, j) in [(0, 2, n + 1), (0, 3, s + 1), (1, 2, n - 1), (1, 3, s - 1)] {
            if orth[dx] && orth[dy] && inside[j] {
                relax(j, diag);
            }
        }
    }
    label
}

/// A distance's heap key: its `f32` bit pattern (monotone for
/// non-negative values), so that key and cell index share one `u64`.
/// Ties within `f32` precision go to the lower cell index, the same on
/// every platform.
fn dist_key(d: f64) -> u64 {
    (d as f32).to_bits() as u64
}

/// Step 2: Lloyd relaxation of the geodesic centroidal Voronoi diagram.
/// Centres stay inside the region (a centroid outside is snapped to its
/// own cell's nearest raster cell).
fn lloyd(region: &EdgeGrid, raster: &Raster, centres: &mut [DVec2]) {
    let tolerance = raster.cell * 0.25;
    for _ in 0..LLOYD_ITERATIONS {
        let label = geodesic_cells(raster, centres);
        let mut sum = vec![DVec2::ZERO; centres.len()];
        let mut count = vec![0usize; centres.len()];
        for &idx in &raster.inside_cells {
            let k = label[idx];
            if k != NO_SITE {
                sum[k as usize] += raster.centre(idx);
                count[k as usize] += 1;
            }
        }
        let mut targets: Vec<Option<DVec2>> = (0..centres.len())
            .map(|k| (count[k] > 0).then(|| sum[k] / count[k] as f64))
            .collect();
        // Centroids not in their own cell (or not in the region): the
        // closest raster cell of their own cell instead.
        let mut snap: Vec<Option<(f64, usize)>> = vec![None; centres.len()];
        let mut needs_snap = vec![false; centres.len()];
        let mut any = false;
        for (k, t) in targets.iter().enumerate() {
            if let Some(t) = *t {
                let own = raster.index(t).is_some_and(|i| label[i] == k as u32);
                if !(own && region.contains(t)) {
                    needs_snap[k] = true;
                    any = true;
                }
            }
        }
        if any {
            for &idx in &raster.inside_cells {
                let k = label[idx];
                if k == NO_SITE || !needs_snap[k as usize] {
                    continue;
                }
                let Some(t) = targets[k as usize] else {
                    continue;
                };
                let d = raster.centre(idx).distance_squared(t);
                if snap[k as usize].is_none_or(|(best, _)| d < best) {
                    snap[k as usize] = Some((d, idx));
                }
            }
            for k in 0..centres.len() {
                if needs_snap[k] {
                    targets[k] = snap[k].map(|(_, idx)| raster.centre(idx));
                }
            }
        }
        let mut moved: f64 = 0.0;
        for (c, t) in centres.iter_mut().zip(&targets) {
            if let Some(t) = *t {
                if t.is_finite() {
                    moved = moved.max(c.distance(t));
                    *c = t;
                }
            }
        }
        if moved < tolerance {
            break;
        }
    }
}

/// Steps 3 and 4: each centre's bounding disc `(centre, radius)`, shrunk
/// to keep `e` from the boundary and `d` from the other discs.
fn fit_discs(
    region: &Polygon,
    edges: &EdgeGrid,
    centres: &[DVec2],
    params: &Params,
) -> Vec<(DVec2, f64)> {
    let gap = params.gap;
    // Step 3: fit inside, exactly (the motif lies in its bounding disc).
    let mut discs: Vec<(DVec2, f64)> = centres
        .iter()
        .filter(|&&c| edges.contains(c))
        .map(|&c| {
            let room = edges.boundary_distance(c) - params.edge;
            (c, params.radius.min(room))
        })
        .filter(|&(_, r)| r >= params.min_radius && r.is_finite())
        .collect();
    if discs.is_empty() {
        return discs;
    }
    let (lo, hi) = region.bbox();
    let mut grid = PointGrid::new(lo, hi, 2.0 * params.radius + gap);
    for (i, &(c, _)) in discs.iter().enumerate() {
        grid.insert(c, i);
    }
    let mut alive = vec![true; discs.len()];
    let offends = |a: (DVec2, f64), b: (DVec2, f64)| a.0.distance(b.0) < a.1 + b.1 + gap;
    // Centres too close for two minimum-size shapes: the later one goes.
    let floor = 2.0 * params.min_radius + gap;
    for i in 0..discs.len() {
        if !alive[i] {
            continue;
        }
        for j in grid.near(discs[i].0) {
            if j > i && alive[j] && discs[i].0.distance(discs[j].0) < floor {
                alive[j] = false;
            }
        }
    }
    // Step 4: the larger disc of each offending pair shrinks.
    for _ in 0..MAX_SHRINK_ROUNDS {
        let mut shrink = vec![false; discs.len()];
        let mut any = false;
        for i in 0..discs.len() {
            if !alive[i] {
                continue;
            }
            for j in grid.near(discs[i].0) {
                if j > i && alive[j] && offends(discs[i], discs[j]) {
                    let (ri, rj) = (discs[i].1, discs[j].1);
                    shrink[i] |= ri >= rj;
                    shrink[j] |= rj >= ri;
                    any = true;
                }
            }
        }
        if !any {
            break;
        }
        for (disc, s) in discs.iter_mut().zip(&shrink) {
            if *s {
                disc.1 = (disc.1 * SHRINK).max(params.min_radius);
            }
        }
    }
    // Whatever still offends (only float edge cases) drops its later shape.
    for i in 0..discs.len() {
        if !alive[i] {
            continue;
        }
        for j in grid.near(discs[i].0) {
            if j > i && alive[j] && offends(discs[i], discs[j]) {
                alive[j] = false;
            }
        }
    }
    discs
        .into_iter()
        .zip(alive)
        .filter_map(|(d, a)| a.then_some(d))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use proptest::prelude::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
        Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1))
    }

    fn disc() -> Polygon {
        Polygon::circle(DVec2::ZERO, 1.0, 32)
    }

    /// A ring: outer radius `r1`, hole radius `r0`, centred at `c`.
    fn ring(c: DVec2, r0: f64, r1: f64) -> Polygon {
        let outer = Polygon::circle(c, r1, 128).rings.remove(0);
        let hole = Polygon::circle(c, r0, 96).rings.remove(0);
        Polygon::new(vec![outer, hole]).unwrap().remove(0)
    }

    /// An L: a 100×100 square without its top-right 60×60 quarter.
    fn ell() -> Polygon {
        let pts = [
            (0., 0.),
            (100., 0.),
            (100., 40.),
            (40., 40.),
            (40., 100.),
            (0., 100.),
        ];
        Polygon::new(vec![pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()])
            .unwrap()
            .remove(0)
    }

    fn area(ps: &[Polygon]) -> f64 {
        ps.iter().map(Polygon::area).sum()
    }

    /// Inside, pairwise disjoint, and areas conserved: checked with the
    /// boolean engine, not with the discs the code reasons about.
    fn check_valid(region: &Polygon, p: &Placement) {
        let scale = region.area();
        for (i, a) in p.placed.iter().enumerate() {
            let out = area(&a.difference(region));
            assert!(out <= 1e-9 * scale, "shape {i} sticks out by {out}");
            for b in &p.placed[i + 1..] {
                let both = area(&a.intersect(b));
                assert!(both <= 1e-9 * scale, "shapes overlap by {both}");
            }
        }
        let total = area(&p.placed) + area(&p.remainder);
        assert!(
            (total - region.area()).abs() <= 1e-3 * region.area(),
            "placed + remainder = {total}, region {}",
            region.area()
        );
    }

    #[test]
    fn placed_shapes_lie_inside_and_do_not_overlap_and_areas_conserve() {
        let region = rect(0.0, 0.0, 300.0, 200.0);
        let p = place(&region, &disc(), 20.0, 10.0, &mut Rng::new(1));
        assert!(p.placed.len() > 20, "{} placed", p.placed.len());
        check_valid(&region, &p);
        // A non-disc motif too (a square reaching the unit circle's edge).
        let sq = normalise_motif(&rect(-1.0, -1.0, 1.0, 1.0)).unwrap();
        let p = place(&region, &sq, 20.0, 0.0, &mut Rng::new(2));
        assert!(p.placed.len() > 20, "{} placed", p.placed.len());
        check_valid(&region, &p);
    }

    /// The paper's Fig. 9 places blobs of 20 with gaps of 25 in the
    /// 25-wide ring an `outline(25)` leaves: they must fit across it.
    #[test]
    fn fig_9_blobs_fit_in_the_outline_ring() {
        let outer = rect(0.0, 0.0, 800.0, 600.0);
        let ring = outer.difference(&rect(25.0, 25.0, 775.0, 575.0)).remove(0);
        let p = place(&ring, &disc(), 20.0, 25.0, &mut Rng::new(1));
        // About one blob per 45 units of the ring's 2,700-unit midline.
        assert!(p.placed.len() > 40, "{} placed", p.placed.len());
        check_valid(&ring, &p);
    }

    #[test]
    fn the_gap_d_is_kept_between_shapes_and_a_margin_from_the_edge() {
        let region = rect(0.0, 0.0, 300.0, 200.0);
        let (s, d) = (16.0, 12.0);
        let p = place(&region, &disc(), s, d, &mut Rng::new(5));
        assert!(!p.placed.is_empty());
        let discs: Vec<(DVec2, f64)> = p
            .placed
            .iter()
            .map(|q| {
                let c = q.centroid();
                let r = q.rings[0].iter().map(|v| v.distance(c)).fold(0.0, f64::max);
                (c, r)
            })
            .collect();
        for (i, &(c, r)) in discs.iter().enumerate() {
            assert!(
                r <= s / 2.0 + 1e-9 && r >= MIN_SCALE * s / 2.0 - 1e-9,
                "radius {r}"
            );
            assert!(region.boundary_distance(c) - r >= (d / 2.0).min(s / 10.0) - 1e-6);
            for &(c2, r2) in &discs[i + 1..] {
                assert!(c.distance(c2) - r - r2 >= d - 1e-6);
            }
        }
        // Most shapes are full size: shrinking is the exception.
        let full = discs.iter().filter(|&&(_, r)| r > 0.99 * s / 2.0).count();
        assert!(
            full * 2 > discs.len(),
            "{full} of {} full size",
            discs.len()
        );
    }

    #[test]
    fn the_same_seed_gives_the_same_points_bit_for_bit() {
        let region = ell();
        let a = place(&region, &disc(), 8.0, 4.0, &mut Rng::new(42));
        let b = place(&region, &disc(), 8.0, 4.0, &mut Rng::new(42));
        let bits = |p: &Placement| -> Vec<u64> {
            p.placed
                .iter()
                .chain(&p.remainder)
                .flat_map(|q| q.rings.iter().flatten())
                .flat_map(|v| [v.x.to_bits(), v.y.to_bits()])
                .collect()
        };
        assert!(!a.placed.is_empty());
        assert_eq!(bits(&a), bits(&b));
        let c = place(&region, &disc(), 8.0, 4.0, &mut Rng::new(43));
        assert_ne!(bits(&a), bits(&c), "another seed, another placement");
    }

    #[test]
    fn a_larger_distance_gives_fewer_placements() {
        let region = rect(0.0, 0.0, 400.0, 400.0);
        let near = place(&region, &disc(), 10.0, 5.0, &mut Rng::new(3));
        let far = place(&region, &disc(), 10.0, 30.0, &mut Rng::new(3));
        assert!(
            far.placed.len() * 2 < near.placed.len(),
            "{} vs {}",
            far.placed.len(),
            near.placed.len()
        );
        check_valid(&region, &far);
    }

    #[test]
    fn a_ring_gets_no_centres_in_its_hole_and_an_l_is_filled() {
        let c = DVec2::new(100.0, 100.0);
        let region = ring(c, 50.0, 100.0);
        let p = place(&region, &disc(), 12.0, 6.0, &mut Rng::new(7));
        assert!(p.placed.len() > 30, "{} placed", p.placed.len());
        for q in &p.placed {
            assert!(q.centroid().distance(c) > 50.0, "a shape in the hole");
        }
        check_valid(&region, &p);
        // Both arms of the L get shapes.
        let l = ell();
        let p = place(&l, &disc(), 8.0, 4.0, &mut Rng::new(7));
        check_valid(&l, &p);
        let arm = |f: &dyn Fn(DVec2) -> bool| p.placed.iter().filter(|q| f(q.centroid())).count();
        let (right, top) = (arm(&|v| v.x > 50.0), arm(&|v| v.y > 50.0));
        assert!(
            right > 5 && top > 5,
            "{right} right, {top} top of {}",
            p.placed.len()
        );
    }

    #[test]
    fn geodesic_cells_go_around_a_slot_not_across_it() {
        // A U: a 100×100 square with a slot 45..55 × 10..100 cut from the
        // top. A at the top of the left arm, B at the bottom right.
        let pts = [
            (0., 0.),
            (100., 0.),
            (100., 100.),
            (55., 100.),
            (55., 10.),
            (45., 10.),
            (45., 100.),
            (0., 100.),
        ];
        let u = Polygon::new(vec![pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()])
            .unwrap()
            .remove(0);
        let raster = Raster::new(&u, 8.0);
        let (a, b) = (DVec2::new(40.0, 95.0), DVec2::new(90.0, 5.0));
        let label = geodesic_cells(&raster, &[a, b]);
        let at = |x: f64, y: f64| label[raster.index(DVec2::new(x, y)).unwrap()];
        // (60, 95) is 20 from A across the slot, ~95 from B: B's by path.
        assert_eq!(at(60.0, 95.0), 1);
        assert_eq!(at(10.0, 95.0), 0);
        // No cell in the slot.
        assert_eq!(at(50.0, 50.0), NO_SITE);
        // Every inside cell is reached.
        assert!(raster.inside_cells.iter().all(|&i| label[i] != NO_SITE));
    }

    #[test]
    fn a_ring_with_one_centre_keeps_it_in_the_ring_after_relaxation() {
        // The single cell is the whole ring, its centroid the hole's centre:
        // Lloyd must snap it back into the ring.
        let c = DVec2::new(0.0, 0.0);
        let region = ring(c, 40.0, 50.0);
        let raster = Raster::new(&region, 8.0);
        let mut centres = vec![DVec2::new(45.0, 0.0)];
        lloyd(&EdgeGrid::new(&region), &raster, &mut centres);
        assert!(region.contains(centres[0]), "{:?}", centres[0]);
        let r = centres[0].length();
        assert!(r > 40.0 && r < 50.0, "{r}");
    }

    #[test]
    fn a_region_smaller_than_the_motif_or_degenerate_input_places_nothing() {
        let small = rect(0.0, 0.0, 4.0, 4.0);
        let p = place(&small, &disc(), 20.0, 2.0, &mut Rng::new(1));
        assert!(p.placed.is_empty());
        assert_eq!(p.remainder, vec![small.clone()]);
        let region = rect(0.0, 0.0, 100.0, 100.0);
        for (s, d) in [
            (0.0, 1.0),
            (-5.0, 1.0),
            (f64::NAN, 1.0),
            (f64::INFINITY, 1.0),
            (5.0, -1.0),
            (5.0, f64::NAN),
            (f64::MAX, f64::MAX),
        ] {
            let p = place(&region, &disc(), s, d, &mut Rng::new(1));
            assert!(p.placed.is_empty(), "s {s} d {d}");
            assert_eq!(p.remainder, vec![region.clone()]);
        }
        let nan = Polygon {
            rings: vec![vec![DVec2::ZERO, DVec2::new(f64::NAN, 1.0), DVec2::ONE]],
        };
        assert!(place(&nan, &disc(), 5.0, 1.0, &mut Rng::new(1))
            .placed
            .is_empty());
        assert!(place(&region, &nan, 5.0, 1.0, &mut Rng::new(1))
            .placed
            .is_empty());
        assert!(normalise_motif(&nan).is_none());
        let p = place(&Polygon::default(), &disc(), 5.0, 1.0, &mut Rng::new(1));
        assert!(p.placed.is_empty() && p.remainder.is_empty());
        let p = place(&region, &Polygon::default(), 5.0, 1.0, &mut Rng::new(1));
        assert!(p.placed.is_empty());
        assert!(normalise_motif(&Polygon::default()).is_none());
    }

    #[test]
    fn extreme_scales_stay_bounded() {
        // A tiny size in a huge region: capped at MAX_PLACEMENTS.
        let region = rect(0.0, 0.0, 1e6, 1e6);
        let p = place(&region, &disc(), 1.0, 0.0, &mut Rng::new(9));
        assert!(p.placed.len() <= MAX_PLACEMENTS && p.placed.len() > 100);
        // A sliver region.
        let thin = rect(0.0, 0.0, 1000.0, 1e-4);
        let p = place(&thin, &disc(), 1.0, 0.0, &mut Rng::new(9));
        assert!(p.placed.is_empty());
    }

    #[test]
    fn a_motif_is_normalised_to_the_unit_disc_at_its_centroid() {
        let m = normalise_motif(&rect(10.0, 20.0, 14.0, 26.0)).unwrap();
        assert!(m.centroid().length() < 1e-12);
        let far = m.rings[0].iter().map(|v| v.length()).fold(0.0, f64::max);
        assert!((far - 1.0).abs() < 1e-12);
        // An un-normalised motif is brought into the unit disc by place.
        let region = rect(0.0, 0.0, 200.0, 200.0);
        let big = Polygon::circle(DVec2::ZERO, 7.0, 16);
        check_valid(&region, &place(&region, &big, 20.0, 5.0, &mut Rng::new(4)));
    }

    fn arb_region() -> impl Strategy<Value = Polygon> {
        proptest::collection::vec((0.0f64..120.0, 0.0f64..120.0), 3..10).prop_filter_map(
            "degenerate",
            |pts| {
                let ring = pts.into_iter().map(|(x, y)| DVec2::new(x, y)).collect();
                Polygon::new(vec![ring])?.into_iter().next()
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Any polygon, any size and gap: inside, disjoint, area conserved.
        #[test]
        fn any_region_gets_a_valid_placement(region in arb_region(),
            s in 2.0f64..30.0, d in 0.0f64..15.0, seed in 0u64..1000) {
            let p = place(&region, &disc(), s, d, &mut Rng::new(seed));
            check_valid(&region, &p);
        }
    }

    /// Timings for the report (run by hand:
    /// `cargo test --release --lib tangle::place::tests::bench -- --ignored --nocapture`).
    #[test]
    #[ignore]
    #[allow(clippy::disallowed_methods)] // a native, hand-run measurement
    fn bench_placement() {
        let cases = [
            (
                "rect 800x600 s20 d25",
                rect(0.0, 0.0, 800.0, 600.0),
                20.0,
                25.0,
            ),
            (
                "ring 400 wide s20 d25",
                ring(DVec2::ZERO, 100.0, 200.0),
                20.0,
                25.0,
            ),
            ("rect 800x600 s4 d2", rect(0.0, 0.0, 800.0, 600.0), 4.0, 2.0),
        ];
        for (name, region, s, d) in cases {
            let mut times = vec![];
            let mut n = 0;
            for seed in 0..7 {
                let t = std::time::Instant::now();
                let p = place(&region, &disc(), s, d, &mut Rng::new(seed));
                times.push(t.elapsed().as_secs_f64() * 1e3);
                n = p.placed.len();
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{name}: {n} placed, min {:.2} ms, median {:.2} ms",
                times[0], times[3]
            );
        }
    }
}

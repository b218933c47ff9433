//! The evaluator: every colour's field on a `w × h` grid with two-level
//! tile culling (see [`cull`]), per-pixel evaluation of what survives, and
//! the backward pass from field adjoints to tape nodes.
use super::scene::{GeomCache, Scene};
use super::{greater, lesser, win_code, CombineOp, Grid, Hit, Win, CAP, NONE, NO_CODE, T1, T2};
use crate::pattern::sdf::Fields;

/// Small tiles per big tile along each axis.
const S: usize = T1 / T2;

/// Scratch and results of evaluating all colour fields on a grid.
#[derive(Debug, Clone)]
pub struct Evaluator {
    /// The grid (`w × h` pixels over the canvas).
    pub grid: Grid,
    /// Multiplier from canvas units to the stored field units.
    pub scale: f64,
    /// Field values, channel-major: `s[c * w·h + y * w + x]`, in `scale` units,
    /// clamped to `±CAP·scale` and to the distance to the canvas edge
    /// ([`super::edge_cap`]).
    pub s: Vec<f64>,
    /// Winners as codes ([`super::win_code`]; [`Evaluator::winner`]
    /// decodes one), same layout (filled only when asked for).
    pub win: Vec<u64>,
    /// Item evaluations done by the last call (a deterministic work measure).
    pub work: u64,
    pub(super) prim_vals: Vec<Fields>,
    pub(super) widths: Vec<f64>,
    pub(super) centre_vals: Vec<f64>,
    pub(super) keep: Vec<bool>,
    /// [`cull`]'s scratch for long chains' values.
    cull_vals: Vec<f64>,
    pub(super) stamp: Vec<u32>,
    pub(super) used: Vec<u32>,
    pub(super) chain1: Vec<(CombineOp, u32)>,
    pub(super) chain2: Vec<(CombineOp, u32)>,
    pub(super) ranges1: Vec<(usize, usize)>,
    pub(super) ranges2: Vec<(usize, usize)>,
    /// Bounds of each channel's value over the current small tile, from
    /// [`cull`].
    bounds2: Vec<(f64, f64)>,
    pub(super) gcache: GeomCache,
    pub(super) lane_channels: Vec<bool>,
    /// Lane items' values at the small-tile centres of the current big
    /// tile, by position in the big tile's used items.
    small_vals: Vec<[f64; S * S]>,
    /// `edge_x[x]`, `edge_y[y]`: [`super::edge_cap`] by column and by row,
    /// so `edge_cap(x, y) = min(edge_x[x], edge_y[y])` (the same bits: the
    /// map is monotone and exact per integer) ([`Grid::edges`]).
    pub(super) edge_x: Vec<f64>,
    pub(super) edge_y: Vec<f64>,
    /// `centres_x[i]`, `centres_y[i]`: the centre of pixel column (row) `i`
    /// in canvas units ([`Grid::centres`], the same bits everywhere).
    pub(super) centres_x: Vec<f64>,
    pub(super) centres_y: Vec<f64>,
    /// The grid `edge_*` and `centres_*` were made for.
    made_for: Option<Grid>,
    /// Culling stamp of the current big tile (counts on across `eval_tiles` calls).
    tile_id: u32,
    /// Unweighted item evaluations of the evaluation in progress.
    raw_work: u64,
}

impl Evaluator {
    /// An evaluator for `n × n` grids on the square canvas whose values
    /// are canvas distances × `scale`.
    pub fn new(n: usize, scale: f64) -> Self {
        Self::on(Grid::square(n), scale)
    }

    /// An evaluator for `grid` whose values are canvas distances × `scale`.
    pub fn on(grid: Grid, scale: f64) -> Self {
        Evaluator {
            grid,
            scale,
            s: vec![],
            win: vec![],
            work: 0,
            prim_vals: vec![],
            widths: vec![],
            centre_vals: vec![],
            keep: vec![],
            cull_vals: vec![],
            stamp: vec![],
            used: vec![],
            chain1: vec![],
            chain2: vec![],
            ranges1: vec![],
            ranges2: vec![],
            bounds2: vec![],
            gcache: GeomCache::default(),
            lane_channels: vec![],
            small_vals: vec![],
            edge_x: vec![],
            edge_y: vec![],
            centres_x: vec![],
            centres_y: vec![],
            made_for: None,
            tile_id: 0,
            raw_work: 0,
        }
    }

    pub(super) fn gather(&mut self, scene: &Scene, nodes: &[f64]) {
        self.prim_vals.clear();
        for p in &scene.rec.prims {
            let mut f = [0.0; 6];
            for k in 0..p.kind.field_count() {
                f[k] = nodes[p.fields[k] as usize];
            }
            self.prim_vals.push(f);
        }
        self.widths.clear();
        self.widths.extend(
            scene
                .rec
                .shapes
                .iter()
                .map(|s| nodes[s.width as usize].max(0.0)),
        );
    }

    /// Evaluate every channel's field from the tape's node values.
    pub fn eval(&mut self, scene: &Scene, nodes: &[f64], winners: bool) {
        self.begin(scene, nodes, winners);
        self.eval_tiles(scene, winners, 0..self.tiles());
        self.finish(scene);
    }

    /// Big tiles (`T1 × T1` pixels) of the grid, the unit of
    /// [`Evaluator::eval_tiles`]: row-major, `w.div_ceil(T1)` per row.
    pub fn tiles(&self) -> usize {
        self.grid.w.div_ceil(T1) * self.grid.h.div_ceil(T1)
    }

    /// Start an evaluation in parts: [`Evaluator::begin`], then
    /// [`Evaluator::eval_tiles`] over consecutive ranges covering
    /// `0..tiles()` in order, then [`Evaluator::finish`]. The fields (and
    /// `work`) are bit for bit those of one [`Evaluator::eval`] call, so a
    /// job can spread one evaluation over several slices.
    pub fn begin(&mut self, scene: &Scene, nodes: &[f64], winners: bool) {
        self.gather(scene, nodes);
        self.gcache.start(scene.rec.shapes.len());
        let g = self.grid;
        if self.made_for != Some(g) {
            (self.edge_x, self.edge_y) = g.edges();
            (self.centres_x, self.centres_y) = g.centres();
            self.made_for = Some(g);
        }
        let nn = g.len();
        let nc = scene.channels.len();
        if self.s.capacity() < nc * nn {
            // Every value is written by the evaluation: a fresh zeroed
            // allocation (pages the system zeroes when first touched) spares
            // this call from writing up to hundreds of megabytes at once.
            self.s = vec![0.0; nc * nn];
        }
        self.s.resize(nc * nn, 0.0);
        if winners {
            self.win.resize(nc * nn, NO_CODE);
        }
        self.centre_vals.resize(scene.items.len(), 0.0);
        // `stamp[i] == tile_id`: item `i` is already in the current big
        // tile's `used`. The ids restart at every evaluation, so the stamps
        // of the last one must go: a stale stamp equal to a new tile's id
        // would leave an item out of that tile, and the fields would depend
        // on the evaluation before (a sharded fit then differed from one fit).
        self.stamp.clear();
        self.stamp.resize(scene.items.len(), u32::MAX);
        self.tile_id = 0;
        self.raw_work = 0;
    }

    /// Finish an evaluation begun with [`Evaluator::begin`]: sets `work`.
    pub fn finish(&mut self, scene: &Scene) {
        // Weighted by the mean item cost so the figure tracks time.
        self.work = (self.raw_work as f64 * scene.cost) as u64;
    }

    /// Item evaluations so far in the evaluation begun last (unweighted).
    pub fn raw_work(&self) -> u64 {
        self.raw_work
    }

    /// Evaluate the big tiles `tiles` (see [`Evaluator::tiles`]); the
    /// ranges of one evaluation must follow each other in order.
    pub fn eval_tiles(&mut self, scene: &Scene, winners: bool, tiles: std::ops::Range<usize>) {
        let (gw, gh) = (self.grid.w, self.grid.h);
        let nn = self.grid.len();
        let (ppx, ppy) = self.grid.ppu();
        let (ix, iy) = (1.0 / ppx, 1.0 / ppy);
        // Half diagonals (canvas units) of the two tile levels, a hair larger
        // for rounding (pixels taken as squares of the larger side).
        let inv = ix.max(iy);
        let h1 = (T1 as f64 * inv) * std::f64::consts::FRAC_1_SQRT_2 * 1.000001;
        let h2 = (T2 as f64 * inv) * std::f64::consts::FRAC_1_SQRT_2 * 1.000001;
        let mut work = 0u64;
        let mut chain1 = std::mem::take(&mut self.chain1);
        let mut chain2 = std::mem::take(&mut self.chain2);
        let mut used = std::mem::take(&mut self.used);
        let mut tile_id = self.tile_id;
        let per_row = gw.div_ceil(T1);
        {
            for t in tiles.start..tiles.end.min(per_row * gh.div_ceil(T1)) {
                let (tx, ty) = (t % per_row, t / per_row);
                let (x0, y0) = (tx * T1, ty * T1);
                let pc = [(x0 + T1 / 2) as f64 * ix, (y0 + T1 / 2) as f64 * iy];
                self.gcache.next();
                for (i, it) in scene.items.iter().enumerate() {
                    self.centre_vals[i] = scene
                        .item_hit(it, &self.prim_vals, &self.widths, pc, &mut self.gcache)
                        .0;
                }
                work += scene.items.len() as u64;
                // Level 1: cull each channel's full chain for the big tile.
                chain1.clear();
                self.ranges1.clear();
                used.clear();
                tile_id = tile_id.wrapping_add(1);
                for ch in &scene.channels {
                    let a = chain1.len();
                    cull(
                        &ch.ops,
                        ch.init,
                        &self.centre_vals,
                        h1,
                        (&mut self.keep, &mut self.cull_vals),
                        &mut chain1,
                    );
                    self.ranges1.push((a, chain1.len()));
                }
                for &(_, it) in &chain1 {
                    if self.stamp[it as usize] != tile_id {
                        self.stamp[it as usize] = tile_id;
                        used.push(it);
                    }
                }
                // Level 2: small tiles, only the items level 1 kept. The
                // lane items' values at all the small tiles' centres at
                // once (lane `k`: small tile `(k % S, k / S)`), the same
                // bits as one `item_hit` per centre.
                let (mut scx, mut scy) = ([0.0; S * S], [0.0; S * S]);
                for k in 0..S * S {
                    scx[k] = (x0 + (k % S) * T2 + T2 / 2) as f64 * ix;
                    scy[k] = (y0 + (k / S) * T2 + T2 / 2) as f64 * iy;
                }
                self.small_vals.clear();
                for &it in &used {
                    let item = &scene.items[it as usize];
                    if item.lanes {
                        let d = self.lane_distances(item, &scx, &scy);
                        let v = self.lane_values(item, &d);
                        self.small_vals.push(v);
                    } else {
                        self.small_vals.push([f64::NAN; S * S]);
                    }
                }
                let scalar_used = used.iter().any(|&it| !scene.items[it as usize].lanes);
                for sy in (y0..(y0 + T1).min(gh)).step_by(T2) {
                    for sx in (x0..(x0 + T1).min(gw)).step_by(T2) {
                        let pc = [(sx + T2 / 2) as f64 * ix, (sy + T2 / 2) as f64 * iy];
                        let k = (sy - y0) / T2 * S + (sx - x0) / T2;
                        for (&it, v) in used.iter().zip(&self.small_vals) {
                            self.centre_vals[it as usize] = v[k];
                        }
                        if scalar_used {
                            self.gcache.next();
                            for &it in &used {
                                let it_ = &scene.items[it as usize];
                                if !it_.lanes {
                                    self.centre_vals[it as usize] = scene
                                        .item_hit(
                                            it_,
                                            &self.prim_vals,
                                            &self.widths,
                                            pc,
                                            &mut self.gcache,
                                        )
                                        .0;
                                }
                            }
                        }
                        work += used.len() as u64;
                        chain2.clear();
                        self.ranges2.clear();
                        self.bounds2.clear();
                        for (c, ch) in scene.channels.iter().enumerate() {
                            let (a, b) = self.ranges1[c];
                            let start = chain2.len();
                            let bounds = cull(
                                &chain1[a..b],
                                ch.init,
                                &self.centre_vals,
                                h2,
                                (&mut self.keep, &mut self.cull_vals),
                                &mut chain2,
                            );
                            self.ranges2.push((start, chain2.len()));
                            self.bounds2.push(bounds);
                        }
                        let (xe, ye) = ((sx + T2).min(gw), (sy + T2).min(gh));
                        // Chains of single circles, points and segments: a 4-lane kernel.
                        self.lane_channels.clear();
                        let (lx, ly, lcap) = self.lane_centres((sx, xe), (sy, ye));
                        let cap_max = lcap.iter().fold(0.0, |m, &c| greater(m, c));
                        for (c, ch) in scene.channels.iter().enumerate() {
                            // A channel whose value is beyond the cap all over
                            // the block is the cap there (the same bits): no
                            // item needs evaluating.
                            let (lo, hi) = self.bounds2[c];
                            if lo >= cap_max || hi <= -cap_max {
                                let side = if lo >= cap_max { 1.0 } else { -1.0 };
                                self.capped(c, side, (sx, xe), (sy, ye), &lcap, winners);
                                self.lane_channels.push(true);
                                continue;
                            }
                            let (a, b) = self.ranges2[c];
                            let ops = &chain2[a..b];
                            let fast = ops.iter().all(|&(_, it)| scene.items[it as usize].lanes);
                            self.lane_channels.push(fast);
                            if fast {
                                work += (ops.len() * (xe - sx) * (ye - sy)) as u64;
                                if winners {
                                    self.lanes::<true>(
                                        scene,
                                        ch.init,
                                        ops,
                                        c,
                                        (sx, xe),
                                        (sy, ye),
                                        (&lx, &ly, &lcap),
                                    );
                                } else {
                                    self.lanes::<false>(
                                        scene,
                                        ch.init,
                                        ops,
                                        c,
                                        (sx, xe),
                                        (sy, ye),
                                        (&lx, &ly, &lcap),
                                    );
                                }
                            }
                        }
                        let scalar = !self.lane_channels.iter().all(|&l| l);
                        for y in (sy..ye).filter(|_| scalar) {
                            for x in sx..xe {
                                let p = [self.centres_x[x], self.centres_y[y]];
                                self.gcache.next();
                                for (c, ch) in scene.channels.iter().enumerate() {
                                    if self.lane_channels[c] {
                                        continue;
                                    }
                                    let (a, b) = self.ranges2[c];
                                    let ops = &chain2[a..b];
                                    work += ops.len() as u64;
                                    let idx = c * nn + y * gw + x;
                                    let cap = self.edge_x[x].min(self.edge_y[y]);
                                    self.pixel(scene, ch.init, ops, p, cap, idx, winners);
                                }
                            }
                        }
                    }
                }
            }
        }
        self.chain1 = chain1;
        self.chain2 = chain2;
        self.used = used;
        self.tile_id = tile_id;
        self.raw_work += work;
    }

    /// Apply a culled chain at one pixel; consecutive same-kind operations
    /// form a run whose minimum is applied once. The value is clamped to
    /// `±edge` (canvas units, at most `CAP`; see [`super::edge_cap`]), and
    /// a clamped value has no winner.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pixel(
        &mut self,
        scene: &Scene,
        init: f64,
        ops: &[(CombineOp, u32)],
        p: [f64; 2],
        edge: f64,
        idx: usize,
        winners: bool,
    ) {
        let cap = CAP.min(edge);
        let mut b = init * CAP;
        // Winner: item, hit, and whether a difference flipped it.
        let mut win: Option<(u32, Hit, bool)> = None;
        let mut i = 0;
        while i < ops.len() {
            let op = ops[i].0;
            let mut best = f64::INFINITY;
            let mut bw = (
                NONE,
                Hit {
                    d: 0.0,
                    prim: NONE,
                    sign: 1.0,
                },
            );
            while i < ops.len() && ops[i].0 == op {
                let it = ops[i].1;
                let (v, h) = scene.item_hit(
                    &scene.items[it as usize],
                    &self.prim_vals,
                    &self.widths,
                    p,
                    &mut self.gcache,
                );
                if v < best {
                    best = v;
                    bw = (it, h);
                }
                i += 1;
            }
            match op {
                CombineOp::Union => {
                    if best < b {
                        b = best;
                        win = Some((bw.0, bw.1, false));
                    }
                }
                CombineOp::Diff => {
                    if -best > b {
                        b = -best;
                        win = Some((bw.0, bw.1, true));
                    }
                }
            }
        }
        if b.abs() >= cap {
            b = b.clamp(-cap, cap);
            win = None;
        }
        self.s[idx] = b * self.scale;
        if winners {
            self.win[idx] = match win {
                None => NO_CODE,
                Some((it, h, flip)) => win_code(it, &h, flip),
            };
        }
    }

    /// The winner record of channel-pixel `idx` (layout of
    /// [`Evaluator::s`]) after an evaluation with winners.
    pub fn winner(&self, scene: &Scene, idx: usize) -> Win {
        scene.decode_win(self.win[idx])
    }

    /// Channel `c`'s values over a block whose every value is at least
    /// its cap (`side` 1) or at most minus it (`side` −1): the clamped
    /// values, as [`Evaluator::lanes`] writes them, and no winners.
    fn capped(
        &mut self,
        c: usize,
        side: f64,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
        caps: &[f64; T2 * T2],
        winners: bool,
    ) {
        let (gw, nn) = (self.grid.w, self.grid.len());
        for j in 0..y1 - y0 {
            let row = c * nn + (y0 + j) * gw + x0;
            for (i, o) in self.s[row..row + x1 - x0].iter_mut().enumerate() {
                *o = side * caps[j * T2 + i] * self.scale;
            }
            if winners {
                self.win[row..row + x1 - x0].fill(NO_CODE);
            }
        }
    }

    /// The palette index at every pixel, by the fields: the colour whose
    /// field is most negative, or the background where none is.
    pub fn colour_indices(&self, scene: &Scene) -> Vec<u16> {
        (0..self.grid.len())
            .map(|i| self.colour_index(scene, i))
            .collect()
    }

    /// The palette index at pixel `i` (`y * w + x`), as in
    /// [`Evaluator::colour_indices`].
    #[inline]
    pub fn colour_index(&self, scene: &Scene, i: usize) -> u16 {
        let nn = self.grid.len();
        let mut best = (0.0, 0u16);
        for (c, ch) in scene.channels.iter().enumerate() {
            let v = self.s[c * nn + i];
            if v < best.0 {
                best = (v, ch.colour);
            }
        }
        best.1
    }
}

/// Drop the operations of `chain` that cannot change a channel's value
/// anywhere within `h` of the point where `vals` (item values) were taken;
/// append the rest, in order, to `out`. Values are 1-Lipschitz, so each
/// lies in `[v − h, v + h]` over the tile.
///
/// 1. Backward: every operation is monotone in the running value B, so a
///    union (difference) whose value is everywhere ≥ that of a later union
///    (difference) never matters.
/// 2. Forward: track an interval for B; a run of unions (differences) that
///    cannot go below (above) it is dropped, and inside a run (where `min`
///    commutes) items that are never the smallest are dropped.
///
/// Returns the interval: the channel's value (before clamping) lies in it
/// everywhere within `h`.
fn cull(
    chain: &[(CombineOp, u32)],
    init: f64,
    vals: &[f64],
    h: f64,
    (keep, vbuf): (&mut Vec<bool>, &mut Vec<f64>),
    out: &mut Vec<(CombineOp, u32)>,
) -> (f64, f64) {
    // Short chains (most small tiles) keep their flags and values on the
    // stack: no resize, and each value is read from `vals` once.
    const SHORT: usize = 16;
    if chain.len() <= SHORT {
        let mut k = [false; SHORT];
        let mut v = [0.0; SHORT];
        for (v, &(_, it)) in v.iter_mut().zip(chain) {
            *v = vals[it as usize];
        }
        let n = chain.len();
        cull_with(chain, init, &v[..n], h, &mut k[..n], out)
    } else {
        keep.clear();
        keep.resize(chain.len(), false);
        vbuf.clear();
        vbuf.extend(chain.iter().map(|&(_, it)| vals[it as usize]));
        cull_with(chain, init, vbuf, h, keep, out)
    }
}

/// [`cull`] with the items' values `v` in chain order and room for the
/// flags in `keep` (both `chain.len()` long).
#[inline(always)]
fn cull_with(
    chain: &[(CombineOp, u32)],
    init: f64,
    v: &[f64],
    h: f64,
    keep: &mut [bool],
    out: &mut Vec<(CombineOp, u32)>,
) -> (f64, f64) {
    let (mut suf_u, mut suf_d) = (f64::INFINITY, f64::INFINITY);
    for ((&(op, _), k), &v) in chain.iter().zip(keep.iter_mut()).zip(v).rev() {
        // Both bounds stay in registers (selects, not a pointer to one).
        let union = op == CombineOp::Union;
        let suf = if union { suf_u } else { suf_d };
        *k = v - h < suf;
        let next = lesser(suf, v + h);
        (suf_u, suf_d) = if union { (next, suf_d) } else { (suf_u, next) };
    }
    let (mut blo, mut bhi) = (init * CAP, init * CAP);
    let mut i = 0;
    while i < chain.len() {
        let op = chain[i].0;
        let mut j = i;
        let (mut m, mut ylo) = (f64::INFINITY, f64::INFINITY);
        while j < chain.len() && chain[j].0 == op {
            if keep[j] {
                m = lesser(m, v[j] + h);
                ylo = lesser(ylo, v[j] - h);
            }
            j += 1;
        }
        let active = m < f64::INFINITY
            && match op {
                CombineOp::Union => ylo < bhi,
                CombineOp::Diff => -ylo > blo,
            };
        if active {
            for k in i..j {
                if keep[k] && v[k] - h <= m {
                    out.push(chain[k]);
                }
            }
            match op {
                CombineOp::Union => {
                    blo = lesser(blo, ylo);
                    bhi = lesser(bhi, m);
                }
                CombineOp::Diff => {
                    blo = greater(blo, -m);
                    bhi = greater(bhi, -ylo);
                }
            }
        }
        i = j;
    }
    (blo, bhi)
}

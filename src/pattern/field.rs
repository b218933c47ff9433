//! Per-colour pattern SDFs (paper §4 "Pattern Distance Fields" and the
//! "on top" operator, Fig. 6/7).
//!
//! For every colour `c` of the pattern the field starts as "nothing"
//! (`+cap`), or "everything" (`−cap`) for the background colour, and each
//! shape, in drawing order, is applied with the paper's operator
//!
//! ```text
//! OnTop(B, F, c) = union(B, union(S, F))   c = stroke,  c = fill
//!                  diff(B, union(S, F))    c ≠ stroke,  c ≠ fill
//!                  diff(union(B, S), F)    c = stroke,  c ≠ fill
//!                  union(diff(B, S), F)    c ≠ stroke,  c = fill
//! ```
//!
//! with `S` the stroke geometry `|d| − w/2` and `F` the fill geometry. As in
//! the paper's formulas (which need `S` and `F` disjoint) a stroked shape's
//! fill is its interior inset by half the stroke width, `d + w/2`, which is
//! exactly the part of the fill a renderer leaves visible under the stroke.
//! `union = min`, `diff(a, b) = max(a, −b)`; boolean shapes (`union`,
//! `intersect`, `difference` blocks) combine signed geometries with min/max.
//!
//! Every value is therefore ± one primitive's distance (plus a width term):
//! the evaluator remembers that "winner" per pixel and colour, which makes
//! the derivative of the field with respect to the primitive's fields (and
//! from there, by the tape, to the parameters) exact.
//!
//! Culling: the canvas is cut into 8×8-pixel tiles. All distances are
//! 1-Lipschitz, so a value at the tile centre bounds it over the tile to
//! ±(half diagonal). Consecutive operations of the same kind on a colour
//! form a run (`min` over its items commutes); items whose lower bound
//! exceeds the run's smallest upper bound, and runs that cannot change the
//! running interval, are dropped for that tile. Cost then follows the shapes
//! near each tile, not every shape for every pixel.
use super::record::{BoolOp, Geom, Recording};
use super::sdf::{self, Fields, PrimKind};

/// "Farther than anything on the canvas", in canvas units.
pub const CAP: f64 = 2.0;
const NONE: u32 = u32::MAX;
/// Big and small tile sides in pixels (two-level culling).
const T1: usize = 16;
const T2: usize = 4;

/// How an item changes a colour's field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CombineOp {
    /// `min(B, X)`
    Union,
    /// `max(B, −X)`
    Diff,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    Fill,
    Stroke,
}

#[derive(Debug, Clone, Copy)]
struct Item {
    shape: u32,
    part: Part,
    /// Whether the shape also has a stroke (then the fill is inset).
    inset: bool,
    /// The primitive when the geometry is a single one (fast path), else `NONE`.
    prim: u32,
    kind: PrimKind,
    /// A filled circle without stroke: eligible for the 4-lane kernel.
    plain_circle: bool,
}

/// One colour's operation list.
#[derive(Debug, Clone)]
pub struct Channel {
    /// Palette index of the colour.
    pub colour: u16,
    /// `+1` for ordinary colours (start empty), `−1` for the background (start full).
    pub init: f64,
    /// Operations in drawing order: (op, item id).
    ops: Vec<(CombineOp, u32)>,
}

/// A recorded pattern prepared for field evaluation.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The recording (tape, shapes, palette).
    pub rec: Recording,
    /// One channel per colour used by a shape (the background only if a shape uses it).
    pub channels: Vec<Channel>,
    items: Vec<Item>,
}

/// What decided a field value at one pixel: `S = psign·prim(p) + wcoef·width + const`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Win {
    /// Primitive index, or `u32::MAX` when no shape reached the pixel (value is the cap).
    pub prim: u32,
    /// Tape node of the stroke width involved.
    pub wnode: u32,
    pub psign: f32,
    pub wcoef: f32,
}

const NO_WIN: Win = Win {
    prim: NONE,
    wnode: 0,
    psign: 0.0,
    wcoef: 0.0,
};

#[derive(Debug, Clone, Copy)]
struct Hit {
    d: f64,
    prim: u32,
    sign: f64,
}

impl Scene {
    /// Build the per-colour operation lists from a recording.
    pub fn new(rec: Recording) -> Scene {
        let mut used = vec![false; rec.colours.len()];
        let mut items = vec![];
        let mut fill_item = vec![NONE; rec.shapes.len()];
        let mut stroke_item = vec![NONE; rec.shapes.len()];
        for (i, s) in rec.shapes.iter().enumerate() {
            for c in [s.fill, s.stroke].into_iter().flatten() {
                used[c as usize] = true;
            }
            let (prim, kind) = match s.geom {
                Geom::Prim(p) => (p, rec.prims[p as usize].kind),
                _ => (NONE, PrimKind::Point),
            };
            if s.stroke.is_some() {
                stroke_item[i] = items.len() as u32;
                items.push(Item {
                    shape: i as u32,
                    part: Part::Stroke,
                    inset: false,
                    prim,
                    kind,
                    plain_circle: false,
                });
            }
            if s.fill.is_some() {
                fill_item[i] = items.len() as u32;
                items.push(Item {
                    shape: i as u32,
                    part: Part::Fill,
                    inset: s.stroke.is_some(),
                    prim,
                    kind,
                    plain_circle: s.stroke.is_none() && prim != NONE && kind == PrimKind::Circle,
                });
            }
        }
        let mut channels = vec![];
        for (c, &u) in used.iter().enumerate() {
            if !u {
                continue;
            }
            let c = c as u16;
            let mut ops: Vec<(CombineOp, u32)> = vec![];
            for (i, s) in rec.shapes.iter().enumerate() {
                let is_s = s.stroke == Some(c);
                let is_f = s.fill == Some(c);
                let (os, of) = match (is_s, is_f) {
                    (true, true) => (CombineOp::Union, CombineOp::Union),
                    (false, false) => (CombineOp::Diff, CombineOp::Diff),
                    (true, false) => (CombineOp::Union, CombineOp::Diff),
                    (false, true) => (CombineOp::Diff, CombineOp::Union),
                };
                if stroke_item[i] != NONE {
                    ops.push((os, stroke_item[i]));
                }
                if fill_item[i] != NONE {
                    ops.push((of, fill_item[i]));
                }
            }
            // Differences before anything was added remove nothing.
            let init = if c == 0 { -1.0 } else { 1.0 };
            if init > 0.0 {
                let lead = ops.iter().take_while(|o| o.0 == CombineOp::Diff).count();
                ops.drain(..lead);
            }
            channels.push(Channel {
                colour: c,
                init,
                ops,
            });
        }
        Scene {
            rec,
            channels,
            items,
        }
    }

    /// Number of shapes.
    pub fn shape_count(&self) -> usize {
        self.rec.shapes.len()
    }

    fn geom(&self, g: &Geom, pv: &[Fields], p: [f64; 2]) -> Hit {
        match g {
            Geom::Prim(i) => {
                let k = self.rec.prims[*i as usize].kind;
                Hit {
                    d: sdf::value(k, &pv[*i as usize], p),
                    prim: *i,
                    sign: 1.0,
                }
            }
            Geom::Path { first, len, closed } => {
                // Squared distances, one square root per path; segments inline.
                let (mut best_d2, mut best_i) = (f64::INFINITY, *first);
                let mut w = 0;
                for i in *first..first + len {
                    let k = self.rec.prims[i as usize].kind;
                    let f = &pv[i as usize];
                    let d2 = if k == PrimKind::Segment {
                        let (ex, ey) = (f[2] - f[0], f[3] - f[1]);
                        let (wx, wy) = (p[0] - f[0], p[1] - f[1]);
                        let l2 = ex * ex + ey * ey;
                        let t = if l2 > 0.0 {
                            ((wx * ex + wy * ey) / l2).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                        let (bx, by) = (wx - ex * t, wy - ey * t);
                        if *closed && ((f[1] <= p[1]) != (f[3] <= p[1])) {
                            let x = f[0] + (p[1] - f[1]) / (f[3] - f[1]) * ex;
                            if x > p[0] {
                                w += if f[3] > f[1] { 1 } else { -1 };
                            }
                        }
                        bx * bx + by * by
                    } else {
                        if *closed {
                            w += sdf::winding(k, f, p);
                        }
                        let d = sdf::value(k, f, p);
                        d * d
                    };
                    if d2 < best_d2 {
                        best_d2 = d2;
                        best_i = i;
                    }
                }
                let d = best_d2.sqrt();
                if w != 0 {
                    Hit {
                        d: -d,
                        prim: best_i,
                        sign: -1.0,
                    }
                } else {
                    Hit {
                        d,
                        prim: best_i,
                        sign: 1.0,
                    }
                }
            }
            Geom::Bool(op, ch) => {
                let mut best = self.geom(&ch[0], pv, p);
                for c in &ch[1..] {
                    let mut h = self.geom(c, pv, p);
                    match op {
                        BoolOp::Union => {
                            if h.d < best.d {
                                best = h
                            }
                        }
                        BoolOp::Intersect => {
                            if h.d > best.d {
                                best = h
                            }
                        }
                        BoolOp::Difference => {
                            h.d = -h.d;
                            h.sign = -h.sign;
                            if h.d > best.d {
                                best = h
                            }
                        }
                    }
                }
                best
            }
        }
    }

    /// Geometry of a compound shape (path, boolean) at `p`, memoised per
    /// point: a shape's fill and stroke items share it. Out of line so the
    /// single-primitive fast path stays small.
    #[inline(never)]
    fn geom_cached(&self, shape: u32, pv: &[Fields], p: [f64; 2], cache: &mut GeomCache) -> Hit {
        let slot = &mut cache.slots[shape as usize];
        if slot.0 == cache.stamp {
            return slot.1;
        }
        let h = self.geom(&self.rec.shapes[shape as usize].geom, pv, p);
        cache.slots[shape as usize] = (cache.stamp, h);
        h
    }

    /// Item value and the hit that decided it (before the channel's op sign).
    #[inline(always)]
    fn item_hit(
        &self,
        it: &Item,
        pv: &[Fields],
        widths: &[f64],
        p: [f64; 2],
        cache: &mut GeomCache,
    ) -> (f64, Hit) {
        let h = if it.prim != NONE {
            let f = &pv[it.prim as usize];
            let d = match it.kind {
                PrimKind::Circle => {
                    ((p[0] - f[0]) * (p[0] - f[0]) + (p[1] - f[1]) * (p[1] - f[1])).sqrt() - f[2]
                }
                PrimKind::Point => {
                    ((p[0] - f[0]) * (p[0] - f[0]) + (p[1] - f[1]) * (p[1] - f[1])).sqrt()
                }
                PrimKind::Segment => sdf::segment_distance(f, p),
                k => sdf::value(k, f, p),
            };
            Hit {
                d,
                prim: it.prim,
                sign: 1.0,
            }
        } else {
            self.geom_cached(it.shape, pv, p, cache)
        };
        let w = widths[it.shape as usize];
        let v = match it.part {
            Part::Fill => {
                if it.inset {
                    h.d + 0.5 * w
                } else {
                    h.d
                }
            }
            Part::Stroke => h.d.abs() - 0.5 * w,
        };
        (v, h)
    }

    /// The winner record of an item's hit (before the channel's op sign).
    fn win_of(&self, it: &Item, h: &Hit) -> Win {
        let wnode = self.rec.shapes[it.shape as usize].width;
        match it.part {
            Part::Fill => Win {
                prim: h.prim,
                wnode,
                psign: h.sign as f32,
                wcoef: if it.inset { 0.5 } else { 0.0 },
            },
            Part::Stroke => {
                let sg = if h.d >= 0.0 { 1.0 } else { -1.0 };
                Win {
                    prim: h.prim,
                    wnode,
                    psign: (sg * h.sign) as f32,
                    wcoef: -0.5,
                }
            }
        }
    }

    /// Item value with its winner record (used by tests).
    #[cfg(test)]
    fn item(&self, it: &Item, pv: &[Fields], widths: &[f64], p: [f64; 2]) -> (f64, Win) {
        let mut cache = GeomCache::default();
        cache.start(self.rec.shapes.len());
        let (v, h) = self.item_hit(it, pv, widths, p, &mut cache);
        (v, self.win_of(it, &h))
    }
}

/// Scratch and results of evaluating all colour fields on an `n × n` grid.
#[derive(Debug, Clone)]
pub struct Evaluator {
    /// Grid side in pixels.
    pub n: usize,
    /// Multiplier from canvas units to the stored field units.
    pub scale: f64,
    /// Field values, channel-major: `s[c * n² + y * n + x]`, in `scale` units,
    /// clamped to `±CAP·scale`.
    pub s: Vec<f64>,
    /// Winners, same layout (filled only when asked for).
    pub win: Vec<Win>,
    /// Item evaluations done by the last call (a deterministic work measure).
    pub work: u64,
    prim_vals: Vec<Fields>,
    widths: Vec<f64>,
    centre_vals: Vec<f64>,
    keep: Vec<bool>,
    stamp: Vec<u32>,
    used: Vec<u32>,
    chain1: Vec<(CombineOp, u32)>,
    chain2: Vec<(CombineOp, u32)>,
    ranges1: Vec<(usize, usize)>,
    ranges2: Vec<(usize, usize)>,
    gcache: GeomCache,
    lane_channels: Vec<bool>,
}

/// Per-point memo of shape geometries (fill and stroke items share one).
#[derive(Debug, Clone, Default)]
struct GeomCache {
    stamp: u32,
    slots: Vec<(u32, Hit)>,
}

impl GeomCache {
    fn start(&mut self, shapes: usize) {
        self.slots.clear();
        self.slots.resize(
            shapes,
            (
                u32::MAX,
                Hit {
                    d: 0.0,
                    prim: NONE,
                    sign: 1.0,
                },
            ),
        );
        self.stamp = 0;
    }
    /// A new point: all memos become stale.
    #[inline]
    fn next(&mut self) {
        self.stamp += 1;
    }
}

impl Evaluator {
    /// An evaluator for `n × n` grids whose values are canvas distances × `scale`.
    pub fn new(n: usize, scale: f64) -> Self {
        Evaluator {
            n,
            scale,
            s: vec![],
            win: vec![],
            work: 0,
            prim_vals: vec![],
            widths: vec![],
            centre_vals: vec![],
            keep: vec![],
            stamp: vec![],
            used: vec![],
            chain1: vec![],
            chain2: vec![],
            ranges1: vec![],
            ranges2: vec![],
            gcache: GeomCache::default(),
            lane_channels: vec![],
        }
    }

    fn gather(&mut self, scene: &Scene, nodes: &[f64]) {
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
        self.gather(scene, nodes);
        self.gcache.start(scene.rec.shapes.len());
        let n = self.n;
        let nc = scene.channels.len();
        self.s.resize(nc * n * n, 0.0);
        if winners {
            self.win.resize(nc * n * n, NO_WIN);
        }
        let inv = 1.0 / n as f64;
        // Half diagonals (canvas units) of the two tile levels, a hair larger for rounding.
        let h1 = (T1 as f64 * inv) * std::f64::consts::FRAC_1_SQRT_2 * 1.000001;
        let h2 = (T2 as f64 * inv) * std::f64::consts::FRAC_1_SQRT_2 * 1.000001;
        let mut work = 0u64;
        self.centre_vals.resize(scene.items.len(), 0.0);
        self.stamp.resize(scene.items.len(), u32::MAX);
        let mut chain1 = std::mem::take(&mut self.chain1);
        let mut chain2 = std::mem::take(&mut self.chain2);
        let mut used = std::mem::take(&mut self.used);
        let mut tile_id = 0u32;
        for ty in 0..n.div_ceil(T1) {
            for tx in 0..n.div_ceil(T1) {
                let (x0, y0) = (tx * T1, ty * T1);
                let pc = [(x0 + T1 / 2) as f64 * inv, (y0 + T1 / 2) as f64 * inv];
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
                        &mut self.keep,
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
                // Level 2: small tiles, only the items level 1 kept.
                for sy in (y0..(y0 + T1).min(n)).step_by(T2) {
                    for sx in (x0..(x0 + T1).min(n)).step_by(T2) {
                        let pc = [(sx + T2 / 2) as f64 * inv, (sy + T2 / 2) as f64 * inv];
                        self.gcache.next();
                        for &it in &used {
                            let it_ = &scene.items[it as usize];
                            self.centre_vals[it as usize] = scene
                                .item_hit(it_, &self.prim_vals, &self.widths, pc, &mut self.gcache)
                                .0;
                        }
                        work += used.len() as u64;
                        chain2.clear();
                        self.ranges2.clear();
                        for (c, ch) in scene.channels.iter().enumerate() {
                            let (a, b) = self.ranges1[c];
                            let start = chain2.len();
                            cull(
                                &chain1[a..b],
                                ch.init,
                                &self.centre_vals,
                                h2,
                                &mut self.keep,
                                &mut chain2,
                            );
                            self.ranges2.push((start, chain2.len()));
                        }
                        let (xe, ye) = ((sx + T2).min(n), (sy + T2).min(n));
                        // Chains of plain filled circles only: a 4-lane kernel.
                        self.lane_channels.clear();
                        for (c, ch) in scene.channels.iter().enumerate() {
                            let (a, b) = self.ranges2[c];
                            let ops = &chain2[a..b];
                            let fast = ops
                                .iter()
                                .all(|&(_, it)| scene.items[it as usize].plain_circle);
                            self.lane_channels.push(fast);
                            if fast {
                                work += (ops.len() * (xe - sx) * (ye - sy)) as u64;
                                self.circle_lanes(
                                    scene,
                                    ch.init,
                                    ops,
                                    c,
                                    (sx, xe),
                                    (sy, ye),
                                    winners,
                                );
                            }
                        }
                        for y in sy..ye {
                            for x in sx..xe {
                                let p = [(x as f64 + 0.5) * inv, (y as f64 + 0.5) * inv];
                                self.gcache.next();
                                for (c, ch) in scene.channels.iter().enumerate() {
                                    if self.lane_channels[c] {
                                        continue;
                                    }
                                    let (a, b) = self.ranges2[c];
                                    let ops = &chain2[a..b];
                                    work += ops.len() as u64;
                                    let idx = c * n * n + y * n + x;
                                    self.pixel(scene, ch.init, ops, p, idx, winners);
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
        self.work = work;
    }

    /// [`Evaluator::pixel`] for a chain of plain filled circles (no stroke,
    /// no inset) over a block of at most 4 pixels per row: four independent
    /// lanes, so the square roots overlap (and vectorise).
    #[allow(clippy::too_many_arguments)]
    fn circle_lanes(
        &mut self,
        scene: &Scene,
        init: f64,
        ops: &[(CombineOp, u32)],
        c: usize,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
        winners: bool,
    ) {
        let n = self.n;
        let inv = 1.0 / n as f64;
        let cap = CAP;
        let mut px = [0.0; 4];
        for (k, v) in px.iter_mut().enumerate() {
            *v = ((x0 + k).min(x1 - 1) as f64 + 0.5) * inv;
        }
        for y in y0..y1 {
            let py = (y as f64 + 0.5) * inv;
            let mut b = [init * cap; 4];
            let mut wi = [NONE; 4];
            let mut flip = [false; 4];
            let mut i = 0;
            while i < ops.len() {
                let op = ops[i].0;
                let mut best = [f64::INFINITY; 4];
                let mut bi = [NONE; 4];
                while i < ops.len() && ops[i].0 == op {
                    let it = ops[i].1;
                    let f = &self.prim_vals[scene.items[it as usize].prim as usize];
                    let dy = py - f[1];
                    for k in 0..4 {
                        let dx = px[k] - f[0];
                        let v = (dx * dx + dy * dy).sqrt() - f[2];
                        if v < best[k] {
                            best[k] = v;
                            bi[k] = it;
                        }
                    }
                    i += 1;
                }
                for k in 0..4 {
                    match op {
                        CombineOp::Union => {
                            if best[k] < b[k] {
                                b[k] = best[k];
                                wi[k] = bi[k];
                                flip[k] = false;
                            }
                        }
                        CombineOp::Diff => {
                            if -best[k] > b[k] {
                                b[k] = -best[k];
                                wi[k] = bi[k];
                                flip[k] = true;
                            }
                        }
                    }
                }
            }
            for k in 0..x1 - x0 {
                let idx = c * n * n + y * n + x0 + k;
                let mut v = b[k];
                let mut w = wi[k];
                if v.abs() >= cap {
                    v = v.clamp(-cap, cap);
                    w = NONE;
                }
                self.s[idx] = v * self.scale;
                if winners {
                    self.win[idx] = if w == NONE {
                        NO_WIN
                    } else {
                        let item = &scene.items[w as usize];
                        Win {
                            prim: item.prim,
                            wnode: scene.rec.shapes[item.shape as usize].width,
                            psign: if flip[k] { -1.0 } else { 1.0 },
                            wcoef: 0.0,
                        }
                    };
                }
            }
        }
    }

    /// Apply a culled chain at one pixel; consecutive same-kind operations
    /// form a run whose minimum is applied once.
    #[inline]
    fn pixel(
        &mut self,
        scene: &Scene,
        init: f64,
        ops: &[(CombineOp, u32)],
        p: [f64; 2],
        idx: usize,
        winners: bool,
    ) {
        let cap = CAP;
        let mut b = init * cap;
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
                None => NO_WIN,
                Some((it, h, flip)) => {
                    let mut w = scene.win_of(&scene.items[it as usize], &h);
                    if flip {
                        w.psign = -w.psign;
                        w.wcoef = -w.wcoef;
                    }
                    w
                }
            };
        }
    }

    /// Chain rule from `ds` (dL/dS per channel-pixel, same layout as
    /// [`Evaluator::s`]) to the tape nodes: adds into `node_adj`.
    /// Needs the winners of the last [`Evaluator::eval`].
    pub fn backward(&self, scene: &Scene, ds: &[f64], node_adj: &mut [f64]) {
        let n = self.n;
        let inv = 1.0 / n as f64;
        let mut prim_adj = vec![[0.0f64; 6]; scene.rec.prims.len()];
        let mut g = [0.0; 6];
        for c in 0..scene.channels.len() {
            for y in 0..n {
                for x in 0..n {
                    let idx = c * n * n + y * n + x;
                    let a = ds[idx] * self.scale;
                    let w = self.win[idx];
                    if a == 0.0 || w.prim == NONE {
                        continue;
                    }
                    let p = [(x as f64 + 0.5) * inv, (y as f64 + 0.5) * inv];
                    let kind = scene.rec.prims[w.prim as usize].kind;
                    let f = &self.prim_vals[w.prim as usize];
                    let k = a * w.psign as f64;
                    let pa = &mut prim_adj[w.prim as usize];
                    if kind == PrimKind::Circle {
                        // Fast path of sdf::grad for the most common primitive.
                        let (dx, dy) = (p[0] - f[0], p[1] - f[1]);
                        let l2 = dx * dx + dy * dy;
                        if l2 > 0.0 {
                            let kl = k / l2.sqrt();
                            pa[0] -= kl * dx;
                            pa[1] -= kl * dy;
                        }
                        pa[2] -= k;
                    } else {
                        sdf::grad(kind, f, p, &mut g);
                        for j in 0..kind.field_count() {
                            pa[j] += k * g[j];
                        }
                    }
                    if w.wcoef != 0.0 {
                        node_adj[w.wnode as usize] += a * w.wcoef as f64;
                    }
                }
            }
        }
        for (p, pa) in scene.rec.prims.iter().zip(&prim_adj) {
            for j in 0..p.kind.field_count() {
                node_adj[p.fields[j] as usize] += pa[j];
            }
        }
    }

    /// The palette index at every pixel, by the fields: the colour whose
    /// field is most negative, or the background where none is.
    pub fn colour_indices(&self, scene: &Scene) -> Vec<u16> {
        let nn = self.n * self.n;
        (0..nn)
            .map(|i| {
                let mut best = (0.0, 0u16);
                for (c, ch) in scene.channels.iter().enumerate() {
                    let v = self.s[c * nn + i];
                    if v < best.0 {
                        best = (v, ch.colour);
                    }
                }
                best.1
            })
            .collect()
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
fn cull(
    chain: &[(CombineOp, u32)],
    init: f64,
    vals: &[f64],
    h: f64,
    keep: &mut Vec<bool>,
    out: &mut Vec<(CombineOp, u32)>,
) {
    keep.clear();
    let (mut suf_u, mut suf_d) = (f64::INFINITY, f64::INFINITY);
    for &(op, it) in chain.iter().rev() {
        let v = vals[it as usize];
        let suf = if op == CombineOp::Union {
            &mut suf_u
        } else {
            &mut suf_d
        };
        keep.push(v - h < *suf);
        *suf = suf.min(v + h);
    }
    keep.reverse();
    let (mut blo, mut bhi) = (init * CAP, init * CAP);
    let mut i = 0;
    while i < chain.len() {
        let op = chain[i].0;
        let mut j = i;
        let (mut m, mut ylo) = (f64::INFINITY, f64::INFINITY);
        while j < chain.len() && chain[j].0 == op {
            if keep[j] {
                let v = vals[chain[j].1 as usize];
                m = m.min(v + h);
                ylo = ylo.min(v - h);
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
                if keep[k] && vals[chain[k].1 as usize] - h <= m {
                    out.push(chain[k]);
                }
            }
            match op {
                CombineOp::Union => {
                    blo = blo.min(ylo);
                    bhi = bhi.min(m);
                }
                CombineOp::Diff => {
                    blo = blo.max(-m);
                    bhi = bhi.max(-ylo);
                }
            }
        }
        i = j;
    }
}

/// Which primitive kinds a scene uses (for reports).
pub fn prim_kinds(scene: &Scene) -> Vec<PrimKind> {
    let mut v: Vec<PrimKind> = vec![];
    for p in &scene.rec.prims {
        if !v.contains(&p.kind) {
            v.push(p.kind);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};

    fn scene(src: &str) -> Scene {
        let p = Program::parse(src).unwrap();
        Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap())
    }

    fn fields(sc: &Scene, n: usize) -> Evaluator {
        let mut e = Evaluator::new(n, 1.0);
        let mut nodes = vec![];
        sc.rec.tape.forward(&sc.rec.float_values(), &mut nodes);
        e.eval(sc, &nodes, true);
        e
    }

    fn at(e: &Evaluator, sc: &Scene, colour: [u8; 3], x: f64, y: f64) -> f64 {
        let c = sc
            .channels
            .iter()
            .position(|ch| sc.rec.colours[ch.colour as usize] == colour)
            .expect("channel");
        let n = e.n;
        let (i, j) = ((x * n as f64) as usize, (y * n as f64) as usize);
        e.s[c * n * n + j * n + i]
    }

    /// The paper's four cases on a hand-built scene: a red square (blue
    /// stroke) drawn over a wide blue disc, over a red disc.
    #[test]
    fn on_top_operator_four_cases() {
        let sc = scene(
            "circle(0.5, 0.5, 0.45, fill: \"#ff0000\");\n\
             circle(0.5, 0.5, 0.35, fill: \"#0000ff\");\n\
             rect(0.5, 0.5, 0.4, 0.4, fill: \"#ff0000\", stroke: \"#0000ff\", width: 0.04);\n\
             circle(0.5, 0.5, 0.05, fill: \"#00ff00\", stroke: \"#00ff00\", width: 0.02);",
        );
        let e = fields(&sc, 200);
        let (red, blue, green) = ([255, 0, 0], [0, 0, 255], [0, 255, 0]);
        // Case c = fill ≠ stroke (red): the rect's inset fill adds red inside ...
        assert!(at(&e, &sc, red, 0.35, 0.5) < 0.0);
        // ... case c = stroke ≠ fill (blue): its stroke ring is blue ...
        assert!(at(&e, &sc, blue, 0.3, 0.5) < 0.0);
        assert!(at(&e, &sc, red, 0.3, 0.5) > 0.0);
        // ... and the stroke removes blue from the inside (fill is not blue).
        assert!(at(&e, &sc, blue, 0.4, 0.5) > 0.0);
        // Case c ≠ stroke, c ≠ fill: the green dot removes red and blue.
        assert!(at(&e, &sc, red, 0.5, 0.5) > 0.0 && at(&e, &sc, blue, 0.5, 0.5) > 0.0);
        // Case c = stroke = fill: the green dot (with its stroke) is green out to r + w/2.
        // At the pixel centre (0.5025, 0.5025): union(S, F) = F = d + w/2.
        let g = at(&e, &sc, green, 0.5, 0.5);
        let d = 0.0025 * 2f64.sqrt() - 0.05;
        assert!((g - (d + 0.01)).abs() < 1e-9, "{g}");
        assert!(at(&e, &sc, green, 0.5, 0.555) < 0.0 && at(&e, &sc, green, 0.5, 0.565) > 0.0);
        // Outside the square but inside the blue disc: blue; red disc ring outside: red.
        assert!(at(&e, &sc, blue, 0.5, 0.18) < 0.0);
        assert!(at(&e, &sc, red, 0.5, 0.1) < 0.0);
        assert!(at(&e, &sc, blue, 0.5, 0.1) > 0.0);
    }

    /// Culling never changes a value: compare with a brute-force evaluation
    /// that applies every operation at every pixel.
    #[test]
    fn culled_fields_equal_brute_force() {
        // Plain filled circles in two colours drawn over each other: the
        // 4-lane circle kernel, with unions and differences.
        check_brute_force(
            "for i in 0..7 { for j in 0..7 { circle(0.05 + i * 0.15, 0.07 + j * 0.14, 0.06, fill: \"#aa0000\"); } }\n\
             for k in 0..9 { circle(0.1 + k * 0.1, 0.5 + 0.3 * sin(k), 0.08, fill: \"#0000aa\"); }",
            61,
        );
        check_brute_force(SCENE, 61);
    }

    const SCENE: &str = "for i in 0..6 { for j in 0..6 { circle(0.1 + i * 0.16, 0.1 + j * 0.16, 0.05, fill: \"#112233\"); } }\n\
             for k in 0..5 { segment(0, k * 0.2 + 0.05, 1, k * 0.2 + 0.1, stroke: \"#aa0000\", width: 0.02); }\n\
             path(fill: \"#00aa00\", stroke: \"#112233\", width: 0.01) { move(0.2, 0.2); quad(0.5, 0.0, 0.8, 0.2); line(0.5, 0.8); close(); }\n\
             difference(fill: \"#ffffff\") { rect(0.7, 0.7, 0.2, 0.2, radius: 0.03, rotation: 0.3); circle(0.7, 0.7, 0.05); }";

    fn check_brute_force(src: &str, n: usize) {
        let sc = scene(src);
        let e = fields(&sc, n);
        let mut nodes = vec![];
        sc.rec.tape.forward(&sc.rec.float_values(), &mut nodes);
        let mut g = Evaluator::new(n, 1.0);
        g.gather(&sc, &nodes);
        for (c, ch) in sc.channels.iter().enumerate() {
            for y in 0..n {
                for x in 0..n {
                    let p = [(x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64];
                    let mut b = ch.init * CAP;
                    for &(op, it) in &ch.ops {
                        let v = sc
                            .item(&sc.items[it as usize], &g.prim_vals, &g.widths, p)
                            .0;
                        b = match op {
                            CombineOp::Union => b.min(v),
                            CombineOp::Diff => b.max(-v),
                        };
                    }
                    let want = b.clamp(-CAP, CAP);
                    let got = e.s[c * n * n + y * n + x];
                    // The winner record explains the value exactly.
                    let w = e.win[c * n * n + y * n + x];
                    if w.prim != NONE {
                        let prim = &sc.rec.prims[w.prim as usize];
                        let pv = sdf::value(prim.kind, &g.prim_vals[w.prim as usize], p);
                        let implied =
                            w.psign as f64 * pv + w.wcoef as f64 * nodes[w.wnode as usize].max(0.0);
                        assert!(
                            (implied - got).abs() < 1e-9,
                            "winner at ({x},{y}) implies {implied}, value {got}"
                        );
                    } else {
                        assert_eq!(got.abs(), CAP);
                    }
                    assert!(
                        (got - want).abs() < 1e-12,
                        "channel {c} pixel ({x},{y}): {got} vs {want}"
                    );
                }
            }
        }
        assert!(
            e.work < (sc.items.len() * n * n * sc.channels.len()) as u64 / 2,
            "culling saved little: {}",
            e.work
        );
    }
}

//! Scene compilation: a recording becomes per-colour lists of operations
//! (the paper's "on top" operator) over fill and stroke items, plus the
//! geometry of each item at a point (paths with winding, booleans).
use super::{CombineOp, Hit, Win, NONE, NO_CODE, NO_WIN};
use crate::pattern::record::{BoolOp, Geom, Recording};
use crate::pattern::sdf::{self, Fields, PrimKind};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    Fill,
    Stroke,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Item {
    pub(super) shape: u32,
    pub(super) part: Part,
    /// Whether the shape also has a stroke (then the fill is inset).
    pub(super) inset: bool,
    /// The primitive when the geometry is a single one (fast path), else `NONE`.
    pub(super) prim: u32,
    pub(super) kind: PrimKind,
    /// A single circle, point or segment: eligible for the 4-lane kernel.
    pub(super) lanes: bool,
}

/// One colour's operation list.
#[derive(Debug, Clone)]
pub struct Channel {
    /// Palette index of the colour.
    pub colour: u16,
    /// `+1` for ordinary colours (start empty), `−1` for the background (start full).
    pub init: f64,
    /// Operations in drawing order: (op, item id).
    pub(super) ops: Vec<(CombineOp, u32)>,
}

/// A recorded pattern prepared for field evaluation.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The recording (tape, shapes, palette).
    pub rec: Recording,
    /// One channel per colour used by a shape (the background only if a shape uses it).
    pub channels: Vec<Channel>,
    pub(super) items: Vec<Item>,
    /// Mean relative cost of an item evaluation (a circle is 1).
    pub(crate) cost: f64,
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
                    lanes: prim != NONE && kind != PrimKind::Rect && kind != PrimKind::Quad,
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
                    lanes: prim != NONE && kind != PrimKind::Rect && kind != PrimKind::Quad,
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
        let cost = if items.is_empty() {
            1.0
        } else {
            items
                .iter()
                .map(|it| geom_cost(&rec, &rec.shapes[it.shape as usize].geom))
                .sum::<f64>()
                / items.len() as f64
        };
        Scene {
            rec,
            channels,
            items,
            cost,
        }
    }

    /// Number of shapes.
    pub fn shape_count(&self) -> usize {
        self.rec.shapes.len()
    }

    /// Whether every value the shapes read (primitive fields, stroke widths)
    /// is finite in `nodes` (a replay of the tape). Recording guarantees it
    /// for the record-time values; other parameter values can still divide
    /// by zero on the tape, and such a point has no field.
    pub fn shapes_finite(&self, nodes: &[f64]) -> bool {
        self.rec.prims.iter().all(|p| {
            p.fields[..p.kind.field_count()]
                .iter()
                .all(|&i| nodes[i as usize].is_finite())
        }) && self
            .rec
            .shapes
            .iter()
            .all(|s| nodes[s.width as usize].is_finite())
    }

    pub(super) fn geom(&self, g: &Geom, pv: &[Fields], p: [f64; 2]) -> Hit {
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
                        // The control points' box contains the curve: when it is
                        // already farther than the best piece, skip the cubic solve.
                        let bx = (f[0].min(f[2]).min(f[4]) - p[0])
                            .max(p[0] - f[0].max(f[2]).max(f[4]))
                            .max(0.0);
                        let by = (f[1].min(f[3]).min(f[5]) - p[1])
                            .max(p[1] - f[1].max(f[3]).max(f[5]))
                            .max(0.0);
                        if bx * bx + by * by >= best_d2 {
                            continue;
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
    pub(super) fn geom_cached(
        &self,
        shape: u32,
        pv: &[Fields],
        p: [f64; 2],
        cache: &mut GeomCache,
    ) -> Hit {
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
    pub(super) fn item_hit(
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
    pub(super) fn win_of(&self, it: &Item, h: &Hit) -> Win {
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

    /// The winner record of a [`super::win_code`].
    pub(super) fn decode_win(&self, code: u64) -> Win {
        if code == NO_CODE {
            return NO_WIN;
        }
        let item = &self.items[(code >> 4 & 0x0fff_ffff) as usize];
        let h = Hit {
            d: if code & 2 != 0 { -1.0 } else { 1.0 },
            prim: (code >> 32) as u32,
            sign: if code & 4 != 0 { -1.0 } else { 1.0 },
        };
        let mut w = self.win_of(item, &h);
        if code & 1 != 0 {
            w.psign = -w.psign;
            w.wcoef = -w.wcoef;
        }
        w
    }

    /// Item value with its winner record (used by tests).
    #[cfg(test)]
    pub(super) fn item(&self, it: &Item, pv: &[Fields], widths: &[f64], p: [f64; 2]) -> (f64, Win) {
        let mut cache = GeomCache::default();
        cache.start(self.rec.shapes.len());
        let (v, h) = self.item_hit(it, pv, widths, p, &mut cache);
        (v, self.win_of(it, &h))
    }
}

/// Per-point memo of shape geometries (fill and stroke items share one).
#[derive(Debug, Clone, Default)]
pub(super) struct GeomCache {
    pub(super) stamp: u32,
    pub(super) slots: Vec<(u32, Hit)>,
}

impl GeomCache {
    pub(super) fn start(&mut self, shapes: usize) {
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
    pub(super) fn next(&mut self) {
        self.stamp += 1;
    }
}

/// Relative cost of evaluating a geometry (circle = 1), measured roughly:
/// a quadratic piece solves a cubic (~10), a rectangle rotates (~3).
fn geom_cost(rec: &Recording, g: &Geom) -> f64 {
    let prim = |i: u32| match rec.prims[i as usize].kind {
        PrimKind::Quad => 10.0,
        PrimKind::Rect => 3.0,
        _ => 1.0,
    };
    match g {
        Geom::Prim(i) => prim(*i),
        Geom::Path { first, len, .. } => (*first..first + len).map(prim).sum(),
        Geom::Bool(_, ch) => ch.iter().map(|c| geom_cost(rec, c)).sum(),
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

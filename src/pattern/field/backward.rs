//! The backward pass: from field adjoints (dL/dS per channel-pixel) to the
//! tape nodes, through the winner of every pixel.
//!
//! A row is walked in runs of pixels with the same winner code, whose
//! record is made once per run. Within a run,
//! circles and segments are taken four pixels at a time ([`f64x4`]) into
//! four partial sums per field, added to the primitive's adjoints at the
//! run's end.
use super::scene::Scene;
use super::tiles::Evaluator;
use super::{Win, NO_CODE};
use crate::pattern::sdf::{self, Fields, PrimKind};
use wide::{f64x4, CmpGt, CmpLt, CmpNe};

impl Evaluator {
    /// Chain rule from `ds` (dL/dS per channel-pixel, same layout as
    /// [`Evaluator::s`]) to the tape nodes: adds into `node_adj`.
    /// Needs the winners of the last [`Evaluator::eval`].
    pub fn backward(&self, scene: &Scene, ds: &[f64], node_adj: &mut [f64]) {
        let (gw, gh, nn) = (self.grid.w, self.grid.h, self.grid.len());
        let mut prim_adj = vec![[0.0f64; 6]; scene.rec.prims.len()];
        for c in 0..scene.channels.len() {
            for y in 0..gh {
                let row = c * nn + y * gw;
                let (wins, dsr) = (&self.win[row..row + gw], &ds[row..row + gw]);
                let mut x = 0;
                while x < gw {
                    let code = wins[x];
                    let mut e = x + 1;
                    while e < gw && wins[e] == code {
                        e += 1;
                    }
                    if code != NO_CODE {
                        let w = scene.decode_win(code);
                        let run = Run {
                            w,
                            xs: &self.centres_x[x..e],
                            py: self.centres_y[y],
                            ds: &dsr[x..e],
                        };
                        self.backward_run(scene, &run, &mut prim_adj[w.prim as usize], node_adj);
                    }
                    x = e;
                }
            }
        }
        for (p, pa) in scene.rec.prims.iter().zip(&prim_adj) {
            for j in 0..p.kind.field_count() {
                node_adj[p.fields[j] as usize] += pa[j];
            }
        }
    }

    /// One run of pixels of a row with the same winner: adds the
    /// primitive's field adjoints into `pa` and the stroke width's into
    /// `node_adj`.
    fn backward_run(&self, scene: &Scene, run: &Run, pa: &mut Fields, node_adj: &mut [f64]) {
        let w = run.w;
        let kind = scene.rec.prims[w.prim as usize].kind;
        let f = &self.prim_vals[w.prim as usize];
        let (scale, sign) = (f64x4::splat(self.scale), f64x4::splat(w.psign as f64));
        let zero = f64x4::ZERO;
        match kind {
            PrimKind::Circle => {
                let cx = f64x4::splat(f[0]);
                let dy = f64x4::splat(run.py - f[1]);
                let mut acc = [zero; 3];
                for_lanes(run, |px, d| {
                    let a = d * scale;
                    let k = a * sign;
                    let dx = px - cx;
                    let l2 = dx * dx + dy * dy;
                    let on = a.cmp_ne(zero);
                    let ok = on & l2.cmp_gt(zero);
                    let kl = ok.blend(k / l2.sqrt(), zero);
                    acc[0] -= kl * dx;
                    acc[1] -= kl * dy;
                    acc[2] -= on.blend(k, zero);
                });
                for j in 0..3 {
                    pa[j] += sum(acc[j]);
                }
            }
            PrimKind::Segment => {
                let (ax, ay) = (f[0], f[1]);
                let (bx, by) = (f[2] - ax, f[3] - ay);
                let len2 = bx * bx + by * by;
                let (ax4, bx4, by4) = (f64x4::splat(ax), f64x4::splat(bx), f64x4::splat(by));
                let py = f64x4::splat(run.py);
                let ty = (py - f64x4::splat(ay)) * by4;
                let il2 = f64x4::splat(if len2 > 0.0 { 1.0 / len2 } else { 0.0 });
                let dy0 = py - f64x4::splat(ay);
                let mut acc = [zero; 4];
                for_lanes(run, |px, d| {
                    let a = d * scale;
                    let k = a * sign;
                    let t = clamp01(((px - ax4) * bx4 + ty) * il2);
                    let dx = px - (ax4 + t * bx4);
                    let dy = dy0 - t * by4;
                    let l2 = dx * dx + dy * dy;
                    let ok = a.cmp_ne(zero) & l2.cmp_gt(zero);
                    let kl = ok.blend(k / l2.sqrt(), zero);
                    let (u, v) = ((f64x4::ONE - t) * kl, t * kl);
                    acc[0] -= u * dx;
                    acc[1] -= u * dy;
                    acc[2] -= v * dx;
                    acc[3] -= v * dy;
                });
                for j in 0..4 {
                    pa[j] += sum(acc[j]);
                }
            }
            _ => {
                let mut g = [0.0; 6];
                for (&px, &d) in run.xs.iter().zip(run.ds) {
                    let a = d * self.scale;
                    if a == 0.0 {
                        continue;
                    }
                    let k = a * w.psign as f64;
                    sdf::grad(kind, f, [px, run.py], &mut g);
                    for j in 0..kind.field_count() {
                        pa[j] += k * g[j];
                    }
                }
            }
        }
        if w.wcoef != 0.0 {
            let s: f64 = run.ds.iter().sum();
            node_adj[w.wnode as usize] += s * self.scale * w.wcoef as f64;
        }
    }
}

/// A run of pixels of one row with the same winner `w`: their centres'
/// x (`xs`), the row's centre y and their adjoints `ds`.
struct Run<'a> {
    w: Win,
    xs: &'a [f64],
    py: f64,
    ds: &'a [f64],
}

/// The sum of the lanes, in a fixed order.
#[inline(always)]
fn sum(v: f64x4) -> f64 {
    let a = v.to_array();
    (a[0] + a[1]) + (a[2] + a[3])
}

/// Calls `f(px, ds)` on the run four pixels at a time; the last call's
/// unused lanes have adjoint 0 (which adds nothing).
#[inline(always)]
fn for_lanes(run: &Run, mut f: impl FnMut(f64x4, f64x4)) {
    let mut xs = run.xs.chunks_exact(4);
    let mut ds = run.ds.chunks_exact(4);
    for (x, d) in (&mut xs).zip(&mut ds) {
        f(lanes(x), lanes(d));
    }
    let (x, d) = (xs.remainder(), ds.remainder());
    if !x.is_empty() {
        f(lanes(x), lanes(d));
    }
}

/// `t.clamp(0.0, 1.0)` lane by lane.
#[inline(always)]
fn clamp01(t: f64x4) -> f64x4 {
    let t = t.cmp_lt(f64x4::ZERO).blend(f64x4::ZERO, t);
    t.cmp_gt(f64x4::ONE).blend(f64x4::ONE, t)
}

/// Up to four values as lanes (zeros after them).
#[inline(always)]
fn lanes(v: &[f64]) -> f64x4 {
    let mut a = [0.0; 4];
    a[..v.len()].copy_from_slice(v);
    f64x4::from(a)
}

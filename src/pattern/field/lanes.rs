//! The lane kernel: a chain made only of single circles, points and
//! segments is evaluated for a whole small tile (`T2 × T2` pixels) at once,
//! item by item, so the square roots overlap (and vectorise) and each
//! item's set-up is paid once per tile, not once per row.
use super::scene::{Item, Part, Scene};
use super::tiles::Evaluator;
use super::{lesser, CombineOp, CAP, NO_CODE, T2};
use crate::pattern::sdf::{self, PrimKind};

impl Evaluator {
    /// [`Evaluator::pixel`] for a chain of single-primitive circle, point and
    /// segment items (fills, inset fills, strokes) over a block of at most
    /// `T2 × T2` pixels: independent lanes, so the square roots overlap
    /// (and vectorise). With `W`, the winners too; without, no winner
    /// bookkeeping at all.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn lanes<const W: bool>(
        &mut self,
        scene: &Scene,
        init: f64,
        ops: &[(CombineOp, u32)],
        c: usize,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
        (px, py, caps): (&[f64; T2 * T2], &[f64; T2 * T2], &[f64; T2 * T2]),
    ) {
        const L: usize = T2 * T2;
        debug_assert!(x1 - x0 <= T2 && y1 - y0 <= T2);
        let (gw, nn) = (self.grid.w, self.grid.len());
        {
            let mut b = [init * CAP; L];
            // Winners as 64-bit codes beside the values, so that the
            // selects below vectorise ([`super::win_code`]; the sign of a
            // single primitive is +1); all ones: none.
            let mut wi = [u64::MAX; L];
            let mut i = 0;
            while i < ops.len() {
                let op = ops[i].0;
                let mut best = [f64::INFINITY; L];
                let mut bi = [u64::MAX; L];
                while i < ops.len() && ops[i].0 == op {
                    let it = ops[i].1;
                    let item = &scene.items[it as usize];
                    let base = (item.prim as u64) << 32 | (it as u64) << 4;
                    let d = self.lane_distances(item, px, py);
                    let vs = self.lane_values(item, &d);
                    // Selects, not branches, and no `min` (its choice
                    // between ±0 is not specified): the first smallest wins.
                    for k in 0..L {
                        let m = vs[k] < best[k];
                        best[k] = if m { vs[k] } else { best[k] };
                        if W {
                            let below = (d[k] < 0.0) | d[k].is_nan();
                            let code = base | (below as u64) << 1;
                            bi[k] = if m { code } else { bi[k] };
                        }
                    }
                    i += 1;
                }
                // A union takes the run's value where it is below B, a
                // difference its negation where that is above B (selects).
                let diff = op == CombineOp::Diff;
                for k in 0..L {
                    if !W {
                        b[k] = match op {
                            CombineOp::Union if best[k] < b[k] => best[k],
                            CombineOp::Diff if -best[k] > b[k] => -best[k],
                            _ => b[k],
                        };
                        continue;
                    }
                    let v = if diff { -best[k] } else { best[k] };
                    let m = if diff { v > b[k] } else { v < b[k] };
                    b[k] = if m { v } else { b[k] };
                    wi[k] = if m { bi[k] | diff as u64 } else { wi[k] };
                }
            }
            let (bw, bh) = (x1 - x0, y1 - y0);
            for j in 0..bh {
                let row = c * nn + (y0 + j) * gw + x0;
                let out = &mut self.s[row..row + bw];
                for (i, o) in out.iter_mut().enumerate() {
                    let k = j * T2 + i;
                    let idx = row + i;
                    let mut v = b[k];
                    let cap = caps[k];
                    let clamped = v.abs() >= cap;
                    if clamped {
                        v = v.clamp(-cap, cap);
                    }
                    *o = v * self.scale;
                    if W {
                        self.win[idx] = if clamped { NO_CODE } else { wi[k] };
                    }
                }
            }
        }
    }

    /// The distances of a lane item's primitive (circle, point or
    /// segment) at `N` points: the same operations as
    /// [`Scene::item_hit`], so the same bits.
    #[inline(always)]
    pub(super) fn lane_distances<const N: usize>(
        &self,
        item: &Item,
        px: &[f64; N],
        py: &[f64; N],
    ) -> [f64; N] {
        let f = &self.prim_vals[item.prim as usize];
        let mut d = [0.0f64; N];
        match item.kind {
            PrimKind::Circle | PrimKind::Point => {
                let r = if item.kind == PrimKind::Circle {
                    f[2]
                } else {
                    0.0
                };
                for k in 0..N {
                    let dx = px[k] - f[0];
                    let dy = py[k] - f[1];
                    d[k] = (dx * dx + dy * dy).sqrt() - r;
                }
            }
            _ => {
                for k in 0..N {
                    d[k] = sdf::segment_distance(f, [px[k], py[k]]);
                }
            }
        }
        d
    }

    /// A lane item's values from its primitive's distances `d` (fill,
    /// inset fill or stroke), as [`Scene::item_hit`] makes them.
    #[inline(always)]
    pub(super) fn lane_values<const N: usize>(&self, item: &Item, d: &[f64; N]) -> [f64; N] {
        let hw = 0.5 * self.widths[item.shape as usize];
        let mut vs = *d;
        match item.part {
            Part::Fill if item.inset => vs.iter_mut().for_each(|v| *v += hw),
            Part::Fill => {}
            Part::Stroke => vs.iter_mut().for_each(|v| *v = v.abs() - hw),
        }
        vs
    }

    /// The pixel centres of a block for [`Evaluator::lanes`], and the
    /// bounds its values are clamped to (`CAP` and the distance to the
    /// canvas edge, [`super::edge_cap`]): lane `k` is pixel
    /// `(x0 + k % T2, y0 + k / T2)`, the block's last column (row)
    /// repeated past its end.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    pub(super) fn lane_centres(
        &self,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
    ) -> ([f64; T2 * T2], [f64; T2 * T2], [f64; T2 * T2]) {
        let mut cx = [0.0; T2];
        let mut cy = [0.0; T2];
        let mut ex = [0.0; T2];
        let mut ey = [0.0; T2];
        for i in 0..T2 {
            let (x, y) = ((x0 + i).min(x1 - 1), (y0 + i).min(y1 - 1));
            cx[i] = self.centres_x[x];
            cy[i] = self.centres_y[y];
            // (Edge values are never NaN.)
            ex[i] = lesser(CAP, self.edge_x[x]);
            ey[i] = self.edge_y[y];
        }
        let mut px = [0.0; T2 * T2];
        let mut py = [0.0; T2 * T2];
        let mut caps = [0.0; T2 * T2];
        for k in 0..T2 * T2 {
            px[k] = cx[k % T2];
            py[k] = cy[k / T2];
            caps[k] = lesser(ex[k % T2], ey[k / T2]);
        }
        (px, py, caps)
    }
}

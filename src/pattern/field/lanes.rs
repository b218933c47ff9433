//! The 4-lane kernel: a chain made only of single circles, points and
//! segments is evaluated for four pixels of a row at once, so the square
//! roots overlap (and vectorise).
use super::scene::{Part, Scene};
use super::tiles::Evaluator;
use super::{CombineOp, Hit, CAP, NONE, NO_WIN};
use crate::pattern::sdf::{self, PrimKind};

impl Evaluator {
    /// [`Evaluator::pixel`] for a chain of single-primitive circle, point and
    /// segment items (fills, inset fills, strokes) over a block of at most 4
    /// pixels per row: four independent lanes, so the square roots overlap
    /// (and vectorise). With `W`, the winners too; without, no winner
    /// bookkeeping at all.
    pub(super) fn lanes<const W: bool>(
        &mut self,
        scene: &Scene,
        init: f64,
        ops: &[(CombineOp, u32)],
        c: usize,
        (x0, x1): (usize, usize),
        (y0, y1): (usize, usize),
    ) {
        let n = self.n;
        let inv = 1.0 / n as f64;
        let mut px = [0.0; 4];
        for (k, v) in px.iter_mut().enumerate() {
            *v = ((x0 + k).min(x1 - 1) as f64 + 0.5) * inv;
        }
        for y in y0..y1 {
            let py = (y as f64 + 0.5) * inv;
            let mut b = [init * CAP; 4];
            let mut wi = [NONE; 4];
            let mut wd = [0.0f64; 4];
            let mut flip = [false; 4];
            let mut i = 0;
            while i < ops.len() {
                let op = ops[i].0;
                let mut best = [f64::INFINITY; 4];
                let mut bi = [NONE; 4];
                let mut bd = [0.0f64; 4];
                while i < ops.len() && ops[i].0 == op {
                    let it = ops[i].1;
                    let item = &scene.items[it as usize];
                    let f = &self.prim_vals[item.prim as usize];
                    let mut d = [0.0f64; 4];
                    match item.kind {
                        PrimKind::Circle | PrimKind::Point => {
                            let r = if item.kind == PrimKind::Circle {
                                f[2]
                            } else {
                                0.0
                            };
                            let dy = py - f[1];
                            for k in 0..4 {
                                let dx = px[k] - f[0];
                                d[k] = (dx * dx + dy * dy).sqrt() - r;
                            }
                        }
                        _ => {
                            for k in 0..4 {
                                d[k] = sdf::segment_distance(f, [px[k], py]);
                            }
                        }
                    }
                    let hw = 0.5 * self.widths[item.shape as usize];
                    let mut vs = d;
                    match item.part {
                        Part::Fill if item.inset => vs.iter_mut().for_each(|v| *v += hw),
                        Part::Fill => {}
                        Part::Stroke => vs.iter_mut().for_each(|v| *v = v.abs() - hw),
                    }
                    for k in 0..4 {
                        let v = vs[k];
                        if W {
                            if v < best[k] {
                                best[k] = v;
                                bi[k] = it;
                                bd[k] = d[k];
                            }
                        } else {
                            // Selects, exactly the branch above (no `min`:
                            // its choice between ±0 is not specified).
                            best[k] = if v < best[k] { v } else { best[k] };
                        }
                    }
                    i += 1;
                }
                for k in 0..4 {
                    if !W {
                        // The branches below as selects.
                        b[k] = match op {
                            CombineOp::Union if best[k] < b[k] => best[k],
                            CombineOp::Diff if -best[k] > b[k] => -best[k],
                            _ => b[k],
                        };
                        continue;
                    }
                    match op {
                        CombineOp::Union => {
                            if best[k] < b[k] {
                                b[k] = best[k];
                                wi[k] = bi[k];
                                wd[k] = bd[k];
                                flip[k] = false;
                            }
                        }
                        CombineOp::Diff => {
                            if -best[k] > b[k] {
                                b[k] = -best[k];
                                wi[k] = bi[k];
                                wd[k] = bd[k];
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
                let cap = CAP.min(self.edge[x0 + k].min(self.edge[y]));
                if v.abs() >= cap {
                    v = v.clamp(-cap, cap);
                    w = NONE;
                }
                self.s[idx] = v * self.scale;
                if W {
                    self.win[idx] = if w == NONE {
                        NO_WIN
                    } else {
                        let item = &scene.items[w as usize];
                        let h = Hit {
                            d: wd[k],
                            prim: item.prim,
                            sign: 1.0,
                        };
                        let mut rec = scene.win_of(item, &h);
                        if flip[k] {
                            rec.psign = -rec.psign;
                            rec.wcoef = -rec.wcoef;
                        }
                        rec
                    };
                }
            }
        }
    }
}

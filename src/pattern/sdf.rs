//! Exact distance functions of the primitives and their derivatives with
//! respect to the primitive's fields (paper §4 "Pattern Distance Fields":
//! circles, rectangles and segments after Quílez, quadratic Bézier curves
//! after Sforza et al.; cubics are converted to quadratics).
//!
//! Every primitive has up to [`MAX_FIELDS`] scalar fields. Circles and
//! rounded rectangles are signed (negative inside); points, segments and
//! Bézier pieces are unsigned distances to a zero-area set (paths get their
//! sign from the winding number, see [`winding`]). The derivative of a
//! distance with respect to the fields follows from the envelope theorem:
//! for `d = |p − q(θ)|` with `q` the closest point, `∂d/∂θ = −n·∂q/∂θ` at the
//! fixed closest parameter, `n = (p − q)/d`.

/// Largest number of fields a primitive has.
pub const MAX_FIELDS: usize = 6;
/// The fields of one primitive.
pub type Fields = [f64; MAX_FIELDS];

/// Primitive kinds. Field layouts:
/// - `Point`: `[x, y]`
/// - `Segment`: `[ax, ay, bx, by]`
/// - `Circle`: `[cx, cy, r]`
/// - `Rect`: `[cx, cy, half_width, half_height, corner_radius, angle]`
///   (angle in radians, counter-clockwise in canvas coordinates)
/// - `Quad`: `[x0, y0, x1, y1, x2, y2]` (start, control, end)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PrimKind {
    Point,
    Segment,
    Circle,
    Rect,
    Quad,
}

impl PrimKind {
    /// How many of the fields are used.
    pub fn field_count(self) -> usize {
        match self {
            PrimKind::Point => 2,
            PrimKind::Segment => 4,
            PrimKind::Circle => 3,
            PrimKind::Rect | PrimKind::Quad => 6,
        }
    }
    /// Whether the distance is signed (has an inside).
    pub fn signed(self) -> bool {
        matches!(self, PrimKind::Circle | PrimKind::Rect)
    }
}

type V2 = [f64; 2];

fn len(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// Distance from `p` to the segment `[ax, ay, bx, by]`.
#[inline(always)]
pub fn segment_distance(f: &Fields, p: V2) -> f64 {
    let (t, _) = segment_t(f, p);
    len(
        p[0] - (f[0] + t * (f[2] - f[0])),
        p[1] - (f[1] + t * (f[3] - f[1])),
    )
}

/// The distance of `p` to the primitive (signed for circles and rectangles).
#[inline]
pub fn value(kind: PrimKind, f: &Fields, p: V2) -> f64 {
    match kind {
        PrimKind::Point => len(p[0] - f[0], p[1] - f[1]),
        PrimKind::Circle => len(p[0] - f[0], p[1] - f[1]) - f[2],
        PrimKind::Segment => {
            let (t, _) = segment_t(f, p);
            len(
                p[0] - (f[0] + t * (f[2] - f[0])),
                p[1] - (f[1] + t * (f[3] - f[1])),
            )
        }
        PrimKind::Rect => rect(f, p, None),
        PrimKind::Quad => quad_closest(f, p).1,
    }
}

/// The distance and its derivatives with respect to the fields (`out`,
/// entries beyond [`PrimKind::field_count`] are zero).
pub fn grad(kind: PrimKind, f: &Fields, p: V2, out: &mut Fields) -> f64 {
    *out = [0.0; MAX_FIELDS];
    match kind {
        PrimKind::Point | PrimKind::Circle => {
            let (dx, dy) = (p[0] - f[0], p[1] - f[1]);
            let l = len(dx, dy);
            if l > 0.0 {
                out[0] = -dx / l;
                out[1] = -dy / l;
            }
            if kind == PrimKind::Circle {
                out[2] = -1.0;
                l - f[2]
            } else {
                l
            }
        }
        PrimKind::Segment => {
            let (t, _) = segment_t(f, p);
            let q = [f[0] + t * (f[2] - f[0]), f[1] + t * (f[3] - f[1])];
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            let l = len(dx, dy);
            if l > 0.0 {
                let n = [dx / l, dy / l];
                out[0] = -(1.0 - t) * n[0];
                out[1] = -(1.0 - t) * n[1];
                out[2] = -t * n[0];
                out[3] = -t * n[1];
            }
            l
        }
        PrimKind::Rect => rect(f, p, Some(out)),
        PrimKind::Quad => {
            let (t, d) = quad_closest(f, p);
            if d > 0.0 {
                let q = quad_point(f, t);
                let n = [(p[0] - q[0]) / d, (p[1] - q[1]) / d];
                let w = [(1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t];
                for k in 0..3 {
                    out[2 * k] = -w[k] * n[0];
                    out[2 * k + 1] = -w[k] * n[1];
                }
            }
            d
        }
    }
}

/// Closest-point parameter on a segment, clamped to `[0, 1]`.
#[inline(always)]
fn segment_t(f: &Fields, p: V2) -> (f64, f64) {
    let (bx, by) = (f[2] - f[0], f[3] - f[1]);
    let l2 = bx * bx + by * by;
    if l2 <= 0.0 {
        return (0.0, 0.0);
    }
    let t = (((p[0] - f[0]) * bx + (p[1] - f[1]) * by) / l2).clamp(0.0, 1.0);
    (t, l2)
}

/// Rounded rectangle, optionally with field derivatives.
#[inline(never)]
fn rect(f: &Fields, p: V2, out: Option<&mut Fields>) -> f64 {
    let (c, s) = (f[5].cos(), f[5].sin());
    let (vx, vy) = (p[0] - f[0], p[1] - f[1]);
    // Local coordinates: rotate by −angle.
    let lx = c * vx + s * vy;
    let ly = -s * vx + c * vy;
    let (hw, hh) = (f[2], f[3]);
    let rmax = hw.min(hh).max(0.0);
    let r = f[4].clamp(0.0, rmax);
    let qx = lx.abs() - hw + r;
    let qy = ly.abs() - hh + r;
    let (ox, oy) = (qx.max(0.0), qy.max(0.0));
    let ol = len(ox, oy);
    let d = ol + qx.max(qy).min(0.0) - r;
    if let Some(out) = out {
        let (gx, gy) = if ol > 0.0 {
            (ox / ol, oy / ol)
        } else if qx > qy {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        out[2] = -gx;
        out[3] = -gy;
        let dr = gx + gy - 1.0;
        if f[4] >= 0.0 && f[4] <= rmax {
            out[4] = dr;
        } else if f[4] > rmax {
            // The radius is clamped to the smaller half side: it moves with it.
            if hw <= hh {
                out[2] += dr;
            } else {
                out[3] += dr;
            }
        }
        let glx = gx * lx.signum();
        let gly = gy * ly.signum();
        out[0] = -(c * glx - s * gly);
        out[1] = -(s * glx + c * gly);
        out[5] = glx * ly - gly * lx;
    }
    d
}

/// Point of a quadratic Bézier at `t`.
pub fn quad_point(f: &Fields, t: f64) -> V2 {
    let u = 1.0 - t;
    [
        u * u * f[0] + 2.0 * u * t * f[2] + t * t * f[4],
        u * u * f[1] + 2.0 * u * t * f[3] + t * t * f[5],
    ]
}

/// Closest point on a quadratic Bézier: `(t, distance)`.
///
/// Stationary points of `|B(t) − p|²` are the roots of the cubic
/// `(B·B) t³ + 3(A·B) t² + (2A·A + m·B) t + m·A` with `A = p1 − p0`,
/// `B = p0 − 2p1 + p2`, `m = p0 − p`. The closed-form roots (Cardano, or the
/// trigonometric form for three real roots) are polished by Newton steps and
/// compared with both end points, which keeps nearly straight curves (tiny
/// leading coefficient) accurate.
#[inline(never)]
pub fn quad_closest(f: &Fields, p: V2) -> (f64, f64) {
    let a = [f[2] - f[0], f[3] - f[1]];
    let b = [f[0] - 2.0 * f[2] + f[4], f[1] - 2.0 * f[3] + f[5]];
    let m = [f[0] - p[0], f[1] - p[1]];
    let dot = |u: V2, v: V2| u[0] * v[0] + u[1] * v[1];
    let c3 = dot(b, b);
    let c2 = 3.0 * dot(a, b);
    let c1 = 2.0 * dot(a, a) + dot(m, b);
    let c0 = dot(m, a);
    let dist2 = |t: f64| {
        let q = quad_point(f, t);
        (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
    };
    let mut best = (0.0, dist2(0.0));
    let d1 = dist2(1.0);
    if d1 < best.1 {
        best = (1.0, d1);
    }
    let mut roots = [0.0f64; 3];
    let n = solve_cubic(c3, c2, c1, c0, &mut roots);
    for &r in &roots[..n] {
        let mut t = r.clamp(0.0, 1.0);
        for _ in 0..3 {
            let g = ((c3 * t + c2) * t + c1) * t + c0;
            let dg = (3.0 * c3 * t + 2.0 * c2) * t + c1;
            if dg.abs() < 1e-300 {
                break;
            }
            t = (t - g / dg).clamp(0.0, 1.0);
        }
        let d = dist2(t);
        if d < best.1 {
            best = (t, d);
        }
    }
    (best.0, best.1.sqrt())
}

/// Real roots of `a t³ + b t² + c t + d`; returns how many were written.
/// Falls back to lower degree when the leading coefficients vanish
/// relative to the others.
pub fn solve_cubic(a: f64, b: f64, c: f64, d: f64, out: &mut [f64; 3]) -> usize {
    let scale = b.abs().max(c.abs()).max(d.abs());
    if a.abs() <= 1e-12 * scale || a == 0.0 {
        // Quadratic b t² + c t + d.
        if b.abs() <= 1e-12 * c.abs().max(d.abs()) || b == 0.0 {
            if c == 0.0 {
                return 0;
            }
            out[0] = -d / c;
            return 1;
        }
        let disc = c * c - 4.0 * b * d;
        if disc < 0.0 {
            out[0] = -c / (2.0 * b); // nearest approach of a complex pair
            return 1;
        }
        let sq = disc.sqrt();
        // Numerically stable pair.
        let q = -0.5 * (c + c.signum() * sq);
        out[0] = q / b;
        out[1] = if q != 0.0 { d / q } else { -c / (2.0 * b) };
        return 2;
    }
    let (b, c, d) = (b / a, c / a, d / a);
    let p = c - b * b / 3.0;
    let q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d;
    let shift = -b / 3.0;
    let disc = q * q / 4.0 + p * p * p / 27.0;
    if disc > 0.0 {
        let sq = disc.sqrt();
        let u = (-q / 2.0 + sq).cbrt();
        let v = (-q / 2.0 - sq).cbrt();
        out[0] = u + v + shift;
        1
    } else {
        let r = (-p / 3.0).max(0.0).sqrt();
        if r == 0.0 {
            out[0] = shift;
            return 1;
        }
        let phi = (-q / (2.0 * r * r * r)).clamp(-1.0, 1.0).acos();
        for (k, o) in out.iter_mut().enumerate() {
            *o = 2.0 * r * ((phi - 2.0 * std::f64::consts::PI * k as f64) / 3.0).cos() + shift;
        }
        3
    }
}

/// Winding-number contribution of a path piece (segment or quadratic) for
/// a horizontal ray from `p` towards +x. Monotone sub-pieces use the
/// half-open rule `(y0 <= py) != (y1 <= py)`, so joints are counted once.
pub fn winding(kind: PrimKind, f: &Fields, p: V2) -> i32 {
    match kind {
        PrimKind::Segment => crossing(f[0], f[1], f[2], f[3], p),
        PrimKind::Quad => {
            let (y0, y1, y2) = (f[1], f[3], f[5]);
            let den = y0 - 2.0 * y1 + y2;
            let te = if den != 0.0 { (y0 - y1) / den } else { -1.0 };
            let mut ts = [0.0, 1.0, 1.0];
            let mut n = 2;
            if te > 0.0 && te < 1.0 {
                ts = [0.0, te, 1.0];
                n = 3;
            }
            let mut w = 0;
            for k in 0..n - 1 {
                let (ta, tb) = (ts[k], ts[k + 1]);
                let ya = quad_point(f, ta)[1];
                let yb = quad_point(f, tb)[1];
                if (ya <= p[1]) != (yb <= p[1]) {
                    // Solve y(t) = py inside [ta, tb], where y is monotone.
                    let (qa, qb, qc) = (den, 2.0 * (y1 - y0), y0 - p[1]);
                    let t = if qa.abs() < 1e-12 {
                        -qc / qb
                    } else {
                        let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
                        let r1 = (-qb + disc) / (2.0 * qa);
                        let r2 = (-qb - disc) / (2.0 * qa);
                        let mid = 0.5 * (ta + tb);
                        if (r1 - mid).abs() < (r2 - mid).abs() {
                            r1
                        } else {
                            r2
                        }
                    }
                    .clamp(ta, tb);
                    if quad_point(f, t)[0] > p[0] {
                        w += if yb > ya { 1 } else { -1 };
                    }
                }
            }
            w
        }
        _ => 0,
    }
}

fn crossing(x0: f64, y0: f64, x1: f64, y1: f64, p: V2) -> i32 {
    if (y0 <= p[1]) != (y1 <= p[1]) {
        let x = x0 + (p[1] - y0) / (y1 - y0) * (x1 - x0);
        if x > p[0] {
            return if y1 > y0 { 1 } else { -1 };
        }
    }
    0
}

/// Weights that turn the four control points of a cubic Bézier into the
/// three points of the quadratic approximating its piece `[ta, tb]`:
/// `quad[k] = Σ_i w[k][i] · cubic[i]`. The piece's end points are exact and
/// its control point is `(3(Q1 + Q2) − (Q0 + Q3)) / 4` of the sub-cubic
/// `Q`, the standard mid-point approximation (error ∝ (tb − ta)³).
pub fn cubic_piece_weights(ta: f64, tb: f64) -> [[f64; 4]; 3] {
    let bern = |t: f64| {
        let u = 1.0 - t;
        [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t]
    };
    let dbern = |t: f64| {
        let u = 1.0 - t;
        [
            -3.0 * u * u,
            3.0 * u * u - 6.0 * u * t,
            6.0 * u * t - 3.0 * t * t,
            3.0 * t * t,
        ]
    };
    let h = (tb - ta) / 3.0;
    let (q0, q3) = (bern(ta), bern(tb));
    let (da, db) = (dbern(ta), dbern(tb));
    let mut ctrl = [0.0; 4];
    for i in 0..4 {
        let q1 = q0[i] + h * da[i];
        let q2 = q3[i] - h * db[i];
        ctrl[i] = (3.0 * (q1 + q2) - (q0[i] + q3[i])) / 4.0;
    }
    [q0, ctrl, q3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

    fn brute(kind: PrimKind, f: &Fields, p: V2) -> f64 {
        // Dense sampling of the curve/segment.
        let n = 20_000;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let q = match kind {
                PrimKind::Segment => [f[0] + t * (f[2] - f[0]), f[1] + t * (f[3] - f[1])],
                PrimKind::Quad => quad_point(f, t),
                _ => unreachable!(),
            };
            best = best.min(len(p[0] - q[0], p[1] - q[1]));
        }
        best
    }

    #[test]
    fn quad_and_segment_match_dense_sampling() {
        let mut r = Rng::new(11);
        for case in 0..300 {
            let mut f = [0.0; 6];
            for v in f.iter_mut() {
                *v = r.f64();
            }
            if case % 5 == 0 {
                // Nearly straight: control point at the chord midpoint (+ tiny offset).
                f[2] = 0.5 * (f[0] + f[4]) + 1e-7;
                f[3] = 0.5 * (f[1] + f[5]);
            }
            let p = [r.range_f64(-0.5, 1.5), r.range_f64(-0.5, 1.5)];
            let d = value(PrimKind::Quad, &f, p);
            let b = brute(PrimKind::Quad, &f, p);
            assert!(
                d <= b + 1e-9 && b - d < 2e-4,
                "case {case}: quad {d} vs brute {b}"
            );
            let ds = value(PrimKind::Segment, &f, p);
            let bs = brute(PrimKind::Segment, &f, p);
            assert!((ds - bs).abs() < 2e-4, "segment {ds} vs {bs}");
        }
    }

    #[test]
    fn rect_matches_brute_force_boundary_distance() {
        let mut r = Rng::new(5);
        for case in 0..100 {
            let f = [
                0.5,
                0.5,
                r.range_f64(0.05, 0.3),
                r.range_f64(0.05, 0.3),
                r.range_f64(0.0, 0.05),
                r.range_f64(-3.0, 3.0),
            ];
            // Boundary samples: straight sides and quarter-circle corners in local coordinates.
            let (hw, hh, rr) = (f[2], f[3], f[4].min(f[2]).min(f[3]));
            let mut pts = vec![];
            let n = 4000;
            for i in 0..=n {
                let t = i as f64 / n as f64;
                let x = -hw + rr + t * 2.0 * (hw - rr);
                let y = -hh + rr + t * 2.0 * (hh - rr);
                pts.extend([[x, -hh], [x, hh], [-hw, y], [hw, y]]);
                let a = t * std::f64::consts::FRAC_PI_2;
                for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
                    pts.push([sx * (hw - rr + rr * a.cos()), sy * (hh - rr + rr * a.sin())]);
                }
            }
            let p = [r.f64(), r.f64()];
            let (c, s) = (f[5].cos(), f[5].sin());
            let (vx, vy) = (p[0] - 0.5, p[1] - 0.5);
            let (lx, ly) = (c * vx + s * vy, -s * vx + c * vy);
            let inside = lx.abs() <= hw && ly.abs() <= hh && {
                let (qx, qy) = (lx.abs() - (hw - rr), ly.abs() - (hh - rr));
                !(qx > 0.0 && qy > 0.0 && len(qx, qy) > rr)
            };
            let b = pts
                .iter()
                .map(|q| len(lx - q[0], ly - q[1]))
                .fold(f64::INFINITY, f64::min);
            let b = if inside { -b } else { b };
            let d = value(PrimKind::Rect, &f, p);
            assert!((d - b).abs() < 1e-3, "case {case}: rect {d} vs brute {b}");
        }
    }

    #[test]
    fn field_gradients_match_finite_differences() {
        let mut r = Rng::new(9);
        for kind in [
            PrimKind::Point,
            PrimKind::Segment,
            PrimKind::Circle,
            PrimKind::Rect,
            PrimKind::Quad,
        ] {
            for _ in 0..50 {
                let mut f = [0.0; 6];
                for v in f.iter_mut() {
                    *v = r.f64();
                }
                if kind == PrimKind::Rect {
                    f[2] = r.range_f64(0.05, 0.3);
                    f[3] = r.range_f64(0.05, 0.3);
                    f[4] = r.range_f64(0.0, 0.04);
                }
                let p = [r.range_f64(-0.2, 1.2), r.range_f64(-0.2, 1.2)];
                let mut g = [0.0; 6];
                grad(kind, &f, p, &mut g);
                for k in 0..kind.field_count() {
                    let h = 1e-6;
                    let (mut a, mut b) = (f, f);
                    a[k] += h;
                    b[k] -= h;
                    let fd = (value(kind, &a, p) - value(kind, &b, p)) / (2.0 * h);
                    assert!(
                        (fd - g[k]).abs() < 1e-4,
                        "{kind:?} field {k}: fd {fd} vs {} at {p:?} {f:?}",
                        g[k]
                    );
                }
            }
        }
    }

    #[test]
    fn winding_of_closed_quad_path() {
        // A lens made of two quadratics from (0.2,0.5) to (0.8,0.5).
        let top = [0.2, 0.5, 0.5, 0.1, 0.8, 0.5];
        let bot = [0.8, 0.5, 0.5, 0.9, 0.2, 0.5];
        let w = |p: V2| winding(PrimKind::Quad, &top, p) + winding(PrimKind::Quad, &bot, p);
        assert_ne!(w([0.5, 0.45]), 0);
        assert_ne!(w([0.5, 0.55]), 0);
        assert_eq!(w([0.5, 0.2]), 0);
        assert_eq!(w([0.1, 0.5]), 0);
        assert_eq!(w([0.9, 0.5]), 0);
    }

    #[test]
    fn cubic_split_into_quadratics_stays_close() {
        let c = [[0.1, 0.1], [0.3, 0.9], [0.7, -0.2], [0.9, 0.6]];
        let cubic = |t: f64| {
            let u = 1.0 - t;
            let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
            [
                (0..4).map(|i| w[i] * c[i][0]).sum::<f64>(),
                (0..4).map(|i| w[i] * c[i][1]).sum::<f64>(),
            ]
        };
        let n = 8;
        let mut worst: f64 = 0.0;
        for k in 0..n {
            let (ta, tb) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let w = cubic_piece_weights(ta, tb);
            let mut f = [0.0; 6];
            for j in 0..3 {
                f[2 * j] = (0..4).map(|i| w[j][i] * c[i][0]).sum();
                f[2 * j + 1] = (0..4).map(|i| w[j][i] * c[i][1]).sum();
            }
            for s in 0..=50 {
                let t = ta + (tb - ta) * s as f64 / 50.0;
                worst = worst.max(value(PrimKind::Quad, &f, cubic(t)));
            }
        }
        assert!(worst < 1e-3, "max deviation {worst}");
    }
}

//! Quadratic Bézier curves: points, the exact closest point (after Sforza
//! et al.), the cubic equation it needs, and the split of a cubic Bézier
//! into quadratic pieces.
use super::Vec2;

/// A quadratic Bézier curve: start, control point, end.
pub type Quad = [Vec2; 3];

/// Point of a quadratic Bézier at `t`.
#[inline]
pub fn quad_point(q: &Quad, t: f64) -> Vec2 {
    let u = 1.0 - t;
    [
        u * u * q[0][0] + 2.0 * u * t * q[1][0] + t * t * q[2][0],
        u * u * q[0][1] + 2.0 * u * t * q[1][1] + t * t * q[2][1],
    ]
}

/// Closest point on a quadratic Bézier to `p`: `(t, distance)`.
///
/// Stationary points of `|B(t) − p|²` are the roots of the cubic
/// `(B·B) t³ + 3(A·B) t² + (2A·A + m·B) t + m·A` with `A = p1 − p0`,
/// `B = p0 − 2p1 + p2`, `m = p0 − p`. The closed-form roots (Cardano, or the
/// trigonometric form for three real roots) are polished by Newton steps and
/// compared with both end points, which keeps nearly straight curves (tiny
/// leading coefficient) accurate.
#[inline(never)]
pub fn quad_closest(q: &Quad, p: Vec2) -> (f64, f64) {
    let a = [q[1][0] - q[0][0], q[1][1] - q[0][1]];
    let b = [
        q[0][0] - 2.0 * q[1][0] + q[2][0],
        q[0][1] - 2.0 * q[1][1] + q[2][1],
    ];
    let m = [q[0][0] - p[0], q[0][1] - p[1]];
    let dot = |u: Vec2, v: Vec2| u[0] * v[0] + u[1] * v[1];
    let c3 = dot(b, b);
    let c2 = 3.0 * dot(a, b);
    let c1 = 2.0 * dot(a, a) + dot(m, b);
    let c0 = dot(m, a);
    let dist2 = |t: f64| {
        let r = quad_point(q, t);
        (r[0] - p[0]).powi(2) + (r[1] - p[1]).powi(2)
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

/// Distance from `p` to a quadratic Bézier and its derivatives with respect
/// to `[x0, y0, x1, y1, x2, y2]` (envelope theorem at the closest point).
pub fn quad_distance_grad(q: &Quad, p: Vec2) -> (f64, [f64; 6]) {
    let (t, d) = quad_closest(q, p);
    let mut out = [0.0; 6];
    if d > 0.0 {
        let c = quad_point(q, t);
        let n = [(p[0] - c[0]) / d, (p[1] - c[1]) / d];
        let w = [(1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t];
        for k in 0..3 {
            out[2 * k] = -w[k] * n[0];
            out[2 * k + 1] = -w[k] * n[1];
        }
    }
    (d, out)
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
        let u = libm::cbrt(-q / 2.0 + sq);
        let v = libm::cbrt(-q / 2.0 - sq);
        out[0] = u + v + shift;
        1
    } else {
        let r = (-p / 3.0).max(0.0).sqrt();
        if r == 0.0 {
            out[0] = shift;
            return 1;
        }
        let phi = libm::acos((-q / (2.0 * r * r * r)).clamp(-1.0, 1.0));
        for (k, o) in out.iter_mut().enumerate() {
            *o = 2.0 * r * libm::cos((phi - 2.0 * std::f64::consts::PI * k as f64) / 3.0) + shift;
        }
        3
    }
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

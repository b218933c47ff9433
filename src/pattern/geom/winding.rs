//! Winding numbers of closed outlines made of segments and quadratic
//! Bézier pieces, for a horizontal ray from the query point towards +x.
//! Monotone sub-pieces use the half-open rule `(y0 <= py) != (y1 <= py)`,
//! so a joint between two pieces is counted once; summing the pieces of a
//! closed outline gives its winding number (non-zero = inside).
use super::bezier::{quad_point, Quad};
use super::Vec2;

/// Contribution of the segment `a b`: `+1` upwards (increasing y), `−1`
/// downwards, `0` when the ray misses it.
#[inline]
pub fn segment_winding(a: Vec2, b: Vec2, p: Vec2) -> i32 {
    let (x0, y0, x1, y1) = (a[0], a[1], b[0], b[1]);
    if (y0 <= p[1]) != (y1 <= p[1]) {
        let x = x0 + (p[1] - y0) / (y1 - y0) * (x1 - x0);
        if x > p[0] {
            return if y1 > y0 { 1 } else { -1 };
        }
    }
    0
}

/// Contribution of a quadratic Bézier piece (split at its y extremum into
/// monotone parts).
pub fn quad_winding(q: &Quad, p: Vec2) -> i32 {
    let (y0, y1, y2) = (q[0][1], q[1][1], q[2][1]);
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
        let ya = quad_point(q, ta)[1];
        let yb = quad_point(q, tb)[1];
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
            if quad_point(q, t)[0] > p[0] {
                w += if yb > ya { 1 } else { -1 };
            }
        }
    }
    w
}

//! Exact distances to points, circles, segments and rounded rectangles and
//! their derivatives (after Quílez).
use super::{len, Vec2};

/// Distance from `p` to the point `c`.
#[inline(always)]
pub fn point_distance(c: Vec2, p: Vec2) -> f64 {
    len(p[0] - c[0], p[1] - c[1])
}

/// Signed distance from `p` to the circle of centre `c` and radius `r`
/// (negative inside).
#[inline(always)]
pub fn circle_distance(c: Vec2, r: f64, p: Vec2) -> f64 {
    len(p[0] - c[0], p[1] - c[1]) - r
}

/// Distance from `p` to the point `c` and its derivatives with respect to
/// `c` (zero at `p = c`). For a circle add `−r` to the distance; its
/// derivative with respect to `r` is `−1`.
#[inline]
pub fn point_distance_grad(c: Vec2, p: Vec2) -> (f64, Vec2) {
    let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
    let l = len(dx, dy);
    if l > 0.0 {
        (l, [-dx / l, -dy / l])
    } else {
        (l, [0.0, 0.0])
    }
}

/// Parameter of the point of segment `a b` closest to `p`, in `[0, 1]`
/// (0 for a degenerate segment).
#[inline(always)]
pub fn segment_closest_t(a: Vec2, b: Vec2, p: Vec2) -> f64 {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let l2 = bx * bx + by * by;
    if l2 <= 0.0 {
        return 0.0;
    }
    (((p[0] - a[0]) * bx + (p[1] - a[1]) * by) / l2).clamp(0.0, 1.0)
}

/// Distance from `p` to the segment `a b`.
#[inline(always)]
pub fn segment_distance(a: Vec2, b: Vec2, p: Vec2) -> f64 {
    let t = segment_closest_t(a, b, p);
    len(
        p[0] - (a[0] + t * (b[0] - a[0])),
        p[1] - (a[1] + t * (b[1] - a[1])),
    )
}

/// Distance from `p` to the segment `a b` and its derivatives with respect
/// to `[ax, ay, bx, by]`.
#[inline]
pub fn segment_distance_grad(a: Vec2, b: Vec2, p: Vec2) -> (f64, [f64; 4]) {
    let t = segment_closest_t(a, b, p);
    let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
    let l = len(dx, dy);
    let mut g = [0.0; 4];
    if l > 0.0 {
        let n = [dx / l, dy / l];
        g[0] = -(1.0 - t) * n[0];
        g[1] = -(1.0 - t) * n[1];
        g[2] = -t * n[0];
        g[3] = -t * n[1];
    }
    (l, g)
}

/// A rectangle with rounded corners: centre, half sides, corner radius
/// (clamped to `[0, min(half sides)]`) and rotation (radians,
/// counter-clockwise in the caller's coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundedRect {
    pub centre: Vec2,
    pub half: Vec2,
    pub radius: f64,
    pub angle: f64,
}

impl RoundedRect {
    /// Signed distance from `p` (negative inside).
    #[inline]
    pub fn distance(&self, p: Vec2) -> f64 {
        self.eval(p, None)
    }

    /// Signed distance and its derivatives with respect to
    /// `[cx, cy, half_w, half_h, radius, angle]`. Where the radius is clamped
    /// to the smaller half side, it moves with that side.
    #[inline]
    pub fn distance_grad(&self, p: Vec2) -> (f64, [f64; 6]) {
        let mut g = [0.0; 6];
        let d = self.eval(p, Some(&mut g));
        (d, g)
    }

    #[inline(never)]
    fn eval(&self, p: Vec2, out: Option<&mut [f64; 6]>) -> f64 {
        let (c, s) = (libm::cos(self.angle), libm::sin(self.angle));
        let (vx, vy) = (p[0] - self.centre[0], p[1] - self.centre[1]);
        // Local coordinates: rotate by −angle.
        let lx = c * vx + s * vy;
        let ly = -s * vx + c * vy;
        let (hw, hh) = (self.half[0], self.half[1]);
        let rmax = hw.min(hh).max(0.0);
        let r = self.radius.clamp(0.0, rmax);
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
            if self.radius >= 0.0 && self.radius <= rmax {
                out[4] = dr;
            } else if self.radius > rmax {
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
}

//! Fit's primitives as packed fields (paper §4 "Pattern Distance Fields":
//! circles, rectangles and segments after Quílez, quadratic Bézier curves
//! after Sforza et al.; cubics are converted to quadratics).
//!
//! The geometry itself (distances, derivatives, closest points, winding)
//! lives in [`crate::geom`]; this file only packs each primitive into up to
//! [`MAX_FIELDS`] scalars (the tape nodes a recording writes) and dispatches
//! on [`PrimKind`]. Circles and rounded rectangles are signed (negative
//! inside); points, segments and Bézier pieces are unsigned distances to a
//! zero-area set (paths get their sign from the winding number, see
//! [`winding`]).
use crate::pattern::geom::bezier::{quad_closest, quad_distance_grad, Quad};
use crate::pattern::geom::primitives;
use crate::pattern::geom::primitives::{point_distance_grad, segment_distance_grad, RoundedRect};
use crate::pattern::geom::winding::{quad_winding, segment_winding};

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

#[inline(always)]
fn seg(f: &Fields) -> (V2, V2) {
    ([f[0], f[1]], [f[2], f[3]])
}

#[inline(always)]
fn quad(f: &Fields) -> Quad {
    [[f[0], f[1]], [f[2], f[3]], [f[4], f[5]]]
}

#[inline(always)]
fn rect(f: &Fields) -> RoundedRect {
    RoundedRect {
        centre: [f[0], f[1]],
        half: [f[2], f[3]],
        radius: f[4],
        angle: f[5],
    }
}

/// Distance from `p` to the segment `[ax, ay, bx, by]`.
#[inline(always)]
pub fn segment_distance(f: &Fields, p: V2) -> f64 {
    let (a, b) = seg(f);
    primitives::segment_distance(a, b, p)
}

/// The distance of `p` to the primitive (signed for circles and rectangles).
#[inline]
pub fn value(kind: PrimKind, f: &Fields, p: V2) -> f64 {
    match kind {
        PrimKind::Point => primitives::point_distance([f[0], f[1]], p),
        PrimKind::Circle => primitives::circle_distance([f[0], f[1]], f[2], p),
        PrimKind::Segment => segment_distance(f, p),
        PrimKind::Rect => rect(f).distance(p),
        PrimKind::Quad => quad_closest(&quad(f), p).1,
    }
}

/// The distance and its derivatives with respect to the fields (`out`,
/// entries beyond [`PrimKind::field_count`] are zero).
pub fn grad(kind: PrimKind, f: &Fields, p: V2, out: &mut Fields) -> f64 {
    *out = [0.0; MAX_FIELDS];
    match kind {
        PrimKind::Point | PrimKind::Circle => {
            let (l, g) = point_distance_grad([f[0], f[1]], p);
            out[..2].copy_from_slice(&g);
            if kind == PrimKind::Circle {
                out[2] = -1.0;
                l - f[2]
            } else {
                l
            }
        }
        PrimKind::Segment => {
            let (a, b) = seg(f);
            let (l, g) = segment_distance_grad(a, b, p);
            out[..4].copy_from_slice(&g);
            l
        }
        PrimKind::Rect => {
            let (d, g) = rect(f).distance_grad(p);
            *out = g;
            d
        }
        PrimKind::Quad => {
            let (d, g) = quad_distance_grad(&quad(f), p);
            *out = g;
            d
        }
    }
}

/// Winding-number contribution of a path piece (segment or quadratic) for
/// a horizontal ray from `p` towards +x (see [`crate::pattern::geom::winding`]).
pub fn winding(kind: PrimKind, f: &Fields, p: V2) -> i32 {
    match kind {
        PrimKind::Segment => {
            let (a, b) = seg(f);
            segment_winding(a, b, p)
        }
        PrimKind::Quad => quad_winding(&quad(f), p),
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use crate::pattern::geom::bezier::cubic_piece_weights;
    use crate::pattern::geom::len;

    fn brute(kind: PrimKind, f: &Fields, p: V2) -> f64 {
        // Dense sampling of the curve/segment.
        let n = 20_000;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let q = match kind {
                PrimKind::Segment => [f[0] + t * (f[2] - f[0]), f[1] + t * (f[3] - f[1])],
                PrimKind::Quad => crate::pattern::geom::bezier::quad_point(&quad(f), t),
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

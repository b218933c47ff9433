//! The geometric and decorative operators on one shape (paper §4.2–4.3):
//! each turns a polygon into its output slots (see [`super::ast`] for the
//! slot order). Grouping operators only relabel, so they live in
//! [`super::expand`].
//!
//! Perturbation (§4.3) is applied to the cutting curves, not to the
//! finished shapes: a split's curve copies and an outline's inset are
//! displaced by Perlin noise seeded by the id of the group the new shapes
//! join, and only then cut the parent. Every new edge is made once and
//! shared by the shapes on both sides, so no gap or overlap can appear.
use super::ast::{CurveDef, StippleKind};
use crate::core::rng::Rng;
use crate::tangle::geom::polygon::{resample_polyline, Polygon};
use crate::tangle::geom::{noise, order};
use glam::DVec2;

/// Hand-drawn wobble: displacement amplitude and feature size in drawing
/// units (0 amplitude: none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wobble {
    pub amplitude: f64,
    pub wavelength: f64,
    pub seed: u64,
}

impl Wobble {
    /// Displace a point.
    pub fn at(&self, p: DVec2) -> DVec2 {
        if self.amplitude <= 0.0 {
            return p;
        }
        p + self.amplitude * noise::displacement(p / self.wavelength.max(1e-9), self.seed)
    }
}

/// The most cut lines one split may lay across one shape (per direction).
pub const MAX_CUTS: usize = 2_000;

/// A split curve as a polyline in its local frame (x across, y along the
/// orientation), covering `x ∈ [x0, x1]`.
fn curve_points(curve: &CurveDef, x0: f64, x1: f64, step: f64) -> Vec<DVec2> {
    let w = (x1 - x0).max(1e-9);
    let periodic = |f: &dyn Fn(f64) -> f64, period: f64| {
        let n = ((w / step.min(period / 8.0).max(w / 20_000.0)).ceil() as usize).max(1);
        (0..=n)
            .map(|i| {
                let x = x0 + w * i as f64 / n as f64;
                DVec2::new(x, f(x))
            })
            .collect::<Vec<_>>()
    };
    match curve {
        CurveDef::Line | CurveDef::Circle | CurveDef::Ngon(_) => {
            vec![DVec2::new(x0, 0.0), DVec2::new(x1, 0.0)]
        }
        CurveDef::Zigzag { amplitude, period } => {
            let p = period.max(1e-3);
            // A triangle wave with its peaks on multiples of p/2.
            periodic(
                &|x: f64| {
                    let t = (x / p).rem_euclid(1.0);
                    amplitude * (4.0 * (t - 0.5).abs() - 1.0)
                },
                p,
            )
        }
        CurveDef::Wave { amplitude, period } => {
            let p = period.max(1e-3);
            periodic(
                &|x: f64| amplitude * (std::f64::consts::TAU * x / p).sin(),
                p,
            )
        }
        CurveDef::Arc { bulge } => {
            let h = bulge * w;
            if h.abs() < 1e-9 {
                return vec![DVec2::new(x0, 0.0), DVec2::new(x1, 0.0)];
            }
            let r = (w * w / 4.0 + h * h) / (2.0 * h.abs());
            let c = (x0 + x1) / 2.0;
            periodic(
                &|x: f64| {
                    let d = (r * r - (x - c) * (x - c)).max(0.0).sqrt() - (r - h.abs());
                    d * h.signum()
                },
                w,
            )
        }
        CurveDef::Polyline(pts) => stretch(pts, x0, x1),
        // An SVG curve is flattened into a polyline when the grammar is
        // resolved; here it can only be the fallback.
        CurveDef::Svg(_) => vec![DVec2::new(x0, 0.0), DVec2::new(x1, 0.0)],
    }
}

/// A drawn polyline stretched so its x range covers `[x0, x1]`, y scaled
/// alike and centred on its mean.
fn stretch(pts: &[DVec2], x0: f64, x1: f64) -> Vec<DVec2> {
    if pts.len() < 2 {
        return vec![DVec2::new(x0, 0.0), DVec2::new(x1, 0.0)];
    }
    let (lo, hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.x), b.max(p.x))
        });
    let s = if hi - lo > 1e-9 {
        (x1 - x0) / (hi - lo)
    } else {
        1.0
    };
    let my = pts.iter().map(|p| p.y).sum::<f64>() / pts.len() as f64;
    let mut out: Vec<DVec2> = pts
        .iter()
        .map(|p| DVec2::new(x0 + (p.x - lo) * s, (p.y - my) * s))
        .collect();
    if out[0].x > out[out.len() - 1].x {
        out.reverse();
    }
    // Extend both ends straight across, so the curve spans the shape.
    let (first, last) = (out[0], out[out.len() - 1]);
    out.insert(0, DVec2::new(x0 - 1.0, first.y));
    out.push(DVec2::new(x1 + 1.0, last.y));
    out
}

/// Regular split (§4.2): copies of `curve` laid across the shape along
/// its orientation `dir`, spaced by `offsets` in turn; `dual` adds copies
/// along the perpendicular. The pieces in reading order: by band along
/// `dir`, then across.
pub fn regular_split(
    poly: &Polygon,
    dir: DVec2,
    curve: &CurveDef,
    offsets: &[f64],
    dual: bool,
    step: f64,
    wobble: &Wobble,
) -> Vec<Polygon> {
    let d = dir.try_normalize().unwrap_or(DVec2::Y);
    let e = across(d);
    let mut cuts = cut_lines(poly, d, curve, offsets, step, wobble);
    let rows = cut_positions(poly, d, offsets);
    let cols = if dual {
        cuts.extend(cut_lines(poly, e, curve, offsets, step, wobble));
        cut_positions(poly, e, offsets)
    } else {
        vec![]
    };
    // Row by row, column by column, then along the row; pieces with equal
    // keys keep the slice's order (their index is the tie-break).
    let mut pieces = poly.slice(&cuts);
    let band = |pos: &[f64], t: f64| pos.partition_point(|&v| v < t) as u64;
    let ncols = cols.len() as u64 + 1; // a column band is 0..=cols.len()
    let mut keys: Vec<order::Key> = pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let c = p.centroid();
            let cell = band(&rows, c.dot(d)) * ncols + band(&cols, c.dot(e));
            (cell, order::key(c.dot(e)), i as u64)
        })
        .collect();
    order::sort(&mut keys);
    keys.iter()
        .map(|k| std::mem::take(&mut pieces[k.2 as usize]))
        .collect()
}

/// The direction across orientation `d`: `d` turned a quarter clockwise
/// (y up), so with `d` = +y (rows going down a y-down page) pieces read
/// left to right.
fn across(d: DVec2) -> DVec2 {
    DVec2::new(d.y, -d.x)
}

/// Where the copies of a split's curve go along `d`: offsets in turn from
/// the shape's extent start, at most [`MAX_CUTS`].
fn cut_positions(poly: &Polygon, d: DVec2, offsets: &[f64]) -> Vec<f64> {
    let (t0, t1) = extent(poly, d);
    let mut out = vec![];
    let mut t = t0;
    for i in 0..MAX_CUTS {
        let o = offsets[i % offsets.len().max(1)].max(super::ast::MIN_LENGTH);
        t += o;
        if t >= t1 {
            break;
        }
        out.push(t);
    }
    out
}

fn extent(poly: &Polygon, d: DVec2) -> (f64, f64) {
    poly.rings
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            let t = p.dot(d);
            (a.min(t), b.max(t))
        })
}

fn cut_lines(
    poly: &Polygon,
    d: DVec2,
    curve: &CurveDef,
    offsets: &[f64],
    step: f64,
    wobble: &Wobble,
) -> Vec<Vec<DVec2>> {
    let e = across(d);
    let (u0, u1) = extent(poly, e);
    let margin = 2.0 + step;
    let local = curve_points(curve, u0 - margin, u1 + margin, step);
    cut_positions(poly, d, offsets)
        .into_iter()
        .map(|t| {
            let line: Vec<DVec2> = local.iter().map(|q| e * q.x + d * (t + q.y)).collect();
            let line = if wobble.amplitude > 0.0 {
                resample_polyline(&line, step)
            } else {
                line
            };
            line.into_iter().map(|p| wobble.at(p)).collect()
        })
        .collect()
}

/// Outline (§4.2): the shape inset by `distance` (the inner shapes; none
/// when it vanishes) and the ring that remains.
pub fn outline(poly: &Polygon, distance: f64, step: f64, wobble: &Wobble) -> [Vec<Polygon>; 2] {
    let mut inner: Vec<Polygon> = poly.inset(distance);
    if wobble.amplitude > 0.0 {
        // Keep the wobble inside the ring so the inner shapes stay inside:
        // a displacement is at most √2 × 1.01 × amplitude (two noises,
        // each within ±1.01), under 0.6 × distance with this cap.
        let w = Wobble {
            amplitude: wobble.amplitude.min(0.4 * distance),
            ..*wobble
        };
        inner = inner
            .iter()
            .flat_map(|p| p.resampled(step).map_points(|q| w.at(q)))
            .collect();
    }
    // The inner shapes lie inside the shape, at least 0.4 × distance from
    // its boundary.
    let ring = poly.minus_inside(&inner);
    [inner, ring]
}

/// The most marks stippling puts in one shape.
pub const MAX_MARKS: usize = 5_000;

/// Stippling: marks (dots, dashes, small curves) scattered inside the
/// shape on a jittered grid of `spacing`, each of about `size`, kept
/// wholly inside.
pub fn stipple(
    poly: &Polygon,
    kind: StippleKind,
    spacing: f64,
    size: f64,
    rng: &mut Rng,
) -> Vec<Polygon> {
    let (lo, hi) = poly.bbox();
    let s = spacing.max(super::ast::MIN_LENGTH);
    let (nx, ny) = (((hi.x - lo.x) / s).ceil(), ((hi.y - lo.y) / s).ceil());
    if !(nx * ny).is_finite() || nx * ny > (MAX_MARKS * 4) as f64 {
        // Too many cells for the budget: widen the spacing to fit it.
        let area = (hi.x - lo.x) * (hi.y - lo.y);
        return stipple(poly, kind, (area / MAX_MARKS as f64).sqrt(), size, rng);
    }
    let r = (size * 0.5).max(0.1);
    let mut out = vec![];
    for j in 0..ny as usize {
        for i in 0..nx as usize {
            let c = lo
                + DVec2::new(
                    (i as f64 + 0.2 + 0.6 * rng.f64()) * s,
                    (j as f64 + 0.2 + 0.6 * rng.f64()) * s,
                );
            let angle = rng.f64() * std::f64::consts::TAU;
            if out.len() >= MAX_MARKS || !poly.contains(c) {
                continue;
            }
            let room = poly.boundary_distance(c);
            if room < 2.0 * r {
                continue;
            }
            let mark = match kind {
                StippleKind::Dots => Polygon::circle(c, r, 8),
                StippleKind::Dashes => {
                    let a = DVec2::from_angle(angle) * (2.0 * r);
                    let n = a.perp().normalize_or_zero() * (0.25 * r);
                    Polygon {
                        rings: vec![vec![c - a - n, c + a - n, c + a + n, c - a + n]],
                    }
                }
                StippleKind::Curves => {
                    // A short crescent: an arc of radius 2r, 0.4r thick.
                    let (k, rad) = (7, 2.0 * r);
                    let centre = c - DVec2::from_angle(angle) * rad;
                    let arc = |rr: f64| -> Vec<DVec2> {
                        (0..k)
                            .map(|m| {
                                let t = angle - 0.5 + m as f64 / (k - 1) as f64;
                                centre + DVec2::from_angle(t) * rr
                            })
                            .collect()
                    };
                    let mut ring = arc(rad + 0.2 * r);
                    ring.extend(arc(rad - 0.2 * r).into_iter().rev());
                    Polygon { rings: vec![ring] }
                }
            };
            // A mark that reaches less far from its centre than the shape's
            // boundary is wholly inside: clipping it would give it back (at
            // the cost of a boolean with the whole shape, most of a
            // stippled tangle's time). Only a dash can reach past 2r.
            let reach = mark.rings[0]
                .iter()
                .map(|p| p.distance(c))
                .fold(0.0, f64::max);
            if reach < room {
                out.push(mark);
            } else {
                out.extend(mark.intersect(poly));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const NONE: Wobble = Wobble {
        amplitude: 0.0,
        wavelength: 40.0,
        seed: 0,
    };

    fn square(s: f64) -> Polygon {
        Polygon::rect(DVec2::ZERO, DVec2::splat(s))
    }

    fn areas(v: &[Polygon]) -> f64 {
        v.iter().map(Polygon::area).sum()
    }

    #[test]
    fn a_dual_split_of_a_square_is_a_grid_in_reading_order() {
        let p = regular_split(
            &square(100.0),
            DVec2::Y,
            &CurveDef::Line,
            &[25.0],
            true,
            2.0,
            &NONE,
        );
        assert_eq!(p.len(), 16);
        assert!((areas(&p) - 10_000.0).abs() < 1e-6);
        // Reading order: rows along the orientation (y), then across (x).
        let c: Vec<DVec2> = p.iter().map(Polygon::centroid).collect();
        assert!(
            (c[0] - DVec2::new(12.5, 12.5)).length() < 1e-6,
            "{:?}",
            c[0]
        );
        assert!(
            (c[1] - DVec2::new(37.5, 12.5)).length() < 1e-6,
            "{:?}",
            c[1]
        );
        assert!(
            (c[4] - DVec2::new(12.5, 37.5)).length() < 1e-6,
            "{:?}",
            c[4]
        );
    }

    #[test]
    fn offsets_are_cycled() {
        let p = regular_split(
            &square(100.0),
            DVec2::Y,
            &CurveDef::Line,
            &[10.0, 30.0],
            false,
            2.0,
            &NONE,
        );
        let h: Vec<f64> = p.iter().map(|q| q.area() / 100.0).collect();
        assert_eq!(h.len(), 6);
        for (got, want) in h.iter().zip([10.0, 30.0, 10.0, 30.0, 10.0, 10.0]) {
            assert!((got - want).abs() < 1e-6, "{h:?}");
        }
    }

    #[test]
    fn wobbly_curved_splits_conserve_area_without_overlap() {
        let w = Wobble {
            amplitude: 2.0,
            wavelength: 30.0,
            seed: 9,
        };
        for curve in [
            CurveDef::Zigzag {
                amplitude: 5.0,
                period: 20.0,
            },
            CurveDef::Wave {
                amplitude: 4.0,
                period: 30.0,
            },
            CurveDef::Arc { bulge: 0.2 },
            CurveDef::Polyline(vec![
                DVec2::ZERO,
                DVec2::new(1.0, 0.5),
                DVec2::new(2.0, 0.0),
            ]),
        ] {
            let parent = Polygon::circle(DVec2::splat(50.0), 50.0, 64);
            let p = regular_split(
                &parent,
                DVec2::new(1.0, 1.0),
                &curve,
                &[12.0],
                true,
                2.0,
                &w,
            );
            assert!(p.len() > 10, "{curve:?}: {}", p.len());
            assert!(
                (areas(&p) - parent.area()).abs() < 1e-3 * parent.area(),
                "{curve:?}"
            );
            let union = areas(&Polygon::union_all(&p));
            assert!(
                (union - areas(&p)).abs() < 1e-3 * parent.area(),
                "{curve:?} overlaps"
            );
        }
    }

    #[test]
    fn an_outline_gives_inner_shapes_and_a_ring_that_tile_the_shape() {
        let w = Wobble {
            amplitude: 3.0,
            wavelength: 20.0,
            seed: 1,
        };
        for wob in [NONE, w] {
            let [inner, ring] = outline(&square(100.0), 10.0, 2.0, &wob);
            assert_eq!(inner.len(), 1);
            assert_eq!(ring.len(), 1);
            assert_eq!(ring[0].rings.len(), 2, "the ring has a hole");
            assert!((areas(&inner) + areas(&ring) - 10_000.0).abs() < 1e-2);
            assert!((areas(&inner) - 6_400.0).abs() < 400.0, "{}", areas(&inner));
        }
        let [inner, ring] = outline(&square(10.0), 6.0, 2.0, &NONE);
        assert!(inner.is_empty());
        assert!((areas(&ring) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn stipple_marks_lie_inside_and_are_bounded() {
        let mut rng = Rng::new(3);
        // A disc with a hole: no mark may reach into the hole either.
        let disc = Polygon::circle(DVec2::splat(50.0), 50.0, 64);
        let parent = disc.difference(&Polygon::circle(DVec2::splat(50.0), 20.0, 32))[0].clone();
        assert_eq!(parent.rings.len(), 2);
        for kind in [StippleKind::Dots, StippleKind::Dashes, StippleKind::Curves] {
            let m = stipple(&parent, kind, 8.0, 2.0, &mut rng);
            assert!(m.len() > 20, "{kind:?}");
            // Kept as they were made (not clipped) or clipped: normalised alike,
            // outer rings counter-clockwise.
            let ccw = |q: &Polygon| crate::tangle::geom::polygon::ring_area2(&q.rings[0]) > 0.0;
            assert!(m.iter().all(ccw), "{kind:?}");
            let outside: f64 = m
                .iter()
                .flat_map(|q| q.difference(&parent))
                .map(|q| q.area())
                .sum();
            assert!(outside < 1e-6);
        }
        let huge = Polygon::rect(DVec2::ZERO, DVec2::splat(1e6));
        assert!(stipple(&huge, StippleKind::Dots, 1.0, 1.0, &mut rng).len() <= MAX_MARKS);
    }
}

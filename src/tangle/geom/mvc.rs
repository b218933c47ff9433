//! Mean value coordinates (Floater 2003; for arbitrary planar polygons and
//! polygons with holes, Hormann & Floater 2006): smooth weights of a point
//! over the vertices of a set of closed rings, used to interpolate values
//! given on a boundary into its inside (Tangle's streamline field, paper
//! §4.2).
//!
//! The Tangle paper cites Meyer et al. 2002's generalised barycentric
//! coordinates, which are defined for convex polygons only. Mean value
//! coordinates are the usual generalisation that stays well defined for
//! non-convex polygons and polygons with holes (every ring contributes, all
//! rings together reproduce linear functions exactly), which is what
//! Tangle's shapes are, so they are used here.
//!
//! For `p` and the ring vertices `P_i`, with `d_i = P_i − p`, `r_i = |d_i|`
//! and `α_i` the signed angle from `d_i` to `d_{i+1}`:
//! `w_i = (tan(α_{i−1}/2) + tan(α_i/2)) / r_i`, normalised to sum to 1.
//! The half-angle tangent is computed without trigonometry, as
//! `A/(r_i r_{i+1} + D)` or, when the angle is obtuse, the equal
//! `(r_i r_{i+1} − D)/A` (`A`, `D` the cross and dot products of `d_i`,
//! `d_{i+1}`), so neither form cancels catastrophically and only `sqrt` is
//! used: the weights are bit-identical natively and in wasm.
//!
//! Rings are closed implicitly (the edge from the last point back to the
//! first) and should be oriented with the region on their left (outer ring
//! counter-clockwise, holes clockwise, y up — as
//! [`crate::tangle::geom::polygon::Polygon`] normalises them): then the weight sum
//! is positive for every point not on the boundary.
use glam::DVec2;
use std::ops::{Add, Mul};

/// A point closer than this (relative to the rings' size) to a vertex gets
/// that vertex's value; this close to an edge, the edge's linear
/// interpolation.
const SNAP: f64 = 1e-10;

/// Mean value weights of `p` over every point of every ring, in order
/// (ring 0's points, then ring 1's, …), written into `out` (cleared first).
/// They sum to 1 and reproduce linear functions: `Σ w_i P_i = p`.
///
/// Robust on the boundary: at a vertex (within a relative 1e-10) that
/// vertex gets weight 1; on an edge, its two ends get the linear
/// interpolation weights. If the weights cannot be normalised (a point
/// where a badly oriented ring cancels the sum, or non-finite input) the
/// nearest vertex gets weight 1. Empty rings contribute nothing; `out` is
/// empty when there are no points at all.
pub fn mean_value_weights(rings: &[Vec<DVec2>], p: DVec2, out: &mut Vec<f64>) {
    out.clear();
    let total: usize = rings.iter().map(Vec::len).sum();
    if total == 0 {
        return;
    }
    out.resize(total, 0.0);
    // Pass 1: distances r_i (kept in `out` until overwritten by the
    // weights, one sqrt per point), the configuration's size (for the
    // relative tolerances) and the nearest vertex.
    let (mut scale, mut nearest, mut k) = (f64::MIN_POSITIVE, (f64::INFINITY, 0), 0);
    for ring in rings {
        for &q in ring {
            let r = (q - p).length();
            scale = scale.max(r);
            if r < nearest.0 {
                nearest = (r, k);
            }
            out[k] = r;
            k += 1;
        }
    }
    let eps = SNAP * scale;
    if nearest.0 <= eps {
        // On a vertex (or a non-finite input): that vertex.
        out.iter_mut().for_each(|w| *w = 0.0);
        out[nearest.1] = 1.0;
        return;
    }

    // Pass 2: on an edge, the edge's linear interpolation; else the
    // weights. w_i needs tan(α_{i−1}/2) and tan(α_i/2); r_i is still in
    // `out[i]` when w_i is written, and the last edge's tangent (which
    // needs r_0) is computed first and reused.
    let mut sum = 0.0;
    let mut base = 0;
    for ring in rings {
        let n = ring.len();
        if n == 0 {
            continue;
        }
        let r = |out: &[f64], i: usize| out[base + i];
        // tan(α_i/2) of edge i → i+1, or the on-edge parameter.
        let half_tan = |out: &[f64], i: usize| -> Result<f64, (usize, usize, f64)> {
            let j = if i + 1 == n { 0 } else { i + 1 };
            let (di, dj) = (ring[i] - p, ring[j] - p);
            let (ri, rj) = (r(out, i), r(out, j));
            let (cross, dot) = (di.perp_dot(dj), di.dot(dj));
            if dot < 0.0 && cross.abs() <= eps * (ri + rj) {
                // p on the segment between P_i and P_j.
                return Err((i, j, ri / (ri + rj)));
            }
            let rr = ri * rj;
            Ok(if dot >= 0.0 {
                cross / (rr + dot)
            } else {
                (rr - dot) / cross
            })
        };
        let on_edge = |out: &mut Vec<f64>, (i, j, t): (usize, usize, f64)| {
            out.iter_mut().for_each(|w| *w = 0.0);
            out[base + i] = 1.0 - t;
            out[base + j] += t;
        };
        let last = match half_tan(out, n - 1) {
            Ok(t) => t,
            Err(e) => return on_edge(out, e),
        };
        let mut prev = last;
        for i in 0..n {
            let cur = if i + 1 == n {
                last
            } else {
                match half_tan(out, i) {
                    Ok(t) => t,
                    Err(e) => return on_edge(out, e),
                }
            };
            let w = (prev + cur) / r(out, i);
            out[base + i] = w;
            sum += w;
            prev = cur;
        }
        base += n;
    }
    if sum.is_finite() && sum.abs() > 1e-300 && out.iter().all(|w| w.is_finite()) {
        let inv = 1.0 / sum;
        out.iter_mut().for_each(|w| *w *= inv);
        return;
    }
    // Degenerate: the nearest vertex takes it all.
    out.iter_mut().for_each(|w| *w = 0.0);
    out[nearest.1] = 1.0;
}

/// `Σ w_i values_i` (weights from [`mean_value_weights`], one value per
/// boundary point; extra entries of the longer slice are ignored).
pub fn interpolate<T>(weights: &[f64], values: &[T]) -> T
where
    T: Copy + Default + Add<Output = T> + Mul<f64, Output = T>,
{
    weights
        .iter()
        .zip(values)
        .fold(T::default(), |acc, (&w, &v)| acc + v * w)
}

/// Mean value interpolation at `p` of `values` given at the rings' points
/// (in [`mean_value_weights`] order), reusing `scratch` for the weights.
pub fn mean_value_interpolate<T>(
    rings: &[Vec<DVec2>],
    values: &[T],
    p: DVec2,
    scratch: &mut Vec<f64>,
) -> T
where
    T: Copy + Default + Add<Output = T> + Mul<f64, Output = T>,
{
    mean_value_weights(rings, p, scratch);
    interpolate(scratch, values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// An L shape (non-convex) with a square hole, region on the left of
    /// every ring.
    fn l_with_hole() -> Vec<Vec<DVec2>> {
        vec![
            vec![
                v(0.0, 0.0),
                v(10.0, 0.0),
                v(10.0, 4.0),
                v(4.0, 4.0),
                v(4.0, 10.0),
                v(0.0, 10.0),
            ],
            vec![v(1.0, 1.0), v(1.0, 2.0), v(2.0, 2.0), v(2.0, 1.0)],
        ]
    }

    fn lin(q: DVec2) -> f64 {
        3.0 * q.x - 2.0 * q.y + 7.0
    }

    #[test]
    fn weights_sum_to_one_and_reproduce_linear_functions() {
        let rings = l_with_hole();
        let values: Vec<f64> = rings.iter().flatten().map(|&q| lin(q)).collect();
        let mut w = Vec::new();
        // Inside points, including in the concave corner and next to the hole.
        for p in [
            v(0.5, 0.5),
            v(3.0, 3.0),
            v(2.5, 1.5),
            v(9.0, 3.5),
            v(1.0, 9.0),
            v(3.9, 3.9),
        ] {
            mean_value_weights(&rings, p, &mut w);
            assert_eq!(w.len(), 10);
            let sum: f64 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "sum {sum} at {p}");
            let f = interpolate(&w, &values);
            assert!((f - lin(p)).abs() < 1e-9, "{f} vs {} at {p}", lin(p));
            let q = interpolate(&w, &rings.concat());
            assert!(q.distance(p) < 1e-9, "linear precision: {q} vs {p}");
        }
    }

    #[test]
    fn on_a_vertex_or_an_edge_the_boundary_value_is_returned() {
        let rings = l_with_hole();
        let values: Vec<f64> = rings.iter().flatten().map(|&q| lin(q)).collect();
        let mut w = Vec::new();
        mean_value_weights(&rings, v(4.0, 4.0), &mut w);
        assert_eq!(w[3], 1.0);
        assert_eq!(w.iter().filter(|&&x| x != 0.0).count(), 1);
        // On a hole's vertex.
        mean_value_weights(&rings, v(2.0, 2.0), &mut w);
        assert_eq!(w[8], 1.0);
        // Mid-edge and nearly on an edge.
        for p in [v(7.0, 0.0), v(7.0, 1e-13), v(4.0, 7.25), v(1.5, 2.0)] {
            mean_value_weights(&rings, p, &mut w);
            let f = mean_value_interpolate(&rings, &values, p, &mut w);
            assert!((f - lin(p)).abs() < 1e-9, "{f} vs {} at {p}", lin(p));
        }
        // Very near a vertex but not on it: still finite, still exact.
        let p = v(4.0 + 1e-7, 4.0 + 1e-7);
        let f = mean_value_interpolate(&rings, &values, p, &mut w);
        assert!(w.iter().all(|x| x.is_finite()));
        assert!((f - lin(p)).abs() < 1e-6);
    }

    #[test]
    fn degenerate_input_gives_finite_weights() {
        let mut w = Vec::new();
        mean_value_weights(&[], v(1.0, 1.0), &mut w);
        assert!(w.is_empty());
        // Repeated points and a single-point ring.
        let rings = vec![
            vec![v(0.0, 0.0), v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            vec![v(5.0, 5.0)],
        ];
        mean_value_weights(&rings, v(0.7, 0.2), &mut w);
        assert!(w.iter().all(|x| x.is_finite()));
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        mean_value_weights(&rings, v(f64::NAN, 0.0), &mut w);
        assert!(w.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn weights_are_smooth_inside() {
        // Interpolated values vary continuously: neighbouring points give
        // neighbouring values for a non-linear boundary function.
        let rings = l_with_hole();
        let values: Vec<f64> = rings.iter().flatten().map(|q| q.x * q.y).collect();
        let mut w = Vec::new();
        let mut last: Option<f64> = None;
        for k in 0..200 {
            let p = v(0.5 + 0.04 * k as f64, 3.0);
            let f = mean_value_interpolate(&rings, &values, p, &mut w);
            if let Some(l) = last {
                assert!((f - l).abs() < 0.5, "jump at {p}: {l} -> {f}");
            }
            last = Some(f);
        }
    }
}

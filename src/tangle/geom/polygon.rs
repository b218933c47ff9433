//! Polygons with holes as highly tessellated closed curves (glam `DVec2`),
//! with booleans, slicing by polylines and offsets from `i_overlay` (the
//! engine under `geo`) and insets from `cavalier_contours` ([`super::offset`]):
//! nothing here clips by hand.
//!
//! A [`Polygon`] is one outer ring (counter-clockwise, y up; clockwise on a
//! y-down screen) and any number of holes (the other way round), rings
//! implicitly closed. Every operation returns polygons normalised the same
//! way, with slivers (rings under [`SLIVER_AREA`]) dropped, so degenerate
//! input (repeated points, zero-area spikes, collinear runs) never reaches
//! a caller as a broken shape. Coordinates must be finite: [`Polygon::new`]
//! refuses anything else, so the engine (which panics on non-finite
//! bounds) is never handed one.
use glam::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::simplify::SimplifyShape;
use i_overlay::float::single::SingleFloatOverlay;
use i_overlay::float::slice::FloatSlice;
use i_overlay::mesh::float::outline::offset::OutlineOffset;
use i_overlay::mesh::float::style::{LineJoin, OutlineStyle};

/// A closed ring of points (the closing edge is implicit).
pub type Ring = Vec<DVec2>;

/// Rings (and pieces) with less area than this are slivers and dropped.
pub const SLIVER_AREA: f64 = 1e-6;

/// Largest coordinate magnitude a polygon may have (far inside the engine's
/// float range, and far beyond any drawing).
pub const MAX_COORD: f64 = 1e9;

/// One polygon with holes: `rings[0]` is the outer ring, the rest holes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polygon {
    pub rings: Vec<Ring>,
}

/// Twice the signed area of a ring (positive = counter-clockwise, y up).
pub fn ring_area2(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    let mut s = 0.0;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        s += a.x * b.y - b.x * a.y;
    }
    s
}

/// Whether `p` is inside the closed ring (even-odd crossings; a point on
/// an edge may go either way).
pub fn ring_contains(r: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let n = r.len();
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (r[i], r[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Length of a closed ring.
pub fn ring_length(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| ring[i].distance(ring[(i + 1) % n])).sum()
}

/// The ring with extra points so that no edge is longer than `step`
/// (`step` ≤ 0 or non-finite: unchanged). Existing points are kept.
pub fn resample_ring(ring: &[DVec2], step: f64) -> Ring {
    resample(ring, step, true)
}

/// A polyline (open) with extra points so that no segment is longer than
/// `step`.
pub fn resample_polyline(line: &[DVec2], step: f64) -> Vec<DVec2> {
    resample(line, step, false)
}

fn resample(pts: &[DVec2], step: f64, closed: bool) -> Vec<DVec2> {
    if !(step.is_finite() && step > 0.0) || pts.len() < 2 {
        return pts.to_vec();
    }
    let n = pts.len();
    let edges = if closed { n } else { n - 1 };
    let mut out = Vec::with_capacity(n);
    for i in 0..edges {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        out.push(a);
        // Bounded: a drawing is at most ~1e9 units and `step` is a
        // caller's sampling resolution, so cap pieces per edge.
        let k = ((a.distance(b) / step).ceil() as usize).clamp(1, 100_000);
        for j in 1..k {
            out.push(a.lerp(b, j as f64 / k as f64));
        }
    }
    if !closed {
        out.push(pts[n - 1]);
    }
    out
}

impl Polygon {
    /// A polygon from rings in any orientation and any nesting (even-odd):
    /// normalised, slivers dropped. Several polygons when the rings describe
    /// several (e.g. a figure eight). `None` when a coordinate is not
    /// finite or beyond [`MAX_COORD`].
    pub fn new(rings: Vec<Ring>) -> Option<Vec<Polygon>> {
        Self::filled(rings, FillRule::EvenOdd)
    }

    /// As [`Polygon::new`], filled by the nonzero winding rule: a ring
    /// inside another is a hole only when it winds the other way.
    pub fn new_nonzero(rings: Vec<Ring>) -> Option<Vec<Polygon>> {
        Self::filled(rings, FillRule::NonZero)
    }

    fn filled(rings: Vec<Ring>, rule: FillRule) -> Option<Vec<Polygon>> {
        if !rings
            .iter()
            .flatten()
            .all(|p| p.is_finite() && p.abs().max_element() <= MAX_COORD)
        {
            return None;
        }
        Some(from_shapes(rings.simplify_shape(rule)))
    }

    /// An axis-aligned rectangle.
    pub fn rect(min: DVec2, max: DVec2) -> Polygon {
        Polygon {
            rings: vec![vec![
                min,
                DVec2::new(max.x, min.y),
                max,
                DVec2::new(min.x, max.y),
            ]],
        }
    }

    /// A circle as a regular `n`-gon (n ≥ 3).
    pub fn circle(c: DVec2, r: f64, n: usize) -> Polygon {
        let n = n.max(3);
        Polygon {
            rings: vec![(0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    c + r * DVec2::new(t.cos(), t.sin())
                })
                .collect()],
        }
    }

    /// Area (outer minus holes), ≥ 0.
    pub fn area(&self) -> f64 {
        self.rings.iter().map(|r| ring_area2(r)).sum::<f64>().abs() * 0.5
    }

    /// Number of points over all rings.
    pub fn vertices(&self) -> usize {
        self.rings.iter().map(Vec::len).sum()
    }

    /// Bounding box `(min, max)` (zeros for an empty polygon).
    pub fn bbox(&self) -> (DVec2, DVec2) {
        let mut it = self.rings.iter().flatten();
        let Some(&first) = it.next() else {
            return (DVec2::ZERO, DVec2::ZERO);
        };
        it.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// The box (min, max) around polygons (infinite and inverted for none).
    pub fn bbox_all<'a>(polys: impl IntoIterator<Item = &'a Polygon>) -> (DVec2, DVec2) {
        polys.into_iter().map(Polygon::bbox).fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(a, b), (c, d)| (a.min(c), b.max(d)),
        )
    }

    /// Area centroid (the bounding box centre for a degenerate polygon).
    pub fn centroid(&self) -> DVec2 {
        let (mut a, mut c) = (0.0, DVec2::ZERO);
        for r in &self.rings {
            let n = r.len();
            for i in 0..n {
                let (p, q) = (r[i], r[(i + 1) % n]);
                let w = p.x * q.y - q.x * p.y;
                a += w;
                c += (p + q) * w;
            }
        }
        if a.abs() < 1e-12 {
            let (lo, hi) = self.bbox();
            return (lo + hi) * 0.5;
        }
        c / (3.0 * a)
    }

    /// Whether `p` is inside (even-odd over all rings; boundary undefined).
    pub fn contains(&self, p: DVec2) -> bool {
        self.rings.iter().filter(|r| ring_contains(r, p)).count() % 2 == 1
    }

    /// Distance from `p` to the nearest boundary point.
    pub fn boundary_distance(&self, p: DVec2) -> f64 {
        let mut d2 = f64::INFINITY;
        for r in &self.rings {
            let n = r.len();
            for i in 0..n {
                let (a, b) = (r[i], r[(i + 1) % n]);
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
                d2 = d2.min(p.distance_squared(a + ab * t));
            }
        }
        d2.sqrt()
    }

    /// `self ∩ other`.
    pub fn intersect(&self, other: &Polygon) -> Vec<Polygon> {
        self.boolean(other, OverlayRule::Intersect)
    }

    /// `self − other`.
    pub fn difference(&self, other: &Polygon) -> Vec<Polygon> {
        self.boolean(other, OverlayRule::Difference)
    }

    /// `self − ⋃ others`.
    pub fn difference_all(&self, others: &[Polygon]) -> Vec<Polygon> {
        if others.is_empty() {
            return vec![self.clone()];
        }
        let clip: Vec<Vec<Ring>> = others.iter().map(|p| p.rings.clone()).collect();
        from_shapes(
            self.rings
                .overlay(&clip, OverlayRule::Difference, FillRule::NonZero),
        )
    }

    /// `self − ⋃ inner` for pieces the caller knows lie strictly inside
    /// `self` (apart from its boundary, as an inset does): when neither
    /// `self` nor any piece has holes and the pieces' boxes are apart, the
    /// result is `self`'s outline with each piece's outline as a hole, made
    /// directly (no boolean: an outline step's most common case, and the
    /// same region [`Polygon::difference_all`] gives). Anything else goes
    /// through [`Polygon::difference_all`].
    pub fn minus_inside(&self, inner: &[Polygon]) -> Vec<Polygon> {
        let simple = self.rings.len() == 1 && inner.iter().all(|p| p.rings.len() == 1);
        let boxes: Vec<(DVec2, DVec2)> = inner.iter().map(Polygon::bbox).collect();
        let (lo, hi) = self.bbox();
        let apart = |(a0, a1): (DVec2, DVec2), (b0, b1): (DVec2, DVec2)| {
            a1.x < b0.x || b1.x < a0.x || a1.y < b0.y || b1.y < a0.y
        };
        let direct = simple
            && boxes
                .iter()
                .all(|&(b0, b1)| b0.x > lo.x && b0.y > lo.y && b1.x < hi.x && b1.y < hi.y)
            && (0..boxes.len()).all(|i| (0..i).all(|j| apart(boxes[i], boxes[j])));
        if !direct {
            return self.difference_all(inner);
        }
        let mut rings = Vec::with_capacity(1 + inner.len());
        rings.push(self.rings[0].clone());
        rings.extend(
            inner
                .iter()
                .map(|p| p.rings[0].iter().rev().copied().collect()),
        );
        vec![Polygon { rings }]
    }

    /// The union of polygons.
    pub fn union_all(polys: &[Polygon]) -> Vec<Polygon> {
        let all: Vec<Vec<Ring>> = polys.iter().map(|p| p.rings.clone()).collect();
        from_shapes(all.simplify_shape(FillRule::NonZero))
    }

    fn boolean(&self, other: &Polygon, rule: OverlayRule) -> Vec<Polygon> {
        from_shapes(self.rings.overlay(&other.rings, rule, FillRule::NonZero))
    }

    /// The pieces the polygon falls into when cut along the polylines
    /// (open curves; parts outside the polygon are ignored). The pieces
    /// tile the polygon: their areas sum to its area.
    pub fn slice(&self, cuts: &[Vec<DVec2>]) -> Vec<Polygon> {
        let cuts: Vec<&Vec<DVec2>> = cuts.iter().filter(|c| c.len() >= 2).collect();
        if cuts.is_empty() {
            return vec![self.clone()];
        }
        let paths: Vec<Vec<DVec2>> = cuts.into_iter().cloned().collect();
        from_shapes(self.rings.slice_by(&paths, FillRule::NonZero))
    }

    /// The polygon grown (`d` > 0) or shrunk (`d` < 0) by `|d|`, corners
    /// mitred (bevelled where sharper than 30°).
    pub fn offset(&self, d: f64) -> Vec<Polygon> {
        if !d.is_finite() {
            return vec![];
        }
        if d == 0.0 {
            return vec![self.clone()];
        }
        let style = OutlineStyle::new(d).line_join(LineJoin::Miter(std::f64::consts::PI / 6.0));
        from_shapes(self.rings.outline(&style))
    }

    /// The polygon with points added so that no edge exceeds `step`.
    pub fn resampled(&self, step: f64) -> Polygon {
        Polygon {
            rings: self.rings.iter().map(|r| resample_ring(r, step)).collect(),
        }
    }

    /// Every point moved by `f`, then normalised again (a displacement can
    /// fold a thin part over itself).
    pub fn map_points(&self, f: impl Fn(DVec2) -> DVec2) -> Vec<Polygon> {
        let rings = self
            .rings
            .iter()
            .map(|r| r.iter().map(|&p| f(p)).collect())
            .collect();
        Polygon::new(rings).unwrap_or_default()
    }
}

/// Engine output → polygons, slivers dropped.
fn from_shapes(shapes: Vec<Vec<Vec<DVec2>>>) -> Vec<Polygon> {
    shapes
        .into_iter()
        .filter_map(|rings| {
            let mut rings: Vec<Ring> = rings
                .into_iter()
                .filter(|r| r.len() >= 3 && ring_area2(r).abs() * 0.5 >= SLIVER_AREA)
                .collect();
            if rings.is_empty() {
                return None;
            }
            // The engine gives the outer ring first; keep that contract
            // even if the first ring was dropped as a sliver.
            let outer = (0..rings.len())
                .max_by(|&a, &b| {
                    ring_area2(&rings[a])
                        .abs()
                        .total_cmp(&ring_area2(&rings[b]).abs())
                })
                .unwrap_or(0);
            rings.swap(0, outer);
            let p = Polygon { rings };
            (p.area() >= SLIVER_AREA).then_some(p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sq(x: f64, y: f64, s: f64) -> Polygon {
        Polygon::rect(DVec2::new(x, y), DVec2::new(x + s, y + s))
    }

    #[test]
    fn a_square_with_a_hole_has_the_right_area_and_inside() {
        let p = Polygon::new(vec![
            sq(0.0, 0.0, 10.0).rings[0].clone(),
            sq(2.0, 2.0, 4.0).rings[0].clone(),
        ])
        .unwrap();
        assert_eq!(p.len(), 1);
        assert!((p[0].area() - 84.0).abs() < 1e-9);
        assert!(p[0].contains(DVec2::new(1.0, 1.0)));
        assert!(!p[0].contains(DVec2::new(3.0, 3.0)));
        assert!(
            ring_area2(&p[0].rings[0]) > 0.0,
            "outer ring counter-clockwise"
        );
        assert!(ring_area2(&p[0].rings[1]) < 0.0, "hole clockwise");
    }

    #[test]
    fn non_finite_points_are_refused_and_slivers_dropped() {
        let bad = vec![vec![DVec2::ZERO, DVec2::new(f64::NAN, 1.0), DVec2::ONE]];
        assert!(Polygon::new(bad).is_none());
        let flat = vec![vec![
            DVec2::ZERO,
            DVec2::new(5.0, 0.0),
            DVec2::new(10.0, 0.0),
        ]];
        assert!(Polygon::new(flat).unwrap().is_empty());
    }

    #[test]
    fn a_line_through_a_square_cuts_it_in_two_halves() {
        let s = sq(0.0, 0.0, 10.0);
        let parts = s.slice(&[vec![DVec2::new(-1.0, 4.0), DVec2::new(11.0, 4.0)]]);
        assert_eq!(parts.len(), 2);
        let mut a: Vec<f64> = parts.iter().map(Polygon::area).collect();
        a.sort_by(f64::total_cmp);
        assert!(
            (a[0] - 40.0).abs() < 1e-6 && (a[1] - 60.0).abs() < 1e-6,
            "{a:?}"
        );
    }

    #[test]
    fn an_inset_square_is_smaller_by_the_distance() {
        let parts = sq(0.0, 0.0, 10.0).inset(2.0);
        assert_eq!(parts.len(), 1);
        assert!((parts[0].area() - 36.0).abs() < 0.05, "{}", parts[0].area());
        assert!(sq(0.0, 0.0, 10.0).inset(6.0).is_empty());
    }

    fn arb_poly() -> impl Strategy<Value = Polygon> {
        proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 3..12).prop_filter_map(
            "degenerate",
            |pts| {
                let ring = pts.into_iter().map(|(x, y)| DVec2::new(x, y)).collect();
                Polygon::new(vec![ring])?.into_iter().next()
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Cutting along any polylines conserves area and the pieces do not
        /// overlap (their union has the sum of their areas).
        #[test]
        fn slicing_conserves_area(p in arb_poly(),
            cut in proptest::collection::vec((-60.0f64..60.0, -60.0f64..60.0), 2..6)) {
            let cut: Vec<DVec2> = cut.into_iter().map(|(x, y)| DVec2::new(x, y)).collect();
            let parts = p.slice(&[cut]);
            let sum: f64 = parts.iter().map(Polygon::area).sum();
            prop_assert!((sum - p.area()).abs() <= 1e-3 * p.area().max(1.0), "{sum} vs {}", p.area());
            let union: f64 = Polygon::union_all(&parts).iter().map(Polygon::area).sum();
            prop_assert!((union - sum).abs() <= 1e-3 * sum.max(1.0), "overlap: {union} vs {sum}");
        }

        /// An inset lies inside the polygon; inset + ring = the polygon.
        #[test]
        fn inset_and_remainder_tile_the_polygon(p in arb_poly(), d in 0.1f64..5.0) {
            let inner = p.inset(d);
            let ring = p.difference_all(&inner);
            let a_in: f64 = inner.iter().map(Polygon::area).sum();
            let a_ring: f64 = ring.iter().map(Polygon::area).sum();
            prop_assert!(a_in <= p.area() + 1e-6);
            prop_assert!((a_in + a_ring - p.area()).abs() <= 1e-3 * p.area().max(1.0));
        }

        /// The ring made directly from an inset's outlines is the region the
        /// boolean difference gives: the same area, the same points inside,
        /// and its holes wind clockwise.
        #[test]
        fn the_direct_ring_is_the_boolean_difference(p in arb_poly(), d in 0.1f64..5.0,
            probes in proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 64)) {
            let inner = p.inset(d);
            let direct = p.minus_inside(&inner);
            let boolean = p.difference_all(&inner);
            let area = |ps: &[Polygon]| ps.iter().map(Polygon::area).sum::<f64>();
            prop_assert!((area(&direct) - area(&boolean)).abs() <= 1e-6 * p.area().max(1.0));
            for (x, y) in probes {
                let q = DVec2::new(x, y);
                // Points within rounding of an edge may fall either way.
                if direct.iter().chain(&boolean).any(|r| r.boundary_distance(q) < 1e-6) {
                    continue;
                }
                let inside = |ps: &[Polygon]| ps.iter().any(|r| r.contains(q));
                prop_assert_eq!(inside(&direct), inside(&boolean), "at {:?}", q);
            }
            for r in &direct {
                prop_assert!(ring_area2(&r.rings[0]) > 0.0);
                prop_assert!(r.rings[1..].iter().all(|h| ring_area2(h) < 0.0));
            }
        }
    }
}

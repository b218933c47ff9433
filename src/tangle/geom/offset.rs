//! Insets of polygons with holes by `cavalier_contours` (a polyline-offset
//! crate: each ring's offset segments and arc joins, trimmed where they
//! meet, without a general boolean overlay), over [`Lf64`], an `f64` whose
//! transcendental functions are the `libm` crate's.
//!
//! Why the number type: the engine is generic over its float type and
//! computes its arc joins with `atan2`, `tan`, `sin` and `cos`. For `f64`
//! those are `std`'s, which call the platform's maths library natively
//! (glibc) and Rust's own port of musl's in wasm; the two can differ in the
//! last bit, and then native and wasm tangles would differ. Routed through
//! [`Lf64`], both run the same `libm` code and give the same bytes. The
//! correctly rounded operations (`+ − × ÷`, `sqrt`, `floor`, …) are the
//! same everywhere and stay plain `f64` ones.
//!
//! An inset's joins: where a ring turns away from the inside (a reflex
//! corner of the outline, a convex corner of a hole) the offset is a
//! circular arc of radius `d`, flattened here to chords within
//! [`arc_tolerance`] of it; elsewhere offset edges are trimmed where they
//! meet, so convex corners stay sharp.
use super::polygon::{ring_area2, ring_contains, Polygon, Ring, SLIVER_AREA};
use cavalier_contours::core::traits::{FuzzyEq, FuzzyOrd, Real};
use cavalier_contours::polyline::{
    PlineCreation, PlineOrientation, PlineSource, PlineSourceMut, Polyline,
};
use cavalier_contours::shape_algorithms::{Shape, ShapeOffsetOptions};
use glam::DVec2;
use num_traits::{Bounded, Float, Num, NumCast, One, ToPrimitive, Zero};
use std::num::FpCategory;
use std::ops::{Add, Div, Mul, Neg, Rem, Sub};

/// An `f64` whose transcendental functions are the `libm` crate's, so that
/// code generic over its float type computes the same bits natively and in
/// wasm (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
#[repr(transparent)]
pub struct Lf64(pub f64);

macro_rules! binary_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl $tr for Lf64 {
            type Output = Lf64;
            #[inline]
            fn $f(self, o: Lf64) -> Lf64 {
                Lf64(self.0 $op o.0)
            }
        }
    )*};
}
binary_ops!(Add add +, Sub sub -, Mul mul *, Div div /, Rem rem %);

impl Neg for Lf64 {
    type Output = Lf64;
    #[inline]
    fn neg(self) -> Lf64 {
        Lf64(-self.0)
    }
}

impl Zero for Lf64 {
    fn zero() -> Self {
        Lf64(0.0)
    }
    fn is_zero(&self) -> bool {
        self.0 == 0.0
    }
}

impl One for Lf64 {
    fn one() -> Self {
        Lf64(1.0)
    }
}

impl Num for Lf64 {
    type FromStrRadixErr = num_traits::ParseFloatError;
    fn from_str_radix(s: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        f64::from_str_radix(s, radix).map(Lf64)
    }
}

impl ToPrimitive for Lf64 {
    fn to_i64(&self) -> Option<i64> {
        self.0.to_i64()
    }
    fn to_u64(&self) -> Option<u64> {
        self.0.to_u64()
    }
    fn to_f64(&self) -> Option<f64> {
        Some(self.0)
    }
}

impl NumCast for Lf64 {
    fn from<T: ToPrimitive>(n: T) -> Option<Self> {
        n.to_f64().map(Lf64)
    }
}

impl Bounded for Lf64 {
    fn min_value() -> Self {
        Lf64(f64::MIN)
    }
    fn max_value() -> Self {
        Lf64(f64::MAX)
    }
}

/// Methods that are one `libm` function of the value(s).
macro_rules! libm_fns {
    ($($f:ident => $l:ident),*) => {$(
        #[inline]
        fn $f(self) -> Self {
            Lf64(libm::$l(self.0))
        }
    )*};
}

/// Methods that are the same `f64` method (exact or correctly rounded
/// everywhere, or not arithmetic at all).
macro_rules! f64_fns {
    ($($f:ident -> $t:ty),*) => {$(
        #[inline]
        fn $f(self) -> $t {
            self.0.$f().into()
        }
    )*};
}

impl From<f64> for Lf64 {
    fn from(v: f64) -> Self {
        Lf64(v)
    }
}

impl Float for Lf64 {
    fn nan() -> Self {
        Lf64(f64::NAN)
    }
    fn infinity() -> Self {
        Lf64(f64::INFINITY)
    }
    fn neg_infinity() -> Self {
        Lf64(f64::NEG_INFINITY)
    }
    fn neg_zero() -> Self {
        Lf64(-0.0)
    }
    fn min_value() -> Self {
        Lf64(f64::MIN)
    }
    fn min_positive_value() -> Self {
        Lf64(f64::MIN_POSITIVE)
    }
    fn epsilon() -> Self {
        Lf64(f64::EPSILON)
    }
    fn max_value() -> Self {
        Lf64(f64::MAX)
    }
    f64_fns!(is_nan -> bool, is_infinite -> bool, is_finite -> bool, is_normal -> bool,
        is_sign_positive -> bool, is_sign_negative -> bool, classify -> FpCategory,
        floor -> Lf64, ceil -> Lf64, round -> Lf64, trunc -> Lf64, fract -> Lf64,
        abs -> Lf64, signum -> Lf64, sqrt -> Lf64, recip -> Lf64,
        to_degrees -> Lf64, to_radians -> Lf64);
    libm_fns!(exp => exp, exp2 => exp2, ln => log, log2 => log2, log10 => log10,
        cbrt => cbrt, sin => sin, cos => cos, tan => tan, asin => asin, acos => acos,
        atan => atan, exp_m1 => expm1, ln_1p => log1p, sinh => sinh, cosh => cosh,
        tanh => tanh, asinh => asinh, acosh => acosh, atanh => atanh);
    fn mul_add(self, a: Self, b: Self) -> Self {
        // Not fused: fma is correctly rounded everywhere, but slow where
        // the machine lacks it, and nothing here needs the extra bits.
        Lf64(self.0 * a.0 + b.0)
    }
    fn powi(self, n: i32) -> Self {
        // std's `powi` is LLVM's, whose rounding is not specified.
        Lf64(libm::pow(self.0, <f64 as From<i32>>::from(n)))
    }
    fn powf(self, n: Self) -> Self {
        Lf64(libm::pow(self.0, n.0))
    }
    fn log(self, base: Self) -> Self {
        Lf64(libm::log(self.0) / libm::log(base.0))
    }
    fn max(self, o: Self) -> Self {
        Lf64(self.0.max(o.0))
    }
    fn min(self, o: Self) -> Self {
        Lf64(self.0.min(o.0))
    }
    fn abs_sub(self, o: Self) -> Self {
        Lf64((self.0 - o.0).max(0.0))
    }
    fn hypot(self, o: Self) -> Self {
        Lf64(libm::hypot(self.0, o.0))
    }
    fn atan2(self, o: Self) -> Self {
        Lf64(libm::atan2(self.0, o.0))
    }
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = libm::sincos(self.0);
        (Lf64(s), Lf64(c))
    }
    fn integer_decode(self) -> (u64, i16, i8) {
        self.0.integer_decode()
    }
}

impl FuzzyEq for Lf64 {
    fn fuzzy_epsilon() -> Self {
        Lf64(f64::fuzzy_epsilon())
    }
    fn fuzzy_eq_eps(&self, other: Self, eps: Self) -> bool {
        self.0.fuzzy_eq_eps(other.0, eps.0)
    }
    fn fuzzy_eq_zero_eps(&self, eps: Self) -> bool {
        self.0.fuzzy_eq_zero_eps(eps.0)
    }
}

impl FuzzyOrd for Lf64 {
    fn fuzzy_gt_eps(&self, other: Self, eps: Self) -> bool {
        self.0.fuzzy_gt_eps(other.0, eps.0)
    }
    fn fuzzy_lt_eps(&self, other: Self, eps: Self) -> bool {
        self.0.fuzzy_lt_eps(other.0, eps.0)
    }
}

impl static_aabb2d_index::IndexableNum for Lf64 {
    fn total_cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl Real for Lf64 {}

/// How far an inset's flattened arc joins may lie from the true arcs: 1%
/// of the distance, at most 0.05 (the drawing unit's flattening) and at
/// least 1e-4.
pub fn arc_tolerance(d: f64) -> f64 {
    (0.01 * d).clamp(1e-4, 0.05)
}

/// Points closer than this along a ring are one point for the engine.
const SAME_POINT: f64 = 1e-7;

/// The ring as the engine's closed polyline (straight segments), with
/// repeated points dropped; `None` when fewer than three remain.
fn to_pline(ring: &[DVec2]) -> Option<Polyline<Lf64>> {
    let mut pl = Polyline::with_capacity(ring.len(), true);
    let mut last: Option<DVec2> = None;
    for &p in ring {
        if last.is_some_and(|q| q.distance_squared(p) <= SAME_POINT * SAME_POINT) {
            continue;
        }
        pl.add(Lf64(p.x), Lf64(p.y), Lf64(0.0));
        last = Some(p);
    }
    while pl.vertex_count() > 1 {
        let (a, b) = (pl.at(0), pl.at(pl.vertex_count() - 1));
        if (a.x.0 - b.x.0).hypot(a.y.0 - b.y.0) > SAME_POINT {
            break;
        }
        pl.remove_last();
    }
    (pl.vertex_count() >= 3).then_some(pl)
}

/// The engine's polyline (arcs flattened) as a ring.
fn to_ring(pl: &Polyline<Lf64>, tolerance: f64) -> Option<Ring> {
    let lines = pl.arcs_to_approx_lines(Lf64(tolerance))?;
    Some(
        lines
            .iter_vertexes()
            .map(|v| DVec2::new(v.x.0, v.y.0))
            .collect(),
    )
}

/// The polygon shrunk by `d` > 0 (see the module docs for its corners):
/// none when it vanishes, several when it pinches off, holes with the
/// outline they lie in. `None` when the engine cannot take the input (a
/// ring crossing itself or another), for the caller to inset another way.
pub fn inset(poly: &Polygon, d: f64) -> Option<Vec<Polygon>> {
    let mut plines = Vec::with_capacity(poly.rings.len());
    for (i, ring) in poly.rings.iter().enumerate() {
        let Some(pl) = to_pline(ring) else {
            // A degenerate outline has no inside to inset; a degenerate
            // hole takes nothing from it.
            if i == 0 {
                return Some(vec![]);
            }
            continue;
        };
        plines.push(pl);
    }
    let tol = arc_tolerance(d);
    if poly.rings.len() == 1 {
        // One ring: the polyline's own offset, without the shape's
        // stitching between rings (a fifth of the work).
        let Some(pl) = plines.pop() else {
            return Some(vec![]);
        };
        if pl.orientation() != PlineOrientation::CounterClockwise {
            return None;
        }
        let (mut outers, mut holes) = (vec![], vec![]);
        for r in pl
            .parallel_offset(Lf64(d))
            .iter()
            .filter_map(|p| to_ring(p, tol))
        {
            let a = ring_area2(&r);
            if r.len() >= 3 && a.abs() * 0.5 >= SLIVER_AREA {
                if a > 0.0 {
                    outers.push(r)
                } else {
                    holes.push(r)
                }
            }
        }
        return Some(merge_touching(assemble(outers, holes)));
    }
    let shape = Shape::from_plines(plines);
    // The outer ring must be counter-clockwise and the holes clockwise.
    if shape.ccw_plines.len() != 1 || shape.cw_plines.len() + 1 != poly.rings.len() {
        return None;
    }
    let out = shape.parallel_offset(Lf64(d), &ShapeOffsetOptions::default());
    let rings = |v: &[cavalier_contours::shape_algorithms::IndexedPolyline<Lf64>]| -> Vec<Ring> {
        v.iter()
            .filter_map(|ip| to_ring(&ip.polyline, tol))
            .filter(|r| r.len() >= 3 && ring_area2(r).abs() * 0.5 >= SLIVER_AREA)
            .collect()
    };
    let (outers, holes) = (rings(&out.ccw_plines), rings(&out.cw_plines));
    Some(merge_touching(assemble(outers, holes)))
}

/// The inset's pieces, with pieces that touch or overlap made one. The
/// engine sometimes closes one inset outline as two loops that share an
/// edge (the leaf example, seed 1: one square's inset came back as a
/// pentagon and a triangle along its diagonal, drawn with a line across
/// it). Pieces whose boxes meet are united; a group whose union has as many
/// pieces as it had (pieces that truly pinched off) is kept as it was, so
/// only a split outline changes.
fn merge_touching(polys: Vec<Polygon>) -> Vec<Polygon> {
    if polys.len() < 2 {
        return polys;
    }
    let boxes: Vec<(DVec2, DVec2)> = polys.iter().map(Polygon::bbox).collect();
    let meet = |i: usize, j: usize| {
        let ((a0, a1), (b0, b1)) = (boxes[i], boxes[j]);
        a0.x <= b1.x && b0.x <= a1.x && a0.y <= b1.y && b0.y <= a1.y
    };
    // Groups of pieces whose boxes meet, directly or through others.
    let mut group: Vec<usize> = (0..polys.len()).collect();
    fn root(group: &mut [usize], mut i: usize) -> usize {
        while group[i] != i {
            group[i] = group[group[i]];
            i = group[i];
        }
        i
    }
    for i in 0..polys.len() {
        for j in 0..i {
            if meet(i, j) {
                let (a, b) = (root(&mut group, i), root(&mut group, j));
                group[a.max(b)] = a.min(b);
            }
        }
    }
    let roots: Vec<usize> = (0..polys.len()).map(|i| root(&mut group, i)).collect();
    let mut out = Vec::with_capacity(polys.len());
    for (i, p) in polys.iter().enumerate() {
        if roots[i] != i {
            continue; // taken with its group's first piece
        }
        let members: Vec<Polygon> = (i..polys.len())
            .filter(|&k| roots[k] == i)
            .map(|k| polys[k].clone())
            .collect();
        if members.len() == 1 {
            out.push(p.clone());
            continue;
        }
        let united = Polygon::union_all(&members);
        if united.len() < members.len() {
            out.extend(united);
        } else {
            out.extend(members);
        }
    }
    out
}

/// Outer rings and holes (none crossing another) as polygons: each hole
/// goes with the smallest outline that holds it.
fn assemble(outers: Vec<Ring>, holes: Vec<Ring>) -> Vec<Polygon> {
    let mut polys: Vec<Polygon> = outers
        .into_iter()
        .map(|r| Polygon { rings: vec![r] })
        .collect();
    let areas: Vec<f64> = polys.iter().map(|p| ring_area2(&p.rings[0])).collect();
    for hole in holes {
        let probe = hole[0];
        let owner = (0..polys.len())
            .filter(|&i| ring_contains(&polys[i].rings[0], probe))
            .min_by(|&a, &b| areas[a].total_cmp(&areas[b]));
        if let Some(i) = owner {
            polys[i].rings.push(hole);
        }
    }
    polys
}

// The method lives beside the engine it runs, so `polygon` does not import
// this module back (tests/layers.rs).
impl Polygon {
    /// The polygon shrunk by `d` > 0: none when it vanishes, several when
    /// it pinches off. By `cavalier_contours` ([`inset`]:
    /// the points farther than `d` from the boundary, so sharp at convex
    /// corners and round at reflex ones); a polygon that engine cannot take
    /// (rings wound the wrong way) goes through [`Polygon::offset`].
    pub fn inset(&self, d: f64) -> Vec<Polygon> {
        if !(d.is_finite() && d > 0.0) {
            return self.offset(-d);
        }
        inset(self, d).unwrap_or_else(|| self.offset(-d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ring(pts: &[(f64, f64)]) -> Ring {
        pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    fn area(ps: &[Polygon]) -> f64 {
        ps.iter().map(Polygon::area).sum()
    }

    #[test]
    fn the_number_type_runs_libm_bit_for_bit() {
        for i in 0..1000 {
            let x = (i as f64 - 500.0) * 0.0137;
            let v = Lf64(x);
            assert_eq!(v.sin().0.to_bits(), libm::sin(x).to_bits());
            assert_eq!(v.cos().0.to_bits(), libm::cos(x).to_bits());
            assert_eq!(v.tan().0.to_bits(), libm::tan(x).to_bits());
            assert_eq!(v.atan().0.to_bits(), libm::atan(x).to_bits());
            assert_eq!(
                v.atan2(Lf64(0.3)).0.to_bits(),
                libm::atan2(x, 0.3).to_bits()
            );
            assert_eq!(
                Lf64(x / 7.0).acos().0.to_bits(),
                libm::acos(x / 7.0).to_bits()
            );
            assert_eq!(v.powi(3).0.to_bits(), libm::pow(x, 3.0).to_bits());
        }
    }

    /// An L (a 20×20 square less its 10×10 top-right quarter) inset by 2:
    /// the points at least 2 from every edge, so round around the reflex
    /// corner (10, 10), where a mitred inset would be square.
    #[test]
    fn an_l_shape_is_inset_with_a_round_inner_corner() {
        let l = Polygon {
            rings: vec![ring(&[
                (0.0, 0.0),
                (20.0, 0.0),
                (20.0, 10.0),
                (10.0, 10.0),
                (10.0, 20.0),
                (0.0, 20.0),
            ])],
        };
        let d = 2.0;
        let parts = inset(&l, d).expect("a simple ccw polygon");
        assert_eq!(parts.len(), 1);
        // Two 16×6 arms less their 6×6 overlap, plus the 2×2 square between
        // the arms' ends less the quarter disc of radius 2 around (10, 10);
        // chords cut inside the arc, so a little more.
        let want = 2.0 * 16.0 * 6.0 - 36.0 + 4.0 - std::f64::consts::PI;
        let got = parts[0].area();
        assert!(got >= want && got < want + 0.05, "{got} vs {want}");
        // (9.2, 9.2) is 1.13 from the corner: out (a mitre would hold it).
        assert!(!parts[0].contains(DVec2::new(9.2, 9.2)));
        assert!(parts[0].contains(DVec2::new(8.5, 8.5)));
    }

    #[test]
    fn a_hole_grows_and_a_waist_pinches_off() {
        let framed = Polygon {
            rings: vec![
                ring(&[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]),
                ring(&[(4.0, 4.0), (4.0, 6.0), (6.0, 6.0), (6.0, 4.0)]),
            ],
        };
        let parts = inset(&framed, 1.0).unwrap();
        assert_eq!(parts.len(), 1);
        assert_eq!(parts[0].rings.len(), 2, "the hole stays a hole");
        assert!(ring_area2(&parts[0].rings[0]) > 0.0 && ring_area2(&parts[0].rings[1]) < 0.0);
        // 8×8 less the hole grown to 4×4 with round corners.
        let want = 64.0 - (16.0 - (4.0 - std::f64::consts::PI));
        assert!((area(&parts) - want).abs() < 0.05, "{}", area(&parts));
        // The frame's sides are 4 wide: an inset of 2.5 leaves nothing.
        assert!(inset(&framed, 2.5).unwrap().is_empty());

        // Two 10×10 squares joined by a 2-wide waist.
        let dumbbell = Polygon {
            rings: vec![ring(&[
                (0.0, 0.0),
                (10.0, 0.0),
                (10.0, 4.0),
                (14.0, 4.0),
                (14.0, 0.0),
                (24.0, 0.0),
                (24.0, 10.0),
                (14.0, 10.0),
                (14.0, 6.0),
                (10.0, 6.0),
                (10.0, 10.0),
                (0.0, 10.0),
            ])],
        };
        assert_eq!(inset(&dumbbell, 0.5).unwrap().len(), 1);
        let pieces = inset(&dumbbell, 1.5).unwrap();
        assert_eq!(pieces.len(), 2, "the waist pinches off");
        // Each is its square's 7×7 core and a sliver reaching towards the
        // waist between the round corners; the two are mirror images.
        for p in &pieces {
            assert!(p.area() > 49.0 && p.area() < 49.5, "{}", p.area());
        }
        assert!((pieces[0].area() - pieces[1].area()).abs() < 1e-9);
    }

    #[test]
    fn degenerate_rings_give_nothing_and_wrong_windings_are_refused() {
        let flat = Polygon {
            rings: vec![ring(&[(0.0, 0.0), (1.0, 0.0), (1.0, 0.0), (0.0, 0.0)])],
        };
        assert_eq!(inset(&flat, 0.1), Some(vec![]));
        // Wound clockwise: not the engine's contract, the caller falls back.
        let cw = Polygon {
            rings: vec![ring(&[(0.0, 0.0), (0.0, 10.0), (10.0, 10.0), (10.0, 0.0)])],
        };
        assert_eq!(inset(&cw, 1.0), None);
    }

    /// Random polygons with random holes, as `Polygon::new` normalises
    /// them (pinches, spikes and nested rings included).
    fn arb_shape() -> impl Strategy<Value = Polygon> {
        let pts = || proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 3..14);
        (pts(), proptest::collection::vec(pts(), 0..3)).prop_filter_map(
            "degenerate",
            |(outer, holes)| {
                let scale = |r: Vec<(f64, f64)>, s: f64| -> Ring {
                    r.into_iter()
                        .map(|(x, y)| DVec2::new(x * s, y * s))
                        .collect()
                };
                let mut rings = vec![scale(outer, 1.0)];
                rings.extend(holes.into_iter().map(|h| scale(h, 0.4)));
                Polygon::new(rings)?.into_iter().next()
            },
        )
    }

    /// A densely sampled wobbly outline, as tangle shapes are (a radius
    /// that waves with the angle, each point jittered), with or without a
    /// wobbly hole in the middle.
    fn arb_wobbly() -> impl Strategy<Value = Polygon> {
        (
            60usize..400,
            2.0f64..9.0,
            0.0f64..0.35,
            proptest::collection::vec(-1.0f64..1.0, 400),
            any::<bool>(),
        )
            .prop_filter_map("degenerate", |(n, k, a, jitter, hole)| {
                let ring = |r0: f64, n: usize, sign: f64| -> Ring {
                    (0..n)
                        .map(|i| {
                            let t = sign * std::f64::consts::TAU * i as f64 / n as f64;
                            let r = r0 * (1.0 + a * (k * t).sin()) + 0.3 * jitter[i % 400];
                            DVec2::new(r * t.cos(), r * t.sin())
                        })
                        .collect()
                };
                let mut rings = vec![ring(40.0, n, 1.0)];
                if hole {
                    rings.push(ring(8.0, n / 2, -1.0));
                }
                Polygon::new(rings)?.into_iter().next()
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// The same on tangle-like outlines: many points, small turns both
        /// ways, insets that pinch off lobes.
        #[test]
        fn wobbly_outlines_are_inset_by_distance(p in arb_wobbly(), d in 0.2f64..14.0,
            probes in proptest::collection::vec((-55.0f64..55.0, -55.0f64..55.0), 200)) {
            let parts = inset(&p, d).expect("normalised polygons are the engine's input");
            let slack = arc_tolerance(d) + 1e-6;
            for (x, y) in probes {
                let q = DVec2::new(x, y);
                let b = p.boundary_distance(q);
                let inside = parts.iter().filter(|r| r.contains(q)).count();
                prop_assert!(inside <= 1, "pieces overlap at {:?}", q);
                if p.contains(q) && b > d + slack {
                    prop_assert!(inside == 1, "{:?} is {b} from the boundary, d = {d}", q);
                }
                if !p.contains(q) || b < d - slack {
                    prop_assert!(inside == 0, "{:?} is {b} from the boundary, d = {d}", q);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]
        /// The inset is exactly the points of the polygon farther than `d`
        /// from its boundary (up to the arc tolerance and rounding), its
        /// pieces do not overlap, outlines wind counter-clockwise and holes
        /// clockwise; and normalised input never needs the fallback.
        #[test]
        fn the_inset_is_the_points_farther_than_d_from_the_boundary(p in arb_shape(),
            d in 0.05f64..6.0,
            probes in proptest::collection::vec((-50.0f64..50.0, -50.0f64..50.0), 200)) {
            let parts = inset(&p, d).expect("normalised polygons are the engine's input");
            let slack = arc_tolerance(d) + 1e-6;
            for (x, y) in probes {
                let q = DVec2::new(x, y);
                let far = p.contains(q) && p.boundary_distance(q) > d + slack;
                let near = !p.contains(q) || p.boundary_distance(q) < d - slack;
                let inside = parts.iter().filter(|r| r.contains(q)).count();
                prop_assert!(inside <= 1, "pieces overlap at {:?}", q);
                if far {
                    prop_assert!(inside == 1, "{:?} is {} from the boundary, d = {d}", q, p.boundary_distance(q));
                }
                if near {
                    prop_assert!(inside == 0, "{:?} is {} from the boundary, d = {d}", q, p.boundary_distance(q));
                }
            }
            for r in &parts {
                prop_assert!(ring_area2(&r.rings[0]) > 0.0);
                prop_assert!(r.rings[1..].iter().all(|h| ring_area2(h) < 0.0));
            }
        }
    }
}

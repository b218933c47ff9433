//! 3-D signed distance helpers on glam `DVec3`: primitives, smooth
//! minimum, rotations built from `libm` (so native and wasm give the same
//! bits) and central-difference gradients.
//!
//! Every primitive here is 1-Lipschitz (|f(p) − f(q)| ≤ |p − q|) and is a
//! lower bound of the true distance outside the shape, so sphere tracing it
//! never steps through a surface. Exact where noted.
use glam::{DMat3, DVec2, DVec3};

/// Sphere of radius `r` at the origin (exact).
pub fn sphere(p: DVec3, r: f64) -> f64 {
    p.length() - r
}

/// Axis-aligned box with half sizes `h` at the origin (exact).
pub fn cuboid(p: DVec3, h: DVec3) -> f64 {
    let q = p.abs() - h;
    q.max(DVec3::ZERO).length() + q.x.max(q.y.max(q.z)).min(0.0)
}

/// Ellipsoid with semi-axes `r` (all > 0): the unit sphere's distance in
/// the scaled space times the smallest semi-axis. 1-Lipschitz and a lower
/// bound of the true distance outside (the map `p ↦ p / r` stretches
/// lengths by at most `1 / min r`).
pub fn ellipsoid(p: DVec3, r: DVec3) -> f64 {
    ((p / r).length() - 1.0) * r.min_element()
}

/// Torus in the xy plane: ring radius `major`, tube radius `minor` (exact).
pub fn torus(p: DVec3, major: f64, minor: f64) -> f64 {
    let q = DVec2::new(DVec2::new(p.x, p.y).length() - major, p.z);
    q.length() - minor
}

/// Capped cylinder along z: radius `r`, half height `h` (exact).
pub fn cylinder(p: DVec3, r: f64, h: f64) -> f64 {
    let d = DVec2::new(DVec2::new(p.x, p.y).length() - r, p.z.abs() - h);
    d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
}

/// Hexagonal prism along z: apothem `r` (centre to flat side), half
/// height `h` (exact, after Quilez).
pub fn hex_prism(p: DVec3, r: f64, h: f64) -> f64 {
    const K: DVec3 = DVec3::new(-0.866_025_403_784_438_6, 0.5, 0.577_350_269_189_625_8);
    let mut a = DVec2::new(p.x.abs(), p.y.abs());
    let kxy = DVec2::new(K.x, K.y);
    a -= 2.0 * kxy.dot(a).min(0.0) * kxy;
    let d = DVec2::new(
        (a - DVec2::new(a.x.clamp(-K.z * r, K.z * r), r)).length() * (a.y - r).signum(),
        p.z.abs() - h,
    );
    d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
}

/// Polynomial smooth minimum with blend width `k` (Quilez): equals
/// `min(a, b)` when `|a − b| ≥ k`, at most `k/4` below it otherwise. Its
/// gradient is a convex combination of the inputs' gradients, so it is
/// 1-Lipschitz when both inputs are.
pub fn smin(a: f64, b: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// Smooth maximum, the mirror of [`smin`].
pub fn smax(a: f64, b: f64, k: f64) -> f64 {
    -smin(-a, -b, k)
}

/// Rotation by `angle` (radians) about the unit `axis` (Rodrigues), with
/// `libm` sine and cosine.
pub fn rotation(axis: DVec3, angle: f64) -> DMat3 {
    let (s, c) = (libm::sin(angle), libm::cos(angle));
    let a = axis.normalize_or(DVec3::Z);
    let t = 1.0 - c;
    DMat3::from_cols(
        DVec3::new(
            t * a.x * a.x + c,
            t * a.x * a.y + s * a.z,
            t * a.x * a.z - s * a.y,
        ),
        DVec3::new(
            t * a.x * a.y - s * a.z,
            t * a.y * a.y + c,
            t * a.y * a.z + s * a.x,
        ),
        DVec3::new(
            t * a.x * a.z + s * a.y,
            t * a.y * a.z - s * a.x,
            t * a.z * a.z + c,
        ),
    )
}

/// A uniformly random rotation from three uniform numbers in `[0, 1)`
/// (Shoemake's unit quaternion), with `libm` trigonometry.
pub fn random_rotation(u1: f64, u2: f64, u3: f64) -> DMat3 {
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (x, y) = (a * libm::sin(tau * u2), a * libm::cos(tau * u2));
    let (z, w) = (b * libm::sin(tau * u3), b * libm::cos(tau * u3));
    DMat3::from_quat(glam::DQuat::from_xyzw(x, y, z, w).normalize())
}

/// An upper bound of the spectral norm of `m` (the most it stretches a
/// length): the square root of the largest absolute row sum of `mᵀm`
/// (Gershgorin). Exact for rotations and axis scalings.
pub fn norm_bound(m: DMat3) -> f64 {
    let g = m.transpose() * m;
    let rows = [g.row(0), g.row(1), g.row(2)];
    rows.iter()
        .map(|r| r.x.abs() + r.y.abs() + r.z.abs())
        .fold(0.0, f64::max)
        .sqrt()
}

/// Central-difference gradient of `f` at `p` with step `h` (6 evaluations).
pub fn gradient(f: &mut impl FnMut(DVec3) -> f64, p: DVec3, h: f64) -> DVec3 {
    let dx = DVec3::new(h, 0.0, 0.0);
    let dy = DVec3::new(0.0, h, 0.0);
    let dz = DVec3::new(0.0, 0.0, h);
    DVec3::new(
        f(p + dx) - f(p - dx),
        f(p + dy) - f(p - dy),
        f(p + dz) - f(p - dz),
    ) / (2.0 * h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

    fn lipschitz(f: impl Fn(DVec3) -> f64) {
        let mut r = Rng::new(5);
        for _ in 0..4000 {
            let p = DVec3::new(
                r.range_f64(-2.0, 2.0),
                r.range_f64(-2.0, 2.0),
                r.range_f64(-2.0, 2.0),
            );
            let q = p + DVec3::new(
                r.range_f64(-0.3, 0.3),
                r.range_f64(-0.3, 0.3),
                r.range_f64(-0.3, 0.3),
            );
            assert!(
                (f(p) - f(q)).abs() <= p.distance(q) * (1.0 + 1e-9) + 1e-12,
                "{p} {q}"
            );
        }
    }

    #[test]
    fn primitives_are_one_lipschitz() {
        lipschitz(|p| sphere(p, 0.7));
        lipschitz(|p| cuboid(p, DVec3::new(0.3, 0.5, 0.2)));
        lipschitz(|p| ellipsoid(p, DVec3::new(1.0, 0.4, 0.2)));
        lipschitz(|p| torus(p, 0.6, 0.2));
        lipschitz(|p| cylinder(p, 0.4, 0.8));
        lipschitz(|p| hex_prism(p, 0.5, 0.3));
        lipschitz(|p| smin(sphere(p, 0.5), cuboid(p - DVec3::X, DVec3::splat(0.4)), 0.3));
    }

    #[test]
    fn rotations_are_orthonormal_and_norm_bound_is_exact_for_them() {
        let m = rotation(DVec3::new(1.0, 2.0, 3.0), 0.7);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((norm_bound(m) - 1.0).abs() < 1e-12);
        let r = random_rotation(0.3, 0.6, 0.9);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!((norm_bound(DMat3::from_diagonal(DVec3::new(1.0, 3.0, 2.0))) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn ellipsoid_never_exceeds_the_true_distance_on_an_axis() {
        let r = DVec3::new(1.0, 0.5, 0.25);
        // On the x axis the true distance outside is x − 1.
        for x in [1.1, 1.5, 3.0] {
            assert!(ellipsoid(DVec3::new(x, 0.0, 0.0), r) <= x - 1.0 + 1e-12);
        }
        assert!(ellipsoid(DVec3::ZERO, r) < 0.0);
    }
}

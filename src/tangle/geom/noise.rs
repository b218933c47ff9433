//! Seeded 2-D Perlin gradient noise (Perlin 2002's quintic fade, 32
//! gradient directions), for
//! hand-drawn wobble (Tangle's perturbation). No tables: the gradient at a
//! lattice point is a hash of the point and the seed, so any seed is free
//! and the result is the same natively and in wasm.
use glam::DVec2;

/// Noise in about `[-1, 1]` at `p` (lattice spacing 1), zero at lattice points.
pub fn perlin(p: DVec2, seed: u64) -> f64 {
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let (fx, fy) = (p.x - x0, p.y - y0);
    // Lattice coordinates beyond ±2^52 have no fraction left; wrap them so
    // the integer conversion stays in range.
    let (ix, iy) = ((x0 % 4_294_967_296.0) as i64, (y0 % 4_294_967_296.0) as i64);
    let g = |dx: i64, dy: i64| -> f64 {
        let h = hash(ix.wrapping_add(dx) as u64, iy.wrapping_add(dy) as u64, seed);
        let [gx, gy] = GRADIENTS[(h >> 59) as usize];
        let (ox, oy) = (fx - dx as f64, fy - dy as f64);
        gx * ox + gy * oy
    };
    let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (u, v) = (fade(fx), fade(fy));
    let a = g(0, 0) + u * (g(1, 0) - g(0, 0));
    let b = g(0, 1) + u * (g(1, 1) - g(0, 1));
    // Gradient noise in 2-D peaks at √½; scale to about ±1.
    (a + v * (b - a)) * std::f64::consts::SQRT_2
}

/// 32 unit gradients evenly around the circle (no trigonometry per call,
/// and the same bits on every platform).
const GRADIENTS: [[f64; 2]; 32] = {
    let mut g = [[0.0; 2]; 32];
    let mut i = 0;
    while i < 32 {
        // cos and sin of i·2π/32 from a quarter table.
        let q = [
            1.0,
            0.980_785_280_403_230_4,
            0.923_879_532_511_286_7,
            0.831_469_612_302_545_2,
            std::f64::consts::FRAC_1_SQRT_2,
            0.555_570_233_019_602_2,
            0.382_683_432_365_089_8,
            0.195_090_322_016_128_3,
            0.0,
        ];
        let k = i % 8;
        let (c, s) = (q[k], q[8 - k]);
        g[i] = match i / 8 {
            0 => [c, s],
            1 => [-s, c],
            2 => [-c, -s],
            _ => [s, -c],
        };
        i += 1;
    }
    g
};

/// A 2-D displacement: two independent noises.
pub fn displacement(p: DVec2, seed: u64) -> DVec2 {
    DVec2::new(
        perlin(p, seed),
        perlin(p + DVec2::new(31.416, 47.853), seed ^ 0x9e37_79b9),
    )
}

fn hash(x: u64, y: u64, seed: u64) -> u64 {
    let mut h = seed ^ 0x243f_6a88_85a3_08d3;
    for v in [x, y] {
        h ^= v.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        h = h.rotate_left(31).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 29;
    }
    h ^ (h >> 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_bounded_continuous_and_seeded() {
        let mut max: f64 = 0.0;
        for i in 0..2000 {
            let p = DVec2::new(i as f64 * 0.137, i as f64 * 0.071 - 40.0);
            let n = perlin(p, 7);
            max = max.max(n.abs());
            let q = p + DVec2::splat(1e-4);
            assert!((perlin(q, 7) - n).abs() < 1e-2, "continuous at {p}");
        }
        assert!(max > 0.3 && max <= 1.01, "{max}");
        assert_eq!(perlin(DVec2::new(3.0, -2.0), 1), 0.0);
        let p = DVec2::new(0.3, 0.6);
        assert_ne!(perlin(p, 1), perlin(p, 2));
        assert_eq!(perlin(p, 1), perlin(p, 1));
        assert!(perlin(DVec2::new(1e300, -1e300), 3).is_finite());
    }
}

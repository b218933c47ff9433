//! Exact Euclidean distance transform of a raster mask (Felzenszwalb &
//! Huttenlocher, "Distance Transforms of Sampled Functions", 2012): the
//! lower envelope of parabolas along columns, then rows, in O(w·h).
//!
//! Distances are measured between pixel centres. [`signed_distance`] puts
//! the boundary half a pixel beyond the last inside pixel, so a pixel's
//! value is `d_out − ½` outside and `−(d_in − ½)` inside, which matches an
//! analytic signed field sampled at pixel centres.

/// "No feature pixel": the squared distance [`edt_squared`] reports then.
pub const INF: f64 = 1e20;

/// Squared Euclidean distance from every pixel to the nearest pixel where
/// `feature` (row-major, `w × h`) is true ([`INF`] when there is none).
/// Exact, O(w·h).
///
/// # Panics
/// When `feature.len() != w * h` (a caller's bug, not an input error).
pub fn edt_squared(feature: &[bool], w: usize, h: usize) -> Vec<f64> {
    assert_eq!(Some(feature.len()), w.checked_mul(h), "mask size");
    let mut g: Vec<f64> = feature.iter().map(|&f| if f { 0.0 } else { INF }).collect();
    let mut f = vec![0.0; w.max(h)];
    let mut d = vec![0.0; w.max(h)];
    let mut v = vec![0usize; w.max(h)];
    let mut z = vec![0.0; w.max(h) + 1];
    // Columns.
    for x in 0..w {
        for y in 0..h {
            f[y] = g[y * w + x];
        }
        dt1(&f[..h], &mut d[..h], &mut v, &mut z);
        for y in 0..h {
            g[y * w + x] = d[y];
        }
    }
    // Rows.
    for y in 0..h {
        f[..w].copy_from_slice(&g[y * w..(y + 1) * w]);
        dt1(&f[..w], &mut d[..w], &mut v, &mut z);
        g[y * w..(y + 1) * w].copy_from_slice(&d[..w]);
    }
    g
}

/// 1-D squared distance transform: lower envelope of parabolas.
fn dt1(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    // Only finite samples carry parabolas; with none, everything stays INF.
    let mut k: isize = -1;
    for q in 0..n {
        if f[q] >= INF {
            continue;
        }
        if k < 0 {
            k = 0;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        loop {
            let p = v[k as usize];
            let s =
                ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[k as usize] {
                k -= 1;
                if k < 0 {
                    break;
                }
            } else {
                k += 1;
                v[k as usize] = q;
                z[k as usize] = s;
                z[k as usize + 1] = f64::INFINITY;
                break;
            }
        }
        if k < 0 {
            k = 0;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
        }
    }
    if k < 0 {
        d.iter_mut().for_each(|x| *x = INF);
        return;
    }
    let mut j = 0usize;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[j + 1] < q as f64 {
            j += 1;
        }
        let p = v[j];
        *dq = (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// Signed distance (in pixels) of a mask, negative inside, `±big` where
/// the mask is full or empty.
pub fn signed_distance(mask: &[bool], w: usize, h: usize, big: f64) -> Vec<f64> {
    let outside: Vec<bool> = mask.iter().map(|&m| !m).collect();
    let to_in = edt_squared(mask, w, h);
    let to_out = edt_squared(&outside, w, h);
    mask.iter()
        .enumerate()
        .map(|(i, &m)| {
            if m {
                -(to_out[i].sqrt() - 0.5).min(big)
            } else {
                (to_in[i].sqrt() - 0.5).min(big)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use proptest::prelude::*;

    #[test]
    fn edt_equals_brute_force_on_random_masks() {
        let mut r = Rng::new(3);
        for case in 0..40 {
            let (w, h) = (1 + r.below(23), 1 + r.below(17));
            let density = [0.02, 0.1, 0.5, 0.9][case % 4];
            let m: Vec<bool> = (0..w * h).map(|_| r.f64() < density).collect();
            let got = edt_squared(&m, w, h);
            for y in 0..h {
                for x in 0..w {
                    let mut best = INF;
                    for yy in 0..h {
                        for xx in 0..w {
                            if m[yy * w + xx] {
                                let d =
                                    (x as f64 - xx as f64).powi(2) + (y as f64 - yy as f64).powi(2);
                                best = best.min(d);
                            }
                        }
                    }
                    assert_eq!(got[y * w + x], best, "case {case} {w}x{h} at ({x},{y})");
                }
            }
        }
    }

    #[test]
    fn signed_distance_of_a_disc_is_close_to_analytic() {
        let n = 64;
        let m: Vec<bool> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
                ((x - 32.0).powi(2) + (y - 32.0).powi(2)).sqrt() < 12.0
            })
            .collect();
        let s = signed_distance(&m, n, n, 1e9);
        for (i, v) in s.iter().enumerate() {
            let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
            let exact = ((x - 32.0).powi(2) + (y - 32.0).powi(2)).sqrt() - 12.0;
            assert!((v - exact).abs() < 1.0, "pixel {i}: {v} vs {exact}");
        }
    }

    fn brute(m: &[bool], w: usize, h: usize) -> Vec<f64> {
        let mut out = vec![INF; w * h];
        for y in 0..h {
            for x in 0..w {
                for yy in 0..h {
                    for xx in 0..w {
                        if m[yy * w + xx] {
                            let d = (x as f64 - xx as f64).powi(2) + (y as f64 - yy as f64).powi(2);
                            out[y * w + x] = out[y * w + x].min(d);
                        }
                    }
                }
            }
        }
        out
    }

    /// A random mask: any size up to 24², any density.
    fn mask() -> impl Strategy<Value = (usize, usize, Vec<bool>)> {
        (1usize..=24, 1usize..=24, 0.0f64..=1.0).prop_flat_map(|(w, h, p)| {
            (
                Just(w),
                Just(h),
                proptest::collection::vec(proptest::bool::weighted(p), w * h),
            )
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]
        /// The transform equals brute force exactly on random masks of any
        /// shape and density (empty and full masks included), and the
        /// signed field is consistent with it.
        #[test]
        fn edt_equals_brute_force_property((w, h, m) in mask()) {
            let got = edt_squared(&m, w, h);
            prop_assert_eq!(&got, &brute(&m, w, h));
            // Signed: negative exactly inside, at least half a pixel from 0.
            let s = signed_distance(&m, w, h, 1e9);
            for i in 0..w * h {
                prop_assert!(m[i] == (s[i] < 0.0) && s[i].abs() >= 0.5, "{} at {}", s[i], i);
            }
        }
    }
}

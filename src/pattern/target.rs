//! Target SDFs from a raster image (paper §4 "Target Image SDF", Fig. 8):
//! per-colour binary masks, then an exact Euclidean distance transform of the
//! mask and of its complement (Felzenszwalb & Huttenlocher 2012), combined
//! into a signed field.
//!
//! Distances are measured between pixel centres; the boundary lies half a
//! pixel beyond the last inside pixel, so the signed value of a pixel is
//! `d_out − ½` outside and `−(d_in − ½)` inside, which matches an analytic
//! field sampled at pixel centres.
use super::field::{Scene, CAP};
use super::record::Rgb;
use crate::core::error::{Error, Result};
use crate::raster::Rgba8Image;

const INF: f64 = 1e20;

/// Squared Euclidean distance from every pixel to the nearest pixel where
/// `feature` is true (`1e20` when there is none). Exact, O(w·h).
pub fn edt_squared(feature: &[bool], w: usize, h: usize) -> Vec<f64> {
    assert_eq!(feature.len(), w * h, "mask size");
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

/// A target: per-channel masks and signed fields on the loss grid.
#[derive(Debug, Clone)]
pub struct Target {
    /// Grid side.
    pub n: usize,
    /// Field units per canvas unit (see `LossOptions::units`).
    pub scale: f64,
    /// Channel-major signed fields, same layout as `Evaluator::s`.
    pub sdf: Vec<f64>,
    /// Channel-major masks (1 inside the colour).
    pub mask: Vec<f32>,
    /// Fraction of pixels farther than the tolerance from every palette colour.
    pub unmatched: f64,
}

/// Palette index of every grid pixel: nearest palette colour (RGB distance).
/// Transparent pixels (alpha < 128) count as background. Returns the indices
/// and the fraction of pixels farther than `tolerance` from their colour.
pub fn snap_to_palette(
    img: &Rgba8Image,
    palette: &[Rgb],
    n: usize,
    tolerance: f64,
) -> (Vec<u16>, f64) {
    let mut out = Vec::with_capacity(n * n);
    let mut far = 0usize;
    let (w, h) = (img.width as usize, img.height as usize);
    for y in 0..n {
        for x in 0..n {
            let sx = (((x as f64 + 0.5) * w as f64 / n as f64) as usize).min(w - 1);
            let sy = (((y as f64 + 0.5) * h as f64 / n as f64) as usize).min(h - 1);
            let px = img.get(sx as u32, sy as u32);
            if px[3] < 128 {
                out.push(0);
                continue;
            }
            let mut best = (f64::INFINITY, 0u16);
            for (i, c) in palette.iter().enumerate() {
                let d: f64 = (0..3)
                    .map(|k| (px[k] as f64 - c[k] as f64).powi(2))
                    .sum::<f64>();
                if d < best.0 {
                    best = (d, i as u16);
                }
            }
            if best.0.sqrt() > tolerance {
                far += 1;
            }
            out.push(best.1);
        }
    }
    (out, far as f64 / (n * n) as f64)
}

impl Target {
    /// Build the per-channel target fields from palette indices on an `n × n` grid.
    pub fn from_indices(scene: &Scene, idx: &[u16], n: usize, scale: f64) -> Target {
        let nn = n * n;
        let mut sdf = Vec::with_capacity(scene.channels.len() * nn);
        let mut mask = Vec::with_capacity(scene.channels.len() * nn);
        let px_to_units = scale / n as f64;
        let big = CAP * n as f64;
        for ch in &scene.channels {
            let m: Vec<bool> = idx.iter().map(|&i| i == ch.colour).collect();
            let d = signed_distance(&m, n, n, big);
            sdf.extend(d.iter().map(|v| v * px_to_units));
            mask.extend(m.iter().map(|&b| if b { 1.0f32 } else { 0.0 }));
        }
        Target {
            n,
            scale,
            sdf,
            mask,
            unmatched: 0.0,
        }
    }

    /// Build a target from an image: snap pixels to the program's palette
    /// (background included) and compute the fields. The image is stretched
    /// to the square canvas (nearest neighbour).
    ///
    /// Fails when more than half of the pixels are farther than `tolerance`
    /// (RGB distance, 0..441) from every colour the program uses.
    pub fn from_image(
        scene: &Scene,
        img: &Rgba8Image,
        n: usize,
        scale: f64,
        tolerance: f64,
    ) -> Result<Target> {
        if img.width == 0 || img.height == 0 {
            return Err(Error::input("the target image is empty"));
        }
        let (idx, far) = snap_to_palette(img, &scene.rec.colours, n, tolerance);
        if far > 0.5 {
            let names: Vec<String> = scene
                .rec
                .colours
                .iter()
                .map(|c| format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]))
                .collect();
            return Err(Error::input(format!(
                "{:.0}% of the target's pixels are not close to any colour of the program ({}); \
                 draw the target in these colours or raise the tolerance (now {tolerance})",
                far * 100.0,
                names.join(", ")
            )));
        }
        let mut t = Target::from_indices(scene, &idx, n, scale);
        t.unmatched = far;
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

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
}

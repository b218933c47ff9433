//! Target SDFs from a raster image (paper §4 "Target Image SDF", Fig. 8):
//! per-colour binary masks, then an exact Euclidean distance transform of the
//! mask and of its complement (Felzenszwalb & Huttenlocher 2012), combined
//! into a signed field.
//!
//! The distance transform itself is shared: [`crate::geom::distance_transform`].
use super::field::{Scene, CAP};
use super::record::Rgb;
use crate::core::error::{Error, Result};
use crate::geom::distance_transform::signed_distance;
use crate::raster::Rgba8Image;

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
pub(crate) fn snap_to_palette(
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

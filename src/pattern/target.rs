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

/// Largest side at which an image target's fields are computed before they
/// are sampled onto the loss grid (a bigger image is snapped to this side
/// first). Keeps the distance transforms of a target a few milliseconds.
const MAX_FIELD_SIDE: usize = 512;

/// Palette index of every pixel of an `n × n` grid laid over the image:
/// nearest palette colour (RGB distance) of the image pixel under each grid
/// pixel's centre. Transparent pixels (alpha < 128) count as background.
/// Returns the indices and the fraction of pixels farther than `tolerance`
/// from their colour.
pub(crate) fn snap_to_palette(
    img: &Rgba8Image,
    palette: &[Rgb],
    n: usize,
    tolerance: f64,
) -> (Vec<u16>, f64) {
    snap_to_palette_wh(img, palette, n, n, tolerance)
}

fn snap_to_palette_wh(
    img: &Rgba8Image,
    palette: &[Rgb],
    nw: usize,
    nh: usize,
    tolerance: f64,
) -> (Vec<u16>, f64) {
    let mut out = Vec::with_capacity(nw * nh);
    let mut far = 0usize;
    let (w, h) = (img.width as usize, img.height as usize);
    for y in 0..nh {
        for x in 0..nw {
            let sx = (((x as f64 + 0.5) * w as f64 / nw as f64) as usize).min(w - 1);
            let sy = (((y as f64 + 0.5) * h as f64 / nh as f64) as usize).min(h - 1);
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
    (out, far as f64 / (nw * nh) as f64)
}

/// Value of the `w × h` field `f` at (u, v) in pixel-centre coordinates
/// (pixel i's centre is at i), bilinear, clamped at the borders.
fn bilinear(f: &[f64], w: usize, h: usize, u: f64, v: f64) -> f64 {
    let u = u.clamp(0.0, (w - 1) as f64);
    let v = v.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (u.floor() as usize, v.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (u - x0 as f64, v - y0 as f64);
    let at = |x: usize, y: usize| f[y * w + x];
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
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

    /// The fields of palette indices on a finer `fw × fh` raster covering
    /// the canvas, sampled (bilinear) at the centres of the `n × n` grid.
    /// Masks are where the sampled field is negative.
    fn from_fine_indices(
        scene: &Scene,
        idx: &[u16],
        fw: usize,
        fh: usize,
        n: usize,
        scale: f64,
    ) -> Target {
        let nn = n * n;
        let mut sdf = Vec::with_capacity(scene.channels.len() * nn);
        let mut mask = Vec::with_capacity(scene.channels.len() * nn);
        // A fine pixel is 1/fw of the canvas across and 1/fh down; the
        // distances are measured in pixels of the mean size.
        let px = 1.0 / ((fw * fh) as f64).sqrt();
        let big = CAP / px;
        let (sx, sy) = (fw as f64 / n as f64, fh as f64 / n as f64);
        for ch in &scene.channels {
            let m: Vec<bool> = idx.iter().map(|&i| i == ch.colour).collect();
            let d = signed_distance(&m, fw, fh, big);
            for y in 0..n {
                let v = (y as f64 + 0.5) * sy - 0.5;
                for x in 0..n {
                    let u = (x as f64 + 0.5) * sx - 0.5;
                    let value = bilinear(&d, fw, fh, u, v) * px * scale;
                    sdf.push(value);
                    mask.push(if value < 0.0 { 1.0f32 } else { 0.0 });
                }
            }
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
        // The fields are computed at the image's own resolution (up to
        // MAX_FIELD_SIDE) and sampled at the grid's cell centres, where the
        // pattern's fields are evaluated. Snapping straight onto a coarser
        // grid would take the pixel right of each centre (the centre of a
        // 2×2 block is a pixel corner), shifting every target by half an
        // image pixel.
        let (w, h) = (img.width as usize, img.height as usize);
        let fw = w.min(MAX_FIELD_SIDE.max(n));
        let fh = h.min(MAX_FIELD_SIDE.max(n));
        let (fw, fh) = if fw <= n && fh <= n {
            (n, n)
        } else {
            (fw.max(1), fh.max(1))
        };
        let (idx, far) = snap_to_palette_wh(img, &scene.rec.colours, fw, fh, tolerance);
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
        let mut t = if (fw, fh) == (n, n) {
            Target::from_indices(scene, &idx, n, scale)
        } else {
            Target::from_fine_indices(scene, &idx, fw, fh, n, scale)
        };
        t.unmatched = far;
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};

    /// A black disc on white, drawn at `side`² with each pixel black when its
    /// centre is inside; the disc's exact signed distance in canvas units.
    fn disc(side: u32, c: (f64, f64), r: f64) -> (Scene, Rgba8Image, impl Fn(f64, f64) -> f64) {
        let src = format!(
            "background \"#ffffff\";\nparam r in [0.05, 0.4] = {r};\ncircle({}, {}, r, fill: \"#000000\");",
            c.0, c.1
        );
        let p = Program::parse(&src).unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        let mut img = Rgba8Image::new(side, side);
        let s = side as f64;
        for y in 0..side {
            for x in 0..side {
                let d = ((x as f64 + 0.5) / s - c.0).hypot((y as f64 + 0.5) / s - c.1) - r;
                img.put(
                    x,
                    y,
                    if d < 0.0 {
                        [0, 0, 0, 255]
                    } else {
                        [255, 255, 255, 255]
                    },
                );
            }
        }
        (scene, img, move |x: f64, y: f64| {
            (x - c.0).hypot(y - c.1) - r
        })
    }

    /// Mean signed and largest error (in grid pixels) of the disc's target
    /// field near its edge, against the exact distance at the cell centres.
    fn field_errors(side: u32, n: usize) -> (f64, f64) {
        let (scene, img, exact) = disc(side, (0.48, 0.53), 0.27);
        let t = Target::from_image(&scene, &img, n, n as f64, 60.0).unwrap();
        let k = scene
            .channels
            .iter()
            .position(|ch| scene.rec.colours[ch.colour as usize] == [0, 0, 0])
            .unwrap();
        let f = &t.sdf[k * n * n..(k + 1) * n * n];
        let (mut sum, mut worst, mut count) = (0.0, 0.0f64, 0usize);
        for y in 0..n {
            for x in 0..n {
                let truth =
                    exact((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64) * n as f64;
                if truth.abs() < 3.0 {
                    let e = f[y * n + x] - truth;
                    sum += e;
                    worst = worst.max(e.abs());
                    count += 1;
                }
            }
        }
        (sum / count as f64, worst)
    }

    #[test]
    fn an_image_bigger_than_the_grid_gives_the_field_at_the_cell_centres() {
        // 256 px images on 64 and 128 grids (what the browser sends), and an
        // odd ratio. Snapping to the grid first took the pixel right of and
        // below every cell centre: the disc came out shifted by half an image
        // pixel, a bias the fit then reproduced.
        for (side, n) in [(256, 64), (256, 128), (300, 64), (512, 128)] {
            let (mean, worst) = field_errors(side, n);
            let fine_px = n as f64 / side as f64; // one image pixel in grid pixels
            assert!(
                mean.abs() < 0.15 * fine_px + 0.01,
                "{side}→{n}: mean error {mean}"
            );
            assert!(
                worst < 0.75 * fine_px + 0.05,
                "{side}→{n}: largest error {worst}"
            );
        }
    }

    #[test]
    fn an_image_the_size_of_the_grid_keeps_the_exact_grid_fields() {
        let (scene, img, _) = disc(64, (0.5, 0.5), 0.2);
        let t = Target::from_image(&scene, &img, 64, 64.0, 60.0).unwrap();
        let (idx, _) = snap_to_palette(&img, &scene.rec.colours, 64, 60.0);
        let g = Target::from_indices(&scene, &idx, 64, 64.0);
        assert_eq!(t.sdf, g.sdf);
        assert_eq!(t.mask, g.mask);
    }
}

//! Other looks of one height map (issue 36): the ways textures made
//! elsewhere are usually shown, for training a classifier that recognises
//! a model whatever program drew it.
//!
//! A [`Look`] turns a height map into a grey image through a chain that
//! other texture programs vary and our one [`super::shade`] fixes:
//!
//! 1. **View**: the height map is rotated by `rotation` and magnified by
//!    `zoom` (0.5–2: features half to twice their rendered size), read
//!    bilinearly on the torus; minified maps are box-filtered first, so
//!    the window is not aliased.
//! 2. **Surface**: either Lambertian shading under a light of any azimuth
//!    and an elevation of 20–70°, with the relief scaled ×0.3–4 and some
//!    ambient light; or (a fifth of the looks) the height itself as grey.
//!    The height's sign is flipped half the time (pits for bumps).
//! 3. **Tone**: contrast stretched to the 1st–99th percentile half the
//!    time, then a gamma of 0.6–1.6.
//! 4. **Sensor**: a Gaussian blur of σ ≤ 1.2 pixels and Gaussian noise of
//!    σ ≤ 4 grey levels, each half the time.
//!
//! The ranges are the issue's list ("other light directions and
//! elevations, relief scales, gamma, a little blur and noise, rescaling
//! 0.5–2×, rotation"), widened slightly at both ends. Everything is drawn
//! from a seeded [`Rng`], so the same seed gives the same bytes natively
//! and in wasm (only IEEE operations and `libm`).
use super::{Light, RELIEF};
use crate::core::rng::Rng;
use crate::texture::image::Gray;

/// One way of showing a height map (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// Degrees, counter-clockwise.
    pub rotation: f64,
    /// Magnification: > 1 shows the features larger.
    pub zoom: f64,
    /// Shade under this light; `None` shows the height as grey.
    pub light: Option<Light>,
    /// Multiplies [`RELIEF`].
    pub relief: f64,
    /// Brightness of the unlit parts (0–1).
    pub ambient: f64,
    /// Heights negated (pits for bumps).
    pub invert: bool,
    /// Stretch the 1st–99th percentiles to [0, 1].
    pub stretch: bool,
    pub gamma: f64,
    /// Gaussian blur, pixels (0: none).
    pub blur: f64,
    /// Gaussian noise, grey units (0: none).
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Look {
    /// A look drawn at random from the module's ranges.
    pub fn random(rng: &mut Rng) -> Look {
        let log_uniform = |rng: &mut Rng, lo: f64, hi: f64| {
            libm::exp(rng.range_f64(libm::log(lo), libm::log(hi)))
        };
        let rotation = rng.range_f64(0.0, 360.0);
        let zoom = log_uniform(rng, 0.5, 2.0);
        let plain = rng.f64() < 0.2;
        let light = Light {
            azimuth: rng.range_f64(0.0, 360.0),
            elevation: rng.range_f64(20.0, 70.0),
        };
        let relief = log_uniform(rng, 0.3, 4.0);
        let ambient = if rng.f64() < 0.5 {
            rng.range_f64(0.0, 0.2)
        } else {
            0.0
        };
        let invert = rng.f64() < 0.5;
        let stretch = rng.f64() < 0.5;
        let gamma = log_uniform(rng, 0.6, 1.6);
        let blur = if rng.f64() < 0.5 {
            rng.range_f64(0.2, 1.2)
        } else {
            0.0
        };
        let noise = if rng.f64() < 0.5 {
            rng.range_f64(0.0, 4.0 / 255.0)
        } else {
            0.0
        };
        Look {
            rotation,
            zoom,
            light: (!plain).then_some(light),
            relief,
            ambient,
            invert,
            stretch,
            gamma,
            blur,
            noise,
            seed: rng.next_u64(),
        }
    }

    /// The `side × side` image of the height map `height` (a tile of the
    /// torus) under this look, centred on the map's centre.
    pub fn apply(&self, height: &Gray, side: usize) -> Gray {
        let mut h = view(height, side, self.rotation, self.zoom);
        if self.invert {
            for v in &mut h.data {
                *v = 1.0 - *v;
            }
        }
        let mut img = match self.light {
            Some(light) => {
                // The relief per pixel of the window: the map's, as
                // `shade` gives it, times `relief`, over the zoom.
                let k = RELIEF * height.width.max(height.height) as f32 * 0.5 * self.relief as f32
                    / self.zoom as f32;
                super::shade_k(&h, light, k, self.ambient as f32)
            }
            None => {
                let mut g = h;
                g.normalise();
                g
            }
        };
        if self.stretch {
            stretch(&mut img, 0.01);
        }
        let g = self.gamma as f32;
        for v in &mut img.data {
            *v = v.clamp(0.0, 1.0).powf(g);
        }
        if self.blur > 0.0 {
            img = blur(&img, self.blur);
        }
        if self.noise > 0.0 {
            let mut rng = Rng::new(self.seed);
            for v in &mut img.data {
                *v = (*v + (gaussian(&mut rng) * self.noise) as f32).clamp(0.0, 1.0);
            }
        }
        img
    }
}

/// A standard normal deviate (Box–Muller).
fn gaussian(rng: &mut Rng) -> f64 {
    let u = rng.f64().max(1e-300);
    let v = rng.f64();
    libm::sqrt(-2.0 * libm::log(u)) * libm::cos(std::f64::consts::TAU * v)
}

/// The `side × side` window of the torus `src`, rotated by `rotation`
/// degrees and magnified by `zoom`, bilinear; when minifying (`zoom < 1`)
/// the map is first box-filtered over `1 / zoom` pixels.
fn view(src: &Gray, side: usize, rotation: f64, zoom: f64) -> Gray {
    let step = 1.0 / zoom.max(1e-3);
    let src = if step > 1.25 {
        box_filter(src, libm::round(step) as usize)
    } else {
        src.clone()
    };
    let (c, s) = (
        libm::cos(rotation.to_radians()),
        libm::sin(rotation.to_radians()),
    );
    let (cx, cy) = (src.width as f64 / 2.0, src.height as f64 / 2.0);
    let half = side as f64 / 2.0;
    let mut out = Gray::new(side, side);
    for y in 0..side {
        for x in 0..side {
            let (u, v) = (
                (x as f64 + 0.5 - half) * step,
                (y as f64 + 0.5 - half) * step,
            );
            let sx = cx + c * u - s * v - 0.5;
            let sy = cy + s * u + c * v - 0.5;
            let (x0, y0) = (libm::floor(sx), libm::floor(sy));
            let (fx, fy) = ((sx - x0) as f32, (sy - y0) as f32);
            let (xi, yi) = (x0 as isize, y0 as isize);
            let top = src.wrapped(xi, yi) * (1.0 - fx) + src.wrapped(xi + 1, yi) * fx;
            let bottom = src.wrapped(xi, yi + 1) * (1.0 - fx) + src.wrapped(xi + 1, yi + 1) * fx;
            out.data[y * side + x] = top * (1.0 - fy) + bottom * fy;
        }
    }
    out
}

/// The wrapped mean over `n × n` pixels around each pixel.
fn box_filter(src: &Gray, n: usize) -> Gray {
    let (w, h) = (src.width, src.height);
    let lo = -((n / 2) as isize);
    let mut rows = Gray::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let sum: f32 = (0..n as isize)
                .map(|d| src.wrapped(x as isize + lo + d, y as isize))
                .sum();
            rows.data[y * w + x] = sum / n as f32;
        }
    }
    let mut out = Gray::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let sum: f32 = (0..n as isize)
                .map(|d| rows.wrapped(x as isize, y as isize + lo + d))
                .sum();
            out.data[y * w + x] = sum / n as f32;
        }
    }
    out
}

/// A separable Gaussian blur of standard deviation `sigma` pixels, edges
/// clamped.
fn blur(img: &Gray, sigma: f64) -> Gray {
    let r = libm::ceil(3.0 * sigma) as isize;
    let weights: Vec<f32> = (-r..=r)
        .map(|d| libm::exp(-((d * d) as f64) / (2.0 * sigma * sigma)) as f32)
        .collect();
    let total: f32 = weights.iter().sum();
    let (w, h) = (img.width as isize, img.height as isize);
    let pass = |src: &Gray, horizontal: bool| {
        let mut out = Gray::new(src.width, src.height);
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0f32;
                for (i, wt) in weights.iter().enumerate() {
                    let d = i as isize - r;
                    let (sx, sy) = if horizontal {
                        ((x + d).clamp(0, w - 1), y)
                    } else {
                        (x, (y + d).clamp(0, h - 1))
                    };
                    acc += wt * src.data[(sy * w + sx) as usize];
                }
                out.data[(y * w + x) as usize] = acc / total;
            }
        }
        out
    };
    pass(&pass(img, true), false)
}

/// Stretch the `q` and `1 − q` quantiles of `img` to 0 and 1 (clamped);
/// a flat image is left alone.
fn stretch(img: &mut Gray, q: f64) {
    let mut sorted = img.data.clone();
    sorted.sort_by(f32::total_cmp);
    let n = sorted.len();
    if n == 0 {
        return;
    }
    let at = |p: f64| sorted[((p * (n - 1) as f64) as usize).min(n - 1)];
    let (lo, hi) = (at(q), at(1.0 - q));
    if hi - lo < 1e-6 {
        return;
    }
    for v in &mut img.data {
        *v = ((*v - lo) / (hi - lo)).clamp(0.0, 1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::models::{render_height, shade, MODELS};

    fn height() -> Gray {
        render_height(&MODELS[3], &MODELS[3].defaults(), 5, 64).unwrap()
    }

    #[test]
    fn the_identity_look_is_our_shading() {
        let h = height();
        let look = Look {
            rotation: 0.0,
            zoom: 1.0,
            light: Some(Light::DEFAULT),
            relief: 1.0,
            ambient: 0.0,
            invert: false,
            stretch: false,
            gamma: 1.0,
            blur: 0.0,
            noise: 0.0,
            seed: 0,
        };
        let a = look.apply(&h, 64);
        let b = shade(&h, Light::DEFAULT);
        let worst = a
            .data
            .iter()
            .zip(&b.data)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-5, "largest difference {worst}");
    }

    #[test]
    fn random_looks_differ_stay_in_range_and_repeat_from_their_seed() {
        let h = height();
        let mut rng = Rng::new(9);
        let looks: Vec<Look> = (0..40).map(|_| Look::random(&mut rng)).collect();
        let images: Vec<Gray> = looks.iter().map(|l| l.apply(&h, 32)).collect();
        for img in &images {
            assert_eq!((img.width, img.height), (32, 32));
            assert!(img.data.iter().all(|v| (0.0..=1.0).contains(v)));
        }
        assert!(images.windows(2).all(|p| p[0] != p[1]));
        assert!(looks.iter().any(|l| l.light.is_none()));
        assert!(looks.iter().any(|l| l.zoom < 0.8) && looks.iter().any(|l| l.zoom > 1.25));
        let mut again = Rng::new(9);
        assert_eq!(Look::random(&mut again).apply(&h, 32), images[0]);
    }

    #[test]
    fn a_half_zoom_shows_the_whole_tile_and_a_double_zoom_a_quarter() {
        // Vertical stripes, 4 periods across the 64² tile.
        let mut h = Gray::new(64, 64);
        for y in 0..64 {
            for x in 0..64 {
                h.data[y * 64 + x] = if (x / 8) % 2 == 0 { 1.0 } else { 0.0 };
            }
        }
        let crossings = |g: &Gray| {
            (1..g.width)
                .filter(|&x| (g.at(x, 16) > 0.5) != (g.at(x - 1, 16) > 0.5))
                .count()
        };
        let plain = |zoom| Look {
            rotation: 0.0,
            zoom,
            light: None,
            relief: 1.0,
            ambient: 0.0,
            invert: false,
            stretch: false,
            gamma: 1.0,
            blur: 0.0,
            noise: 0.0,
            seed: 0,
        };
        // 32-pixel windows: 1:1 shows 2 periods, zoom ½ shows 4, zoom 2 one.
        assert_eq!(crossings(&plain(1.0).apply(&h, 32)), 3);
        assert_eq!(crossings(&plain(0.5).apply(&h, 32)), 7);
        assert_eq!(crossings(&plain(2.0).apply(&h, 32)), 1);
    }
}

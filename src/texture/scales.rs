//! The twelve perceptual scales (paper §4, footnote 2; MISSION X4):
//! contrast, repetition, granularity, randomness, roughness, feature
//! density, directionality, structural complexity, coarseness, regularity,
//! local orientation and uniformity, each rated 1–9.
//!
//! The paper's scales are averaged human ratings; we have none. So every
//! scale here is a documented **computational estimate** — a classic image
//! measure chosen to rise with the property (Tamura, Mori & Yamawaki 1978
//! for coarseness, contrast and directionality; Amadasun & King 1989's
//! NGTDM for complexity; autocorrelation peaks for repetition and
//! regularity; the structure tensor for local orientation; block
//! statistics for uniformity). They are estimates, not human ratings:
//! the UI and docs must say so, and [`parse_ratings`] reads a CSV of human
//! ratings that replaces them ([`apply_ratings`]).
//!
//! A raw measure ([`measure`]) is mapped to 1–9 by quantiles over a
//! dataset ([`ScaleQuantiles::fit`], then [`ScaleQuantiles::to_likert`]):
//! the 1/9 … 8/9 quantiles of each raw measure are the cut points, so
//! over the fitting set each level holds about a ninth of the samples.
//!
//! Every measure is taken on a working copy: the image's central square,
//! resampled to 128² (so the rating does not depend on the size), values
//! as given (the shaded texture in [0, 1]). Measures that look at offsets
//! (autocorrelation, spectrum, Tamura windows) treat the image as a torus,
//! which dataset textures are.
//!
//! Transcendental functions are the `libm` crate's, so a measure has the
//! same bits natively and in wasm (the model classifier reads the raw
//! measures of the user's image in the browser, [`super::globals`]).
use crate::core::error::{Error, Result};
use crate::texture::image::Gray;
use serde::{Deserialize, Serialize};

/// The number of perceptual scales.
pub const N_SCALES: usize = 12;

/// The range of a scale: the ratings' Likert scale, 1 to 9 (a requested
/// scale may be a fraction; a rating or an estimate is whole).
pub const SCALE_RANGE: (f64, f64) = (1.0, 9.0);

/// The scales' names in the paper's order (also the CSV column names).
pub const SCALE_NAMES: [&str; N_SCALES] = [
    "contrast",
    "repetition",
    "granularity",
    "randomness",
    "roughness",
    "feature_density",
    "directionality",
    "structural_complexity",
    "coarseness",
    "regularity",
    "local_orientation",
    "uniformity",
];

/// One value per scale, in [`SCALE_NAMES`] order.
pub type Scales = [f64; N_SCALES];

/// Side of the working copy every measure is taken on.
pub const WORK: usize = 128;

/// The smallest image side the estimators accept.
pub const MIN_SIDE: usize = 16;

/// The raw estimate of every scale for `img` (larger = more of the
/// property). Errors: an image smaller than [`MIN_SIDE`] or with a
/// non-finite value.
pub fn measure(img: &Gray) -> Result<Scales> {
    let w = working_copy(img)?;
    let grad = Gradient::new(&w);
    let acf = Autocorrelation::new(&w);
    Ok([
        contrast(&w),
        repetition(&acf),
        granularity(&w, &grad),
        randomness(&w),
        roughness(&w),
        feature_density(&grad),
        directionality(&grad),
        structural_complexity(&w),
        coarseness(&w),
        regularity(&acf),
        local_orientation(&grad),
        uniformity(&w),
    ])
}

// ---------------------------------------------------------------------------
// The working copy and shared pieces.

/// The central square of `img`, bilinearly resampled to WORK².
fn working_copy(img: &Gray) -> Result<Vec<f64>> {
    let s = img.width.min(img.height);
    if s < MIN_SIDE || img.data.len() != img.width * img.height {
        return Err(Error::input(format!(
            "the perceptual scales need an image of at least {MIN_SIDE}×{MIN_SIDE} pixels \
             (got {}×{})",
            img.width, img.height
        ))
        .at("image"));
    }
    if img.data.iter().any(|v| !v.is_finite()) {
        return Err(Error::input("the image has a non-finite value").at("image"));
    }
    let (ox, oy) = ((img.width - s) / 2, (img.height - s) / 2);
    let k = s as f64 / WORK as f64;
    let mut out = vec![0.0; WORK * WORK];
    for y in 0..WORK {
        let sy = ((y as f64 + 0.5) * k - 0.5).clamp(0.0, (s - 1) as f64);
        let (y0, fy) = (sy.floor() as usize, sy - sy.floor());
        let y1 = (y0 + 1).min(s - 1);
        for x in 0..WORK {
            let sx = ((x as f64 + 0.5) * k - 0.5).clamp(0.0, (s - 1) as f64);
            let (x0, fx) = (sx.floor() as usize, sx - sx.floor());
            let x1 = (x0 + 1).min(s - 1);
            let at = |xx: usize, yy: usize| img.at(ox + xx, oy + yy) as f64;
            let a = at(x0, y0) + fx * (at(x1, y0) - at(x0, y0));
            let b = at(x0, y1) + fx * (at(x1, y1) - at(x0, y1));
            out[y * WORK + x] = a + fy * (b - a);
        }
    }
    Ok(out)
}

#[inline]
fn at(w: &[f64], x: isize, y: isize) -> f64 {
    let n = WORK as isize;
    w[(y.rem_euclid(n) * n + x.rem_euclid(n)) as usize]
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n;
    (m, var.sqrt())
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    if s.is_empty() {
        return 0.0;
    }
    s[((s.len() - 1) as f64 * q).round() as usize]
}

/// Wrapped box mean of radius `r` (separable).
fn box_mean(w: &[f64], r: usize) -> Vec<f64> {
    // Each output sums its 2r + 1 neighbours in the order of `d` from −r
    // to r (wrapping at the edges), as `at` reads them, with the wrap
    // done once per row or line instead of once per tap.
    let n = WORK;
    let k = 1.0 / (2 * r + 1) as f64;
    let wrap = |i: isize| i.rem_euclid(n as isize) as usize;
    let mut tmp = vec![0.0; n * n];
    let mut ext = vec![0.0; n + 2 * r];
    for (src, dst) in w.chunks_exact(n).zip(tmp.chunks_exact_mut(n)) {
        for (i, e) in ext.iter_mut().enumerate() {
            *e = src[wrap(i as isize - r as isize)];
        }
        for (x, o) in dst.iter_mut().enumerate() {
            *o = ext[x..x + 2 * r + 1].iter().fold(0.0, |s, v| s + v) * k;
        }
    }
    let mut out = vec![0.0; n * n];
    let mut sum = vec![0.0; n];
    for (y, dst) in out.chunks_exact_mut(n).enumerate() {
        sum.fill(0.0);
        for d in -(r as isize)..=r as isize {
            let line = wrap(y as isize + d);
            for (s, v) in sum.iter_mut().zip(&tmp[line * n..][..n]) {
                *s += v;
            }
        }
        for (o, s) in dst.iter_mut().zip(&sum) {
            *o = s * k;
        }
    }
    out
}

/// Sobel gradients and the structure tensor's local coherence.
struct Gradient {
    gx: Vec<f64>,
    gy: Vec<f64>,
    mag: Vec<f64>,
    /// Local coherence (λ1 − λ2)/(λ1 + λ2) of the structure tensor smoothed
    /// over a 7×7 window, and its trace (the local gradient energy).
    coherence: Vec<f64>,
    energy: Vec<f64>,
}

impl Gradient {
    fn new(w: &[f64]) -> Gradient {
        let n = WORK;
        let mut gx = vec![0.0; n * n];
        let mut gy = vec![0.0; n * n];
        for y in 0..n as isize {
            for x in 0..n as isize {
                let i = y as usize * n + x as usize;
                gx[i] = (at(w, x + 1, y - 1) + 2.0 * at(w, x + 1, y) + at(w, x + 1, y + 1)
                    - at(w, x - 1, y - 1)
                    - 2.0 * at(w, x - 1, y)
                    - at(w, x - 1, y + 1))
                    / 8.0;
                gy[i] = (at(w, x - 1, y + 1) + 2.0 * at(w, x, y + 1) + at(w, x + 1, y + 1)
                    - at(w, x - 1, y - 1)
                    - 2.0 * at(w, x, y - 1)
                    - at(w, x + 1, y - 1))
                    / 8.0;
            }
        }
        let mag: Vec<f64> = gx
            .iter()
            .zip(&gy)
            .map(|(a, b)| libm::hypot(*a, *b))
            .collect();
        let jxx = box_mean(&gx.iter().map(|a| a * a).collect::<Vec<_>>(), 3);
        let jyy = box_mean(&gy.iter().map(|a| a * a).collect::<Vec<_>>(), 3);
        let jxy = box_mean(
            &gx.iter().zip(&gy).map(|(a, b)| a * b).collect::<Vec<_>>(),
            3,
        );
        let mut coherence = vec![0.0; n * n];
        let mut energy = vec![0.0; n * n];
        for i in 0..n * n {
            let tr = jxx[i] + jyy[i];
            let d = ((jxx[i] - jyy[i]).powi(2) + 4.0 * jxy[i] * jxy[i]).sqrt();
            coherence[i] = if tr > 1e-12 { d / tr } else { 0.0 };
            energy[i] = tr;
        }
        Gradient {
            gx,
            gy,
            mag,
            coherence,
            energy,
        }
    }
}

/// 2-D FFT of a WORK² real image (forward), as (re, im) in f32.
fn fft2(w: &[f64], inverse: bool, im_in: Option<&[f32]>) -> (Vec<f32>, Vec<f32>) {
    let n = WORK;
    let mut re: Vec<f32> = w.iter().map(|&v| v as f32).collect();
    let mut im: Vec<f32> = im_in
        .map(|v| v.to_vec())
        .unwrap_or_else(|| vec![0.0; n * n]);
    crate::geom::fft::fft2(&mut re, &mut im, n, n, inverse).expect("WORK is a power of two");
    (re, im)
}

/// The power spectrum of the mean-removed working copy.
fn power(w: &[f64]) -> Vec<f64> {
    let (m, _) = mean_sd(w);
    let centred: Vec<f64> = w.iter().map(|v| v - m).collect();
    let (re, im) = fft2(&centred, false, None);
    re.iter()
        .zip(&im)
        .map(|(a, b)| (*a as f64).powi(2) + (*b as f64).powi(2))
        .collect()
}

/// Signed frequency / offset of index `i` on the WORK torus.
fn signed(i: usize) -> isize {
    if i < WORK / 2 {
        i as isize
    } else {
        i as isize - WORK as isize
    }
}

/// The normalised circular autocorrelation and its peaks outside the
/// central lobe.
struct Autocorrelation {
    /// Peaks (dx, dy, value), strongest first; only offsets in the upper
    /// half plane (the ACF is symmetric).
    peaks: Vec<(isize, isize, f64)>,
}

impl Autocorrelation {
    fn new(w: &[f64]) -> Autocorrelation {
        let n = WORK;
        let p = power(w);
        let zero = p.iter().map(|_| 0.0f64).collect::<Vec<_>>();
        let (re, _) = fft2(
            &p,
            true,
            Some(&zero.iter().map(|&v| v as f32).collect::<Vec<_>>()),
        );
        let c0 = re[0] as f64;
        if c0 <= 1e-12 {
            return Autocorrelation { peaks: vec![] };
        }
        let acf: Vec<f64> = re.iter().map(|&v| v as f64 / c0).collect();
        // The central lobe ends where the ring-averaged ACF first falls
        // below 0.3 (or at a quarter of the image).
        let mut ring = vec![(0.0, 0usize); n / 2 + 1];
        for y in 0..n {
            for x in 0..n {
                let r = ((signed(x).pow(2) + signed(y).pow(2)) as f64)
                    .sqrt()
                    .round() as usize;
                if r <= n / 2 {
                    ring[r].0 += acf[y * n + x];
                    ring[r].1 += 1;
                }
            }
        }
        let lobe = (1..=n / 4)
            .find(|&r| ring[r].0 / ring[r].1.max(1) as f64 <= 0.3)
            .unwrap_or(n / 4) as f64;
        let mut peaks = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let (dx, dy) = (signed(x), signed(y));
                if dy < 0 || (dy == 0 && dx < 0) {
                    continue;
                }
                let r = ((dx * dx + dy * dy) as f64).sqrt();
                if r < lobe.max(2.0) || r > (n / 2) as f64 {
                    continue;
                }
                let v = acf[y * n + x];
                // A maximum: no neighbour higher and some lower (so the
                // ridge of stripes, constant along them, has peaks too).
                let (mut higher, mut lower) = (false, false);
                for oy in -1..=1isize {
                    for ox in -1..=1isize {
                        if ox != 0 || oy != 0 {
                            let u = at(&acf, x as isize + ox, y as isize + oy);
                            higher |= u > v;
                            lower |= u < v;
                        }
                    }
                }
                let is_max = !higher && lower;
                if is_max && v > 0.0 {
                    peaks.push((dx, dy, v));
                }
            }
        }
        peaks.sort_by(|a, b| b.2.total_cmp(&a.2));
        Autocorrelation { peaks }
    }
}

// ---------------------------------------------------------------------------
// The twelve estimators.

/// **Contrast** (Tamura): σ / α₄^¼, the grey-level spread discounted by
/// the kurtosis α₄ = μ₄/σ⁴ (a few extreme pixels look less contrasty than
/// a spread histogram). An estimate, not a human rating.
pub fn contrast(w: &[f64]) -> f64 {
    let (m, sd) = mean_sd(w);
    if sd < 1e-9 {
        return 0.0;
    }
    let m4 = w.iter().map(|v| (v - m).powi(4)).sum::<f64>() / w.len() as f64;
    let kurt = m4 / sd.powi(4);
    sd / libm::pow(kurt, 0.25)
}

/// **Repetition**: the height of the strongest autocorrelation peak
/// outside the central lobe (1 = an exact repeat, ~0 = nothing repeats),
/// in any direction (stripes repeat too). An estimate, not a human rating.
fn repetition(acf: &Autocorrelation) -> f64 {
    acf.peaks.first().map_or(0.0, |p| p.2)
}

/// **Regularity**: repetition along two independent directions — the
/// geometric mean of the strongest autocorrelation peak and the strongest
/// peak at least 25° away from it. A lattice with exact placement scores
/// high; jitter and random placement blur the peaks. An estimate, not a
/// human rating.
fn regularity(acf: &Autocorrelation) -> f64 {
    let Some(&(x1, y1, a1)) = acf.peaks.first() else {
        return 0.0;
    };
    let t1 = libm::atan2(y1 as f64, x1 as f64);
    let a2 = acf
        .peaks
        .iter()
        .find(|&&(x, y, _)| {
            let mut d = (libm::atan2(y as f64, x as f64) - t1).abs() % std::f64::consts::PI;
            d = d.min(std::f64::consts::PI - d);
            d > 25f64.to_radians()
        })
        .map_or(0.0, |p| p.2);
    (a1 * a2).sqrt()
}

/// **Randomness**: the normalised entropy of the power spectrum after
/// dividing out its radial profile (so a 1/f slope does not count):
/// energy spread evenly over directions and frequencies (noise, random
/// placement) gives ~1, energy in a few harmonics (a lattice, stripes)
/// much less. An estimate, not a human rating.
fn randomness(w: &[f64]) -> f64 {
    let n = WORK;
    let p = power(w);
    let rmax = n / 2;
    let mut ring = vec![(0.0, 0usize); rmax + 1];
    let radius = |x: usize, y: usize| {
        ((signed(x).pow(2) + signed(y).pow(2)) as f64)
            .sqrt()
            .round() as usize
    };
    for y in 0..n {
        for x in 0..n {
            let r = radius(x, y);
            if (1..=rmax).contains(&r) {
                ring[r].0 += p[y * n + x];
                ring[r].1 += 1;
            }
        }
    }
    let mut q = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let r = radius(x, y);
            if (1..=rmax).contains(&r) {
                let m = ring[r].0 / ring[r].1 as f64;
                q.push(if m > 1e-15 { p[y * n + x] / m } else { 0.0 });
            }
        }
    }
    let total: f64 = q.iter().sum();
    if total <= 1e-15 {
        return 0.0;
    }
    let h: f64 = q
        .iter()
        .filter(|&&v| v > 0.0)
        .map(|&v| {
            let pr = v / total;
            -pr * libm::log(pr)
        })
        .sum();
    h / libm::log(q.len() as f64)
}

/// **Granularity**: how much the texture is made of small isotropic
/// grains — the density of local brightness maxima (5×5, with some
/// prominence) weighted by how isotropic the neighbourhood is (1 −
/// structure-tensor coherence), per 1000 pixels. An estimate, not a human
/// rating.
fn granularity(w: &[f64], g: &Gradient) -> f64 {
    let n = WORK;
    let s = box_mean(w, 1);
    let range = percentile(&s, 0.99) - percentile(&s, 0.01);
    if range < 1e-6 {
        return 0.0;
    }
    let mut score = 0.0;
    for y in 0..n as isize {
        for x in 0..n as isize {
            let v = at(&s, x, y);
            let mut is_max = true;
            let mut lo = v;
            for oy in -2..=2 {
                for ox in -2..=2 {
                    if ox == 0 && oy == 0 {
                        continue;
                    }
                    let u = at(&s, x + ox, y + oy);
                    is_max &= u < v;
                    lo = lo.min(u);
                }
            }
            if is_max && v - lo > 0.1 * range {
                score += 1.0 - g.coherence[y as usize * n + x as usize];
            }
        }
    }
    score * 1000.0 / (n * n) as f64
}

/// **Roughness**: the mean absolute fine-scale detail, |I − 3×3 mean of I|
/// (rough surfaces change at the finest scale). An estimate, not a human
/// rating.
fn roughness(w: &[f64]) -> f64 {
    let s = box_mean(w, 1);
    w.iter().zip(&s).map(|(a, b)| (a - b).abs()).sum::<f64>() / w.len() as f64
}

/// **Feature density**: the fraction of pixels on an edge — gradient
/// maxima across the edge (non-maximum suppression) above a quarter of the
/// 99th-percentile gradient (and an absolute floor). More features, more
/// edges. An estimate, not a human rating.
fn feature_density(g: &Gradient) -> f64 {
    let n = WORK;
    let t = (0.25 * percentile(&g.mag, 0.99)).max(0.01);
    let mut count = 0usize;
    for y in 0..n as isize {
        for x in 0..n as isize {
            let i = y as usize * n + x as usize;
            let m = g.mag[i];
            if m < t {
                continue;
            }
            // Step one pixel along the gradient's dominant octant.
            let (gx, gy) = (g.gx[i], g.gy[i]);
            let (dx, dy) = if gx.abs() > 2.0 * gy.abs() {
                (1, 0)
            } else if gy.abs() > 2.0 * gx.abs() {
                (0, 1)
            } else if gx * gy > 0.0 {
                (1, 1)
            } else {
                (1, -1)
            };
            if m >= at(&g.mag, x + dx, y + dy) && m >= at(&g.mag, x - dx, y - dy) {
                count += 1;
            }
        }
    }
    count as f64 / (n * n) as f64
}

/// **Directionality** (after Tamura): how peaked the histogram of
/// gradient orientations is — 1 − its normalised entropy over 16 bins of
/// [0, π), weighted by gradient magnitude (pixels above a fifth of the
/// 95th percentile). Stripes ≈ 1, isotropic noise ≈ 0; a grid's two
/// directions score in between. An estimate, not a human rating.
fn directionality(g: &Gradient) -> f64 {
    const BINS: usize = 16;
    let t = 0.2 * percentile(&g.mag, 0.95);
    let mut hist = [0.0f64; BINS];
    for i in 0..g.mag.len() {
        if g.mag[i] <= t || g.mag[i] < 1e-9 {
            continue;
        }
        let th = libm::atan2(g.gy[i], g.gx[i]).rem_euclid(std::f64::consts::PI);
        let b = ((th / std::f64::consts::PI * BINS as f64) as usize).min(BINS - 1);
        hist[b] += g.mag[i];
    }
    let total: f64 = hist.iter().sum();
    if total <= 0.0 {
        return 0.0;
    }
    let h: f64 = hist
        .iter()
        .filter(|&&v| v > 0.0)
        .map(|&v| -(v / total) * libm::log(v / total))
        .sum();
    1.0 - h / libm::log(BINS as f64)
}

/// **Structural complexity** (Amadasun & King's NGTDM complexity): over
/// 16 grey levels, how often neighbouring levels differ and by how much,
/// relative to each level's deviation from its 3×3 neighbourhood mean.
/// Many different, abruptly changing structures score high. An estimate,
/// not a human rating.
fn structural_complexity(w: &[f64]) -> f64 {
    const G: usize = 16;
    let n = WORK;
    let (lo, hi) = (percentile(w, 0.0), percentile(w, 1.0));
    if hi - lo < 1e-9 {
        return 0.0;
    }
    let q: Vec<usize> = w
        .iter()
        .map(|&v| (((v - lo) / (hi - lo) * G as f64) as usize).min(G - 1))
        .collect();
    let mut s = [0.0f64; G];
    let mut count = [0usize; G];
    for y in 0..n as isize {
        for x in 0..n as isize {
            let i = q[y as usize * n + x as usize];
            let mut sum = 0.0;
            for oy in -1..=1isize {
                for ox in -1..=1isize {
                    if ox != 0 || oy != 0 {
                        let j = q[((y + oy).rem_euclid(n as isize) * n as isize
                            + (x + ox).rem_euclid(n as isize))
                            as usize];
                        sum += j as f64;
                    }
                }
            }
            s[i] += (i as f64 - sum / 8.0).abs();
            count[i] += 1;
        }
    }
    let total = (n * n) as f64;
    let p: Vec<f64> = count.iter().map(|&c| c as f64 / total).collect();
    let mut c = 0.0;
    for i in 0..G {
        for j in 0..G {
            if p[i] > 0.0 && p[j] > 0.0 {
                c += (i as f64 - j as f64).abs() / (p[i] + p[j]) * (p[i] * s[i] + p[j] * s[j]);
            }
        }
    }
    c / total
}

/// **Coarseness** (Tamura): at every pixel, the window size 2^k (k = 1..5)
/// whose averages differ most between opposite neighbours (horizontally or
/// vertically); the mean best size, in working pixels (of 128). Large
/// features, large windows. An estimate, not a human rating.
fn coarseness(w: &[f64]) -> f64 {
    let n = WORK;
    let means: Vec<Vec<f64>> = (1..=5).map(|k| box_mean(w, (1usize << k) / 2)).collect();
    let mut total = 0.0;
    for y in 0..n as isize {
        for x in 0..n as isize {
            let mut best = (0.0, 1usize);
            for (k, a) in means.iter().enumerate() {
                let h = (1isize << (k + 1)) / 2;
                let eh = (at(a, x + h, y) - at(a, x - h, y)).abs();
                let ev = (at(a, x, y + h) - at(a, x, y - h)).abs();
                let e = eh.max(ev);
                // Prefer the larger window when nearly tied (Tamura's rule
                // picks the maximum; ties at flat spots go coarse).
                if e >= best.0 * 0.999 {
                    best = (e, 1usize << (k + 1));
                }
            }
            total += best.1 as f64;
        }
    }
    total / (n * n) as f64
}

/// **Local orientation**: how strongly small neighbourhoods have one
/// orientation, whatever it is — the mean structure-tensor coherence over
/// 7×7 windows, weighted by local gradient energy. Wavy or curved stripes
/// score high here but lower on directionality. An estimate, not a human
/// rating.
fn local_orientation(g: &Gradient) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (c, e) in g.coherence.iter().zip(&g.energy) {
        num += c * e;
        den += e;
    }
    if den > 1e-15 {
        num / den
    } else {
        0.0
    }
}

/// **Uniformity**: how alike the texture's parts are — on a 4×4 grid of
/// blocks, 1 / (1 + spread of block means / overall σ + relative spread of
/// block σs). A stationary texture ≈ 1; one that changes across the image
/// less. An estimate, not a human rating.
fn uniformity(w: &[f64]) -> f64 {
    const B: usize = 4;
    let n = WORK;
    let bs = n / B;
    let (_, sd) = mean_sd(w);
    if sd < 1e-9 {
        return 1.0;
    }
    let mut means = Vec::new();
    let mut sds = Vec::new();
    for by in 0..B {
        for bx in 0..B {
            let block: Vec<f64> = (0..bs)
                .flat_map(|y| (0..bs).map(move |x| (by * bs + y) * n + bx * bs + x))
                .map(|i| w[i])
                .collect();
            let (m, s) = mean_sd(&block);
            means.push(m);
            sds.push(s);
        }
    }
    let (_, sm) = mean_sd(&means);
    let (ms, ss) = mean_sd(&sds);
    1.0 / (1.0 + sm / sd + if ms > 1e-9 { ss / ms } else { 0.0 })
}

// ---------------------------------------------------------------------------
// Raw measures → 1..9.

/// Cut points mapping each raw measure to 1–9: the 1/9 … 8/9 quantiles of
/// that measure over a dataset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScaleQuantiles {
    pub edges: Vec<[f64; 8]>,
}

impl ScaleQuantiles {
    /// Fit on the raw measures of a dataset (at least one sample, all finite).
    pub fn fit(raw: &[Scales]) -> Result<ScaleQuantiles> {
        if raw.is_empty() {
            return Err(Error::input(
                "fitting scale quantiles needs at least one sample",
            ));
        }
        if raw.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::input("a raw scale measure is not finite"));
        }
        let edges = (0..N_SCALES)
            .map(|s| {
                let mut v: Vec<f64> = raw.iter().map(|r| r[s]).collect();
                v.sort_by(|a, b| a.total_cmp(b));
                let mut e = [0.0; 8];
                for (j, ej) in e.iter_mut().enumerate() {
                    // Linear interpolation between order statistics.
                    let pos = (v.len() - 1) as f64 * (j + 1) as f64 / 9.0;
                    let (i, f) = (pos.floor() as usize, pos - pos.floor());
                    let hi = v[(i + 1).min(v.len() - 1)];
                    *ej = v[i] + f * (hi - v[i]);
                }
                e
            })
            .collect();
        Ok(ScaleQuantiles { edges })
    }

    /// Likert levels 1–9: one plus the number of cut points below the raw value.
    pub fn to_likert(&self, raw: &Scales) -> [u8; N_SCALES] {
        let mut out = [1u8; N_SCALES];
        for (s, o) in out.iter_mut().enumerate() {
            let below = self.edges[s].iter().filter(|&&e| e < raw[s]).count();
            *o = 1 + below as u8;
        }
        out
    }
}

// ---------------------------------------------------------------------------
// Human ratings.

/// The most bytes and rows a ratings CSV may have.
pub const MAX_RATINGS_BYTES: usize = 8 << 20;
pub const MAX_RATINGS_ROWS: usize = 100_000;

/// One sample's human ratings (averages allowed: any value in [1, 9]).
#[derive(Clone, Debug, PartialEq)]
pub struct Rating {
    pub id: String,
    pub scales: Scales,
}

fn syntax(line: usize, column: usize, message: impl Into<String>) -> Error {
    Error::Syntax {
        line,
        column,
        message: message.into(),
    }
}

/// Split one CSV line into (column, field) with RFC 4180 quotes ("" inside).
fn split_csv(line: &str, lineno: usize) -> Result<Vec<(usize, String)>> {
    let mut out = Vec::new();
    let mut chars = line.char_indices().peekable();
    let mut start = 1;
    let mut field = String::new();
    let mut quoted = false;
    let mut at_start = true;
    while let Some((i, c)) = chars.next() {
        if at_start {
            start = line[..i].chars().count() + 1;
            at_start = false;
            if c == '"' {
                quoted = true;
                continue;
            }
        }
        if quoted {
            if c == '"' {
                if chars.peek().map(|p| p.1) == Some('"') {
                    chars.next();
                    field.push('"');
                } else {
                    quoted = false;
                    // Only spaces may follow a closing quote before the comma.
                    while let Some(&(j, d)) = chars.peek() {
                        if d == ',' {
                            break;
                        }
                        if !d.is_whitespace() {
                            return Err(syntax(
                                lineno,
                                line[..j].chars().count() + 1,
                                "unexpected text after a closing quote",
                            ));
                        }
                        chars.next();
                    }
                }
            } else {
                field.push(c);
            }
        } else if c == ',' {
            out.push((start, std::mem::take(&mut field)));
            at_start = true;
        } else {
            field.push(c);
        }
    }
    if quoted {
        return Err(syntax(
            lineno,
            start,
            "a quoted field is not closed on its line",
        ));
    }
    if at_start {
        start = line.chars().count() + 1;
    }
    out.push((start, field));
    Ok(out)
}

fn column_name(s: &str) -> String {
    s.trim().to_ascii_lowercase().replace([' ', '-'], "_")
}

/// Read a CSV of human ratings: a header `id,<the 12 scale names in any
/// order>` (case, spaces and hyphens in names do not matter; the first
/// column may also be called `sample` or `sample_id`), then one row per
/// sample: its id and 12 values in [1, 9]. Blank lines and lines starting
/// with `#` are skipped. Errors are syntax errors at a line and column.
pub fn parse_ratings(text: &str) -> Result<Vec<Rating>> {
    if text.len() > MAX_RATINGS_BYTES {
        return Err(Error::limit(format!(
            "a ratings file may have at most {MAX_RATINGS_BYTES} bytes (this one has {})",
            text.len()
        )));
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((hl, header)) = lines.next() else {
        return Err(syntax(
            1,
            1,
            "the ratings file is empty: expected a header `id,contrast,...`",
        ));
    };
    let cols = split_csv(header, hl)?;
    if !matches!(
        column_name(&cols[0].1).as_str(),
        "id" | "sample" | "sample_id"
    ) {
        return Err(syntax(
            hl,
            cols[0].0,
            "the first column must be `id` (the sample id)",
        ));
    }
    if cols.len() != N_SCALES + 1 {
        return Err(syntax(
            hl,
            1,
            format!(
                "the header must have `id` and the {N_SCALES} scales ({}), got {} columns",
                SCALE_NAMES.join(", "),
                cols.len()
            ),
        ));
    }
    // Column k (k ≥ 1) holds scale order[k - 1].
    let mut order = Vec::with_capacity(N_SCALES);
    for (c, name) in &cols[1..] {
        let nm = column_name(name);
        let Some(s) = SCALE_NAMES.iter().position(|&n| n == nm) else {
            return Err(syntax(
                hl,
                *c,
                format!(
                    "unknown scale column `{}`; scales: {}",
                    name.trim(),
                    SCALE_NAMES.join(", ")
                ),
            ));
        };
        if order.contains(&s) {
            return Err(syntax(
                hl,
                *c,
                format!("scale column `{}` appears twice", name.trim()),
            ));
        }
        order.push(s);
    }
    let mut out: Vec<Rating> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (ln, line) in lines {
        if out.len() >= MAX_RATINGS_ROWS {
            return Err(Error::limit(format!(
                "a ratings file may have at most {MAX_RATINGS_ROWS} rows"
            )));
        }
        let fields = split_csv(line, ln)?;
        if fields.len() != N_SCALES + 1 {
            return Err(syntax(
                ln,
                1,
                format!(
                    "expected {} fields (id and {N_SCALES} ratings), got {}",
                    N_SCALES + 1,
                    fields.len()
                ),
            ));
        }
        let id = fields[0].1.trim().to_string();
        if id.is_empty() {
            return Err(syntax(ln, fields[0].0, "the sample id is empty"));
        }
        if !seen.insert(id.clone()) {
            return Err(syntax(
                ln,
                fields[0].0,
                format!("sample `{id}` is rated twice"),
            ));
        }
        let mut scales = [0.0; N_SCALES];
        for (k, (c, f)) in fields[1..].iter().enumerate() {
            let v: f64 = f.trim().parse().map_err(|_| {
                syntax(
                    ln,
                    *c,
                    format!("`{}` is not a number ({})", f.trim(), SCALE_NAMES[order[k]]),
                )
            })?;
            if !(SCALE_RANGE.0..=SCALE_RANGE.1).contains(&v) {
                return Err(syntax(
                    ln,
                    *c,
                    format!("{} = {v} is outside the 1–9 scale", SCALE_NAMES[order[k]]),
                ));
            }
            scales[order[k]] = v;
        }
        out.push(Rating { id, scales });
    }
    Ok(out)
}

/// Replace the estimated scales of the samples whose id has a human
/// rating (`ids[i]` names `scales[i]`); returns how many were replaced.
pub fn apply_ratings(ids: &[String], scales: &mut [Scales], ratings: &[Rating]) -> usize {
    let by_id: std::collections::HashMap<&str, &Scales> =
        ratings.iter().map(|r| (r.id.as_str(), &r.scales)).collect();
    let mut n = 0;
    for (id, s) in ids.iter().zip(scales.iter_mut()) {
        if let Some(r) = by_id.get(id.as_str()) {
            *s = **r;
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests;

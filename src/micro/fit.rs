//! Reconstruction (paper §6.1, §12.1): the Fourier-domain loss between a
//! fitted field and a target SDF volume sampled on an n³ grid,
//!
//! `L = log( 1/(2N) Σᵢ (|Aᵢ − Âᵢ|² + |θᵢ − θ̂ᵢ|²) + ε )`
//!
//! over the N coefficients of the 3-D DFT (amplitudes A, phases θ), and
//! the synthetic structures of the paper's dataset (gyroid 1D, Eq. 40).
//! The DFT is the crate's one FFT ([`crate::geom::fft::RealFft3`]: the half
//! spectrum of real input, whose other half is its conjugate); plans,
//! buffers and the spectrum are reused between calls ([`Fourier`]), and
//! [`Fourier::half_loss`] compares with a target spectrum computed once
//! without allocating. Phases come from [`atan2`], a polynomial (pure
//! `f64` arithmetic, within 3e-13 of libm's, which moves a loss by less
//! than 1e-12 of itself; the same bytes natively and in wasm, and
//! vectorised by the compiler), computed only in blocks of bins that
//! have an amplitude above the phase floor (a periodic structure's
//! spectrum is mostly below it); sums run over eight
//! accumulators in a fixed order ([`sum8`]). The image loss of analysis by
//! synthesis (Eq. 39) compares amplitudes only ([`amplitude_loss`]). The
//! fit itself (request, job, optimisers) is in [`super::fit_api`].
use crate::core::error::{Error, Result};
use crate::geom::fft::{plane_weight, RealFft3, C64};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Amplitudes and phases of the 3-D DFT of an n³ volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    pub amp: Vec<f64>,
    pub phase: Vec<f64>,
    /// How many coefficients of the whole spectrum each entry stands for:
    /// empty for a whole spectrum (one each, `kx + nx·(ky + ny·kz)`); for a
    /// half spectrum of real input ([`Fourier::half_spectrum`], laid out as
    /// [`RealFft3::forward`]) 2, or 1 on the planes kz = 0 and kz = nz/2,
    /// whose conjugates are themselves.
    pub weight: Vec<f64>,
}

/// A reusable DFT of volumes of one shape `[nx, ny, nz]` (each a power of
/// two, or 1 for a flat axis: a 2-D image is `[w, h, 1]`): plans, scratch
/// and the amplitudes are kept between calls, so a fit's thousands of
/// transforms allocate nothing ([`Fourier::half_loss`]).
#[derive(Debug, Clone)]
pub struct Fourier {
    fft: RealFft3,
    amp: Vec<f64>,
    terms: Vec<f64>,
}

/// Below this fraction of the largest amplitude a coefficient's phase is
/// rounding noise: it counts as 0.
const PHASE_FLOOR: f64 = 1e-9;

/// `atan(t)/t ≈ P(t²)` for |t| ≤ tan(π/8), the constant term 1: least
/// squares of the angle's error `t·P(t²) − atan t` at 400 Chebyshev nodes
/// in t² (computed at 40 digits), coefficients of t⁰, t², t⁴, ..., t¹⁴.
/// Its error is below 2e-13: far under what a phase needs next to the
/// loss's ε of 1e-12 (eight terms where the 1e-15 of eleven cost three
/// more multiply-adds on the loss loop's critical path).
const ATAN_P: [f64; 8] = [
    1.0,
    -0.33333333251781677,
    0.19999990368498816,
    -0.1428529531382644,
    0.11102007775361325,
    -0.08980719193022284,
    0.0692603158046254,
    -0.03688082780333567,
];
/// tan(π/8) = √2 − 1.
const TAN_PI_8: f64 = 0.41421356237309503;

/// The angle of `x + iy` in `[−π, π]`, as `libm::atan2` within 3e-13
/// (`atan2_is_within_3e_13_of_libm`), with the same signs at ±0; finite
/// inputs (a NaN gives a NaN). Pure arithmetic without branches on the
/// hot path: one division, ten products and seven sums for the
/// polynomial; the same bytes on every
/// target. Reduction: `t = min/max` of |x|, |y| in [0, 1]; above tan(π/8)
/// `atan t = π/4 + atan((t − 1)/(t + 1))`, so the polynomial sees
/// |t| ≤ tan(π/8); then the octant. The polynomial is evaluated by
/// Estrin's scheme (pairs of terms, then powers s², s⁴ of s = t²): five
/// dependent operations after the division (s, s², s⁴, a product, a sum)
/// where Horner's rule has fourteen, and the loss loop was bound by that
/// chain's latency more than by its instruction count (bench micro
/// --only loss: about a sixth off an evaluation, for 1 % fewer
/// instructions).
#[inline(always)]
pub fn atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay > ax;
    let (mn, mx) = if steep { (ax, ay) } else { (ay, ax) };
    let big = mn > TAN_PI_8 * mx;
    let (num, den) = if big { (mn - mx, mn + mx) } else { (mn, mx) };
    let t = if den > 0.0 { num / den } else { 0.0 };
    let (s, c) = (t * t, &ATAN_P);
    let s2 = s * s;
    let p = ((c[0] + c[1] * s) + s2 * (c[2] + c[3] * s))
        + (s2 * s2) * ((c[4] + c[5] * s) + s2 * (c[6] + c[7] * s));
    let r = t * p + if big { FRAC_PI_4 } else { 0.0 };
    let r = if steep { FRAC_PI_2 - r } else { r };
    let r = if x.is_sign_negative() { PI - r } else { r };
    // r ≥ +0 here, so y's sign is the result's (−0 for y = −0): a mask
    // and an or, where a select on the sign took eight instructions.
    r.copysign(y)
}

fn phase_of(c: C64, a: f64, floor: f64) -> f64 {
    if a > floor {
        atan2(c.im, c.re)
    } else {
        0.0
    }
}

/// `Σ v` in a fixed order: eight running sums (`v[i]` into sum `i mod 8`),
/// then `((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))`. Every loss sum
/// here is this one, so the fused [`Fourier::half_loss`] and
/// [`fourier_loss`] agree bit for bit, and the compiler keeps the sums in
/// vector registers.
pub fn sum8(v: &[f64]) -> f64 {
    let mut s = [0.0f64; 8];
    let mut chunks = v.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            s[k] += c[k];
        }
    }
    for (k, x) in chunks.remainder().iter().enumerate() {
        s[k] += x;
    }
    ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]))
}

/// The largest of `v` (0 for none; NaNs skipped). A compare and select
/// rather than `f64::max` (whose NaN rule SSE2 has no instruction for):
/// the same result here, where no running maximum is NaN, in vector
/// registers.
fn max_of(v: &[f64]) -> f64 {
    let mut m = [0.0f64; 8];
    let mut chunks = v.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            m[k] = if c[k] > m[k] { c[k] } else { m[k] };
        }
    }
    for (k, x) in chunks.remainder().iter().enumerate() {
        m[k] = m[k].max(*x);
    }
    m.iter().copied().fold(0.0, f64::max)
}

impl Fourier {
    /// A transform of `dims` volumes; each side a power of two (1 allowed).
    pub fn new(dims: [usize; 3]) -> Result<Fourier> {
        if dims
            .iter()
            .any(|&d| d == 0 || !d.is_power_of_two() || d > 4096)
            || dims.iter().product::<usize>() < 2
        {
            return Err(Error::input(format!(
                "a Fourier loss needs sides that are powers of two (got {}×{}×{})",
                dims[0], dims[1], dims[2]
            )));
        }
        let fft = RealFft3::new(dims)?;
        let m = fft.planes() * dims[0] * dims[1];
        Ok(Fourier {
            fft,
            amp: vec![0.0; m],
            terms: vec![0.0; m],
        })
    }

    /// The shape this transform takes.
    pub fn dims(&self) -> [usize; 3] {
        self.fft.dims()
    }

    /// Values per volume.
    pub fn len(&self) -> usize {
        self.dims().iter().product()
    }

    /// Whether the volume is empty (never: at least two values).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The whole DFT of `values` (x fastest).
    fn transform(&mut self, values: &[f64]) -> Result<Vec<C64>> {
        let (re, im) = self.fft.forward(values)?;
        let (re, im) = (re.to_vec(), im.to_vec());
        Ok(self.fft.whole(&re, &im))
    }

    /// Amplitudes and phases of the DFT of `values`.
    pub fn spectrum(&mut self, values: &[f64]) -> Result<Spectrum> {
        let data = self.transform(values)?;
        let amp: Vec<f64> = data.iter().map(|c| c.norm_sqr().sqrt()).collect();
        let floor = max_of(&amp) * PHASE_FLOOR;
        let phase = data
            .iter()
            .zip(&amp)
            .map(|(c, &a)| phase_of(*c, a, floor))
            .collect();
        Ok(Spectrum {
            amp,
            phase,
            weight: vec![],
        })
    }

    /// The half spectrum of real `values` with its weights (see
    /// [`Spectrum::weight`]): the coefficients with `kz ≤ nz/2`; the others
    /// are their complex conjugates (same amplitude, opposite phase), so
    /// [`fourier_loss`] of two half spectra equals that of the whole ones
    /// up to rounding.
    pub fn half_spectrum(&mut self, values: &[f64]) -> Result<Spectrum> {
        let [nx, ny, nz] = self.dims();
        let (re, im) = self.fft.forward(values)?;
        let amp: Vec<f64> = re
            .iter()
            .zip(im)
            .map(|(r, i)| (r * r + i * i).sqrt())
            .collect();
        let floor = max_of(&amp) * PHASE_FLOOR;
        let phase = re
            .iter()
            .zip(im)
            .zip(&amp)
            .map(|((&r, &i), &a)| phase_of(C64::new(r, i), a, floor))
            .collect();
        let weight = (0..amp.len())
            .map(|i| plane_weight(i / (nx * ny), nz))
            .collect();
        Ok(Spectrum { amp, phase, weight })
    }

    /// `fourier_loss(&self.half_spectrum(values)?, target)`, bit for bit,
    /// without building the spectrum: the loss of one fit evaluation.
    /// `target` must be a half spectrum of this shape.
    pub fn half_loss(&mut self, values: &[f64], target: &Spectrum) -> Result<f64> {
        let [nx, ny, nz] = self.dims();
        let (re, im) = self.fft.forward(values)?;
        let m = re.len();
        if target.amp.len() != m || target.phase.len() != m || target.weight.len() != m {
            return Err(Error::input(format!(
                "the target spectrum has {} coefficients; this transform's half spectrum has {m}",
                target.amp.len()
            )));
        }
        // Indexed over slices of one length, so that it vectorises.
        let (amp, cr, ci) = (&mut self.amp[..m], &re[..m], &im[..m]);
        for l in 0..m {
            amp[l] = (cr[l] * cr[l] + ci[l] * ci[l]).sqrt();
        }
        let floor = max_of(&self.amp) * PHASE_FLOOR;
        let plane = nx * ny;
        for kz in 0..m / plane {
            let w = plane_weight(kz, nz);
            let r = kz * plane..(kz + 1) * plane;
            let terms = &mut self.terms[r.clone()];
            let (amp, cr, ci) = (&self.amp[r.clone()], &re[r.clone()], &im[r.clone()]);
            let (ta, tp) = (&target.amp[r.clone()], &target.phase[r]);
            // By blocks: one whose amplitudes are all at or below the
            // floor has every phase 0 and skips the atan2s (most of a
            // periodic structure's spectrum: near the truth, gyroid 1D
            // (Eq. 40) has 79 bins above it at 32³, in 51 of 2,176 blocks;
            // `bench micro`'s gyroid 2,032 bins in 688 blocks). Fusing the
            // maximum into the amplitudes' pass, or these terms into
            // `sum8`'s running sums, cost more instructions than the
            // passes they save (callgrind), so both stay separate. A plane
            // with no bin above the floor, or more than half of them (a
            // dense spectrum, where testing every block cost 4 % more than
            // no blocks), is one loop without blocks.
            let above = amp.iter().fold(0usize, |n, &a| n + usize::from(a > floor));
            if above == 0 || 2 * above > plane {
                loss_terms(terms, [amp, cr, ci, ta, tp], w, floor, above > 0);
                continue;
            }
            let mut l = 0;
            let mut blocks = terms.chunks_exact_mut(LOSS_BLOCK);
            for t in &mut blocks {
                let b = l..l + LOSS_BLOCK;
                let a = &amp[b.clone()];
                let phases = a.iter().fold(false, |any, &a| any | (a > floor));
                let (cr, ci, ta, tp) = (&cr[b.clone()], &ci[b.clone()], &ta[b.clone()], &tp[b]);
                loss_terms(t, [a, cr, ci, ta, tp], w, floor, phases);
                l += LOSS_BLOCK;
            }
            let t = blocks.into_remainder();
            let rest = [&amp[l..], &cr[l..], &ci[l..], &ta[l..], &tp[l..]];
            loss_terms(t, rest, w, floor, true);
        }
        Ok(loss_of_sum(sum8(&self.terms), self.len() as f64))
    }

    /// The paper's loss without its phase term,
    /// `log(1/(2N) Σᵢ |Aᵢ − Âᵢ|² + ε)`, of the values last given to
    /// [`Fourier::half_loss`] (whose amplitudes it reuses: no transform). A coarse-to-fine fit's middle
    /// stage: smooth in the frequencies where the phases are a needle.
    pub fn last_amplitude_loss(&mut self, target: &Spectrum) -> f64 {
        let [nx, ny, nz] = self.dims();
        let plane = nx * ny;
        let m = self.amp.len().min(target.amp.len());
        for kz in 0..m.div_ceil(plane) {
            let w = plane_weight(kz, nz);
            let r = kz * plane..((kz + 1) * plane).min(m);
            let (a, ta) = (&self.amp[r.clone()], &target.amp[r.clone()]);
            for ((t, a), b) in self.terms[r].iter_mut().zip(a).zip(ta) {
                let d = a - b;
                *t = w * (d * d);
            }
        }
        loss_of_sum(sum8(&self.terms[..m]), self.len() as f64)
    }

    /// The coarse loss ([`Profiles`]) of the values last given to
    /// [`Fourier::half_loss`] (its amplitudes reused: no transform).
    pub fn last_profile_loss(&self, target: &Profiles) -> f64 {
        target.loss(&self.amp)
    }

    /// Amplitudes alone, of the whole spectrum (the image loss, Eq. 39,
    /// compares only these).
    pub fn amplitudes(&mut self, values: &[f64]) -> Result<Vec<f64>> {
        let data = self.transform(values)?;
        Ok(data.iter().map(|c| c.norm_sqr().sqrt()).collect())
    }
}

/// The coarse view of a spectrum that a coarse-to-fine fit compares first
/// (see `micro::fit_api`): on each coordinate plane of frequencies (kx ky,
/// ky kz, kz kx), the power of the whole spectrum summed over the third
/// axis (the DC bin left out, so an offset such as a sheet's thickness does
/// not count), blurred by a periodic Gaussian of `sigma` bins,
/// square-rooted and scaled to unit length. The loss is `1 − ⟨p, p̂⟩`
/// averaged over the planes of more than one bin: 0 for the same profiles
/// up to scale, at most 1.
///
/// Why: the paper's loss of a periodic structure is a needle in its
/// frequencies (phases of the leakage bins match only at the exact value;
/// gyroid 1D scores −27.6 at η = 100 and about +1 two percent away), so a
/// search over several frequencies meets a plateau. Blurred profiles of
/// peaks at different frequencies still overlap, and their products fall
/// smoothly toward the true frequencies. Planes rather than one profile
/// per axis: folding each axis to |k| made fibres turned by θ and by −θ
/// the same (bench micro's fibres 2D then ended on the mirror image).
#[derive(Debug, Clone)]
pub struct Profiles {
    dims: [usize; 3],
    /// Per axis, the `n × n` blur weights (row `i`: the weights of the
    /// bins blurred into bin `i`).
    kernels: [Vec<f64>; 3],
    /// The target's profiles, one per plane.
    target: [Vec<f64>; 3],
}

/// The coordinate planes: (row axis, column axis) of each.
const PLANES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

impl Profiles {
    /// The target's profiles, from its half spectrum ([`Fourier::half_spectrum`])
    /// of a `dims` volume; `sigma` in bins (> 0).
    pub fn new(target: &Spectrum, dims: [usize; 3], sigma: f64) -> Profiles {
        let kernels = dims.map(|n| {
            let mut k = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    let d = i.abs_diff(j).min(n - i.abs_diff(j)) as f64 / sigma;
                    k[i * n + j] = libm::exp(-0.5 * d * d);
                }
            }
            k
        });
        let mut p = Profiles {
            dims,
            kernels,
            target: PLANES.map(|(a, b)| vec![0.0; dims[a] * dims[b]]),
        };
        p.target = p.profiles(&target.amp);
        p
    }

    /// The profiles of the half-spectrum amplitudes `amp` (laid out as
    /// [`RealFft3::forward`]).
    fn profiles(&self, amp: &[f64]) -> [Vec<f64>; 3] {
        let [nx, ny, nz] = self.dims;
        let planes = amp.len() / (nx * ny).max(1);
        let mut out = PLANES.map(|(a, b)| vec![0.0; self.dims[a] * self.dims[b]]);
        for kz in 0..planes {
            // A bin on a plane of weight 2 stands for its conjugate too,
            // at (−kx, −ky, −kz); the others' conjugates are kept.
            let both = plane_weight(kz, nz) > 1.0;
            let cz = (nz - kz) % nz;
            for kx in 0..nx {
                let cx = (nx - kx) % nx;
                let row = &amp[(kz * nx + kx) * ny..][..ny];
                for (ky, &a) in row.iter().enumerate() {
                    if kz == 0 && kx == 0 && ky == 0 {
                        continue;
                    }
                    let p = a * a;
                    let cy = (ny - ky) % ny;
                    out[0][kx * ny + ky] += p;
                    out[1][ky * nz + kz] += p;
                    out[2][kz * nx + kx] += p;
                    if both {
                        out[0][cx * ny + cy] += p;
                        out[1][cy * nz + cz] += p;
                        out[2][cz * nx + cx] += p;
                    }
                }
            }
        }
        for (o, &(a, b)) in out.iter_mut().zip(&PLANES) {
            let (na, nb) = (self.dims[a], self.dims[b]);
            let (ka, kb) = (&self.kernels[a], &self.kernels[b]);
            // Along b (each row), then along a (each column).
            let mut t = vec![0.0; na * nb];
            for r in 0..na {
                let src = &o[r * nb..][..nb];
                for c in 0..nb {
                    let k = &kb[c * nb..][..nb];
                    t[r * nb + c] = k.iter().zip(src).map(|(k, v)| k * v).sum();
                }
            }
            for r in 0..na {
                let k = &ka[r * na..][..na];
                for c in 0..nb {
                    let s: f64 = (0..na).map(|i| k[i] * t[i * nb + c]).sum();
                    o[r * nb + c] = s.max(0.0).sqrt();
                }
            }
            let norm = o.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > 0.0 {
                o.iter_mut().for_each(|v| *v /= norm);
            }
        }
        out
    }

    /// The loss of the half-spectrum amplitudes `amp` against the target.
    fn loss(&self, amp: &[f64]) -> f64 {
        let p = self.profiles(amp);
        let (mut sum, mut planes) = (0.0, 0);
        for (p, t) in p.iter().zip(&self.target) {
            if p.len() < 2 {
                continue;
            }
            let dot: f64 = p.iter().zip(t).map(|(x, y)| x * y).sum();
            let empty = |v: &[f64]| v.iter().all(|x| *x == 0.0);
            sum += match (empty(p), empty(t)) {
                (true, true) => 0.0,
                (false, false) => (1.0 - dot).max(0.0),
                _ => 1.0,
            };
            planes += 1;
        }
        sum / planes.max(1) as f64
    }
}

/// The 3-D DFT of `values` (n³, x fastest), n a power of two ≥ 2.
pub fn spectrum(values: &[f64], n: usize) -> Result<Spectrum> {
    if n < 2 || !n.is_power_of_two() || values.len() != n * n * n {
        return Err(Error::input(format!(
            "a Fourier loss needs an n³ volume with n a power of two (got {} values, n = {n})",
            values.len()
        )));
    }
    Fourier::new([n, n, n])?.spectrum(values)
}

/// The image loss of Eq. 39: `log(1/N Σ |Aᵢ − Âᵢ|² + ε)` over amplitudes.
pub fn amplitude_loss(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1);
    let s: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    libm::log(s / n as f64 + 1e-12)
}

/// The paper's Fourier loss between two spectra of the same size.
/// Both spectra must be of the same kind (whole, or half with weights).
pub fn fourier_loss(a: &Spectrum, b: &Spectrum) -> f64 {
    let n = a.amp.len().min(b.amp.len());
    let mut terms = Vec::with_capacity(n);
    let mut count = 0.0;
    for i in 0..n {
        let da = a.amp[i] - b.amp[i];
        let dp = a.phase[i] - b.phase[i];
        let w = a.weight.get(i).copied().unwrap_or(1.0);
        terms.push(w * (da * da + dp * dp));
        count += w;
    }
    loss_of_sum(sum8(&terms), count)
}

/// Bins per block of [`Fourier::half_loss`]'s loop: a block whose phases
/// are all 0 skips its atan2s. Eight: four two-wide vectors (SSE2, wasm
/// simd128); a block that computes them costs the test more (so dense
/// planes skip the blocks).
const LOSS_BLOCK: usize = 8;

/// The loss terms `w·((a − â)² + (θ − θ̂)²)` of a run of bins, `v` =
/// [amplitudes, real parts, imaginary parts, target amplitudes, target
/// phases]; θ = atan2 where `a > floor`, else 0. `phases = false` asserts
/// that no amplitude is above the floor: every θ is 0 and no atan2 runs
/// (the same terms, bit for bit). Indexed over slices of one length, so
/// that it vectorises (zipped iterators the compiler left scalar).
#[inline(always)]
fn loss_terms(terms: &mut [f64], v: [&[f64]; 5], w: f64, floor: f64, phases: bool) {
    let n = terms.len();
    let [amp, cr, ci, ta, tp] = v.map(|s| &s[..n]);
    if phases {
        for l in 0..n {
            let a = amp[l];
            let da = a - ta[l];
            let p = atan2(ci[l], cr[l]);
            let dp = (if a > floor { p } else { 0.0 }) - tp[l];
            terms[l] = w * (da * da + dp * dp);
        }
    } else {
        for l in 0..n {
            let da = amp[l] - ta[l];
            let dp = 0.0 - tp[l];
            terms[l] = w * (da * da + dp * dp);
        }
    }
}

fn loss_of_sum(s: f64, count: f64) -> f64 {
    libm::log(s / (2.0 * count.max(1.0)) + 1e-12)
}

/// Gyroid 1D (Eq. 40): `Σᵢ sin(xᵢ η) / η` sampled on an n³ grid of
/// spacing `h` from the origin (x fastest).
pub fn gyroid_1d(eta: f64, n: usize, h: f64) -> Vec<f64> {
    let s: Vec<f64> = (0..n).map(|i| libm::sin(i as f64 * h * eta)).collect();
    let mut out = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                out.push((s[x] + s[y] + s[z]) / eta);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use crate::optim::{AskTell, Cmaes, CmaesOptions};
    use std::f64::consts::TAU;

    /// [`atan2`] against `libm::atan2`: a million random points of every
    /// octant over 80 binary orders of magnitude (some near the axes), a
    /// million angles evenly around the circle, the reduction's edge, and
    /// the axes and signed zeros. (The polynomial's own error is 1.96e-13
    /// at worst; the former eleven terms passed this at 1e-15.)
    #[test]
    fn atan2_is_within_3e_13_of_libm() {
        let mut r = Rng::new(9);
        let mut worst = 0.0f64;
        for i in 0..1_000_000 {
            let scale = libm::exp2((r.f64() * 80.0 - 40.0).floor());
            let squash = if i % 3 == 0 { 1e-6 } else { 1.0 };
            let (y, x) = ((r.f64() - 0.5) * scale, (r.f64() - 0.5) * scale * squash);
            let (y, x) = if i % 2 == 0 { (y, x) } else { (x, y) };
            worst = worst.max((atan2(y, x) - libm::atan2(y, x)).abs());
        }
        for k in 0..1_000_000 {
            let a = -PI + TAU * k as f64 / 1e6;
            let (y, x) = (libm::sin(a), libm::cos(a));
            worst = worst.max((atan2(y, x) - libm::atan2(y, x)).abs());
        }
        assert!(worst <= 3e-13, "worst error {worst:e}");
        let edge = TAN_PI_8;
        for (y, x) in [
            (0.0, 0.0),
            (0.0, -0.0),
            (-0.0, 0.0),
            (-0.0, -0.0),
            (1.0, 0.0),
            (-1.0, -0.0),
            (0.0, 2.0),
            (-0.0, -2.0),
            (1.0, 1.0),
            (-3.0, -3.0),
            (edge, 1.0),
            (-1.0, edge),
            (f64::from_bits(edge.to_bits() + 1), -1.0),
            (1e-300, 1.0),
            (1.0, -1e-300),
        ] {
            let (a, b) = (atan2(y, x), libm::atan2(y, x));
            assert!((a - b).abs() <= 3e-13, "atan2({y}, {x}): {a} vs {b}");
            assert_eq!(
                a.is_sign_negative(),
                b.is_sign_negative(),
                "atan2({y}, {x})"
            );
        }
        assert!(atan2(f64::NAN, 1.0).is_nan());
    }

    /// The loss with [`atan2`] against the loss of the same transform with
    /// `libm::atan2`'s phases: within 1e-12 of itself, near the truth (the
    /// bench's candidate, η = 101 for 100) and far from it, on the 32³
    /// grid and on small shapes.
    #[test]
    fn the_polynomial_atan2_moves_the_loss_by_less_than_1e_12_of_it() {
        let (n, h) = (32, 0.25 / 32.0);
        let gyroids = (gyroid_1d(101.0, n, h), gyroid_1d(100.0, n, h));
        let far = (gyroid_1d(250.0, n, h), gyroid_1d(100.0, n, h));
        let mut cases = vec![([n, n, n], gyroids), ([n, n, n], far)];
        for dims in [[8, 4, 2], [16, 16, 1], [4, 8, 16]] {
            let len: usize = dims.iter().product();
            let a = (0..len).map(|i| libm::sin(i as f64 * 0.71) + 0.2).collect();
            let b = (0..len).map(|i| libm::cos(i as f64 * 0.37 + 1.0)).collect();
            cases.push((dims, (a, b)));
        }
        for (dims, (a, b)) in cases {
            let mut f = Fourier::new(dims).unwrap();
            let target = f.half_spectrum(&b).unwrap();
            let got = f.half_loss(&a, &target).unwrap();
            // The same loss, phases from libm.
            let libm_half = |v: &[f64]| {
                let mut fft = RealFft3::new(dims).unwrap();
                let (re, im) = fft.forward(v).unwrap();
                let amp: Vec<f64> = re
                    .iter()
                    .zip(im)
                    .map(|(r, i)| (r * r + i * i).sqrt())
                    .collect();
                let floor = max_of(&amp) * PHASE_FLOOR;
                let phase = re.iter().zip(im).zip(&amp);
                let phase =
                    phase.map(|((r, i), a)| if *a > floor { libm::atan2(*i, *r) } else { 0.0 });
                (amp.clone(), phase.collect::<Vec<f64>>())
            };
            let ((aa, ap), (ba, bp)) = (libm_half(&a), libm_half(&b));
            let plane = dims[0] * dims[1];
            let (mut s, mut count) = (0.0, 0.0);
            for i in 0..aa.len() {
                let w = plane_weight(i / plane, dims[2]);
                s += w * ((aa[i] - ba[i]).powi(2) + (ap[i] - bp[i]).powi(2));
                count += w;
            }
            let want = libm::log(s / (2.0 * count) + 1e-12);
            let rel = ((got - want) / want).abs();
            assert!(rel < 1e-12, "{dims:?}: {got} vs {want} (relative {rel:e})");
        }
    }

    #[test]
    fn fft_matches_a_direct_dft() {
        let n = 4;
        let mut r = Rng::new(2);
        let v: Vec<f64> = (0..n * n * n).map(|_| r.f64() - 0.5).collect();
        let s = spectrum(&v, n).unwrap();
        for (kx, ky, kz) in [(0, 0, 0), (1, 2, 3), (3, 1, 0), (2, 2, 2)] {
            let (mut re, mut im) = (0.0, 0.0);
            for z in 0..n {
                for y in 0..n {
                    for x in 0..n {
                        let a = -TAU * (kx * x + ky * y + kz * z) as f64 / n as f64;
                        let val = v[x + n * (y + n * z)];
                        re += val * a.cos();
                        im += val * a.sin();
                    }
                }
            }
            let i = kx + n * (ky + n * kz);
            assert!((s.amp[i] - (re * re + im * im).sqrt()).abs() < 1e-9);
            if s.amp[i] > 1e-9 {
                assert!((s.phase[i] - im.atan2(re)).abs() < 1e-9);
            }
        }
        assert!(spectrum(&v, 3).is_err());
    }

    #[test]
    fn a_half_spectrum_gives_the_loss_of_the_whole() {
        for dims in [[8, 4, 2], [4, 4, 1], [1, 8, 2], [16, 16, 16]] {
            let len: usize = dims.iter().product();
            let a: Vec<f64> = (0..len).map(|i| libm::sin(i as f64 * 0.71) + 0.2).collect();
            let b: Vec<f64> = (0..len).map(|i| libm::cos(i as f64 * 0.37 + 1.0)).collect();
            let mut f = Fourier::new(dims).unwrap();
            let whole = fourier_loss(&f.spectrum(&a).unwrap(), &f.spectrum(&b).unwrap());
            let half = fourier_loss(&f.half_spectrum(&a).unwrap(), &f.half_spectrum(&b).unwrap());
            assert!((whole - half).abs() < 1e-9, "{dims:?}: {whole} vs {half}");
        }
    }

    #[test]
    fn the_fused_half_loss_is_the_loss_of_the_half_spectra_bit_for_bit() {
        let dense = |dims: [usize; 3]| {
            let len: usize = dims.iter().product();
            let a: Vec<f64> = (0..len).map(|i| libm::sin(i as f64 * 0.71) + 0.2).collect();
            let b: Vec<f64> = (0..len).map(|i| libm::cos(i as f64 * 0.37 + 1.0)).collect();
            (dims, a, b)
        };
        let mut cases: Vec<_> = [[32, 32, 32], [8, 4, 2], [1, 8, 2], [16, 16, 1], [2, 2, 4]]
            .map(dense)
            .into();
        // Sparse spectra, where most blocks skip their atan2s: gyroid 1D
        // near the truth and far from it, and on planes of 4 values (no
        // whole block).
        let (n, h) = (32, 0.25 / 32.0);
        for eta in [101.0, 250.0] {
            cases.push(([n, n, n], gyroid_1d(eta, n, h), gyroid_1d(100.0, n, h)));
        }
        cases.push(([2, 2, 2], gyroid_1d(30.0, 2, 0.1), gyroid_1d(20.0, 2, 0.1)));
        // Along x only: every plane but kz = 0 has no bin above the floor.
        let along_x = |f: f64| {
            (0..n * n * n)
                .map(|i| libm::sin(f * (i % n) as f64))
                .collect::<Vec<f64>>()
        };
        cases.push(([n, n, n], along_x(0.3), along_x(0.5)));
        for (dims, a, b) in cases {
            let mut f = Fourier::new(dims).unwrap();
            let t = f.half_spectrum(&b).unwrap();
            let want = fourier_loss(&f.half_spectrum(&a).unwrap(), &t);
            assert_eq!(
                f.half_loss(&a, &t).unwrap().to_bits(),
                want.to_bits(),
                "{dims:?}"
            );
            // Reusing the buffers changes nothing.
            assert_eq!(
                f.half_loss(&a, &t).unwrap().to_bits(),
                want.to_bits(),
                "{dims:?}"
            );
        }
        let mut f = Fourier::new([4, 4, 4]).unwrap();
        let t = f.half_spectrum(&[0.0; 64]).unwrap();
        assert!(f.half_loss(&[0.0; 8], &t).is_err());
        let mut g = Fourier::new([8, 4, 4]).unwrap();
        assert!(g.half_loss(&[0.0; 128], &t).is_err());
    }

    /// A block whose amplitudes are all at or below the floor gives the
    /// same terms without its atan2s, bit for bit; with one amplitude above
    /// it, the phase counts (so the test of `half_loss` must see it).
    #[test]
    fn loss_terms_skip_atan2_only_where_every_phase_is_zero() {
        let mut r = Rng::new(4);
        let floor = 0.5;
        for _ in 0..1000 {
            let v: [Vec<f64>; 5] = [0.0, 1.0, 1.0, 1.0, 3.0]
                .map(|s| (0..LOSS_BLOCK).map(|_| (r.f64() - 0.5) * 2.0 * s).collect());
            let mut amp: Vec<f64> = v[0].iter().map(|a| a.abs() * floor).collect();
            amp[3] = floor;
            let w = if r.f64() < 0.5 { 1.0 } else { 2.0 };
            let terms = |amp: &[f64], phases: bool| {
                let mut t = vec![0.0; LOSS_BLOCK];
                loss_terms(&mut t, [amp, &v[1], &v[2], &v[3], &v[4]], w, floor, phases);
                t.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(terms(&amp, true), terms(&amp, false));
            amp[5] = floor * 1.5;
            if v[2][5] != 0.0 {
                assert_ne!(terms(&amp, true), terms(&amp, false));
            }
        }
    }

    /// At the truth the loss sum is exactly 0 (the loss is log ε, its
    /// floor); a perturbed parameter scores higher, more so further away.
    #[test]
    fn the_loss_is_zero_at_the_truth_and_grows_with_a_perturbation() {
        let (n, h) = (32, 0.25 / 32.0);
        let mut f = Fourier::new([n, n, n]).unwrap();
        let t = f.half_spectrum(&gyroid_1d(100.0, n, h)).unwrap();
        let at = |f: &mut Fourier, eta: f64| f.half_loss(&gyroid_1d(eta, n, h), &t).unwrap();
        let zero = at(&mut f, 100.0);
        assert_eq!(zero, libm::log(1e-12));
        let near = at(&mut f, 101.0);
        let far = at(&mut f, 150.0);
        assert!(near > zero + 10.0, "{near} vs {zero}");
        assert!(far > near, "{far} vs {near}");
    }

    /// The coarse profiles' loss is 0 at the truth, blind to scale and to
    /// an offset, and falls all the way from η = 250 to the true η = 100
    /// of gyroid 1D, where the paper's loss is a needle on a plateau (it
    /// rises from η = 140 to 120, and is within 1.5 of its far value until
    /// 2 % from the truth). The amplitude loss is 0 at the truth too.
    #[test]
    fn the_coarse_profiles_have_a_wide_basin_where_the_paper_loss_has_a_needle() {
        let (n, h) = (32, 0.25 / 32.0);
        let mut f = Fourier::new([n, n, n]).unwrap();
        let truth = gyroid_1d(100.0, n, h);
        let t = f.half_spectrum(&truth).unwrap();
        let m = Profiles::new(&t, [n, n, n], 2.0);
        let mut at = |v: &[f64]| {
            let exact = f.half_loss(v, &t).unwrap();
            (f.last_profile_loss(&m), exact, f.last_amplitude_loss(&t))
        };
        let (coarse, exact, amp) = at(&truth);
        assert!(
            coarse.abs() < 1e-12 && amp == exact,
            "{coarse} {exact} {amp}"
        );
        let scaled: Vec<f64> = truth.iter().map(|v| 3.0 * v + 0.7).collect();
        assert!(at(&scaled).0.abs() < 1e-12, "{}", at(&scaled).0);
        let path = [
            250.0, 200.0, 160.0, 140.0, 120.0, 110.0, 105.0, 102.0, 100.0,
        ];
        let losses: Vec<(f64, f64, f64)> = path.iter().map(|&e| at(&gyroid_1d(e, n, h))).collect();
        for (w, e) in losses.windows(2).zip(path.windows(2)) {
            assert!(
                w[1].0 < w[0].0,
                "coarse loss at η = {} and {}: {:?}",
                e[0],
                e[1],
                w
            );
        }
        let exact: Vec<f64> = losses.iter().map(|l| l.1).collect();
        assert!(exact.windows(2).any(|w| w[1] > w[0]), "{exact:?}");
        assert!(exact[4] > exact[0] - 1.5, "{exact:?}");
    }

    /// The paper's Gyroid [1D] reconstruction: CMA-ES with the Fourier
    /// loss on a 32³ grid recovers η = 100 ± 2 from η = 300 (range 10..400).
    /// (The phase term makes the optimum a narrow well: away from η = 100
    /// exactly, leakage spreads phases over every coefficient.)
    #[test]
    fn cmaes_recovers_the_gyroid_1d_parameter() {
        let (n, h) = (32, 0.25 / 32.0);
        let target = spectrum(&gyroid_1d(100.0, n, h), n).unwrap();
        let (lo, hi) = (10.0, 400.0);
        let eta = |u: f64| lo + (hi - lo) * u;
        let loss = |u: f64| fourier_loss(&spectrum(&gyroid_1d(eta(u), n, h), n).unwrap(), &target);
        let mut es = Cmaes::new(
            &[(300.0 - lo) / (hi - lo)],
            CmaesOptions {
                population: 100,
                sigma: 0.6,
                generations: 30,
                tolerance: 1e-10,
                restarts: false,
            },
        );
        let mut rng = Rng::new(1);
        let mut evals = 0;
        loop {
            let batch = es.ask(&mut rng);
            if batch.is_empty() {
                break;
            }
            let losses: Vec<f64> = batch.iter().map(|u| loss(u[0])).collect();
            evals += batch.len();
            es.tell(batch, &losses);
        }
        let best = es.best().unwrap();
        let got = eta(best.u[0]);
        assert!(
            (got - 100.0).abs() < 2.0,
            "η = {got} after {evals} evaluations (loss {})",
            best.loss
        );
        // And the loss tells: far parameters score far worse.
        assert!(loss((300.0 - lo) / (hi - lo)) > best.loss + 5.0);
    }
}

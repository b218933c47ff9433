//! Reconstruction (paper §6.1, §12.1): the Fourier-domain loss between a
//! fitted field and a target SDF volume sampled on an n³ grid,
//!
//! `L = log( 1/(2N) Σᵢ (|Aᵢ − Âᵢ|² + |θᵢ − θ̂ᵢ|²) + ε )`
//!
//! over the N coefficients of the 3-D DFT (amplitudes A, phases θ), and
//! the synthetic structures of the paper's dataset (gyroid 1D, Eq. 40).
//! The DFT is an in-place radix-2 FFT along each axis (n a power of two);
//! twiddles come from `libm`, so native and wasm agree bit for bit
//! ([`Fourier`] keeps them and its scratch between calls). The image loss
//! of analysis by synthesis (Eq. 39) compares amplitudes only
//! ([`amplitude_loss`]). The fit itself (request, job, optimisers) is in
//! [`super::fit_api`].
use crate::core::error::{Error, Result};
use std::f64::consts::TAU;

/// A complex number as `[re, im]`.
type C = [f64; 2];

/// In-place radix-2 FFT of `buf` (length a power of two).
fn fft(buf: &mut [C], tw: &[C]) {
    let n = buf.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            buf.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let step = n / len;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let w = tw[k * step];
                let a = buf[start + k];
                let b = buf[start + k + len / 2];
                let t = [b[0] * w[0] - b[1] * w[1], b[0] * w[1] + b[1] * w[0]];
                buf[start + k] = [a[0] + t[0], a[1] + t[1]];
                buf[start + k + len / 2] = [a[0] - t[0], a[1] - t[1]];
            }
        }
        len <<= 1;
    }
}

/// Amplitudes and phases of the 3-D DFT of an n³ volume (x fastest).
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    pub amp: Vec<f64>,
    pub phase: Vec<f64>,
    /// How many coefficients of the whole spectrum each entry stands for:
    /// empty for a whole spectrum (one each); for a half spectrum of real
    /// input ([`Fourier::half_spectrum`]) 2, or 1 on the planes kx = 0 and
    /// kx = nx/2, whose conjugates are themselves.
    pub weight: Vec<f64>,
}

/// A reusable DFT of volumes of one shape `[nx, ny, nz]` (each a power of
/// two, or 1 for a flat axis: a 2-D image is `[w, h, 1]`): twiddles and
/// scratch are kept between calls, so a fit's thousands of transforms
/// allocate only their spectra.
#[derive(Debug, Clone)]
pub struct Fourier {
    dims: [usize; 3],
    tw: [Vec<C>; 3],
    data: Vec<C>,
    line: Vec<C>,
}

fn twiddles(n: usize) -> Vec<C> {
    (0..n / 2)
        .map(|k| {
            let a = -TAU * k as f64 / n as f64;
            [libm::cos(a), libm::sin(a)]
        })
        .collect()
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
        let len = dims.iter().product();
        Ok(Fourier {
            dims,
            tw: [twiddles(dims[0]), twiddles(dims[1]), twiddles(dims[2])],
            data: vec![[0.0; 2]; len],
            line: vec![[0.0; 2]; dims.iter().copied().max().unwrap_or(1)],
        })
    }

    /// The shape this transform takes.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Values per volume.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Whether the volume is empty (never: at least two values).
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The DFT coefficients of `values` (x fastest), in place in the scratch.
    fn transform(&mut self, values: &[f64]) -> Result<&[C]> {
        if values.len() != self.data.len() {
            return Err(Error::input(format!(
                "a {}×{}×{} transform needs {} values (got {})",
                self.dims[0],
                self.dims[1],
                self.dims[2],
                self.data.len(),
                values.len()
            )));
        }
        for (d, &v) in self.data.iter_mut().zip(values) {
            *d = [v, 0.0];
        }
        let [nx, ny, nz] = self.dims;
        // x: contiguous lines.
        if nx > 1 {
            for chunk in self.data.chunks_exact_mut(nx) {
                fft(chunk, &self.tw[0]);
            }
        }
        // y and z: gather a strided line, transform, scatter.
        for (axis, n, stride) in [(1usize, ny, nx), (2, nz, nx * ny)] {
            if n < 2 {
                continue;
            }
            let line = &mut self.line[..n];
            for base in 0..self.data.len() {
                // Lines start where the axis coordinate is 0.
                if !(base / stride).is_multiple_of(n) {
                    continue;
                }
                for (i, l) in line.iter_mut().enumerate() {
                    *l = self.data[base + i * stride];
                }
                fft(line, &self.tw[axis]);
                for (i, l) in line.iter().enumerate() {
                    self.data[base + i * stride] = *l;
                }
            }
        }
        Ok(&self.data)
    }

    /// Amplitudes and phases of the DFT of `values`.
    pub fn spectrum(&mut self, values: &[f64]) -> Result<Spectrum> {
        let data = self.transform(values)?;
        let amp: Vec<f64> = data
            .iter()
            .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
            .collect();
        // The phase of a coefficient at rounding-noise level is noise: 0.
        let floor = amp.iter().copied().fold(0.0, f64::max) * 1e-9;
        let phase = data
            .iter()
            .zip(&amp)
            .map(|(c, &a)| {
                if a > floor {
                    libm::atan2(c[1], c[0])
                } else {
                    0.0
                }
            })
            .collect();
        Ok(Spectrum {
            amp,
            phase,
            weight: vec![],
        })
    }

    /// The DFT of real `values` on the coefficients with `kx ≤ nx/2` only:
    /// the others are their complex conjugates (same amplitude, opposite
    /// phase), so a loss over these, weighted, equals the loss over all
    /// while the y and z passes and the phases cost about half.
    fn transform_half(&mut self, values: &[f64]) -> Result<usize> {
        if values.len() != self.data.len() {
            return Err(Error::input(format!(
                "a {}×{}×{} transform needs {} values (got {})",
                self.dims[0],
                self.dims[1],
                self.dims[2],
                self.data.len(),
                values.len()
            )));
        }
        for (d, &v) in self.data.iter_mut().zip(values) {
            *d = [v, 0.0];
        }
        let [nx, ny, nz] = self.dims;
        if nx > 1 {
            for chunk in self.data.chunks_exact_mut(nx) {
                fft(chunk, &self.tw[0]);
            }
        }
        let h = if nx > 1 { nx / 2 + 1 } else { 1 };
        for (axis, n, stride) in [(1usize, ny, nx), (2, nz, nx * ny)] {
            if n < 2 {
                continue;
            }
            let line = &mut self.line[..n];
            for base in 0..self.data.len() {
                if base % nx >= h || !(base / stride).is_multiple_of(n) {
                    continue;
                }
                for (i, l) in line.iter_mut().enumerate() {
                    *l = self.data[base + i * stride];
                }
                fft(line, &self.tw[axis]);
                for (i, l) in line.iter().enumerate() {
                    self.data[base + i * stride] = *l;
                }
            }
        }
        Ok(h)
    }

    /// The half spectrum of real `values` with its weights (see
    /// [`Spectrum::weight`]); [`fourier_loss`] of two half spectra equals
    /// that of the whole ones up to rounding.
    pub fn half_spectrum(&mut self, values: &[f64]) -> Result<Spectrum> {
        let h = self.transform_half(values)?;
        let nx = self.dims[0];
        let m = h * self.dims[1] * self.dims[2];
        let (mut amp, mut re_im, mut weight) = (
            Vec::with_capacity(m),
            Vec::with_capacity(m),
            Vec::with_capacity(m),
        );
        for (i, c) in self.data.iter().enumerate() {
            let kx = i % nx;
            if kx >= h {
                continue;
            }
            amp.push((c[0] * c[0] + c[1] * c[1]).sqrt());
            re_im.push(*c);
            weight.push(if kx == 0 || 2 * kx == nx { 1.0 } else { 2.0 });
        }
        let floor = amp.iter().copied().fold(0.0, f64::max) * 1e-9;
        let phase = re_im
            .iter()
            .zip(&amp)
            .map(|(c, &a)| {
                if a > floor {
                    libm::atan2(c[1], c[0])
                } else {
                    0.0
                }
            })
            .collect();
        Ok(Spectrum { amp, phase, weight })
    }

    /// Amplitudes alone (the image loss, Eq. 39, compares only these).
    pub fn amplitudes(&mut self, values: &[f64]) -> Result<Vec<f64>> {
        let data = self.transform(values)?;
        Ok(data
            .iter()
            .map(|c| (c[0] * c[0] + c[1] * c[1]).sqrt())
            .collect())
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
    let mut s = 0.0;
    let mut count = 0.0;
    for i in 0..n {
        let da = a.amp[i] - b.amp[i];
        let dp = a.phase[i] - b.phase[i];
        let w = a.weight.get(i).copied().unwrap_or(1.0);
        s += w * (da * da + dp * dp);
        count += w;
    }
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

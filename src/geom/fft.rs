//! The crate's one FFT, over `realfft`/`rustfft`: a reusable 3-D
//! real-to-complex transform ([`RealFft3`], Micro's Fourier loss) and an
//! in-place 2-D complex transform of `f32` planes ([`fft2`], the texture
//! models' spectral synthesis and the texture scale analysis).
//!
//! Sides are powers of two (1 allowed for a flat axis of a 3-D volume).
//! Arithmetic is `f64` throughout; [`fft2`] converts its `f32` planes in and
//! out. Neither direction is scaled (an inverse after a forward gives `n`
//! times the input).
//!
//! Determinism: native and wasm must give the same bytes. rustfft picks
//! SIMD kernels (AVX/SSE on x86, NEON, wasm simd) when its features of those
//! names are on, and their rounding differs from the scalar path: the crate
//! depends on `realfft`/`rustfft` with `default-features = false`, which
//! leaves all of them off. That is not enough: rustfft computes its
//! twiddles with std `cos`/`sin`, which natively are the platform's libm
//! (glibc) and in wasm32 the `libm` crate, and those differ in the last bit
//! for about 4 % of the twiddles of sizes ≥ 32 (e.g. `sin(−2π·11/32)`).
//! Measured (scalar rustfft 6.4.1, same inputs, native vs wasm32 in node):
//! sizes 2–32 give the same bytes, 64–8192 do not. So rustfft runs only
//! its hard-coded butterflies of length ≤ [`LEAF`] (and realfft its
//! real-to-complex step of length ≤ [`LEAF`]), whose few twiddles are
//! checked equal to the `libm` crate's (`kernel_twiddles_agree_with_the_libm_crate`);
//! longer transforms are split into those (Cooley–Tukey, four-step) with
//! twiddles from the `libm` crate, computed the same way on every target.
use crate::core::error::{Error, Result};
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// A complex number.
pub type C64 = Complex<f64>;

/// Largest side accepted.
pub const MAX_FFT_SIDE: usize = 4096;

/// Longest transform handed to rustfft as it is (see the module docs).
pub const LEAF: usize = 32;

/// A complex FFT of one power-of-two length and direction.
enum Plan {
    /// rustfft's butterfly (length ≤ [`LEAF`]).
    Leaf(Arc<dyn Fft<f64>>),
    /// Four-step: `n = n1 · n2` with `n1 = LEAF`: `n2` transforms of
    /// length `n1` on the transposed input, twiddles `W_n^(j2·k1)`, then
    /// `n1` transforms of length `n2`, then a transpose.
    Split {
        n1: usize,
        n2: usize,
        first: Arc<dyn Fft<f64>>,
        second: Box<Plan>,
        twiddles: Vec<C64>,
    },
}

impl Plan {
    fn new(n: usize, inverse: bool, planner: &mut FftPlanner<f64>) -> Plan {
        let leaf = |len: usize, planner: &mut FftPlanner<f64>| {
            if inverse {
                planner.plan_fft_inverse(len)
            } else {
                planner.plan_fft_forward(len)
            }
        };
        if n <= LEAF {
            return Plan::Leaf(leaf(n, planner));
        }
        let (n1, n2) = (LEAF, n / LEAF);
        let sign = if inverse { 1.0 } else { -1.0 };
        let mut twiddles = Vec::with_capacity(n);
        for j2 in 0..n2 {
            for k1 in 0..n1 {
                let a = sign * std::f64::consts::TAU * ((j2 * k1) % n) as f64 / n as f64;
                twiddles.push(C64::new(libm::cos(a), libm::sin(a)));
            }
        }
        Plan::Split {
            n1,
            n2,
            first: leaf(n1, planner),
            second: Box::new(Plan::new(n2, inverse, planner)),
            twiddles,
        }
    }

    /// Transform `buf` in place: consecutive transforms of this length.
    /// `tmp` is resized as needed.
    fn process(&self, buf: &mut [C64], tmp: &mut Vec<C64>) {
        match self {
            Plan::Leaf(f) => {
                let need = f.get_inplace_scratch_len();
                if tmp.len() < need {
                    tmp.resize(need, C64::default());
                }
                f.process_with_scratch(buf, &mut tmp[..need]);
            }
            Plan::Split {
                n1,
                n2,
                first,
                second,
                twiddles,
            } => {
                let (n1, n2) = (*n1, *n2);
                let n = n1 * n2;
                let mut t = vec![C64::default(); n];
                for x in buf.chunks_exact_mut(n) {
                    // t[j2·n1 + j1] = x[j1·n2 + j2]
                    for j1 in 0..n1 {
                        for j2 in 0..n2 {
                            t[j2 * n1 + j1] = x[j1 * n2 + j2];
                        }
                    }
                    first.process(&mut t);
                    for (v, w) in t.iter_mut().zip(twiddles) {
                        *v *= w;
                    }
                    // x[k1·n2 + j2] = t[j2·n1 + k1]
                    for j2 in 0..n2 {
                        for k1 in 0..n1 {
                            x[k1 * n2 + j2] = t[j2 * n1 + k1];
                        }
                    }
                    second.process(x, tmp);
                    // X[k1 + n1·k2] = x[k1·n2 + k2]
                    t.copy_from_slice(x);
                    for k1 in 0..n1 {
                        for k2 in 0..n2 {
                            x[k1 + n1 * k2] = t[k1 * n2 + k2];
                        }
                    }
                }
            }
        }
    }
}

fn check_side(n: usize, flat_ok: bool) -> bool {
    n.is_power_of_two() && n <= MAX_FFT_SIDE && (flat_ok || n >= 2)
}

/// A forward 3-D FFT of real `nx × ny × nz` volumes (x fastest) giving the
/// coefficients with `kx ≤ nx/2` (the others are their complex conjugates:
/// `X[kx, ky, kz] = conj X[nx − kx, −ky, −kz]`). Plans, scratch and the
/// output are kept between calls: a fit's thousands of transforms
/// allocate nothing.
pub struct RealFft3 {
    dims: [usize; 3],
    half: usize,
    r2c: Option<Arc<dyn RealToComplex<f64>>>,
    /// x when longer than [`LEAF`]: a complex transform of the real row.
    fx: Option<Plan>,
    fy: Option<Plan>,
    fz: Option<Plan>,
    row: Vec<f64>,
    crow: Vec<C64>,
    scratch: Vec<C64>,
    lines: Vec<C64>,
    out: Vec<C64>,
}

impl std::fmt::Debug for RealFft3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealFft3")
            .field("dims", &self.dims)
            .finish()
    }
}

impl Clone for RealFft3 {
    fn clone(&self) -> Self {
        RealFft3::new(self.dims).expect("dims were checked")
    }
}

impl RealFft3 {
    /// A transform of `dims` volumes: each side a power of two up to
    /// [`MAX_FFT_SIDE`] (1 allowed), at least two values in all.
    pub fn new(dims: [usize; 3]) -> Result<RealFft3> {
        if dims.iter().any(|&d| !check_side(d, true)) || dims.iter().product::<usize>() < 2 {
            return Err(Error::input(format!(
                "an FFT needs sides that are powers of two up to {MAX_FFT_SIDE} \
                 (got {}×{}×{})",
                dims[0], dims[1], dims[2]
            )));
        }
        let [nx, ny, nz] = dims;
        let half = if nx > 1 { nx / 2 + 1 } else { 1 };
        let r2c = (nx > 1 && nx <= LEAF).then(|| RealFftPlanner::<f64>::new().plan_fft_forward(nx));
        let mut planner = FftPlanner::<f64>::new();
        let fx = (nx > LEAF).then(|| Plan::new(nx, false, &mut planner));
        let fy = (ny > 1).then(|| Plan::new(ny, false, &mut planner));
        let fz = (nz > 1).then(|| Plan::new(nz, false, &mut planner));
        let scratch_len = r2c.as_ref().map_or(0, |p| p.get_scratch_len());
        Ok(RealFft3 {
            dims,
            half,
            r2c,
            fx,
            fy,
            fz,
            row: vec![0.0; nx],
            crow: vec![C64::default(); nx],
            scratch: vec![C64::default(); scratch_len],
            lines: vec![C64::default(); half * ny.max(nz)],
            out: vec![C64::default(); half * ny * nz],
        })
    }

    /// The shape this transform takes.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Coefficients kept along x: `nx/2 + 1` (1 for a flat x).
    pub fn half(&self) -> usize {
        self.half
    }

    /// The half spectrum of `values` (`nx·ny·nz` of them, x fastest), laid
    /// out as `kx + half·(ky + ny·kz)`.
    pub fn forward(&mut self, values: &[f64]) -> Result<&[C64]> {
        let [nx, ny, nz] = self.dims;
        if values.len() != nx * ny * nz {
            return Err(Error::input(format!(
                "a {nx}×{ny}×{nz} transform needs {} values (got {})",
                nx * ny * nz,
                values.len()
            )));
        }
        let h = self.half;
        // x: one real-to-complex transform per row.
        match &self.r2c {
            Some(r2c) => {
                for (src, dst) in values.chunks_exact(nx).zip(self.out.chunks_exact_mut(h)) {
                    self.row.copy_from_slice(src);
                    let need = r2c.get_scratch_len();
                    if self.scratch.len() < need {
                        self.scratch.resize(need, C64::default());
                    }
                    r2c.process_with_scratch(&mut self.row, dst, &mut self.scratch[..need])
                        .map_err(|e| Error::input(format!("FFT: {e}")))?;
                }
            }
            None => match &self.fx {
                Some(fx) => {
                    for (src, dst) in values.chunks_exact(nx).zip(self.out.chunks_exact_mut(h)) {
                        for (c, &v) in self.crow.iter_mut().zip(src) {
                            *c = C64::new(v, 0.0);
                        }
                        fx.process(&mut self.crow, &mut self.scratch);
                        dst.copy_from_slice(&self.crow[..h]);
                    }
                }
                None => {
                    for (d, &v) in self.out.iter_mut().zip(values) {
                        *d = C64::new(v, 0.0);
                    }
                }
            },
        }
        // y: per z plane, gather the h lines (kx fixed) contiguously.
        if let Some(fy) = &self.fy {
            let lines = &mut self.lines[..h * ny];
            for plane in self.out.chunks_exact_mut(h * ny) {
                for y in 0..ny {
                    for kx in 0..h {
                        lines[kx * ny + y] = plane[kx + h * y];
                    }
                }
                fy.process(lines, &mut self.scratch);
                for y in 0..ny {
                    for kx in 0..h {
                        plane[kx + h * y] = lines[kx * ny + y];
                    }
                }
            }
        }
        // z: per y row, gather the h lines along z.
        if let Some(fz) = &self.fz {
            let lines = &mut self.lines[..h * nz];
            let plane = h * ny;
            for y in 0..ny {
                for z in 0..nz {
                    let base = z * plane + y * h;
                    for kx in 0..h {
                        lines[kx * nz + z] = self.out[base + kx];
                    }
                }
                fz.process(lines, &mut self.scratch);
                for z in 0..nz {
                    let base = z * plane + y * h;
                    for kx in 0..h {
                        self.out[base + kx] = lines[kx * nz + z];
                    }
                }
            }
        }
        Ok(&self.out)
    }

    /// The whole spectrum (`kx + nx·(ky + ny·kz)`) from a half one given by
    /// [`RealFft3::forward`]: the missing coefficients are conjugates.
    pub fn whole(&self, half: &[C64]) -> Vec<C64> {
        let [nx, ny, nz] = self.dims;
        let h = self.half;
        let mut out = Vec::with_capacity(nx * ny * nz);
        for kz in 0..nz {
            for ky in 0..ny {
                for kx in 0..nx {
                    out.push(if kx < h {
                        half[kx + h * (ky + ny * kz)]
                    } else {
                        let (mx, my, mz) = (nx - kx, (ny - ky) % ny, (nz - kz) % nz);
                        half[mx + h * (my + ny * mz)].conj()
                    });
                }
            }
        }
        out
    }
}

/// In-place 2-D complex FFT of a `w × h` plane (x fastest) given as real
/// and imaginary parts; `inverse` flips the sign of the exponent (no
/// scaling). Sides are powers of two up to [`MAX_FFT_SIDE`] (1 allowed).
pub fn fft2(re: &mut [f32], im: &mut [f32], w: usize, h: usize, inverse: bool) -> Result<()> {
    if !check_side(w, true) || !check_side(h, true) || re.len() != w * h || im.len() != w * h {
        return Err(Error::input(format!(
            "a 2-D FFT needs power-of-two sides up to {MAX_FFT_SIDE} and w·h values \
             (got {w}×{h}, {} and {} values)",
            re.len(),
            im.len()
        )));
    }
    let mut planner = FftPlanner::<f64>::new();
    let fx = (w > 1).then(|| Plan::new(w, inverse, &mut planner));
    let fy = (h > 1).then(|| Plan::new(h, inverse, &mut planner));
    let mut buf: Vec<C64> = re
        .iter()
        .zip(im.iter())
        .map(|(&r, &i)| C64::new(r as f64, i as f64))
        .collect();
    let mut scratch = vec![];
    if let Some(fx) = &fx {
        fx.process(&mut buf, &mut scratch);
    }
    if let Some(fy) = &fy {
        // Columns: transpose, transform the rows, transpose back.
        let mut t = vec![C64::default(); w * h];
        for y in 0..h {
            for x in 0..w {
                t[x * h + y] = buf[y * w + x];
            }
        }
        fy.process(&mut t, &mut scratch);
        for y in 0..h {
            for x in 0..w {
                buf[y * w + x] = t[x * h + y];
            }
        }
    }
    for ((r, i), c) in re.iter_mut().zip(im.iter_mut()).zip(&buf) {
        *r = c.re as f32;
        *i = c.im as f32;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use std::f64::consts::PI;

    fn naive(values: &[C64], dims: [usize; 3], sign: f64) -> Vec<C64> {
        let [nx, ny, nz] = dims;
        let mut out = vec![C64::default(); values.len()];
        for kz in 0..nz {
            for ky in 0..ny {
                for kx in 0..nx {
                    let mut s = C64::default();
                    for z in 0..nz {
                        for y in 0..ny {
                            for x in 0..nx {
                                let a = sign
                                    * 2.0
                                    * PI
                                    * ((kx * x) as f64 / nx as f64
                                        + (ky * y) as f64 / ny as f64
                                        + (kz * z) as f64 / nz as f64);
                                s += values[x + nx * (y + ny * z)] * C64::new(a.cos(), a.sin());
                            }
                        }
                    }
                    out[kx + nx * (ky + ny * kz)] = s;
                }
            }
        }
        out
    }

    #[test]
    fn the_3d_real_fft_matches_a_naive_dft() {
        let mut r = Rng::new(7);
        for dims in [
            [4, 4, 4],
            [8, 2, 4],
            [1, 8, 2],
            [2, 1, 1],
            [8, 4, 1],
            [16, 1, 2],
        ] {
            let len: usize = dims.iter().product();
            let v: Vec<f64> = (0..len).map(|_| r.f64() - 0.5).collect();
            let mut f = RealFft3::new(dims).unwrap();
            let half = f.forward(&v).unwrap().to_vec();
            assert_eq!(half.len(), f.half() * dims[1] * dims[2]);
            let whole = f.whole(&half);
            let c: Vec<C64> = v.iter().map(|&x| C64::new(x, 0.0)).collect();
            let want = naive(&c, dims, -1.0);
            for (i, (a, b)) in whole.iter().zip(&want).enumerate() {
                assert!((a - b).norm() < 1e-9, "{dims:?} at {i}: {a} vs {b}");
            }
        }
        assert!(RealFft3::new([3, 4, 4]).is_err());
        assert!(RealFft3::new([1, 1, 1]).is_err());
        assert!(RealFft3::new([4, 4, 4])
            .unwrap()
            .forward(&[0.0; 8])
            .is_err());
    }

    /// A random `w × h` signal's [`fft2`] against the naive DFT, within
    /// `tol`: (input re, input im, output re, output im).
    fn fft2_against_naive(
        r: &mut Rng,
        w: usize,
        h: usize,
        tol: f64,
    ) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) {
        let re0: Vec<f32> = (0..w * h).map(|_| r.f64() as f32 - 0.5).collect();
        let im0: Vec<f32> = (0..w * h).map(|_| r.f64() as f32 - 0.5).collect();
        let (mut re, mut im) = (re0.clone(), im0.clone());
        fft2(&mut re, &mut im, w, h, false).unwrap();
        let c: Vec<C64> = re0
            .iter()
            .zip(&im0)
            .map(|(&a, &b)| C64::new(a as f64, b as f64))
            .collect();
        let want = naive(&c, [w, h, 1], -1.0);
        for i in 0..w * h {
            let d = C64::new(re[i] as f64, im[i] as f64) - want[i];
            assert!(d.norm() < tol, "{w}×{h} at {i}: {d}");
        }
        (re0, im0, re, im)
    }

    #[test]
    fn the_2d_fft_matches_a_naive_dft_and_round_trips() {
        let mut r = Rng::new(3);
        for (w, h) in [(4, 4), (8, 2), (1, 4), (16, 8)] {
            let (re0, im0, mut re, mut im) = fft2_against_naive(&mut r, w, h, 1e-5);
            fft2(&mut re, &mut im, w, h, true).unwrap();
            let n = (w * h) as f32;
            for i in 0..w * h {
                assert!((re[i] / n - re0[i]).abs() < 1e-5 && (im[i] / n - im0[i]).abs() < 1e-5);
            }
        }
        let (mut re, mut im) = (vec![0.0; 6], vec![0.0; 6]);
        assert!(fft2(&mut re, &mut im, 3, 2, false).is_err());
    }

    /// The twiddles rustfft's butterflies of length ≤ 32 (Butterfly16:
    /// k = 1..3 of 16; Butterfly32: k = 1..7 of 32; Butterfly8: √½) and
    /// realfft's real-to-complex step of length n ≤ 32 (k = 1..n/4 of n)
    /// use are std `cos`/`sin` of `−2π/n · k`; in wasm32 std takes those
    /// from the `libm` crate. Equal bits here mean native and wasm run
    /// these kernels with the same numbers. (Longer sizes are not all equal,
    /// e.g. `sin(−2π·11/32)`, hence the split in [`Plan`].)
    #[test]
    fn kernel_twiddles_agree_with_the_libm_crate() {
        for n in [2usize, 4, 8, 16, 32] {
            for k in 0..n / 4 + 1 {
                let a = -2f64 * PI / n as f64 * k as f64;
                assert_eq!(a.cos().to_bits(), libm::cos(a).to_bits(), "cos n={n} k={k}");
                assert_eq!(a.sin().to_bits(), libm::sin(a).to_bits(), "sin n={n} k={k}");
            }
        }
        assert_eq!(0.5f64.sqrt().to_bits(), libm::sqrt(0.5).to_bits());
    }

    /// Lengths above [`LEAF`] go through the four-step split.
    #[test]
    fn long_transforms_match_a_naive_dft() {
        let mut r = Rng::new(11);
        for (w, h) in [(64, 2), (128, 1), (2, 256)] {
            fft2_against_naive(&mut r, w, h, 1e-4);
        }
        let dims = [64, 2, 64];
        let v: Vec<f64> = (0..64 * 2 * 64).map(|_| r.f64() - 0.5).collect();
        let mut f = RealFft3::new(dims).unwrap();
        let half = f.forward(&v).unwrap().to_vec();
        let whole = f.whole(&half);
        let c: Vec<C64> = v.iter().map(|&x| C64::new(x, 0.0)).collect();
        let want = naive(&c, dims, -1.0);
        for (i, (a, b)) in whole.iter().zip(&want).enumerate() {
            assert!((a - b).norm() < 1e-9, "at {i}: {a} vs {b}");
        }
    }
}

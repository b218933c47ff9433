//! The crate's one FFT: a reusable 3-D real-to-complex transform
//! ([`RealFft3`], Micro's Fourier loss: radix-4 passes over many signals at
//! once, written here, see [`RealFft3`]) and an in-place 2-D complex
//! transform of `f32` planes over `rustfft` ([`fft2`], the texture models'
//! spectral synthesis and the texture scale analysis).
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
//! [`RealFft3`] does not use rustfft: its own passes (plain `f64` adds and
//! multiplies, `libm` twiddles) give the same bytes everywhere by
//! construction (`bench micro --only loss` times it against the former
//! rustfft path, kept in the bench).
use crate::core::error::{Error, Result};
use realfft::num_complex::Complex;
use rustfft::algorithm::butterflies::{
    Butterfly16, Butterfly2, Butterfly32, Butterfly4, Butterfly8,
};
use rustfft::algorithm::Dft;
use rustfft::{Fft, FftDirection};
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

/// rustfft's kernel for a power-of-two length ≤ [`LEAF`]: the very
/// algorithm its scalar planner picks for that length (a checked test), made
/// directly, so that the planner and the algorithms it would pick for other
/// lengths (Rader, Bluestein, mixed radix: about 200 KB of wasm) are not
/// linked into every module that uses this FFT.
fn leaf(len: usize, inverse: bool) -> Arc<dyn Fft<f64>> {
    let d = if inverse {
        FftDirection::Inverse
    } else {
        FftDirection::Forward
    };
    match len {
        2 => Arc::new(Butterfly2::new(d)),
        4 => Arc::new(Butterfly4::new(d)),
        8 => Arc::new(Butterfly8::new(d)),
        16 => Arc::new(Butterfly16::new(d)),
        32 => Arc::new(Butterfly32::new(d)),
        // Length 1 (the planner's choice too); no other length reaches here.
        _ => Arc::new(Dft::new(len, d)),
    }
}

impl Plan {
    fn new(n: usize, inverse: bool) -> Plan {
        if n <= LEAF {
            return Plan::Leaf(leaf(n, inverse));
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
            first: leaf(n1, inverse),
            second: Box::new(Plan::new(n2, inverse)),
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

/// Lanes a [`LaneFft`] transforms together: `2 · n · LANES` values of one
/// block stay in the L1 cache through all its stages.
const LANES: usize = 64;

/// A forward complex FFT of one power-of-two length `n` applied to many
/// signals at once ("lanes"): the signals are the columns of `n` rows, real
/// and imaginary parts in separate arrays, so each butterfly is one loop
/// over contiguous lanes of elementwise arithmetic, which the compiler
/// vectorises and which rounds the same way on every target (Rust neither
/// fuses multiply-adds nor reorders float operations). Decimation in
/// frequency, radix 4 (each stage reads and writes the rows once where two
/// radix-2 stages would twice) and one radix-2 stage when log₂ n is odd
/// (fused with the last radix-4 one by [`LaneFft::run_to`]), twiddles from
/// the `libm` crate (`W = 1` and `W = −i` exact). The output rows come in
/// bit-reversed order, as radix 2 leaves them: [`LaneFft::run_to`] stores
/// them in order, or the caller reads row `rev[k]` for coefficient k.
#[derive(Debug, Clone)]
struct LaneFft {
    n: usize,
    /// `W_n^k = exp(−2πik/n)` for k < n.
    wr: Vec<f64>,
    wi: Vec<f64>,
    /// Where coefficient k is before reordering (bit reversal of k).
    rev: Vec<usize>,
}

/// `(a, b) ← (a + b, a − b)` over lanes: the radix-2 butterfly with `w = 1`.
#[inline(always)]
fn butterfly_one(ar: &mut [f64], ai: &mut [f64], br: &mut [f64], bi: &mut [f64]) {
    let lanes = ar
        .iter_mut()
        .zip(ai.iter_mut())
        .zip(br.iter_mut().zip(bi.iter_mut()));
    for ((ar, ai), (br, bi)) in lanes {
        let (xr, xi, yr, yi) = (*ar, *ai, *br, *bi);
        *ar = xr + yr;
        *ai = xi + yi;
        *br = xr - yr;
        *bi = xi - yi;
    }
}

/// Four rows of a sub-transform (at offsets 0, q, 2q, 3q), real or
/// imaginary parts.
type Rows4<'a> = [&'a mut [f64]; 4];

/// The radix-4 butterfly over lanes, rows `x0..x3` of a sub-transform of
/// length 4q at offsets 0, q, 2q, 3q: with `t0 = x0 + x2`, `t1 = x0 − x2`,
/// `t2 = x1 + x3`, `t3 = −i (x1 − x3)`, row 0 gets `t0 + t2`, row 1
/// `(t0 − t2)·w2`, row 2 `(t1 + t3)·w1`, row 3 `(t1 − t3)·w3` (the order two
/// radix-2 stages leave them in). `w = None`: all twiddles 1.
#[inline(always)]
fn radix4(re: Rows4, im: Rows4, w: Option<[(f64, f64); 3]>) {
    let [r0, r1, r2, r3] = re;
    let [i0, i1, i2, i3] = im;
    let n = r0.len();
    let (r1, r2, r3) = (&mut r1[..n], &mut r2[..n], &mut r3[..n]);
    let (i0, i1, i2, i3) = (&mut i0[..n], &mut i1[..n], &mut i2[..n], &mut i3[..n]);
    match w {
        None => {
            for l in 0..n {
                let (t0r, t0i) = (r0[l] + r2[l], i0[l] + i2[l]);
                let (t1r, t1i) = (r0[l] - r2[l], i0[l] - i2[l]);
                let (t2r, t2i) = (r1[l] + r3[l], i1[l] + i3[l]);
                let (t3r, t3i) = (i1[l] - i3[l], r3[l] - r1[l]);
                r0[l] = t0r + t2r;
                i0[l] = t0i + t2i;
                r1[l] = t0r - t2r;
                i1[l] = t0i - t2i;
                r2[l] = t1r + t3r;
                i2[l] = t1i + t3i;
                r3[l] = t1r - t3r;
                i3[l] = t1i - t3i;
            }
        }
        Some([(w1r, w1i), (w2r, w2i), (w3r, w3i)]) => {
            for l in 0..n {
                let (t0r, t0i) = (r0[l] + r2[l], i0[l] + i2[l]);
                let (t1r, t1i) = (r0[l] - r2[l], i0[l] - i2[l]);
                let (t2r, t2i) = (r1[l] + r3[l], i1[l] + i3[l]);
                let (t3r, t3i) = (i1[l] - i3[l], r3[l] - r1[l]);
                r0[l] = t0r + t2r;
                i0[l] = t0i + t2i;
                let (ar, ai) = (t0r - t2r, t0i - t2i);
                r1[l] = ar * w2r - ai * w2i;
                i1[l] = ar * w2i + ai * w2r;
                let (br, bi) = (t1r + t3r, t1i + t3i);
                r2[l] = br * w1r - bi * w1i;
                i2[l] = br * w1i + bi * w1r;
                let (cr, ci) = (t1r - t3r, t1i - t3i);
                r3[l] = cr * w3r - ci * w3i;
                i3[l] = cr * w3i + ci * w3r;
            }
        }
    }
}

/// Rows `r0 < r1` (at `stride`), lanes `c0..c0 + w`, of one array.
#[inline(always)]
fn two_rows(
    v: &mut [f64],
    stride: usize,
    r0: usize,
    r1: usize,
    c0: usize,
    w: usize,
) -> (&mut [f64], &mut [f64]) {
    let (lo, hi) = v.split_at_mut(r1 * stride);
    (&mut lo[r0 * stride + c0..][..w], &mut hi[c0..][..w])
}

/// Rows `r, r + q, r + 2q, r + 3q` (q ≥ 1, at `stride`), lanes
/// `c0..c0 + w`, of one array.
#[inline(always)]
fn four_rows(v: &mut [f64], stride: usize, r: usize, q: usize, c0: usize, w: usize) -> Rows4<'_> {
    let d = q * stride;
    let v = &mut v[r * stride + c0..];
    let (a, v) = v.split_at_mut(d);
    let (b, v) = v.split_at_mut(d);
    let (c, e) = v.split_at_mut(d);
    [&mut a[..w], &mut b[..w], &mut c[..w], &mut e[..w]]
}

/// Rows `r, r + q, ..., r + (K − 1)·q` (q ≥ 1, at `stride`), lanes
/// `c0..c0 + w` (within a row), of one array; with `rev_order`, slot k
/// holds row `r + rev(k)·q` (`rev`: K's bit reversal).
#[inline(always)]
fn rows_mut<const K: usize>(
    v: &mut [f64],
    stride: usize,
    r: usize,
    q: usize,
    c0: usize,
    w: usize,
    rev_order: bool,
) -> [&mut [f64]; K] {
    let d = q * stride;
    let mut rest = &mut v[r * stride + c0..];
    let mut rows: [&mut [f64]; K] = std::array::from_fn(|k| {
        let tail = std::mem::take(&mut rest);
        if k + 1 < K {
            let (row, tail) = tail.split_at_mut(d);
            rest = tail;
            &mut row[..w]
        } else {
            &mut tail[..w]
        }
    });
    if rev_order {
        let bits = K.trailing_zeros();
        for k in 0..K {
            let j = k.reverse_bits() >> (usize::BITS - bits);
            if k < j {
                rows.swap(k, j);
            }
        }
    }
    rows
}

/// Rows `r..r + K` (at `stride`), lanes `c0..c0 + w`, of one array.
#[inline(always)]
fn rows_at<const K: usize>(v: &[f64], stride: usize, r: usize, c0: usize, w: usize) -> [&[f64]; K] {
    std::array::from_fn(|k| &v[(r + k) * stride + c0..][..w])
}

/// Lanes per chunk of the fused kernels: values of a chunk are loaded into
/// local arrays, transformed and stored, so the compiler keeps them in
/// vector registers without alias checks between the 32 rows.
const CHUNK: usize = 4;

/// The fused radix-8 butterfly (see [`radix8_last`]) on `L` lanes: `x[r]`
/// and `x[8 + r]` are row r's real and imaginary parts; returns the rows.
#[inline(always)]
fn radix8_lanes<const L: usize>(x: &[[f64; L]; 16], w: [(f64, f64); 3]) -> [[f64; L]; 16] {
    let [(w1r, w1i), (w2r, w2i), (w3r, w3i)] = w;
    let mut y = [[0.0; L]; 16];
    for l in 0..L {
        let (r, i) = (|k: usize| x[k][l], |k: usize| x[8 + k][l]);
        // Rows 0, 2, 4, 6: radix 4, twiddles 1.
        let (t0r, t0i) = (r(0) + r(4), i(0) + i(4));
        let (t1r, t1i) = (r(0) - r(4), i(0) - i(4));
        let (t2r, t2i) = (r(2) + r(6), i(2) + i(6));
        let (t3r, t3i) = (i(2) - i(6), r(6) - r(2));
        let (y0r, y0i) = (t0r + t2r, t0i + t2i);
        let (y2r, y2i) = (t0r - t2r, t0i - t2i);
        let (y4r, y4i) = (t1r + t3r, t1i + t3i);
        let (y6r, y6i) = (t1r - t3r, t1i - t3i);
        // Rows 1, 3, 5, 7: radix 4 with twiddles.
        let (t0r, t0i) = (r(1) + r(5), i(1) + i(5));
        let (t1r, t1i) = (r(1) - r(5), i(1) - i(5));
        let (t2r, t2i) = (r(3) + r(7), i(3) + i(7));
        let (t3r, t3i) = (i(3) - i(7), r(7) - r(3));
        let (y1r, y1i) = (t0r + t2r, t0i + t2i);
        let (ar, ai) = (t0r - t2r, t0i - t2i);
        let (y3r, y3i) = (ar * w2r - ai * w2i, ar * w2i + ai * w2r);
        let (br, bi) = (t1r + t3r, t1i + t3i);
        let (y5r, y5i) = (br * w1r - bi * w1i, br * w1i + bi * w1r);
        let (cr, ci) = (t1r - t3r, t1i - t3i);
        let (y7r, y7i) = (cr * w3r - ci * w3i, cr * w3i + ci * w3r);
        // Radix 2 on the pairs.
        let out = [
            y0r + y1r,
            y0r - y1r,
            y2r + y3r,
            y2r - y3r,
            y4r + y5r,
            y4r - y5r,
            y6r + y7r,
            y6r - y7r,
            y0i + y1i,
            y0i - y1i,
            y2i + y3i,
            y2i - y3i,
            y4i + y5i,
            y4i - y5i,
            y6i + y7i,
            y6i - y7i,
        ];
        for (k, v) in out.into_iter().enumerate() {
            y[k][l] = v;
        }
    }
    y
}

/// The last two stages of a transform whose length has an odd log₂,
/// fused: over lanes, the eight rows of a sub-transform of length 8
/// (`src`, consecutive) go through the radix-4 butterflies of that stage
/// (rows 0, 2, 4, 6 without twiddles; rows 1, 3, 5, 7 with `w`) and then
/// the radix-2 butterflies of rows (0, 1), (2, 3), (4, 5), (6, 7): the same
/// operations as [`radix4`] then [`butterfly_one`], in registers, written
/// to the rows `dst` (one memory pass where those are two).
#[inline(always)]
fn radix8_last(
    sr: [&[f64]; 8],
    si: [&[f64]; 8],
    dr: [&mut [f64]; 8],
    di: [&mut [f64]; 8],
    w: [(f64, f64); 3],
) {
    let n = sr[0].len();
    let src: [&[f64]; 16] =
        std::array::from_fn(|k| if k < 8 { &sr[k][..n] } else { &si[k - 8][..n] });
    let [d0, d1, d2, d3, d4, d5, d6, d7] = dr;
    let [e0, e1, e2, e3, e4, e5, e6, e7] = di;
    let mut dst: [&mut [f64]; 16] = [
        d0, d1, d2, d3, d4, d5, d6, d7, e0, e1, e2, e3, e4, e5, e6, e7,
    ];
    let whole = n - n % CHUNK;
    let mut l = 0;
    while l < whole {
        let x: [[f64; CHUNK]; 16] =
            std::array::from_fn(|k| src[k][l..l + CHUNK].try_into().expect("chunk"));
        let y = radix8_lanes(&x, w);
        for (d, y) in dst.iter_mut().zip(&y) {
            d[l..l + CHUNK].copy_from_slice(y);
        }
        l += CHUNK;
    }
    while l < n {
        let x: [[f64; 1]; 16] = std::array::from_fn(|k| [src[k][l]]);
        let y = radix8_lanes(&x, w);
        for (d, y) in dst.iter_mut().zip(&y) {
            d[l] = y[0];
        }
        l += 1;
    }
}

/// The last stage of a transform whose length has an even log₂: the four
/// rows of a sub-transform of length 4 (`src`, consecutive) through
/// [`radix4`] without twiddles, written to the rows `dst`.
#[inline(always)]
fn radix4_last(sr: [&[f64]; 4], si: [&[f64]; 4], dr: [&mut [f64]; 4], di: [&mut [f64]; 4]) {
    let n = sr[0].len();
    let sr = sr.map(|s| &s[..n]);
    let si = si.map(|s| &s[..n]);
    let [d0, d1, d2, d3] = dr;
    let [e0, e1, e2, e3] = di;
    let (d0, d1, d2, d3) = (&mut d0[..n], &mut d1[..n], &mut d2[..n], &mut d3[..n]);
    let (e0, e1, e2, e3) = (&mut e0[..n], &mut e1[..n], &mut e2[..n], &mut e3[..n]);
    for l in 0..n {
        let (t0r, t0i) = (sr[0][l] + sr[2][l], si[0][l] + si[2][l]);
        let (t1r, t1i) = (sr[0][l] - sr[2][l], si[0][l] - si[2][l]);
        let (t2r, t2i) = (sr[1][l] + sr[3][l], si[1][l] + si[3][l]);
        let (t3r, t3i) = (si[1][l] - si[3][l], sr[3][l] - sr[1][l]);
        d0[l] = t0r + t2r;
        e0[l] = t0i + t2i;
        d1[l] = t0r - t2r;
        e1[l] = t0i - t2i;
        d2[l] = t1r + t3r;
        e2[l] = t1i + t3i;
        d3[l] = t1r - t3r;
        e3[l] = t1i - t3i;
    }
}

impl LaneFft {
    fn new(n: usize) -> LaneFft {
        let (mut wr, mut wi) = (vec![], vec![]);
        for k in 0..n {
            let a = -std::f64::consts::TAU * k as f64 / n as f64;
            wr.push(libm::cos(a));
            wi.push(libm::sin(a));
        }
        let bits = n.trailing_zeros();
        let rev: Vec<usize> = (0..n)
            .map(|r| {
                if bits == 0 {
                    r
                } else {
                    r.reverse_bits() >> (usize::BITS - bits)
                }
            })
            .collect();
        LaneFft { n, wr, wi, rev }
    }

    /// Transform lanes `from..to` of the `n` rows of `re`/`im` that start
    /// every `stride` values (row r's lane l at `r · stride + l`), in place;
    /// coefficient k is left in row `rev[k]`.
    fn run(&self, re: &mut [f64], im: &mut [f64], stride: usize, from: usize, to: usize) {
        let mut c0 = from;
        while c0 < to {
            let w = (c0 + LANES).min(to) - c0;
            self.stages(re, im, stride, c0, w, 1);
            if self.n.trailing_zeros() % 2 == 1 {
                for b in (0..self.n).step_by(2) {
                    let (ar, br) = two_rows(re, stride, b, b + 1, c0, w);
                    let (ai, bi) = two_rows(im, stride, b, b + 1, c0, w);
                    butterfly_one(ar, ai, br, bi);
                }
            }
            c0 += w;
        }
    }

    /// [`LaneFft::run`] with its last stage out of place: lanes `from..to`
    /// of the rows of `re`/`im` are transformed (and overwritten on the
    /// way), the coefficients written to the rows of `dr`/`di` (same
    /// `stride`): coefficient k to row k when `ordered`, else to row
    /// `rev[k]` as `run` leaves them. The same numbers as `run`, bit for
    /// bit, with one memory pass less when log₂ n is odd (the last radix-4
    /// and the radix-2 stage fused, [`radix8_last`]), and the reordering
    /// (a pass of row swaps) folded into the last stage's stores.
    #[allow(clippy::too_many_arguments)]
    fn run_to(
        &self,
        re: &mut [f64],
        im: &mut [f64],
        dr: &mut [f64],
        di: &mut [f64],
        stride: usize,
        from: usize,
        to: usize,
        ordered: bool,
    ) {
        let n = self.n;
        // The last stage's length: 8 (fused) or 4; the radix-4 stages
        // before it in place.
        let last = if n.trailing_zeros() % 2 == 1 { 8 } else { 4 };
        let mut c0 = from;
        while c0 < to {
            let w = (c0 + LANES).min(to) - c0;
            if n < last {
                // n = 1 or 2: in order as they are.
                self.run(re, im, stride, c0, c0 + w);
                for r in 0..n {
                    dr[r * stride + c0..][..w].copy_from_slice(&re[r * stride + c0..][..w]);
                    di[r * stride + c0..][..w].copy_from_slice(&im[r * stride + c0..][..w]);
                }
            } else {
                self.stages(re, im, stride, c0, w, last);
                // Block b's output k is coefficient rev[b + k] = rev[b] +
                // rev_last(k)·(n/last): in order, the rows rev[b] + j·n/last
                // in the bit-reversed order of j.
                let q = n / last;
                let to_row = |b: usize| if ordered { (self.rev[b], q) } else { (b, 1) };
                if last == 8 {
                    let tw = [1, 2, 3].map(|m| (self.wr[m * q], self.wi[m * q]));
                    for b in (0..n).step_by(8) {
                        let (r, d) = to_row(b);
                        radix8_last(
                            rows_at(re, stride, b, c0, w),
                            rows_at(im, stride, b, c0, w),
                            rows_mut(dr, stride, r, d, c0, w, ordered),
                            rows_mut(di, stride, r, d, c0, w, ordered),
                            tw,
                        );
                    }
                } else {
                    for b in (0..n).step_by(4) {
                        let (r, d) = to_row(b);
                        radix4_last(
                            rows_at(re, stride, b, c0, w),
                            rows_at(im, stride, b, c0, w),
                            rows_mut(dr, stride, r, d, c0, w, ordered),
                            rows_mut(di, stride, r, d, c0, w, ordered),
                        );
                    }
                }
            }
            c0 += w;
        }
    }

    /// The radix-4 stages for lanes `c0..c0 + w`, in place, from the whole
    /// length down to sub-transforms of length `last` (exclusive).
    fn stages(
        &self,
        re: &mut [f64],
        im: &mut [f64],
        stride: usize,
        c0: usize,
        w: usize,
        last: usize,
    ) {
        let n = self.n;
        // Sub-transforms of length `len`, four rows `q` apart each.
        let mut len = n;
        while len >= 4 && len > last {
            let q = len / 4;
            let step = n / len;
            for b in (0..n).step_by(len) {
                for j in 0..q {
                    let tw = (j > 0)
                        .then(|| [1, 2, 3].map(|m| (self.wr[m * j * step], self.wi[m * j * step])));
                    radix4(
                        four_rows(re, stride, b + j, q, c0, w),
                        four_rows(im, stride, b + j, q, c0, w),
                        tw,
                    );
                }
            }
            len = q;
        }
    }
}

/// `d[x·ny + ky] = s[rev[ky]·nx + x]`: an `nx`-wide plane whose row
/// `rev[ky]` holds `ky`, transposed. With both sides even, by 2 × 2 blocks
/// (two loads of adjacent values, two stores of adjacent values: vector
/// moves and shuffles) rather than one strided store per value.
fn transpose(s: &[f64], d: &mut [f64], rev: &[usize], nx: usize, ny: usize) {
    if !nx.is_multiple_of(2) || !ny.is_multiple_of(2) {
        for (ky, &row) in rev.iter().enumerate() {
            for (x, &v) in s[row * nx..(row + 1) * nx].iter().enumerate() {
                d[x * ny + ky] = v;
            }
        }
        return;
    }
    for ky in (0..ny).step_by(2) {
        let a = s[rev[ky] * nx..][..nx].chunks_exact(2);
        let b = s[rev[ky + 1] * nx..][..nx].chunks_exact(2);
        for ((a, b), d) in a.zip(b).zip(d.chunks_exact_mut(2 * ny)) {
            d[ky..ky + 2].copy_from_slice(&[a[0], b[0]]);
            d[ny + ky..ny + ky + 2].copy_from_slice(&[a[1], b[1]]);
        }
    }
}

/// The weight of the `kz` plane of a half spectrum of a volume `nz` deep:
/// how many coefficients of the whole spectrum each of its entries stands
/// for (1 on the planes kz = 0 and kz = nz/2, whose conjugates lie in
/// themselves; 2 on the others, whose conjugates are not kept).
pub fn plane_weight(kz: usize, nz: usize) -> f64 {
    if kz == 0 || 2 * kz == nz {
        1.0
    } else {
        2.0
    }
}

/// A forward 3-D FFT of real `nx × ny × nz` volumes (x fastest) giving the
/// coefficients with `kz ≤ nz/2` (the others are their complex conjugates:
/// `X[kx, ky, kz] = conj X[−kx, −ky, nz − kz]`, indices mod the sides), as
/// separate real and imaginary parts laid out `ky + ny·(kx + nx·kz)`.
/// Plans, scratch and the output are kept between calls: a fit's thousands
/// of transforms allocate nothing.
///
/// The steps, each a [`LaneFft`] over contiguous lanes: along z a real
/// transform (even and odd planes packed as one complex signal of length
/// nz/2, then split), along y per kz plane, then each plane transposed and
/// along x. Pure `f64` arithmetic with `libm` twiddles: the same bytes
/// natively and in wasm.
#[derive(Clone)]
pub struct RealFft3 {
    dims: [usize; 3],
    /// kz planes kept: nz/2 + 1 (1 for a flat z).
    planes: usize,
    /// Length nz/2 along z (the packed real transform), y, x.
    fz: LaneFft,
    fy: LaneFft,
    fx: LaneFft,
    /// `W_nz^k` for k ≤ nz/2 (the real transform's split).
    zr: Vec<f64>,
    zi: Vec<f64>,
    /// Packed z signals of one block of lanes: nz/2 rows of [`LANES`].
    pr: Vec<f64>,
    pi: Vec<f64>,
    /// After z and y: planes of `ky · nx + x`.
    ar: Vec<f64>,
    ai: Vec<f64>,
    /// The result: planes of `kx · ny + ky`.
    br: Vec<f64>,
    bi: Vec<f64>,
}

impl std::fmt::Debug for RealFft3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RealFft3")
            .field("dims", &self.dims)
            .finish()
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
        let planes = if nz > 1 { nz / 2 + 1 } else { 1 };
        let m = (nz / 2).max(1);
        let (mut zr, mut zi) = (vec![], vec![]);
        for k in 0..=nz / 2 {
            let a = -std::f64::consts::TAU * k as f64 / nz as f64;
            zr.push(libm::cos(a));
            zi.push(libm::sin(a));
        }
        let len = planes * nx * ny;
        Ok(RealFft3 {
            dims,
            planes,
            fz: LaneFft::new(m),
            fy: LaneFft::new(ny),
            fx: LaneFft::new(nx),
            zr,
            zi,
            pr: vec![0.0; m * LANES],
            pi: vec![0.0; m * LANES],
            ar: vec![0.0; len],
            ai: vec![0.0; len],
            br: vec![0.0; len],
            bi: vec![0.0; len],
        })
    }

    /// The shape this transform takes.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The kz planes kept: `nz/2 + 1` (1 for a flat z).
    pub fn planes(&self) -> usize {
        self.planes
    }

    /// The half spectrum of `values` (`nx·ny·nz` of them, x fastest): real
    /// and imaginary parts laid out `ky + ny·(kx + nx·kz)`, `kz ≤ nz/2`.
    pub fn forward(&mut self, values: &[f64]) -> Result<(&[f64], &[f64])> {
        let [nx, ny, nz] = self.dims;
        if values.len() != nx * ny * nz {
            return Err(Error::input(format!(
                "a {nx}×{ny}×{nz} transform needs {} values (got {})",
                nx * ny * nz,
                values.len()
            )));
        }
        let plane = nx * ny;
        // z: real to complex, by blocks of lanes.
        if nz == 1 {
            self.ar.copy_from_slice(values);
            self.ai.fill(0.0);
        } else {
            let m = nz / 2;
            let mut c0 = 0;
            while c0 < plane {
                let w = LANES.min(plane - c0);
                for j in 0..m {
                    self.pr[j * LANES..][..w].copy_from_slice(&values[2 * j * plane + c0..][..w]);
                    self.pi[j * LANES..][..w]
                        .copy_from_slice(&values[(2 * j + 1) * plane + c0..][..w]);
                }
                self.fz.run(&mut self.pr, &mut self.pi, LANES, 0, w);
                self.split_z(c0, w);
                c0 += w;
            }
        }
        // y: per kz plane, lanes along x, from `a` into `b` (coefficient
        // ky left in row `fy.rev[ky]`, read so by the transpose).
        for kz in 0..self.planes {
            let r = kz * plane..(kz + 1) * plane;
            let (sr, si) = (&mut self.ar[r.clone()], &mut self.ai[r.clone()]);
            let (dr, di) = (&mut self.br[r.clone()], &mut self.bi[r]);
            self.fy.run_to(sr, si, dr, di, nx, 0, nx, false);
        }
        // x: per plane, transposed back into `a` so that the lanes run
        // along ky, then transformed into `b`, in order.
        for kz in 0..self.planes {
            let r = kz * plane..(kz + 1) * plane;
            for (src, dst) in [(&self.br, &mut self.ar), (&self.bi, &mut self.ai)] {
                transpose(&src[r.clone()], &mut dst[r.clone()], &self.fy.rev, nx, ny);
            }
            let (sr, si) = (&mut self.ar[r.clone()], &mut self.ai[r.clone()]);
            let (dr, di) = (&mut self.br[r.clone()], &mut self.bi[r]);
            self.fx.run_to(sr, si, dr, di, ny, 0, ny, true);
        }
        Ok((&self.br, &self.bi))
    }

    /// The real transform's last step for lanes `c0..c0 + w`: from the
    /// packed spectrum `Z` (length m = nz/2, in `pr`/`pi`) the coefficients
    /// `X[k] = E[k] + W^k O[k]`, `E = (Z[k] + conj Z[m−k])/2`,
    /// `O = (Z[k] − conj Z[m−k])/2i`, for k = 0..=m, into `ar`/`ai`.
    fn split_z(&mut self, c0: usize, w: usize) {
        let m = self.dims[2] / 2;
        let plane = self.dims[0] * self.dims[1];
        // k = 0 and k = m (from Z[0] alone), then k and m − k together:
        // one load of Z[k] and Z[m − k] and their sums (which commute
        // exactly) serve both, each X computed by the formula's own
        // operations (the same bits as one k at a time).
        {
            let a = self.fz.rev[0];
            let (ar, ai) = (&self.pr[a * LANES..][..w], &self.pi[a * LANES..][..w]);
            for (k, sign) in [(0, 1.0), (m, -1.0)] {
                let xr = &mut self.ar[k * plane + c0..][..w];
                for l in 0..w {
                    xr[l] = ar[l] + sign * ai[l];
                }
                self.ai[k * plane + c0..][..w].fill(0.0);
            }
        }
        for k in 1..=m / 2 {
            let j = m - k;
            let (a, b) = (self.fz.rev[k], self.fz.rev[j]);
            if k == j {
                // X[m/2] alone: the formula with Z[m − k] = Z[k] (x − x
                // is 0 only for finite x, so it is computed as written).
                let (ar, ai) = (&self.pr[a * LANES..][..w], &self.pi[a * LANES..][..w]);
                let (br, bi) = (ar, ai);
                let (wr, wi) = (self.zr[k], self.zi[k]);
                let xr = &mut self.ar[k * plane + c0..][..w];
                let xi = &mut self.ai[k * plane + c0..][..w];
                for l in 0..w {
                    let (er, ei) = ((ar[l] + br[l]) * 0.5, (ai[l] - bi[l]) * 0.5);
                    let (or, oi) = ((ai[l] + bi[l]) * 0.5, (br[l] - ar[l]) * 0.5);
                    xr[l] = er + (wr * or - wi * oi);
                    xi[l] = ei + (wr * oi + wi * or);
                }
                continue;
            }
            let (ar, ai) = (&self.pr[a * LANES..][..w], &self.pi[a * LANES..][..w]);
            let (br, bi) = (&self.pr[b * LANES..][..w], &self.pi[b * LANES..][..w]);
            let (wr, wi) = (self.zr[k], self.zi[k]);
            let (vr, vi) = (self.zr[j], self.zi[j]);
            let (lo_r, hi_r) = self.ar.split_at_mut(j * plane);
            let (lo_i, hi_i) = self.ai.split_at_mut(j * plane);
            let (xr, xi) = (
                &mut lo_r[k * plane + c0..][..w],
                &mut lo_i[k * plane + c0..][..w],
            );
            let (yr, yi) = (&mut hi_r[c0..][..w], &mut hi_i[c0..][..w]);
            for l in 0..w {
                let (sr, si) = ((ar[l] + br[l]) * 0.5, (ai[l] + bi[l]) * 0.5);
                // X[k] = E + W^k O: E = (sr, (ai − bi)/2), O = (si, (br − ar)/2).
                let (ei, oi) = ((ai[l] - bi[l]) * 0.5, (br[l] - ar[l]) * 0.5);
                xr[l] = sr + (wr * si - wi * oi);
                xi[l] = ei + (wr * oi + wi * si);
                // X[m − k]: E = (sr, (bi − ai)/2), O = (si, (ar − br)/2).
                let (ei, oi) = ((bi[l] - ai[l]) * 0.5, (ar[l] - br[l]) * 0.5);
                yr[l] = sr + (vr * si - vi * oi);
                yi[l] = ei + (vr * oi + vi * si);
            }
        }
    }

    /// The whole spectrum (`kx + nx·(ky + ny·kz)`) from a half one given by
    /// [`RealFft3::forward`]: the missing coefficients are conjugates.
    pub fn whole(&self, re: &[f64], im: &[f64]) -> Vec<C64> {
        let [nx, ny, nz] = self.dims;
        let at = |kx: usize, ky: usize, kz: usize| {
            let i = ky + ny * (kx + nx * kz);
            C64::new(re[i], im[i])
        };
        let mut out = Vec::with_capacity(nx * ny * nz);
        for kz in 0..nz {
            for ky in 0..ny {
                for kx in 0..nx {
                    out.push(if kz < self.planes {
                        at(kx, ky, kz)
                    } else {
                        at((nx - kx) % nx, (ny - ky) % ny, nz - kz).conj()
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
    let fx = (w > 1).then(|| Plan::new(w, inverse));
    let fy = (h > 1).then(|| Plan::new(h, inverse));
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
            [2, 64, 8],
            [4, 2, 128],
            // Every length from 1 to 256 on each axis (radix-4 stages and
            // the odd radix-2 one; z halves its length).
            [32, 2, 2],
            [2, 32, 4],
            [256, 1, 2],
            [1, 256, 2],
            [2, 2, 256],
            [1, 1, 512],
            [128, 4, 2],
        ] {
            let len: usize = dims.iter().product();
            let v: Vec<f64> = (0..len).map(|_| r.f64() - 0.5).collect();
            let mut f = RealFft3::new(dims).unwrap();
            let (re, im) = f.forward(&v).unwrap();
            let (re, im) = (re.to_vec(), im.to_vec());
            assert_eq!(re.len(), f.planes() * dims[0] * dims[1]);
            let whole = f.whole(&re, &im);
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

    /// [`LaneFft::run_to`] (fused last stages, out of place, in order or
    /// not) gives [`LaneFft::run`]'s numbers bit for bit, rows reordered:
    /// every length to 512, lane counts that fill no chunk or block (1, 3,
    /// 67), lanes starting inside a row.
    #[test]
    fn the_fused_out_of_place_lane_fft_equals_the_staged_one_bit_for_bit() {
        let mut r = Rng::new(5);
        for bits in 0..=9 {
            let n = 1usize << bits;
            let f = LaneFft::new(n);
            for (stride, from, to) in [(1, 0, 1), (3, 0, 3), (70, 2, 69), (130, 1, 130)] {
                let re: Vec<f64> = (0..n * stride).map(|_| r.f64() - 0.5).collect();
                let im: Vec<f64> = (0..n * stride).map(|_| r.f64() - 0.5).collect();
                let (mut wr, mut wi) = (re.clone(), im.clone());
                f.run(&mut wr, &mut wi, stride, from, to);
                for ordered in [false, true] {
                    let (mut sr, mut si) = (re.clone(), im.clone());
                    let (mut dr, mut di) = (vec![7.0; n * stride], vec![7.0; n * stride]);
                    f.run_to(
                        &mut sr, &mut si, &mut dr, &mut di, stride, from, to, ordered,
                    );
                    for k in 0..n {
                        let row = if ordered { f.rev[k] } else { k };
                        for l in 0..stride {
                            let (a, b) = (k * stride + l, row * stride + l);
                            let want = if (from..to).contains(&l) {
                                (wr[b].to_bits(), wi[b].to_bits())
                            } else {
                                (7f64.to_bits(), 7f64.to_bits())
                            };
                            let got = (dr[a].to_bits(), di[a].to_bits());
                            assert_eq!(got, want, "n {n}, row {k}, lane {l}, ordered {ordered}");
                        }
                    }
                }
            }
        }
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

    /// [`leaf`] is the kernel rustfft's own planner picks: the same bits
    /// for every length ≤ [`LEAF`] and both directions.
    #[test]
    fn leaves_are_the_planners_kernels() {
        let mut planner = rustfft::FftPlanner::<f64>::new();
        for n in [1usize, 2, 4, 8, 16, 32] {
            for inverse in [false, true] {
                let theirs = if inverse {
                    planner.plan_fft_inverse(n)
                } else {
                    planner.plan_fft_forward(n)
                };
                let ours = leaf(n, inverse);
                assert_eq!(ours.len(), n);
                let input: Vec<C64> = (0..n)
                    .map(|k| C64::new((k as f64 * 0.37).sin() + 0.1, (k as f64 * 1.3).cos() - 0.2))
                    .collect();
                let (mut a, mut b) = (input.clone(), input);
                theirs.process(&mut a);
                ours.process(&mut b);
                let bits = |v: &[C64]| {
                    v.iter()
                        .flat_map(|c| [c.re.to_bits(), c.im.to_bits()])
                        .collect::<Vec<_>>()
                };
                assert_eq!(bits(&a), bits(&b), "n={n} inverse={inverse}");
            }
        }
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
        let (re, im) = f.forward(&v).unwrap();
        let (re, im) = (re.to_vec(), im.to_vec());
        let whole = f.whole(&re, &im);
        let c: Vec<C64> = v.iter().map(|&x| C64::new(x, 0.0)).collect();
        let want = naive(&c, dims, -1.0);
        for (i, (a, b)) in whole.iter().zip(&want).enumerate() {
            assert!((a - b).norm() < 1e-9, "at {i}: {a} vs {b}");
        }
    }
}

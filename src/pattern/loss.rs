//! The loss between the pattern's and the target's colour fields (paper §4
//! "Loss Function", Eq. 2–4) and its exact gradient.
//!
//! `L = L_S + α_N·L_N`, `L_S = 1/|C| Σ_c mean (S_c(G) − S_c(I))²`,
//! `L_N = 1/|C| Σ_c mean (1 − ⟨n_G, n_I⟩²)`, `α_N = 0.05`.
//!
//! Normals `n = ∇S/|∇S|` are central differences on the grid for both
//! fields (the target field only exists on the grid); the normal term is
//! differentiated through that stencil, so the gradient is exact for the
//! loss as computed. Pixels where either gradient vanishes contribute 0.
//!
//! Units ([`SdfUnits`]): the paper does not say. With fields in canvas units
//! (0..1) `L_S` is ~1e-3 near a fit while `L_N` stays ~0.1, so `0.05·L_N`
//! dominates and pulls fits towards edge alignment only; in pixel units of
//! the loss grid (the default) `L_S` is ~1–100 and leads, with `L_N`
//! refining near convergence as the paper describes. `filigree bench fit`
//! reports both.
use super::field::{Evaluator, Grid, Scene};
use super::record::Canvas;
use super::target::{coverage, Target};
use serde::{Deserialize, Serialize};
use wide::{f64x4, CmpGt, CmpNe};

/// Which loss to minimise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LossKind {
    /// The paper's loss: L2 of the fields plus 0.05 × normal alignment.
    #[default]
    Sdf,
    /// Mean absolute difference of the fields.
    L1,
    /// L2 of the field difference summed over a Gaussian pyramid.
    Pyramid,
    /// L2 of the rendered colour coverage (1-pixel anti-aliased) against the
    /// target's coverage read from its field the same way: differentiable
    /// rendering, for comparison.
    Image,
}

impl LossKind {
    /// Parse `sdf | l1 | pyramid | image`.
    pub fn parse(s: &str) -> Option<LossKind> {
        Some(match s {
            "sdf" => LossKind::Sdf,
            "l1" => LossKind::L1,
            "pyramid" => LossKind::Pyramid,
            "image" => LossKind::Image,
            _ => return None,
        })
    }
}

/// The unit of field values in the loss.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SdfUnits {
    /// Pixels of the loss grid (canvas distance × grid pixels per canvas
    /// unit: × grid size on the square canvas). Default.
    #[default]
    Pixels,
    /// Canvas units (the canvas's shorter side is 1).
    Canvas,
}

/// Loss settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LossOptions {
    pub kind: LossKind,
    /// Loss grid side in pixels (default 128; at least 8, at most 1024);
    /// on a canvas that is not square, its longer side ([`Grid::on`]).
    pub grid: usize,
    /// α_N, the weight of the normal-alignment term (default 0.05).
    pub normal_weight: f64,
    pub units: SdfUnits,
}

impl Default for LossOptions {
    fn default() -> Self {
        LossOptions {
            kind: LossKind::Sdf,
            grid: 128,
            normal_weight: 0.05,
            units: SdfUnits::Pixels,
        }
    }
}

impl LossOptions {
    /// Field units per canvas unit on the square canvas.
    pub fn scale(&self) -> f64 {
        self.scale_on(Canvas::SQUARE)
    }

    /// Field units per canvas unit on `canvas`: in pixels, the grid's
    /// pixels per canvas unit along the longer side ([`Grid::long_ppu`]).
    pub fn scale_on(&self, canvas: Canvas) -> f64 {
        match self.units {
            SdfUnits::Pixels => Grid::on(canvas, self.grid).long_ppu(),
            SdfUnits::Canvas => 1.0,
        }
    }
}

/// Unit central-difference normals of channel fields (zero where flat) on `g`.
fn normals(s: &[f64], g: &Grid, out: &mut Vec<[f64; 2]>) {
    out.clear();
    let nn = g.len();
    for c in 0..s.len() / nn {
        normals_rows(&s[c * nn..(c + 1) * nn], g.w, g.h, 0..g.h, out);
    }
}

/// Rows `rows` of one `w × h` channel field's normals (see [`normals`]),
/// appended to `out`: a job builds the normals a few rows at a time with it.
pub(crate) fn normals_rows(
    f: &[f64],
    w: usize,
    h: usize,
    rows: std::ops::Range<usize>,
    out: &mut Vec<[f64; 2]>,
) {
    for y in rows {
        for x in 0..w {
            let (xm, xp) = (x.saturating_sub(1), (x + 1).min(w - 1));
            let (ym, yp) = (y.saturating_sub(1), (y + 1).min(h - 1));
            let gx = (f[y * w + xp] - f[y * w + xm]) / (xp - xm).max(1) as f64;
            let gy = (f[yp * w + x] - f[ym * w + x]) / (yp - ym).max(1) as f64;
            let l = (gx * gx + gy * gy).sqrt();
            out.push(if l > 1e-12 {
                [gx / l, gy / l]
            } else {
                [0.0, 0.0]
            });
        }
    }
}

/// One 3×3 binomial blur + decimation by two of a `w × h` field, clamped
/// borders; the result and its size.
fn down(src: &[f64], (w, h): (usize, usize)) -> (Vec<f64>, (usize, usize)) {
    let (mw, mh) = (w.div_ceil(2), h.div_ceil(2));
    let k = [0.25, 0.5, 0.25];
    let mut out = vec![0.0; mw * mh];
    for y in 0..mh {
        for x in 0..mw {
            let mut acc = 0.0;
            for (dy, wy) in k.iter().enumerate() {
                let sy = (2 * y + dy).saturating_sub(1).min(h - 1);
                for (dx, wx) in k.iter().enumerate() {
                    let sx = (2 * x + dx).saturating_sub(1).min(w - 1);
                    acc += wy * wx * src[sy * w + sx];
                }
            }
            out[y * mw + x] = acc;
        }
    }
    (out, (mw, mh))
}

/// Transpose of [`down`]: scatter `g` (its output) back onto the `w × h` grid.
fn down_t(g: &[f64], (w, h): (usize, usize), out: &mut [f64]) {
    let (mw, mh) = (w.div_ceil(2), h.div_ceil(2));
    let k = [0.25, 0.5, 0.25];
    for y in 0..mh {
        for x in 0..mw {
            let v = g[y * mw + x];
            for (dy, wy) in k.iter().enumerate() {
                let sy = (2 * y + dy).saturating_sub(1).min(h - 1);
                for (dx, wx) in k.iter().enumerate() {
                    let sx = (2 * x + dx).saturating_sub(1).min(w - 1);
                    out[sy * w + sx] += wy * wx * v;
                }
            }
        }
    }
}

/// The loss of fields `s` against `t`; with `ds`, also dL/dS (same layout).
pub fn loss(
    opts: &LossOptions,
    s: &[f64],
    t: &Target,
    t_normals: &[[f64; 2]],
    ds: Option<&mut [f64]>,
) -> f64 {
    loss_with(opts, s, t, t_normals, ds, &mut Scratch::default())
}

/// The normal term's derivatives along one row, by pixel: with respect to
/// the pixel's x and y stencil differences ([`sdf_row`], [`scatter_row`]).
#[derive(Debug, Clone, Default)]
struct Scratch {
    gx: Vec<f64>,
    gy: Vec<f64>,
}

/// [`loss`] with a scratch row the caller keeps (no allocation per call).
fn loss_with(
    opts: &LossOptions,
    s: &[f64],
    t: &Target,
    t_normals: &[[f64; 2]],
    ds: Option<&mut [f64]>,
    scratch: &mut Scratch,
) -> f64 {
    if opts.kind != LossKind::Sdf {
        return loss_reference(opts, s, t, t_normals, ds);
    }
    let g = (t.grid.w, t.grid.h);
    let nn = t.grid.len();
    let channels = s.len() / nn;
    if channels == 0 {
        return 0.0;
    }
    let norm = 1.0 / (channels * nn) as f64;
    let w = opts.normal_weight;
    let normals = w != 0.0;
    let (mut sum_s, mut sum_n) = (0.0, 0.0);
    match ds {
        None => {
            for r in 0..channels * g.1 {
                let (a, b) =
                    sdf_row::<false>(s, &t.sdf, t_normals, g, r, normals, 0.0, (&mut [], &mut []));
                sum_s += a;
                sum_n += b;
            }
        }
        Some(d) => {
            // dL_S/dS row by row, each row set just before the normal
            // term's stencil first adds into it (while it is in cache).
            let set_row = |d: &mut [f64], r: usize| {
                let row = r * g.0..(r + 1) * g.0;
                for ((d, a), b) in d[row.clone()]
                    .iter_mut()
                    .zip(&s[row.clone()])
                    .zip(&t.sdf[row])
                {
                    *d = 2.0 * (a - b) * norm;
                }
            };
            for v in [&mut scratch.gx, &mut scratch.gy] {
                v.clear();
                v.resize(g.0, 0.0);
            }
            for r in 0..channels * g.1 {
                if r % g.1 == 0 {
                    set_row(d, r);
                }
                if (r + 1) % g.1 != 0 {
                    set_row(d, r + 1);
                }
                let (a, b) = sdf_row::<true>(
                    s,
                    &t.sdf,
                    t_normals,
                    g,
                    r,
                    normals,
                    norm * w,
                    (&mut scratch.gx, &mut scratch.gy),
                );
                sum_s += a;
                sum_n += b;
                if normals {
                    scatter_row(d, g, r, (&scratch.gx, &scratch.gy));
                }
            }
        }
    }
    sdf_total(sum_s, sum_n, norm, w)
}

/// `L_S + α_N·L_N` from the row sums of [`sdf_row`].
#[inline]
fn sdf_total(sum_s: f64, sum_n: f64, norm: f64, w: f64) -> f64 {
    let mut total = sum_s * norm;
    if w != 0.0 {
        total += w * (sum_n * norm);
    }
    total
}

/// One pixel's normal term `1 − ⟨g, t⟩²/|g|²` (0 where the target normal
/// or the field gradient `g` vanishes) and its derivative with respect to
/// `g`, `−2q/|g|²·(t − q·g/|g|²)` with `q = ⟨g, t⟩`: no square root, and
/// selects instead of branches so that rows vectorise.
#[inline(always)]
fn normal_px(gx: f64, gy: f64, tn: [f64; 2]) -> (f64, f64, f64) {
    let l2 = gx * gx + gy * gy;
    let q = gx * tn[0] + gy * tn[1];
    // (Bitwise, not short-circuit: no branch.)
    let ok = ((tn[0] != 0.0) | (tn[1] != 0.0)) & (l2 > 1e-24);
    let il2 = 1.0 / if ok { l2 } else { 1.0 };
    let qi = q * il2;
    let term = if ok { 1.0 - q * qi } else { 0.0 };
    let k = if ok { -2.0 * qi } else { 0.0 };
    (term, k * (tn[0] - qi * gx), k * (tn[1] - qi * gy))
}

/// [`normal_px`] on four pixels at once with explicit SIMD lanes: the
/// same IEEE operations in the same order lane by lane, and comparisons
/// with the same NaN behaviour (`!=` true, `>` false), so the same bits.
/// (LLVM leaves the scalar form unvectorised.)
#[inline(always)]
fn normal_px4(gx: f64x4, gy: f64x4, tx: f64x4, ty: f64x4) -> (f64x4, f64x4, f64x4) {
    let (zero, one) = (f64x4::ZERO, f64x4::ONE);
    let l2 = gx * gx + gy * gy;
    let q = gx * tx + gy * ty;
    let ok = (tx.cmp_ne(zero) | ty.cmp_ne(zero)) & l2.cmp_gt(f64x4::splat(1e-24));
    let il2 = one / ok.blend(l2, one);
    let qi = q * il2;
    let term = ok.blend(one - q * qi, zero);
    let k = ok.blend(f64x4::splat(-2.0) * qi, zero);
    (term, k * (tx - qi * gx), k * (ty - qi * gy))
}

/// Σ (a − b)² over `a` and `b` in four partial sums (lane `k` takes every
/// fourth element, the remainder goes to lane 0): four sums break the serial
/// add chain and vectorise. Callers combine the lanes in their own order.
fn squared_differences4(a: &[f64], b: &[f64]) -> [f64; 4] {
    let mut acc = [0.0f64; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for k in 0..4 {
            let e = x[k] - y[k];
            acc[k] += e * e;
        }
    }
    for (x, y) in ar.iter().zip(br) {
        acc[0] += (x - y) * (x - y);
    }
    acc
}
/// Row `r` (channel `r / h`, row `r % h`) of the SDF loss on a `w × h`
/// grid `(w, h)`: the sums of
/// `(S − T)²` and of the normal terms (central differences, one-sided at
/// the borders), each in four partial sums. With `G`, `gg[x]` receives the
/// normal term's derivative with respect to the pixel's stencil difference
/// (× `gscale` and the inverse spacing), for [`scatter_row`]. Both
/// [`loss`] and [`LossPass`] take every sum through here, so they give
/// the same bits.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sdf_row<const G: bool>(
    s: &[f64],
    t: &[f64],
    tn: &[[f64; 2]],
    (n, h): (usize, usize),
    r: usize,
    normals: bool,
    gscale: f64,
    (ggx, ggy): (&mut [f64], &mut [f64]),
) -> (f64, f64) {
    // (`n` is the row length: the square grid's side, as this was written.)
    let nn = n * h;
    let (c, y) = (r / h, r % h);
    let o = c * nn;
    let f = &s[o..o + nn];
    let row = &f[y * n..y * n + n];
    let tr = &t[o + y * n..o + y * n + n];
    let acc = squared_differences4(row, tr);
    let ls = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    if !normals {
        return (ls, 0.0);
    }
    let (ym, yp) = (y.saturating_sub(1), (y + 1).min(h - 1));
    let ihy = 1.0 / (yp - ym).max(1) as f64;
    let (up, dn) = (&f[ym * n..ym * n + n], &f[yp * n..yp * n + n]);
    let tnr = &tn[o + y * n..o + y * n + n];
    let mut an = [0.0f64; 4];
    // One pixel with its own stencil (the borders, and rows under 3 wide).
    let one = |x: usize, an: &mut [f64; 4], ggx: &mut [f64], ggy: &mut [f64]| {
        edge_px::<G>(x, (row, up, dn), tnr, ihy, gscale, an, (ggx, ggy))
    };
    if n < 3 {
        for x in 0..n {
            one(x, &mut an, ggx, ggy);
        }
    } else {
        one(0, &mut an, ggx, ggy);
        // The interior: central differences, four lanes.
        let m = n - 2;
        let (l, rr) = (&row[..m], &row[2..]);
        let (u, d) = (&up[1..n - 1], &dn[1..n - 1]);
        let tm = &tnr[1..n - 1];
        let chunks = m / 4;
        let mut acc_n = f64x4::new(an);
        let lanes = l
            .chunks_exact(4)
            .zip(rr.chunks_exact(4))
            .zip(u.chunks_exact(4).zip(d.chunks_exact(4)))
            .zip(tm.chunks_exact(4));
        for (ch, (((lc, rc), (uc, dc)), tc)) in lanes.enumerate() {
            let v = |a: &[f64]| f64x4::new([a[0], a[1], a[2], a[3]]);
            let gx = (v(rc) - v(lc)) * f64x4::splat(0.5);
            let gy = (v(dc) - v(uc)) * f64x4::splat(ihy);
            let tx = f64x4::new([tc[0][0], tc[1][0], tc[2][0], tc[3][0]]);
            let ty = f64x4::new([tc[0][1], tc[1][1], tc[2][1], tc[3][1]]);
            let (term, a, b) = normal_px4(gx, gy, tx, ty);
            acc_n += term;
            if G {
                // (`a · gscale · ½` in that order, as `one` does.)
                let a = (a * f64x4::splat(gscale) * f64x4::splat(0.5)).to_array();
                let b = (b * f64x4::splat(gscale) * f64x4::splat(ihy)).to_array();
                ggx[4 * ch + 1..4 * ch + 5].copy_from_slice(&a);
                ggy[4 * ch + 1..4 * ch + 5].copy_from_slice(&b);
            }
        }
        an = acc_n.to_array();
        for i in 4 * chunks..m {
            let gx = (rr[i] - l[i]) * 0.5;
            let gy = (d[i] - u[i]) * ihy;
            let (term, a, b) = normal_px(gx, gy, tm[i]);
            an[0] += term;
            if G {
                ggx[i + 1] = a * gscale * 0.5;
                ggy[i + 1] = b * gscale * ihy;
            }
        }
        one(n - 1, &mut an, ggx, ggy);
    }
    (ls, (an[0] + an[1]) + (an[2] + an[3]))
}

/// One pixel of [`sdf_row`] with its own stencil (one-sided at the row's
/// ends): its normal term into `an[0]`, with `G` its derivative into `gg[x]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn edge_px<const G: bool>(
    x: usize,
    (row, up, dn): (&[f64], &[f64], &[f64]),
    tnr: &[[f64; 2]],
    ihy: f64,
    gscale: f64,
    an: &mut [f64; 4],
    (ggx, ggy): (&mut [f64], &mut [f64]),
) {
    let n = row.len();
    let (xm, xp) = (x.saturating_sub(1), (x + 1).min(n - 1));
    let ihx = 1.0 / (xp - xm).max(1) as f64;
    let gx = (row[xp] - row[xm]) * ihx;
    let gy = (dn[x] - up[x]) * ihy;
    let (term, a, b) = normal_px(gx, gy, tnr[x]);
    an[0] += term;
    if G {
        ggx[x] = a * gscale * ihx;
        ggy[x] = b * gscale * ihy;
    }
}

/// Add the normal term's gradient of row `r` (from [`sdf_row`]'s `gg`)
/// into `d` through the central-difference stencil (`n` wide, `h` high).
fn scatter_row(d: &mut [f64], (n, h): (usize, usize), r: usize, (gx, gy): (&[f64], &[f64])) {
    let nn = n * h;
    let (c, y) = (r / h, r % h);
    let o = c * nn;
    let (ym, yp) = (y.saturating_sub(1), (y + 1).min(h - 1));
    {
        let row = &mut d[o + y * n..o + y * n + n];
        if n < 3 {
            for (x, g) in gx.iter().enumerate().take(n) {
                let (xm, xp) = (x.saturating_sub(1), (x + 1).min(n - 1));
                row[xp] += g;
                row[xm] -= g;
            }
        } else {
            // Gather form of `row[x + 1] += g[x]; row[x − 1] −= g[x]`.
            for j in 1..n - 1 {
                row[j] += gx[j - 1] - gx[j + 1];
            }
            // (Pixel 0 differences over [0, 1], pixel n − 1 over [n − 2, n − 1].)
            row[0] -= gx[0] + gx[1];
            row[n - 1] += gx[n - 2] + gx[n - 1];
        }
    }
    let (dp, dm) = (o + yp * n, o + ym * n);
    for (d, g) in d[dp..dp + n].iter_mut().zip(gy) {
        *d += g;
    }
    for (d, g) in d[dm..dm + n].iter_mut().zip(gy) {
        *d -= g;
    }
}

/// The loss as first written (the normal term with a square root and a
/// branch per pixel, scattered gradients): the reference the fast
/// [`loss`] is tested against, and the "before" figure of `bench fit`.
#[doc(hidden)]
pub fn loss_reference(
    opts: &LossOptions,
    s: &[f64],
    t: &Target,
    t_normals: &[[f64; 2]],
    ds: Option<&mut [f64]>,
) -> f64 {
    let g = (t.grid.w, t.grid.h);
    let nn = t.grid.len();
    let channels = s.len() / nn;
    if channels == 0 {
        return 0.0;
    }
    let norm = 1.0 / (channels * nn) as f64;
    let mut ds = ds;
    // Sdf, L1 and Pyramid assign every entry; Image only the band near edges.
    if let (LossKind::Image, Some(d)) = (opts.kind, ds.as_deref_mut()) {
        d.iter_mut().for_each(|v| *v = 0.0);
    }
    let mut total = 0.0;
    match opts.kind {
        LossKind::Sdf => {
            let acc = squared_differences4(s, &t.sdf);
            total += (acc[0] + acc[1] + acc[2] + acc[3]) * norm;
            if let Some(d) = ds.as_deref_mut() {
                for ((d, a), b) in d.iter_mut().zip(s).zip(&t.sdf) {
                    *d = 2.0 * (a - b) * norm;
                }
            }
            if opts.normal_weight != 0.0 {
                total += opts.normal_weight
                    * normal_term(s, g, t_normals, norm * opts.normal_weight, ds);
            }
        }
        LossKind::L1 => {
            for i in 0..s.len() {
                let e = s[i] - t.sdf[i];
                total += e.abs() * norm;
                if let Some(d) = ds.as_deref_mut() {
                    d[i] = e.signum() * norm;
                }
            }
        }
        LossKind::Image => {
            let to_px = t.grid.long_ppu() / t.scale;
            for i in 0..s.len() {
                let a = coverage(s[i] * to_px);
                let e = a - t.cover[i];
                total += e * e * norm;
                if let Some(d) = ds.as_deref_mut() {
                    let inside = 0.5 - s[i] * to_px;
                    if inside > 0.0 && inside < 1.0 {
                        d[i] = 2.0 * e * norm * -to_px;
                    }
                }
            }
        }
        LossKind::Pyramid => {
            for c in 0..channels {
                let lo = c * nn;
                let d = ds.as_deref_mut().map(|d| &mut d[lo..lo + nn]);
                pyramid_channel(
                    &mut total,
                    &s[lo..lo + nn],
                    &t.sdf[lo..lo + nn],
                    g,
                    channels,
                    d,
                );
            }
        }
    }
    total
}

/// One channel (`w × h`) of the pyramid loss: each level's share added to
/// `total` in turn; with `ds` (this channel's part), dL/dS too. Levels stop
/// when the shorter side is under 16 pixels.
fn pyramid_channel(
    total: &mut f64,
    s: &[f64],
    t: &[f64],
    size: (usize, usize),
    channels: usize,
    ds: Option<&mut [f64]>,
) {
    let mut level: Vec<f64> = s.iter().zip(t).map(|(a, b)| a - b).collect();
    let mut sizes = vec![size];
    let mut grads: Vec<Vec<f64>> = vec![];
    loop {
        let m = *sizes.last().expect("size");
        let k = 1.0 / (channels * m.0 * m.1) as f64;
        *total += level.iter().map(|e| e * e).sum::<f64>() * k;
        if ds.is_some() {
            grads.push(level.iter().map(|e| 2.0 * e * k).collect());
        }
        if m.0.min(m.1) < 16 || sizes.len() >= 5 {
            break;
        }
        let (next, mm) = down(&level, m);
        level = next;
        sizes.push(mm);
    }
    if let Some(d) = ds {
        // Back from the coarsest level: g_{k-1} += downᵀ g_k.
        for k in (1..grads.len()).rev() {
            let (fine, coarse) = grads.split_at_mut(k);
            let mut acc = fine[k - 1].clone();
            down_t(&coarse[0], sizes[k - 1], &mut acc);
            fine[k - 1] = acc;
        }
        d.copy_from_slice(&grads[0]);
    }
}

/// Clamped neighbour indices and inverse spacings of a central difference.
fn stencil(n: usize) -> Vec<(usize, usize, f64)> {
    (0..n)
        .map(|i| {
            let (m, p) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (m, p, 1.0 / (p - m).max(1) as f64)
        })
        .collect()
}

/// `Σ (1 − ⟨n_G, n_T⟩²) / (|C|·w·h)` and its gradient (× `gscale`) through
/// the stencil, on a `w × h` grid `(n, h)`.
fn normal_term(
    s: &[f64],
    (n, h): (usize, usize),
    tn: &[[f64; 2]],
    gscale: f64,
    ds: Option<&mut [f64]>,
) -> f64 {
    let nn = n * h;
    let channels = s.len() / nn;
    let st = stencil(n);
    let sty = stencil(h);
    let mut sum = 0.0;
    let mut ds = ds;
    for c in 0..channels {
        let o = c * nn;
        let f = &s[o..o + nn];
        for (y, &(ym, yp, ihy)) in sty.iter().enumerate() {
            let (row, rm, rp) = (y * n, ym * n, yp * n);
            // A row-local sum keeps the accumulator in a register.
            let mut row_sum = 0.0;
            for (x, &(xm, xp, ihx)) in st.iter().enumerate() {
                let t = tn[o + row + x];
                if t[0] == 0.0 && t[1] == 0.0 {
                    continue;
                }
                let gx = (f[row + xp] - f[row + xm]) * ihx;
                let gy = (f[rp + x] - f[rm + x]) * ihy;
                let l2 = gx * gx + gy * gy;
                if l2 <= 1e-24 {
                    continue;
                }
                let il = 1.0 / l2.sqrt();
                let (nx, ny) = (gx * il, gy * il);
                let dot = nx * t[0] + ny * t[1];
                row_sum += 1.0 - dot * dot;
                if let Some(d) = ds.as_deref_mut() {
                    // d(1 − dot²)/dg = −2·dot·(t − dot·n)/|g|
                    let k = -2.0 * dot * il * gscale;
                    let ggx = k * (t[0] - dot * nx) * ihx;
                    let ggy = k * (t[1] - dot * ny) * ihy;
                    d[o + row + xp] += ggx;
                    d[o + row + xm] -= ggx;
                    d[o + rp + x] += ggy;
                    d[o + rm + x] -= ggy;
                }
            }
            sum += row_sum;
        }
    }
    sum / (channels * nn) as f64
}

/// [`loss`] without gradient, in parts of a bounded number of field
/// values, for a job that must not spend one long slice on the loss of a
/// big grid. Every sum is taken in the order [`loss`] takes it, so the
/// result is the same bits.
#[derive(Debug, Clone, Default)]
pub struct LossPass {
    /// 0: going; 2: done.
    phase: u8,
    /// Where the pass is: a channel row (`Sdf`), a value (`L1`, `Image`)
    /// or a channel (`Pyramid`).
    pos: usize,
    acc: [f64; 2],
    total: f64,
}

impl LossPass {
    pub fn new() -> Self {
        Self::default()
    }

    /// Go on for about `budget` field values (one row or channel at
    /// least); `Some(loss)` when finished.
    pub fn run(
        &mut self,
        opts: &LossOptions,
        s: &[f64],
        t: &Target,
        t_normals: &[[f64; 2]],
        budget: usize,
    ) -> Option<f64> {
        let g = (t.grid.w, t.grid.h);
        let nn = t.grid.len();
        let channels = s.len() / nn;
        if channels == 0 {
            return Some(0.0);
        }
        let norm = 1.0 / (channels * nn) as f64;
        let budget = budget.max(1);
        match (opts.kind, self.phase) {
            (_, 2) => {}
            (LossKind::Sdf, _) => {
                // Rows of every channel, in order, through `sdf_row` as
                // `loss` takes them: the main and normal sums in `acc[0..2]`.
                let rows = channels * g.1;
                let end = rows.min(self.pos.saturating_add(budget.div_ceil(g.0)));
                let normals = opts.normal_weight != 0.0;
                for r in self.pos..end {
                    let (a, b) = sdf_row::<false>(
                        s,
                        &t.sdf,
                        t_normals,
                        g,
                        r,
                        normals,
                        0.0,
                        (&mut [], &mut []),
                    );
                    self.acc[0] += a;
                    self.acc[1] += b;
                }
                self.pos = end;
                if end == rows {
                    self.total = sdf_total(self.acc[0], self.acc[1], norm, opts.normal_weight);
                    self.phase = 2;
                }
            }
            (LossKind::L1 | LossKind::Image, _) => {
                let end = s.len().min(self.pos.saturating_add(budget));
                let to_px = t.grid.long_ppu() / t.scale;
                let (sv, tv, tm) = (
                    &s[self.pos..end],
                    &t.sdf[self.pos..end],
                    &t.cover[self.pos..end],
                );
                for ((&v, &d), &m) in sv.iter().zip(tv).zip(tm) {
                    if opts.kind == LossKind::L1 {
                        let e = v - d;
                        self.total += e.abs() * norm;
                    } else {
                        let e = coverage(v * to_px) - m;
                        self.total += e * e * norm;
                    }
                }
                self.pos = end;
                if end == s.len() {
                    self.phase = 2;
                }
            }
            (LossKind::Pyramid, _) => {
                // Whole channels: each is a pyramid of its own.
                let end = channels.min(self.pos + budget.div_ceil(nn));
                for c in self.pos..end {
                    let lo = c * nn;
                    pyramid_channel(
                        &mut self.total,
                        &s[lo..lo + nn],
                        &t.sdf[lo..lo + nn],
                        g,
                        channels,
                        None,
                    );
                }
                self.pos = end;
                if end == channels {
                    self.phase = 2;
                }
            }
        }
        (self.phase == 2).then_some(self.total)
    }
}

/// A pattern, a target and a loss: evaluates `L(params)` and `∇L`.
#[derive(Debug, Clone)]
pub struct Objective {
    /// The pattern.
    pub scene: Scene,
    /// The target fields.
    pub target: Target,
    /// Loss settings.
    pub opts: LossOptions,
    target_normals: Vec<[f64; 2]>,
    eval: Evaluator,
    nodes: Vec<f64>,
    adj: Vec<f64>,
    ds: Vec<f64>,
    /// Loss evaluations so far (with or without gradient).
    pub evaluations: u64,
    /// Work units of the last evaluation (item evaluations; deterministic).
    pub last_work: u64,
    /// The next big tile of a loss evaluated in parts.
    next_tile: usize,
    /// The loss pass of a loss evaluated in parts, once its fields are done.
    pass: Option<LossPass>,
    /// A row of normal-term derivatives ([`sdf_row`]).
    scratch: Scratch,
    /// Take [`Objective::loss`] and [`Objective::loss_grad`] through
    /// [`loss_reference`] (the "before" figure of `bench fit`).
    #[doc(hidden)]
    pub reference: bool,
}

impl Objective {
    /// Combine a scene and a target built for the same grid and units.
    pub fn new(scene: Scene, target: Target, opts: LossOptions) -> Objective {
        let mut tn = vec![];
        normals(&target.sdf, &target.grid, &mut tn);
        let canvas = scene.rec.canvas;
        let eval = Evaluator::on(Grid::on(canvas, opts.grid), opts.scale_on(canvas));
        Objective {
            scene,
            target,
            opts,
            target_normals: tn,
            eval,
            nodes: vec![],
            adj: vec![],
            ds: vec![],
            evaluations: 0,
            last_work: 0,
            next_tile: 0,
            pass: None,
            scratch: Scratch::default(),
            reference: false,
        }
    }

    /// [`loss`] (or [`loss_reference`]) of the current fields.
    fn field_loss(&mut self, grad: bool) -> f64 {
        let ds = if grad {
            self.ds.resize(self.eval.s.len(), 0.0);
            Some(&mut self.ds[..])
        } else {
            None
        };
        let (s, t, tn) = (&self.eval.s, &self.target, &self.target_normals);
        if self.reference {
            loss_reference(&self.opts, s, t, tn, ds)
        } else {
            loss_with(&self.opts, s, t, tn, ds, &mut self.scratch)
        }
    }

    /// Put in the target (and its normals, built with [`normals_rows`]) of
    /// an objective made with a pending one while a job builds it in parts.
    pub(crate) fn set_target(&mut self, target: Target, target_normals: Vec<[f64; 2]>) {
        self.target = target;
        self.target_normals = target_normals;
    }

    /// Number of float parameters.
    pub fn dim(&self) -> usize {
        self.scene.rec.float_params.len()
    }

    /// The loss at `params` (float parameters, declaration order, raw units).
    pub fn loss(&mut self, params: &[f64]) -> f64 {
        if let Some(l) = self.begin_loss(params) {
            return l;
        }
        while !self.loss_tiles(u64::MAX).0 {}
        self.end_loss()
    }

    /// [`Objective::loss`] in parts, for a job that must not block on one
    /// evaluation at a big grid: `begin_loss`, then `loss_tiles` until it
    /// says the fields are done, then `end_loss`; the same bits as `loss`.
    /// `Some(loss)` when there is nothing to evaluate (the parameters make
    /// a shape non-finite: the loss is infinite).
    pub fn begin_loss(&mut self, params: &[f64]) -> Option<f64> {
        self.scene.rec.tape.forward(params, &mut self.nodes);
        if !self.scene.shapes_finite(&self.nodes) {
            // The program divides by zero (or worse) at these parameters.
            self.evaluations += 1;
            self.last_work = self.scene.rec.prims.len() as u64 + 1;
            return Some(f64::INFINITY);
        }
        self.eval.begin(&self.scene, &self.nodes, false);
        self.next_tile = 0;
        self.pass = None;
        None
    }

    /// Evaluate big tiles of the fields begun by [`Objective::begin_loss`]
    /// until about `budget` item evaluations are spent (one tile at
    /// least). Returns whether the fields are complete and the item
    /// evaluations spent.
    pub fn loss_tiles(&mut self, budget: u64) -> (bool, u64) {
        let before = self.eval.raw_work();
        let tiles = self.eval.tiles();
        while self.next_tile < tiles {
            let t = self.next_tile;
            self.eval.eval_tiles(&self.scene, false, t..t + 1);
            self.next_tile += 1;
            if self.eval.raw_work() - before >= budget {
                break;
            }
        }
        (self.next_tile >= tiles, self.eval.raw_work() - before + 1)
    }

    /// Field values the loss pass reads (a work measure).
    pub fn loss_size(&self) -> u64 {
        self.eval.s.len() as u64
    }

    /// The fraction of the fields evaluated so far in the current loss.
    pub fn tiles_fraction(&self) -> f64 {
        self.next_tile as f64 / self.eval.tiles().max(1) as f64
    }

    /// The loss pass of a loss evaluated in parts, once
    /// [`Objective::loss_tiles`] has completed the fields: about `budget`
    /// field values per call; `Some(loss)` at the end (the same bits as
    /// [`Objective::loss`]).
    pub fn loss_pass(&mut self, budget: usize) -> Option<f64> {
        let pass = match self.pass.as_mut() {
            Some(p) => p,
            None => {
                self.eval.finish(&self.scene);
                self.evaluations += 1;
                self.last_work = self.eval.work;
                self.pass.insert(LossPass::new())
            }
        };
        let l = pass.run(
            &self.opts,
            &self.eval.s,
            &self.target,
            &self.target_normals,
            budget,
        )?;
        self.pass = None;
        Some(if l.is_finite() { l } else { f64::INFINITY })
    }

    /// The loss once [`Objective::loss_tiles`] has completed the fields.
    pub fn end_loss(&mut self) -> f64 {
        self.eval.finish(&self.scene);
        self.evaluations += 1;
        self.last_work = self.eval.work;
        let l = self.field_loss(false);
        if l.is_finite() {
            l
        } else {
            f64::INFINITY
        }
    }

    /// The loss and its exact gradient (written to `grad`, raw units).
    pub fn loss_grad(&mut self, params: &[f64], grad: &mut [f64]) -> f64 {
        self.scene.rec.tape.forward(params, &mut self.nodes);
        if !self.scene.shapes_finite(&self.nodes) {
            self.evaluations += 1;
            self.last_work = self.scene.rec.prims.len() as u64 + 1;
            grad.iter_mut().for_each(|g| *g = 0.0);
            return f64::INFINITY;
        }
        self.eval.eval(&self.scene, &self.nodes, true);
        self.evaluations += 1;
        self.last_work = self.eval.work * 2;
        let l = self.field_loss(true);
        self.adj.clear();
        self.adj.resize(self.nodes.len(), 0.0);
        self.eval.backward(&self.scene, &self.ds, &mut self.adj);
        grad.iter_mut().for_each(|g| *g = 0.0);
        self.scene
            .rec
            .tape
            .backward(&self.nodes, &mut self.adj, grad);
        if !l.is_finite() {
            grad.iter_mut().for_each(|g| *g = 0.0);
            return f64::INFINITY;
        }
        l
    }

    /// The fields of the last evaluation (channel-major).
    pub fn fields(&self) -> &[f64] {
        &self.eval.s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};

    fn objective(src: &str, truth: &[f64], kind: LossKind, n: usize) -> Objective {
        objective_on(src, truth, kind, n, Canvas::SQUARE)
    }

    /// [`objective`] on `canvas` (`n` the grid's longer side).
    fn objective_on(
        src: &str,
        truth: &[f64],
        kind: LossKind,
        n: usize,
        canvas: Canvas,
    ) -> Objective {
        let p = Program::parse(src).unwrap();
        let rec = p
            .record_on(&p.defaults(), &RecordLimits::default(), canvas)
            .unwrap();
        let scene = Scene::new(rec);
        let opts = LossOptions {
            kind,
            grid: n,
            ..Default::default()
        };
        let mut ev = Evaluator::on(Grid::on(canvas, n), opts.scale_on(canvas));
        let mut nodes = vec![];
        scene.rec.tape.forward(truth, &mut nodes);
        ev.eval(&scene, &nodes, false);
        let idx = ev.colour_indices(&scene);
        let t = Target::from_indices(&scene, &idx, n, opts.scale_on(canvas));
        Objective::new(scene, t, opts)
    }

    /// [`objective_on`] with the target an image of the truth rendered
    /// anti-aliased (4×4 samples) at twice the grid's side: its fields and
    /// coverage are sub-pixel, the coverage fractional along outlines.
    fn objective_aa(
        src: &str,
        truth: &[f64],
        kind: LossKind,
        n: usize,
        canvas: Canvas,
    ) -> Objective {
        let o = objective_on(src, truth, kind, n, canvas);
        let img = crate::pattern::render::render(&o.scene, truth, 2 * n, 4).unwrap();
        let t = Target::from_image(&o.scene, &img, n, o.opts.scale_on(canvas), 60.0).unwrap();
        let soft = t.cover.iter().filter(|&&a| a > 0.01 && a < 0.99).count();
        assert!(soft > 50, "{soft} fractional pixels");
        Objective::new(o.scene, t, o.opts)
    }

    const SRC: &str = "param dx in [0.1, 0.3] = 0.2;\nparam r in [0.02, 0.08] = 0.05;\nparam a in [-0.5, 0.5] = 0.1;\n\
        param w in [0.005, 0.03] = 0.01;\n\
        for i in 0..3 { circle(0.2 + i * dx, 0.3, r, fill: \"#d62728\"); }\n\
        rect(0.5, 0.7, 0.3, 0.1, radius: 0.02, rotation: a, fill: \"#1f77b4\", stroke: \"#2ca02c\", width: w);\n\
        path(stroke: \"#2ca02c\", width: w) { move(0.1, 0.9); quad(0.5, 0.5 + a * 0.3, 0.9, 0.9); }\n\
        segment(0.1, 0.1 + r, 0.9, 0.15, stroke: \"#d62728\", width: w * 2);";

    /// Every loss's analytic gradient matches central differences, against
    /// a target drawn on the grid (hard masks) and against an anti-aliased
    /// image (sub-pixel fields, fractional coverage), on the square canvas
    /// and on a wide and a tall one (rectangular grids).
    #[test]
    fn gradients_match_central_differences_for_every_loss() {
        let kinds = [
            LossKind::Sdf,
            LossKind::L1,
            LossKind::Pyramid,
            LossKind::Image,
        ];
        let truth = [0.22, 0.06, 0.2, 0.015];
        // (Grids an even number of pixels wide: on an odd one a pixel centre
        // lies at x = 0.5, midway between two circles of SRC at `p`, where
        // the loss has a kink that central differences average over.)
        let canvases = [
            Canvas::SQUARE,
            Canvas::of_pixels(300, 240),
            Canvas::of_pixels(200, 240),
        ];
        let cases = kinds
            .into_iter()
            .flat_map(|k| [(k, false), (k, true)])
            .flat_map(|c| canvases.map(|v| (c, v)));
        for ((kind, aa), canvas) in cases {
            let mut o = if aa {
                objective_aa(SRC, &truth, kind, 48, canvas)
            } else {
                objective_on(SRC, &truth, kind, 48, canvas)
            };
            if !canvas.is_square() {
                assert!(o.target.grid.w != o.target.grid.h);
            }
            let p = [0.2, 0.045, 0.05, 0.012];
            let mut g = [0.0; 4];
            let l = o.loss_grad(&p, &mut g);
            assert!((l - o.loss(&p)).abs() < 1e-12);
            for k in 0..4 {
                let h = 1e-6;
                let (mut a, mut b) = (p, p);
                a[k] += h;
                b[k] -= h;
                let fd = (o.loss(&a) - o.loss(&b)) / (2.0 * h);
                let tol = 1e-3 * (1.0 + fd.abs().max(g[k].abs()));
                assert!(
                    (fd - g[k]).abs() < tol,
                    "{kind:?} (anti-aliased target: {aa}, {canvas:?}) param {k}: fd {fd} vs analytic {}",
                    g[k]
                );
            }
        }
    }

    /// The loss pass in parts of any size gives the bits of the one-go
    /// loss, for every loss kind and with and without the normal term; so
    /// does a whole loss evaluated in parts through the objective.
    #[test]
    fn loss_in_parts_gives_the_same_bits_as_one_go() {
        for kind in [
            LossKind::Sdf,
            LossKind::L1,
            LossKind::Pyramid,
            LossKind::Image,
        ] {
            let sizes = [
                (37, Canvas::SQUARE),
                (48, Canvas::SQUARE),
                (41, Canvas::of_pixels(300, 240)),
            ];
            for (n, canvas) in sizes {
                let mut o = objective_on(SRC, &[0.22, 0.06, 0.2, 0.015], kind, n, canvas);
                let p = [0.2, 0.045, 0.05, 0.012];
                let want = o.loss(&p);
                for nw in [0.05, 0.0] {
                    let opts = LossOptions {
                        normal_weight: nw,
                        ..o.opts
                    };
                    let one = loss(&opts, o.fields(), &o.target, &o.target_normals, None);
                    if nw != 0.0 {
                        assert_eq!(one.to_bits(), want.to_bits());
                    }
                    for budget in [1, 7, 1000, usize::MAX] {
                        let mut pass = LossPass::new();
                        let mut calls = 0;
                        let got = loop {
                            calls += 1;
                            if let Some(l) =
                                pass.run(&opts, o.fields(), &o.target, &o.target_normals, budget)
                            {
                                break l;
                            }
                        };
                        assert_eq!(
                            got.to_bits(),
                            one.to_bits(),
                            "{kind:?} n {n} budget {budget}"
                        );
                        if budget == 1 && kind != LossKind::Pyramid {
                            assert!(calls >= o.target.grid.h, "{calls}");
                        }
                    }
                }
                for budget in [1, 500, u64::MAX] {
                    assert!(o.begin_loss(&p).is_none());
                    while !o.loss_tiles(budget).0 {}
                    let got = loop {
                        if let Some(l) = o.loss_pass(budget as usize) {
                            break l;
                        }
                    };
                    assert_eq!(got.to_bits(), want.to_bits(), "{kind:?} n {n}");
                }
            }
        }
    }

    /// The fast SDF loss (fused rows, no square root, gathered gradients)
    /// equals the per-pixel reference, loss and dL/dS, to 1e-12 relative,
    /// on random fields with flat patches (vanishing gradients), zero target
    /// normals, every grid side from 1 to 9 and odd sizes, rectangles
    /// (wide and tall, a canvas that is not square), 1 to 3 channels, with
    /// and without the normal term.
    #[test]
    fn fast_sdf_loss_equals_the_reference_on_random_fields() {
        let mut rng = crate::core::rng::Rng::new(9);
        let squares = (1..10).chain([17, 37, 64]).map(|n| (n, n));
        let rects = [(1, 5), (5, 1), (2, 7), (7, 3), (17, 9), (9, 17), (37, 64)];
        for (w, h) in squares.chain(rects) {
            for channels in 1..4 {
                for nw in [0.05, 0.0, 1.0] {
                    let len = channels * w * h;
                    let field = |rng: &mut crate::core::rng::Rng| -> Vec<f64> {
                        (0..len)
                            .map(|_| {
                                let v = rng.range_f64(-20.0, 20.0);
                                // A third of the values on a coarse lattice: flat patches.
                                if rng.range_f64(0.0, 1.0) < 0.33 {
                                    (v / 8.0).round() * 8.0
                                } else {
                                    v
                                }
                            })
                            .collect()
                    };
                    let s = field(&mut rng);
                    let grid = Grid {
                        w,
                        h,
                        canvas: Canvas::of_pixels(w, h),
                    };
                    let t = Target {
                        grid,
                        scale: grid.long_ppu(),
                        sdf: field(&mut rng),
                        cover: vec![0.0; len],
                        unmatched: 0.0,
                    };
                    let mut tn = vec![];
                    normals(&t.sdf, &t.grid, &mut tn);
                    let opts = LossOptions {
                        grid: w.max(h),
                        normal_weight: nw,
                        ..Default::default()
                    };
                    let (mut d1, mut d2) = (vec![0.0; len], vec![7.0; len]);
                    let want = loss_reference(&opts, &s, &t, &tn, Some(&mut d1));
                    let got = loss(&opts, &s, &t, &tn, Some(&mut d2));
                    let plain = loss(&opts, &s, &t, &tn, None);
                    assert_eq!(got.to_bits(), plain.to_bits(), "{w}×{h}");
                    assert!(
                        (got - want).abs() <= 1e-12 * want.abs().max(1e-300),
                        "{w}×{h} c {channels} nw {nw}: {got} vs {want}"
                    );
                    let scale = d1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (i, (a, b)) in d2.iter().zip(&d1).enumerate() {
                        assert!(
                            (a - b).abs() <= 1e-12 * scale,
                            "{w}×{h} c {channels} nw {nw} ds[{i}]: {a} vs {b}"
                        );
                    }
                }
            }
        }
    }

    /// Through the objective (fields, loss, backward, tape): the fast path
    /// and the reference path give the same loss and parameter gradient to
    /// 1e-12 relative at random parameters.
    #[test]
    fn objective_fast_path_equals_the_reference_path() {
        let mut rng = crate::core::rng::Rng::new(3);
        let mut o = objective(SRC, &[0.22, 0.06, 0.2, 0.015], LossKind::Sdf, 53);
        let (lo, hi) = ([0.1, 0.02, -0.5, 0.005], [0.3, 0.08, 0.5, 0.03]);
        for _ in 0..20 {
            let p: Vec<f64> = (0..4).map(|k| rng.range_f64(lo[k], hi[k])).collect();
            let (mut g1, mut g2) = (vec![0.0; 4], vec![0.0; 4]);
            o.reference = true;
            let want = o.loss_grad(&p, &mut g1);
            let want_l = o.loss(&p);
            o.reference = false;
            let got = o.loss_grad(&p, &mut g2);
            assert_eq!(got.to_bits(), o.loss(&p).to_bits());
            assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} vs {want}");
            assert!((want_l - want).abs() <= 1e-12 * want.abs());
            let scale = g1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..4 {
                assert!((g1[k] - g2[k]).abs() <= 1e-12 * scale, "{g1:?} vs {g2:?}");
            }
        }
    }

    /// Against an anti-aliased image of the truth, the image-space loss
    /// (what the polish minimises) is lowest at the truth along every
    /// parameter: a parabola through the loss at the truth and a step
    /// either side (a step moves outlines by at most 0.1 grid pixel) has
    /// its vertex within a quarter step, i.e. 0.025 pixel. Against hard
    /// masks of the same image (the polish before) the vertices were
    /// 0.34–1.1 steps away: the radius and the width pulled down.
    #[test]
    fn the_image_loss_on_an_antialiased_target_is_lowest_at_the_truth() {
        let truth = [0.22, 0.06, 0.2, 0.015];
        let n = 48;
        let mut o = objective_aa(SRC, &truth, LossKind::Image, n, Canvas::SQUARE);
        let px = 1.0 / n as f64;
        // Steps moving outlines by about 0.1 pixel: dx moves the third
        // circle twice as far, the rectangle's corners lie ~0.17 from its
        // centre, a stroke's edges move by half its width.
        let steps = [0.05 * px, 0.1 * px, 0.1 * px / 0.17, 0.2 * px];
        let at = o.loss(&truth);
        let mut bad = vec![];
        for (k, h) in steps.into_iter().enumerate() {
            let mut x = truth;
            x[k] = truth[k] - h;
            let lo = o.loss(&x);
            x[k] = truth[k] + h;
            let hi = o.loss(&x);
            let curve = lo - 2.0 * at + hi;
            let vertex = (lo - hi) / (2.0 * curve);
            eprintln!("param {k}: vertex {vertex:+.3} steps (loss {lo:.3e} {at:.3e} {hi:.3e})");
            if !(curve > 0.0 && vertex.abs() < 0.25) {
                bad.push(format!("param {k}: the minimum is {vertex:+.3} steps away"));
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("; "));
    }

    #[test]
    fn loss_is_minimal_at_the_truth() {
        let truth = [0.22, 0.06, 0.2, 0.015];
        let mut o = objective(SRC, &truth, LossKind::Sdf, 64);
        let at = o.loss(&truth);
        assert!(at < 0.15, "{at}");
        let off = o.loss(&[0.25, 0.06, 0.2, 0.015]);
        // (Fields stop at the canvas edge, so pixels near it add at most
        // their distance to the edge: the margin is 0.15, not more.)
        assert!(off > at * 5.0 && off > at + 0.15, "{off} vs {at}");
    }

    /// A tape that divides by zero only at some parameter values: those
    /// points are invalid (infinite loss, zero gradient), never NaN.
    #[test]
    fn parameters_that_divide_by_zero_give_an_infinite_loss() {
        let src = "param a in [0, 1] = 0.25;\ncircle(0.5, 0.5, 0.02 / (a - 0.5) ^ 2 * 0.01, fill: \"#000\");";
        let mut o = objective(src, &[0.25], LossKind::Sdf, 32);
        assert!(o.loss(&[0.25]).is_finite());
        assert_eq!(o.loss(&[0.5]), f64::INFINITY);
        let mut g = [1.0];
        assert_eq!(o.loss_grad(&[0.5], &mut g), f64::INFINITY);
        assert_eq!(g, [0.0]);
        // 0/0 too.
        let src = "param a in [0, 1] = 0.25;\ncircle(0.5, 0.5, 0.1 * (a - 0.5) / (a - 0.5), fill: \"#000\");";
        let mut o = objective(src, &[0.25], LossKind::Sdf, 32);
        assert!(o.loss(&[0.3]).is_finite());
        assert_eq!(o.loss(&[0.5]), f64::INFINITY);
    }
}

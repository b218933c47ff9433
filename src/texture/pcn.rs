//! PCN-2, the PCA-based convolutional network of Section 3 of the paper:
//! two stages of (PCA filter bank → zero-padded convolution → max pooling),
//! feature-map combination by an indexing matrix between them, and an output
//! stage of binary hashing and block histograms.
//!
//! - **Filters.** Patches of `k1 × k2` pixels are taken every `patch_step`
//!   pixels, each with its mean removed; the filters are the leading
//!   eigenvectors of `X Xᵀ` (nalgebra's `SymmetricEigen::try_new`, which
//!   gives up rather than hangs). Each filter's sign is fixed so that its
//!   largest component is positive, so training is deterministic.
//! - **Convolution.** Each output is the filter's dot product with the
//!   mean-removed, zero-padded patch around the pixel, exactly the
//!   projection PCA learned. It is computed as a direct convolution: one
//!   `axpy` over a row per filter tap, with each output summing its taps in
//!   the same order. That loop vectorises without reordering any sum, so
//!   native and wasm give the same bytes (an im2col + sgemm kernel picks its
//!   summation order by CPU). The patch mean is subtracted as
//!   `mean(patch) · Σ filter`, from a box filter of the padded image.
//! - **Hashing.** The paper hashes all `L2` binarised maps into one integer
//!   per pixel, which for its `L2 = 38` would need 2³⁸ histogram bins. We
//!   hash them in groups of `hash_bits` maps (PCANet's usual 8 or fewer),
//!   one histogram per group and block. Each histogram is normalised to sum
//!   to one and square-rooted (the Hellinger map), so a linear classifier
//!   on the features compares histograms sensibly.
//! - **Intensity.** Sign hashing makes the features blind to contrast and
//!   brightness, which two of the twelve scales are about. `intensity_bins`
//!   appends the (square-rooted) histogram of the prepared image's grey
//!   levels; 0 turns it off and gives the paper's features alone.
use super::Gray;
use crate::core::error::{Error, Result};
use nalgebra::{DMatrix, SymmetricEigen};
use serde::{Deserialize, Serialize};

/// PCN-2's settings; the defaults are the paper's where it gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PcnConfig {
    /// Filter (patch) height and width, pixels: k1 = k2 = 7 in the paper.
    pub k1: usize,
    pub k2: usize,
    /// Filters in the first and second stage: L1 = 16, L2 = 38.
    pub l1: usize,
    pub l2: usize,
    /// Training patches are taken every `patch_step` pixels (< k1, k2).
    pub patch_step: usize,
    /// Max-pooling window, pixels a side (2 in the paper).
    pub pool: usize,
    /// Stage-2 maps hashed together into one code (1–8).
    pub hash_bits: usize,
    /// Histograms over a `blocks × blocks` grid of the final maps.
    pub blocks: usize,
    /// Input side: every image is resampled to `side × side` first.
    pub side: usize,
    /// Bins of the appended grey-level histogram (0: none).
    pub intensity_bins: usize,
    /// The indexing matrix, as rows: stage-2 subset `i` is the sum of the
    /// stage-1 maps listed in `combination[i]`. Empty means identity.
    pub combination: Vec<Vec<usize>>,
    /// The pixel scale of the training images (see [`PcnConfig::window`]):
    /// a whole texture is read as if its short side were `texture_side`
    /// pixels, and the network sees a centred `side × side` window of it.
    /// The dataset's crops are such windows of textures rendered at twice
    /// their size, so an index trained on crops sets `2 · side`. 0 reads
    /// every image whole (its centre square resampled to `side`).
    pub texture_side: usize,
    /// Scales of rotation-invariant LBP histograms appended to the
    /// features ([`super::lbp`]; 0: none, the paper's features alone).
    /// 3, chosen on the validation part of the cross-implementation set
    /// (issue 36; 4 looks a base): 26.1% of its textures recognised
    /// without, 30.4% with.
    pub lbp_scales: usize,
    /// The network reads the view's grey levels as ranks (histogram
    /// equalised; ties share their mean rank), so its filters and codes do
    /// not change with a tone curve (issue 36). The intensity histogram
    /// and the LBP still read the view itself. On, chosen on the same
    /// validation part: 30.4% → 33.2% recognised.
    pub equalise: bool,
}

impl Default for PcnConfig {
    fn default() -> Self {
        PcnConfig {
            k1: 7,
            k2: 7,
            l1: 16,
            l2: 38,
            patch_step: 3,
            pool: 2,
            hash_bits: 4,
            blocks: 1,
            side: 128,
            intensity_bins: 16,
            combination: Vec::new(),
            texture_side: 0,
            lbp_scales: 3,
            equalise: true,
        }
    }
}

fn bad(field: &str, message: String) -> Error {
    Error::input(message).at(field)
}

impl PcnConfig {
    /// Checks the settings, as the paper's constraints and our limits.
    pub fn validate(&self) -> Result<()> {
        let taps = self.k1 * self.k2;
        if !(1..=15).contains(&self.k1) || !(1..=15).contains(&self.k2) {
            return Err(bad(
                "k1",
                format!(
                    "filters are 1 to 15 pixels a side, not {}×{}",
                    self.k1, self.k2
                ),
            ));
        }
        if self.l1 == 0 || self.l2 == 0 || self.l1 > taps || self.l2 > taps {
            return Err(bad(
                "l1",
                format!(
                    "need 1 ≤ L1, L2 ≤ k1·k2 = {taps} filters (L1 = {}, L2 = {})",
                    self.l1, self.l2
                ),
            ));
        }
        if self.patch_step == 0 || self.patch_step > self.k1.max(self.k2) {
            return Err(bad(
                "patch_step",
                format!("the patch step must be 1 to {}", self.k1.max(self.k2)),
            ));
        }
        if !(1..=4).contains(&self.pool) {
            return Err(bad("pool", "pooling is 1 to 4 pixels a side".into()));
        }
        if !(1..=8).contains(&self.hash_bits) {
            return Err(bad("hash_bits", "hash 1 to 8 maps per code".into()));
        }
        if !(16..=1024).contains(&self.side) {
            return Err(bad(
                "side",
                format!(
                    "the input side must be 16 to 1024 pixels, not {}",
                    self.side
                ),
            ));
        }
        let last = self.side / self.pool / self.pool;
        if self.blocks == 0 || self.blocks > last.max(1) {
            return Err(bad(
                "blocks",
                format!("1 to {last} blocks a side fit the final maps"),
            ));
        }
        if self.texture_side != 0 && !(self.side..=16 * self.side).contains(&self.texture_side) {
            return Err(bad(
                "texture_side",
                format!(
                    "the texture side must be 0 or {} to {} pixels, not {}",
                    self.side,
                    16 * self.side,
                    self.texture_side
                ),
            ));
        }
        if self.lbp_scales > 4 {
            return Err(bad("lbp_scales", "at most 4 LBP scales".into()));
        }
        if self.intensity_bins > 256 {
            return Err(bad("intensity_bins", "at most 256 grey-level bins".into()));
        }
        for (i, row) in self.combination.iter().enumerate() {
            if row.is_empty() || row.iter().any(|&j| j >= self.l1) {
                return Err(bad(
                    "combination",
                    format!("row {i} must list stage-1 maps 0 to {}", self.l1 - 1),
                ));
            }
        }
        Ok(())
    }

    /// The side, in the image's pixels, of the centred square the network
    /// reads from an image whose short side is `short`: the image at its
    /// own pixel scale up to `texture_side` (a window of `side` pixels),
    /// a proportionally larger window of a larger image (so any image is
    /// read as a texture `texture_side` pixels across), and the whole of an
    /// image smaller than `side`. A `side × side` image is always read
    /// whole, so training on the dataset's images is unchanged.
    pub fn window(&self, short: usize) -> usize {
        if self.texture_side == 0 {
            return short;
        }
        (short * self.side / self.texture_side)
            .max(self.side)
            .min(short)
    }

    /// What the network reads of `img`: its [`PcnConfig::window`],
    /// resampled to `side × side`.
    pub fn view(&self, img: &Gray) -> Result<Gray> {
        prepare_window(img, self.side, self.window(img.width.min(img.height)))
    }

    /// What the network reads of `img` for a query, two windows of it
    /// whose scores are summed (test-time augmentation): when the
    /// [`PcnConfig::window`] is smaller than the image's centred square, the
    /// windows in that square's top-left and bottom-right corners (for an
    /// image of at least `2 · window`, two diagonal quadrants: the dataset's
    /// crops 0 and 3 of a `texture_side` render), each resampled to
    /// `side × side`; otherwise the one [`PcnConfig::view`]. Two, not four:
    /// on the validation split four windows recognised 83.0% of 256²
    /// renders, two 81.9%, the centre window alone 79.3%, and four cost
    /// about 0.15 s a texture in the browser, the budget
    /// (`docs/bench/texture-accuracy-2026-12-03.md`).
    pub fn views(&self, img: &Gray) -> Result<Vec<Gray>> {
        self.corner_views(img, false)
    }

    /// The windows in all four corners of the image's centred square, in
    /// the dataset's crop order (top-left, top-right, bottom-left,
    /// bottom-right: a `texture_side` render's four crops), or the one
    /// [`PcnConfig::view`] as [`PcnConfig::views`]. The scales of an image
    /// are measured over these, as a base's label is over its crops.
    pub fn quadrant_views(&self, img: &Gray) -> Result<Vec<Gray>> {
        self.corner_views(img, true)
    }

    fn corner_views(&self, img: &Gray, four: bool) -> Result<Vec<Gray>> {
        let s = img.width.min(img.height);
        let w = self.window(s);
        if img.width == 0 || img.height == 0 || w >= s {
            return Ok(vec![self.view(img)?]);
        }
        let (x0, y0) = ((img.width - s) / 2, (img.height - s) / 2);
        let d = s - w;
        let corners: &[(usize, usize)] = if four {
            &[(0, 0), (d, 0), (0, d), (d, d)]
        } else {
            &[(0, 0), (d, d)]
        };
        corners
            .iter()
            .map(|&(dx, dy)| {
                let mut sub = Gray::new(w, w);
                for y in 0..w {
                    let from = (y0 + dy + y) * img.width + x0 + dx;
                    sub.data[y * w..(y + 1) * w].copy_from_slice(&img.data[from..from + w]);
                }
                prepare(&sub, self.side)
            })
            .collect()
    }

    /// The network's input map of a prepared view ([`PcnConfig::equalise`]).
    fn network_input(&self, view: &Gray) -> Map {
        if !self.equalise {
            return as_map(view);
        }
        let n = view.data.len();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| view.data[a].total_cmp(&view.data[b]));
        let mut ranked = view.clone();
        let mut i = 0;
        while i < n {
            let mut j = i + 1;
            while j < n && view.data[order[j]] == view.data[order[i]] {
                j += 1;
            }
            let r = ((i + j - 1) as f64 / 2.0 / (n.max(2) - 1) as f64) as f32;
            for &k in &order[i..j] {
                ranked.data[k] = r;
            }
            i = j;
        }
        as_map(&ranked)
    }

    /// The indexing matrix's rows (identity when none is given).
    pub fn subsets(&self) -> Vec<Vec<usize>> {
        if self.combination.is_empty() {
            (0..self.l1).map(|i| vec![i]).collect()
        } else {
            self.combination.clone()
        }
    }

    /// Length of a feature vector.
    pub fn feature_len(&self) -> usize {
        let groups = self.l2.div_ceil(self.hash_bits);
        let bins: usize = (0..groups)
            .map(|g| 1usize << (self.l2 - g * self.hash_bits).min(self.hash_bits))
            .sum();
        self.subsets().len() * self.blocks * self.blocks * bins
            + self.intensity_bins
            + self.lbp_scales * super::lbp::bins_per_scale()
    }
}

/// A trained PCN-2: the settings and both stages' filter banks, each filter
/// `k1·k2` values in raster order.
#[derive(Clone, Debug, PartialEq)]
pub struct Pcn {
    pub config: PcnConfig,
    pub stage1: Vec<Vec<f32>>,
    /// One bank of `l2` filters per stage-2 subset.
    pub stage2: Vec<Vec<Vec<f32>>>,
}

/// Resamples the centre square of `img` to `side × side` by area averaging
/// (or bilinear upsampling when the square is smaller).
pub fn prepare(img: &Gray, side: usize) -> Result<Gray> {
    prepare_window(img, side, img.width.min(img.height))
}

/// Resamples the centred `window × window` square of `img` (at most its
/// short side) to `side × side`, as [`prepare`] does the whole square.
pub fn prepare_window(img: &Gray, side: usize, window: usize) -> Result<Gray> {
    if img.width == 0 || img.height == 0 {
        return Err(Error::input("the image is empty"));
    }
    let s = window.clamp(1, img.width.min(img.height));
    let (x0, y0) = ((img.width - s) / 2, (img.height - s) / 2);
    let mut out = Gray::new(side, side);
    let scale = s as f64 / side as f64;
    for y in 0..side {
        for x in 0..side {
            out.data[y * side + x] = if scale > 1.0 {
                let (ax, bx) = (x as f64 * scale, (x + 1) as f64 * scale);
                let (ay, by) = (y as f64 * scale, (y + 1) as f64 * scale);
                let mut sum = 0.0;
                let mut wsum = 0.0;
                for yy in ay.floor() as usize..(by.ceil() as usize).min(s) {
                    let wy = (by.min(yy as f64 + 1.0) - ay.max(yy as f64)).max(0.0);
                    for xx in ax.floor() as usize..(bx.ceil() as usize).min(s) {
                        let w = wy * (bx.min(xx as f64 + 1.0) - ax.max(xx as f64)).max(0.0);
                        sum += w * img.at(x0 + xx, y0 + yy) as f64;
                        wsum += w;
                    }
                }
                (sum / wsum.max(1e-12)) as f32
            } else {
                let fx = ((x as f64 + 0.5) * scale - 0.5).clamp(0.0, (s - 1) as f64);
                let fy = ((y as f64 + 0.5) * scale - 0.5).clamp(0.0, (s - 1) as f64);
                let (ix, iy) = (fx as usize, fy as usize);
                let (jx, jy) = ((ix + 1).min(s - 1), (iy + 1).min(s - 1));
                let (tx, ty) = ((fx - ix as f64) as f32, (fy - iy as f64) as f32);
                let a = img.at(x0 + ix, y0 + iy) * (1.0 - tx) + img.at(x0 + jx, y0 + iy) * tx;
                let b = img.at(x0 + ix, y0 + jy) * (1.0 - tx) + img.at(x0 + jx, y0 + jy) * tx;
                a * (1.0 - ty) + b * ty
            };
        }
    }
    Ok(out)
}

/// A map of `w × h` values.
#[derive(Clone, Debug)]
struct Map {
    w: usize,
    h: usize,
    v: Vec<f32>,
}

/// Accumulates `X Xᵀ` over mean-removed `k1 × k2` patches taken every
/// `step` pixels from `m` (patches inside the map only).
fn accumulate_patches(
    m: &Map,
    k1: usize,
    k2: usize,
    step: usize,
    cov: &mut [f64],
    count: &mut usize,
) {
    let taps = k1 * k2;
    let mut patch = vec![0f64; taps];
    if m.w < k2 || m.h < k1 {
        return;
    }
    for y in (0..=m.h - k1).step_by(step) {
        for x in (0..=m.w - k2).step_by(step) {
            let mut mean = 0.0;
            for dy in 0..k1 {
                for dx in 0..k2 {
                    let v = m.v[(y + dy) * m.w + x + dx] as f64;
                    patch[dy * k2 + dx] = v;
                    mean += v;
                }
            }
            mean /= taps as f64;
            for p in &mut patch {
                *p -= mean;
            }
            for i in 0..taps {
                let pi = patch[i];
                if pi == 0.0 {
                    continue;
                }
                let row = &mut cov[i * taps..(i + 1) * taps];
                for j in i..taps {
                    row[j] += pi * patch[j];
                }
            }
            *count += 1;
        }
    }
}

/// The `l` leading eigenvectors of the accumulated (upper-triangle)
/// covariance, as filters with their largest component positive.
fn pca_filters(mut cov: Vec<f64>, taps: usize, l: usize, count: usize) -> Result<Vec<Vec<f32>>> {
    if count == 0 {
        return Err(Error::input(
            "no training patches: the images are smaller than a filter",
        ));
    }
    for i in 0..taps {
        for j in 0..i {
            cov[i * taps + j] = cov[j * taps + i];
        }
    }
    let scale = 1.0 / count as f64;
    let m = DMatrix::from_fn(taps, taps, |i, j| cov[i * taps + j] * scale);
    if m.iter().any(|v| !v.is_finite()) {
        return Err(Error::input("the training patches are not finite"));
    }
    let eig = SymmetricEigen::try_new(m, 1e-12, 100_000)
        .ok_or_else(|| Error::input("the PCA eigen-decomposition did not converge"))?;
    let mut order: Vec<usize> = (0..taps).collect();
    // Largest eigenvalue first; ties by index so the order is fixed.
    order.sort_by(|&a, &b| {
        eig.eigenvalues[b]
            .total_cmp(&eig.eigenvalues[a])
            .then(a.cmp(&b))
    });
    Ok(order
        .iter()
        .take(l)
        .map(|&c| {
            let col = eig.eigenvectors.column(c);
            let big = (0..taps).fold(0, |best, i| {
                if col[i].abs() > col[best].abs() + 1e-12 {
                    i
                } else {
                    best
                }
            });
            let sign = if col[big] < 0.0 { -1.0 } else { 1.0 };
            (0..taps).map(|i| (sign * col[i]) as f32).collect()
        })
        .collect())
}

/// Outputs computed together in [`convolve`].
const LANES: usize = 16;

/// Zero-padded convolution of `m` with each filter, patch means removed:
/// `out[f](x, y) = Σ_t filter[f][t] · (p_t − mean(p))` over the patch `p`
/// centred on (x, y).
fn convolve(m: &Map, filters: &[Vec<f32>], k1: usize, k2: usize) -> Vec<Map> {
    let (w, h) = (m.w, m.h);
    let (oy, ox) = (k1 / 2, k2 / 2);
    // Padded copy: (h + k1 − 1) × (w + k2 − 1), the image at (ox, oy).
    let pw = w + k2 - 1;
    let ph = h + k1 - 1;
    let mut pad = vec![0f32; pw * ph];
    for y in 0..h {
        pad[(y + oy) * pw + ox..(y + oy) * pw + ox + w].copy_from_slice(&m.v[y * w..(y + 1) * w]);
    }
    // Patch means: a box filter over the padded image (zeros count).
    let mut mean = vec![0f32; w * h];
    let inv = 1.0 / (k1 * k2) as f32;
    for dy in 0..k1 {
        for dx in 0..k2 {
            for y in 0..h {
                let src = &pad[(y + dy) * pw + dx..(y + dy) * pw + dx + w];
                for (o, s) in mean[y * w..(y + 1) * w].iter_mut().zip(src) {
                    *o += *s;
                }
            }
        }
    }
    for v in &mut mean {
        *v *= inv;
    }
    filters
        .iter()
        .map(|f| {
            let mut out = vec![0f32; w * h];
            for y in 0..h {
                let row = &mut out[y * w..(y + 1) * w];
                // Sixteen outputs at a time stay in registers while the
                // taps are summed (in tap order, so every output is the
                // same sum as the plain loop's, bit for bit).
                let mut x = 0;
                // (One slice per filter row and a fixed-size array per tap
                // keep the bounds checks out of the lanes' loop.)
                while x + LANES <= w {
                    let mut acc = [0f32; LANES];
                    for (dy, taps) in f.chunks_exact(k2).take(k1).enumerate() {
                        let line = &pad[(y + dy) * pw + x..][..k2 - 1 + LANES];
                        for (dx, &c) in taps.iter().enumerate() {
                            let src: &[f32; LANES] =
                                line[dx..dx + LANES].try_into().expect("LANES values");
                            // Indexed, not zipped: the tests' -O2 build left
                            // `Zip::new` a call per tap (a quarter of a
                            // texture's analysis there).
                            #[allow(clippy::needless_range_loop)]
                            for i in 0..LANES {
                                acc[i] += c * src[i];
                            }
                        }
                    }
                    row[x..x + LANES].copy_from_slice(&acc);
                    x += LANES;
                }
                for (xo, o) in row.iter_mut().enumerate().skip(x) {
                    for dy in 0..k1 {
                        for dx in 0..k2 {
                            *o += f[dy * k2 + dx] * pad[(y + dy) * pw + dx + xo];
                        }
                    }
                }
            }
            let sum: f32 = f.iter().sum();
            for (o, mu) in out.iter_mut().zip(&mean) {
                *o -= sum * *mu;
            }
            Map { w, h, v: out }
        })
        .collect()
}

/// The same convolution as im2col + one matrix product: the mean-removed
/// patches as the columns of a `taps × pixels` matrix, times the
/// `filters × taps` bank (nalgebra, whose f32 products run on
/// matrixmultiply's CPU-dispatched kernels). This is the reference
/// formulation, kept as the baseline `bench texture` times [`convolve`]
/// against, and tested to agree with it; the index never uses it, because
/// its sums are ordered by whichever kernel the CPU gets.
pub fn convolve_im2col(
    width: usize,
    height: usize,
    data: &[f32],
    filters: &[Vec<f32>],
    k1: usize,
    k2: usize,
) -> Vec<Vec<f32>> {
    let (w, h) = (width, height);
    let (oy, ox) = (k1 / 2, k2 / 2);
    let taps = k1 * k2;
    let mut cols = DMatrix::<f32>::zeros(taps, w * h);
    let mut patch = vec![0f32; taps];
    for y in 0..h {
        for x in 0..w {
            for dy in 0..k1 {
                for dx in 0..k2 {
                    let (sy, sx) = (
                        (y + dy) as isize - oy as isize,
                        (x + dx) as isize - ox as isize,
                    );
                    patch[dy * k2 + dx] =
                        if sy >= 0 && sx >= 0 && (sy as usize) < h && (sx as usize) < w {
                            data[sy as usize * w + sx as usize]
                        } else {
                            0.0
                        };
                }
            }
            let mean = patch.iter().sum::<f32>() / taps as f32;
            let mut col = cols.column_mut(y * w + x);
            for (o, v) in col.iter_mut().zip(&patch) {
                *o = v - mean;
            }
        }
    }
    let bank = DMatrix::<f32>::from_fn(filters.len(), taps, |f, t| filters[f][t]);
    let out = bank * cols;
    (0..filters.len())
        .map(|f| (0..w * h).map(|p| out[(f, p)]).collect())
        .collect()
}

/// [`convolve`] on a bare image, for the bench's comparison with
/// [`convolve_im2col`].
pub fn convolve_direct(
    width: usize,
    height: usize,
    data: &[f32],
    filters: &[Vec<f32>],
    k1: usize,
    k2: usize,
) -> Vec<Vec<f32>> {
    let m = Map {
        w: width,
        h: height,
        v: data.to_vec(),
    };
    convolve(&m, filters, k1, k2)
        .into_iter()
        .map(|m| m.v)
        .collect()
}

/// Max pooling over `p × p` windows (the last partial row/column dropped).
fn max_pool(m: &Map, p: usize) -> Map {
    let (w, h) = ((m.w / p).max(1), (m.h / p).max(1));
    let mut v = vec![f32::NEG_INFINITY; w * h];
    let cols = (w * p).min(m.w);
    for y in 0..(h * p).min(m.h) {
        let out = &mut v[(y / p) * w..][..w];
        for (o, px) in out.iter_mut().zip(m.v[y * m.w..][..cols].chunks(p)) {
            for &s in px {
                *o = o.max(s);
            }
        }
    }
    Map { w, h, v }
}

/// Stage-2 inputs: each subset's stage-1 maps summed.
fn combine(maps: &[Map], subsets: &[Vec<usize>]) -> Vec<Map> {
    subsets
        .iter()
        .map(|row| {
            let mut out = maps[row[0]].clone();
            for &j in &row[1..] {
                for (o, s) in out.v.iter_mut().zip(&maps[j].v) {
                    *o += *s;
                }
            }
            out
        })
        .collect()
}

fn as_map(img: &Gray) -> Map {
    Map {
        w: img.width,
        h: img.height,
        v: img.data.clone(),
    }
}

impl Pcn {
    /// Learns both stages' filters from `images` (each resampled to the
    /// configured side first).
    pub fn train(images: &[Gray], config: PcnConfig) -> Result<Pcn> {
        config.validate()?;
        if images.is_empty() {
            return Err(Error::input("PCN training needs at least one image"));
        }
        let c = &config;
        let taps = c.k1 * c.k2;
        let inputs: Vec<Map> = images
            .iter()
            .map(|g| c.view(g).map(|g| c.network_input(&g)))
            .collect::<Result<_>>()?;
        let mut cov = vec![0f64; taps * taps];
        let mut count = 0;
        for m in &inputs {
            accumulate_patches(m, c.k1, c.k2, c.patch_step, &mut cov, &mut count);
        }
        let stage1 = pca_filters(cov, taps, c.l1, count)?;
        let subsets = c.subsets();
        let mut covs = vec![vec![0f64; taps * taps]; subsets.len()];
        let mut counts = vec![0usize; subsets.len()];
        for m in &inputs {
            let pooled: Vec<Map> = convolve(m, &stage1, c.k1, c.k2)
                .iter()
                .map(|o| max_pool(o, c.pool))
                .collect();
            for (s, input) in combine(&pooled, &subsets).iter().enumerate() {
                accumulate_patches(
                    input,
                    c.k1,
                    c.k2,
                    c.patch_step,
                    &mut covs[s],
                    &mut counts[s],
                );
            }
        }
        let stage2 = covs
            .into_iter()
            .zip(counts)
            .map(|(cov, n)| pca_filters(cov, taps, c.l2, n))
            .collect::<Result<_>>()?;
        Ok(Pcn {
            config,
            stage1,
            stage2,
        })
    }

    /// The feature vector of one image (any size; its
    /// [`PcnConfig::view`] first).
    pub fn features(&self, img: &Gray) -> Result<Vec<f32>> {
        let c = &self.config;
        let prepared = c.view(img)?;
        let input = c.network_input(&prepared);
        let pooled: Vec<Map> = convolve(&input, &self.stage1, c.k1, c.k2)
            .iter()
            .map(|o| max_pool(o, c.pool))
            .collect();
        let mut out = Vec::with_capacity(c.feature_len());
        for (input, bank) in combine(&pooled, &c.subsets()).iter().zip(&self.stage2) {
            let maps: Vec<Map> = convolve(input, bank, c.k1, c.k2)
                .iter()
                .map(|o| max_pool(o, c.pool))
                .collect();
            hash_histograms(&maps, c.hash_bits, c.blocks, &mut out);
        }
        if c.intensity_bins > 0 {
            let mut hist = vec![0f32; c.intensity_bins];
            for &v in &prepared.data {
                let b = ((v.clamp(0.0, 1.0) * c.intensity_bins as f32) as usize)
                    .min(c.intensity_bins - 1);
                hist[b] += 1.0;
            }
            let n = prepared.data.len() as f32;
            out.extend(hist.iter().map(|h| (h / n).sqrt()));
        }
        if c.lbp_scales > 0 {
            out.extend(super::lbp::lbp_histograms(&prepared, c.lbp_scales));
        }
        Ok(out)
    }
}

/// Binary hashing of `maps` in groups of `bits`, then one square-rooted,
/// normalised histogram per group and block, appended to `out`.
fn hash_histograms(maps: &[Map], bits: usize, blocks: usize, out: &mut Vec<f32>) {
    let (w, h) = (maps[0].w, maps[0].h);
    for group in maps.chunks(bits) {
        let bins = 1usize << group.len();
        let mut codes = vec![0u16; w * h];
        for (b, m) in group.iter().enumerate() {
            for (code, v) in codes.iter_mut().zip(&m.v) {
                if *v > 0.0 {
                    *code |= 1 << b;
                }
            }
        }
        for by in 0..blocks {
            for bx in 0..blocks {
                let (y0, y1) = (by * h / blocks, (by + 1) * h / blocks);
                let (x0, x1) = (bx * w / blocks, (bx + 1) * w / blocks);
                let mut hist = vec![0u32; bins];
                for y in y0..y1 {
                    for x in x0..x1 {
                        hist[codes[y * w + x] as usize] += 1;
                    }
                }
                let n = ((y1 - y0) * (x1 - x0)).max(1) as f32;
                out.extend(hist.iter().map(|&k| (k as f32 / n).sqrt()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

    fn noise(side: usize, seed: u64) -> Gray {
        let mut r = Rng::new(seed);
        Gray {
            width: side,
            height: side,
            data: (0..side * side).map(|_| r.f64() as f32).collect(),
        }
    }

    /// Stripes of period `p` along x or y: a texture with structure.
    fn stripes(side: usize, p: f32, along_x: bool) -> Gray {
        let mut g = Gray::new(side, side);
        for y in 0..side {
            for x in 0..side {
                let t = if along_x { x } else { y } as f32;
                g.data[y * side + x] = 0.5 + 0.5 * (t * std::f32::consts::TAU / p).sin();
            }
        }
        g
    }

    fn small() -> PcnConfig {
        PcnConfig {
            k1: 5,
            k2: 5,
            l1: 4,
            l2: 6,
            patch_step: 2,
            side: 32,
            intensity_bins: 4,
            // The paper's network alone (the shipped additions are tested
            // on their own below and in `super::super::lbp`).
            lbp_scales: 0,
            equalise: false,
            ..PcnConfig::default()
        }
    }

    #[test]
    fn the_equalised_network_is_blind_to_a_tone_curve_and_lbp_extends_the_features() {
        let cfg = PcnConfig {
            equalise: true,
            lbp_scales: 2,
            ..small()
        };
        let imgs = [noise(48, 3), stripes(48, 5.0, true)];
        let pcn = Pcn::train(&imgs, cfg.clone()).unwrap();
        let img = noise(32, 9); // the view itself: no resampling between the tone curve and the ranks
        let mut toned = img.clone();
        for v in &mut toned.data {
            *v = v.powf(1.7);
        }
        let (a, b) = (pcn.features(&img).unwrap(), pcn.features(&toned).unwrap());
        assert_eq!(a.len(), cfg.feature_len());
        let network =
            cfg.feature_len() - cfg.intensity_bins - 2 * crate::texture::lbp::bins_per_scale();
        assert_eq!(a[..network], b[..network], "the network reads ranks");
        assert_ne!(
            a[network..network + 4],
            b[network..network + 4],
            "the grey levels do move"
        );
        // Unequalised, the same tone curve changes the network's codes.
        let plain = Pcn::train(&imgs, small()).unwrap();
        assert_ne!(
            plain.features(&img).unwrap()[..network],
            plain.features(&toned).unwrap()[..network]
        );
    }

    #[test]
    fn pca_filters_are_orthonormal() {
        let imgs: Vec<Gray> = (0..4)
            .map(|s| noise(48, s))
            .chain([stripes(48, 6.0, true)])
            .collect();
        let pcn = Pcn::train(&imgs, small()).unwrap();
        for bank in std::iter::once(&pcn.stage1).chain(pcn.stage2.iter()) {
            for (i, a) in bank.iter().enumerate() {
                for (j, b) in bank.iter().enumerate() {
                    let dot: f32 = a.iter().zip(b).map(|(x, y)| x * y).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((dot - want).abs() < 1e-4, "filters {i}, {j}: dot {dot}");
                }
            }
        }
    }

    /// The direct convolution equals the textbook definition: the filter's
    /// dot product with the zero-padded, mean-removed patch at each pixel,
    /// on a map narrower than the kernel's 16 lanes and on one wider (the
    /// lanes and the leftover columns).
    #[test]
    fn convolution_matches_a_naive_patch_projection() {
        for width in [11, 37] {
            convolution_matches_naive(width);
        }
    }

    fn convolution_matches_naive(width: usize) {
        let img = noise(width, 3);
        let m = as_map(&Gray {
            width,
            height: 9,
            data: img.data[..width * 9].to_vec(),
        });
        let (k1, k2) = (3, 5);
        let mut r = Rng::new(9);
        let filters: Vec<Vec<f32>> = (0..3)
            .map(|_| (0..k1 * k2).map(|_| r.f64() as f32 - 0.5).collect())
            .collect();
        let got = convolve(&m, &filters, k1, k2);
        for (f, out) in filters.iter().zip(&got) {
            for y in 0..m.h {
                for x in 0..m.w {
                    let mut patch = vec![0f64; k1 * k2];
                    for dy in 0..k1 {
                        for dx in 0..k2 {
                            let (sy, sx) =
                                (y as isize + dy as isize - 1, x as isize + dx as isize - 2);
                            if sy >= 0 && sx >= 0 && (sy as usize) < m.h && (sx as usize) < m.w {
                                patch[dy * k2 + dx] = m.v[sy as usize * m.w + sx as usize] as f64;
                            }
                        }
                    }
                    let mean = patch.iter().sum::<f64>() / patch.len() as f64;
                    let want: f64 = patch
                        .iter()
                        .zip(f)
                        .map(|(p, c)| (p - mean) * *c as f64)
                        .sum();
                    let v = out.v[y * m.w + x] as f64;
                    assert!((v - want).abs() < 1e-5, "({x}, {y}): {v} vs {want}");
                }
            }
        }
    }

    /// The bench's im2col + matrix-product baseline computes the same
    /// convolution (up to the kernel's rounding).
    #[test]
    fn im2col_baseline_agrees_with_the_direct_convolution() {
        let img = noise(37, 4);
        let filters: Vec<Vec<f32>> = (0..5)
            .map(|f| {
                (0..49)
                    .map(|t| ((f * 49 + t) as f32 * 0.37).sin())
                    .collect()
            })
            .collect();
        let a = convolve_direct(37, 37, &img.data, &filters, 7, 7);
        let b = convolve_im2col(37, 37, &img.data, &filters, 7, 7);
        for (fa, fb) in a.iter().zip(&b) {
            for (x, y) in fa.iter().zip(fb) {
                assert!((x - y).abs() < 1e-4, "{x} vs {y}");
            }
        }
    }

    /// Windows that do not divide the map: the last row and column that
    /// fit no whole window are dropped, as the pooled size says.
    #[test]
    fn max_pooling_of_a_ragged_map_takes_whole_windows_only() {
        let m = Map {
            w: 7,
            h: 8,
            v: (0..56).map(|i| ((i * 13) % 17) as f32).collect(),
        };
        let p = max_pool(&m, 3);
        assert_eq!((p.w, p.h), (2, 2));
        for y in 0..2 {
            for x in 0..2 {
                let mut want = f32::NEG_INFINITY;
                for dy in 0..3 {
                    for dx in 0..3 {
                        want = want.max(m.v[(3 * y + dy) * 7 + 3 * x + dx]);
                    }
                }
                assert_eq!(p.v[y * 2 + x], want);
            }
        }
    }

    #[test]
    fn max_pooling_takes_each_windows_maximum() {
        let m = Map {
            w: 5,
            h: 4,
            v: (0..20).map(|i| ((i * 7) % 11) as f32).collect(),
        };
        let p = max_pool(&m, 2);
        assert_eq!((p.w, p.h), (2, 2));
        for y in 0..2 {
            for x in 0..2 {
                let want = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .map(|(dx, dy)| m.v[(2 * y + dy) * 5 + 2 * x + dx])
                    .fold(f32::NEG_INFINITY, f32::max);
                assert_eq!(p.v[y * 2 + x], want);
            }
        }
    }

    #[test]
    fn features_have_the_promised_length_and_unit_histograms() {
        let cfg = PcnConfig {
            blocks: 2,
            combination: vec![vec![0, 1], vec![2], vec![3, 0]],
            ..small()
        };
        let pcn = Pcn::train(&[noise(40, 1), stripes(40, 5.0, false)], cfg.clone()).unwrap();
        let f = pcn.features(&noise(64, 2)).unwrap();
        assert_eq!(f.len(), cfg.feature_len());
        // Three subsets × two groups (4 + 2 maps) × four blocks histograms,
        // each of unit L2 norm after the square root, plus the grey levels.
        let norm2: f32 = f.iter().map(|v| v * v).sum();
        assert!((norm2 - (3 * 2 * 4 + 1) as f32).abs() < 1e-3, "{norm2}");
    }

    #[test]
    fn features_tell_orientation_apart_and_are_deterministic() {
        let imgs = [
            stripes(48, 6.0, true),
            stripes(48, 6.0, false),
            noise(48, 5),
        ];
        let a = Pcn::train(&imgs, small()).unwrap();
        let b = Pcn::train(&imgs, small()).unwrap();
        assert_eq!(a, b);
        let fx = a.features(&stripes(40, 6.0, true)).unwrap();
        let fy = a.features(&stripes(40, 6.0, false)).unwrap();
        let fx2 = a.features(&stripes(40, 7.0, true)).unwrap();
        let d = |p: &[f32], q: &[f32]| p.iter().zip(q).map(|(x, y)| (x - y) * (x - y)).sum::<f32>();
        assert!(
            d(&fx, &fx2) < d(&fx, &fy),
            "same orientation should be closer: {} vs {}",
            d(&fx, &fx2),
            d(&fx, &fy)
        );
        assert_eq!(fx, a.features(&stripes(40, 6.0, true)).unwrap());
    }

    /// A query image twice the window reads as its two diagonal quadrants
    /// (the dataset's crops 0 and 3); an image the size of the view reads
    /// whole, once.
    #[test]
    fn a_large_query_reads_two_diagonal_windows() {
        let c = PcnConfig {
            side: 32,
            texture_side: 64,
            ..PcnConfig::default()
        };
        let big = noise(64, 5);
        let views = c.views(&big).unwrap();
        assert_eq!(views.len(), 2);
        for (v, d) in views.iter().zip([0, 32]) {
            assert_eq!((v.width, v.height), (32, 32));
            for y in 0..32 {
                for x in 0..32 {
                    assert!((v.at(x, y) - big.at(d + x, d + y)).abs() < 1e-6);
                }
            }
        }
        let small = noise(32, 6);
        assert_eq!(c.views(&small).unwrap(), vec![c.view(&small).unwrap()]);
        // Between the two, the windows overlap in the corners.
        let mid = noise(48, 7);
        let v = c.views(&mid).unwrap();
        assert_eq!(v.len(), 2);
        assert!((v[1].at(31, 31) - mid.at(47, 47)).abs() < 1e-6);
    }

    #[test]
    fn bad_settings_and_inputs_are_errors() {
        assert!(PcnConfig {
            l1: 50,
            ..PcnConfig::default()
        }
        .validate()
        .is_err());
        assert!(PcnConfig {
            hash_bits: 0,
            ..PcnConfig::default()
        }
        .validate()
        .is_err());
        assert!(PcnConfig {
            combination: vec![vec![99]],
            ..PcnConfig::default()
        }
        .validate()
        .is_err());
        assert!(Pcn::train(&[], small()).is_err());
        assert!(prepare(&Gray::new(0, 3), 32).is_err());
        let nan = Gray {
            width: 32,
            height: 32,
            data: vec![f32::NAN; 1024],
        };
        assert!(Pcn::train(&[nan], small()).is_err());
    }

    #[test]
    fn the_view_reads_textures_at_the_training_crops_pixel_scale() {
        let c = PcnConfig {
            side: 32,
            texture_side: 64,
            ..PcnConfig::default()
        };
        // A training image (side²) whole; a texture up to twice that at its
        // own pixels; larger ones scaled down to read as 64 across; smaller
        // ones whole.
        assert_eq!(
            [20, 32, 48, 64, 128, 256].map(|s| c.window(s)),
            [20, 32, 32, 32, 64, 128]
        );
        let whole = PcnConfig {
            side: 32,
            ..PcnConfig::default()
        };
        assert_eq!(whole.window(256), 256);
        // The view of a 64² ramp is its centre 32² square, pixel for pixel.
        let ramp = Gray {
            width: 64,
            height: 64,
            data: (0..64 * 64).map(|i| i as f32).collect(),
        };
        let v = c.view(&ramp).unwrap();
        assert_eq!((v.width, v.height), (32, 32));
        for y in 0..32 {
            for x in 0..32 {
                assert_eq!(v.at(x, y), ramp.at(x + 16, y + 16));
            }
        }
        assert!(PcnConfig {
            texture_side: 16,
            ..c.clone()
        }
        .validate()
        .is_err());
    }

    #[test]
    fn prepare_averages_down_and_keeps_a_constant_constant() {
        let g = Gray {
            width: 90,
            height: 60,
            data: vec![0.25; 5400],
        };
        let p = prepare(&g, 32).unwrap();
        assert!(p.data.iter().all(|v| (v - 0.25).abs() < 1e-6));
        let up = prepare(
            &Gray {
                width: 8,
                height: 8,
                data: vec![0.75; 64],
            },
            32,
        )
        .unwrap();
        assert!(up.data.iter().all(|v| (v - 0.75).abs() < 1e-6));
    }
}

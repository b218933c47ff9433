//! Fit's global stage for repeating designs: find the basin of a periodic
//! parameter before the gradient stage polishes it (issue 37).
//!
//! Period, angle and phase make the loss a comb of narrow basins, and a GA
//! over raw parameters at full resolution rarely lands in the right tooth.
//! This stage splits the problem the way the field does:
//!
//! 1. **Spectra** ([`Metric::Spectrum`]): a low-discrepancy sample of the
//!    whole parameter box, drawn at a low resolution, is compared with the
//!    target by the magnitudes of their windowed Fourier transforms, one per
//!    colour, blurred over a few frequency bins. A shift moves only the phase
//!    of a transform, so the comparison ignores where the pattern sits and
//!    sees its period, angle and proportions as a smooth landscape.
//! 2. **Sensitivity** ([`Metric::Spectrum`] again): for each of the best few
//!    distinct points, every parameter is swept over its range with the
//!    others held. Parameters the spectrum barely notices (offsets,
//!    positions: the "phase") are told apart from the structural ones.
//! 3. **Phase sweep** ([`Metric::Loss`]): around each of those points, the
//!    phase-like parameters are sampled over their whole range and the
//!    others jittered a little, with Fit's own loss at full resolution.
//!
//! Every point the sweep scored goes to Fit's archive; Adam refines the best
//! distinct ones as after the GA. Each stage hands out whole batches
//! (ask/tell, like [`crate::optim::AskTell`]), so a batch is evaluated in
//! shards across the worker pool or native threads.
use super::field::{Evaluator, Grid, Scene};
use super::target::{coverage, Target};
use crate::core::rng::Rng;
use crate::geom::fft::fft2;
use crate::optim::{best_distinct, Scored};
use serde::{Deserialize, Serialize};

/// The global stage's budgets (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GlobalOptions {
    /// Points of the spectral sample of the whole box.
    pub samples: usize,
    /// Distinct points of the spectral sample examined further.
    pub basins: usize,
    /// Points of the phase sweep around each of them.
    pub sweep: usize,
    /// Longer side of the spectral comparison's grid (a power of two at most).
    pub grid: usize,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        GlobalOptions {
            samples: 1024,
            basins: 6,
            sweep: 48,
            grid: 64,
        }
    }
}

impl GlobalOptions {
    /// The paper budget's: four times the sample, more basins, a denser sweep.
    pub fn thorough() -> GlobalOptions {
        GlobalOptions {
            samples: 4096,
            basins: 10,
            sweep: 96,
            grid: 64,
        }
    }

    /// Spectral evaluations and loss evaluations it asks for at most, for
    /// `dim` parameters.
    pub fn evaluations(&self, dim: usize) -> (usize, usize) {
        (
            self.samples + self.basins * dim * SENSITIVITY_PROBES,
            self.basins * self.sweep,
        )
    }
}

/// Values of one parameter tried for the sensitivity (evenly over the range).
const SENSITIVITY_PROBES: usize = 4;

/// A parameter whose largest change of the spectral loss over its range is
/// at most this fraction of the most telling parameter's counts as phase.
const PHASE_SENSITIVITY: f64 = 0.3;

/// Half-width (normalised) of the jitter of structural parameters in the sweep.
const JITTER: f64 = 0.04;

/// Two basins closer than this (normalised, in every structural parameter)
/// are one.
const SAME_BASIN: f64 = 0.03;

/// Which comparison a batch wants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// [`Spectral::loss`]: shift-invariant, low resolution.
    Spectrum,
    /// Fit's own loss.
    Loss,
}

#[derive(Debug, Clone, PartialEq)]
enum Stage {
    Sample,
    Sensitivity,
    Sweep,
    Finished,
}

/// The stage's state: what it asked for and what it learnt.
#[derive(Debug, Clone)]
pub struct GlobalSearch {
    opts: GlobalOptions,
    dim: usize,
    stage: Stage,
    /// Scored spectral sample.
    spectral: Vec<Scored>,
    /// The points examined further, with their spectral loss.
    basins: Vec<Scored>,
    /// Per basin, which parameters are phase-like.
    phase: Vec<Vec<bool>>,
    /// Points scored with Fit's loss.
    scored: Vec<Scored>,
    asked: usize,
}

/// The `n`-th point of the `dim`-dimensional R-sequence (Roberts' additive
/// recurrence on the generalised golden ratio), shifted by `shift`: a
/// low-discrepancy sequence that is good for every prefix and every `dim`.
fn r_sequence(n: usize, shift: &[f64]) -> Vec<f64> {
    let d = shift.len();
    // φ_d: the positive root of x^(d+1) = x + 1.
    let mut phi = 2.0f64;
    for _ in 0..40 {
        phi = libm::pow(1.0 + phi, 1.0 / (d as f64 + 1.0));
    }
    let mut a = 1.0;
    (0..d)
        .map(|k| {
            a /= phi;
            let v = shift[k] + (n as f64 + 1.0) * a;
            v - v.floor()
        })
        .collect()
}

impl GlobalSearch {
    pub fn new(dim: usize, opts: GlobalOptions) -> GlobalSearch {
        GlobalSearch {
            opts,
            dim,
            stage: Stage::Sample,
            spectral: vec![],
            basins: vec![],
            phase: vec![],
            scored: vec![],
            asked: 0,
        }
    }

    /// Evaluations it asks for at most (spectral and loss together).
    pub fn budget(&self) -> usize {
        let (s, l) = self.opts.evaluations(self.dim);
        s + l
    }

    /// The stage in words, for progress.
    pub fn describe(&self) -> &'static str {
        match self.stage {
            Stage::Sample => "global search: comparing spectra",
            Stage::Sensitivity => "global search: telling period from phase",
            Stage::Sweep => "global search: sweeping the phase",
            Stage::Finished => "global search: done",
        }
    }

    /// Points scored with Fit's loss (the sweep), for choosing Adam's starts.
    pub fn scored(&self) -> &[Scored] {
        &self.scored
    }

    /// The next batch and how to score it; `None` when finished.
    pub fn ask(&mut self, rng: &mut Rng) -> Option<(Vec<Vec<f64>>, Metric)> {
        match self.stage {
            Stage::Sample => {
                let shift: Vec<f64> = (0..self.dim).map(|_| rng.f64()).collect();
                let batch = (0..self.opts.samples)
                    .map(|n| r_sequence(n, &shift))
                    .collect();
                Some((batch, Metric::Spectrum))
            }
            Stage::Sensitivity => {
                let mut batch = vec![];
                for b in &self.basins {
                    for k in 0..self.dim {
                        for j in 0..SENSITIVITY_PROBES {
                            let mut u = b.u.clone();
                            u[k] = (j as f64 + 0.5) / SENSITIVITY_PROBES as f64;
                            batch.push(u);
                        }
                    }
                }
                Some((batch, Metric::Spectrum))
            }
            Stage::Sweep => {
                let mut batch = vec![];
                for (b, phase) in self.basins.iter().zip(&self.phase) {
                    let shift: Vec<f64> = (0..self.dim).map(|_| rng.f64()).collect();
                    batch.push(b.u.clone());
                    for n in 1..self.opts.sweep {
                        let r = r_sequence(n, &shift);
                        let u = (0..self.dim)
                            .map(|k| {
                                if phase[k] {
                                    r[k]
                                } else {
                                    (b.u[k] + (2.0 * r[k] - 1.0) * JITTER).clamp(0.0, 1.0)
                                }
                            })
                            .collect();
                        batch.push(u);
                    }
                }
                Some((batch, Metric::Loss))
            }
            Stage::Finished => None,
        }
        .inspect(|(b, _)| self.asked += b.len())
    }

    /// The scores of the batch last asked for, in order.
    pub fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        let scored = batch
            .into_iter()
            .zip(losses)
            .map(|(u, &loss)| Scored { u, loss });
        match self.stage {
            Stage::Sample => {
                self.spectral.extend(scored);
                self.basins = distinct_basins(&self.spectral, self.opts.basins);
                self.stage = if self.dim == 0 || self.basins.is_empty() {
                    Stage::Finished
                } else {
                    Stage::Sensitivity
                };
            }
            Stage::Sensitivity => {
                let probes: Vec<Scored> = scored.collect();
                let per = self.dim * SENSITIVITY_PROBES;
                self.phase = self
                    .basins
                    .iter()
                    .zip(probes.chunks(per))
                    .map(|(b, p)| phase_like(b.loss, p, self.dim))
                    .collect();
                self.stage = Stage::Sweep;
            }
            Stage::Sweep => {
                self.scored.extend(scored);
                self.stage = Stage::Finished;
            }
            Stage::Finished => {}
        }
    }
}

/// The `k` best points of `all` (finite losses) no two of which are closer
/// than [`SAME_BASIN`] in every coordinate.
fn distinct_basins(all: &[Scored], k: usize) -> Vec<Scored> {
    let finite: Vec<Scored> = all.iter().filter(|s| s.loss.is_finite()).cloned().collect();
    let mut out: Vec<Scored> = vec![];
    for s in best_distinct(&finite, finite.len()) {
        if out.len() == k {
            break;
        }
        let near = out.iter().any(|o| {
            o.u.iter()
                .zip(&s.u)
                .all(|(a, b)| (a - b).abs() < SAME_BASIN)
        });
        if !near {
            out.push(s);
        }
    }
    out
}

/// Which parameters are phase-like at a point of spectral loss `at`, from
/// its probes ([`SENSITIVITY_PROBES`] per parameter, in order): those whose
/// largest change is at most [`PHASE_SENSITIVITY`] of the largest.
fn phase_like(at: f64, probes: &[Scored], dim: usize) -> Vec<bool> {
    let change: Vec<f64> = (0..dim)
        .map(|k| {
            probes[k * SENSITIVITY_PROBES..(k + 1) * SENSITIVITY_PROBES]
                .iter()
                .map(|p| {
                    if p.loss.is_finite() {
                        (p.loss - at).abs()
                    } else {
                        f64::INFINITY
                    }
                })
                .fold(0.0, f64::max)
        })
        .collect();
    let most = change.iter().copied().fold(0.0, f64::max);
    change
        .iter()
        .map(|&c| most > 0.0 && c <= PHASE_SENSITIVITY * most)
        .collect()
}

/// Spectral descriptors of a picture: per colour, the blurred magnitude of
/// the windowed transform of its coverage, and its mean coverage.
#[derive(Debug, Clone, Default)]
struct Descriptor {
    mags: Vec<f32>,
    means: Vec<f64>,
}

/// The shift-invariant comparison ([`Metric::Spectrum`]).
#[derive(Debug, Clone)]
pub struct Spectral {
    eval: Evaluator,
    nodes: Vec<f64>,
    /// The target's descriptor.
    target: Descriptor,
    /// Side of the (square, zero-padded) transform.
    side: usize,
    window_x: Vec<f64>,
    window_y: Vec<f64>,
    /// Scratch.
    re: Vec<f32>,
    im: Vec<f32>,
    mine: Descriptor,
    /// Work units of the last evaluation (item evaluations plus transform values).
    pub last_work: u64,
}

/// Weight of the mean-coverage term against the spectra.
const MEAN_WEIGHT: f64 = 1.0;

impl Spectral {
    /// The comparison with `target` (its coverage, on any grid) at a grid
    /// of `n` pixels along the canvas's longer side (rounded down to a power
    /// of two, at most the target's).
    pub fn new(scene: &Scene, target: &Target, n: usize) -> Spectral {
        let tg = target.grid;
        let long = tg.w.max(tg.h);
        let mut side = 8usize;
        while side * 2 <= n.min(long) {
            side *= 2;
        }
        let grid = Grid::on(scene.rec.canvas, side);
        let hann = |len: usize| -> Vec<f64> {
            (0..len)
                .map(|i| {
                    let t = (i as f64 + 0.5) / len as f64;
                    0.5 - 0.5 * libm::cos(std::f64::consts::TAU * t)
                })
                .collect()
        };
        let mut s = Spectral {
            eval: Evaluator::on(grid, grid.long_ppu()),
            nodes: vec![],
            target: Descriptor::default(),
            side,
            window_x: hann(grid.w),
            window_y: hann(grid.h),
            re: vec![],
            im: vec![],
            mine: Descriptor::default(),
            last_work: 0,
        };
        let channels = scene.channels.len();
        let plane = tg.w * tg.h;
        let mut cover = Vec::with_capacity(channels * grid.len());
        for c in 0..channels {
            let src = target.cover.get(c * plane..(c + 1) * plane).unwrap_or(&[]);
            cover.extend(resample_area(src, (tg.w, tg.h), (grid.w, grid.h)));
        }
        let mut d = Descriptor::default();
        s.describe(&cover, &mut d);
        s.target = d;
        s
    }

    /// The grid the candidates are drawn on.
    pub fn grid(&self) -> Grid {
        self.eval.grid
    }

    /// Spectral loss of `params` (float parameters, raw units); +∞ where
    /// the program makes a shape non-finite.
    pub fn loss(&mut self, scene: &Scene, params: &[f64]) -> f64 {
        scene.rec.tape.forward(params, &mut self.nodes);
        if !scene.shapes_finite(&self.nodes) {
            self.last_work = scene.rec.prims.len() as u64 + 1;
            return f64::INFINITY;
        }
        self.eval.eval(scene, &self.nodes, false);
        let cover: Vec<f64> = self.eval.s.iter().map(|&d| coverage(d)).collect();
        let mut mine = std::mem::take(&mut self.mine);
        self.describe(&cover, &mut mine);
        let t = &self.target;
        let spectra: f64 = mine
            .mags
            .iter()
            .zip(&t.mags)
            .map(|(a, b)| {
                let d = (a - b) as f64;
                d * d
            })
            .sum();
        let means: f64 = mine
            .means
            .iter()
            .zip(&t.means)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        self.mine = mine;
        self.last_work = self.eval.work + (self.side * self.side * self.target.means.len()) as u64;
        spectra + MEAN_WEIGHT * means
    }

    /// The descriptor of channel-major coverage on the comparison's grid.
    fn describe(&mut self, cover: &[f64], out: &mut Descriptor) {
        let g = self.eval.grid;
        let n = self.side;
        let plane = g.w * g.h;
        out.mags.clear();
        out.means.clear();
        let norm = 1.0 / plane as f64;
        for ch in cover.chunks_exact(plane) {
            let mean = ch.iter().sum::<f64>() * norm;
            self.re.clear();
            self.re.resize(n * n, 0.0);
            self.im.clear();
            self.im.resize(n * n, 0.0);
            for y in 0..g.h {
                for x in 0..g.w {
                    self.re[y * n + x] =
                        ((ch[y * g.w + x] - mean) * self.window_x[x] * self.window_y[y]) as f32;
                }
            }
            fft2(&mut self.re, &mut self.im, n, n, false).expect("a power-of-two side");
            let mag: Vec<f32> = self
                .re
                .iter()
                .zip(&self.im)
                .map(|(r, i)| ((r * r + i * i).sqrt() as f64 * norm) as f32)
                .collect();
            out.mags.extend(blur_circular(&mag, n));
            out.means.push(mean);
        }
    }
}

/// A 5 × 5 binomial blur of an `n × n` plane that wraps around (a
/// transform's bins are circular), so nearby frequencies overlap.
fn blur_circular(p: &[f32], n: usize) -> Vec<f32> {
    const K: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
    let mut tmp = vec![0.0f32; n * n];
    for y in 0..n {
        for x in 0..n {
            tmp[y * n + x] = (0..5).map(|k| K[k] * p[y * n + (x + n + k - 2) % n]).sum();
        }
    }
    let mut out = vec![0.0f32; n * n];
    for y in 0..n {
        for x in 0..n {
            out[y * n + x] = (0..5)
                .map(|k| K[k] * tmp[((y + n + k - 2) % n) * n + x])
                .sum();
        }
    }
    out
}

/// Area-average resampling of a `sw × sh` plane to `dw × dh` (each
/// destination pixel the mean of the source area under it). An empty
/// source gives zeros.
fn resample_area(src: &[f64], (sw, sh): (usize, usize), (dw, dh): (usize, usize)) -> Vec<f64> {
    if src.len() != sw * sh || sw == 0 || sh == 0 {
        return vec![0.0; dw * dh];
    }
    // Weights of source index i in destination index j along one axis.
    let axis = |s: usize, d: usize| -> Vec<Vec<(usize, f64)>> {
        let r = s as f64 / d as f64;
        (0..d)
            .map(|j| {
                let (a, b) = (j as f64 * r, (j + 1) as f64 * r);
                let mut w = vec![];
                let mut i = a.floor() as usize;
                while (i as f64) < b && i < s {
                    let lo = (i as f64).max(a);
                    let hi = ((i + 1) as f64).min(b);
                    if hi > lo {
                        w.push((i, (hi - lo) / r));
                    }
                    i += 1;
                }
                w
            })
            .collect()
    };
    let (wx, wy) = (axis(sw, dw), axis(sh, dh));
    let mut rows = vec![0.0; dw * sh];
    for y in 0..sh {
        for (x, w) in wx.iter().enumerate() {
            rows[y * dw + x] = w.iter().map(|&(i, f)| f * src[y * sw + i]).sum();
        }
    }
    let mut out = vec![0.0; dw * dh];
    for (y, w) in wy.iter().enumerate() {
        for x in 0..dw {
            out[y * dw + x] = w.iter().map(|&(i, f)| f * rows[i * dw + x]).sum();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r_sequence_fills_the_box_evenly() {
        let shift = [0.3, 0.7];
        let pts: Vec<Vec<f64>> = (0..256).map(|n| r_sequence(n, &shift)).collect();
        // Every cell of a 4 × 4 grid holds close to 16 points.
        let mut cells = [0usize; 16];
        for p in &pts {
            assert!(p.iter().all(|v| (0.0..1.0).contains(v)));
            cells[(p[0] * 4.0) as usize * 4 + (p[1] * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| (12..=20).contains(&c)), "{cells:?}");
    }

    #[test]
    fn area_resampling_keeps_the_mean() {
        let src: Vec<f64> = (0..100 * 60).map(|i| ((i * 7) % 13) as f64).collect();
        let mean = src.iter().sum::<f64>() / src.len() as f64;
        let out = resample_area(&src, (100, 60), (64, 38));
        let m2 = out.iter().sum::<f64>() / out.len() as f64;
        assert!((mean - m2).abs() < 0.05, "{mean} vs {m2}");
    }

    #[test]
    fn phase_is_what_the_spectrum_barely_notices() {
        let probe = |l: f64| Scored { u: vec![], loss: l };
        // Parameter 0 changes the loss by up to 1.0, parameter 1 by 0.05.
        let probes: Vec<Scored> = [0.1, 1.1, 0.5, 0.2, 0.12, 0.13, 0.15, 0.1]
            .into_iter()
            .map(probe)
            .collect();
        assert_eq!(phase_like(0.1, &probes, 2), vec![false, true]);
    }
}

//! `micro-fit` (paper §6, §12): fit some numbers of a scene to a target
//! with the Fourier loss, shared by `filigree micro fit` and the browser.
//!
//! The parameters to fit are JSON pointers (RFC 6901) into the scene text,
//! each with a range: `{"pointer": "/children/0/period", "lo": 0.1, "hi": 1}`.
//! A number that is an integer in the scene (a seed, a count) stays one
//! (rounded). The target is one of
//! - `{"kind": "scene", "scene": "..."}`: another scene sampled on the same
//!   grid (a synthetic exemplar, as in the paper's Table 3);
//! - `{"kind": "volume", "values": [...]}`: a sampled SDF, `grid³` values,
//!   x fastest;
//! - `{"kind": "slices", "pngs": [...], "range": R}`: a stack of grey slice
//!   images (`grid × grid` each; their count a power of two ≤ `grid`) on
//!   planes evenly spaced in z over the sample box; grey `g ∈ [0, 1]` is
//!   the distance `(2g − 1) R` (dark inside), and the fitted field is
//!   clamped to `±R` to match;
//! - `{"kind": "image", "png": ... | "scene": "..."}`: analysis by synthesis
//!   (§12.2): a picture rendered with `render` (camera, steps, shading; the
//!   image's own size, each side a power of two), compared by the amplitude
//!   loss of Eq. 39. Given a `scene`, the target picture is rendered here.
//!
//! The volume is sampled at the cell centres of a `grid³` lattice over the
//! box `center ± half`; the loss is Eq. 36's log MSE of amplitude and phase
//! spectra ([`super::fit::fourier_loss`]). The optimiser (`cmaes`,
//! `nelder-mead`, `powell`, all ask/tell in [`crate::optim`]) works in
//! normalised coordinates; the start is the scene's own values.
//!
//! Coarse to fine ([`MicroFitRequest::coarse_to_fine`], volume targets):
//! the paper's loss of a periodic structure is a needle in its frequencies,
//! so the budget is split into stages that compare coarser views first
//! ([`COARSE_TO_FINE`]); each evaluation still computes the paper's loss,
//! which alone picks the best point and is the loss reported.
//!
//! Parallel: `shards: [k, n]` makes this job shard k of n of one fit. Every
//! shard asks the same batch, evaluates points `k, k + n, ...`, and the
//! shards exchange their losses ([`Job::outbox`]/[`Job::inbox`]), so each
//! tells its optimiser the same full batch and ends with the result of one
//! unsharded fit, bit for bit.
//!
//! The response carries no time (the core reads no clock): the CLI and the
//! page measure seconds around the job.
use super::api::{start_render, MicroRenderRequest, RenderJob};
use super::fit::{amplitude_loss, Fourier, Profiles, Spectrum};
use super::periodic::Wave;
use super::scene::{self, Node, Op, Scene};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Progress, Step};
use crate::core::request_limits as lim;
use crate::core::rng::Rng;
use crate::optim::{AskTell, Cmaes, CmaesOptions, NelderMead, Powell, Scored};
use crate::raster::{decode_png, decode_sent, Limits};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use serde_bytes::ByteBuf;
use serde_json::Value;

/// Largest grid side, parameter count, budget, image side, population.
pub const MAX_FIT_GRID: u32 = 64;
pub const MAX_FIT_PARAMS: usize = 32;
pub const MAX_FIT_BUDGET: u32 = 100_000;
pub const MAX_FIT_IMAGE_SIDE: u32 = 256;
pub const MAX_FIT_POPULATION: u32 = 1000;
/// Numbers of a scene a fit may set stay within this magnitude.
const MAX_VALUE: f64 = 1e9;

/// Which optimiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Optimizer {
    /// CMA-ES: a population per generation (global, the paper's choice).
    #[default]
    Cmaes,
    /// Nelder–Mead simplex from the scene's values, random restarts.
    NelderMead,
    /// Powell's conjugate directions from the scene's values (local).
    Powell,
}

/// A number of the scene to fit, and its range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitParam {
    /// JSON pointer to a number in the scene, e.g. `/children/0/period`.
    pub pointer: String,
    pub lo: f64,
    pub hi: f64,
    /// More pointers that take the same value (a tied parameter, e.g. one
    /// frequency along x, y and z).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<String>,
}

/// What to fit to (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum FitTarget {
    Scene {
        scene: String,
    },
    Volume {
        values: Vec<f64>,
    },
    Slices {
        pngs: Vec<ByteBuf>,
        #[serde(default = "one")]
        range: f64,
    },
    Image {
        #[serde(default)]
        png: Option<ByteBuf>,
        #[serde(default)]
        scene: Option<String>,
    },
}

fn one() -> f64 {
    1.0
}

impl Default for FitTarget {
    fn default() -> Self {
        FitTarget::Scene {
            scene: String::new(),
        }
    }
}

/// `micro-fit` / `filigree micro fit`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MicroFitRequest {
    /// The scene as JSON text; its values are the start.
    pub scene: String,
    pub params: Vec<FitParam>,
    pub target: FitTarget,
    /// Samples per side of the volume (a power of two).
    pub grid: u32,
    /// The sample box `center ± half` (world units).
    pub center: [f64; 3],
    pub half: f64,
    pub optimizer: Optimizer,
    /// Loss evaluations in all (the start point's included).
    pub budget: u32,
    /// CMA-ES samples per generation (0: 4 + ⌊3 ln d⌋).
    pub population: u32,
    /// CMA-ES initial step, as a fraction of each range.
    pub sigma: f64,
    pub seed: u64,
    /// Image targets: how to render (its `scene`, `width` and `height` are
    /// ignored: the candidate and the target image's size are used).
    pub render: MicroRenderRequest,
    /// `[k, n]`: this job is shard k of n of one fit.
    pub shards: Option<(usize, usize)>,
    /// Coarse to fine (volume targets only): the budget in three stages,
    /// each optimiser run starting from the last one's best point. The
    /// first compares power profiles on the frequency planes blurred over
    /// [`COARSE_SIGMA_BINS`] frequency bins ([`Profiles`]: a wide basin
    /// around the true frequencies, which the paper's loss hides in a
    /// needle), the second amplitude spectra alone (the loss without its
    /// phase term), the last the paper's loss ([`COARSE_TO_FINE`] has the
    /// shares). Every evaluation still computes the paper's loss: `loss`,
    /// `history` and the best point are by it throughout. Off by default.
    pub coarse_to_fine: bool,
}

/// [`MicroFitRequest::coarse_to_fine`]'s stages: what each compares, the
/// fraction of the budget spent when it ends, and its optimiser's initial
/// step (CMA-ES; normalised units, `None`: the request's `sigma`, with
/// restarts). Measured on `bench micro`'s gyroid 3D and 5D (a NumPy
/// prototype of the same stages): the profiles find every frequency to
/// about 0.01 % but not the thickness (it moves only the DC bin), the
/// amplitudes bring both inside the paper's loss's needle (about 1 %
/// wide), the last stage polishes.
pub const COARSE_TO_FINE: [(Compare, f64, Option<f64>); 3] = [
    (Compare::Profiles, 0.4, None),
    (Compare::Amplitudes, 0.7, Some(0.01)),
    (Compare::Exact, 1.0, Some(0.002)),
];

/// Powell's line searches on the coarse profiles stop at brackets this
/// wide (normalised units; 1e-7 elsewhere). Polishing the coarse loss's
/// minima to 1e-7 cost about 250 evaluations per start on gyroid 5D, so
/// the first stage (1200 of 3000) saw the start, stuck in a local minimum
/// of the profiles (frequencies ≈ 161, 190, 140), and one restart; at 1e-3
/// it makes 4–5 restarts and finds (100, 120, 80) on seeds 1–3 (issue 12).
pub const COARSE_LINE_TOLERANCE: f64 = 1e-3;

/// The blur of the coarse stage's profiles, in frequency bins.
pub const COARSE_SIGMA_BINS: f64 = 2.0;

/// What a stage of a fit compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    /// Blurred power profiles on the frequency planes ([`Profiles`]).
    Profiles,
    /// Amplitude spectra ([`Fourier::last_amplitude_loss`]).
    Amplitudes,
    /// The paper's loss.
    Exact,
}

impl Default for MicroFitRequest {
    fn default() -> Self {
        MicroFitRequest {
            scene: String::new(),
            params: vec![],
            target: FitTarget::default(),
            grid: 32,
            center: [0.0; 3],
            half: 1.0,
            optimizer: Optimizer::Cmaes,
            budget: 1500,
            population: 20,
            sigma: 0.3,
            seed: 1,
            render: MicroRenderRequest {
                width: 64,
                height: 64,
                ..Default::default()
            },
            shards: None,
            coarse_to_fine: false,
        }
    }
}

/// The result of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MicroFitResponse {
    /// Best values, one per request parameter (integers rounded).
    pub values: Vec<f64>,
    /// The scene with those values, as JSON text.
    pub scene: String,
    pub loss: f64,
    /// Loss of the scene as given (the start).
    pub initial_loss: f64,
    /// Best loss after each batch, and the evaluations done by then.
    pub history: Vec<f64>,
    pub history_evaluations: Vec<u64>,
    pub evaluations: u64,
    /// With a target scene: the MSE of the fitted field against it on a
    /// grid shifted by half a cell, over the target's variance there
    /// (0: identical; about 1 or more: no better than a constant).
    pub validation: Option<f64>,
}

struct Param {
    /// The pointer and those tied to it.
    pointers: Vec<String>,
    lo: f64,
    hi: f64,
    integer: bool,
}

/// What an evaluation samples.
#[derive(Clone)]
enum Sampler {
    /// The field at `points`; clamped to ±R when `clamp` is set. `axes`:
    /// the lattice's coordinates along x, y and z when `points` is that
    /// lattice (x fastest), for [`sample_grid`].
    Volume {
        points: Vec<DVec3>,
        clamp: Option<f64>,
        axes: Option<Box<[Vec<f64>; 3]>>,
    },
    /// A grey rendering of `width × height` with these settings.
    Image(MicroRenderRequest),
}

/// One sampling in progress.
enum Work {
    Volume {
        scene: Box<Scene>,
        values: Vec<f64>,
        points: usize,
        clamp: Option<f64>,
    },
    Render(Box<RenderJob>),
}

/// Scene evaluations (or their equivalent) per job step.
const WORK_PER_STEP: usize = 60_000;

/// The value a sample stores: clamped to `±clamp` when set, and finite.
#[inline(always)]
fn stored(v: f64, clamp: Option<f64>) -> f64 {
    let v = match clamp {
        Some(r) => v.clamp(-r, r),
        None => v,
    };
    if v.is_finite() {
        v
    } else {
        MAX_VALUE
    }
}

/// Sample `scene` on the lattice `axes` (x fastest) into `out` at once when
/// its root is a periodic function (Eq. 11): each factor depends on one
/// coordinate, so its values along its axis are computed once (n sines, not
/// n³) and every point multiplies them in the order [`Periodic::raw`]
/// does, which gives the values of [`Scene::eval`] bit for bit. `false`
/// (and `out` untouched) for any other scene.
fn sample_grid(
    scene: &Scene,
    axes: &[Vec<f64>; 3],
    clamp: Option<f64>,
    out: &mut Vec<f64>,
) -> bool {
    let Op::Periodic(t) = &scene.root else {
        return false;
    };
    let [nx, ny, nz] = [axes[0].len(), axes[1].len(), axes[2].len()];
    // Per term, per factor: its axis and its values along that axis.
    let tables: Vec<Vec<(usize, Vec<f64>)>> = t
        .terms
        .iter()
        .map(|term| {
            term.iter()
                .map(|f| {
                    let a = f.axis as usize;
                    let vals = axes[a]
                        .iter()
                        .map(|&c| {
                            let x = f.freq * c + f.phase;
                            let w = match f.wave {
                                Wave::Sin => libm::sin(x),
                                Wave::Cos => libm::cos(x),
                            };
                            let mut r = 1.0;
                            for _ in 0..f.power {
                                r *= f.amp * w;
                            }
                            r
                        })
                        .collect();
                    (a, vals)
                })
                .collect()
        })
        .collect();
    // Per row (y, z), per term: the factors before the first one along x
    // are one number for the row (`c`), the rest multiply a row of x
    // values, each in the term's order (so the products round as in
    // `raw`). The common shapes (nothing after the first x factor, or one
    // more factor) are one fused kernel over a plane's rows; others are
    // multiplied out in `prods` first.
    let plans: Vec<(usize, usize)> = tables
        .iter()
        .map(|term| {
            let lead = term.iter().position(|(a, _)| *a == 0);
            (lead.unwrap_or(term.len()), term.len())
        })
        .collect();
    // Plane by plane (one stays in the L1 cache throughout): every value
    // starts as the constant, the plane adds its terms in place (one
    // kernel per term over all its rows: rows of 32 spent more on their
    // loops' set-up than on their values), then the sheet and the finish,
    // by elementwise arithmetic and selects (no branches: the compiler
    // vectorises them).
    out.clear();
    out.reserve(nx * ny * nz);
    let (thick, inv) = (t.thickness, t.inv_bound);
    // `stored` with the clamp hoisted. Without one, NaN and ±∞ all become
    // `MAX_VALUE`, as the clamped path's NaN → +∞ → unclamped does.
    let finish = |row: &mut [f64]| match clamp {
        None => row.iter_mut().for_each(|v| {
            let s = *v * inv;
            *v = if s.is_finite() { s } else { MAX_VALUE };
        }),
        Some(lim) => row.iter_mut().for_each(|v| {
            let s = *v * inv;
            let s = if s.is_nan() { f64::INFINITY } else { s };
            let s = if s < -lim {
                -lim
            } else if s > lim {
                lim
            } else {
                s
            };
            *v = if s.is_finite() { s } else { MAX_VALUE };
        }),
    };
    // Per plane z, per term: its per-row numbers (`c`, the factors before
    // the first along x; `w`, one more factor along y or z) for every y,
    // then one kernel over the plane.
    let (mut c, mut w) = (vec![0.0; ny], vec![0.0; ny]);
    let mut prods = vec![0.0; nx * ny];
    for z in 0..nz {
        let start = out.len();
        out.resize(start + nx * ny, t.constant);
        let plane = &mut out[start..];
        for (term, &(lead, len)) in tables.iter().zip(&plans) {
            let at = |a: usize, vals: &[f64], y: usize| if a == 1 { vals[y] } else { vals[z] };
            for (y, c) in c.iter_mut().enumerate() {
                *c = 1.0;
                for (a, vals) in &term[..lead] {
                    *c *= at(*a, vals, y);
                }
            }
            if lead == len {
                add_rows(plane, &c);
                continue;
            }
            let vx = &term[lead].1[..nx];
            match &term[lead + 1..] {
                [] => add_rows_x(plane, &c, vx),
                [(0, v2)] => add_rows_xx(plane, &c, vx, v2),
                [(a, v2)] => {
                    for (y, w) in w.iter_mut().enumerate() {
                        *w = at(*a, v2, y);
                    }
                    add_rows_xw(plane, &c, vx, &w);
                }
                rest => {
                    for (y, row) in prods.chunks_exact_mut(nx).enumerate() {
                        row.iter_mut().zip(vx).for_each(|(p, v)| *p = c[y] * v);
                        for (a, vals) in rest {
                            if *a == 0 {
                                row.iter_mut().zip(vals).for_each(|(p, v)| *p *= v);
                            } else {
                                let v = at(*a, vals, y);
                                row.iter_mut().for_each(|p| *p *= v);
                            }
                        }
                    }
                    plane.iter_mut().zip(&prods).for_each(|(s, p)| *s += p);
                }
            }
        }
        if thick > 0.0 {
            plane.iter_mut().for_each(|v| *v = v.abs() - thick);
        }
        finish(plane);
    }
    true
}

/// `plane[y·nx + x] += c[y]` (nx = plane.len() / c.len()). These kernels
/// take the plane and the tables as separate slices, which the compiler
/// knows do not overlap: each row is one vectorised loop without checks.
#[inline(never)]
fn add_rows(plane: &mut [f64], c: &[f64]) {
    let nx = plane.len() / c.len();
    for (row, &c) in plane.chunks_exact_mut(nx).zip(c) {
        row.iter_mut().for_each(|s| *s += c);
    }
}

/// `plane[y·nx + x] += c[y]·vx[x]`.
#[inline(never)]
fn add_rows_x(plane: &mut [f64], c: &[f64], vx: &[f64]) {
    let nx = vx.len();
    for (row, &c) in plane.chunks_exact_mut(nx).zip(c) {
        row.iter_mut().zip(vx).for_each(|(s, v)| *s += c * v);
    }
}

/// `plane[y·nx + x] += c[y]·vx[x]·w[y]`.
#[inline(never)]
fn add_rows_xw(plane: &mut [f64], c: &[f64], vx: &[f64], w: &[f64]) {
    let nx = vx.len();
    for ((row, &c), &w) in plane.chunks_exact_mut(nx).zip(c).zip(w) {
        row.iter_mut().zip(vx).for_each(|(s, v)| *s += c * v * w);
    }
}

/// `plane[y·nx + x] += c[y]·vx[x]·v2[x]`.
#[inline(never)]
fn add_rows_xx(plane: &mut [f64], c: &[f64], vx: &[f64], v2: &[f64]) {
    let nx = vx.len();
    let v2 = &v2[..nx];
    for (row, &c) in plane.chunks_exact_mut(nx).zip(c) {
        row.iter_mut()
            .zip(vx)
            .zip(v2)
            .for_each(|((s, v), w)| *s += c * v * w);
    }
}

impl Work {
    /// Start sampling `scene`; `text` renders it (image samplers only);
    /// `buffer` is reused for the samples.
    fn new(
        sampler: &Sampler,
        scene: Scene,
        text: impl FnOnce() -> String,
        buffer: Vec<f64>,
    ) -> Result<Work> {
        Ok(match sampler {
            Sampler::Volume { points, clamp, .. } => {
                let mut values = buffer;
                values.clear();
                values.reserve(points.len());
                Work::Volume {
                    scene: Box::new(scene),
                    values,
                    points: points.len(),
                    clamp: *clamp,
                }
            }
            Sampler::Image(r) => Work::Render(Box::new(start_render(MicroRenderRequest {
                scene: text(),
                ..r.clone()
            })?)),
        })
    }

    /// Advance by about `budget` evaluations; the samples when finished.
    fn advance(&mut self, sampler: &Sampler, budget: usize) -> Result<(usize, Option<Vec<f64>>)> {
        match self {
            Work::Volume {
                scene,
                values,
                points,
                clamp,
            } => {
                let Sampler::Volume {
                    points: pts, axes, ..
                } = sampler
                else {
                    return Err(Error::input("micro-fit: sampler mismatch"));
                };
                let from = values.len();
                let separable = from == 0
                    && axes
                        .as_deref()
                        .is_some_and(|a| sample_grid(scene, a, *clamp, values));
                let stop = if separable {
                    *points
                } else {
                    let stop = (from + budget).min(*points);
                    for p in &pts[from..stop] {
                        values.push(stored(scene.eval(*p), *clamp));
                    }
                    stop
                };
                let done = stop - from;
                Ok(if values.len() == *points {
                    (done, Some(std::mem::take(values)))
                } else {
                    (done, None)
                })
            }
            Work::Render(job) => match job.step()? {
                Step::Running(_) => Ok((budget, None)),
                Step::Done(out) => {
                    let img = decode_png(
                        &out.png,
                        Limits {
                            max_side: MAX_FIT_IMAGE_SIDE,
                            max_pixels: (MAX_FIT_IMAGE_SIDE * MAX_FIT_IMAGE_SIDE) as u64,
                        },
                    )?;
                    Ok((budget, Some(grey(&img.data))))
                }
            },
        }
    }
}

/// Mean of RGB in `[0, 1]` per pixel.
fn grey(rgba: &[u8]) -> Vec<f64> {
    rgba.chunks_exact(4)
        .map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / (3.0 * 255.0))
        .collect()
}

/// The target's spectrum, as the loss compares it.
enum TargetSpectrum {
    Full(Spectrum),
    Amplitudes(Vec<f64>),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    /// Sampling the target.
    Target,
    /// Evaluating the start point.
    Start,
    Optimise,
    /// Sampling target and fit on the validation grid.
    Validate,
    Finished,
}

#[derive(Debug, Clone, PartialEq)]
enum Exchange {
    None,
    Ready(Vec<f64>),
    Waiting,
}

/// A running fit.
pub struct MicroFitJob {
    base: Value,
    params: Vec<Param>,
    sampler: Sampler,
    fourier: Fourier,
    target_scene: Option<(Scene, String)>,
    target: Option<TargetSpectrum>,
    opt: Box<dyn AskTell + Send>,
    /// How to make the next stage's optimiser; the stages left (first:
    /// the current one) and the coarse target once known.
    make: MakeOpt,
    stages: Vec<(Compare, f64, Option<f64>)>,
    profiles: Option<Profiles>,
    rng: Rng,
    phase: Phase,
    work: Option<Work>,
    /// The last samples' buffer, reused by the next sampling.
    spare: Vec<f64>,
    batch: Vec<Vec<f64>>,
    /// Per batch point: the loss its stage compares (told to the
    /// optimiser) and the paper's loss (which picks the best).
    losses: Vec<f64>,
    exact: Vec<f64>,
    next: usize,
    shards: (usize, usize),
    exchange: Exchange,
    budget: u64,
    evaluations: u64,
    best: Scored,
    initial_loss: f64,
    history: Vec<f64>,
    history_evaluations: Vec<u64>,
    /// Validation: the points and the target's samples once taken.
    validation_points: Vec<DVec3>,
    validation_target: Option<Vec<f64>>,
    validation: Option<f64>,
}

fn is_pow2(v: u32) -> bool {
    v.is_power_of_two()
}

/// Cell centres of an `nx × ny × nz` lattice over `center ± half` (x fastest),
/// shifted by `shift` cells.
fn lattice(dims: [usize; 3], center: [f64; 3], half: f64, shift: f64) -> Vec<DVec3> {
    lattice_and_axes(dims, center, half, shift).0
}

/// [`lattice`] and its coordinates along each axis (the same numbers).
fn lattice_and_axes(
    dims: [usize; 3],
    center: [f64; 3],
    half: f64,
    shift: f64,
) -> (Vec<DVec3>, Box<[Vec<f64>; 3]>) {
    let c = DVec3::from_array(center);
    let mut out = Vec::with_capacity(dims.iter().product());
    let coord = |i: usize, n: usize| -half + (i as f64 + 0.5 + shift) * 2.0 * half / n as f64;
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                out.push(c + DVec3::new(coord(x, dims[0]), coord(y, dims[1]), coord(z, dims[2])));
            }
        }
    }
    let axes = [0, 1, 2].map(|a| {
        (0..dims[a])
            .map(|i| center[a] + coord(i, dims[a]))
            .collect()
    });
    (out, Box::new(axes))
}

/// The fitting sampler of a lattice.
fn volume_sampler(dims: [usize; 3], req: &MicroFitRequest, clamp: Option<f64>) -> Sampler {
    let (points, axes) = lattice_and_axes(dims, req.center, req.half, 0.0);
    Sampler::Volume {
        points,
        clamp,
        axes: Some(axes),
    }
}

fn decode_grey(bytes: &[u8], field: &str) -> Result<(u32, u32, Vec<f64>)> {
    let img = decode_sent(
        bytes,
        Limits {
            max_side: MAX_FIT_IMAGE_SIDE,
            max_pixels: (MAX_FIT_IMAGE_SIDE * MAX_FIT_IMAGE_SIDE) as u64,
        },
    )
    .map_err(|e| Error::input(format!("`{field}`: {}", e.inner())).at(field))?;
    Ok((img.width, img.height, grey(&img.data)))
}

/// Check a request and set the fit up (the target is sampled in the steps).
pub fn start_fit(req: MicroFitRequest) -> Result<MicroFitJob> {
    lim::int_in("grid", req.grid, (2, MAX_FIT_GRID))?;
    if !is_pow2(req.grid) {
        return Err(Error::input(format!(
            "`grid` must be a power of two (2, 4, 8, 16, 32 or 64; got {})",
            req.grid
        ))
        .at("grid"));
    }
    for (i, v) in req.center.iter().enumerate() {
        lim::finite_in(&format!("center.{i}"), *v, (-1e6, 1e6))?;
    }
    lim::finite_in("half", req.half, (1e-9, 1e6))?;
    lim::int_in("budget", req.budget, (1, MAX_FIT_BUDGET))?;
    lim::int_in("population", req.population, (0, MAX_FIT_POPULATION))?;
    if req.population == 1 {
        return Err(
            Error::input("`population` must be 0 (automatic) or at least 2").at("population"),
        );
    }
    lim::finite_in("sigma", req.sigma, (1e-6, 1.0))?;
    let shards = match req.shards {
        None => (0, 1),
        Some((k, n)) => {
            if n == 0 || n > 64 || k >= n {
                return Err(Error::input(format!(
                    "`shards` [{k}, {n}]: need 1..=64 shards and an index below their count"
                ))
                .at("shards"));
            }
            (k, n)
        }
    };
    if req.params.is_empty() {
        return Err(Error::input(
            "`params` is empty: name at least one number of the scene to fit, e.g. \
             {\"pointer\": \"/period\", \"lo\": 0.1, \"hi\": 1}",
        )
        .at("params"));
    }
    if req.params.len() > MAX_FIT_PARAMS {
        return Err(Error::limit(format!(
            "{} parameters; at most {MAX_FIT_PARAMS} can be fitted at once",
            req.params.len()
        ))
        .at("params"));
    }
    // The scene: checked as a scene, then read as plain JSON to edit.
    scene::parse(&req.scene)?;
    let base: Value = serde_json::from_str(&req.scene)
        .map_err(|e| Error::input(format!("the scene is not JSON: {e}")).at("scene"))?;
    let mut params = Vec::with_capacity(req.params.len());
    let mut start = Vec::with_capacity(req.params.len());
    for (i, p) in req.params.iter().enumerate() {
        let field = format!("params.{i}");
        lim::finite_in(&format!("{field}.lo"), p.lo, (-MAX_VALUE, MAX_VALUE))?;
        lim::finite_in(&format!("{field}.hi"), p.hi, (-MAX_VALUE, MAX_VALUE))?;
        if p.lo >= p.hi {
            return Err(Error::input(format!(
                "`{field}`: the range {}..{} is empty (lo must be below hi)",
                p.lo, p.hi
            ))
            .at(format!("{field}.lo")));
        }
        if p.also.len() > MAX_FIT_PARAMS {
            return Err(Error::limit(format!(
                "`{field}.also` ties {} pointers; at most {MAX_FIT_PARAMS} can be",
                p.also.len()
            ))
            .at(format!("{field}.also")));
        }
        let mut x = 0.0;
        let mut integer = false;
        let mut pointers = vec![];
        let all = std::iter::once((format!("{field}.pointer"), &p.pointer)).chain(
            p.also
                .iter()
                .enumerate()
                .map(|(j, q)| (format!("{field}.also.{j}"), q)),
        );
        for (j, (f, ptr)) in all.enumerate() {
            let Some(v) = base.pointer(ptr) else {
                return Err(Error::input(format!(
                    "`{f}`: '{ptr}' names nothing in the scene (a JSON pointer such as \
                     /children/0/period)"
                ))
                .at(f));
            };
            let Some(xv) = v.as_f64() else {
                return Err(Error::input(format!(
                    "`{f}`: '{ptr}' is not a number in the scene (it is {})",
                    kind_of(v)
                ))
                .at(f));
            };
            let seen = req.params[..i]
                .iter()
                .flat_map(|q| std::iter::once(&q.pointer).chain(&q.also))
                .chain(&pointers)
                .any(|q| q == ptr);
            if seen {
                return Err(Error::input(format!("`{f}`: '{ptr}' is listed twice")).at(f));
            }
            if j == 0 {
                x = xv;
                integer = v.is_i64() || v.is_u64();
            }
            pointers.push(ptr.clone());
        }
        params.push(Param {
            pointers,
            lo: p.lo,
            hi: p.hi,
            integer,
        });
        start.push(((x - p.lo) / (p.hi - p.lo)).clamp(0.0, 1.0));
    }
    let n = req.grid as usize;
    let mut target_scene = None;
    let (sampler, fourier, target) = match &req.target {
        FitTarget::Scene { scene: text } => {
            let s = scene::parse(text).map_err(|e| retarget(e, "target.scene"))?;
            target_scene = Some((s, text.clone()));
            let dims = [n, n, n];
            (volume_sampler(dims, &req, None), Fourier::new(dims)?, None)
        }
        FitTarget::Volume { values } => {
            if values.len() != n * n * n {
                return Err(Error::input(format!(
                    "`target.values`: a {n}³ grid needs {} values (got {})",
                    n * n * n,
                    values.len()
                ))
                .at("target.values"));
            }
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(
                    Error::input(format!("`target.values.{i}` is not a finite number"))
                        .at(format!("target.values.{i}")),
                );
            }
            let dims = [n, n, n];
            let mut f = Fourier::new(dims)?;
            let t = TargetSpectrum::Full(f.half_spectrum(values)?);
            (volume_sampler(dims, &req, None), f, Some(t))
        }
        FitTarget::Slices { pngs, range } => {
            lim::finite_in("target.range", *range, (1e-12, 1e6))?;
            let c = pngs.len();
            if c == 0 || !c.is_power_of_two() || c > n {
                return Err(Error::input(format!(
                    "`target.pngs`: {c} slices; give a power of two of them, at most `grid` ({n})"
                ))
                .at("target.pngs"));
            }
            let mut values = Vec::with_capacity(n * n * c);
            for (i, png) in pngs.iter().enumerate() {
                let field = format!("target.pngs.{i}");
                let (w, h, g) = decode_grey(png, &field)?;
                if (w, h) != (n as u32, n as u32) {
                    return Err(Error::input(format!(
                        "`{field}` is {w}×{h}; each slice must be grid × grid ({n}×{n})"
                    ))
                    .at(field));
                }
                // Image rows go down; the lattice's y goes up.
                for y in (0..n).rev() {
                    values.extend(
                        g[y * n..(y + 1) * n]
                            .iter()
                            .map(|v| (2.0 * v - 1.0) * range),
                    );
                }
            }
            let dims = [n, n, c];
            let mut f = Fourier::new(dims)?;
            let t = TargetSpectrum::Full(f.half_spectrum(&values)?);
            (volume_sampler(dims, &req, Some(*range)), f, Some(t))
        }
        FitTarget::Image { png, scene: text } => {
            let mut render = req.render.clone();
            let target = match (png, text) {
                (Some(png), None) => {
                    let (w, h, g) = decode_grey(png, "target.png")?;
                    render.width = w;
                    render.height = h;
                    Some(g)
                }
                (None, Some(text)) => {
                    let s = scene::parse(text).map_err(|e| retarget(e, "target.scene"))?;
                    target_scene = Some((s, text.clone()));
                    None
                }
                _ => {
                    return Err(Error::input(
                        "an image target needs exactly one of `png` (a picture) and `scene` \
                         (a scene to render as the picture)",
                    )
                    .at("target"))
                }
            };
            for (name, v) in [("width", render.width), ("height", render.height)] {
                if !is_pow2(v) || !(2..=MAX_FIT_IMAGE_SIDE).contains(&v) {
                    let field = if target.is_some() {
                        "target.png".to_string()
                    } else {
                        format!("render.{name}")
                    };
                    return Err(Error::input(format!(
                        "the image {name} is {v}; analysis by synthesis needs a power of two \
                         from 2 to {MAX_FIT_IMAGE_SIDE}"
                    ))
                    .at(field));
                }
            }
            // Check the render settings once, now.
            start_render(MicroRenderRequest {
                scene: r#"{"type": "sphere", "radius": 1}"#.into(),
                ..render.clone()
            })
            .map_err(|e| match e.field() {
                Some(f) => {
                    let f = format!("render.{f}");
                    e.at(f)
                }
                None => e,
            })?;
            let dims = [render.width as usize, render.height as usize, 1];
            let mut f = Fourier::new(dims)?;
            let t = match target {
                Some(g) => Some(TargetSpectrum::Amplitudes(f.amplitudes(&g)?)),
                None => None,
            };
            (Sampler::Image(render), f, t)
        }
    };
    let dim = params.len();
    let inner = (req.budget as usize).saturating_sub(1);
    if req.coarse_to_fine && matches!(req.target, FitTarget::Image { .. }) {
        return Err(Error::input(
            "`coarse_to_fine` compares volume spectra; an image target (analysis by \
             synthesis) has no such stages: turn it off",
        )
        .at("coarse_to_fine"));
    }
    let make = MakeOpt {
        optimizer: req.optimizer,
        population: if req.population >= 2 {
            req.population as usize
        } else {
            4 + (3.0 * libm::log(dim as f64)).floor() as usize
        },
        sigma: req.sigma,
        inner,
    };
    if make.optimizer == Optimizer::Cmaes && inner > 0 && inner < make.population {
        // Fewer evaluations than one generation: CMA-ES would never update
        // and the fit would return its start unchanged. (A budget of 1
        // asks for the start's loss alone, and gets it.)
        return Err(Error::input(format!(
            "`budget` {} is less than one CMA-ES generation: it needs at least {} \
             evaluations (the start and a population of {}), or 1 for the start's \
             loss alone; give a bigger budget or a smaller `population`",
            req.budget,
            make.population + 1,
            make.population
        ))
        .at("budget"));
    }
    let stages = if req.coarse_to_fine {
        COARSE_TO_FINE.to_vec()
    } else {
        vec![(Compare::Exact, 1.0, None)]
    };
    let opt = make.make(&start, 0, stages[0]);
    let validation_points = if target_scene.is_some() {
        lattice([n, n, n], req.center, req.half, 0.5)
    } else {
        vec![]
    };
    let has_target = target.is_some();
    Ok(MicroFitJob {
        base,
        params,
        sampler,
        fourier,
        target_scene,
        target,
        opt,
        make,
        stages,
        profiles: None,
        rng: Rng::new(req.seed),
        phase: if has_target {
            Phase::Start
        } else {
            Phase::Target
        },
        work: None,
        spare: vec![],
        batch: vec![start.clone()],
        losses: vec![f64::NAN],
        exact: vec![f64::NAN],
        next: 0,
        shards,
        exchange: Exchange::None,
        budget: req.budget as u64,
        evaluations: 0,
        best: Scored {
            u: start,
            loss: f64::INFINITY,
        },
        initial_loss: f64::INFINITY,
        history: vec![],
        history_evaluations: vec![],
        validation_points,
        validation_target: None,
        validation: None,
    })
}

/// How a fit makes its optimiser for each stage.
struct MakeOpt {
    optimizer: Optimizer,
    population: usize,
    sigma: f64,
    /// Evaluations after the start point.
    inner: usize,
}

impl MakeOpt {
    /// The optimiser of a stage `(compare, end, sigma)` from `start` that
    /// ends when `end` of the budget is spent (`used` of it already is),
    /// with CMA-ES's initial step `sigma` (`None`: the request's, with
    /// restarts). Powell on the coarse profiles stops its line searches at
    /// [`COARSE_LINE_TOLERANCE`].
    fn make(
        &self,
        start: &[f64],
        used: usize,
        (compare, end, sigma): (Compare, f64, Option<f64>),
    ) -> Box<dyn AskTell + Send> {
        let evals = ((self.inner as f64 * end).round() as usize)
            .min(self.inner)
            .saturating_sub(used);
        match self.optimizer {
            Optimizer::Cmaes => Box::new(Cmaes::new(
                start,
                CmaesOptions {
                    population: self.population,
                    sigma: sigma.unwrap_or(self.sigma),
                    generations: evals / self.population,
                    tolerance: 1e-10,
                    restarts: sigma.is_none(),
                },
            )),
            Optimizer::NelderMead => Box::new(NelderMead::starting_at(start, evals)),
            Optimizer::Powell => {
                let p = Powell::new(start, evals);
                Box::new(if compare == Compare::Profiles {
                    p.with_line_tolerance(COARSE_LINE_TOLERANCE)
                } else {
                    p
                })
            }
        }
    }
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "true or false",
        Value::Number(_) => "a number",
        Value::String(_) => "text",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// A scene error about the target scene, naming its field.
fn retarget(e: Error, field: &str) -> Error {
    let inner = e.inner().clone();
    let msg = match &inner {
        Error::Syntax { message, .. } => format!("target: {message}"),
        other => format!("target: {other}"),
    };
    match inner {
        Error::Syntax { line, column, .. } => Error::Syntax {
            line,
            column,
            message: msg,
        }
        .at(field),
        Error::Limit(..) => Error::limit(msg).at(field),
        _ => Error::input(msg).at(field),
    }
}

impl MicroFitJob {
    /// Raw values of a normalised point (integers rounded).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        self.params
            .iter()
            .zip(u)
            .map(|(p, &u)| {
                let v = p.lo + u.clamp(0.0, 1.0) * (p.hi - p.lo);
                if p.integer {
                    v.round()
                } else {
                    v
                }
            })
            .collect()
    }

    /// The scene JSON with the values of `u` written in.
    fn scene_value(&self, u: &[f64]) -> Value {
        let mut v = self.base.clone();
        for (p, x) in self.params.iter().zip(self.values(u)) {
            let new = if p.integer {
                Value::from(x as i64)
            } else {
                serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
            };
            for ptr in &p.pointers {
                if let Some(slot) = v.pointer_mut(ptr) {
                    *slot = new.clone();
                }
            }
        }
        v
    }

    /// The compiled scene at `u`, or `None` where the values are invalid.
    fn scene_at(&self, u: &[f64]) -> Option<(Scene, Value)> {
        let v = self.scene_value(u);
        let node = Node::deserialize(&v).ok()?;
        let s = scene::compile(node).ok()?;
        Some((s, v))
    }

    /// The paper's loss of fitting samples.
    fn loss_of(&mut self, values: &[f64]) -> Result<f64> {
        Ok(self.losses_of(values)?.1)
    }

    /// The loss the current stage compares and the paper's loss of
    /// fitting samples (the same number outside coarse-to-fine stages).
    fn losses_of(&mut self, values: &[f64]) -> Result<(f64, f64)> {
        let finite = |l: f64| if l.is_nan() { f64::INFINITY } else { l };
        let compare = self.stages.first().map_or(Compare::Exact, |s| s.0);
        Ok(match &self.target {
            Some(TargetSpectrum::Full(t)) => {
                let exact = finite(self.fourier.half_loss(values, t)?);
                let stage = match compare {
                    Compare::Exact => exact,
                    Compare::Amplitudes => finite(self.fourier.last_amplitude_loss(t)),
                    Compare::Profiles => {
                        if self.profiles.is_none() {
                            let dims = self.fourier.dims();
                            self.profiles = Some(Profiles::new(t, dims, COARSE_SIGMA_BINS));
                        }
                        let m = self.profiles.as_ref().expect("profiles");
                        finite(self.fourier.last_profile_loss(m))
                    }
                };
                (stage, exact)
            }
            Some(TargetSpectrum::Amplitudes(t)) => {
                let a = self.fourier.amplitudes(values)?;
                let l = finite(amplitude_loss(&a, t));
                (l, l)
            }
            None => return Err(Error::input("micro-fit: no target yet")),
        })
    }

    /// The scene at the normalised point `u` (`None` where its values are
    /// invalid). With [`MicroFitJob::sample`] and
    /// [`MicroFitJob::loss_of_samples`] these are the three parts of one
    /// evaluation, public so `bench micro --only loss` can time each.
    pub fn scene_for(&self, u: &[f64]) -> Option<Scene> {
        self.scene_at(u).map(|(s, _)| s)
    }

    /// The fitting samples of `scene` (volume targets): on the lattice at
    /// once where the scene allows ([`sample_grid`]), else point by point;
    /// `pointwise` forces the latter (same values, bit for bit).
    pub fn sample(&self, scene: &Scene, pointwise: bool) -> Result<Vec<f64>> {
        let Sampler::Volume {
            points,
            clamp,
            axes,
        } = &self.sampler
        else {
            return Err(Error::input(
                "micro-fit: only volume targets are sampled on a lattice",
            ));
        };
        let mut out = Vec::with_capacity(points.len());
        let done = !pointwise
            && axes
                .as_deref()
                .is_some_and(|a| sample_grid(scene, a, *clamp, &mut out));
        if !done {
            out.extend(points.iter().map(|p| stored(scene.eval(*p), *clamp)));
        }
        Ok(out)
    }

    /// One loss evaluation at the normalised point `u` the way the job's
    /// steps do it (the scene, its samples into the reused buffer, FFT and
    /// loss); infinite where the values are invalid. For `bench micro`.
    pub fn evaluate(&mut self, u: &[f64]) -> Result<f64> {
        let Some((s, v)) = self.scene_at(u) else {
            return Ok(f64::INFINITY);
        };
        let spare = std::mem::take(&mut self.spare);
        let mut work = Work::new(&self.sampler, s, || v.to_string(), spare)?;
        loop {
            if let (_, Some(values)) = work.advance(&self.sampler, WORK_PER_STEP)? {
                let l = self.loss_of(&values)?;
                self.spare = values;
                return Ok(l);
            }
        }
    }

    /// The loss of fitting samples against the target (once it is sampled:
    /// after the job's first step for a scene target).
    pub fn loss_of_samples(&mut self, values: &[f64]) -> Result<f64> {
        self.loss_of(values)
    }

    /// This shard's points' losses to exchange: the stage's and the
    /// paper's loss of each, in turn.
    fn own_losses(&self) -> Vec<f64> {
        let (k, n) = self.shards;
        let pairs = self.losses.iter().zip(&self.exact).skip(k).step_by(n);
        pairs.flat_map(|(&l, &e)| [l, e]).collect()
    }

    fn progress(&self, stage: &str) -> Progress {
        let f = self.evaluations as f64 / self.budget.max(1) as f64;
        let p = Progress::new(0.02 + 0.96 * f, stage);
        if self.best.loss.is_finite() {
            p.with_figure(self.best.loss)
                .with_values(self.values(&self.best.u))
        } else {
            p
        }
    }

    /// Advance the sampling of the current batch point; `Some(loss)` when
    /// it is evaluated. Returns the work done too.
    fn eval_point(&mut self, budget: usize) -> Result<(usize, Option<(f64, f64)>)> {
        const INVALID: (f64, f64) = (f64::INFINITY, f64::INFINITY);
        if self.work.is_none() {
            let u = self.batch[self.next].clone();
            match self.scene_at(&u) {
                None => return Ok((1, Some(INVALID))),
                Some((s, v)) => match Work::new(
                    &self.sampler,
                    s,
                    || v.to_string(),
                    std::mem::take(&mut self.spare),
                ) {
                    Ok(w) => self.work = Some(w),
                    Err(_) => return Ok((1, Some(INVALID))),
                },
            }
        }
        let work = self.work.as_mut().expect("work");
        let (done, values) = match work.advance(&self.sampler, budget) {
            Ok(r) => r,
            Err(_) => {
                self.work = None;
                return Ok((budget, Some(INVALID)));
            }
        };
        match values {
            None => Ok((done, None)),
            Some(v) => {
                self.work = None;
                let n = v.len();
                let losses = self.losses_of(&v)?;
                self.spare = v;
                Ok((done + n, Some(losses)))
            }
        }
    }

    /// All points of the batch are known: tell the optimiser (or the start).
    fn tell_batch(&mut self) {
        let batch = std::mem::take(&mut self.batch);
        let finite = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .map(|&l| if l.is_nan() { f64::INFINITY } else { l })
                .collect()
        };
        let (losses, exact) = (finite(&self.losses), finite(&self.exact));
        self.evaluations += batch.len() as u64;
        for (u, &l) in batch.iter().zip(&exact) {
            if l < self.best.loss {
                self.best = Scored {
                    u: u.clone(),
                    loss: l,
                };
            }
        }
        if self.phase == Phase::Start {
            self.initial_loss = exact[0];
            self.phase = Phase::Optimise;
        } else {
            self.opt.tell(batch, &losses);
        }
        self.history.push(self.best.loss);
        self.history_evaluations.push(self.evaluations);
        self.losses.clear();
        self.exact.clear();
    }

    /// The finished fit.
    fn output(&self) -> MicroFitResponse {
        let v = self.scene_value(&self.best.u);
        MicroFitResponse {
            values: self.values(&self.best.u),
            scene: serde_json::to_string_pretty(&v).unwrap_or_else(|_| v.to_string()),
            loss: self.best.loss,
            initial_loss: self.initial_loss,
            history: self.history.clone(),
            history_evaluations: self.history_evaluations.clone(),
            evaluations: self.evaluations,
            validation: self.validation,
        }
    }

    /// Sample the target scene (preparation, or validation points).
    fn sample_target(&mut self, budget: usize) -> Result<Option<Vec<f64>>> {
        if self.work.is_none() {
            let Some((s, text)) = &self.target_scene else {
                return Err(Error::input("micro-fit: no target scene"));
            };
            let sampler = self.active_sampler();
            self.work = Some(Work::new(&sampler, s.clone(), || text.clone(), vec![])?);
        }
        let sampler = self.active_sampler();
        let work = self.work.as_mut().expect("work");
        let (_, v) = work.advance(&sampler, budget)?;
        if v.is_some() {
            self.work = None;
        }
        Ok(v)
    }

    /// Validation samples on the shifted grid; fitting samples otherwise.
    fn active_sampler(&self) -> Sampler {
        if self.phase == Phase::Validate {
            Sampler::Volume {
                points: self.validation_points.clone(),
                clamp: None,
                axes: None,
            }
        } else {
            self.sampler.clone()
        }
    }
}

impl Job for MicroFitJob {
    type Output = MicroFitResponse;

    fn outbox(&mut self) -> Option<Vec<f64>> {
        match std::mem::replace(&mut self.exchange, Exchange::None) {
            Exchange::Ready(part) => {
                self.exchange = Exchange::Waiting;
                Some(part)
            }
            other => {
                self.exchange = other;
                None
            }
        }
    }

    fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
        let (k, n) = self.shards;
        if self.exchange != Exchange::Waiting {
            return Err(Error::input(
                "unexpected exchange: this fit is not waiting for its sibling shards",
            ));
        }
        if parts.len() != n {
            return Err(Error::input(format!(
                "exchange: {} parts for {n} shards",
                parts.len()
            )));
        }
        let len = self.batch.len();
        for (j, part) in parts.iter().enumerate() {
            let want = 2 * ((len + n - 1 - j) / n);
            if part.len() != want {
                return Err(Error::input(format!(
                    "loss exchange: shard {j} sent {} losses for its {} points (two each)",
                    part.len(),
                    want / 2
                )));
            }
        }
        let own = self.own_losses();
        if own
            .iter()
            .zip(&parts[k])
            .any(|(a, b)| a.to_bits() != b.to_bits())
        {
            return Err(Error::input(
                "loss exchange: the shards disagree on the batch",
            ));
        }
        for i in 0..len {
            self.losses[i] = parts[i % n][2 * (i / n)];
            self.exact[i] = parts[i % n][2 * (i / n) + 1];
        }
        self.exchange = Exchange::None;
        self.tell_batch();
        Ok(())
    }

    fn step(&mut self) -> Result<Step<MicroFitResponse>> {
        if self.exchange != Exchange::None {
            return Err(Error::input(
                "this fit waits for its sibling shards' losses; drive it with \
                 core::parallel::run_sharded",
            ));
        }
        let mut work = 0usize;
        while work < WORK_PER_STEP {
            match self.phase {
                Phase::Target => {
                    if let Some(v) = self.sample_target(WORK_PER_STEP)? {
                        self.target = Some(match &self.sampler {
                            Sampler::Volume { .. } => {
                                TargetSpectrum::Full(self.fourier.half_spectrum(&v)?)
                            }
                            Sampler::Image(_) => {
                                TargetSpectrum::Amplitudes(self.fourier.amplitudes(&v)?)
                            }
                        });
                        self.phase = Phase::Start;
                    }
                    return Ok(Step::Running(Progress::new(0.01, "sampling the target")));
                }
                Phase::Start | Phase::Optimise => {
                    if self.batch.is_empty() {
                        let b = self.opt.ask(&mut self.rng);
                        if b.is_empty() && self.stages.len() > 1 {
                            // The next stage, from this one's best point.
                            self.stages.remove(0);
                            let from = self.opt.best().map_or(&self.best.u, |b| &b.u).clone();
                            let used = self.evaluations.saturating_sub(1) as usize;
                            self.opt = self.make.make(&from, used, self.stages[0]);
                            continue;
                        }
                        if b.is_empty() {
                            self.phase = if self.validation_points.is_empty() {
                                Phase::Finished
                            } else {
                                Phase::Validate
                            };
                            continue;
                        }
                        self.losses = vec![f64::NAN; b.len()];
                        self.exact = vec![f64::NAN; b.len()];
                        self.batch = b;
                        self.next = self.shards.0;
                    }
                    if self.next < self.batch.len() {
                        let (w, l) = self.eval_point(WORK_PER_STEP - work)?;
                        work += w;
                        if let Some((l, e)) = l {
                            self.losses[self.next] = l;
                            self.exact[self.next] = e;
                            self.next += self.shards.1;
                        }
                        continue;
                    }
                    if self.shards.1 > 1 {
                        self.exchange = Exchange::Ready(self.own_losses());
                        return Ok(Step::Running(self.progress("exchanging losses")));
                    }
                    self.tell_batch();
                    return Ok(Step::Running(self.progress(match self.phase {
                        Phase::Start => "evaluating the start",
                        _ => "optimising",
                    })));
                }
                Phase::Validate => {
                    if self.validation_target.is_none() {
                        if let Some(v) = self.sample_target(WORK_PER_STEP)? {
                            self.validation_target = Some(v);
                        }
                        return Ok(Step::Running(self.progress("validating")));
                    }
                    let Some((s, _)) = self.scene_at(&self.best.u) else {
                        self.phase = Phase::Finished;
                        continue;
                    };
                    let t = self.validation_target.as_ref().expect("target samples");
                    let f: Vec<f64> = self.validation_points.iter().map(|p| s.eval(*p)).collect();
                    let mean = t.iter().sum::<f64>() / t.len() as f64;
                    let var: f64 = t.iter().map(|v| (v - mean) * (v - mean)).sum();
                    let err: f64 = t.iter().zip(&f).map(|(a, b)| (a - b) * (a - b)).sum();
                    self.validation = Some(if var > 0.0 { err / var } else { err });
                    self.phase = Phase::Finished;
                    return Ok(Step::Running(self.progress("validating")));
                }
                Phase::Finished => return Ok(Step::Done(self.output())),
            }
        }
        Ok(Step::Running(self.progress(match self.phase {
            Phase::Start => "evaluating the start",
            _ => "optimising",
        })))
    }
}

//! The whole fit as a resumable job (paper §4 "Optimization Procedure" and
//! §5 "Pattern Optimization": GA initialisation of 25 generations of 250,
//! then Adam for 250 iterations from each of the 10 best candidates with
//! patience 100 and 3 refinements; the best result is returned).
use super::field::{Evaluator, Grid, Scene};
use super::global::{GlobalOptions, GlobalSearch, Metric, Spectral};
use super::loss::{LossKind, LossOptions, Objective};
use super::record::{Canvas, Program, RecordLimits};
use super::target::{BuildWork, Target, TargetBuild};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Progress, Step};
use crate::core::rng::Rng;
use crate::optim::{best_distinct, Adam, AskTell, GaOptions, InitMethod, Initializer, Scored};
use crate::raster::Rgba8Image;
use serde::{Deserialize, Serialize};

/// Preset budgets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Budget {
    /// A small, fast fit: population 64 × 8 generations, 3 candidates × 120
    /// Adam iterations (patience 40), 64² loss grid.
    Quick,
    /// The paper's settings: 250 × 25, 10 candidates × 250 iterations
    /// (patience 100, 3 refinements), 128² grid.
    Paper,
}

impl Budget {
    /// Parse `quick | paper`.
    pub fn parse(s: &str) -> Option<Budget> {
        match s {
            "quick" => Some(Budget::Quick),
            "paper" => Some(Budget::Paper),
            _ => None,
        }
    }
}

/// Everything that controls a fit. All budgets are explicit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    pub init: InitMethod,
    pub ga: GaOptions,
    /// Candidates refined with Adam (paper: 10).
    pub candidates: usize,
    /// Adam iterations per candidate (paper: 250).
    pub iterations: usize,
    /// Adam learning rate in normalised units (paper: 0.025).
    pub lr: f64,
    /// Iterations without improvement before a refinement (paper: 100).
    pub patience: usize,
    /// Refinements before a candidate stops (paper: 3).
    pub refinements: usize,
    /// Seed for every random choice.
    pub seed: u64,
    pub loss: LossOptions,
    /// Work per [`Job::step`] in item evaluations (~5–20 ns each); at least
    /// one loss evaluation is always done.
    pub work_per_step: u64,
    /// Extra Adam iterations on the image-space loss from the best SDF
    /// result (0 = off, the paper's method). The SDF loss finds the basin
    /// robustly but its composed fields are not exact distances inside
    /// overlaps, which biases the optimum slightly; `filigree bench fit`
    /// (`image_same_init`) shows this polish removing most of that bias.
    /// The image loss reads the target's coverage from its field as it
    /// reads the pattern's ([`super::loss::coverage`]), so its minimum is
    /// the truth for an anti-aliased target as for a hard-edged one.
    #[serde(default)]
    pub polish: usize,
    /// Split one fit over `shards.1` identical jobs (the browser's worker
    /// pool, or native threads; see [`crate::core::parallel`]): job
    /// `shards.0` evaluates every `shards.1`-th point of each initialisation
    /// batch and the shards exchange their losses ([`Job::outbox`] /
    /// [`Job::inbox`]), so every job tells its initialiser the same full
    /// batch and stays identical; then each job refines a contiguous share
    /// of the candidates with Adam, and a last exchange gives every shard
    /// the best of all shares (and the merged history and evaluation count)
    /// before the polish. Every shard then returns the result of one
    /// unsharded fit, bit for bit. `(0, 1)` = alone.
    #[serde(default = "one_shard")]
    pub shards: (usize, usize),
    /// The global stage for repeating designs ([`super::global`]) instead
    /// of `init`'s initialiser (`None`: `init`, the paper's method).
    #[serde(default)]
    pub global: Option<GlobalOptions>,
}

fn one_shard() -> (usize, usize) {
    (0, 1)
}

impl FitOptions {
    /// Options for a preset budget.
    pub fn budget(b: Budget) -> FitOptions {
        let paper = FitOptions {
            init: InitMethod::Genetic,
            ga: GaOptions::default(),
            candidates: 10,
            iterations: 250,
            lr: 0.025,
            patience: 100,
            refinements: 3,
            seed: 1,
            loss: LossOptions::default(),
            work_per_step: 300_000,
            polish: 0,
            shards: (0, 1),
            global: None,
        };
        match b {
            Budget::Paper => paper,
            Budget::Quick => FitOptions {
                ga: GaOptions {
                    population: 64,
                    generations: 8,
                    ..GaOptions::default()
                },
                candidates: 3,
                iterations: 120,
                patience: 40,
                loss: LossOptions {
                    grid: 64,
                    ..LossOptions::default()
                },
                ..paper
            },
        }
    }
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions::budget(Budget::Paper)
    }
}

/// Where the target comes from.
#[derive(Debug, Clone)]
pub enum TargetSource<'a> {
    /// An image, snapped to the program's palette with an RGB tolerance.
    Image(&'a Rgba8Image, f64),
    /// The program itself drawn with these float parameter values.
    Params(&'a [f64]),
}

/// The outcome of a fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitResult {
    /// Float parameter names, declaration order.
    pub names: Vec<String>,
    /// Best float parameter values.
    pub params: Vec<f64>,
    /// Values of all declared parameters (integers as given), declaration order.
    pub all_values: Vec<f64>,
    /// Loss at `params`.
    pub loss: f64,
    /// Best loss after initialisation, before Adam.
    pub init_loss: f64,
    /// Best loss so far after each GA batch and each Adam iteration.
    pub history: Vec<f64>,
    /// Loss evaluations done.
    pub evaluations: u64,
    /// The candidates Adam started from (raw float parameter values), best first.
    pub start_points: Vec<Vec<f64>>,
    /// Image-space loss at `params` after polishing (when `polish > 0`);
    /// `loss` is then the SDF loss at the polished `params`.
    pub polish_loss: Option<f64>,
}

/// Build the scene (recorded with `values`) and target for a fit.
pub(crate) fn prepare(
    program: &Program,
    values: &[f64],
    target: &TargetSource,
    loss: &LossOptions,
) -> Result<(Scene, Target)> {
    let canvas = match target {
        TargetSource::Image(img, _) => image_canvas(img),
        TargetSource::Params(_) => Canvas::SQUARE,
    };
    let scene = fit_scene(program, values, loss, canvas)?;
    let scale = loss.scale_on(canvas);
    let t = match target {
        TargetSource::Image(img, tol) => Target::from_image(&scene, img, loss.grid, scale, *tol)?,
        TargetSource::Params(p) => {
            let idx = colour_indices(&scene, p, loss.grid)?;
            Target::from_indices(&scene, &idx, loss.grid, scale)
        }
    };
    Ok((scene, t))
}

/// The canvas of a fit to an image: the image's aspect, its shorter side 1
/// ([`Canvas::of_pixels`]), so nothing is stretched. A target drawn from
/// parameters is on the square canvas.
pub fn image_canvas(img: &Rgba8Image) -> Canvas {
    Canvas::of_pixels(img.width as usize, img.height as usize)
}

/// The scene of a fit (recorded with `values` on `canvas`), checked: a
/// grid in range, shapes to draw and float parameters to fit.
fn fit_scene(
    program: &Program,
    values: &[f64],
    loss: &LossOptions,
    canvas: Canvas,
) -> Result<Scene> {
    if !(8..=1024).contains(&loss.grid) {
        return Err(Error::input(format!(
            "loss grid {} is outside 8..=1024 pixels",
            loss.grid
        )));
    }
    let rec = program.record_on(values, &RecordLimits::default(), canvas)?;
    let scene = Scene::new(rec);
    if scene.channels.is_empty() {
        return Err(Error::input(
            "the program draws no shapes, so there is nothing to fit",
        ));
    }
    if scene.rec.float_params.is_empty() {
        return Err(Error::input(
            "the program declares no float parameters ('param name in [lo, hi];'), so there is nothing to fit",
        ));
    }
    Ok(scene)
}

/// A fit's target, owned, for a job that builds it in its steps.
#[derive(Debug, Clone)]
pub enum TargetData {
    /// An image, snapped to the program's palette with an RGB tolerance.
    Image(Rgba8Image, f64),
    /// The program itself drawn with these float parameter values.
    Params(Vec<f64>),
}

impl TargetData {
    /// The canvas the fit draws on ([`image_canvas`], or square).
    pub fn canvas(&self) -> Canvas {
        match self {
            TargetData::Image(img, _) => image_canvas(img),
            TargetData::Params(_) => Canvas::SQUARE,
        }
    }
}

/// Work units of one step of a target's preparation ([`BuildWork`]: about
/// 5–20 ns each), chosen for steps of a few milliseconds
/// (`filigree bench slices`).
pub const PREPARE_WORK_PER_STEP: BuildWork = 200_000;

/// A fit's target built in bounded parts ([`TargetBuild`]), then its
/// normals a few rows at a time: what [`prepare`] does in one go, bit for bit.
pub(crate) struct Preparation {
    build: Option<TargetBuild>,
    /// The built target while its normals are computed.
    target: Option<Target>,
    normals: Vec<[f64; 2]>,
    /// Next channel and row of the normals.
    channel: usize,
    row: usize,
}

impl Preparation {
    /// Go on for about `budget` work units (a row or line at least); the
    /// target and its normals once complete. Fails when the target image
    /// matches no colour of the program.
    pub(crate) fn step(
        &mut self,
        scene: &Scene,
        budget: BuildWork,
    ) -> Result<Option<(Target, Vec<[f64; 2]>)>> {
        if let Some(b) = &mut self.build {
            if let Some(t) = b.step(scene, budget)? {
                self.normals = Vec::with_capacity(t.sdf.len());
                self.target = Some(t);
                self.build = None;
            }
            return Ok(None);
        }
        let t = self
            .target
            .as_ref()
            .expect("a target while normals are built");
        let (w, h) = (t.grid.w, t.grid.h);
        let nn = t.grid.len();
        let channels = t.sdf.len() / nn;
        let mut spent: BuildWork = 0;
        while self.channel < channels && spent < budget.max(1) {
            let f = &t.sdf[self.channel * nn..(self.channel + 1) * nn];
            super::loss::normals_rows(f, w, h, self.row..self.row + 1, &mut self.normals);
            spent += 4 * w as BuildWork;
            self.row += 1;
            if self.row == h {
                self.row = 0;
                self.channel += 1;
            }
        }
        if self.channel < channels {
            return Ok(None);
        }
        let t = self.target.take().expect("target");
        Ok(Some((t, std::mem::take(&mut self.normals))))
    }

    /// A rough fraction done.
    pub(crate) fn fraction(&self, scene: &Scene) -> f64 {
        match (&self.build, &self.target) {
            (Some(b), _) => 0.9 * b.fraction(scene),
            (None, Some(t)) => {
                let nn = t.grid.len().max(1);
                0.9 + 0.1 * self.normals.len() as f64 / t.sdf.len().max(nn) as f64
            }
            (None, None) => 1.0,
        }
    }
}

/// Check a fit's program and target and start its preparation: only the
/// recording and the checks happen here; [`Preparation::step`] builds the
/// target's fields and normals.
pub(crate) fn begin_prepare(
    program: &Program,
    values: &[f64],
    target: TargetData,
    loss: &LossOptions,
) -> Result<(Scene, Preparation)> {
    let canvas = target.canvas();
    let scene = fit_scene(program, values, loss, canvas)?;
    let scale = loss.scale_on(canvas);
    let build = match target {
        TargetData::Image(img, tol) => TargetBuild::image(&scene, img, loss.grid, scale, tol)?,
        TargetData::Params(p) => TargetBuild::drawn(&scene, &p, loss.grid, scale)?,
    };
    Ok((
        scene,
        Preparation {
            build: Some(build),
            target: None,
            normals: vec![],
            channel: 0,
            row: 0,
        },
    ))
}

/// Palette index per pixel of the scene drawn with `params` on the grid of
/// `n` pixels along the longer side of its canvas (`n × n` on a square).
pub fn colour_indices(scene: &Scene, params: &[f64], n: usize) -> Result<Vec<u16>> {
    let nodes = super::render::checked_nodes(scene, params)?;
    let mut ev = Evaluator::on(Grid::on(scene.rec.canvas, n), 1.0);
    ev.eval(scene, &nodes, false);
    Ok(ev.colour_indices(scene))
}

enum Phase {
    /// Building the target's fields ([`FitJob::start`]).
    Prepare,
    Init,
    Refine,
    Polish,
    Finished,
}

/// A fit, stepped in slices. Progress: `figure` = best loss so far,
/// `values` = the best float parameters so far (declaration order).
pub struct FitJob {
    obj: Objective,
    /// The target in the making (with [`Phase::Prepare`]).
    prep: Option<Preparation>,
    opts: FitOptions,
    rng: Rng,
    lo: Vec<f64>,
    hi: Vec<f64>,
    names: Vec<String>,
    all_values: Vec<f64>,
    phase: Phase,
    init: Initializer,
    /// The global stage, when it replaces `init` ([`FitOptions::global`]).
    global: Option<GlobalSearch>,
    /// Its shift-invariant comparison (made once the target is built).
    spectral: Option<Spectral>,
    /// How the current batch is scored.
    metric: Metric,
    batch: Vec<Vec<f64>>,
    batch_losses: Vec<f64>,
    archive: Vec<Scored>,
    candidates: Vec<Scored>,
    cand: usize,
    adam: Option<Adam>,
    best: Scored,
    init_loss: f64,
    history: Vec<f64>,
    done: usize,
    planned: usize,
    generation: usize,
    grad: Vec<f64>,
    polish: Option<(Objective, Adam)>,
    polish_loss: Option<f64>,
    /// Sharded initialisation: this job's losses of the current batch (NaN
    /// where another shard evaluates) and the next index to look at.
    shard_losses: Vec<f64>,
    shard_next: usize,
    /// Every candidate of the whole fit (a shard refines only its share).
    all_candidates: Vec<Scored>,
    /// Length of `history` when refinement began.
    refine_from: usize,
    /// Whether the shards have shared their refinement results.
    shared_best: bool,
    exchange: Exchange,
}

/// Where a sharded job is in an exchange with its sibling shards.
#[derive(Debug, Clone, PartialEq)]
enum Exchange {
    None,
    /// Own part ready to hand out.
    Ready(Shared, Vec<f64>),
    /// Handed out; waiting for every shard's part.
    Waiting(Shared),
}

/// What the shards exchange.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shared {
    /// Losses of their points of the current initialisation batch.
    Batch,
    /// `[best loss, evaluations, best point (dim values), refinement history...]`.
    Best,
}

impl FitJob {
    /// A fit of `program` (recorded with `values`, one per declared
    /// parameter; the integer ones stay fixed) to `target`.
    pub fn new(
        program: &Program,
        values: &[f64],
        target: &TargetSource,
        opts: FitOptions,
    ) -> Result<FitJob> {
        let (scene, t) = prepare(program, values, target, &opts.loss)?;
        Ok(FitJob::from_parts(scene, t, opts))
    }

    /// [`FitJob::new`] with the target's fields built in the job's first
    /// steps rather than here (this only records the program and checks
    /// the request), so no slice of the job is long. The result is the same,
    /// bit for bit; until the preparation is done, [`FitJob::objective`]
    /// has an empty target.
    pub fn start(
        program: &Program,
        values: &[f64],
        target: TargetData,
        opts: FitOptions,
    ) -> Result<FitJob> {
        let (scene, prep) = begin_prepare(program, values, target, &opts.loss)?;
        let canvas = scene.rec.canvas;
        let pending = Target::pending(Grid::on(canvas, opts.loss.grid), opts.loss.scale_on(canvas));
        let mut job = FitJob::from_parts(scene, pending, opts);
        job.prep = Some(prep);
        job.phase = Phase::Prepare;
        Ok(job)
    }

    /// A fit from a prepared scene and target (same grid and units as `opts.loss`).
    pub fn from_parts(scene: Scene, target: Target, opts: FitOptions) -> FitJob {
        let decls = scene.rec.float_decls();
        let lo: Vec<f64> = decls.iter().map(|d| d.lo).collect();
        let hi: Vec<f64> = decls.iter().map(|d| d.hi).collect();
        let names = decls.iter().map(|d| d.name.clone()).collect();
        let all_values = scene.rec.values.clone();
        let dim = lo.len();
        let init = Initializer::new(opts.init, dim, opts.ga);
        let global = opts.global.map(|g| GlobalSearch::new(dim, g));
        let init_budget = global.as_ref().map_or(init.budget(), |g| g.budget());
        let planned = init_budget + opts.candidates * opts.iterations + opts.polish;
        let obj = Objective::new(scene, target, opts.loss);
        FitJob {
            obj,
            prep: None,
            rng: Rng::new(opts.seed),
            lo,
            hi,
            names,
            all_values,
            phase: Phase::Init,
            init,
            global,
            spectral: None,
            metric: Metric::Loss,
            batch: vec![],
            batch_losses: vec![],
            archive: vec![],
            candidates: vec![],
            cand: 0,
            adam: None,
            best: Scored {
                u: vec![0.5; dim],
                loss: f64::INFINITY,
            },
            init_loss: f64::INFINITY,
            history: vec![],
            done: 0,
            planned: planned.max(1),
            generation: 0,
            grad: vec![0.0; dim],
            opts,
            polish: None,
            polish_loss: None,
            shard_losses: vec![],
            shard_next: 0,
            all_candidates: vec![],
            refine_from: 0,
            shared_best: false,
            exchange: Exchange::None,
        }
    }

    /// A fit that skips initialisation and runs Adam from `starts` (raw
    /// float parameter values), e.g. to compare losses from the same
    /// initialisation.
    pub fn refine_from(
        scene: Scene,
        target: Target,
        opts: FitOptions,
        starts: &[Vec<f64>],
    ) -> FitJob {
        let mut job = FitJob::from_parts(scene, target, opts);
        job.candidates = starts
            .iter()
            .map(|x| Scored {
                u: x.iter()
                    .enumerate()
                    .map(|(k, v)| ((v - job.lo[k]) / (job.hi[k] - job.lo[k])).clamp(0.0, 1.0))
                    .collect(),
                loss: f64::INFINITY,
            })
            .collect();
        job.all_candidates = job.candidates.clone();
        job.planned = (job.candidates.len() * opts.iterations + opts.polish).max(1);
        job.phase = Phase::Refine;
        job
    }

    /// Raw parameter values of a normalised point.
    pub fn denormalise(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .enumerate()
            .map(|(k, v)| self.lo[k] + v * (self.hi[k] - self.lo[k]))
            .collect()
    }

    /// The objective (scene, target, loss).
    pub fn objective(&self) -> &Objective {
        &self.obj
    }

    /// Best float parameters so far (raw units) and their loss.
    pub fn best(&self) -> (Vec<f64>, f64) {
        (self.denormalise(&self.best.u), self.best.loss)
    }

    fn consider(&mut self, u: &[f64], loss: f64) {
        if loss < self.best.loss {
            self.best = Scored {
                u: u.to_vec(),
                loss,
            };
        }
    }

    fn progress(&self) -> Progress {
        let stage = match self.phase {
            // Before the first loss: a small share of the whole fit.
            Phase::Prepare => {
                let f = self
                    .prep
                    .as_ref()
                    .map_or(1.0, |p| p.fraction(&self.obj.scene));
                return Progress::new(0.01 * f, "preparing the target");
            }
            Phase::Init => match &self.global {
                Some(g) => g.describe().to_string(),
                None => format!(
                    "initialisation ({:?}), batch {}",
                    self.opts.init,
                    self.generation + 1
                ),
            },
            Phase::Refine => format!(
                "Adam on candidate {} of {}",
                (self.cand + 1).min(self.candidates.len()),
                self.candidates.len()
            ),
            Phase::Polish => "polishing with the image-space loss".into(),
            Phase::Finished => "done".into(),
        };
        let p = Progress::new(self.done as f64 / self.planned as f64, stage);
        if self.best.loss.is_finite() {
            // The best float parameters so far, so a view can draw them live.
            p.with_figure(self.best.loss)
                .with_values(self.denormalise(&self.best.u))
        } else {
            p
        }
    }

    /// Evaluations the initialisation (or the global stage) asks for at most.
    fn init_budget(&self) -> usize {
        self.global
            .as_ref()
            .map_or(self.init.budget(), |g| g.budget())
    }

    /// Score batch point `i` as the batch wants; returns the score and the work.
    fn score_point(&mut self, i: usize) -> (f64, u64) {
        let x = self.denormalise(&self.batch[i]);
        match self.metric {
            Metric::Loss => {
                let l = self.obj.loss(&x);
                (l, self.obj.last_work)
            }
            Metric::Spectrum => {
                let sp = self.spectral.as_mut().expect("made with the global stage");
                let l = sp.loss(&self.obj.scene, &x);
                (l, sp.last_work)
            }
        }
    }

    /// Evaluate the next batch point; returns work done.
    fn eval_batch_point(&mut self) -> u64 {
        let i = self.batch_losses.len();
        let (l, work) = self.score_point(i);
        self.record_point(i, l);
        work
    }

    /// Record batch point `i`'s score. Only Fit's own loss makes a point a
    /// candidate; a spectral score is the global stage's alone.
    fn record_point(&mut self, i: usize, l: f64) {
        self.batch_losses.push(l);
        self.done += 1;
        if self.metric == Metric::Loss {
            let u = self.batch[i].clone();
            self.consider(&u, l);
            self.archive.push(Scored { u, loss: l });
        }
    }

    /// Tell the finished batch to the initialiser (or the global stage) and
    /// ask for the next; an empty batch means the initialisation is over.
    fn next_batch(&mut self) {
        if !self.batch.is_empty() {
            let b = std::mem::take(&mut self.batch);
            let l = std::mem::take(&mut self.batch_losses);
            match &mut self.global {
                Some(g) => g.tell(b, &l),
                None => self.init.tell(b, &l),
            }
            if self.best.loss.is_finite() {
                self.history.push(self.best.loss);
            }
            self.generation += 1;
        }
        match &mut self.global {
            Some(g) => {
                if self.spectral.is_none() {
                    let grid = self.opts.global.map_or(64, |o| o.grid);
                    self.spectral = Some(Spectral::new(&self.obj.scene, &self.obj.target, grid));
                }
                (self.batch, self.metric) = g.ask(&mut self.rng).unwrap_or((vec![], Metric::Loss));
            }
            None => self.batch = self.init.ask(&mut self.rng),
        }
    }
}

/// Sharding (see [`FitOptions::shards`]).
impl FitJob {
    /// This shard's losses of the current batch: points `k, k + n, ...`.
    fn own_losses(&self) -> Vec<f64> {
        let (k, n) = self.opts.shards;
        self.shard_losses
            .iter()
            .skip(k)
            .step_by(n)
            .copied()
            .collect()
    }

    fn merge_batch(&mut self, k: usize, n: usize, parts: Vec<Vec<f64>>) -> Result<()> {
        let len = self.batch.len();
        for (j, part) in parts.iter().enumerate() {
            let want = (len + n - 1 - j) / n;
            if part.len() != want {
                return Err(Error::input(format!(
                    "loss exchange: shard {j} sent {} losses for its {want} points",
                    part.len()
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
        // Record in batch order, exactly as one unsharded job does.
        for i in 0..len {
            self.record_point(i, parts[i % n][i / n]);
        }
        Ok(())
    }

    /// `[best loss, evaluations, best point..., refinement history...]`.
    fn best_part(&self) -> Vec<f64> {
        let mut part = vec![self.best.loss, self.obj.evaluations as f64];
        part.extend(&self.best.u);
        part.extend(&self.history[self.refine_from..]);
        part
    }

    /// Adopt the best of all shares, as one fit that refined every candidate
    /// in order would have it: ties go to the earlier shard, evaluations add
    /// up, and the history is the running best over the shares in order.
    fn merge_best(&mut self, k: usize, parts: Vec<Vec<f64>>) -> Result<()> {
        let dim = self.lo.len();
        if parts.iter().any(|p| p.len() < 2 + dim) {
            return Err(Error::input("best exchange: a shard sent a short part"));
        }
        let own = self.best_part();
        if parts[k].len() != own.len()
            || parts[k]
                .iter()
                .zip(&own)
                .any(|(a, b)| a.to_bits() != b.to_bits())
        {
            return Err(Error::input(
                "best exchange: the shards disagree on this shard's result",
            ));
        }
        let mut best: Option<Scored> = None;
        let mut evaluations = 0u64;
        let mut history = self.history[..self.refine_from].to_vec();
        let mut running = history.last().copied().unwrap_or(f64::INFINITY);
        for p in &parts {
            if best.as_ref().is_none_or(|b| p[0] < b.loss) {
                best = Some(Scored {
                    u: p[2..2 + dim].to_vec(),
                    loss: p[0],
                });
            }
            evaluations += p[1] as u64;
            for &h in &p[2 + dim..] {
                running = running.min(h);
                history.push(running);
            }
        }
        self.best = best.expect("at least one shard");
        self.obj.evaluations = evaluations;
        self.history = history;
        self.done = self
            .done
            .max(self.init_budget() + self.opts.candidates * self.opts.iterations);
        self.shared_best = true;
        Ok(())
    }
}

impl Job for FitJob {
    type Output = FitResult;

    fn outbox(&mut self) -> Option<Vec<f64>> {
        match std::mem::replace(&mut self.exchange, Exchange::None) {
            Exchange::Ready(what, part) => {
                self.exchange = Exchange::Waiting(what);
                Some(part)
            }
            other => {
                self.exchange = other;
                None
            }
        }
    }

    /// Every shard's part of the exchange, in shard order.
    fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
        let (k, n) = self.opts.shards;
        let Exchange::Waiting(what) = self.exchange else {
            return Err(Error::input(
                "unexpected exchange: this fit is not waiting for its sibling shards",
            ));
        };
        if parts.len() != n {
            return Err(Error::input(format!(
                "exchange: {} parts for {n} shards",
                parts.len()
            )));
        }
        match what {
            Shared::Batch => self.merge_batch(k, n, parts)?,
            Shared::Best => self.merge_best(k, parts)?,
        }
        self.exchange = Exchange::None;
        Ok(())
    }

    fn step(&mut self) -> Result<Step<FitResult>> {
        let mut work = 0u64;
        let mut evals = 0;
        if let Phase::Prepare = self.phase {
            let prep = self.prep.as_mut().expect("preparation");
            if let Some((t, normals)) = prep.step(&self.obj.scene, PREPARE_WORK_PER_STEP)? {
                self.obj.set_target(t, normals);
                self.prep = None;
                self.phase = Phase::Init;
            }
            return Ok(Step::Running(self.progress()));
        }
        while work < self.opts.work_per_step || evals == 0 {
            match self.phase {
                Phase::Prepare => unreachable!("prepared above"),
                Phase::Init => {
                    if self.batch_losses.len() == self.batch.len() {
                        self.next_batch();
                        self.shard_losses = vec![f64::NAN; self.batch.len()];
                        self.shard_next = 0;
                        if self.batch.is_empty() {
                            self.candidates =
                                best_distinct(&self.archive, self.opts.candidates.max(1));
                            self.all_candidates = self.candidates.clone();
                            self.refine_from = self.history.len();
                            let (k, n) = self.opts.shards;
                            if n > 1 {
                                // This shard refines its contiguous share.
                                let size = self.candidates.len().div_ceil(n);
                                let end = ((k + 1) * size).min(self.candidates.len());
                                self.candidates =
                                    self.candidates[(k * size).min(end)..end].to_vec();
                            }
                            self.archive = vec![];
                            self.init_loss = self.best.loss;
                            self.done = self.done.max(self.init_budget());
                            self.phase = Phase::Refine;
                        }
                        continue;
                    }
                    if self.opts.shards.1 > 1 {
                        if self.exchange != Exchange::None {
                            // Nothing to do until the driver brings the other shards' losses.
                            return Ok(Step::Running(self.progress()));
                        }
                        let (k, n) = self.opts.shards;
                        while self.shard_next < self.batch.len() && self.shard_next % n != k {
                            self.shard_next += 1;
                        }
                        if self.shard_next == self.batch.len() {
                            self.exchange = Exchange::Ready(Shared::Batch, self.own_losses());
                            return Ok(Step::Running(self.progress()));
                        }
                        let i = self.shard_next;
                        let (l, w) = self.score_point(i);
                        self.shard_losses[i] = l;
                        self.shard_next += 1;
                        work += w;
                        evals += 1;
                        continue;
                    }
                    work += self.eval_batch_point();
                    evals += 1;
                }
                Phase::Refine => {
                    if self.adam.is_none() {
                        if self.cand >= self.candidates.len() || self.opts.iterations == 0 {
                            if self.opts.shards.1 > 1 && !self.shared_best {
                                if self.exchange == Exchange::None {
                                    self.exchange = Exchange::Ready(Shared::Best, self.best_part());
                                }
                                // Nothing to do until every shard's best arrives.
                                return Ok(Step::Running(self.progress()));
                            }
                            self.phase = if self.opts.polish > 0 {
                                Phase::Polish
                            } else {
                                Phase::Finished
                            };
                            continue;
                        }
                        let c = self.candidates[self.cand].clone();
                        self.adam = Some(Adam::new(
                            c,
                            self.opts.lr,
                            self.opts.patience,
                            self.opts.refinements,
                        ));
                    }
                    let u = self.adam.as_ref().expect("adam").u.clone();
                    let x = self.denormalise(&u);
                    let mut g = std::mem::take(&mut self.grad);
                    let l = self.obj.loss_grad(&x, &mut g);
                    for (k, gk) in g.iter_mut().enumerate() {
                        *gk *= self.hi[k] - self.lo[k];
                    }
                    self.consider(&u, l);
                    let adam = self.adam.as_mut().expect("adam");
                    let go_on = adam.update(l, &g);
                    self.grad = g;
                    self.done += 1;
                    self.history.push(self.best.loss);
                    work += self.obj.last_work;
                    evals += 1;
                    let it = adam.iterations;
                    if !go_on || it >= self.opts.iterations {
                        self.done += self.opts.iterations - it.min(self.opts.iterations);
                        self.adam = None;
                        self.cand += 1;
                    }
                }
                Phase::Polish => {
                    if self.polish.is_none() {
                        let mut lo = self.obj.opts;
                        lo.kind = LossKind::Image;
                        let obj =
                            Objective::new(self.obj.scene.clone(), self.obj.target.clone(), lo);
                        let start = Scored {
                            u: self.best.u.clone(),
                            loss: f64::INFINITY,
                        };
                        let adam = Adam::new(
                            start,
                            self.opts.lr,
                            self.opts.patience,
                            self.opts.refinements,
                        );
                        self.polish = Some((obj, adam));
                    }
                    let (obj, adam) = self.polish.as_mut().expect("polish");
                    let u = adam.u.clone();
                    let x: Vec<f64> = u
                        .iter()
                        .enumerate()
                        .map(|(k, v)| self.lo[k] + v * (self.hi[k] - self.lo[k]))
                        .collect();
                    let mut g = std::mem::take(&mut self.grad);
                    let l = obj.loss_grad(&x, &mut g);
                    for (k, gk) in g.iter_mut().enumerate() {
                        *gk *= self.hi[k] - self.lo[k];
                    }
                    let go_on = adam.update(l, &g);
                    self.grad = g;
                    self.done += 1;
                    work += obj.last_work;
                    evals += 1;
                    let it = adam.iterations;
                    if !go_on || it >= self.opts.polish {
                        self.done += self.opts.polish - it.min(self.opts.polish);
                        let best = adam.best.clone();
                        self.obj.evaluations += obj.evaluations;
                        // Report the main (SDF) loss at the polished point.
                        let x = self.denormalise(&best.u);
                        let sdf = self.obj.loss(&x);
                        self.best = Scored {
                            u: best.u,
                            loss: sdf,
                        };
                        self.polish_loss = Some(best.loss);
                        self.phase = Phase::Finished;
                    }
                }
                Phase::Finished => {
                    let params = self.denormalise(&self.best.u);
                    let mut all_values = self.all_values.clone();
                    for (k, &i) in self.obj.scene.rec.float_params.iter().enumerate() {
                        all_values[i] = params[k];
                    }
                    let start_points = self
                        .all_candidates
                        .iter()
                        .map(|c| self.denormalise(&c.u))
                        .collect();
                    return Ok(Step::Done(FitResult {
                        start_points,
                        names: self.names.clone(),
                        params,
                        all_values,
                        loss: self.best.loss,
                        init_loss: self.init_loss,
                        history: std::mem::take(&mut self.history),
                        evaluations: self.obj.evaluations,
                        polish_loss: self.polish_loss,
                    }));
                }
            }
        }
        Ok(Step::Running(self.progress()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::run_quietly;
    use crate::pattern::generators::generator;

    fn small(grid: usize) -> FitOptions {
        let mut o = FitOptions::budget(Budget::Quick);
        o.ga.population = 12;
        o.ga.generations = 2;
        o.candidates = 2;
        o.iterations = 6;
        o.loss.grid = grid;
        o
    }

    /// A fit started with [`FitJob::start`] (target built in its steps)
    /// returns what [`FitJob::new`] (target built at once) returns, bit for
    /// bit, for a drawn and an image target, and its preparation is spread
    /// over several steps at a big grid.
    #[test]
    fn stepping_the_preparation_gives_the_same_bits() {
        let p = Program::parse(generator("circles-mix").unwrap().source).unwrap();
        let vals = p.defaults();
        let truth: Vec<f64> = p
            .record(&vals, &RecordLimits::default())
            .unwrap()
            .float_values()
            .iter()
            .map(|v| v * 1.04)
            .collect();
        let img = {
            let scene = fit_scene(&p, &vals, &small(64).loss, Canvas::SQUARE).unwrap();
            let mut ev = Evaluator::new(150, 1.0);
            let nodes = crate::pattern::render::checked_nodes(&scene, &truth).unwrap();
            ev.eval(&scene, &nodes, false);
            let idx = ev.colour_indices(&scene);
            let mut img = Rgba8Image::new(150, 150);
            for (px, &i) in img.data.chunks_exact_mut(4).zip(&idx) {
                let c = scene.rec.colours[i as usize];
                px.copy_from_slice(&[c[0], c[1], c[2], 255]);
            }
            img
        };
        let cases = [
            (TargetData::Params(truth.clone()), 40),
            (TargetData::Image(img.clone(), 40.0), 64),
        ];
        for (data, grid) in cases {
            let o = small(grid);
            let src = match &data {
                TargetData::Params(x) => TargetSource::Params(x),
                TargetData::Image(i, t) => TargetSource::Image(i, *t),
            };
            let want = run_quietly(FitJob::new(&p, &vals, &src, o).unwrap()).unwrap();
            let job = FitJob::start(&p, &vals, data.clone(), o).unwrap();
            assert!(
                job.objective().target.sdf.is_empty(),
                "nothing built at the start"
            );
            let got = run_quietly(job).unwrap();
            assert_eq!(
                format!(
                    "{:?}",
                    got.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                ),
                format!(
                    "{:?}",
                    want.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                )
            );
            assert_eq!(got.loss.to_bits(), want.loss.to_bits());
            assert_eq!(got, want);
        }
        // At grid 1024 the preparation takes many steps.
        let mut job = FitJob::start(&p, &vals, TargetData::Params(truth), small(1024)).unwrap();
        let mut prep_steps = 0;
        while let Phase::Prepare = job.phase {
            let Step::Running(pr) = job.step().unwrap() else {
                panic!("done while preparing");
            };
            if let Phase::Prepare = job.phase {
                assert_eq!(pr.stage, "preparing the target");
            }
            prep_steps += 1;
        }
        assert!(
            prep_steps > 20,
            "{prep_steps} preparation steps at grid 1024"
        );
        assert_eq!(
            job.objective().target.sdf.len(),
            job.objective().scene.channels.len() << 20
        );
    }
}

//! The whole fit as a resumable job (paper §4 "Optimization Procedure" and
//! §5 "Pattern Optimization": GA initialisation of 25 generations of 250,
//! then Adam for 250 iterations from each of the 10 best candidates with
//! patience 100 and 3 refinements; the best result is returned).
use super::field::{Evaluator, Scene};
use super::loss::{LossKind, LossOptions, Objective};
use super::record::{Program, RecordLimits};
use super::target::Target;
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
    /// Native threads for evaluating GA batches (1 = none; ignored in wasm).
    pub threads: usize,
    /// Extra Adam iterations on the image-space loss from the best SDF
    /// result (0 = off, the paper's method). The SDF loss finds the basin
    /// robustly but its composed fields are not exact distances inside
    /// overlaps, which biases the optimum slightly; `filigree bench fit`
    /// (`image_same_init`) shows this polish removing most of that bias.
    #[serde(default)]
    pub polish: usize,
    /// Split one fit over `shards.1` identical jobs (a browser worker pool):
    /// job `shards.0` evaluates every `shards.1`-th point of each
    /// initialisation batch, the driver exchanges the losses
    /// ([`Job::outbox`] / [`Job::inbox`]) so every job tells its initialiser
    /// the same full batch and stays identical, and then each job refines a
    /// contiguous share of the candidates with Adam. The best result over
    /// the shares equals the result of one unsharded fit. `(0, 1)` = alone.
    #[serde(default = "one_shard")]
    pub shards: (usize, usize),
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
            threads: 1,
            polish: 0,
            shards: (0, 1),
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
pub fn prepare(
    program: &Program,
    values: &[f64],
    target: &TargetSource,
    loss: &LossOptions,
) -> Result<(Scene, Target)> {
    if !(8..=1024).contains(&loss.grid) {
        return Err(Error::input(format!(
            "loss grid {} is outside 8..=1024 pixels",
            loss.grid
        )));
    }
    let rec = program.record(values, &RecordLimits::default())?;
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
    let t = match target {
        TargetSource::Image(img, tol) => {
            Target::from_image(&scene, img, loss.grid, loss.scale(), *tol)?
        }
        TargetSource::Params(p) => {
            let idx = colour_indices(&scene, p, loss.grid)?;
            Target::from_indices(&scene, &idx, loss.grid, loss.scale())
        }
    };
    Ok((scene, t))
}

/// Palette index per pixel of the scene drawn with `params` on an `n × n` grid.
pub fn colour_indices(scene: &Scene, params: &[f64], n: usize) -> Result<Vec<u16>> {
    if params.len() != scene.rec.float_params.len() {
        return Err(Error::input(format!(
            "the program has {} float parameters but {} values were given",
            scene.rec.float_params.len(),
            params.len()
        )));
    }
    let mut nodes = vec![];
    scene.rec.tape.forward(params, &mut nodes);
    if !scene.shapes_finite(&nodes) {
        return Err(Error::input(
            "with these parameter values a shape's coordinates or sizes are not finite numbers \
             (a division by zero in the program?)",
        ));
    }
    let mut ev = Evaluator::new(n, 1.0);
    ev.eval(scene, &nodes, false);
    Ok(ev.colour_indices(scene))
}

enum Phase {
    Init,
    Refine,
    Polish,
    Finished,
}

/// A fit, stepped in slices. Progress: `figure` = best loss so far,
/// `values` = the best float parameters so far (declaration order).
pub struct FitJob {
    obj: Objective,
    opts: FitOptions,
    rng: Rng,
    lo: Vec<f64>,
    hi: Vec<f64>,
    names: Vec<String>,
    all_values: Vec<f64>,
    phase: Phase,
    init: Initializer,
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
    #[cfg(not(target_arch = "wasm32"))]
    workers: Vec<Objective>,
    polish: Option<(Objective, Adam)>,
    polish_loss: Option<f64>,
    /// Sharded initialisation: this job's losses of the current batch (NaN
    /// where another shard evaluates), the next index to look at, and
    /// whether the batch waits for the other shards' losses.
    shard_losses: Vec<f64>,
    shard_next: usize,
    exchange: Exchange,
}

/// Where a sharded job is in a loss exchange.
#[derive(Debug, Clone, PartialEq)]
enum Exchange {
    None,
    /// Own losses ready to hand out.
    Ready(Vec<f64>),
    /// Handed out; waiting for the full batch.
    Waiting,
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

    /// A fit from a prepared scene and target (same grid and units as `opts.loss`).
    pub fn from_parts(scene: Scene, target: Target, opts: FitOptions) -> FitJob {
        let decls = scene.rec.float_decls();
        let lo: Vec<f64> = decls.iter().map(|d| d.lo).collect();
        let hi: Vec<f64> = decls.iter().map(|d| d.hi).collect();
        let names = decls.iter().map(|d| d.name.clone()).collect();
        let all_values = scene.rec.values.clone();
        let dim = lo.len();
        let init = Initializer::new(opts.init, dim, opts.ga);
        let planned = init.budget() + opts.candidates * opts.iterations + opts.polish;
        let obj = Objective::new(scene, target, opts.loss);
        FitJob {
            obj,
            rng: Rng::new(opts.seed),
            lo,
            hi,
            names,
            all_values,
            phase: Phase::Init,
            init,
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
            #[cfg(not(target_arch = "wasm32"))]
            workers: vec![],
            polish: None,
            polish_loss: None,
            shard_losses: vec![],
            shard_next: 0,
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
            Phase::Init => format!(
                "initialisation ({:?}), batch {}",
                self.opts.init,
                self.generation + 1
            ),
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

    /// Evaluate pending batch points; returns work done.
    fn eval_batch_points(&mut self) -> u64 {
        let i = self.batch_losses.len();
        #[cfg(not(target_arch = "wasm32"))]
        if self.opts.threads > 1 {
            let t = self.opts.threads;
            while self.workers.len() < t {
                self.workers.push(self.obj.clone());
            }
            let end = (i + 4 * t).min(self.batch.len());
            let points: Vec<Vec<f64>> = self.batch[i..end]
                .iter()
                .map(|u| self.denormalise(u))
                .collect();
            let chunk = points.len().div_ceil(t).max(1);
            let mut out = vec![0.0; points.len()];
            let mut work = 0u64;
            std::thread::scope(|s| {
                let mut handles = vec![];
                for ((w, ps), os) in self
                    .workers
                    .iter_mut()
                    .zip(points.chunks(chunk))
                    .zip(out.chunks_mut(chunk))
                {
                    handles.push(s.spawn(move || {
                        let mut wk = 0;
                        for (p, o) in ps.iter().zip(os.iter_mut()) {
                            *o = w.loss(p);
                            wk += w.last_work;
                        }
                        wk
                    }));
                }
                for h in handles {
                    work += h.join().expect("fit worker thread panicked");
                }
            });
            self.obj.evaluations += out.len() as u64;
            for (k, l) in out.into_iter().enumerate() {
                self.record_point(i + k, l);
            }
            return work / t as u64;
        }
        let x = self.denormalise(&self.batch[i]);
        let l = self.obj.loss(&x);
        self.record_point(i, l);
        self.obj.last_work
    }

    fn record_point(&mut self, i: usize, l: f64) {
        let u = self.batch[i].clone();
        self.batch_losses.push(l);
        self.consider(&u, l);
        self.archive.push(Scored { u, loss: l });
        self.done += 1;
    }
}

impl Job for FitJob {
    type Output = FitResult;

    fn outbox(&mut self) -> Option<Vec<f64>> {
        match std::mem::replace(&mut self.exchange, Exchange::Waiting) {
            Exchange::Ready(v) => Some(v),
            other => {
                self.exchange = other;
                None
            }
        }
    }

    /// The full batch of losses, every shard's part merged.
    fn inbox(&mut self, losses: Vec<f64>) -> Result<()> {
        if self.exchange != Exchange::Waiting || losses.len() != self.batch.len() {
            return Err(Error::input(format!(
                "unexpected loss exchange: {} losses for a batch of {}",
                losses.len(),
                self.batch.len()
            )));
        }
        let (k, n) = self.opts.shards;
        for (i, &l) in losses.iter().enumerate() {
            // Our own losses must come back unchanged: the shards agree on the batch.
            if i % n == k && l.to_bits() != self.shard_losses[i].to_bits() {
                return Err(Error::input(
                    "loss exchange: the shards disagree on the batch",
                ));
            }
        }
        // Record in batch order, exactly as one unsharded job does.
        for (i, l) in losses.into_iter().enumerate() {
            self.record_point(i, l);
        }
        self.exchange = Exchange::None;
        Ok(())
    }

    fn step(&mut self) -> Result<Step<FitResult>> {
        let mut work = 0u64;
        let mut evals = 0;
        while work < self.opts.work_per_step || evals == 0 {
            match self.phase {
                Phase::Init => {
                    if self.batch_losses.len() == self.batch.len() {
                        if !self.batch.is_empty() {
                            let b = std::mem::take(&mut self.batch);
                            let l = std::mem::take(&mut self.batch_losses);
                            self.init.tell(b, &l);
                            self.history.push(self.best.loss);
                            self.generation += 1;
                        }
                        self.batch = self.init.ask(&mut self.rng);
                        self.shard_losses = vec![f64::NAN; self.batch.len()];
                        self.shard_next = 0;
                        if self.batch.is_empty() {
                            self.candidates =
                                best_distinct(&self.archive, self.opts.candidates.max(1));
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
                            self.done = self.done.max(self.init.budget());
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
                            self.exchange = Exchange::Ready(self.shard_losses.clone());
                            return Ok(Step::Running(self.progress()));
                        }
                        let i = self.shard_next;
                        let x = self.denormalise(&self.batch[i]);
                        self.shard_losses[i] = self.obj.loss(&x);
                        self.shard_next += 1;
                        work += self.obj.last_work;
                        evals += 1;
                        continue;
                    }
                    work += self.eval_batch_points();
                    evals += 1;
                }
                Phase::Refine => {
                    if self.adam.is_none() {
                        if self.cand >= self.candidates.len() || self.opts.iterations == 0 {
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
                        .candidates
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

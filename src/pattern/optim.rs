//! Initialisation and refinement (paper §4 "Parameter Set Initialization",
//! Fig. 9, and "Parameter Set Optimization", Fig. 10).
//!
//! All search happens in normalised coordinates `u ∈ [0, 1]^d` (each
//! parameter mapped from its declared range), so one learning rate and one
//! mutation width suit every parameter. The initialisers are ask/tell state
//! machines: they hand out batches of points and take their losses back,
//! which lets a job evaluate a batch over several slices, or a pool of
//! workers evaluate it in parallel, with identical results.
use crate::core::rng::Rng;
use serde::{Deserialize, Serialize};

/// How to pick starting points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum InitMethod {
    /// Genetic algorithm: tournament selection, 2-point crossover, Gaussian
    /// mutation, elitism (the paper's choice).
    #[default]
    Genetic,
    /// Random sampling that re-samples one parameter of the best point at a time.
    Random,
    /// Nelder–Mead simplex with random restarts.
    NelderMead,
}

/// Genetic-algorithm settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaOptions {
    /// Population size (paper: 250).
    pub population: usize,
    /// Generations after the initial one (paper: 25).
    pub generations: usize,
    /// Probability that a pair of parents is crossed over.
    pub crossover: f64,
    /// Probability that a child is mutated.
    pub mutation: f64,
    /// Standard deviation of a gene's Gaussian mutation (normalised units).
    pub sigma: f64,
    /// Best individuals copied unchanged into the next generation.
    pub elite: usize,
}

impl Default for GaOptions {
    fn default() -> Self {
        GaOptions {
            population: 250,
            generations: 25,
            crossover: 0.7,
            mutation: 0.3,
            sigma: 0.1,
            elite: 5,
        }
    }
}

/// An evaluated point.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    pub u: Vec<f64>,
    pub loss: f64,
}

/// The `k` best distinct points of `all` (closer than 1e-3 counts as the same).
pub fn best_distinct(all: &[Scored], k: usize) -> Vec<Scored> {
    let mut idx: Vec<usize> = (0..all.len()).collect();
    idx.sort_by(|&a, &b| all[a].loss.total_cmp(&all[b].loss).then(a.cmp(&b)));
    let mut out: Vec<Scored> = vec![];
    for i in idx {
        if out.len() == k {
            break;
        }
        let s = &all[i];
        let near = out.iter().any(|o| {
            o.u.iter()
                .zip(&s.u)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
                < 1e-3
        });
        if !near {
            out.push(s.clone());
        }
    }
    out
}

fn clamp01(v: &mut [f64]) {
    v.iter_mut().for_each(|x| *x = x.clamp(0.0, 1.0));
}

fn gauss(rng: &mut Rng) -> f64 {
    // Box–Muller; one value per call keeps the stream simple.
    let u1 = rng.f64().max(1e-300);
    let u2 = rng.f64();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// An ask/tell initialiser.
#[derive(Debug, Clone)]
pub enum Initializer {
    Genetic(Ga),
    Random(RandomSearch),
    NelderMead(NelderMead),
}

impl Initializer {
    /// A new initialiser for `dim` parameters with the GA's evaluation
    /// budget (`population × (generations + 1)`) for every method.
    pub fn new(method: InitMethod, dim: usize, ga: GaOptions) -> Initializer {
        let budget = ga.population * (ga.generations + 1);
        match method {
            InitMethod::Genetic => Initializer::Genetic(Ga {
                opts: ga,
                dim,
                pop: vec![],
                gen: 0,
            }),
            InitMethod::Random => Initializer::Random(RandomSearch {
                dim,
                batch: ga.population,
                budget,
                used: 0,
                best: None,
                coord: 0,
            }),
            InitMethod::NelderMead => Initializer::NelderMead(NelderMead::new(dim, budget)),
        }
    }

    /// Total evaluations this initialiser will ask for (an upper bound).
    pub fn budget(&self) -> usize {
        match self {
            Initializer::Genetic(g) => {
                g.opts.population
                    + g.opts.generations * g.opts.population.saturating_sub(g.opts.elite)
            }
            Initializer::Random(r) => r.budget,
            Initializer::NelderMead(n) => n.budget,
        }
    }

    /// The next batch to evaluate; empty when finished.
    pub fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        match self {
            Initializer::Genetic(g) => g.ask(rng),
            Initializer::Random(r) => r.ask(rng),
            Initializer::NelderMead(n) => n.ask(rng),
        }
    }

    /// Losses of the last batch, in order.
    pub fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        match self {
            Initializer::Genetic(g) => g.tell(batch, losses),
            Initializer::Random(r) => r.tell(batch, losses),
            Initializer::NelderMead(n) => n.tell(batch, losses),
        }
    }
}

/// Genetic algorithm state.
#[derive(Debug, Clone)]
pub struct Ga {
    opts: GaOptions,
    dim: usize,
    /// Current population, sorted best first once evaluated.
    pop: Vec<Scored>,
    gen: usize,
}

impl Ga {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        let p = self.opts.population.max(2);
        if self.pop.is_empty() && self.gen == 0 {
            return (0..p)
                .map(|_| (0..self.dim).map(|_| rng.f64()).collect())
                .collect();
        }
        if self.gen > self.opts.generations {
            return vec![];
        }
        let elite = self.opts.elite.min(p - 1);
        let mut children = vec![];
        let tournament = |rng: &mut Rng, pop: &[Scored]| -> Vec<f64> {
            let mut best = rng.below(pop.len());
            for _ in 0..2 {
                let c = rng.below(pop.len());
                if pop[c].loss < pop[best].loss {
                    best = c;
                }
            }
            pop[best].u.clone()
        };
        while children.len() < p - elite {
            let mut a = tournament(rng, &self.pop);
            let mut b = tournament(rng, &self.pop);
            if rng.f64() < self.opts.crossover && self.dim >= 2 {
                let mut i = rng.below(self.dim + 1);
                let mut j = rng.below(self.dim + 1);
                if i > j {
                    std::mem::swap(&mut i, &mut j);
                }
                for k in i..j {
                    std::mem::swap(&mut a[k], &mut b[k]);
                }
            }
            for c in [&mut a, &mut b] {
                if rng.f64() < self.opts.mutation {
                    let indpb = (2.0 / self.dim as f64).min(1.0);
                    for g in c.iter_mut() {
                        if rng.f64() < indpb {
                            *g += self.opts.sigma * gauss(rng);
                        }
                    }
                    clamp01(c);
                }
            }
            children.push(a);
            if children.len() < p - elite {
                children.push(b);
            }
        }
        children
    }

    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        let elite = if self.pop.is_empty() {
            0
        } else {
            self.opts.elite.min(self.pop.len())
        };
        let mut next: Vec<Scored> = self.pop[..elite].to_vec();
        next.extend(
            batch
                .into_iter()
                .zip(losses)
                .map(|(u, &loss)| Scored { u, loss }),
        );
        next.sort_by(|a, b| a.loss.total_cmp(&b.loss));
        self.pop = next;
        self.gen += 1;
    }

    /// The current population, best first.
    pub fn population(&self) -> &[Scored] {
        &self.pop
    }
}

/// Random sampling, one parameter at a time (paper §4).
#[derive(Debug, Clone)]
pub struct RandomSearch {
    dim: usize,
    batch: usize,
    budget: usize,
    used: usize,
    best: Option<Scored>,
    coord: usize,
}

impl RandomSearch {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        let n = self.batch.min(self.budget - self.used);
        if n == 0 {
            return vec![];
        }
        match &self.best {
            None => (0..n)
                .map(|_| (0..self.dim).map(|_| rng.f64()).collect())
                .collect(),
            Some(b) => (0..n)
                .map(|_| {
                    let mut u = b.u.clone();
                    if self.dim > 0 {
                        u[self.coord % self.dim] = rng.f64();
                    }
                    u
                })
                .collect(),
        }
    }
    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        self.used += batch.len();
        self.coord += 1;
        for (u, &loss) in batch.into_iter().zip(losses) {
            if self.best.as_ref().is_none_or(|b| loss < b.loss) {
                self.best = Some(Scored { u, loss });
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum NmStage {
    Start,
    Init,
    Reflect,
    Expand,
    Contract { outside: bool },
    Shrink,
}

/// Nelder–Mead simplex with restarts from random points when it collapses.
#[derive(Debug, Clone)]
pub struct NelderMead {
    dim: usize,
    budget: usize,
    used: usize,
    simplex: Vec<Scored>,
    stage: NmStage,
    xr: Option<Scored>,
    centroid: Vec<f64>,
}

impl NelderMead {
    fn new(dim: usize, budget: usize) -> Self {
        NelderMead {
            dim,
            budget,
            used: 0,
            simplex: vec![],
            stage: NmStage::Start,
            xr: None,
            centroid: vec![],
        }
    }

    fn along(&self, from: &[f64], to: &[f64], t: f64) -> Vec<f64> {
        let mut v: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + t * (b - a)).collect();
        clamp01(&mut v);
        v
    }

    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        if self.used >= self.budget {
            return vec![];
        }
        match self.stage {
            NmStage::Start => {
                let x0: Vec<f64> = (0..self.dim).map(|_| rng.f64()).collect();
                let mut pts = vec![x0.clone()];
                for i in 0..self.dim {
                    let mut x = x0.clone();
                    x[i] += if x[i] > 0.5 { -0.2 } else { 0.2 };
                    pts.push(x);
                }
                self.stage = NmStage::Init;
                pts
            }
            NmStage::Reflect => {
                self.simplex.sort_by(|a, b| a.loss.total_cmp(&b.loss));
                let d = self.dim;
                self.centroid = (0..d)
                    .map(|k| self.simplex[..d].iter().map(|s| s.u[k]).sum::<f64>() / d as f64)
                    .collect();
                vec![self.along(&self.simplex[d].u, &self.centroid, 2.0)]
            }
            NmStage::Expand => {
                let xr = self.xr.as_ref().expect("reflected point");
                vec![self.along(&self.centroid, &xr.u, 2.0)]
            }
            NmStage::Contract { outside } => {
                let d = self.dim;
                let xr = self.xr.as_ref().expect("reflected point");
                let to = if outside { &xr.u } else { &self.simplex[d].u };
                vec![self.along(&self.centroid, to, 0.5)]
            }
            NmStage::Shrink => {
                let b = self.simplex[0].u.clone();
                self.simplex[1..]
                    .iter()
                    .map(|s| self.along(&b, &s.u, 0.5))
                    .collect()
            }
            NmStage::Init => unreachable!("Init is always told before the next ask"),
        }
    }

    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        self.used += batch.len();
        let mut pts: Vec<Scored> = batch
            .into_iter()
            .zip(losses)
            .map(|(u, &loss)| Scored { u, loss })
            .collect();
        let d = self.dim;
        match self.stage {
            NmStage::Init => {
                self.simplex = pts;
                self.stage = NmStage::Reflect;
            }
            NmStage::Reflect => {
                let xr = pts.pop().expect("one point");
                let (fb, fs, fw) = (
                    self.simplex[0].loss,
                    self.simplex[d.saturating_sub(1)].loss,
                    self.simplex[d].loss,
                );
                if xr.loss < fb {
                    self.xr = Some(xr);
                    self.stage = NmStage::Expand;
                } else if xr.loss < fs {
                    self.simplex[d] = xr;
                    self.stage = NmStage::Reflect;
                } else {
                    let outside = xr.loss < fw;
                    self.xr = Some(xr);
                    self.stage = NmStage::Contract { outside };
                }
            }
            NmStage::Expand => {
                let xe = pts.pop().expect("one point");
                let xr = self.xr.take().expect("reflected");
                self.simplex[d] = if xe.loss < xr.loss { xe } else { xr };
                self.stage = NmStage::Reflect;
            }
            NmStage::Contract { outside } => {
                let xc = pts.pop().expect("one point");
                let xr = self.xr.take().expect("reflected");
                let bar = if outside {
                    xr.loss
                } else {
                    self.simplex[d].loss
                };
                if xc.loss <= bar {
                    self.simplex[d] = xc;
                    self.stage = NmStage::Reflect;
                } else {
                    self.stage = NmStage::Shrink;
                }
            }
            NmStage::Shrink => {
                for (s, p) in self.simplex[1..].iter_mut().zip(pts) {
                    *s = p;
                }
                self.stage = NmStage::Reflect;
            }
            NmStage::Start => {}
        }
        if self.stage == NmStage::Reflect {
            // Restart when the simplex has collapsed.
            let size = self.simplex[1..]
                .iter()
                .map(|s| {
                    s.u.iter()
                        .zip(&self.simplex[0].u)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                })
                .fold(0.0, f64::max);
            if size < 1e-4 {
                self.stage = NmStage::Start;
            }
        }
    }
}

/// Adam (Kingma & Ba) in normalised coordinates with the paper's patience
/// and refinement: after `patience` iterations without a new best, reload
/// the best point, halve the learning rate and reset the moments; after
/// `refinements` such reloads the run stops.
#[derive(Debug, Clone)]
pub struct Adam {
    pub u: Vec<f64>,
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
    pub lr: f64,
    pub best: Scored,
    since_best: usize,
    pub refinements: usize,
    patience: usize,
    max_refinements: usize,
    pub iterations: usize,
}

impl Adam {
    /// Start from `start` with learning rate `lr`.
    pub fn new(start: Scored, lr: f64, patience: usize, max_refinements: usize) -> Adam {
        let d = start.u.len();
        Adam {
            u: start.u.clone(),
            m: vec![0.0; d],
            v: vec![0.0; d],
            t: 0,
            lr,
            best: start,
            since_best: 0,
            refinements: 0,
            patience,
            max_refinements,
            iterations: 0,
        }
    }

    /// Take the loss and gradient at `self.u` and move. Returns false when
    /// the run has stopped (too many refinements).
    pub fn update(&mut self, loss: f64, grad: &[f64]) -> bool {
        self.iterations += 1;
        if loss < self.best.loss {
            self.best = Scored {
                u: self.u.clone(),
                loss,
            };
            self.since_best = 0;
        } else {
            self.since_best += 1;
            if self.since_best >= self.patience {
                self.refinements += 1;
                if self.refinements > self.max_refinements {
                    return false;
                }
                self.u = self.best.u.clone();
                self.lr *= 0.5;
                self.m.iter_mut().for_each(|x| *x = 0.0);
                self.v.iter_mut().for_each(|x| *x = 0.0);
                self.t = 0;
                self.since_best = 0;
                return true;
            }
        }
        let (b1, b2, eps): (f64, f64, f64) = (0.9, 0.999, 1e-8);
        self.t += 1;
        let c1 = 1.0 - b1.powi(self.t);
        let c2 = 1.0 - b2.powi(self.t);
        for (k, &gk) in grad.iter().enumerate().take(self.u.len()) {
            let g = if gk.is_finite() { gk } else { 0.0 };
            self.m[k] = b1 * self.m[k] + (1.0 - b1) * g;
            self.v[k] = b2 * self.v[k] + (1.0 - b2) * g * g;
            let step = self.lr * (self.m[k] / c1) / ((self.v[k] / c2).sqrt() + eps);
            self.u[k] = (self.u[k] - step).clamp(0.0, 1.0);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive(method: InitMethod, f: impl Fn(&[f64]) -> f64) -> Vec<Scored> {
        let mut rng = Rng::new(1);
        let ga = GaOptions {
            population: 40,
            generations: 15,
            ..Default::default()
        };
        let mut init = Initializer::new(method, 3, ga);
        let mut all = vec![];
        loop {
            let b = init.ask(&mut rng);
            if b.is_empty() {
                break;
            }
            let l: Vec<f64> = b.iter().map(|u| f(u)).collect();
            all.extend(
                b.iter()
                    .zip(&l)
                    .map(|(u, &loss)| Scored { u: u.clone(), loss }),
            );
            init.tell(b, &l);
        }
        assert!(
            all.len() <= init.budget() + 3,
            "{} > {}",
            all.len(),
            init.budget()
        );
        best_distinct(&all, 5)
    }

    #[test]
    fn initialisers_find_a_quadratic_bowl() {
        let f = |u: &[f64]| (u[0] - 0.3).powi(2) + (u[1] - 0.7).powi(2) + (u[2] - 0.5).powi(2);
        for m in [
            InitMethod::Genetic,
            InitMethod::Random,
            InitMethod::NelderMead,
        ] {
            let best = drive(m, f);
            assert!(best[0].loss < 2e-3, "{m:?}: {}", best[0].loss);
            assert_eq!(best.len(), 5);
        }
    }

    #[test]
    fn adam_converges_and_stops_after_refinements() {
        let mut a = Adam::new(
            Scored {
                u: vec![0.9, 0.1],
                loss: f64::INFINITY,
            },
            0.025,
            20,
            3,
        );
        let mut n = 0;
        while n < 2000 {
            let u = a.u.clone();
            let l = (u[0] - 0.4).powi(2) + 10.0 * (u[1] - 0.6).powi(2);
            if !a.update(l, &[2.0 * (u[0] - 0.4), 20.0 * (u[1] - 0.6)]) {
                break;
            }
            n += 1;
        }
        assert!(n < 2000, "never stopped");
        assert!(a.best.loss < 1e-6, "{}", a.best.loss);
        assert_eq!(a.refinements, 4);
    }
}

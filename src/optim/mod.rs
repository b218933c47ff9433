//! Optimisers shared by the tools: derivative-free searches behind one
//! ask/tell interface ([`AskTell`]) and a gradient method ([`Adam`]).
//!
//! Nothing here knows about patterns, images or losses: every optimiser
//! works in normalised coordinates `u ∈ [0, 1]^d` (the caller maps each
//! parameter from its range), takes losses as plain numbers and draws its
//! randomness from a seeded [`Rng`]. Fit (paper §4, "Parameter Set
//! Initialization/Optimization") uses [`Ga`] (the paper's choice),
//! [`RandomSearch`] and [`NelderMead`] to pick starting points and [`Adam`]
//! with patience and refinement to polish them.
//!
//! Files: [`ga`] (genetic algorithm), [`random`] (random sampling one
//! coordinate at a time), [`nelder_mead`] (simplex with restarts),
//! [`cmaes`], [`powell`] (conjugate directions, bounded), [`adam`].
//!
//! ## Ask/tell
//!
//! An optimiser never calls the objective. The caller asks for a batch,
//! evaluates it however it likes (over several job slices, on a pool of
//! workers, in shards that each evaluate a part) and tells the losses back.
//! The sequence of batches depends only on the seed and the losses told, so
//! a batch evaluated in pieces gives the same run as one evaluated at once.
//! Population methods hand out many points per batch, simplex and line
//! methods one or a few.
//!
//! A new method (CMA-ES: a batch of λ samples per generation, `tell`
//! updates mean, step size and covariance; Powell: one point per line-search
//! probe, `tell` advances the bracket) implements [`AskTell`] and, if Fit
//! should offer it, gets a variant in [`InitMethod`] and [`Initializer`].
use crate::core::rng::Rng;
use serde::{Deserialize, Serialize};

pub mod adam;
pub mod cmaes;
pub mod ga;
pub mod nelder_mead;
pub mod powell;
pub mod random;

pub use adam::Adam;
pub use cmaes::{Cmaes, CmaesOptions};
pub use ga::{Ga, GaOptions};
pub use nelder_mead::NelderMead;
pub use powell::Powell;
pub use random::RandomSearch;

/// An optimiser driven from outside: it proposes batches of points and
/// learns their losses; it never evaluates anything itself.
///
/// Contract (what callers rely on and implementations must keep):
/// - coordinates are normalised, every proposed point lies in `[0, 1]^d`;
/// - each [`AskTell::ask`] is answered by one [`AskTell::tell`] with the same
///   batch, in the same order, before the next `ask`;
/// - lower is better; `+∞` marks an invalid point (the objective could not
///   be evaluated there) and must never become the best while a finite loss
///   exists;
/// - given the same seed and the same losses, the batches are identical
///   (no clocks, no hidden randomness, no dependence on batch timing);
/// - an empty batch means finished, and then [`AskTell::done`] is true.
pub trait AskTell {
    /// The next batch of points to evaluate; empty when finished.
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>>;
    /// The losses of the batch last asked for, in order.
    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]);
    /// Whether the optimiser has finished: the next `ask` returns no points.
    fn done(&self) -> bool;
    /// The best point told so far, if any.
    fn best(&self) -> Option<&Scored>;
    /// An upper bound on the evaluations it asks for in total.
    fn budget(&self) -> usize;
}

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

pub(crate) fn clamp01(v: &mut [f64]) {
    v.iter_mut().for_each(|x| *x = x.clamp(0.0, 1.0));
}

pub(crate) fn gauss(rng: &mut Rng) -> f64 {
    // Box–Muller; one value per call keeps the stream simple.
    let u1 = rng.f64().max(1e-300);
    let u2 = rng.f64();
    (-2.0 * libm::log(u1)).sqrt() * libm::cos(std::f64::consts::TAU * u2)
}

/// One of the initialisers Fit offers, chosen at run time.
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
            InitMethod::Genetic => Initializer::Genetic(Ga::new(dim, ga)),
            InitMethod::Random => {
                Initializer::Random(RandomSearch::new(dim, ga.population, budget))
            }
            InitMethod::NelderMead => Initializer::NelderMead(NelderMead::new(dim, budget)),
        }
    }

    fn inner(&self) -> &dyn AskTell {
        match self {
            Initializer::Genetic(g) => g,
            Initializer::Random(r) => r,
            Initializer::NelderMead(n) => n,
        }
    }

    fn inner_mut(&mut self) -> &mut dyn AskTell {
        match self {
            Initializer::Genetic(g) => g,
            Initializer::Random(r) => r,
            Initializer::NelderMead(n) => n,
        }
    }
}

impl AskTell for Initializer {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        self.inner_mut().ask(rng)
    }
    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        self.inner_mut().tell(batch, losses)
    }
    fn done(&self) -> bool {
        self.inner().done()
    }
    fn best(&self) -> Option<&Scored> {
        self.inner().best()
    }
    fn budget(&self) -> usize {
        self.inner().budget()
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
        // Finished means the next ask is empty; the best told is the best seen.
        assert!(init.done());
        assert!(init.ask(&mut rng).is_empty());
        let best_seen = all.iter().map(|s| s.loss).fold(f64::INFINITY, f64::min);
        assert_eq!(init.best().map(|b| b.loss), Some(best_seen));
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

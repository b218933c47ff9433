//! Genetic algorithm (paper §4 "Parameter Set Initialization", Fig. 9):
//! tournament selection, two-point crossover, Gaussian mutation, elitism.
use super::{clamp01, gauss, AskTell, Scored};
use crate::core::rng::Rng;
use serde::{Deserialize, Serialize};

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
    /// A GA over `dim` normalised parameters.
    pub fn new(dim: usize, opts: GaOptions) -> Ga {
        Ga {
            opts,
            dim,
            pop: vec![],
            gen: 0,
        }
    }

    /// The current population, best first.
    pub fn population(&self) -> &[Scored] {
        &self.pop
    }
}

impl AskTell for Ga {
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

    fn done(&self) -> bool {
        self.gen > self.opts.generations
    }

    fn best(&self) -> Option<&Scored> {
        self.pop.first()
    }

    fn budget(&self) -> usize {
        self.opts.population
            + self.opts.generations * self.opts.population.saturating_sub(self.opts.elite)
    }
}

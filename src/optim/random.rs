//! Random sampling that re-samples one coordinate of the best point at a
//! time (paper §4, the alternative to the GA).
use super::{AskTell, Scored};
use crate::core::rng::Rng;

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
    /// `budget` evaluations over `dim` parameters, `batch` per ask.
    pub fn new(dim: usize, batch: usize, budget: usize) -> RandomSearch {
        RandomSearch {
            dim,
            batch,
            budget,
            used: 0,
            best: None,
            coord: 0,
        }
    }
}

impl AskTell for RandomSearch {
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

    fn done(&self) -> bool {
        self.used >= self.budget
    }

    fn best(&self) -> Option<&Scored> {
        self.best.as_ref()
    }

    fn budget(&self) -> usize {
        self.budget
    }
}

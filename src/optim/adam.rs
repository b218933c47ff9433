//! Adam (Kingma & Ba) with the patience and refinement of pOp (paper §4
//! "Parameter Set Optimization", Fig. 10). A gradient method, so not an
//! [`super::AskTell`]: the caller evaluates loss and gradient at [`Adam::u`]
//! and calls [`Adam::update`].
use super::Scored;

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
        let c1 = 1.0 - libm::pow(b1, self.t as f64);
        let c2 = 1.0 - libm::pow(b2, self.t as f64);
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

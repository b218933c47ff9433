//! Nelder–Mead simplex search with random restarts when the simplex
//! collapses (an alternative initialiser for Fit).
use super::{clamp01, AskTell, Scored};
use crate::core::rng::Rng;

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
    /// Best point told so far (restarts forget the simplex, not this).
    best: Option<Scored>,
    /// Where the first simplex starts (else a random point).
    start: Option<Vec<f64>>,
}

impl NelderMead {
    /// A simplex search over `dim` parameters with `budget` evaluations.
    pub fn new(dim: usize, budget: usize) -> Self {
        NelderMead {
            dim,
            budget,
            used: 0,
            simplex: vec![],
            stage: NmStage::Start,
            xr: None,
            centroid: vec![],
            best: None,
            start: None,
        }
    }

    /// A search whose first simplex starts at `x0` (restarts are random).
    pub fn starting_at(x0: &[f64], budget: usize) -> Self {
        let mut nm = NelderMead::new(x0.len().max(1), budget);
        let mut x = x0.to_vec();
        x.resize(nm.dim, 0.5);
        clamp01(&mut x);
        nm.start = Some(x);
        nm
    }

    fn along(&self, from: &[f64], to: &[f64], t: f64) -> Vec<f64> {
        let mut v: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + t * (b - a)).collect();
        clamp01(&mut v);
        v
    }
}

impl AskTell for NelderMead {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        if self.used >= self.budget {
            return vec![];
        }
        match self.stage {
            NmStage::Start => {
                let x0: Vec<f64> = match self.start.take() {
                    Some(x) => x,
                    None => (0..self.dim).map(|_| rng.f64()).collect(),
                };
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
        for p in &pts {
            if self.best.as_ref().is_none_or(|b| p.loss < b.loss) {
                self.best = Some(p.clone());
            }
        }
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

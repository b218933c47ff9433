//! CMA-ES (Hansen's covariance matrix adaptation evolution strategy,
//! "The CMA Evolution Strategy: A Tutorial", 2016) behind the ask/tell
//! interface, in normalised coordinates `[0, 1]^d`.
//!
//! One batch is one generation of λ samples; `tell` updates the mean, the
//! step size (cumulative step-size adaptation) and the covariance (rank-one
//! and rank-μ updates). Samples outside the box are clamped to it and the
//! update uses the clamped points, so the mean stays inside. The covariance
//! is decomposed by cyclic Jacobi rotations (fixed sweep order: the same
//! bits natively and in wasm; dimensions here are small).
//!
//! With [`CmaesOptions::restarts`] (what Micro's reconstruction uses) a run
//! that has settled restarts from a random mean with twice the population
//! (IPOP-CMA-ES), and the last quarter of the budget polishes the best point
//! found: landscapes such as a gyroid's frequency, a narrow well in a wide
//! plateau of local minima, are then found from any start.
#![allow(clippy::needless_range_loop)] // small dense matrix code reads best indexed

use super::{gauss, AskTell, Scored};
use crate::core::rng::Rng;

/// Settings of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CmaesOptions {
    /// Samples per generation (0: 4 + ⌊3 ln d⌋).
    pub population: usize,
    /// Initial step size, in normalised units.
    pub sigma: f64,
    pub generations: usize,
    /// Stop when σ · the largest axis of the search ellipsoid is below this.
    pub tolerance: f64,
    /// Restarts with a growing population (IPOP-CMA-ES, Auger & Hansen
    /// 2005) for landscapes with many local minima: a run whose σ · largest
    /// axis falls below [`RESTART_SHRINK`] · its initial σ has found its
    /// basin; while more than a quarter of the budget (`population ·
    /// generations` evaluations) is left, the next run starts from a random
    /// mean with twice the population. The last quarter polishes: one run
    /// from the best point so far with the first population and σ =
    /// [`POLISH_SIGMA`], until `tolerance` or the budget.
    pub restarts: bool,
}

/// A run that has shrunk its search ellipsoid by this factor has settled in
/// a basin (with restarts on, the next run begins).
pub const RESTART_SHRINK: f64 = 1e-2;
/// The polishing run's initial step (normalised units).
pub const POLISH_SIGMA: f64 = 1e-2;

impl Default for CmaesOptions {
    fn default() -> Self {
        CmaesOptions {
            population: 0,
            sigma: 0.3,
            generations: 100,
            tolerance: 1e-9,
            restarts: false,
        }
    }
}

/// A CMA-ES run.
#[derive(Debug, Clone)]
pub struct Cmaes {
    n: usize,
    lambda: usize,
    weights: Vec<f64>,
    mueff: f64,
    cc: f64,
    cs: f64,
    c1: f64,
    cmu: f64,
    damps: f64,
    chi_n: f64,
    mean: Vec<f64>,
    sigma: f64,
    c: Vec<f64>,
    pc: Vec<f64>,
    ps: Vec<f64>,
    /// Eigenvectors (columns, row-major n×n) and square roots of eigenvalues of C.
    b: Vec<f64>,
    d: Vec<f64>,
    generation: usize,
    opts: CmaesOptions,
    best: Option<Scored>,
    /// Evaluations told so far (all runs) and the whole budget.
    used: usize,
    total: usize,
    /// The initial σ of the current run; whether it is the polishing run.
    sigma0: f64,
    polishing: bool,
    /// The first run's population (the polishing run's too).
    lambda0: usize,
}

impl Cmaes {
    /// A run from the mean `start` (normalised coordinates).
    pub fn new(start: &[f64], opts: CmaesOptions) -> Cmaes {
        let n = start.len().max(1);
        let lambda = if opts.population >= 2 {
            opts.population
        } else {
            4 + (3.0 * libm::log(n as f64)).floor() as usize
        };
        let mu = lambda / 2;
        let raw: Vec<f64> = (1..=mu)
            .map(|i| (libm::log(mu as f64 + 0.5) - libm::log(i as f64)).max(0.0))
            .collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mueff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let nf = n as f64;
        let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
        let cs = (mueff + 2.0) / (nf + mueff + 5.0);
        let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
        let cmu = (1.0 - c1).min(2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff));
        let damps = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
        let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        let mut mean = start.to_vec();
        mean.resize(n, 0.5);
        super::clamp01(&mut mean);
        let mut c = vec![0.0; n * n];
        let mut b = vec![0.0; n * n];
        for i in 0..n {
            c[i * n + i] = 1.0;
            b[i * n + i] = 1.0;
        }
        Cmaes {
            n,
            lambda,
            weights,
            mueff,
            cc,
            cs,
            c1,
            cmu,
            damps,
            chi_n,
            mean,
            sigma: opts.sigma,
            c,
            pc: vec![0.0; n],
            ps: vec![0.0; n],
            b,
            d: vec![1.0; n],
            generation: 0,
            opts,
            best: None,
            used: 0,
            total: lambda * opts.generations,
            sigma0: opts.sigma,
            polishing: false,
            lambda0: lambda,
        }
    }

    /// Whether the current run has settled (restarts) or converged.
    fn run_over(&self) -> bool {
        let axis = self.d.iter().copied().fold(0.0, f64::max);
        let spread = self.sigma * axis;
        let settled =
            self.opts.restarts && !self.polishing && spread < RESTART_SHRINK * self.sigma0;
        settled || spread < self.opts.tolerance
    }

    /// With restarts: replace a finished run by the next one (a random
    /// mean and twice the population, or the polishing run from the best
    /// point); `false` when the budget allows no further run.
    fn restart(&mut self, rng: &mut Rng) -> bool {
        let left = self.total.saturating_sub(self.used);
        let (mean, lambda, sigma, polish) = match &self.best {
            _ if self.polishing => return false,
            Some(b) if 4 * left <= self.total || left < 4 * 2 * self.lambda => {
                (b.u.clone(), self.lambda0, POLISH_SIGMA, true)
            }
            _ => (
                (0..self.n).map(|_| rng.f64()).collect(),
                2 * self.lambda,
                self.opts.sigma,
                false,
            ),
        };
        if left < lambda {
            return false;
        }
        let mut next = Cmaes::new(
            &mean,
            CmaesOptions {
                population: lambda,
                sigma,
                generations: left / lambda,
                ..self.opts
            },
        );
        next.best = self.best.take();
        next.used = self.used;
        next.total = self.total;
        next.polishing = polish;
        next.lambda0 = self.lambda0;
        *self = next;
        true
    }

    /// The current mean and step size.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// `B D z`.
    fn bdz(&self, z: &[f64]) -> Vec<f64> {
        let n = self.n;
        (0..n)
            .map(|i| (0..n).map(|k| self.b[i * n + k] * self.d[k] * z[k]).sum())
            .collect()
    }

    /// `C^(-1/2) y = B D⁻¹ Bᵀ y`.
    fn inv_sqrt(&self, y: &[f64]) -> Vec<f64> {
        let n = self.n;
        let bt: Vec<f64> = (0..n)
            .map(|k| (0..n).map(|i| self.b[i * n + k] * y[i]).sum::<f64>() / self.d[k])
            .collect();
        (0..n)
            .map(|i| (0..n).map(|k| self.b[i * n + k] * bt[k]).sum())
            .collect()
    }
}

/// Eigen-decomposition of the symmetric n×n matrix `a` (row-major) by
/// cyclic Jacobi sweeps: eigenvalues and eigenvectors (columns of `v`).
pub fn jacobi_eigen(a: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = a.to_vec();
    let mut v = vec![0.0; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _sweep in 0..60 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j] * a[i * n + j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

impl AskTell for Cmaes {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        let polish_due = !self.polishing && 4 * self.total.saturating_sub(self.used) <= self.total;
        if self.opts.restarts && (self.run_over() || polish_due) && !self.restart(rng) {
            self.total = self.used;
        }
        if self.done() {
            return vec![];
        }
        (0..self.lambda)
            .map(|_| {
                let z: Vec<f64> = (0..self.n).map(|_| gauss(rng)).collect();
                let y = self.bdz(&z);
                let mut x: Vec<f64> = self
                    .mean
                    .iter()
                    .zip(&y)
                    .map(|(m, y)| m + self.sigma * y)
                    .collect();
                super::clamp01(&mut x);
                x
            })
            .collect()
    }

    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        let n = self.n;
        self.used += batch.len();
        let mut order: Vec<usize> = (0..batch.len()).collect();
        order.sort_by(|&a, &b| losses[a].total_cmp(&losses[b]).then(a.cmp(&b)));
        if let Some(&i) = order.first() {
            let better = self.best.as_ref().is_none_or(|b| losses[i] < b.loss);
            if losses[i].is_finite() && better {
                self.best = Some(Scored {
                    u: batch[i].clone(),
                    loss: losses[i],
                });
            }
        }
        let old = self.mean.clone();
        let ys: Vec<Vec<f64>> = order
            .iter()
            .take(self.weights.len())
            .map(|&i| {
                batch[i]
                    .iter()
                    .zip(&old)
                    .map(|(x, m)| (x - m) / self.sigma)
                    .collect()
            })
            .collect();
        let mut yw = vec![0.0; n];
        for (w, y) in self.weights.iter().zip(&ys) {
            for k in 0..n {
                yw[k] += w * y[k];
            }
        }
        for k in 0..n {
            self.mean[k] = old[k] + self.sigma * yw[k];
        }
        super::clamp01(&mut self.mean);
        let cy = self.inv_sqrt(&yw);
        let a = (self.cs * (2.0 - self.cs) * self.mueff).sqrt();
        for k in 0..n {
            self.ps[k] = (1.0 - self.cs) * self.ps[k] + a * cy[k];
        }
        let ps_norm = self.ps.iter().map(|v| v * v).sum::<f64>().sqrt();
        let g = (self.generation + 1) as f64;
        let hsig = ps_norm / (1.0 - libm::pow(1.0 - self.cs, 2.0 * g)).sqrt() / self.chi_n
            < 1.4 + 2.0 / (n as f64 + 1.0);
        let hs = if hsig { 1.0 } else { 0.0 };
        let ac = (self.cc * (2.0 - self.cc) * self.mueff).sqrt();
        for k in 0..n {
            self.pc[k] = (1.0 - self.cc) * self.pc[k] + hs * ac * yw[k];
        }
        let keep = 1.0 - self.c1 - self.cmu;
        for i in 0..n {
            for j in 0..n {
                let mut rank_mu = 0.0;
                for (w, y) in self.weights.iter().zip(&ys) {
                    rank_mu += w * y[i] * y[j];
                }
                let c = self.c[i * n + j];
                self.c[i * n + j] = keep * c
                    + self.c1
                        * (self.pc[i] * self.pc[j] + (1.0 - hs) * self.cc * (2.0 - self.cc) * c)
                    + self.cmu * rank_mu;
            }
        }
        self.sigma *= libm::exp(((self.cs / self.damps) * (ps_norm / self.chi_n - 1.0)).min(1.0));
        self.sigma = self.sigma.clamp(1e-300, 1.0);
        let (vals, vecs) = jacobi_eigen(&self.c, n);
        self.d = vals.iter().map(|v| v.max(1e-300).sqrt()).collect();
        self.b = vecs;
        self.generation += 1;
    }

    fn done(&self) -> bool {
        if self.opts.restarts {
            // Another run may follow a finished one (see `ask`).
            return self.used + self.lambda > self.total;
        }
        self.generation >= self.opts.generations || self.run_over()
    }

    fn best(&self) -> Option<&Scored> {
        self.best.as_ref()
    }

    fn budget(&self) -> usize {
        self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(f: impl Fn(&[f64]) -> f64, start: &[f64], opts: CmaesOptions, seed: u64) -> Scored {
        let mut es = Cmaes::new(start, opts);
        let mut rng = Rng::new(seed);
        loop {
            let batch = es.ask(&mut rng);
            if batch.is_empty() {
                break;
            }
            let losses: Vec<f64> = batch.iter().map(|x| f(x)).collect();
            es.tell(batch, &losses);
        }
        es.best().unwrap().clone()
    }

    #[test]
    fn minimises_a_rotated_ellipsoid() {
        let target = [0.3, 0.7, 0.45, 0.6];
        let f = |x: &[f64]| {
            let d: Vec<f64> = x.iter().zip(&target).map(|(a, b)| a - b).collect();
            let r = d[0] + d[1];
            let s = d[0] - d[1];
            r * r + 100.0 * s * s + 10.0 * d[2] * d[2] + 1000.0 * d[3] * d[3]
        };
        let best = run(
            f,
            &[0.9, 0.1, 0.1, 0.1],
            CmaesOptions {
                generations: 300,
                ..Default::default()
            },
            1,
        );
        assert!(best.loss < 1e-12, "{best:?}");
        for (a, b) in best.u.iter().zip(&target) {
            assert!((a - b).abs() < 1e-5, "{best:?}");
        }
        // Same seed, same run.
        let again = run(
            f,
            &[0.9, 0.1, 0.1, 0.1],
            CmaesOptions {
                generations: 300,
                ..Default::default()
            },
            1,
        );
        assert_eq!(best, again);
    }

    /// Runs with restarts evaluate at most their budget and end empty-handed
    /// only when `done` says so.
    fn run_counted(f: impl Fn(&[f64]) -> f64, opts: CmaesOptions, seed: u64) -> (Scored, usize) {
        let mut es = Cmaes::new(&[0.8], opts);
        let mut rng = Rng::new(seed);
        let mut evals = 0;
        loop {
            let batch = es.ask(&mut rng);
            if batch.is_empty() {
                assert!(es.done());
                break;
            }
            evals += batch.len();
            let losses: Vec<f64> = batch.iter().map(|x| f(x)).collect();
            es.tell(batch, &losses);
        }
        assert!(
            evals <= es.budget() && es.budget() <= 20 * 75,
            "{evals} {}",
            es.budget()
        );
        (es.best().unwrap().clone(), evals)
    }

    #[test]
    fn restarts_find_a_narrow_basin_a_single_run_misses() {
        // A wide bowl around the start (0.8) and a deeper, narrow well at
        // 0.2: the gyroid frequency's landscape in one dimension.
        let f = |x: &[f64]| {
            let w = (x[0] - 0.2) / 0.01;
            (x[0] - 0.8).powi(2) - 10.0 * libm::exp(-w * w)
        };
        let opts = |restarts| CmaesOptions {
            population: 20,
            sigma: 0.3,
            generations: 75,
            tolerance: 1e-10,
            restarts,
        };
        let mut single_missed = 0;
        for seed in 1..=6 {
            let (best, _) = run_counted(f, opts(true), seed);
            assert!((best.u[0] - 0.2).abs() < 1e-3, "seed {seed}: {best:?}");
            assert_eq!(
                run_counted(f, opts(true), seed).0,
                best,
                "same seed, same run"
            );
            let (single, _) = run_counted(f, opts(false), seed);
            if (single.u[0] - 0.2).abs() > 0.05 {
                single_missed += 1;
            }
        }
        assert!(
            single_missed >= 3,
            "one run found the well {} times in 6",
            6 - single_missed
        );
    }

    #[test]
    fn jacobi_diagonalises() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0];
        let (vals, v) = jacobi_eigen(&a, 3);
        for k in 0..3 {
            // A v_k = λ_k v_k
            for i in 0..3 {
                let av: f64 = (0..3).map(|j| a[i * 3 + j] * v[j * 3 + k]).sum();
                assert!((av - vals[k] * v[i * 3 + k]).abs() < 1e-10);
            }
        }
    }
}

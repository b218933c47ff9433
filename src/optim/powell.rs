//! Powell's conjugate direction method (Powell 1964; the "modified" form
//! of Numerical Recipes §10.7 and SciPy) behind the ask/tell interface,
//! bounded to the box `[0, 1]^d`, derivative-free.
//!
//! Each cycle minimises along every direction in turn (starting with the
//! axes), then tries the cycle's net displacement as a new direction and,
//! when it pays off (Powell's test), replaces the direction of largest
//! decrease with it. A line minimisation asks for one point per probe: it
//! brackets a minimum from the current point (growing steps by the golden
//! ratio, clipped to the box) and narrows the bracket by golden sections.
//! A search has converged when a cycle gains less than a relative `1e-10`;
//! while budget remains, it then restarts from a random point with the axes
//! (a local method made multi-start; the best point over all starts is the
//! answer). It stops when the evaluation budget is spent.
#![allow(clippy::needless_range_loop)] // small vector code reads best indexed

use super::{AskTell, Scored};
use crate::core::rng::Rng;

const GOLD: f64 = 0.381_966_011_250_105_1;
const GROW: f64 = 1.618_033_988_749_895;
/// A line search stops when its bracket is narrower than this (in units
/// of the unit-length direction) or after this many probes.
const LINE_TOL: f64 = 1e-7;
const LINE_PROBES: usize = 40;
/// First bracketing step along a direction.
const FIRST_STEP: f64 = 0.05;

/// One line minimisation along `dir` from `origin` (`t = 0`, loss `f0`).
#[derive(Debug, Clone)]
struct Line {
    origin: Vec<f64>,
    dir: Vec<f64>,
    /// Feasible range of t (the box).
    lo: f64,
    hi: f64,
    /// Probes so far (t, loss), sorted by t.
    probes: Vec<(f64, f64)>,
    /// The bracket width at which the search stops.
    tol: f64,
}

impl Line {
    fn new(origin: Vec<f64>, dir: Vec<f64>, f0: f64, tol: f64) -> Line {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (x, d) in origin.iter().zip(&dir) {
            if d.abs() > 1e-15 {
                let (a, b) = ((0.0 - x) / d, (1.0 - x) / d);
                lo = lo.max(a.min(b));
                hi = hi.min(a.max(b));
            }
        }
        if !lo.is_finite() || !hi.is_finite() {
            (lo, hi) = (0.0, 0.0);
        }
        Line {
            origin,
            dir,
            lo: lo.min(0.0),
            hi: hi.max(0.0),
            probes: vec![(0.0, f0)],
            tol,
        }
    }

    fn point(&self, t: f64) -> Vec<f64> {
        self.origin
            .iter()
            .zip(&self.dir)
            .map(|(x, d)| (x + t * d).clamp(0.0, 1.0))
            .collect()
    }

    /// Index of the lowest probe (the first of equals).
    fn best(&self) -> usize {
        let mut b = 0;
        for (i, p) in self.probes.iter().enumerate() {
            if p.1 < self.probes[b].1 {
                b = i;
            }
        }
        b
    }

    /// The next t to probe, or `None` when the line is done.
    fn next(&self) -> Option<f64> {
        if self.probes.len() >= LINE_PROBES {
            return None;
        }
        let b = self.best();
        let tb = self.probes[b].0;
        let left = (b > 0).then(|| self.probes[b - 1].0);
        let right = self.probes.get(b + 1).map(|p| p.0);
        let at_lo = tb <= self.lo;
        let at_hi = tb >= self.hi;
        // Bracketing: grow away from the best on a side with no probe yet.
        if right.is_none() && !at_hi {
            let step = left.map_or(FIRST_STEP, |l| (GROW * (tb - l)).max(FIRST_STEP));
            return Some((tb + step).min(self.hi));
        }
        if left.is_none() && !at_lo {
            let step = right.map_or(FIRST_STEP, |r| (GROW * (r - tb)).max(FIRST_STEP));
            return Some((tb - step).max(self.lo));
        }
        // Golden section of the larger side of the bracket.
        let a = left.unwrap_or(tb);
        let c = right.unwrap_or(tb);
        if c - a < self.tol {
            return None;
        }
        let t = if c - tb > tb - a {
            tb + GOLD * (c - tb)
        } else {
            tb - GOLD * (tb - a)
        };
        // Too close to an existing probe to tell anything new.
        if (t - tb).abs() < self.tol * 0.25 {
            return None;
        }
        Some(t)
    }

    fn tell(&mut self, t: f64, f: f64) {
        let i = self.probes.partition_point(|p| p.0 < t);
        if self.probes.get(i).is_some_and(|p| p.0 == t) {
            return;
        }
        self.probes.insert(i, (t, f));
    }

    /// The lowest probe: (t, loss).
    fn result(&self) -> (f64, f64) {
        self.probes[self.best()]
    }
}

#[derive(Debug, Clone)]
enum Stage {
    /// Evaluate the start point.
    Start,
    /// Minimising along direction `i` of the cycle.
    Along(usize),
    /// Evaluate the extrapolated point `2x − x_start`.
    Extrapolate,
    /// Minimising along the cycle's net displacement.
    NewDirection,
    /// Converged: start again from a random point.
    Restart,
    Finished,
}

/// Powell's method from a start point, within an evaluation budget.
#[derive(Debug, Clone)]
pub struct Powell {
    dim: usize,
    budget: usize,
    used: usize,
    x: Vec<f64>,
    fx: f64,
    dirs: Vec<Vec<f64>>,
    /// Start of the current cycle and its loss.
    x_start: Vec<f64>,
    f_start: f64,
    /// Largest decrease along one direction this cycle, and which.
    big: f64,
    big_i: usize,
    line: Option<Line>,
    /// The extrapolated point's loss.
    stage: Stage,
    best: Option<Scored>,
    /// Cycles run and restarts made.
    pub cycles: usize,
    pub restarts: usize,
    /// A line search stops when its bracket is narrower than this
    /// (normalised units; [`Powell::with_line_tolerance`]).
    line_tol: f64,
}

fn axes(dim: usize) -> Vec<Vec<f64>> {
    (0..dim)
        .map(|i| (0..dim).map(|k| if k == i { 1.0 } else { 0.0 }).collect())
        .collect()
}

impl Powell {
    /// A search from `start` (normalised coordinates) with `budget` evaluations.
    pub fn new(start: &[f64], budget: usize) -> Powell {
        let dim = start.len().max(1);
        let mut x = start.to_vec();
        x.resize(dim, 0.5);
        super::clamp01(&mut x);
        Powell {
            dim,
            budget,
            used: 0,
            x: x.clone(),
            fx: f64::INFINITY,
            dirs: axes(dim),
            x_start: x,
            f_start: f64::INFINITY,
            big: 0.0,
            big_i: 0,
            line: None,
            stage: Stage::Start,
            best: None,
            cycles: 0,
            restarts: 0,
            line_tol: LINE_TOL,
        }
    }

    /// Stop each line search at a bracket of width `tol` (default 1e-7):
    /// a coarse loss (a first stage) gains nothing from polishing its
    /// minima, and looser lines leave budget for more restarts.
    pub fn with_line_tolerance(mut self, tol: f64) -> Powell {
        if tol.is_finite() && tol > 0.0 {
            self.line_tol = tol;
        }
        self
    }

    fn start_line(&mut self, dir: Vec<f64>) {
        self.line = Some(Line::new(self.x.clone(), dir, self.fx, self.line_tol));
    }

    fn begin_cycle(&mut self) {
        self.x_start = self.x.clone();
        self.f_start = self.fx;
        self.big = 0.0;
        self.big_i = 0;
        self.stage = Stage::Along(0);
        self.start_line(self.dirs[0].clone());
    }

    /// Finish the current line: move to its best point.
    fn finish_line(&mut self) -> f64 {
        let line = self.line.take().expect("a line in progress");
        let (t, f) = line.result();
        let before = self.fx;
        if f < self.fx {
            self.x = line.point(t);
            self.fx = f;
        }
        before - self.fx
    }

    /// Advance the state machine until it needs a point evaluated (returned)
    /// or has finished (`None`).
    fn advance(&mut self, rng: &mut Rng) -> Option<Vec<f64>> {
        loop {
            match self.stage {
                Stage::Start => return Some(self.x.clone()),
                Stage::Restart => {
                    self.restarts += 1;
                    self.x = (0..self.dim).map(|_| rng.f64()).collect();
                    self.fx = f64::INFINITY;
                    self.dirs = axes(self.dim);
                    self.stage = Stage::Start;
                }
                Stage::Finished => return None,
                Stage::Extrapolate => {
                    let p: Vec<f64> = self
                        .x
                        .iter()
                        .zip(&self.x_start)
                        .map(|(x, s)| (2.0 * x - s).clamp(0.0, 1.0))
                        .collect();
                    return Some(p);
                }
                Stage::Along(i) => {
                    let line = self.line.as_ref().expect("a line in progress");
                    if let Some(t) = line.next() {
                        return Some(line.point(t));
                    }
                    let gain = self.finish_line();
                    if gain > self.big {
                        self.big = gain;
                        self.big_i = i;
                    }
                    if i + 1 < self.dim {
                        self.stage = Stage::Along(i + 1);
                        self.start_line(self.dirs[i + 1].clone());
                    } else {
                        self.end_cycle();
                    }
                }
                Stage::NewDirection => {
                    let line = self.line.as_ref().expect("a line in progress");
                    if let Some(t) = line.next() {
                        return Some(line.point(t));
                    }
                    let dir = line.dir.clone();
                    self.finish_line();
                    // Replace the direction of largest decrease (NR keeps
                    // the order by moving the last one into its place).
                    let last = self.dim - 1;
                    self.dirs[self.big_i] = self.dirs[last].clone();
                    self.dirs[last] = dir;
                    self.begin_cycle();
                }
            }
        }
    }

    /// After every direction of a cycle: stop, or try the net displacement.
    fn end_cycle(&mut self) {
        self.cycles += 1;
        let gain = self.f_start - self.fx;
        let scale = self.f_start.abs() + self.fx.abs();
        // Converged (or no finite gain to measure: NaN compares as none).
        let tol = 1e-10 * scale + 1e-20;
        if (2.0 * gain).partial_cmp(&tol) != Some(std::cmp::Ordering::Greater) {
            self.stage = Stage::Restart;
            return;
        }
        self.stage = Stage::Extrapolate;
    }

    fn after_extrapolate(&mut self, fe: f64) {
        let (f0, f1, big) = (self.f_start, self.fx, self.big);
        let d: Vec<f64> = self
            .x
            .iter()
            .zip(&self.x_start)
            .map(|(x, s)| x - s)
            .collect();
        let norm = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let worth = fe < f0
            && 2.0 * (f0 - 2.0 * f1 + fe) * (f0 - f1 - big).powi(2) < big * (f0 - fe).powi(2);
        if fe < self.fx {
            // Keep the better point whatever the test says.
            self.x = self
                .x
                .iter()
                .zip(&self.x_start)
                .map(|(x, s)| (2.0 * x - s).clamp(0.0, 1.0))
                .collect();
            self.fx = fe;
        }
        if worth && norm > 1e-12 {
            let dir: Vec<f64> = d.iter().map(|v| v / norm).collect();
            self.stage = Stage::NewDirection;
            self.start_line(dir);
        } else {
            self.begin_cycle();
        }
    }
}

impl AskTell for Powell {
    fn ask(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        if self.used >= self.budget {
            self.stage = Stage::Finished;
            return vec![];
        }
        self.advance(rng).map_or_else(Vec::new, |p| vec![p])
    }

    fn tell(&mut self, batch: Vec<Vec<f64>>, losses: &[f64]) {
        let (Some(p), Some(&f)) = (batch.into_iter().next(), losses.first()) else {
            return;
        };
        self.used += 1;
        let f = if f.is_nan() { f64::INFINITY } else { f };
        if self.best.as_ref().is_none_or(|b| f < b.loss) {
            self.best = Some(Scored {
                u: p.clone(),
                loss: f,
            });
        }
        match self.stage {
            Stage::Start => {
                self.fx = f;
                self.begin_cycle();
            }
            Stage::Extrapolate => self.after_extrapolate(f),
            Stage::Along(_) | Stage::NewDirection => {
                let line = self.line.as_mut().expect("a line in progress");
                // The probe's t along the line (recover it from the point).
                let t = line
                    .dir
                    .iter()
                    .zip(p.iter().zip(&line.origin))
                    .filter(|(d, _)| d.abs() > 1e-12)
                    .map(|(d, (x, o))| (x - o) / d)
                    .next();
                if let Some(t) = line.next().or(t) {
                    line.tell(t, f);
                }
            }
            Stage::Restart | Stage::Finished => {}
        }
        if self.used >= self.budget {
            self.stage = Stage::Finished;
        }
    }

    fn done(&self) -> bool {
        matches!(self.stage, Stage::Finished) || self.used >= self.budget
    }

    fn best(&self) -> Option<&Scored> {
        self.best.as_ref()
    }

    fn budget(&self) -> usize {
        self.budget
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(f: impl Fn(&[f64]) -> f64, start: &[f64], budget: usize) -> (Powell, usize) {
        let mut p = Powell::new(start, budget);
        let mut rng = Rng::new(1);
        let mut n = 0;
        loop {
            let b = p.ask(&mut rng);
            if b.is_empty() {
                break;
            }
            assert!(b[0].iter().all(|v| (0.0..=1.0).contains(v)));
            let l: Vec<f64> = b.iter().map(|u| f(u)).collect();
            n += b.len();
            p.tell(b, &l);
        }
        assert!(p.done());
        (p, n)
    }

    #[test]
    fn powell_minimises_a_rotated_valley() {
        // A narrow valley along (1, 1): coordinate search alone crawls.
        let f = |u: &[f64]| {
            let (a, b) = (u[0] - 0.3, u[1] - 0.6);
            (a + b).powi(2) + 100.0 * (a - b).powi(2)
        };
        let (p, n) = run(f, &[0.9, 0.1], 2000);
        let best = p.best().unwrap();
        assert!(best.loss < 1e-10, "loss {} after {n}", best.loss);
        assert_eq!(n, 2000, "restarts use the whole budget");
        assert!(p.restarts >= 1 && p.cycles >= 2);
    }

    #[test]
    fn powell_stops_at_a_bound_and_keeps_the_budget() {
        // Minimum outside the box at u0 = −0.5: the answer is the face u0 = 0.
        let f = |u: &[f64]| (u[0] + 0.5).powi(2) + (u[1] - 0.25).powi(2);
        let (p, n) = run(f, &[0.5, 0.5], 500);
        let best = p.best().unwrap();
        assert!(
            best.u[0] < 1e-9 && (best.u[1] - 0.25).abs() < 1e-5,
            "{:?}",
            best.u
        );
        assert!(n <= 500);
        let (_, n) = run(f, &[0.5, 0.5], 7);
        assert_eq!(n, 7);
    }

    #[test]
    fn powell_survives_invalid_points() {
        let f = |u: &[f64]| {
            if u[0] > 0.7 {
                f64::NAN
            } else {
                (u[0] - 0.6).powi(2)
            }
        };
        let (p, _) = run(f, &[0.2], 300);
        let best = p.best().unwrap();
        assert!((best.u[0] - 0.6).abs() < 1e-4, "{:?}", best.u);
    }
}

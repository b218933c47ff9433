//! The recorded computation of a pattern program (paper §3 "Differentiable
//! Vector Patterns": the pattern is differentiated end to end).
//!
//! A [`Tape`] is a straight-line list of scalar operations whose inputs are
//! the program's float parameters. Recording folds everything that does not
//! depend on a float parameter (loop counters, integer parameters, literals)
//! into constants, so the tape holds only the parameter-dependent arithmetic
//! plus the constants that shapes read. Replaying it forward gives every
//! shape field; [`Tape::backward`] is reverse-mode differentiation.
//!
//! Transcendental functions come from the `libm` crate, not `f64`'s methods
//! (which call the platform's C library natively): the same inputs then give
//! the same bits natively and in wasm, so seeded fits agree everywhere.

/// One tape operation. Operands are indices of earlier nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Op {
    /// A constant; its value is fixed at record time.
    Const,
    /// Float parameter number `k`.
    Param(u32),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Sin(u32),
    Cos(u32),
    Tan(u32),
    Atan(u32),
    Atan2(u32, u32),
    /// `sqrt(max(x, 0))`; derivative 0 where x ≤ 0.
    Sqrt(u32),
    Abs(u32),
    Exp(u32),
    /// Natural logarithm.
    Ln(u32),
    Pow(u32, u32),
    Min(u32, u32),
    Max(u32, u32),
    /// `a - b·floor(a/b)` (result has the sign of b).
    Mod(u32, u32),
    /// Piecewise-constant functions (floor, ceil, round, comparisons ...):
    /// the value is recomputed, the derivative is zero.
    Step(StepFn, u32, u32),
    /// `if c != 0 { a } else { b }`, chosen per replay.
    Select(u32, u32, u32),
}

/// The piecewise-constant functions a tape can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepFn {
    Floor,
    Ceil,
    Round,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
    Not,
}

impl StepFn {
    /// Evaluate on plain numbers (booleans are 0 and 1).
    pub fn apply(self, a: f64, b: f64) -> f64 {
        let t = |c: bool| if c { 1.0 } else { 0.0 };
        match self {
            StepFn::Floor => a.floor(),
            StepFn::Ceil => a.ceil(),
            StepFn::Round => a.round(),
            StepFn::Lt => t(a < b),
            StepFn::Le => t(a <= b),
            StepFn::Gt => t(a > b),
            StepFn::Ge => t(a >= b),
            StepFn::Eq => t(a == b),
            StepFn::Ne => t(a != b),
            StepFn::And => t(a != 0.0 && b != 0.0),
            StepFn::Or => t(a != 0.0 || b != 0.0),
            StepFn::Not => t(a == 0.0),
        }
    }
}

/// Evaluate a binary/unary op on plain numbers. Shared by constant folding
/// at record time and by [`Tape::forward`], so both agree bit for bit.
pub fn apply(op: Op, v: &[f64]) -> f64 {
    let g = |i: u32| v[i as usize];
    match op {
        Op::Const | Op::Param(_) => unreachable!("leaf op has no operands"),
        Op::Add(a, b) => g(a) + g(b),
        Op::Sub(a, b) => g(a) - g(b),
        Op::Mul(a, b) => g(a) * g(b),
        Op::Div(a, b) => g(a) / g(b),
        Op::Neg(a) => -g(a),
        Op::Sin(a) => libm::sin(g(a)),
        Op::Cos(a) => libm::cos(g(a)),
        Op::Tan(a) => libm::tan(g(a)),
        Op::Atan(a) => libm::atan(g(a)),
        Op::Atan2(a, b) => libm::atan2(g(a), g(b)),
        Op::Sqrt(a) => g(a).max(0.0).sqrt(),
        Op::Abs(a) => g(a).abs(),
        Op::Exp(a) => libm::exp(g(a)),
        Op::Ln(a) => libm::log(g(a)),
        Op::Pow(a, b) => libm::pow(g(a), g(b)),
        Op::Min(a, b) => g(a).min(g(b)),
        Op::Max(a, b) => g(a).max(g(b)),
        Op::Mod(a, b) => {
            let (x, y) = (g(a), g(b));
            x - y * (x / y).floor()
        }
        Op::Step(f, a, b) => f.apply(g(a), g(b)),
        Op::Select(c, a, b) => {
            if g(c) != 0.0 {
                g(a)
            } else {
                g(b)
            }
        }
    }
}

/// Smallest and largest of some values (NaN counts as unbounded).
fn hull(v: &[f64]) -> (f64, f64) {
    if v.iter().any(|x| x.is_nan()) {
        return (f64::NEG_INFINITY, f64::INFINITY);
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}

/// `sin` over `[lo, hi]`: the ends, and ±1 where a peak lies inside.
fn sin_interval((lo, hi): (f64, f64)) -> (f64, f64) {
    use std::f64::consts::{FRAC_PI_2, TAU};
    if !(hi - lo).is_finite() || hi - lo >= TAU {
        return (-1.0, 1.0);
    }
    let (mut a, mut b) = hull(&[libm::sin(lo), libm::sin(hi)]);
    // Peaks at π/2 + 2kπ, troughs at -π/2 + 2kπ.
    if ((lo - FRAC_PI_2) / TAU).ceil() <= ((hi - FRAC_PI_2) / TAU).floor() {
        b = 1.0;
    }
    if ((lo + FRAC_PI_2) / TAU).ceil() <= ((hi + FRAC_PI_2) / TAU).floor() {
        a = -1.0;
    }
    // libm's rounding may put an end a hair past the exact value.
    (a - 1e-12, b + 1e-12)
}

/// Interval extension of one non-leaf op over its operands' bounds `b`.
fn interval(op: Op, b: &[(f64, f64)]) -> (f64, f64) {
    const ALL: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);
    let g = |i: u32| b[i as usize];
    let mono = |f: fn(f64) -> f64, (lo, hi): (f64, f64)| hull(&[f(lo), f(hi)]);
    match op {
        Op::Const | Op::Param(_) => unreachable!("leaf op has no operands"),
        Op::Add(x, y) => (g(x).0 + g(y).0, g(x).1 + g(y).1),
        Op::Sub(x, y) => (g(x).0 - g(y).1, g(x).1 - g(y).0),
        Op::Mul(x, y) => {
            let (a, c) = (g(x), g(y));
            // 0·inf is NaN: an unbounded operand times an interval holding 0.
            hull(&[a.0 * c.0, a.0 * c.1, a.1 * c.0, a.1 * c.1])
        }
        Op::Div(x, y) => {
            let (a, c) = (g(x), g(y));
            if c.0 <= 0.0 && c.1 >= 0.0 {
                ALL
            } else {
                hull(&[a.0 / c.0, a.0 / c.1, a.1 / c.0, a.1 / c.1])
            }
        }
        Op::Neg(x) => (-g(x).1, -g(x).0),
        Op::Sin(x) => sin_interval(g(x)),
        Op::Cos(x) => sin_interval((
            g(x).0 + std::f64::consts::FRAC_PI_2,
            g(x).1 + std::f64::consts::FRAC_PI_2,
        )),
        Op::Tan(x) => {
            let (lo, hi) = g(x);
            use std::f64::consts::{FRAC_PI_2, PI};
            // An asymptote at π/2 + kπ inside: unbounded.
            if !(hi - lo).is_finite()
                || ((lo - FRAC_PI_2) / PI).ceil() <= ((hi - FRAC_PI_2) / PI).floor()
            {
                ALL
            } else {
                mono(libm::tan, g(x))
            }
        }
        Op::Atan(x) => mono(libm::atan, g(x)),
        Op::Atan2(..) => (-std::f64::consts::PI, std::f64::consts::PI),
        Op::Sqrt(x) => mono(|v| v.max(0.0).sqrt(), g(x)),
        Op::Abs(x) => {
            let (lo, hi) = g(x);
            if lo >= 0.0 {
                (lo, hi)
            } else if hi <= 0.0 {
                (-hi, -lo)
            } else {
                (0.0, (-lo).max(hi))
            }
        }
        Op::Exp(x) => mono(libm::exp, g(x)),
        Op::Ln(x) => {
            let (lo, hi) = g(x);
            if hi <= 0.0 {
                ALL
            } else {
                (
                    if lo <= 0.0 {
                        f64::NEG_INFINITY
                    } else {
                        libm::log(lo)
                    },
                    libm::log(hi),
                )
            }
        }
        Op::Pow(x, y) => {
            let (a, e) = (g(x), g(y));
            let corners = [
                libm::pow(a.0, e.0),
                libm::pow(a.0, e.1),
                libm::pow(a.1, e.0),
                libm::pow(a.1, e.1),
            ];
            if a.0 > 0.0 {
                // Monotone in each argument for a positive base.
                hull(&corners)
            } else if e.0 == e.1 && e.0.fract() == 0.0 && e.0 >= 0.0 {
                // An integer power: the ends and 0 (if the base crosses it).
                let (lo, hi) = hull(&corners);
                if a.0 <= 0.0 && a.1 >= 0.0 {
                    (lo.min(0.0), hi.max(0.0))
                } else {
                    (lo, hi)
                }
            } else {
                ALL
            }
        }
        Op::Min(x, y) => (g(x).0.min(g(y).0), g(x).1.min(g(y).1)),
        Op::Max(x, y) => (g(x).0.max(g(y).0), g(x).1.max(g(y).1)),
        Op::Mod(_, y) => {
            let (lo, hi) = g(y);
            if lo > 0.0 {
                (0.0, hi)
            } else if hi < 0.0 {
                (lo, 0.0)
            } else {
                ALL
            }
        }
        Op::Step(f, x, _) => match f {
            StepFn::Floor => mono(f64::floor, g(x)),
            StepFn::Ceil => mono(f64::ceil, g(x)),
            StepFn::Round => mono(f64::round, g(x)),
            _ => (0.0, 1.0),
        },
        Op::Select(c, x, y) => {
            let cb = g(c);
            if cb.0 == cb.1 && cb.0 != 0.0 {
                g(x)
            } else if cb == (0.0, 0.0) {
                g(y)
            } else {
                (g(x).0.min(g(y).0), g(x).1.max(g(y).1))
            }
        }
    }
}

/// A recorded straight-line program over the float parameters.
#[derive(Debug, Clone, Default)]
pub struct Tape {
    ops: Vec<Op>,
    /// Values at record time; constants keep theirs on replay.
    init: Vec<f64>,
}

impl Tape {
    /// An empty tape.
    pub fn new() -> Self {
        Self::default()
    }

    /// Append a node with its record-time value; returns its index.
    pub fn push(&mut self, op: Op, value: f64) -> u32 {
        self.ops.push(op);
        self.init.push(value);
        (self.ops.len() - 1) as u32
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// True when the tape has no nodes.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Number of non-constant nodes (the work of one replay).
    pub fn active_len(&self) -> usize {
        self.ops.iter().filter(|o| !matches!(o, Op::Const)).count()
    }

    /// The record-time value of node `i`.
    pub fn init_value(&self, i: u32) -> f64 {
        self.init[i as usize]
    }

    /// Drop every node from `len` on (undoing a trial recording).
    pub fn truncate(&mut self, len: usize) {
        self.ops.truncate(len);
        self.init.truncate(len);
    }

    /// Interval bounds of every node when each float parameter `k` may take
    /// any value in `ranges[k]` (interval arithmetic: every bound holds, but
    /// correlated operands make it wider than the exact range). A node that
    /// cannot be bounded gets `(-inf, inf)`.
    pub fn bounds(&self, ranges: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let mut b: Vec<(f64, f64)> = Vec::with_capacity(self.ops.len());
        for (i, &op) in self.ops.iter().enumerate() {
            let r = match op {
                Op::Const => (self.init[i], self.init[i]),
                Op::Param(k) => ranges[k as usize],
                _ => interval(op, &b),
            };
            let r = if r.0.is_nan() || r.1.is_nan() || r.0 > r.1 {
                (f64::NEG_INFINITY, f64::INFINITY)
            } else {
                r
            };
            b.push(r);
        }
        b
    }

    /// Replay with `params` (one value per float parameter); `vals` is
    /// resized to [`Tape::len`] and receives every node's value.
    pub fn forward(&self, params: &[f64], vals: &mut Vec<f64>) {
        vals.clear();
        vals.extend_from_slice(&self.init);
        for (i, &op) in self.ops.iter().enumerate() {
            vals[i] = match op {
                Op::Const => continue,
                Op::Param(k) => params[k as usize],
                _ => apply(op, vals),
            };
        }
    }

    /// Reverse sweep. `adj` holds dL/d(node) for the nodes shapes read (and
    /// is overwritten with all adjoints); `grad` (one per parameter) is
    /// accumulated into.
    pub fn backward(&self, vals: &[f64], adj: &mut [f64], grad: &mut [f64]) {
        for i in (0..self.ops.len()).rev() {
            let a = adj[i];
            if a == 0.0 {
                continue;
            }
            let v = |j: u32| vals[j as usize];
            let mut add = |j: u32, d: f64| {
                let d = a * d;
                if d.is_finite() {
                    adj[j as usize] += d;
                }
            };
            match self.ops[i] {
                Op::Const | Op::Step(..) => {}
                Op::Param(k) => grad[k as usize] += a,
                Op::Add(x, y) => {
                    add(x, 1.0);
                    add(y, 1.0);
                }
                Op::Sub(x, y) => {
                    add(x, 1.0);
                    add(y, -1.0);
                }
                Op::Mul(x, y) => {
                    add(x, v(y));
                    add(y, v(x));
                }
                Op::Div(x, y) => {
                    add(x, 1.0 / v(y));
                    add(y, -v(x) / (v(y) * v(y)));
                }
                Op::Neg(x) => add(x, -1.0),
                Op::Sin(x) => add(x, libm::cos(v(x))),
                Op::Cos(x) => add(x, -libm::sin(v(x))),
                Op::Tan(x) => {
                    let c = libm::cos(v(x));
                    add(x, 1.0 / (c * c))
                }
                Op::Atan(x) => add(x, 1.0 / (1.0 + v(x) * v(x))),
                Op::Atan2(y, x) => {
                    let r2 = v(x) * v(x) + v(y) * v(y);
                    if r2 > 0.0 {
                        add(y, v(x) / r2);
                        add(x, -v(y) / r2);
                    }
                }
                Op::Sqrt(x) => {
                    if v(x) > 0.0 {
                        add(x, 0.5 / vals[i])
                    }
                }
                Op::Abs(x) => add(x, if v(x) >= 0.0 { 1.0 } else { -1.0 }),
                Op::Exp(x) => add(x, vals[i]),
                Op::Ln(x) => add(x, 1.0 / v(x)),
                Op::Pow(x, y) => {
                    let (b, e) = (v(x), v(y));
                    add(x, e * libm::pow(b, e - 1.0));
                    if b > 0.0 {
                        add(y, vals[i] * libm::log(b));
                    }
                }
                Op::Min(x, y) => {
                    if v(x) <= v(y) {
                        add(x, 1.0)
                    } else {
                        add(y, 1.0)
                    }
                }
                Op::Max(x, y) => {
                    if v(x) >= v(y) {
                        add(x, 1.0)
                    } else {
                        add(y, 1.0)
                    }
                }
                Op::Mod(x, y) => {
                    add(x, 1.0);
                    add(y, -(v(x) / v(y)).floor());
                }
                Op::Select(c, x, y) => {
                    if v(c) != 0.0 {
                        add(x, 1.0)
                    } else {
                        add(y, 1.0)
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_and_backward_match_finite_differences() {
        // f(p0, p1) = sin(p0) * p1 / (1 + p0^2) + max(p0, p1) + atan2(p1, p0)
        let mut t = Tape::new();
        let p0 = t.push(Op::Param(0), 0.0);
        let p1 = t.push(Op::Param(1), 0.0);
        let one = t.push(Op::Const, 1.0);
        let s = t.push(Op::Sin(p0), 0.0);
        let m = t.push(Op::Mul(s, p1), 0.0);
        let q = t.push(Op::Mul(p0, p0), 0.0);
        let d = t.push(Op::Add(one, q), 0.0);
        let f1 = t.push(Op::Div(m, d), 0.0);
        let mx = t.push(Op::Max(p0, p1), 0.0);
        let at = t.push(Op::Atan2(p1, p0), 0.0);
        let f2 = t.push(Op::Add(f1, mx), 0.0);
        let f = t.push(Op::Add(f2, at), 0.0);
        let eval = |p: &[f64]| {
            let mut v = vec![];
            t.forward(p, &mut v);
            v[f as usize]
        };
        let p = [0.7, 0.3];
        let mut vals = vec![];
        t.forward(&p, &mut vals);
        let mut adj = vec![0.0; t.len()];
        adj[f as usize] = 1.0;
        let mut g = [0.0; 2];
        t.backward(&vals, &mut adj, &mut g);
        for k in 0..2 {
            let h = 1e-6;
            let mut a = p;
            let mut b = p;
            a[k] += h;
            b[k] -= h;
            let fd = (eval(&a) - eval(&b)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-6, "param {k}: fd {fd} vs {}", g[k]);
        }
    }

    /// Interval bounds hold: for every shipped generator, the tape's value
    /// of every node at random parameters within the ranges lies inside its
    /// bounds.
    #[test]
    fn interval_bounds_hold_at_random_parameters() {
        use crate::pattern::generators::GENERATORS;
        use crate::pattern::record::{Program, RecordLimits};
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for g in GENERATORS {
            let p = Program::parse(g.source).unwrap();
            let r = p.record(&p.defaults(), &RecordLimits::default()).unwrap();
            let ranges: Vec<(f64, f64)> = r.float_decls().iter().map(|d| (d.lo, d.hi)).collect();
            let b = r.tape.bounds(&ranges);
            let mut vals = vec![];
            for _ in 0..200 {
                let q: Vec<f64> = ranges
                    .iter()
                    .map(|&(lo, hi)| lo + (hi - lo) * rnd())
                    .collect();
                r.tape.forward(&q, &mut vals);
                for (i, (&v, &(lo, hi))) in vals.iter().zip(&b).enumerate() {
                    assert!(
                        lo <= v && v <= hi,
                        "{}: node {i} = {v} outside [{lo}, {hi}]",
                        g.name
                    );
                }
            }
        }
        // Peaks inside an interval are found.
        let mut t = Tape::new();
        let p = t.push(Op::Param(0), 0.0);
        let s = t.push(Op::Sin(p), 0.0);
        let c = t.push(Op::Cos(p), 0.0);
        let b = t.bounds(&[(1.0, 2.0)]);
        assert!(b[s as usize].1 >= 1.0 && b[s as usize].0 <= 1f64.sin());
        assert!(b[c as usize].0 <= 2f64.cos() && b[c as usize].1 >= 1f64.cos());
    }
}

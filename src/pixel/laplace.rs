//! Section 3.3 (solver): the discrete Laplace equation ΔI = 0 with the
//! annotated pixels held fixed, solved per vector component.
//!
//! Domain and boundary: the whole image grid with a *Neumann* (no-flux)
//! boundary — a pixel on the border simply has fewer neighbours in its
//! stencil. The reference tool instead treats everything outside the image
//! as a fixed zero, which drags vectors towards zero near the borders; with
//! Neumann, a single annotated direction fills the whole image unchanged.
//! Free pixels satisfy `deg(i)·x_i − Σ_{j~i} x_j = 0` exactly as the 5-point
//! Laplacian, `deg(i)` being the number of in-image neighbours.
//!
//! Solver: conjugate gradients preconditioned by one symmetric multigrid
//! V-cycle. Coarse levels aggregate 2×2 blocks and take the Galerkin operator
//! `PᵀAP` of piecewise-constant prolongation `P`, which for this graph
//! Laplacian is again a weighted 5-point stencil — so fixed pixels, holes and
//! odd sizes need no special cases. Smoothing is red–black Gauss–Seidel (red–black
//! before, black–red after, which keeps the preconditioner symmetric) and the coarsest
//! level (≤ 64 cells) is solved exactly by Cholesky. Work per iteration is
//! linear in the pixel count and iteration counts stay small as images grow.
//! All arithmetic is sequential IEEE f64, so native and wasm agree bit for bit.

use super::orientation::SparseAnnotations;
use crate::core::limits::MAX_SOLVE_PIXELS;

/// Relative residual `‖b − Ax‖ / ‖b‖` at which a component is solved.
pub const TOLERANCE: f64 = 1e-8;
/// Safety cap on CG iterations per component.
pub use crate::core::limits::MAX_SOLVER_ITERATIONS as MAX_ITERATIONS;
/// Gauss–Seidel sweeps before and after each coarse correction.
const SMOOTHING: usize = 2;
/// Over-correction of the piecewise-constant coarse correction: constant
/// prolongation underestimates smooth errors' energy, and scaling it by
/// ~1.5–1.9 (Braess's trick for aggregation multigrid) roughly halves the
/// iteration count. Below 2 the preconditioner stays positive definite.
const COARSE_SCALE: f64 = 1.8;
const COARSEST_CELLS: usize = 64;

/// One grid level: a weighted graph Laplacian plus diagonal leak to fixed
/// pixels. Arrays are stored with one ghost cell on every side (stride
/// `w + 2`) whose weights and values stay zero, so the stencil loops need no
/// boundary branches.
struct Level {
    w: usize,
    h: usize,
    /// Diagonal; `0` marks a cell with no unknowns (fixed pixels, empty blocks, ghosts).
    diag: Vec<f64>,
    /// `1 / diag`, or `0` where `diag` is `0`.
    inv: Vec<f64>,
    /// Coupling weight between (x, y) and (x+1, y); the matrix entry is `−east`.
    east: Vec<f64>,
    /// Coupling weight between (x, y) and (x, y+1).
    south: Vec<f64>,
}

impl Level {
    fn stride(&self) -> usize {
        self.w + 2
    }

    fn len(&self) -> usize {
        (self.w + 2) * (self.h + 2)
    }

    /// Padded index of interior cell (x, y).
    fn at(&self, x: usize, y: usize) -> usize {
        (y + 1) * (self.w + 2) + x + 1
    }

    fn finest(w: usize, h: usize, fixed: &[bool]) -> Level {
        let n = (w + 2) * (h + 2);
        let mut lv = Level {
            w,
            h,
            diag: vec![0.0; n],
            inv: vec![0.0; n],
            east: vec![0.0; n],
            south: vec![0.0; n],
        };
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if fixed[i] {
                    continue;
                }
                let p = lv.at(x, y);
                let deg = (x > 0) as u32 + (x + 1 < w) as u32 + (y > 0) as u32 + (y + 1 < h) as u32;
                lv.diag[p] = deg as f64;
                if x + 1 < w && !fixed[i + 1] {
                    lv.east[p] = 1.0;
                }
                if y + 1 < h && !fixed[i + w] {
                    lv.south[p] = 1.0;
                }
            }
        }
        lv.finish();
        lv
    }

    fn finish(&mut self) {
        for (d, v) in self.diag.iter_mut().zip(self.inv.iter_mut()) {
            // Cancellation can leave round-off where a block has no unknowns.
            if *d < 1e-12 {
                *d = 0.0;
            }
            *v = if *d > 0.0 { 1.0 / *d } else { 0.0 };
        }
    }

    /// Galerkin coarsening with 2×2 aggregates: `A_c = Pᵀ A P`.
    fn coarsen(&self) -> Level {
        let (cw, ch) = (self.w.div_ceil(2), self.h.div_ceil(2));
        let n = (cw + 2) * (ch + 2);
        let mut c = Level {
            w: cw,
            h: ch,
            diag: vec![0.0; n],
            inv: vec![0.0; n],
            east: vec![0.0; n],
            south: vec![0.0; n],
        };
        for y in 0..self.h {
            for x in 0..self.w {
                let i = self.at(x, y);
                let ci = c.at(x / 2, y / 2);
                c.diag[ci] += self.diag[i];
                if self.east[i] != 0.0 {
                    if x % 2 == 0 {
                        // Both ends in the same aggregate: −w twice off the diagonal.
                        c.diag[ci] -= 2.0 * self.east[i];
                    } else {
                        c.east[ci] += self.east[i];
                    }
                }
                if self.south[i] != 0.0 {
                    if y % 2 == 0 {
                        c.diag[ci] -= 2.0 * self.south[i];
                    } else {
                        c.south[ci] += self.south[i];
                    }
                }
            }
        }
        c.finish();
        c
    }

    #[inline(always)]
    fn off(&self, x: &[f64], i: usize, s: usize) -> f64 {
        self.east[i] * x[i + 1]
            + self.east[i - 1] * x[i - 1]
            + self.south[i] * x[i + s]
            + self.south[i - s] * x[i - s]
    }

    /// `y = A x` on interior cells (inactive cells get 0: all their weights are 0).
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        let s = self.stride();
        for row in 1..=self.h {
            for i in row * s + 1..row * s + 1 + self.w {
                y[i] = self.diag[i] * x[i] - self.off(x, i, s);
            }
        }
    }

    /// Update the cells of one colour of the red–black checkerboard
    /// (`(x + y) % 2 == colour`). Cells of one colour only read the other
    /// colour, so the loop has no dependency chain and runs at throughput.
    fn gs_colour(&self, x: &mut [f64], b: &[f64], colour: usize) {
        let s = self.stride();
        for row in 1..=self.h {
            let first = (colour + row - 1) % 2;
            let base = row * s + 1;
            for i in (base + first..base + self.w).step_by(2) {
                x[i] = (b[i] + self.off(x, i, s)) * self.inv[i];
            }
        }
    }

    /// Red then black: one Gauss–Seidel sweep.
    fn gs_forward(&self, x: &mut [f64], b: &[f64]) {
        self.gs_colour(x, b, 0);
        self.gs_colour(x, b, 1);
    }

    /// Black then red: the adjoint of [`Level::gs_forward`], which keeps the
    /// V-cycle (and so the CG preconditioner) symmetric.
    fn gs_backward(&self, x: &mut [f64], b: &[f64]) {
        self.gs_colour(x, b, 1);
        self.gs_colour(x, b, 0);
    }
}

/// Exact solver for the coarsest level (dense Cholesky over its unknowns).
struct Dense {
    cells: Vec<usize>,
    l: Vec<f64>,
}

impl Dense {
    fn new(lv: &Level) -> Dense {
        let cells: Vec<usize> = (0..lv.len()).filter(|&i| lv.diag[i] > 0.0).collect();
        let m = cells.len();
        let mut a = vec![0.0; m * m];
        let mut e = vec![0.0; lv.len()];
        let mut col = vec![0.0; lv.len()];
        for (c, &j) in cells.iter().enumerate() {
            e[j] = 1.0;
            lv.apply(&e, &mut col);
            e[j] = 0.0;
            for (r, &i) in cells.iter().enumerate() {
                a[r * m + c] = col[i];
            }
        }
        // In-place Cholesky, lower triangle.
        for j in 0..m {
            let mut d = a[j * m + j];
            for k in 0..j {
                d -= a[j * m + k] * a[j * m + k];
            }
            let d = d.max(1e-300).sqrt();
            a[j * m + j] = d;
            for i in j + 1..m {
                let mut s = a[i * m + j];
                for k in 0..j {
                    s -= a[i * m + k] * a[j * m + k];
                }
                a[i * m + j] = s / d;
            }
        }
        Dense { cells, l: a }
    }

    fn solve(&self, b: &[f64], x: &mut [f64]) {
        let m = self.cells.len();
        let mut y: Vec<f64> = self.cells.iter().map(|&i| b[i]).collect();
        for i in 0..m {
            let s: f64 = y[i] - (0..i).map(|k| self.l[i * m + k] * y[k]).sum::<f64>();
            y[i] = s / self.l[i * m + i];
        }
        for i in (0..m).rev() {
            let s: f64 = y[i] - (i + 1..m).map(|k| self.l[k * m + i] * y[k]).sum::<f64>();
            y[i] = s / self.l[i * m + i];
        }
        x.fill(0.0);
        for (k, &i) in self.cells.iter().enumerate() {
            x[i] = y[k];
        }
    }
}

/// The multigrid hierarchy plus scratch buffers for V-cycles.
struct Multigrid {
    levels: Vec<Level>,
    coarsest: Dense,
    /// Per level: solution, right-hand side, residual.
    x: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    r: Vec<Vec<f64>>,
}

impl Multigrid {
    fn new(finest: Level) -> Multigrid {
        let mut levels = vec![finest];
        while levels.last().is_some_and(|l| l.w * l.h > COARSEST_CELLS) {
            let next = levels.last().map(Level::coarsen).expect("non-empty");
            levels.push(next);
        }
        let coarsest = Dense::new(levels.last().expect("non-empty"));
        let sizes: Vec<usize> = levels.iter().map(Level::len).collect();
        let bufs = || sizes.iter().map(|&n| vec![0.0; n]).collect::<Vec<_>>();
        Multigrid {
            levels,
            coarsest,
            x: bufs(),
            b: bufs(),
            r: bufs(),
        }
    }

    /// `z = M⁻¹ r` by one V-cycle from zero (padded vectors of the finest level).
    fn precondition(&mut self, r: &[f64], z: &mut [f64]) {
        self.b[0].copy_from_slice(r);
        self.vcycle(0);
        z.copy_from_slice(&self.x[0]);
    }

    fn vcycle(&mut self, l: usize) {
        let last = self.levels.len() - 1;
        if l == last {
            let (b, x) = (&self.b[l], &mut self.x[l]);
            self.coarsest.solve(b, x);
            return;
        }
        let lv = &self.levels[l];
        {
            let (x, b) = (&mut self.x[l], &self.b[l]);
            x.fill(0.0);
            for _ in 0..SMOOTHING {
                lv.gs_forward(x, b);
            }
            let r = &mut self.r[l];
            lv.apply(x, r);
            for (ri, bi) in r.iter_mut().zip(b) {
                *ri = bi - *ri;
            }
        }
        let coarse = &self.levels[l + 1];
        {
            let (fine_r, coarse_b) = (&self.r[l], &mut self.b[l + 1]);
            coarse_b.fill(0.0);
            for y in 0..lv.h {
                let (fi, ci) = (lv.at(0, y), coarse.at(0, y / 2));
                for x in 0..lv.w {
                    // Inactive cells have zero residual, so no test is needed.
                    coarse_b[ci + x / 2] += fine_r[fi + x];
                }
            }
        }
        self.vcycle(l + 1);
        let lv = &self.levels[l];
        let coarse = &self.levels[l + 1];
        let (head, tail) = self.x.split_at_mut(l + 1);
        let (x, xc) = (&mut head[l], &tail[0]);
        for y in 0..lv.h {
            let (fi, ci) = (lv.at(0, y), coarse.at(0, y / 2));
            for cx in 0..lv.w {
                if lv.diag[fi + cx] > 0.0 {
                    x[fi + cx] += COARSE_SCALE * xc[ci + cx / 2];
                }
            }
        }
        let b = &self.b[l];
        for _ in 0..SMOOTHING {
            lv.gs_backward(x, b);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Where a component's CG stands.
struct Cg {
    x: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    rz: f64,
    b_norm: f64,
    iterations: usize,
    done: bool,
}

/// The Laplace solve as a resumable object: each [`LaplaceSolver::run`] call
/// does a bounded number of CG iterations. Components are solved one after
/// the other (x, then y) with the same hierarchy.
pub struct LaplaceSolver {
    w: usize,
    h: usize,
    fixed: Vec<bool>,
    values: Vec<[f64; 2]>,
    mg: Option<Multigrid>,
    component: usize,
    cg: Option<Cg>,
    solution: [Vec<f64>; 2],
    iterations: [usize; 2],
    residual: [f64; 2],
}

/// Figures of a finished solve.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SolveStats {
    /// CG iterations per component.
    pub iterations: [usize; 2],
    /// Final relative residual per component.
    pub relative_residual: [f64; 2],
    /// Width and height of the grid solved on: the source's, or a reduced
    /// one for sources above [`crate::core::limits::MAX_SOLVE_PIXELS`].
    pub grid: [usize; 2],
}

impl LaplaceSolver {
    /// Set up `ΔI = 0` on a `w`×`h` grid, with `values[i]` held where `fixed[i]`.
    pub fn new(w: usize, h: usize, fixed: Vec<bool>, values: Vec<[f64; 2]>) -> LaplaceSolver {
        assert_eq!(fixed.len(), w * h);
        assert_eq!(values.len(), w * h);
        LaplaceSolver {
            w,
            h,
            fixed,
            values,
            mg: None,
            component: 0,
            cg: None,
            solution: [vec![], vec![]],
            iterations: [0; 2],
            residual: [0.0; 2],
        }
    }

    /// Roughly how many pixel visits one CG iteration costs (matrix product +
    /// V-cycle ≈ 4 sweeps × 4/3 for the coarse levels + vector updates).
    pub fn cost_per_iteration(&self) -> usize {
        self.w * self.h * 10
    }

    /// Do about `budget` pixel visits of work (at least one unit of progress).
    /// Returns `true` when both components are solved.
    pub fn run(&mut self, budget: usize) -> bool {
        let mut spent = 0usize;
        loop {
            if self.component == 2 {
                return true;
            }
            if self.mg.is_none() {
                self.mg = Some(Multigrid::new(Level::finest(self.w, self.h, &self.fixed)));
                spent += self.w * self.h * 4;
            } else if self.cg.is_none() {
                self.cg = Some(self.start_component());
                spent += self.w * self.h * 3;
            } else {
                let done = self.iterate();
                spent += self.cost_per_iteration();
                if done {
                    let cg = self.cg.take().expect("running");
                    let c = self.component;
                    self.iterations[c] = cg.iterations;
                    self.residual[c] = if cg.b_norm == 0.0 {
                        0.0
                    } else {
                        dot(&cg.r, &cg.r).sqrt() / cg.b_norm
                    };
                    self.solution[c] = cg.x;
                    self.component += 1;
                }
            }
            if spent >= budget {
                return self.component == 2;
            }
        }
    }

    fn start_component(&mut self) -> Cg {
        let (w, h, c) = (self.w, self.h, self.component);
        let n = (w + 2) * (h + 2);
        let mut b = vec![0.0; n];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if self.fixed[i] {
                    continue;
                }
                let mut s = 0.0;
                if x > 0 && self.fixed[i - 1] {
                    s += self.values[i - 1][c];
                }
                if x + 1 < w && self.fixed[i + 1] {
                    s += self.values[i + 1][c];
                }
                if y > 0 && self.fixed[i - w] {
                    s += self.values[i - w][c];
                }
                if y + 1 < h && self.fixed[i + w] {
                    s += self.values[i + w][c];
                }
                b[(y + 1) * (w + 2) + x + 1] = s;
            }
        }
        let b_norm = dot(&b, &b).sqrt();
        let x = vec![0.0; n];
        let r = b;
        let mut z = vec![0.0; n];
        let done = b_norm == 0.0;
        let mut rz = 0.0;
        if !done {
            self.mg.as_mut().expect("built").precondition(&r, &mut z);
            rz = dot(&r, &z);
        }
        let p = z.clone();
        Cg {
            x,
            r,
            z,
            p,
            ap: vec![0.0; n],
            rz,
            b_norm,
            iterations: 0,
            done,
        }
    }

    /// One PCG iteration; `true` when converged (or capped).
    fn iterate(&mut self) -> bool {
        let mg = self.mg.as_mut().expect("built");
        let cg = self.cg.as_mut().expect("running");
        if cg.done || cg.iterations >= MAX_ITERATIONS {
            return true;
        }
        mg.levels[0].apply(&cg.p, &mut cg.ap);
        let pap = dot(&cg.p, &cg.ap);
        if pap.is_nan() || pap <= 0.0 {
            // Exactly converged (p = 0) or no unknowns at all.
            cg.done = true;
            return true;
        }
        let alpha = cg.rz / pap;
        for i in 0..cg.x.len() {
            cg.x[i] += alpha * cg.p[i];
            cg.r[i] -= alpha * cg.ap[i];
        }
        cg.iterations += 1;
        if dot(&cg.r, &cg.r).sqrt() <= TOLERANCE * cg.b_norm {
            cg.done = true;
            return true;
        }
        mg.precondition(&cg.r, &mut cg.z);
        let rz = dot(&cg.r, &cg.z);
        let beta = rz / cg.rz;
        cg.rz = rz;
        for i in 0..cg.p.len() {
            cg.p[i] = cg.z[i] + beta * cg.p[i];
        }
        false
    }

    /// Fraction done, for progress: components finished plus a guess within one.
    pub fn fraction(&self) -> f64 {
        let within = self
            .cg
            .as_ref()
            .map_or(0.0, |c| (c.iterations as f64 / 30.0).min(0.95));
        ((self.component as f64 + within) / 2.0).min(1.0)
    }

    /// The solved field (fixed pixels keep their values). Call after `run`
    /// returned `true`.
    pub fn field(&self) -> Vec<[f64; 2]> {
        let w = self.w;
        (0..w * self.h)
            .map(|i| {
                if self.fixed[i] {
                    self.values[i]
                } else {
                    let p = (i / w + 1) * (w + 2) + i % w + 1;
                    [
                        self.solution[0].get(p).copied().unwrap_or(0.0),
                        self.solution[1].get(p).copied().unwrap_or(0.0),
                    ]
                }
            })
            .collect()
    }

    /// Iterations and residuals of the finished solve.
    pub fn stats(&self) -> SolveStats {
        SolveStats {
            iterations: self.iterations,
            relative_residual: self.residual,
            grid: [self.w, self.h],
        }
    }
}

/// Solve at once: the field and the solve's figures.
pub fn solve(
    w: usize,
    h: usize,
    fixed: Vec<bool>,
    values: Vec<[f64; 2]>,
) -> (Vec<[f64; 2]>, SolveStats) {
    let mut s = LaplaceSolver::new(w, h, fixed, values);
    while !s.run(usize::MAX / 2) {}
    (s.field(), s.stats())
}

/// The smallest whole factor `f` that brings a `w`×`h` grid to at most
/// `max` cells when each `f`×`f` block becomes one cell.
pub fn reduction_factor(w: usize, h: usize, max: usize) -> usize {
    let mut f = 1;
    while w.div_ceil(f) * h.div_ceil(f) > max.max(1) {
        f += 1;
    }
    f
}

/// The orientation field of a whole source, as a resumable object.
///
/// Sources up to [`MAX_SOLVE_PIXELS`] pixels are solved exactly as
/// [`LaplaceSolver`] does. Bigger ones are solved on a grid reduced by a
/// whole factor `f` (each `f`×`f` block one cell; a block is fixed when it
/// holds annotated pixels, with their mean vector), and the field is
/// interpolated back bilinearly, each annotated pixel keeping its own
/// vector. The solve's cost is then bounded whatever the source size, and
/// the interpolation is done a few rows per step.
pub struct FieldSolver {
    w: usize,
    h: usize,
    f: usize,
    annotations: SparseAnnotations,
    solver: LaplaceSolver,
    /// The solved (reduced) field, once the solve is done.
    coarse: Option<Vec<[f64; 2]>>,
    /// Next row to interpolate, and the next annotation to look at.
    row: usize,
    next_fixed: usize,
    field: Vec<[f32; 2]>,
}

impl FieldSolver {
    /// Set up the solve for a `w`×`h` source with these annotated pixels
    /// (sorted by index, as [`super::orientation::annotate_sparse`] gives).
    pub fn new(w: usize, h: usize, annotations: SparseAnnotations) -> FieldSolver {
        let f = reduction_factor(w, h, MAX_SOLVE_PIXELS);
        let (rw, rh) = (w.div_ceil(f), h.div_ceil(f));
        let mut fixed = vec![false; rw * rh];
        let mut values = vec![[0.0; 2]; rw * rh];
        if f == 1 {
            for &(i, v) in &annotations {
                fixed[i as usize] = true;
                values[i as usize] = v;
            }
        } else {
            let mut count = vec![0u32; rw * rh];
            for &(i, v) in &annotations {
                let (x, y) = (i as usize % w, i as usize / w);
                let b = (y / f) * rw + x / f;
                fixed[b] = true;
                values[b][0] += v[0];
                values[b][1] += v[1];
                count[b] += 1;
            }
            for (v, &c) in values.iter_mut().zip(&count) {
                if c > 0 {
                    *v = [v[0] / c as f64, v[1] / c as f64];
                }
            }
        }
        FieldSolver {
            w,
            h,
            f,
            annotations,
            solver: LaplaceSolver::new(rw, rh, fixed, values),
            coarse: None,
            row: 0,
            next_fixed: 0,
            field: Vec::new(),
        }
    }

    /// The factor the grid was reduced by (1: solved at full resolution).
    pub fn factor(&self) -> usize {
        self.f
    }

    /// Do about `budget` pixel visits of work; `true` when the field is ready.
    pub fn run(&mut self, budget: usize) -> bool {
        if self.coarse.is_none() {
            if !self.solver.run(budget) {
                return false;
            }
            self.coarse = Some(self.solver.field());
            self.field = Vec::with_capacity(self.w * self.h);
            return false;
        }
        self.interpolate(budget)
    }

    /// Fill about `budget` pixels of the full-resolution field, whole rows.
    fn interpolate(&mut self, budget: usize) -> bool {
        let coarse = self.coarse.as_ref().expect("solved");
        let (w, f) = (self.w, self.f);
        let (rw, rh) = (w.div_ceil(f), self.h.div_ceil(f));
        let mut done = 0;
        while self.row < self.h && (done == 0 || done + w <= budget) {
            let y = self.row;
            if f == 1 {
                let row = &coarse[y * w..(y + 1) * w];
                self.field
                    .extend(row.iter().map(|v| [v[0] as f32, v[1] as f32]));
            } else {
                // Cell centres of the reduced grid sit at (X + 0.5)·f.
                let fy = ((y as f64 + 0.5) / f as f64 - 0.5).clamp(0.0, (rh - 1) as f64);
                let y0 = fy.floor() as usize;
                let y1 = (y0 + 1).min(rh - 1);
                let ty = fy - y0 as f64;
                for x in 0..w {
                    let i = (y * w + x) as u32;
                    let a = self.annotations.get(self.next_fixed);
                    if let Some(&(_, v)) = a.filter(|a| a.0 == i) {
                        self.next_fixed += 1;
                        self.field.push([v[0] as f32, v[1] as f32]);
                        continue;
                    }
                    let fx = ((x as f64 + 0.5) / f as f64 - 0.5).clamp(0.0, (rw - 1) as f64);
                    let x0 = fx.floor() as usize;
                    let x1 = (x0 + 1).min(rw - 1);
                    let tx = fx - x0 as f64;
                    let at = |xx: usize, yy: usize| coarse[yy * rw + xx];
                    let (a, b, c, d) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
                    let lerp = |k: usize| {
                        let top = a[k] + (b[k] - a[k]) * tx;
                        let bottom = c[k] + (d[k] - c[k]) * tx;
                        (top + (bottom - top) * ty) as f32
                    };
                    self.field.push([lerp(0), lerp(1)]);
                }
            }
            self.row += 1;
            done += w;
        }
        self.row == self.h
    }

    /// Fraction done, for progress.
    pub fn fraction(&self) -> f64 {
        if self.coarse.is_none() {
            0.9 * self.solver.fraction()
        } else {
            0.9 + 0.1 * self.row as f64 / self.h.max(1) as f64
        }
    }

    /// Figures of the solve (after [`FieldSolver::run`] returned `true`).
    pub fn stats(&self) -> SolveStats {
        self.solver.stats()
    }

    /// The field, one `[x, y]` per source pixel, row-major.
    pub fn into_field(self) -> Vec<[f32; 2]> {
        self.field
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Max |Δ| over free pixels with the Neumann stencil.
    #[allow(clippy::needless_range_loop)]
    fn max_laplacian(w: usize, h: usize, fixed: &[bool], f: &[[f64; 2]]) -> f64 {
        let mut worst: f64 = 0.0;
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if fixed[i] {
                    continue;
                }
                for c in 0..2 {
                    let mut s = 0.0;
                    let mut n = 0.0;
                    for (ok, j) in [
                        (x > 0, i.wrapping_sub(1)),
                        (x + 1 < w, i + 1),
                        (y > 0, i.wrapping_sub(w)),
                        (y + 1 < h, i + w),
                    ] {
                        if ok {
                            s += f[j][c];
                            n += 1.0;
                        }
                    }
                    worst = worst.max((n * f[i][c] - s).abs());
                }
            }
        }
        worst
    }

    #[test]
    fn one_fixed_pixel_fills_everything_neumann() {
        // Neumann boundary: a lone constraint spreads unchanged (the reference
        // tool's zero-outside boundary would shrink it towards the edges).
        let (w, h) = (37, 23);
        let mut fixed = vec![false; w * h];
        let mut values = vec![[0.0; 2]; w * h];
        fixed[5 * w + 7] = true;
        values[5 * w + 7] = [0.6, -0.8];
        let (f, st) = solve(w, h, fixed, values);
        for v in &f {
            assert!(
                (v[0] - 0.6).abs() < 1e-8 && (v[1] + 0.8).abs() < 1e-8,
                "{v:?}"
            );
        }
        assert!(st.iterations[0] < 40, "{st:?}");
    }

    #[test]
    fn converges_quickly_and_satisfies_the_equation() {
        let (w, h) = (200, 150);
        let mut fixed = vec![false; w * h];
        let mut values = vec![[0.0; 2]; w * h];
        for x in 20..180 {
            fixed[30 * w + x] = true;
            values[30 * w + x] = [1.0, 0.0];
            fixed[120 * w + x] = true;
            values[120 * w + x] = [0.0, 1.0];
        }
        for y in 40..110 {
            fixed[y * w + 100] = true;
            values[y * w + 100] = [-1.0, 0.5];
        }
        let (f, st) = solve(w, h, fixed.clone(), values.clone());
        for i in 0..w * h {
            if fixed[i] {
                assert_eq!(f[i], values[i]);
            }
        }
        assert!(max_laplacian(w, h, &fixed, &f) < 1e-7);
        assert!(st.iterations[0] < 60 && st.iterations[1] < 60, "{st:?}");
    }

    #[test]
    fn stepping_gives_the_same_bits_as_one_go() {
        let (w, h) = (64, 48);
        let mut fixed = vec![false; w * h];
        let mut values = vec![[0.0; 2]; w * h];
        for k in 0..40 {
            let i = (5 + k / 2) * w + 10 + k;
            fixed[i] = true;
            values[i] = [k as f64 / 40.0, 1.0 - k as f64 / 40.0];
        }
        let (once, _) = solve(w, h, fixed.clone(), values.clone());
        let mut s = LaplaceSolver::new(w, h, fixed, values);
        let mut steps = 0;
        while !s.run(1) {
            steps += 1;
        }
        assert!(steps > 5);
        assert_eq!(s.field(), once);
    }

    #[test]
    fn reduction_factor_is_the_smallest_that_fits() {
        assert_eq!(reduction_factor(512, 512, 512 * 512), 1);
        assert_eq!(reduction_factor(513, 512, 512 * 512), 2);
        assert_eq!(reduction_factor(4096, 4096, 512 * 512), 8);
        assert_eq!(reduction_factor(4096, 1, 512 * 512), 1);
        assert_eq!(reduction_factor(3000, 700, 512 * 512), 3);
    }

    #[test]
    fn field_solver_at_full_resolution_equals_the_plain_solve() {
        let (w, h) = (40, 30);
        let ann: SparseAnnotations = vec![(65, [1.0, 0.0]), (66, [0.8, 0.6]), (900, [0.0, -1.0])];
        let mut fixed = vec![false; w * h];
        let mut values = vec![[0.0; 2]; w * h];
        for &(i, v) in &ann {
            fixed[i as usize] = true;
            values[i as usize] = v;
        }
        let (plain, _) = solve(w, h, fixed, values);
        let mut fs = FieldSolver::new(w, h, ann);
        assert_eq!(fs.factor(), 1);
        while !fs.run(5000) {}
        let want: Vec<[f32; 2]> = plain.iter().map(|v| [v[0] as f32, v[1] as f32]).collect();
        assert_eq!(fs.into_field(), want);
    }

    #[test]
    fn reduced_solve_keeps_annotations_and_follows_the_full_one() {
        // 1100×300 (> 512²): solved on a 550×150 grid. Annotated pixels keep
        // their vectors; elsewhere the field stays close to the exact solve,
        // and its direction (what placement uses) agrees almost everywhere.
        let (w, h) = (1100usize, 300usize);
        let mut ann: SparseAnnotations = Vec::new();
        for x in 100..1000 {
            ann.push(((60 * w + x) as u32, [1.0, 0.0]));
        }
        for y in 100..280 {
            ann.push(((y * w + 700) as u32, [0.0, 1.0]));
        }
        ann.sort_unstable_by_key(|e| e.0);
        let mut fs = FieldSolver::new(w, h, ann.clone());
        assert_eq!(fs.factor(), 2);
        let mut steps = 0;
        while !fs.run(1_000_000) {
            steps += 1;
        }
        assert!(steps > 3);
        assert_eq!(fs.stats().grid, [550, 150]);
        let field = fs.into_field();
        assert_eq!(field.len(), w * h);
        for &(i, v) in &ann {
            assert_eq!(field[i as usize], [v[0] as f32, v[1] as f32]);
        }
        let mut fixed = vec![false; w * h];
        let mut values = vec![[0.0; 2]; w * h];
        for &(i, v) in &ann {
            fixed[i as usize] = true;
            values[i as usize] = v;
        }
        let (exact, _) = solve(w, h, fixed, values);
        let mut worst: f64 = 0.0;
        let mut disagree = 0;
        for (a, b) in field.iter().zip(&exact) {
            let d = ((a[0] as f64 - b[0]).powi(2) + (a[1] as f64 - b[1]).powi(2)).sqrt();
            worst = worst.max(d);
            let da = crate::pixel::Direction8::nearest([a[0] as f64, a[1] as f64]);
            if da != crate::pixel::Direction8::nearest(*b) {
                disagree += 1;
            }
        }
        assert!(worst < 0.1, "largest difference {worst}");
        assert!(disagree * 200 < w * h, "{disagree} directions differ");
    }
}

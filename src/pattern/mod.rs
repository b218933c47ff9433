//! Fit: find the parameters of a procedural vector pattern that best match
//! a target image (Riso, Sforza & Pellacini, "pOp: Parameter Optimization of
//! Differentiable Vector Patterns", EGSR 2022).
//!
//! Files in the paper's order:
//! - §3 "Procedural Vector Patterns": [`lang`] (the pattern language),
//!   [`record`] (running a program once to record shapes and a tape),
//!   [`tape`] (reverse-mode differentiation of the recorded arithmetic).
//! - §4 "Loss Function": [`loss`] (L = L_S + 0.05·L_N, alternatives, exact gradients).
//! - §4 "Pattern Distance Fields": `sdf` (the primitives packed as tape
//!   fields; their geometry is the shared [`crate::geom`]), [`field`]
//!   (per-colour fields, the "on top" operator, booleans, tile culling).
//! - §4 "Target Image SDF": [`target`] (palette masks; the exact EDT is
//!   [`crate::pattern::geom::distance_transform`]).
//! - §4 "Optimization Procedure", "Parameter Set Initialization/Optimization":
//!   the shared [`crate::optim`] (GA, random sampling, Nelder–Mead, Adam with
//!   patience and refinement), [`fit`] (the whole fit as a stepped
//!   [`crate::core::job::Job`]).
//! - §5 "Results": [`generators`] (Table 1's generator family as programs).
//! - Output and plain-data entry points: [`render`] (raster, SVG), [`api`].
//!
//! ## Design choices
//!
//! **A purpose-built language recorded to a tape.** Patterns are programs
//! (loops, functions, conditionals, trig, transforms, shape statements) in a
//! small language parsed here, not an embedded general scripting engine. A
//! program runs once per assignment of its `int param`s; every arithmetic
//! operation that depends on a float `param` is appended to a tape and all
//! else is folded into constants. A loss evaluation replays only that tape
//! (tens to hundreds of nodes) and its reverse sweep gives exact gradients,
//! so the interpreter's cost is paid once per fit, not per evaluation (the
//! issue measured ~27 µs per run for an interpreter with plain floats, and a
//! dual-number interpreter would eat most of a ~400 µs loss+gradient budget).
//! Errors carry line and column; an operation limit, a shape limit and a
//! call-depth limit bound every run.
//!
//! **Branching on float parameters is an error.** `if` conditions and loop
//! bounds must be known at record time (constants, loop counters, `int
//! param`s). One tape then stays valid for every value the optimiser tries,
//! and the shape count never changes mid-fit (the paper's fixed "element
//! types"); value choices that depend on float parameters stay differentiable
//! through `select`, `min`, `max`, `abs` and `clamp`, which are tape
//! operations. The alternative (re-record when a decision flips) makes the
//! loss discontinuous in ways the optimiser cannot see.
//!
//! **Units.** Fields are compared in pixels of the loss grid by default
//! ([`loss::SdfUnits`]); see [`loss`] and `filigree bench fit` (`units`).
//!
//! **Coordinates.** The canvas ([`record::Canvas`]) is `[0, W] × [0, H]`,
//! y down, its shorter side 1: `[0, 1]²` for a square target (so every
//! square fit, render and golden file is what it was before, bit for bit),
//! the target image's aspect otherwise, so a non-square design is never
//! stretched (a 300 × 240 target is `[0, 1.25] × [0, 1]`; programs read
//! `WIDTH` and `HEIGHT`). Loss and raster grids ([`field::Grid`]) have the
//! canvas's aspect, their longer side the requested size; angles in radians.
//!
//! **Public surface.** The request API ([`api`]) plus what the CLI, the
//! benchmarks and `tests/fit.rs` drive directly (programs, scenes, targets,
//! objectives, fit jobs, rendering). The language's parser, the tape and the
//! primitive packing are crate-private; the types they contribute to that
//! surface are re-exported from [`record`].
pub mod api;
pub mod field;
pub mod fit;
pub mod generators;
pub mod geom;
pub mod global;
pub(crate) mod lang;
pub mod loss;
pub mod optim;
pub mod record;
pub mod render;
pub(crate) mod sdf;
pub mod state;
pub(crate) mod tape;
pub mod target;

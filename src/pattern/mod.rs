//! Fit: parameters of procedural vector patterns from a target image
//! (Riso, Sforza & Pellacini, "pOp: Parameter Optimization of
//! Differentiable Vector Patterns", EGSR 2022).
pub mod api;
pub mod field;
pub mod fit;
pub mod generators;
pub mod lang;
pub mod loss;
pub mod optim;
pub mod record;
pub mod render;
pub mod sdf;
pub mod tape;
pub mod target;

//! Pieces every tool shares: errors, limits, long-running jobs, seeded randomness.
pub mod error;
pub mod job;
pub mod limits;
pub mod rng;

//! Pieces every tool shares: errors, long-running jobs, seeded randomness.
pub mod error;
pub mod job;
pub mod rng;

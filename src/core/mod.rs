//! Pieces every tool shares: errors, long-running jobs and their parallel
//! driver, seeded randomness.
pub mod error;
pub mod job;
pub mod parallel;
pub mod rng;

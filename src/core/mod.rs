//! Pieces every tool shares: errors, long-running jobs, seeded randomness.
pub mod error;
pub mod job;
pub mod request_limits;
pub mod rng;

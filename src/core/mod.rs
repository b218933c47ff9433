//! Pieces every tool shares: errors, limits, long-running jobs and their
//! parallel driver, seeded randomness, plain pixels.
pub mod check;
pub mod error;
pub mod image;
pub mod job;
pub mod limits;
pub mod parallel;
pub mod request_limits;
pub mod rng;
pub mod value;

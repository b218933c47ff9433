//! Long work as resumable objects.
//!
//! A busy wasm call cannot read a cancel message, so every long computation is
//! a [`Job`]: each [`Job::step`] call does one bounded slice of work (≤ ~20 ms
//! at the largest inputs, most steps a few ms; `filigree bench slices`
//! measures them) and says how far along it is. A request's `start_*`
//! function only checks the request and sets up cheap state; work that grows
//! with the input happens in the steps. The browser worker runs
//! slices until ~15 ms have passed, posts progress, yields to its event loop
//! (where a `cancel` message can arrive) and goes on. Natively,
//! [`run_to_end`] drives the same object and checks a cancel flag between
//! slices. Both paths execute the same slices in the same order, which is what
//! keeps native and wasm results identical.
use crate::core::error::{Error, Result};
use crate::core::image::RawImage;
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};

/// How far a job has come.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Progress {
    /// Fraction done in `0.0..=1.0`. Monotone over a job's life.
    pub fraction: f64,
    /// What the job is doing now, e.g. "solving orientations".
    pub stage: String,
    /// The current figure of merit, if the job has one (e.g. a loss).
    pub figure: Option<f64>,
    /// The current best answer's values, if the job has them (e.g. the
    /// parameters of the best fit so far), so a view can show it live.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<f64>>,
    /// A picture of those values, if the job draws them and this step
    /// drew one (e.g. a fit asked for `preview`), so a view can show it
    /// without a second job.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub picture: Option<RawImage>,
}

impl Progress {
    pub fn new(fraction: f64, stage: impl Into<String>) -> Self {
        Progress {
            fraction: fraction.clamp(0.0, 1.0),
            stage: stage.into(),
            figure: None,
            values: None,
            picture: None,
        }
    }
    pub fn with_figure(mut self, figure: f64) -> Self {
        self.figure = Some(figure);
        self
    }
    pub fn with_values(mut self, values: Vec<f64>) -> Self {
        self.values = Some(values);
        self
    }
    pub fn with_picture(mut self, picture: RawImage) -> Self {
        self.picture = Some(picture);
        self
    }
}

/// What one slice of work ended with.
#[derive(Debug)]
pub enum Step<T> {
    /// More work to do.
    Running(Progress),
    /// Finished; the job must not be stepped again.
    Done(T),
}

/// A resumable computation. `step` must do a bounded amount of work.
pub trait Job {
    type Output;
    /// Do one slice of work.
    fn step(&mut self) -> Result<Step<Self::Output>>;

    /// This job's part of an exchange with its sibling shards (e.g. a
    /// sharded fit's losses of one batch). Checked after every step; when it
    /// returns `Some`, the job cannot go on until the driver hands it every
    /// shard's part with [`Job::inbox`]. The exchange is an all-gather: the
    /// driver only relays, it never merges (see [`crate::core::parallel`]).
    /// Most jobs never exchange.
    fn outbox(&mut self) -> Option<Vec<f64>> {
        None
    }

    /// Every shard's answer to the last [`Job::outbox`], in shard order
    /// (this job's own part included).
    fn inbox(&mut self, _parts: Vec<Vec<f64>>) -> Result<()> {
        Err(Error::input("this job takes no input while it runs"))
    }
}

/// A cancel flag shared between whoever drives a job and whoever may stop it.
#[derive(Debug, Default)]
pub struct Cancel(AtomicBool);

impl Cancel {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed)
    }
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Where a job stopped when advanced.
pub(crate) enum Halt<T> {
    /// It handed in its part of an exchange.
    Exchange(Vec<f64>),
    /// It finished.
    Done(T),
}

/// Step `job` until it asks for an exchange or finishes (the loop of
/// [`run_to_end`], and of each shard in [`crate::core::parallel`]).
pub(crate) fn advance<J: Job>(
    job: &mut J,
    cancel: &Cancel,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<Halt<J::Output>> {
    loop {
        if cancel.is_cancelled() {
            return Err(Error::Cancelled);
        }
        match job.step()? {
            Step::Running(p) => {
                on_progress(&p);
                if let Some(part) = job.outbox() {
                    return Ok(Halt::Exchange(part));
                }
            }
            Step::Done(out) => return Ok(Halt::Done(out)),
        }
    }
}

/// Drive `job` to completion natively, reporting progress after each slice and
/// checking `cancel` between slices. A job that asks for an exchange with
/// sibling shards ([`Job::outbox`]) cannot be finished alone: that is an
/// error here; use [`crate::core::parallel::run_sharded`].
pub fn run_to_end<J: Job>(
    mut job: J,
    cancel: &Cancel,
    mut on_progress: impl FnMut(&Progress),
) -> Result<J::Output> {
    match advance(&mut job, cancel, &mut on_progress)? {
        Halt::Done(out) => Ok(out),
        Halt::Exchange(_) => Err(Error::input(
            "this job is one shard of a parallel run and asks to exchange data with \
             its siblings; drive it with core::parallel::run_sharded",
        )),
    }
}

/// Drive a job to completion with no progress reporting and no cancellation.
pub fn run_quietly<J: Job>(job: J) -> Result<J::Output> {
    run_to_end(job, &Cancel::new(), |_| {})
}

/// A job that is a single function call: for work that is always short
/// (e.g. inspecting an image) but should still travel the same protocol.
pub struct OneShot<F>(Option<F>);

impl<F> OneShot<F> {
    pub fn new(f: F) -> Self {
        OneShot(Some(f))
    }
}

impl<T, F: FnOnce() -> Result<T>> Job for OneShot<F> {
    type Output = T;
    fn step(&mut self) -> Result<Step<T>> {
        match self.0.take() {
            Some(f) => f().map(Step::Done),
            None => Err(Error::input("this job has already finished")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Count {
        n: u32,
        to: u32,
    }
    impl Job for Count {
        type Output = u32;
        fn step(&mut self) -> Result<Step<u32>> {
            self.n += 1;
            if self.n == self.to {
                Ok(Step::Done(self.n))
            } else {
                Ok(Step::Running(Progress::new(
                    self.n as f64 / self.to as f64,
                    "counting",
                )))
            }
        }
    }

    #[test]
    fn runs_to_end_and_reports_monotone_progress() {
        let mut seen = vec![];
        let out = run_to_end(Count { n: 0, to: 5 }, &Cancel::new(), |p| {
            seen.push(p.fraction)
        })
        .unwrap();
        assert_eq!(out, 5);
        assert_eq!(seen.len(), 4);
        assert!(seen.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn cancel_stops_between_slices() {
        let cancel = Cancel::new();
        let mut steps = 0;
        let r = run_to_end(Count { n: 0, to: 100 }, &cancel, |_| {
            steps += 1;
            if steps == 3 {
                cancel.cancel();
            }
        });
        assert_eq!(r, Err(Error::Cancelled));
        assert_eq!(steps, 3);
    }

    /// A job that wants an exchange after its first step.
    struct Asks;
    impl Job for Asks {
        type Output = ();
        fn step(&mut self) -> Result<Step<()>> {
            Ok(Step::Running(Progress::new(0.5, "waiting")))
        }
        fn outbox(&mut self) -> Option<Vec<f64>> {
            Some(vec![1.0])
        }
    }

    #[test]
    fn run_to_end_refuses_a_job_that_needs_siblings_instead_of_looping() {
        let e = run_quietly(Asks).unwrap_err();
        assert!(e.to_string().contains("run_sharded"), "{e}");
    }

    #[test]
    fn one_shot_runs_once() {
        let mut j = OneShot::new(|| Ok(7));
        assert!(matches!(j.step(), Ok(Step::Done(7))));
        assert!(j.step().is_err());
    }
}

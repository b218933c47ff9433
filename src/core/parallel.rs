//! One way to run a job in parallel: the same job split into `n` shards that
//! exchange data mid-way, driven natively here exactly as the browser's worker
//! pool drives them (`www/app/client.js`, `runSharded`).
//!
//! A sharded job is built once per shard (`k` of `n`). It steps on its own
//! until it needs its siblings: then [`Job::outbox`] gives its part, and the
//! driver waits until every shard has handed in a part, gives each shard the
//! list of all parts in shard order ([`Job::inbox`]), and steps on. The driver
//! only relays (an all-gather); every merge is the job's own business, so the
//! page and this driver cannot disagree about it. Shards that follow the
//! convention end with the same, merged output; the driver returns shard 0's.
//!
//! Two drivers with one contract: [`run_sharded`] steps the shards in turn on
//! the calling thread (deterministic, and what wasm can do), and natively
//! [`run_sharded_threads`] advances each shard on its own scoped thread
//! between exchanges. Both give the same output bits.
use crate::core::error::{Error, Result};
use crate::core::job::{advance, Cancel, Halt, Job, Progress};

/// After a round in which every unfinished shard was advanced: either all
/// shards are done (their outputs), or all of them wait for an exchange
/// (delivered here), or they are out of step (an error).
fn settle<J: Job>(
    jobs: &mut [J],
    halts: Vec<Option<Halt<J::Output>>>,
    outputs: &mut [Option<J::Output>],
) -> Result<bool> {
    let mut parts = Vec::with_capacity(jobs.len());
    for (k, h) in halts.into_iter().enumerate() {
        match h {
            Some(Halt::Exchange(p)) => parts.push((k, p)),
            Some(Halt::Done(out)) => outputs[k] = Some(out),
            None => {}
        }
    }
    if parts.is_empty() {
        return Ok(true);
    }
    if parts.len() != jobs.len() {
        let waiting: Vec<usize> = parts.iter().map(|(k, _)| *k).collect();
        return Err(Error::input(format!(
            "the shards are out of step: shards {waiting:?} wait for an exchange that the \
             others finished without"
        )));
    }
    let all: Vec<Vec<f64>> = parts.into_iter().map(|(_, p)| p).collect();
    for job in jobs.iter_mut() {
        job.inbox(all.clone())?;
    }
    Ok(false)
}

fn first_output<T>(outputs: Vec<Option<T>>) -> Result<T> {
    outputs
        .into_iter()
        .next()
        .flatten()
        .ok_or_else(|| Error::input("a sharded run needs at least one shard"))
}

/// Drive the shards `jobs` (shard `k` at index `k`) to the end on this
/// thread, relaying their exchanges; `on_progress(k, p)` after every slice.
/// Returns shard 0's output.
pub fn run_sharded<J: Job>(
    mut jobs: Vec<J>,
    cancel: &Cancel,
    mut on_progress: impl FnMut(usize, &Progress),
) -> Result<J::Output> {
    let mut outputs: Vec<Option<J::Output>> = jobs.iter().map(|_| None).collect();
    loop {
        let mut halts = Vec::with_capacity(jobs.len());
        for (k, job) in jobs.iter_mut().enumerate() {
            halts.push(if outputs[k].is_some() {
                None
            } else {
                Some(advance(job, cancel, &mut |p| on_progress(k, p))?)
            });
        }
        if settle(&mut jobs, halts, &mut outputs)? {
            return first_output(outputs);
        }
    }
}

/// Like [`run_sharded`], but each shard advances on its own scoped thread
/// between exchanges (native only; the CLI's `--threads`). Same output bits.
#[cfg(not(target_arch = "wasm32"))]
pub fn run_sharded_threads<J>(
    mut jobs: Vec<J>,
    cancel: &Cancel,
    on_progress: impl FnMut(usize, &Progress) + Send,
) -> Result<J::Output>
where
    J: Job + Send,
    J::Output: Send,
{
    let on_progress = std::sync::Mutex::new(on_progress);
    let mut outputs: Vec<Option<J::Output>> = jobs.iter().map(|_| None).collect();
    loop {
        let halts: Vec<Result<Option<Halt<J::Output>>>> = std::thread::scope(|s| {
            let handles: Vec<_> = jobs
                .iter_mut()
                .enumerate()
                .map(|(k, job)| {
                    let finished = outputs[k].is_some();
                    let on_progress = &on_progress;
                    s.spawn(move || {
                        if finished {
                            return Ok(None);
                        }
                        let mut report = |p: &Progress| {
                            if let Ok(mut f) = on_progress.lock() {
                                f(k, p)
                            }
                        };
                        advance(job, cancel, &mut report).map(Some)
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join()
                        .unwrap_or_else(|_| Err(Error::input("a shard's thread panicked")))
                })
                .collect()
        });
        let halts = halts.into_iter().collect::<Result<Vec<_>>>()?;
        if settle(&mut jobs, halts, &mut outputs)? {
            return first_output(outputs);
        }
    }
}

/// Threads for a native parallel run (the CLI's and the benchmarks'
/// `--threads`): `asked` when it is within [`request_limits::THREADS`],
/// else all cores up to that limit's top.
///
/// [`request_limits::THREADS`]: crate::core::request_limits::THREADS
pub fn threads(asked: Option<usize>) -> Result<usize> {
    let (lo, hi) = crate::core::request_limits::THREADS;
    match asked {
        Some(n) if (lo..=hi).contains(&n) => Ok(n),
        Some(n) => Err(Error::input(format!(
            "`threads` must be in {lo}..={hi} (got {n})"
        ))),
        #[cfg(not(target_arch = "wasm32"))]
        None => Ok(std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(hi)),
        #[cfg(target_arch = "wasm32")]
        None => Ok(1),
    }
}

/// Maps `f` over `items` on all cores natively (one thread in wasm),
/// keeping the order. Each thread takes the next item when it is free, so
/// items of very different cost (an SVM that converges in 50 epochs beside
/// one that needs 1,000) keep every core busy; which thread computes an
/// item never changes its result.
pub fn par_map<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync) -> Vec<U> {
    #[cfg(not(target_arch = "wasm32"))]
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    #[cfg(target_arch = "wasm32")]
    let threads = 1;
    par_map_threads(items, threads, f)
}

/// [`par_map`] on at most `threads` threads (native; one in wasm). The one
/// native thread driver of the crate besides [`run_sharded_threads`].
pub fn par_map_threads<T: Sync, U: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> U + Sync,
) -> Vec<U> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let threads = threads.clamp(1, 64).min(items.len().max(1));
        if threads > 1 {
            let next = AtomicUsize::new(0);
            let work = || {
                let mut mine = Vec::new();
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    mine.push((i, f(item)));
                }
                mine
            };
            let done: Vec<(usize, U)> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads).map(|_| s.spawn(work)).collect();
                handles
                    .into_iter()
                    .flat_map(|h| h.join().expect("a worker thread panicked"))
                    .collect()
            });
            let mut out: Vec<Option<U>> = (0..items.len()).map(|_| None).collect();
            for (i, u) in done {
                out[i] = Some(u);
            }
            return out
                .into_iter()
                .map(|u| u.expect("every item mapped"))
                .collect();
        }
    }
    #[cfg(target_arch = "wasm32")]
    let _ = threads;
    items.iter().map(f).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::Step;

    /// Shard `k` of `n` sums the numbers `0..len` it owns (`i % n == k`),
    /// exchanges partial sums every `every` numbers, and ends with the total.
    struct Sum {
        k: usize,
        n: usize,
        i: usize,
        len: usize,
        every: usize,
        mine: f64,
        total: f64,
        ready: bool,
    }

    fn shards(n: usize) -> Vec<Sum> {
        (0..n)
            .map(|k| Sum {
                k,
                n,
                i: 0,
                len: 100,
                every: 10,
                mine: 0.0,
                total: 0.0,
                ready: false,
            })
            .collect()
    }

    impl Job for Sum {
        type Output = f64;
        fn step(&mut self) -> Result<Step<f64>> {
            if self.i == self.len {
                return Ok(Step::Done(self.total));
            }
            if self.i % self.n == self.k {
                self.mine += self.i as f64;
            }
            self.i += 1;
            self.ready = self.i.is_multiple_of(self.every);
            Ok(Step::Running(Progress::new(
                self.i as f64 / 100.0,
                "summing",
            )))
        }
        fn outbox(&mut self) -> Option<Vec<f64>> {
            std::mem::take(&mut self.ready).then(|| vec![std::mem::take(&mut self.mine)])
        }
        fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
            assert_eq!(parts.len(), self.n);
            self.total += parts.iter().map(|p| p[0]).sum::<f64>();
            Ok(())
        }
    }

    #[test]
    fn both_drivers_relay_every_exchange_and_agree() {
        for n in 1..=4 {
            let a = run_sharded(shards(n), &Cancel::new(), |_, _| {}).unwrap();
            let b = run_sharded_threads(shards(n), &Cancel::new(), |_, _| {}).unwrap();
            assert_eq!(a, 4950.0, "{n} shards");
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    #[test]
    fn shards_out_of_step_are_an_error_not_a_hang() {
        let mut jobs = shards(2);
        jobs[1].every = 1000; // never asks to exchange
        let e = run_sharded(jobs, &Cancel::new(), |_, _| {}).unwrap_err();
        assert!(e.to_string().contains("out of step"), "{e}");
    }

    #[test]
    fn cancel_stops_every_driver() {
        let cancel = Cancel::new();
        cancel.cancel();
        assert_eq!(
            run_sharded(shards(2), &cancel, |_, _| {}),
            Err(Error::Cancelled)
        );
        assert_eq!(
            run_sharded_threads(shards(2), &cancel, |_, _| {}),
            Err(Error::Cancelled)
        );
    }
}

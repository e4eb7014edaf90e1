//! What bounds a run, how it ended, and how far it got.

pub(crate) use crate::kernel::outcome::{Limit, Status};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Bounds on one run. A run that reaches one ends `Incomplete`, with every pending cell
/// reported undecided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Cells processed at most.
    pub max_cells: u64,
    /// Wall-clock time at most.
    pub timeout: Option<Duration>,
    /// Bytes held by pending cells at most (`Prune::bytes`).
    pub max_memory: usize,
}

/// The default memory bound on pending cells: 2 GiB.
pub(crate) const DEFAULT_MAX_MEMORY: usize = 2 << 30;

impl Default for Limits {
    fn default() -> Self {
        Limits { max_cells: 1_000_000, timeout: None, max_memory: DEFAULT_MAX_MEMORY }
    }
}

/// A snapshot of a run's progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Cells processed so far.
    pub processed: u64,
    /// Cells waiting.
    pub pending: usize,
    /// Share of the start cell's measure already decided, in [0, 1]; NaN when unknown.
    pub decided: f64,
}

/// The clock and counters the drivers (and the phases of a job outside them) check before taking
/// work.
pub(crate) struct Budget<'a> {
    limits: Limits,
    cancel: &'a AtomicBool,
    t0: Instant,
}

impl<'a> Budget<'a> {
    pub(crate) fn start(limits: Limits, cancel: &'a AtomicBool) -> Self {
        Budget { limits, cancel, t0: Instant::now() }
    }

    pub(crate) fn elapsed(&self) -> Duration {
        self.t0.elapsed()
    }

    /// The limit that forbids processing another cell after `processed` with `pending_bytes`
    /// waiting, if any.
    pub(super) fn exhausted(&self, processed: u64, pending_bytes: usize) -> Option<Limit> {
        if let Some(limit) = self.interrupted() {
            return Some(limit);
        }
        if processed >= self.limits.max_cells {
            return Some(Limit::Boxes);
        }
        if pending_bytes > self.limits.max_memory {
            return Some(Limit::Memory);
        }
        None
    }

    /// Cancel or time: the limits that do not depend on counts.
    pub(crate) fn interrupted(&self) -> Option<Limit> {
        if self.cancel.load(Ordering::Relaxed) {
            return Some(Limit::Cancelled);
        }
        match self.limits.timeout {
            Some(t) if self.t0.elapsed() >= t => Some(Limit::Time),
            _ => None,
        }
    }

    pub(super) fn cells_left(&self, processed: u64) -> u64 {
        self.limits.max_cells.saturating_sub(processed)
    }

    pub(super) fn max_memory(&self) -> usize {
        self.limits.max_memory
    }
}

/// CPU time consumed by this process so far, in seconds (0 where the OS will not say).
pub fn process_cpu_seconds() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec through a valid pointer and reads nothing else.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    if rc == 0 {
        ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
    } else {
        0.0
    }
}

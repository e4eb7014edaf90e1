//! What bounds a run, how it ended, and how far it got.

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
pub const DEFAULT_MAX_MEMORY: usize = 2 << 30;

impl Default for Limits {
    fn default() -> Self {
        Limits { max_cells: 1_000_000, timeout: None, max_memory: DEFAULT_MAX_MEMORY }
    }
}

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// `max_cells` cells were processed.
    Boxes,
    /// `timeout` elapsed.
    Time,
    /// Pending cells would have held more than `max_memory` bytes.
    Memory,
    /// The caller raised the cancel flag.
    Cancelled,
    /// The sink asked to stop.
    Sink,
}

impl Limit {
    /// The name used in reports and messages.
    pub fn name(self) -> &'static str {
        match self {
            Limit::Boxes => "boxes",
            Limit::Time => "time",
            Limit::Memory => "memory",
            Limit::Cancelled => "cancelled",
            Limit::Sink => "sink",
        }
    }
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Every cell was decided: the results enclose everything sought in the start cell.
    Complete,
    /// Stopped by a limit; results and undecided cells together enclose everything sought.
    Incomplete(Limit),
}

impl Status {
    /// True for `Complete`.
    pub fn is_complete(self) -> bool {
        self == Status::Complete
    }

    /// The first limit of two runs that make up one answer: complete only if both are.
    pub fn and(self, other: Status) -> Status {
        match self {
            Status::Complete => other,
            s => s,
        }
    }
}

/// Why a result is incomplete: a limit stopped its run, or the run ended with something it could
/// not decide. "Complete" means none of these: every cell decided, nothing left open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Incompleteness {
    /// A limit stopped the run.
    Limit(Limit),
    /// Strips were set aside as near-degenerate (undecided as a whole).
    NearDegenerate,
    /// Cells were left undecided at the precision.
    Undecided,
}

impl Incompleteness {
    /// The one rule: the limit that stopped the run, else near-degenerate strips, else undecided
    /// cells; `None` for a complete result.
    ///
    /// # Examples
    ///
    /// ```
    /// use linkspace::kernel::search::{Incompleteness, Limit, Status};
    /// assert_eq!(Incompleteness::of(Status::Complete, 0, false), None);
    /// assert_eq!(Incompleteness::of(Status::Complete, 3, false), Some(Incompleteness::Undecided));
    /// assert_eq!(Incompleteness::of(Status::Incomplete(Limit::Boxes), 3, true), Some(Incompleteness::Limit(Limit::Boxes)));
    /// ```
    pub fn of(status: Status, undecided: usize, near_degenerate: bool) -> Option<Self> {
        match status {
            Status::Incomplete(l) => Some(Incompleteness::Limit(l)),
            Status::Complete if near_degenerate => Some(Incompleteness::NearDegenerate),
            Status::Complete if undecided > 0 => Some(Incompleteness::Undecided),
            Status::Complete => None,
        }
    }

    /// The name used in reports and messages (a limit's own name, `near_degenerate`,
    /// `undecided`).
    pub fn name(self) -> &'static str {
        match self {
            Incompleteness::Limit(l) => l.name(),
            Incompleteness::NearDegenerate => "near_degenerate",
            Incompleteness::Undecided => "undecided",
        }
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

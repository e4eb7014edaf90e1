//! How a run is bounded and stopped: the `Control` every job takes from its front end.

use super::Limits;
use std::sync::atomic::AtomicBool;

/// How a search runs: its bounds, worker threads and cancel flag.
#[derive(Clone, Copy, Debug)]
pub struct Control<'a> {
    /// Cells, time and memory.
    pub limits: Limits,
    /// 1: depth first on the calling thread; more: breadth first, level by level, on that many
    /// threads. The results are the same (for a run no limit stopped).
    pub threads: usize,
    /// Raised by the caller to stop the run (`Incomplete(Cancelled)`).
    pub cancel: &'a AtomicBool,
}

static NEVER: AtomicBool = AtomicBool::new(false);

impl Control<'static> {
    /// One thread, never cancelled.
    pub fn with_limits(limits: Limits) -> Self {
        Control { limits, threads: 1, cancel: &NEVER }
    }
}

impl<'a> Control<'a> {
    /// The same control with what is left, at this moment, of its timeout by a run that
    /// started at `start`: the steps of one answer share one deadline.
    pub fn remaining_since(self, start: std::time::Instant) -> Self {
        let timeout = self.limits.timeout.map(|t| t.saturating_sub(start.elapsed()));
        Control { limits: Limits { timeout, ..self.limits }, ..self }
    }

    /// The same control with `share` (in (0, 1]) of its timeout: for the searches of a job that
    /// leaves the rest of its deadline to reading their boxes out.
    pub fn share_of_time(self, share: f64) -> Self {
        let timeout = self.limits.timeout.map(|t| t.mul_f64(share.clamp(0.0, 1.0)));
        Control { limits: Limits { timeout, ..self.limits }, ..self }
    }

    /// The limit that stops a job started at `start` now, if any: the cancel flag, or its
    /// timeout passed. The phases after a search (re-examinations, read-outs) ask it between
    /// items and leave what they have not reached as it is, undecided or unread.
    pub fn stopped_since(&self, start: std::time::Instant) -> Option<super::Limit> {
        if self.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            return Some(super::Limit::Cancelled);
        }
        self.limits.timeout.filter(|&t| start.elapsed() >= t).map(|_| super::Limit::Time)
    }

    /// The same control with another cell budget.
    pub fn max_cells(self, max_cells: u64) -> Self {
        Control { limits: Limits { max_cells, ..self.limits }, ..self }
    }
}


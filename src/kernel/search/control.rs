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

    /// The same control with another cell budget.
    pub fn max_cells(self, max_cells: u64) -> Self {
        Control { limits: Limits { max_cells, ..self.limits }, ..self }
    }
}


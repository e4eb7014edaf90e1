//! How the 3R searches run on the kernel (`crate::kernel::search`) within the caller's
//! `search::Control`: the serial or the level-by-level driver picked by the thread count, and the depth-first `Order` that puts the results of either driver in the
//! same order.
//!
//! Why an order: a few decisions of the 3R searches look at results found before (the ±π
//! seam can show one root twice; a cusp proven by ε-inflation may overlap an earlier one).
//! `Prune::process` must not (its answer depends on the cell alone, so that threads change
//! nothing), so those decisions are made after the run, over the results sorted in the order
//! of the depth-first walk: the order of the hand-written loops that came before, whatever
//! driver or thread count ran the search.

use crate::kernel::search::Control;
use crate::kernel::search::{self, Progress, Prune, Sink, Stats, Status, Store, Undecided, Wire};
use std::ops::ControlFlow;

/// A cell's place in the depth-first walk of the search tree: the cell owns the slice
/// `[at, at + span)` of `u128`, its children cut it into equal parts in the order they are
/// explored, so sorting leaves by `at` gives the depth-first order. Past about 80 levels the
/// slices are empty and ties keep the driver's order (sorting is stable).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Order {
    at: u128,
    span: u128,
}

impl Order {
    /// The start cell.
    pub const ROOT: Order = Order { at: 0, span: u128::MAX };

    /// Child `i` of `n` (explored in that order).
    #[inline]
    pub fn child(self, i: usize, n: usize) -> Order {
        // at + span·(i + 1) ≤ at + parent span: no overflow.
        // Shifts for the usual one, two or four children: a u128 division is a library call.
        let span = match n {
            0 | 1 => self.span,
            2 => self.span >> 1,
            4 => self.span >> 2,
            _ => self.span / n as u128,
        };
        Order { at: self.at + span * i as u128, span }
    }
}

/// Collects what a run reports, and passes progress on.
pub(crate) struct Gather<'p, C, F> {
    pub found: Vec<F>,
    pub undecided: Vec<(C, Undecided)>,
    progress: &'p mut dyn FnMut(&Progress),
}

impl<C, F> Sink<C, F> for Gather<'_, C, F> {
    fn found(&mut self, found: F) -> ControlFlow<()> {
        self.found.push(found);
        ControlFlow::Continue(())
    }

    fn undecided(&mut self, cell: C, why: Undecided) -> ControlFlow<()> {
        self.undecided.push((cell, why));
        ControlFlow::Continue(())
    }

    fn progress(&mut self, p: &Progress) {
        (self.progress)(p)
    }
}

/// What a run gave: how it ended, its counters, what it reported in driver order, and the
/// workers (for counters a search keeps beyond the kernel's).
pub(crate) struct Outcome<P: Prune> {
    pub status: Status,
    pub stats: Stats,
    pub found: Vec<P::Found>,
    pub undecided: Vec<(P::Cell, Undecided)>,
    pub workers: Vec<P>,
}

/// Runs the `Prune`s that `make` builds (one per worker) from `start` as `control` says.
pub(crate) fn drive<P: Prune + Send>(mut make: impl FnMut() -> P, start: P::Cell, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Outcome<P> {
    let mut sink = Gather { found: Vec::new(), undecided: Vec::new(), progress };
    let mut workers: Vec<P> = (0..control.threads.max(1)).map(|_| make()).collect();
    let (status, stats) = if workers.len() == 1 {
        search::run(&mut workers[0], start, Store::DepthFirst, &control.limits, control.cancel, &mut sink)
    } else {
        search::run_by_level(&mut workers, start, &control.limits, control.cancel, &mut sink)
    };
    Outcome { status, stats, found: sink.found, undecided: sink.undecided, workers }
}

/// As `drive`, with the search shared among the processes of `search::run_shared` when there
/// are any (every process then gets every result; the workers' own counters count only what
/// this process decided).
pub(crate) fn drive_shared<P>(mut make: impl FnMut() -> P, start: P::Cell, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Outcome<P>
where
    P: Prune + Send,
    P::Cell: Wire,
    P::Found: Wire,
{
    if search::rank_and_size().1 == 1 {
        return drive(make, start, control, progress);
    }
    let mut sink = Gather { found: Vec::new(), undecided: Vec::new(), progress };
    let mut workers: Vec<P> = (0..control.threads.max(1)).map(|_| make()).collect();
    let (status, stats) = search::run_shared(&mut workers, start, &control.limits, control.cancel, &mut sink);
    Outcome { status, stats, found: sink.found, undecided: sink.undecided, workers }
}

impl Wire for Order {
    fn put(&self, out: &mut Vec<u8>) {
        for w in [self.at, self.span] {
            ((w >> 64) as u64, w as u64).put(out);
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        let mut word = || {
            let (hi, lo) = <(u64, u64)>::take(input);
            (u128::from(hi) << 64) | u128::from(lo)
        };
        let at = word();
        Order { at, span: word() }
    }
}

/// Ignores progress.
pub(crate) fn no_progress(_: &Progress) {}

#[cfg(test)]
mod tests {
    use super::Order;

    /// Leaves sorted by `Order` come in depth-first order, whatever the branching.
    #[test]
    fn orders_follow_the_depth_first_walk() {
        let r = Order::ROOT;
        let (a, b, c) = (r.child(0, 3), r.child(1, 3), r.child(2, 3));
        let (a1, a2) = (a.child(0, 2), a.child(1, 2));
        let b1 = b.child(0, 1);
        let mut leaves = vec![c, b1.child(1, 2), a2, b1.child(0, 2), a1.child(0, 1)];
        leaves.sort();
        assert_eq!(leaves, vec![a1.child(0, 1), a2, b1.child(0, 2), b1.child(1, 2), c]);
    }
}

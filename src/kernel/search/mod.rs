//! The branch-and-prune kernel: one search loop for every analysis.
//!
//! The kernel knows *cells*, not equations: a cell is whatever a search splits (an interval
//! box, a pair of boxes, a (θ₂, θ₃) square). A search plugs in a `Prune`, whose `process` step
//! decides one cell: discard it (with a reason counted in `Stats`), report what it holds (a
//! `Found` carrying its certificate), leave it undecided at precision (with a reason), or split
//! it. The kernel owns the rest: the order of work (`Store`), `Limits` (cells, time, memory),
//! cancellation, progress, the `Sink` that receives results as they come, per-reason `Stats`,
//! and the one `Status { Finished, Stopped(Limit) }` (`outcome`).
//! This is ibex's `Solver(System, Ctc, Bsc, CellBuffer)` split, statically dispatched.
//!
//! `run` walks the tree on the calling thread in the chosen `Store` order; `run_by_level` walks
//! it breadth first on as many threads as it is given `Prune`s, and reports exactly the cells
//! the serial breadth-first walk would, in the same order, for any thread count.
//!
//! `run_shared` is `run_by_level` with each level shared among processes (`share`: MPI ranks
//! through the binary's `Peers`), reporting what one process reports.
//!
//! `polynomial` is the kernel's client for `EquationSystem`s (the solver of Porta, Ros and Thomas (2006) and the
//! trapezoid distance solver): `Solver`, `SolverSettings`, `BoxSink`.
//!
//! Does no IO and knows nothing of mechanisms, URDF or ROS.

mod control;
mod driver;
mod limits;
mod polynomial;
mod settings;
mod share;
mod store;

pub use control::Control;
pub use driver::{run, run_by_level, run_shared};
pub use crate::kernel::outcome::{BoxStatus, Completeness, Incompleteness, Limit, Status};
pub use limits::{process_cpu_seconds, Limits, Progress};
pub(crate) use limits::Budget;
pub use polynomial::{contractor_with_newton_on, default_contractor, width_units, BoxSink, Collect, ContractorFactory, Enclosure, RefinePlan, Refinement, SolveError, SolveStats, Solver};
pub use settings::{SettingsError, SolverSettings};
pub use share::{rank_and_size, share_searches, Peers, Wire};
pub(crate) use share::{components_shared, map_shared, total};
pub use store::Store;

use smallvec::SmallVec;
use std::collections::BTreeMap;
use std::ops::ControlFlow;

/// One search: how a cell is decided.
///
/// Contract: `process` may keep scratch state, but its answer depends on the cell alone (not on
/// the cells processed before), so that the parallel driver gives the serial answer. A cell is
/// discarded only when it provably holds nothing the search looks for.
pub trait Prune {
    /// What is split: a box, a pair of boxes, ...
    type Cell: Send;
    /// What is reported, with its certificate (a unique root, a point inside a strip, ...).
    type Found: Send;
    /// Why a cell is discarded: the search's closed set of proofs, counted per reason in
    /// `Stats::discarded` (`NoDiscard` for a search that discards nothing).
    type Reason: Reason;

    /// Decides one cell.
    fn process(&mut self, cell: Self::Cell) -> Step<Self::Cell, Self::Found, Self::Reason>;

    /// As `process`, for a search whose one cell can take long (an LP per variable of a large
    /// system): once `stop` says so (the run's deadline or cancel), it may leave the cell
    /// `Undecided` instead of finishing it. The default finishes it.
    fn process_until(&mut self, cell: Self::Cell, stop: &dyn Fn() -> bool) -> Step<Self::Cell, Self::Found, Self::Reason> {
        let _ = stop;
        self.process(cell)
    }

    /// The cell's share of the start cell's measure, in [0, 1], for `Progress::decided`;
    /// 0 (the default) when the search has no measure.
    fn share(&self, _cell: &Self::Cell) -> f64 {
        0.0
    }

    /// Depth of the cell in the search tree, for `Stats::max_level`.
    fn level(&self, _cell: &Self::Cell) -> u32 {
        0
    }

    /// Bytes the cell holds, for the memory limit; the default counts its inline size only.
    fn bytes(&self, _cell: &Self::Cell) -> usize {
        std::mem::size_of::<Self::Cell>()
    }

    /// Best-first key: `Store::BestFirst` takes the cell with the smallest key first.
    fn key(&self, _cell: &Self::Cell) -> f64 {
        0.0
    }
}

/// A discard reason of one search: a proof that a cell holds nothing sought.
pub trait Reason: Copy + Send {
    /// Its name in `Stats::discarded` and in reports.
    fn name(self) -> &'static str;
}

/// The reason type of a search that never discards a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoDiscard {}

impl Reason for NoDiscard {
    fn name(self) -> &'static str {
        match self {}
    }
}

/// What `Prune::process` decided.
pub enum Step<C, F, R> {
    /// Provably holds nothing sought; the reason is counted in `Stats::discarded`.
    Discard(R),
    /// Holds what is sought, with the certificate inside `F`.
    Found(F),
    /// Neither discarded nor proven at the precision asked for; the reason travels to the sink.
    Undecided(C, &'static str),
    /// To be searched further as these children (in the order they should be explored).
    Split(SmallVec<[C; 4]>),
}

/// The reason of a cell a `Prune` left `Undecided` because the run's deadline or cancel came
/// while it was deciding it (`Prune::process_until`): the run then ends `Incomplete` on that limit.
pub const INTERRUPTED: &str = "interrupted";

/// Why a cell is reported undecided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Undecided {
    /// The search reached its precision without a proof; the reason names what was missing.
    Precision(&'static str),
    /// Never processed: a limit stopped the run first (`Status` names which).
    Pending,
}

impl Undecided {
    /// A short machine-readable reason: the precision reason, or `"limit"`.
    pub fn reason(self) -> &'static str {
        match self {
            Undecided::Precision(r) => r,
            Undecided::Pending => "limit",
        }
    }
}

/// Where results go, as they are found.
pub trait Sink<C, F> {
    /// Receives what a cell holds; `Break` stops the run (`Incomplete(Sink)`).
    fn found(&mut self, found: F) -> ControlFlow<()>;
    /// Receives an undecided cell; `Break` stops the run (pending cells are then not reported).
    fn undecided(&mut self, cell: C, why: Undecided) -> ControlFlow<()>;
    /// Receives progress now and then; the default ignores it.
    fn progress(&mut self, _p: &Progress) {}
}

/// Counters of a run, the same for every search.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Cells processed.
    pub processed: u64,
    /// Cells split.
    pub split: u64,
    /// Results reported (`Step::Found`).
    pub found: u64,
    /// Cells reported undecided (at precision or pending).
    pub undecided: u64,
    /// Discarded cells per reason.
    pub discarded: BTreeMap<&'static str, u64>,
    /// Deepest level reached.
    pub max_level: u32,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// CPU seconds of the process over the run (all threads).
    pub cpu_seconds: f64,
}

impl Stats {
    /// The counters of one answer made of this run and `other` (run after it): counts and
    /// seconds summed, the deeper level kept.
    pub fn add(&mut self, other: &Stats) {
        self.processed += other.processed;
        self.split += other.split;
        self.found += other.found;
        self.undecided += other.undecided;
        for (reason, n) in &other.discarded {
            *self.discarded.entry(reason).or_insert(0) += n;
        }
        self.max_level = self.max_level.max(other.max_level);
        self.seconds += other.seconds;
        self.cpu_seconds += other.cpu_seconds;
    }

    /// Cells discarded for any reason.
    pub fn discarded_total(&self) -> u64 {
        self.discarded.values().sum()
    }

    /// Cells discarded for `reason`.
    pub fn discarded(&self, reason: impl Reason) -> u64 {
        self.discarded.get(reason.name()).copied().unwrap_or(0)
    }
}

/// `f` of every item, in item order, computed on up to `threads` threads (independent jobs
/// after a search: probes of isolated boxes, certificates of cusp neighbourhoods).
pub(crate) fn map_parallel<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    if threads <= 1 || items.len() < 2 {
        return items.iter().map(f).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, R)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads.min(items.len()))
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(i) else { break };
                        mine.push((i, f(item)));
                    }
                    mine
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("invariant: parallel jobs do not panic")).collect()
    });
    done.sort_unstable_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}

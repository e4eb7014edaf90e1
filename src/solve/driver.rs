//! The branch-and-prune driver: the seed's Algorithm 1.
//!
//! Take a box from the pool; shrink it until it is proven empty, is no wider than sigma, or one
//! round no longer removes a significant share of its volume (rho); bisect it in the last case.
//! The pool is a stack (depth first, lowest half first), so runs are deterministic.
//! Limits end a run `Incomplete`, and then every box still pending is reported as `Undecided`:
//! nothing is silently dropped.

use super::settings::{SettingsError, SolverSettings};
use crate::contract::{Contraction, Contractor, LpShrink, Newton, Propagation, Sequence};
use crate::interval::IntervalBox;
use crate::lp::LpCounters;
use crate::system::{EquationSystem, SystemError, VarId};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use thiserror::Error;

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Limit {
    /// `max_boxes` boxes were processed.
    Boxes,
    /// `timeout` elapsed.
    Time,
    /// The caller raised the cancel flag.
    Cancelled,
    /// The sink asked to stop.
    Sink,
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case", tag = "status", content = "limit")]
pub enum Status {
    /// Every box was decided: the solution boxes enclose every solution in the initial box.
    Complete,
    /// Stopped by a limit; solution and undecided boxes together enclose every solution.
    Incomplete(Limit),
}

/// The tag of a reported box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxStatus {
    /// No wider than sigma and not proven empty.
    Solution,
    /// A solution box proven (interval Newton) to hold exactly one solution.
    Unique,
    /// Left unprocessed when a limit stopped the run.
    Undecided,
}

/// A snapshot of a run's progress.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Progress {
    /// Boxes processed so far.
    pub processed: u64,
    /// Boxes waiting in the pool.
    pub pending: usize,
    /// Share of the initial (primary) volume already decided, in [0, 1].
    pub decided: f64,
}

/// Where results go, as they are found.
pub trait BoxSink {
    /// Receives one box; `Break` stops the run (`Incomplete(Sink)`).
    fn emit(&mut self, status: BoxStatus, b: &IntervalBox) -> ControlFlow<()>;
    /// Receives progress now and then; the default ignores it.
    fn progress(&mut self, _p: &Progress) {}
}

/// Collects boxes into vectors.
#[derive(Clone, Debug, Default)]
pub struct Collect {
    /// Solution boxes, in the order found.
    pub solutions: Vec<IntervalBox>,
    /// Per solution box: whether it is certified to hold exactly one solution.
    pub unique: Vec<bool>,
    /// Boxes left undecided by a limit.
    pub undecided: Vec<IntervalBox>,
}

impl BoxSink for Collect {
    fn emit(&mut self, status: BoxStatus, b: &IntervalBox) -> ControlFlow<()> {
        match status {
            BoxStatus::Solution | BoxStatus::Unique => {
                self.solutions.push(b.clone());
                self.unique.push(status == BoxStatus::Unique);
            }
            BoxStatus::Undecided => self.undecided.push(b.clone()),
        }
        ControlFlow::Continue(())
    }
}

/// Counters of a run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Boxes taken from the pool.
    pub processed: u64,
    /// Boxes proven empty.
    pub empty: u64,
    /// Boxes bisected.
    pub bisected: u64,
    /// Solution boxes reported.
    pub solutions: u64,
    /// Shrink rounds (propagation plus, where enabled, LP).
    pub shrink_rounds: u64,
    /// LP statistics.
    pub lp: LpCounters,
    /// Solution boxes certified by interval Newton to hold exactly one solution.
    pub certified: u64,
    /// Solution boxes later proven empty by `Solver::drop_spurious`.
    pub spurious_dropped: u64,
    /// True when the time limit (or a cancel) stopped `drop_spurious` before it re-examined
    /// every candidate box; the boxes it did not reach are reported as they were.
    pub post_processing_cut_short: bool,
    /// Deepest tree level reached.
    pub max_level: u32,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// CPU seconds of the process over the run (all threads): what the peers' figures count,
    /// and far less sensitive than wall time to other work on the machine.
    pub cpu_seconds: f64,
}

/// The result of `Solver::enclose`.
#[derive(Clone, Debug)]
pub struct Enclosure {
    /// How the run ended.
    pub status: Status,
    /// Its counters.
    pub stats: Stats,
    /// Solution boxes (spurious isolated ones dropped).
    pub solutions: Vec<IntervalBox>,
    /// Per solution box: certified to hold exactly one solution.
    pub unique: Vec<bool>,
    /// Boxes a limit left undecided.
    pub undecided: Vec<IntervalBox>,
}

/// What cannot be run.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SolveError {
    /// Bad settings.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// Bad system.
    #[error(transparent)]
    System(#[from] SystemError),
}

/// Makes the shrink pipeline for one run (a run owns its contractors: they keep scratch state).
pub type ContractorFactory<'a> = Box<dyn Fn(&'a EquationSystem, &SolverSettings) -> Box<dyn Contractor + Send + 'a> + Send + Sync + 'a>;

/// A validated system with validated settings.
pub struct Solver<'a> {
    system: &'a EquationSystem,
    settings: SolverSettings,
    primaries: Vec<VarId>,
    factory: Option<std::sync::Arc<ContractorFactory<'a>>>,
}

/// The default pipeline: propagation, then interval Newton on small boxes of square systems,
/// then (unless disabled, and unless Newton certified the box) the LP shrink.
pub fn default_contractor<'a>(system: &'a EquationSystem, settings: &SolverSettings) -> Box<dyn Contractor + Send + 'a> {
    let mut steps: Vec<Box<dyn Contractor + Send + 'a>> = vec![Box::new(Propagation::new(system))];
    if let Some(newton) = Newton::new(system, settings.newton_width) {
        steps.push(Box::new(newton));
    }
    if settings.use_lp {
        let mut lp = LpShrink::new(system);
        lp.backend = settings.lp_backend;
        steps.push(Box::new(lp));
    }
    Box::new(Sequence(steps))
}

impl<'a> Solver<'a> {
    /// Validates both; after this, `run` cannot fail.
    pub fn new(system: &'a EquationSystem, settings: SolverSettings) -> Result<Self, SolveError> {
        settings.validate()?;
        system.validate()?;
        Ok(Self { system, primaries: system.primaries(), settings, factory: None })
    }

    /// Replaces the default shrink pipeline (`default_contractor`) with `factory`'s, e.g. to add
    /// interval Newton or trapezoid clipping. Every contractor must keep the `Contractor`
    /// contract: only proven-empty parts go.
    pub fn with_contractor(mut self, factory: ContractorFactory<'a>) -> Self {
        self.factory = Some(std::sync::Arc::new(factory));
        self
    }

    pub(super) fn primaries(&self) -> &[VarId] {
        &self.primaries
    }

    pub(super) fn initial(&self) -> IntervalBox {
        self.system.initial_box()
    }

    /// Bisects the widest primary at its midpoint: the fixed rule both drivers share.
    pub(super) fn split(&self, b: &IntervalBox) -> (IntervalBox, IntervalBox) {
        let (i, _) = b.widest(&self.primaries).expect("invariant: validated system has primaries");
        b.bisect(i)
    }

    /// The limit that forbids processing `upcoming` more boxes now, if any.
    pub(super) fn limit_before(&self, stats: &Stats, upcoming: u64, t0: Instant, cancel: &AtomicBool) -> Option<Limit> {
        if stats.processed + upcoming > self.settings.max_boxes {
            return Some(Limit::Boxes);
        }
        self.limit_reached(stats, t0, cancel)
    }

    pub(super) fn contractor(&self) -> Box<dyn Contractor + Send + 'a> {
        match &self.factory {
            Some(f) => f(self.system, &self.settings),
            None => default_contractor(self.system, &self.settings),
        }
    }

    /// The settings in force.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// Runs branch and prune from the system's initial box.
    pub fn run(&self, cancel: &AtomicBool, sink: &mut dyn BoxSink) -> (Status, Stats) {
        self.run_from(self.system.initial_box(), cancel, sink)
    }

    /// Runs branch and prune from `start`.
    pub fn run_from(&self, start: IntervalBox, cancel: &AtomicBool, sink: &mut dyn BoxSink) -> (Status, Stats) {
        let t0 = Instant::now();
        let c0 = process_cpu_seconds();
        let mut stats = Stats::default();
        let mut contractor = self.contractor();
        let reference = start.clone();
        let volume = |b: &IntervalBox| self.relative_volume(b, &reference);
        let mut pool = vec![start];
        let mut pending_volume = 1.0;
        let mut status = Status::Complete;
        let mut last_progress = Instant::now();

        while let Some(mut b) = pool.pop() {
            pending_volume -= volume(&b);
            if let Some(limit) = self.limit_reached(&stats, t0, cancel) {
                pool.push(b);
                status = Status::Incomplete(limit);
                break;
            }
            stats.processed += 1;
            stats.max_level = stats.max_level.max(b.level);
            let shrunk = self.shrink(&mut b, contractor.as_mut(), &mut stats);
            match shrunk {
                Shrunk::Empty => stats.empty += 1,
                Shrunk::Solution | Shrunk::Unique => {
                    stats.solutions += 1;
                    let tag = if matches!(shrunk, Shrunk::Unique) { BoxStatus::Unique } else { BoxStatus::Solution };
                    if sink.emit(tag, &b).is_break() {
                        status = Status::Incomplete(Limit::Sink);
                        break;
                    }
                }
                Shrunk::Stalled => {
                    let (lower, upper) = self.split(&b);
                    stats.bisected += 1;
                    pending_volume += volume(&lower) + volume(&upper);
                    // Pushed last, popped first: the lower half is explored first.
                    pool.push(upper);
                    pool.push(lower);
                }
            }
            if last_progress.elapsed().as_millis() >= 200 {
                last_progress = Instant::now();
                let decided = (1.0 - pending_volume).clamp(0.0, 1.0);
                sink.progress(&Progress { processed: stats.processed, pending: pool.len(), decided });
            }
        }
        if status != Status::Complete {
            // Report what is left, in the order it would have been explored.
            while let Some(b) = pool.pop() {
                if sink.emit(BoxStatus::Undecided, &b).is_break() {
                    break;
                }
            }
        }
        stats.lp = contractor.lp_counters();
        stats.seconds = t0.elapsed().as_secs_f64();
        stats.cpu_seconds = process_cpu_seconds() - c0;
        (status, stats)
    }

    /// Runs to the end, then drops proven-empty isolated boxes (`drop_spurious` on clusters of
    /// at most two boxes): what the CLI and the node report. `progress` sees the run's progress.
    pub fn enclose(&self, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> Enclosure {
        struct Sink<'p> {
            collect: Collect,
            progress: &'p mut dyn FnMut(&Progress),
        }
        impl BoxSink for Sink<'_> {
            fn emit(&mut self, status: BoxStatus, b: &IntervalBox) -> ControlFlow<()> {
                self.collect.emit(status, b)
            }
            fn progress(&mut self, p: &Progress) {
                (self.progress)(p)
            }
        }
        let t0 = Instant::now();
        let c0 = process_cpu_seconds();
        let mut sink = Sink { collect: Collect::default(), progress };
        let (status, mut stats) = if self.settings.threads > 1 {
            self.run_parallel(self.settings.threads, cancel, &mut sink, None)
        } else {
            self.run(cancel, &mut sink)
        };
        // The time limit covers the whole call, post-processing included (issue 9, item 6).
        let deadline = self.settings.timeout.map(|t| t0 + t);
        let (solutions, unique, dropped, cut_short) = self.drop_spurious(std::mem::take(&mut sink.collect.solutions), std::mem::take(&mut sink.collect.unique), 2, cancel, deadline);
        stats.spurious_dropped = dropped;
        stats.post_processing_cut_short = cut_short;
        stats.solutions -= dropped;
        stats.seconds = t0.elapsed().as_secs_f64();
        stats.cpu_seconds = process_cpu_seconds() - c0;
        Enclosure { status, stats, solutions, unique, undecided: sink.collect.undecided }
    }

    /// Re-examines solution boxes that sit in clusters of at most `max_cluster` boxes with a
    /// deeper search (sigma / 16), and drops those it proves empty; returns the survivors, their
    /// uniqueness flags, the number dropped, and whether `deadline` (or `cancel`) cut the
    /// re-examination short. Boxes flagged unique are certified and kept.
    ///
    /// Why: a box reaching sigma is accepted without proof that it holds a solution, and at
    /// coarse sigma a few such near misses form clusters of their own. A solution curve never
    /// leaves a lone box (it crosses into its neighbours, which then touch it), and an isolated
    /// root survives the deeper search, so only proven-empty boxes go. The search is bounded;
    /// a box it cannot decide stays, and so does every box left when the deadline passes: each
    /// deeper search gets only the time that remains, so the call ends near the deadline.
    pub fn drop_spurious(&self, boxes: Vec<IntervalBox>, unique: Vec<bool>, max_cluster: usize, cancel: &AtomicBool, deadline: Option<Instant>) -> (Vec<IntervalBox>, Vec<bool>, u64, bool) {
        let (labels, n) = crate::interval::components(&boxes);
        let mut sizes = vec![0usize; n];
        for &l in &labels {
            sizes[l] += 1;
        }
        let mut deeper = Solver {
            system: self.system,
            primaries: self.primaries.clone(),
            settings: SolverSettings { sigma: self.settings.sigma / 16.0, max_boxes: 4_000, ..self.settings.clone() },
            factory: self.factory.clone(),
        };
        let mut kept = Vec::with_capacity(boxes.len());
        let mut kept_unique = Vec::with_capacity(boxes.len());
        let mut dropped = 0;
        let mut cut_short = false;
        for ((b, l), u) in boxes.into_iter().zip(labels).zip(unique) {
            if !u && sizes[l] <= max_cluster {
                let remaining = deadline.map(|d| d.saturating_duration_since(Instant::now()));
                if cut_short || cancel.load(Ordering::Relaxed) || remaining.is_some_and(|r| r.is_zero()) {
                    cut_short = true;
                    kept.push(b);
                    kept_unique.push(u);
                    continue;
                }
                deeper.settings.timeout = remaining.or(self.settings.timeout);
                let mut probe = Collect::default();
                let (status, _) = deeper.run_from(b.clone(), cancel, &mut probe);
                if status == Status::Complete && probe.solutions.is_empty() {
                    dropped += 1;
                    continue;
                }
                cut_short |= matches!(status, Status::Incomplete(Limit::Time | Limit::Cancelled));
            }
            kept.push(b);
            kept_unique.push(u);
        }
        (kept, kept_unique, dropped, cut_short)
    }

    fn limit_reached(&self, stats: &Stats, t0: Instant, cancel: &AtomicBool) -> Option<Limit> {
        if cancel.load(Ordering::Relaxed) {
            return Some(Limit::Cancelled);
        }
        if stats.processed >= self.settings.max_boxes {
            return Some(Limit::Boxes);
        }
        match self.settings.timeout {
            Some(t) if t0.elapsed() >= t => Some(Limit::Time),
            _ => None,
        }
    }

    /// Lines 5–9 of the seed's Algorithm 1.
    pub(super) fn shrink(&self, b: &mut IntervalBox, contractor: &mut dyn Contractor, stats: &mut Stats) -> Shrunk {
        loop {
            stats.shrink_rounds += 1;
            let before = b.clone();
            // The whole pipeline runs even when its first step reached sigma: the LP is what
            // proves most near-miss boxes empty, and a spurious solution box costs more than it.
            match contractor.contract(b) {
                Contraction::Empty => return Shrunk::Empty,
                Contraction::Proven if self.size(b) <= self.settings.sigma => {
                    stats.certified += 1;
                    return Shrunk::Unique;
                }
                _ => {}
            }
            if self.size(b) <= self.settings.sigma {
                if let Some(proven) = contractor.certify(b) {
                    if self.size(&proven) <= self.settings.sigma {
                        *b = IntervalBox { level: b.level, ..proven };
                        stats.certified += 1;
                        return Shrunk::Unique;
                    }
                }
                return Shrunk::Solution;
            }
            if self.relative_volume(b, &before) > self.settings.rho {
                return Shrunk::Stalled;
            }
        }
    }

    fn size(&self, b: &IntervalBox) -> f64 {
        b.widest(&self.primaries).map_or(0.0, |(_, w)| w)
    }

    /// Volume of `b` over the primaries, relative to `reference`; components of zero width in
    /// the reference are left out so that fixed values do not make every volume zero.
    fn relative_volume(&self, b: &IntervalBox, reference: &IntervalBox) -> f64 {
        self.primaries
            .iter()
            .filter(|&&i| reference.width(i) > 0.0)
            .map(|&i| b.width(i) / reference.width(i))
            .product()
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

pub(super) enum Shrunk {
    Empty,
    Solution,
    Unique,
    Stalled,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interval::{interval, point};
    use crate::system::{Equation, Monomial, Term, VarRole};

    /// x² + y² = 1, x = y: two solutions at ±(1/√2, 1/√2).
    fn two_points() -> EquationSystem {
        let mut s = EquationSystem::default();
        let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
        s.add(Equation::circle(x, y));
        s.add(Equation::new(
            vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }, Term { coef: point(-1.0), mono: Monomial::Linear(y) }],
            point(0.0),
        ));
        s
    }

    #[test]
    fn finds_both_isolated_solutions() {
        let s = two_points();
        let solver = Solver::new(&s, SolverSettings { sigma: 1e-6, ..Default::default() }).expect("valid");
        let mut out = Collect::default();
        let (status, stats) = solver.run(&AtomicBool::new(false), &mut out);
        assert_eq!(status, Status::Complete);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(out.solutions.iter().any(|b| b.contains(&[h, h])));
        assert!(out.solutions.iter().any(|b| b.contains(&[-h, -h])));
        assert!(out.solutions.iter().all(|b| b.width(0) <= 1e-6 && b.width(1) <= 1e-6));
        assert_eq!(stats.solutions as usize, out.solutions.len());
    }

    #[test]
    fn a_limit_reports_every_pending_box() {
        let s = two_points();
        let solver = Solver::new(&s, SolverSettings { sigma: 1e-9, max_boxes: 2, ..Default::default() }).expect("valid");
        let mut out = Collect::default();
        let (status, _) = solver.run(&AtomicBool::new(false), &mut out);
        assert_eq!(status, Status::Incomplete(Limit::Boxes));
        let h = std::f64::consts::FRAC_1_SQRT_2;
        for p in [[h, h], [-h, -h]] {
            assert!(out.solutions.iter().chain(&out.undecided).any(|b| b.contains(&p)), "lost {p:?}");
        }
    }

    #[test]
    fn cancellation_stops_at_once() {
        let s = two_points();
        let solver = Solver::new(&s, SolverSettings::default()).expect("valid");
        let mut out = Collect::default();
        let (status, stats) = solver.run(&AtomicBool::new(true), &mut out);
        assert_eq!(status, Status::Incomplete(Limit::Cancelled));
        assert_eq!(stats.processed, 0);
        assert_eq!(out.undecided.len(), 1);
    }
}

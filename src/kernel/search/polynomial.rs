//! The kernel's client for equation systems: Algorithm 1 of Porta, Ros and Thomas (2006) as a
//! `Prune`.
//!
//! A cell is an `IntervalBox`. `SystemPrune` shrinks it until it is proven empty, is no wider
//! than sigma, or one round no longer removes a significant share of its volume (rho), and
//! bisects it in the last case (widest primary at its midpoint, lower half first). Widths are
//! absolute unless `SolverSettings::scaled_widths` gives each primary a unit of its own
//! (`width_units`), read by sigma, Newton's threshold and the bisection alike.
//! `Solver` is the preset that wires a system, its contractors and the settings to the kernel
//! (as ibex's `DefaultSolver`): depth first on one thread, level by level on several, with the
//! same set of boxes. Limits end a run `Incomplete`, and then every box still pending is
//! reported as `Undecided`: nothing is silently dropped.

use super::limits::{process_cpu_seconds, Limit, Limits, Progress, Status};
use super::settings::{SettingsError, SolverSettings};

pub(crate) use crate::kernel::outcome::BoxStatus;
use super::{driver, Store, Wire};
use crate::kernel::contract::{Contraction, Contractor, Filter, Filtered, LpShrink, Newton, Propagation, Sequence};
use crate::kernel::interval::IntervalBox;
use crate::kernel::lp::LpCounters;
use crate::kernel::system::{EquationSystem, SystemError, VarId};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use thiserror::Error;

mod prune;

use self::prune::{Boxes, Screen, Shared, SystemPrune};

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
    /// Per solution box: `Unique` when it is certified to hold exactly one solution, else
    /// `Solution`.
    pub tags: Vec<BoxStatus>,
    /// Boxes left undecided by a limit.
    pub undecided: Vec<IntervalBox>,
}

impl BoxSink for Collect {
    fn emit(&mut self, status: BoxStatus, b: &IntervalBox) -> ControlFlow<()> {
        match status {
            BoxStatus::Solution | BoxStatus::Unique => {
                self.solutions.push(b.clone());
                self.tags.push(status);
            }
            BoxStatus::Undecided => self.undecided.push(b.clone()),
        }
        ControlFlow::Continue(())
    }
}

/// Counters of a run of the polynomial solver (the kernel's `Stats` in the names of Porta et al.
/// 2006).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolveStats {
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
    /// Certified boxes proven to hold the same solution as another certified box, and merged
    /// into it (`Solver::merge_shared_certificates`): each solution is counted once.
    pub certificates_merged: u64,
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
    pub stats: SolveStats,
    /// Solution boxes (spurious isolated ones dropped).
    pub solutions: Vec<IntervalBox>,
    /// Per solution box: `Unique` when certified to hold exactly one solution, else `Solution`.
    pub tags: Vec<BoxStatus>,
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

/// The budget of `Solver::refine`.
#[derive(Clone, Debug, PartialEq)]
pub struct RefinePlan {
    /// Per round, the run's sigma divided by this.
    pub divisors: Vec<f64>,
    /// Cells per round.
    pub max_boxes: u64,
    /// The widest cluster tried, in sigmas (scaled widths).
    pub max_width: f64,
}

impl Default for RefinePlan {
    /// Two rounds, at sigma / 32 and sigma / 1024, 20 000 cells each, on clusters at most
    /// 16 sigmas wide (the 3-RPR's unproven cusp clusters at sigma 5e-2 span up to 9, the
    /// equal five-bar's circles of cusp roots 40).
    fn default() -> Self {
        Self { divisors: vec![32.0, 1024.0], max_boxes: 20_000, max_width: 16.0 }
    }
}

/// What `Solver::refine` made of a cluster.
#[derive(Clone, Debug)]
pub enum Refinement {
    /// A round completed with boxes the caller accepts (none: the cluster holds no root).
    Settled(Collect),
    /// No round did; what was tried.
    Unsettled(String),
    /// Wider than the plan's `max_width`: not tried.
    TooWide,
}

/// Makes the shrink pipeline for one run (a run owns its contractors: they keep scratch state).
pub type ContractorFactory<'a> = Box<dyn Fn(&'a EquationSystem, &SolverSettings) -> Box<dyn Contractor + Send + 'a> + Send + Sync + 'a>;

/// A validated system with validated settings.
pub struct Solver<'a> {
    system: &'a EquationSystem,
    settings: SolverSettings,
    primaries: Vec<VarId>,
    /// Per variable, the unit its width is measured in (`width_units`).
    units: Vec<f64>,
    factory: Option<std::sync::Arc<ContractorFactory<'a>>>,
    /// When every run of this solver must end, whenever it starts (`until`): the phases of
    /// one job share one deadline.
    deadline: Option<Instant>,
}

/// The default pipeline: propagation, then interval Newton on small boxes of square systems,
/// then (unless disabled, and unless Newton certified the box) the LP shrink.
pub fn default_contractor<'a>(system: &'a EquationSystem, settings: &SolverSettings) -> Box<dyn Contractor + Send + 'a> {
    contractor_with_newton_on(system, system, settings)
}

/// The default pipeline on `system`, its interval Newton on `square` (the same variables, a
/// square subset of the rows): for a system that carries redundant rows for propagation and the
/// LP, which would keep Newton from certifying.
pub fn contractor_with_newton_on<'a>(system: &'a EquationSystem, square: &'a EquationSystem, settings: &SolverSettings) -> Box<dyn Contractor + Send + 'a> {
    let mut steps: Vec<Box<dyn Contractor + Send + 'a>> = vec![Box::new(Propagation::new(system))];
    if let Some(newton) = Newton::new(square, settings.newton_width) {
        steps.push(Box::new(newton.with_units(width_units(system, settings))));
    }
    if settings.use_lp {
        let mut lp = LpShrink::new(system);
        lp.backend = settings.lp_backend;
        steps.push(Box::new(lp));
    }
    Box::new(Sequence(steps))
}

/// Per variable of `system`, the unit its width is measured in: 1 for every variable unless
/// `settings.scaled_widths`; then, for a primary, its width in the initial box divided by the
/// narrowest positive finite width among the primaries there (so the narrowest keep unit 1 and
/// sigma keeps its meaning for them), and 1 for the rest (derived variables, fixed or unbounded
/// primaries). A pure function of the system and the settings: every box of a run, and every
/// re-examination of one, measures in the same units.
pub fn width_units(system: &EquationSystem, settings: &SolverSettings) -> Vec<f64> {
    let mut units = vec![1.0; system.vars.len()];
    if !settings.scaled_widths {
        return units;
    }
    let start = system.initial_box();
    let width = |i: VarId| start.width(i);
    let usable = |w: f64| w.is_finite() && w > 0.0;
    let primaries = system.primaries();
    let Some(narrowest) = primaries.iter().map(|&i| width(i)).filter(|&w| usable(w)).min_by(f64::total_cmp) else { return units };
    for i in primaries {
        if usable(width(i)) {
            units[i] = width(i) / narrowest;
        }
    }
    units
}

impl<'a> Solver<'a> {
    /// Validates both; after this, `run` cannot fail.
    pub fn new(system: &'a EquationSystem, settings: SolverSettings) -> Result<Self, SolveError> {
        settings.validate()?;
        system.validate()?;
        let units = width_units(system, &settings);
        Ok(Self { system, primaries: system.primaries(), units, settings, factory: None, deadline: None })
    }

    /// The same solver whose every run, and every re-examination after one, also ends by
    /// `deadline` (the earlier of it and each run's own timeout): the searches of one job, run
    /// one after the other, share the job's deadline instead of each taking its full timeout.
    pub fn until(mut self, deadline: Option<Instant>) -> Self {
        self.deadline = earliest(self.deadline, deadline);
        self
    }

    /// Replaces the default shrink pipeline (`default_contractor`) with `factory`'s, e.g. to add
    /// interval Newton or trapezoid clipping. Every contractor must keep the `Contractor`
    /// contract: only proven-empty parts go.
    pub fn with_contractor(mut self, factory: ContractorFactory<'a>) -> Self {
        self.factory = Some(std::sync::Arc::new(factory));
        self
    }

    /// Adds `filter` after the current pipeline (the default or `with_contractor`'s), wrapped in
    /// `contract::Filtered`: a box it proves `Outside` is empty, and a box it cannot place
    /// `Inside` keeps no certificate. For conditions that are not equations of the system.
    pub fn with_filter(mut self, filter: std::sync::Arc<dyn Filter + Send + Sync + 'a>) -> Self {
        let inner = self.factory.take();
        self.factory = Some(std::sync::Arc::new(Box::new(move |system: &'a EquationSystem, settings: &SolverSettings| -> Box<dyn Contractor + Send + 'a> {
            let pipeline = match &inner {
                Some(f) => f(system, settings),
                None => default_contractor(system, settings),
            };
            // Judged before the pipeline too: a box the filter drops costs no contraction.
            let screened: Box<dyn Contractor + Send + 'a> = Box::new(Sequence(vec![Box::new(Screen(Shared(filter.clone()))), pipeline]));
            Box::new(Filtered { inner: screened, filters: vec![Box::new(Shared(filter.clone()))] })
        })));
        self
    }

    fn contractor(&self) -> Box<dyn Contractor + Send + 'a> {
        match &self.factory {
            Some(f) => f(self.system, &self.settings),
            None => default_contractor(self.system, &self.settings),
        }
    }

    /// The settings in force.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// The kernel's limits for these settings, for a run starting now: its timeout cut to what
    /// is left before the deadline (`until`).
    fn limits(&self) -> Limits {
        let left = self.deadline.map(|d| d.saturating_duration_since(Instant::now()));
        let timeout = match (self.settings.timeout, left) {
            (Some(t), Some(l)) => Some(t.min(l)),
            (t, l) => t.or(l),
        };
        Limits { max_cells: self.settings.max_boxes, timeout, max_memory: self.settings.max_memory }
    }

    /// A `Prune` over boxes of this system, measuring volumes against `reference`.
    fn prune(&self, reference: &IntervalBox, diagonals: bool) -> SystemPrune<'a, '_> {
        SystemPrune {
            solver: self,
            contractor: self.contractor(),
            reference_widths: self.primaries.iter().map(|&i| reference.width(i)).collect(),
            shrink_rounds: 0,
            certified: 0,
            diagonals: diagonals.then(Vec::new),
        }
    }

    /// Runs branch and prune from the system's initial box, depth first.
    pub fn run(&self, cancel: &AtomicBool, sink: &mut dyn BoxSink) -> (Status, SolveStats) {
        self.run_from(self.system.initial_box(), cancel, sink)
    }

    /// Runs branch and prune from `start`, depth first.
    pub fn run_from(&self, start: IntervalBox, cancel: &AtomicBool, sink: &mut dyn BoxSink) -> (Status, SolveStats) {
        let mut prune = self.prune(&start, false);
        let (status, stats) = driver::run(&mut prune, start, Store::DepthFirst, &self.limits(), cancel, &mut Boxes(sink));
        let mut out = SolveStats::from_kernel(&stats);
        prune.add_counters(&mut out);
        (status, out)
    }

    /// Runs on `threads` worker threads (at least 1), breadth first: the same set of boxes as
    /// `run`, reported level by level. `level_diagonals`, when given, receives per tree level
    /// the widest primary diagonal among that level's boxes after shrinking (those not proven
    /// empty): the enclosure reached at each iteration (Porta et al. 2006, section V).
    pub fn run_parallel(&self, threads: usize, cancel: &AtomicBool, sink: &mut dyn BoxSink, level_diagonals: Option<&mut Vec<f64>>) -> (Status, SolveStats) {
        let start = self.system.initial_box();
        let mut workers: Vec<_> = (0..threads.max(1)).map(|_| self.prune(&start, level_diagonals.is_some())).collect();
        let (status, stats) = driver::run_shared(&mut workers, start, &self.limits(), cancel, &mut Boxes(sink));
        let mut out = SolveStats::from_kernel(&stats);
        let mut widest: Vec<f64> = Vec::new();
        for w in &workers {
            w.add_counters(&mut out);
            for (l, &d) in w.diagonals.iter().flatten().enumerate() {
                if widest.len() <= l {
                    widest.resize(l + 1, 0.0);
                }
                widest[l] = widest[l].max(d);
            }
        }
        if let Some(peers) = super::share::peers() {
            // Each process counted the cells it decided: the run's counters are their sums, and
            // a level's widest diagonal the widest any process saw.
            let mine = [out.shrink_rounds, out.certified, out.lp.solved, out.lp.unverified].map(|c| c as f64);
            let [shrink_rounds, certified, solved, unverified] = <[f64; 4]>::try_from(super::share::sum(peers, &mine)).expect("invariant: four sums");
            (out.shrink_rounds, out.certified, out.lp.solved, out.lp.unverified) = (shrink_rounds as u64, certified as u64, solved as u64, unverified as u64);
            if level_diagonals.is_some() {
                widest = super::share::widest(peers, &widest);
            }
        }
        if let Some(d) = level_diagonals {
            *d = widest;
        }
        (status, out)
    }

    /// Runs to the end, then drops proven-empty isolated boxes (`drop_spurious` on clusters of
    /// at most two boxes): what the CLI and the node report. `progress` sees the run's progress.
    pub fn enclose(&self, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> Enclosure {
        struct Forward<'p> {
            collect: Collect,
            progress: &'p mut dyn FnMut(&Progress),
        }
        impl BoxSink for Forward<'_> {
            fn emit(&mut self, status: BoxStatus, b: &IntervalBox) -> ControlFlow<()> {
                self.collect.emit(status, b)
            }
            fn progress(&mut self, p: &Progress) {
                (self.progress)(p)
            }
        }
        let t0 = Instant::now();
        let c0 = process_cpu_seconds();
        let mut sink = Forward { collect: Collect::default(), progress };
        // Shared among processes, a run goes level by level (`run_shared`), whatever the threads.
        let (status, mut stats) = if self.settings.threads > 1 || super::share::peers().is_some() {
            self.run_parallel(self.settings.threads, cancel, &mut sink, None)
        } else {
            self.run(cancel, &mut sink)
        };
        // The time limit covers the whole call, post-processing included.
        let deadline = earliest(self.settings.timeout.map(|t| t0 + t), self.deadline);
        let (solutions, tags, dropped, cut_short) = self.drop_spurious(std::mem::take(&mut sink.collect.solutions), std::mem::take(&mut sink.collect.tags), 2, cancel, deadline);
        let (solutions, tags, merged) = self.merge_shared_certificates(solutions, tags);
        stats.spurious_dropped = dropped;
        stats.certificates_merged = merged;
        stats.post_processing_cut_short = cut_short;
        stats.solutions -= dropped + merged;
        stats.seconds = t0.elapsed().as_secs_f64();
        stats.cpu_seconds = process_cpu_seconds() - c0;
        if let Some(peers) = super::share::peers() {
            // The CPU time of every process of a shared run.
            stats.cpu_seconds = super::share::sum(peers, &[stats.cpu_seconds])[0];
        }
        Enclosure { status, stats, solutions, tags, undecided: sink.collect.undecided }
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
    ///
    /// Shared like the search (`share::map_shared`): called on the thread that shares this
    /// process's searches, every process runs its share of the probes and of the labelling.
    pub fn drop_spurious(&self, boxes: Vec<IntervalBox>, tags: Vec<BoxStatus>, max_cluster: usize, cancel: &AtomicBool, deadline: Option<Instant>) -> (Vec<IntervalBox>, Vec<BoxStatus>, u64, bool) {
        self.drop_spurious_on(boxes, tags, max_cluster, cancel, deadline, true)
    }

    /// `drop_spurious`, shared with the other processes or (`shared` false: where the processes'
    /// paths may part, on their clocks) within this one.
    fn drop_spurious_on(&self, boxes: Vec<IntervalBox>, tags: Vec<BoxStatus>, max_cluster: usize, cancel: &AtomicBool, deadline: Option<Instant>, shared: bool) -> (Vec<IntervalBox>, Vec<BoxStatus>, u64, bool) {
        let threads = self.settings.threads;
        let (labels, n) = if shared { super::components_shared(&boxes, threads) } else { crate::kernel::interval::components(&boxes) };
        let mut sizes = vec![0usize; n];
        for &l in &labels {
            sizes[l] += 1;
        }
        let deeper = Solver {
            system: self.system,
            primaries: self.primaries.clone(),
            units: self.units.clone(),
            settings: SolverSettings { sigma: self.settings.sigma / 16.0, max_boxes: 4_000, ..self.settings.clone() },
            factory: self.factory.clone(),
            deadline: self.deadline,
        };
        // Each probe is an independent deterministic run: spread them over the workers. A probe
        // gets only the time left before the deadline; none starts after it (or a cancel).
        let probe = |b: &IntervalBox| -> Probe {
            let remaining = deadline.map(|d| d.saturating_duration_since(Instant::now()));
            if cancel.load(Ordering::Relaxed) || remaining.is_some_and(|r| r.is_zero()) {
                return Probe::NotRun;
            }
            let timed = Solver { system: deeper.system, primaries: deeper.primaries.clone(), units: deeper.units.clone(), settings: SolverSettings { timeout: remaining.or(self.settings.timeout), ..deeper.settings.clone() }, factory: deeper.factory.clone(), deadline: deeper.deadline };
            let mut found = Collect::default();
            match timed.run_from(b.clone(), cancel, &mut found) {
                (Status::Finished, _) if found.solutions.is_empty() => Probe::Empty,
                (Status::Stopped(Limit::Time | Limit::Cancelled), _) => Probe::NotRun,
                _ => Probe::Kept,
            }
        };
        let candidates: Vec<usize> = (0..boxes.len()).filter(|&i| tags[i] != BoxStatus::Unique && sizes[labels[i]] <= max_cluster).collect();
        let probes = if shared { super::map_shared(&candidates, threads, |&i| probe(&boxes[i])) } else { super::map_parallel(&candidates, threads, |&i| probe(&boxes[i])) };
        let cut_short = probes.contains(&Probe::NotRun);
        let mut drop = vec![false; boxes.len()];
        for (&i, p) in candidates.iter().zip(probes) {
            drop[i] = p == Probe::Empty;
        }
        let mut kept = Vec::with_capacity(boxes.len());
        let mut kept_tags = Vec::with_capacity(boxes.len());
        let mut dropped = 0;
        for ((b, u), d) in boxes.into_iter().zip(tags).zip(drop) {
            if d {
                dropped += 1;
            } else {
                kept.push(b);
                kept_tags.push(u);
            }
        }
        (kept, kept_tags, dropped, cut_short)
    }

    /// Makes each certificate count one solution. Two certified boxes of one run can hold the
    /// same root: a root near a face of two cells is certified from both, and a certificate may
    /// widen its cell (`Contractor::certify`). For every two certified boxes A and B that meet,
    /// the contractors are run on A ∩ B:
    /// - proven empty: A's root lies outside B and B's outside A, two solutions;
    /// - proven to hold exactly one root (or a certified box inside A ∩ B holding every root of
    ///   A ∩ B): that root is A's, since A holds one only, and B's likewise, so the two boxes hold
    ///   the same solution and are replaced by the certified enclosure;
    /// - otherwise B stays a solution box, no longer counted as certified (it may hold A's root).
    ///
    /// Returns the boxes, their flags, and how many boxes were merged away.
    pub fn merge_shared_certificates(&self, boxes: Vec<IntervalBox>, tags: Vec<BoxStatus>) -> (Vec<IntervalBox>, Vec<BoxStatus>, u64) {
        let certified: Vec<usize> = (0..boxes.len()).filter(|&i| tags[i] == BoxStatus::Unique).collect();
        let certified_boxes: Vec<IntervalBox> = certified.iter().map(|&i| boxes[i].clone()).collect();
        let (labels, n) = super::components_shared(&certified_boxes, self.settings.threads);
        let mut sizes = vec![0usize; n];
        for &l in &labels {
            sizes[l] += 1;
        }
        if sizes.iter().all(|&s| s <= 1) {
            return (boxes, tags, 0);
        }
        let mut boxes = boxes;
        let mut tags = tags;
        let mut gone = vec![false; boxes.len()];
        let mut contractor = self.contractor();
        let mut merged = 0;
        for (component, &size) in sizes.iter().enumerate() {
            if size <= 1 {
                continue;
            }
            // Certified boxes kept so far in this component, by index into `boxes`.
            let mut kept: Vec<usize> = Vec::new();
            for (k, &i) in certified.iter().enumerate() {
                if labels[k] != component {
                    continue;
                }
                let mut placed = true;
                for &j in &kept {
                    if !boxes[j].intersects(&boxes[i]) {
                        continue;
                    }
                    match Self::same_root(contractor.as_mut(), &boxes[j], &boxes[i]) {
                        SharedRoot::Distinct => {}
                        SharedRoot::Same(enclosure) => {
                            boxes[j] = IntervalBox { level: boxes[j].level.max(boxes[i].level), ..enclosure };
                            gone[i] = true;
                            merged += 1;
                            placed = false;
                            break;
                        }
                        SharedRoot::Unknown => {
                            tags[i] = BoxStatus::Solution;
                            placed = false;
                            break;
                        }
                    }
                }
                if placed {
                    kept.push(i);
                }
            }
        }
        let mut out_boxes = Vec::with_capacity(boxes.len());
        let mut out_tags = Vec::with_capacity(boxes.len());
        for ((b, u), g) in boxes.into_iter().zip(tags).zip(gone) {
            if !g {
                out_boxes.push(b);
                out_tags.push(u);
            }
        }
        (out_boxes, out_tags, merged)
    }

    /// Whether certified boxes `a` and `b`, which meet, hold the same root (see
    /// `merge_shared_certificates`).
    fn same_root(contractor: &mut dyn Contractor, a: &IntervalBox, b: &IntervalBox) -> SharedRoot {
        let mut common = IntervalBox { dims: a.dims.iter().zip(&b.dims).map(|(x, y)| x.intersection(*y)).collect(), level: a.level };
        if common.is_void() {
            return SharedRoot::Distinct;
        }
        let inside_both = |p: &IntervalBox| p.dims.iter().zip(a.dims.iter().zip(&b.dims)).all(|(p, (x, y))| p.subset(*x) && p.subset(*y));
        match contractor.contract(&mut common) {
            Contraction::Empty => SharedRoot::Distinct,
            Contraction::Proven => SharedRoot::Same(common),
            _ => match contractor.certify(&common) {
                Some(p) if inside_both(&p) => SharedRoot::Same(p),
                _ => SharedRoot::Unknown,
            },
        }
    }

    /// Re-searches one unproven cluster (`boxes`, boxes of this system from a run of this
    /// solver) at finer sigmas, one round per entry of `plan.divisors`, to prove its roots.
    /// Each round searches the cluster's hull, its primaries widened by this run's sigma (so a
    /// root on a face of the hull lies inside the start box, where Krawczyk can certify it) and
    /// cut to the initial box, at `sigma / divisor` with `plan.max_boxes` cells and at most
    /// `timeout`, then drops proven-empty isolated boxes (`drop_spurious`). The start box holds
    /// every box of the cluster, so a root of the cluster missing from a complete round's output
    /// is proven absent: `Settled` when a round completes and `settled` accepts its solution
    /// boxes and flags (every box certified, say); the caller may replace the cluster by them.
    /// A cluster wider than `plan.max_width` sigmas (scaled widths, `width_units`) is not tried:
    /// that is a curve of roots, not an isolated point. The search is this solver's (its
    /// contractors and units) with other limits: nothing is a second implementation.
    pub fn refine(&self, boxes: &[IntervalBox], plan: &RefinePlan, timeout: Option<std::time::Duration>, settled: &dyn Fn(&[IntervalBox], &[BoxStatus]) -> bool, cancel: &AtomicBool) -> Refinement {
        let Some(first) = boxes.first() else { return Refinement::Settled(Collect::default()) };
        let mut hull = first.clone();
        for b in &boxes[1..] {
            for (h, x) in hull.dims.iter_mut().zip(&b.dims) {
                *h = h.convex_hull(*x);
            }
        }
        if self.size(&hull) > plan.max_width * self.settings.sigma {
            return Refinement::TooWide;
        }
        let initial = self.system.initial_box();
        let mut start = initial.clone();
        for &i in &self.primaries {
            let margin = self.settings.sigma * self.units[i];
            let (lo, hi) = (hull.dims[i].inf() - margin, hull.dims[i].sup() + margin);
            start.dims[i] = crate::kernel::interval::interval(lo, hi).intersection(initial.dims[i]);
        }
        let t0 = Instant::now();
        let mut tried = Vec::new();
        for &d in &plan.divisors {
            let sigma = self.settings.sigma / d;
            let left = timeout.map(|t| t.saturating_sub(t0.elapsed()));
            if cancel.load(Ordering::Relaxed) || left.is_some_and(|r| r.is_zero()) {
                tried.push(format!("sigma {sigma:.1e}: no time left"));
                break;
            }
            let finer = Solver { system: self.system, primaries: self.primaries.clone(), units: self.units.clone(), settings: SolverSettings { sigma, max_boxes: plan.max_boxes, timeout: left, threads: 1, ..self.settings.clone() }, factory: self.factory.clone(), deadline: self.deadline };
            let mut found = Collect::default();
            let (status, stats) = finer.run_from(start.clone(), cancel, &mut found);
            if let Status::Stopped(limit) = status {
                tried.push(format!("sigma {sigma:.1e}: stopped on its {} limit after {} boxes", limit.name(), stats.processed));
                break;
            }
            let deadline = left.map(|l| t0 + l);
            let (solutions, tags, _, _) = finer.drop_spurious_on(found.solutions, found.tags, 2, cancel, deadline, false);
            if settled(&solutions, &tags) {
                return Refinement::Settled(Collect { solutions, tags, undecided: Vec::new() });
            }
            tried.push(format!("sigma {sigma:.1e}: {} boxes, {} certified", solutions.len(), tags.iter().filter(|t| **t == BoxStatus::Unique).count()));
        }
        Refinement::Unsettled(format!("re-searched at a finer sigma without settling it ({})", tried.join("; ")))
    }

    /// The widest primary of `b` in width units (`width_units`), with its scaled width.
    fn widest(&self, b: &IntervalBox) -> Option<(VarId, f64)> {
        self.primaries.iter().map(|&i| (i, b.width(i) / self.units[i])).fold(None, |best, (i, w)| match best {
            Some((_, bw)) if bw >= w => best,
            _ => Some((i, w)),
        })
    }

    fn size(&self, b: &IntervalBox) -> f64 {
        self.widest(b).map_or(0.0, |(_, w)| w)
    }
}

/// The earlier of two optional deadlines (none: no deadline).
fn earliest(a: Option<Instant>, b: Option<Instant>) -> Option<Instant> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// What `Solver::same_root` proved of two certified boxes that meet.
enum SharedRoot {
    /// Their common part holds no root: two solutions.
    Distinct,
    /// One root, enclosed by this certified box inside both.
    Same(IntervalBox),
    /// Neither proven.
    Unknown,
}

/// What re-examining one box showed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Probe {
    /// Proven to hold no solution.
    Empty,
    /// Not proven empty.
    Kept,
    /// Not (or not fully) re-examined: the deadline or a cancel came first.
    NotRun,
}

impl Wire for Probe {
    fn put(&self, out: &mut Vec<u8>) {
        (*self as u8).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        [Probe::Empty, Probe::Kept, Probe::NotRun][usize::from(u8::take(input))]
    }
}

#[cfg(test)]
mod tests;

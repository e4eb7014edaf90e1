//! `SystemPrune`: the kernel's `Prune` over boxes of one system, Algorithm 1 of Porta, Ros and
//! Thomas (2006) on one box (shrink by the pipeline until empty, no wider than sigma, or
//! stalled by rho; then bisect the widest primary), with the adapters that wire it to the
//! kernel (`Boxes` to a `BoxSink`, `Screen` for a shared filter) and the counters it adds to
//! `SolveStats`.

use super::super::{Prune, Sink, Stats, Step, Undecided};
use super::{BoxSink, BoxStatus, SolveStats, Solver};
use crate::kernel::contract::{Contraction, Contractor, Filter, Inclusion};
use crate::kernel::interval::IntervalBox;
use crate::kernel::search::Progress;
use smallvec::smallvec;
use std::ops::ControlFlow;

/// A filter shared by every run's pipeline.
pub(super) struct Shared<'a>(pub(super) std::sync::Arc<dyn Filter + Send + Sync + 'a>);

impl Filter for Shared<'_> {
    fn judge(&self, b: &IntervalBox) -> Inclusion {
        self.0.judge(b)
    }
}

/// A filter as the first step of a pipeline: `Empty` for a box it proves `Outside`, else
/// `Unchanged`.
pub(super) struct Screen<F>(pub(super) F);

impl<F: Filter> Contractor for Screen<F> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        match self.0.judge(b) {
            Inclusion::Outside => Contraction::Empty,
            _ => Contraction::Unchanged,
        }
    }

    fn name(&self) -> &'static str {
        "screen"
    }
}

/// Algorithm 1 of Porta et al. (2006) on one box: a `Prune` whose cells are boxes of the system.
pub(super) struct SystemPrune<'a, 's> {
    pub(super) solver: &'s Solver<'a>,
    pub(super) contractor: Box<dyn Contractor + Send + 'a>,
    /// Widths of the primaries in the start box, for volume shares.
    pub(super) reference_widths: Vec<f64>,
    pub(super) shrink_rounds: u64,
    pub(super) certified: u64,
    /// Per level, the widest diagonal of a box not proven empty, when asked for.
    pub(super) diagonals: Option<Vec<f64>>,
}

impl SystemPrune<'_, '_> {
    /// Lines 5–9 of Algorithm 1 of Porta et al. (2006).
    fn shrink(&mut self, b: &mut IntervalBox, stop: &dyn Fn() -> bool) -> Shrunk {
        let sigma = self.solver.settings.sigma;
        loop {
            self.shrink_rounds += 1;
            let before = b.clone();
            // The whole pipeline runs even when its first step reached sigma: the LP is what
            // proves most near-miss boxes empty, and a spurious solution box costs more than it.
            match self.contractor.contract_until(b, stop) {
                Contraction::Empty => return Shrunk::Empty,
                Contraction::Proven if self.solver.size(b) <= sigma => {
                    self.certified += 1;
                    return Shrunk::Unique;
                }
                _ => {}
            }
            if self.solver.size(b) <= sigma {
                if let Some(proven) = self.contractor.certify(b) {
                    if self.solver.size(&proven) <= sigma {
                        *b = IntervalBox { level: b.level, ..proven };
                        self.certified += 1;
                        return Shrunk::Unique;
                    }
                }
                return Shrunk::Solution;
            }
            // The deadline (or a cancel) may have cut the contraction short: what it proved
            // holds, but the box is not finished.
            if stop() {
                return Shrunk::Interrupted;
            }
            if self.relative_volume(b, &before) > self.solver.settings.rho {
                return Shrunk::Stalled;
            }
        }
    }

    /// Volume of `b` over the primaries, relative to `reference`; components of zero width in
    /// the start box are left out so that fixed values do not make every volume zero.
    fn relative_volume(&self, b: &IntervalBox, reference: &IntervalBox) -> f64 {
        self.solver.primaries.iter().filter(|&&i| reference.width(i) > 0.0).map(|&i| b.width(i) / reference.width(i)).product()
    }

    pub(super) fn add_counters(&self, out: &mut SolveStats) {
        out.shrink_rounds += self.shrink_rounds;
        out.certified += self.certified;
        let lp = self.contractor.lp_counters();
        out.lp.solved += lp.solved;
        out.lp.unverified += lp.unverified;
    }
}

/// Why the polynomial search discards a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SystemDiscard {
    /// The contractors proved it empty.
    Empty,
}

impl super::super::Reason for SystemDiscard {
    fn name(self) -> &'static str {
        "empty"
    }
}

impl Prune for SystemPrune<'_, '_> {
    type Cell = IntervalBox;
    type Found = (BoxStatus, IntervalBox);
    type Reason = SystemDiscard;

    fn process(&mut self, b: IntervalBox) -> Step<IntervalBox, (BoxStatus, IntervalBox), SystemDiscard> {
        self.process_until(b, &|| false)
    }

    fn process_until(&mut self, mut b: IntervalBox, stop: &dyn Fn() -> bool) -> Step<IntervalBox, (BoxStatus, IntervalBox), SystemDiscard> {
        let shrunk = self.shrink(&mut b, stop);
        if let Some(d) = &mut self.diagonals {
            if !matches!(shrunk, Shrunk::Empty) {
                let l = b.level as usize;
                if d.len() <= l {
                    d.resize(l + 1, 0.0);
                }
                d[l] = d[l].max(b.diagonal(&self.solver.primaries));
            }
        }
        match shrunk {
            Shrunk::Empty => Step::Discard(SystemDiscard::Empty),
            Shrunk::Solution => Step::Found((BoxStatus::Solution, b)),
            Shrunk::Unique => Step::Found((BoxStatus::Unique, b)),
            Shrunk::Interrupted => Step::Undecided(b, super::super::INTERRUPTED),
            Shrunk::Stalled => {
                let (i, _) = self.solver.widest(&b).expect("invariant: a box wider than sigma has a primary");
                let (lower, upper) = b.bisect(i);
                Step::Split(smallvec![lower, upper])
            }
        }
    }

    fn share(&self, b: &IntervalBox) -> f64 {
        self.solver.primaries.iter().zip(&self.reference_widths).filter(|(_, &w)| w > 0.0).map(|(&i, &w)| b.width(i) / w).product()
    }

    fn level(&self, b: &IntervalBox) -> u32 {
        b.level
    }

    fn bytes(&self, b: &IntervalBox) -> usize {
        std::mem::size_of::<IntervalBox>() + std::mem::size_of_val(b.dims.as_slice())
    }
}

/// Routes the kernel's results to a `BoxSink`.
pub(super) struct Boxes<'s>(pub(super) &'s mut dyn BoxSink);

impl Sink<IntervalBox, (BoxStatus, IntervalBox)> for Boxes<'_> {
    fn found(&mut self, (status, b): (BoxStatus, IntervalBox)) -> ControlFlow<()> {
        self.0.emit(status, &b)
    }

    fn undecided(&mut self, b: IntervalBox, _why: Undecided) -> ControlFlow<()> {
        self.0.emit(BoxStatus::Undecided, &b)
    }

    fn progress(&mut self, p: &Progress) {
        self.0.progress(p)
    }
}

impl SolveStats {
    pub(super) fn from_kernel(s: &Stats) -> Self {
        SolveStats {
            processed: s.processed,
            empty: s.discarded(SystemDiscard::Empty),
            bisected: s.split,
            solutions: s.found,
            max_level: s.max_level,
            seconds: s.seconds,
            cpu_seconds: s.cpu_seconds,
            ..SolveStats::default()
        }
    }
}

enum Shrunk {
    Empty,
    Solution,
    Unique,
    Stalled,
    /// The deadline or a cancel came before the box was finished.
    Interrupted,
}

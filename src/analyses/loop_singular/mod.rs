//! Singular sets of closed-loop mechanisms: the searches on the augmented systems that
//! `formulate::singular` builds (a client of the kernel's `Solver`, as `distances` and `arm3r`
//! are of `search`), their clustering, and the searches on the type-II image of 2-dof mechanisms (`image`: its
//! cusps, nodes, regions and the assembly-mode verdict). The orchestrations front ends run are
//! jobs of the application layer (`app::loops`).
//!
//! `SingularProblem::solve` runs the kernel's `Solver` on each chart: a box of chart `k` proven
//! to hold only directions owned by another chart (the first index of largest |m|) is dropped,
//! because that chart finds them; the rest are merged by their configuration parts.

use crate::kernel::interval::IntervalBox;
use crate::formulate::singular::{Coordinates, SingularProblem};
pub use sets::SingularSets;
use crate::kernel::outcome::BoxStatus;
use crate::kernel::search::{components_shared, Limit, SolveError, SolveStats, SolverSettings, Status};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

pub mod image;
mod sets;
mod points;

impl<L: Coordinates> SingularProblem<L> {
    /// Runs the solver on every chart and merges the results. `settings.max_boxes` applies per
    /// chart; `settings.timeout` to the whole call.
    pub fn solve(&self, settings: &SolverSettings, cancel: &AtomicBool) -> Result<SingularSet, SolveError> {
        if self.expected_dimension == 0 && self.dof == 1 {
            if let Some(rates) = self.linkage.rate_matrix(self.kind, &self.actuated, self.output.as_ref()) {
                return self.solve_points(&rates, settings, cancel);
            }
        }
        self.solve_charts(settings, cancel)
    }

    /// Every chart searched from its whole box.
    fn solve_charts(&self, settings: &SolverSettings, cancel: &AtomicBool) -> Result<SingularSet, SolveError> {
        let t0 = Instant::now();
        let mut boxes = Vec::new();
        let mut status = Status::Finished;
        let mut stats = Vec::new();
        let mut dropped_other_chart = 0u64;
        let mut unsearched_charts = 0;
        for k in 0..self.chart_count() {
            let remaining = settings.timeout.map(|t| t.saturating_sub(t0.elapsed()));
            let cancelled = cancel.load(std::sync::atomic::Ordering::Relaxed);
            if cancelled || remaining.is_some_and(|r| r.is_zero()) {
                // No time left: the charts from k on are not built. One undecided box, the
                // augmented system's whole box (every multiplier over its chart reach), holds
                // each of them (chart j has m_j = 1 within that reach): a mechanism of thousands
                // of joints has thousands of charts, and a box per chart would cost more to
                // build and report than the deadline allows.
                status = Status::Stopped(if cancelled { Limit::Cancelled } else { Limit::Time });
                boxes.push(SingularBox { chart: k, b: self.augmented.initial_box(), status: BoxStatus::Undecided });
                unsearched_charts = self.chart_count() - k;
                break;
            }
            let chart = self.chart(k);
            let s = SolverSettings { timeout: remaining, ..settings.clone() };
            let solver = self.linkage.extended_solver(&chart, s)?;
            let e = solver.enclose(cancel, &mut |_| {});
            if e.status != Status::Finished {
                status = e.status;
            }
            for (b, u) in e.solutions.into_iter().zip(e.tags.into_iter().map(|t| t == BoxStatus::Unique)) {
                if self.owned_elsewhere(k, &b) {
                    dropped_other_chart += 1;
                    continue;
                }
                // A certificate of the augmented system is one of the mechanism only where its
                // rows are faithful (see `Coordinates::rows_faithful`); elsewhere the box stays.
                let certified = u && self.linkage.rows_faithful(&b);
                boxes.push(SingularBox { chart: k, b, status: if certified { BoxStatus::Unique } else { BoxStatus::Solution } });
            }
            for b in e.undecided {
                boxes.push(SingularBox { chart: k, b, status: BoxStatus::Undecided });
            }
            stats.push(e.stats);
        }
        let mut set = self.clustered(boxes, status, stats, dropped_other_chart, unsearched_charts, settings.threads);
        set.seconds = t0.elapsed().as_secs_f64();
        Ok(set)
    }

    /// The set from its boxes: clusters by configuration part (the same configuration found in
    /// two charts, or a curve crossing from one chart to the next, is one cluster), labelled on
    /// `threads` threads and every process sharing the search. The caller sets `seconds`.
    fn clustered(&self, boxes: Vec<SingularBox>, status: Status, stats: Vec<SolveStats>, dropped_other_chart: u64, unsearched_charts: usize, threads: usize) -> SingularSet {
        let projected: Vec<IntervalBox> = boxes.iter().map(|x| IntervalBox::new(x.b.dims[..self.base_vars].to_vec())).collect();
        let (labels, n) = components_shared(&projected, threads);
        let mut clusters = vec![Cluster::default(); n];
        for (i, &l) in labels.iter().enumerate() {
            clusters[l].boxes.push(i);
            match boxes[i].status {
                BoxStatus::Unique => clusters[l].certified = true,
                BoxStatus::Undecided => clusters[l].undecided = true,
                BoxStatus::Solution => {}
            }
        }
        SingularSet { status, boxes, labels, clusters, stats, dropped_other_chart, unsearched_charts, seconds: 0.0 }
    }

    /// True when every direction in `b` (chart `k`, `m_k = 1`) is owned by another chart: some
    /// earlier component has |m_j| ≥ 1 or some later one |m_j| > 1, so the largest |m| is first
    /// reached elsewhere, inside that chart's domain, and that chart reports it.
    fn owned_elsewhere(&self, k: usize, b: &IntervalBox) -> bool {
        self.multipliers.iter().enumerate().any(|(j, &m)| {
            let mig = b.dims[m].mig();
            (j < k && mig >= 1.0) || (j > k && mig > 1.0)
        })
    }
}


/// One box of a singular set, in its chart's variables.
#[derive(Clone, Debug)]
pub struct SingularBox {
    /// The chart (index of the multiplier fixed to 1).
    pub chart: usize,
    /// The box.
    pub b: IntervalBox,
    /// Its status.
    pub status: BoxStatus,
}

/// Boxes whose configuration parts touch.
#[derive(Clone, Debug, Default)]
pub struct Cluster {
    /// Indices into `SingularSet::boxes`.
    pub boxes: Vec<usize>,
    /// Holds a certified box: at least one singular configuration is proven inside.
    pub certified: bool,
    /// Holds an undecided box.
    pub undecided: bool,
}

/// Every singular configuration lies in one of `boxes` (when `status` is complete, in a
/// certified or solution box).
#[derive(Clone, Debug)]
pub struct SingularSet {
    /// Complete, or the last limit met.
    pub status: Status,
    /// The boxes of all charts, minus those proven to belong to another chart.
    pub boxes: Vec<SingularBox>,
    /// Per box, its cluster.
    pub labels: Vec<usize>,
    /// Clusters by configuration part.
    pub clusters: Vec<Cluster>,
    /// Per chart, the solver's counters.
    pub stats: Vec<SolveStats>,
    /// Boxes dropped as duplicates owned by another chart.
    pub dropped_other_chart: u64,
    /// Charts a limit left unsearched (the last ones): one undecided box, of the first of them,
    /// holds them all.
    pub unsearched_charts: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl SingularSet {
    /// The one rule: the limit that stopped a search, else the boxes left undecided.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        crate::kernel::outcome::Completeness::of(self.status, self.boxes.iter().filter(|b| b.status == BoxStatus::Undecided).count(), false)
    }

    /// Clusters with a certified box.
    pub fn certified_clusters(&self) -> usize {
        self.clusters.iter().filter(|c| c.certified).count()
    }
}

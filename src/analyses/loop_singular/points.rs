//! Finite singular sets of 1-dof mechanisms: input or output sets whose velocity rows form a
//! square matrix `M(q)` of the configuration (`RateMatrix`: `[F_q; A]` or `[F_q; O]`), singular
//! exactly at the set's points (the turning points of an actuated joint, the dead centres of an
//! output joint).
//!
//! Searching every chart from its whole box covers the configuration curve once per chart, at
//! boxes fine enough for the null-vector rows to cut it: most of the time goes to boxes on the
//! curve far from any point. Here the curve is searched once, in the configuration variables
//! alone (the linkage's own system and filters), and a box goes as soon as one of two proofs
//! holds over it (a `Filter`, judged before and after each round of contraction):
//! - `M` is regular: `‖I − Y·M‖∞ < 1` with `Y ≈ M(mid)⁻¹` (`krawczyk::preconditioned_hull`),
//!   `Y·M` enclosed as `Σ_f (Y·C_f)·f` over the factors `f` of its entries
//!   (`RateMatrix::preconditioned`), far tighter than the interval product `Y·M(b)`;
//! - the bordered system has no root: with `u`, `v` the singular vectors of `M(mid)` for its
//!   smallest singular value and `k` the largest component of `v`, the matrix `A` = `M` with
//!   column `k` replaced by `u` regular over the box shows that every singular configuration
//!   there has a one-dimensional kernel with `v_k ≠ 0`, and the solution of
//!   `A (v_{−k}, g) = −M_k` (the kernel normalised by `v_k = 1`, and `g`, zero exactly at the
//!   singular configurations) is enclosed; a `g` enclosure without zero drops the box.
//!
//! Each box left at `LEAF_WIDTH` is solved in the square system of one chart: when the bordered
//! enclosure proves chart `k` owns every kernel direction there (`|v_j| < 1` before `k`, `≤ 1`
//! after: the first largest component), chart `k` is searched from the box and that enclosure,
//! where Krawczyk (the chart solver's `Newton`) certifies its point at once; otherwise every
//! chart is searched from the box, as the whole-box search would. Every point of the set lies in
//! a reported box, certified or not, or in an undecided one: nothing is dropped without one of
//! those proofs.

use crate::kernel::outcome::BoxStatus;
use super::{SingularBox, SingularSet};
use crate::kernel::contract::krawczyk::preconditioned_hull;
use crate::kernel::contract::{Contractor, Filter, Inclusion, Newton};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::formulate::singular::{Coordinates, RateMatrix, SingularProblem};
use crate::kernel::search::{Collect, Limit, SolveError, SolveStats, SolverSettings, Status};
use crate::kernel::system::EquationSystem;
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Width of the configuration boxes solved in a chart (or sigma, when coarser). Around a fold
/// point the bordered matrix is regular over boxes of about this width, and Krawczyk then
/// certifies the chart's system from a start box this wide.
const LEAF_WIDTH: f64 = 0.1;

/// Drops every box over which the rate matrix is proven regular.
struct Regular<'r> {
    rates: &'r RateMatrix,
    base_vars: usize,
}

impl Filter for Regular<'_> {
    fn judge(&self, b: &IntervalBox) -> Inclusion {
        let cfg = &b.dims[..self.base_vars];
        if regular(self.rates, cfg) || matches!(bordered(self.rates, cfg), Bordered::Empty) {
            Inclusion::Outside
        } else {
            Inclusion::Straddles
        }
    }
}

/// `M` at the box's midpoint, in floating point (for preconditioners only).
fn at_midpoint(rates: &RateMatrix, cfg: &[Interval]) -> Option<DMatrix<f64>> {
    let mid: Vec<Interval> = cfg.iter().map(|d| point(d.mid())).collect();
    let m = rates.over(&mid).map(|x| x.mid());
    m.iter().all(|x| x.is_finite()).then_some(m)
}

/// A real approximate inverse, finite.
fn inverse(m: DMatrix<f64>) -> Option<DMatrix<f64>> {
    m.try_inverse().filter(|y| y.iter().all(|x| x.is_finite()))
}

/// Whether every matrix `M(q)`, `q` in the box, is proven regular.
fn regular(rates: &RateMatrix, cfg: &[Interval]) -> bool {
    let Some(y) = at_midpoint(rates, cfg).and_then(inverse) else { return false };
    let n = rates.order();
    let w = rates.preconditioned(&y, cfg);
    let e = DMatrix::from_fn(n, n, |i, j| identity(i, j).sub(w[(i, j)]));
    preconditioned_hull(&e, &DVector::from_element(n, Iv::ZERO)).is_some()
}

fn identity(i: usize, j: usize) -> Iv {
    if i == j {
        Iv { lo: 1.0, hi: 1.0 }
    } else {
        Iv::ZERO
    }
}

/// What the bordered matrix shows over a box (module doc).
enum Bordered {
    /// No singular configuration.
    Empty,
    /// Every singular configuration's kernel, normalised by `v_k = 1`, lies in the enclosure
    /// (component `k` holds the border's unknown).
    Kernel(usize, DVector<Interval>),
    /// Nothing proven.
    Unknown,
}

/// The bordered system `Σ_{j≠k} M_j v_j + u·g = −M_k` over the box (module doc), preconditioned
/// by the inverse of its matrix at the midpoint.
fn bordered(rates: &RateMatrix, cfg: &[Interval]) -> Bordered {
    let n = rates.order();
    let Some(m0) = at_midpoint(rates, cfg) else { return Bordered::Unknown };
    let svd = m0.clone().svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return Bordered::Unknown };
    let Some(smallest) = (0..n).min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b])) else { return Bordered::Unknown };
    let Some(k) = (0..n).max_by(|&a, &b| v_t[(smallest, a)].abs().total_cmp(&v_t[(smallest, b)].abs())) else { return Bordered::Unknown };
    let border: Vec<f64> = (0..n).map(|i| u[(i, smallest)]).collect();
    let mut a0 = m0;
    for (i, &ui) in border.iter().enumerate() {
        a0[(i, k)] = ui;
    }
    let Some(y) = inverse(a0) else { return Bordered::Unknown };
    let w = rates.preconditioned(&y, cfg);
    let e = DMatrix::from_fn(n, n, |i, j| {
        if j == k {
            // Column k of Y·A is Y·u.
            border.iter().enumerate().fold(identity(i, j), |acc, (l, &ul)| acc.sub(Iv { lo: ul, hi: ul }.scale(y[(i, l)])))
        } else {
            identity(i, j).sub(w[(i, j)])
        }
    });
    let z = DVector::from_fn(n, |i, _| w[(i, k)].neg());
    let Some(x) = preconditioned_hull(&e, &z) else { return Bordered::Unknown };
    if !x[k].contains(0.0) {
        return Bordered::Empty;
    }
    Bordered::Kernel(k, x)
}

/// Where a configuration box's singular points are searched.
enum Plan {
    /// Proven to hold none.
    Empty,
    /// Chart `k` owns all of them; its search starts from this box.
    One(usize, IntervalBox),
    /// Not proven: every chart, from the configuration box.
    Every,
}

impl<L: Coordinates> SingularProblem<L> {
    /// The set of a 1-dof input or output set whose rows form `rates` (module doc): the
    /// configuration curve first, then each of its boxes not proven regular in its chart.
    /// `settings.max_boxes` applies to each search; `settings.timeout` to the whole call.
    pub(super) fn solve_points(&self, rates: &RateMatrix, settings: &SolverSettings, cancel: &AtomicBool) -> Result<SingularSet, SolveError> {
        if cancel.load(Ordering::Relaxed) || settings.timeout.is_some_and(|t| t.is_zero()) {
            // Nothing searched: the charts' one undecided box, as the whole-box search reports.
            return self.solve_charts(settings, cancel);
        }
        let t0 = Instant::now();
        let left = || settings.timeout.map(|t| t.saturating_sub(t0.elapsed()));
        let regular: Arc<dyn Filter + Send + Sync + '_> = Arc::new(Regular { rates, base_vars: self.base_vars });
        let curve_settings = SolverSettings { sigma: LEAF_WIDTH.max(settings.sigma), ..settings.clone() };
        let curve = self.linkage.extended_solver(self.linkage.system(), curve_settings)?.with_filter(regular);
        let mut leaves = Collect::default();
        let (mut status, curve_stats) = if settings.threads > 1 { curve.run_parallel(settings.threads, cancel, &mut leaves, None) } else { curve.run(cancel, &mut leaves) };
        let mut stats = vec![SolveStats::default(); self.chart_count()];
        let mut boxes = Vec::new();
        let mut dropped_other_chart = 0u64;
        let mut charts: Vec<Option<EquationSystem>> = vec![None; self.chart_count()];
        let undecided = |leaf: &IntervalBox| SingularBox { chart: 0, b: self.with_configuration(self.augmented.initial_box(), leaf), status: BoxStatus::Undecided };
        boxes.extend(leaves.undecided.iter().map(undecided));
        for (i, leaf) in leaves.solutions.iter().enumerate() {
            let remaining = left();
            let cancelled = cancel.load(Ordering::Relaxed);
            if cancelled || remaining.is_some_and(|r| r.is_zero()) {
                status = Status::Stopped(if cancelled { Limit::Cancelled } else { Limit::Time });
                boxes.extend(leaves.solutions[i..].iter().map(undecided));
                break;
            }
            let runs: Vec<(usize, IntervalBox)> = match self.plan(rates, leaf) {
                Plan::Empty => continue,
                Plan::One(k, start) => vec![(k, start)],
                Plan::Every => (0..self.chart_count()).map(|k| (k, self.with_configuration(self.chart_box(k), leaf))).collect(),
            };
            for (k, start) in runs {
                let chart = charts[k].get_or_insert_with(|| self.chart(k));
                let solver = self.linkage.extended_solver(chart, SolverSettings { timeout: left(), threads: 1, ..settings.clone() })?;
                let mut found = Collect::default();
                let (s, st) = solver.run_from(start, cancel, &mut found);
                if s != Status::Finished {
                    status = s;
                }
                add(&mut stats[k], &st);
                for (b, u) in found.solutions.into_iter().zip(found.tags.into_iter().map(|t| t == BoxStatus::Unique)) {
                    if self.owned_elsewhere(k, &b) {
                        dropped_other_chart += 1;
                        continue;
                    }
                    let certified = u && self.linkage.rows_faithful(&b);
                    boxes.push(SingularBox { chart: k, b, status: if certified { BoxStatus::Unique } else { BoxStatus::Solution } });
                }
                boxes.extend(found.undecided.into_iter().map(|b| SingularBox { chart: k, b, status: BoxStatus::Undecided }));
            }
        }
        // A point on the face between two configuration boxes is found from both (a bisection
        // line through a symmetric mechanism's point, say): two certified boxes of one chart
        // that meet hold one point when Krawczyk proves their hull holds exactly one root.
        let mut keep = vec![true; boxes.len()];
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                let (a, b) = (&boxes[i], &boxes[j]);
                if !keep[i] || !keep[j] || a.status != BoxStatus::Unique || b.status != BoxStatus::Unique || a.chart != b.chart {
                    continue;
                }
                let Some(chart) = charts[a.chart].as_ref() else { continue };
                if a.b.dims.iter().zip(&b.b.dims).any(|(x, y)| x.intersection(*y).is_empty()) {
                    continue;
                }
                let hull = IntervalBox { dims: a.b.dims.iter().zip(&b.b.dims).map(|(x, y)| x.convex_hull(*y)).collect(), level: a.b.level };
                if Newton::new(chart, f64::INFINITY).and_then(|mut n| n.certify(&hull)).is_some() {
                    keep[j] = false;
                }
            }
        }
        let boxes: Vec<SingularBox> = boxes.into_iter().zip(keep).filter_map(|(b, k)| k.then_some(b)).collect();
        // The curve's search comes after the charts' counters, so that entry k stays chart k's.
        stats.push(curve_stats);
        let mut set = self.clustered(boxes, status, stats, dropped_other_chart, 0, settings.threads);
        set.seconds = t0.elapsed().as_secs_f64();
        Ok(set)
    }

    /// Where the singular points of the configuration box `leaf` are searched (module doc).
    fn plan(&self, rates: &RateMatrix, leaf: &IntervalBox) -> Plan {
        let n = rates.order();
        let (k, x) = match bordered(rates, &leaf.dims[..self.base_vars]) {
            Bordered::Empty => return Plan::Empty,
            Bordered::Unknown => return Plan::Every,
            Bordered::Kernel(k, x) => (k, x),
        };
        if !(0..n).all(|j| j == k || if j < k { x[j].mag() < 1.0 } else { x[j].mag() <= 1.0 }) {
            return Plan::Every;
        }
        let mut start = self.with_configuration(self.chart_box(k), leaf);
        for (j, &mj) in self.multipliers.iter().enumerate() {
            if j != k {
                start.dims[mj] = x[j].intersection(start.dims[mj]);
            }
        }
        Plan::One(k, start)
    }

    /// Chart `k`'s initial box (`m_k = 1`) without building its system.
    fn chart_box(&self, k: usize) -> IntervalBox {
        let mut b = self.augmented.initial_box();
        b.dims[self.multipliers[k]] = interval(1.0, 1.0);
        b
    }

    /// `b` with its configuration part replaced by `configuration`'s.
    fn with_configuration(&self, mut b: IntervalBox, configuration: &IntervalBox) -> IntervalBox {
        b.dims[..self.base_vars].copy_from_slice(&configuration.dims[..self.base_vars]);
        b
    }
}

/// Adds one search's counters to a chart's.
fn add(total: &mut SolveStats, s: &SolveStats) {
    total.processed += s.processed;
    total.empty += s.empty;
    total.bisected += s.bisected;
    total.solutions += s.solutions;
    total.shrink_rounds += s.shrink_rounds;
    total.lp.solved += s.lp.solved;
    total.lp.unverified += s.lp.unverified;
    total.certified += s.certified;
    total.spurious_dropped += s.spurious_dropped;
    total.post_processing_cut_short |= s.post_processing_cut_short;
    total.max_level = total.max_level.max(s.max_level);
    total.seconds += s.seconds;
    total.cpu_seconds += s.cpu_seconds;
}

#[cfg(test)]
mod tests {
    use crate::model::urdf;
    use crate::formulate::{Coordinates, SingularKind, SingularProblem};
    use crate::kernel::search::SolverSettings;
    use std::sync::atomic::AtomicBool;

    /// A triple rocker (s + l > p + q): the crank turns back twice, the rocker twice.
    const TRIPLE_ROCKER: &str = r#"<robot name="triple_rocker">
  <link name="ground"/><link name="crank"/><link name="coupler"/><link name="rocker"/>
  <joint name="crank_joint" type="continuous"><parent link="ground"/><child link="crank"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="coupler_joint" type="continuous"><parent link="crank"/><child link="coupler"/>
    <origin xyz="3 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="rocker_joint" type="continuous"><parent link="ground"/><child link="rocker"/>
    <origin xyz="4 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <loop name="closure" type="revolute">
    <predecessor link="coupler"><origin xyz="2.5 0 0" rpy="0 0 0"/></predecessor>
    <successor link="rocker"><origin xyz="3 0 0" rpy="0 0 0"/></successor>
    <axis xyz="0 0 1"/>
  </loop>
</robot>"#;

    #[test]
    fn the_curve_search_finds_what_every_chart_finds() {
        let m = urdf::parse(TRIPLE_ROCKER).expect("parses");
        let settings = SolverSettings { sigma: 1e-6, ..Default::default() };
        let cancel = AtomicBool::new(false);
        for (kind, actuated, output) in [
            (SingularKind::Input, "crank_joint", None),
            (SingularKind::Input, "rocker_joint", None),
            (SingularKind::Output, "crank_joint", Some(crate::formulate::Output::Joints(vec!["rocker_joint".into()]))),
        ] {
            let p = SingularProblem::new(&m, &[], kind, &[actuated.to_string()], output).expect("builds");
            let rates = p.linkage.rate_matrix(kind, &p.actuated, p.output.as_ref()).expect("square rows");
            let fast = p.solve_points(&rates, &settings, &cancel).expect("valid");
            let charts = p.solve_charts(&settings, &cancel).expect("valid");
            assert!(fast.status.finished() && charts.status.finished());
            assert_eq!(fast.clusters.len(), 2, "{kind:?} {actuated}");
            assert_eq!(fast.certified_clusters(), 2, "{kind:?} {actuated}");
            assert_eq!(fast.boxes.len(), 2, "{kind:?} {actuated}: one box per point");
            assert_eq!(charts.clusters.len(), 2, "{kind:?} {actuated}");
            // The same points, in the same charts: each box of one run meets a box of the other.
            for a in &fast.boxes {
                assert!(charts.boxes.iter().any(|b| b.chart == a.chart && a.b.dims.iter().zip(&b.b.dims).all(|(x, y)| !x.intersection(*y).is_empty())), "{kind:?} {actuated}: {a:?}");
            }
            // The curve search's counters come after the charts'.
            assert_eq!(fast.stats.len(), p.chart_count() + 1);
        }
        // The bundled crank-rocker's rocker dead centres at crank ±2π/3 lie on bisection lines
        // (cos = −1/2): found from two boxes each, reported once.
        let m = urdf::parse(include_str!("../../../urdf/four_bar.urdf")).expect("parses");
        let p = SingularProblem::new(&m, &[], SingularKind::Output, &["crank_joint".to_string()], Some(crate::formulate::Output::Joints(vec!["rocker_joint".into()]))).expect("builds");
        let set = p.solve(&settings, &cancel).expect("valid");
        assert_eq!((set.clusters.len(), set.certified_clusters(), set.boxes.len()), (4, 4, 4));
    }
}

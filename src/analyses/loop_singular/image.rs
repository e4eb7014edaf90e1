//! The type-II singular set's image in actuator space, for 2-dof linkages whose actuated joints
//! are coordinates of their own (revolute joints to the ground, sliders): the searches on the
//! cusp and node systems of `formulate::singular::image` (whose doc gives the systems), certified
//! like the 3R ones (Krawczyk, as in Benoit, Delanoue, Lagrange and Wenger 2019), the regions of
//! actuator space the set cuts and the assembly modes over each, the verdict on non-singular
//! assembly-mode change, and the JSON report (`ImageReport`).
//!
//! ## ActuatorRegions and the verdict
//! The image of `S`'s cover is rasterised on a grid of actuator space (periodic for revolute
//! actuators); the free cells' connected components are regions, and over one sample point of
//! each a certified `solve` counts the configurations and the sign of `det F_p` (the passive
//! Jacobian) at each. `det F_p ≠ 0` on `C ∖ S`, so an assembly-mode change without crossing `S`
//! joins two configurations over the same actuator point with the same sign, and by
//! continuation inside the region two such configurations over every point of a region.
//! - **yes**: a certified cusp (encircling it changes assembly mode, McAree & Daniel 1999).
//! - **no**: the cusp and node searches complete with none found, every region sampled,
//!   certified, and holding at most one configuration of each sign. What the grid cannot see:
//!   a region lying wholly inside the cover of `S` (thinner than the boxes); with no cusp and no
//!   node the image is a union of disjoint embedded curves, so such a region would lie between
//!   two image curves closer than the cover's width (or inside a loop smaller than it).
//! - **undecided** otherwise, with the reason.

use crate::kernel::outcome::{BoxStatus, Completeness};
use crate::kernel::interval::{components, point, Bounds, Interval, IntervalBox};
use crate::formulate::singular::image::{CuspFormulation, CuspProblem, NodeProblem};
use crate::formulate::singular::SingularProblem;
use crate::analyses::arm3r::{cusps, nodes};
use crate::formulate::singular::pose::{LockedLegMap, PlatformTorus};
use crate::kernel::search::{Control, Limit, Limits, RefinePlan, Refinement, SettingsError, SolveError, SolveStats, Solver, SolverSettings, Status};
use crate::kernel::system::{EquationSystem, Monomial, VarId};
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

mod assembly;
mod report;

pub use self::assembly::{regions, verdict, ActuatorRegion, ActuatorRegions, AssemblyChangeVerdict, RASTER_BYTES_PER_CELL};
pub use self::report::{cusp_records, node_records, Counts, ImageCusp, ImageNode, ImagePoints, ImageReport};

/// True when every direction of `vars` in `b` (chart `k`: `vars[k] = 1`) is owned by another
/// chart (see `SingularProblem::owned_elsewhere`); `skip` is never the largest (fixed to 0).
fn owned_elsewhere(vars: &[VarId], k: usize, b: &[Interval], skip: Option<usize>) -> bool {
    vars.iter().enumerate().any(|(j, &m)| {
        if Some(j) == skip {
            return false;
        }
        let mig = b[m].mig();
        (j < k && mig >= 1.0) || (j > k && mig > 1.0)
    })
}

impl CuspProblem {
    /// The solver of chart pair `i`, at `settings`.
    fn chart_solver<'s>(&'s self, sp: &'s SingularProblem, i: usize, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        let chart = &self.charts[i].1;
        // The pose systems are not extensions of the linkage's: no joint-limit filter (the
        // pose formulation takes continuous revolute joints only, its travels bound h). Their
        // rows are general quadratics, which the LP relaxation leaves out: no LP shrink.
        match self.formulation {
            CuspFormulation::Pose => Solver::new(chart, SolverSettings { use_lp: false, ..settings }),
            _ => sp.linkage.extended_solver(chart, settings),
        }
    }

    /// True when `bx` of chart pair `i` is proven to be another chart's.
    fn other_chart(&self, i: usize, bx: &IntervalBox) -> bool {
        let (k, tau) = self.charts[i].0;
        owned_elsewhere(&self.v, k, &bx.dims, None) || owned_elsewhere(&self.tangent, tau, &bx.dims, Some(k + 1))
    }

    /// Runs the solver on every chart pair, in scaled widths (`scaled`); boxes proven to be
    /// another chart's are dropped, the rest clustered by configuration; each unproven cluster
    /// is then re-searched finer (`refine_points`).
    pub fn solve(&self, sp: &SingularProblem, settings: &SolverSettings, cancel: &AtomicBool) -> Result<PointSearch, SolveError> {
        if let Some(torus) = self.torus() {
            return solve_cusps_on_torus(torus, settings, cancel);
        }
        let t0 = Instant::now();
        let mut found = Vec::new();
        let mut status = Status::Finished;
        let mut stats = Vec::new();
        let mut dropped = 0u64;
        for (i, (_, chart)) in self.charts.iter().enumerate() {
            let Some(s) = remaining(settings, t0) else {
                status = Status::Stopped(Limit::Time);
                found.push(ChartBox { chart: i, b: chart.initial_box(), kind: BoxStatus::Undecided, note: None });
                continue;
            };
            let e = self.chart_solver(sp, i, s)?.enclose(cancel, &mut |_| {});
            if e.status != Status::Finished {
                status = e.status;
            }
            for (b, u) in e.solutions.into_iter().zip(e.tags.into_iter().map(|t| t == BoxStatus::Unique)) {
                if self.other_chart(i, &b) {
                    dropped += 1;
                    continue;
                }
                found.push(ChartBox { chart: i, b, kind: if u { BoxStatus::Unique } else { BoxStatus::Solution }, note: None });
            }
            found.extend(e.undecided.into_iter().map(|b| ChartBox { chart: i, b, kind: BoxStatus::Undecided, note: None }));
            stats.push(e.stats);
        }
        let tangent = self.tangent[0];
        let cluster = |found: &[ChartBox]| self.cluster(sp, found);
        // Proven: every box certified with μ away from 0, and the cluster one root (`unique`).
        let proven = |p: &FoundPoint| p.unproven_reason(Status::Finished).is_none();
        let accept = |b: &[IntervalBox], t: &[BoxStatus]| t.iter().all(|t| *t == BoxStatus::Unique) && b.iter().all(|b| !b.dims[tangent].contains(0.0));
        let found = refine_points(found, &cluster, &proven, &|i, s| self.chart_solver(sp, i, s), &|i, b| self.other_chart(i, b), &accept, settings, t0, cancel)?;
        let points = cluster(&found);
        Ok(PointSearch { status, points, stats, dropped_other_chart: dropped, seconds: t0.elapsed().as_secs_f64() })
    }

    /// The clusters of `found` by configuration (the base variables).
    fn cluster(&self, sp: &SingularProblem, found: &[ChartBox]) -> Vec<FoundPoint> {
        let projected: Vec<IntervalBox> = found.iter().map(|c| IntervalBox::new(c.b.dims[..self.base_vars].to_vec())).collect();
        let (labels, n) = components(&projected);
        let mut points: Vec<FoundPoint> = (0..n).map(|_| FoundPoint::default()).collect();
        for (c, &l) in found.iter().zip(&labels) {
            let p = &mut points[l];
            p.boxes.push(c.b.clone());
            p.kinds.push(c.kind);
            p.members.push(c.chart);
            if let Some(note) = &c.note {
                if !p.refinement.contains(note) {
                    p.refinement.push(note.clone());
                }
            }
        }
        for p in &mut points {
            // μ away from 0 on every certified box: a tangent, so a cusp (not a corank-2 point).
            p.degenerate = p.boxes.iter().any(|bx| bx.dims[self.tangent[0]].contains(0.0));
            for b in &p.boxes {
                widen(&mut p.joints, bounds(self.joint_values(sp, b)));
            }
        }
        points
    }
}

/// The limits of `settings` as a `Control` with `cancel`.
pub(super) fn control_of<'c>(settings: &SolverSettings, cancel: &'c AtomicBool) -> Control<'c> {
    Control { limits: Limits { max_cells: settings.max_boxes, timeout: settings.timeout, max_memory: settings.max_memory }, threads: settings.threads, cancel }
}

/// The 3R arms' cusp search (`arm3r::cusps`) on a platform's actuator map, at precision
/// sigma (radians of both angles). A box the search leaves at the precision unproven (too
/// coarse for Krawczyk near a cusp, at the image's sigma) is settled by the same search at the
/// finer precisions of `RefinePlan`: each round is complete on its own, and the first round
/// that leaves nothing at the precision is kept (the last one tried otherwise). Returns the
/// round kept and the precisions tried after the first.
fn torus_cusps(map: &LockedLegMap, settings: &SolverSettings, control: &Control, t0: Instant) -> Result<(cusps::CuspSearch, Vec<f64>), SolveError> {
    in_rounds(settings, t0, |precision| {
        let cusp_settings = cusps::CuspSettings { precision, method: cusps::Method::Krawczyk };
        let round = cusps::search_with(map, &cusp_settings, &control.remaining_since(t0), &mut |_| {}).map_err(|_| SettingsError::Sigma(settings.sigma))?;
        let settled = round.status != Status::Finished || round.undecided.is_empty() && round.cusps.iter().all(|c| c.unique);
        Ok((round, settled))
    })
}

/// Runs `search` at precision sigma (at most 0.5 rad), then, while a round leaves boxes at the
/// precision undecided (`settled` false) and time is left, at the finer precisions of
/// `RefinePlan`. Each round is a complete search on its own; the first settled round is kept
/// (the last one run otherwise), with the precisions tried after the first.
fn in_rounds<T>(settings: &SolverSettings, t0: Instant, mut search: impl FnMut(f64) -> Result<(T, bool), SolveError>) -> Result<(T, Vec<f64>), SolveError> {
    settings.validate()?;
    // Boxes are at most sigma wide in both angles; the torus searches take precisions below one
    // radian, and a box half a radian wide is already coarser than any useful answer.
    let sigma = settings.sigma.min(0.5);
    let (mut kept, mut settled) = search(sigma)?;
    let mut tried = Vec::new();
    for d in RefinePlan::default().divisors {
        if settled || settings.timeout.is_some_and(|t| t0.elapsed() >= t) {
            break;
        }
        tried.push(sigma / d);
        (kept, settled) = search(sigma / d)?;
    }
    Ok((kept, tried))
}

/// The kernel's counters of a search on the torus, as the solver's.
fn torus_stats(stats: &crate::kernel::search::Stats, certified: u64) -> SolveStats {
    SolveStats {
        processed: stats.processed,
        empty: stats.discarded_total(),
        bisected: stats.split,
        solutions: stats.found,
        certified,
        max_level: stats.max_level,
        seconds: stats.seconds,
        cpu_seconds: stats.cpu_seconds,
        ..Default::default()
    }
}

/// The cusps of the `Torus` formulation (`torus_cusps`). Each certified cusp is one point (the
/// search proves `∇det ≠ 0` there: a Whitney cusp, never a corank-two point); a cusp whose
/// travels lie outside a slider's limits is no configuration and is dropped, one that may lie
/// on a limit stays unproven. Undecided boxes are clustered. Boxes are written in the pose
/// systems' variables (`PlatformTorus::pose_box`), so readings and clustering are theirs.
fn solve_cusps_on_torus(torus: &PlatformTorus, settings: &SolverSettings, cancel: &AtomicBool) -> Result<PointSearch, SolveError> {
    let t0 = Instant::now();
    let map = &torus.map;
    let (found, tried) = torus_cusps(map, settings, &control_of(settings, cancel), t0)?;
    let refined = (!tried.is_empty()).then(|| format!("searched again at precisions {}", tried.iter().map(|p| format!("{p:e}")).collect::<Vec<_>>().join(", ")));
    let mut points = Vec::new();
    for c in &found.cusps {
        let (kind, note) = match map.within_travel(c.theta) {
            Some(false) => continue,
            Some(true) if c.unique => (BoxStatus::Unique, None),
            Some(true) => (BoxStatus::Solution, None),
            None => (BoxStatus::Solution, Some("its travels may lie on a slider's limit".to_string())),
        };
        let refinement = note.into_iter().chain(refined.clone().filter(|_| kind != BoxStatus::Unique)).collect();
        points.push(FoundPoint { boxes: vec![torus.pose_box(c.theta)], kinds: vec![kind], degenerate: false, joints: bounds(torus.joint_values(c.theta)), members: vec![0], refinement });
    }
    // Undecided boxes, clustered; those proven outside the travels hold no configuration.
    let open: Vec<&cusps::Undecided> = found.undecided.iter().filter(|u| map.within_travel(u.theta) != Some(false)).collect();
    let (labels, n) = components(&open.iter().map(|u| IntervalBox::new(u.theta.to_vec())).collect::<Vec<_>>());
    for l in 0..n {
        let mut p = FoundPoint::default();
        for (u, _) in open.iter().zip(&labels).filter(|(_, k)| **k == l) {
            p.boxes.push(torus.pose_box(u.theta));
            p.members.push(0);
            p.kinds.push(if u.reason == cusps::Reason::Limit { BoxStatus::Undecided } else { BoxStatus::Solution });
            widen(&mut p.joints, bounds(torus.joint_values(u.theta)));
            let why = "∇det may vanish there: a crossing of the type-II curve rather than a cusp?";
            if u.reason == cusps::Reason::GradDetMayVanish && !p.refinement.iter().any(|r| r == why) {
                p.refinement.push(why.to_string());
            }
        }
        p.refinement.extend(refined.clone());
        points.push(p);
    }
    let certified = found.cusps.iter().filter(|c| c.unique).count() as u64;
    Ok(PointSearch { status: found.status, points, stats: vec![torus_stats(&found.stats, certified)], dropped_other_chart: 0, seconds: t0.elapsed().as_secs_f64() })
}

/// The nodes of the `Torus` formulation: the 3R arms' node search (`arm3r::nodes`, system
/// (3) of Benoit et al. (2019) over pairs of torus boxes) on the platform's actuator map, at
/// precision sigma and, while pairs stay undecided at the precision, finer (`in_rounds`), with the
/// certified cusps of `torus_cusps` for its injectivity certificates near cusps. A node one of
/// whose points lies outside a slider's travel is dropped; one that may lie on a limit stays
/// unproven.
fn solve_nodes_on_torus(torus: &PlatformTorus, settings: &SolverSettings, cancel: &AtomicBool) -> Result<NodeSearch, SolveError> {
    let t0 = Instant::now();
    let map = &torus.map;
    let control = control_of(settings, cancel);
    let (found_cusps, _) = torus_cusps(map, settings, &control, t0)?;
    let (found, _) = in_rounds(settings, t0, |precision| {
        let node_settings = nodes::NodeSettings { precision };
        let round = nodes::search_with(map, &found_cusps.cusps, &[], &node_settings, &control.remaining_since(t0), &mut |_| {}).map_err(|_| SettingsError::Sigma(settings.sigma))?;
        let settled = round.status != Status::Finished || round.undecided.is_empty();
        Ok((round, settled))
    })?;
    let mut pairs = Vec::new();
    let certified = found.nodes.iter().map(|n| (n.theta, true));
    let open = found.undecided.iter().map(|t| (*t, false));
    for (theta, proven) in certified.chain(open) {
        let (a, b) = (map.within_travel(theta[0]), map.within_travel(theta[1]));
        if a == Some(false) || b == Some(false) {
            continue;
        }
        let kind = match (proven, a == Some(true) && b == Some(true)) {
            (true, true) => BoxStatus::Unique,
            (true, false) => BoxStatus::Solution,
            (false, _) if found.status == Status::Finished => BoxStatus::Solution,
            (false, _) => BoxStatus::Undecided,
        };
        pairs.push(NodePair { joints: [bounds(torus.joint_values(theta[0])), bounds(torus.joint_values(theta[1]))], kind });
    }
    let stats = torus_stats(&found.stats, found.nodes.len() as u64);
    Ok(NodeSearch { status: found_cusps.status.and(found.status), pairs, near_diagonal: Vec::new(), injective: found.stats.discarded.get("injective").copied().unwrap_or(0), dropped_other_chart: 0, stats: vec![stats], seconds: t0.elapsed().as_secs_f64() })
}

/// A box of a point search, with the chart (system) it is a box of.
#[derive(Clone, Debug)]
struct ChartBox {
    chart: usize,
    b: IntervalBox,
    kind: BoxStatus,
    /// What a refinement tried on it without settling it.
    note: Option<String>,
}

/// The refinement of a point search (cusps, nodes): each cluster of `found` (`cluster`) that is
/// not `proven` is re-searched, one chart at a time, by that chart's solver (`solver`) on the
/// hull of the cluster's boxes of that chart (`Solver::refine`, the default `RefinePlan`), with
/// a share of the time left of `settings.timeout` (counted from `t0`). When every chart of the
/// cluster settles (each round's output `accept`ed), the cluster's boxes are replaced by the
/// refined ones, minus those proven another chart's (`other_chart`) and those meeting none of
/// the chart's original boxes (a root there lies in a box of another cluster, or of none, since
/// the first search is complete on its chart's domain). Otherwise the cluster stays as it was,
/// its boxes noting what was tried.
#[allow(clippy::too_many_arguments)]
fn refine_points<'s>(
    mut found: Vec<ChartBox>,
    cluster: &dyn Fn(&[ChartBox]) -> Vec<FoundPoint>,
    proven: &dyn Fn(&FoundPoint) -> bool,
    solver: &dyn Fn(usize, SolverSettings) -> Result<Solver<'s>, SolveError>,
    other_chart: &dyn Fn(usize, &IntervalBox) -> bool,
    accept: &dyn Fn(&[IntervalBox], &[BoxStatus]) -> bool,
    settings: &SolverSettings,
    t0: Instant,
    cancel: &AtomicBool,
) -> Result<Vec<ChartBox>, SolveError> {
    let points = cluster(&found);
    let todo: Vec<&FoundPoint> = points.iter().filter(|p| !proven(p)).collect();
    let plan = RefinePlan::default();
    let mut replaced = vec![false; found.len()];
    let mut added = Vec::new();
    for (n, p) in todo.iter().enumerate() {
        let mut charts: Vec<usize> = p.members.clone();
        charts.sort_unstable();
        charts.dedup();
        let mut results = Vec::new();
        let mut note = None;
        for &c in &charts {
            let Some(s) = remaining(settings, t0) else {
                note = Some("not re-searched finer: no time left".to_string());
                break;
            };
            let share = s.timeout.map(|t| t / (todo.len() - n) as u32);
            let boxes: Vec<IntervalBox> = p.boxes.iter().zip(&p.members).filter(|(_, m)| **m == c).map(|(b, _)| b.clone()).collect();
            match solver(c, s)?.refine(&boxes, &plan, share, accept, cancel) {
                Refinement::Settled(out) => results.push((c, boxes, out)),
                Refinement::Unsettled(why) => {
                    note = Some(why);
                    break;
                }
                Refinement::TooWide => break,
            }
        }
        let members = |f: &ChartBox| p.boxes.iter().zip(&p.members).any(|(b, c)| *c == f.chart && *b == f.b);
        if note.is_none() && results.len() == charts.len() {
            for (i, f) in found.iter().enumerate() {
                if members(f) {
                    replaced[i] = true;
                }
            }
            for (c, originals, out) in results {
                for (b, u) in out.solutions.into_iter().zip(out.tags.into_iter().map(|t| t == BoxStatus::Unique)) {
                    if other_chart(c, &b) || !originals.iter().any(|o| o.intersects(&b)) {
                        continue;
                    }
                    added.push(ChartBox { chart: c, b, kind: if u { BoxStatus::Unique } else { BoxStatus::Solution }, note: None });
                }
            }
        } else if let Some(why) = note {
            for f in found.iter_mut().filter(|f| members(f)) {
                f.note = Some(why.clone());
            }
        }
    }
    let mut kept: Vec<ChartBox> = found.drain(..).zip(replaced).filter(|(_, r)| !r).map(|(f, _)| f).collect();
    kept.extend(added);
    Ok(kept)
}

/// The settings for the rest of a run that started at `t0`; `None` when no time is left.
/// Widths are scaled (`SolverSettings::scaled_widths`): see `scaled`.
fn remaining(settings: &SolverSettings, t0: Instant) -> Option<SolverSettings> {
    let left = settings.timeout.map(|t| t.saturating_sub(t0.elapsed()));
    if left.is_some_and(|r| r.is_zero()) {
        return None;
    }
    Some(SolverSettings { timeout: left, ..scaled(settings) })
}

/// `settings` with `scaled_widths` on, as the image searches (cover, cusps, nodes) run: their
/// systems mix travels (a slider's range, [1, 40] on the 3-RPR), cosines and sines ([−1, 1])
/// and chart directions ([−1.05, 1.05]); in absolute widths sigma and the bisection treat a
/// travel as twenty times longer than an angle, so the searches tile `S` twenty times finer
/// along the travels than across the angles (the 3-RPR cusp search: over ten minutes, against
/// under a minute scaled). On mechanisms without sliders every unit is 1 or 1.05.
pub fn scaled(settings: &SolverSettings) -> SolverSettings {
    SolverSettings { scaled_widths: true, ..settings.clone() }
}

/// A cluster of boxes of a point search (cusps).
#[derive(Clone, Debug, Default)]
pub struct FoundPoint {
    /// The boxes (in the chart system's variables).
    pub boxes: Vec<IntervalBox>,
    /// Their kinds.
    pub kinds: Vec<BoxStatus>,
    /// `μ` may vanish: possibly a corank-two point rather than a cusp.
    pub degenerate: bool,
    /// Free joint values, the hull over the boxes (radians or metres).
    pub joints: BTreeMap<String, Bounds>,
    /// Per box, the chart (system) it is a box of.
    pub members: Vec<usize>,
    /// What a finer re-search tried without settling the cluster.
    pub refinement: Vec<String>,
}

impl FoundPoint {
    /// Holds a certified box.
    pub fn certified(&self) -> bool {
        self.kinds.contains(&BoxStatus::Unique)
    }

    /// Exactly one root proven: every box certified and all overlapping the first (the same
    /// root seen from two charts).
    pub fn unique(&self) -> bool {
        self.kinds.iter().all(|k| *k == BoxStatus::Unique) && self.boxes.iter().all(|b| self.boxes[0].dims.iter().zip(&b.dims).all(|(x, y)| !x.intersection(*y).is_empty()))
    }

    /// Why the cluster is not one proven cusp (`None` when it is): the first of a limit that
    /// left boxes unsearched, `μ` that may vanish, boxes at sigma without a proof, and certified
    /// boxes that do not overlap (possibly several roots); then what a finer re-search tried
    /// without settling it (`refine_points`). `status` is the search's.
    pub fn unproven_reason(&self, status: Status) -> Option<String> {
        let why = self.unproven_alone(status)?;
        Some(if self.refinement.is_empty() { why } else { format!("{why}; {}", self.refinement.join("; ")) })
    }

    fn unproven_alone(&self, status: Status) -> Option<String> {
        if self.kinds.contains(&BoxStatus::Undecided) {
            let limit = match status {
                Status::Stopped(l) => format!("its {} limit", l.name()),
                Status::Finished => "a limit".to_string(),
            };
            return Some(format!("the search stopped on {limit} with boxes of this cluster unsearched"));
        }
        if self.degenerate {
            return Some("μ may vanish: possibly a corank-two point of the type-II set rather than a cusp".to_string());
        }
        let unproven = self.kinds.iter().filter(|k| **k == BoxStatus::Solution).count();
        if unproven > 0 {
            return Some(format!("{unproven} of its {} boxes reached sigma without a Krawczyk proof (a multiple root or a curve of roots there?)", self.boxes.len()));
        }
        (!self.unique()).then(|| format!("{} certified boxes that do not all overlap: possibly more than one cusp", self.boxes.len()))
    }
}

/// The result of the cusp search.
#[derive(Clone, Debug)]
pub struct PointSearch {
    /// Complete, or the last limit met.
    pub status: Status,
    /// Clusters by configuration.
    pub points: Vec<FoundPoint>,
    /// Per chart pair, the solver's counters.
    pub stats: Vec<SolveStats>,
    /// Boxes dropped as another chart's.
    pub dropped_other_chart: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl PointSearch {
    /// Proven cusps: certified clusters with `μ ≠ 0`.
    pub fn proven(&self) -> usize {
        self.points.iter().filter(|p| p.certified() && !p.degenerate).count()
    }
}

impl NodeProblem {
    /// Runs the node search: on the torus for a platform with a locked leg
    /// (`solve_nodes_on_torus`), otherwise on the doubled systems in scaled widths (`scaled`).
    pub fn solve(&self, sp: &SingularProblem, settings: &SolverSettings, cancel: &AtomicBool) -> Result<NodeSearch, SolveError> {
        if let Some(torus) = self.torus() {
            return solve_nodes_on_torus(torus, settings, cancel);
        }
        let t0 = Instant::now();
        let mut status = Status::Finished;
        let mut out = NodeSearch { status, pairs: Vec::new(), near_diagonal: Vec::new(), injective: 0, dropped_other_chart: 0, stats: Vec::new(), seconds: 0.0 };
        let config: Vec<VarId> = (0..sp.base_vars).filter(|i| !self.shared.contains(i)).collect();
        for ((k, k2), system, map) in &self.charts {
            let Some(s) = remaining(settings, t0) else {
                status = Status::Stopped(Limit::Time);
                out.near_diagonal.push(system.initial_box());
                continue;
            };
            let e = sp.linkage.extended_solver(system, s)?.enclose(cancel, &mut |_| {});
            if e.status != Status::Finished {
                status = e.status;
            }
            let mapped: Vec<VarId> = sp.multipliers.iter().map(|&m| map[m]).collect();
            let boxes = e.solutions.into_iter().zip(e.tags);
            for (bx, kind) in boxes.chain(e.undecided.into_iter().map(|b| (b, BoxStatus::Undecided))) {
                let d = &bx.dims;
                if owned_elsewhere(&sp.multipliers, *k, d, None) || owned_elsewhere(&mapped, *k2, d, None) {
                    out.dropped_other_chart += 1;
                    continue;
                }
                let apart = config.iter().find(|&&i| d[i].intersection(d[map[i]]).is_empty());
                match apart {
                    Some(&i) => {
                        // In (k, k) both orders of a pair are roots: keep copy A first.
                        if k == k2 && d[i].sup() > d[map[i]].inf() {
                            continue;
                        }
                        let a = IntervalBox::new(d[..sp.base_vars].to_vec());
                        let b = IntervalBox::new((0..sp.base_vars).map(|j| d[map[j]]).collect());
                        out.pairs.push(NodePair { joints: [bounds(sp.joint_values(&a)), bounds(sp.joint_values(&b))], kind });
                    }
                    None if k == k2 && kind != BoxStatus::Undecided && injective(&sp.chart(*k), &self.shared, &bx, map) => out.injective += 1,
                    None => out.near_diagonal.push(bx),
                }
            }
            out.stats.push(e.stats);
        }
        out.status = status;
        out.seconds = t0.elapsed().as_secs_f64();
        Ok(out)
    }
}

/// Joint values as `Bounds`.
pub(super) fn bounds(values: BTreeMap<String, (f64, f64)>) -> BTreeMap<String, Bounds> {
    values.into_iter().map(|(n, v)| (n, [v.0, v.1])).collect()
}

/// `joints` widened to hold `more` too.
fn widen(joints: &mut BTreeMap<String, Bounds>, more: BTreeMap<String, Bounds>) {
    for (n, v) in more {
        let e = joints.entry(n).or_insert(v);
        *e = [e[0].min(v[0]), e[1].max(v[1])];
    }
}

/// The actuated joints' values among `joints`: a point's image in actuator space.
pub(super) fn actuator_image(sp: &SingularProblem, joints: &BTreeMap<String, Bounds>) -> BTreeMap<String, Bounds> {
    sp.actuated.iter().filter_map(|a| joints.get(a).map(|b| (a.clone(), *b))).collect()
}

/// A node pair: the free joint values over its two configuration boxes.
#[derive(Clone, Debug)]
pub struct NodePair {
    /// The two points' joint values (radians or metres).
    pub joints: [BTreeMap<String, Bounds>; 2],
    /// Certified (one pair in the doubled box), solution (unproven) or undecided (a limit).
    pub kind: BoxStatus,
}

/// The result of the node search.
#[derive(Clone, Debug)]
pub struct NodeSearch {
    /// Complete, or the last limit met.
    pub status: Status,
    /// Pairs of disjoint configuration boxes with shared actuator values.
    pub pairs: Vec<NodePair>,
    /// Doubled boxes meeting the diagonal without an injectivity certificate (undecided).
    pub near_diagonal: Vec<IntervalBox>,
    /// Doubled boxes meeting the diagonal dropped by the injectivity certificate.
    pub injective: u64,
    /// Boxes dropped as another chart's.
    pub dropped_other_chart: u64,
    /// Per chart pair, the solver's counters.
    pub stats: Vec<SolveStats>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl NodeSearch {
    /// Certified node pairs.
    pub fn proven(&self) -> usize {
        self.pairs.iter().filter(|p| p.kind == BoxStatus::Unique).count()
    }
    /// Unproven pairs plus near-diagonal boxes.
    pub fn undecided(&self) -> usize {
        self.pairs.len() - self.proven() + self.near_diagonal.len()
    }
}

/// The injectivity certificate of a doubled box meeting the diagonal (both copies in chart `sys`):
/// with the shared (actuator) variables fixed, the chart system's interval Jacobian over the hull
/// of both copies has full column rank, so the copies coincide (mean-value theorem).
fn injective(sys: &EquationSystem, shared: &[VarId], bx: &IntervalBox, map: &[VarId]) -> bool {
    let hull: Vec<Interval> = (0..sys.vars.len()).map(|i| bx.dims[i].convex_hull(bx.dims[map[i]])).collect();
    let cols: Vec<VarId> = (0..sys.vars.len()).filter(|i| !shared.contains(i)).collect();
    let col_of: BTreeMap<VarId, usize> = cols.iter().enumerate().map(|(j, &v)| (v, j)).collect();
    let mut rows: Vec<Vec<Interval>> = Vec::new();
    for e in &sys.equations {
        if e.vars().all(|v| shared.contains(&v)) {
            continue;
        }
        let mut row = vec![point(0.0); cols.len()];
        let mut add = |v: VarId, x: Interval| {
            if let Some(&j) = col_of.get(&v) {
                row[j] += x;
            }
        };
        for t in &e.terms {
            match t.mono {
                Monomial::Linear(x) => add(x, t.coef),
                Monomial::Square(x) => add(x, point(2.0) * t.coef * hull[x]),
                Monomial::Product(x, y) => {
                    add(x, t.coef * hull[y]);
                    add(y, t.coef * hull[x]);
                }
            }
        }
        rows.push(row);
    }
    full_column_rank(&rows)
}

/// True when every real matrix in the interval matrix `m` (rows ≥ columns) has full column rank:
/// `P = (M_cᵀ M_c)⁻¹ M_cᵀ` from the midpoint, and `‖I − P·M‖∞ < 1` in interval arithmetic.
pub fn full_column_rank(m: &[Vec<Interval>]) -> bool {
    let r = m.len();
    let Some(c) = m.first().map(Vec::len) else { return false };
    if r < c || c == 0 {
        return r >= c;
    }
    let mc: Vec<Vec<f64>> = m.iter().map(|row| row.iter().map(|x| x.mid()).collect()).collect();
    if mc.iter().flatten().any(|x| !x.is_finite()) {
        return false;
    }
    // Normal matrix and its inverse (Gauss–Jordan with partial pivoting, f64: only a preconditioner).
    let mut a: Vec<Vec<f64>> = (0..c).map(|i| (0..c).map(|j| (0..r).map(|k| mc[k][i] * mc[k][j]).sum::<f64>()).chain((0..c).map(move |j| if i == j { 1.0 } else { 0.0 })).collect()).collect();
    for col in 0..c {
        let p = (col..c).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs())).unwrap_or(col);
        if a[p][col].abs() < 1e-300 {
            return false;
        }
        a.swap(col, p);
        let piv = a[col][col];
        for x in a[col].iter_mut() {
            *x /= piv;
        }
        let pivot_row = a[col].clone();
        for (i, row) in a.iter_mut().enumerate() {
            let f = row[col];
            if i != col && f != 0.0 {
                for (x, y) in row.iter_mut().zip(&pivot_row) {
                    *x -= f * y;
                }
            }
        }
    }
    // P = N⁻¹ M_cᵀ.
    let p: Vec<Vec<f64>> = (0..c).map(|i| (0..r).map(|k| (0..c).map(|j| a[i][c + j] * mc[k][j]).sum()).collect()).collect();
    let mut norm = 0.0f64;
    for (i, p_row) in p.iter().enumerate() {
        let mut row_sum = point(0.0);
        for j in 0..c {
            let mut x = point(if i == j { 1.0 } else { 0.0 });
            for (pk, m_row) in p_row.iter().zip(m) {
                x -= point(*pk) * m_row[j];
            }
            row_sum += x.abs();
        }
        norm = norm.max(row_sum.sup());
    }
    norm < 1.0
}

/// Interval determinant by Laplace expansion along the first row (small matrices).
pub(super) fn det(m: &[Vec<Interval>]) -> Interval {
    match m.len() {
        0 => point(1.0),
        1 => m[0][0],
        2 => m[0][0] * m[1][1] - m[0][1] * m[1][0],
        n => (0..n).fold(point(0.0), |acc, j| {
            let minor: Vec<Vec<Interval>> = m[1..].iter().map(|row| row.iter().enumerate().filter(|(c, _)| *c != j).map(|(_, x)| *x).collect()).collect();
            let t = m[0][j] * det(&minor);
            if j % 2 == 0 {
                acc + t
            } else {
                acc - t
            }
        }),
    }
}

/// `complete` or `incomplete`, as the reports spell a status.
pub(super) fn status_word(s: Status) -> &'static str {
    Completeness::of_run(s).word()
}

#[cfg(test)]
mod tests;

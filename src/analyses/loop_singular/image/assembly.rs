//! The regions of actuator space the image of the type-II set cuts, and the verdict on
//! non-singular assembly-mode change (the module doc of `image` gives the argument): the
//! image of the set's cover rasterised on a grid (`Axis`), the free cells' components, a
//! certified solve at one sample of each (`sample_region`, or `sample_region_on_torus` for a
//! platform), then `verdict` from the searches and the regions.

use super::{control_of, det, status_word, NodeSearch, PointSearch};
use crate::analyses::arm3r::{self, TorusMap};
use crate::analyses::loop_singular::SingularSet;
use crate::formulate::linkage::LinkageProblem;
use crate::formulate::singular::image::{check, ImageError};
use crate::formulate::singular::pose::PlatformTorus;
use crate::formulate::singular::{Parts, SingularError, SingularProblem};
use crate::kernel::interval::{point, Interval, IntervalBox};
use crate::kernel::search::{Budget, Limit, Limits, SolverSettings, Status};
use crate::model::Mechanism;
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// One actuator axis of the region grid.
#[derive(Clone, Copy, Debug)]
struct Axis {
    lo: f64,
    hi: f64,
    periodic: bool,
}

impl Axis {
    fn cell(&self, i: usize, n: usize) -> (f64, f64) {
        let w = (self.hi - self.lo) / n as f64;
        (self.lo + w * i as f64, self.lo + w * (i + 1) as f64)
    }
    /// Does the cell `[a, b]` meet `[lo, hi]` (modulo 2π on a periodic axis)?
    fn meets(&self, (a, b): (f64, f64), (lo, hi): (f64, f64)) -> bool {
        if !(lo.is_finite() && hi.is_finite()) {
            return true;
        }
        let shifts: &[f64] = if self.periodic { &[-2.0 * PI, 0.0, 2.0 * PI] } else { &[0.0] };
        hi - lo >= self.hi - self.lo || shifts.iter().any(|s| lo + s <= b && a <= hi + s)
    }
    /// The cells of an `n`-cell axis that `[lo, hi]` meets, ascending: the index range of each
    /// shift, widened by a cell against rounding, each candidate then checked with `meets`, so
    /// the raster is exactly that of testing every cell, at the cost of the cells an image covers.
    fn cells_meeting(&self, (lo, hi): (f64, f64), n: usize) -> Vec<usize> {
        if !(lo.is_finite() && hi.is_finite()) || hi - lo >= self.hi - self.lo {
            return (0..n).collect();
        }
        let w = (self.hi - self.lo) / n as f64;
        let shifts: &[f64] = if self.periodic { &[-2.0 * PI, 0.0, 2.0 * PI] } else { &[0.0] };
        let mut out = Vec::new();
        for s in shifts {
            let first = (((lo + s - self.lo) / w).floor() - 1.0).max(0.0);
            let last = (((hi + s - self.lo) / w).floor() + 1.0).min(n as f64 - 1.0);
            if first <= last {
                out.extend(first as usize..=last as usize);
            }
        }
        out.sort_unstable();
        out.dedup();
        out.retain(|&i| self.meets(self.cell(i, n), (lo, hi)));
        out
    }
}

/// `ActuatorRegions::sign` of the linkage's own samples.
const SIGN_OF_F_P: &str = "det F_p";

/// Bytes the raster of a `grid × grid` region search holds per cell: the blocked flag, the
/// flood fill's reached flag and its member index.
pub const RASTER_BYTES_PER_CELL: usize = 2 + std::mem::size_of::<usize>();

/// A region of actuator space (a component of the grid's free cells) and its assembly modes.
#[derive(Clone, Debug)]
pub struct ActuatorRegion {
    /// Grid cells in the region.
    pub cells: usize,
    /// The sample point (actuator values, in the order of `actuated`).
    pub sample: Vec<f64>,
    /// Configurations over the sample, when every solution box was certified and the run complete.
    pub configurations: Option<usize>,
    /// Of those, how many with `ActuatorRegions::sign` `> 0` and `< 0` (`None` where a sign is
    /// not proven).
    pub signs: Option<[usize; 2]>,
    /// Certified solution boxes, unproven boxes, undecided boxes of the sample's solve.
    pub boxes: [usize; 3],
}

/// ActuatorRegions of actuator space cut by the image of `S`.
#[derive(Clone, Debug)]
pub struct ActuatorRegions {
    /// Grid cells per axis.
    pub grid: usize,
    /// `complete`, or `incomplete` when the deadline or cancel stopped the raster (then no
    /// region is listed).
    pub status: Status,
    /// Cells meeting the image of the cover of `S`.
    pub blocked_cells: usize,
    /// The function whose signs the regions count: `det F_p`, or on a platform's torus `det Df`
    /// of its actuator map, which vanishes on the same set (so its sign is `det F_p`'s, or the
    /// opposite, over the whole torus: the two counts may be swapped).
    pub sign: &'static str,
    /// The regions.
    pub regions: Vec<ActuatorRegion>,
    /// Wall-clock seconds (raster and samples).
    pub seconds: f64,
}

/// The regions of actuator space for `sp`'s input set `set` (its cover), on a `grid × grid`
/// raster, with a certified solve of `m` at one sample of each. `settings.timeout` bounds all
/// the samples together (each gets what the ones before it left, at least a millisecond, so a
/// sample that finds no time reports itself unproven instead of being skipped).
pub fn regions(m: &Mechanism, sp: &SingularProblem, set: &SingularSet, grid: usize, settings: &SolverSettings, cancel: &AtomicBool) -> Result<ActuatorRegions, ImageError> {
    check(sp)?;
    let t0 = Instant::now();
    // The kernel's own cancel-or-time check, from the same start.
    let budget = Budget::start(Limits { timeout: settings.timeout, ..Limits::default() }, cancel);
    let mut scratch = sp.linkage.system.clone();
    let parts = Parts::new(&sp.linkage, &mut scratch)?;
    let mut axes = Vec::new();
    for a in &sp.actuated {
        let (_, vars) = parts.own_coordinate(&sp.linkage, a).ok_or_else(|| ImageError::NotCoordinate(a.clone()))?;
        axes.push(if vars.len() == 2 {
            Axis { lo: -PI, hi: PI, periodic: true }
        } else {
            let d = sp.linkage.system.vars[vars[0]].domain;
            Axis { lo: d.inf(), hi: d.sup(), periodic: false }
        });
    }
    let images: Vec<Vec<(f64, f64)>> = set.boxes.iter().map(|b| sp.actuator_values(&b.b)).collect();
    let stopped = || budget.interrupted();
    let unfinished = |limit: Limit| ActuatorRegions { grid, status: Status::Stopped(limit), blocked_cells: 0, sign: SIGN_OF_F_P, regions: Vec::new(), seconds: t0.elapsed().as_secs_f64() };
    let mut blocked = vec![false; grid * grid];
    for (k, im) in images.iter().enumerate() {
        if k % 64 == 0 {
            if let Some(limit) = stopped() {
                return Ok(unfinished(limit));
            }
        }
        let rows = axes[0].cells_meeting(im[0], grid);
        for j in axes[1].cells_meeting(im[1], grid) {
            for &i in &rows {
                blocked[i * grid + j] = true;
            }
        }
    }
    if let Some(limit) = stopped() {
        return Ok(unfinished(limit));
    }
    let mut out = ActuatorRegions { grid, status: Status::Finished, blocked_cells: blocked.iter().filter(|b| **b).count(), sign: SIGN_OF_F_P, regions: Vec::new(), seconds: 0.0 };
    let wrap = |x: i64, ax: &Axis| if (0..grid as i64).contains(&x) { Some(x as usize) } else if ax.periodic { Some(x.rem_euclid(grid as i64) as usize) } else { None };
    let free_regions = crate::kernel::interval::flood_fill(grid * grid, |c| !blocked[c], |c, next| {
        let (i, j) = (c / grid, c % grid);
        for (axis, di) in [(0usize, -1i64), (0, 1), (1, -1), (1, 1)] {
            let (mut a, mut b) = (i as i64, j as i64);
            if axis == 0 { a += di } else { b += di }
            if let (Some(a), Some(b)) = (wrap(a, &axes[0]), wrap(b, &axes[1])) {
                next.push(a * grid + b);
            }
        }
    });
    if let Some(limit) = stopped() {
        return Ok(unfinished(limit));
    }
    // A platform with a locked leg is sampled on its torus (`sample_region_on_torus`).
    let torus = PlatformTorus::new(m, &sp.linkage.fixed_joints, &sp.actuated);
    if torus.is_some() {
        out.sign = "det Df";
    }
    for members in free_regions {
        let start = members[0];
        // The sample: the member cell nearest the members' mean (in grid indices), so a chart's
        // label sits inside the region rather than at its first cell; any cell would do for the
        // count, which is constant over the region.
        let n = members.len() as f64;
        let (mi, mj) = members.iter().fold((0.0, 0.0), |(a, b), &c| (a + (c / grid) as f64 / n, b + (c % grid) as f64 / n));
        let far = |c: usize| ((c / grid) as f64 - mi).powi(2) + ((c % grid) as f64 - mj).powi(2);
        let pick = members.iter().copied().min_by(|&x, &y| far(x).total_cmp(&far(y))).unwrap_or(start);
        let cells = members.len();
        let (i, j) = (pick / grid, pick % grid);
        let (a, b) = (axes[0].cell(i, grid), axes[1].cell(j, grid));
        let sample = vec![0.5 * (a.0 + a.1), 0.5 * (b.0 + b.1)];
        let left = SolverSettings { timeout: settings.timeout.map(|t| t.saturating_sub(t0.elapsed()).max(std::time::Duration::from_millis(1))), ..settings.clone() };
        out.regions.push(match &torus {
            Some(torus) => sample_region_on_torus(torus, &sample, cells, &left, cancel),
            None => sample_region(m, sp, &sample, cells, &left, cancel)?,
        });
    }
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// A certified solve with the actuators at `sample`: configurations and the signs of `det F_p`.
fn sample_region(m: &Mechanism, sp: &SingularProblem, sample: &[f64], cells: usize, settings: &SolverSettings, cancel: &AtomicBool) -> Result<ActuatorRegion, ImageError> {
    let fixed: Vec<(String, f64)> = sp.actuated.iter().cloned().zip(sample.iter().copied()).collect();
    let lp = LinkageProblem::new(m, &fixed, &[]).map_err(SingularError::from)?;
    let mut scratch = lp.system.clone();
    let parts = Parts::new(&lp, &mut scratch)?;
    let s = SolverSettings { sigma: settings.sigma.min(1e-6), ..settings.clone() };
    let Ok(solver) = lp.solver(s) else {
        return Ok(ActuatorRegion { cells, sample: sample.to_vec(), configurations: None, signs: None, boxes: [0, 0, 0] });
    };
    let e = solver.enclose(cancel, &mut |_| {});
    let certified: Vec<&IntervalBox> = e.solutions.iter().zip(&e.tags).filter(|(_, t)| **t == crate::kernel::outcome::BoxStatus::Unique).map(|(b, _)| b).collect();
    let boxes = [certified.len(), e.solutions.len() - certified.len(), e.undecided.len()];
    let complete = e.status == Status::Finished && boxes[1] == 0 && boxes[2] == 0;
    let configurations = complete.then_some(certified.len());
    let mut signs = Some([0usize, 0]);
    for b in &certified {
        let d = det(&parts.jacobian(&b.dims));
        match (d.inf() > 0.0, d.sup() < 0.0, signs.as_mut()) {
            (true, _, Some(s)) => s[0] += 1,
            (_, true, Some(s)) => s[1] += 1,
            _ => signs = None,
        }
    }
    Ok(ActuatorRegion { cells, sample: sample.to_vec(), configurations, signs: if complete { signs } else { None }, boxes })
}

/// `sample_region` on a platform's torus: every `(α, φ)` with the actuated legs' squared
/// lengths at the sample (`arm3r::ik::solve_target` on the actuator map), and the sign of
/// `det Df` at each. `det Df` vanishes exactly on the type-II set, as `det F_p` does, so a
/// path of configurations off the set keeps its sign: the regions' argument holds with it.
/// Solutions proven outside a slider's travel are no configurations; one that may lie on a
/// limit leaves the count unproven.
fn sample_region_on_torus(torus: &PlatformTorus, sample: &[f64], cells: usize, settings: &SolverSettings, cancel: &AtomicBool) -> ActuatorRegion {
    let map = &torus.map;
    let unproven = ActuatorRegion { cells, sample: sample.to_vec(), configurations: None, signs: None, boxes: [0, 0, 0] };
    let order = torus.actuated_order();
    let mut target = [Interval::EMPTY; 2];
    for (k, &i) in order.iter().enumerate() {
        target[k] = point(sample[i]).sqr();
    }
    let precision = settings.sigma.min(1e-6);
    let Ok(found) = arm3r::ik::solve_target(map, target, precision, &control_of(settings, cancel), &mut |_| {}) else {
        return unproven;
    };
    let mut counted = 0;
    let mut signs = Some([0usize, 0]);
    let mut open = found.clusters.len();
    for b in &found.unique {
        match map.within_travel(*b) {
            Some(false) => continue,
            Some(true) => {}
            None => {
                open += 1;
                continue;
            }
        }
        counted += 1;
        let d = TorusMap::derived(map, *b, 1).det.value();
        match (d.inf() > 0.0, d.sup() < 0.0, signs.as_mut()) {
            (true, _, Some(s)) => s[0] += 1,
            (_, true, Some(s)) => s[1] += 1,
            _ => signs = None,
        }
    }
    let complete = found.status == Status::Finished && open == 0;
    ActuatorRegion { cells, sample: sample.to_vec(), configurations: complete.then_some(counted), signs: if complete { signs } else { None }, boxes: [counted, 0, open] }
}

/// Can the mechanism change assembly mode without crossing a type-II singularity? `Some(true)`,
/// `Some(false)` or `None` (undecided), with the argument.
#[derive(Clone, Debug)]
pub struct AssemblyChangeVerdict {
    /// The answer, `None` while undecided.
    pub answer: Option<bool>,
    /// Why.
    pub reason: String,
}

impl AssemblyChangeVerdict {
    /// `yes`, `no` or `undecided`, as reports write it.
    pub fn word(&self) -> &'static str {
        match self.answer {
            Some(true) => "yes",
            Some(false) => "no",
            None => "undecided",
        }
    }
}

/// The verdict from the searches (see the module doc for what each answer rests on).
pub fn verdict(cover: &SingularSet, cusps: &PointSearch, nodes: &NodeSearch, regions: &ActuatorRegions) -> AssemblyChangeVerdict {
    if cusps.proven() > 0 {
        return AssemblyChangeVerdict { answer: Some(true), reason: format!("{} certified cusp(s) of the type-II image: a loop around one changes assembly mode without crossing a singularity", cusps.proven()) };
    }
    let mut gaps = Vec::new();
    if cover.status != Status::Finished {
        gaps.push("the type-II cover is incomplete".to_string());
    }
    if cusps.status != Status::Finished || !cusps.points.is_empty() {
        gaps.push(format!("the cusp search is {} with {} unproven cluster(s)", status_word(cusps.status), cusps.points.len()));
    }
    if nodes.status != Status::Finished || nodes.undecided() > 0 {
        gaps.push(format!("the node search is {} with {} undecided pair(s) or near-diagonal box(es)", status_word(nodes.status), nodes.undecided()));
    }
    if nodes.proven() > 0 {
        gaps.push(format!("{} certified node(s): the image crosses itself", nodes.proven()));
    }
    for (i, r) in regions.regions.iter().enumerate() {
        match r.signs {
            None => gaps.push(format!("region {i} (sample {:?}): configurations or their signs not proven", r.sample)),
            Some([p, n]) if p > 1 || n > 1 => gaps.push(format!("region {i} (sample {:?}): {p} configurations with det F_p > 0 and {n} with < 0 (two of one sign may be one sheet)", r.sample)),
            Some(_) => {}
        }
    }
    if let Status::Stopped(limit) = regions.status {
        gaps.push(format!("the raster of regions stopped early ({} limit)", limit.name()));
    } else if regions.regions.is_empty() {
        gaps.push("no region found on the grid".to_string());
    }
    if gaps.is_empty() {
        AssemblyChangeVerdict {
            answer: Some(false),
            reason: format!(
                "no cusp and no node (searches complete); over each of the {} regions the grid reaches, at most one configuration with each sign of det F_p, a sign no path off the type-II set can change (regions thinner than the cover are not sampled)",
                regions.regions.len()
            ),
        }
    } else {
        AssemblyChangeVerdict { answer: None, reason: gaps.join("; ") }
    }
}

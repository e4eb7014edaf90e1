//! The self-motion set of a seven-revolute arm at a tip pose (Burdick 1989): every
//! configuration within the joint limits that puts the tip frame at the pose, a union of curves.
//!
//! One joint is the curve's parameter. Its range is cut into cells; on each cell the other six
//! joints form a `Chain6R` whose coefficients enclose their values over every angle of the cell
//! (`Chain6R::holding_over`), and the 6R search (`ik::solve`) encloses every solution of the pose
//! over the cell. A box it certifies holds, for every parameter angle of its cell, exactly one
//! configuration (Krawczyk's test on interval coefficients is parametric): a certified piece of
//! arc, over which the other six joints are functions of the parameter. Boxes it cannot certify
//! (near a singular configuration of the six, or where the cell is too wide for the test) are
//! kept as solution boxes that may hold configurations; cells a limit leaves unsearched are kept
//! whole, undecided. Nothing within the limits is lost.
//!
//! Boxes that touch (the pieces of one arc meet at the cells' common angles) form clusters, the
//! candidate components; two components nearer than a box's width share one, and a component
//! crossing a continuous joint's seam at ±π is two.

use super::chain::Chain6R;
use super::ik::{self, PoseTarget};
use super::Manip6rError;
use crate::kernel::interval::{components, interval, Interval, IntervalBox};
use crate::kernel::search::{BoxStatus, Control, Limit, Stats, Status};
use crate::model::{JointKind, Mechanism};

/// A cell's solutions are pieces of curve whose extent is about the cell's width times their
/// slope: boxes up to this many cell widths that Krawczyk cannot certify are tried inflated.
const INFLATE_CELLS: f64 = 8.0;

/// Cells of the parameter's range searched at most: a finer cut is refused, not run.
pub const MAX_CELLS: usize = 100_000;

/// One box of the cover: an interval per joint of the seven, in chain order.
#[derive(Clone, Debug)]
pub struct MotionBox {
    /// The joints' intervals, base first (the parameter's is its cell).
    pub joints: Vec<Interval>,
    /// `Unique`: a certified piece of arc (exactly one configuration for every parameter angle
    /// of the cell); `Solution`: may hold configurations; `Undecided`: a cell left unsearched.
    pub tag: BoxStatus,
    /// Its cluster (touching boxes).
    pub cluster: usize,
}

/// The cover of a self-motion set.
#[derive(Clone, Debug)]
pub struct SelfMotionSet {
    /// The seven joints, base first.
    pub joints: Vec<String>,
    /// Index of the parameter joint in `joints`.
    pub parameter: usize,
    /// The parameter's range searched, and the width of its cells.
    pub range: (f64, f64),
    /// Width of a cell (radians).
    pub cell: f64,
    /// Cells searched, of all cells.
    pub cells: (usize, usize),
    /// The boxes, cell after cell.
    pub boxes: Vec<MotionBox>,
    /// Clusters of touching boxes.
    pub clusters: usize,
    /// `Finished` when every cell was searched to the end; otherwise the limit that stopped it.
    pub status: Status,
    /// The 6R searches' counters, summed.
    pub stats: Stats,
}

impl SelfMotionSet {
    /// Boxes certified as pieces of arc.
    pub fn certified(&self) -> usize {
        self.boxes.iter().filter(|b| b.tag == BoxStatus::Unique).count()
    }

    /// Complete when every cell was searched and every box certified.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        crate::kernel::outcome::Completeness::of(self.status, self.boxes.len() - self.certified(), false)
    }
}

/// What one cell's search found: its boxes over the seven joints with their tags, how it ended,
/// its counters, and whether it ran (a cell a limit kept from starting is kept whole).
struct CellCover {
    boxes: Vec<(Vec<Interval>, BoxStatus)>,
    status: Status,
    stats: Stats,
    searched: bool,
}

/// The revolute joints of `m` from `base` (default: the root) to `tip` (default: the end of the
/// revolute path), base first.
fn revolute_path(m: &Mechanism, base: Option<&str>, tip: &str) -> Vec<String> {
    let tip = m.link(tip).expect("invariant: the chain names its tip link");
    let path = m.path_to(tip);
    let start = base.and_then(|b| m.link(b)).map_or(0, |b| path.iter().position(|&j| m.joints[j].parent == b).unwrap_or(0));
    path[start..].iter().filter(|&&j| matches!(m.joints[j].kind, JointKind::Revolute { .. })).map(|&j| m.joints[j].name.clone()).collect()
}

/// The joint a self-motion set is parametrised by when none is named: the third revolute joint
/// from the base of the longest revolute path (the elbow of the arms sold with seven joints),
/// once that path is seven joints long.
pub fn default_parameter(m: &Mechanism) -> Result<String, Manip6rError> {
    let revolute = |l: usize| m.path_to(l).into_iter().filter(|&j| matches!(m.joints[j].kind, JointKind::Revolute { .. })).map(|j| m.joints[j].name.clone()).collect::<Vec<_>>();
    let longest = (0..m.links.len()).map(revolute).max_by_key(Vec::len).unwrap_or_default();
    match longest.len() {
        7 => Ok(longest[2].clone()),
        n => Err(Manip6rError::NotSixR(format!("a self-motion set is of seven revolute joints; the longest revolute path of '{}' has {n} (choose the chain with --base and --tip)", m.name))),
    }
}

/// The cover of the self-motion set of the seven-revolute chain of `m` from `base` to `tip` at
/// `target`, with `parameter` the joint whose range (its limits, or `within` them) is cut into
/// cells at most `cell` wide and
/// the other boxes at most `precision` wide, within `control`: its time shared by all cells, its
/// cell budget each cell's, its threads searching cells side by side.
#[allow(clippy::too_many_arguments)]
pub fn cover(m: &Mechanism, base: Option<&str>, tip: Option<&str>, parameter: &str, within: Option<(f64, f64)>, target: &PoseTarget, cell: f64, precision: f64, control: &Control) -> Result<SelfMotionSet, Manip6rError> {
    if !(cell.is_finite() && cell > 0.0 && cell <= 1.0) {
        return Err(Manip6rError::NotSixR(format!("the cell width must be a number of radians in (0, 1], got {cell}")));
    }
    let j = m.joint(parameter).ok_or_else(|| Manip6rError::NotSixR(format!("--parameter: '{parameter}' is not a joint of the file")))?;
    let JointKind::Revolute { limits } = m.joints[j].kind else {
        return Err(Manip6rError::NotSixR(format!("--parameter: joint '{parameter}' is not revolute")));
    };
    let pi = crate::analyses::arm3r::PI_UP;
    let limited = limits.map_or((-pi, pi), |(lo, hi)| (lo.max(-pi), hi.min(pi)));
    let range = match within {
        None => limited,
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() && lo < hi && lo.max(limited.0) < hi.min(limited.1) => (lo.max(limited.0), hi.min(limited.1)),
        Some((lo, hi)) => return Err(Manip6rError::NotSixR(format!("--range {lo},{hi}: not an interval that meets the range of '{parameter}', [{}, {}]", limited.0, limited.1))),
    };
    let count = ((range.1 - range.0) / cell).ceil().max(1.0);
    if count > MAX_CELLS as f64 {
        return Err(Manip6rError::NotSixR(format!("{count} cells of {cell} rad: at most {MAX_CELLS} (choose a wider --cell)")));
    }
    let count = count as usize;
    let edge = |k: usize| if k == count { range.1 } else { range.0 + (range.1 - range.0) * k as f64 / count as f64 };
    // The chain over the first cell tells the joints and whether seven remain with one held.
    let first = Chain6R::holding_over(m, base, tip, &[(parameter.to_string(), interval(edge(0), edge(1)))])?;
    let joints = revolute_path(m, base, &first.tip);
    let at = joints.iter().position(|n| n == parameter).ok_or_else(|| Manip6rError::NotSixR(format!("--parameter: joint '{parameter}' is not on the chain")))?;
    let start = std::time::Instant::now();
    let with_parameter = |six: &[Interval; 6], cell: Interval| {
        let mut all = six.to_vec();
        all.insert(at, cell);
        all
    };
    // Each cell is an independent search (the cells are spread over the threads, each search on
    // one): its boxes, or the limit that kept it from starting, with its counters. A cell not
    // started is kept whole, undecided.
    let cells: Vec<usize> = (0..count).collect();
    let run_cell = |&k: &usize| -> Result<CellCover, Manip6rError> {
        let span = interval(edge(k), edge(k + 1));
        let stopped = if control.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            Some(Limit::Cancelled)
        } else {
            control.limits.timeout.filter(|&t| start.elapsed() >= t).map(|_| Limit::Time)
        };
        if let Some(limit) = stopped {
            // The other joints' ranges do not depend on the cell.
            let whole = first.ranges.map(|(lo, hi)| interval(lo, hi));
            return Ok(CellCover { boxes: vec![(with_parameter(&whole, span), BoxStatus::Undecided)], status: Status::Stopped(limit), stats: Stats::default(), searched: false });
        }
        let chain = Chain6R::holding_over(m, base, tip, &[(parameter.to_string(), span)])?;
        let cell_control = Control { threads: 1, ..*control }.remaining_since(start);
        let found = ik::solve_over(&chain, target, precision, INFLATE_CELLS * span.wid(), &cell_control)?;
        let mut boxes: Vec<(Vec<Interval>, BoxStatus)> = found.unique.iter().map(|b| (with_parameter(b, span), BoxStatus::Unique)).collect();
        boxes.extend(found.clusters.iter().map(|c| (with_parameter(&c.hull, span), BoxStatus::Solution)));
        Ok(CellCover { boxes, status: found.status, stats: found.stats, searched: true })
    };
    let (mut boxes, mut stats, mut status, mut searched) = (Vec::new(), Stats::default(), Status::Finished, 0);
    for cell in crate::kernel::search::map_parallel(&cells, control.threads.max(1), run_cell) {
        let cell = cell?;
        boxes.extend(cell.boxes);
        status = status.and(cell.status);
        stats.processed += cell.stats.processed;
        stats.split += cell.stats.split;
        searched += usize::from(cell.searched);
    }
    let as_boxes: Vec<IntervalBox> = boxes.iter().map(|(b, _)| IntervalBox::new(b.clone())).collect();
    let (labels, clusters) = components(&as_boxes);
    Ok(SelfMotionSet {
        joints,
        parameter: at,
        range,
        cell: (range.1 - range.0) / count as f64,
        cells: (searched, count),
        boxes: boxes.into_iter().zip(labels).map(|((joints, tag), cluster)| MotionBox { joints, tag, cluster }).collect(),
        clusters,
        status,
        stats,
    })
}

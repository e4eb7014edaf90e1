//! Internal motions: the lines θ₃ = const of joint space on which f is constant.
//!
//! f forgets θ₂ exactly when the end point lies on the second axis, which depends on θ₃ only:
//! `a₂ × q(θ₃) = 0` with `q` the end point in the second joint's frame (`Chain3R::off_axis2`).
//! Every θ₃ where that may hold is enclosed by bisecting [-π, π] into dyadic cells no wider
//! than the precision and keeping the cells where all three components may vanish.
//! A run of kept cells is one `Band`: its `theta3` encloses the line(s), and its `strip` adds
//! one cell on each side, so every point outside the strip is at least one cell away from any
//! internal motion (the searches decide such points; boxes inside strips are set aside).
//! The cells are the very intervals the 2-D searches make by bisecting at midpoints, so a
//! search box is either inside a strip or has no interior point in common with it.

use super::chain::Chain3R;
use super::drive::{drive, no_progress, Order};
use crate::kernel::search::Control;
use crate::kernel::interval::interval;
use crate::kernel::search::{Limits, Prune, Status, Step};
use inari::Interval;

/// Upper end of the joint range: the smallest double above π, so [-PI_UP, PI_UP] covers the
/// whole circle.
pub const PI_UP: f64 = 3.1415926535897936;

/// The full joint range, as an interval.
pub(crate) fn full_range() -> Interval {
    interval(-PI_UP, PI_UP)
}

pub use crate::formulate::torus::Band;

/// How many internal-motion lines the true bands (`near` is `None`) hold: a line at θ₃ = ±π
/// gives a band at each end of [-π, π], one line on the circle.
pub fn line_count(bands: &[Band]) -> usize {
    let lines: Vec<&Band> = bands.iter().filter(|b| b.near.is_none()).collect();
    let seam = match (lines.first(), lines.last()) {
        (Some(first), Some(last)) if lines.len() > 1 => first.theta3[0] <= -std::f64::consts::PI && last.theta3[1] >= std::f64::consts::PI,
        _ => false,
    };
    lines.len() - usize::from(seam)
}

/// The cell no wider than `precision` at the upper (`upper`) or lower end of `cell`, by
/// repeated midpoint bisection.
fn fine_end(mut cell: Interval, precision: f64, upper: bool) -> Interval {
    while cell.wid() > precision {
        let m = cell.mid();
        cell = if upper { interval(m, cell.sup()) } else { interval(cell.inf(), m) };
    }
    cell
}

/// True when `t3` overlaps a strip without lying inside it: the searches then cut θ₃ first,
/// so that the box soon lies inside the strip or away from it.
pub(crate) fn straddles(bands: &[Band], t3: Interval) -> bool {
    bands.iter().any(|b| t3.inf() < b.strip[1] && b.strip[0] < t3.sup() && !b.holds(t3))
}

/// The θ₃ walk of `bands`: every leaf cell is reported (marked or not), with its place in the
/// θ₃ order, since runs of marked cells need their neighbours.
struct StripPrune<'a> {
    chain: &'a Chain3R,
    precision: f64,
    near: f64,
    /// The chain's lengths are uncertain (`Chain3R::uncertainty`).
    uncertain: bool,
}

impl Prune for StripPrune<'_> {
    type Cell = (Interval, Order);
    type Found = (Order, (Interval, bool, Option<f64>));
    type Reason = crate::kernel::search::NoDiscard;

    fn process(&mut self, (t, order): (Interval, Order)) -> Step<Self::Cell, Self::Found, crate::kernel::search::NoDiscard> {
        let off = self.chain.off_axis2(t);
        let possible = off.iter().all(|c| c.contains(0.0));
        // May the point come within `near` of the axis (each component's smallest magnitude)?
        let close = off.iter().all(|c| c.mig() <= self.near);
        if t.wid() <= self.precision {
            Step::Found((order, (t, possible || close, (close && !possible).then_some(self.near))))
        } else if !close {
            Step::Found((order, (t, false, None)))
        } else if self.uncertain && possible && [t.inf(), t.sup()].iter().all(|&e| self.chain.off_axis2(interval(e, e)).iter().all(|c| c.contains(0.0))) {
            // An uncertain arm's point may lie on the axis over a whole stretch of θ₃: a cell
            // where it may at both ends (and in between) lies inside that stretch's band, and
            // its halves would say the same down to the precision. Kept whole: the band's ends
            // are still found cell by cell, and a marked cell only ever widens a strip.
            Step::Found((order, (t, true, None)))
        } else {
            let m = t.mid();
            Step::Split([(interval(t.inf(), m), order.child(0, 2)), (interval(m, t.sup()), order.child(1, 2))].into_iter().collect())
        }
    }
}

/// Cells the walk of `bands_within` takes at most. A walk about the true lines of an exact arm
/// takes a few hundred (a line's cells are split only within the precision of it), and so does
/// an uncertain arm's, whose point may lie on the axis over a whole stretch of θ₃ (cells inside
/// it are kept whole: split, that stretch would go down to the precision, 5·10⁸ cells for
/// 0.05 rad at 1e-10). A bound for what no walk should need.
pub(crate) const BAND_CELLS: u64 = 1 << 20;

/// The internal-motion strips of `chain`, from dyadic cells no wider than `precision`, with no
/// limit but `BAND_CELLS`.
pub fn bands(chain: &Chain3R, precision: f64) -> Vec<Band> {
    bands_within(chain, precision, &Control::with_limits(Limits { timeout: None, ..Limits::default() })).0
}

/// The internal-motion strips of `chain`, from dyadic cells no wider than `precision`, found
/// within `control`'s time and cancel flag (and `BAND_CELLS`), with how the walk ended.
pub(crate) fn bands_within(chain: &Chain3R, precision: f64, control: &Control) -> (Vec<Band>, Status) {
    // Near-degenerate: the point within `near` of axis 2, where one turn of θ₂ moves the image
    // by less than a search box of this precision does (about precision × the arm's length).
    let near = precision * chain.length_scale() / (2.0 * std::f64::consts::PI);
    // Cells in order of θ₃, each marked when the end point may lie on axis 2 there, or
    // (second flag) is proven within `near` of it without being proven on it. A cell a limit
    // left unwalked is marked as one where the point may lie on the axis: a partial list of
    // cells would make strips unsound, while a wider strip is only set aside (and the limit
    // makes the answer incomplete).
    let limits = Limits { max_cells: BAND_CELLS, max_memory: usize::MAX, ..control.limits };
    let control = Control { limits, threads: 1, ..*control };
    let mut run = drive(|| StripPrune { chain, precision, near, uncertain: chain.uncertainty > 0.0 }, (full_range(), Order::ROOT), &control, &mut no_progress);
    run.found.extend(run.undecided.drain(..).map(|((t, order), _)| (order, (t, true, None))));
    run.found.sort_by_key(|(order, _)| *order);
    let cells: Vec<(Interval, bool, Option<f64>)> = run.found.into_iter().map(|(_, cell)| cell).collect();
    let mut out = Vec::new();
    let n = cells.len();
    let mut i = 0;
    while i < n {
        if !cells[i].1 {
            i += 1;
            continue;
        }
        let mut start = i;
        let mut near_bound: Option<f64> = None;
        while i < n && cells[i].1 {
            if let Some(d) = cells[i].2 {
                near_bound = Some(near_bound.map_or(d, |b: f64| b.max(d)));
            }
            i += 1;
        }
        // A run holding a cell where the point may lie on the axis is a true band: trimmed to
        // those cells (close-only cells beside it are within the strip's margin anyway).
        if let (Some(first), Some(last)) = ((start..i).find(|&k| cells[k].2.is_none()), (start..i).rev().find(|&k| cells[k].2.is_none())) {
            let end = i;
            start = first;
            i = last + 1;
            let (lo, hi) = (cells[start].0.inf(), cells[i - 1].0.sup());
            let below = if start > 0 { fine_end(cells[start - 1].0, precision, true).inf() } else { lo };
            let above = if i < n { fine_end(cells[i].0, precision, false).sup() } else { hi };
            out.push(Band { theta3: [lo, hi], strip: [below, above], near: None });
            i = end;
            continue;
        }
        let (lo, hi) = (cells[start].0.inf(), cells[i - 1].0.sup());
        // One fine cell on each side as margin, cut out of the neighbour by the same midpoint
        // bisections a search makes, so its outer end is a point every search cuts at too.
        let below = if start > 0 { fine_end(cells[start - 1].0, precision, true).inf() } else { lo };
        let above = if i < n { fine_end(cells[i].0, precision, false).sup() } else { hi };
        out.push(Band { theta3: [lo, hi], strip: [below, above], near: near_bound });
    }
    (out, run.status)
}

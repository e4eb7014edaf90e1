//! Inverse kinematics of the half-section map: every (θ₂, θ₃) with `f(θ₂, θ₃) = (r², z)`.
//!
//! Branch and prune over [-π, π]² on `F(θ) = (ρ(θ) − r², z(θ) − z)`: a box goes when `F ≠ 0`
//! on it (centred forms); Krawczyk proves a unique solution in a box, which is then shrunk to the
//! precision. Near a singular point several solutions merge and Df is nearly singular there, so
//! Krawczyk cannot separate them: such boxes reach the precision undecided, and touching ones
//! are reported together as one cluster that may hold one or several solutions (or, on an
//! internal-motion line, a whole line of them).

use super::chain::Chain3R;
use super::map::TorusMap;
use super::cusps::{bisect, meet_on_torus};
use super::drive::{drive_shared, no_progress, Order};
use crate::kernel::search::Wire;
use crate::kernel::search::Control;
use crate::kernel::contract::krawczyk::{self, Step as K};
use super::motion;
use super::Manip3rError;
use crate::kernel::interval::{components_of_edges, point, touching_pairs};
use crate::kernel::search::{Limits, Progress, Prune, Stats, Status, Step};
use inari::Interval;
use smallvec::smallvec;

/// The outcome of an inverse-kinematics query.
#[derive(Clone, Debug)]
pub struct IkSolutions {
    /// Boxes each holding exactly one solution, for every geometry in the uncertainty box.
    pub unique: Vec<[Interval; 2]>,
    /// Hulls of clusters of undecided boxes: each may hold solutions, none elsewhere.
    pub clusters: Vec<IkCluster>,
    /// `Complete` when every box was decided; otherwise the limit that stopped the run.
    pub status: Status,
    /// The kernel's counters; discards by reason: `no_solution` (F ≠ 0 on the box),
    /// `krawczyk_empty`.
    pub stats: Stats,
}

/// Touching undecided boxes, reported as one.
#[derive(Clone, Copy, Debug)]
pub struct IkCluster {
    /// Hull of the boxes.
    pub hull: [Interval; 2],
    /// How many boxes; 0 for a strip about an internal-motion line whose image may be the
    /// point, set aside unsearched: every θ₂ solves the query on the line (`solve_target`).
    pub boxes: usize,
}

/// Solves `f(θ₂, θ₃) = (radius², z)` (see the module doc), depth first on one thread, with at
/// most `max_boxes` boxes.
pub fn solve(chain: &Chain3R, radius: f64, z: f64, precision: f64, max_boxes: u64) -> Result<IkSolutions, Manip3rError> {
    let control = Control::with_limits(Limits { max_cells: max_boxes, ..Limits::default() });
    solve_with(chain, radius, z, precision, &control, &mut no_progress)
}

/// As `solve`, within `control`, reporting progress.
pub fn solve_with(chain: &Chain3R, radius: f64, z: f64, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<IkSolutions, Manip3rError> {
    if !(radius.is_finite() && z.is_finite() && radius >= 0.0) {
        return Err(Manip3rError::BadPoint(radius, z));
    }
    solve_target(chain, [point(radius).sqr(), point(z)], precision, control, progress)
}

/// A box of the search, with its place in the depth-first walk.
#[derive(Clone, Copy, Debug)]
pub struct IkCell {
    b: [Interval; 2],
    order: Order,
    level: u32,
}

impl Wire for IkCell {
    fn put(&self, out: &mut Vec<u8>) {
        (self.b, self.order, self.level).put(out)
    }
    fn take(input: &mut &[u8]) -> Self {
        let (b, order, level) = Wire::take(input);
        IkCell { b, order, level }
    }
}

/// The test of the module doc, one box at a time.
struct IkPrune<'a, M: TorusMap + ?Sized> {
    chain: &'a M,
    target: [Interval; 2],
    precision: f64,
    /// θ₃ strips about internal-motion lines, reported whole and not searched.
    aside: &'a [Interval],
}

/// Why the inverse-kinematics search discards a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IkDiscard {
    /// Its image misses the target.
    NoSolution,
    /// Krawczyk proves it holds no solution.
    KrawczykEmpty,
    /// It lies in a strip about an internal-motion line, which the result reports whole.
    InternalMotion,
}

impl crate::kernel::search::Reason for IkDiscard {
    fn name(self) -> &'static str {
        match self {
            IkDiscard::NoSolution => "no_solution",
            IkDiscard::KrawczykEmpty => "krawczyk_empty",
            IkDiscard::InternalMotion => "internal_motion",
        }
    }
}


impl<M: TorusMap + ?Sized> Prune for IkPrune<'_, M> {
    type Cell = IkCell;
    type Found = (Order, [Interval; 2]);
    type Reason = IkDiscard;

    fn process(&mut self, cell: IkCell) -> Step<IkCell, (Order, [Interval; 2]), IkDiscard> {
        let (chain, target, precision) = (self.chain, self.target, self.precision);
        let b = cell.b;
        if self.aside.iter().any(|s| s.inf() <= b[1].inf() && b[1].sup() <= s.sup()) {
            return Step::Discard(IkDiscard::InternalMotion);
        }
        // A box reaching into a strip is cut at its edge, so the strip is set aside whole.
        if let Some(cut) = self.aside.iter().flat_map(|s| [s.inf(), s.sup()]).find(|&c| b[1].inf() < c && c < b[1].sup()) {
            let child = |t3, i| IkCell { b: [b[0], t3], order: cell.order.child(i, 2), level: cell.level + 1 };
            return Step::Split(smallvec![child(crate::kernel::interval::interval(b[1].inf(), cut), 0), child(crate::kernel::interval::interval(cut, b[1].sup()), 1)]);
        }
        let m = [b[0].mid(), b[1].mid()];
        // `derived` tightens enclosures over uncertain lengths (mean-value form in them).
        let over = chain.derived(b, 1);
        let at = chain.derived([point(m[0]), point(m[1])], 1);
        let dx = [b[0] - point(m[0]), b[1] - point(m[1])];
        let mut fm = [Interval::EMPTY; 2];
        let mut jac = [[Interval::EMPTY; 2]; 2];
        let mut empty = false;
        for k in 0..2 {
            let (fk, ak) = (over.f[k], at.f[k]);
            let g = fk.grad();
            let value = (fk.value() - target[k]).intersection(ak.value() - target[k] + g[0] * dx[0] + g[1] * dx[1]);
            empty |= !value.contains(0.0);
            fm[k] = ak.value() - target[k];
            jac[k] = g;
        }
        if empty {
            return Step::Discard(IkDiscard::NoSolution);
        }
        match krawczyk::step_array(&b, &m, &fm, &jac) {
            K::Empty => return Step::Discard(IkDiscard::KrawczykEmpty),
            K::Unique(k) => {
                let k = krawczyk::tighten(k, precision, |k| {
                    let mk = [k[0].mid(), k[1].mid()];
                    let o = chain.derived(*k, 1);
                    let a = chain.derived([point(mk[0]), point(mk[1])], 1);
                    let fmk = [a.f[0].value() - target[0], a.f[1].value() - target[1]];
                    krawczyk::step_array(k, &mk, &fmk, &[o.f[0].grad(), o.f[1].grad()])
                });
                return Step::Found((cell.order, k));
            }
            _ => {}
        }
        if b[0].wid().max(b[1].wid()) <= precision {
            return Step::Undecided(cell, "precision");
        }
        let (lo, hi) = bisect(b, false);
        let child = |b, i| IkCell { b, order: cell.order.child(i, 2), level: cell.level + 1 };
        Step::Split(smallvec![child(lo, 0), child(hi, 1)])
    }

    fn level(&self, cell: &IkCell) -> u32 {
        cell.level
    }
}

/// Solves `f(θ₂, θ₃) ∈ target`, with `target` enclosures of (ρ, z) (for a point known only up
/// to rounding, e.g. after a change of frame): every solution for every target in the box is
/// enclosed, and a box is unique when it holds exactly one for each. See `solve`.
pub fn solve_target<M: TorusMap + ?Sized>(chain: &M, target: [Interval; 2], precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<IkSolutions, Manip3rError> {
    super::check_precision(precision)?;
    if target.iter().any(|t| t.is_empty() || !t.inf().is_finite() || !t.sup().is_finite()) {
        return Err(Manip3rError::BadPoint(target[0].mid(), target[1].mid()));
    }
    // A point that may be the image of an internal-motion line is solved by the whole line:
    // found before searching, a strip about the line is set aside (a search there would go
    // down to the precision all along the line) and reported as one cluster of 0 boxes.
    let t0 = std::time::Instant::now();
    let (aside, walk) = line_strips(chain, target, precision, control);
    let start = IkCell { b: [motion::full_range(), motion::full_range()], order: Order::ROOT, level: 0 };
    let mut run = drive_shared(|| IkPrune { chain, target, precision, aside: &aside }, start, &control.remaining_since(t0), progress);
    run.status = walk.and(run.status);
    run.found.sort_by_key(|(order, _)| *order);
    let mut unique: Vec<[Interval; 2]> = Vec::new();
    for (_, k) in run.found {
        // The ±π seam, where the range overlaps itself by an ulp, is the only place one
        // solution can be proven twice: the first in depth-first order is kept.
        if !unique.iter().any(|u| meet_on_torus(u, &k) && (0..2).any(|i| u[i].disjoint(k[i]))) {
            unique.push(k);
        }
    }
    run.undecided.sort_by_key(|(c, _)| c.order);
    let undecided: Vec<[Interval; 2]> = run.undecided.iter().map(|(c, _)| c.b).collect();
    let mut clusters = cluster(&undecided);
    clusters.extend(aside.iter().map(|t3| IkCluster { hull: [motion::full_range(), *t3], boxes: 0 }));
    Ok(IkSolutions { unique, clusters, status: run.status, stats: run.stats })
}

/// Half-width (radians of θ₃) of the strip set aside about an internal-motion line: boxes
/// beside it must be about as narrow as their distance from the line to be decided, so the
/// search costs about 2π over this per side.
const LINE_MARGIN: f64 = 1.0 / 1024.0;

/// The θ₃ strips about the internal-motion lines whose image may be the target (the image of
/// a line is one point: f at any θ₂ over the band's θ₃ encloses it), found within `control`,
/// with how the walk for them ended.
fn line_strips<M: TorusMap + ?Sized>(chain: &M, target: [Interval; 2], precision: f64, control: &Control) -> (Vec<Interval>, Status) {
    let mut out: Vec<Interval> = Vec::new();
    let (bands, walk) = chain.bands(precision, control);
    for band in bands.iter().filter(|b| b.near.is_none()) {
        let t3 = crate::kernel::interval::interval(band.theta3[0], band.theta3[1]);
        let image = chain.derived([point(0.0), t3], 0);
        if (0..2).all(|k| !image.f[k].value().disjoint(target[k])) {
            let full = motion::full_range();
            let lo = (band.theta3[0] - LINE_MARGIN).max(full.inf());
            let hi = (band.theta3[1] + LINE_MARGIN).min(full.sup());
            out.push(crate::kernel::interval::interval(lo, hi));
        }
    }
    (out, walk)
}

/// Groups boxes that touch on the torus, listed by their first box.
fn cluster(boxes: &[[Interval; 2]]) -> Vec<IkCluster> {
    let n = boxes.len();
    // Contacts in the plane by the sweep, then an all-pairs pass over the few boxes on the ±π
    // edges for contacts across the seam.
    let all: Vec<usize> = (0..n).collect();
    let (mut contacts, _) = touching_pairs(&all, 2, |i, d| boxes[i][d]);
    // Deliberately a little below π: boxes this close to the seam may meet copies across it.
    #[allow(clippy::approx_constant)]
    const NEAR_SEAM: f64 = 3.14159;
    let edge: Vec<usize> = all.iter().copied().filter(|&i| boxes[i].iter().any(|d| d.inf() <= -NEAR_SEAM || d.sup() >= NEAR_SEAM)).collect();
    for (x, &i) in edge.iter().enumerate() {
        contacts.extend(edge[x + 1..].iter().filter(|&&j| meet_on_torus(&boxes[i], &boxes[j])).map(|&j| (i, j)));
    }
    components_of_edges(n, contacts)
        .into_iter()
        .map(|members| {
            let hull = members.iter().fold(boxes[members[0]], |h, &i| [h[0].convex_hull(boxes[i][0]), h[1].convex_hull(boxes[i][1])]);
            IkCluster { hull, boxes: members.len() }
        })
        .collect()
}

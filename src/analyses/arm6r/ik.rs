//! Certified inverse kinematics of a 6R arm: every joint vector within the joint ranges that
//! puts the tip frame at a given pose, each in a box proven to hold exactly one.
//!
//! First phase, joints 2, 3, 5, 6 only (joints 1 and 4 keep their whole ranges): axis 4 (its
//! frame's origin and direction) seen from axis 1 must be the same whether joints 1–3 or the
//! pose and joints 6, 5 place it; five invariants under turns about axis 1 (`Axis4Sides`)
//! depend on joints 2, 3 on one side and 6, 5 on the other. The start cell is narrowed by a
//! traversal of pairs of one-side boxes (`invariant_pairs`), each side's enclosures computed
//! once per box; measured on a general 6R, that took the median time per pose from about 0.8 s
//! to 0.04 s (CPU), the same solutions. Its leaves are narrowed by Krawczyk on the invariants
//! (or discarded, also by the rows combined along the Jacobian's singular vectors, which
//! clears the near misses of poses whose two sides' invariants nearly touch along a curve).
//! Cells wider than its leaves (pairs left when its budget ran out) are searched on the
//! invariants with their mean-value test and one Gauss–Seidel sweep (`first_phase`).
//!
//! Then joints 1 and 4, still whole, are narrowed to the turns that align the two sides
//! (`Ik6Prune::align`: each turn's direction from a box of cos and sin). Measured on 1,000
//! poses of a general 6R, these two steps took the median from 46 to 33 ms and the poses over
//! 0.1 s from 58 to 8, in one run.
//!
//! Second phase, once those four are narrow: meet in the middle, `L(θ₁,θ₂,θ₃) = R(θ₄,θ₅,θ₆)`
//! (`Chain6R::split`), twelve scalar equations
//! (nine rotation entries, three coordinates) whose sides each depend on three angles, so the
//! interval enclosures of a side over a box wrap far less than the full product over six.
//! A box is discarded when one of the twelve excludes 0, by its natural enclosure or by its
//! mean-value form `H(m) + J(B)(B − m)`, whose Jacobian columns are the joints' twists
//! (`d side/dθ = ±[ξ]^·side`); the mean-value form also contracts the box (one Gauss–Seidel
//! sweep). Small boxes go to Krawczyk (`contract::krawczyk`) on a square system that has the
//! same solutions where `trace(R_L R_Rᵀ) > −1`: `p_L − p_R = 0` and `vee(skew(R_L R_Rᵀ)) = 0`
//! (the rotation part vanishes for rotations by 0 and π only; the trace excludes π). Its
//! Jacobian is the arm's twist Jacobian at a solution, well conditioned away from
//! singularities. Boxes reaching the precision undecided (near a singular pose) are reported
//! as clusters: nothing is lost.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::chain::{add, cos_sin, cross, mul, mv, Affine, Chain6R, IAffine, Side, V};
use super::{Manip6rError, Pose64};
use crate::kernel::contract::krawczyk::{self, Step as K};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{interval, point, trig, Interval};
use crate::analyses::arm3r::drive::{drive, no_progress};
use crate::formulate::{angles::stated, stated as st};
use crate::kernel::search::{Control, Progress, Prune, Stats, Status, Step};
use super::invariant_pairs;

mod closed_form;
pub use self::closed_form::Degeneracy;
mod answer;
mod boxes;
mod fallback;
use self::answer::{answer, Searched};
mod invariants;
mod parallel_axes;
mod square;
mod singular_curves;
pub use self::singular_curves::{CurveKind, Ik6Curve};

use self::invariants::{first_phase, invariants, INNER};
pub(super) use self::invariants::{Axis4Sides, Half};
use smallvec::{smallvec, SmallVec};
use std::sync::atomic::{AtomicU64, Ordering};

/// The tip pose sought: an enclosure of one rigid transform (base frame).
#[derive(Clone, Copy, Debug)]
pub struct PoseTarget(pub(crate) IAffine);

impl PoseTarget {
    /// The pose `x, y, z, roll, pitch, yaw` as decimals (metres, radians; URDF convention),
    /// enclosed exactly as a file's numbers are.
    pub fn stated(v: [f64; 6]) -> Result<PoseTarget, Manip6rError> {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(Manip6rError::BadPose(format!("not finite numbers: {v:?}")));
        }
        Ok(PoseTarget(IAffine { r: st::rpy([v[3], v[4], v[5]]), t: [stated(v[0]), stated(v[1]), stated(v[2])] }))
    }

    /// Every entry of `p` widened by `radius`: for a pose computed in floating point, whose
    /// rotation is orthogonal only up to rounding (the enclosure must hold a rigid transform).
    pub fn around(p: &Pose64, radius: f64) -> Result<PoseTarget, Manip6rError> {
        let ok = p.r.iter().flatten().chain(p.t.iter()).all(|x| x.is_finite()) && radius.is_finite() && radius >= 0.0;
        if !ok {
            return Err(Manip6rError::BadPose(format!("not finite numbers: {p:?}")));
        }
        let w = |x: f64| interval(x - radius, x + radius);
        Ok(PoseTarget(IAffine { r: p.r.map(|row| row.map(w)), t: p.t.map(w) }))
    }
}

/// The outcome of a 6R inverse-kinematics query.
#[derive(Clone, Debug)]
pub struct Ik6Solutions {
    /// Boxes each holding exactly one solution (for every rigid pose in the target), sorted.
    pub unique: Vec<[Interval; 6]>,
    /// Hulls of touching undecided boxes: each may hold solutions, none lie elsewhere.
    pub clusters: Vec<Ik6Cluster>,
    /// At a wrist- or shoulder-singular pose, where the singular branches' solutions lie.
    pub curves: Vec<Ik6Curve>,
    /// `Complete` when every box was decided; otherwise the limit that stopped the run.
    pub status: Status,
    /// The kernel's counters; discards by reason.
    pub stats: Stats,
    /// Which method answered.
    pub method: Ik6Method,
}

/// Which method answered an inverse-kinematics query.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ik6Method {
    /// The closed form of a recognised geometry (`closed_form`: a spherical wrist, or axes
    /// 2, 3, 4 parallel with axes 5 and 6 meeting), every candidate certified by Krawczyk but
    /// those of an elbow's double root (left undecided) and singular curves (covered); its
    /// counters are the boxes it reported.
    ClosedForm,
    /// The branch-and-prune search.
    Search,
    /// The search, the geometry recognised but the pose left by the closed form (why).
    SearchAfter(Degeneracy),
    /// The closed form's certified candidates, and the search of boxes about the candidates
    /// it left (why the first was left).
    ClosedFormAndSearch(Degeneracy),
}

impl Ik6Method {
    /// `closed_form` or `search`, as reports write it.
    pub fn name(self) -> &'static str {
        match self {
            Ik6Method::ClosedForm => "closed_form",
            Ik6Method::Search | Ik6Method::SearchAfter(_) => "search",
            Ik6Method::ClosedFormAndSearch(_) => "closed_form_and_search",
        }
    }

    /// Why the closed form of a recognised geometry left the pose, or some of its candidates,
    /// to the search.
    pub fn declined(self) -> Option<Degeneracy> {
        match self {
            Ik6Method::SearchAfter(why) | Ik6Method::ClosedFormAndSearch(why) => Some(why),
            _ => None,
        }
    }
}

/// Touching undecided boxes, reported as one.
#[derive(Clone, Copy, Debug)]
pub struct Ik6Cluster {
    /// Hull of the boxes.
    pub hull: [Interval; 6],
    /// How many boxes.
    pub boxes: usize,
}

/// Why the search discards a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ik6Discard {
    /// One of the twelve equations excludes 0 on it.
    NoSolution,
    /// Krawczyk proves it holds no solution.
    KrawczykEmpty,
    /// The only solution near it lies outside it: a neighbouring cell claims it.
    ClaimedElsewhere,
    /// Axis 4 seen from axis 1 differs on the two sides (the first phase: joints 2, 3, 5, 6).
    Axis4,
    /// No turn of joint 1, or of joint 4, within its range carries one side's axis 4 (or
    /// frame) onto the other's (`Ik6Prune::align`).
    Unaligned,
}

impl crate::kernel::search::Reason for Ik6Discard {
    fn name(self) -> &'static str {
        match self {
            Ik6Discard::NoSolution => "no_solution",
            Ik6Discard::KrawczykEmpty => "krawczyk_empty",
            Ik6Discard::ClaimedElsewhere => "claimed_elsewhere",
            Ik6Discard::Axis4 => "axis_4_invariants",
            Ik6Discard::Unaligned => "joint_1_or_4_turn",
        }
    }
}

/// A box of the search.
#[derive(Clone, Copy, Debug)]
pub struct Ik6Cell {
    b: [[f64; 2]; 6],
    level: u32,
    /// Joints 1 and 4 were narrowed to the turns that align the sides (`Ik6Prune::align`).
    aligned: bool,
}

/// Krawczyk is tried on boxes at most this wide (radians): wider ones rarely contract, and
/// the attempt costs about two evaluations.
const KRAWCZYK_WIDTH: f64 = 0.25;

/// Rows of the invariants of axis 4 relative to axis 1 (`invariants`).
pub(super) const INVARIANTS: usize = 5;

/// Joints 1 and 4 are split only once joints 2, 3, 5, 6 are this narrow (radians).
const FIRST_WIDTH: f64 = 0.02;

/// The pair traversal's limits: past them its pending pairs are searched as cells (the
/// nodes' arena then holds at most about 65 MB).
const PAIR_BUDGET: invariant_pairs::Budget = invariant_pairs::Budget { pairs: 20_000_000, boxes: 500_000 };

/// Cells this narrow (radians) that Krawczyk cannot decide are tried once more, inflated.
const INFLATE_WIDTH: f64 = 1e-5;

/// One split of the equation (`Chain6R::split`): sides and the joint of each block.
pub(super) type Split = (Side<3>, Side<3>, [usize; 3], [usize; 3]);

/// Rows per split: nine rotation entries, three coordinates, and the last right joint's axis
/// direction, which that joint does not turn (three more rows free of its angle).
const ROWS: usize = 15;

/// How many of the three cyclic splits (after joint 0, 1, 2) the search tests. Measured on a
/// general 6R: all three cut the boxes processed by 2.5 but cost 3 times as much per box.
const SPLITS: usize = 1;

struct Ik6Prune<'a> {
    splits: &'a [Split],
    sides: &'a Axis4Sides,
    precision: f64,
    /// Cells this narrow that Krawczyk cannot decide are tried once more, inflated
    /// (`INFLATE_WIDTH`, or wider for a chain whose coefficients span a range: `solve_over`).
    inflate: f64,
    /// Pairs the start cell's traversal examined, on every thread: work the kernel counts as
    /// one cell.
    pairs: &'a AtomicU64,
}

/// The twelve residuals `L − R` (rotation row-major, then translation).
#[inline]
fn residual(l: &Affine, r: &Affine) -> [Iv; 12] {
    let mut h = [Iv::ZERO; 12];
    for i in 0..3 {
        for j in 0..3 {
            h[3 * i + j] = l.r[i][j].sub(r.r[i][j]);
        }
        h[9 + i] = l.t[i].sub(r.t[i]);
    }
    h
}

fn excludes_zero(x: Iv) -> bool {
    x.lo > 0.0 || x.hi < 0.0
}

#[inline(always)]
fn sub3(a: &V, b: &V) -> V {
    [a[0].sub(b[0]), a[1].sub(b[1]), a[2].sub(b[2])]
}

fn mid(b: &[[f64; 2]; 6]) -> [f64; 6] {
    b.map(|x| 0.5 * (x[0] + x[1]))
}

fn width(b: &[[f64; 2]; 6]) -> f64 {
    b.iter().map(|x| x[1] - x[0]).fold(0.0, f64::max)
}

#[inline(always)]
fn dot(a: &V, b: &V) -> Iv {
    add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]))
}

/// A split's two sides' frames over the box `b`.
#[inline]
fn frames_of(split: &Split, b: &[[f64; 2]; 6]) -> ([Affine; 7], [Affine; 7]) {
    let cs = |k: usize| cos_sin(b[k][0], b[k][1]);
    let (left, right, lv, rv) = split;
    (left.frames(&lv.map(cs)), right.frames(&rv.map(cs)))
}

/// The split's `ROWS` residuals at `m` and their Jacobian over `b` (into `jac`), or None when
/// one residual's natural enclosure over `b` excludes 0.
#[inline]
fn equations(split: &Split, b: &[[f64; 2]; 6], m: &[f64; 6], jac: &mut [[Iv; 6]; ROWS]) -> Option<[Iv; ROWS]> {
    let (left, right, lv, rv) = split;
    let (fl, fr) = frames_of(split, b);
    let (l, r) = (fl[3], fr[3]);
    let axis_value = |fl: &[Affine; 7], fr: &[Affine; 7]| -> (V, V) {
        let a = &right.axes[2];
        (mv(&fl[3].r, a), mv(&fr[2].r, a))
    };
    let h = residual(&l, &r);
    let (al, ar) = axis_value(&fl, &fr);
    if h.iter().any(|&x| excludes_zero(x)) || (0..3).any(|i| excludes_zero(al[i].sub(ar[i]))) {
        return None;
    }
    let (ml, mr) = frames_of(split, &m.map(|x| [x, x]));
    let h = residual(&ml[3], &mr[3]);
    let (aml, amr) = axis_value(&ml, &mr);
    let mut out = [Iv::ZERO; ROWS];
    out[..12].copy_from_slice(&h);
    for i in 0..3 {
        out[12 + i] = aml[i].sub(amr[i]);
    }
    // Columns: d(L − R)/dθ = [ξ]^·(side) for every joint (the right side turns by −θ and
    // enters with a minus); the axis rows' right value does not depend on the last joint.
    for (b_, on_left) in [(0, true), (1, true), (2, true), (0, false), (1, false), (2, false)] {
        let (side, frames, v) = if on_left { (&l, &fl, lv[b_]) } else { (&r, &fr, rv[b_]) };
        let (w, p) = if on_left { left.axis(frames, b_) } else { right.axis(frames, b_) };
        for j in 0..3 {
            let col = cross(&w, &[side.r[0][j], side.r[1][j], side.r[2][j]]);
            for i in 0..3 {
                jac[3 * i + j][v] = col[i];
            }
        }
        let pos = cross(&w, &sub3(&side.t, &p));
        let axis = if on_left { cross(&w, &al) } else if b_ < 2 { cross(&w, &ar) } else { [Iv::ZERO; 3] };
        for i in 0..3 {
            jac[9 + i][v] = pos[i];
            jac[12 + i][v] = axis[i];
        }
    }
    Some(out)
}

/// `(c, s)`, a positive multiple of `(cos θ, sin θ)` for the turn `θ` about the unit axis `a`
/// that carries `from` onto `to`: with `p` the part of `from` across the axis,
/// `from·to − (a·from)(a·to) = |p|² cos θ` and `(a × from)·to = |p|² sin θ`.
fn turn_between(a: &V, from: &V, to: &V) -> (Interval, Interval) {
    let c = dot(from, to).sub(mul(dot(a, from), dot(a, to)));
    (c.to(), dot(&cross(a, from), to).to())
}

/// The parts of `[lo, hi]` equal to `phi` modulo a turn (at most a few turns are searched; a
/// wider range is returned whole).
fn copies_in(phi: Interval, lo: f64, hi: f64) -> SmallVec<[[f64; 2]; 2]> {
    let turn = std::f64::consts::TAU;
    let (first, last) = (((lo - phi.sup()) / turn).floor(), ((hi - phi.inf()) / turn).ceil());
    if !(first.is_finite() && last.is_finite()) || last - first > 8.0 {
        return smallvec![[lo, hi]];
    }
    let mut out = SmallVec::new();
    let mut k = first;
    while k <= last {
        let x = (phi + Interval::TAU * point(k)).intersection(interval(lo, hi));
        if !x.is_empty() {
            out.push([x.inf(), x.sup()]);
        }
        k += 1.0;
    }
    out
}

impl Ik6Prune<'_> {
    /// The start cell: joints 2, 3, 5, 6 narrowed by the pair traversal of the invariants
    /// (`invariant_pairs`), joints 1 and 4 whole; the pairs it leaves are the cells to search.
    fn start(&self, cell: Ik6Cell, stop: &dyn Fn() -> bool) -> Step<Ik6Cell, ([Interval; 6], [Interval; 6]), Ik6Discard> {
        let b = cell.b;
        let found = invariant_pairs::pairs(self.sides, [b[1], b[2]], [b[5], b[4]], FIRST_WIDTH, PAIR_BUDGET, stop);
        self.pairs.fetch_add(found.examined, Ordering::Relaxed);
        let cells: SmallVec<[Ik6Cell; 4]> = found
            .leaves
            .iter()
            .chain(&found.pending)
            .map(|&(l, r)| {
                let mut nb = b;
                (nb[1], nb[2], nb[5], nb[4]) = (l[0], l[1], r[0], r[1]);
                Ik6Cell { b: nb, level: 1, aligned: false }
            })
            .collect();
        if cells.is_empty() {
            return Step::Discard(Ik6Discard::Axis4);
        }
        Step::Split(cells)
    }

    /// Joints 1 and 4 of a cell whose joints 2, 3, 5, 6 are narrow, narrowed to the turns that
    /// align the two sides. Joint 1 turns the left side's axis 4 (joint 1 at 0) onto the
    /// right side's about axis 1: its point and its direction each give the turn's direction up
    /// to a box (`turn_between`, `trig::angle`). Joint 4 then turns the left side's frame onto
    /// the right side's about axis 4 (`R_R = R_L·Rot(a₄, θ₄)`): for `e` across `a₄`,
    /// `(R_L e⊥·R_R e⊥, R_L(a₄ × e)·R_R e⊥)` is a positive multiple of `(cos θ₄, sin θ₄)`,
    /// `e⊥ = e − (a₄·e)a₄`. Each turn is kept where it is congruent to its angle, so a cell
    /// may become several, or none. Without these, both joints would be bisected over their
    /// whole ranges in every cell the invariants leave.
    fn align(&self, cell: &Ik6Cell) -> SmallVec<[Ik6Cell; 4]> {
        let b = cell.b;
        let (.., ul, dl) = self.sides.placed(Half::Left, &[b[1], b[2]]);
        let (.., ur, dr) = self.sides.placed(Half::Right, &[b[5], b[4]]);
        let a1 = &self.sides.a1;
        let mut first: SmallVec<[[f64; 2]; 2]> = smallvec![b[0]];
        for (from, to) in [(&ul, &ur), (&dl, &dr)] {
            let (c, s) = turn_between(a1, from, to);
            if let Some(phi) = trig::angle(c, s) {
                first = first.iter().flat_map(|r| copies_in(phi, r[0], r[1])).collect();
            }
        }
        let split = &self.splits[0];
        let a4 = &split.1.axes[2];
        // A coordinate axis far from a₄, made exactly perpendicular to it.
        let size = |i: usize| a4[i].lo.abs().max(a4[i].hi.abs());
        let k = (0..3).min_by(|&i, &j| size(i).total_cmp(&size(j))).unwrap_or(0);
        let mut e = [Iv::ZERO; 3];
        e[k] = Iv { lo: 1.0, hi: 1.0 };
        let along = dot(a4, &e);
        let across: V = [0, 1, 2].map(|i| e[i].sub(mul(along, a4[i])));
        let w = cross(a4, &e);
        let mut out = SmallVec::new();
        for r1 in first {
            let mut nb = b;
            nb[0] = r1;
            let (fl, fr) = frames_of(split, &nb);
            let (rl, rr) = (&fl[3].r, &fr[2].r);
            let seen = mv(rr, &across);
            let (c, s) = (dot(&mv(rl, &across), &seen).to(), dot(&mv(rl, &w), &seen).to());
            let fourth: SmallVec<[[f64; 2]; 2]> = match trig::angle(c, s) {
                Some(phi) => copies_in(phi, b[3][0], b[3][1]),
                None => smallvec![b[3]],
            };
            for r4 in fourth {
                nb[3] = r4;
                out.push(Ik6Cell { b: nb, aligned: true, ..*cell });
            }
        }
        out
    }

    /// Any cell but the start cell (see the module doc).
    fn examine(&mut self, cell: Ik6Cell) -> Step<Ik6Cell, ([Interval; 6], [Interval; 6]), Ik6Discard> {
        let b = cell.b;
        let m = mid(&b);
        let mut hm = [Iv::ZERO; 3 * ROWS + INVARIANTS];
        let mut jac = [[Iv::ZERO; 6]; 3 * ROWS + INVARIANTS];
        let mut rows = self.splits.len() * ROWS;
        {
            let inv: &mut [[Iv; 6]; INVARIANTS] = (&mut jac[rows..rows + INVARIANTS]).try_into().expect("invariant: INVARIANTS rows");
            let Some(h) = invariants(self.sides, &b, &m, inv) else {
                return Step::Discard(Ik6Discard::Axis4);
            };
            hm[rows..rows + INVARIANTS].copy_from_slice(&h);
            if INNER.iter().any(|&v| b[v][1] - b[v][0] > FIRST_WIDTH) {
                return first_phase(&cell, &m, &h, inv);
            }
        }
        if !cell.aligned {
            let cells = self.align(&cell);
            if cells.is_empty() {
                return Step::Discard(Ik6Discard::Unaligned);
            }
            return Step::Split(cells);
        }
        for (i, split) in self.splits.iter().enumerate() {
            let at = i * ROWS;
            let rows: &mut [[Iv; 6]; ROWS] = (&mut jac[at..at + ROWS]).try_into().expect("invariant: ROWS rows");
            let Some(h) = equations(split, &b, &m, rows) else {
                return Step::Discard(Ik6Discard::NoSolution);
            };
            hm[at..at + ROWS].copy_from_slice(&h);
        }
        rows += INVARIANTS;
        let mut dx: [Iv; 6] = [0, 1, 2, 3, 4, 5].map(|v| Iv { lo: b[v][0], hi: b[v][1] }.sub(Iv { lo: m[v], hi: m[v] }));
        // One Gauss–Seidel sweep of the mean-value form (valid for any x in b: the segment
        // from m to x stays in b, over which `jac` encloses the derivative).
        let mut nb = b;
        for row in 0..rows {
            for v in 0..6 {
                let a = jac[row][v];
                if !excludes_zero(a) {
                    continue;
                }
                let rest = (0..6).filter(|&u| u != v).fold(hm[row], |acc, u| add(acc, mul(jac[row][u], dx[u])));
                let x = point(m[v]) - rest.to() / a.to();
                let cut = x.intersection(interval(nb[v][0], nb[v][1]));
                if cut.is_empty() {
                    return Step::Discard(Ik6Discard::NoSolution);
                }
                nb[v] = [cut.inf(), cut.sup()];
                dx[v] = Iv { lo: nb[v][0], hi: nb[v][1] }.sub(Iv { lo: m[v], hi: m[v] });
            }
        }
        let shrunk = (0..6).any(|v| nb[v][1] - nb[v][0] < 0.8 * (b[v][1] - b[v][0]));
        if shrunk {
            return Step::Split(smallvec![Ik6Cell { b: nb, ..cell }]);
        }
        if width(&b) <= KRAWCZYK_WIDTH {
            let bi = b.map(|x| interval(x[0], x[1]));
            match square::newton(&self.splits[0], &bi) {
                K::Empty => return Step::Discard(Ik6Discard::KrawczykEmpty),
                K::Unique(k) => {
                    let k = krawczyk::tighten(k, self.precision, |k| square::newton(&self.splits[0], k));
                    if square::not_a_half_turn(&self.splits[0], &k) {
                        return Step::Found((k, bi));
                    }
                }
                K::Contracted(k) => {
                    for v in 0..6 {
                        nb[v] = [nb[v][0].max(k[v].inf()), nb[v][1].min(k[v].sup())];
                        if nb[v][0] > nb[v][1] {
                            return Step::Discard(Ik6Discard::KrawczykEmpty);
                        }
                    }
                }
                K::Failed => {}
            }
        }
        if width(&nb) <= self.inflate {
            // A solution on or near the cell's faces: Krawczyk cannot put its image inside the
            // cell; a box about the cell's centre, a few times wider, may prove it (ε-inflation).
            // The cell claims the solution when its box meets the cell; neighbours claiming the
            // same one are merged after the run (each box is proven to hold only one).
            let c = mid(&nb);
            let r = (4.0 * width(&nb)).max(1e-9);
            let wide = c.map(|x| interval(x - r, x + r));
            if let K::Unique(k) = square::newton(&self.splits[0], &wide) {
                let k = krawczyk::tighten(k, self.precision, |k| square::newton(&self.splits[0], k));
                let meets = (0..6).all(|v| k[v].sup() >= cell.b[v][0] && k[v].inf() <= cell.b[v][1]);
                if !meets {
                    return Step::Discard(Ik6Discard::ClaimedElsewhere);
                }
                if square::not_a_half_turn(&self.splits[0], &k) {
                    return Step::Found((k, wide));
                }
            }
        }
        if width(&nb) <= self.precision {
            return Step::Undecided(Ik6Cell { b: nb, ..cell }, "precision");
        }
        // Bisect where the box's width moves the equations most (the largest smear).
        let smear = |v: usize| (0..rows).map(|row| jac[row][v].lo.abs().max(jac[row][v].hi.abs())).sum::<f64>() * (nb[v][1] - nb[v][0]);
        // Joints 2, 3, 5, 6 first: the invariants decide them alone, and joints 1 and 4
        // follow from them (contracted, or split once the others are narrow).
        let inner = [1, 2, 4, 5].iter().any(|&v| nb[v][1] - nb[v][0] > FIRST_WIDTH);
        let allowed = |v: &usize| !inner || ![0, 3].contains(v);
        let widest = (0..6).filter(allowed).max_by(|&x, &y| (nb[x][1] - nb[x][0]).total_cmp(&(nb[y][1] - nb[y][0]))).unwrap_or(0);
        let pick = (0..6).filter(allowed).filter(|&v| smear(v).is_finite()).max_by(|&x, &y| smear(x).total_cmp(&smear(y)));
        let v = match pick {
            Some(v) if smear(v) > 0.0 && nb[v][1] - nb[v][0] > self.precision => v,
            _ => widest,
        };
        let c = 0.5 * (nb[v][0] + nb[v][1]);
        let (mut lo, mut hi) = (nb, nb);
        lo[v][1] = c;
        hi[v][0] = c;
        let child = |b| Ik6Cell { b, level: cell.level + 1, ..cell };
        Step::Split(smallvec![child(lo), child(hi)])
    }

}

impl Prune for Ik6Prune<'_> {
    type Cell = Ik6Cell;
    /// The solution's box and a box in which it is proven the only solution.
    type Found = ([Interval; 6], [Interval; 6]);
    type Reason = Ik6Discard;

    fn process(&mut self, cell: Ik6Cell) -> Step<Ik6Cell, ([Interval; 6], [Interval; 6]), Ik6Discard> {
        self.process_until(cell, &|| false)
    }

    fn process_until(&mut self, cell: Ik6Cell, stop: &dyn Fn() -> bool) -> Step<Ik6Cell, ([Interval; 6], [Interval; 6]), Ik6Discard> {
        // Only the start cell is at level 0: every other cell descends from it.
        if cell.level == 0 {
            self.start(cell, stop)
        } else {
            self.examine(cell)
        }
    }

    fn level(&self, cell: &Ik6Cell) -> u32 {
        cell.level
    }
}

/// Every solution of `pose(θ) = target` with each θₖ in `chain.ranges[k]` (see the module doc),
/// boxes tightened to `precision` (radians), within `control`.
pub fn solve(chain: &Chain6R, target: &PoseTarget, precision: f64, control: &Control) -> Result<Ik6Solutions, Manip6rError> {
    solve_with(chain, target, precision, control, &mut no_progress)
}

/// As `solve`, reporting progress. A recognised geometry is solved in closed form
/// (`closed_form`); the candidates it cannot certify are searched in a box about each
/// (`fallback`); a pose whose branches it cannot enclose, and every other arm, is searched.
pub fn solve_with(chain: &Chain6R, target: &PoseTarget, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<Ik6Solutions, Manip6rError> {
    if !(precision > 0.0 && precision < 1.0) {
        return Err(Manip6rError::BadPrecision(precision));
    }
    let Some(geometry) = closed_form::recognise(chain) else {
        return solve_inflating(chain, target, precision, INFLATE_WIDTH, control, progress);
    };
    let start = std::time::Instant::now();
    match closed_form::solve(chain, &geometry, target, precision) {
        closed_form::ClosedForm::Solved { unique, curves } => {
            // Every box reported: the certified ones and those of the curves' covers.
            let n = (unique.len() + curves.iter().map(|c| c.1.len()).sum::<usize>()) as u64;
            let stats = Stats { processed: n, found: n, seconds: start.elapsed().as_secs_f64(), ..Stats::default() };
            Ok(Ik6Solutions { unique, clusters: Vec::new(), curves: Ik6Curve::all(curves), status: Status::Finished, stats, method: Ik6Method::ClosedForm })
        }
        closed_form::ClosedForm::Partly(partly) => match fallback::finish(chain, target, precision, partly, &control.remaining_since(start), progress) {
            Ok(found) => Ok(found),
            Err(why) => {
                let found = solve_inflating(chain, target, precision, INFLATE_WIDTH, &control.remaining_since(start), progress)?;
                Ok(Ik6Solutions { method: Ik6Method::SearchAfter(why), ..found })
            }
        },
        closed_form::ClosedForm::Degenerate(why) => {
            let found = solve_inflating(chain, target, precision, INFLATE_WIDTH, control, progress)?;
            Ok(Ik6Solutions { method: Ik6Method::SearchAfter(why), ..found })
        }
    }
}

/// As `solve`, by the search alone whatever the geometry: the reference the closed form is
/// checked and measured against.
pub fn search(chain: &Chain6R, target: &PoseTarget, precision: f64, control: &Control) -> Result<Ik6Solutions, Manip6rError> {
    solve_inflating(chain, target, precision, INFLATE_WIDTH, control, &mut no_progress)
}

/// As `solve`, for a chain whose coefficients span a range (a joint held over an interval,
/// `Chain6R::holding_over`): its solutions are then pieces of curve about `extent` wide, which
/// contraction cannot narrow further, so cells up to `extent` wide that Krawczyk cannot decide
/// are tried once more, inflated about their centre.
pub fn solve_over(chain: &Chain6R, target: &PoseTarget, precision: f64, extent: f64, control: &Control) -> Result<Ik6Solutions, Manip6rError> {
    solve_inflating(chain, target, precision, extent.max(INFLATE_WIDTH), control, &mut no_progress)
}

fn solve_inflating(chain: &Chain6R, target: &PoseTarget, precision: f64, inflate: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<Ik6Solutions, Manip6rError> {
    if !(precision > 0.0 && precision < 1.0) {
        return Err(Manip6rError::BadPrecision(precision));
    }
    let run = search_within(chain, target, precision, inflate, chain.ranges.map(|(lo, hi)| [lo, hi]), control, progress);
    Ok(answer(chain, run, Ik6Method::Search))
}

/// Every solution of the pose within `start` (a box within the ranges), by the search; its
/// processed count is the cells and the pairs of the start cell's traversal.
fn search_within(chain: &Chain6R, target: &PoseTarget, precision: f64, inflate: f64, start: [[f64; 2]; 6], control: &Control, progress: &mut dyn FnMut(&Progress)) -> Searched {
    let splits: Vec<Split> = (0..SPLITS).map(|f| chain.split(&target.0, f)).collect();
    let start = Ik6Cell { b: start, level: 0, aligned: false };
    let sides = Axis4Sides::new(&splits[0]);
    let pairs = AtomicU64::new(0);
    let mut run = drive(|| Ik6Prune { splits: &splits, sides: &sides, precision, inflate, pairs: &pairs }, start, control, progress);
    run.stats.processed += pairs.load(Ordering::Relaxed);
    let undecided = run.undecided.iter().map(|(c, _)| c.b.map(|x| interval(x[0], x[1]))).collect();
    Searched { found: run.found, undecided, status: run.status, stats: run.stats }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm6r::cuspidal::Rng;
    use crate::analyses::arm6r::three_parallel::tests::{chain, family};

    /// Random joint vectors within the limits of the general 6R fixture and of random arms,
    /// the pose of each: over boxes about joints 2, 3, 5, 6, joints 1 and 4 are narrowed from
    /// their whole ranges (`Ik6Prune::align`), and some cell holds the generating vector.
    #[test]
    fn aligned_turns_hold_the_joints_that_made_the_pose() {
        let general = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ik6_general_6r.urdf")).expect("fixture");
        let mut rng = Rng(4242);
        let mut narrowed = 0;
        for seed in 0..=4 {
            let c = if seed == 0 { chain(&general) } else { chain(&family(seed, 0.7, true)) };
            for _ in 0..6 {
                let q: [f64; 6] = std::array::from_fn(|k| rng.uniform(c.ranges[k].0.max(-3.0), c.ranges[k].1.min(3.0)));
                let target = PoseTarget::around(&c.pose(&q), 1e-12).expect("finite");
                let splits = vec![c.split(&target.0, 0)];
                let sides = Axis4Sides::new(&splits[0]);
                let pairs = AtomicU64::new(0);
                let prune = Ik6Prune { splits: &splits, sides: &sides, precision: 1e-10, inflate: INFLATE_WIDTH, pairs: &pairs };
                let mut b = c.ranges.map(|(lo, hi)| [lo, hi]);
                for k in INNER {
                    b[k] = [q[k] - 0.004, q[k] + 0.006];
                }
                let cells = prune.align(&Ik6Cell { b, level: 1, aligned: false });
                let holds = |cell: &Ik6Cell| (0..6).all(|k| cell.b[k][0] <= q[k] && q[k] <= cell.b[k][1]);
                assert!(cells.iter().any(holds), "seed {seed}, q {q:?}: {cells:?}");
                assert!(cells.iter().all(|cell| cell.aligned && INNER.iter().all(|&k| cell.b[k] == b[k])));
                let w = |k: usize| cells.iter().map(|cell| cell.b[k][1] - cell.b[k][0]).sum::<f64>();
                if w(0) < 1.0 && w(3) < 1.0 {
                    narrowed += 1;
                }
            }
        }
        // Most boxes narrow both joints to under a radian (a point of axis 4 near axis 1, or a
        // direction along it, leaves joint 1 as it was).
        assert!(narrowed >= 20, "{narrowed} of 30");
    }
}

//! The verdict a designer asks for first: is the arm cuspidal, how many aspects, how many
//! inverse-kinematics solutions at most.
//!
//! Arguments, in the order tried:
//!
//! 1. **Parallel axes 2 and 3** (PUMA, KUKA KR, ABB IRB, UR positioning structures), proven on the
//!    exact (rounded) geometry. Then f = g∘h with h the planar 2R map of joints 2, 3 into the
//!    plane ⟂ a₂ (lengths l₂ = dist(axis 2, axis 3) > 0, l₃ = dist(point, axis 3) > 0) and
//!    g(w) = (ρ, z) of the in-plane point w. With a₁ ∦ a₂, z is affine on the plane with
//!    parallel level lines, and along each ρ is a strictly convex parabola (leading coefficient
//!    1), whose minima form the line L = {w : (o₂ + w)·ê = 0}, ê ∝ a₁ × a₂. So
//!    det Df = det Dg(h)·det Dh, g is injective on each open side of L and h on each side of
//!    its fold (sin of the elbow angle ≠ 0). On an aspect both signs are constant, so f is
//!    injective there: **non-cuspidal** (at most one solution per aspect), on the full torus and
//!    on any sub-domain (an aspect of a sub-domain lies in one aspect of the torus). h maps each
//!    side of its fold onto the open annulus |l₂ − l₃| < |w| < l₂ + l₃, which L (at distance
//!    d = |o₂·ê| from the centre) cuts in two iff d < l₂ + l₃: then **4 aspects** and, a point
//!    of L inside the annulus having mirror images on both sides, **4 solutions** at most;
//!    otherwise 2 and 2. Every comparison is made in interval arithmetic; one that is not
//!    decided leaves the count `null`.
//! 2. **A certified cusp** (a regular zero of the system (2) of Benoit et al. 2019, unique in its
//!    box) makes any 3R cuspidal: near a cusp value three solutions merge, two of them in one
//!    aspect. With joint limits, only a cusp strictly inside them counts (the argument is local).
//! 3. **No cusp**, the cusp search complete with nothing undecided on the full torus, and the
//!    singular set det Df = 0 proven a smooth curve (∇det ≠ 0 wherever det may vanish: on the
//!    leaves of the aspects' cover when they are counted, else on a bounded quadtree): by Salunkhe, Spartalis, Capco, Chablat, Wenger (2022), a generic 3R
//!    is cuspidal iff it has a cusp, so **non-cuspidal**. We take a smooth singular set as the
//!    genericity this needs; where smoothness is not proven (crossing branches, a box budget
//!    spent) the verdict is `null`.
//!
//! Under arguments 2 and 3, aspects and the largest number of solutions come from
//! `aspects` (the piece graph of the singular-curve cover, and certified inverse kinematics at
//! sample points against the bound 4, or the number of aspects for a non-cuspidal arm); each
//! is `null` with its reason where that argument does not close.

use super::chain::{cross, dot, sub, Pose};
pub use super::chain::V3;
use super::cusps::evaluate_without_tangency;
use super::drive::{drive, no_progress};
use crate::kernel::search::Control;
use super::limits::JointLimits;
use super::{Chain3R, Singularities};
use crate::kernel::search::{Limit, Prune, Status, Step};
use crate::kernel::interval::{point, strict_sign};
use crate::model::{JointKind, Mechanism};
use inari::Interval;
use super::select::Scope;
use super::aspects::AspectsUndecided;

/// Cell budgets of the verdict's searches: the smoothness quadtree (a few thousand boxes on
/// the robots seen), the singular-curve cover behind the aspects, and one sample's IK.
const SMOOTH_CELLS: u64 = 2_000_000;
const COVER_CELLS: u64 = 4_000_000;
const IK_CELLS: u64 = 200_000;

/// `"verdict"` in the JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// true, false, or null (undecided).
    pub cuspidal: Option<bool>,
    /// Number of aspects on the full torus, when proven.
    pub aspects: Option<u32>,
    /// Largest number of inverse-kinematics solutions (of joints 1–3) of one point, when proven.
    pub max_ik_solutions: Option<u32>,
    /// True when `cuspidal` rests on a proof.
    pub certified: bool,
    /// The argument used, or why there is none.
    pub reason: String,
}

impl Verdict {
    /// One line for the CLI.
    pub fn line(&self) -> String {
        let c = match self.cuspidal {
            Some(true) => "CUSPIDAL",
            Some(false) => "NON-CUSPIDAL",
            None => "cuspidality UNDECIDED",
        };
        let n = |x: Option<u32>| x.map_or("?".into(), |v| v.to_string());
        format!("verdict: {c} ({}), aspects {}, at most {} IK solutions: {}", if self.certified { "certified" } else { "not certified" }, n(self.aspects), n(self.max_ik_solutions), self.reason)
    }

    /// The CLI's first line for an arm read as `scope` says: [`Verdict::line`] when the verdict
    /// is the arm's, otherwise naming the sub-chain and point it is about.
    pub fn headline(&self, scope: &Scope) -> String {
        let line = self.line();
        if scope.stands_for_arm {
            return line;
        }
        format!("verdict of the {}:{}", scope.subject, line.strip_prefix("verdict:").unwrap_or(&line))
    }

    /// The verdict with its reason naming the sub-chain and point, and the question left open,
    /// when it does not stand for the arm (for a front end that shows the reason alone).
    pub fn scoped(&self, scope: &Scope) -> Verdict {
        match &scope.not_answered {
            Some(open) if !scope.stands_for_arm => Verdict { reason: format!("{}: {}; {open}", scope.subject, self.reason), ..self.clone() },
            _ => self.clone(),
        }
    }
}

/// The exact (rounded) geometry of the reduced chain at θ₂ = θ₃ = 0, in the first link's frame
/// (axis 1 through its origin): axis 1's direction, axis 2 (point, direction), axis 3 (point,
/// direction) and the analysed point. The same data `branches` builds the singular set from.
#[derive(Clone, Copy, Debug)]
pub struct Geometry {
    /// Axis 1's direction (through the origin).
    pub a1: V3,
    /// A point of axis 2 and its direction.
    pub o2: V3,
    /// Axis 2's direction.
    pub d2: V3,
    /// A point of axis 3 (at θ₂ = 0).
    pub o3: V3,
    /// Axis 3's direction (at θ₂ = 0).
    pub d3: V3,
    /// The analysed point (at θ₂ = θ₃ = 0).
    pub p: V3,
}

/// `Geometry` of a reduced mechanism with three revolute joints, `None` otherwise.
pub fn geometry(m: &Mechanism) -> Option<Geometry> {
    let tip = (0..m.links.len()).find(|&l| m.joints.iter().all(|j| j.parent != l))?;
    let path = m.path_to(tip);
    let rev: Vec<usize> = path.iter().copied().filter(|&j| matches!(m.joints[j].kind, JointKind::Revolute { .. })).collect();
    if rev.len() != 3 {
        return None;
    }
    let axis = |j: usize| -> V3 { let a = m.joints[j].axis; [point(a[0]), point(a[1]), point(a[2])] };
    let a1 = axis(rev[0]);
    let start = path.iter().position(|&j| j == rev[0])? + 1;
    let mut acc = Pose::identity();
    let (mut o2, mut d2, mut o3, mut d3) = ([point(0.0); 3], [point(0.0); 3], [point(0.0); 3], [point(0.0); 3]);
    for &j in &path[start..] {
        acc = acc.then(&Pose::from_origin(&m.joints[j], 0.0));
        if j == rev[1] {
            (o2, d2) = (acc.t, super::chain::apply(&acc.r, &axis(j)));
        }
        if j == rev[2] {
            (o3, d3) = (acc.t, super::chain::apply(&acc.r, &axis(j)));
        }
    }
    Some(Geometry { a1, o2, d2, o3, d3, p: acc.t })
}

/// Argument 1 on the reduced mechanism (`select::positioning`'s), or `None` when axes 2 and 3
/// are not proven parallel (or a₁ not proven apart from a₂, or a length not proven positive).
pub fn parallel_structure(m: &Mechanism) -> Option<Verdict> {
    let Geometry { a1, o2, d2, o3, d3, p } = geometry(m)?;
    let zero = |v: &V3| v.iter().all(|x| x.inf() == 0.0 && x.sup() == 0.0);
    let nonzero = |v: &V3| v.iter().any(|x| strict_sign(*x).is_some());
    if !zero(&cross(&d2, &d3)) {
        return None;
    }
    let n12 = cross(&a1, &d2);
    if !nonzero(&n12) {
        return None;
    }
    // Distance of q from the line through o along d: |(q − o) × d| / |d|.
    let dist = |q: &V3, o: &V3, d: &V3| {
        let c = cross(&sub(q, o), d);
        (dot(&c, &c) / dot(d, d)).sqrt()
    };
    let (l2, l3) = (dist(&o3, &o2, &d2), dist(&p, &o3, &d3));
    if !(l2.inf() > 0.0 && l3.inf() > 0.0) {
        return None;
    }
    let d: Interval = (dot(&o2, &n12) / dot(&n12, &n12).sqrt()).abs();
    let reach = l2 + l3;
    let (aspects, k) = if d.sup() < reach.inf() {
        (Some(4), Some(4))
    } else if d.inf() > reach.sup() {
        (Some(2), Some(2))
    } else {
        (None, None)
    };
    Some(Verdict {
        cuspidal: Some(false),
        aspects,
        max_ik_solutions: k,
        certified: true,
        reason: format!(
            "axes 2 and 3 are exactly parallel and axis 1 is not: f factors through the planar 2R map of joints 2-3 (l2 = {:.6}, l3 = {:.6}), injective on each aspect (see arm3r::verdict); the fold line of (rho, z) lies {:.6} from axis 2 against a reach of {:.6}",
            l2.mid(), l3.mid(), d.mid(), reach.mid()
        ),
    })
}

/// Consecutive axes within this angle (radians) of parallel or perpendicular, or this distance
/// (metres) of meeting, without being proven so, are the near-degeneracies an undecided verdict
/// names.
const NEAR_ANGLE: f64 = 1e-2;
const NEAR_DISTANCE: f64 = 1e-3;

/// The near-degeneracies of the pairs of axes 1-2 and 2-3 of a reduced mechanism (`joints` its
/// three joints' names), measured at θ₂ = θ₃ = 0 (their angles and distances do not depend on
/// the joints): each a phrase with an upper bound of its measure.
pub fn near_degeneracies(mechanism: &Mechanism, joints: &[String; 3]) -> Vec<String> {
    let Some(Geometry { a1, o2, d2, o3, d3, .. }) = geometry(mechanism) else {
        return Vec::new();
    };
    let pairs = [([point(0.0); 3], a1, o2, d2), (o2, d2, o3, d3)].into_iter().enumerate().map(|(k, (oa, da, ob, db))| (format!("axes of {} and {}", joints[k], joints[k + 1]), oa, da, ob, db));
    near_axis_pairs(pairs)
}

/// The near-degeneracies of pairs of axes, each given as (its words, a point and a direction of
/// the one axis, a point and a direction of the other, in one frame): axes nearly parallel,
/// perpendicular or meeting without being exactly so, each a phrase with an upper bound of its
/// measure.
pub fn near_axis_pairs(pairs: impl IntoIterator<Item = (String, [Interval; 3], [Interval; 3], [Interval; 3], [Interval; 3])>) -> Vec<String> {
    let exact_zero = |x: Interval| x.inf() == 0.0 && x.sup() == 0.0;
    let mut found = Vec::new();
    for (names, oa, da, ob, db) in pairs {
        let norms = (dot(&da, &da) * dot(&db, &db)).sqrt();
        let c = cross(&da, &db);
        let sin = (dot(&c, &c).sqrt() / norms).sup();
        if !c.iter().all(|x| exact_zero(*x)) && sin <= NEAR_ANGLE {
            // Nearly parallel: their distance is not a measure worth stating.
            found.push(format!("{names} within {:.1e} rad of parallel", sin.asin()));
            continue;
        }
        let along = dot(&da, &db);
        let cos = (along.abs() / norms).sup();
        if !exact_zero(along) && cos <= NEAR_ANGLE {
            found.push(format!("{names} within {:.1e} rad of perpendicular", cos.asin()));
        }
        // The distance between the lines: |(ob − oa)·(da × db)| / |da × db|.
        let offset = dot(&sub(&ob, &oa), &c);
        let distance = (offset.abs() / dot(&c, &c).sqrt()).sup();
        if !exact_zero(offset) && distance <= NEAR_DISTANCE {
            found.push(format!("{names} within {distance:.1e} m of meeting"));
        }
    }
    found
}

/// The smallest tolerance written with one digit that covers `offset` (2.04e-4 → 3e-4).
fn covering(offset: f64) -> f64 {
    let unit = 10f64.powf(offset.log10().floor());
    let mut digit = (offset / unit).ceil();
    loop {
        let t: f64 = format!("{:.0e}", digit * unit).parse().expect("a number");
        if t >= offset {
            return t;
        }
        digit += 1.0;
    }
}

/// What an undecided verdict adds to its reason: the near-degeneracies measured on the chain
/// (axes nearly parallel, perpendicular or meeting; a nearly spherical wrist), and the option
/// that would settle them (`--snap-tolerance` covering the values left as written). With none
/// measured and nothing to snap, whether a finer `--precision` can help: yes where det Df = 0
/// is proven a smooth curve (the undecided boxes are only too wide), not where det and its
/// gradient may both vanish (crossing branches). That proof runs within `control`.
pub fn blockers(prepared: &super::Prepared, chain: &Chain3R, precision: f64, control: &Control) -> String {
    let mut near = near_degeneracies(&prepared.mechanism, &chain.joints);
    if let Some(d) = prepared.choice.wrist_spread.filter(|&d| d <= NEAR_DISTANCE) {
        near.push(format!("a nearly spherical wrist (axes of {} miss one point by {d:.1e} m, so the origin of {} is analysed, not the wrist centre)", prepared.choice.wrist_joints.join(", "), prepared.choice.wrist_joints[0]));
    }
    let mut text = if near.is_empty() { String::new() } else { format!("; near-degenerate geometry: {}", near.join("; ")) };
    match prepared.unsnapped {
        Some(offset) => {
            let t = covering(offset);
            let option = match (prepared.exact_geometry, t <= crate::model::rounding::ANGLE_TOLERANCE) {
                (true, true) => "dropping --exact-geometry".to_string(),
                (true, false) => format!("--snap-tolerance {t:e} instead of --exact-geometry"),
                (false, _) => format!("--snap-tolerance {t:e}"),
            };
            text.push_str(&format!("; values on the chain are written up to {offset:.1e} rad off a quarter turn or a coordinate axis: {option} would snap them"));
        }
        None if !near.is_empty() => text.push_str("; no value on the chain is near enough a quarter turn to snap, so no option settles it"),
        None => match smooth_singular_set(chain, 1e-6, &control.max_cells(SMOOTH_CELLS)) {
            Smooth::Proven => text.push_str(&format!("; no near-degenerate geometry, and det Df = 0 is proven a smooth curve: the undecided boxes are only too wide, a finer --precision {:.0e} may settle them", precision / 10.0)),
            Smooth::Undecided(n) => text.push_str(&format!("; no near-degenerate geometry, but det Df and its gradient may both vanish in {n} boxes (crossing singular branches?), which a finer --precision is not expected to settle")),
            Smooth::Stopped(..) => {}
        },
    }
    text
}

/// Outcome of the smoothness proof of det Df = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smooth {
    /// ∇det ≠ 0 wherever det may vanish.
    Proven,
    /// Boxes left at the width where det and ∇det may both vanish.
    Undecided(u64),
    /// A limit stopped the proof, with this many boxes pending or left.
    Stopped(Limit, u64),
}

/// Proves det Df = 0 a smooth curve over the torus: every box has det ≠ 0 or a component of
/// ∇det ≠ 0, or is bisected, down to `min_width`, within `control` (a few thousand boxes on
/// the robots seen).
pub fn smooth_singular_set(chain: &Chain3R, min_width: f64, control: &Control) -> Smooth {
    let full = super::motion::full_range();
    let run = drive(|| SmoothPrune { chain, min_width }, [full, full], control, &mut no_progress);
    let left = run.undecided.len() as u64;
    match run.status {
        Status::Stopped(limit) => Smooth::Stopped(limit, left),
        Status::Finished if left == 0 => Smooth::Proven,
        Status::Finished => Smooth::Undecided(left),
    }
}

/// The smoothness test of `smooth_singular_set`, one box at a time.
struct SmoothPrune<'a> {
    chain: &'a Chain3R,
    min_width: f64,
}

/// Why the smoothness proof of det Df = 0 discards a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SmoothDiscard {
    /// det Df ≠ 0 on it.
    Regular,
    /// ∇det Df ≠ 0 on it: the singular set is a smooth curve there.
    Smooth,
}

impl crate::kernel::search::Reason for SmoothDiscard {
    fn name(self) -> &'static str {
        match self {
            SmoothDiscard::Regular => "regular",
            SmoothDiscard::Smooth => "smooth",
        }
    }
}


impl Prune for SmoothPrune<'_> {
    type Cell = [Interval; 2];
    type Found = std::convert::Infallible;
    type Reason = SmoothDiscard;

    fn process(&mut self, b: [Interval; 2]) -> Step<[Interval; 2], Self::Found, SmoothDiscard> {
        let e = evaluate_without_tangency(self.chain, b);
        let excludes = |x: Interval| strict_sign(x).is_some();
        if excludes(e.det) {
            return Step::Discard(SmoothDiscard::Regular);
        }
        if excludes(e.grad_det[0]) || excludes(e.grad_det[1]) {
            return Step::Discard(SmoothDiscard::Smooth);
        }
        if b[0].wid().max(b[1].wid()) < self.min_width {
            return Step::Undecided(b, "gradient may vanish");
        }
        let (lo, hi) = super::cusps::bisect(b, false);
        Step::Split([hi, lo].into_iter().collect())
    }
}

/// The aspects on the full torus (`aspects::count`) within `COVER_CELLS`.
fn aspects(chain: &Chain3R, control: &Control) -> Result<u32, AspectsUndecided> {
    super::aspects::count(chain, &control.max_cells(COVER_CELLS))
}

/// Aspects (counted already) and the largest number of IK solutions under arguments 2 and 3
/// (`aspects`), with what to add to the reason.
fn counts(chain: &Chain3R, aspects: Result<u32, AspectsUndecided>, cusps: &[[f64; 2]], internal_motion: bool, control: &Control) -> (Option<u32>, Option<u32>, String) {
    let (aspects, mut why) = match aspects {
        Ok(n) => (Some(n), format!("; {n} aspects (components of det Df != 0, from the singular-curve cover: every cell regular or crossed by one arc)")),
        Err(e) => (None, format!("; aspects not proven: {e}")),
    };
    if internal_motion {
        why.push_str("; IK solutions unbounded: infinitely many at the image of each internal-motion line");
        return (aspects, None, why);
    }
    // At most 4 (a quartic); a non-cuspidal arm has at most one per aspect.
    let cuspidal = !cusps.is_empty();
    let bound = if cuspidal { 4 } else { aspects.map_or(4, |a| a.min(4)) };
    let (best, proven) = super::aspects::max_ik_solutions(chain, bound, cusps, &control.max_cells(IK_CELLS));
    if proven {
        why.push_str(&format!("; at most {bound} IK solutions ({}), reached at a sample point with {best} certified solutions", if bound == 4 && (cuspidal || aspects.is_none_or(|a| a >= 4)) { "a 3R's bound" } else { "one per aspect" }));
        (aspects, Some(best), why)
    } else {
        why.push_str(&format!("; IK solutions: {best} certified at best among the samples, against a bound of {bound}: the maximum is not proven"));
        (aspects, None, why)
    }
}

/// The verdict for a prepared arm from its (unfiltered, full-torus) singularity run. Its
/// searches (smoothness, aspects, sample IK) run with `control`'s threads, cancel flag and
/// timeout (the caller passes what its run left of it) and their own cell budgets
/// (`SMOOTH_CELLS`, `COVER_CELLS`, `IK_CELLS` a sample); a limit that stops one leaves its
/// count `null`, with the limit named.
pub fn decide(mechanism: &Mechanism, chain: &Chain3R, run: &Singularities, limits: &JointLimits, control: &Control) -> Verdict {
    if let Some(mut v) = parallel_structure(mechanism) {
        // The bound counts isolated solutions: at an internal-motion line's image they form a line.
        let lines = super::motion::line_count(&run.cusps.bands);
        if v.max_ik_solutions.is_some() && lines > 0 {
            v.reason = format!("off the images of its {lines} internal-motion line(s), where the solutions form a whole line; {}", v.reason);
        }
        return v;
    }
    if chain.uncertainty > 0.0 {
        return Verdict { cuspidal: None, aspects: None, max_ik_solutions: None, certified: false, reason: "uncertain lengths: the arguments used here speak of one geometry".into() };
    }
    let certified: Vec<_> = run.cusps.cusps.iter().filter(|c| c.unique).collect();
    if let Some(c) = certified.iter().find(|c| limits.holds(&c.theta)) {
        let centres: Vec<[f64; 2]> = certified.iter().map(|c| [c.theta[0].mid(), c.theta[1].mid()]).collect();
        let (aspects, max_ik_solutions, more) = counts(chain, aspects(chain, control), &centres, !run.cusps.bands.is_empty(), control);
        return Verdict {
            cuspidal: Some(true),
            aspects,
            max_ik_solutions,
            certified: true,
            reason: format!(
                "{} certified cusps; one at ({}, {}) = ({:.6}, {:.6}){}: three solutions merge there, two in one aspect{more}",
                certified.len(),
                chain.joints[1],
                chain.joints[2],
                c.theta[0].mid(),
                c.theta[1].mid(),
                if limits.restrict() { ", strictly inside the joint limits" } else { "" }
            ),
        };
    }
    if !certified.is_empty() {
        return Verdict { cuspidal: None, aspects: None, max_ik_solutions: None, certified: false, reason: format!("{} certified cusps, none strictly inside the joint limits (the full torus is cuspidal; --ignore-limits)", certified.len()) };
    }
    let near = run.cusps.bands.iter().filter(|b| b.near.is_some()).count();
    if near > 0 {
        return Verdict {
            cuspidal: None,
            aspects: None,
            max_ik_solutions: None,
            certified: false,
            reason: format!("{near} near-degenerate strips (the point may pass within {:.1e} m of axis 2 but is nowhere proven on it) were set aside undecided: the geometry as written is a tiny perturbation the searches cannot resolve (drop --exact-geometry to snap it)", run.cusps.bands.iter().filter_map(|b| b.near).fold(0.0, f64::max)),
        };
    }
    let undecided = run.cusps.undecided.len();
    if !run.cusps.status.finished() || undecided > 0 || run.cusps.cusps.iter().any(|c| !c.unique) {
        return Verdict {
            cuspidal: None,
            aspects: None,
            max_ik_solutions: None,
            certified: false,
            reason: format!("no certified cusp, but the cusp search left {undecided} boxes undecided on the full torus ({})", if run.cusps.status.finished() { "no limit stopped it" } else { "a limit stopped it" }),
        };
    }
    // A counted aspect cover proves the smoothness too: each of its leaves has det ≠ 0 or a
    // component of ∇det of one strict sign, and the leaves tile the torus. The smoothness
    // quadtree runs only where the count fails.
    let counted = aspects(chain, control);
    let smooth = if counted.is_ok() { Smooth::Proven } else { smooth_singular_set(chain, 1e-6, &control.max_cells(SMOOTH_CELLS)) };
    match smooth {
        Smooth::Proven => {
            let (aspects, max_ik_solutions, more) = counts(chain, counted, &[], !run.cusps.bands.is_empty(), control);
            Verdict {
                cuspidal: Some(false),
                aspects,
                max_ik_solutions,
                certified: true,
                reason: format!(
                    "no cusp on the whole torus (search complete) and det Df = 0 proven a smooth curve: a generic 3R without cusp is non-cuspidal (Salunkhe, Spartalis, Capco, Chablat, Wenger 2022){}{more}",
                    if run.cusps.bands.is_empty() { String::new() } else { format!("; {} internal-motion lines (each mapped to one point) were set aside by the cusp search and are not cusps", super::motion::line_count(&run.cusps.bands)) }
                ),
            }
        }
        Smooth::Undecided(n) => Verdict {
            cuspidal: None,
            aspects: None,
            max_ik_solutions: None,
            certified: false,
            reason: format!("no cusp on the whole torus, but the singular set is not proven smooth ({n} boxes where det and its gradient may both vanish: crossing branches?), so the generic theorem does not apply"),
        },
        Smooth::Stopped(limit, n) => Verdict {
            cuspidal: None,
            aspects: None,
            max_ik_solutions: None,
            certified: false,
            reason: format!("no cusp on the whole torus, but the smoothness proof of the singular set was stopped by the {} limit ({n} boxes left), so the generic theorem does not apply", limit.name()),
        },
    }
}

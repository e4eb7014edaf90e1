//! Closed-form certified inverse kinematics of arms with a spherical wrist whose axes 2 and 3
//! are parallel (PUMA, KUKA KR, Stäubli TX, ABB IRB, Motoman: any offsets along or between
//! the axes, any angle between axes 1 and 2 but parallel).
//!
//! # Recognition
//!
//! `spherical_wrist` proves on the chain's interval coefficients (after the rounding policy,
//! when one applied) that axes 4, 5, 6 meet in one point `W`, taken as the origin of joint 4's,
//! 5's or 6's frame, and that axes 2 and 3 are parallel: exact zeros of cross products where
//! a relation must hold exactly, strict signs where axes must not be parallel (4 and 5, 5 and
//! 6, 1 and 2). Coefficients that only *contain* a meeting (a decimal quarter turn taken as
//! written) prove nothing, and the search answers. `recognise` tries this geometry, then the
//! second one with a closed form, axes 2, 3, 4 parallel (`parallel_axes`), whose branches are
//! certified here the same way.
//!
//! # The decomposition (Pieper 1968; the subproblems of Paden 1985, as in Elias & Wen 2022)
//!
//! `W` is fixed by joints 1–3 and, from the target, known: `W = G·w₆` with `G = target·Post⁻¹`.
//! In joint 1's frame let `P` be `W`, `u` axis 2's direction. Joints 2 and 3 turn about lines
//! along `u`, so `u·W` (in link 1) is a constant `h`: joint 1 solves `(R₁u)·P = h`, an equation
//! `a cos θ + b sin θ = c` (subproblem 4, up to two roots). Joint 1 placed, the distance from
//! axis 2's origin to `W` depends on joint 3 alone: the same form again (subproblem 3). Joint 2
//! turns the one vector onto the other (subproblem 1). Then `M = R₀₄ᵀ·G.r =
//! R₄·Pre₅·R₅·Pre₆·R₆`: `a₄·M a₆` depends on joint 5 alone (subproblem 4), joints 4 and 6 are
//! each a turn carrying one known vector onto another (subproblem 1).
//!
//! Every step is interval arithmetic on enclosures of exact quantities, so each returns
//! enclosures of all its exact roots for every value the coefficients enclose; its branch count
//! is proven by its discriminant's sign. Every exact solution within the joint ranges therefore
//! lies in one of the candidate boxes (each branch's angles, each copy in the range), and each
//! candidate holds one. A candidate is certified by the search's own Krawczyk test on a box
//! about it (`square`): exactly one solution there, so the candidate's. Certified boxes proven
//! pairwise disjoint hold distinct solutions: the answer is complete and each box unique.
//!
//! Anything the enclosures cannot decide is a `Degeneracy`. A candidate Krawczyk does not
//! certify, or a copy meeting a joint limit, still encloses its branch's one solution: the
//! search answers for a box about it alone (`Partly`), the other candidates keep their
//! certificates. Joint 3's discriminant holding 0 (the elbow stretched out or folded, or nearly)
//! is enclosed about its double root: the branch's box holds none, one or two solutions, and is
//! reported undecided (`Branches::double`). Another discriminant holding 0 or a turn's vector on
//! its axis (at or near a singular pose) leaves the branches themselves unknown, and two certified boxes overlapping leaves
//! their count unproven: then the search answers the whole pose. Either way nothing is lost
//! near singular poses.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::boxes::{any_meet, merged, overlapping};
use super::parallel_axes::{self, ParallelAxes};
use super::singular_curves::{self, SingularWrist};
use super::{square, CurveKind, PoseTarget, Split};
use crate::analyses::arm6r::chain::{Chain6R, IAffine};
use crate::formulate::stated;
use crate::kernel::contract::krawczyk::{self, Step as K};
use crate::kernel::interval::{interval, point, strict_sign, trig, Interval};
use smallvec::SmallVec;

pub(super) type V3 = [Interval; 3];
pub(super) type M3 = [[Interval; 3]; 3];
/// Joints 4, 5, 6 of one wrist branch (modulo a turn).
type WristAngles = (Interval, Interval, Interval);

pub(super) fn dot(a: &V3, b: &V3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: &V3, b: &V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(super) fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn exact_zero(v: &V3) -> bool {
    v.iter().all(|x| x.inf() == 0.0 && x.sup() == 0.0)
}

pub(super) fn nonzero(v: &V3) -> bool {
    v.iter().any(|x| strict_sign(*x).is_some())
}

/// `R(a, θ)·v` for the unit axis `a`, from enclosures of `cos θ`, `sin θ`:
/// `(a·v)a + cos θ (v − (a·v)a) + sin θ (a × v)` (Rodrigues).
pub(super) fn rotate(a: &V3, c: Interval, s: Interval, v: &V3) -> V3 {
    let along = dot(a, v);
    let w = cross(a, v);
    [0, 1, 2].map(|i| along * a[i] + c * (v[i] - along * a[i]) + s * w[i])
}

/// The matrix of `R(a, θ)`: `aaᵀ + cos θ (I − aaᵀ) + sin θ [a]×`.
pub(super) fn rotation(a: &V3, c: Interval, s: Interval) -> M3 {
    let e = |j: usize| {
        let mut v = [point(0.0); 3];
        v[j] = point(1.0);
        rotate(a, c, s, &v)
    };
    let cols = [e(0), e(1), e(2)];
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| cols[j][i]))
}

/// Why the closed form leaves a pose to the search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Degeneracy {
    /// A discriminant's enclosure holds 0: two roots may coincide (a singular pose, or near one).
    Discriminant,
    /// A turn's vectors lie on its axis as far as the enclosures tell: the turn is not determined.
    Direction,
    /// An angle's enclosure meets a joint limit without lying within the range.
    Limit,
    /// Krawczyk did not prove a candidate the only solution about it.
    Uncertified,
    /// Two certified boxes overlap, or a wrist-singular branch's cover meets another box: they
    /// may hold one solution.
    Overlap,
}

impl Degeneracy {
    /// As reports write it.
    pub fn name(self) -> &'static str {
        match self {
            Degeneracy::Discriminant => "discriminant_holds_zero",
            Degeneracy::Direction => "turn_undetermined",
            Degeneracy::Limit => "angle_at_joint_limit",
            Degeneracy::Uncertified => "candidate_not_certified",
            Degeneracy::Overlap => "certified_boxes_overlap",
        }
    }
}

/// What `solve` found.
#[derive(Clone, Debug)]
pub(crate) enum ClosedForm {
    /// Every solution within the joint ranges, each in its own certified box, but those of
    /// wrist-singular branches, each branch's in its cover (`singular_curves`).
    Solved { unique: Vec<[Interval; 6]>, curves: Vec<(CurveKind, Vec<[Interval; 6]>)> },
    /// Some candidates certified, the others left to a search of a box about each.
    Partly(Partly),
    /// A step the enclosures could not decide: the search must answer the whole pose.
    Degenerate(Degeneracy),
}

/// The candidates of a pose the closed form certified, and boxes about those it could not:
/// every solution within the ranges lies in one of the certified boxes or one of the boxes
/// to search (within the ranges, pairwise disjoint).
#[derive(Clone, Debug)]
pub(crate) struct Partly {
    /// Certified boxes, each with a region (holding it) where its solution is the only one.
    pub certified: Vec<([Interval; 6], [Interval; 6])>,
    /// Boxes the search must answer for, as `[lo, hi]` per joint.
    pub search: Vec<[[f64; 2]; 6]>,
    /// Why the first of them was left.
    pub why: Degeneracy,
    /// The covers of singular branches (`singular_curves`), disjoint from the other boxes.
    pub curves: Vec<(CurveKind, Vec<[Interval; 6]>)>,
    /// Boxes about an elbow's double root (`Branches::double`), each holding none, one or two
    /// solutions, disjoint from the certified boxes: left undecided.
    pub undecided: Vec<[Interval; 6]>,
}

/// What `recognise` proved (module doc): the wrist centre and the constants of the position
/// equations, each an enclosure of the exact value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SphericalWrist {
    /// `W` in joint 6's frame (on axis 6, so the same before and after its turn).
    w6: V3,
    /// `W` in joint 3's frame after its turn (`Pre₄·w₄`).
    v: V3,
    /// Axis 2's direction in joint 1's frame after its turn.
    u: V3,
    /// `u·W` in link 1, the same at every angle of joints 2 and 3.
    h: Interval,
    /// `|Pre₃.t + Pre₃.r R₃(θ₃) v|² = k₃ + α₃ cos θ₃ + β₃ sin θ₃`.
    k3: Interval,
    alpha3: Interval,
    beta3: Interval,
    /// Axis 4 in joint 5's frame, and axis 6 in joint 5's frame.
    e4: V3,
    d6: V3,
}

/// A geometry with a closed form: a spherical wrist (this module) or axes 2, 3, 4 parallel
/// (`parallel_axes`).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Geometry {
    SphericalWrist(SphericalWrist),
    ParallelAxes(ParallelAxes),
}

/// The geometry `chain`'s coefficients prove, if any: a spherical wrist first, then axes 2, 3,
/// 4 parallel.
pub(crate) fn recognise(chain: &Chain6R) -> Option<Geometry> {
    spherical_wrist(chain).map(Geometry::SphericalWrist).or_else(|| parallel_axes::recognise(chain).map(Geometry::ParallelAxes))
}

/// Proves the conditions of the module doc on `chain`'s coefficients, or `None` when one is not
/// proven (it may be false, or hold only up to rounding the enclosures cannot exclude).
///
/// Each relation is between consecutive axes, tested in the frame of the first of the two after
/// its turn, where it holds at every angle.
pub(crate) fn spherical_wrist(chain: &Chain6R) -> Option<SphericalWrist> {
    let a = &chain.axes;
    let pre = &chain.pre;
    // Axis k+1 in joint k's frame (after its turn): direction.
    let next = |k: usize| stated::apply(&pre[k + 1].r, &a[k + 1]);
    let (d5, d6) = (next(3), next(4));
    if !(nonzero(&cross(&a[3], &d5)) && nonzero(&cross(&a[4], &d6))) {
        return None;
    }
    // W as the origin of joint 4's, 5's or 6's frame, written in joint 4's frame, in joint 5's,
    // and relative to joint 6's origin in joint 5's frame; each must lie on the axis there.
    let (p5, p6) = (pre[4].t, pre[5].t);
    let zero = [point(0.0); 3];
    let w5_of_4 = stated::apply_transposed(&pre[4].r, &p5).map(|x| -x);
    let candidates = [(zero, w5_of_4, sub(&w5_of_4, &p6)), (p5, zero, p6.map(|x| -x)), (add(&p5, &stated::apply(&pre[4].r, &p6)), p6, zero)];
    let on_axes = |(w4, w5, rel6): &(V3, V3, V3)| exact_zero(&cross(w4, &a[3])) && exact_zero(&cross(w5, &a[4])) && exact_zero(&cross(rel6, &d6));
    let (w4, _, rel6) = candidates.into_iter().find(on_axes)?;
    // Axes 2 and 3 parallel, axis 1 not parallel to them.
    let u = next(0);
    if !(exact_zero(&cross(&a[1], &next(1))) && nonzero(&cross(&a[0], &u))) {
        return None;
    }
    let v = add(&stated::apply(&pre[3].r, &w4), &pre[3].t);
    // u·X = u·Pre₂.t + a₂·Pre₃.t + (Pre₃.rᵀa₂)·v: joint 2 turns about a₂, and Pre₃.rᵀa₂ = ±a₃
    // is fixed by joint 3's turn.
    let h = dot(&u, &pre[1].t) + dot(&a[1], &pre[2].t) + dot(&stated::apply_transposed(&pre[2].r, &a[1]), &v);
    // |t + R₃v|² with t = Pre₃.rᵀPre₃.t, R₃v by Rodrigues.
    let t = stated::apply_transposed(&pre[2].r, &pre[2].t);
    let (at, av) = (dot(&a[2], &t), dot(&a[2], &v));
    let two = point(2.0);
    Some(SphericalWrist {
        w6: stated::apply_transposed(&pre[5].r, &rel6),
        v,
        u,
        h,
        k3: dot(&pre[2].t, &pre[2].t) + dot(&v, &v) + two * at * av,
        alpha3: two * (dot(&t, &v) - at * av),
        beta3: two * dot(&t, &cross(&a[2], &v)),
        e4: stated::apply_transposed(&pre[4].r, &a[3]),
        d6,
    })
}

/// Up to two roots θ (modulo a turn) of `a cos θ + b sin θ = c` for every value of the
/// coefficients' enclosures (subproblems 3 and 4 of Paden 1985 reduce to it): with
/// `ρ² = a² + b²` and `D = ρ² − c²`, none when `D < 0`, two when `D > 0`,
/// `(cos θ, sin θ) = ((ac ± b√D)/ρ², (bc ∓ a√D)/ρ²)`; a `D` holding 0 is `Discriminant`.
pub(crate) fn cos_sin_roots(a: Interval, b: Interval, c: Interval) -> Result<SmallVec<[Interval; 2]>, Degeneracy> {
    let r2 = a.sqr() + b.sqr();
    let d = r2 - c.sqr();
    let mut out = SmallVec::new();
    if d.sup() < 0.0 {
        return Ok(out);
    }
    if !(d.inf() > 0.0 && r2.inf() > 0.0) {
        return Err(Degeneracy::Discriminant);
    }
    let root = d.sqrt();
    for sign in [1.0, -1.0] {
        let sr = point(sign) * root;
        let (cos, sin) = ((a * c + b * sr) / r2, (b * c - a * sr) / r2);
        out.push(trig::angle(cos, sin).ok_or(Degeneracy::Direction)?);
    }
    Ok(out)
}

/// The turn θ (modulo a turn) about the unit axis `a` carrying `from` onto `to`, for vectors
/// known to be so carried (subproblem 1): `(from·to − (a·from)(a·to), (a × from)·to)` is a
/// positive multiple of `(cos θ, sin θ)`; `Direction` when that box holds the origin.
pub(crate) fn turn(a: &V3, from: &V3, to: &V3) -> Result<Interval, Degeneracy> {
    let c = dot(from, to) - dot(a, from) * dot(a, to);
    trig::angle(c, dot(&cross(a, from), to)).ok_or(Degeneracy::Direction)
}

/// The copies `phi + 2πk` (modulo a turn) meeting `[lo, hi]`, each with its `k` and whether
/// it meets a limit without lying within (`Limit`: the solution may lie on either side).
fn copies(phi: Interval, (lo, hi): (f64, f64)) -> SmallVec<[(f64, Interval, Option<Degeneracy>); 2]> {
    let tau = std::f64::consts::TAU;
    let (first, last) = (((lo - phi.sup()) / tau).floor(), ((hi - phi.inf()) / tau).ceil());
    let mut out = SmallVec::new();
    let mut k = first;
    while k <= last {
        let x = phi + Interval::TAU * point(k);
        if x.inf() >= lo && x.sup() <= hi {
            out.push((k, x, None));
        } else if !(x.sup() < lo || x.inf() > hi) {
            out.push((k, x, Some(Degeneracy::Limit)));
        }
        k += 1.0;
    }
    out
}

pub(super) fn cos_sin(x: Interval) -> (Interval, Interval) {
    (trig::cos(x), trig::sin(x))
}

/// Every solution's angles modulo a turn (module doc), at most eight; the position branches
/// whose joint 5 has a double root (`singular_curves`); at a shoulder-singular pose the boxes over
/// pieces of joint 1's range (`singular_curves::shoulder`).
#[derive(Default)]
pub(super) struct Branches {
    pub points: SmallVec<[[Interval; 6]; 8]>,
    pub singular: SmallVec<[SingularWrist; 4]>,
    pub shoulder: Vec<[Interval; 6]>,
    /// Covers built whole by the geometry's own module (`parallel_axes`).
    pub covers: Vec<(CurveKind, Vec<[Interval; 6]>)>,
    /// Branches whose elbow (joint 3's law of cosines) has a double root as far as the
    /// enclosures tell (the elbow stretched out or folded, or nearly): joint 3 enclosed about it
    /// (`singular_curves::double_root`), the box holding the branch's solutions, none, one or
    /// two, which no certificate can tell apart.
    pub double: SmallVec<[[Interval; 6]; 4]>,
}

/// The branches of the pose `g` (module doc): joint 1's roots, each followed by
/// `after_joint1`. With the wrist centre on axis 1 as far as the enclosures tell (joint 1's
/// equation vanishing whole), every angle of joint 1 may solve: the shoulder's cover.
fn branches(chain: &Chain6R, wrist: &SphericalWrist, g: &IAffine) -> Result<Branches, Degeneracy> {
    let (a, pre) = (&chain.axes, &chain.pre);
    let wrist_centre = add(&stated::apply(&g.r, &wrist.w6), &g.t);
    let p = stated::apply_transposed(&pre[0].r, &sub(&wrist_centre, &pre[0].t));
    let u = &wrist.u;
    // (R₁u)·P = (a₁·u)(a₁·P) + cos θ₁ (u·P − (a₁·u)(a₁·P)) + sin θ₁ (a₁ × u)·P.
    let (ua, pa) = (dot(&a[0], u), dot(&a[0], &p));
    let (a1, b1, c1) = (dot(u, &p) - ua * pa, dot(&cross(&a[0], u), &p), wrist.h - ua * pa);
    let mut found = Branches::default();
    match cos_sin_roots(a1, b1, c1) {
        Ok(roots) => {
            for t1 in roots {
                after_joint1(chain, wrist, g, &p, t1, &mut found)?;
            }
        }
        Err(Degeneracy::Discriminant) if [a1, b1, c1].iter().all(|x| x.contains(0.0)) => {
            found.shoulder = singular_curves::shoulder(chain, |t1, one| after_joint1(chain, wrist, g, &p, t1, one))?;
        }
        Err(why) => return Err(why),
    }
    Ok(found)
}

/// Joints 3, 2 and the wrist for joint 1 at `t1` (the wrist centre `p` in joint 1's frame
/// before its turn), into `found`.
fn after_joint1(chain: &Chain6R, wrist: &SphericalWrist, g: &IAffine, p: &V3, t1: Interval, found: &mut Branches) -> Result<(), Degeneracy> {
    let (a, pre) = (&chain.axes, &chain.pre);
    let (c1, s1) = cos_sin(t1);
    let z = sub(&rotate(&a[0], c1, -s1, p), &pre[1].t);
    let (elbows, double) = elbow(wrist.alpha3, wrist.beta3, dot(&z, &z) - wrist.k3)?;
    for t3 in elbows {
        let (c3, s3) = cos_sin(t3);
        let y = add(&pre[2].t, &stated::apply(&pre[2].r, &rotate(&a[2], c3, s3, &wrist.v)));
        let t2 = turn(&a[1], &y, &stated::apply_transposed(&pre[1].r, &z))?;
        let (c2, s2) = cos_sin(t2);
        let mut r = stated::mul(&pre[0].r, &rotation(&a[0], c1, s1));
        for (k, (c, s)) in [(1, (c2, s2)), (2, (c3, s3))] {
            r = stated::mul(&stated::mul(&r, &pre[k].r), &rotation(&a[k], c, s));
        }
        r = stated::mul(&r, &pre[3].r);
        // M = R₀₄ᵀ·G.r = R₄·Pre₅.r·R₅·Pre₆.r·R₆.
        let m = stated::mul(&[0, 1, 2].map(|i| [0, 1, 2].map(|j| r[j][i])), &g.r);
        match wrist_branches(chain, wrist, &m) {
            Ok(wrists) => {
                let all = wrists.into_iter().map(|(t4, t5, t6)| [t1, t2, t3, t4, t5, t6]);
                if double {
                    found.double.extend(all);
                } else {
                    found.points.extend(all);
                }
            }
            Err(Degeneracy::Discriminant) => {
                let (a5, b5, c5) = joint5_equation(chain, wrist, &m);
                if let Some(t5) = singular_curves::double_root(a5, b5, c5)? {
                    found.singular.push(SingularWrist { position: [t1, t2, t3], m, t5 });
                }
            }
            Err(why) => return Err(why),
        }
    }
    Ok(())
}

/// Joint 3's roots of `α cos θ₃ + β sin θ₃ = γ` (the law of cosines), and whether they are one
/// enclosure about a double root (`Branches::double`).
pub(super) fn elbow(alpha: Interval, beta: Interval, gamma: Interval) -> Result<(SmallVec<[Interval; 2]>, bool), Degeneracy> {
    match cos_sin_roots(alpha, beta, gamma) {
        Err(Degeneracy::Discriminant) => Ok((singular_curves::double_root(alpha, beta, gamma)?.into_iter().collect(), true)),
        roots => Ok((roots?, false)),
    }
}

/// `A cos θ₅ + B sin θ₅ = C`, joint 5's equation `a₄·M a₆ = e₄·R₅ d₆` written out (Rodrigues).
fn joint5_equation(chain: &Chain6R, wrist: &SphericalWrist, m: &M3) -> (Interval, Interval, Interval) {
    let a = &chain.axes;
    let (e4, d6, a5) = (&wrist.e4, &wrist.d6, &a[4]);
    let k = dot(e4, a5) * dot(a5, d6);
    (dot(e4, d6) - k, dot(e4, &cross(a5, d6)), dot(&a[3], &stated::apply(m, &a[5])) - k)
}

/// Joints 4, 5, 6 from `M = R₄·Pre₅.r·R₅·Pre₆.r·R₆`: `a₄·M a₆ = e₄·R₅ d₆` (joint 5,
/// subproblem 4), then `R₄(Pre₅.r R₅ d₆) = M a₆` and `R₆(Mᵀa₄) = Pre₆.rᵀ R₅ᵀ e₄` (subproblem 1).
fn wrist_branches(chain: &Chain6R, wrist: &SphericalWrist, m: &M3) -> Result<SmallVec<[WristAngles; 2]>, Degeneracy> {
    let (a, pre) = (&chain.axes, &chain.pre);
    let (e4, d6, a5) = (&wrist.e4, &wrist.d6, &a[4]);
    let ma6 = stated::apply(m, &a[5]);
    let mta4 = stated::apply_transposed(m, &a[3]);
    let (a5c, b5c, c5c) = joint5_equation(chain, wrist, m);
    let mut out = SmallVec::new();
    for t5 in cos_sin_roots(a5c, b5c, c5c)? {
        let (c5, s5) = cos_sin(t5);
        let t4 = turn(&a[3], &stated::apply(&pre[4].r, &rotate(a5, c5, s5, d6)), &ma6)?;
        let t6 = turn(&a[5], &mta4, &stated::apply_transposed(&pre[5].r, &rotate(a5, c5, -s5, e4)))?;
        out.push((t4, t5, t6));
    }
    Ok(out)
}

/// A box about the candidate `c` on which Krawczyk proves exactly one solution, tightened to
/// `precision`: a few radii are tried, from just wider than the candidate (the residual at its
/// centre is about its width times the Jacobian's condition) to a micro-radian.
///
/// The square system's zeros include every solution of the twelve equations, and the candidate
/// holds one (module doc), so one zero in the box is that solution: the search's test of the
/// trace (`square::not_a_half_turn`), which proves a zero it found blind is a solution, is not
/// needed here.
///
/// Returns the tightened box and the region the certificate holds on.
fn certify(split: &Split, c: &[Interval; 6], precision: f64) -> Option<([Interval; 6], [Interval; 6])> {
    let w = c.iter().map(|x| x.wid()).fold(0.0, f64::max);
    // A wide region leaves room for the Krawczyk image; near an elbow or wrist singularity
    // the Jacobian's spread over a wide region swells the image past it, so tighter
    // regions (still holding the enclosure) are tried before wider ones.
    for r in [(16.0 * w).max(1e-12), (2.0 * w).max(1e-12), (0.5 * w).max(1e-12), (1e3 * w).max(1e-9), (1e5 * w).max(1e-6)] {
        let region = c.map(|x| interval(x.inf() - r, x.sup() + r));
        if let K::Unique(k) = square::newton(split, &region) {
            return Some((krawczyk::tighten(k, precision, |k| square::newton(split, k)), region));
        }
    }
    None
}

/// The certified box `k` moved by `turns[d]` whole turns in each joint `d`, when it is proven to
/// lie within `region` moved the same way: the equations are 2π-periodic in every angle, so the
/// moved region holds exactly one solution, the moved copy of the one in `region`, and it lies
/// in the moved box. Each end of the moved region is enclosed (`x + 2πt` in interval
/// arithmetic), and the moved box must lie within the innermost values of both ends; `None`
/// when rounding leaves that unproven. Returned with the moved region rounded inward, on which
/// the moved solution is still the only one.
fn moved(k: &[Interval; 6], region: &[Interval; 6], turns: &[f64; 6]) -> Option<([Interval; 6], [Interval; 6])> {
    let (mut out, mut within) = (*k, *region);
    for d in 0..6 {
        if turns[d] == 0.0 {
            continue;
        }
        let by = Interval::TAU * point(turns[d]);
        let x = k[d] + by;
        let (lo, hi) = (point(region[d].inf()) + by, point(region[d].sup()) + by);
        if !(x.inf() >= lo.sup() && x.sup() <= hi.inf()) {
            return None;
        }
        out[d] = x;
        within[d] = interval(lo.sup(), hi.inf());
    }
    Some((out, within))
}

/// Every solution of `pose(θ) = target` with each θₖ in `chain.ranges[k]`, each in a box
/// certified unique and tightened to `precision`; or those certified and boxes about the
/// candidates left to the search; or why the search must answer the whole pose.
pub(crate) fn solve(chain: &Chain6R, geometry: &Geometry, target: &PoseTarget, precision: f64) -> ClosedForm {
    match solve_or_degenerate(chain, geometry, target, precision) {
        Ok(Partly { certified, search, curves, undecided, .. }) if search.is_empty() && undecided.is_empty() => ClosedForm::Solved { unique: certified.into_iter().map(|(k, _)| k).collect(), curves },
        Ok(partly) => ClosedForm::Partly(partly),
        Err(why) => ClosedForm::Degenerate(why),
    }
}

/// A box about the candidate `c` within the ranges, for the search: `c` holds its solution
/// (module doc), and a margin of its width keeps that solution off the box's faces.
fn search_box(chain: &Chain6R, c: &[Interval; 6]) -> [[f64; 2]; 6] {
    std::array::from_fn(|d| {
        let r = c[d].wid().max(1e-9);
        let (lo, hi) = chain.ranges[d];
        [(c[d].inf() - r).max(lo), (c[d].sup() + r).min(hi)]
    })
}

fn solve_or_degenerate(chain: &Chain6R, geometry: &Geometry, target: &PoseTarget, precision: f64) -> Result<Partly, Degeneracy> {
    let g = target.0.then(&chain.post.inverse());
    let Branches { points: all, singular, shoulder, covers, double } = match geometry {
        Geometry::SphericalWrist(wrist) => branches(chain, wrist, &g)?,
        Geometry::ParallelAxes(arm) => parallel_axes::branches(chain, arm, &g)?,
    };
    let mut split = None;
    let mut found: Vec<([Interval; 6], [Interval; 6])> = Vec::new();
    let mut left: Vec<([Interval; 6], Degeneracy)> = Vec::new();
    for b in all {
        // Each copy meeting the ranges: the branch moved by whole turns `t`, joint by joint,
        // and whether some joint's copy meets a limit.
        let mut moves: Vec<([f64; 6], [Interval; 6], Option<Degeneracy>)> = vec![([0.0; 6], b, None)];
        for k in 0..6 {
            let each = copies(b[k], chain.ranges[k]);
            moves = moves.iter().flat_map(|(t, x, at)| each.iter().map(move |&(turns, y, limit)| {
                let (mut t, mut x) = (*t, *x);
                (t[k], x[k]) = (turns, y);
                (t, x, at.or(limit))
            })).collect();
        }
        if moves.is_empty() {
            continue;
        }
        // The branch certified once; each copy is its certified box moved (`moved`), or
        // certified on its own when rounding leaves the move unproven.
        let split = split.get_or_insert_with(|| chain.split(&target.0, 0));
        let Some((k, region)) = certify(split, &b, precision) else {
            left.extend(moves.iter().map(|(_, c, _)| (*c, Degeneracy::Uncertified)));
            continue;
        };
        for (turns, c, limit) in &moves {
            if let Some(w) = limit {
                left.push((*c, *w));
                continue;
            }
            match moved(&k, &region, turns) {
                Some(x) => found.push(x),
                None => match certify(split, c, precision) {
                    Some(x) => found.push(x),
                    None => left.push((*c, Degeneracy::Uncertified)),
                },
            }
        }
    }
    let undecided: Vec<[Interval; 6]> = double.iter().flat_map(|b| singular_curves::copies_within(chain, b, None)).collect();
    let certified: Vec<[Interval; 6]> = found.iter().map(|f| f.0).collect();
    if overlapping(certified.iter()) || any_meet(&undecided, &certified) {
        return Err(Degeneracy::Overlap);
    }
    if let Some(split) = split.as_ref().filter(|_| !left.is_empty()) {
        if let Some(all) = polished(chain, split, &found, &left, precision) {
            (found, left) = (all, Vec::new());
        }
    }
    found.sort_by(|a, b| a.0.iter().map(|x| x.inf()).partial_cmp(b.0.iter().map(|x| x.inf())).unwrap_or(std::cmp::Ordering::Equal));
    let why = left.first().map_or(if undecided.is_empty() { Degeneracy::Uncertified } else { Degeneracy::Discriminant }, |l| l.1);
    let search = merged(left.iter().map(|(c, _)| search_box(chain, c)).collect());
    let wrists = singular.iter().map(|s| (CurveKind::Wrist, singular_curves::cover(chain, s)));
    let curves: Vec<(CurveKind, Vec<[Interval; 6]>)> = wrists.chain([(CurveKind::Shoulder, shoulder)]).chain(covers).filter(|c| !c.1.is_empty()).collect();
    // A box of a cover meeting another box: one solution may be counted in both.
    let boxes: Vec<[Interval; 6]> = found.iter().map(|f| f.0).chain(search.iter().map(|b| b.map(|x| interval(x[0], x[1])))).chain(undecided.iter().copied()).collect();
    for (i, c) in curves.iter().enumerate() {
        if any_meet(&c.1, &boxes) || curves[..i].iter().any(|other| any_meet(&c.1, &other.1)) {
            return Err(Degeneracy::Overlap);
        }
    }
    Ok(Partly { certified: found, search, why, curves, undecided })
}

/// Every candidate certified, counting: `found` as certified about their candidates, the
/// candidates `left` each from a point Newton's method reaches from its centre, certified on
/// tiny regions about it (near a singularity the candidate's enclosure is wider than any
/// region Krawczyk can prove). Such a box holds a solution but not necessarily its
/// candidate's; yet the exact solutions within the ranges are at most the candidates (one
/// per branch and copy), so as many pairwise disjoint certified boxes within the ranges, each
/// holding a solution of all twelve equations (`square::not_a_half_turn`), hold them all.
/// `None` unless every candidate is so certified.
fn polished(chain: &Chain6R, split: &Split, found: &[([Interval; 6], [Interval; 6])], left: &[([Interval; 6], Degeneracy)], precision: f64) -> Option<Vec<([Interval; 6], [Interval; 6])>> {
    let mut all = found.to_vec();
    for (c, _) in left {
        let mut x = c.map(|v| v.mid());
        for _ in 0..8 {
            x = square::image(split, &x.map(point))?.map(|v| v.mid());
        }
        // The image of the point is as wide as the data's uncertainty seen through the inverse
        // Jacobian: a region must be wider than that, and narrow enough that the Jacobian's
        // spread over it stays small.
        let spread = square::image(split, &x.map(point))?.iter().map(|v| v.wid()).fold(0.0, f64::max);
        let proven = [2.0, 8.0, 32.0, 128.0].into_iter().find_map(|f| {
            let r = (f * spread).max(1e-15);
            let region = x.map(|v| interval(v - r, v + r));
            match square::newton(split, &region) {
                K::Unique(k) => Some((krawczyk::tighten(k, precision, |k| square::newton(split, k)), region)),
                _ => None,
            }
        });
        let (k, region) = proven?;
        let within = (0..6).all(|d| k[d].inf() >= chain.ranges[d].0 && k[d].sup() <= chain.ranges[d].1);
        if !within || !square::not_a_half_turn(split, &k) {
            return None;
        }
        all.push((k, region));
    }
    (!overlapping(all.iter().map(|f| &f.0))).then_some(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm6r::cuspidal::Rng;
    use crate::analyses::arm6r::three_parallel::tests::chain;

    /// `x` widened by a few ulps: an enclosure of data computed in `f64`.
    fn near(x: f64) -> Interval {
        let r = 4.0 * f64::EPSILON * (1.0 + x.abs());
        interval(x - r, x + r)
    }

    /// Whether `phi` holds `theta` modulo a turn.
    fn holds_angle(phi: Interval, theta: f64) -> bool {
        let turns = ((phi.mid() - theta) / std::f64::consts::TAU).round();
        phi.contains(theta + turns * std::f64::consts::TAU)
    }

    fn unit(rng: &mut Rng) -> [f64; 3] {
        let v = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / n)
    }

    /// Random `a, b` and a root θ: `c = a cos θ + b sin θ`; two enclosures, one holding θ, the
    /// other the mirrored root `2·atan2(b, a) − θ`. Beyond `ρ` none; at `ρ` (a double root, as
    /// computed) the discriminant holds 0.
    #[test]
    fn cos_sin_roots_enclose_both_roots_and_count_them() {
        let mut rng = Rng(1985);
        for _ in 0..2000 {
            let (a, b, theta) = (rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), rng.uniform(-3.1, 3.1));
            let c = a * theta.cos() + b * theta.sin();
            let other = 2.0 * b.atan2(a) - theta;
            let rho = (a * a + b * b).sqrt();
            match cos_sin_roots(near(a), near(b), near(c)) {
                Ok(roots) => {
                    assert_eq!(roots.len(), 2, "{a} {b} {c}");
                    assert!(roots.iter().any(|&r| holds_angle(r, theta)) && roots.iter().any(|&r| holds_angle(r, other)), "{a} {b} {theta}: {roots:?}");
                    assert!(roots.iter().all(|r| r.wid() < 1e-6));
                }
                // Only where the two roots nearly coincide.
                Err(why) => assert!(why == Degeneracy::Discriminant && (rho - c.abs()) < 1e-9 * rho, "{a} {b} {theta}: {why:?}"),
            }
            assert_eq!(cos_sin_roots(near(a), near(b), near(1.001 * rho + 1e-6)).map(|r| r.len()), Ok(0));
        }
        assert_eq!(cos_sin_roots(point(3.0), point(4.0), point(5.0)), Err(Degeneracy::Discriminant));
        assert_eq!(cos_sin_roots(point(0.0), point(0.0), interval(-1e-9, 1e-9)), Err(Degeneracy::Discriminant));
    }

    /// Random axes, vectors and turns: `turn` encloses the turn carrying `from` onto `R(a, θ)·from`;
    /// a vector along the axis leaves it undetermined.
    #[test]
    fn turn_encloses_the_turn_between_two_vectors() {
        let mut rng = Rng(2022);
        for _ in 0..2000 {
            let (a, from, theta) = (unit(&mut rng), [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)], rng.uniform(-3.1, 3.1));
            let r = crate::analyses::arm6r::chain::rotation64(&a, theta).r;
            let to: [f64; 3] = [0, 1, 2].map(|i| (0..3).map(|j| r[i][j] * from[j]).sum());
            let phi = turn(&a.map(near), &from.map(near), &to.map(near)).expect("a vector off the axis");
            assert!(holds_angle(phi, theta) && phi.wid() < 1e-6, "{a:?} {from:?} {theta}: {phi:?}");
            let along = a.map(|x| near(0.3 * x));
            assert_eq!(turn(&a.map(near), &along, &along), Err(Degeneracy::Direction));
        }
    }

    #[test]
    fn copies_within_the_range_and_at_its_limits() {
        let x = interval(0.5, 0.5 + 1e-12);
        let inside = |c: SmallVec<[(f64, Interval, Option<Degeneracy>); 2]>| c.iter().map(|y| (y.0, y.2)).collect::<Vec<_>>();
        assert_eq!(inside(copies(x, (-3.2, 3.2))), vec![(0.0, None)]);
        assert_eq!(inside(copies(x, (-6.1, 6.1))), vec![(-1.0, None), (0.0, None)]);
        assert!(copies(x, (0.6, 1.0)).is_empty());
        assert_eq!(inside(copies(x, (0.5 + 1e-13, 1.0))), vec![(0.0, Some(Degeneracy::Limit))]);
    }

    /// The bundled spherical-wrist arms are recognised (after the rounding policy); the UR5
    /// (offset wrist) and a general 6R are not.
    #[test]
    fn spherical_wrists_are_recognised() {
        let file = |f: &str| std::fs::read_to_string(format!("{}/{f}", env!("CARGO_MANIFEST_DIR"))).expect("bundled");
        for f in ["urdf/puma560.urdf", "urdf/kuka_kr16.urdf", "urdf/staubli_tx90.urdf", "tests/data/abb_irb140_style.urdf"] {
            assert!(matches!(recognise(&chain(&file(f))), Some(Geometry::SphericalWrist(_))), "{f}");
        }
        for f in ["urdf/ur5.urdf", "tests/data/ur5_ros_style.urdf"] {
            assert!(matches!(recognise(&chain(&file(f))), Some(Geometry::ParallelAxes(_))), "{f}");
        }
        for f in ["urdf/ur5.urdf", "tests/data/ik6_general_6r.urdf", "tests/data/fanuc_crx10ial_style.urdf", "tests/data/doosan_style_6r.urdf"] {
            assert!(spherical_wrist(&chain(&file(f))).is_none(), "{f}");
        }
    }
}

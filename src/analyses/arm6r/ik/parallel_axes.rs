//! Closed-form certified inverse kinematics of arms whose axes 2, 3 and 4 are parallel and
//! whose axes 5 and 6 meet (Universal Robots UR3/5/10 and their e-series, Techman TM, and the
//! like: any offsets along or between the axes, any angle between axes 1 and 2, between
//! axes 4 and 5 or between axes 5 and 6 but the exclusions below).
//!
//! # Recognition
//!
//! `recognise` proves on the chain's interval coefficients (after the rounding policy, when
//! one applied) that axes 2, 3, 4 are parallel and that axes 5 and 6 meet, at a point `W`:
//! exact zeros of cross and triple products; strict signs where axes must not be parallel
//! (1 and 2, 4 and 5, 5 and 6). Coefficients that only *contain* a relation prove nothing,
//! and the search answers.
//!
//! # The decomposition (Hawkins 2013; in the subproblems of Paden 1985, as in Elias & Wen 2022)
//!
//! Let `u` be the common direction of axes 2, 3, 4 in joint 1's frame after its turn (`F₁`).
//! Joints 2, 3, 4 turn about lines along `u`, so they keep every point's coordinate along `u`
//! in `F₁`. `W` lies on axis 5, so it is fixed in link 4, and on axis 6, so the target places
//! it: `W = G·w₆` with `G = target·Post⁻¹`. Hence `u·W` in `F₁` is a constant `h`, and joint 1
//! solves `(R₁u)·P = h` (`P` is `W` in joint 1's frame before its turn), an equation
//! `a cos θ + b sin θ = c` (subproblem 4, up to two roots). With `M = F₁ᵀ·G.r`, axis 6's
//! direction `M a₆` has the coordinate `u·M a₆ = e·R₅ d₆` along `u` (`e` is `u` and `d₆` is
//! axis 6, both in joint 5's frame before its turn): joint 5 by subproblem 4 again (up to two
//! roots; the two coincide where axis 6 is parallel to `u`, the wrist singularity). Joint 6
//! turns `Mᵀu` onto `u` as joint 5 leaves it in joint 6's frame (subproblem 1; undetermined
//! when axis 6 is along `u`). Then link 4's orientation `A = M·(Pre₅.r R₅ Pre₆.r R₆)ᵀ` and
//! with it joint 4's origin `O₄ = W − A·w₄` are known. What remains is planar: the distance
//! from axis 2's origin to `O₄` depends on joint 3 alone (the law of cosines, subproblem 3, up
//! to two roots), joint 2 turns the one vector onto the other, and joint 4 turns axis 5 onto
//! its place in `A` (subproblem 1). At most eight branches.
//!
//! # The wrist singularity
//!
//! Where axis 6 lies along `u` (joint 5's equation has a double root), joint 6 no longer moves
//! the tip out of the plane: it turns freely, joints 2, 3, 4 following in the plane, so a
//! branch of joints 1 and 5 is a curve parametrised by joint 6 (`aligned_wrist`), both elbows
//! on it, ending where the elbow stretches out. Joint 5's roots are enclosed about the double
//! root (`singular_curves::double_root`), joint 6 is taken in pieces over its range, and the
//! rest is solved for each piece; the cover holds every solution of the branch, whether the
//! pose is exactly singular (the curve) or just off it (isolated solutions beside it).
//!
//! Each step is interval arithmetic on enclosures of exact quantities, each branch count is
//! proven by a discriminant's sign, and anything else undecided is a `Degeneracy` that hands the
//! whole pose to the search: the guarantees of `closed_form` (candidates, copies in the joint
//! ranges, Krawczyk certificates, disjoint boxes) carry over unchanged.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::closed_form::{add, cos_sin, cos_sin_roots, cross, dot, elbow, exact_zero, nonzero, rotate, rotation, sub, turn, Branches, Degeneracy, M3, V3};
use super::singular_curves::{self, CurveKind};
use crate::analyses::arm6r::chain::{Chain6R, IAffine};
use crate::formulate::stated;
use crate::kernel::interval::{point, Interval};
use smallvec::SmallVec;

/// What `recognise` proved (module doc): `W` and the constants of the equations, each an
/// enclosure of the exact value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ParallelAxes {
    /// `W` in joint 6's frame (on axis 6, so the same before and after its turn).
    w6: V3,
    /// `W` in joint 4's frame after its turn (on axis 5: fixed by joint 5).
    w4: V3,
    /// Joint 4's origin in joint 3's frame after its turn.
    v: V3,
    /// `u` in joint 1's frame after its turn, and in joint 5's frame before its turn.
    u: V3,
    e: V3,
    /// `u·W` in `F₁`, the same at every angle of joints 2, 3, 4.
    h: Interval,
    /// `|Pre₃.t + Pre₃.r R₃(θ₃) v|² = k₃ + α₃ cos θ₃ + β₃ sin θ₃`.
    k3: Interval,
    alpha3: Interval,
    beta3: Interval,
}

/// Proves the conditions of the module doc on `chain`'s coefficients, or `None` when one is not
/// proven. Each relation is between consecutive axes, tested in the frame of the first of the
/// two after its turn, where it holds at every angle.
pub(crate) fn recognise(chain: &Chain6R) -> Option<ParallelAxes> {
    let (a, pre) = (&chain.axes, &chain.pre);
    let next = |k: usize| stated::apply(&pre[k + 1].r, &a[k + 1]);
    let u = next(0);
    // Axes 2, 3, 4 parallel; axis 1 not along them; axes 4 and 5, 5 and 6 not parallel.
    if !(exact_zero(&cross(&a[1], &next(1))) && exact_zero(&cross(&a[2], &next(2)))) {
        return None;
    }
    let (d5, d6) = (next(3), next(4));
    let across = cross(&d6, &a[4]);
    if !(nonzero(&cross(&a[0], &u)) && nonzero(&cross(&a[3], &d5)) && nonzero(&across)) {
        return None;
    }
    // Axes 5 and 6 meet: axis 5 through joint 5's origin along a₅, axis 6 through p₆ along d₆,
    // coplanar. W = p₆ + t d₆ with (p₆ + t d₆) × a₅ = 0.
    let p6 = pre[5].t;
    let coplanar = dot(&p6, &cross(&a[4], &d6));
    if !(coplanar.inf() == 0.0 && coplanar.sup() == 0.0) {
        return None;
    }
    let t = -dot(&cross(&p6, &a[4]), &across) / dot(&across, &across);
    let w5 = add(&p6, &d6.map(|x| t * x));
    let w4 = add(&pre[4].t, &stated::apply(&pre[4].r, &w5));
    let u3 = stated::apply_transposed(&pre[2].r, &a[1]);
    let u4 = stated::apply_transposed(&pre[3].r, &u3);
    let v = pre[3].t;
    let h = dot(&u, &pre[1].t) + dot(&a[1], &pre[2].t) + dot(&u3, &pre[3].t) + dot(&u4, &w4);
    // |t + R₃v|² with t = Pre₃.rᵀPre₃.t, R₃v by Rodrigues.
    let t3 = stated::apply_transposed(&pre[2].r, &pre[2].t);
    let (at, av) = (dot(&a[2], &t3), dot(&a[2], &v));
    let two = point(2.0);
    Some(ParallelAxes {
        w6: a[5].map(|x| t * x),
        w4,
        v,
        u,
        e: stated::apply_transposed(&pre[4].r, &u4),
        h,
        k3: dot(&pre[2].t, &pre[2].t) + dot(&v, &v) + two * at * av,
        alpha3: two * (dot(&t3, &v) - at * av),
        beta3: two * dot(&t3, &cross(&a[2], &v)),
    })
}

fn transpose(m: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[j][i]))
}

/// Every solution's angles modulo a turn (module doc), at most eight; at a wrist-singular
/// pose the curve of each branch of joints 1 and 5 whose joint 5 has a double root, as a cover
/// (`aligned_wrist`).
pub(super) fn branches(chain: &Chain6R, arm: &ParallelAxes, g: &IAffine) -> Result<Branches, Degeneracy> {
    let (a, pre) = (&chain.axes, &chain.pre);
    let w = add(&stated::apply(&g.r, &arm.w6), &g.t);
    let p = stated::apply_transposed(&pre[0].r, &sub(&w, &pre[0].t));
    let u = &arm.u;
    // (R₁u)·P = (a₁·u)(a₁·P) + cos θ₁ (u·P − (a₁·u)(a₁·P)) + sin θ₁ (a₁ × u)·P.
    let (ua, pa) = (dot(&a[0], u), dot(&a[0], &p));
    let d6 = stated::apply(&pre[5].r, &a[5]);
    let (e, a5) = (&arm.e, &a[4]);
    let k5 = dot(e, a5) * dot(a5, &d6);
    let mut out = Branches::default();
    for t1 in cos_sin_roots(dot(u, &p) - ua * pa, dot(&cross(&a[0], u), &p), arm.h - ua * pa)? {
        let (c1, s1) = cos_sin(t1);
        let f1 = stated::mul(&pre[0].r, &rotation(&a[0], c1, s1));
        let wrist = Wrist { m: stated::mul(&transpose(&f1), &g.r), w1: rotate(&a[0], c1, -s1, &p), t1 };
        let mtu = stated::apply_transposed(&wrist.m, u);
        let (a5c, b5c, c5c) = (dot(e, &d6) - k5, dot(e, &cross(a5, &d6)), dot(u, &stated::apply(&wrist.m, &a[5])) - k5);
        match cos_sin_roots(a5c, b5c, c5c) {
            Ok(roots) => {
                for t5 in roots {
                    let (c5, s5) = cos_sin(t5);
                    let t6 = turn(&a[5], &mtu, &stated::apply_transposed(&pre[5].r, &rotate(a5, c5, -s5, e)))?;
                    let (found, double) = position(chain, arm, &wrist, t5, t6, false)?;
                    if double {
                        out.double.extend(found);
                    } else {
                        out.points.extend(found);
                    }
                }
            }
            Err(Degeneracy::Discriminant) => {
                if let Some(t5) = singular_curves::double_root(a5c, b5c, c5c)? {
                    let cover = aligned_wrist(chain, arm, &wrist, t5)?;
                    if !cover.is_empty() {
                        out.covers.push((CurveKind::WristAligned, cover));
                    }
                }
            }
            Err(why) => return Err(why),
        }
    }
    Ok(out)
}

/// A position's solutions for joints 5 and 6 (both elbows).
type Candidates = SmallVec<[[Interval; 6]; 2]>;

/// Joint 1's root `t1`, the wrist's matrix `M = F₁ᵀ·G.r` and `W` in joint 1's frame after
/// its turn.
struct Wrist {
    m: M3,
    w1: V3,
    t1: Interval,
}

/// Joints 3, 2, 4 for joints 5 and 6 at `t5`, `t6` (module doc), and whether the elbow's two
/// roots meet as far as the enclosures tell, one enclosure holding both
/// (`closed_form::elbow`): along a curve (`along`) where `t6`'s piece reaches a fold, or at an
/// isolated solution with the elbow stretched out (`Branches::double`).
fn position(chain: &Chain6R, arm: &ParallelAxes, wrist: &Wrist, t5: Interval, t6: Interval, along: bool) -> Result<(Candidates, bool), Degeneracy> {
    let (a, pre, a5) = (&chain.axes, &chain.pre, &chain.axes[4]);
    let ((c5, s5), (c6, s6)) = (cos_sin(t5), cos_sin(t6));
    let n = stated::mul(&stated::mul(&stated::mul(&pre[4].r, &rotation(a5, c5, s5)), &pre[5].r), &rotation(&a[5], c6, s6));
    let link4 = stated::mul(&wrist.m, &transpose(&n));
    let z = sub(&sub(&wrist.w1, &stated::apply(&link4, &arm.w4)), &pre[1].t);
    // Axis 5 in link 4, and where `A` puts it.
    let x = stated::apply(&pre[4].r, a5);
    let ax = stated::apply(&link4, &x);
    let (elbows, double) = elbow(arm.alpha3, arm.beta3, dot(&z, &z) - arm.k3)?;
    let mut out = SmallVec::new();
    for t3 in elbows {
        let (c3, s3) = cos_sin(t3);
        let y = add(&pre[2].t, &stated::apply(&pre[2].r, &rotate(&a[2], c3, s3, &arm.v)));
        let t2 = turn(&a[1], &y, &stated::apply_transposed(&pre[1].r, &z))?;
        let (c2, s2) = cos_sin(t2);
        // B = Pre₂.r R₂ Pre₃.r R₃ Pre₄.r, and R₄ x = Bᵀ A x.
        let b = stated::mul(&stated::mul(&stated::mul(&pre[1].r, &rotation(&a[1], c2, s2)), &pre[2].r), &stated::mul(&rotation(&a[2], c3, s3), &pre[3].r));
        let t4 = turn(&a[3], &x, &stated::apply_transposed(&b, &ax))?;
        out.push([wrist.t1, t2, t3, t4, t5, t6]);
    }
    Ok((out, double && !along))
}

/// The cover of a branch whose axis 6 lies along `u` as far as the enclosures tell: joint 6 in
/// pieces over its whole range, joint 5 in its double root's enclosure `t5`, the rest solved for
/// each piece in interval arithmetic (`position`), every other angle's copies within its range.
/// Every exact solution of the branch with joint 6 in a piece lies in one of the piece's boxes:
/// the equation joint 6 solves off the singularity is dropped, the others hold, so the boxes
/// hold the curve (an exactly singular pose) or the isolated solutions beside it (a pose just
/// off it).
fn aligned_wrist(chain: &Chain6R, arm: &ParallelAxes, wrist: &Wrist, t5: Interval) -> Result<Vec<[Interval; 6]>, Degeneracy> {
    let mut cover = Vec::new();
    for t6 in singular_curves::pieces(chain.ranges[5]) {
        for b in &position(chain, arm, wrist, t5, t6, true)?.0 {
            cover.extend(singular_curves::copies_within(chain, b, Some(5)));
        }
    }
    Ok(cover)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm6r::three_parallel::tests::{chain, family};

    fn file(f: &str) -> String {
        std::fs::read_to_string(format!("{}/{f}", env!("CARGO_MANIFEST_DIR"))).expect("bundled")
    }

    /// The bundled UR-style arms and members of the three-parallel family are recognised; the
    /// spherical-wrist arms and a general 6R are not.
    #[test]
    fn three_parallel_axes_are_recognised() {
        for f in ["urdf/ur5.urdf", "tests/data/ur5_ros_style.urdf"] {
            assert!(recognise(&chain(&file(f))).is_some(), "{f}");
        }
        for seed in 1..=6 {
            assert!(recognise(&chain(&family(seed, 0.7, true))).is_some(), "seed {seed}");
        }
        for f in ["urdf/puma560.urdf", "urdf/kuka_kr16.urdf", "tests/data/ik6_general_6r.urdf", "tests/data/fanuc_crx10ial_style.urdf", "tests/data/doosan_style_6r.urdf"] {
            assert!(recognise(&chain(&file(f))).is_none(), "{f}");
        }
    }

    /// Random members of the family and random joint vectors: some branch holds the vector
    /// (modulo a turn), every branch is narrow.
    #[test]
    fn some_branch_holds_the_joints_that_made_the_pose() {
        let mut rng = crate::analyses::arm6r::cuspidal::Rng(2013);
        for seed in 1..=8 {
            let c = chain(&family(seed, if seed % 2 == 0 { 0.7 } else { std::f64::consts::FRAC_PI_2 }, seed > 2));
            let arm = recognise(&c).expect("a member");
            for _ in 0..10 {
                let q: [f64; 6] = std::array::from_fn(|_| rng.uniform(-3.0, 3.0));
                let pose = c.pose(&q);
                let r = 1e-13;
                let target = IAffine { r: pose.r.map(|row| row.map(|x| crate::kernel::interval::interval(x - r, x + r))), t: pose.t.map(|x| crate::kernel::interval::interval(x - r, x + r)) };
                let g = target.then(&c.post.inverse());
                let found = branches(&c, &arm, &g).expect("a generic pose").points;
                let holds = |b: &[Interval; 6]| (0..6).all(|k| {
                    let turns = ((b[k].mid() - q[k]) / std::f64::consts::TAU).round();
                    b[k].contains(q[k] + turns * std::f64::consts::TAU)
                });
                assert!(found.iter().any(holds), "seed {seed}, q {q:?}: {found:?}");
                assert!(found.len() <= 8 && found.iter().flatten().all(|x| x.wid() < 1e-6), "{found:?}");
            }
        }
    }
}

//! The solutions of a spherical-wrist arm's branches at a singular pose, where they form
//! curves in the joint space (Pieper 1968; the subproblems of Paden 1985 with a double root
//! or a vanishing equation): each enclosed by a cover of boxes, none claimed unique.
//!
//! # The wrist
//!
//! Joint 5 lines axes 4 and 6 up, and joints 4 and 6 turn together. With joints 1–3 of the
//! branch enclosed, the wrist's matrix `M = R₄·Pre₅.r·R₅·Pre₆.r·R₆` is enclosed. Joint 5
//! solves `A cos θ₅ + B sin θ₅ = C` (`closed_form::joint5_equation`); when the discriminant
//! `A² + B² − C²` holds 0, `cos(θ₅ − φ) = C/ρ` (with `φ` the angle of `(A, B)` and
//! `ρ² = A² + B²`) lies within `[C/ρ]` near 1 (or −1), so every root lies within
//! `φ ± arccos(inf C/ρ)` (or about `φ + π`): `double_root`. Whether the pose is exactly singular
//! (a curve of solutions) or just off it (two isolated solutions, a wrist flip apart, both
//! near the curve) the enclosures cannot tell; either way every solution of the branch lies
//! in the cover `cover` builds: joint 4 in pieces over its whole range; for `θ₄` in a piece and
//! `θ₅` in its enclosure, `R₆ = Pre₆.rᵀ·R₅ᵀ·Pre₅.rᵀ·R₄ᵀ·M` is enclosed, and `θ₆` is the turn
//! about axis 6 carrying a vector `x` onto `R₆x` (subproblem 1): every exact solution with
//! `θ₄` in the piece has its `θ₆` there.
//!
//! # The shoulder
//!
//! With the wrist centre on axis 1, joint 1's equation `(R₁u)·P = h` holds at every angle:
//! joint 1 turns freely, joints 2 and 3 stay, the wrist follows. `shoulder` takes joint 1 in
//! pieces over its whole range and solves the rest of the decomposition for each piece in
//! interval arithmetic (`closed_form::after_joint1`): every exact solution with joint 1 in the
//! piece lies in one of the piece's boxes.

use super::closed_form::{cos_sin, rotate, turn, Branches, Degeneracy, M3};
use super::copies_in;
use crate::analyses::arm6r::chain::Chain6R;
use crate::formulate::stated;
use crate::kernel::interval::{interval, point, trig, Interval};

/// Joint 4's pieces are at most this wide (radians): the cover's resolution along the curve.
pub(crate) const PIECE: f64 = 1.0 / 32.0;

/// Joints 1–3 of a branch whose wrist is singular as far as the enclosures tell, the wrist's
/// matrix `M`, and joint 5's enclosure (modulo a turn).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SingularWrist {
    pub position: [Interval; 3],
    pub m: M3,
    pub t5: Interval,
}

/// Every root θ (modulo a turn) of `a cos θ + b sin θ = c` in one enclosure, when the
/// discriminant holds 0 (module doc); `Ok(None)` when there is none; `Discriminant` when
/// the enclosures leave both double roots possible (`C/ρ` reaching both 1 and −1), or two
/// separate roots, or `ρ` may vanish.
pub(crate) fn double_root(a: Interval, b: Interval, c: Interval) -> Result<Option<Interval>, Degeneracy> {
    let r2 = a.sqr() + b.sqr();
    if !(r2.inf() > 0.0) {
        return Err(Degeneracy::Discriminant);
    }
    let phi = trig::angle(a, b).ok_or(Degeneracy::Discriminant)?;
    let q = c / r2.sqrt();
    let (lo, hi) = (q.inf(), q.sup());
    if lo > 1.0 || hi < -1.0 {
        return Ok(None);
    }
    // The upper end of `arccos x`, the angle of `(x, √(1 − x²))`: the widest half-width the
    // roots can have.
    let half = |x: f64| trig::angle(point(x), (point(1.0) - point(x).sqr()).sqrt()).map_or(std::f64::consts::PI, |t| t.sup());
    if hi >= 1.0 && lo > -1.0 {
        let r = half(lo);
        Ok(Some(phi + interval(-r, r)))
    } else if lo <= -1.0 && hi < 1.0 {
        let r = half(-hi);
        Ok(Some(phi + Interval::PI + interval(-r, r)))
    } else {
        Err(Degeneracy::Discriminant)
    }
}

/// Boxes enclosing every solution of the branch `s` within the ranges (module doc), joint 4
/// in pieces at most `PIECE` wide, each angle's copies within its range.
pub(crate) fn cover(chain: &Chain6R, s: &SingularWrist) -> Vec<[Interval; 6]> {
    let (a, pre, ranges) = (&chain.axes, &chain.pre, &chain.ranges);
    let within = |phi: Interval, k: usize| copies_in(phi, ranges[k].0, ranges[k].1);
    let mut position: Vec<[Interval; 3]> = vec![[point(0.0); 3]];
    for k in 0..3 {
        let each = within(s.position[k], k);
        position = position.iter().flat_map(|p| each.iter().map(move |r| {
            let mut p = *p;
            p[k] = interval(r[0], r[1]);
            p
        })).collect();
    }
    let fifth = within(s.t5, 4);
    if position.is_empty() || fifth.is_empty() {
        return Vec::new();
    }
    // A coordinate direction far from axis 6: its turn about the axis is well determined.
    let size = |i: usize| a[5][i].mag();
    let k = (0..3).min_by(|&i, &j| size(i).total_cmp(&size(j))).unwrap_or(0);
    let mut x = [point(0.0); 3];
    x[k] = point(1.0);
    let mx = stated::apply(&s.m, &x);
    let mut out = Vec::new();
    for t4 in pieces(ranges[3]) {
        let (c4, s4) = cos_sin(t4);
        let y4 = stated::apply_transposed(&pre[4].r, &rotate(&a[3], c4, -s4, &mx));
        for f in &fifth {
            let t5 = interval(f[0], f[1]);
            let (c5, s5) = cos_sin(t5);
            let y = stated::apply_transposed(&pre[5].r, &rotate(&a[4], c5, -s5, &y4));
            let sixth = match turn(&a[5], &x, &y) {
                Ok(t6) => within(t6, 5).to_vec(),
                // The enclosures leave the turn open: the whole range holds it.
                Err(_) => vec![[ranges[5].0, ranges[5].1]],
            };
            for g in &sixth {
                for p in &position {
                    out.push([p[0], p[1], p[2], t4, t5, interval(g[0], g[1])]);
                }
            }
        }
    }
    out
}

/// Boxes enclosing every solution within the ranges at a shoulder-singular pose (module
/// doc): joint 1 in pieces at most `PIECE` wide, `branches` solving the rest for a piece, each
/// other angle's copies within its range; a piece whose wrist is singular too has its wrist
/// covered as at a wrist singularity (`cover`).
pub(crate) fn shoulder(chain: &Chain6R, mut branches: impl FnMut(Interval, &mut Branches) -> Result<(), Degeneracy>) -> Result<Vec<[Interval; 6]>, Degeneracy> {
    let mut out = Vec::new();
    for t1 in pieces(chain.ranges[0]) {
        let mut found = Branches::default();
        branches(t1, &mut found)?;
        for b in found.points {
            out.extend(copies_within(chain, &b, Some(0)));
        }
        // Where the curve meets a wrist singularity, the piece's wrist is covered whole.
        for s in &found.singular {
            out.extend(cover(chain, s));
        }
    }
    Ok(out)
}

/// `[lo, hi]` in pieces at most `PIECE` wide sharing their ends, the first starting at `lo`
/// and the last ending at `hi`: together the whole range.
pub(super) fn pieces((lo, hi): (f64, f64)) -> Vec<Interval> {
    let n = ((hi - lo) / PIECE).ceil().max(1.0) as usize;
    let end = |i: usize| if i == n { hi } else { lo + (hi - lo) * (i as f64 / n as f64) };
    (0..n).map(|i| interval(end(i), end(i + 1))).collect()
}

/// The copies of the box `b` (angles modulo a turn) within the ranges, each angle's copies
/// clipped to its range, but a curve's parameter `along`, already a piece of its range
/// (whose copies are other pieces).
pub(super) fn copies_within(chain: &Chain6R, b: &[Interval; 6], along: Option<usize>) -> Vec<[Interval; 6]> {
    let mut out = vec![*b];
    for k in (0..6).filter(|&k| Some(k) != along) {
        let each = copies_in(b[k], chain.ranges[k].0, chain.ranges[k].1);
        out = out.iter().flat_map(|x| each.iter().map(move |r| {
            let mut x = *x;
            x[k] = interval(r[0], r[1]);
            x
        })).collect();
    }
    out
}

/// Where the solutions of a singular branch lie: on a curve, or, for a pose just off the
/// singularity, at isolated points on it, which the pose's enclosure cannot tell apart
/// (module doc). The cover encloses them all within the ranges; its boxes may hold
/// solutions, none is claimed unique.
#[derive(Clone, Debug)]
pub struct Ik6Curve {
    /// Which singularity.
    pub kind: CurveKind,
    /// Boxes, the curve's parameter (joint 4 at a spherical wrist, joint 6 at a wrist aligned
    /// with three parallel axes, joint 1 at the shoulder) in pieces at most 1/32 rad wide, the
    /// joints that move with it following.
    pub cover: Vec<[Interval; 6]>,
    /// The cover's hull: the joints' ranges along the curve.
    pub hull: [Interval; 6],
}

/// The singularities whose solutions form curves in closed form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// Joint 5 lines axes 4 and 6 up: joints 4 and 6 turn together (one branch of joints 1–3).
    Wrist,
    /// The wrist centre on axis 1: joint 1 turns freely, joints 4–6 following (joints 2 and 3
    /// fixed); the boxes of every branch.
    Shoulder,
    /// Joint 5 lines axis 6 up with axes 2, 3, 4 (all four parallel, as in the UR family):
    /// joint 6 turns freely, joints 2, 3, 4 following in the plane (one branch of joints 1
    /// and 5, both elbows).
    WristAligned,
}

impl CurveKind {
    /// As reports write it.
    pub fn name(self) -> &'static str {
        match self {
            CurveKind::Wrist | CurveKind::WristAligned => "wrist_singular",
            CurveKind::Shoulder => "shoulder_singular",
        }
    }

    /// The joints (from 0) that move along the curve.
    pub fn moving(self) -> &'static [usize] {
        match self {
            CurveKind::Wrist => &[3, 5],
            CurveKind::Shoulder => &[0, 3, 4, 5],
            CurveKind::WristAligned => &[1, 2, 3, 5],
        }
    }
}

impl Ik6Curve {
    pub(super) fn all(covers: Vec<(CurveKind, Vec<[Interval; 6]>)>) -> Vec<Ik6Curve> {
        covers.into_iter().map(|(kind, cover)| Ik6Curve { kind, hull: super::boxes::hull(&cover), cover }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm6r::cuspidal::Rng;

    /// `x` widened by a few ulps.
    fn near(x: f64) -> Interval {
        let r = 4.0 * f64::EPSILON * (1.0 + x.abs());
        interval(x - r, x + r)
    }

    /// A double root θ of `a cos θ + b sin θ = c` (`c = ±ρ`), and roots a hair either side of
    /// it (`c` just inside): one enclosure holds them all; beyond `ρ` there is none.
    #[test]
    fn double_root_encloses_the_roots_about_a_double_root() {
        let mut rng = Rng(1989);
        for _ in 0..2000 {
            let (a, b, sign) = (rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), if rng.uniform(0.0, 1.0) < 0.5 { 1.0 } else { -1.0 });
            let rho = (a * a + b * b).sqrt();
            let phi = b.atan2(a) + if sign < 0.0 { std::f64::consts::PI } else { 0.0 };
            for off in [0.0, 1e-9, -1e-9] {
                let theta = phi + off;
                let c = a * theta.cos() + b * theta.sin();
                let Ok(Some(t5)) = double_root(near(a), near(b), near(c)) else { panic!("{a} {b} {c}") };
                let turns = ((t5.mid() - theta) / std::f64::consts::TAU).round();
                assert!(t5.contains(theta + turns * std::f64::consts::TAU), "{a} {b} {theta}: {t5:?}");
                // About the square root of the data's width relative to ρ.
                assert!(t5.wid() < 1e-6 / rho.sqrt(), "{rho}: {t5:?}");
            }
            assert_eq!(double_root(near(a), near(b), near(sign * 1.001 * rho)), Ok(None));
        }
        assert_eq!(double_root(point(0.0), point(0.0), point(0.0)), Err(Degeneracy::Discriminant));
    }
}

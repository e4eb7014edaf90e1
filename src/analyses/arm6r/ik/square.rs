//! The square system the certificates are taken on, and its Krawczyk step.
//!
//! On a split (`Chain6R::split`, `L(θ₁,θ₂,θ₃) = R(θ₄,θ₅,θ₆)`), the six equations
//! `p_L − p_R = 0` and `vee(skew(R_L R_Rᵀ)) = 0` have the solutions of the twelve where
//! `trace(R_L R_Rᵀ) > −1` (the rotation part vanishes for rotations by 0 and π only; the trace
//! excludes π). Their Jacobian is the arm's twist Jacobian at a solution. Both the search's
//! small boxes and the closed form's candidates are certified here, so a box is unique by one
//! test whichever method proposed it.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::{frames_of, mid, sub3, Split};
use crate::analyses::arm6r::chain::{cross, mm, Affine, M, V};
use crate::kernel::contract::krawczyk::{self, Step as K};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{point, Interval};

fn transpose(m: &M) -> M {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[j][i]))
}

fn skew(w: &V) -> M {
    let z = Iv::ZERO;
    [[z, w[2].neg(), w[1]], [w[2], z, w[0].neg()], [w[1].neg(), w[0], z]]
}

/// `vee` of the skew part of `x`, `(x₃₂ − x₂₃, x₁₃ − x₃₁, x₂₁ − x₁₂)/2`.
fn vee_skew(x: &M) -> V {
    [x[2][1].sub(x[1][2]), x[0][2].sub(x[2][0]), x[1][0].sub(x[0][1])].map(|v| v.scale(0.5))
}

/// The twist of each joint over the box: (direction, point) in the base frame, and on which
/// side it acts (the left side's value or the right's).
#[inline]
fn twists(split: &Split, fl: &[Affine; 7], fr: &[Affine; 7]) -> [(V, V, bool); 6] {
    let (left, right) = (&split.0, &split.1);
    let l = |k| {
        let (w, p) = left.axis(fl, k);
        (w, p, true)
    };
    let r = |k| {
        let (w, p) = right.axis(fr, k);
        (w, p, false)
    };
    [l(0), l(1), l(2), r(2), r(1), r(0)]
}

/// One Krawczyk step on the square system of the module doc over `b`.
pub(super) fn newton(split: &Split, b: &[Interval; 6]) -> K<[Interval; 6]> {
    let (m, fm, jac) = linearised(split, b);
    krawczyk::step_array(b, &m, &fm, &jac)
}

/// Krawczyk's image of `b` (unintersected); on a point box, a Newton step from it.
pub(super) fn image(split: &Split, b: &[Interval; 6]) -> Option<[Interval; 6]> {
    let (m, fm, jac) = linearised(split, b);
    krawczyk::image_array(b, &m, &fm, &jac)
}

/// The system at the centre of `b` and its Jacobian over `b`.
fn linearised(split: &Split, b: &[Interval; 6]) -> ([f64; 6], [Interval; 6], [[Interval; 6]; 6]) {
    let bb = b.map(|x| [x.inf(), x.sup()]);
    let m = mid(&bb);
    let (fl, fr) = frames_of(split, &bb);
    let (ml, mr) = frames_of(split, &m.map(|x| [x, x]));
    let (l, r) = (fl[3], fr[3]);
    let e = mm(&l.r, &transpose(&r.r));
    let em = mm(&ml[3].r, &transpose(&mr[3].r));
    let pm = sub3(&ml[3].t, &mr[3].t);
    let wm = vee_skew(&em);
    let fm: [Interval; 6] = [pm[0], pm[1], pm[2], wm[0], wm[1], wm[2]].map(Iv::to);
    let mut jac = [[point(0.0); 6]; 6];
    for (v, (w, p, on_left)) in twists(split, &fl, &fr).iter().enumerate() {
        let (pos, rot) = if *on_left {
            (cross(w, &sub3(&l.t, p)), vee_skew(&mm(&skew(w), &e)))
        } else {
            (cross(w, &sub3(&r.t, p)), vee_skew(&mm(&e, &skew(w))))
        };
        for i in 0..3 {
            jac[i][v] = pos[i].to();
            jac[i + 3][v] = rot[i].to();
        }
    }
    (m, fm, jac)
}

/// Whether `trace(R_L R_Rᵀ) > −1` on the box: a zero of the square system there solves all
/// twelve equations.
pub(super) fn not_a_half_turn(split: &Split, b: &[Interval; 6]) -> bool {
    let (fl, fr) = frames_of(split, &b.map(|x| [x.inf(), x.sup()]));
    let e = mm(&fl[3].r, &transpose(&fr[3].r));
    e[0][0].add(e[1][1]).add(e[2][2]).lo > -1.0
}

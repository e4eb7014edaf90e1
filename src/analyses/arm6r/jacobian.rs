//! The arm's Jacobian over a joint box, and the one proof that `det J` excludes zero there.
//!
//! Column k of the spatial Jacobian is `(ωₖ, pₖ × ωₖ)` for joint k's axis direction ωₖ through
//! the point pₖ (base frame), here enclosed over a box of joint angles in outward arithmetic.
//! The box is regular when `‖I − Y·J(B)‖∞ ≤ r < 1` with `Y ≈ mid(J)⁻¹` in `f64`: every
//! eigenvalue of `Y·J` then lies within r of 1, so `det(Y·J) ∈ [(1−r)⁶, (1+r)⁶]` (positive),
//! and `det J = det(Y·J) / det Y` has the sign of `det Y` (enclosed by interval Gaussian
//! elimination) and magnitude at least `(1−r)⁶ / |det Y|`. The cuspidality witness and the
//! path check both read their proofs from here.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::chain::{cos_sin, cross, Side, V};
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{point, Interval};
use nalgebra::Matrix6;

/// The enclosure of the arm's Jacobian over the joint box `b` (`[lo, hi]` per joint).
pub(crate) fn jacobian_over(arm: &Side<6>, b: &[[f64; 2]; 6]) -> [[Iv; 6]; 6] {
    let cs = [0, 1, 2, 3, 4, 5].map(|k| cos_sin(b[k][0], b[k][1]));
    let frames = arm.frames(&cs);
    let mut jac = [[Iv::ZERO; 6]; 6];
    for k in 0..6 {
        let (w, p): (V, V) = arm.axis(&frames, k);
        let v = cross(&p, &w);
        for i in 0..3 {
            jac[i][k] = w[i];
            jac[i + 3][k] = v[i];
        }
    }
    jac
}

/// A proof that every matrix of an interval Jacobian is regular (module doc).
#[derive(Clone, Debug)]
pub(crate) struct Regularity {
    /// The preconditioner `Y ≈ mid(J)⁻¹`.
    y: Matrix6<f64>,
    /// An upper bound of `‖I − Y·J‖∞` over the box, below 1.
    pub(crate) r: f64,
}

/// The proof for `jac`, or None when the preconditioned test fails.
pub(crate) fn regularity(jac: &[[Iv; 6]; 6]) -> Option<Regularity> {
    let mid = Matrix6::from_fn(|i, j| 0.5 * (jac[i][j].lo + jac[i][j].hi));
    let y = mid.try_inverse()?;
    if !y.iter().all(|x| x.is_finite()) {
        return None;
    }
    let mut worst: f64 = 0.0;
    for i in 0..6 {
        let mut row = 0.0;
        for j in 0..6 {
            let mut e = if i == j { Iv { lo: 1.0, hi: 1.0 } } else { Iv::ZERO };
            for l in 0..6 {
                e = e.sub(jac[l][j].scale(y[(i, l)]));
            }
            // Upper bound of |e|, rounded up.
            row = (row + e.lo.abs().max(e.hi.abs())).next_up();
        }
        if !(row < 1.0) {
            return None;
        }
        worst = worst.max(row);
    }
    Some(Regularity { y, r: worst })
}

/// Whether every matrix in the interval Jacobian of the arm over the joint box `b` is regular.
pub(crate) fn regular_over(arm: &Side<6>, b: &[[f64; 2]; 6]) -> bool {
    regularity(&jacobian_over(arm, b)).is_some()
}

/// `det J` over the box of a proof: an interval excluding zero, or None when `det Y` cannot be
/// given a sign (it then stays unproven).
pub(crate) fn det_enclosure(proof: &Regularity) -> Option<Interval> {
    let det_y = det_of_point(&proof.y);
    if det_y.contains(0.0) || det_y.is_empty() {
        return None;
    }
    let r = point(proof.r);
    let one = point(1.0);
    let sixth = |x: Interval| (x.sqr() * x).sqr();
    let det_yj = sixth(one - r).convex_hull(sixth(one + r));
    let d = det_yj / det_y;
    (!d.contains(0.0) && !d.is_empty()).then_some(d)
}

/// The exact determinant of a point matrix, enclosed by Gaussian elimination in interval
/// arithmetic (pivots chosen on the enclosures, so the same order serves the exact matrix).
fn det_of_point(m: &Matrix6<f64>) -> Interval {
    let mut a: [[Interval; 6]; 6] = [0, 1, 2, 3, 4, 5].map(|i| [0, 1, 2, 3, 4, 5].map(|j| point(m[(i, j)])));
    let mut det = point(1.0);
    for k in 0..6 {
        let p = (k..6).max_by(|&i, &j| a[i][k].mig().total_cmp(&a[j][k].mig())).expect("invariant: a row remains");
        if p != k {
            a.swap(p, k);
            det = -det;
        }
        let pivot = a[k][k];
        if pivot.contains(0.0) || pivot.is_empty() {
            return Interval::ENTIRE;
        }
        det *= pivot;
        for i in k + 1..6 {
            let f = a[i][k] / pivot;
            for j in k + 1..6 {
                a[i][j] -= f * a[k][j];
            }
        }
    }
    det
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_determinant_of_a_point_matrix_is_enclosed() {
        let m = Matrix6::from_fn(|i, j| if i == j { 2.0 + i as f64 } else { 0.1 * (i as f64 - j as f64) });
        let d = det_of_point(&m);
        assert!(d.contains(m.determinant()) && d.wid() < 1e-9 * d.mag(), "{d:?}");
        let mut swapped = m;
        swapped.swap_rows(0, 3);
        assert!(det_of_point(&swapped).contains(-m.determinant()));
    }
}

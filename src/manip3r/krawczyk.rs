//! The Krawczyk operator: interval Newton for square systems, with existence and uniqueness.
//!
//! For `F: ℝⁿ → ℝⁿ`, a box `B`, a point `m ∈ B`, an enclosure `J` of the Jacobian of `F` over
//! `B` and any real matrix `Y` (we take the inverse of `mid J`):
//!
//! ```text
//! K(B) = m − Y F(m) + (I − Y J)(B − m)
//! ```
//!
//! | outcome | meaning |
//! |---|---|
//! | `K ⊂ int B` | `F` has exactly one zero in `B` (and it lies in `K`) |
//! | `K ∩ B = ∅` | `F` has no zero in `B` |
//! | otherwise | every zero in `B` lies in `K ∩ B` |
//!
//! `F(m)` and `J` may be enclosures over a box of parameters too: then each statement holds for
//! every parameter value in it.
//!
//! # References
//! R. Krawczyk, Computing 4 (1969); A. Neumaier, *Interval methods for systems of equations*,
//! Cambridge University Press (1990), section 5.

use crate::interval::fast::Iv;
use inari::Interval;
use nalgebra::SMatrix;

/// What one Krawczyk step proved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step<const N: usize> {
    /// Exactly one zero in the box; it lies in the given (smaller) box.
    Unique([Interval; N]),
    /// No zero in the box.
    Empty,
    /// Every zero lies in the given box (the intersection `K ∩ B`).
    Contracted([Interval; N]),
    /// `mid J` is singular or the arithmetic overflowed: nothing proven.
    Failed,
}

/// One Krawczyk step on `b`, with `fm ⊇ F(m)` at the point `m` and `jac ⊇ J(b)` (row i = ∇Fᵢ).
///
/// The arithmetic is `interval::fast::Iv` (inlined, one ulp outward per operation) rather than inari's:
/// this step runs once per pair of boxes in the node search, where inari's out-of-line calls
/// dominated. Products with the point matrix `Y` scale by a double, and zero entries of `J`
/// (the node system has four) are skipped.
pub fn step<const N: usize>(b: &[Interval; N], m: &[f64; N], fm: &[Interval; N], jac: &[[Interval; N]; N]) -> Step<N> {
    let mid = SMatrix::<f64, N, N>::from_fn(|i, j| jac[i][j].mid());
    if !mid.iter().all(|v| v.is_finite()) {
        return Step::Failed;
    }
    let Some(y) = mid.try_inverse() else { return Step::Failed };
    if !y.iter().all(|v| v.is_finite()) {
        return Step::Failed;
    }
    let jac: [[Iv; N]; N] = jac.map(|row| row.map(Iv::from));
    let fm: [Iv; N] = fm.map(Iv::from);
    let mut dx = [Iv::ZERO; N];
    for j in 0..N {
        let r = Iv::from(b[j]).sub(Iv { lo: m[j], hi: m[j] });
        if r.lo.is_nan() {
            return Step::Failed;
        }
        dx[j] = r;
    }
    let mut k = [Interval::EMPTY; N];
    for i in 0..N {
        let mut acc = Iv { lo: m[i], hi: m[i] };
        for l in 0..N {
            acc = acc.sub(fm[l].scale(y[(i, l)]));
        }
        for j in 0..N {
            // (I − Y J)_{ij}
            let mut e = if i == j { Iv { lo: 1.0, hi: 1.0 } } else { Iv::ZERO };
            for l in 0..N {
                if jac[l][j] != Iv::ZERO {
                    e = e.sub(jac[l][j].scale(y[(i, l)]));
                }
            }
            acc = acc.add(e.mul(dx[j]));
        }
        if !(acc.lo.is_finite() && acc.hi.is_finite()) {
            return Step::Failed;
        }
        k[i] = acc.to();
    }
    if (0..N).all(|i| k[i].interior(b[i])) {
        return Step::Unique(k);
    }
    let mut out = [Interval::EMPTY; N];
    for i in 0..N {
        out[i] = k[i].intersection(b[i]);
        if out[i].is_empty() {
            return Step::Empty;
        }
    }
    Step::Contracted(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interval::{interval, point};

    /// F(x, y) = (x² + y² − 1, x − y): zeros at ±(1/√2, 1/√2).
    fn circle_line(b: &[Interval; 2]) -> Step<2> {
        let m = [b[0].mid(), b[1].mid()];
        let fm = [point(m[0]).sqr() + point(m[1]).sqr() - point(1.0), point(m[0]) - point(m[1])];
        let two = point(2.0);
        let jac = [[two * b[0], two * b[1]], [point(1.0), point(-1.0)]];
        step(b, &m, &fm, &jac)
    }

    #[test]
    fn proves_the_root_excludes_the_empty_and_contracts_the_rest() {
        assert!(matches!(circle_line(&[interval(0.6, 0.8), interval(0.6, 0.8)]), Step::Unique(_)));
        assert_eq!(circle_line(&[interval(0.1, 0.2), interval(0.1, 0.2)]), Step::Empty);
        match circle_line(&[interval(0.0, 1.0), interval(0.0, 1.0)]) {
            Step::Contracted(k) | Step::Unique(k) => assert!(k[0].contains(0.5f64.sqrt())),
            other => panic!("unexpected {other:?}"),
        }
    }
}

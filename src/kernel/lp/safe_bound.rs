//! Neumaier–Shcherbina safe bounds: rigorous consequences of arbitrary LP multipliers.
//!
//! For rows `aₖ·x ∈ Bₖ` and any multipliers `μ`, every feasible `x` in the box `X` satisfies
//! `q·x = Σ μₖ (aₖ·x) + (q − Aᵀμ)·x ∈ Σ μₖ Bₖ + (q − Aᵀμ)·X`.
//! Evaluated in outward-rounded interval arithmetic, the infimum of the right-hand side is a
//! verified lower bound of `q·x`, whatever the quality of `μ`.
//! With `q = 0` the same enclosure must contain 0 for any feasible point: when it does not,
//! the rows have no solution in the box (a verified Farkas certificate).

use super::Relaxation;
use crate::kernel::interval::{point, Interval};

fn enclosure(rel: &Relaxation, b: &[Interval], q: &[(usize, f64)], mu: &[f64]) -> Interval {
    let mut residual: Vec<Interval> = vec![point(0.0); rel.n];
    for &(j, v) in q {
        residual[j] += point(v);
    }
    let mut total = point(0.0);
    for (row, &m) in rel.rows.iter().zip(mu) {
        if m == 0.0 || !m.is_finite() {
            continue;
        }
        let m = point(m);
        total += m * row.bounds;
        for &(j, a) in &row.coefs {
            residual[j] -= m * point(a);
        }
    }
    residual.iter().zip(b).fold(total, |acc, (r, x)| acc + *r * *x)
}

/// A verified lower bound of `q·x` over the points of box `b` that satisfy every row, from the
/// multipliers `mu` (one per row). Returns `-∞` when nothing useful follows.
pub(crate) fn lower_bound(rel: &Relaxation, b: &[Interval], q: &[(usize, f64)], mu: &[f64]) -> f64 {
    let e = enclosure(rel, b, q, mu);
    if e.is_empty() {
        f64::NEG_INFINITY
    } else {
        e.inf()
    }
}

/// True when the multipliers `mu` prove that no point of `b` satisfies every row.
pub(crate) fn certified_infeasible(rel: &Relaxation, b: &[Interval], mu: &[f64]) -> bool {
    let e = enclosure(rel, b, &[], mu);
    !e.is_empty() && !e.contains(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use crate::kernel::lp::{Row, Sides};

    fn row(coefs: Vec<(usize, f64)>, lo: f64, hi: f64) -> Row {
        Row { coefs, bounds: interval(lo, hi), sides: Sides::Both }
    }

    #[test]
    fn any_multipliers_give_a_valid_bound() {
        // x + y = 1 on [0,1]², minimise x: true minimum 0.
        let rel = Relaxation { n: 2, rows: vec![row(vec![(0, 1.0), (1, 1.0)], 1.0, 1.0)] };
        let b = [interval(0.0, 1.0), interval(0.0, 1.0)];
        for mu in [-3.0, -1.0, 0.0, 0.3, 1.0, 2.5] {
            assert!(lower_bound(&rel, &b, &[(0, 1.0)], &[mu]) <= 0.0);
        }
        // The optimal multiplier (μ = 1, residual on y is −1·[0,1]) reaches it.
        assert_eq!(lower_bound(&rel, &b, &[(0, 1.0)], &[1.0]), 0.0);
    }

    #[test]
    fn farkas_certificate_is_checked_not_trusted() {
        // x + y = 3 on [0,1]²: infeasible; μ = 1 proves it, μ = 0 proves nothing.
        let rel = Relaxation { n: 2, rows: vec![row(vec![(0, 1.0), (1, 1.0)], 3.0, 3.0)] };
        let b = [interval(0.0, 1.0), interval(0.0, 1.0)];
        assert!(certified_infeasible(&rel, &b, &[1.0]));
        assert!(!certified_infeasible(&rel, &b, &[0.0]));
        // x + y = 1.5 is feasible: no multiplier may claim otherwise.
        let ok = Relaxation { n: 2, rows: vec![row(vec![(0, 1.0), (1, 1.0)], 1.5, 1.5)] };
        for mu in [-2.0, -0.5, 0.5, 7.0] {
            assert!(!certified_infeasible(&ok, &b, &[mu]));
        }
    }
}

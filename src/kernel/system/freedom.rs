//! How many degrees of freedom a system has: counted (unknowns minus rows), and measured at a
//! point of its solution set that Newton finds (unknowns minus the rank of the Jacobian there).
//!
//! The count alone misleads both ways: an overconstrained linkage (Bennett's) moves although it
//! has more rows than unknowns, and an architecturally singular platform has as many rows as
//! unknowns but moves (or is singular) at every assembly. A search over a k-dimensional
//! continuum at sigma needs on the order of sigma^-k boxes, so a user should hear k before the
//! run, not after a minute. Numerical (f64, coefficient midpoints): a diagnosis, never a proof;
//! the search's results do not depend on it.

use super::{EquationSystem, Monomial};
use nalgebra::{DMatrix, DVector};

/// What `freedom` found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Freedom {
    /// Variables not fixed by their domain (width > 0).
    pub unknowns: usize,
    /// Equations.
    pub rows: usize,
    /// At the point with the most freedoms among those Newton found, if it found one.
    pub at_point: Option<LocalFreedom>,
}

/// The Jacobian's rank at a solution point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalFreedom {
    /// Numerical rank of the Jacobian over the unknowns (singular values above 1e-7 of the
    /// largest).
    pub rank: usize,
    /// `unknowns − rank`: the dimension of the solution set there (if it is a manifold there).
    pub dof: usize,
    /// Largest residual at the point.
    pub residual: f64,
    /// Whether `rank` counts directions of a tiny singular value along which the solutions do
    /// not go on: an isolated root with a nearly singular Jacobian (roots close together).
    pub nearly_singular: bool,
}

impl Freedom {
    /// Unknowns minus rows (negative for an overconstrained count).
    pub fn counted(&self) -> i64 {
        self.unknowns as i64 - self.rows as i64
    }
}

/// Systems with more unknowns than this are counted only: an SVD per Newton step would cost more
/// than the diagnosis is worth (a chain of thousands of joints).
const LARGEST: usize = 240;

/// The work all Newton steps together may take, in multiply-adds of their SVDs (rows × unknowns
/// × the smaller of the two): about 50 ms. A small system gets every start; a large one fewer
/// steps, so the diagnosis never delays a run noticeably (and stays repeatable: no clock).
const BUDGET: f64 = 5e7;

/// Counts the freedoms of `system` and measures them at solution points: Gauss–Newton
/// (least-squares steps through the SVD) from `starts` pseudo-random points of the initial box
/// (seeded by `seed`, so a run is repeatable); of the points that converge inside the box, the
/// one with the most freedoms is reported.
pub fn freedom(system: &EquationSystem, starts: usize, seed: u64) -> Freedom {
    let free: Vec<usize> = (0..system.vars.len()).filter(|&i| system.vars[i].domain.wid() > 0.0).collect();
    let mut out = Freedom { unknowns: free.len(), rows: system.equations.len(), at_point: None };
    if free.is_empty() || free.len() > LARGEST || system.equations.is_empty() {
        return out;
    }
    let mut column = vec![usize::MAX; system.vars.len()];
    for (k, &i) in free.iter().enumerate() {
        column[i] = k;
    }
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let domains: Vec<(f64, f64)> = system.vars.iter().map(|v| (v.domain.inf(), v.domain.sup())).collect();
    let (m, n) = (system.equations.len() as f64, free.len() as f64);
    let step_cost = m * n * m.min(n);
    let mut spent = 0.0;
    for _ in 0..starts {
        if spent > BUDGET {
            break;
        }
        let mut x: Vec<f64> = domains.iter().map(|&(lo, hi)| if hi > lo { lo + (hi - lo) * uniform() } else { lo }).collect();
        let mut converged = false;
        for _ in 0..50 {
            spent += step_cost;
            if spent > BUDGET {
                break;
            }
            let (r, j) = residual_and_jacobian(system, &x, &column, free.len());
            if r.amax() < 1e-11 {
                converged = true;
                break;
            }
            let Some(step) = j.svd(true, true).solve(&(-&r), 1e-12).ok() else { break };
            for (k, &i) in free.iter().enumerate() {
                x[i] += step[k];
            }
            if x.iter().any(|v| !v.is_finite()) {
                break;
            }
        }
        let inside = x.iter().zip(&domains).all(|(v, &(lo, hi))| {
            let slack = 1e-9 * (1.0 + hi.abs().max(lo.abs()));
            lo - slack <= *v && *v <= hi + slack
        });
        if converged && inside {
            let (r, j) = residual_and_jacobian(system, &x, &column, free.len());
            let svd = j.clone().svd(false, true);
            let largest = svd.singular_values.max().max(1.0);
            let numerical_rank = svd.singular_values.iter().filter(|&&s| s > 1e-7 * largest).count();
            let mut rank = numerical_rank;
            // Where the count expects isolated points, a tiny singular value is a curve only if
            // the solutions go on along its direction; otherwise the point is an isolated root
            // with a nearly singular Jacobian (two assemblies close together).
            if let (true, Some(v_t)) = (j.nrows() >= j.ncols(), svd.v_t.as_ref()) {
                for (k, &sigma) in svd.singular_values.iter().enumerate() {
                    if sigma <= 1e-7 * largest && !extends_along(system, &x, &free, &column, &v_t.row(k).transpose()) {
                        rank += 1;
                    }
                }
                spent += 40.0 * step_cost;
            }
            let found = LocalFreedom { rank, dof: free.len() - rank, residual: r.amax(), nearly_singular: rank > numerical_rank };
            // A solution set may have components of several dimensions (isolated assemblies
            // beside a self-motion): the largest seen is what the search will have to cover.
            // Likewise a nearly singular point among regular ones: the user hears of it.
            if out.at_point.is_none_or(|best| (found.dof, found.nearly_singular) > (best.dof, best.nearly_singular)) {
                out.at_point = Some(found);
            }
        }
    }
    out
}

/// Length of the step along a near-null direction in `extends_along`: far beyond the distance
/// at which two isolated roots with a nearly singular Jacobian could lie (their least-squares
/// residual there grows with its square), small against a linkage's dimensions.
const TANGENT_STEP: f64 = 1e-3;

/// Whether the solution set through `x` goes on along the unit direction `v` (over the free
/// variables): Gauss–Newton restricted to the hyperplane through `x + h·v` orthogonal to `v`
/// converges to a solution there. On a curve with tangent `v` it does; at an isolated root
/// whose Jacobian is nearly singular along `v` the residual there stays of order `h²`.
fn extends_along(system: &EquationSystem, x: &[f64], free: &[usize], column: &[usize], v: &DVector<f64>) -> bool {
    let n = free.len();
    let mut y = x.to_vec();
    for (k, &i) in free.iter().enumerate() {
        y[i] += TANGENT_STEP * v[k];
    }
    let across = DMatrix::identity(n, n) - v * v.transpose();
    for _ in 0..20 {
        let (r, j) = residual_and_jacobian(system, &y, column, n);
        if r.amax() < 1e-11 {
            return true;
        }
        let Some(step) = (j * &across).svd(true, true).solve(&(-&r), 1e-12).ok() else { return false };
        let step = &across * step;
        for (k, &i) in free.iter().enumerate() {
            y[i] += step[k];
        }
        if y.iter().any(|v| !v.is_finite()) {
            return false;
        }
    }
    false
}

/// Residuals (coefficient midpoints) and the Jacobian over the free variables at `x`.
fn residual_and_jacobian(system: &EquationSystem, x: &[f64], column: &[usize], n: usize) -> (DVector<f64>, DMatrix<f64>) {
    let m = system.equations.len();
    let mut r = DVector::zeros(m);
    let mut j = DMatrix::zeros(m, n);
    for (row, e) in system.equations.iter().enumerate() {
        r[row] = e.residual(x);
        let mut add = |var: usize, d: f64| {
            if column[var] != usize::MAX {
                j[(row, column[var])] += d;
            }
        };
        for t in &e.terms {
            let c = t.coef.mid();
            match t.mono {
                Monomial::Linear(a) => add(a, c),
                Monomial::Square(a) => add(a, 2.0 * c * x[a]),
                Monomial::Product(a, b) => {
                    add(a, c * x[b]);
                    add(b, c * x[a]);
                }
            }
        }
    }
    (r, j)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::{interval, point};
    use crate::kernel::system::{Equation, Term, VarRole};

    fn circle_system(extra_row: bool) -> EquationSystem {
        let mut s = EquationSystem::default();
        let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
        s.add(Equation::circle(x, y));
        if extra_row {
            s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }], point(-0.6)));
        }
        s
    }

    #[test]
    fn a_circle_has_one_freedom_and_a_point_on_it_none() {
        let f = freedom(&circle_system(false), 8, 1);
        assert_eq!((f.unknowns, f.rows, f.counted()), (2, 1, 1));
        assert_eq!(f.at_point.map(|l| (l.rank, l.dof)), Some((1, 1)));
        let f = freedom(&circle_system(true), 8, 1);
        assert_eq!(f.counted(), 0);
        assert_eq!(f.at_point.map(|l| (l.rank, l.dof)), Some((2, 0)));
    }

    #[test]
    fn a_repeated_row_is_counted_but_not_measured() {
        // Three rows, two unknowns, but the third row repeats the second: one point, rank 2.
        let mut s = circle_system(true);
        s.add(Equation::new(vec![Term { coef: point(2.0), mono: Monomial::Linear(0) }], point(-1.2)));
        let f = freedom(&s, 8, 1);
        assert_eq!(f.counted(), -1);
        assert_eq!(f.at_point.map(|l| (l.rank, l.dof)), Some((2, 0)));
    }

    #[test]
    fn two_roots_close_together_are_isolated_and_a_singular_curve_is_not() {
        // A circle written 1e6 times its usual size, and the line x = 1 − 1e-15: two roots 9e-8
        // apart, where the Jacobian's smallest singular value, about 4e-8, is far below the rank
        // tolerance (1e-7 of 2e6). The set does not go on along that direction: no freedom.
        let mut s = EquationSystem::default();
        let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
        let square = |v| Term { coef: point(1e6), mono: Monomial::Square(v) };
        s.add(Equation::new(vec![square(x), square(y)], point(-1e6)));
        s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }], point(-(1.0 - 1e-15))));
        let f = freedom(&s, 8, 1);
        assert_eq!(f.counted(), 0);
        assert_eq!(f.at_point.map(|l| (l.rank, l.dof)), Some((2, 0)));
        // The circle written twice: a curve where the count (two rows, two unknowns) expects
        // points, and its tangent is a freedom.
        let mut s = circle_system(false);
        s.add(Equation::circle(0, 1));
        let f = freedom(&s, 8, 1);
        assert_eq!(f.counted(), 0);
        assert_eq!(f.at_point.map(|l| (l.rank, l.dof)), Some((1, 1)));
    }

    #[test]
    fn no_solution_in_the_box_is_no_measurement() {
        let mut s = circle_system(false);
        s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(0) }], point(-3.0)));
        assert_eq!(freedom(&s, 8, 1).at_point, None);
    }
}

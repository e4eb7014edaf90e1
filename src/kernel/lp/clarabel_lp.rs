//! The clarabel adapter: rows and box to `Ax + s = b, s ∈ K`, one solver per call reused for all
//! objectives through `update_q`, answers turned into verified bounds by `safe_bound`.

use super::{safe_bound, LpCounters, LpOutcome, Relaxation, Sides};
use crate::kernel::interval::{interval, Interval};
use crate::kernel::system::VarId;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT, ZeroConeT,
};

/// Where a clarabel row came from: `(relaxation row, sign)`, or a box bound (`None`).
type Origin = Option<(usize, f64)>;

struct Assembled {
    rows_i: Vec<usize>,
    cols_j: Vec<usize>,
    vals: Vec<f64>,
    rhs: Vec<f64>,
    origin: Vec<Origin>,
    n_eq: usize,
}

impl Assembled {
    fn push(&mut self, coefs: &[(usize, f64)], sign: f64, rhs: f64, origin: Origin) {
        let r = self.rhs.len();
        for &(j, a) in coefs {
            self.rows_i.push(r);
            self.cols_j.push(j);
            self.vals.push(sign * a);
        }
        self.rhs.push(rhs);
        self.origin.push(origin);
    }
}

fn assemble(rel: &Relaxation, b: &[Interval]) -> Assembled {
    let mut a = Assembled { rows_i: vec![], cols_j: vec![], vals: vec![], rhs: vec![], origin: vec![], n_eq: 0 };
    for (k, row) in rel.rows.iter().enumerate() {
        if row.sides == Sides::Equal {
            a.push(&row.coefs, 1.0, row.bounds.mid(), Some((k, 1.0)));
        }
    }
    a.n_eq = a.rhs.len();
    for (k, row) in rel.rows.iter().enumerate() {
        let (lo, hi) = (row.bounds.inf(), row.bounds.sup());
        if matches!(row.sides, Sides::Upper | Sides::Both) {
            a.push(&row.coefs, 1.0, hi, Some((k, 1.0)));
        }
        if matches!(row.sides, Sides::Lower | Sides::Both) {
            a.push(&row.coefs, -1.0, -lo, Some((k, -1.0)));
        }
    }
    for (j, x) in b.iter().enumerate() {
        a.push(&[(j, 1.0)], 1.0, x.sup(), None);
        a.push(&[(j, 1.0)], -1.0, -x.inf(), None);
    }
    a
}

pub(super) fn bound(rel: &Relaxation, b: &[Interval], targets: &[VarId], counters: &mut LpCounters, stop: &dyn Fn() -> bool) -> LpOutcome {
    let n = rel.n;
    let asm = assemble(rel, b);
    let m = asm.rhs.len();
    let a_mat = CscMatrix::new_from_triplets(m, n, asm.rows_i.clone(), asm.cols_j.clone(), asm.vals.clone());
    let p_mat = CscMatrix::<f64>::zeros((n, n));
    let cones: Vec<SupportedConeT<f64>> = if asm.n_eq > 0 {
        vec![ZeroConeT(asm.n_eq), NonnegativeConeT(m - asm.n_eq)]
    } else {
        vec![NonnegativeConeT(m)]
    };
    // Presolve would drop rows and forbid `update_q`; loose tolerances are fine because the
    // answer is only a proposal that `safe_bound` verifies.
    let settings = match DefaultSettingsBuilder::default()
        .verbose(false)
        .presolve_enable(false)
        .max_iter(60)
        .tol_gap_abs(1e-7)
        .tol_gap_rel(1e-7)
        .build()
    {
        Ok(s) => s,
        Err(_) => return LpOutcome::Bounds(targets.iter().map(|&t| b[t]).collect()),
    };
    let mut q = vec![0.0; n];
    let mut solver = match DefaultSolver::new(&p_mat, &q, &a_mat, &asm.rhs, &cones, settings) {
        Ok(s) => s,
        Err(_) => return LpOutcome::Bounds(targets.iter().map(|&t| b[t]).collect()),
    };

    let mut mu = vec![0.0; rel.rows.len()];
    let mut current: Vec<Interval> = b.to_vec();
    let mut result = Vec::with_capacity(targets.len());
    for &t in targets {
        for sign in [1.0, -1.0] {
            if stop() {
                break;
            }
            q.iter_mut().for_each(|v| *v = 0.0);
            q[t] = sign;
            if solver.update_q(&q).is_err() {
                counters.unverified += 1;
                continue;
            }
            solver.solve();
            counters.solved += 1;
            let sol = &solver.solution;
            multipliers(&asm.origin, &sol.z, &mut mu);
            match sol.status {
                SolverStatus::Solved | SolverStatus::AlmostSolved => {
                    let lb = safe_bound::lower_bound(rel, &current, &[(t, sign)], &mu);
                    let x = current[t];
                    let narrowed = if sign > 0.0 {
                        interval(lb.max(x.inf()), x.sup())
                    } else {
                        interval(x.inf(), (-lb).min(x.sup()))
                    };
                    if narrowed.is_empty() {
                        return LpOutcome::Infeasible;
                    }
                    if narrowed == x {
                        counters.unverified += u64::from(lb == f64::NEG_INFINITY);
                    }
                    current[t] = narrowed;
                }
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                    if safe_bound::certified_infeasible(rel, &current, &mu) {
                        return LpOutcome::Infeasible;
                    }
                    counters.unverified += 1;
                }
                _ => counters.unverified += 1,
            }
        }
        result.push(current[t]);
    }
    LpOutcome::Bounds(result)
}

/// Folds clarabel's duals back onto relaxation rows.
///
/// Clarabel's optimality condition for an LP is `q + Aᵀz = 0`, so the multiplier of a row that
/// entered with sign `s` is `−s·z`; box rows are left out and absorbed by the residual term of
/// the safe bound.
fn multipliers(origin: &[Origin], z: &[f64], mu: &mut [f64]) {
    mu.iter_mut().for_each(|v| *v = 0.0);
    for (o, &zr) in origin.iter().zip(z) {
        if let Some((k, s)) = o {
            mu[*k] += -s * zr;
        }
    }
}

//! Linear relaxations and their verified bounds: the only importer of `clarabel`.
//!
//! A `Relaxation` is a set of rows `a·x ∈ [lo, hi]`, each valid for every solution in the box it
//! was built for. `Relaxation::bound` minimises and maximises variables over the rows and the
//! box with clarabel, then turns each floating-point answer into a *verified* bound with the
//! Neumaier–Shcherbina argument (`safe_bound`): the LP solver only proposes multipliers, and
//! interval arithmetic proves what they imply. A wrong or inaccurate LP answer can therefore only
//! weaken a bound, never cut a solution.
//!
//! References: A. Neumaier, O. Shcherbina, "Safe bounds in linear and mixed-integer linear
//! programming", Math. Programming 99 (2004); CuikSuite `simplex.h`.

mod clarabel_lp;
mod safe_bound;
mod simplex;

use crate::kernel::interval::Interval;
use crate::kernel::system::VarId;


/// One linear row `Σ coef·x ∈ bounds`, valid for every solution in the current box.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    /// Sparse coefficients (exact floats: the row *is* this linear form).
    pub coefs: Vec<(VarId, f64)>,
    /// Enclosure of the row's value over all solutions in the box; both ends finite.
    pub bounds: Interval,
    /// Which side(s) the LP should enforce: the other side only serves the safe bound.
    pub sides: Sides,
}

/// The sides of a row handed to the LP solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sides {
    /// `lo = hi`: an equality.
    Equal,
    /// Only `a·x ≤ hi`.
    Upper,
    /// Only `a·x ≥ lo`.
    Lower,
    /// Both `lo ≤ a·x ≤ hi`.
    Both,
}

/// Rows over `n` variables.
#[derive(Clone, Debug, Default)]
pub(crate) struct Relaxation {
    /// Number of variables (the box dimension).
    pub n: usize,
    /// The rows.
    pub rows: Vec<Row>,
}

/// What bounding a set of variables proved.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum LpOutcome {
    /// No point of the box satisfies the rows: proven by a verified certificate or bound.
    Infeasible,
    /// Verified enclosures for the requested variables, in request order (each within the box).
    Bounds(Vec<Interval>),
}

/// The LP solver that proposes multipliers to `safe_bound` (soundness never depends on it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LpBackend {
    /// The dense bounded-variable simplex of this module, warm-started across objectives.
    #[default]
    Simplex,
    /// The clarabel interior-point solver.
    Clarabel,
}

/// Counters for statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LpCounters {
    /// Linear programs solved.
    pub solved: u64,
    /// LP answers that could not be turned into a useful verified bound.
    pub unverified: u64,
}

impl Relaxation {
    /// Verified bounds of each variable in `targets` over the rows and the box `b`, from the
    /// multipliers `backend` proposes.
    ///
    /// Inclusion: every `x ∈ b` satisfying all rows has `x[targets[k]] ∈ result[k]`, for every
    /// backend.
    ///
    /// `stop` is asked before each LP; once it says yes, the remaining bounds are left as they
    /// are (one LP per side of each target: a large system's relaxation can take minutes).
    pub(crate) fn bound_with(
        &self,
        backend: LpBackend,
        b: &[Interval],
        targets: &[VarId],
        counters: &mut LpCounters,
        stop: &dyn Fn() -> bool,
    ) -> LpOutcome {
        match backend {
            LpBackend::Simplex => simplex::bound(self, b, targets, counters, stop),
            LpBackend::Clarabel => clarabel_lp::bound(self, b, targets, counters, stop),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;

    #[test]
    fn both_backends_bound_a_segment_and_prove_infeasibility() {
        // x + y = 1, x − y ∈ [0, 0.5] on [0,1]²: x ∈ [0.5, 0.75], y ∈ [0.25, 0.5].
        let rel = Relaxation {
            n: 2,
            rows: vec![
                Row { coefs: vec![(0, 1.0), (1, 1.0)], bounds: interval(1.0, 1.0), sides: Sides::Equal },
                Row { coefs: vec![(0, 1.0), (1, -1.0)], bounds: interval(0.0, 0.5), sides: Sides::Both },
            ],
        };
        for backend in [LpBackend::Simplex, LpBackend::Clarabel] {
            let b = [interval(0.0, 1.0), interval(0.0, 1.0)];
            let mut c = LpCounters::default();
            match rel.bound_with(backend, &b, &[0, 1], &mut c, &|| false) {
                LpOutcome::Bounds(v) => {
                    assert!(v[0].inf() > 0.49 && v[0].inf() <= 0.5 && v[0].sup() >= 0.75 && v[0].sup() < 0.76, "{backend:?}");
                    assert!(v[1].inf() > 0.24 && v[1].inf() <= 0.25 && v[1].sup() >= 0.5 && v[1].sup() < 0.51, "{backend:?}");
                }
                other => panic!("{backend:?}: expected bounds, got {other:?}"),
            }
            assert_eq!(c, LpCounters { solved: 4, unverified: 0 }, "{backend:?}");
            let small = [interval(0.0, 0.2), interval(0.0, 0.2)];
            assert_eq!(rel.bound_with(backend, &small, &[0, 1], &mut c, &|| false), LpOutcome::Infeasible, "{backend:?}");
        }
    }
}

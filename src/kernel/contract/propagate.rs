//! Equation-wise interval constraint propagation (HC4-style projection of every term).
//!
//! For `constant + Σ cₖ mₖ ∋ 0`, each term satisfies `cₖ mₖ ∈ −(constant + Σ_{j≠k} cⱼ mⱼ)`;
//! dividing by `cₖ` and inverting the monomial narrows its variables.
//! Every step uses inari's outward-rounded arithmetic, so no solution is ever removed.
//! Cheap, so the driver runs it before the LP shrink.

use super::{Contraction, Contractor};
use crate::kernel::interval::{interval, Interval, IntervalBox};
use crate::kernel::system::{Equation, EquationSystem, Monomial};

/// Propagates every equation in turn, sweeping until a sweep narrows no component by more than
/// `min_gain` of its width (or `max_sweeps` sweeps ran).
pub struct Propagation<'a> {
    system: &'a EquationSystem,
    /// Relative width reduction below which another sweep is not worth it.
    pub min_gain: f64,
    /// Upper bound on sweeps per call.
    pub max_sweeps: usize,
    partial: Vec<Interval>,
}

impl<'a> Propagation<'a> {
    /// A propagator over all equations of `system`.
    pub fn new(system: &'a EquationSystem) -> Self {
        Self { system, min_gain: 0.01, max_sweeps: 20, partial: Vec::new() }
    }
}

impl Contractor for Propagation<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        let mut outcome = Contraction::Unchanged;
        for _ in 0..self.max_sweeps {
            let before: Vec<f64> = b.dims.iter().map(|d| d.wid()).collect();
            for e in &self.system.equations {
                if !project(e, &mut b.dims, &mut self.partial) {
                    return Contraction::Empty;
                }
            }
            let mut best_gain: f64 = 0.0;
            for (d, w0) in b.dims.iter().zip(&before) {
                if *w0 > 0.0 {
                    best_gain = best_gain.max(1.0 - d.wid() / w0);
                }
            }
            if best_gain > 0.0 {
                outcome = Contraction::Reduced;
            }
            if best_gain < self.min_gain {
                break;
            }
        }
        outcome
    }

    fn name(&self) -> &'static str {
        "propagation"
    }
}

/// Narrows `b` by one equation; returns false when the equation is proven unsatisfiable in `b`.
///
/// `partial` is scratch space for suffix sums, kept by the caller to avoid allocation.
pub(crate) fn project(e: &Equation, b: &mut [Interval], partial: &mut Vec<Interval>) -> bool {
    let n = e.terms.len();
    // suffix[k] = Σ_{j≥k} cⱼ mⱼ over the box as it is now.
    partial.clear();
    partial.resize(n + 1, interval(0.0, 0.0));
    for k in (0..n).rev() {
        let t = &e.terms[k];
        partial[k] = partial[k + 1] + t.coef * t.mono.eval(b);
    }
    if !(e.constant + partial[0]).contains(0.0) {
        return false;
    }
    // prefix = constant + Σ_{j<k} cⱼ mⱼ, recomputed from narrowed components as we go.
    let mut prefix = e.constant;
    for k in 0..n {
        let t = e.terms[k];
        let others = prefix + partial[k + 1];
        if !t.coef.contains(0.0) {
            let target = -others / t.coef;
            if !narrow_monomial(t.mono, target, b) {
                return false;
            }
        }
        prefix += t.coef * t.mono.eval(b);
    }
    true
}

/// Narrows the variables of `mono` to values where `mono ∈ target`.
fn narrow_monomial(mono: Monomial, target: Interval, b: &mut [Interval]) -> bool {
    match mono {
        Monomial::Linear(x) => {
            b[x] = b[x].intersection(target);
            !b[x].is_empty()
        }
        Monomial::Square(x) => {
            let sq = target.intersection(interval(0.0, f64::INFINITY));
            if sq.is_empty() {
                return false;
            }
            let r = sq.sqrt();
            let pos = b[x].intersection(r);
            let neg = b[x].intersection(-r);
            b[x] = pos.convex_hull(neg);
            !b[x].is_empty()
        }
        Monomial::Product(x, y) => {
            if !b[y].contains(0.0) {
                b[x] = b[x].intersection(target / b[y]);
                if b[x].is_empty() {
                    return false;
                }
            }
            if !b[x].contains(0.0) {
                b[y] = b[y].intersection(target / b[x]);
                if b[y].is_empty() {
                    return false;
                }
            }
            true
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::point;
    use crate::kernel::system::{Term, VarRole};
    use proptest::prelude::*;

    fn circle_and_line() -> EquationSystem {
        // x² + y² = 1 and x + y = 1.2
        let mut s = EquationSystem::default();
        let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
        s.add(Equation::circle(x, y));
        s.add(Equation::new(
            vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }, Term { coef: point(1.0), mono: Monomial::Linear(y) }],
            point(-1.2),
        ));
        s
    }

    #[test]
    fn narrows_and_detects_emptiness() {
        let s = circle_and_line();
        let mut p = Propagation::new(&s);
        let mut b = s.initial_box();
        assert_eq!(p.contract(&mut b), Contraction::Reduced);
        assert!(b.dims[0].inf() >= 0.2 - 1e-12);
        let mut far = IntervalBox::new(vec![interval(-1.0, -0.5), interval(-1.0, -0.5)]);
        assert_eq!(p.contract(&mut far), Contraction::Empty);
    }

    proptest! {
        // Soundness: the two true solutions x = 0.6 ± √0.56/2 survive any box containing them.
        #[test]
        fn never_removes_a_true_solution(lo0 in -1.0f64..0.0, lo1 in -1.0f64..0.0, hi0 in 0.0f64..1.0, hi1 in 0.0f64..1.0, which in 0usize..2) {
            let s = circle_and_line();
            let d = (2.0f64 - 1.44).sqrt() / 2.0; // (x - y)/2 from x+y=1.2, x²+y²=1
            let (x, y) = if which == 0 { (0.6 + d, 0.6 - d) } else { (0.6 - d, 0.6 + d) };
            // Margins keep the real solution (within an ulp of the float one) inside the box.
            let m = 1e-9;
            let mut b = IntervalBox::new(vec![interval(lo0.min(x - m), hi0.max(x + m)), interval(lo1.min(y - m), hi1.max(y + m))]);
            let mut p = Propagation::new(&s);
            prop_assert_ne!(p.contract(&mut b), Contraction::Empty);
            prop_assert!(b.dims[0].inf() <= x + 1e-12 && b.dims[0].sup() >= x - 1e-12);
            prop_assert!(b.dims[1].inf() <= y + 1e-12 && b.dims[1].sup() >= y - 1e-12);
        }
    }
}

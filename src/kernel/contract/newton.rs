//! Interval Newton for square `EquationSystem`s: quadratic convergence near regular roots, and a
//! certificate that a box holds exactly one solution.
//!
//! A thin adapter: it evaluates `f(c)` at the midpoint `c` and an enclosure `J(X)` of the
//! Jacobian over `X` (inari, outward rounded), and hands them to the crate's one Krawczyk
//! operator (`contract::krawczyk::step`, which owns the operator, its rounding and its
//! references) and to its ε-inflation (`krawczyk::inflate`).

use super::krawczyk::{self, Inflation, Step};
use super::{Contraction, Contractor};
use crate::kernel::interval::{point, Interval, IntervalBox};
use crate::kernel::system::{EquationSystem, Monomial, VarId};
use nalgebra::{DMatrix, DVector};
use std::cmp::Ordering;

/// Krawczyk contraction, run only on boxes no wider than `max_width` in the primaries.
pub struct Newton<'a> {
    system: &'a EquationSystem,
    primaries: Vec<VarId>,
    /// Boxes wider than this (in any primary) are left alone: far from a root the
    /// linearisation is too loose to pay for itself.
    pub max_width: f64,
    /// Per variable, the unit `max_width` is read in (empty: 1 for every variable).
    units: Vec<f64>,
}

impl<'a> Newton<'a> {
    /// `None` unless the system is square (as many equations as variables).
    pub fn new(system: &'a EquationSystem, max_width: f64) -> Option<Self> {
        (system.equations.len() == system.vars.len()).then(|| Self { system, primaries: system.primaries(), max_width, units: Vec::new() })
    }

    /// Reads `max_width` per variable in `units` (one per variable of the system; see
    /// `search::width_units`): a primary is narrow enough when its width is at most
    /// `max_width · units[i]`.
    pub fn with_units(mut self, units: Vec<f64>) -> Self {
        self.units = units;
        self
    }

    fn jacobian(&self, x: &[Interval]) -> DMatrix<Interval> {
        let n = x.len();
        let mut j = DMatrix::from_element(n, n, point(0.0));
        for (k, e) in self.system.equations.iter().enumerate() {
            for t in &e.terms {
                match t.mono {
                    Monomial::Linear(v) => j[(k, v)] += t.coef,
                    Monomial::Square(v) => j[(k, v)] += t.coef * point(2.0) * x[v],
                    Monomial::Product(a, b) => {
                        j[(k, a)] += t.coef * x[b];
                        j[(k, b)] += t.coef * x[a];
                    }
                }
            }
        }
        j
    }

    /// The shared Krawczyk step on `x`.
    fn step(&self, x: &[Interval]) -> Step<Vec<Interval>> {
        let (b, c, fc, j) = self.linearise(x);
        krawczyk::step(&b, &c, &fc, &j).map(|k| k.data.into())
    }

    /// Krawczyk's image of `x` (for ε-inflation).
    fn image(&self, x: &[Interval]) -> Option<Vec<Interval>> {
        let (b, c, fc, j) = self.linearise(x);
        krawczyk::image(&b, &c, &fc, &j).map(|k| k.data.into())
    }

    /// The box, its midpoint `c`, `f(c)` and `J(x)`, as the Krawczyk step takes them.
    fn linearise(&self, x: &[Interval]) -> (DVector<Interval>, DVector<f64>, DVector<Interval>, DMatrix<Interval>) {
        let c: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let cpoint: Vec<Interval> = c.iter().map(|&v| point(v)).collect();
        let fc = DVector::from_iterator(x.len(), self.system.equations.iter().map(|e| e.eval(&cpoint)));
        (DVector::from_column_slice(x), DVector::from_vec(c), fc, self.jacobian(x))
    }
}

impl Contractor for Newton<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        // A NaN width (never in a valid box) counts as too wide.
        let narrow = |i: &VarId| matches!(b.dims[*i].wid().partial_cmp(&(self.max_width * self.units.get(*i).copied().unwrap_or(1.0))), Some(Ordering::Less | Ordering::Equal));
        if !self.primaries.iter().all(narrow) {
            return Contraction::Unchanged;
        }
        match self.step(&b.dims) {
            Step::Failed => Contraction::Unchanged,
            Step::Empty => Contraction::Empty,
            Step::Unique(k) => {
                b.dims = k;
                Contraction::Proven
            }
            Step::Contracted(k) if k == b.dims => Contraction::Unchanged,
            Step::Contracted(k) => {
                b.dims = k;
                Contraction::Reduced
            }
        }
    }

    fn name(&self) -> &'static str {
        "krawczyk"
    }

    /// The shared ε-inflation (`krawczyk::inflate`) from `b`: four rounds, each component grown by
    /// 5% of its width, 0.5% of the widest primary's width and a few ulps, so certification
    /// does not depend on where a link's rest pose is (see `inflate` on the widest term).
    fn certify(&mut self, b: &IntervalBox) -> Option<IntervalBox> {
        let policy = Inflation { rounds: 4, own: 0.05, widest: 0.005, widest_of: &self.primaries, absolute: 0.0, ulps: 4.0 };
        let dims = krawczyk::inflate(&b.dims, &policy, |x| self.image(x))?;
        Some(IntervalBox { dims, level: b.level })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use crate::kernel::system::{Equation, Term, VarRole};

    #[test]
    fn certifies_a_regular_root_and_empties_a_rootless_box() {
        // x² + y² = 1, x − y = 0
        let mut s = EquationSystem::default();
        let x = s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        let y = s.add_var("y", VarRole::Primary, interval(-1.0, 1.0));
        s.add(Equation::circle(x, y));
        s.add(Equation::new(vec![Term { coef: point(1.0), mono: Monomial::Linear(x) }, Term { coef: point(-1.0), mono: Monomial::Linear(y) }], point(0.0)));
        let mut n = Newton::new(&s, 1.0).expect("square");
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let mut near = IntervalBox::new(vec![interval(0.6, 0.8), interval(0.65, 0.75)]);
        let mut last = Contraction::Unchanged;
        for _ in 0..5 {
            last = n.contract(&mut near);
        }
        assert_eq!(last, Contraction::Proven);
        assert!(near.contains(&[h, h]) && near.width(0) < 1e-12);
        let mut far = IntervalBox::new(vec![interval(0.1, 0.2), interval(0.1, 0.2)]);
        assert_eq!(n.contract(&mut far), Contraction::Empty);
    }
}

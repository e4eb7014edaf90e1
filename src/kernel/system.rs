//! Polynomial systems over named variables: the contract between problem builders and solvers.
//!
//! An `Equation` is `constant + Σ coef·monomial ∋ 0`, with monomials of degree at most two and
//! coefficients given as intervals (point intervals for exact models, wider ones for uncertain
//! geometry).
//! The planar formulation of Porta, Ros and Thomas (2006) needs exactly three shapes, which
//! `EquationKind` recognises once at construction so the LP relaxation can treat them specially:
//! linear equations, circles `x² + y² = 1`, and bilinear definitions `z = x·y`.
//! This module does no IO and knows nothing of mechanisms.

use crate::kernel::interval::{point, Interval, IntervalBox};
use thiserror::Error;

mod freedom;
pub(crate) mod multilinear;

pub use freedom::{freedom, Freedom, LocalFreedom};
pub use multilinear::Poly;

/// Index of a variable in its system (and of its component in an `IntervalBox`).
pub type VarId = usize;

/// Whether the solver branches on a variable and measures box size on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VarRole {
    /// Independent unknown: bisected, and counted in the box size compared with sigma.
    Primary,
    /// Determined by the primaries through the equations (a traced point, a slider product):
    /// narrowed by contractors, never bisected, not counted in the size.
    Derived,
}

/// A named unknown with its initial domain.
#[derive(Clone, Debug)]
pub struct Variable {
    /// Name used in reports, e.g. `c_link2` or `x_trace0`.
    pub name: String,
    /// Primary or derived.
    pub role: VarRole,
    /// The initial search interval.
    pub domain: Interval,
}

/// A monomial of degree one or two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Monomial {
    /// `x`
    Linear(VarId),
    /// `x²`
    Square(VarId),
    /// `x·y` with `x != y`
    Product(VarId, VarId),
}

impl Monomial {
    /// Interval enclosure of the monomial over `b` (outward rounded; `x²` uses `sqr`, which is
    /// tighter than `x·x`).
    pub fn eval(&self, b: &[Interval]) -> Interval {
        match *self {
            Monomial::Linear(x) => b[x],
            Monomial::Square(x) => b[x].sqr(),
            Monomial::Product(x, y) => b[x] * b[y],
        }
    }

    /// Value at a point.
    pub fn eval_point(&self, x: &[f64]) -> f64 {
        match *self {
            Monomial::Linear(i) => x[i],
            Monomial::Square(i) => x[i] * x[i],
            Monomial::Product(i, j) => x[i] * x[j],
        }
    }

    fn vars(&self) -> [Option<VarId>; 2] {
        match *self {
            Monomial::Linear(x) | Monomial::Square(x) => [Some(x), None],
            Monomial::Product(x, y) => [Some(x), Some(y)],
        }
    }
}

/// `coef · monomial`
#[derive(Clone, Copy, Debug)]
pub struct Term {
    /// Coefficient, as an interval.
    pub coef: Interval,
    /// The monomial it multiplies.
    pub mono: Monomial,
}

/// The shape of an equation, recognised once at construction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EquationKind {
    /// Only degree-one terms.
    Linear,
    /// `x² + y² − 1 = 0`.
    Circle {
        /// cosine-like variable
        x: VarId,
        /// sine-like variable
        y: VarId,
    },
    /// `z − x·y = 0`.
    Bilinear {
        /// the product variable
        z: VarId,
        /// first factor
        x: VarId,
        /// second factor
        y: VarId,
    },
    /// Any other quadratic: used by propagation only.
    Quadratic,
}

/// `constant + Σ terms ∋ 0`.
#[derive(Clone, Debug)]
pub struct Equation {
    /// The terms; a monomial may appear more than once.
    pub terms: Vec<Term>,
    /// The constant part.
    pub constant: Interval,
    /// The recognised shape.
    pub kind: EquationKind,
}

impl Equation {
    /// Builds an equation and recognises its shape.
    pub fn new(terms: Vec<Term>, constant: Interval) -> Self {
        let kind = classify(&terms, constant);
        Self { terms, constant, kind }
    }

    /// `x² + y² − 1 = 0`
    pub fn circle(x: VarId, y: VarId) -> Self {
        let one = point(1.0);
        Self::new(
            vec![Term { coef: one, mono: Monomial::Square(x) }, Term { coef: one, mono: Monomial::Square(y) }],
            point(-1.0),
        )
    }

    /// `z − x·y = 0`
    pub fn bilinear(z: VarId, x: VarId, y: VarId) -> Self {
        Self::new(
            vec![
                Term { coef: point(1.0), mono: Monomial::Linear(z) },
                Term { coef: point(-1.0), mono: Monomial::Product(x, y) },
            ],
            point(0.0),
        )
    }

    /// Interval enclosure of the left-hand side over the box.
    pub fn eval(&self, b: &[Interval]) -> Interval {
        self.terms.iter().fold(self.constant, |acc, t| acc + t.coef * t.mono.eval(b))
    }

    /// Residual at a point, with coefficient midpoints (for tests and reports, not for proofs).
    pub fn residual(&self, x: &[f64]) -> f64 {
        self.terms.iter().fold(self.constant.mid(), |acc, t| acc + t.coef.mid() * t.mono.eval_point(x))
    }

    /// Every variable the equation mentions (with repetitions).
    pub fn vars(&self) -> impl Iterator<Item = VarId> + '_ {
        self.terms.iter().flat_map(|t| t.mono.vars()).flatten()
    }
}

fn classify(terms: &[Term], constant: Interval) -> EquationKind {
    let is_point = |i: Interval, v: f64| i.inf() == v && i.sup() == v;
    if terms.iter().all(|t| matches!(t.mono, Monomial::Linear(_))) {
        return EquationKind::Linear;
    }
    match terms {
        [Term { coef: a, mono: Monomial::Square(x) }, Term { coef: b, mono: Monomial::Square(y) }]
            if x != y && is_point(*a, 1.0) && is_point(*b, 1.0) && is_point(constant, -1.0) =>
        {
            EquationKind::Circle { x: *x, y: *y }
        }
        [Term { coef: a, mono: Monomial::Linear(z) }, Term { coef: b, mono: Monomial::Product(x, y) }]
            if is_point(*a, 1.0) && is_point(*b, -1.0) && is_point(constant, 0.0) && z != x && z != y =>
        {
            EquationKind::Bilinear { z: *z, x: *x, y: *y }
        }
        _ => EquationKind::Quadratic,
    }
}

/// What is wrong with a system handed to a solver.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SystemError {
    /// An equation names a variable the system does not have.
    #[error("equation {equation} refers to variable {var}, but the system has {count} variables")]
    UnknownVariable {
        /// index of the equation
        equation: usize,
        /// the bad id
        var: VarId,
        /// number of variables
        count: usize,
    },
    /// A coefficient or constant is empty or not finite.
    #[error("equation {equation} has an empty or non-finite coefficient")]
    BadCoefficient {
        /// index of the equation
        equation: usize,
    },
    /// A variable's domain is empty or unbounded.
    #[error("variable {name} has an empty or unbounded domain")]
    BadDomain {
        /// the variable
        name: String,
    },
}

/// Variables with domains, and the equations over them.
#[derive(Clone, Debug, Default)]
pub struct EquationSystem {
    /// The unknowns, indexed by `VarId`.
    pub vars: Vec<Variable>,
    /// The equations, all of which must hold.
    pub equations: Vec<Equation>,
}

impl EquationSystem {
    /// Adds a variable and returns its id.
    pub fn add_var(&mut self, name: impl Into<String>, role: VarRole, domain: Interval) -> VarId {
        self.vars.push(Variable { name: name.into(), role, domain });
        self.vars.len() - 1
    }

    /// Adds an equation.
    pub fn add(&mut self, e: Equation) {
        self.equations.push(e);
    }

    /// Ids of the primary variables.
    pub fn primaries(&self) -> Vec<VarId> {
        (0..self.vars.len()).filter(|&i| self.vars[i].role == VarRole::Primary).collect()
    }

    /// The box of all initial domains.
    pub fn initial_box(&self) -> IntervalBox {
        IntervalBox::new(self.vars.iter().map(|v| v.domain).collect())
    }

    /// Id of the variable named `name`.
    pub fn var(&self, name: &str) -> Option<VarId> {
        self.vars.iter().position(|v| v.name == name)
    }

    /// Checks ids, coefficients and domains once, so solvers can trust the system afterwards.
    pub fn validate(&self) -> Result<(), SystemError> {
        let count = self.vars.len();
        for v in &self.vars {
            if v.domain.is_empty() || !v.domain.inf().is_finite() || !v.domain.sup().is_finite() {
                return Err(SystemError::BadDomain { name: v.name.clone() });
            }
        }
        for (k, e) in self.equations.iter().enumerate() {
            if let Some(var) = e.vars().find(|&v| v >= count) {
                return Err(SystemError::UnknownVariable { equation: k, var, count });
            }
            let finite = |i: Interval| !i.is_empty() && i.inf().is_finite() && i.sup().is_finite();
            if !finite(e.constant) || !e.terms.iter().all(|t| finite(t.coef)) {
                return Err(SystemError::BadCoefficient { equation: k });
            }
        }
        Ok(())
    }

    /// Largest absolute residual at a point (coefficient midpoints): for tests and reports.
    pub fn max_residual(&self, x: &[f64]) -> f64 {
        self.equations.iter().map(|e| e.residual(x).abs()).fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;

    #[test]
    fn shapes_are_recognised() {
        assert_eq!(Equation::circle(0, 1).kind, EquationKind::Circle { x: 0, y: 1 });
        assert_eq!(Equation::bilinear(2, 0, 1).kind, EquationKind::Bilinear { z: 2, x: 0, y: 1 });
        let lin = Equation::new(vec![Term { coef: point(2.0), mono: Monomial::Linear(0) }], point(1.0));
        assert_eq!(lin.kind, EquationKind::Linear);
    }

    #[test]
    fn evaluation_encloses_point_values() {
        let e = Equation::circle(0, 1);
        let b = [interval(0.5, 0.7), interval(0.6, 0.9)];
        let v = e.eval(&b);
        for (x, y) in [(0.5, 0.6), (0.7, 0.9), (0.6, 0.8)] {
            assert!(v.contains(e.residual(&[x, y])));
        }
    }

    #[test]
    fn validation_names_the_problem() {
        let mut s = EquationSystem::default();
        s.add_var("x", VarRole::Primary, interval(-1.0, 1.0));
        s.add(Equation::circle(0, 3));
        assert_eq!(s.validate(), Err(SystemError::UnknownVariable { equation: 0, var: 3, count: 1 }));
    }
}

//! Sparse polynomials of any degree over the variables of an `EquationSystem`, with interval
//! coefficients: what the Cayley–Menger builders expand determinants into.
//!
//! `Poly` is symbolic (a sum of monomials with interval coefficients), built once by a problem
//! builder with `add`, `mul` and `scale`, and evaluated over boxes with outward rounding.
//! The name says what the solver of Porta et al. (2003) needs: a polynomial whose every variable
//! has exponent at most one is *multilinear* (`Poly::is_multilinear`), and for those the values on
//! a box lie in the convex hull of the values at its corners (Rikun 1997), which the trapezoid
//! clipping of `contract::TrapezoidClip` uses. Exponents up to two are allowed too, for the
//! formulation that keeps one variable per distance (Bernstein control points instead of corners).
//! This module does no IO and knows nothing of geometry.

use super::VarId;
use crate::kernel::interval::{point, Interval};
use std::collections::BTreeMap;

/// A monomial: `(variable, exponent)` pairs sorted by variable, every exponent at least one; the
/// empty monomial is the constant 1.
pub(crate) type Powers = Vec<(VarId, u8)>;

/// `Σ coef · monomial`, with interval coefficients.
///
/// Coefficients are enclosures: a product or sum of coefficients is computed with inari's
/// outward rounding, so the polynomial a builder expands encloses the exact one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Poly {
    terms: BTreeMap<Powers, Interval>,
}

impl Poly {
    /// The zero polynomial.
    pub fn zero() -> Self {
        Self::default()
    }

    /// The constant `c` (zero when `c` is exactly 0).
    pub fn constant(c: Interval) -> Self {
        let mut p = Self::zero();
        p.add_term(Vec::new(), c);
        p
    }

    /// The variable `v`.
    pub fn var(v: VarId) -> Self {
        let mut p = Self::zero();
        p.add_term(vec![(v, 1)], point(1.0));
        p
    }

    /// True when every coefficient is exactly zero (no term stored).
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    fn add_term(&mut self, mono: Powers, c: Interval) {
        let exact_zero = |i: Interval| i.inf() == 0.0 && i.sup() == 0.0;
        if exact_zero(c) {
            return;
        }
        let sum = self.terms.get(&mono).map_or(c, |&old| old + c);
        // Cancellation to an exact zero removes the term (a wider sum around zero stays).
        if exact_zero(sum) {
            self.terms.remove(&mono);
        } else {
            self.terms.insert(mono, sum);
        }
    }

    /// `self + other`
    pub fn add(&self, other: &Poly) -> Poly {
        let mut p = self.clone();
        for (m, c) in &other.terms {
            p.add_term(m.clone(), *c);
        }
        p
    }

    /// `c · self`
    pub fn scale(&self, c: Interval) -> Poly {
        let mut p = Poly::zero();
        for (m, k) in &self.terms {
            p.add_term(m.clone(), *k * c);
        }
        p
    }

    /// `self · other`
    pub fn mul(&self, other: &Poly) -> Poly {
        let mut p = Poly::zero();
        for (ma, ca) in &self.terms {
            for (mb, cb) in &other.terms {
                p.add_term(merge(ma, mb), *ca * *cb);
            }
        }
        p
    }

    /// The terms, monomials in a fixed (sorted) order.
    pub fn terms(&self) -> impl Iterator<Item = (&Powers, Interval)> + '_ {
        self.terms.iter().map(|(m, c)| (m, *c))
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// True for the zero polynomial.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The variables that occur, sorted and distinct.
    pub fn vars(&self) -> Vec<VarId> {
        let mut v: Vec<VarId> = self.terms.keys().flat_map(|m| m.iter().map(|&(x, _)| x)).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Highest exponent of `v` in any term.
    pub fn degree_in(&self, v: VarId) -> u8 {
        self.terms.keys().flat_map(|m| m.iter()).filter(|&&(x, _)| x == v).map(|&(_, e)| e).max().unwrap_or(0)
    }

    /// True when no variable has an exponent above one.
    pub fn is_multilinear(&self) -> bool {
        self.terms.keys().all(|m| m.iter().all(|&(_, e)| e <= 1))
    }

    /// Natural interval extension over the box `b` (outward rounded): every value the exact
    /// polynomial takes on `b` lies in the result.
    pub fn eval(&self, b: &[Interval]) -> Interval {
        self.terms.iter().fold(point(0.0), |acc, (m, c)| acc + *c * monomial(m, b))
    }

    /// Value at a point with coefficient midpoints: for tests and reports, not for proofs.
    pub fn eval_point(&self, x: &[f64]) -> f64 {
        self.terms.iter().map(|(m, c)| c.mid() * m.iter().map(|&(v, e)| x[v].powi(e as i32)).product::<f64>()).sum()
    }

    /// The same polynomial with every variable renamed by `map`.
    pub fn rename(&self, map: impl Fn(VarId) -> VarId) -> Poly {
        let mut p = Poly::zero();
        for (m, c) in &self.terms {
            let renamed: Powers = m.iter().map(|&(v, e)| (map(v), e)).collect();
            p.add_term(merge(&renamed, &[]), *c);
        }
        p
    }
}

/// Enclosure of `Π x_v^e` over `b`; squares use `sqr`, which is tighter than `x·x`.
pub(crate) fn monomial(m: &[(VarId, u8)], b: &[Interval]) -> Interval {
    m.iter().fold(point(1.0), |acc, &(v, e)| acc * power(b[v], e))
}

pub(crate) fn power(x: Interval, e: u8) -> Interval {
    match e {
        0 => point(1.0),
        1 => x,
        2 => x.sqr(),
        _ => {
            // Even powers are nonnegative; odd ones are monotone, so products of sqr and x are
            // sound (only a little wider than the tightest enclosure).
            let half = power(x, e / 2).sqr();
            if e % 2 == 1 {
                half * x
            } else {
                half
            }
        }
    }
}

/// Product of two monomials, sorted, exponents added.
fn merge(a: &[(VarId, u8)], b: &[(VarId, u8)]) -> Powers {
    let mut out: Powers = a.iter().chain(b).copied().collect();
    out.sort_unstable_by_key(|&(v, _)| v);
    let mut merged: Powers = Vec::with_capacity(out.len());
    for (v, e) in out {
        match merged.last_mut() {
            Some((w, f)) if *w == v => *f += e,
            _ => merged.push((v, e)),
        }
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use proptest::prelude::*;

    #[test]
    fn products_merge_exponents_and_cancellation_drops_terms() {
        let x = Poly::var(0);
        let y = Poly::var(1);
        let xy = x.mul(&y);
        assert!(xy.is_multilinear());
        let x2 = x.mul(&x);
        assert!(!x2.is_multilinear());
        assert_eq!(x2.degree_in(0), 2);
        let zero = xy.add(&y.mul(&x).scale(point(-1.0)));
        assert!(zero.is_zero());
        assert_eq!(x.add(&y).vars(), vec![0, 1]);
    }

    proptest! {
        // Inclusion: the value at any point of the box lies in the interval evaluation.
        #[test]
        fn evaluation_encloses_point_values(a in -3.0f64..3.0, w in 0.0f64..2.0, t in 0.0f64..=1.0, s in 0.0f64..=1.0) {
            // p = 1.5 x² y − 2 x y + 0.1 y² + 3
            let x = Poly::var(0);
            let y = Poly::var(1);
            let p = x.mul(&x).mul(&y).scale(point(1.5))
                .add(&x.mul(&y).scale(point(-2.0)))
                .add(&y.mul(&y).scale(point(0.1)))
                .add(&Poly::constant(point(3.0)));
            let b = [interval(a, a + w), interval(-a, -a + w)];
            let pt = [a + t * w, -a + s * w];
            let (v, e) = (p.eval(&b), p.eval_point(&pt));
            // The point value is itself rounded: allow a few ulps of slack.
            prop_assert!(v.inf() - 1e-9 <= e && e <= v.sup() + 1e-9);
        }
    }
}

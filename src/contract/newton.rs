//! Interval Newton (Krawczyk's operator) for square systems: quadratic convergence near regular
//! roots, and a certificate that a box holds exactly one solution.
//!
//! `K(X) = c − Y·f(c) + (I − Y·J(X))·(X − c)`, with `c` the midpoint, `J(X)` an interval
//! enclosure of the Jacobian over `X` and `Y` any real matrix (the inverse of `mid J`).
//! Every root in `X` lies in `K(X)`, so `X ∩ K(X)` loses none; `K(X) ⊂ int X` proves a unique
//! root in `X` (Krawczyk 1969; Moore 1977; Neumaier, *Interval Methods for Systems of
//! Equations*, 1990, §5.2). `Y` is computed in floating point: it needs no accuracy, only the
//! interval products that use it are rounded outward.

use super::{Contraction, Contractor};
use crate::interval::{interval, point, Interval, IntervalBox};
use crate::system::{EquationSystem, Monomial, VarId};
use nalgebra::DMatrix;

/// Krawczyk contraction, run only on boxes no wider than `max_width` in the primaries.
pub struct Newton<'a> {
    system: &'a EquationSystem,
    primaries: Vec<VarId>,
    /// Boxes wider than this (in any primary) are left alone: far from a root the
    /// linearisation is too loose to pay for itself.
    pub max_width: f64,
}

impl<'a> Newton<'a> {
    /// `None` unless the system is square (as many equations as variables).
    pub fn new(system: &'a EquationSystem, max_width: f64) -> Option<Self> {
        (system.equations.len() == system.vars.len()).then(|| Self { system, primaries: system.primaries(), max_width })
    }

    fn jacobian(&self, x: &[Interval]) -> Vec<Vec<Interval>> {
        let n = x.len();
        let mut j = vec![vec![point(0.0); n]; n];
        for (k, e) in self.system.equations.iter().enumerate() {
            for t in &e.terms {
                match t.mono {
                    Monomial::Linear(v) => j[k][v] = j[k][v] + t.coef,
                    Monomial::Square(v) => j[k][v] = j[k][v] + t.coef * point(2.0) * x[v],
                    Monomial::Product(a, b) => {
                        j[k][a] = j[k][a] + t.coef * x[b];
                        j[k][b] = j[k][b] + t.coef * x[a];
                    }
                }
            }
        }
        j
    }
}

impl Newton<'_> {
    /// Krawczyk's image `K(X)`, not yet intersected with `X`; `None` when `mid J(X)` cannot be
    /// inverted or the image is not finite.
    fn image(&self, x: &[Interval]) -> Option<Vec<Interval>> {
        let n = x.len();
        let c: Vec<f64> = x.iter().map(|d| d.mid()).collect();
        let cpoint: Vec<Interval> = c.iter().map(|&v| point(v)).collect();
        let fc: Vec<Interval> = self.system.equations.iter().map(|e| e.eval(&cpoint)).collect();
        let j = self.jacobian(x);
        let jm = DMatrix::from_fn(n, n, |r, s| j[r][s].mid());
        let y = jm.try_inverse()?;
        if !y.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut out = Vec::with_capacity(n);
        for r in 0..n {
            // K_r = c_r − Σ_s Y_rs f_s(c) + Σ_s (δ_rs − Σ_t Y_rt J_ts)(X_s − c_s)
            let mut k = point(c[r]);
            for s in 0..n {
                k = k - point(y[(r, s)]) * fc[s];
            }
            for s in 0..n {
                let mut m = if r == s { point(1.0) } else { point(0.0) };
                for t in 0..n {
                    m = m - point(y[(r, t)]) * j[t][s];
                }
                k = k + m * (x[s] - point(c[s]));
            }
            if k.is_empty() {
                return None;
            }
            out.push(k);
        }
        Some(out)
    }
}

impl Contractor for Newton<'_> {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        let x = &b.dims;
        if self.primaries.iter().any(|&i| !(x[i].wid() <= self.max_width)) {
            return Contraction::Unchanged;
        }
        let Some(k) = self.image(x) else { return Contraction::Unchanged };
        let mut outcome = Contraction::Unchanged;
        let mut unique = true;
        let mut next = x.clone();
        for (r, k) in k.into_iter().enumerate() {
            unique &= k.inf() > x[r].inf() && k.sup() < x[r].sup();
            let narrowed = x[r].intersection(k);
            if narrowed.is_empty() {
                return Contraction::Empty;
            }
            if narrowed != x[r] {
                outcome = Contraction::Reduced;
            }
            next[r] = narrowed;
        }
        b.dims = next;
        if unique {
            Contraction::Proven
        } else {
            outcome
        }
    }

    fn name(&self) -> &'static str {
        "krawczyk"
    }

    /// Epsilon-inflation (Rump 1983): a box that is already tight around a root rarely shows
    /// `K(X) ⊂ int X`, so try on `X` widened, then on the widened hull of `X` and `K(X)`, a few
    /// times. Every root of `b` stays in every trial box (each holds `b`, and `K` keeps the roots
    /// of its argument), so when `K(X') ⊂ int X'` the returned `K(X')` holds the one root of
    /// `X'` and every root of `b`.
    ///
    /// Inflating by a component's own radius is not enough: a component can be far narrower
    /// than the box (`c = cos φ` near φ = 0 is `w²/2` wide when `s` is `w` wide, and a box
    /// Newton has shrunk to a few ulps is narrower than its coefficients' uncertainty), while
    /// `K` of that component is as wide as the box's curvature or coefficients make it. So each
    /// component also gets 1% of the widest primary radius, and later rounds inflate `K`'s own
    /// hull: certification no longer depends on where a link's rest pose is.
    fn certify(&mut self, b: &IntervalBox) -> Option<IntervalBox> {
        let inflate = |dims: &mut Vec<Interval>, primaries: &[VarId]| {
            let widest = primaries.iter().map(|&i| dims[i].rad()).fold(0.0, f64::max);
            for d in dims.iter_mut() {
                let pad = 0.1 * d.rad() + 0.01 * widest + 4.0 * f64::EPSILON * d.mag().max(1.0);
                *d = interval(d.inf() - pad, d.sup() + pad);
            }
        };
        let mut x = b.dims.clone();
        inflate(&mut x, &self.primaries);
        for _ in 0..4 {
            let k = self.image(&x)?;
            if k.iter().zip(&x).all(|(k, x)| k.inf() > x.inf() && k.sup() < x.sup()) {
                return Some(IntervalBox { dims: k, level: b.level });
            }
            x = k.iter().zip(&b.dims).map(|(k, b)| k.convex_hull(*b)).collect();
            inflate(&mut x, &self.primaries);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::{Equation, Term, VarRole};

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

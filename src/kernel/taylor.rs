//! Forward-mode automatic differentiation over intervals, in two variables, to order 4.
//!
//! A `Taylor` holds interval enclosures, over a box, of the Taylor coefficients
//! `∂^{i+j} u / ∂θ₂^i ∂θ₃^j / (i! j!)` of a function `u` for `i + j ≤ order`.
//! Sums and products follow Leibniz's rule coefficient by coefficient, which holds at every
//! point of the box, so with inari's outward rounding the result encloses the true coefficients
//! of the sum or product at every point: value, gradient, Hessian (and third and fourth
//! derivatives) of any polynomial in jets are sound over the box.
//!
//! Only the two angles themselves go through sine and cosine (`Taylor::sin_cos`), whose
//! derivatives are again sines and cosines, so no composition rule beyond the product is needed.
//!
//! The coefficients use `crate::kernel::interval::fast::Iv`, a minimal interval type whose operations inline: each result is
//! the round-to-nearest floating-point result moved one ulp outward (`next_down`/`next_up`),
//! which contains the exact result because rounding to nearest errs by at most half an ulp.
//! inari's operations are not inlined across crates and dominated the run time; `Iv` is
//! slightly wider (one ulp per operation) and converts to and from `inari::Interval` at the API.

use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::trig;
use inari::Interval;

/// Highest order a `Taylor` can carry.
pub const MAX_ORDER: usize = 4;
const LEN: usize = (MAX_ORDER + 1) * (MAX_ORDER + 2) / 2;

/// Index of the coefficient of `θ₂^i θ₃^j` where `d = i + j`.
const fn index(d: usize, j: usize) -> usize {
    d * (d + 1) / 2 + j
}

/// A truncated Taylor expansion in (θ₂, θ₃) with interval coefficients; see the module doc.
#[derive(Clone, Copy, Debug)]
pub struct Taylor {
    c: [Iv; LEN],
    order: usize,
}

impl Taylor {
    /// The constant `v`, carried to `order`.
    pub fn constant(v: Interval, order: usize) -> Self {
        let mut c = [Iv::ZERO; LEN];
        c[0] = Iv::from(v);
        Self { c, order: order.min(MAX_ORDER) }
    }

    /// Jets of `sin θ_k` and `cos θ_k` (`k` = 0 for θ₂, 1 for θ₃) over `x ∋ θ_k`.
    pub fn sin_cos(k: usize, x: Interval, order: usize) -> (Self, Self) {
        let order = order.min(MAX_ORDER);
        let (s, c) = (trig::sin(x), trig::cos(x));
        // The n-th derivative cycles through sin, cos, -sin, -cos; divided by n!.
        let sin_derivs = [s, c, -s, -c, s];
        let cos_derivs = [c, -s, -c, s, c];
        let factorial = [1.0, 1.0, 2.0, 6.0, 24.0];
        let mut sj = Self::zero(order);
        let mut cj = Self::zero(order);
        for n in 0..=order {
            let f = crate::kernel::interval::point(factorial[n]);
            let at = if k == 0 { index(n, 0) } else { index(n, n) };
            sj.c[at] = Iv::from(sin_derivs[n] / f);
            cj.c[at] = Iv::from(cos_derivs[n] / f);
        }
        (sj, cj)
    }

    fn zero(order: usize) -> Self {
        Self { c: [Iv::ZERO; LEN], order: order.min(MAX_ORDER) }
    }

    /// Highest order carried.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Enclosure of the value.
    pub fn value(&self) -> Interval {
        self.c[0].to()
    }

    /// Enclosure of the gradient (∂/∂θ₂, ∂/∂θ₃); needs order ≥ 1.
    pub fn grad(&self) -> [Interval; 2] {
        debug_assert!(self.order >= 1);
        [self.c[index(1, 0)].to(), self.c[index(1, 1)].to()]
    }

    /// The partial derivative along θ₂ (`k` = 0) or θ₃ (`k` = 1), one order lower.
    pub fn d(&self, k: usize) -> Self {
        debug_assert!(self.order >= 1);
        let mut out = Self::zero(self.order - 1);
        for d in 0..self.order {
            for j in 0..=d {
                let i = d - j;
                // ∂/∂θ₂ of c·θ₂^(i+1) θ₃^j is (i+1)·c·θ₂^i θ₃^j; likewise for θ₃. Small integer
                // factors times a double are exact unless they overflow, which `mul` handles.
                let (from, factor) = if k == 0 { (index(d + 1, j), i + 1) } else { (index(d + 1, j + 1), j + 1) };
                out.c[index(d, j)] = if factor == 1 { self.c[from] } else { self.c[from].mul(Iv { lo: factor as f64, hi: factor as f64 }) };
            }
        }
        out
    }

    /// `a · b` where `a` depends on θ₂ only and `b` on θ₃ only (as the jets of `sin_cos`
    /// and their combinations do): the product then has a single term per coefficient.
    pub fn outer(a: &Taylor, b: &Taylor) -> Taylor {
        let order = a.order.min(b.order);
        let mut out = Self::zero(order);
        for i in 0..=order {
            for j in 0..=(order - i) {
                out.c[index(i + j, j)] = a.c[index(i, 0)].mul(b.c[index(j, j)]);
            }
        }
        out
    }

    /// `a·c + b·d + e` for jets `a`, `b` of θ₃ only and interval constants `c`, `d`, `e`:
    /// touches only the pure-θ₃ coefficients.
    pub fn theta3_combination(a: &Taylor, c: Interval, b: &Taylor, d: Interval, e: Interval) -> Taylor {
        let order = a.order.min(b.order);
        let (c, d) = (Iv::from(c), Iv::from(d));
        let mut out = Self::zero(order);
        for j in 0..=order {
            let at = index(j, j);
            out.c[at] = a.c[at].mul(c).add(b.c[at].mul(d));
        }
        out.c[0] = out.c[0].add(Iv::from(e));
        out
    }

    /// Coefficient-wise intersection of two enclosures of the same jet (to the lower order).
    /// Where the two are disjoint, which sound enclosures never are, `self` is kept.
    pub fn intersect(&self, o: &Taylor) -> Taylor {
        let order = self.order.min(o.order);
        let mut out = Taylor::zero(order);
        for n in 0..index(order + 1, 0) {
            let (a, b) = (self.c[n], o.c[n]);
            let (lo, hi) = (a.lo.max(b.lo), a.hi.min(b.hi));
            out.c[n] = if lo <= hi { Iv { lo, hi } } else { a };
        }
        out
    }

    /// `self · s` for an interval constant `s`.
    pub fn scale(&self, s: Interval) -> Self {
        let s = Iv::from(s);
        let mut out = *self;
        for v in out.c.iter_mut().take(index(self.order + 1, 0)) {
            *v = v.mul(s);
        }
        out
    }

    /// `self + s` for an interval constant `s`.
    pub fn shift(&self, s: Interval) -> Self {
        let mut out = *self;
        out.c[0] = out.c[0].add(Iv::from(s));
        out
    }
}

impl std::ops::Add for Taylor {
    type Output = Taylor;
    fn add(self, o: Taylor) -> Taylor {
        let order = self.order.min(o.order);
        let mut out = Taylor::zero(order);
        for n in 0..index(order + 1, 0) {
            out.c[n] = self.c[n].add(o.c[n]);
        }
        out
    }
}

impl std::ops::Sub for Taylor {
    type Output = Taylor;
    #[allow(clippy::suspicious_arithmetic_impl)] // the `+` computes an index, not the difference
    fn sub(self, o: Taylor) -> Taylor {
        let order = self.order.min(o.order);
        let mut out = Taylor::zero(order);
        for n in 0..index(order + 1, 0) {
            out.c[n] = self.c[n].sub(o.c[n]);
        }
        out
    }
}

impl std::ops::Neg for Taylor {
    type Output = Taylor;
    fn neg(self) -> Taylor {
        let mut out = self;
        for v in out.c.iter_mut() {
            *v = v.neg();
        }
        out
    }
}

impl std::ops::Mul for Taylor {
    type Output = Taylor;
    fn mul(self, o: Taylor) -> Taylor {
        let order = self.order.min(o.order);
        let mut out = Taylor::zero(order);
        for da in 0..=order {
            for db in 0..=(order - da) {
                for ja in 0..=da {
                    let a = self.c[index(da, ja)];
                    for jb in 0..=db {
                        let at = index(da + db, ja + jb);
                        out.c[at] = out.c[at].add(a.mul(o.c[index(db, jb)]));
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::{interval, point};

    /// u = sin(θ₂)·cos(θ₃)² + θ-free constant, checked against hand derivatives at a point.
    #[test]
    fn derivatives_of_a_product_match_hand_formulas() {
        let (t2, t3) = (0.7, -1.3);
        let (s2, c2) = Taylor::sin_cos(0, point(t2), 4);
        let (s3, c3) = Taylor::sin_cos(1, point(t3), 4);
        let u = s2 * c3 * c3 + Taylor::constant(point(2.0), 4);
        let close = |i: Interval, v: f64| i.inf() - 1e-12 <= v && v <= i.sup() + 1e-12;
        assert!(close(u.value(), t2.sin() * t3.cos().powi(2) + 2.0));
        let g = u.grad();
        assert!(close(g[0], t2.cos() * t3.cos().powi(2)));
        assert!(close(g[1], -2.0 * t2.sin() * t3.cos() * t3.sin()));
        // ∂²u/∂θ₂∂θ₃ and ∂⁴u/∂θ₃⁴ through repeated `d`.
        assert!(close(u.d(0).d(1).value(), -2.0 * t2.cos() * t3.cos() * t3.sin()));
        // cos² = (1 + cos 2θ)/2, so its fourth derivative is 8 cos 2θ.
        assert!(close(u.d(1).d(1).d(1).d(1).value(), t2.sin() * 8.0 * (2.0 * t3).cos()));
        assert_eq!(u.d(1).d(1).d(1).d(1).order(), 0);
        // The separable product agrees with the general one.
        let (a, b) = (Taylor::outer(&s2, &c3), s2 * c3);
        for n in 0..LEN {
            assert!(a.c[n].lo >= b.c[n].lo && a.c[n].hi <= b.c[n].hi);
        }
        let _ = (c2, s3);
    }

    proptest::proptest! {
        /// Every operation of `Iv` contains the exact result at sampled points (checked
        /// against inari, itself outward rounded).
        #[test]
        fn iv_contains_inari(a in -1e3f64..1e3, w in 0.0f64..10.0, b in -1e3f64..1e3, v in 0.0f64..10.0) {
            let (x, y) = (interval(a, a + w), interval(b, b + v));
            let (p, q) = (Iv::from(x), Iv::from(y));
            let c = crate::kernel::interval::point(b);
            for (mine, theirs) in [(p.add(q), x + y), (p.sub(q), x - y), (p.mul(q), x * y), (p.neg(), -x), (p.scale(b), c * x), (p.scale(0.0), x * crate::kernel::interval::point(0.0))] {
                proptest::prop_assert!(mine.lo <= theirs.inf() && theirs.sup() <= mine.hi);
            }
        }
    }

    #[test]
    fn box_jets_enclose_point_jets() {
        let b = [interval(0.5, 0.6), interval(-0.2, 0.1)];
        let f = |x: [Interval; 2]| {
            let (s2, c2) = Taylor::sin_cos(0, x[0], 3);
            let (s3, c3) = Taylor::sin_cos(1, x[1], 3);
            (s2 * c3 - c2 * s3 * s3).d(0).d(1)
        };
        let whole = f(b);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let p = [point(0.5 + 0.1 * t), point(-0.2 + 0.3 * t)];
            let v = f(p);
            assert!(whole.value().subset(whole.value()) && v.value().inf() >= whole.value().inf() && v.value().sup() <= whole.value().sup());
            for i in 0..2 {
                assert!(!v.grad()[i].disjoint(whole.grad()[i]));
            }
        }
    }
}

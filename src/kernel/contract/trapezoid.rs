//! Trapezoid clipping of polynomial equations `p(x) = 0`: the `Reduce_Box` of Porta, Thomas,
//! Ros and Torras (2003, Fig. 3).
//!
//! For a multilinear `p` over a box, the graph `(x, p(x))` lies in the convex hull of the `2^k`
//! points `(corner, p(corner))` (Rikun 1997). Projected onto the plane of one variable `x_v` and
//! the value, that hull lies in a trapezoid whose vertical sides are `[min, max]` of `p` over the
//! corners on the faces `x_v = lower` and `x_v = upper`. Intersecting the trapezoid with the line
//! `p = 0` gives a range of `x_v` outside which no root lies: clip `x_v` to it, or empty the box
//! when the line misses the trapezoid.
//!
//! Two ways to get the sides (Table I of Porta et al. 2003 compares them):
//! - `FaceBounds::Corners`: the corner values, all `2^k` of them computed at once by a tensor
//!   transform in `O(k·2^k)`. For a variable of degree two the same transform gives Bernstein
//!   control points at the two ends and the middle, and the trapezoid becomes the hull of three
//!   vertical segments: the same clip, one more abscissa.
//! - `FaceBounds::IntervalArithmetic`: natural interval evaluation of `p` with `x_v` fixed at each
//!   end, `O(terms)` per face, looser. Valid only for variables of degree one (a degree-two
//!   variable is then not clipped, only the emptiness test applies).
//!
//! Soundness: control values are inari enclosures, abscissae are intervals, and every crossing
//! of the hull with `p = 0` is computed in interval arithmetic and rounded outward.
//! A box is emptied only when every control value of some equation is provably of one sign.

use super::{Contraction, Contractor};
use crate::kernel::interval::{point, Interval, IntervalBox};
use crate::kernel::interval::fast::Iv;
use crate::kernel::system::multilinear::{power, Poly};
use crate::kernel::system::VarId;
use thiserror::Error;

/// How the vertical sides of the trapezoids are bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceBounds {
    /// From the control points (the corner values of a multilinear equation): tight, `O(k·2^k)`.
    Corners,
    /// By interval evaluation of the equation on each face: loose, `O(terms)`.
    IntervalArithmetic,
}

/// An equation the clipper cannot take.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum ClipError {
    /// A variable has exponent above two.
    #[error("equation {equation}: variable {var} has degree {degree}; trapezoid clipping takes degree at most 2 per variable")]
    Degree {
        /// index of the equation
        equation: usize,
        /// the variable
        var: VarId,
        /// its degree
        degree: u8,
    },
    /// The control-point tensor would be too large.
    #[error("equation {equation} has {size} control points; at most {max} are allowed")]
    TooLarge {
        /// index of the equation
        equation: usize,
        /// its number of control points
        size: usize,
        /// the cap
        max: usize,
    },
}

/// Largest number of control points per equation (3^12 or 2^19): bounds the work per box.
pub const MAX_CONTROL_POINTS: usize = 1 << 19;

/// One equation in the form the clipper evaluates fast.
#[derive(Clone, Debug)]
struct Compiled {
    /// Global ids of the variables, in local order.
    vars: Vec<VarId>,
    /// Degree (1 or 2) of each local variable.
    degrees: Vec<u8>,
    /// Stride of each local variable in the dense tensor.
    strides: Vec<usize>,
    /// Dense power-basis coefficients, indexed by `Σ exponent_i · stride_i`.
    power: Vec<Interval>,
    /// The terms over local variables, for interval evaluation.
    terms: Vec<(Vec<(usize, u8)>, Interval)>,
}

impl Compiled {
    fn new(index: usize, p: &Poly) -> Result<Self, ClipError> {
        let vars = p.vars();
        let degrees: Vec<u8> = vars.iter().map(|&v| p.degree_in(v)).collect();
        if let Some((k, &d)) = degrees.iter().enumerate().find(|(_, &d)| d > 2) {
            return Err(ClipError::Degree { equation: index, var: vars[k], degree: d });
        }
        let mut strides = Vec::with_capacity(vars.len());
        let mut size: usize = 1;
        for &d in &degrees {
            strides.push(size);
            size = size.saturating_mul(d as usize + 1);
            if size > MAX_CONTROL_POINTS {
                return Err(ClipError::TooLarge { equation: index, size, max: MAX_CONTROL_POINTS });
            }
        }
        let local = |v: VarId| vars.binary_search(&v).expect("invariant: v is among p.vars()");
        let mut power = vec![point(0.0); size];
        let mut terms = Vec::with_capacity(p.len());
        for (m, c) in p.terms() {
            let at: usize = m.iter().map(|&(v, e)| strides[local(v)] * e as usize).sum();
            power[at] += c;
            terms.push((m.iter().map(|&(v, e)| (local(v), e)).collect(), c));
        }
        Ok(Self { vars, degrees, strides, power, terms })
    }

    fn eval(&self, x: &[Interval]) -> Interval {
        self.terms.iter().fold(point(0.0), |acc, (m, c)| acc + *c * m.iter().fold(point(1.0), |a, &(v, e)| a * power(x[v], e)))
    }
}

/// The `Reduce_Box` of Porta et al. (2003) over a list of polynomial equations `p = 0`, as a
/// `Contractor`.
///
/// One call makes one pass over the equations; the driver repeats passes while they pay (rho).
///
/// # Examples
///
/// ```
/// use linkspace::kernel::contract::{Contraction, Contractor, FaceBounds, TrapezoidClip};
/// use linkspace::kernel::interval::{interval, point};
/// use linkspace::kernel::system::Poly;
/// use linkspace::kernel::interval::IntervalBox;
/// // x·y − 1 = 0 on [0.5, 4] × [0.5, 1]: x ≥ 1 follows.
/// let p = Poly::var(0).mul(&Poly::var(1)).add(&Poly::constant(point(-1.0)));
/// let mut clip = TrapezoidClip::new(&[p], FaceBounds::Corners).unwrap();
/// let mut b = IntervalBox::new(vec![interval(0.5, 4.0), interval(0.5, 1.0)]);
/// assert_eq!(clip.contract(&mut b), Contraction::Reduced);
/// assert!(b.dims[0].inf() > 0.9);
/// ```
///
/// See also `formulate::cayley_menger`, which builds such equations from distances.
///
/// # References
/// J. M. Porta, F. Thomas, L. Ros, C. Torras, "A branch-and-prune algorithm for solving systems
/// of distance constraints", ICRA 2003. A. D. Rikun, "A convex envelope formula for multilinear
/// functions", J. Global Optimization 10, 1997.
#[derive(Clone, Debug)]
pub struct TrapezoidClip {
    equations: Vec<Compiled>,
    /// Corners (the method of Porta et al. 2003) or interval arithmetic (its comparison).
    pub faces: FaceBounds,
    work: Vec<Iv>,
    local: Vec<Interval>,
    lo: Vec<[f64; 3]>,
    hi: Vec<[f64; 3]>,
}

impl TrapezoidClip {
    /// Compiles the equations `p = 0`; fails on a variable of degree above two or an equation
    /// with more than `MAX_CONTROL_POINTS` control points.
    pub fn new(equations: &[Poly], faces: FaceBounds) -> Result<Self, ClipError> {
        let equations = equations.iter().enumerate().map(|(k, p)| Compiled::new(k, p)).collect::<Result<Vec<_>, _>>()?;
        Ok(Self { equations, faces, work: Vec::new(), local: Vec::new(), lo: Vec::new(), hi: Vec::new() })
    }

    /// Number of equations.
    pub fn len(&self) -> usize {
        self.equations.len()
    }

    /// True when there is no equation.
    pub fn is_empty(&self) -> bool {
        self.equations.is_empty()
    }

    /// Control points of the largest equation (the per-box cost driver).
    pub fn max_control_points(&self) -> usize {
        self.equations.iter().map(|e| e.power.len()).max().unwrap_or(0)
    }

    /// Fills `lo[i][j]`, `hi[i][j]`: bounds of the control values at abscissa `j` of variable `i`.
    ///
    /// Per axis, the power basis on `[l, u]` becomes Bernstein coefficients (corner values for
    /// degree one): `b0 = p(l)`, `b2 = p(u)`, and for degree two `b1 = a0 + a1 (l + u)/2 + a2 l u`.
    /// Only exact scalars `l`, `u` multiply the coefficients, which lets the arithmetic be plain
    /// `f64` rounded to nearest and then moved one ulp outward (`fast::Iv`): sound, and several
    /// times faster than general interval products.
    fn control_bounds(&mut self, e: usize, b: &[Interval]) {
        let eq = &self.equations[e];
        let k = eq.vars.len();
        self.lo.clear();
        self.lo.resize(k, [f64::INFINITY; 3]);
        self.hi.clear();
        self.hi.resize(k, [f64::NEG_INFINITY; 3]);
        self.work.clear();
        self.work.extend(eq.power.iter().map(|&c| Iv::from(c)));
        let size = self.work.len();
        let w = &mut self.work;
        for i in 0..k {
            let d = b[eq.vars[i]];
            let (l, u) = (d.inf(), d.sup());
            let s = eq.strides[i];
            let n = eq.degrees[i] as usize + 1;
            for start in (0..size).step_by(s * n) {
                for at in start..start + s {
                    if n == 2 {
                        let (a0, a1) = (w[at], w[at + s]);
                        w[at] = a0.add(a1.scale(l));
                        w[at + s] = a0.add(a1.scale(u));
                    } else {
                        let (a0, a1, a2) = (w[at], w[at + s], w[at + 2 * s]);
                        let (a1l, a1u) = (a1.scale(l), a1.scale(u));
                        let a2l = a2.scale(l);
                        w[at] = a0.add(a1l).add(a2l.scale(l));
                        w[at + s] = a0.add(a1l.add(a1u).scale(0.5)).add(a2l.scale(u));
                        w[at + 2 * s] = a0.add(a1u).add(a2.scale(u).scale(u));
                    }
                }
            }
        }
        // ∞ − ∞ after an overflow: no bounds at all (the caller then clips nothing).
        if w.iter().any(|v| v.lo.is_nan() || v.hi.is_nan()) {
            return;
        }
        // Extremes over each slice x_i = abscissa j, one strided pass per axis.
        for i in 0..k {
            let s = eq.strides[i];
            let n = eq.degrees[i] as usize + 1;
            let (lo, hi) = (&mut self.lo[i], &mut self.hi[i]);
            for start in (0..size).step_by(s * n) {
                for j in 0..n {
                    for v in &w[start + j * s..start + (j + 1) * s] {
                        lo[j] = lo[j].min(v.lo);
                        hi[j] = hi[j].max(v.hi);
                    }
                }
            }
        }
    }

    /// Face bounds by interval evaluation (degree-one variables only; others get no bounds).
    fn interval_bounds(&mut self, e: usize, b: &[Interval]) -> bool {
        let eq = &self.equations[e];
        let k = eq.vars.len();
        self.local.clear();
        self.local.extend(eq.vars.iter().map(|&v| b[v]));
        if !eq.eval(&self.local).contains(0.0) {
            return false;
        }
        self.lo.clear();
        self.lo.resize(k, [f64::INFINITY; 3]);
        self.hi.clear();
        self.hi.resize(k, [f64::NEG_INFINITY; 3]);
        for i in 0..k {
            if eq.degrees[i] != 1 {
                continue;
            }
            let d = self.local[i];
            for (j, end) in [d.inf(), d.sup()].into_iter().enumerate() {
                self.local[i] = point(end);
                let f = eq.eval(&self.local);
                self.lo[i][j] = f.inf();
                self.hi[i][j] = f.sup();
            }
            self.local[i] = d;
        }
        true
    }
}

/// The range of `x` where the hull of the vertical segments `{xs[j]} × [lo[j], hi[j]]` meets the
/// line `value = 0`, rounded outward; `None` when it misses.
///
/// `xs` are enclosures of the (exact) abscissae. The hull meets the line in a segment whose ends
/// lie on edges between vertices of opposite sign, so the extreme crossings of all such vertex
/// pairs (and of the vertical segments through zero) are its ends.
pub fn clip_segment(xs: &[Interval], lo: &[f64], hi: &[f64]) -> Option<(f64, f64)> {
    let (mut a, mut z) = (f64::INFINITY, f64::NEG_INFINITY);
    let n = xs.len();
    for j in 0..n {
        if lo[j] <= 0.0 && hi[j] >= 0.0 {
            a = a.min(xs[j].inf());
            z = z.max(xs[j].sup());
        }
    }
    for p in 0..n {
        for q in 0..n {
            if p == q {
                continue;
            }
            // A vertex below the line at p, one above at q.
            for fp in [lo[p], hi[p]] {
                for fq in [lo[q], hi[q]] {
                    if fp < 0.0 && fq > 0.0 {
                        let (fp, fq) = (point(fp), point(fq));
                        let t = -fp / (fq - fp);
                        let x = xs[p] + (xs[q] - xs[p]) * t;
                        a = a.min(x.inf());
                        z = z.max(x.sup());
                    }
                }
            }
        }
    }
    (a <= z).then_some((a, z))
}

impl Contractor for TrapezoidClip {
    fn contract(&mut self, b: &mut IntervalBox) -> Contraction {
        let mut outcome = Contraction::Unchanged;
        for e in 0..self.equations.len() {
            match self.faces {
                FaceBounds::Corners => self.control_bounds(e, &b.dims),
                FaceBounds::IntervalArithmetic => {
                    if !self.interval_bounds(e, &b.dims) {
                        return Contraction::Empty;
                    }
                }
            }
            let eq = &self.equations[e];
            for (i, &v) in eq.vars.iter().enumerate() {
                let d = b.dims[v];
                let n = eq.degrees[i] as usize + 1;
                if !(self.lo[i][..n].iter().chain(&self.hi[i][..n]).all(|v| !v.is_nan()) && self.lo[i][0] <= self.hi[i][0]) {
                    continue; // no usable bounds (interval arithmetic on degree two, or overflow)
                }
                let (l, u) = (point(d.inf()), point(d.sup()));
                let xs: &[Interval] = if n == 2 { &[l, u] } else { &[l, (l + u) * point(0.5), u] };
                let Some((x0, x1)) = clip_segment(xs, &self.lo[i][..n], &self.hi[i][..n]) else {
                    return Contraction::Empty;
                };
                if x0 > d.inf() || x1 < d.sup() {
                    let narrowed = d.intersection(crate::kernel::interval::interval(x0.max(d.inf()), x1.min(d.sup())));
                    if narrowed.is_empty() {
                        return Contraction::Empty;
                    }
                    if narrowed != d {
                        b.dims[v] = narrowed;
                        outcome = Contraction::Reduced;
                    }
                }
            }
        }
        outcome
    }

    fn name(&self) -> &'static str {
        match self.faces {
            FaceBounds::Corners => "trapezoid (corners)",
            FaceBounds::IntervalArithmetic => "trapezoid (interval arithmetic)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use proptest::prelude::*;

    fn hyperbola() -> Poly {
        // x·y − 1
        Poly::var(0).mul(&Poly::var(1)).add(&Poly::constant(point(-1.0)))
    }

    #[test]
    fn clips_the_hyperbola_to_its_trapezoid() {
        // On [0.5, 4] × [0.5, 1]: corners −0.75, 1, 1, 3 (x low: −0.75, −0.5; x high: 1, 3).
        // The lower edge from −0.75 to 1 crosses zero at x = 0.5 + 3.5·0.75/1.75 = 2; the
        // upper edge from −0.5 to 3 at x = 0.5 + 3.5·0.5/3.5 = 1.
        let mut c = TrapezoidClip::new(&[hyperbola()], FaceBounds::Corners).unwrap();
        let mut b = IntervalBox::new(vec![interval(0.5, 4.0), interval(0.5, 1.0)]);
        assert_eq!(c.contract(&mut b), Contraction::Reduced);
        assert!((b.dims[0].inf() - 1.0).abs() < 1e-12, "{:?}", b.dims[0]);
        let mut far = IntervalBox::new(vec![interval(2.0, 3.0), interval(1.0, 2.0)]);
        assert_eq!(c.contract(&mut far), Contraction::Empty);
    }

    #[test]
    fn interval_faces_are_never_tighter_than_corners() {
        let p = Poly::var(0).mul(&Poly::var(1)).add(&Poly::var(0).mul(&Poly::var(2)).scale(point(-1.0))).add(&Poly::constant(point(0.3)));
        let start = IntervalBox::new(vec![interval(-1.0, 1.0), interval(0.0, 2.0), interval(0.5, 1.5)]);
        let mut corners = start.clone();
        let mut ia = start.clone();
        TrapezoidClip::new(std::slice::from_ref(&p), FaceBounds::Corners).unwrap().contract(&mut corners);
        TrapezoidClip::new(&[p], FaceBounds::IntervalArithmetic).unwrap().contract(&mut ia);
        for (c, i) in corners.dims.iter().zip(&ia.dims) {
            assert!(c.wid() <= i.wid() + 1e-12);
        }
    }

    #[test]
    fn rejects_cubes() {
        let x = Poly::var(0);
        assert!(matches!(TrapezoidClip::new(&[x.mul(&x).mul(&x)], FaceBounds::Corners), Err(ClipError::Degree { degree: 3, .. })));
    }

    proptest! {
        // Soundness: a polynomial shifted to vanish at a random point r keeps r in any box that
        // holds it, for both face bounds, with and without a squared variable.
        #[test]
        fn never_removes_a_root(
            r in proptest::array::uniform3(-2.0f64..2.0),
            k in proptest::array::uniform4(-3.0f64..3.0),
            lo in proptest::array::uniform3(0.0f64..2.0),
            hi in proptest::array::uniform3(0.0f64..2.0),
            square in proptest::bool::ANY,
            ia in proptest::bool::ANY,
        ) {
            let x = Poly::var(0);
            let y = Poly::var(1);
            let z = Poly::var(2);
            // q = k0 x y + k1 y z + k2 x z (+ k3 x² when square) + linear part, minus q(r).
            let mut q = x.mul(&y).scale(point(k[0])).add(&y.mul(&z).scale(point(k[1]))).add(&x.mul(&z).scale(point(k[2]))).add(&z.scale(point(0.7)));
            if square {
                q = q.add(&x.mul(&x).scale(point(k[3])));
            }
            let at = q.eval(&[point(r[0]), point(r[1]), point(r[2])]);
            let q = q.add(&Poly::constant(-at));
            let faces = if ia { FaceBounds::IntervalArithmetic } else { FaceBounds::Corners };
            let mut c = TrapezoidClip::new(&[q], faces).unwrap();
            let mut b = IntervalBox::new((0..3).map(|i| interval(r[i] - lo[i], r[i] + hi[i])).collect());
            prop_assert_ne!(c.contract(&mut b), Contraction::Empty);
            prop_assert!(b.contains(&r), "{:?} lost {:?}", b, r);
        }
    }
}

//! The linear-form algebra the spatial builder writes its rows in: `Form` (`constant + Σ coef·var`),
//! rotations and vectors of forms (`RotF`, `Vec3F`), constant rotations (`rot_about`,
//! `rodrigues`) and points as rotated parts per group plus a linear rest (`Pos`).
//! Pure interval arithmetic on coefficients: no variable or equation is created here (that is
//! `Builder`'s), so every function is a plain value computation.

use crate::formulate::angles::{cos_sin, reduce, stated};
use crate::formulate::stated::{self as st, IMat3, IVec3};
use crate::kernel::interval::trig;
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::VarId;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// `constant + Σ coef·var`.
#[derive(Clone, Debug)]
pub(super) struct Form {
    pub(super) terms: Vec<(VarId, Interval)>,
    pub(super) constant: Interval,
}

impl Form {
    pub(super) fn constant(k: Interval) -> Self {
        Self { terms: Vec::new(), constant: k }
    }

    pub(super) fn var(v: VarId) -> Self {
        Self { terms: vec![(v, point(1.0))], constant: point(0.0) }
    }

    pub(super) fn zero() -> Self {
        Self::constant(point(0.0))
    }

    pub(super) fn scaled(&self, k: Interval) -> Self {
        Self { terms: self.terms.iter().map(|&(v, c)| (v, c * k)).collect(), constant: self.constant * k }
    }

    pub(super) fn add(&mut self, o: &Form) {
        self.terms.extend_from_slice(&o.terms);
        self.constant += o.constant;
    }

    pub(super) fn add_scaled(&mut self, o: &Form, k: Interval) {
        if k.inf() == 0.0 && k.sup() == 0.0 {
            return;
        }
        self.add(&o.scaled(k));
    }

    /// Repeated variables merged; exactly-zero coefficients left out (a tiny one is a term
    /// like any other: dropping it could lose solutions).
    pub(super) fn merged(&self) -> Form {
        let mut m: BTreeMap<VarId, Interval> = BTreeMap::new();
        for &(v, c) in &self.terms {
            let e = m.entry(v).or_insert(point(0.0));
            *e += c;
        }
        Form { terms: m.into_iter().filter(|&(_, c)| !(c.inf() == 0.0 && c.sup() == 0.0)).collect(), constant: self.constant }
    }

    pub(super) fn eval(&self, b: &[Interval]) -> Interval {
        self.terms.iter().fold(self.constant, |acc, &(v, c)| acc + c * b[v])
    }
}

pub(super) type Vec3F = [Form; 3];
pub(super) type RotF = [[Form; 3]; 3];

pub(super) fn const_rot(m: &IMat3) -> RotF {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| Form::constant(m[i][j])))
}

/// `G·K` for a constant `K`.
pub(super) fn rot_times(g: &RotF, k: &IMat3) -> RotF {
    [0, 1, 2].map(|i| {
        [0, 1, 2].map(|j| {
            let mut f = Form::zero();
            for (l, gl) in g[i].iter().enumerate() {
                f.add_scaled(gl, k[l][j]);
            }
            f.merged()
        })
    })
}

/// `G·v` for a constant `v`.
pub(super) fn rot_apply(g: &RotF, v: &IVec3) -> Vec3F {
    [0, 1, 2].map(|i| {
        let mut f = Form::zero();
        for (l, gl) in g[i].iter().enumerate() {
            f.add_scaled(gl, v[l]);
        }
        f.merged()
    })
}

pub(super) fn sub3(a: &Vec3F, b: &Vec3F) -> Vec3F {
    [0, 1, 2].map(|i| {
        let mut f = a[i].clone();
        f.add_scaled(&b[i], point(-1.0));
        f.merged()
    })
}

/// The rotation by the stated angle `v` about the unit axis `a` (Rodrigues).
pub(super) fn rot_about(a: &IVec3, v: f64) -> IMat3 {
    let (c, s) = cos_sin(reduce(stated(v)).expect("checked reducible"));
    rodrigues(a, c, s)
}

/// `aaᵀ + c(I − aaᵀ) + s[a]×`
pub(super) fn rodrigues(a: &IVec3, c: Interval, s: Interval) -> IMat3 {
    let (aat, rest, skew) = rodrigues_parts(a);
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| aat[i][j] + c * rest[i][j] + s * skew[i][j]))
}

/// `(aaᵀ, I − aaᵀ, [a]×)`; components of `a` that are exactly 0 keep exact zeros.
pub(super) fn rodrigues_parts(a: &IVec3) -> (IMat3, IMat3, IMat3) {
    let z = point(0.0);
    let aat = [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[i] * a[j]));
    let rest = [0, 1, 2].map(|i| [0, 1, 2].map(|j| if i == j { point(1.0) - aat[i][j] } else { -aat[i][j] }));
    let skew = [[z, -a[2], a[1]], [a[2], z, -a[0]], [-a[1], a[0], z]];
    (aat, rest, skew)
}

pub(super) fn imat_mul(a: &IMat3, b: &IMat3) -> IMat3 {
    st::mul(a, b)
}

/// A point as rotated parts per group plus a linear rest: `Σ G_g·v_g + rest`.
#[derive(Clone, Debug)]
pub(super) struct Pos {
    pub(super) rotated: Vec<(usize, IVec3)>,
    pub(super) rest: Vec3F,
}

impl Pos {
    pub(super) fn origin() -> Self {
        Self { rotated: Vec::new(), rest: [Form::zero(), Form::zero(), Form::zero()] }
    }

    /// Adds `G_g·v`; the ground's group (0) is the identity, so its part is a constant.
    pub(super) fn add_rotated(&mut self, g: usize, v: IVec3) {
        if g == 0 {
            for (r, x) in self.rest.iter_mut().zip(v) {
                r.constant += x;
            }
        } else {
            self.rotated.push((g, v));
        }
    }

    pub(super) fn minus(&self, o: &Pos) -> Pos {
        let mut out = self.clone();
        for &(g, v) in &o.rotated {
            out.rotated.push((g, v.map(|x| -x)));
        }
        out.rest = sub3(&self.rest, &o.rest);
        out
    }

    /// Parts of one group summed: `Σ_g G_g·(Σ v)`.
    pub(super) fn by_group(&self) -> BTreeMap<usize, IVec3> {
        let mut m: BTreeMap<usize, IVec3> = BTreeMap::new();
        for &(g, v) in &self.rotated {
            let e = m.entry(g).or_insert([point(0.0); 3]);
            for (x, y) in e.iter_mut().zip(v) {
                *x += y;
            }
        }
        m
    }
}

pub(super) fn is_zero(x: Interval) -> bool {
    x.inf() == 0.0 && x.sup() == 0.0
}

/// The bounding box on the unit circle of the arc of angles `arc` (sound cos and sin).
pub(super) fn arc_box(arc: Interval) -> (Interval, Interval) {
    let unit = interval(-1.0, 1.0);
    (trig::cos(arc).intersection(unit), trig::sin(arc).intersection(unit))
}

/// Two unit vectors completing `a` to an orthonormal frame.
pub(super) fn across(a: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let helper = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = (helper - a * a.dot(&helper)).normalize();
    [e1, a.cross(&e1)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn rodrigues_encloses_the_rotation() {
        let a = Vector3::new(1.0, 2.0, -0.5).normalize();
        let r = rot_about(&st::axis(&a), 0.7);
        let want = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(a), 0.7);
        for i in 0..3 {
            for j in 0..3 {
                assert!(r[i][j].inf() - 1e-14 <= want[(i, j)] && want[(i, j)] <= r[i][j].sup() + 1e-14);
            }
        }
    }

    #[test]
    fn across_completes_an_orthonormal_frame() {
        for a in [Vector3::z(), Vector3::x(), Vector3::new(0.3, -0.4, 0.5).normalize()] {
            let [e1, e2] = across(&a);
            assert!(e1.dot(&a).abs() < 1e-15 && e2.dot(&a).abs() < 1e-15 && (e1.norm() - 1.0).abs() < 1e-15 && (e2.norm() - 1.0).abs() < 1e-15);
        }
    }
}

//! The kinematic map of a 3R chain from its URDF transforms.
//!
//! A `Chain3R` is built from a `Mechanism` that is a serial chain with exactly three revolute
//! joints (fixed joints anywhere are folded in; the end point is the origin of the chain's last
//! link). With `a₁` the first axis through the origin of the first joint frame, the map is
//!
//! ```text
//! f(θ₂, θ₃) = (ρ, z),   ρ = |p − (a₁·p) a₁|²,   z = a₁·p,
//! ```
//!
//! where `p` is the end point in the first link's frame. ρ is the squared radius of Benoit et al.
//! (2019), which is smooth where the radius is not (on the first axis); reports give the radius √ρ.
//! Rodrigues' formula makes `p` affine in `(cos θ₂, sin θ₂, 1) ⊗ (cos θ₃, sin θ₃, 1)` for any
//! axes and offsets, so the chain is stored as nine interval 3-vectors and evaluated as `Taylor`
//! jets: no per-robot formula is typed by hand, and non-orthogonal chains work the same way.
//!
//! With an uncertainty `h > 0`, every non-zero translation component of every joint origin on
//! the chain becomes the interval `[v − h, v + h]`, and every enclosure holds for every geometry
//! in that box. `derived` keeps the lengths correlated: the end point is linear in the joint
//! translations, so its derivative along each length is exact, and the mean-value form in the
//! lengths is intersected with the natural enclosure.

pub(crate) use crate::formulate::torus::Derived;
pub use crate::formulate::torus::Jets;
use crate::kernel::taylor::Taylor;
use super::Manip3rError;
use crate::kernel::interval::{interval, point};
use crate::model::{Joint, JointKind, Mechanism};
use inari::Interval;

/// An interval 3-vector.
pub type V3 = [Interval; 3];
pub(super) type M3 = [[Interval; 3]; 3];

/// A 3R chain reduced to its kinematic map (see the module doc).
#[derive(Clone, Debug)]
pub struct Chain3R {
    /// The robot's name.
    pub name: String,
    /// URDF names of the three revolute joints, base first.
    pub joints: [String; 3],
    /// The link whose origin is the end point.
    pub tip_link: String,
    /// Half-width added to every length (0 for the nominal geometry).
    pub uncertainty: f64,
    /// The end point's coefficients over the whole box of lengths.
    coef: Coefficients,
    /// With uncertain lengths: the coefficients at the nominal lengths, and their derivatives
    /// along each uncertain length (the map is linear in the lengths, so these are exact).
    /// Empty `sensitivity` when the lengths are exact.
    nominal: Coefficients,
    sensitivity: Vec<Coefficients>,
    /// The second axis in its joint frame.
    axis2: V3,
}

/// The end point as coefficients of (cos θ₂, sin θ₂, 1) ⊗ (cos θ₃, sin θ₃, 1).
#[derive(Clone, Copy, Debug)]
struct Coefficients {
    /// Perpendicular part of `p` (relative to a₁): `perp[a][b]`, `a` over (cos θ₂, sin θ₂, 1),
    /// `b` over (cos θ₃, sin θ₃, 1).
    perp: [[V3; 3]; 3],
    /// `a₁·p` in the same basis.
    along: [[Interval; 3]; 3],
    /// The end point in the second joint's frame: `q(θ₃) = q[0] cos θ₃ + q[1] sin θ₃ + q[2]`.
    q: [V3; 3],
}

pub(super) fn dot(a: &V3, b: &V3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: &V3, b: &V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(super) fn scale(a: &V3, s: Interval) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(super) fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn apply(m: &M3, v: &V3) -> V3 {
    [dot(&m[0], v), dot(&m[1], v), dot(&m[2], v)]
}

/// Rodrigues' formula: `R(a, θ) v = (v − a(a·v)) cos θ + (a × v) sin θ + a(a·v)`, as the three
/// coefficients of (cos θ, sin θ, 1).
pub(super) fn rodrigues(a: &V3, v: &V3) -> [V3; 3] {
    let along = scale(a, dot(a, v));
    [sub(v, &along), cross(a, v), along]
}

pub(super) const ZERO: Interval = inari::const_interval!(0.0, 0.0);

/// Jets of sin θ₂, cos θ₂, sin θ₃, cos θ₃ over `theta`.
fn trig_jets(theta: [Interval; 2], order: usize) -> [Taylor; 4] {
    let (s2, c2) = Taylor::sin_cos(0, theta[0], order);
    let (s3, c3) = Taylor::sin_cos(1, theta[1], order);
    [s2, c2, s3, c3]
}

/// A rigid transform with interval entries.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pose {
    pub(super) r: M3,
    pub(super) t: V3,
}

impl Pose {
    pub(super) fn identity() -> Self {
        let mut r = [[ZERO; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            row[i] = point(1.0);
        }
        Pose { r, t: [ZERO; 3] }
    }

    pub(super) fn from_origin(joint: &Joint, h: f64) -> Self {
        let tr = joint.origin.translation.vector;
        // Lengths given in the file carry the uncertainty; zero offsets are structure, not
        // lengths. v ± h rounded outward, so every length within h of v is inside.
        let t = [0, 1, 2].map(|i| if tr[i] != 0.0 && h > 0.0 { point(tr[i]) + interval(-h, h) } else { point(tr[i]) });
        Self::with_translation(joint, t)
    }

    /// The rotation of `joint`'s origin (exact when the rounding policy made it so) with the
    /// translation `t`.
    pub(super) fn with_translation(joint: &Joint, t: V3) -> Self {
        let m = joint.rotation_matrix();
        Pose { r: m.map(|row| row.map(point)), t }
    }

    /// `self ∘ other`: first `other`, then `self`.
    #[allow(clippy::needless_range_loop)] // 3 × 3 matrix product: indices read as the formula
    pub(super) fn then(&self, other: &Pose) -> Pose {
        let mut r = [[ZERO; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = self.r[i][0] * other.r[0][j] + self.r[i][1] * other.r[1][j] + self.r[i][2] * other.r[2][j];
            }
        }
        Pose { r, t: add(&apply(&self.r, &other.t), &self.t) }
    }
}

impl Coefficients {
    /// The coefficients of the chain along `path` (root first) with revolute axes `axes`, the
    /// joint translations given by `translation(joint)` and the rotations from the file.
    fn new(m: &Mechanism, path: &[usize], axes: &[V3; 3], translation: &dyn Fn(usize) -> V3) -> Self {
        // Poses between consecutive revolute joints: each joint's origin, preceded by the fixed
        // joints since the previous revolute one.
        let mut segments = [Pose::identity(); 4];
        let mut seg = 0;
        for &j in path {
            let joint = &m.joints[j];
            segments[seg] = segments[seg].then(&Pose::with_translation(joint, translation(j)));
            if matches!(joint.kind, JointKind::Revolute { .. }) {
                seg += 1;
            }
        }
        let [a1, a2, a3] = axes;
        // segments[1]: second joint frame in the first link; [2]: third joint frame in the
        // second link; [3]: tip link in the third link.
        let tip_point = segments[3].t;
        let in_third = rodrigues(a3, &tip_point);
        let mut q = [0, 1, 2].map(|b| apply(&segments[2].r, &in_third[b]));
        q[2] = add(&q[2], &segments[2].t);
        let mut perp = [[[ZERO; 3]; 3]; 3];
        let mut along = [[ZERO; 3]; 3];
        for b in 0..3 {
            let in_second = rodrigues(a2, &q[b]);
            for a in 0..3 {
                let mut p = apply(&segments[1].r, &in_second[a]);
                if a == 2 && b == 2 {
                    p = add(&p, &segments[1].t);
                }
                let z = dot(a1, &p);
                along[a][b] = z;
                perp[a][b] = sub(&p, &scale(a1, z));
            }
        }
        Coefficients { perp, along, q }
    }

    /// Jets of the three components of the end point's perpendicular part and of z, from the
    /// jets of (sin, cos) of θ₂ and θ₃.
    fn point(&self, trig: &[Taylor; 4]) -> ([Taylor; 3], Taylor) {
        let [s2, c2, s3, c3] = trig;
        let basis3 = |coef: [Interval; 3]| Taylor::theta3_combination(c3, coef[0], s3, coef[1], coef[2]);
        // The h's depend on θ₃ only, c2 and s2 on θ₂ only.
        let combine = |h: [Taylor; 3]| Taylor::outer(c2, &h[0]) + Taylor::outer(s2, &h[1]) + h[2];
        let p = [0, 1, 2].map(|i| combine([0, 1, 2].map(|a| basis3([self.perp[a][0][i], self.perp[a][1][i], self.perp[a][2][i]]))));
        let z = combine([0, 1, 2].map(|a| basis3(self.along[a])));
        (p, z)
    }
}

impl Chain3R {
    /// Reads the chain from a mechanism; `uncertainty` is the half-width `h` given to every length.
    ///
    /// Errors: loops, branches, a joint other than revolute or fixed on the chain, not exactly
    /// three revolute joints, `h` negative or not finite, and a map that is degenerate (the end
    /// point does not move, or moves along a curve only, so det Df vanishes identically).
    pub fn from_mechanism(m: &Mechanism, uncertainty: f64) -> Result<Self, Manip3rError> {
        if !(uncertainty.is_finite() && uncertainty >= 0.0) {
            return Err(Manip3rError::BadUncertainty(uncertainty));
        }
        if !m.loops.is_empty() {
            return Err(Manip3rError::NotSerial(format!("it has {} loop closures", m.loops.len())));
        }
        let leaves: Vec<usize> = (0..m.links.len()).filter(|&l| m.joints.iter().all(|j| j.parent != l)).collect();
        let tip = match leaves.as_slice() {
            [t] => *t,
            _ => {
                let names: Vec<&str> = leaves.iter().map(|&l| m.links[l].name.as_str()).collect();
                return Err(Manip3rError::NotSerial(format!("it branches into several end links ({})", names.join(", "))));
            }
        };
        let path = m.path_to(tip);
        let mut revolute = Vec::new();
        for &j in &path {
            match m.joints[j].kind {
                JointKind::Revolute { .. } if m.joints[j].mimic.is_some() => {
                    let leader = m.joints[j].mimic.as_ref().map_or("", |x| x.joint.as_str());
                    return Err(Manip3rError::NotThreeR(format!("joint '{}' follows '{leader}' through <mimic>, which the 3R analyses do not model yet", m.joints[j].name)));
                }
                JointKind::Revolute { .. } => revolute.push(j),
                JointKind::Fixed => {}
                JointKind::Prismatic { .. } => return Err(Manip3rError::NotThreeR(format!("joint '{}' is prismatic", m.joints[j].name))),
                JointKind::Spherical | JointKind::Floating => return Err(Manip3rError::NotThreeR(format!("joint '{}' is not revolute", m.joints[j].name))),
            }
        }
        if revolute.len() != 3 {
            return Err(Manip3rError::NotThreeR(format!("the chain to '{}' has {} revolute joints", m.links[tip].name, revolute.len())));
        }
        let h = uncertainty;
        let axis = |k: usize| -> V3 { let a = m.joints[revolute[k]].axis; [point(a[0]), point(a[1]), point(a[2])] };
        let axes = [axis(0), axis(1), axis(2)];
        let coef = Coefficients::new(m, &path, &axes, &|j| Pose::from_origin(&m.joints[j], h).t);
        // The uncertain lengths, as (joint, component); the end point is linear in the joint
        // translations (rotations are fixed), so its derivative along one length is the map
        // built with that translation component 1 and every other translation 0.
        let mut lengths = Vec::new();
        if h > 0.0 {
            for &j in &path {
                for i in 0..3 {
                    if m.joints[j].origin.translation.vector[i] != 0.0 {
                        lengths.push((j, i));
                    }
                }
            }
        }
        if let Some(&(j, i)) = lengths.iter().min_by(|a, b| m.joints[a.0].origin.translation.vector[a.1].abs().total_cmp(&m.joints[b.0].origin.translation.vector[b.1].abs())) {
            let length = m.joints[j].origin.translation.vector[i].abs();
            if h >= length {
                return Err(Manip3rError::UncertaintyTooLarge { h, joint: m.joints[j].name.clone(), length, axis: ["x", "y", "z"][i] });
            }
        }
        let nominal = Coefficients::new(m, &path, &axes, &|j| Pose::from_origin(&m.joints[j], 0.0).t);
        let sensitivity = lengths
            .iter()
            .map(|&(jl, il)| Coefficients::new(m, &path, &axes, &|j| [0, 1, 2].map(|i| if (j, i) == (jl, il) { point(1.0) } else { ZERO })))
            .collect();
        let chain = Chain3R {
            name: m.name.clone(),
            joints: [0, 1, 2].map(|k| m.joints[revolute[k]].name.clone()),
            tip_link: m.links[tip].name.clone(),
            uncertainty,
            coef,
            nominal,
            sensitivity,
            axis2: axes[1],
        };
        chain.check_not_degenerate()?;
        Ok(chain)
    }

    /// Jets of ρ and z over the box `theta` = (θ₂, θ₃), to `order` (≤ 4): the natural
    /// enclosure over every geometry in the box of lengths.
    pub fn jets(&self, theta: [Interval; 2], order: usize) -> Jets {
        let (p, z) = self.coef.point(&trig_jets(theta, order));
        Jets { rho: p[0] * p[0] + p[1] * p[1] + p[2] * p[2], z }
    }

    /// `jets(theta, order).derived()`, tightened for uncertain lengths by the mean-value form in
    /// the lengths: every quantity Q of `Derived` (each Taylor coefficient) lies in
    /// `Q(θ, nominal) + Σₖ ∂Q/∂δₖ(θ, Δ) · [−h, h]` with `Δ` the box of lengths, which is
    /// intersected with the natural enclosure. Shared lengths then stay correlated across
    /// the terms of ρ, z and their derivatives (the dependency problem of the natural form),
    /// and the width due to the lengths is their true effect plus O(h·(h + |θ box|)).
    /// The derivatives are exact forward-mode ones: the end point is linear in the lengths.
    #[allow(clippy::needless_range_loop)] // 2 × 2 Jacobian entries: indices read as the formula
    pub fn derived(&self, theta: [Interval; 2], order: usize) -> Derived {
        let trig = trig_jets(theta, order);
        let (p, z) = self.coef.point(&trig);
        let natural = Jets { rho: p[0] * p[0] + p[1] * p[1] + p[2] * p[2], z }.derived();
        if self.sensitivity.is_empty() {
            return natural;
        }
        let (pn, zn) = self.nominal.point(&trig);
        let mut mv = Jets { rho: pn[0] * pn[0] + pn[1] * pn[1] + pn[2] * pn[2], z: zn }.derived();
        let spread = interval(-self.uncertainty, self.uncertainty);
        let nd = natural;
        for s in &self.sensitivity {
            let (pk, zk) = s.point(&trig);
            // ∂ρ/∂δ = 2 p·∂p/∂δ with p over the whole box of lengths; ∂z/∂δ is exact.
            let fk = [(p[0] * pk[0] + p[1] * pk[1] + p[2] * pk[2]).scale(point(2.0)), zk];
            let dfk = [[fk[0].d(0), fk[0].d(1)], [fk[1].d(0), fk[1].d(1)]];
            let detk = dfk[0][0] * nd.df[1][1] + nd.df[0][0] * dfk[1][1] - dfk[0][1] * nd.df[1][0] - nd.df[0][1] * dfk[1][0];
            for a in 0..2 {
                mv.f[a] = mv.f[a] + fk[a].scale(spread);
                for i in 0..2 {
                    mv.df[a][i] = mv.df[a][i] + dfk[a][i].scale(spread);
                }
            }
            mv.det = mv.det + detk.scale(spread);
            if nd.det.order() >= 1 {
                let (d0, d1) = (nd.det.d(0), nd.det.d(1));
                let (d0k, d1k) = (detk.d(0), detk.d(1));
                for a in 0..2 {
                    let gk = dfk[a][1] * d0 + nd.df[a][1] * d0k - dfk[a][0] * d1 - nd.df[a][0] * d1k;
                    mv.g[a] = mv.g[a] + gk.scale(spread);
                }
            }
        }
        Derived {
            f: [0, 1].map(|a| nd.f[a].intersect(&mv.f[a])),
            df: [0, 1].map(|a| [0, 1].map(|i| nd.df[a][i].intersect(&mv.df[a][i]))),
            det: nd.det.intersect(&mv.det),
            g: if nd.det.order() >= 1 { [0, 1].map(|a| nd.g[a].intersect(&mv.g[a])) } else { nd.g },
        }
    }

    /// The end point's part perpendicular to the first axis, `p − (a₁·p) a₁`, over the box
    /// `theta` = (θ₂, θ₃), in the first link's frame (so in the first joint's frame at θ₁ = 0):
    /// its direction about a₁ gives θ₁ in inverse kinematics. Natural interval evaluation.
    #[allow(clippy::needless_range_loop)] // tensor coefficients c[a][b] paired with e2[a], e3[b]
    pub fn perp(&self, theta: [Interval; 2]) -> [Interval; 3] {
        let e2 = [crate::kernel::interval::trig::cos(theta[0]), crate::kernel::interval::trig::sin(theta[0]), point(1.0)];
        let e3 = [crate::kernel::interval::trig::cos(theta[1]), crate::kernel::interval::trig::sin(theta[1]), point(1.0)];
        let mut p = [ZERO; 3];
        for a in 0..3 {
            for b in 0..3 {
                p = add(&p, &scale(&self.coef.perp[a][b], e2[a] * e3[b]));
            }
        }
        p
    }

    /// f at a point, in plain floating point (midpoints of the coefficients): for sampling and
    /// tests only, never for decisions.
    #[allow(clippy::needless_range_loop)] // tensor coefficients c[a][b] paired with e2[a], e3[b]
    pub fn eval_f64(&self, t2: f64, t3: f64) -> [f64; 2] {
        let e2 = [t2.cos(), t2.sin(), 1.0];
        let e3 = [t3.cos(), t3.sin(), 1.0];
        let mut p = [0.0; 3];
        let mut z = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                let w = e2[a] * e3[b];
                for (i, pi) in p.iter_mut().enumerate() {
                    *pi += self.coef.perp[a][b][i].mid() * w;
                }
                z += self.coef.along[a][b].mid() * w;
            }
        }
        [p[0] * p[0] + p[1] * p[1] + p[2] * p[2], z]
    }

    /// `a₂ × q(θ₃)` over `t3`: zero exactly when the end point lies on the second axis, where
    /// the whole θ₂-line maps to one point (an internal motion). Centred form, intersected with
    /// the natural one.
    pub fn off_axis2(&self, t3: Interval) -> [Interval; 3] {
        let m = point(t3.mid());
        let eval = |t: Interval, deriv: bool| -> [Interval; 3] {
            let (s, c) = (crate::kernel::interval::trig::sin(t), crate::kernel::interval::trig::cos(t));
            // q = q0 cos + q1 sin + q2; q' = −q0 sin + q1 cos.
            let v: V3 = if deriv {
                add(&scale(&self.coef.q[0], -s), &scale(&self.coef.q[1], c))
            } else {
                add(&add(&scale(&self.coef.q[0], c), &scale(&self.coef.q[1], s)), &self.coef.q[2])
            };
            cross(&self.axis2, &v)
        };
        let natural = eval(t3, false);
        let at_mid = eval(m, false);
        let slope = eval(t3, true);
        [0, 1, 2].map(|i| natural[i].intersection(at_mid[i] + slope[i] * (t3 - m)))
    }

    /// A length scale of the arm: the largest |coefficient| of the end point (metres).
    pub fn length_scale(&self) -> f64 {
        let mut m: f64 = 0.0;
        for row in &self.coef.perp {
            for v in row {
                for c in v {
                    m = m.max(c.mag());
                }
            }
        }
        for row in &self.coef.along {
            for c in row {
                m = m.max(c.mag());
            }
        }
        m.max(f64::MIN_POSITIVE)
    }

    fn check_not_degenerate(&self) -> Result<(), Manip3rError> {
        // Sample a coarse grid in floating point: a map whose Jacobian determinant is zero at
        // every sample (to relative 1e-9) is degenerate; one that never moves is reported as such.
        let n = 13;
        let mut spread: f64 = 0.0;
        let mut scale: f64 = 0.0;
        let mut det_max: f64 = 0.0;
        let f0 = self.eval_f64(0.3, 0.4);
        for i in 0..n {
            for j in 0..n {
                let t = [-3.0 + 6.0 * i as f64 / (n - 1) as f64 + 0.01, -3.0 + 6.0 * j as f64 / (n - 1) as f64 + 0.02];
                let jets = self.jets([point(t[0]), point(t[1])], 1);
                let d = jets.det().value().mid();
                let f = [jets.rho.value().mid(), jets.z.value().mid()];
                spread = spread.max((f[0] - f0[0]).abs()).max((f[1] - f0[1]).abs());
                scale = scale.max(f[0].abs().sqrt()).max(f[1].abs());
                det_max = det_max.max(d.abs());
            }
        }
        if spread <= 1e-12 * (1.0 + scale * scale) {
            return Err(Manip3rError::TipDoesNotMove(format!("'{}'", self.tip_link)));
        }
        if det_max <= 1e-9 * (1.0 + scale).powi(4) {
            return Err(Manip3rError::Degenerate(format!("'{}'", self.tip_link)));
        }
        Ok(())
    }
}

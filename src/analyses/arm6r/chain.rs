//! The six revolute joints of an arm, base to tip, as interval affine maps.
//!
//! The tip frame is `Pre₁·R₁(θ₁)·Pre₂·R₂(θ₂)···Pre₆·R₆(θ₆)·Post`, with `Preₖ` the origin of
//! joint k preceded by the fixed joints since joint k−1 (merged) and `Post` the fixed joints after
//! joint 6. Every coefficient encloses the file's decimals (`formulate::stated`; a rotation the
//! rounding policy made exact stays exact). A joint's rotation is written `P + cos θ·Q + sin θ·S`
//! (`P = aaᵀ`, `Q = I − P`, `S = [a]×`), so a rotation followed by a constant map is one
//! *block* `A + c·B + s·C` in which c and s occur once per entry (less interval wrapping than a
//! product), and axis-aligned joints keep exact zeros and ones.

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::Manip6rError;
use crate::kernel::interval::fast::Iv;
use crate::kernel::interval::{point, trig, Interval};
use crate::model::{JointKind, Mechanism};
use crate::formulate::stated;

/// A rigid transform in `f64`: `x ↦ r·x + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose64 {
    /// Rotation, row-major.
    pub r: [[f64; 3]; 3],
    /// Translation.
    pub t: [f64; 3],
}

impl Pose64 {
    /// The identity.
    pub const IDENTITY: Pose64 = Pose64 { r: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], t: [0.0; 3] };

    /// `self ∘ o`: first `o`, then `self`.
    pub fn then(&self, o: &Pose64) -> Pose64 {
        let mut r = [[0.0; 3]; 3];
        let mut t = self.t;
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = (0..3).map(|k| self.r[i][k] * o.r[k][j]).sum();
            }
            t[i] += (0..3).map(|k| self.r[i][k] * o.t[k]).sum::<f64>();
        }
        Pose64 { r, t }
    }

    /// The largest entry-wise difference of rotations plus the distance of translations: a
    /// plain closeness measure for checks.
    pub fn distance(&self, o: &Pose64) -> f64 {
        let mut d: f64 = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                d = d.max((self.r[i][j] - o.r[i][j]).abs());
            }
        }
        d + (0..3).map(|i| (self.t[i] - o.t[i]).powi(2)).sum::<f64>().sqrt()
    }

    /// The URDF pose `xyz`, `rpy` (`Rz(yaw)·Ry(pitch)·Rx(roll)`).
    pub fn from_xyz_rpy(v: [f64; 6]) -> Pose64 {
        let (sr, cr) = v[3].sin_cos();
        let (sp, cp) = v[4].sin_cos();
        let (sy, cy) = v[5].sin_cos();
        let r = [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ];
        Pose64 { r, t: [v[0], v[1], v[2]] }
    }
}

/// A 3-vector of outward intervals.
pub(crate) type V = [Iv; 3];
/// A 3×3 matrix of outward intervals, row-major.
pub(crate) type M = [[Iv; 3]; 3];

/// An interval affine map `x ↦ r·x + t`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Affine {
    pub r: M,
    pub t: V,
}

/// The same with inari intervals, for construction (exact where the entries allow).
#[derive(Clone, Copy, Debug)]
pub(crate) struct IAffine {
    pub r: [[Interval; 3]; 3],
    pub t: [Interval; 3],
}

impl IAffine {
    pub(crate) fn identity() -> IAffine {
        IAffine { r: stated::identity(), t: [point(0.0); 3] }
    }

    /// `self ∘ o`.
    pub(crate) fn then(&self, o: &IAffine) -> IAffine {
        let t = stated::apply(&self.r, &o.t);
        IAffine { r: stated::mul(&self.r, &o.r), t: [0, 1, 2].map(|i| t[i] + self.t[i]) }
    }

    /// The inverse, enclosing the exact inverse of every rigid map in the enclosure whose
    /// rotation is orthogonal (the exact one): `(rᵀ, −rᵀ·t)`.
    pub(crate) fn inverse(&self) -> IAffine {
        let rt = [0, 1, 2].map(|i| [0, 1, 2].map(|j| self.r[j][i]));
        let t = stated::apply(&rt, &self.t);
        IAffine { r: rt, t: t.map(|x| -x) }
    }

    pub(crate) fn fast(&self) -> Affine {
        Affine { r: self.r.map(|row| row.map(Iv::from)), t: self.t.map(Iv::from) }
    }

    fn mid(&self) -> Pose64 {
        Pose64 { r: self.r.map(|row| row.map(|x| x.mid())), t: self.t.map(|x| x.mid()) }
    }
}

/// Product skipping exact zeros and using `scale` for point factors (tighter, and exact zeros stay exact).
#[inline(always)]
pub(crate) fn mul(a: Iv, b: Iv) -> Iv {
    if a == Iv::ZERO || b == Iv::ZERO {
        Iv::ZERO
    } else if a.lo == a.hi {
        b.scale(a.lo)
    } else if b.lo == b.hi {
        a.scale(b.lo)
    } else {
        a.mul(b)
    }
}

/// Sum skipping exact zeros.
#[inline(always)]
pub(crate) fn add(a: Iv, b: Iv) -> Iv {
    if a == Iv::ZERO {
        b
    } else if b == Iv::ZERO {
        a
    } else {
        a.add(b)
    }
}

// The hot loops below fill arrays by index rather than through `array::map`, whose closures
// the optimiser left as calls (a third of the IK search's time); the arithmetic is the same.

#[inline(always)]
pub(crate) fn mv(a: &M, v: &V) -> V {
    let mut out = [Iv::ZERO; 3];
    for i in 0..3 {
        out[i] = add(add(mul(a[i][0], v[0]), mul(a[i][1], v[1])), mul(a[i][2], v[2]));
    }
    out
}

#[inline(always)]
pub(crate) fn mm(a: &M, b: &M) -> M {
    let mut out = [[Iv::ZERO; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = add(add(mul(a[i][0], b[0][j]), mul(a[i][1], b[1][j])), mul(a[i][2], b[2][j]));
        }
    }
    out
}

#[inline(always)]
pub(crate) fn cross(a: &V, b: &V) -> V {
    [
        mul(a[1], b[2]).sub(mul(a[2], b[1])),
        mul(a[2], b[0]).sub(mul(a[0], b[2])),
        mul(a[0], b[1]).sub(mul(a[1], b[0])),
    ]
}

#[inline(always)]
pub(crate) fn compose(a: &Affine, b: &Affine) -> Affine {
    let mut t = mv(&a.r, &b.t);
    for i in 0..3 {
        t[i] = add(t[i], a.t[i]);
    }
    Affine { r: mm(&a.r, &b.r), t }
}

/// `A + c·B + s·C`: a joint rotation followed by a constant map (see the module doc).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    a: Affine,
    b: Affine,
    c: Affine,
}

impl Block {
    /// `R(σθ)·next` for the unit axis `axis`, σ = ±1.
    fn new(axis: &[Interval; 3], sign: f64, next: &IAffine) -> Block {
        let z = point(0.0);
        let p = [0, 1, 2].map(|i| [0, 1, 2].map(|j| axis[i] * axis[j]));
        let q = [0, 1, 2].map(|i| [0, 1, 2].map(|j| if i == j { point(1.0) - p[i][j] } else { -p[i][j] }));
        let s = [[z, -axis[2], axis[1]], [axis[2], z, -axis[0]], [-axis[1], axis[0], z]].map(|row| row.map(|x| x * point(sign)));
        let part = |m: [[Interval; 3]; 3]| IAffine { r: stated::mul(&m, &next.r), t: stated::apply(&m, &next.t) }.fast();
        Block { a: part(p), b: part(q), c: part(s) }
    }

    #[inline(always)]
    pub(crate) fn at(&self, c: Iv, s: Iv) -> Affine {
        #[inline(always)]
        fn e(a: Iv, b: Iv, x: Iv, c: Iv, s: Iv) -> Iv {
            add(add(a, mul(c, b)), mul(s, x))
        }
        let mut out = Affine { r: [[Iv::ZERO; 3]; 3], t: [Iv::ZERO; 3] };
        for i in 0..3 {
            for j in 0..3 {
                out.r[i][j] = e(self.a.r[i][j], self.b.r[i][j], self.c.r[i][j], c, s);
            }
            out.t[i] = e(self.a.t[i], self.b.t[i], self.c.t[i], c, s);
        }
        out
    }
}

/// A constant map followed by `N` blocks: one side of an equation, or the whole arm.
#[derive(Clone, Debug)]
pub(crate) struct Side<const N: usize> {
    pub k0: Affine,
    pub blocks: [Block; N],
    /// Each block's axis in the frame before it.
    pub axes: [V; N],
}

impl<const N: usize> Side<N> {
    /// The frames before each block and the end map: `frames[N]` is the side's value.
    #[inline]
    pub(crate) fn frames(&self, cs: &[(Iv, Iv); N]) -> [Affine; 7] {
        let mut out = [self.k0; 7];
        for k in 0..N {
            out[k + 1] = compose(&out[k], &self.blocks[k].at(cs[k].0, cs[k].1));
        }
        out
    }

    /// The rotation axis (direction, a point on it) of block `k` given the frames.
    #[inline(always)]
    pub(crate) fn axis(&self, frames: &[Affine], k: usize) -> (V, V) {
        (mv(&frames[k].r, &self.axes[k]), frames[k].t)
    }
}

/// Sound cos and sin of an angle interval.
#[inline]
pub(crate) fn cos_sin(lo: f64, hi: f64) -> (Iv, Iv) {
    let x = crate::kernel::interval::interval(lo, hi);
    (Iv::from(trig::cos(x)), Iv::from(trig::sin(x)))
}

/// The six revolute joints of an arm with interval coefficients (see the module doc).
#[derive(Clone, Debug)]
pub struct Chain6R {
    /// Base link.
    pub base: String,
    /// Tip link.
    pub tip: String,
    /// The joints, base first.
    pub joints: [String; 6],
    /// The range searched per joint: its limits, or [−π, π] (outward) when continuous.
    pub ranges: [(f64, f64); 6],
    /// Continuous joints (their range closes on itself).
    pub continuous: [bool; 6],
    pub(crate) pre: [IAffine; 6],
    pub(crate) post: IAffine,
    pub(crate) axes: [[Interval; 3]; 6],
}

impl Chain6R {
    /// The near-degeneracies of consecutive axes (nearly parallel, perpendicular or meeting
    /// without being exactly so), in the words the 3R verdicts use: each pair measured in the
    /// frame of its first joint, where it does not depend on the joint angles.
    pub fn near_degeneracies(&self) -> Vec<String> {
        let pairs = (0..5).map(|k| {
            let next = stated::apply(&self.pre[k + 1].r, &self.axes[k + 1]);
            (format!("axes of {} and {}", self.joints[k], self.joints[k + 1]), [point(0.0); 3], self.axes[k], self.pre[k + 1].t, next)
        });
        crate::analyses::arm3r::verdict::near_axis_pairs(pairs)
    }

    /// The chain from `base` (default: the root) to `tip` (default: the end link of the
    /// revolute path, followed down a single line of fixed joints), which must hold exactly six
    /// revolute joints and otherwise only fixed ones.
    pub fn from_mechanism(m: &Mechanism, base: Option<&str>, tip: Option<&str>) -> Result<Chain6R, Manip6rError> {
        Self::holding(m, base, tip, &[])
    }

    /// `from_mechanism` with the revolute joints of `held` held at their values (radians): each
    /// becomes part of the fixed transform between its neighbours, so a seven-joint arm with one
    /// joint held is a six-joint arm.
    pub fn holding(m: &Mechanism, base: Option<&str>, tip: Option<&str>, held: &[(String, f64)]) -> Result<Chain6R, Manip6rError> {
        for (name, value) in held {
            let j = m.joint(name).ok_or_else(|| Manip6rError::NotSixR(format!("--fix: '{name}' is not a joint of the file")))?;
            let JointKind::Revolute { limits } = m.joints[j].kind else {
                return Err(Manip6rError::NotSixR(format!("--fix: joint '{name}' is not revolute")));
            };
            if !value.is_finite() || limits.is_some_and(|(lo, hi)| *value < lo || *value > hi) {
                return Err(Manip6rError::NotSixR(format!("--fix: {name}={value} is not a finite value within its limits")));
            }
        }
        let held: Vec<(String, Interval)> = held.iter().map(|(n, v)| (n.clone(), crate::formulate::angles::stated(*v))).collect();
        Self::holding_over(m, base, tip, &held)
    }

    /// As `holding`, each held joint over a range of angles: the chain's coefficients enclose
    /// their values over every angle of it, so a box certified on this chain holds exactly one
    /// solution for every held angle in the range (the parametric form of Krawczyk's test).
    pub(crate) fn holding_over(m: &Mechanism, base: Option<&str>, tip: Option<&str>, held: &[(String, Interval)]) -> Result<Chain6R, Manip6rError> {
        let held_at = |j: usize| held.iter().find(|(n, _)| *n == m.joints[j].name).map(|(_, v)| *v);
        if !m.loops.is_empty() {
            return Err(Manip6rError::NotSixR("the mechanism has loop closures".into()));
        }
        let find = |name: &str| m.link(name).ok_or_else(|| Manip6rError::NotSixR(format!("'{name}' is not a link of the file")));
        let base = match base {
            Some(b) => find(b)?,
            None => m.root,
        };
        let revolute = |j: usize| matches!(m.joints[j].kind, JointKind::Revolute { .. }) && held_at(j).is_none();
        let below = |l: usize| -> Option<Vec<usize>> {
            let full = m.path_to(l);
            if l == base {
                return Some(Vec::new());
            }
            if base == m.root {
                return Some(full);
            }
            full.iter().position(|&j| m.joints[j].parent == base).map(|k| full[k..].to_vec())
        };
        let tip = match tip {
            Some(t) => find(t)?,
            None => {
                let count = |l: usize| below(l).map(|p| p.iter().filter(|&&j| revolute(j)).count());
                let ends: Vec<usize> = (0..m.links.len()).filter(|&l| m.links[l].parent_joint.is_some_and(revolute) && count(l) == Some(6)).collect();
                let [t] = ends.as_slice() else {
                    return Err(Manip6rError::NotSixR(format!("{} links end a path of six revolute joints: choose the tip", ends.len())));
                };
                let mut at = *t;
                loop {
                    let kids: Vec<usize> = m.joints.iter().filter(|j| j.parent == at).map(|j| j.child).collect();
                    match kids.as_slice() {
                        [c] if matches!(m.joints[m.links[*c].parent_joint.expect("invariant: a child has a parent joint")].kind, JointKind::Fixed) => at = *c,
                        _ => break at,
                    }
                }
            }
        };
        let path = below(tip).ok_or_else(|| Manip6rError::NotSixR(format!("'{}' is not below '{}'", m.links[tip].name, m.links[base].name)))?;
        if let Some((name, _)) = held.iter().find(|(n, _)| !path.iter().any(|&j| m.joints[j].name == *n)) {
            return Err(Manip6rError::NotSixR(format!("--fix: joint '{name}' is not on the chain from '{}' to '{}'", m.links[base].name, m.links[tip].name)));
        }
        let mut pre = Vec::new();
        let mut names = Vec::new();
        let mut ranges = Vec::new();
        let mut continuous = Vec::new();
        let mut axes = Vec::new();
        let mut acc = IAffine::identity();
        for &j in &path {
            let joint = &m.joints[j];
            let origin = IAffine {
                r: match joint.exact_rotation {
                    Some(r) => r.map(|row| row.map(point)),
                    None => stated::rpy(joint.rpy),
                },
                t: stated::translation(&joint.origin.translation.vector),
            };
            acc = acc.then(&origin);
            match (joint.kind, held_at(j)) {
                (JointKind::Fixed, _) => {}
                (JointKind::Revolute { .. }, Some(range)) => acc = acc.then(&IAffine { r: stated::about_axis_over(&stated::axis(&joint.axis), range), t: [point(0.0); 3] }),
                (JointKind::Revolute { limits }, None) => {
                    if joint.mimic.is_some() {
                        return Err(Manip6rError::NotSixR(format!("joint '{}' follows another through <mimic>", joint.name)));
                    }
                    pre.push(acc);
                    acc = IAffine::identity();
                    names.push(joint.name.clone());
                    continuous.push(limits.is_none());
                    ranges.push(limits.unwrap_or((-crate::analyses::arm3r::PI_UP, crate::analyses::arm3r::PI_UP)));
                    axes.push(stated::axis(&joint.axis));
                }
                _ => return Err(Manip6rError::NotSixR(format!("joint '{}' is neither revolute nor fixed", joint.name))),
            }
        }
        if pre.len() != 6 {
            return Err(Manip6rError::NotSixR(format!("the chain from '{}' to '{}' has {} revolute joints", m.links[base].name, m.links[tip].name, pre.len())));
        }
        Ok(Chain6R {
            base: m.links[base].name.clone(),
            tip: m.links[tip].name.clone(),
            joints: six(names)?,
            ranges: six(ranges)?,
            continuous: six(continuous)?,
            pre: six(pre)?,
            post: acc,
            axes: six(axes)?,
        })
    }

    /// The same chain with the file's joint limits set aside: every joint continuous over
    /// [−π, π] (outward), so the analysis covers the whole torus.
    pub fn without_limits(mut self) -> Chain6R {
        let pi = crate::analyses::arm3r::PI_UP;
        self.ranges = [(-pi, pi); 6];
        self.continuous = [true; 6];
        self
    }

    /// The same chain searched over one turn per joint: each range cut to [−π, π] (a joint
    /// whose limits span more than a turn then covers the whole circle once, and its solutions
    /// are configurations rather than joint vectors).
    pub fn within_one_turn(mut self) -> Chain6R {
        let pi = crate::analyses::arm3r::PI_UP;
        for k in 0..6 {
            let (lo, hi) = self.ranges[k];
            if hi - lo >= std::f64::consts::TAU {
                self.continuous[k] = true;
            }
            self.ranges[k] = (lo.max(-pi), hi.min(pi));
        }
        self
    }

    /// The whole arm as one side: `Pre₁·R₁·Pre₂···R₆·Post` (frames 0..5 are the joint frames).
    pub(crate) fn arm(&self) -> Side<6> {
        let next = |k: usize| if k < 5 { self.pre[k + 1] } else { self.post };
        Side {
            k0: self.pre[0].fast(),
            blocks: [0, 1, 2, 3, 4, 5].map(|k| Block::new(&self.axes[k], 1.0, &next(k))),
            axes: self.axes.map(|a| a.map(Iv::from)),
        }
    }

    /// The two sides of the equation split after joint `f` (0, 1 or 2), joints `f+1..f+3` on
    /// the left: `Pre_{f+1}R_{f+1}···R_{f+3}Pre_{f+4}` equals the rest moved to the other side
    /// (rotations by −θ, inverses of the constant maps, `G = target·Post⁻¹`). For `f = 0`:
    /// `Pre₁R₁Pre₂R₂Pre₃R₃Pre₄ = G·R₆(−θ₆)Pre₆⁻¹·R₅(−θ₅)Pre₅⁻¹·R₄(−θ₄)`. Returns the sides and
    /// the joint of each block (left, then right in block order).
    pub(crate) fn split(&self, target: &IAffine, f: usize) -> (Side<3>, Side<3>, [usize; 3], [usize; 3]) {
        let lv = [f, f + 1, f + 2];
        let rv = [(f + 5) % 6, (f + 4) % 6, (f + 3) % 6];
        let left = Side {
            k0: self.pre[f].fast(),
            blocks: lv.map(|k| Block::new(&self.axes[k], 1.0, &self.pre[k + 1])),
            axes: lv.map(|k| self.axes[k].map(Iv::from)),
        };
        let g = target.then(&self.post.inverse());
        let next = |b: usize, j: usize| match (b, j) {
            (2, _) => IAffine::identity(),
            (_, 0) => self.pre[0].inverse().then(&g),
            _ => self.pre[j].inverse(),
        };
        let right = Side {
            k0: if f == 0 { g.fast() } else { IAffine::identity().fast() },
            blocks: [0, 1, 2].map(|b| Block::new(&self.axes[rv[b]], -1.0, &next(b, rv[b]))),
            axes: rv.map(|k| self.axes[k].map(Iv::from)),
        };
        (left, right, lv, rv)
    }

    /// The tip pose at `q` in `f64` (from the midpoints of the coefficients).
    pub fn pose(&self, q: &[f64; 6]) -> Pose64 {
        let mut p = Pose64::IDENTITY;
        for k in 0..6 {
            p = p.then(&self.pre[k].mid()).then(&rotation64(&self.axes[k].map(|x| x.mid()), q[k]));
        }
        p.then(&self.post.mid())
    }

    /// Each joint's axis at `q` in `f64`, base frame: (unit direction, a point on it).
    pub fn joint_axes(&self, q: &[f64; 6]) -> [([f64; 3], [f64; 3]); 6] {
        let mut p = Pose64::IDENTITY;
        let mut out = [([0.0; 3], [0.0; 3]); 6];
        for k in 0..6 {
            p = p.then(&self.pre[k].mid());
            let a = self.axes[k].map(|x| x.mid());
            out[k] = ([0, 1, 2].map(|i| (0..3).map(|j| p.r[i][j] * a[j]).sum()), p.t);
            p = p.then(&rotation64(&a, q[k]));
        }
        out
    }

    /// The spatial Jacobian at `q` in `f64`: column k is `(ωₖ, pₖ × ωₖ)` for joint k's axis
    /// direction ωₖ through the point pₖ, in the base frame.
    pub fn jacobian(&self, q: &[f64; 6]) -> [[f64; 6]; 6] {
        let mut p = Pose64::IDENTITY;
        let mut jac = [[0.0; 6]; 6];
        for k in 0..6 {
            p = p.then(&self.pre[k].mid());
            let a = self.axes[k].map(|x| x.mid());
            let w: [f64; 3] = [0, 1, 2].map(|i| (0..3).map(|j| p.r[i][j] * a[j]).sum());
            let o = p.t;
            let v = [o[1] * w[2] - o[2] * w[1], o[2] * w[0] - o[0] * w[2], o[0] * w[1] - o[1] * w[0]];
            for i in 0..3 {
                jac[i][k] = w[i];
                jac[i + 3][k] = v[i];
            }
            p = p.then(&rotation64(&a, q[k]));
        }
        jac
    }

    /// det of `jacobian(q)`: zero exactly at the singular configurations.
    pub fn det_jacobian(&self, q: &[f64; 6]) -> f64 {
        nalgebra::Matrix6::from_fn(|i, j| self.jacobian(q)[i][j]).determinant()
    }
}

fn six<T: std::fmt::Debug>(v: Vec<T>) -> Result<[T; 6], Manip6rError> {
    v.try_into().map_err(|v: Vec<T>| Manip6rError::NotSixR(format!("{} revolute joints", v.len())))
}

/// The rotation by `t` about the unit axis `a`.
pub(crate) fn rotation64(a: &[f64; 3], t: f64) -> Pose64 {
    let (s, c) = t.sin_cos();
    let mut r = [[0.0; 3]; 3];
    let sk = [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            r[i][j] = a[i] * a[j] + c * (id - a[i] * a[j]) + s * sk[i][j];
        }
    }
    Pose64 { r, t: [0.0; 3] }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The UR5 as written: axes 1 and 2 are 3.2e-10 rad off perpendicular (its π/2 is written
    /// to nine decimals), and turning joint 3's frame by 4e-3 rad about x makes axes 2 and 3 nearly
    /// parallel; an exactly perpendicular or parallel pair is not named.
    #[test]
    fn near_degenerate_axes_are_named_with_their_bound() {
        let xml = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/ur5.urdf")).expect("bundled");
        let near = |xml: &str| Chain6R::from_mechanism(&crate::model::urdf::parse(xml).expect("parses"), None, None).expect("six joints").near_degeneracies();
        let as_written = near(&xml);
        assert!(as_written.iter().any(|n| n.starts_with("axes of joint_1 and joint_2 within") && n.ends_with("rad of perpendicular")), "{as_written:?}");
        assert!(!as_written.iter().any(|n| n.contains("joint_2 and joint_3")), "{as_written:?}");
        let joint3 = xml.find("<joint name=\"joint_3\"").expect("joint_3");
        let origin = joint3 + xml[joint3..].find("rpy=\"0 0 0\"").expect("joint_3's rpy");
        let tilted = format!("{}rpy=\"0.004 0 0\"{}", &xml[..origin], &xml[origin + "rpy=\"0 0 0\"".len()..]);
        let found = near(&tilted);
        assert!(found.iter().any(|n| n == "axes of joint_2 and joint_3 within 4.0e-3 rad of parallel"), "{found:?}");
    }

    /// Test idea: a seven-joint arm with one joint held is the six-joint arm whose tip pose at
    /// the six free values is the seven-joint pose at those values and the held one (forward
    /// kinematics of the file's joints in f64, written out here without the chain's code), and
    /// its coefficients enclose the exact held rotation (the pose agrees to rounding).
    #[test]
    fn a_held_joint_folds_into_the_fixed_transforms() {
        let xml = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/iiwa14.urdf")).expect("bundled");
        let m = crate::model::urdf::parse(&xml).expect("parses");
        let held = 0.3;
        let chain = Chain6R::holding(&m, None, None, &[("joint_3".into(), held)]).expect("six remain");
        assert_eq!(chain.joints, ["joint_1", "joint_2", "joint_4", "joint_5", "joint_6", "joint_7"].map(String::from));
        let q6 = [0.4, -0.7, 1.1, 0.2, -0.5, 0.9];
        let tip = m.link(&chain.tip).expect("tip");
        let mut free = q6.iter();
        let mut reference = Pose64::IDENTITY;
        for j in m.path_to(tip) {
            let joint = &m.joints[j];
            let o = joint.origin.translation.vector;
            reference = reference.then(&Pose64::from_xyz_rpy([o[0], o[1], o[2], joint.rpy[0], joint.rpy[1], joint.rpy[2]]));
            if let JointKind::Revolute { .. } = joint.kind {
                let q = if joint.name == "joint_3" { held } else { *free.next().expect("six free values") };
                reference = reference.then(&rotation64(&[joint.axis[0], joint.axis[1], joint.axis[2]], q));
            }
        }
        assert!(chain.pose(&q6).distance(&reference) < 1e-12, "{:?} vs {reference:?}", chain.pose(&q6));
        for bad in [("joint_9", 0.0), ("joint_3", f64::NAN), ("joint_3", 10.0)] {
            assert!(Chain6R::holding(&m, None, None, &[(bad.0.into(), bad.1)]).is_err(), "{bad:?}");
        }
    }
}

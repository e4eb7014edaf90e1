//! Parallel platforms with six legs fixed (Stewart–Gough 6-6, or any six legs), in pose
//! coordinates: the platform's position `t` and rotation `R` in the base frame are the unknowns.
//!
//! The mechanism is read as `platform` reads it (a floating platform, legs of a base ball joint, a
//! prismatic joint and a spherical loop onto the platform). With `b_i` the base ball centre of
//! leg i, `p_i` its platform ball centre (platform frame) and `L_i` its length,
//! `|t + R p_i − b_i|² = L_i²` expands to
//!
//! `s + 2 p_i·w − 2 b_i·t − 2 b_iᵀ R p_i = L_i² − |p_i|² − |b_i|²`, with `w = Rᵀt`, `s = |t|²`,
//!
//! a row LINEAR in `(s, w, t, R)`: the LP relaxation uses all six leg rows and their
//! differences directly. `R`'s first two columns `a`, `b` are the primaries with `t`; the third
//! column `c = a×b`, the products `tᵢ·Rᵢⱼ` and `aᵢ·bⱼ`, `w` and `s` are derived, each by one
//! bilinear or linear row (so the LP's McCormick cuts see them), with `|a|² = |b|² = 1` and
//! `a·b = 0`. That system is square (one row per variable), which Krawczyk certifies. The
//! redundant rows `|c|² = 1`, `a·c = b·c = 0` and `RRᵀ = I` (`PoseRows::Redundant`) save boxes
//! but cost more than they save; with them, Krawczyk runs on the square rows alone.
//!
//! Every coefficient encloses the stated model: ball centres and axes through `stated`, leg
//! values as stated decimals (`angles::stated`), outward-rounded interval arithmetic.

use super::angles::{angle_interval, stated};
use super::platform::{read_legs, PlatformError};
use super::stated::{self as st, IMat3, IVec3};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::model::{JointKind, Mechanism};
use crate::kernel::search::{contractor_with_newton_on, SolveError, Solver, SolverSettings};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// Which rows beyond the square system are written. The square system alone is the faster
/// (README: 2.7x less CPU on the Stewart references, for the same certified assemblies).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PoseRows {
    /// The square system only.
    #[default]
    Square,
    /// Plus `|c|² = 1`, `a·c = b·c = 0` and the rows of `RRᵀ = I`: fewer boxes, each dearer.
    Redundant,
}

/// One leg in pose coordinates.
#[derive(Clone, Debug)]
pub struct PoseLeg {
    /// Name of the prismatic joint.
    pub name: String,
    /// Base ball centre, base frame.
    pub base: IVec3,
    /// Platform ball centre, platform frame.
    pub top: IVec3,
    /// Squared ball-to-ball length for the fixed value.
    pub squared: Interval,
}

/// A six-legged platform with its legs fixed, as an `EquationSystem` in pose coordinates.
#[derive(Clone, Debug)]
pub struct PoseProblem {
    /// The robot's name.
    pub name: String,
    /// Name of the platform link.
    pub platform: String,
    /// Name of the floating joint: the joint values are `NAME.x`, ..., `NAME.yaw`.
    pub floating: String,
    /// The legs, in file order.
    pub legs: Vec<PoseLeg>,
    /// Joint values as given (`--fix`).
    pub fixed: Vec<(String, f64)>,
    /// The system: every row.
    pub system: EquationSystem,
    /// The square rows over the same variables (Krawczyk's).
    square: EquationSystem,
    /// Position variables.
    pub t: [VarId; 3],
    /// Rotation variables, `r[i][j]` = `R_ij` (column j is the platform's axis j).
    pub r: [[VarId; 3]; 3],
    /// Free joints, as reported: the floating joint's position and roll, pitch, yaw.
    pub free_joints: Vec<String>,
    /// The base's frame in the root frame, when fixed joints hold it below the root.
    base_in_root: Option<Box<(IMat3, IVec3)>>,
}

/// Linear forms and products, written into a system.
struct Rows {
    system: EquationSystem,
    square: Vec<Equation>,
    products: BTreeMap<(VarId, VarId), VarId>,
}

impl Rows {
    /// The derived variable `x·y` (one bilinear row), shared between rows.
    fn product(&mut self, x: VarId, y: VarId) -> VarId {
        let key = (x.min(y), x.max(y));
        if let Some(&z) = self.products.get(&key) {
            return z;
        }
        let (nx, ny) = (self.system.vars[x].name.clone(), self.system.vars[y].name.clone());
        let dom = self.system.vars[x].domain * self.system.vars[y].domain;
        let z = self.system.add_var(format!("{nx}*{ny}"), VarRole::Derived, dom);
        self.square(Equation::bilinear(z, x, y));
        self.products.insert(key, z);
        z
    }

    /// A row of the square system.
    fn square(&mut self, e: Equation) {
        self.square.push(e.clone());
        self.system.add(e);
    }

    /// A redundant row (not in the square system).
    fn redundant(&mut self, e: Equation) {
        self.system.add(e);
    }
}

fn linear(terms: &[(VarId, Interval)], constant: Interval) -> Equation {
    let mut merged: BTreeMap<VarId, Interval> = BTreeMap::new();
    for &(v, c) in terms {
        *merged.entry(v).or_insert(point(0.0)) += c;
    }
    Equation::new(merged.into_iter().map(|(v, c)| Term { coef: c, mono: Monomial::Linear(v) }).collect(), constant)
}

fn norm2(v: &IVec3) -> Interval {
    v[0].sqr() + v[1].sqr() + v[2].sqr()
}

/// A platform on six legs, each fixed: what the pose and the distance builders read.
pub(crate) struct SixLegs {
    /// Index of the platform link.
    pub platform: usize,
    /// Name of the floating joint carrying the platform.
    pub floating: String,
    /// The legs, in file order.
    pub legs: Vec<PoseLeg>,
    /// The base's frame in the root frame when a fixed joint holds the base below the root
    /// (poses are solved in the base's frame and reported in the root's).
    pub base_in_root: Option<(IMat3, IVec3)>,
}

/// Reads the six legs of `m`'s platform with their values from `fixed` (as for `solve --fix`:
/// the prismatic joint's travel, metres); `model` names the builder in refusals.
pub(crate) fn six_legs(m: &Mechanism, fixed: &[(String, f64)], model: &str) -> Result<SixLegs, PlatformError> {
    let (base, platform, read) = read_legs(m)?;
    if read.len() != 6 {
        return Err(PlatformError::Unsupported(format!("{} legs: {model} takes six", read.len())));
    }
    let floating = m.joints.iter().find(|j| j.kind == JointKind::Floating && j.child == platform).map(|j| j.name.clone()).unwrap_or_default();
    let mut legs = Vec::new();
    for leg in &read {
        let joint = &m.joints[leg.joint];
        // The last value given counts, as for the other builders.
        let value = fixed.iter().rev().find(|(n, _)| *n == leg.name).map(|&(_, v)| v).ok_or_else(|| PlatformError::NotFixed(leg.name.clone()))?;
        if !value.is_finite() {
            return Err(PlatformError::NotFinite(leg.name.clone()));
        }
        if let JointKind::Prismatic { limits: (lower, upper) } = joint.kind {
            if value < lower || value > upper {
                return Err(PlatformError::OutsideLimits { leg: leg.name.clone(), value, lower, upper });
            }
        }
        // The rod's ball in the cylinder frame: o.t + o.R·(q·axis + on_rod) = u + q·d.
        let rot = match joint.exact_rotation {
            Some(r) => r.map(|row| row.map(point)),
            None => st::rpy(joint.rpy),
        };
        let u = {
            let on_rod = st::apply(&rot, &st::translation(&leg.on_rod));
            let o = st::translation(&joint.origin.translation.vector);
            [0, 1, 2].map(|i| o[i] + on_rod[i])
        };
        let d = st::apply(&rot, &st::axis(&joint.axis));
        let q = stated(value);
        let top_in_cylinder: IVec3 = [0, 1, 2].map(|i| u[i] + q * d[i]);
        // A ball on a link fixed below the base: its centre carried into the base's frame.
        let centre = st::translation(&leg.base);
        let in_base = if leg.mount == base {
            centre
        } else {
            let (r, p) = st::placement(m, base, leg.mount);
            let turned = st::apply(&r, &centre);
            [0, 1, 2].map(|i| p[i] + turned[i])
        };
        legs.push(PoseLeg { name: leg.name.clone(), base: in_base, top: st::translation(&leg.on_platform), squared: norm2(&top_in_cylinder) });
    }
    for (name, _) in fixed {
        if !legs.iter().any(|l| l.name == *name) {
            return Err(PlatformError::UnknownLeg(name.clone()));
        }
    }
    let base_in_root = (base != m.root).then(|| st::placement(m, m.root, base));
    Ok(SixLegs { platform, floating, legs, base_in_root })
}

impl PoseProblem {
    /// Reads the platform of `m` with every leg fixed by `fixed` (leg name, its value as for
    /// `solve --fix`: the prismatic joint's travel, metres), the square system alone.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)]) -> Result<Self, PlatformError> {
        Self::with_rows(m, fixed, PoseRows::default())
    }

    /// As `new`, with the rows `rows` says.
    pub fn with_rows(m: &Mechanism, fixed: &[(String, f64)], rows: PoseRows) -> Result<Self, PlatformError> {
        let SixLegs { platform, floating, legs, base_in_root } = six_legs(m, fixed, "the pose model")?;
        let mut w = Rows { system: EquationSystem::default(), square: Vec::new(), products: BTreeMap::new() };
        // t lies within reach of every base ball: |t − b_i| ≤ L_i + |p_i|.
        let mut tdom = [Interval::ENTIRE; 3];
        for leg in &legs {
            let reach = (leg.squared.sqrt() + norm2(&leg.top).sqrt()).sup();
            for (k, dom) in tdom.iter_mut().enumerate() {
                *dom = dom.intersection(leg.base[k] + interval(-reach, reach));
            }
        }
        if tdom.iter().any(|d| d.is_empty()) {
            return Err(PlatformError::NotAPlatform("the legs cannot reach a common platform position".into()));
        }
        let t = [0, 1, 2].map(|k| w.system.add_var(format!("t{}", ["x", "y", "z"][k]), VarRole::Primary, tdom[k]));
        let unit = interval(-1.0, 1.0);
        let mut r = [[0; 3]; 3];
        for j in 0..3 {
            for (i, row) in r.iter_mut().enumerate() {
                let role = if j < 2 { VarRole::Primary } else { VarRole::Derived };
                row[j] = w.system.add_var(format!("R{}{}", i + 1, j + 1), role, unit);
            }
        }
        let col = |j: usize| [r[0][j], r[1][j], r[2][j]];
        let (a, b, c) = (col(0), col(1), col(2));
        let (one, zero) = (point(1.0), point(0.0));
        // c = a × b.
        for (i, &ci) in c.iter().enumerate() {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = w.product(a[j], b[k]);
            let n = w.product(a[k], b[j]);
            w.square(linear(&[(ci, one), (p, -one), (n, one)], zero));
        }
        // |a|² = |b|² = 1, a·b = 0.
        let sq = |v: [VarId; 3]| Equation::new(v.iter().map(|&x| Term { coef: one, mono: Monomial::Square(x) }).collect(), -one);
        w.square(sq(a));
        w.square(sq(b));
        let ab: Vec<(VarId, Interval)> = (0..3).map(|i| (w.product(a[i], b[i]), one)).collect();
        w.square(linear(&ab, zero));
        // w = Rᵀt, s = |t|².
        let reach = tdom.iter().map(|d| d.mag()).fold(0.0, |acc: f64, m| acc + m * m).sqrt() * (1.0 + 1e-12);
        let wv = ["x", "y", "z"].map(|a| w.system.add_var(format!("w{a}"), VarRole::Derived, interval(-reach, reach)));
        for (j, &wj) in wv.iter().enumerate() {
            let mut terms = vec![(wj, one)];
            for (&ti, row) in t.iter().zip(&r) {
                terms.push((w.product(ti, row[j]), -one));
            }
            w.square(linear(&terms, zero));
        }
        let s = w.system.add_var("s", VarRole::Derived, tdom.iter().fold(zero, |acc, d| acc + d.sqr()));
        let mut terms: Vec<Term> = t.iter().map(|&x| Term { coef: -one, mono: Monomial::Square(x) }).collect();
        terms.push(Term { coef: one, mono: Monomial::Linear(s) });
        w.square(Equation::new(terms, zero));
        // The legs: s + 2 p·w − 2 b·t − 2 bᵀRp = L² − |p|² − |b|².
        let two = point(2.0);
        for leg in &legs {
            let mut terms = vec![(s, one)];
            for (&wj, &pj) in wv.iter().zip(&leg.top) {
                terms.push((wj, two * pj));
            }
            for (&ti, &bi) in t.iter().zip(&leg.base) {
                terms.push((ti, -two * bi));
            }
            for (i, row) in r.iter().enumerate() {
                for (j, &x) in row.iter().enumerate() {
                    terms.push((x, -two * leg.base[i] * leg.top[j]));
                }
            }
            w.square(linear(&terms, norm2(&leg.top) + norm2(&leg.base) - leg.squared));
        }
        if rows == PoseRows::Redundant {
            // |c|² = 1, a·c = b·c = 0.
            w.redundant(sq(c));
            for u in [a, b] {
                let uc: Vec<(VarId, Interval)> = (0..3).map(|i| (w.product(u[i], c[i]), one)).collect();
                w.redundant(linear(&uc, zero));
            }
            // Rows of R: unit and orthogonal.
            for (i, row) in r.iter().enumerate() {
                w.redundant(sq(*row));
                for other in &r[i + 1..] {
                    let dot: Vec<(VarId, Interval)> = (0..3).map(|j| (w.product(row[j], other[j]), one)).collect();
                    w.redundant(linear(&dot, zero));
                }
            }
        }
        let square = EquationSystem { vars: w.system.vars.clone(), equations: w.square };
        let free_joints = ["x", "y", "z", "roll", "pitch", "yaw"].iter().map(|p| format!("{floating}.{p}")).collect();
        Ok(Self { name: m.name.clone(), platform: m.links[platform].name.clone(), floating, legs, fixed: fixed.to_vec(), system: w.system, square, t, r, free_joints, base_in_root: base_in_root.map(Box::new) })
    }

    /// Whether the square rows alone are the system (no redundant rows).
    pub fn is_square(&self) -> bool {
        self.system.equations.len() == self.system.vars.len()
    }

    /// The solver: propagation, Krawczyk on the square rows once every primary is at most
    /// `settings.newton_width` wide, and the LP shrink over every row.
    pub fn solver<'s>(&'s self, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        let solver = Solver::new(&self.system, settings)?;
        Ok(solver.with_contractor(Box::new(move |system: &'s EquationSystem, settings: &SolverSettings| contractor_with_newton_on(system, &self.square, settings))))
    }

    /// The rotation over the box.
    fn rotation(&self, b: &IntervalBox) -> [[Interval; 3]; 3] {
        self.r.map(|row| row.map(|x| b.dims[x]))
    }

    /// The floating joint's values over the box (`joint_values_of`).
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        joint_values_of(&self.free_joints, self.t.map(|v| b.dims[v]), &self.rotation(b))
    }

    /// The platform's pose at the box midpoint (`pose_of`).
    pub fn pose(&self, b: &IntervalBox) -> super::Pose {
        pose_of(&self.legs, self.t.map(|v| b.dims[v]), &self.rotation(b))
    }

    /// The platform link's pose over the box, as the spatial model reports link poses.
    pub fn link_pose(&self, b: &IntervalBox) -> super::LinkPose {
        link_pose_of(&self.legs, self.t.map(|v| b.dims[v]), &self.rotation(b), self.base_in_root.as_deref())
    }
}

/// The floating joint's values for a platform at position `t` with rotation `r` (enclosures):
/// position (metres) and roll, pitch, yaw (radians, URDF `Rz(yaw)·Ry(pitch)·Rx(roll)` with pitch
/// in [−π/2, π/2]), outward rounded; roll and yaw are the whole turn where `r` reaches pitch ±π/2.
/// `free_joints` names them in that order.
pub(crate) fn joint_values_of(free_joints: &[String], t: [Interval; 3], r: &[[Interval; 3]; 3]) -> BTreeMap<String, (f64, f64)> {
    let cos_pitch = (r[0][0].sqr() + r[1][0].sqr()).sqrt();
    let pitch = angle_interval(cos_pitch, -r[2][0]);
    let pi = std::f64::consts::PI;
    let turn = interval(-pi, pi) + interval(-4e-15, 4e-15);
    let (roll, yaw) = if cos_pitch.inf() > 0.0 { (angle_interval(r[2][2], r[2][1]), angle_interval(r[0][0], r[1][0])) } else { (turn, turn) };
    let values = [t[0], t[1], t[2], roll, pitch, yaw];
    free_joints.iter().zip(values).map(|(n, x)| (n.clone(), (x.inf(), x.sup()))).collect()
}

/// The platform's pose at the midpoint of the enclosures `t`, `r`: the nearest rotation to the
/// midpoint of `r`, the midpoint of `t`, and the largest misfit of a leg's squared length there.
pub(crate) fn pose_of(legs: &[PoseLeg], t: [Interval; 3], r: &[[Interval; 3]; 3]) -> super::Pose {
    let mid = Matrix3::from_fn(|i, j| r[i][j].mid());
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&mid));
    let t = Vector3::new(t[0].mid(), t[1].mid(), t[2].mid());
    let leg_residual = legs
        .iter()
        .map(|l| {
            let p = Vector3::new(l.top[0].mid(), l.top[1].mid(), l.top[2].mid());
            let base = Vector3::new(l.base[0].mid(), l.base[1].mid(), l.base[2].mid());
            ((rot * p + t - base).norm_squared() - l.squared.mid()).abs()
        })
        .fold(0.0, f64::max);
    let (roll, pitch, yaw) = rot.euler_angles();
    super::Pose { position: [t.x, t.y, t.z], quaternion: [rot.w, rot.i, rot.j, rot.k], rpy: [roll, pitch, yaw], leg_residual }
}

/// The platform link's pose for the enclosures `t`, `r`, as the spatial model reports link poses.
///
/// `base_in_root` places the base's frame, in which `t` and `r` are solved, in the root frame.
pub(crate) fn link_pose_of(legs: &[PoseLeg], t: [Interval; 3], r: &[[Interval; 3]; 3], base_in_root: Option<&(IMat3, IVec3)>) -> super::LinkPose {
    let (t, r) = match base_in_root {
        None => (t, *r),
        Some((rotation, origin)) => {
            let moved = st::apply(rotation, &t);
            ([0, 1, 2].map(|i| origin[i] + moved[i]), st::mul(rotation, r))
        }
    };
    let r = &r;
    let pose = pose_of(legs, t, r);
    let width = r.iter().flatten().map(|x| x.wid()).fold(0.0, f64::max);
    super::LinkPose { position: Some(t.map(|x| [x.inf(), x.sup()])), quaternion: Some(pose.quaternion), rotation_width: Some(width) }
}

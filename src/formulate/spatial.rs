//! Spatial linkages: any tree of revolute, prismatic, fixed, spherical and floating joints closed
//! by revolute, prismatic, spherical, fixed, universal and cylindrical loops, as a degree-2
//! system the LP-shrink solver takes unchanged (linear equations, circles `c² + s² = 1`,
//! bilinear definitions `z = x·y`, and a few general quadratics for propagation and Newton).
//!
//! Representation (fewer unknowns than one free frame per body, and no orthogonality equation
//! to write): a joint's motion is its own unknowns — `(c, s)` with a circle for a revolute
//! joint, a travel `d` for a prismatic one, three such pairs (Euler z-y-x, pitch cosine ≥ 0 so
//! that no rotation is counted twice) for a ball or floating joint, plus three coordinates for
//! a floating one. Each rigid group's rotation is a 3×3 matrix of linear forms in variables:
//! constant for the ground and the links welded to it, linear in `(c, s)` for a group hung on a
//! known frame by a revolute joint, and one level deeper for each further joint, where the
//! product of a rotation entry and `c` or `s` is a derived variable with a bilinear definition
//! (entries with several terms are first named by a derived variable with a linear equation).
//! Every product of rotations is then a rotation by construction: no unit-norm or
//! orthogonality equation is needed.
//!
//! Positions are sums of `G·v` (group rotation times a constant vector) and linear parts, so
//! loop closures are linear equations in these variables: points coincide (3 rows), axes
//! coincide (3 rows), welded or sliding rotations agree on two columns (6 rows), universal
//! axes stay perpendicular (one bilinear row).
//!
//! A link between two ball joints (a rod hung on a spherical tree joint and closed by one
//! spherical loop, or such a leg with a prismatic joint between its two balls) spins freely
//! about the line of its balls: it gets no rotation at all and becomes a distance constraint
//! between its two ball centres, `|B − A|² = L²`, expanded with `|G·v|² = |v|²` for each
//! rotation (exact on the solutions, where every `G` is a rotation), so that a leg whose one
//! end is on the ground is linear in the rotation variables of the other end.
//!
//! Every coefficient encloses its value in the stated model (`stated`): parsed decimals widened
//! by an ulp, rotations through sound interval trigonometry. No non-zero term is dropped.
//! Builds only; solving is `search`'s job.


mod build;
mod builder;
mod forms;
mod legs;

use self::builder::AxisPair;
use self::forms::{Form, Pos, RotF};
use super::angles::{self, against_limits, wrap};
use super::linkage::LinkageError;
use super::stated::{self as st, IMat3, IVec3};
use crate::kernel::contract::{Filtered, Inclusion};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::model::{JointKind, Mechanism};
use crate::kernel::search::{default_contractor, SolveError, Solver, SolverSettings};
use crate::kernel::system::{EquationKind, EquationSystem, Monomial, VarId};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;

/// How a joint's value is read off a box.
#[derive(Clone, Debug)]
enum Reading {
    /// `atan2(s, c)`.
    Angle { c: VarId, s: VarId },
    /// A variable (travel, floating position).
    Var(VarId),
    /// The angle of a revolute (or cylindrical) loop about its axis.
    LoopAngle(usize),
    /// The travel of a prismatic (or cylindrical) loop along its axis.
    LoopTravel(usize),
}

/// A point of a link whose world coordinates are traced.
#[derive(Clone, Debug)]
pub struct Trace3 {
    /// `LINK@X,Y,Z` (or `LINK@X,Y`) as given.
    pub name: String,
    /// World x, y, z variables.
    pub xyz: [VarId; 3],
}

/// Where a link is, as the builder knows it.
#[derive(Clone, Debug)]
struct LinkPlace {
    name: String,
    /// `(group, K)` with the link's rotation `G_group·K`; `None` for a link that spins freely
    /// between two ball joints (its orientation is not determined).
    rotation: Option<(usize, IMat3)>,
    /// Its frame origin; `None` when it depends on an undetermined spin.
    position: Option<Pos>,
}

/// A closure's frames and axes, kept to read its values back.
#[derive(Clone, Debug)]
struct LoopFrames {
    pred: (usize, IMat3),
    succ: (usize, IMat3),
    pred_at: Pos,
    succ_at: Pos,
    axis: IVec3,
    /// Two unit vectors completing `axis` to an orthonormal frame (f64, for read-outs).
    across: [Vector3<f64>; 2],
}

/// A link's pose over a box.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkPose {
    /// Frame origin in the root frame, per coordinate `[lo, hi]`; `None` when it is not
    /// determined (a leg between two ball joints spins freely).
    pub position: Option<[[f64; 2]; 3]>,
    /// `[w, x, y, z]` of the rotation at the box's midpoint (projected onto rotations); `None`
    /// for a link that spins freely between two ball joints.
    pub quaternion: Option<[f64; 4]>,
    /// The largest width of an entry of the rotation matrix over the box: how far the
    /// quaternion may be off.
    pub rotation_width: Option<f64>,
}

/// How a free joint of a spatial linkage moves in the system's unknowns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum JointMotion {
    /// Its own angle, `c = cos θ`, `s = sin θ` (a revolute tree joint, one Euler angle).
    Angle { c: VarId, s: VarId },
    /// Its own variable (a travel, a floating joint's coordinate).
    Var(VarId),
    /// A loop joint: its value is read from the closure frames' relative pose.
    Loop,
}

/// A spatial linkage as a polynomial system, with what is needed to read answers back.
#[derive(Clone, Debug)]
pub struct SpatialProblem {
    /// The system to solve.
    pub system: EquationSystem,
    /// Robot name.
    pub name: String,
    /// Joint values (tree and loop) read from each box, in file order; multi-motion joints get
    /// one entry per motion (`J.yaw`, `J.pitch`, `J.roll`, `J.x`…, `L.travel`).
    pub free_joints: Vec<String>,
    /// Joints fixed by the user, with their values.
    pub fixed_joints: Vec<(String, f64)>,
    /// Traced points.
    pub traces: Vec<Trace3>,
    /// What the builder simplified, one line each (legs reduced to distances).
    pub reductions: Vec<String>,
    groups: Vec<RotF>,
    links: Vec<LinkPlace>,
    loops: Vec<Option<LoopFrames>>,
    readings: Vec<(String, Reading)>,
    limits: Vec<(usize, Interval, Interval)>,
    /// Axis closures written with two of their three rows: the third component of both axes,
    /// which must agree in sign (see `axes_agree`).
    signs: Vec<(Form, Form)>,
    /// The same closures, for their velocity rows (`axis_velocities`).
    axis_pairs: Vec<AxisPair>,
}

/// A linear form `Σ a·x + constant` over the system's variables.
pub(crate) type LinearForm = (Vec<(VarId, Interval)>, Interval);

/// What the velocity rows of an axis closure written with two rows need: with `|u| = |v| = 1`
/// and `u = v`, the derivative `δ = d/dt (u − v)` is orthogonal to `u`, so its three rows have
/// rank two everywhere on the closure (the two rows written lose rank where the component left
/// out vanishes); `δ = ν·u` with one more unknown `ν` is square and forces `ν = u·δ = 0`.
#[derive(Clone, Debug)]
pub(crate) struct AxisVelocity {
    /// The predecessor's axis, per component.
    pub u: [LinearForm; 3],
    /// `u − v`, per component.
    pub diff: [LinearForm; 3],
    /// The equations (indices) written for this closure.
    pub rows: Vec<usize>,
}

fn e_mentions(m: Monomial, v: VarId) -> bool {
    match m {
        Monomial::Linear(x) | Monomial::Square(x) => x == v,
        Monomial::Product(x, y) => x == v || y == v,
    }
}

fn imat_t(a: &IMat3) -> IMat3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

impl SpatialProblem {
    /// Builds the spatial system of `m`, with `fixed` joint values and traced points
    /// `(link, [x, y, z])` in the link's frame.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, [f64; 3], String)]) -> Result<Self, LinkageError> {
        if let Some(j) = m.joints.iter().find(|j| j.mimic.is_some() && j.kind != JointKind::Fixed) {
            let leader = j.mimic.as_ref().map_or("", |x| x.joint.as_str());
            return Err(LinkageError::Mimic { joint: j.name.clone(), leader: leader.to_string() });
        }
        if m.loops.is_empty() {
            return Err(LinkageError::NoLoops);
        }
        // Whether a loop can close is a property of the geometry: judged with every joint
        // free and no limits (as the planar builder does).
        let limited = m.joints.iter().any(|j| matches!(j.kind, JointKind::Revolute { limits: Some(_) }));
        if fixed.is_empty() && !limited {
            return Self::build(m, fixed, traces, true, true);
        }
        Self::build(m, &[], &[], false, true)?;
        Self::build(m, fixed, traces, true, false)
    }

    fn eval_rot(&self, g: usize, k: &IMat3, b: &[Interval]) -> IMat3 {
        let r = [0, 1, 2].map(|i| [0, 1, 2].map(|j| self.groups[g][i][j].eval(b)));
        st::mul(&r, k)
    }

    fn eval_pos(&self, p: &Pos, b: &[Interval]) -> IVec3 {
        let mut out = [0, 1, 2].map(|i| p.rest[i].eval(b));
        for (&g, v) in &p.by_group() {
            let r = [0, 1, 2].map(|i| [0, 1, 2].map(|j| self.groups[g][i][j].eval(b)));
            for (o, x) in out.iter_mut().zip(st::apply(&r, v)) {
                *o += x;
            }
        }
        out
    }

    fn reading(&self, r: &Reading, b: &IntervalBox) -> Interval {
        let d = &b.dims;
        match *r {
            Reading::Angle { c, s } => wrap(angles::angle_interval(d[c], d[s])),
            Reading::Var(v) => d[v],
            Reading::LoopAngle(k) => {
                let Some(f) = &self.loops[k] else { return interval(-std::f64::consts::PI, std::f64::consts::PI) };
                // Q = F_pᵀ F_s = Rot(a, ψ): cos ψ = e1ᵀQe1, sin ψ = e2ᵀQe1.
                let q = st::mul(&imat_t(&self.eval_rot(f.pred.0, &f.pred.1, d)), &self.eval_rot(f.succ.0, &f.succ.1, d));
                let [e1, e2] = f.across;
                let e1i = [e1.x, e1.y, e1.z].map(point);
                let e2i = [e2.x, e2.y, e2.z].map(point);
                let qe1 = st::apply(&q, &e1i);
                // e1, e2 are orthonormal to the axis only to rounding: widen by that.
                let slack = interval(-1e-12, 1e-12);
                let c = (0..3).fold(point(0.0), |acc, i| acc + e1i[i] * qe1[i]) + slack;
                let s = (0..3).fold(point(0.0), |acc, i| acc + e2i[i] * qe1[i]) + slack;
                wrap(angles::angle_interval(c, s))
            }
            Reading::LoopTravel(k) => {
                let Some(f) = &self.loops[k] else { return Interval::ENTIRE };
                let rp = self.eval_rot(f.pred.0, &f.pred.1, d);
                let diff = {
                    let (s, p) = (self.eval_pos(&f.succ_at, d), self.eval_pos(&f.pred_at, d));
                    [0, 1, 2].map(|i| s[i] - p[i])
                };
                let local = st::apply_transposed(&rp, &diff);
                (0..3).fold(point(0.0), |acc, i| acc + f.axis[i] * local[i])
            }
        }
    }

    /// Values of the free joints over the box (radians or metres), keyed by name; outward
    /// rounded.
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.readings.iter().map(|(name, r)| {
            let x = self.reading(r, b);
            (name.clone(), (x.inf(), x.sup()))
        }).collect()
    }

    /// Every link's pose over the box, keyed by link name.
    pub fn link_poses(&self, b: &IntervalBox) -> BTreeMap<String, LinkPose> {
        self.link_poses_of(b, |_| true)
    }

    /// `link_poses` of the links `keep` names only (the others are not computed).
    pub fn link_poses_of(&self, b: &IntervalBox, keep: impl Fn(&str) -> bool) -> BTreeMap<String, LinkPose> {
        let d = &b.dims;
        self.links
            .iter()
            .filter(|place| keep(&place.name))
            .map(|place| {
                let position = place.position.as_ref().map(|p| self.eval_pos(p, d).map(|x| [x.inf(), x.sup()]));
                let (quaternion, rotation_width) = match place.rotation {
                    Some((g, k)) => {
                        let r = self.eval_rot(g, &k, d);
                        let mid = Matrix3::from_fn(|i, j| r[i][j].mid());
                        let width = r.iter().flatten().map(|x| x.wid()).fold(0.0, f64::max);
                        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&mid));
                        (Some([q.w, q.i, q.j, q.k]), Some(width))
                    }
                    None => (None, None),
                };
                (place.name.clone(), LinkPose { position, quaternion, rotation_width })
            })
            .collect()
    }

    /// Where the box lies against the limits of the limited revolute joints and loops, and
    /// against the sign agreement of the axis closures written with two rows.
    pub fn limit_verdict(&self, b: &IntervalBox) -> Inclusion {
        let mut verdict = Inclusion::Inside;
        for (u, v) in &self.signs {
            let (u, v) = (u.eval(&b.dims), v.eval(&b.dims));
            if (u.sup() < 0.0 && v.inf() > 0.0) || (u.inf() > 0.0 && v.sup() < 0.0) {
                return Inclusion::Outside;
            }
            if !((u.inf() > 0.0 && v.inf() > 0.0) || (u.sup() < 0.0 && v.sup() < 0.0)) {
                verdict = Inclusion::Straddles;
            }
        }
        for &(k, lower, upper) in &self.limits {
            verdict = verdict.and(against_limits(self.reading(&self.readings[k].1, b), lower, upper));
            if verdict == Inclusion::Outside {
                return verdict;
            }
        }
        verdict
    }

    /// How a free joint moves in the system's unknowns: its own angle `(c, s)` or variable
    /// (tree joints), or a loop joint whose value is read from its closure frames; `None` for a
    /// name that is not a free joint. The singular-set builder takes the rates of the first two.
    pub(crate) fn joint_motion(&self, name: &str) -> Option<JointMotion> {
        let (_, r) = self.readings.iter().find(|(n, _)| n == name)?;
        Some(match *r {
            Reading::Angle { c, s } => JointMotion::Angle { c, s },
            Reading::Var(v) => JointMotion::Var(v),
            Reading::LoopAngle(_) | Reading::LoopTravel(_) => JointMotion::Loop,
        })
    }

    /// The axis closures written with two rows, for faithful velocity rows (see
    /// `AxisVelocity`).
    pub(crate) fn axis_velocities(&self) -> Vec<AxisVelocity> {
        let linear = |f: &Form| -> LinearForm { (f.merged().terms, f.constant) };
        self.axis_pairs.iter().map(|p| AxisVelocity { u: [0, 1, 2].map(|i| linear(&p.u[i])), diff: [0, 1, 2].map(|i| linear(&p.diff[i])), rows: p.rows.clone() }).collect()
    }

    /// True when some axis closure written with two rows may have its left-out component at
    /// zero in `b` (configuration variables first): there the two rows lose rank where the
    /// three would not (the mirror branch the sign filter removes meets the true one).
    pub(crate) fn axis_rows_may_degenerate(&self, b: &IntervalBox) -> bool {
        self.signs.iter().any(|(u, v)| u.eval(&b.dims).contains(0.0) || v.eval(&b.dims).contains(0.0))
    }

    /// A solver for `system`, which extends this problem's system (its first variables are
    /// this problem's, as in the singular-set systems), with the joint-limit and sign filters
    /// of `solver`.
    pub fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        debug_assert!(system.vars.len() >= self.system.vars.len());
        let solver = Solver::new(system, settings)?;
        if self.limits.is_empty() && self.signs.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }

    /// A solver for this problem: the default pipeline, plus a joint-limit filter when joints
    /// carry limits (it sees every box, certified ones included).
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        self.extended_solver(&self.system, settings)
    }

    /// Fills the derived variables of a point whose primaries are set (the others NaN), from
    /// their defining equations (each derived variable appears linearly in one, after the
    /// variables it depends on): for tests and references. `false` when some stay unknown.
    pub fn complete_point(&self, x: &mut [f64]) -> bool {
        loop {
            let mut progress = false;
            for e in &self.system.equations {
                let unknown: Vec<VarId> = {
                    let mut v: Vec<VarId> = e.vars().filter(|&v| x[v].is_nan()).collect();
                    v.dedup();
                    v
                };
                let [v] = unknown.as_slice() else { continue };
                let Some(coef) = e.terms.iter().find(|t| t.mono == Monomial::Linear(*v)).map(|t| t.coef.mid()) else { continue };
                if e.terms.iter().any(|t| t.mono != Monomial::Linear(*v) && e_mentions(t.mono, *v)) {
                    continue;
                }
                x[*v] = 0.0;
                x[*v] = -e.residual(x) / coef;
                progress = true;
            }
            if !progress {
                return x.iter().all(|v| !v.is_nan());
            }
        }
    }

    /// True when the system has as many equations as unknowns, so that interval Newton can
    /// certify isolated assemblies.
    pub fn is_square(&self) -> bool {
        self.system.equations.len() == self.system.vars.len()
    }

    /// How many equations are quadratics the LP relaxation does not use (distance rows).
    pub fn quadratic_rows(&self) -> usize {
        self.system.equations.iter().filter(|e| e.kind == EquationKind::Quadratic).count()
    }
}

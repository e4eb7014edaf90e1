//! Planar linkages: a `Mechanism` whose joint axes are all parallel becomes the seed-000 system.
//!
//! One angle per rigid group of links (links joined by fixed, prismatic or fixed-by-the-user
//! joints turn together), as `c = cos φ`, `s = sin φ` with `c² + s² = 1`; the ground's angle is 0.
//! One loop-closure vector equation per `<loop>` (the fundamental cycles of the spanning tree):
//! the closure point reached through the predecessor equals the one reached through the
//! successor, which is linear in the `c, s` variables.
//! Slider travel `d` enters as `d·c`, `d·s`: new variables defined by the bilinear equations
//! `z = d·c` (the seed's hyperbolic equations).
//! Traced points (the seed's equation 5) are derived variables defined by linear equations.
//! Builds only; solving is `search`'s job.

use super::angles::{self, against_limits, cos_sin, reduce, stated, wrap};
use super::stated::{self, IMat3, IVec3};
use crate::kernel::contract::{Contraction, Contractor, Filtered, Propagation, Inclusion};
use crate::kernel::search::{default_contractor, SolveError, Solver, SolverSettings};
use crate::kernel::interval::{interval, point, Interval, IntervalBox};
use crate::kernel::interval::trig;
use crate::model::{JointKind, Mechanism, ModelError};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use thiserror::Error;

/// What stops a mechanism from becoming a planar linkage problem.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum LinkageError {
    /// The description itself is bad.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Joint axes are not all parallel (or a slider axis is not in the plane).
    #[error("not planar: {0} (the planar builder takes planar linkages only; `solve --model spatial` takes the rest)")]
    NonPlanar(String),
    /// `--fix` names no joint or loop.
    #[error("--fix: no joint or loop named '{0}'")]
    UnknownJoint(String),
    /// `--fix` on a joint that does not move.
    #[error("--fix: joint '{0}' is fixed and takes no value")]
    NotMovable(String),
    /// `--fix` on a joint of more than one degree of freedom.
    #[error("--fix: joint '{0}' is a {1} joint: --fix sets one value, of a revolute, continuous or prismatic joint")]
    NotOneValue(String, &'static str),
    /// A fixed value outside the joint's limits, or not finite.
    #[error("--fix {joint}={value}: outside its limits [{lower}, {upper}]")]
    OutsideLimits {
        /// joint
        joint: String,
        /// value given
        value: f64,
        /// lower limit
        lower: f64,
        /// upper limit
        upper: f64,
    },
    /// A revolute value too large to reduce modulo 2π accurately.
    #[error("--fix {joint}={value}: more than {max:e} rad, too many turns to reduce modulo 2π accurately; give the angle modulo 2π", max = angles::MAX_REDUCIBLE)]
    TooManyTurns {
        /// joint
        joint: String,
        /// value given
        value: f64,
    },
    /// A value that is not a finite number.
    #[error("--fix {0}: the value is not a finite number")]
    NotFinite(String),
    /// The loop provably cannot close for any joint values.
    #[error("loop '{0}' cannot close: its links are too short or too long to meet (proven by interval propagation)")]
    CannotClose(String),
    /// A closure row has no unknown left and its constant excludes 0: as written, the loop's
    /// two chains miss each other whatever the joint values.
    #[error("loop '{name}' cannot close as written: whatever the joint values, one of its closure rows (a coordinate difference of its two chains) is the constant [{lower:e}, {upper:e}], not 0")]
    Gap {
        /// The loop.
        name: String,
        /// The constant's enclosure.
        lower: f64,
        /// The constant's enclosure.
        upper: f64,
    },
    /// Fixed angles around a cycle contradict each other.
    #[error("loop '{0}': the fixed joint angles around it contradict each other")]
    Contradiction(String),
    /// A joint follows another through `<mimic>`.
    #[error("joint '{joint}' follows '{leader}' through <mimic>, which planar linkages do not model yet")]
    Mimic {
        /// the follower
        joint: String,
        /// the joint it follows
        leader: String,
    },
    /// A traced point names an unknown link.
    #[error("--trace: no link named '{0}'")]
    UnknownTraceLink(String),
    /// A spatial description leaves some motion free that no loop constrains (a link spinning
    /// between two ball joints outside the recognised patterns, a ball or floating joint on no
    /// loop).
    #[error("under-constrained: {0}")]
    UnderConstrained(String),
    /// A joint or closure the spatial builder does not model.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A traced point off the plane z = 0 of its link's frame, with the planar model forced.
    #[error("--trace '{0}': the planar model traces points of the plane z = 0 of a link's frame")]
    TraceOffPlane(String),
    /// A tree has no loop to close: every joint value is a configuration.
    #[error("the mechanism has no <loop> closure: every joint value is a configuration, there is nothing to enclose (serial chains: see `singularities`)")]
    NoLoops,
    /// `--model pose` or `distances` on a mechanism that is not a platform on six fixed legs.
    #[error("--model pose or distances: {0}")]
    Platform(#[from] super::PlatformError),
    /// A traced point with `--model pose` or `distances`, which place only the platform.
    #[error("--trace {0}: the pose and distance models place the platform only; trace with --model spatial")]
    TraceOnPose(String),
    /// The pose or distance model where joint coordinates are needed (singular sets).
    #[error("the pose and distance models have no joint coordinates to differentiate; singular sets take --model planar, spatial or auto")]
    NotJointModel,
}

/// The pair of variables of a rotating group, or the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Angle {
    Ground,
    Free { c: VarId, s: VarId },
}

/// A rotation of the plane known as an angle (for read-outs) and as its cosine and sine (for
/// coefficients), both enclosures of the same exact rotation.
#[derive(Clone, Copy, Debug)]
struct Turn {
    angle: Interval,
    c: Interval,
    s: Interval,
}

impl Turn {
    fn zero() -> Self {
        Self { angle: point(0.0), c: point(1.0), s: point(0.0) }
    }

    /// The turn by `angle` (already reduced to about a turn, so the read-out stays tight).
    fn by(angle: Interval) -> Self {
        let (c, s) = cos_sin(angle);
        Self { angle, c, s }
    }

    /// The direction of the in-plane vector `(x, y)`, which must miss the origin.
    fn towards(x: Interval, y: Interval) -> Self {
        let len = (x.sqr() + y.sqr()).sqrt();
        Self { angle: angles::angle_interval(x, y), c: x / len, s: y / len }
    }

    fn plus(self, o: Turn) -> Turn {
        Turn { angle: self.angle + o.angle, c: self.c * o.c - self.s * o.s, s: self.s * o.c + self.c * o.s }
    }

    fn neg(self) -> Turn {
        Turn { angle: -self.angle, c: self.c, s: -self.s }
    }

    fn minus(self, o: Turn) -> Turn {
        self.plus(o.neg())
    }

    /// `R(self)·v`
    fn rotate(&self, v: [Interval; 2]) -> [Interval; 2] {
        [self.c * v[0] - self.s * v[1], self.s * v[0] + self.c * v[1]]
    }
}

/// How a joint's value is read off a solution box.
#[derive(Clone, Debug)]
enum Reading {
    /// `sign·(φ_b − φ_a) + offset`.
    Revolute { a: usize, b: usize, sign: f64, offset: Interval },
    /// A travel variable.
    Travel(VarId),
}

/// A point whose world coordinates are traced (seed 000, eq. 5).
#[derive(Clone, Debug)]
pub struct Trace {
    /// `LINK@X,Y` as given.
    pub name: String,
    /// World x variable.
    pub x: VarId,
    /// World y variable.
    pub y: VarId,
}

/// A planar linkage as a polynomial system, with what is needed to read joint values back.
///
/// Every coefficient is an interval enclosing its value in the stated mechanism (the decimals of
/// the file and of `--fix`, see `stated`), so the boxes enclose that mechanism's configurations.
#[derive(Clone, Debug)]
pub struct LinkageProblem {
    /// The system to solve.
    pub system: EquationSystem,
    /// Robot name.
    pub name: String,
    /// Joints (tree and loop) with unknown values, in file order.
    pub free_joints: Vec<String>,
    /// Joints fixed by the user, with their values.
    pub fixed_joints: Vec<(String, f64)>,
    /// Traced points.
    pub traces: Vec<Trace>,
    /// Per link: (name, group angle, offset to the group angle, rest yaw in the plane).
    links: Vec<(String, Angle, Interval, Interval)>,
    readings: Vec<(String, Reading)>,
    /// Revolute readings with limits: (index into `readings`, lower, upper), enclosing the stated limits.
    limits: Vec<(usize, Interval, Interval)>,
}

/// A 2-D linear form `Σ coef·var + constant`, one per coordinate.
#[derive(Clone, Debug)]
struct Form2 {
    x: Vec<(VarId, Interval)>,
    y: Vec<(VarId, Interval)>,
    constant: [Interval; 2],
}

impl Default for Form2 {
    fn default() -> Self {
        Self { x: Vec::new(), y: Vec::new(), constant: [point(0.0); 2] }
    }
}

/// Where a slider's travel lives.
#[derive(Clone, Copy, Debug)]
enum Travel {
    Known(Interval),
    Var(VarId),
}

struct Builder<'m> {
    m: &'m Mechanism,
    system: EquationSystem,
    /// Plane basis as columns: e1, e2, normal.
    basis: IMat3,
    /// Per link: rest rotation in the world, enclosed.
    rest: Vec<IMat3>,
    /// Per link: (group, offset).
    group: Vec<(usize, Turn)>,
    /// Per group: its angle variables.
    angles: Vec<Angle>,
    /// Cache of product variables `travel × (c or s)`.
    products: BTreeMap<(VarId, VarId), VarId>,
}

impl Builder<'_> {
    /// In-plane coordinates of a world vector.
    fn planar(&self, v: IVec3) -> [Interval; 2] {
        let p = stated::apply_transposed(&self.basis, &v);
        [p[0], p[1]]
    }

    /// In-plane coordinates of `rest[link]·v`.
    fn planar_from(&self, link: usize, v: IVec3) -> [Interval; 2] {
        self.planar(stated::apply(&self.rest[link], &v))
    }

    /// The rest direction of the x-axis of the frame `rot` on `link`, in the plane.
    fn yaw(&self, link: usize, rot: &IMat3) -> Turn {
        let x = stated::apply(&stated::mul(&self.rest[link], rot), &[point(1.0), point(0.0), point(0.0)]);
        let [a, b] = self.planar(x);
        Turn::towards(a, b)
    }

    /// Adds `scale·R(φ_link)·v` where `v` is given in the link's rest orientation, projected.
    fn add_rotated(&self, f: &mut Form2, link: usize, v: [Interval; 2], scale: Interval) {
        let (g, off) = self.group[link];
        let v = off.rotate(v).map(|x| x * scale);
        match self.angles[g] {
            Angle::Ground => {
                f.constant[0] += v[0];
                f.constant[1] += v[1];
            }
            Angle::Free { c, s } => {
                f.x.push((c, v[0]));
                f.x.push((s, -v[1]));
                f.y.push((s, v[0]));
                f.y.push((c, v[1]));
            }
        }
    }

    /// Adds `d·R(φ_link)·w`.
    fn add_travel(&mut self, f: &mut Form2, link: usize, w: [Interval; 2], d: Travel) {
        let d = match d {
            Travel::Known(v) => return self.add_rotated(f, link, w, v),
            Travel::Var(d) => d,
        };
        let (g, off) = self.group[link];
        let w = off.rotate(w);
        match self.angles[g] {
            Angle::Ground => {
                f.x.push((d, w[0]));
                f.y.push((d, w[1]));
            }
            Angle::Free { c, s } => {
                let zc = self.product(d, c);
                let zs = self.product(d, s);
                f.x.push((zc, w[0]));
                f.x.push((zs, -w[1]));
                f.y.push((zs, w[0]));
                f.y.push((zc, w[1]));
            }
        }
    }

    fn product(&mut self, d: VarId, c: VarId) -> VarId {
        if let Some(&z) = self.products.get(&(d, c)) {
            return z;
        }
        let dom = self.system.vars[d].domain;
        let reach = dom.mag();
        let name = format!("{}*{}", self.system.vars[d].name, self.system.vars[c].name);
        let z = self.system.add_var(name, VarRole::Derived, interval(-reach, reach));
        self.system.add(Equation::bilinear(z, d, c));
        self.products.insert((d, c), z);
        z
    }

    /// Position of `link`'s frame origin relative to the frame at the end of `from` (a prefix of
    /// `link`'s path from the root), as a linear form. Starting below the common prefix of two
    /// paths keeps terms that cancel exactly out of the equations, instead of leaving interval
    /// coefficients that merely straddle zero.
    fn position_after(&mut self, link: usize, skip: usize, travel: &BTreeMap<usize, Travel>) -> Form2 {
        let mut f = Form2::default();
        for j in self.m.path_to(link).into_iter().skip(skip) {
            let joint = &self.m.joints[j];
            let v = self.planar_from(joint.parent, stated::translation(&joint.origin.translation.vector));
            self.add_rotated(&mut f, joint.parent, v, point(1.0));
            if let Some(&d) = travel.get(&j) {
                let w = stated::apply(&stated::rpy(joint.rpy), &stated::axis(&joint.axis));
                let w = self.planar_from(joint.parent, w);
                self.add_travel(&mut f, joint.parent, w, d);
            }
        }
        f
    }
}

/// `constant + Σ coef·var ∋ 0`, merging repeated variables; only exactly-zero coefficients are
/// left out (a tiny coefficient is a term like any other: dropping it could lose solutions).
fn equation_from(terms: &[(VarId, Interval)], constant: Interval) -> Option<Equation> {
    let mut merged: BTreeMap<VarId, Interval> = BTreeMap::new();
    for &(v, c) in terms {
        let e = merged.entry(v).or_insert(point(0.0));
        *e += c;
    }
    let terms: Vec<Term> = merged
        .into_iter()
        .filter(|&(_, c)| !(c.inf() == 0.0 && c.sup() == 0.0))
        .map(|(v, c)| Term { coef: c, mono: Monomial::Linear(v) })
        .collect();
    if terms.is_empty() {
        None
    } else {
        Some(Equation::new(terms, constant))
    }
}

/// The bounding box on the unit circle of the arc of angles `arc` (sound cos and sin).
fn arc_box(arc: Interval) -> (Interval, Interval) {
    let (c, s) = (trig::cos(arc), trig::sin(arc));
    let unit = interval(-1.0, 1.0);
    (c.intersection(unit), s.intersection(unit))
}

impl LinkageProblem {
    /// Builds the planar system of `m`, with `fixed` joint values and traced points
    /// `(link name, x, y)` in the link's frame.
    pub fn new(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Self, LinkageError> {
        // A mimic couples two joint values: an equation the builder does not write yet, so it is
        // refused by name rather than silently ignored.
        if let Some(j) = m.joints.iter().find(|j| j.mimic.is_some() && j.kind != JointKind::Fixed) {
            let leader = j.mimic.as_ref().map_or("", |x| x.joint.as_str());
            return Err(LinkageError::Mimic { joint: j.name.clone(), leader: leader.to_string() });
        }
        // Whether a loop can close at all is a property of the geometry: judge it with every
        // joint free and no revolute limits. A fixed value or a limit that leaves no
        // configuration is an answer (complete, no box), not bad input.
        let limited = m.joints.iter().any(|j| matches!(j.kind, JointKind::Revolute { limits: Some(_) }));
        if fixed.is_empty() && !limited {
            return Self::build(m, fixed, traces, true, true);
        }
        Self::build(m, &[], &[], false, true)?;
        Self::build(m, fixed, traces, true, false)
    }

    fn build(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)], respect_limits: bool, check_closure: bool) -> Result<Self, LinkageError> {
        // Rest orientation of every link (all joint values zero).
        let n_links = m.links.len();
        let mut rest = vec![UnitQuaternion::identity(); n_links];
        let mut order: Vec<usize> = (0..n_links).collect();
        order.sort_by_key(|&l| m.path_to(l).len());
        for &l in &order {
            if let Some(j) = m.links[l].parent_joint {
                let joint = &m.joints[j];
                rest[l] = rest[joint.parent] * joint.origin.rotation;
            }
        }

        // The common axis: every revolute axis must be parallel to it, every slider across it.
        let mut normal: Option<Vector3<f64>> = None;
        let mut revolute_axes = Vec::new();
        let mut slider_axes = Vec::new();
        for j in &m.joints {
            let w = rest[j.parent] * (j.origin.rotation * j.axis);
            match j.kind {
                JointKind::Revolute { .. } => revolute_axes.push((j.name.clone(), w)),
                JointKind::Prismatic { .. } => slider_axes.push((j.name.clone(), w)),
                JointKind::Fixed => {}
                JointKind::Spherical | JointKind::Floating => return Err(LinkageError::NonPlanar(format!("joint '{}' is spherical or floating", j.name))),
            }
        }
        for l in &m.loops {
            let w = rest[l.predecessor] * (l.predecessor_origin.rotation * l.axis);
            // Welds and two-motion closures are the spatial builder's (`formulate::spatial`).
            if l.compound.is_some() || l.kind == JointKind::Fixed {
                return Err(LinkageError::NonPlanar(format!("loop '{}' is {}", l.name, l.type_name())));
            }
            match l.kind {
                JointKind::Prismatic { .. } => slider_axes.push((l.name.clone(), w)),
                JointKind::Spherical | JointKind::Floating => return Err(LinkageError::NonPlanar(format!("loop '{}' is spherical", l.name))),
                _ => revolute_axes.push((l.name.clone(), w)),
            }
        }
        for (name, w) in &revolute_axes {
            match normal {
                None => normal = Some(if w.z < 0.0 { -w } else { *w }),
                Some(n) if n.cross(w).norm() > 1e-9 => {
                    return Err(LinkageError::NonPlanar(format!("the axis of '{name}' is not parallel to the others")))
                }
                _ => {}
            }
        }
        let n = normal.unwrap_or_else(Vector3::z);
        for (name, w) in &slider_axes {
            if n.dot(w).abs() > 1e-9 {
                return Err(LinkageError::NonPlanar(format!("the slider axis of '{name}' leaves the plane of motion")));
            }
        }
        // Planarity first: a spatial serial chain is told to look elsewhere, not that it lacks loops.
        if m.loops.is_empty() {
            return Err(LinkageError::NoLoops);
        }
        // Any rotation taking z to n gives a right-handed plane basis (e1, e2).
        let basis = Rotation3::rotation_between(&Vector3::z(), &n).unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), PI));

        // Resolve --fix.
        let mut fixed_tree: BTreeMap<usize, f64> = BTreeMap::new();
        let mut fixed_loop: BTreeMap<usize, f64> = BTreeMap::new();
        for (name, value) in fixed {
            if !value.is_finite() {
                return Err(LinkageError::NotFinite(name.clone()));
            }
            let (kind, slot) = if let Some(j) = m.joint(name) {
                (m.joints[j].kind, (true, j))
            } else if let Some(l) = m.loops.iter().position(|l| &l.name == name) {
                (m.loops[l].kind, (false, l))
            } else {
                return Err(LinkageError::UnknownJoint(name.clone()));
            };
            let limits = match kind {
                JointKind::Fixed => return Err(LinkageError::NotMovable(name.clone())),
                JointKind::Spherical => return Err(LinkageError::NotOneValue(name.clone(), "ball")),
                JointKind::Floating => return Err(LinkageError::NotOneValue(name.clone(), "floating")),
                JointKind::Revolute { limits } => {
                    if reduce(stated(*value)).is_none() {
                        return Err(LinkageError::TooManyTurns { joint: name.clone(), value: *value });
                    }
                    limits
                }
                JointKind::Prismatic { limits } => Some(limits),
            };
            if let Some((lower, upper)) = limits {
                if *value < lower || *value > upper {
                    return Err(LinkageError::OutsideLimits { joint: name.clone(), value: *value, lower, upper });
                }
            }
            if slot.0 { fixed_tree.insert(slot.1, *value) } else { fixed_loop.insert(slot.1, *value) };
        }

        let sign_of = |w: Vector3<f64>| if w.dot(&n) < 0.0 { -1.0 } else { 1.0 };
        // The turn of a revolute joint fixed at `v` about an axis of sign `sign`, reduced.
        let fixed_turn = |sign: f64, v: f64| {
            let t = Turn::by(reduce(stated(v)).expect("checked reducible above"));
            if sign < 0.0 {
                t.neg()
            } else {
                t
            }
        };

        // Rest rotations enclosed, in the same order as the f64 ones above.
        let mut rest_i = vec![stated::identity(); n_links];
        for &l in &order {
            if let Some(j) = m.links[l].parent_joint {
                let joint = &m.joints[j];
                rest_i[l] = stated::mul(&rest_i[joint.parent], &stated::rpy(joint.rpy));
            }
        }

        // Rigid groups: walk the tree from the root.
        let mut group = vec![(usize::MAX, Turn::zero()); n_links];
        let mut group_count = 1;
        group[m.root] = (0, Turn::zero());
        for &l in &order {
            let Some(j) = m.links[l].parent_joint else { continue };
            let joint = &m.joints[j];
            let (pg, poff) = group[joint.parent];
            group[l] = match (joint.kind, fixed_tree.get(&j)) {
                (JointKind::Revolute { .. }, None) => {
                    group_count += 1;
                    (group_count - 1, Turn::zero())
                }
                (JointKind::Revolute { .. }, Some(&v)) => {
                    let w = rest[joint.parent] * (joint.origin.rotation * joint.axis);
                    (pg, poff.plus(fixed_turn(sign_of(w), v)))
                }
                _ => (pg, poff),
            };
        }
        let mut b = Builder { m, system: EquationSystem::default(), basis: stated::basis(&basis), rest: rest_i, group, angles: vec![Angle::Ground; group_count], products: BTreeMap::new() };

        // Prismatic loops and fixed revolute loops weld their two sides' groups together.
        for (k, l) in m.loops.iter().enumerate() {
            let welded = match (l.kind, fixed_loop.get(&k)) {
                (JointKind::Prismatic { .. }, _) => Some(Turn::zero()),
                (JointKind::Revolute { .. }, Some(&v)) => {
                    let w = rest[l.predecessor] * (l.predecessor_origin.rotation * l.axis);
                    Some(fixed_turn(sign_of(w), v))
                }
                _ => None,
            };
            let Some(turn) = welded else { continue };
            // φ_successor = φ_predecessor + turn + (rest yaw difference of the closure frames).
            let rest_turn = b.yaw(l.predecessor, &stated::rpy(l.predecessor_rpy)).minus(b.yaw(l.successor, &stated::rpy(l.successor_rpy)));
            let (gp, op) = b.group[l.predecessor];
            let (gs, os) = b.group[l.successor];
            let target = op.plus(turn).plus(rest_turn).minus(os); // φ_gs = φ_gp + target
            if gp == gs {
                let miss = (target.angle.mid() + PI).rem_euclid(2.0 * PI) - PI;
                if miss.abs() > 1e-9 {
                    return Err(LinkageError::Contradiction(l.name.clone()));
                }
                continue;
            }
            // Relabel the group that is not the ground.
            let (from, into, off) = if gs != 0 { (gs, gp, target) } else { (gp, gs, target.neg()) };
            for g in b.group.iter_mut() {
                if g.0 == from {
                    *g = (into, g.1.plus(off));
                }
            }
        }

        // Angle variables for every group still in use, named after its first link.
        for l in 0..n_links {
            let g = b.group[l].0;
            if g != 0 && b.angles[g] == Angle::Ground {
                let name = &m.links[l].name;
                let (mut dc, mut ds) = (interval(-1.0, 1.0), interval(-1.0, 1.0));
                // A limited joint to the ground bounds the group's angle to an arc.
                if let Some(j) = m.links[l].parent_joint {
                    let joint = &m.joints[j];
                    if let (JointKind::Revolute { limits: Some((lo, hi)) }, 0, true) = (joint.kind, b.group[joint.parent].0, respect_limits) {
                        let w = rest[joint.parent] * (joint.origin.rotation * joint.axis);
                        let base = b.group[joint.parent].1.angle - b.group[l].1.angle;
                        let limits = stated(lo).convex_hull(stated(hi));
                        let arc = if sign_of(w) > 0.0 { base + limits } else { base - limits };
                        (dc, ds) = arc_box(arc);
                    }
                }
                let c = b.system.add_var(format!("cos_{name}"), VarRole::Primary, dc);
                let s = b.system.add_var(format!("sin_{name}"), VarRole::Primary, ds);
                b.system.add(Equation::circle(c, s));
                b.angles[g] = Angle::Free { c, s };
            }
        }

        // Travel variables.
        let mut travel: BTreeMap<usize, Travel> = BTreeMap::new();
        let mut readings = Vec::new();
        let mut limit_list = Vec::new();
        let mut free_joints = Vec::new();
        // A slider's travel domain encloses its stated limits.
        let travel_domain = |(lo, hi): (f64, f64)| interval(stated(lo).inf(), stated(hi).sup());
        for (j, joint) in m.joints.iter().enumerate() {
            match joint.kind {
                JointKind::Prismatic { limits } => {
                    let t = match fixed_tree.get(&j) {
                        Some(&v) => Travel::Known(stated(v)),
                        None => {
                            let v = b.system.add_var(format!("d_{}", joint.name), VarRole::Primary, travel_domain(limits));
                            readings.push((joint.name.clone(), Reading::Travel(v)));
                            free_joints.push(joint.name.clone());
                            Travel::Var(v)
                        }
                    };
                    travel.insert(j, t);
                }
                JointKind::Revolute { limits } if !fixed_tree.contains_key(&j) => {
                    let w = rest[joint.parent] * (joint.origin.rotation * joint.axis);
                    if let (Some((lo, hi)), true) = (limits, respect_limits) {
                        limit_list.push((readings.len(), stated(lo), stated(hi)));
                    }
                    readings.push((joint.name.clone(), Reading::Revolute { a: joint.parent, b: joint.child, sign: sign_of(w), offset: point(0.0) }));
                    free_joints.push(joint.name.clone());
                }
                _ => {}
            }
        }

        // One vector equation per loop: the closure point through the predecessor minus the one
        // through the successor, both from the last link their tree paths share.
        let mut loop_equations: Vec<(String, Vec<usize>)> = Vec::new();
        for (k, l) in m.loops.iter().enumerate() {
            let (pp, ps) = (m.path_to(l.predecessor), m.path_to(l.successor));
            let shared = pp.iter().zip(&ps).take_while(|(a, b)| a == b).count();
            let mut f = b.position_after(l.predecessor, shared, &travel);
            let a = b.planar_from(l.predecessor, stated::translation(&l.predecessor_origin.translation.vector));
            b.add_rotated(&mut f, l.predecessor, a, point(1.0));
            if let JointKind::Prismatic { limits } = l.kind {
                let t = match fixed_loop.get(&k) {
                    Some(&v) => Travel::Known(stated(v)),
                    None => {
                        let v = b.system.add_var(format!("d_{}", l.name), VarRole::Primary, travel_domain(limits));
                        readings.push((l.name.clone(), Reading::Travel(v)));
                        free_joints.push(l.name.clone());
                        Travel::Var(v)
                    }
                };
                let w = stated::apply(&stated::rpy(l.predecessor_rpy), &stated::axis(&l.axis));
                let w = b.planar_from(l.predecessor, w);
                b.add_travel(&mut f, l.predecessor, w, t);
            } else if !fixed_loop.contains_key(&k) {
                let w = rest[l.predecessor] * (l.predecessor_origin.rotation * l.axis);
                let offset = b.yaw(l.successor, &stated::rpy(l.successor_rpy)).angle - b.yaw(l.predecessor, &stated::rpy(l.predecessor_rpy)).angle;
                let sign = sign_of(w);
                if let (JointKind::Revolute { limits: Some((lo, hi)) }, true) = (l.kind, respect_limits) {
                    limit_list.push((readings.len(), stated(lo), stated(hi)));
                }
                readings.push((l.name.clone(), Reading::Revolute { a: l.predecessor, b: l.successor, sign, offset: if sign < 0.0 { -offset } else { offset } }));
                free_joints.push(l.name.clone());
            }
            let mut minus = b.position_after(l.successor, shared, &travel);
            let s = b.planar_from(l.successor, stated::translation(&l.successor_origin.translation.vector));
            b.add_rotated(&mut minus, l.successor, s, point(1.0));
            let mut rows = Vec::new();
            for (coord, (pos, neg)) in [(&f.x, &minus.x), (&f.y, &minus.y)].into_iter().enumerate() {
                let mut terms = pos.clone();
                terms.extend(neg.iter().map(|&(v, c)| (v, -c)));
                let constant = f.constant[coord] - minus.constant[coord];
                match equation_from(&terms, constant) {
                    Some(e) => {
                        rows.push(b.system.equations.len());
                        b.system.add(e);
                    }
                    None if check_closure && !constant.contains(0.0) => return Err(LinkageError::CannotClose(l.name.clone())),
                    // A row that `--fix` values (or shared links) made constant stays an
                    // equation: the solver then refutes it (no configuration: a complete run with
                    // no box) or keeps it, and it keeps Newton from certifying a closure that
                    // rounding cannot confirm.
                    None => {
                        rows.push(b.system.equations.len());
                        b.system.add(Equation::new(Vec::new(), constant));
                    }
                }
            }
            loop_equations.push((l.name.clone(), rows));
        }

        // Traced points.
        let mut trace_out = Vec::new();
        for (link_name, x, y) in traces {
            let link = m.link(link_name).ok_or_else(|| LinkageError::UnknownTraceLink(link_name.clone()))?;
            let mut f = b.position_after(link, 0, &travel);
            let v = b.planar_from(link, [stated(*x), stated(*y), point(0.0)]);
            b.add_rotated(&mut f, link, v, point(1.0));
            let name = format!("{link_name}@{x},{y}");
            let init = b.system.initial_box();
            let reach = |terms: &[(VarId, Interval)], c: Interval| terms.iter().fold(c, |acc, &(v, k)| acc + k * init.dims[v]);
            let (rx, ry) = (reach(&f.x, f.constant[0]), reach(&f.y, f.constant[1]));
            let tx = b.system.add_var(format!("x_{name}"), VarRole::Derived, rx);
            let ty = b.system.add_var(format!("y_{name}"), VarRole::Derived, ry);
            for (t, terms, c) in [(tx, &f.x, f.constant[0]), (ty, &f.y, f.constant[1])] {
                let mut all = terms.clone();
                all.push((t, point(-1.0)));
                if let Some(e) = equation_from(&all, c) {
                    b.system.add(e);
                }
            }
            trace_out.push(Trace { name, x: tx, y: ty });
        }

        // A loop that cannot close on its own is bad input, not an empty answer.
        let start = b.system.initial_box();
        for (name, rows) in loop_equations.iter().filter(|_| check_closure) {
            let mut sub = EquationSystem { vars: b.system.vars.clone(), equations: rows.iter().map(|&r| b.system.equations[r].clone()).collect() };
            sub.equations.extend(b.system.equations.iter().filter(|e| !matches!(e.kind, crate::kernel::system::EquationKind::Linear)).cloned());
            let mut probe = start.clone();
            if Propagation::new(&sub).contract(&mut probe) == Contraction::Empty {
                return Err(LinkageError::CannotClose(name.clone()));
            }
        }

        let links = (0..n_links)
            .map(|l| {
                let (g, off) = b.group[l];
                let yaw = b.yaw(l, &stated::identity()).angle;
                (m.links[l].name.clone(), b.angles[g], off.angle, yaw)
            })
            .collect();
        let fixed_joints = fixed.to_vec();
        Ok(Self { system: b.system, name: m.name.clone(), free_joints, fixed_joints, traces: trace_out, links, readings, limits: limit_list })
    }

    /// World orientation of every link over the box, radians, keyed by link name; outward
    /// rounded.
    pub fn link_angles(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.link_angles_of(b, |_| true)
    }

    /// `link_angles` of the links `keep` names only (the others are not computed).
    pub fn link_angles_of(&self, b: &IntervalBox, keep: impl Fn(&str) -> bool) -> BTreeMap<String, (f64, f64)> {
        self.links.iter().filter(|(name, ..)| keep(name)).map(|(name, angle, off, yaw)| (name.clone(), bounds(wrap(self.angle(b, *angle, *off + *yaw))))).collect()
    }

    fn angle(&self, b: &IntervalBox, angle: Angle, off: Interval) -> Interval {
        match angle {
            Angle::Ground => off,
            Angle::Free { c, s } => angles::angle_interval(b.dims[c], b.dims[s]) + off,
        }
    }

    /// Values of the free joints over the box (radians or metres), keyed by joint name; outward
    /// rounded.
    pub fn joint_values(&self, b: &IntervalBox) -> BTreeMap<String, (f64, f64)> {
        self.readings.iter().map(|(name, r)| (name.clone(), bounds(self.reading(r, b)))).collect()
    }

    fn reading(&self, r: &Reading, b: &IntervalBox) -> Interval {
        match *r {
            Reading::Travel(v) => b.dims[v],
            Reading::Revolute { a, b: c, sign, offset } => {
                let pa = self.angle(b, self.links[a].1, self.links[a].2);
                let pc = self.angle(b, self.links[c].1, self.links[c].2);
                let d = pc - pa;
                wrap(if sign > 0.0 { d } else { -d } + offset)
            }
        }
    }

    /// Where the box lies against the limits of the limited revolute joints (angles compared
    /// modulo 2π, any number of turns). The joint intervals are outward-rounded enclosures
    /// (`angles`), so `Outside` means no point of the box respects the limits.
    pub fn limit_verdict(&self, b: &IntervalBox) -> Inclusion {
        let mut verdict = Inclusion::Inside;
        for &(k, lower, upper) in &self.limits {
            verdict = verdict.and(against_limits(self.reading(&self.readings[k].1, b), lower, upper));
            if verdict == Inclusion::Outside {
                return verdict;
            }
        }
        verdict
    }

    /// True when some limited revolute joint's value over `b` lies wholly outside its limits.
    pub fn violates_limits(&self, b: &IntervalBox) -> bool {
        self.limit_verdict(b) == Inclusion::Outside
    }

    /// A solver for this problem: the default pipeline, plus a joint-limit filter when joints
    /// away from the ground carry limits (those next to it already bound the initial box). The
    /// filter sees every box, certified ones included.
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        let solver = Solver::new(&self.system, settings)?;
        if self.limits.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }

    /// A box's point in the system's variables from link angles (radians, by link name) and
    /// slider travels (by joint name): for tests and references. Traced and product variables
    /// are filled in from the equations.
    pub fn point_from(&self, angles: &BTreeMap<String, f64>, travels: &BTreeMap<String, f64>) -> Option<Vec<f64>> {
        let mut x = vec![f64::NAN; self.system.vars.len()];
        for (name, angle, off, yaw) in &self.links {
            if let Angle::Free { c, s } = angle {
                let phi = angles.get(name)? - off.mid() - yaw.mid();
                x[*c] = phi.cos();
                x[*s] = phi.sin();
            }
        }
        for (name, r) in &self.readings {
            if let Reading::Travel(v) = r {
                x[*v] = *travels.get(name)?;
            }
        }
        // Derived variables: products, then traces (each defined by one equation).
        for e in &self.system.equations {
            if let crate::kernel::system::EquationKind::Bilinear { z, x: a, y: c } = e.kind {
                x[z] = x[a] * x[c];
            }
        }
        for t in &self.traces {
            for v in [t.x, t.y] {
                let e = self.system.equations.iter().find(|e| e.terms.iter().any(|k| k.mono == Monomial::Linear(v)))?;
                let coef = e.terms.iter().find(|k| k.mono == Monomial::Linear(v))?.coef.mid();
                x[v] = 0.0;
                x[v] = -e.residual(&x) / coef;
            }
        }
        Some(x)
    }
}

/// How a free joint's value moves with the system's variables: what velocity-level analyses
/// (singularities, `formulate::singular`) need. `Angles` is `φ_plus − φ_minus` (plus a constant),
/// each group angle given by its `(cos, sin)` variables, `None` for the ground.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointCoordinate {
    /// A revolute joint: the difference of two group angles.
    Angles {
        /// the group angle that enters with a plus sign
        plus: Option<(VarId, VarId)>,
        /// the group angle that enters with a minus sign
        minus: Option<(VarId, VarId)>,
    },
    /// A slider: its travel variable.
    Travel(VarId),
}

impl LinkageProblem {
    /// How the free joint `name` depends on the system's variables; `None` for a joint that is
    /// not free (unknown, fixed by `--fix`, or welded).
    pub fn joint_coordinate(&self, name: &str) -> Option<JointCoordinate> {
        let (_, r) = self.readings.iter().find(|(n, _)| n == name)?;
        let pair = |link: usize| match self.links[link].1 {
            Angle::Ground => None,
            Angle::Free { c, s } => Some((c, s)),
        };
        Some(match *r {
            Reading::Travel(v) => JointCoordinate::Travel(v),
            Reading::Revolute { a, b, sign, .. } if sign > 0.0 => JointCoordinate::Angles { plus: pair(b), minus: pair(a) },
            Reading::Revolute { a, b, .. } => JointCoordinate::Angles { plus: pair(a), minus: pair(b) },
        })
    }

    /// A solver for `system`, which must extend this problem's system (the same variables
    /// first, in order, then its own): the default pipeline plus this problem's joint-limit
    /// filter, which reads only the shared variables. Used by augmented systems (singular sets).
    pub fn extended_solver<'s>(&'s self, system: &'s EquationSystem, settings: SolverSettings) -> Result<Solver<'s>, SolveError> {
        debug_assert!(system.vars.len() >= self.system.vars.len());
        let solver = Solver::new(system, settings)?;
        if self.limits.is_empty() {
            return Ok(solver);
        }
        Ok(solver.with_contractor(Box::new(move |system, settings| {
            Box::new(Filtered { inner: default_contractor(system, settings), filters: vec![Box::new(move |b: &IntervalBox| self.limit_verdict(b))] })
        })))
    }
}

fn bounds(x: Interval) -> (f64, f64) {
    (x.inf(), x.sup())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_box_encloses_the_arc() {
        let (c, s) = arc_box(interval(-0.3, 2.0));
        for k in 0..=100 {
            let a = -0.3 + 2.3 * k as f64 / 100.0;
            assert!(c.contains(a.cos()) && s.contains(a.sin()));
        }
        assert!(c.sup() >= 1.0 && s.sup() >= 1.0 && s.inf() < -0.29);
    }
}

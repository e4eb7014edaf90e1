//! `LinkageProblem::build`, step by step: the links' rest orientations, the plane of motion
//! (every revolute axis parallel, every slider across it), the `--fix` values, the rigid groups
//! (links that turn together share one angle) and the welds of fixed loops, then the angle and
//! travel variables, two closure rows per loop, the traced points and the closure check. The
//! steps run in this order on one `Builder`, which fixes the variable and equation order.

use super::{Angle, LinkageError, LinkageProblem, Reading, Trace, Turn};
use crate::formulate::angles::{reduce, stated};
use crate::formulate::stated::{self, IMat3, IVec3};
use crate::kernel::contract::{Contraction, Contractor, Propagation};
use crate::kernel::interval::trig;
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use crate::model::{JointKind, Mechanism};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use std::collections::BTreeMap;
use std::f64::consts::PI;

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
/// The system being written and what the steps share: the plane, the groups and their angle
/// variables, and the readings of the free joints.
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
    /// Per link: rest rotation in the world (f64), for axis directions and their signs.
    rest_f64: Vec<UnitQuaternion<f64>>,
    /// The plane's normal, against which axis signs are read.
    normal: Vector3<f64>,
    respect_limits: bool,
    readings: Vec<(String, Reading)>,
    /// Revolute readings with limits: (index into `readings`, lower, upper).
    limits: Vec<(usize, Interval, Interval)>,
    free_joints: Vec<String>,
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
    pub(super) fn build(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)], respect_limits: bool, check_closure: bool) -> Result<Self, LinkageError> {
        let n_links = m.links.len();
        let (rest, order) = rest_orientations(m);
        let n = plane_normal(m, &rest)?;
        // Planarity first: a spatial serial chain is told to look elsewhere, not that it lacks loops.
        if m.loops.is_empty() {
            return Err(LinkageError::NoLoops);
        }
        // Any rotation taking z to n gives a right-handed plane basis (e1, e2).
        let basis = Rotation3::rotation_between(&Vector3::z(), &n).unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), PI));
        let (fixed_tree, fixed_loop) = fixed_values(m, fixed)?;

        // Rest rotations enclosed, in the same order as the f64 ones above.
        let mut rest_i = vec![stated::identity(); n_links];
        for &l in &order {
            if let Some(j) = m.links[l].parent_joint {
                let joint = &m.joints[j];
                rest_i[l] = stated::mul(&rest_i[joint.parent], &stated::rpy(joint.rpy));
            }
        }
        let (group, group_count) = rigid_groups(m, &order, &rest, &fixed_tree, &n);
        let mut b = Builder {
            m,
            system: EquationSystem::default(),
            basis: stated::basis(&basis),
            rest: rest_i,
            group,
            angles: vec![Angle::Ground; group_count],
            products: BTreeMap::new(),
            rest_f64: rest,
            normal: n,
            respect_limits,
            readings: Vec::new(),
            limits: Vec::new(),
            free_joints: Vec::new(),
        };
        b.weld_loops(&fixed_loop)?;
        b.add_angles();
        let travel = b.add_travels(&fixed_tree);
        let tree_readings = b.readings.len();
        // One vector equation per loop: the closure point through the predecessor minus the one
        // through the successor, both from the last link their tree paths share.
        let mut loop_equations: Vec<(String, Vec<usize>)> = Vec::new();
        for k in 0..m.loops.len() {
            let rows = b.close_loop(k, &fixed_loop, &travel, check_closure)?;
            loop_equations.push((m.loops[k].name.clone(), rows));
        }
        let trace_out = b.trace(traces, &travel)?;
        b.check_closure(&loop_equations, check_closure)?;

        let links = (0..n_links)
            .map(|l| {
                let (g, off) = b.group[l];
                let yaw = b.yaw(l, &stated::identity()).angle;
                (m.links[l].name.clone(), b.angles[g], off.angle, yaw)
            })
            .collect();
        let fixed_joints = fixed.to_vec();
        Ok(Self { system: b.system, name: m.name.clone(), free_joints: b.free_joints, fixed_joints, traces: trace_out, links, readings: b.readings, tree_readings, limits: b.limits })
    }
}

/// `--fix` values by joint (or loop) index.
type FixedValues = BTreeMap<usize, f64>;

/// Rest orientation of every link (all joint values zero), and the links ordered by depth
/// (parents first).
fn rest_orientations(m: &Mechanism) -> (Vec<UnitQuaternion<f64>>, Vec<usize>) {
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
    (rest, order)
}

/// The common axis: every revolute axis must be parallel to it, every slider across it.
fn plane_normal(m: &Mechanism, rest: &[UnitQuaternion<f64>]) -> Result<Vector3<f64>, LinkageError> {
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
    Ok(n)
}

/// Resolve --fix: each value checked against its joint, split into tree joints and loops (by
/// index).
fn fixed_values(m: &Mechanism, fixed: &[(String, f64)]) -> Result<(FixedValues, FixedValues), LinkageError> {
    let mut fixed_tree: FixedValues = BTreeMap::new();
    let mut fixed_loop: FixedValues = BTreeMap::new();
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
    Ok((fixed_tree, fixed_loop))
}

/// The sign of an axis `w` against the plane normal `n`.
fn sign_of(n: &Vector3<f64>, w: Vector3<f64>) -> f64 {
    if w.dot(n) < 0.0 { -1.0 } else { 1.0 }
}

/// The turn of a revolute joint fixed at `v` about an axis of sign `sign`, reduced.
fn fixed_turn(sign: f64, v: f64) -> Turn {
    let t = Turn::by(reduce(stated(v)).expect("checked reducible above"));
    if sign < 0.0 {
        t.neg()
    } else {
        t
    }
}

/// Rigid groups: walk the tree from the root. Per link its group and its offset to the
/// group's angle, and the number of groups (the ground's is 0).
fn rigid_groups(m: &Mechanism, order: &[usize], rest: &[UnitQuaternion<f64>], fixed_tree: &FixedValues, n: &Vector3<f64>) -> (Vec<(usize, Turn)>, usize) {
    let mut group = vec![(usize::MAX, Turn::zero()); m.links.len()];
    let mut group_count = 1;
    group[m.root] = (0, Turn::zero());
    for &l in order {
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
                (pg, poff.plus(fixed_turn(sign_of(n, w), v)))
            }
            _ => (pg, poff),
        };
    }
    (group, group_count)
}

/// A slider's travel domain encloses its stated limits.
fn travel_domain((lo, hi): (f64, f64)) -> Interval {
    interval(stated(lo).inf(), stated(hi).sup())
}

impl Builder<'_> {
    /// Prismatic loops and fixed revolute loops weld their two sides' groups together.
    fn weld_loops(&mut self, fixed_loop: &FixedValues) -> Result<(), LinkageError> {
        let m = self.m;
        for (k, l) in m.loops.iter().enumerate() {
            let welded = match (l.kind, fixed_loop.get(&k)) {
                (JointKind::Prismatic { .. }, _) => Some(Turn::zero()),
                (JointKind::Revolute { .. }, Some(&v)) => {
                    let w = self.rest_f64[l.predecessor] * (l.predecessor_origin.rotation * l.axis);
                    Some(fixed_turn(sign_of(&self.normal, w), v))
                }
                _ => None,
            };
            let Some(turn) = welded else { continue };
            // φ_successor = φ_predecessor + turn + (rest yaw difference of the closure frames).
            let rest_turn = self.yaw(l.predecessor, &stated::rpy(l.predecessor_rpy)).minus(self.yaw(l.successor, &stated::rpy(l.successor_rpy)));
            let (gp, op) = self.group[l.predecessor];
            let (gs, os) = self.group[l.successor];
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
            for g in self.group.iter_mut() {
                if g.0 == from {
                    *g = (into, g.1.plus(off));
                }
            }
        }
        Ok(())
    }

    /// Angle variables for every group still in use, named after its first link.
    fn add_angles(&mut self) {
        let m = self.m;
        for l in 0..m.links.len() {
            let g = self.group[l].0;
            if g != 0 && self.angles[g] == Angle::Ground {
                let name = &m.links[l].name;
                let (mut dc, mut ds) = (interval(-1.0, 1.0), interval(-1.0, 1.0));
                // A limited joint to the ground bounds the group's angle to an arc.
                if let Some(j) = m.links[l].parent_joint {
                    let joint = &m.joints[j];
                    if let (JointKind::Revolute { limits: Some((lo, hi)) }, 0, true) = (joint.kind, self.group[joint.parent].0, self.respect_limits) {
                        let w = self.rest_f64[joint.parent] * (joint.origin.rotation * joint.axis);
                        let base = self.group[joint.parent].1.angle - self.group[l].1.angle;
                        let limits = stated(lo).convex_hull(stated(hi));
                        let arc = if sign_of(&self.normal, w) > 0.0 { base + limits } else { base - limits };
                        (dc, ds) = arc_box(arc);
                    }
                }
                let c = self.system.add_var(format!("cos_{name}"), VarRole::Primary, dc);
                let s = self.system.add_var(format!("sin_{name}"), VarRole::Primary, ds);
                self.system.add(Equation::circle(c, s));
                self.angles[g] = Angle::Free { c, s };
            }
        }
    }

    /// Travel variables of the tree's sliders, and the readings of its free joints.
    fn add_travels(&mut self, fixed_tree: &FixedValues) -> BTreeMap<usize, Travel> {
        let m = self.m;
        let mut travel: BTreeMap<usize, Travel> = BTreeMap::new();
        for (j, joint) in m.joints.iter().enumerate() {
            match joint.kind {
                JointKind::Prismatic { limits } => {
                    let t = match fixed_tree.get(&j) {
                        Some(&v) => Travel::Known(stated(v)),
                        None => {
                            let v = self.system.add_var(format!("d_{}", joint.name), VarRole::Primary, travel_domain(limits));
                            self.readings.push((joint.name.clone(), Reading::Travel(v)));
                            self.free_joints.push(joint.name.clone());
                            Travel::Var(v)
                        }
                    };
                    travel.insert(j, t);
                }
                JointKind::Revolute { limits } if !fixed_tree.contains_key(&j) => {
                    let w = self.rest_f64[joint.parent] * (joint.origin.rotation * joint.axis);
                    if let (Some((lo, hi)), true) = (limits, self.respect_limits) {
                        self.limits.push((self.readings.len(), stated(lo), stated(hi)));
                    }
                    self.readings.push((joint.name.clone(), Reading::Revolute { a: joint.parent, b: joint.child, sign: sign_of(&self.normal, w), offset: point(0.0) }));
                    self.free_joints.push(joint.name.clone());
                }
                _ => {}
            }
        }
        travel
    }

    /// The two rows of loop `k` (and its travel variable or reading): the closure point
    /// through the predecessor minus the one through the successor. Returns the rows written.
    fn close_loop(&mut self, k: usize, fixed_loop: &FixedValues, travel: &BTreeMap<usize, Travel>, check_closure: bool) -> Result<Vec<usize>, LinkageError> {
        let m = self.m;
        let l = &m.loops[k];
        let (pp, ps) = (m.path_to(l.predecessor), m.path_to(l.successor));
        let shared = pp.iter().zip(&ps).take_while(|(a, b)| a == b).count();
        let mut f = self.position_after(l.predecessor, shared, travel);
        let a = self.planar_from(l.predecessor, stated::translation(&l.predecessor_origin.translation.vector));
        self.add_rotated(&mut f, l.predecessor, a, point(1.0));
        if let JointKind::Prismatic { limits } = l.kind {
            let t = match fixed_loop.get(&k) {
                Some(&v) => Travel::Known(stated(v)),
                None => {
                    let v = self.system.add_var(format!("d_{}", l.name), VarRole::Primary, travel_domain(limits));
                    self.readings.push((l.name.clone(), Reading::Travel(v)));
                    self.free_joints.push(l.name.clone());
                    Travel::Var(v)
                }
            };
            let w = stated::apply(&stated::rpy(l.predecessor_rpy), &stated::axis(&l.axis));
            let w = self.planar_from(l.predecessor, w);
            self.add_travel(&mut f, l.predecessor, w, t);
        } else if !fixed_loop.contains_key(&k) {
            let w = self.rest_f64[l.predecessor] * (l.predecessor_origin.rotation * l.axis);
            let offset = self.yaw(l.successor, &stated::rpy(l.successor_rpy)).angle - self.yaw(l.predecessor, &stated::rpy(l.predecessor_rpy)).angle;
            let sign = sign_of(&self.normal, w);
            if let (JointKind::Revolute { limits: Some((lo, hi)) }, true) = (l.kind, self.respect_limits) {
                self.limits.push((self.readings.len(), stated(lo), stated(hi)));
            }
            self.readings.push((l.name.clone(), Reading::Revolute { a: l.predecessor, b: l.successor, sign, offset: if sign < 0.0 { -offset } else { offset } }));
            self.free_joints.push(l.name.clone());
        }
        let mut minus = self.position_after(l.successor, shared, travel);
        let s = self.planar_from(l.successor, stated::translation(&l.successor_origin.translation.vector));
        self.add_rotated(&mut minus, l.successor, s, point(1.0));
        let mut rows = Vec::new();
        for (coord, (pos, neg)) in [(&f.x, &minus.x), (&f.y, &minus.y)].into_iter().enumerate() {
            let mut terms = pos.clone();
            terms.extend(neg.iter().map(|&(v, c)| (v, -c)));
            let constant = f.constant[coord] - minus.constant[coord];
            match equation_from(&terms, constant) {
                Some(e) => {
                    rows.push(self.system.equations.len());
                    self.system.add(e);
                }
                None if check_closure && !constant.contains(0.0) => return Err(LinkageError::CannotClose(l.name.clone())),
                // A row that `--fix` values (or shared links) made constant stays an
                // equation: the solver then refutes it (no configuration: a complete run with
                // no box) or keeps it, and it keeps Newton from certifying a closure that
                // rounding cannot confirm.
                None => {
                    rows.push(self.system.equations.len());
                    self.system.add(Equation::new(Vec::new(), constant));
                }
            }
        }
        Ok(rows)
    }

    /// Traced points: world x and y as derived variables, one linear definition each.
    fn trace(&mut self, traces: &[(String, f64, f64)], travel: &BTreeMap<usize, Travel>) -> Result<Vec<Trace>, LinkageError> {
        let m = self.m;
        let mut trace_out = Vec::new();
        for (link_name, x, y) in traces {
            let link = m.link(link_name).ok_or_else(|| LinkageError::UnknownTraceLink(link_name.clone()))?;
            let mut f = self.position_after(link, 0, travel);
            let v = self.planar_from(link, [stated(*x), stated(*y), point(0.0)]);
            self.add_rotated(&mut f, link, v, point(1.0));
            let name = format!("{link_name}@{x},{y}");
            let init = self.system.initial_box();
            let reach = |terms: &[(VarId, Interval)], c: Interval| terms.iter().fold(c, |acc, &(v, k)| acc + k * init.dims[v]);
            let (rx, ry) = (reach(&f.x, f.constant[0]), reach(&f.y, f.constant[1]));
            let tx = self.system.add_var(format!("x_{name}"), VarRole::Derived, rx);
            let ty = self.system.add_var(format!("y_{name}"), VarRole::Derived, ry);
            for (t, terms, c) in [(tx, &f.x, f.constant[0]), (ty, &f.y, f.constant[1])] {
                let mut all = terms.clone();
                all.push((t, point(-1.0)));
                if let Some(e) = equation_from(&all, c) {
                    self.system.add(e);
                }
            }
            trace_out.push(Trace { name, x: tx, y: ty });
        }
        Ok(trace_out)
    }

    /// A loop that cannot close on its own is bad input, not an empty answer: each loop's rows
    /// with every nonlinear row, propagated over the initial box (when `check_closure`).
    fn check_closure(&self, loop_equations: &[(String, Vec<usize>)], check_closure: bool) -> Result<(), LinkageError> {
        let start = self.system.initial_box();
        for (name, rows) in loop_equations.iter().filter(|_| check_closure) {
            let mut sub = EquationSystem { vars: self.system.vars.clone(), equations: rows.iter().map(|&r| self.system.equations[r].clone()).collect() };
            sub.equations.extend(self.system.equations.iter().filter(|e| !matches!(e.kind, crate::kernel::system::EquationKind::Linear)).cloned());
            let mut probe = start.clone();
            if Propagation::new(&sub).contract(&mut probe) == Contraction::Empty {
                return Err(LinkageError::CannotClose(name.clone()));
            }
        }
        Ok(())
    }
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

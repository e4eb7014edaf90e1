//! `SpatialProblem::build`, step by step: the `--fix` values checked, legs found (`legs`), the
//! tree placed link by link from the root outward, floating links bounded, the closures written
//! loop by loop, traced points named, and, when judging the geometry, each loop tested for
//! closing on its own. The steps run in this order on one `Assembly`, which owns the `Builder`
//! and what the problem reads back: the order fixes the system's variables and equations.

use super::builder::{axes_agree, vanished_note, AxisPair, Builder};
use super::forms::{across, arc_box, const_rot, imat_mul, rot_about, rot_apply, rot_times, Form, Pos, RotF, Vec3F};
use super::legs::{self, Leg, Travel};
use super::{LinkPlace, LoopFrames, Reading, SpatialProblem, Trace3};
use crate::formulate::angles::{reduce, stated};
use crate::formulate::linkage::LinkageError;
use crate::formulate::stated::{self as st, IMat3};
use crate::kernel::contract::{Contraction, Contractor, Propagation};
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::system::{Equation, EquationSystem, Monomial, Term, VarId, VarRole};
use crate::model::{Compound, Joint, JointKind, LoopClosure, Mechanism};
use nalgebra::UnitQuaternion;
use std::collections::BTreeMap;

impl SpatialProblem {
    pub(super) fn build(m: &Mechanism, fixed: &[(String, f64)], traces: &[(String, [f64; 3], String)], respect_limits: bool, check_closure: bool) -> Result<Self, LinkageError> {
        let n_links = m.links.len();
        let (fixed_tree, fixed_loop) = fixed_values(m, fixed)?;

        // Which links each loop touches, children per link, traced links.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n_links];
        for (j, joint) in m.joints.iter().enumerate() {
            children[joint.parent].push(j);
        }
        let traced: Vec<usize> = traces.iter().filter_map(|(n, _, _)| m.link(n)).collect();
        let (legs, in_leg) = legs::find(m, &children, &traced);
        legs::refuse_undetermined(m, &children, &in_leg)?;

        let mut a = Assembly::new(m, Builder::new(check_closure), respect_limits);
        let mut order: Vec<usize> = (0..n_links).collect();
        order.sort_by_key(|&l| m.path_to(l).len());
        let reach = reach(m);
        for &l in &order {
            a.place(l, &fixed_tree, &in_leg, reach)?;
        }
        a.bound_floating(&legs, reach);

        // Closures.
        // Rest orientation of every link (all joint values zero), to pick which axis row a
        // revolute closure can do without.
        let mut rest = vec![UnitQuaternion::identity(); n_links];
        for &l in &order {
            if let Some(j) = m.links[l].parent_joint {
                rest[l] = rest[m.joints[j].parent] * m.joints[j].origin.rotation;
            }
        }
        let leg_of: BTreeMap<usize, &Leg> = legs.iter().map(|leg| (leg.closure, leg)).collect();
        for k in 0..m.loops.len() {
            match leg_of.get(&k) {
                Some(leg) => a.close_leg(k, leg)?,
                None => a.close_joint(k, &rest, fixed_loop.get(&k).copied())?,
            }
        }

        let trace_out = a.trace(traces)?;
        if check_closure {
            a.check_closure()?;
        }
        Ok(a.finish(fixed, trace_out))
    }
}

/// `--fix` values by joint (or loop) index.
type FixedValues = BTreeMap<usize, f64>;

/// The `--fix` values checked against their joints, split into tree joints and loops (by
/// index).
fn fixed_values(m: &Mechanism, fixed: &[(String, f64)]) -> Result<(FixedValues, FixedValues), LinkageError> {
    let mut fixed_tree: FixedValues = BTreeMap::new();
    let mut fixed_loop: FixedValues = BTreeMap::new();
    for (name, value) in fixed {
        if !value.is_finite() {
            return Err(LinkageError::NotFinite(name.clone()));
        }
        let (kind, compound, tree, slot) = if let Some(j) = m.joint(name) {
            (m.joints[j].kind, None, true, j)
        } else if let Some(l) = m.loops.iter().position(|l| &l.name == name) {
            (m.loops[l].kind, m.loops[l].compound, false, l)
        } else {
            return Err(LinkageError::UnknownJoint(name.clone()));
        };
        let limits = match (kind, compound) {
            (JointKind::Spherical, _) => return Err(LinkageError::NotOneValue(name.clone(), "ball")),
            (JointKind::Floating, _) => return Err(LinkageError::NotOneValue(name.clone(), "floating")),
            (JointKind::Fixed, _) | (_, Some(_)) => return Err(LinkageError::NotMovable(name.clone())),
            (JointKind::Revolute { limits }, None) => {
                if reduce(stated(*value)).is_none() {
                    return Err(LinkageError::TooManyTurns { joint: name.clone(), value: *value });
                }
                limits
            }
            (JointKind::Prismatic { limits }, None) => Some(limits),
        };
        if let Some((lower, upper)) = limits {
            if *value < lower || *value > upper {
                return Err(LinkageError::OutsideLimits { joint: name.clone(), value: *value, lower, upper });
            }
        }
        if tree { fixed_tree.insert(slot, *value) } else { fixed_loop.insert(slot, *value) };
    }
    Ok((fixed_tree, fixed_loop))
}

/// Reach: every frame of the mechanism lies within the sum of all its offsets and travels from
/// the root (any link is reached from the root through tree joints and closures), which bounds
/// floating positions.
fn reach(m: &Mechanism) -> f64 {
    let mut reach = 0.0f64;
    for j in &m.joints {
        reach += j.origin.translation.vector.norm() * (1.0 + 1e-9);
        if let JointKind::Prismatic { limits: (lo, hi) } = j.kind {
            reach += lo.abs().max(hi.abs()) * (1.0 + 1e-9);
        }
    }
    for l in &m.loops {
        reach += (l.predecessor_origin.translation.vector.norm() + l.successor_origin.translation.vector.norm()) * (1.0 + 1e-9);
        if let JointKind::Prismatic { limits: (lo, hi) } = l.kind {
            reach += lo.abs().max(hi.abs()) * (1.0 + 1e-9);
        }
    }
    reach + 1.0
}

/// A travel's domain: its stated limits, outward.
fn travel_domain((lo, hi): (f64, f64)) -> Interval {
    interval(stated(lo).inf(), stated(hi).sup())
}

/// A closure row left with no unknown, its constant excluding 0: the chains of loop `name`
/// miss each other by that much whatever the joint values.
fn gap(name: &str) -> impl Fn(Interval) -> LinkageError + '_ {
    move |k: Interval| LinkageError::Gap { name: name.to_string(), lower: k.inf(), upper: k.sup() }
}

/// Column `j` of a rotation of forms.
fn col(r: &RotF, j: usize) -> Vec3F {
    [r[0][j].clone(), r[1][j].clone(), r[2][j].clone()]
}

/// A loop's two closure frames in the world, as `close_joint` reads them.
struct Sides {
    /// The predecessor's and the successor's rotation.
    rp: RotF,
    rs: RotF,
    /// The loop axis through each.
    axis_p: Vec3F,
    axis_s: Vec3F,
    /// Their origins.
    pf: Vec3F,
    sf: Vec3F,
}

/// What the steps of `build` share: the builder, where each link is, and what the problem
/// reads back (joint readings, limits, sign filters, closure frames and rows).
struct Assembly<'m> {
    m: &'m Mechanism,
    b: Builder,
    respect_limits: bool,
    places: Vec<LinkPlace>,
    readings: Vec<(String, Reading)>,
    free_joints: Vec<String>,
    limits: Vec<(usize, Interval, Interval)>,
    /// The travel of each leg's prismatic joint, by tree joint.
    leg_travel: BTreeMap<usize, Travel>,
    reductions: Vec<String>,
    /// Floating links and their position variables.
    floating: Vec<(usize, [VarId; 3])>,
    signs: Vec<(Form, Form)>,
    axis_pairs: Vec<AxisPair>,
    /// The closure rows of each loop, by loop name.
    loop_rows: Vec<(String, Vec<usize>)>,
    frames: Vec<Option<LoopFrames>>,
}

impl<'m> Assembly<'m> {
    /// Nothing placed but the root, at the origin with the ground's rotation.
    fn new(m: &'m Mechanism, b: Builder, respect_limits: bool) -> Self {
        let mut places: Vec<LinkPlace> = m.links.iter().map(|l| LinkPlace { name: l.name.clone(), rotation: None, position: None }).collect();
        places[m.root] = LinkPlace { name: m.links[m.root].name.clone(), rotation: Some((0, st::identity())), position: Some(Pos::origin()) };
        Self {
            m,
            b,
            respect_limits,
            places,
            readings: Vec::new(),
            free_joints: Vec::new(),
            limits: Vec::new(),
            leg_travel: BTreeMap::new(),
            reductions: Vec::new(),
            floating: Vec::new(),
            signs: Vec::new(),
            axis_pairs: Vec::new(),
            loop_rows: Vec::new(),
            frames: vec![None; m.loops.len()],
        }
    }

    /// A free joint motion read back as `name`.
    fn read(&mut self, name: String, r: Reading) {
        self.readings.push((name.clone(), r));
        self.free_joints.push(name);
    }

    /// Places link `l` on its parent joint; the parent is placed already (links go by depth).
    fn place(&mut self, l: usize, fixed_tree: &FixedValues, in_leg: &[bool], reach: f64) -> Result<(), LinkageError> {
        let m = self.m;
        let Some(j) = m.links[l].parent_joint else { return Ok(()) };
        let joint = &m.joints[j];
        let parent = joint.parent;
        let o = st::rpy(joint.rpy);
        let t = st::translation(&joint.origin.translation.vector);
        // A leg's rod: its travel is the leg's, and it has no place of its own.
        // A link welded to a rod between two balls: its pose is as undetermined as the rod's.
        if in_leg[l] && joint.kind == JointKind::Fixed {
            return Ok(());
        }
        if let (true, JointKind::Prismatic { limits }) = (in_leg[l], joint.kind) {
            let tv = match fixed_tree.get(&j) {
                Some(&v) => Travel::Known(stated(v)),
                None => {
                    let v = self.b.system.add_var(format!("d_{}", joint.name), VarRole::Primary, travel_domain(limits));
                    self.read(joint.name.clone(), Reading::Var(v));
                    Travel::Var(v)
                }
            };
            self.leg_travel.insert(j, tv);
            return Ok(());
        }
        let (Some((g, k)), Some(ppos)) = (self.places[parent].rotation, self.places[parent].position.clone()) else {
            return Err(LinkageError::Unsupported(format!("joint '{}' hangs on link '{}', whose pose a ball-jointed leg leaves undetermined", joint.name, m.links[parent].name)));
        };
        let mut at = ppos.clone();
        at.add_rotated(g, st::apply(&k, &t));
        let ko = imat_mul(&k, &o);
        let fixed = fixed_tree.get(&j).copied();
        match joint.kind {
            JointKind::Fixed => {
                self.places[l].rotation = Some((g, ko));
                self.places[l].position = Some(at);
            }
            JointKind::Revolute { limits } => self.place_revolute(l, joint, limits, fixed, (g, ko), at),
            JointKind::Prismatic { limits } => self.place_prismatic(l, joint, limits, fixed, (g, ko), at),
            JointKind::Spherical if in_leg[l] => {
                // The first ball of a leg: its centre is known, its spin is not.
                self.places[l].position = Some(at);
            }
            JointKind::Spherical | JointKind::Floating => self.place_ball(l, joint, (g, ko), at, reach),
        }
        Ok(())
    }

    /// A link on a revolute joint: turned by its fixed value, or a new group turned by
    /// `(cos, sin)` on the unit circle (within the arc of its limits when they are respected).
    fn place_revolute(&mut self, l: usize, joint: &Joint, limits: Option<(f64, f64)>, fixed: Option<f64>, (g, ko): (usize, IMat3), at: Pos) {
        let a = st::axis(&joint.axis);
        let name = &joint.name;
        if let Some(v) = fixed {
            self.places[l].rotation = Some((g, imat_mul(&ko, &rot_about(&a, v))));
        } else {
            let (mut dc, mut ds) = (interval(-1.0, 1.0), interval(-1.0, 1.0));
            if let (Some((lo, hi)), true) = (limits, self.respect_limits) {
                (dc, ds) = arc_box(stated(lo).convex_hull(stated(hi)));
                self.limits.push((self.readings.len(), stated(lo), stated(hi)));
            }
            let c = self.b.system.add_var(format!("cos_{name}"), VarRole::Primary, dc);
            let s = self.b.system.add_var(format!("sin_{name}"), VarRole::Primary, ds);
            self.b.define(Equation::circle(c, s));
            let mo = rot_times(&self.b.groups[g], &ko);
            let gr = self.b.rot_by(&mo, &a, c, s, name);
            let ng = self.b.new_group(gr);
            self.places[l].rotation = Some((ng, st::identity()));
            self.read(name.clone(), Reading::Angle { c, s });
        }
        self.places[l].position = Some(at);
    }

    /// A link on a prismatic joint: the parent's rotation, moved along the axis by the fixed
    /// value or by a travel variable.
    fn place_prismatic(&mut self, l: usize, joint: &Joint, limits: (f64, f64), fixed: Option<f64>, (g, ko): (usize, IMat3), mut at: Pos) {
        let a = st::axis(&joint.axis);
        let name = &joint.name;
        self.places[l].rotation = Some((g, ko));
        let w = st::apply(&ko, &a);
        match fixed {
            Some(v) => at.add_rotated(g, w.map(|x| x * stated(v))),
            None => {
                let d = self.b.system.add_var(format!("d_{name}"), VarRole::Primary, travel_domain(limits));
                if g == 0 {
                    for (r, wi) in at.rest.iter_mut().zip(w) {
                        r.add(&Form { terms: vec![(d, wi)], constant: point(0.0) });
                    }
                } else {
                    let dir = rot_apply(&self.b.groups[g], &w);
                    for (r, di) in at.rest.iter_mut().zip(&dir) {
                        let f = self.b.times_var(di, d);
                        r.add(&f);
                    }
                }
                self.read(name.clone(), Reading::Var(d));
            }
        }
        self.places[l].position = Some(at);
    }

    /// A link on a ball or floating joint: three Euler turns (yaw, pitch, roll) after the
    /// parent's rotation, and for a floating joint a free position and rotation in the root
    /// frame instead.
    fn place_ball(&mut self, l: usize, joint: &Joint, (g, ko): (usize, IMat3), mut at: Pos, reach: f64) {
        let name = &joint.name;
        let mut gr = rot_times(&self.b.groups[g], &ko);
        if joint.kind == JointKind::Floating {
            // The pose is free: position and rotation in the root frame.
            gr = const_rot(&st::identity());
            at = Pos::origin();
            let mut vars = [0; 3];
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                let v = self.b.system.add_var(format!("{name}.{axis}"), VarRole::Primary, interval(-reach, reach));
                at.rest[i] = Form::var(v);
                self.read(format!("{name}.{axis}"), Reading::Var(v));
                vars[i] = v;
            }
            self.floating.push((l, vars));
        }
        let z = point(0.0);
        let o1 = point(1.0);
        for (part, axis, dc) in [("yaw", [z, z, o1], interval(-1.0, 1.0)), ("pitch", [z, o1, z], interval(0.0, 1.0)), ("roll", [o1, z, z], interval(-1.0, 1.0))] {
            let c = self.b.system.add_var(format!("cos_{name}.{part}"), VarRole::Primary, dc);
            let s = self.b.system.add_var(format!("sin_{name}.{part}"), VarRole::Primary, interval(-1.0, 1.0));
            self.b.define(Equation::circle(c, s));
            gr = self.b.rot_by(&gr, &axis, c, s, &format!("{name}.{part}"));
            self.read(format!("{name}.{part}"), Reading::Angle { c, s });
        }
        let ng = self.b.new_group(gr);
        self.places[l].rotation = Some((ng, st::identity()));
        self.places[l].position = Some(at);
    }

    /// A floating link closed by a leg lies within the leg's reach of the leg's first ball:
    /// |p| ≤ |A| + max |u + d·w| + |t| (t: the ball on the floating link), a far tighter box
    /// than the sum of every offset in the file.
    fn bound_floating(&mut self, legs: &[Leg], reach: f64) {
        let m = self.m;
        for &(f, vars) in &self.floating {
            let start = self.b.system.initial_box();
            let mut r = reach;
            for leg in legs {
                let lp = &m.loops[leg.closure];
                if leg.far_link(m) != f {
                    continue;
                }
                let t = if lp.predecessor == f { lp.predecessor_origin.translation.vector } else { lp.successor_origin.translation.vector };
                let Some(apos) = self.places[m.joints[leg.joint].child].position.clone() else { continue };
                let a = self.b.forms(&apos).map(|x| x.eval(&start.dims));
                let na = (a[0].sqr() + a[1].sqr() + a[2].sqr()).sqrt().sup();
                let nu = (leg.u[0].sqr() + leg.u[1].sqr() + leg.u[2].sqr()).sqrt().sup();
                let nd = Leg::travel_bound(leg.travel_in(m, &self.leg_travel), &self.b.system);
                // w is a unit vector: |u + d·w| ≤ |u| + |d|; sums rounded up by a relative margin.
                r = r.min((na + nu + nd + t.norm()) * (1.0 + 1e-12) + 1e-12);
            }
            for v in vars {
                self.b.system.vars[v].domain = interval(-r, r);
            }
        }
    }

    /// The closure of loop `k`, the ball at the far end of `leg`: one distance row.
    fn close_leg(&mut self, k: usize, leg: &Leg) -> Result<(), LinkageError> {
        let m = self.m;
        let lp = &m.loops[k];
        let mut rows = Vec::new();
        let vanished_before = self.b.vanished.len();
        // |B − A|² = |u + d·w|² = |u|² + 2(u·w)d + d²
        let joint = &m.joints[leg.joint];
        let other = leg.far_link(m);
        let (Some((go, ko)), Some(po)) = (self.places[other].rotation, self.places[other].position.clone()) else {
            return Err(LinkageError::UnderConstrained(format!("loop '{}' joins two legs that spin between ball joints", lp.name)));
        };
        let t_other = if lp.predecessor == other { st::translation(&lp.predecessor_origin.translation.vector) } else { st::translation(&lp.successor_origin.translation.vector) };
        let mut bpos = po;
        bpos.add_rotated(go, st::apply(&ko, &t_other));
        let apos = self.places[joint.child].position.clone().expect("a leg's first ball is placed");
        let d = bpos.minus(&apos);
        let u = leg.u;
        let uu = u[0].sqr() + u[1].sqr() + u[2].sqr();
        let uw2 = point(2.0) * (u[0] * leg.w[0] + u[1] * leg.w[1] + u[2] * leg.w[2]);
        let length2 = match leg.travel_in(m, &self.leg_travel) {
            Some(Travel::Known(v)) => (uu + uw2 * v + v.sqr(), None),
            Some(Travel::Var(dv)) => (uu, Some((uw2, dv))),
            None => (uu, None),
        };
        self.b.distance(&d, length2, &lp.name, &mut rows).map_err(gap(&lp.name))?;
        let names: Vec<&str> = leg.links.iter().map(|&x| m.links[x].name.as_str()).collect();
        self.reductions.push(format!("{} (ball joints '{}' and '{}'): a distance constraint, no rotation", names.join(" + "), joint.name, lp.name));
        self.reductions.extend(vanished_note(&lp.name, &self.b.vanished[vanished_before..]));
        self.loop_rows.push((lp.name.clone(), rows));
        Ok(())
    }

    /// Loop `lp`'s frame on `link`: its rotation `(group, K)` and its origin.
    fn closure_side(&self, lp: &LoopClosure, link: usize, origin: &nalgebra::Isometry3<f64>, rpy: [f64; 3]) -> Result<((usize, IMat3), Pos), LinkageError> {
        let (Some((g, kk)), Some(p)) = (self.places[link].rotation, self.places[link].position.clone()) else {
            return Err(LinkageError::UnderConstrained(format!("loop '{}' closes on link '{}', which spins between two ball joints", lp.name, self.m.links[link].name)));
        };
        let mut at = p;
        at.add_rotated(g, st::apply(&kk, &st::translation(&origin.translation.vector)));
        Ok(((g, imat_mul(&kk, &st::rpy(rpy))), at))
    }

    /// The closure rows of loop `k` by its kind (`rest`: every link's rest orientation;
    /// `fixed_value`: its `--fix` value), and its frames for read-outs.
    fn close_joint(&mut self, k: usize, rest: &[UnitQuaternion<f64>], fixed_value: Option<f64>) -> Result<(), LinkageError> {
        let m = self.m;
        let lp = &m.loops[k];
        let mut rows = Vec::new();
        let vanished_before = self.b.vanished.len();
        let cannot = gap(&lp.name);
        let (fp, pp) = self.closure_side(lp, lp.predecessor, &lp.predecessor_origin, lp.predecessor_rpy)?;
        let (fs, ps) = self.closure_side(lp, lp.successor, &lp.successor_origin, lp.successor_rpy)?;
        let a = st::axis(&lp.axis);
        let rp = rot_times(&self.b.groups[fp.0], &fp.1);
        let rs = rot_times(&self.b.groups[fs.0], &fs.1);
        let (pf, sf) = (self.b.forms(&pp), self.b.forms(&ps));
        let axis_p = rot_apply(&rp, &a);
        let axis_s = rot_apply(&rs, &a);
        match (lp.kind, lp.compound) {
            (JointKind::Spherical, _) => self.b.equal(&pf, &sf, &mut rows).map_err(cannot)?,
            (JointKind::Fixed, _) => {
                self.b.equal(&pf, &sf, &mut rows).map_err(&cannot)?;
                for j in 0..2 {
                    self.b.equal(&col(&rp, j), &col(&rs, j), &mut rows).map_err(&cannot)?;
                }
            }
            (JointKind::Revolute { .. }, Some(Compound::Universal { axis2 })) => {
                self.b.equal(&pf, &sf, &mut rows).map_err(&cannot)?;
                let a2 = rot_apply(&rs, &st::axis(&axis2));
                let mut dot = Form::zero();
                for i in 0..3 {
                    let p = self.b.times_form(&axis_p[i], &a2[i], (&format!("axis{i}_{}", lp.name), &format!("axis2{i}_{}", lp.name)));
                    dot.add(&p);
                }
                self.b.zero(&dot, &mut rows).map_err(cannot)?;
            }
            (JointKind::Revolute { limits }, _) => {
                self.b.equal(&pf, &sf, &mut rows).map_err(&cannot)?;
                match fixed_value {
                    Some(v) => {
                        let turned = rot_times(&rp, &rot_about(&a, v));
                        for j in 0..2 {
                            self.b.equal(&col(&turned, j), &col(&rs, j), &mut rows).map_err(&cannot)?;
                        }
                    }
                    None => {
                        let w = rest[lp.predecessor] * (lp.predecessor_origin.rotation * lp.axis);
                        axes_agree(&mut self.b, &axis_p, &axis_s, w, &mut rows, &mut self.signs, &mut self.axis_pairs).map_err(cannot)?;
                        if let (Some((lo, hi)), true) = (limits, self.respect_limits) {
                            self.limits.push((self.readings.len(), stated(lo), stated(hi)));
                        }
                        self.read(lp.name.clone(), Reading::LoopAngle(k));
                    }
                }
            }
            (JointKind::Prismatic { limits }, _) => {
                let sides = Sides { rp, rs, axis_p, axis_s, pf, sf };
                self.close_prismatic(k, limits, &sides, rest, fixed_value, &mut rows)?;
            }
            (JointKind::Floating, _) => return Err(LinkageError::Unsupported(format!("loop '{}' is floating: it constrains nothing", lp.name))),
        }
        self.frames[k] = Some(LoopFrames { pred: fp, succ: fs, pred_at: pp, succ_at: ps, axis: a, across: across(&lp.axis) });
        self.reductions.extend(vanished_note(&lp.name, &self.b.vanished[vanished_before..]));
        self.loop_rows.push((lp.name.clone(), rows));
        Ok(())
    }

    /// A prismatic (or cylindrical) closure: rotations agree on two columns (axes only, for a
    /// cylindrical one), and `succ − pred = d·(axis in the world)`.
    fn close_prismatic(&mut self, k: usize, limits: (f64, f64), sides: &Sides, rest: &[UnitQuaternion<f64>], fixed_value: Option<f64>, rows: &mut Vec<usize>) -> Result<(), LinkageError> {
        let m = self.m;
        let lp = &m.loops[k];
        let cannot = gap(&lp.name);
        let Sides { rp, rs, axis_p, axis_s, pf, sf } = sides;
        let cylindrical = lp.compound == Some(Compound::Cylindrical);
        let mut travel_var = None;
        if cylindrical {
            let w = rest[lp.predecessor] * (lp.predecessor_origin.rotation * lp.axis);
            axes_agree(&mut self.b, axis_p, axis_s, w, rows, &mut self.signs, &mut self.axis_pairs).map_err(&cannot)?;
        } else {
            for j in 0..2 {
                self.b.equal(&col(rp, j), &col(rs, j), rows).map_err(&cannot)?;
            }
        }
        // succ − pred = d·(axis in the world)
        let mut target = pf.clone();
        match fixed_value {
            Some(v) => {
                for i in 0..3 {
                    target[i].add_scaled(&axis_p[i], stated(v));
                }
            }
            None => {
                let d = self.b.system.add_var(format!("d_{}", lp.name), VarRole::Primary, travel_domain(limits));
                for i in 0..3 {
                    let f = self.b.times_var(&axis_p[i], d);
                    target[i].add(&f);
                }
                travel_var = Some(d);
            }
        }
        self.b.equal(&target, sf, rows).map_err(&cannot)?;
        if cylindrical {
            self.read(lp.name.clone(), Reading::LoopAngle(k));
        }
        if travel_var.is_some() {
            let label = if cylindrical { format!("{}.travel", lp.name) } else { lp.name.clone() };
            self.read(label, Reading::LoopTravel(k));
        }
        Ok(())
    }

    /// Traced points: world coordinates as derived variables, one definition each.
    fn trace(&mut self, traces: &[(String, [f64; 3], String)]) -> Result<Vec<Trace3>, LinkageError> {
        let m = self.m;
        let mut trace_out = Vec::new();
        for (link_name, xyz, label) in traces {
            let link = m.link(link_name).ok_or_else(|| LinkageError::UnknownTraceLink(link_name.clone()))?;
            let (Some((g, kk)), Some(p)) = (self.places[link].rotation, self.places[link].position.clone()) else {
                return Err(LinkageError::UnderConstrained(format!("--trace {label}: link '{link_name}' spins between two ball joints")));
            };
            let mut at = p;
            at.add_rotated(g, st::apply(&kk, &xyz.map(stated)));
            let f = self.b.forms(&at);
            let mut vars = [0; 3];
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                let dom = self.b.initial(&f[i]);
                let v = self.b.system.add_var(format!("{axis}_{label}"), VarRole::Derived, dom);
                let mut e = f[i].clone();
                e.terms.push((v, point(-1.0)));
                let e = e.merged();
                let terms = e.terms.iter().map(|&(x, c)| Term { coef: c, mono: Monomial::Linear(x) }).collect();
                self.b.define(Equation::new(terms, e.constant));
                vars[i] = v;
            }
            trace_out.push(Trace3 { name: label.clone(), xyz: vars });
        }
        Ok(trace_out)
    }

    /// Each loop's rows with the definitions, propagated over the initial box: a loop proven
    /// empty on its own cannot close.
    fn check_closure(&self) -> Result<(), LinkageError> {
        let b = &self.b;
        let start = b.system.initial_box();
        for (name, rows) in &self.loop_rows {
            let mut sub = EquationSystem { vars: b.system.vars.clone(), equations: rows.iter().map(|&r| b.system.equations[r].clone()).collect() };
            sub.equations.extend(b.definitions.iter().map(|&r| b.system.equations[r].clone()));
            let mut probe = start.clone();
            if Propagation::new(&sub).contract(&mut probe) == Contraction::Empty {
                return Err(LinkageError::CannotClose(name.clone()));
            }
        }
        Ok(())
    }

    /// The problem, with `fixed` and the traced points.
    fn finish(self, fixed: &[(String, f64)], traces: Vec<Trace3>) -> SpatialProblem {
        SpatialProblem {
            system: self.b.system,
            name: self.m.name.clone(),
            free_joints: self.free_joints,
            fixed_joints: fixed.to_vec(),
            traces,
            reductions: self.reductions,
            groups: self.b.groups,
            links: self.places,
            loops: self.frames,
            readings: self.readings,
            limits: self.limits,
            signs: self.signs,
            axis_pairs: self.axis_pairs,
        }
    }
}

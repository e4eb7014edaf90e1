//! Choosing the 3R positioning structure of a real arm's URDF.
//!
//! Vendor files are trees, not chains: a `world` or `base` root with a fixed or floating joint,
//! side links (`base`, `tool0`, `flange`), six or seven revolute joints. The analyses need one
//! path with three revolute joints and a point that only those three move. `positioning` picks
//! them and returns a reduced `Mechanism` (that path only) that every 3R analysis takes as is,
//! with a `Choice` that says what was chosen and why.
//!
//! - Base and tip follow KDL/MoveIt: `base` (default: the root, or the link a floating root
//!   joint carries) and `tip` (default: the end
//!   link of the longest revolute path: the child of its last revolute joint, followed down a
//!   single line of fixed joints to its end, so a 3R file's `tool` link is the tip, while side
//!   links that branch off (`tool0` beside `flange`) stop the descent).
//! - Joints named in `locks` become fixed at the given value (a 7R arm is a 6R arm then).
//! - Three revolute joints: the point is the tip link's origin (or `tip_point`).
//! - Six: joints 1–3 position the wrist, judged from the axes of joints 4–6 wherever the file
//!   puts their frames (`wrist`: proven to meet within the tolerance, proven not to, or
//!   neither). With a spherical wrist the point is the wrist centre, which joints 4–6 do not
//!   move; otherwise a point of joint 3's child, which they do not move either: the origin of
//!   joint 4's frame (e.g. UR), or the point of axis 4 nearest axis 5 when that origin is on
//!   axis 3 (e.g. Fanuc CRX), where joint 3 would not move it; `tip_point` picks another point.
//! - `Scope` says what a verdict on the choice is about: the arm (a 3R arm, or a spherical
//!   wrist's centre), or only a 3R sub-chain and a point (the headline then names both).
//! - A point on a link after joint 3 is accepted only when every revolute axis between joint 3
//!   and that link passes through it (within `length_tolerance`), so the point is moved by
//!   joints 1–3 alone.
//!
//! The miss distances are bounded in interval arithmetic on the (rounded or exact) geometry.

use super::chain::{add, apply, cross, dot, sub, Pose, V3};
use super::Manip3rError;
use crate::kernel::interval::point;
use crate::model::{Joint, JointKind, Link, Mechanism};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Unit, Vector3};

mod wrist;

use self::wrist::{nearest_on_first, wrist, Wrist};

/// What the user asked for (all optional).
#[derive(Clone, Debug, Default)]
pub struct ChainSpec {
    /// Base link (default: the root).
    pub base: Option<String>,
    /// Tip link (default: see the module doc).
    pub tip: Option<String>,
    /// A point `(link, xyz in that link's frame)` to analyse instead of the default.
    pub tip_point: Option<(String, [f64; 3])>,
    /// Revolute joints held at a value (radians).
    pub locks: Vec<(String, f64)>,
    /// Largest distance (metres) by which axes may miss a point that joints 4… must not move.
    /// 0 means the default, `LENGTH_TOLERANCE`.
    pub length_tolerance: f64,
}

/// Default for `ChainSpec::length_tolerance`: a micrometre, far below any machined offset and
/// far above what a 1e-5 rad rounding of an orientation moves an axis over a metre-sized arm.
pub(crate) const LENGTH_TOLERANCE: f64 = 1e-6;

/// What was chosen, for the report.
#[derive(Clone, Debug)]
pub struct Choice {
    /// Base link.
    pub base: String,
    /// Tip link of the chain as chosen (before cutting at the analysed point).
    pub tip: String,
    /// The three revolute joints analysed, base first.
    pub joints: [String; 3],
    /// Revolute joints on the chain after the third (they do not move the point).
    pub wrist_joints: Vec<String>,
    /// Locked joints and their values.
    pub locked: Vec<(String, f64)>,
    /// The analysed point: link and coordinates in that link's frame.
    pub point_link: String,
    /// Coordinates of the point in `point_link`'s frame.
    pub point: [f64; 3],
    /// Upper bound (metres) of the distance of the point from the wrist axes (0 when exact).
    pub wrist_miss: f64,
    /// Why this chain and point.
    pub reason: String,
    /// The joint whose frame origin is the analysed point, when that is the choice (a 6R arm
    /// without a spherical wrist): the reduced chain's link for it is made up.
    pub origin_of: Option<String>,
    /// Six joints without a spherical wrist: a lower bound (metres) of how far the wrist axes
    /// miss one point, when measured.
    pub wrist_spread: Option<f64>,
    /// Six-joint chains: whether axes 4-6 were proven to meet in one point (true) or to miss
    /// every point (false); `None` for other chains or when neither was proven.
    pub spherical_wrist: Option<bool>,
    /// What a verdict on this chain and point is about.
    pub scope: Scope,
}

impl Choice {
    /// The analysed point as the file names it, for messages, when the reduced chain's name for
    /// it is made up: the joint whose origin it is and the link that holds it.
    pub fn origin_text(&self) -> Option<String> {
        self.origin_of.as_ref().map(|joint| format!("(the origin of joint '{joint}', in link '{}')", self.point_link))
    }
}

/// What the 3R analyses of a choice speak for: the arm, or only a sub-chain and a point.
#[derive(Clone, Debug, PartialEq)]
pub struct Scope {
    /// The analysed sub-chain and point, e.g. `3R sub-chain joints 1-3 (joint_1, joint_2,
    /// joint_3) of 'ur5', point link_3@-0.39225,0,0`.
    pub subject: String,
    /// True when the 3R verdict is the arm's: a three-joint arm, or a six-joint arm analysed at
    /// the centre of its spherical wrist (its positioning structure). False when the wrist is
    /// not spherical, joints are locked or the point was given by hand on a longer chain.
    pub stands_for_arm: bool,
    /// When it does not stand for the arm: the question it leaves open.
    pub not_answered: Option<String>,
}

/// The reduced mechanism and what was chosen. `snap_tolerance` is the rounding policy's (radians):
/// wrist axes that a turn of it could make meet are judged to meet.
pub(crate) fn positioning(m: &Mechanism, spec: &ChainSpec, snap_tolerance: f64) -> Result<(Mechanism, Choice), Manip3rError> {
    if !m.loops.is_empty() {
        return Err(Manip3rError::NotSerial(format!("it has {} loop closures", m.loops.len())));
    }
    let tol = if spec.length_tolerance > 0.0 { spec.length_tolerance } else { LENGTH_TOLERANCE };
    let base = match &spec.base {
        Some(b) => find_link(m, b, "--base")?,
        None => floating_root(m).unwrap_or(m.root),
    };
    check_locks(m, spec)?;
    let rq = Request { m, spec, base };
    let tip = match (&spec.tip, &spec.tip_point) {
        (Some(t), _) => find_link(m, t, "--tip")?,
        (None, Some((l, _))) => find_link(m, l, "--tip-point")?,
        (None, None) => rq.default_tip()?,
    };
    let path = rq.below(tip).ok_or_else(|| Manip3rError::Selection(format!("tip '{}' is not below base '{}'", m.links[tip].name, m.links[base].name)))?;
    rq.check_path(&path, tip)?;
    let revolute: Vec<usize> = path.iter().copied().filter(|&j| rq.moving(j)).collect();
    let n = revolute.len();
    let (b, t) = (m.links[base].name.clone(), m.links[tip].name.clone());
    if n < 3 {
        return Err(Manip3rError::NotThreeR(format!("the chain from '{b}' to '{t}' has {n} revolute joints")));
    }
    let third = path.iter().position(|&j| j == revolute[2]).expect("invariant: on the path");
    let l3 = m.joints[revolute[2]].child;
    // Poses of every later joint frame, and of every later link, in link 3's frame.
    let mut acc = Pose::identity();
    let mut frames = Vec::new(); // (joint, its frame in l3's frame, child's frame in l3's frame)
    for &j in &path[third + 1..] {
        let frame = acc.then(&Pose::from_origin(&m.joints[j], 0.0));
        acc = match rq.locked(j) {
            Some(v) => frame.then(&rotation(&m.joints[j], v)),
            None => frame,
        };
        frames.push((j, frame, acc));
    }
    let later: Vec<(usize, Pose)> = frames.iter().filter(|(j, _, _)| rq.moving(*j)).map(|(j, f, _)| (*j, *f)).collect();
    let names = |js: &[usize]| js.iter().map(|&j| m.joints[j].name.clone()).collect::<Vec<_>>();
    let wrist_joints = names(&revolute[3..]);
    let joints: [String; 3] = [0, 1, 2].map(|k| m.joints[revolute[k]].name.clone());
    let mut choice = Choice {
        base: b.clone(),
        tip: t.clone(),
        joints: joints.clone(),
        wrist_joints: wrist_joints.clone(),
        locked: spec.locks.clone(),
        point_link: t.clone(),
        point: [0.0; 3],
        wrist_miss: 0.0,
        reason: String::new(),
        origin_of: None,
        wrist_spread: None,
        spherical_wrist: None,
        scope: Scope { subject: String::new(), stands_for_arm: false, not_answered: None },
    };
    let lock_text = if spec.locks.is_empty() { String::new() } else { format!(" with {} locked", spec.locks.iter().map(|(n, v)| format!("{n}={v}")).collect::<Vec<_>>().join(", ")) };
    let picked = Picked { rq: &rq, tol, tip, revolute: &revolute, l3, frames: &frames, later: &later, names: (&b, &t), joints: &joints, wrist_joints: &wrist_joints, lock_text: &lock_text };
    // Where the point hangs (None: keep the whole path, the tip's origin being the point).
    let point_in_l3: Option<Attach> = if let Some((pl, xyz)) = &spec.tip_point {
        picked.given_point(pl, xyz, &mut choice)?
    } else if n == 3 {
        choice.reason = format!("chain {b} -> {t}{lock_text}: three revolute joints; the point is the origin of '{t}'");
        None
    } else if n == 6 {
        Some(picked.six_joint_point(snap_tolerance, &mut choice))
    } else {
        let hint = if n == 7 { format!("hold one with --fix JOINT=VALUE (e.g. --fix {}=0)", m.joints[revolute[2]].name) } else { "cut it with --base/--tip or give --tip-point LINK@X,Y,Z".into() };
        return Err(Manip3rError::NotThreeR(format!("the chain from '{b}' to '{t}' has {n} revolute joints{lock_text}: {hint}")));
    };
    let (links, joints_out) = rq.reduced(&path, third, point_in_l3);
    let on_path: Vec<usize> = path.iter().copied().filter(|&j| matches!(m.joints[j].kind, JointKind::Revolute { .. })).collect();
    let numbers: Vec<usize> = revolute[..3].iter().map(|j| 1 + on_path.iter().position(|k| k == j).expect("invariant: on the path")).collect();
    choice.scope = scope(&m.name, &choice, &numbers, on_path.len(), spec.tip_point.is_some(), &lock_text);
    Ok((Mechanism { name: m.name.clone(), links, joints: joints_out, loops: Vec::new(), root: 0, transmission_joints: Vec::new() }, choice))
}

/// The link `name` of `m`, which the option `what` named.
fn find_link(m: &Mechanism, name: &str, what: &str) -> Result<usize, Manip3rError> {
    m.link(name).ok_or_else(|| Manip3rError::Selection(format!("{what} '{name}' is not a link of the file")))
}

/// Every lock (`ChainSpec::locks`, `--fix`) names a revolute joint of the file, with a finite value
/// within its limits.
fn check_locks(m: &Mechanism, spec: &ChainSpec) -> Result<(), Manip3rError> {
    for (name, value) in &spec.locks {
        let j = m.joint(name).ok_or_else(|| Manip3rError::Selection(format!("--fix: '{name}' is not a joint of the file")))?;
        let JointKind::Revolute { limits } = m.joints[j].kind else {
            return Err(Manip3rError::Selection(format!("--fix: joint '{name}' is not revolute")));
        };
        if !value.is_finite() {
            return Err(Manip3rError::Selection(format!("--fix: the value for '{name}' is not a finite number")));
        }
        if let Some((lo, hi)) = limits {
            if *value < lo || *value > hi {
                return Err(Manip3rError::Selection(format!("--fix: {name}={value} is outside its limits [{lo}, {hi}]")));
            }
        }
    }
    Ok(())
}

/// The arm, the request and the base: what every step of `positioning` asks of them.
struct Request<'a> {
    m: &'a Mechanism,
    spec: &'a ChainSpec,
    base: usize,
}

impl Request<'_> {
    /// The value joint `j` is locked at, if any.
    fn locked(&self, j: usize) -> Option<f64> {
        self.spec.locks.iter().find(|(n, _)| *n == self.m.joints[j].name).map(|(_, v)| *v)
    }

    /// A revolute joint that is not locked.
    fn moving(&self, j: usize) -> bool {
        matches!(self.m.joints[j].kind, JointKind::Revolute { .. }) && self.locked(j).is_none()
    }

    /// Joints from base down to `l`, or None when `l` is not below base.
    fn below(&self, l: usize) -> Option<Vec<usize>> {
        let m = self.m;
        let full = m.path_to(l);
        if self.base == m.root {
            return Some(full);
        }
        if l == self.base {
            return Some(Vec::new());
        }
        full.iter().position(|&j| m.joints[j].parent == self.base).map(|k| full[k..].to_vec())
    }

    /// The end link of the longest revolute path: the child of a moving revolute joint with the
    /// most moving revolute joints above it (side links on fixed joints lose). Prismatic joints
    /// count as moving here, so that a chain with one is refused by name later rather than cut
    /// short before it.
    fn default_tip(&self) -> Result<usize, Manip3rError> {
        let m = self.m;
        let movable = |j: usize| self.moving(j) || matches!(m.joints[j].kind, JointKind::Prismatic { .. });
        let count = |l: usize| self.below(l).map(|p| p.iter().filter(|&&j| movable(j)).count());
        let best = (0..m.links.len()).filter_map(count).max().unwrap_or(0);
        let ends: Vec<usize> = (0..m.links.len())
            .filter(|&l| m.links[l].parent_joint.is_some_and(&movable) && count(l) == Some(best))
            .collect();
        match ends.as_slice() {
            // Down a single line of fixed joints to its end link (a 3R file's `tool`);
            // where it branches (tool0 beside flange) the branching link ends the chain.
            [t] => {
                let mut at = *t;
                Ok(loop {
                    let kids: Vec<usize> = m.joints.iter().filter(|j| j.parent == at).map(|j| j.child).collect();
                    match kids.as_slice() {
                        [c] if matches!(m.joints[m.links[*c].parent_joint.expect("child")].kind, JointKind::Fixed) => at = *c,
                        _ => break at,
                    }
                })
            }
            [] => Err(Manip3rError::NotThreeR(format!("no revolute joint below link '{}'", m.links[self.base].name))),
            many => {
                let names: Vec<&str> = many.iter().map(|&l| m.links[l].name.as_str()).collect();
                Err(Manip3rError::Selection(format!("several end links with {best} revolute joints ({}): choose one with --tip", names.join(", "))))
            }
        }
    }

    /// The locks lie on `path` (base to `tip`), and its joints are revolute (not following
    /// another through `<mimic>`, unless locked) or fixed.
    fn check_path(&self, path: &[usize], tip: usize) -> Result<(), Manip3rError> {
        let m = self.m;
        for (name, _) in &self.spec.locks {
            if !path.iter().any(|&j| m.joints[j].name == *name) {
                return Err(Manip3rError::Selection(format!("--fix: joint '{name}' is not on the chain from '{}' to '{}'", m.links[self.base].name, m.links[tip].name)));
            }
        }
        for &j in path {
            let joint = &m.joints[j];
            match joint.kind {
                JointKind::Revolute { .. } if joint.mimic.is_some() && self.locked(j).is_none() => {
                    let leader = joint.mimic.as_ref().map_or("", |x| x.joint.as_str());
                    return Err(Manip3rError::NotThreeR(format!("joint '{}' follows '{leader}' through <mimic>, which the 3R analyses do not model yet", joint.name)));
                }
                JointKind::Revolute { .. } | JointKind::Fixed => {}
                JointKind::Prismatic { .. } => return Err(Manip3rError::NotThreeR(format!("joint '{}' is prismatic", joint.name))),
                JointKind::Spherical | JointKind::Floating => return Err(Manip3rError::NotThreeR(format!("joint '{}' is not revolute", joint.name))),
            }
        }
        Ok(())
    }

    /// The reduced mechanism's links and joints: base, the links down to joint 3's child (or the
    /// whole path when the tip's origin is the point), locked joints made fixed, and a virtual
    /// tip link at the point.
    fn reduced(&self, path: &[usize], third: usize, point_in_l3: Option<Attach>) -> (Vec<Link>, Vec<Joint>) {
        let m = self.m;
        let base = self.base;
        let keep: Vec<usize> = if matches!(point_in_l3, Some(Attach::UnderJoint3(..))) { path[..=third].to_vec() } else { path.to_vec() };
        let mut links = vec![Link { name: m.links[base].name.clone(), parent_joint: None, collisions: m.links[base].collisions.clone() }];
        let mut joints_out: Vec<Joint> = Vec::new();
        for &j in &keep {
            let mut joint = m.joints[j].clone();
            joint.parent = links.len() - 1;
            joint.child = links.len();
            if let Some(v) = self.locked(j) {
                joint.origin *= Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&Unit::new_normalize(joint.axis), v));
                let (r, p, y) = joint.origin.rotation.euler_angles();
                joint.rpy = [r, p, y];
                // A quarter turn about a coordinate axis keeps an exact frame exact.
                joint.exact_rotation = match (joint.exact_rotation, crate::model::rounding::exact_turn(&joint.axis, v)) {
                    (Some(frame), Some(turn)) => Some(crate::model::rounding::compose(&frame, &turn)),
                    (frame, _) if v == 0.0 => frame,
                    _ => None,
                };
                joint.kind = JointKind::Fixed;
                joint.mimic = None;
            }
            let child = &m.links[m.joints[j].child];
            links.push(Link { name: child.name.clone(), parent_joint: Some(joints_out.len()), collisions: child.collisions.clone() });
            joints_out.push(joint);
        }
        if let Some(Attach::UnderJoint3(p, mut name) | Attach::UnderTip(p, mut name)) = point_in_l3 {
            while m.link(&name).is_some() || m.joint(&name).is_some() {
                name.push('_');
            }
            let mid = p.map(|x| x.mid());
            let parent = links.len() - 1;
            joints_out.push(Joint {
                name: format!("{name}_joint"),
                kind: JointKind::Fixed,
                parent,
                child: links.len(),
                origin: Isometry3::translation(mid[0], mid[1], mid[2]),
                rpy: [0.0; 3],
                axis: Vector3::x(),
                mimic: None,
                exact_rotation: Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
            });
            links.push(Link { name, parent_joint: Some(joints_out.len() - 1), collisions: Vec::new() });
        }
        (links, joints_out)
    }
}

/// The chain picked (base to tip, its revolute joints, the frames after joint 3), with what
/// choosing the analysed point reads from it.
struct Picked<'a> {
    rq: &'a Request<'a>,
    /// The length tolerance (metres).
    tol: f64,
    tip: usize,
    revolute: &'a [usize],
    /// Joint 3's child.
    l3: usize,
    /// Per joint after joint 3: (joint, its frame in l3's frame, child's frame in l3's frame).
    frames: &'a [(usize, Pose, Pose)],
    /// The moving ones among them, with their frames.
    later: &'a [(usize, Pose)],
    /// Base and tip link names.
    names: (&'a str, &'a str),
    joints: &'a [String; 3],
    wrist_joints: &'a [String],
    lock_text: &'a str,
}

impl Picked<'_> {
    /// Joint `j`'s axis in l3's frame, as (point, direction), from its frame `f`.
    fn axis_line(&self, f: &Pose, j: usize) -> (V3, V3) {
        (f.t, apply(&f.r, &axis3(&self.rq.m.joints[j])))
    }

    /// Upper bound of the largest distance of `p` from the later axes (unit vectors).
    fn miss(&self, p: &V3) -> f64 {
        self.later.iter().map(|(j, f)| {
            let (o, d) = self.axis_line(f, *j);
            let c = cross(&sub(p, &o), &d);
            dot(&c, &c).sup().max(0.0).sqrt()
        }).fold(0.0, f64::max)
    }

    /// The point given by `--tip-point` (`pl`, `xyz`), accepted when the later axes pass
    /// through it; `None` when it is the tip's origin on a 3R chain.
    fn given_point(&self, pl: &str, xyz: &[f64; 3], choice: &mut Choice) -> Result<Option<Attach>, Manip3rError> {
        let m = self.rq.m;
        let (b, t) = self.names;
        let (n, lock_text, joints) = (self.revolute.len(), self.lock_text, self.joints);
        let l = find_link(m, pl, "--tip-point")?;
        if !xyz.iter().all(|v| v.is_finite()) {
            return Err(Manip3rError::Selection("--tip-point: coordinates must be finite".into()));
        }
        let local: V3 = xyz.map(point);
        let in_l3 = if l == self.l3 {
            local
        } else if let Some((_, _, f)) = self.frames.iter().find(|(j, _, _)| m.joints[*j].child == l) {
            add(&apply(&f.r, &local), &f.t)
        } else {
            return Err(Manip3rError::Selection(format!("--tip-point: link '{pl}' is not on the chain after joint '{}' (joints 1-3 must move it)", joints[2])));
        };
        let mv = self.miss(&in_l3);
        if mv > self.tol {
            return Err(Manip3rError::Selection(format!("--tip-point: the point is {mv:.3e} m off the axes of {}, which would move it", self.wrist_joints.join(", "))));
        }
        choice.point_link = pl.to_string();
        choice.point = *xyz;
        choice.wrist_miss = mv;
        choice.reason = format!("chain {b} -> {t}{lock_text}, {n} revolute joints; the point {xyz:?} of link '{pl}' given by --tip-point, moved by {} only", joints.join(", "));
        let name = format!("{pl}@{},{},{}", xyz[0], xyz[1], xyz[2]);
        Ok(if n == 3 && l == self.tip {
            // The whole path is kept (its links carry collision shapes); the point hangs
            // under the tip at its coordinates there, unless it is the tip's origin.
            (xyz != &[0.0; 3]).then_some(Attach::UnderTip(local, name))
        } else {
            Some(Attach::UnderJoint3(in_l3, name))
        })
    }

    /// The point of a six-joint chain: the wrist centre when the wrist is spherical, else a
    /// point of joint 3's child that joints 4-6 do not move.
    fn six_joint_point(&self, snap_tolerance: f64, choice: &mut Choice) -> Attach {
        let m = self.rq.m;
        let (b, t) = self.names;
        let (tol, later, lock_text, joints, wrist_joints) = (self.tol, self.later, self.lock_text, self.joints, self.wrist_joints);
        let axes: [(V3, V3); 3] = [0, 1, 2].map(|k| self.axis_line(&later[k].1, later[k].0));
        // A turn of the snapping tolerance at a wrist frame moves an axis by that angle times
        // the frame's distance from the point: the axes "meet" within that much, and never
        // within less than the length tolerance.
        let origins: Vec<V3> = self.frames.iter().take_while(|(j, _, _)| *j != later[2].0).map(|(_, f, _)| f.t).chain([later[2].1.t]).collect();
        let wrist_tol = |c: &V3| {
            let lever: f64 = origins.iter().map(|o| { let d = sub(c, o); dot(&d, &d).sup().max(0.0).sqrt() }).sum();
            tol.max(snap_tolerance * lever)
        };
        match wrist(&axes, &wrist_tol) {
            Wrist::Spherical { centre, miss: mv } => {
                let x = centre.map(|v| v.mid());
                choice.point_link = m.links[self.l3].name.clone();
                choice.point = x;
                choice.wrist_miss = mv;
                choice.spherical_wrist = Some(true);
                choice.reason = format!(
                    "chain {b} -> {t}{lock_text}: 6 revolute joints with a spherical wrist (axes of {} meet within {mv:.1e} m); joints {} position the wrist centre {:?} in '{}'",
                    wrist_joints.join(", "), joints.join(", "), choice.point, choice.point_link
                );
                Attach::UnderJoint3(x.map(point), "wrist_centre".into())
            }
            test => {
                choice.spherical_wrist = matches!(test, Wrist::Apart(_)).then_some(false);
                let why = match &test {
                    Wrist::Apart(t) => format!("no point lies within {t:.1e} m of the axes of {}", wrist_joints.join(", ")),
                    _ => format!("the axes of {} neither provably meet nor provably miss one point", wrist_joints.join(", ")),
                };
                // Every point of joint 3's child is moved by joints 1-3 alone; one on axis 3
                // would not move with joint 3 (a degenerate map). Joint 4's frame origin is
                // taken when it is off axis 3, else the point of axis 4 nearest axis 5 (where
                // they meet, when they do), a point of the wrist fixed by the geometry.
                let (o4, d4) = axes[0];
                let a3 = axis3(&m.joints[self.revolute[2]]);
                let off_axis3 = |p: &V3| {
                    let c = cross(p, &a3);
                    dot(&c, &c).inf() > tol * tol * dot(&a3, &a3).sup()
                };
                let mid = |v: &V3| v.map(|x| x.mid());
                let foot = nearest_on_first(&mid(&o4), &mid(&d4), &mid(&axes[1].0), &mid(&axes[1].1)).map(|x| x.map(point));
                let (p, what) = match foot {
                    Some(f) if !off_axis3(&o4) && off_axis3(&f) => (f, format!("the point of the axis of '{}' nearest the axis of '{}'", wrist_joints[0], wrist_joints[1])),
                    _ => (o4, format!("the origin of joint '{}'", wrist_joints[0])),
                };
                choice.point_link = m.links[self.l3].name.clone();
                choice.point = mid(&p);
                // A point of joint 4's parent link: joints 4-6 do not move it.
                choice.wrist_miss = 0.0;
                choice.reason = format!(
                    "chain {b} -> {t}{lock_text}: 6 revolute joints, wrist not spherical ({why}); analysing {what} {:?} in '{}', on its axis, which joints 4-6 do not move (--tip-point LINK@X,Y,Z for another point)",
                    choice.point, choice.point_link
                );
                if what.starts_with("the origin") {
                    choice.origin_of = Some(wrist_joints[0].clone());
                }
                choice.wrist_spread = match test {
                    Wrist::Apart(t) => Some(t),
                    _ => None,
                };
                let name = if what.starts_with("the origin") { format!("{}_origin", wrist_joints[0]) } else { "wrist_point".into() };
                Attach::UnderJoint3(p, name)
            }
        }
    }
}

/// What a verdict on `choice` is about. `numbers` are the analysed joints' places (from 1) among
/// the `total` revolute joints of the chain.
fn scope(robot: &str, choice: &Choice, numbers: &[usize], total: usize, by_hand: bool, lock_text: &str) -> Scope {
    let [x, y, z] = choice.point;
    let point = format!("{}@{x},{y},{z}", choice.point_link);
    let places = if numbers.windows(2).all(|w| w[1] == w[0] + 1) {
        format!("joints {}-{}", numbers[0], numbers[2])
    } else {
        format!("joints {}", numbers.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", "))
    };
    let names = choice.joints.join(", ");
    if total == 3 {
        return Scope { subject: format!("3R arm '{robot}' ({names}), point {point}"), stands_for_arm: true, not_answered: None };
    }
    if choice.spherical_wrist == Some(true) && !by_hand && choice.locked.is_empty() {
        return Scope { subject: format!("positioning structure of '{robot}' ({places}: {names}), wrist centre {point}"), stands_for_arm: true, not_answered: None };
    }
    Scope {
        subject: format!("3R sub-chain {places} ({names}) of '{robot}'{lock_text}, point {point}"),
        stands_for_arm: false,
        not_answered: Some(format!("not the arm's verdict: whether the {total}-joint arm '{robot}' is cuspidal is a different question, not answered here")),
    }
}

/// The default base below a floating root joint: the link it carries (the robot's own frame;
/// the floating joint only places the robot in the world, as a virtual joint does in MoveIt).
/// `None` unless the root's only joint is floating.
fn floating_root(m: &Mechanism) -> Option<usize> {
    let mut from_root = m.joints.iter().filter(|j| j.parent == m.root);
    match (from_root.next(), from_root.next()) {
        (Some(j), None) if j.kind == JointKind::Floating => Some(j.child),
        _ => None,
    }
}

/// Where the analysed point is attached in the reduced mechanism, with its link's name.
enum Attach {
    /// In the frame of joint 3's child, the path cut there.
    UnderJoint3(V3, String),
    /// In the tip's frame, the whole path kept.
    UnderTip(V3, String),
}

/// The rotation of a locked joint about its axis by `v`, as a pose.
fn rotation(joint: &Joint, v: f64) -> Pose {
    let a = axis3(joint);
    let (s, c) = (crate::kernel::interval::trig::sin(point(v)), crate::kernel::interval::trig::cos(point(v)));
    let mut r = [[point(0.0); 3]; 3];
    for col in 0..3 {
        let mut e = [point(0.0); 3];
        e[col] = point(1.0);
        let [x, y, z] = super::chain::rodrigues(&a, &e);
        let v = add(&add(&super::chain::scale(&x, c), &super::chain::scale(&y, s)), &z);
        for row in 0..3 {
            r[row][col] = v[row];
        }
    }
    Pose { r, t: [point(0.0); 3] }
}

fn axis3(joint: &Joint) -> V3 {
    let a = joint.axis;
    [point(a[0]), point(a[1]), point(a[2])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn line(o: Vector3<f64>, u: Vector3<f64>) -> (V3, V3) {
        ([o[0], o[1], o[2]].map(point), [u[0], u[1], u[2]].map(point))
    }

    fn unit(a: f64, b: f64) -> Vector3<f64> {
        Vector3::new(a.cos() * b.cos(), a.sin() * b.cos(), b.sin())
    }

    proptest! {
        /// Three axes through one point, each given by a point anywhere along it (as frames can
        /// be placed anywhere on their axes): proven to meet, at that point.
        #[test]
        fn concurrent_axes_meet_wherever_their_frames_are(
            c in prop::array::uniform3(-1.0f64..1.0),
            dirs in prop::array::uniform3((0.0f64..std::f64::consts::TAU, -1.5f64..1.5)),
            along in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let c = Vector3::from(c);
            let us = dirs.map(|(a, b)| unit(a, b));
            // Skip nearly parallel pairs: then no point is fixed by the geometry.
            prop_assume!((0..3).all(|i| us[i].cross(&us[(i + 1) % 3]).norm() > 0.1));
            let axes = [0, 1, 2].map(|k| line(c + us[k] * along[k], us[k]));
            match wrist(&axes, &|_| LENGTH_TOLERANCE) {
                Wrist::Spherical { centre, miss } => {
                    prop_assert!(miss <= LENGTH_TOLERANCE);
                    prop_assert!((Vector3::from(centre.map(|x| x.mid())) - c).norm() < 1e-9);
                }
                _ => prop_assert!(false, "not proven to meet"),
            }
        }

        /// The same with the third axis moved off the point by more than twice the tolerance:
        /// proven to miss (or, very close to parallel, at least never claimed to meet).
        #[test]
        fn an_offset_axis_is_proven_apart(
            c in prop::array::uniform3(-1.0f64..1.0),
            dirs in prop::array::uniform3((0.0f64..std::f64::consts::TAU, -1.5f64..1.5)),
            offset in 1e-5f64..0.2,
        ) {
            let c = Vector3::from(c);
            let us = dirs.map(|(a, b)| unit(a, b));
            prop_assume!((0..3).all(|i| us[i].cross(&us[(i + 1) % 3]).norm() > 0.1));
            let away = us[2].cross(&us[0]).normalize() * offset;
            let axes = [line(c, us[0]), line(c, us[1]), line(c + away, us[2])];
            match wrist(&axes, &|_| LENGTH_TOLERANCE) {
                Wrist::Apart(t) => prop_assert_eq!(t, LENGTH_TOLERANCE),
                Wrist::Spherical { .. } => prop_assert!(false, "an axis {offset} m off was said to meet"),
                Wrist::Undecided => prop_assert!(offset < 1e-3, "undecided at {offset} m"),
            }
        }
    }

    #[test]
    fn parallel_wrist_axes_are_apart() {
        // Axes 4 and 6 parallel 0.15 apart, axis 5 meeting axis 4 (a CRX-like wrist).
        let axes = [line(Vector3::zeros(), Vector3::x()), line(Vector3::new(0.54, -0.15, 0.0), Vector3::y()), line(Vector3::new(0.7, -0.15, 0.0), Vector3::x())];
        assert!(matches!(wrist(&axes, &|_| LENGTH_TOLERANCE), Wrist::Apart(_)));
        assert_eq!(nearest_on_first(&[0.0; 3], &[1.0, 0.0, 0.0], &[0.54, -0.15, 0.0], &[0.0, 1.0, 0.0]), Some([0.54, 0.0, 0.0]));
    }
}

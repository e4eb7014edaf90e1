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
//! - Six: joints 1–3 position the wrist. With a spherical wrist (axes 4, 5 and 6 through one
//!   point) the point is the wrist centre, which joints 4–6 do not move; otherwise (e.g. UR)
//!   the origin of joint 4's frame, on axis 4, which joints 4–6 do not move either; `tip_point`
//!   picks another point.
//! - A point on a link after joint 3 is accepted only when every revolute axis between joint 3
//!   and that link passes through it (within `length_tolerance`), so the point is moved by
//!   joints 1–3 alone.
//!
//! The miss distances are bounded in interval arithmetic on the (rounded or exact) geometry.

use super::chain::{add, apply, cross, dot, sub, Pose, V3};
use super::Manip3rError;
use crate::interval::point;
use crate::model::{Joint, JointKind, Link, Mechanism};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Unit, Vector3};

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
    /// 0 means the default, [`LENGTH_TOLERANCE`].
    pub length_tolerance: f64,
}

/// Default for `ChainSpec::length_tolerance`: a micrometre, far below any machined offset and
/// far above what a 1e-5 rad rounding of an orientation moves an axis over a metre-sized arm.
pub const LENGTH_TOLERANCE: f64 = 1e-6;

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
}

impl Choice {
    /// The analysed point as the file names it, for messages, when the reduced chain's name for
    /// it is made up: the joint whose origin it is and the link that holds it.
    pub fn origin_text(&self) -> Option<String> {
        self.origin_of.as_ref().map(|joint| format!("(the origin of joint '{joint}', in link '{}')", self.point_link))
    }
}

/// The reduced mechanism and what was chosen.
pub fn positioning(m: &Mechanism, spec: &ChainSpec) -> Result<(Mechanism, Choice), Manip3rError> {
    if !m.loops.is_empty() {
        return Err(Manip3rError::NotSerial(format!("it has {} loop closures", m.loops.len())));
    }
    let tol = if spec.length_tolerance > 0.0 { spec.length_tolerance } else { LENGTH_TOLERANCE };
    let link = |name: &str, what: &str| m.link(name).ok_or_else(|| Manip3rError::Selection(format!("{what} '{name}' is not a link of the file")));
    let base = match &spec.base {
        Some(b) => link(b, "--base")?,
        None => floating_root(m).unwrap_or(m.root),
    };
    for (name, value) in &spec.locks {
        let j = m.joint(name).ok_or_else(|| Manip3rError::Selection(format!("--lock: '{name}' is not a joint of the file")))?;
        let JointKind::Revolute { limits } = m.joints[j].kind else {
            return Err(Manip3rError::Selection(format!("--lock: joint '{name}' is not revolute")));
        };
        if !value.is_finite() {
            return Err(Manip3rError::Selection(format!("--lock: the value for '{name}' is not a finite number")));
        }
        if let Some((lo, hi)) = limits {
            if *value < lo || *value > hi {
                return Err(Manip3rError::Selection(format!("--lock: {name}={value} is outside its limits [{lo}, {hi}]")));
            }
        }
    }
    let locked = |j: usize| spec.locks.iter().find(|(n, _)| *n == m.joints[j].name).map(|(_, v)| *v);
    let moving = |j: usize| matches!(m.joints[j].kind, JointKind::Revolute { .. }) && locked(j).is_none();
    // Joints from base down to `l`, or None when `l` is not below base.
    let below = |l: usize| -> Option<Vec<usize>> {
        let full = m.path_to(l);
        if base == m.root {
            return Some(full);
        }
        if l == base {
            return Some(Vec::new());
        }
        full.iter().position(|&j| m.joints[j].parent == base).map(|k| full[k..].to_vec())
    };
    let tip = match (&spec.tip, &spec.tip_point) {
        (Some(t), _) => link(t, "--tip")?,
        (None, Some((l, _))) => link(l, "--tip-point")?,
        (None, None) => {
            // The end link of the longest revolute path: the child of a moving revolute joint
            // with the most moving revolute joints above it (side links on fixed joints lose).
            // Prismatic joints count as moving here, so that a chain with one is refused by
            // name below rather than cut short before it.
            let movable = |j: usize| moving(j) || matches!(m.joints[j].kind, JointKind::Prismatic { .. });
            let count = |l: usize| below(l).map(|p| p.iter().filter(|&&j| movable(j)).count());
            let best = (0..m.links.len()).filter_map(count).max().unwrap_or(0);
            let ends: Vec<usize> = (0..m.links.len())
                .filter(|&l| m.links[l].parent_joint.is_some_and(&movable) && count(l) == Some(best))
                .collect();
            match ends.as_slice() {
                // Down a single line of fixed joints to its end link (a 3R file's `tool`);
                // where it branches (tool0 beside flange) the branching link ends the chain.
                [t] => {
                    let mut at = *t;
                    loop {
                        let kids: Vec<usize> = m.joints.iter().filter(|j| j.parent == at).map(|j| j.child).collect();
                        match kids.as_slice() {
                            [c] if matches!(m.joints[m.links[*c].parent_joint.expect("child")].kind, JointKind::Fixed) => at = *c,
                            _ => break at,
                        }
                    }
                }
                [] => return Err(Manip3rError::NotThreeR(format!("no revolute joint below link '{}'", m.links[base].name))),
                many => {
                    let names: Vec<&str> = many.iter().map(|&l| m.links[l].name.as_str()).collect();
                    return Err(Manip3rError::Selection(format!("several end links with {best} revolute joints ({}): choose one with --tip", names.join(", "))));
                }
            }
        }
    };
    let path = below(tip).ok_or_else(|| Manip3rError::Selection(format!("tip '{}' is not below base '{}'", m.links[tip].name, m.links[base].name)))?;
    for (name, _) in &spec.locks {
        if !path.iter().any(|&j| m.joints[j].name == *name) {
            return Err(Manip3rError::Selection(format!("--lock: joint '{name}' is not on the chain from '{}' to '{}'", m.links[base].name, m.links[tip].name)));
        }
    }
    for &j in &path {
        let joint = &m.joints[j];
        match joint.kind {
            JointKind::Revolute { .. } if joint.mimic.is_some() && locked(j).is_none() => {
                let leader = joint.mimic.as_ref().map_or("", |x| x.joint.as_str());
                return Err(Manip3rError::NotThreeR(format!("joint '{}' follows '{leader}' through <mimic>, which the 3R analyses do not model yet", joint.name)));
            }
            JointKind::Revolute { .. } | JointKind::Fixed => {}
            JointKind::Prismatic { .. } => return Err(Manip3rError::NotThreeR(format!("joint '{}' is prismatic", joint.name))),
            JointKind::Spherical | JointKind::Floating => return Err(Manip3rError::NotThreeR(format!("joint '{}' is not revolute", joint.name))),
        }
    }
    let revolute: Vec<usize> = path.iter().copied().filter(|&j| moving(j)).collect();
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
        acc = match locked(j) {
            Some(v) => frame.then(&rotation(&m.joints[j], v)),
            None => frame,
        };
        frames.push((j, frame, acc));
    }
    let axis_line = |f: &Pose, j: usize| -> (V3, V3) { (f.t, apply(&f.r, &axis3(&m.joints[j]))) };
    let later: Vec<(usize, Pose)> = frames.iter().filter(|(j, _, _)| moving(*j)).map(|(j, f, _)| (*j, *f)).collect();
    // Upper bound of the largest distance of `p` from the later axes (unit vectors).
    let miss = |p: &V3| -> f64 {
        later.iter().map(|(j, f)| {
            let (o, d) = axis_line(f, *j);
            let c = cross(&sub(p, &o), &d);
            dot(&c, &c).sup().max(0.0).sqrt()
        }).fold(0.0, f64::max)
    };
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
    };
    let lock_text = if spec.locks.is_empty() { String::new() } else { format!(" with {} locked", spec.locks.iter().map(|(n, v)| format!("{n}={v}")).collect::<Vec<_>>().join(", ")) };
    // Where the point hangs (None: keep the whole path, the tip's origin being the point).
    let point_in_l3: Option<Attach> = if let Some((pl, xyz)) = &spec.tip_point {
        let l = link(pl, "--tip-point")?;
        if !xyz.iter().all(|v| v.is_finite()) {
            return Err(Manip3rError::Selection("--tip-point: coordinates must be finite".into()));
        }
        let local: V3 = xyz.map(point);
        let in_l3 = if l == l3 {
            local
        } else if let Some((_, _, f)) = frames.iter().find(|(j, _, _)| m.joints[*j].child == l) {
            add(&apply(&f.r, &local), &f.t)
        } else {
            return Err(Manip3rError::Selection(format!("--tip-point: link '{pl}' is not on the chain after joint '{}' (joints 1-3 must move it)", joints[2])));
        };
        let mv = miss(&in_l3);
        if mv > tol {
            return Err(Manip3rError::Selection(format!("--tip-point: the point is {mv:.3e} m off the axes of {}, which would move it", wrist_joints.join(", "))));
        }
        choice.point_link = pl.clone();
        choice.point = *xyz;
        choice.wrist_miss = mv;
        choice.reason = format!("chain {b} -> {t}{lock_text}, {n} revolute joints; the point {xyz:?} of link '{pl}' given by --tip-point, moved by {} only", joints.join(", "));
        let name = format!("{pl}@{},{},{}", xyz[0], xyz[1], xyz[2]);
        if n == 3 && l == tip {
            // The whole path is kept (its links carry collision shapes); the point hangs
            // under the tip at its coordinates there, unless it is the tip's origin.
            (xyz != &[0.0; 3]).then_some(Attach::UnderTip(local, name))
        } else {
            Some(Attach::UnderJoint3(in_l3, name))
        }
    } else if n == 3 {
        choice.reason = format!("chain {b} -> {t}{lock_text}: three revolute joints; the point is the origin of '{t}'");
        None
    } else if n == 6 {
        let (o4, d4) = axis_line(&later[0].1, later[0].0);
        let (o5, d5) = axis_line(&later[1].1, later[1].0);
        // Closest point of axis 4 to axis 5, in floating point; its distance from every wrist
        // axis is then bounded soundly, so the choice rests on the bound, not on this guess.
        let mid = |v: &V3| v.map(|x| x.mid());
        let (p, u, q, v) = (Vector3::from(mid(&o4)), Vector3::from(mid(&d4)), Vector3::from(mid(&o5)), Vector3::from(mid(&d5)));
        let w = p - q;
        let (a, bb, c, d, e) = (u.dot(&u), u.dot(&v), v.dot(&v), u.dot(&w), v.dot(&w));
        let den = a * c - bb * bb;
        let centre = (den.abs() > 1e-12).then(|| p + u * ((bb * e - c * d) / den));
        let bound = centre.map(|x| miss(&[x[0], x[1], x[2]].map(point)));
        match (centre, bound) {
            (Some(x), Some(mv)) if mv <= tol => {
                choice.point_link = m.links[l3].name.clone();
                choice.point = [x[0], x[1], x[2]];
                choice.wrist_miss = mv;
                choice.reason = format!(
                    "chain {b} -> {t}{lock_text}: 6 revolute joints with a spherical wrist (axes of {} meet within {mv:.1e} m); joints {} position the wrist centre {:?} in '{}'",
                    wrist_joints.join(", "), joints.join(", "), choice.point, choice.point_link
                );
                Some(Attach::UnderJoint3([x[0], x[1], x[2]].map(point), "wrist_centre".into()))
            }
            _ => {
                let o = o4;
                choice.point_link = m.links[l3].name.clone();
                choice.point = mid(&o);
                choice.wrist_miss = miss(&o);
                let why = bound.map_or("axes 4 and 5 are parallel".to_string(), |mv| format!("axes of {} miss one point by at least {mv:.3e} m", wrist_joints.join(", ")));
                choice.reason = format!(
                    "chain {b} -> {t}{lock_text}: 6 revolute joints, wrist not spherical ({why}); analysing the origin of joint '{}' {:?} in '{}', on its axis, which joints 4-6 do not move (--tip-point LINK@X,Y,Z for another point)",
                    wrist_joints[0], choice.point, choice.point_link
                );
                // The origin of joint 4 lies on axis 4 only; joints 5 and 6 do not move it
                // because it is in joint 4's parent link.
                choice.wrist_miss = 0.0;
                choice.origin_of = Some(wrist_joints[0].clone());
                choice.wrist_spread = bound;
                Some(Attach::UnderJoint3(o, format!("{}_origin", wrist_joints[0])))
            }
        }
    } else {
        let hint = if n == 7 { format!("lock one with --lock JOINT=VALUE (e.g. --lock {}=0)", m.joints[revolute[2]].name) } else { "cut it with --base/--tip or give --tip-point LINK@X,Y,Z".into() };
        return Err(Manip3rError::NotThreeR(format!("the chain from '{b}' to '{t}' has {n} revolute joints{lock_text}: {hint}")));
    };
    // The reduced mechanism: base, the links down to joint 3's child (or the whole path when the
    // tip's origin is the point), and a virtual tip link at the point.
    let keep: Vec<usize> = if matches!(point_in_l3, Some(Attach::UnderJoint3(..))) { path[..=third].to_vec() } else { path.clone() };
    let mut links = vec![Link { name: m.links[base].name.clone(), parent_joint: None, collisions: m.links[base].collisions.clone() }];
    let mut joints_out: Vec<Joint> = Vec::new();
    for &j in &keep {
        let mut joint = m.joints[j].clone();
        joint.parent = links.len() - 1;
        joint.child = links.len();
        if let Some(v) = locked(j) {
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
    Ok((Mechanism { name: m.name.clone(), links, joints: joints_out, loops: Vec::new(), root: 0, transmission_joints: Vec::new() }, choice))
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
    let (s, c) = (crate::interval::trig::sin(point(v)), crate::interval::trig::cos(point(v)));
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

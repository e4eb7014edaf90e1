//! What a front end shows of a loaded mechanism before asking it anything: its links, joints
//! (type, limits, axis, mimic) and loop closures, as plain data with the types spelled as URDF
//! spells them; and what the node answers for it (`questions`).

use crate::model::{JointKind, Mechanism};

/// A mechanism as read from its file.
#[derive(Clone, Debug, PartialEq)]
pub struct MechanismInfo {
    /// The robot's name.
    pub name: String,
    /// Link names, the ground first.
    pub links: Vec<String>,
    /// Tree joints, in file order.
    pub joints: Vec<JointInfo>,
    /// Loop closures (`<loop>`), in file order.
    pub loops: Vec<LoopInfo>,
    /// Joints of the file's `<transmission>` elements: the actuated joints by default.
    pub actuated: Vec<String>,
}

/// What the node makes of a mechanism loaded as it is (no fixed joints, no traced points).
#[derive(Clone, Debug, PartialEq)]
pub struct Questions {
    /// `manipulator_3r`, `planar_linkage`, `spatial_linkage`, `parallel_platform` or
    /// `unsupported`.
    pub kind: &'static str,
    /// The node's services it answers (`solve`, `singularities`, …).
    pub services: Vec<&'static str>,
    /// The joints a configuration of it names.
    pub free_joints: Vec<String>,
    /// What it is outside of (empty when nothing); for `unsupported`, the reason.
    pub limitation: String,
}

/// A tree joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointInfo {
    /// URDF name.
    pub name: String,
    /// `revolute`, `continuous` (a revolute joint without limits), `prismatic`, `fixed`,
    /// `spherical` or `floating`.
    pub kind: &'static str,
    /// `(lower, upper)` in radians or metres, when the joint has limits.
    pub limits: Option<(f64, f64)>,
    /// Parent link.
    pub parent: String,
    /// Child link.
    pub child: String,
    /// Unit axis in the joint frame.
    pub axis: [f64; 3],
    /// The joint followed through `<mimic>`, with multiplier and offset.
    pub mimic: Option<(String, f64, f64)>,
}

/// A loop closure.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopInfo {
    /// Name of the `<loop>` element.
    pub name: String,
    /// Its type as written (`revolute`, `prismatic`, `spherical`, `fixed`, `universal`,
    /// `cylindrical`).
    pub kind: &'static str,
    /// The link of the closure's first frame.
    pub predecessor: String,
    /// The link of its second frame.
    pub successor: String,
    /// Limits of its (first) motion, when it has any.
    pub limits: Option<(f64, f64)>,
}

fn kind_and_limits(kind: JointKind) -> (&'static str, Option<(f64, f64)>) {
    match kind {
        JointKind::Revolute { limits: Some(l) } => ("revolute", Some(l)),
        JointKind::Revolute { limits: None } => ("continuous", None),
        JointKind::Prismatic { limits } => ("prismatic", Some(limits)),
        JointKind::Fixed => ("fixed", None),
        JointKind::Spherical => ("spherical", None),
        JointKind::Floating => ("floating", None),
    }
}

/// The links, joints and loops of `m`: read off the file, no analysis built.
pub fn describe(m: &Mechanism) -> MechanismInfo {
    let link = |i: usize| m.links.get(i).map_or_else(String::new, |l| l.name.clone());
    let joints = m
        .joints
        .iter()
        .map(|j| {
            let (kind, limits) = kind_and_limits(j.kind);
            JointInfo { name: j.name.clone(), kind, limits, parent: link(j.parent), child: link(j.child), axis: [j.axis.x, j.axis.y, j.axis.z], mimic: j.mimic.as_ref().map(|x| (x.joint.clone(), x.multiplier, x.offset)) }
        })
        .collect();
    let loops = m.loops.iter().map(|l| LoopInfo { name: l.name.clone(), kind: l.type_name(), predecessor: link(l.predecessor), successor: link(l.successor), limits: kind_and_limits(l.kind).1 }).collect();
    MechanismInfo { name: m.name.clone(), links: m.links.iter().map(|l| l.name.clone()).collect(), joints, loops, actuated: m.transmission_joints.clone() }
}

/// What the node answers for `m` (`Questions`): the node's own choice of analysis, built once
/// here and dropped.
pub fn questions(m: &Mechanism) -> Questions {
    match super::analysis::load_urdf(m, &[], &[]) {
        Ok(a) => Questions { kind: a.kind().name(), services: a.services().iter().map(|s| s.name()).collect(), free_joints: a.free_joints(), limitation: a.limitation() },
        Err(e) => Questions { kind: "unsupported", services: Vec::new(), free_joints: Vec::new(), limitation: e.to_string() },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_four_bar_reads_as_written() {
        let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/four_bar.urdf")).expect("bundled");
        let info = describe(&crate::model::urdf::parse(&text).expect("parses"));
        assert_eq!(info.name, "four_bar");
        assert_eq!(info.loops.len(), 1);
        assert_eq!(info.loops[0].kind, "revolute");
        assert!(info.joints.iter().all(|j| j.kind == "continuous" && j.limits.is_none()), "{:?}", info.joints);
        assert_eq!(info.links[0], info.joints[0].parent);
    }
}

//! Reading a `Mechanism` from URDF: the only importer of `urdf_rs`.
//!
//! Links and joints come through `urdf_rs`; loop closures through our `<loop>` extension element,
//! which `urdf_rs` (and every standard URDF tool) ignores, so it is read from the XML with
//! `roxmltree`. The element follows URDF+ (Chignoli et al., 2024, arXiv:2411.19753):
//!
//! ```xml
//! <loop name="loop15" type="revolute">   <!-- revolute | prismatic | spherical | fixed | universal | cylindrical -->
//!   <predecessor link="link1"><origin xyz="7 0 0" rpy="0 0 0"/></predecessor>
//!   <successor link="link5"><origin xyz="12 0 0" rpy="0 0 0"/></successor>
//!   <axis xyz="0 0 1"/>
//!   <!-- universal only: <axis2 xyz="1 0 0"/>, in the successor's closure frame -->
//! </loop>
//! ```

use super::{Collision, Compound, Joint, JointKind, Link, LoopClosure, Mechanism, Mimic, ModelError, Shape};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::collections::{HashMap, HashSet};

/// The deepest element nesting accepted. A URDF needs a handful of levels (robot, link, visual,
/// geometry, mesh); `urdf_rs` reads nested elements recursively, so a hostile document nested
/// tens of thousands deep would overflow the stack, which no error handling can catch.
pub const MAX_DEPTH: usize = 256;

/// Refuses a document nested deeper than `MAX_DEPTH`. A scan of the text, before any parser
/// (the XML parser recurses too): for a well-formed document it counts exactly; a malformed one
/// is left to the parser's error.
fn check_depth(xml: &str) -> Result<(), ModelError> {
    let bytes = xml.as_bytes();
    let skip_past = |from: usize, end: &str| xml[from..].find(end).map_or(bytes.len(), |k| from + k + end.len());
    let (mut i, mut depth) = (0usize, 0usize);
    while i < bytes.len() {
        match bytes[i] {
            b'<' if xml[i..].starts_with("<!--") => i = skip_past(i, "-->"),
            b'<' if xml[i..].starts_with("<![CDATA[") => i = skip_past(i, "]]>"),
            b'<' if xml[i..].starts_with("<?") => i = skip_past(i, "?>"),
            b'<' if xml[i..].starts_with("<!") => i = skip_past(i, ">"),
            b'<' if xml[i..].starts_with("</") => {
                depth = depth.saturating_sub(1);
                i = skip_past(i, ">");
            }
            b'<' => {
                // An opening tag: its end is the first '>' outside quoted attribute values.
                let mut j = i + 1;
                let mut quote = None;
                while j < bytes.len() && !(quote.is_none() && bytes[j] == b'>') {
                    match (quote, bytes[j]) {
                        (None, q @ (b'"' | b'\'')) => quote = Some(q),
                        (Some(q), c) if c == q => quote = None,
                        _ => {}
                    }
                    j += 1;
                }
                if bytes.get(j.wrapping_sub(1)) != Some(&b'/') {
                    depth += 1;
                    if depth > MAX_DEPTH {
                        let line = 1 + xml[..i].matches('\n').count();
                        return Err(ModelError::Malformed(format!("elements are nested more than {MAX_DEPTH} deep (line {line})")));
                    }
                }
                i = j + 1;
            }
            _ => i += 1,
        }
    }
    Ok(())
}

/// Parses a URDF document (with optional `<loop>` elements) into a checked `Mechanism`.
pub fn parse(xml: &str) -> Result<Mechanism, ModelError> {
    check_depth(xml)?;
    let doc = roxmltree::Document::parse(xml).map_err(|e| ModelError::Malformed(e.to_string()))?;
    let robot_el = doc.root_element();
    if robot_el.tag_name().name() != "robot" {
        return Err(ModelError::Malformed(format!("root element is <{}>, not <robot>", robot_el.tag_name().name())));
    }
    // urdf_rs is a foreign parser on untrusted input: a panic inside it must not take us down.
    let robot = std::panic::catch_unwind(|| urdf_rs::read_from_string(xml))
        .map_err(|_| ModelError::Malformed("the URDF parser failed on this document".into()))?
        .map_err(|e| ModelError::Malformed(e.to_string()))?;

    let (index, mut links) = read_links(&robot)?;
    // Joint and loop names share one namespace.
    let mut names = HashSet::new();
    let joints = read_joints(&robot, &index, &mut links, &mut names)?;
    let root = find_root(&links, &joints)?;
    let mut loops = Vec::new();
    for el in robot_el.children().filter(|n| n.has_tag_name("loop")) {
        loops.push(read_loop(el, &index, &mut names)?);
    }
    Ok(Mechanism { name: robot.name.clone(), links, joints, loops, root, transmission_joints: transmission_joints(robot_el) })
}

/// Link names to indices, in file order.
type LinkIndex = HashMap<String, usize>;

/// The links, with their collision geometry; none has a parent joint yet.
fn read_links(robot: &urdf_rs::Robot) -> Result<(LinkIndex, Vec<Link>), ModelError> {
    let mut index = HashMap::new();
    let mut links = Vec::new();
    for l in &robot.links {
        if index.insert(l.name.clone(), links.len()).is_some() {
            return Err(ModelError::Duplicate(l.name.clone()));
        }
        let collisions = l.collision.iter().map(|c| collision(&l.name, c)).collect::<Result<_, _>>()?;
        links.push(Link { name: l.name.clone(), parent_joint: None, collisions });
    }
    if links.is_empty() {
        return Err(ModelError::Malformed("the robot has no links".into()));
    }
    Ok((index, links))
}

/// The link named `link`, which `element` refers to.
fn find(index: &LinkIndex, element: &str, link: &str) -> Result<usize, ModelError> {
    index.get(link).copied().ok_or_else(|| ModelError::UnknownLink { element: element.into(), link: link.into() })
}

/// The tree joints, each link's parent joint set on the way (a link with two is refused);
/// their names go into `names`.
fn read_joints(robot: &urdf_rs::Robot, index: &LinkIndex, links: &mut [Link], names: &mut HashSet<String>) -> Result<Vec<Joint>, ModelError> {
    let mut joints = Vec::new();
    for j in &robot.joints {
        if !names.insert(j.name.clone()) {
            return Err(ModelError::Duplicate(j.name.clone()));
        }
        let element = format!("joint '{}'", j.name);
        let parent = find(index, &element, &j.parent.link)?;
        let child = find(index, &element, &j.child.link)?;
        let kind = joint_kind(&element, j)?;
        let origin = pose(&element, j.origin.xyz.0, j.origin.rpy.0)?;
        // As ROS's parser: only joints that move along or about an axis read it; a fixed joint's
        // `<axis xyz="0 0 0"/>` (common in vendor files) is ignored, not refused.
        let axis = match kind {
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => unit_axis(&element, j.axis.xyz.0)?,
            _ => Vector3::x(),
        };
        let mimic = j.mimic.as_ref().map(|m| Mimic { joint: m.joint.clone(), multiplier: m.multiplier.unwrap_or(1.0), offset: m.offset.unwrap_or(0.0) });
        if links[child].parent_joint.is_some() {
            return Err(ModelError::NotATree(format!("link '{}' is the child of two joints", links[child].name)));
        }
        links[child].parent_joint = Some(joints.len());
        joints.push(Joint { name: j.name.clone(), kind, parent, child, origin, rpy: j.origin.rpy.0, axis, mimic, exact_rotation: None });
    }
    Ok(joints)
}

/// A joint's motion, with its limits checked.
fn joint_kind(element: &str, j: &urdf_rs::Joint) -> Result<JointKind, ModelError> {
    Ok(match j.joint_type {
        urdf_rs::JointType::Revolute => {
            let (lo, hi) = (j.limit.lower, j.limit.upper);
            check_finite(element, &[lo, hi])?;
            // urdf_rs fills a missing <limit> with 0..0; no range means no limit to use.
            let limits = if lo < hi {
                Some((lo, hi))
            } else if lo == hi {
                None
            } else {
                return Err(bad(element, "limit lower is above upper"));
            };
            JointKind::Revolute { limits }
        }
        urdf_rs::JointType::Continuous => JointKind::Revolute { limits: None },
        urdf_rs::JointType::Prismatic => {
            let (lo, hi) = (j.limit.lower, j.limit.upper);
            check_finite(element, &[lo, hi])?;
            if !(lo < hi) {
                return Err(bad(element, "a prismatic joint needs <limit lower < upper> to bound its travel"));
            }
            JointKind::Prismatic { limits: (lo, hi) }
        }
        urdf_rs::JointType::Fixed => JointKind::Fixed,
        urdf_rs::JointType::Spherical => JointKind::Spherical,
        urdf_rs::JointType::Floating => JointKind::Floating,
        ref other => return Err(ModelError::UnsupportedJoint { joint: j.name.clone(), kind: format!("{other:?}").to_lowercase() }),
    })
}

/// The one root link, the tree checked: one link without a parent joint, and every link
/// reaching it.
fn find_root(links: &[Link], joints: &[Joint]) -> Result<usize, ModelError> {
    let roots: Vec<usize> = (0..links.len()).filter(|&i| links[i].parent_joint.is_none()).collect();
    let root = match roots.as_slice() {
        [r] => *r,
        [] => return Err(ModelError::NotATree("every link has a parent: the joints form a cycle".into())),
        many => {
            let names: Vec<&str> = many.iter().map(|&i| links[i].name.as_str()).collect();
            return Err(ModelError::NotATree(format!("several root links ({}); close loops with <loop>, not <joint>", names.join(", "))));
        }
    };
    // With one root and one parent per link, a link that cannot reach the root sits on a cycle.
    for start in 0..links.len() {
        let mut at = start;
        for _ in 0..=links.len() {
            match links[at].parent_joint {
                Some(j) => at = joints[j].parent,
                None => break,
            }
        }
        if at != root {
            return Err(ModelError::NotATree(format!("link '{}' is on a cycle of joints", links[start].name)));
        }
    }
    Ok(root)
}

/// One `<loop>` element (see the module doc); its name goes into `names`.
fn read_loop(el: roxmltree::Node<'_, '_>, index: &LinkIndex, names: &mut HashSet<String>) -> Result<LoopClosure, ModelError> {
    let name = el.attribute("name").unwrap_or("").to_string();
    let element = format!("loop '{name}'");
    if name.is_empty() {
        return Err(bad("a <loop> element", "it has no name"));
    }
    if !names.insert(name.clone()) {
        return Err(ModelError::Duplicate(name));
    }
    let side = |tag: &str| -> Result<(usize, Isometry3<f64>, [f64; 3]), ModelError> {
        let s = el.children().find(|n| n.has_tag_name(tag)).ok_or_else(|| bad(&element, &format!("missing <{tag} link=\"…\">")))?;
        let link = s.attribute("link").ok_or_else(|| bad(&element, &format!("<{tag}> has no link attribute")))?;
        let link = find(index, &element, link)?;
        let origin = s.children().find(|n| n.has_tag_name("origin"));
        let xyz = triple(&element, origin.and_then(|o| o.attribute("xyz")), [0.0; 3])?;
        let rpy = triple(&element, origin.and_then(|o| o.attribute("rpy")), [0.0; 3])?;
        Ok((link, pose(&element, xyz, rpy)?, rpy))
    };
    let (predecessor, predecessor_origin, predecessor_rpy) = side("predecessor")?;
    let (successor, successor_origin, successor_rpy) = side("successor")?;
    let axis = unit_axis(&element, triple(&element, el.children().find(|n| n.has_tag_name("axis")).and_then(|a| a.attribute("xyz")), [1.0, 0.0, 0.0])?)?;
    let limit = el.children().find(|n| n.has_tag_name("limit"));
    let number = |attr: &str| -> Result<Option<f64>, ModelError> {
        match limit.and_then(|l| l.attribute(attr)) {
            None => Ok(None),
            Some(t) => t.trim().parse::<f64>().ok().filter(|v| v.is_finite()).map(Some).ok_or_else(|| bad(&element, &format!("limit {attr}='{t}' is not a finite number"))),
        }
    };
    let kind = match el.attribute("type").unwrap_or("revolute") {
        "revolute" | "continuous" => JointKind::Revolute { limits: number("lower")?.zip(number("upper")?).filter(|(l, u)| l < u) },
        "prismatic" => match number("lower")?.zip(number("upper")?) {
            Some((l, u)) if l < u => JointKind::Prismatic { limits: (l, u) },
            _ => return Err(bad(&element, "a prismatic loop needs <limit lower < upper>")),
        },
        "spherical" => JointKind::Spherical,
        "fixed" => JointKind::Fixed,
        "universal" => JointKind::Revolute { limits: None },
        "cylindrical" => match number("lower")?.zip(number("upper")?) {
            Some((l, u)) if l < u => JointKind::Prismatic { limits: (l, u) },
            _ => return Err(bad(&element, "a cylindrical loop needs <limit lower < upper> to bound its travel")),
        },
        other => return Err(ModelError::UnsupportedJoint { joint: name, kind: other.into() }),
    };
    let compound = match el.attribute("type") {
        Some("universal") => {
            let a2 = el.children().find(|n| n.has_tag_name("axis2")).ok_or_else(|| bad(&element, "a universal loop needs <axis2 xyz=\"…\"/>, its second axis in the successor's closure frame"))?;
            let axis2 = unit_axis(&element, triple(&element, a2.attribute("xyz"), [0.0; 3])?)?;
            Some(Compound::Universal { axis2 })
        }
        Some("cylindrical") => Some(Compound::Cylindrical),
        _ => None,
    };
    if predecessor == successor {
        return Err(bad(&element, "predecessor and successor are the same link"));
    }
    Ok(LoopClosure { name, kind, predecessor, predecessor_origin, predecessor_rpy, successor, successor_origin, successor_rpy, axis, compound })
}

/// The joints named by `<transmission>` elements, each once, in file order.
fn transmission_joints(robot_el: roxmltree::Node<'_, '_>) -> Vec<String> {
    let mut transmission_joints: Vec<String> = Vec::new();
    for t in robot_el.children().filter(|n| n.has_tag_name("transmission")) {
        for j in t.children().filter(|n| n.has_tag_name("joint")) {
            if let Some(name) = j.attribute("name") {
                if !transmission_joints.iter().any(|n| n == name) {
                    transmission_joints.push(name.to_string());
                }
            }
        }
    }
    transmission_joints
}

/// A `<collision>` element, with its sizes checked.
fn collision(link: &str, c: &urdf_rs::Collision) -> Result<Collision, ModelError> {
    let element = format!("collision of link '{link}'");
    let origin = pose(&element, c.origin.xyz.0, c.origin.rpy.0)?;
    let size = |values: &[f64]| -> Result<(), ModelError> {
        check_finite(&element, values)?;
        if values.iter().any(|&v| v < 0.0) {
            return Err(bad(&element, "a size is negative"));
        }
        Ok(())
    };
    let shape = match &c.geometry {
        urdf_rs::Geometry::Cylinder { radius, length } => {
            size(&[*radius, *length])?;
            Shape::Cylinder { radius: *radius, length: *length }
        }
        urdf_rs::Geometry::Capsule { radius, length } => {
            size(&[*radius, *length])?;
            Shape::Capsule { radius: *radius, length: *length }
        }
        urdf_rs::Geometry::Sphere { radius } => {
            size(&[*radius])?;
            Shape::Sphere { radius: *radius }
        }
        urdf_rs::Geometry::Box { size: s } => {
            size(&s.0)?;
            Shape::Box { size: s.0 }
        }
        urdf_rs::Geometry::Mesh { filename, .. } => Shape::Mesh { filename: filename.clone() },
    };
    Ok(Collision { name: c.name.clone(), origin, shape })
}

fn bad(element: &str, problem: &str) -> ModelError {
    ModelError::BadValue { element: element.into(), problem: problem.into() }
}

fn check_finite(element: &str, values: &[f64]) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(bad(element, "a number is NaN or infinite"))
    }
}

fn triple(element: &str, text: Option<&str>, default: [f64; 3]) -> Result<[f64; 3], ModelError> {
    let Some(text) = text else { return Ok(default) };
    let v: Vec<f64> = text.split_whitespace().map(|t| t.parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad(element, &format!("'{text}' is not three numbers")))?;
    match v.as_slice() {
        [a, b, c] => {
            check_finite(element, &[*a, *b, *c])?;
            Ok([*a, *b, *c])
        }
        _ => Err(bad(element, &format!("'{text}' is not three numbers"))),
    }
}

pub(super) fn pose(element: &str, xyz: [f64; 3], rpy: [f64; 3]) -> Result<Isometry3<f64>, ModelError> {
    check_finite(element, &xyz)?;
    check_finite(element, &rpy)?;
    // URDF rpy is roll about x, then pitch about y, then yaw about z, all fixed axes.
    Ok(Isometry3::from_parts(Translation3::new(xyz[0], xyz[1], xyz[2]), UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])))
}

fn unit_axis(element: &str, xyz: [f64; 3]) -> Result<Vector3<f64>, ModelError> {
    check_finite(element, &xyz)?;
    let v = Vector3::new(xyz[0], xyz[1], xyz[2]);
    let n = v.norm();
    if n > 1e-12 {
        Ok(v / n)
    } else {
        Err(bad(element, "the axis is the zero vector"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deeply_nested_documents_are_refused_in_one_line() {
        let nested = |n: usize| format!("<robot name=\"r\"><link name=\"a\"/>{}{}</robot>", "<x>".repeat(n), "</x>".repeat(n));
        // Deep enough to overflow the stack of a recursive reader: refused before any.
        let err = parse(&nested(20_000)).expect_err("refused").to_string();
        assert!(err.contains("nested more than 256 deep") && !err.contains('\n'), "{err}");
        // Within the bound the document is read (a robot with one link and an unknown element).
        assert_eq!(parse(&nested(MAX_DEPTH - 2)).expect("read").links.len(), 1);
    }

    #[test]
    fn bundled_butterfly_has_three_loops_on_a_tree() {
        let m = parse(include_str!("../../urdf/double_butterfly.urdf")).expect("bundled file parses");
        assert_eq!(m.name, "double_butterfly");
        assert_eq!((m.links.len(), m.joints.len(), m.loops.len()), (8, 7, 3));
        assert_eq!(m.links[m.root].name, "link0");
    }

    #[test]
    fn bundled_octahedral_has_spherical_loops_and_a_floating_platform() {
        let m = parse(include_str!("../../urdf/octahedral.urdf")).expect("bundled file parses");
        assert_eq!(m.loops.len(), 6);
        assert!(m.loops.iter().all(|l| l.kind == JointKind::Spherical));
        assert_eq!(m.joints.iter().filter(|j| j.kind == JointKind::Floating).count(), 1);
        assert_eq!(m.joints.iter().filter(|j| j.kind == JointKind::Spherical).count(), 6);
    }

    #[test]
    fn fixed_joints_ignore_their_axis_and_mimics_are_kept() {
        // Vendor files (xacro-expanded) write `<axis xyz="0 0 0"/>` on fixed joints; ROS ignores it.
        let xml = "<robot name='r'><link name='a'/><link name='b'/><link name='c'/>\
            <joint name='weld' type='fixed'><parent link='a'/><child link='b'/><axis xyz='0 0 0'/></joint>\
            <joint name='finger' type='revolute'><parent link='b'/><child link='c'/><axis xyz='0 0 1'/>\
            <limit lower='-1' upper='1' effort='1' velocity='1'/><mimic joint='weld' multiplier='-2' offset='0.5'/></joint></robot>";
        let m = parse(xml).expect("loads as ROS loads it");
        assert_eq!(m.joints[0].kind, JointKind::Fixed);
        assert_eq!(m.joints[1].mimic, Some(Mimic { joint: "weld".into(), multiplier: -2.0, offset: 0.5 }));
    }

    #[test]
    fn bad_documents_give_errors_that_name_the_problem() {
        let cases = [
            ("<robot name='r'><link name='a'/>", "malformed URDF"),
            ("<robot name='r'><link name='a'/><joint name='j' type='planar'><parent link='a'/><child link='b'/></joint><link name='b'/></robot>", "planar"),
            ("<robot name='r'><link name='a'/><link name='b'/></robot>", "several root links"),
            ("<robot name='r'><link name='a'/><loop name='l'><predecessor link='a'/><successor link='zz'/></loop></robot>", "unknown link 'zz'"),
            ("<robot name='r'><link name='a'/><link name='b'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/><axis xyz='0 0 0'/></joint></robot>", "zero vector"),
        ];
        for (xml, needle) in cases {
            let err = parse(xml).expect_err(xml).to_string();
            assert!(err.contains(needle), "{err} should mention {needle}");
        }
    }
}

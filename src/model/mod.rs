//! Mechanisms: links, tree joints and loop closures, independent of any file format.
//!
//! `urdf` is the only reader (and the only importer of `urdf_rs`). A `Mechanism` is checked once
//! when built: one root (the ground), every other link with exactly one parent joint, loop
//! closures between known links, finite numbers.

pub mod rounding;
pub mod urdf;

use std::collections::{BTreeMap, HashMap};
use nalgebra::{Isometry3, Vector3};
use thiserror::Error;

/// What a joint lets move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// Rotation about the axis; `limits` in radians when the file gives a usable range.
    Revolute {
        /// `(lower, upper)`, or `None` for continuous joints.
        limits: Option<(f64, f64)>,
    },
    /// Translation along the axis within `limits` (metres).
    Prismatic {
        /// `(lower, upper)`.
        limits: (f64, f64),
    },
    /// No motion: the child is welded to the parent.
    Fixed,
    /// A ball joint: free rotation about the joint origin (tree joints and `<loop type="spherical">`).
    Spherical,
    /// No constraint at all: the child's pose is free (a platform whose pose the loops decide).
    Floating,
}

/// A tree joint: `child`'s frame is `parent`'s frame moved by `origin`, then by the joint motion
/// along or about `axis` (a unit vector in the joint frame).
#[derive(Clone, Debug)]
pub struct Joint {
    /// URDF name.
    pub name: String,
    /// Motion type.
    pub kind: JointKind,
    /// Index of the parent link.
    pub parent: usize,
    /// Index of the child link.
    pub child: usize,
    /// Pose of the joint frame in the parent frame.
    pub origin: Isometry3<f64>,
    /// The origin's roll, pitch, yaw as parsed: builders that enclose the stated model take
    /// their rotations from these, not from the rounded `origin`.
    pub rpy: [f64; 3],
    /// Unit axis in the joint frame (+x for joints that have none: fixed, floating, spherical).
    pub axis: Vector3<f64>,
    /// The joint this one follows through `<mimic>`, if any.
    pub mimic: Option<Mimic>,
    /// The origin's rotation as an exact matrix, set by the rounding policy (`rounding`) when
    /// `rpy` are exact quarter turns: the quaternion in `origin` cannot hold cos(π/2) = 0
    /// exactly, and an entry of 1e-17 is a different (near-degenerate) robot.
    pub exact_rotation: Option<[[f64; 3]; 3]>,
}

impl Joint {
    /// The origin's rotation matrix: exact when the rounding policy set it, else from `origin`.
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        if let Some(r) = self.exact_rotation {
            return r;
        }
        let m = self.origin.rotation.to_rotation_matrix();
        [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[(i, j)]))
    }
}

/// A URDF `<mimic>`: this joint's value is `multiplier · value(joint) + offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mimic {
    /// The joint followed.
    pub joint: String,
    /// Default 1.
    pub multiplier: f64,
    /// Default 0.
    pub offset: f64,
}

/// A loop closure: a frame on `predecessor` and a frame on `successor` that must coincide up to
/// the closure's own motion (our URDF extension, see README).
#[derive(Clone, Debug)]
pub struct LoopClosure {
    /// Name of the `<loop>` element.
    pub name: String,
    /// Motion the closure allows (revolute, prismatic, spherical or fixed; limits as for
    /// joints; the first motion of a universal or cylindrical closure, see `compound`).
    pub kind: JointKind,
    /// Index of the predecessor link.
    pub predecessor: usize,
    /// Closure frame in the predecessor's frame.
    pub predecessor_origin: Isometry3<f64>,
    /// `predecessor_origin`'s roll, pitch, yaw as parsed.
    pub predecessor_rpy: [f64; 3],
    /// Index of the successor link.
    pub successor: usize,
    /// Closure frame in the successor's frame.
    pub successor_origin: Isometry3<f64>,
    /// `successor_origin`'s roll, pitch, yaw as parsed.
    pub successor_rpy: [f64; 3],
    /// Unit axis in the predecessor's closure frame.
    pub axis: Vector3<f64>,
    /// A closure of two motions: `kind` holds the first (revolute about `axis` for a universal
    /// joint, prismatic along `axis` for a cylindrical one), this the second. `None` for the
    /// one-motion closures (revolute, prismatic, spherical, fixed).
    pub compound: Option<Compound>,
}

/// The second motion of a two-motion loop closure (`<loop type="universal|cylindrical">`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Compound {
    /// A universal (Hooke, cardan) joint: `axis` on the predecessor and `axis2` on the
    /// successor stay perpendicular, and the closure points coincide.
    Universal {
        /// Unit axis in the successor's closure frame (`<axis2 xyz>`).
        axis2: Vector3<f64>,
    },
    /// A cylindrical joint: the successor turns about `axis` as well as sliding along it.
    Cylindrical,
}

impl LoopClosure {
    /// The closure's type as written in the file (`revolute`, `prismatic`, `spherical`, `fixed`,
    /// `universal`, `cylindrical`).
    pub fn type_name(&self) -> &'static str {
        match (self.compound, self.kind) {
            (Some(Compound::Universal { .. }), _) => "universal",
            (Some(Compound::Cylindrical), _) => "cylindrical",
            (None, JointKind::Revolute { .. }) => "revolute",
            (None, JointKind::Prismatic { .. }) => "prismatic",
            (None, JointKind::Spherical) => "spherical",
            (None, JointKind::Fixed) => "fixed",
            (None, JointKind::Floating) => "floating",
        }
    }
}

/// A rigid body.
#[derive(Clone, Debug)]
pub struct Link {
    /// URDF name.
    pub name: String,
    /// Index of the joint whose child this link is (`None` for the root).
    pub parent_joint: Option<usize>,
    /// The link's `<collision>` elements, in the link frame.
    pub collisions: Vec<Collision>,
}

/// One `<collision>` element of a link.
#[derive(Clone, Debug)]
pub struct Collision {
    /// Its `name` attribute, if any.
    pub name: Option<String>,
    /// Pose of the shape in the link frame.
    pub origin: Isometry3<f64>,
    /// The shape, in its own frame (cylinders and capsules along z, centred).
    pub shape: Shape,
}

/// A collision shape as URDF gives it. Sizes are checked finite and non-negative.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `<cylinder radius length>`: along z, centred.
    Cylinder {
        /// metres
        radius: f64,
        /// metres, end to end
        length: f64,
    },
    /// `<capsule radius length>` (the SDF convention): the cylinder part along z, centred, with
    /// hemispheres of `radius` on its ends.
    Capsule {
        /// metres
        radius: f64,
        /// metres, between the hemispheres' centres
        length: f64,
    },
    /// `<sphere radius>`.
    Sphere {
        /// metres
        radius: f64,
    },
    /// `<box size>`.
    Box {
        /// metres, full sizes along x, y, z
        size: [f64; 3],
    },
    /// `<mesh filename>`.
    Mesh {
        /// As written in the file.
        filename: String,
    },
}

/// A mechanism: a spanning tree of joints rooted at the ground, plus loop closures.
#[derive(Clone, Debug)]
pub struct Mechanism {
    /// The robot's name.
    pub name: String,
    /// Links; `links[root]` is the ground.
    pub links: Vec<Link>,
    /// Tree joints.
    pub joints: Vec<Joint>,
    /// Loop closures.
    pub loops: Vec<LoopClosure>,
    /// Index of the ground link.
    pub root: usize,
    /// Joints named in the file's `<transmission>` elements, in file order, each once: the
    /// actuated joints by default.
    pub transmission_joints: Vec<String>,
}

/// What is wrong with a mechanism description. Messages name the element at fault.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum ModelError {
    /// The file is not well-formed XML or not a URDF robot.
    #[error("malformed URDF: {0}")]
    Malformed(String),
    /// A joint or loop names a link that does not exist.
    #[error("{element} refers to unknown link '{link}'")]
    UnknownLink {
        /// the joint or loop
        element: String,
        /// the missing link
        link: String,
    },
    /// The joints do not form a tree with a single root.
    #[error("joints do not form a tree: {0}")]
    NotATree(String),
    /// A joint type the analysis does not handle.
    #[error("joint '{joint}' has type {kind}, which linkspace does not support")]
    UnsupportedJoint {
        /// the joint
        joint: String,
        /// its type
        kind: String,
    },
    /// A number is NaN or infinite, an axis is zero, or limits are inverted.
    #[error("{element}: {problem}")]
    BadValue {
        /// where
        element: String,
        /// what
        problem: String,
    },
    /// Two elements share a name.
    #[error("duplicate name '{0}'")]
    Duplicate(String),
}

impl Mechanism {
    /// Links joined to their parent by a fixed joint, each with the link it moves with (the
    /// nearest ancestor whose own joint is not fixed, or the root): such a link's pose is that
    /// body's composed with the fixed joints' origins, so reports list it once instead of in every
    /// box.
    pub fn rigid_links(&self) -> BTreeMap<String, String> {
        let parent_joint: HashMap<usize, &Joint> = self.joints.iter().map(|j| (j.child, j)).collect();
        let mut out = BTreeMap::new();
        for (i, link) in self.links.iter().enumerate() {
            let mut body = i;
            // A tree: following parents ends at the root within `links.len()` steps.
            while let Some(j) = parent_joint.get(&body).filter(|j| j.kind == JointKind::Fixed) {
                body = j.parent;
            }
            if body != i {
                out.insert(link.name.clone(), self.links[body].name.clone());
            }
        }
        out
    }

    /// Index of the link named `name`.
    pub fn link(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Index of the tree joint named `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Tree joints from the root down to `link`, root first.
    pub fn path_to(&self, link: usize) -> Vec<usize> {
        let mut path = Vec::new();
        let mut at = link;
        while let Some(j) = self.links[at].parent_joint {
            path.push(j);
            at = self.joints[j].parent;
        }
        path.reverse();
        path
    }

    /// Moves the origin of tree joint `joint` to `xyz`, `rpy` (as a file would state them):
    /// `origin` and `rpy` change together, and an exact rotation the rounding policy set is
    /// dropped (the policy runs again on the new values when an analysis reads the mechanism).
    pub fn set_joint_origin(&mut self, joint: usize, xyz: [f64; 3], rpy: [f64; 3]) -> Result<(), ModelError> {
        let j = &mut self.joints[joint];
        j.origin = urdf::pose(&format!("joint '{}'", j.name), xyz, rpy)?;
        j.rpy = rpy;
        j.exact_rotation = None;
        Ok(())
    }

    /// Moves one closure frame of loop `closure` (`successor` false: the predecessor's) to
    /// `xyz`, `rpy`.
    pub fn set_loop_origin(&mut self, closure: usize, successor: bool, xyz: [f64; 3], rpy: [f64; 3]) -> Result<(), ModelError> {
        let l = &mut self.loops[closure];
        let origin = urdf::pose(&format!("loop '{}'", l.name), xyz, rpy)?;
        if successor {
            (l.successor_origin, l.successor_rpy) = (origin, rpy);
        } else {
            (l.predecessor_origin, l.predecessor_rpy) = (origin, rpy);
        }
        Ok(())
    }

    /// Number of independent cycles (one per loop closure on a spanning tree).
    pub fn cycle_count(&self) -> usize {
        self.loops.len()
    }
}

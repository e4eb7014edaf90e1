//! The joint and workspace records shared by the 3R reports (`report::manip3r`) and the closed-form
//! singular branches (`branches`): intervals as `[lower, upper]`, joints by URDF name, the
//! workspace as radius and z.

use super::chain::Chain3R;
use inari::Interval;
use std::collections::BTreeMap;

pub(crate) use crate::kernel::interval::bounds;
pub(crate) use crate::kernel::interval::Bounds;

/// Joint intervals keyed by joint name (the second and third joints).
pub type Joints = BTreeMap<String, Bounds>;

/// `joints` in the order of `names` (records keyed by name → the positional records of
/// `app` and the ROS messages); a joint the record does not name is unbounded.
pub fn joints_over(joints: &Joints, names: &[String]) -> Vec<Bounds> {
    names.iter().map(|n| joints.get(n).copied().unwrap_or([f64::NEG_INFINITY, f64::INFINITY])).collect()
}

/// A workspace box.
#[derive(Clone, Debug, PartialEq)]
pub struct Workspace {
    /// Distance from the first axis.
    pub radius: Bounds,
    /// Coordinate along the first axis.
    pub z: Bounds,
}

impl Workspace {
    /// `[radius, z]`, the order of `app::SingularityResult::workspace_names`.
    pub fn bounds(&self) -> [Bounds; 2] {
        [self.radius, self.z]
    }
}

/// The second and third joints of `chain` over `theta`, by name.
pub(crate) fn joints(chain: &Chain3R, theta: &[Interval; 2]) -> Joints {
    BTreeMap::from([(chain.joints[1].clone(), bounds(theta[0])), (chain.joints[2].clone(), bounds(theta[1]))])
}

/// The radius √ρ over `rho` (ρ ≥ 0 always holds).
pub fn radius(rho: Interval) -> Interval {
    rho.intersection(crate::kernel::interval::interval(0.0, f64::INFINITY)).sqrt()
}

/// The workspace box of `(ρ, z)`.
pub(crate) fn workspace(rho: Interval, z: Interval) -> Workspace {
    Workspace { radius: bounds(radius(rho)), z: bounds(z) }
}

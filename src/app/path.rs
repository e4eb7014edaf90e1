//! Joint paths checked against a singular set: the 6R arm's (`det J = 0`, `arm6r::path`) or
//! its 3R positioning structure's (`det Df = 0`, `arm3r::path`), one verdict per segment.

use super::arm::Arm;
use crate::analyses::joint_path::PathCheck;
use crate::analyses::arm3r::{self, Manip3rError};
use crate::analyses::arm6r::{self, Chain6R, Manip6rError};
use crate::kernel::search::Control;
use std::time::Instant;

/// Which singular set a path is checked against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathSet {
    /// The six-revolute arm's: `det J = 0` (the arm loses a direction of the tip's motion).
    Arm6R,
    /// The 3R positioning structure's: `det Df = 0` of its half-section map (the analysed point
    /// loses a direction of motion in the plane of joint 1).
    Positioning3R,
}

impl ArmPathCheck {
    /// The one-line summary: the arm (the sub-chain, its point and det Df for a 3R check) and
    /// how many segments cross, touch or are clear.
    pub fn headline(&self) -> String {
        let c = self.check.counts();
        let mut line = format!(
            "{}: {} segments: {} cross a singularity, {} touch or undecided, {} clear",
            if self.set == PathSet::Arm6R { &self.arm } else { &self.subject },
            self.check.segments.len(),
            c.crosses,
            c.touches_or_undecided,
            c.clear
        );
        if c.not_decided > 0 {
            let limit = self.completeness().reason().map_or("a", |r| r.name());
            line += &format!(", {} not decided (stopped on the {limit} limit)", c.not_decided);
        }
        line
    }

    /// Whether every segment is decided (`PathCheck::completeness`).
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        self.check.completeness()
    }
}

impl PathSet {
    /// The set's short name in reports and messages: `6r` or `3r`.
    pub fn name(self) -> &'static str {
        match self {
            PathSet::Arm6R => "6r",
            PathSet::Positioning3R => "3r",
        }
    }

    /// The determinant whose zeros the set is, as the reasons write it.
    pub fn det(self) -> &'static str {
        match self {
            PathSet::Arm6R => "det J",
            PathSet::Positioning3R => "det Df",
        }
    }
}

/// What `path-check` found.
#[derive(Clone, Debug)]
pub struct ArmPathCheck {
    /// One verdict per segment.
    pub check: PathCheck,
    /// The set checked against.
    pub set: PathSet,
    /// What the verdicts concern: the arm or the sub-chain and point, and the determinant.
    pub subject: String,
    /// The arm: base, tip and the joints of the waypoints.
    pub arm: String,
    /// The joints of the waypoints' values, in order.
    pub joints: Vec<String>,
    /// The tolerance (radians) crossings were narrowed to.
    pub tolerance: f64,
    /// Wall time.
    pub seconds: f64,
}

/// Decides each segment of the joint path through `waypoints` (joints in `chain.joints`
/// order, radians) against `det J = 0`: clear, crossing a singularity (narrowed to
/// `tolerance`), or undecided.
pub fn check_path(chain: &Chain6R, waypoints: &[[f64; 6]], tolerance: f64, control: &Control) -> Result<ArmPathCheck, Manip6rError> {
    let start = Instant::now();
    let check = arm6r::path::check(chain, waypoints, tolerance, control)?;
    let arm = format!("{} -> {} ({})", chain.base, chain.tip, chain.joints.join(", "));
    Ok(ArmPathCheck {
        check,
        set: PathSet::Arm6R,
        subject: format!("6R arm {} -> {}: {}", chain.base, chain.tip, PathSet::Arm6R.det()),
        arm,
        joints: chain.joints.to_vec(),
        tolerance,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The joints a 3R path's waypoints give, in order: the three of the positioning structure,
/// then those after them on the chain (locked joints left out).
pub fn positioning_joints(arm: &Arm) -> Vec<String> {
    let choice = &arm.prepared.choice;
    choice.joints.iter().chain(&choice.wrist_joints).cloned().collect()
}

/// Decides each segment of the path through `waypoints` (radians, `positioning_joints(arm)`
/// order) against the 3R positioning structure's `det Df = 0`: clear, crossing (narrowed to
/// `tolerance`), or undecided. Only joints 2 and 3 of the structure move `det Df`.
pub fn check_path3(arm: &Arm, waypoints: &[Vec<f64>], tolerance: f64, control: &Control) -> Result<ArmPathCheck, Manip3rError> {
    let start = Instant::now();
    let joints = positioning_joints(arm);
    let choice = &arm.prepared.choice;
    // The chain's joints are the choice's, base first (the reduced mechanism keeps their names).
    let place = |name: &str| joints.iter().position(|j| j == name);
    let theta = match (place(&arm.chain.joints[1]), place(&arm.chain.joints[2])) {
        (Some(i), Some(j)) => [i, j],
        _ => return Err(Manip3rError::BadPath(format!("joints '{}' and '{}' of the sub-chain are not among the arm's joints ({})", arm.chain.joints[1], arm.chain.joints[2], joints.join(", ")))),
    };
    let check = arm3r::path::check(&arm.chain, theta, joints.len(), waypoints, tolerance, control)?;
    Ok(ArmPathCheck {
        check,
        set: PathSet::Positioning3R,
        subject: format!("{}: {}", choice.scope.subject, PathSet::Positioning3R.det()),
        arm: format!("{} -> {} ({})", choice.base, choice.tip, joints.join(", ")),
        joints,
        tolerance,
        seconds: start.elapsed().as_secs_f64(),
    })
}

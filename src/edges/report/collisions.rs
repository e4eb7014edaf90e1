//! What `linkspace collisions --json` writes: the capsules, the pairs checked, and the
//! colliding, free and undecided boxes over (θ₂, θ₃).

use super::kernel::CompletenessDef;
use crate::analyses::arm3r::collision::{CollisionSet, Scene};
use crate::analyses::arm3r::records::{bounds, Joints};
use crate::app::ArmCollisions;
use crate::kernel::outcome::Completeness;
use inari::Interval;
use serde::Serialize;
use std::collections::BTreeMap;

/// A capsule of the collision scene.
#[derive(Clone, Debug, Serialize)]
pub struct BodyRecord {
    /// Collision element name (or `link/index`).
    pub name: String,
    /// Its link.
    pub link: String,
    /// Radius (metres).
    pub radius: f64,
    /// Segment end points in the link frame (metres).
    pub segment: [[f64; 3]; 2],
}

/// A colliding box.
#[derive(Clone, Debug, Serialize)]
pub struct CollidingRecord {
    /// Joint box.
    pub joints: Joints,
    /// The two bodies proven to collide on all of it.
    pub pair: [String; 2],
}

/// A free or undecided box.
#[derive(Clone, Debug, Serialize)]
pub struct BoxRecord {
    /// Joint box.
    pub joints: Joints,
}

/// What `linkspace collisions --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct CollisionReport {
    /// Robot name.
    pub robot: String,
    /// The three revolute joints, base first.
    pub joints: [String; 3],
    /// Precision (radians).
    pub precision: f64,
    /// The capsules.
    pub bodies: Vec<BodyRecord>,
    /// The pairs checked, by body name.
    pub pairs: Vec<[String; 2]>,
    /// `status` and, when incomplete, `limit`: the limit that stopped the run (`boxes`, `time`,
    /// `memory` or `cancelled`).
    #[serde(flatten, serialize_with = "CompletenessDef::serialize")]
    pub completeness: Completeness,
    /// Boxes where a pair collides everywhere.
    pub colliding: Vec<CollidingRecord>,
    /// Boxes where no pair collides anywhere.
    pub free: Vec<BoxRecord>,
    /// The rest.
    pub undecided: Vec<BoxRecord>,
    /// Counters and areas.
    pub stats: CollisionStats,
}

/// Counters and areas (rad²) of a classification.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct CollisionStats {
    /// Boxes processed.
    pub processed: u64,
    /// Bisections.
    pub bisected: u64,
    /// Total area of the colliding boxes.
    pub colliding_area: f64,
    /// Total area of the free boxes.
    pub free_area: f64,
    /// Total area of the undecided boxes.
    pub undecided_area: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl CollisionReport {
    /// What `linkspace collisions --json` writes of `found`, classified at `precision`.
    pub fn of(found: &ArmCollisions, precision: f64) -> Self {
        Self::new(&found.scene, precision, &found.set)
    }

    /// Builds the report of a classification.
    pub fn new(scene: &Scene, precision: f64, set: &CollisionSet) -> Self {
        let capsules = scene.capsules();
        let name = |k: usize| {
            let (i, j) = scene.pairs()[k];
            [capsules[i].name.clone(), capsules[j].name.clone()]
        };
        let joints = |theta: &[Interval; 2]| BTreeMap::from([(scene.joints[1].clone(), bounds(theta[0])), (scene.joints[2].clone(), bounds(theta[1]))]);
        CollisionReport {
            robot: scene.name.clone(),
            joints: scene.joints.clone(),
            precision,
            bodies: capsules.iter().map(|c| BodyRecord { name: c.name.clone(), link: c.link.clone(), radius: c.radius, segment: c.segment }).collect(),
            pairs: (0..scene.pairs().len()).map(name).collect(),
            completeness: set.completeness(),
            colliding: set.colliding.iter().map(|c| CollidingRecord { joints: joints(&c.theta), pair: name(c.pair) }).collect(),
            free: set.free.iter().map(|b| BoxRecord { joints: joints(b) }).collect(),
            undecided: set.undecided.iter().map(|b| BoxRecord { joints: joints(b) }).collect(),
            stats: CollisionStats {
                processed: set.stats.processed,
                bisected: set.stats.split,
                colliding_area: set.colliding_area,
                free_area: set.free_area,
                undecided_area: set.undecided_area,
                seconds: set.seconds,
            },
        }
    }
}

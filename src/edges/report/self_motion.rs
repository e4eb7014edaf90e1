//! The JSON of `linkspace self-motion`: the cover of a seven-revolute arm's self-motion set at a
//! pose, its boxes with their tags and clusters, and each cluster's joint ranges.

use super::kernel::CompletenessDef;
use crate::app::ArmSelfMotion;
use crate::kernel::outcome::Completeness;
use crate::kernel::search::BoxStatus;
use serde::Serialize;
use std::collections::BTreeMap;

/// Joint name → [lo, hi] (radians).
pub type JointRanges = BTreeMap<String, [f64; 2]>;

/// One box of the cover.
#[derive(Clone, Debug, Serialize)]
pub struct MotionBoxRecord {
    /// Its interval per joint.
    pub joints: JointRanges,
    /// `unique` (a certified piece of arc: exactly one configuration for every parameter angle
    /// of its cell), `solution` (may hold configurations) or `undecided` (a cell left unsearched).
    pub tag: &'static str,
    /// Its cluster.
    pub cluster: usize,
}

/// A cluster of touching boxes: a candidate component.
#[derive(Clone, Debug, Serialize)]
pub struct ClusterRecord {
    /// Boxes in it.
    pub boxes: usize,
    /// Of which certified pieces of arc.
    pub certified: usize,
    /// The hull of its boxes, per joint.
    pub ranges: JointRanges,
}

/// What `linkspace self-motion --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct SelfMotionReport {
    /// The seven joints, base first.
    pub joints: Vec<String>,
    /// The joint whose range is cut into cells.
    pub parameter: String,
    /// Its range searched.
    pub range: [f64; 2],
    /// The width of a cell (radians).
    pub cell: f64,
    /// Cells searched, of `cells`.
    pub cells_searched: usize,
    /// Cells in the range.
    pub cells: usize,
    /// The pose as given (as `ik6` takes it).
    pub pose: Vec<f64>,
    /// `status` and, when incomplete, `limit`: complete when every cell was searched and every
    /// box is a certified piece of arc.
    #[serde(flatten, serialize_with = "CompletenessDef::serialize")]
    pub completeness: Completeness,
    /// Boxes certified as pieces of arc.
    pub certified: usize,
    /// The clusters.
    pub clusters: Vec<ClusterRecord>,
    /// The boxes, cell after cell.
    pub boxes: Vec<MotionBoxRecord>,
    /// Boxes the 6R searches processed.
    pub processed: u64,
    /// Wall time (seconds).
    pub seconds: f64,
}

impl SelfMotionReport {
    /// The report of a run.
    pub fn of(found: &ArmSelfMotion) -> Self {
        let set = &found.set;
        let named = |b: &[crate::kernel::interval::Interval]| -> JointRanges { set.joints.iter().zip(b).map(|(n, x)| (n.clone(), [x.inf() + 0.0, x.sup() + 0.0])).collect() };
        let mut clusters: Vec<ClusterRecord> = (0..set.clusters).map(|_| ClusterRecord { boxes: 0, certified: 0, ranges: JointRanges::new() }).collect();
        for b in &set.boxes {
            let c = &mut clusters[b.cluster];
            c.boxes += 1;
            c.certified += usize::from(b.tag == BoxStatus::Unique);
            for (n, x) in set.joints.iter().zip(&b.joints) {
                // + 0.0: an interval's bound may be −0, which reads oddly.
                let r = c.ranges.entry(n.clone()).or_insert([x.inf() + 0.0, x.sup() + 0.0]);
                *r = [r[0].min(x.inf() + 0.0), r[1].max(x.sup() + 0.0)];
            }
        }
        SelfMotionReport {
            joints: set.joints.clone(),
            parameter: set.joints[set.parameter].clone(),
            range: [set.range.0, set.range.1],
            cell: set.cell,
            cells_searched: set.cells.0,
            cells: set.cells.1,
            pose: found.pose.numbers().to_vec(),
            completeness: set.completeness(),
            certified: set.certified(),
            clusters,
            boxes: set.boxes.iter().map(|b| MotionBoxRecord { joints: named(&b.joints), tag: b.tag.name(), cluster: b.cluster }).collect(),
            processed: set.stats.processed,
            seconds: found.seconds,
        }
    }
}

//! What `linkspace solve --json` writes (schema in README): a linkage's configuration-space box
//! set (`app::BoxSetResult`, as `app::SolveRun` returns it), with what the problem adds per
//! box: the links' orientations (planar model) or poses (spatial model).

use super::kernel;
use crate::app::{BoxSetResult, LinkReadout, ResultBox, TracedBounds};
use crate::kernel::interval::Bounds;
use crate::formulate::singular::Coordinates;
use crate::formulate::spatial::LinkPose;
use crate::formulate::Linkage;
use crate::kernel::search::{BoxStatus, SolveStats, SolverSettings, Status};
use crate::kernel::system::VarRole;
use serde::Serialize;
use std::collections::BTreeMap;

/// One reported box, in the user's terms; made as it is written (`Records`), its names
/// borrowed from the result.
#[derive(Clone, Debug, Serialize)]
pub struct BoxRecord<'a> {
    /// Free joint values (radians or metres), keyed by joint name.
    pub joints: BTreeMap<&'a str, Bounds>,
    /// Every link's world-frame orientation in the plane (radians), keyed by link name.
    pub link_angles: BTreeMap<&'a str, Bounds>,
    /// Traced points' world coordinates, keyed by `LINK@X,Y` (or `LINK@X,Y,Z`).
    pub traces: BTreeMap<&'a str, TracedPoint>,
    /// Spatial model only: every link's pose in the root frame (position intervals, quaternion
    /// `[w, x, y, z]` at the box midpoint).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link_poses: Option<BTreeMap<&'a str, LinkPoseRecord<'a>>>,
    /// The raw box, one entry per system variable (see `variables`).
    #[serde(rename = "box")]
    pub box_: &'a [Bounds],
    /// Depth in the search tree.
    pub level: u32,
    /// Certified by interval Newton to hold exactly one solution (solution boxes only).
    pub unique: bool,
}

/// World coordinates of a traced point.
#[derive(Clone, Debug, Serialize)]
pub struct TracedPoint {
    /// x interval
    pub x: Bounds,
    /// y interval
    pub y: Bounds,
    /// z interval (spatial model only)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<Bounds>,
}

/// A link's pose over a box.
#[derive(Clone, Debug, Serialize)]
pub struct LinkPoseRecord<'a>(#[serde(with = "LinkPoseDef")] pub &'a LinkPose);

/// `LinkPose`, field for field.
#[derive(Serialize)]
#[serde(remote = "LinkPose")]
struct LinkPoseDef {
    position: Option<[[f64; 2]; 3]>,
    quaternion: Option<[f64; 4]>,
    rotation_width: Option<f64>,
}

/// A system variable as listed in the report.
#[derive(Clone, Debug, Serialize)]
pub struct VariableInfo {
    /// Name, e.g. `cos_link7`.
    pub name: String,
    /// `primary` or `derived`.
    #[serde(with = "kernel::VarRoleDef")]
    pub role: VarRole,
}

/// The whole result of `linkspace solve`.
#[derive(Clone, Debug, Serialize)]
pub struct SolveReport<'a> {
    /// Robot name from the URDF.
    pub mechanism: String,
    /// `planar` or `spatial`: the builder that made the system.
    pub model: String,
    /// Why that model: what made the mechanism planar or not, or that it was forced.
    pub model_reason: String,
    /// What the spatial builder simplified (legs between ball joints reduced to distances).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reductions: Vec<String>,
    /// Links joined to their parent by a fixed joint, each with the link it moves with: a box
    /// lists only the links that move on their own (`Mechanism::rigid_links`).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub rigid_links: BTreeMap<String, String>,
    /// Joints whose values were solved for.
    pub free_joints: Vec<String>,
    /// Joints fixed with `--fix`.
    pub fixed_joints: BTreeMap<String, f64>,
    /// The solver settings.
    #[serde(with = "kernel::SolverSettingsDef")]
    pub settings: SolverSettings,
    /// `complete`, or `incomplete` with the limit.
    #[serde(flatten, with = "kernel::StatusDef")]
    pub status: Status,
    /// The system's variables, in box order.
    pub variables: Vec<VariableInfo>,
    /// Solution boxes.
    pub solutions: Records<'a>,
    /// Connected components of the solution boxes (touching boxes share a component).
    pub clusters: usize,
    /// Boxes left undecided by a limit (empty when complete).
    pub undecided: Records<'a>,
    /// Counters and time.
    #[serde(with = "kernel::SolveStatsDef")]
    pub stats: SolveStats,
}

impl<'a> SolveReport<'a> {
    /// The report of `result`, a run of `problem` (`app::SolveRun::run_reading`) with its
    /// boxes' `links` read out (one per box, in order); `rigid_links` as
    /// `Mechanism::rigid_links` gives them.
    pub fn new(problem: &Linkage, result: &'a BoxSetResult, links: &'a [LinkReadout], rigid_links: BTreeMap<String, String>) -> Self {
        SolveReport {
            mechanism: result.mechanism.clone(),
            model: problem.model().name().to_string(),
            model_reason: problem.model_reason().to_string(),
            reductions: problem.reductions().to_vec(),
            rigid_links: rigid_links.clone(),
            free_joints: result.joint_names.clone(),
            fixed_joints: result.fixed_joints.iter().cloned().collect(),
            settings: result.settings.clone(),
            status: result.status,
            variables: result
                .variables
                .iter()
                .enumerate()
                .map(|(i, name)| VariableInfo { name: name.clone(), role: if result.primaries.contains(&i) { VarRole::Primary } else { VarRole::Derived } })
                .collect(),
            solutions: Records { result, links, solutions: true },
            clusters: result.clusters,
            undecided: Records { result, links, solutions: false },
            stats: result.stats.clone(),
        }
    }
}

/// The solution boxes (or the undecided ones) of a result, each made into its `BoxRecord`
/// only as it is written: a report of a million boxes holds one record at a time.
#[derive(Clone, Copy, Debug)]
pub struct Records<'a> {
    result: &'a BoxSetResult,
    links: &'a [LinkReadout],
    solutions: bool,
}

impl Serialize for Records<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let unread = LinkReadout::Unread;
        let kept = |b: &ResultBox| if self.solutions { b.status.is_solution() } else { b.status == BoxStatus::Undecided };
        s.collect_seq(self.result.boxes.iter().enumerate().filter(|(_, b)| kept(b)).map(|(i, b)| box_record(self.result, b, self.links.get(i).unwrap_or(&unread))))
    }
}

/// One box of `result` in the user's terms, with its links as the run read them out.
fn box_record<'a>(result: &'a BoxSetResult, b: &'a ResultBox, links: &'a LinkReadout) -> BoxRecord<'a> {
    let traced = |t: &TracedBounds| TracedPoint { x: t.x, y: t.y, z: t.z };
    let (link_angles, link_poses) = match links {
        LinkReadout::Angles(a) => (a.iter().map(|(k, &(lo, hi))| (k.as_str(), [lo, hi])).collect(), None),
        LinkReadout::Poses(p) => (BTreeMap::new(), Some(p.iter().map(|(k, pose)| (k.as_str(), LinkPoseRecord(pose))).collect())),
        LinkReadout::Unread => (BTreeMap::new(), None),
    };
    BoxRecord {
        joints: result.joint_names.iter().map(String::as_str).zip(b.joints.iter().copied()).collect(),
        link_angles,
        traces: result.traces.iter().map(String::as_str).zip(b.traces.iter().map(traced)).collect(),
        link_poses,
        box_: &b.bounds,
        level: b.level,
        unique: b.status == BoxStatus::Unique,
    }
}

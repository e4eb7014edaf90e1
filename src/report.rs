//! Solve reports: what `linkspace solve --json` writes (schema in README), built from a run.
//!
//! Pure data: no IO here; the CLI writes it, the ROS node will publish it.

use crate::interval::{components, IntervalBox};
use crate::problems::spatial::LinkPose;
use crate::problems::{Linkage, LinkageProblem, SpatialProblem};
use crate::search::{SolveStats as Stats, SolverSettings, Status};
use crate::system::{EquationSystem, VarRole};
use serde::Serialize;

pub mod distances;
pub(crate) mod kernel;
pub mod singular;
use std::collections::BTreeMap;

pub use crate::interval::Bounds;

/// One reported box, in the user's terms.
#[derive(Clone, Debug, Serialize)]
pub struct BoxRecord {
    /// Free joint values (radians or metres), keyed by joint name.
    pub joints: BTreeMap<String, Bounds>,
    /// Every link's world-frame orientation in the plane (radians), keyed by link name.
    pub link_angles: BTreeMap<String, Bounds>,
    /// Traced points' world coordinates, keyed by `LINK@X,Y` (or `LINK@X,Y,Z`).
    pub traces: BTreeMap<String, TracedPoint>,
    /// Spatial model only: every link's pose in the root frame (position intervals, quaternion
    /// `[w, x, y, z]` at the box midpoint).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub link_poses: Option<BTreeMap<String, LinkPose>>,
    /// The raw box, one entry per system variable (see `variables`).
    #[serde(rename = "box")]
    pub box_: Vec<Bounds>,
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
pub struct SolveReport {
    /// Robot name from the URDF.
    pub mechanism: String,
    /// `planar` or `spatial`: the builder that made the system.
    pub model: String,
    /// Why that model: what made the mechanism planar or not, or that it was forced.
    pub model_reason: String,
    /// What the spatial builder simplified (legs between ball joints reduced to distances).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reductions: Vec<String>,
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
    pub solutions: Vec<BoxRecord>,
    /// Connected components of the solution boxes (touching boxes share a component).
    pub clusters: usize,
    /// Boxes left undecided by a limit (empty when complete).
    pub undecided: Vec<BoxRecord>,
    /// Counters and time.
    #[serde(with = "kernel::SolveStatsDef")]
    pub stats: Stats,
}

impl SolveReport {
    /// A report of one model's run, without its variables and boxes yet (`add_run`).
    #[allow(clippy::too_many_arguments)]
    fn empty(mechanism: &str, model: &str, reason: &str, free_joints: &[String], fixed_joints: &[(String, f64)], settings: &SolverSettings, status: Status, stats: Stats) -> Self {
        SolveReport {
            mechanism: mechanism.into(),
            model: model.into(),
            model_reason: reason.into(),
            reductions: Vec::new(),
            free_joints: free_joints.to_vec(),
            fixed_joints: fixed_joints.iter().cloned().collect(),
            settings: settings.clone(),
            status,
            variables: Vec::new(),
            solutions: Vec::new(),
            clusters: 0,
            undecided: Vec::new(),
            stats,
        }
    }

    /// The system's variables and the run's boxes, each read by the model's `record`.
    fn add_run(&mut self, system: &EquationSystem, record: impl Fn(&IntervalBox) -> BoxRecord, solutions: &[IntervalBox], unique: &[bool], undecided: &[IntervalBox]) {
        self.variables = system.vars.iter().map(|v| VariableInfo { name: v.name.clone(), role: v.role }).collect();
        self.solutions = solutions.iter().zip(unique).map(|(b, &u)| BoxRecord { unique: u, ..record(b) }).collect();
        self.clusters = components(solutions).1;
        self.undecided = undecided.iter().map(record).collect();
    }
}

impl LinkageProblem {
    /// One box in the user's terms.
    pub fn record(&self, b: &IntervalBox) -> BoxRecord {
        let pair = |(lo, hi): (f64, f64)| [lo, hi];
        BoxRecord {
            joints: self.joint_values(b).into_iter().map(|(k, v)| (k, pair(v))).collect(),
            link_angles: self.link_angles(b).into_iter().map(|(k, v)| (k, pair(v))).collect(),
            traces: self
                .traces
                .iter()
                .map(|t| {
                    let (x, y) = (b.dims[t.x], b.dims[t.y]);
                    (t.name.clone(), TracedPoint { x: [x.inf(), x.sup()], y: [y.inf(), y.sup()], z: None })
                })
                .collect(),
            link_poses: None,
            box_: b.dims.iter().map(|d| [d.inf(), d.sup()]).collect(),
            level: b.level,
            unique: false,
        }
    }

    /// The report of a finished run.
    pub fn report(&self, settings: &SolverSettings, status: Status, stats: Stats, solutions: &[IntervalBox], unique: &[bool], undecided: &[IntervalBox]) -> SolveReport {
        let mut report = SolveReport::empty(&self.name, "planar", PLANAR_REASON, &self.free_joints, &self.fixed_joints, settings, status, stats);
        report.add_run(&self.system, |b| self.record(b), solutions, unique, undecided);
        report
    }
}

/// Why a mechanism the planar builder accepts is solved with it.
pub const PLANAR_REASON: &str = "every revolute axis is parallel and every slider lies in the plane: one angle per rigid group";

impl SpatialProblem {
    /// One box in the user's terms.
    pub fn record(&self, b: &IntervalBox) -> BoxRecord {
        BoxRecord {
            joints: self.joint_values(b).into_iter().map(|(k, (lo, hi))| (k, [lo, hi])).collect(),
            link_angles: BTreeMap::new(),
            traces: self
                .traces
                .iter()
                .map(|t| {
                    let [x, y, z] = t.xyz.map(|v| [b.dims[v].inf(), b.dims[v].sup()]);
                    (t.name.clone(), TracedPoint { x, y, z: Some(z) })
                })
                .collect(),
            link_poses: Some(self.link_poses(b)),
            box_: b.dims.iter().map(|d| [d.inf(), d.sup()]).collect(),
            level: b.level,
            unique: false,
        }
    }

    /// The report of a finished run; `reason` says why the spatial model was chosen.
    #[allow(clippy::too_many_arguments)]
    pub fn report(&self, reason: &str, settings: &SolverSettings, status: Status, stats: Stats, solutions: &[IntervalBox], unique: &[bool], undecided: &[IntervalBox]) -> SolveReport {
        let mut report = SolveReport::empty(&self.name, "spatial", reason, &self.free_joints, &self.fixed_joints, settings, status, stats);
        report.reductions = self.reductions.clone();
        report.add_run(&self.system, |b| self.record(b), solutions, unique, undecided);
        report
    }
}

impl Linkage {
    /// The report of a finished run (`solve --json`).
    #[allow(clippy::too_many_arguments)]
    pub fn report(&self, settings: &SolverSettings, status: Status, stats: Stats, solutions: &[IntervalBox], unique: &[bool], undecided: &[IntervalBox]) -> SolveReport {
        match self {
            Self::Planar(p) => p.report(settings, status, stats, solutions, unique, undecided),
            Self::Spatial(p, why) => p.report(why, settings, status, stats, solutions, unique, undecided),
        }
    }
}

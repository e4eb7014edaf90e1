//! Singular-set reports: what `linkspace loop-singularities --json` writes, built from a
//! `SingularSet`. Pure data, no IO.

use crate::kernel::outcome::BoxStatus;
use super::Bounds;
use crate::kernel::interval::IntervalBox;
use crate::formulate::singular::{Coordinates, Output, SingularProblem};
use crate::analyses::loop_singular::{SingularSet};
use crate::kernel::search::{SolveStats, SolverSettings, Status};
use serde::Serialize;
use std::collections::BTreeMap;

/// One singular set of one mechanism.
#[derive(Clone, Debug, Serialize)]
pub struct SingularReport {
    /// Robot name.
    pub mechanism: String,
    /// The model the linkage was built with, as `solve --model auto` chooses: `planar` or
    /// `spatial`.
    pub model: &'static str,
    /// `cspace`, `input` or `output`.
    pub kind: &'static str,
    /// Actuated joints, in the order of `actuators` below.
    pub actuated: Vec<String>,
    /// The output (output singularities only): `LINK@X,Y` or joint names joined by commas;
    /// `passive joints` when none was given.
    pub output: Option<String>,
    /// Joints fixed with `--fix`.
    pub fixed_joints: BTreeMap<String, f64>,
    /// Degrees of freedom (coordinates minus loop rows).
    pub dof: isize,
    /// Dimension of the set for generic geometry: 0 points, 1 curves, negative generically empty.
    pub expected_dimension: isize,
    /// Charts of the projective sphere of multipliers searched.
    pub charts: usize,
    /// The solver settings (max_boxes per chart, timeout for all).
    #[serde(with = "super::kernel::SolverSettingsDef")]
    pub settings: SolverSettings,
    /// `complete`, or `incomplete` with the limit.
    #[serde(flatten, with = "super::kernel::StatusDef")]
    pub status: Status,
    /// Counts.
    pub summary: Summary,
    /// Clusters of boxes whose configuration parts touch.
    pub clusters: Vec<ClusterRecord>,
    /// Every box.
    pub boxes: Vec<SingularBoxRecord>,
    /// Per chart, the solver's counters.
    #[serde(serialize_with = "super::kernel::solve_stats_list")]
    pub stats: Vec<SolveStats>,
    /// Wall-clock seconds, all charts.
    pub seconds: f64,
}

/// What is proven and what is not.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Clusters in all.
    pub clusters: usize,
    /// Clusters holding a certified box: each holds at least one singular configuration.
    pub certified_clusters: usize,
    /// Clusters without a certified box (no proof that they hold a singular configuration, none
    /// that they do not).
    pub unproven_clusters: usize,
    /// Boxes left undecided by a limit.
    pub undecided_boxes: usize,
    /// Boxes in all.
    pub boxes: usize,
    /// Boxes dropped because they are proven to be another chart's (found there).
    pub dropped_as_other_charts: u64,
    /// Charts a limit left unsearched (the last ones), all held by one undecided box.
    pub unsearched_charts: usize,
}

/// A cluster: for a point set, one singular configuration (certified or not).
#[derive(Clone, Debug, Serialize)]
pub struct ClusterRecord {
    /// Holds a certified box.
    pub certified: bool,
    /// Holds an undecided box.
    pub undecided: bool,
    /// Number of boxes.
    pub boxes: usize,
    /// Hull of the free joint values over the cluster's boxes.
    pub joints: BTreeMap<String, Bounds>,
    /// Hull of the actuated joint values, in the order of `actuated`.
    pub actuators: Vec<Bounds>,
}

/// One box.
#[derive(Clone, Debug, Serialize)]
pub struct SingularBoxRecord {
    /// Chart index.
    pub chart: usize,
    /// `unique`, `solution` or `undecided` (`BoxStatus::name`).
    #[serde(serialize_with = "super::kernel::box_status")]
    pub status: BoxStatus,
    /// Index into `clusters`.
    pub cluster: usize,
    /// Free joint values.
    pub joints: BTreeMap<String, Bounds>,
    /// Actuated joint values, in the order of `actuated`.
    pub actuators: Vec<Bounds>,
    /// The null vector's components (velocity or row multipliers), in the chart's scale.
    pub multipliers: Vec<Bounds>,
}

fn hull(a: Bounds, b: (f64, f64)) -> Bounds {
    [a[0].min(b.0), a[1].max(b.1)]
}

impl SingularReport {
    /// The report of `set`, a run of `p` with `settings`.
    pub fn new<L: Coordinates>(p: &SingularProblem<L>, settings: &SolverSettings, set: &SingularSet) -> Self {
        let record = |b: &IntervalBox| -> (BTreeMap<String, Bounds>, Vec<Bounds>) {
            let joints = p.joint_values(b).into_iter().map(|(k, (lo, hi))| (k, [lo, hi])).collect();
            let act = p.actuator_values(b).into_iter().map(|(lo, hi)| [lo, hi]).collect();
            (joints, act)
        };
        let boxes: Vec<SingularBoxRecord> = set
            .boxes
            .iter()
            .zip(&set.labels)
            .map(|(sb, &cluster)| {
                let (joints, actuators) = record(&sb.b);
                let multipliers = p.multipliers.iter().map(|&m| [sb.b.dims[m].inf(), sb.b.dims[m].sup()]).collect();
                SingularBoxRecord { chart: sb.chart, status: sb.status, cluster, joints, actuators, multipliers }
            })
            .collect();
        let clusters: Vec<ClusterRecord> = set
            .clusters
            .iter()
            .map(|c| {
                let mut joints: BTreeMap<String, Bounds> = BTreeMap::new();
                let mut actuators: Vec<Bounds> = vec![[f64::INFINITY, f64::NEG_INFINITY]; p.actuated.len()];
                for &i in &c.boxes {
                    for (k, v) in &boxes[i].joints {
                        let e = joints.entry(k.clone()).or_insert([f64::INFINITY, f64::NEG_INFINITY]);
                        *e = hull(*e, (v[0], v[1]));
                    }
                    for (a, v) in actuators.iter_mut().zip(&boxes[i].actuators) {
                        *a = hull(*a, (v[0], v[1]));
                    }
                }
                ClusterRecord { certified: c.certified, undecided: c.undecided, boxes: c.boxes.len(), joints, actuators }
            })
            .collect();
        let certified = set.certified_clusters();
        let summary = Summary {
            clusters: clusters.len(),
            certified_clusters: certified,
            unproven_clusters: clusters.len() - certified,
            undecided_boxes: set.boxes.iter().filter(|b| b.status == BoxStatus::Undecided).count(),
            boxes: boxes.len(),
            dropped_as_other_charts: set.dropped_other_chart,
            unsearched_charts: set.unsearched_charts,
        };
        let output = match (&p.output, p.kind) {
            (Some(Output::Point { link, x, y }), _) => Some(format!("{link}@{x},{y}")),
            (Some(Output::Joints(j)), _) => Some(j.join(",")),
            (None, crate::formulate::singular::SingularKind::Output) => Some("passive joints".to_string()),
            _ => None,
        };
        SingularReport {
            mechanism: p.linkage.name().to_string(),
            model: p.model().name(),
            kind: p.kind.name(),
            actuated: p.actuated.clone(),
            output,
            fixed_joints: p.linkage.fixed_joints().iter().cloned().collect(),
            dof: p.dof,
            expected_dimension: p.expected_dimension,
            charts: p.chart_count(),
            settings: settings.clone(),
            status: set.status,
            summary,
            clusters,
            boxes,
            stats: set.stats.clone(),
            seconds: set.seconds,
        }
    }
}

//! The plain-data results the node's messages are made from: box sets (`BoxSetResult`, each
//! box with its `BoxStatus` and joint values), classifications of a configuration, and the
//! singularity and inverse-kinematics results of its services.

use super::six::ArmVerdictLine;
use crate::kernel::interval::Bounds;
use crate::kernel::outcome::{BoxStatus, Status};
use super::{prepare, Answer, Input, Job, JobError, Prepared};
use crate::kernel::search::{Control, Limits, Progress, SolveStats as Stats, SolverSettings};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// One box of a result, in the system's variables and in joint space.
#[derive(Clone, Debug, PartialEq)]
pub struct ResultBox {
    /// Solution or undecided.
    pub status: BoxStatus,
    /// One interval per system variable (`BoxSetResult::variables`).
    pub bounds: Vec<Bounds>,
    /// One interval per free joint (`BoxSetResult::joint_names`): radians or metres.
    pub joints: Vec<Bounds>,
    /// Depth in the search tree.
    pub level: u32,
    /// Connected component among the solution boxes; `None` for undecided boxes.
    pub cluster: Option<usize>,
    /// World coordinates of every traced point (`BoxSetResult::traces`).
    pub traces: Vec<TracedBounds>,
}

/// A traced point's world coordinates over a box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedBounds {
    /// x interval
    pub x: Bounds,
    /// y interval
    pub y: Bounds,
    /// z interval (spatial model only)
    pub z: Option<Bounds>,
}

/// The result of one run: boxes that together enclose every solution.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSetResult {
    /// Robot name.
    pub mechanism: String,
    /// What was analysed, e.g. `configuration_space`.
    pub analysis: String,
    /// How the run ended.
    pub status: Status,
    /// The settings it ran with.
    pub settings: SolverSettings,
    /// System variable names, in box order.
    pub variables: Vec<String>,
    /// Indices of the primary variables (those measured against sigma).
    pub primaries: Vec<usize>,
    /// Free joint names, in file order.
    pub joint_names: Vec<String>,
    /// Joints fixed for this run, with their values.
    pub fixed_joints: Vec<(String, f64)>,
    /// Traced point names (`LINK@X,Y`).
    pub traces: Vec<String>,
    /// Solution boxes first (in the order found), then undecided ones.
    pub boxes: Vec<ResultBox>,
    /// Number of connected components of the solution boxes.
    pub clusters: usize,
    /// Counters and time.
    pub stats: Stats,
}

/// An isolated solution: a cluster of solution boxes no wider than a few sigma, i.e. one
/// assembly mode of a rigid (or fully fixed) mechanism.
#[derive(Clone, Debug, PartialEq)]
pub struct AssemblyMode {
    /// The cluster's index.
    pub cluster: usize,
    /// Joint values at the middle of the cluster's hull, free joints then fixed ones.
    pub joints: Vec<(String, f64)>,
}

impl BoxSetResult {
    /// The one rule: the limit that stopped the run, else the boxes left undecided (a
    /// platform's cluster without a proof leaves a finished run incomplete).
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        let undecided = self.boxes.iter().filter(|b| b.status == BoxStatus::Undecided).count();
        crate::kernel::outcome::Completeness::of(self.status, undecided, false)
    }

    /// The isolated solutions: clusters whose hull is at most `4·sigma` wide in every primary
    /// variable. A curve of solutions spans far more than that.
    pub fn assembly_modes(&self) -> Vec<AssemblyMode> {
        let mut modes = Vec::new();
        // Members of every cluster in one pass: filtering all boxes once per cluster is
        // O(boxes × clusters), minutes for a large box set that a limit cut into many clusters.
        let mut by_cluster: Vec<Vec<&ResultBox>> = vec![Vec::new(); self.clusters];
        for b in &self.boxes {
            if let Some(members) = b.cluster.and_then(|c| by_cluster.get_mut(c)) {
                members.push(b);
            }
        }
        for (cluster, members) in by_cluster.into_iter().enumerate() {
            let hull = |pick: &dyn Fn(&ResultBox) -> &Vec<Bounds>, i: usize| {
                members.iter().map(|b| pick(b)[i]).fold([f64::INFINITY, f64::NEG_INFINITY], |h, x| [h[0].min(x[0]), h[1].max(x[1])])
            };
            let narrow = self.primaries.iter().all(|&i| {
                let h = hull(&|b| &b.bounds, i);
                h[1] - h[0] <= 4.0 * self.settings.sigma
            });
            if members.is_empty() || !narrow {
                continue;
            }
            let mut joints: Vec<(String, f64)> = (0..self.joint_names.len())
                .map(|i| {
                    let h = hull(&|b| &b.joints, i);
                    (self.joint_names[i].clone(), 0.5 * (h[0] + h[1]))
                })
                .collect();
            joints.extend(self.fixed_joints.iter().cloned());
            modes.push(AssemblyMode { cluster, joints });
        }
        modes
    }
}

/// Where a joint configuration sits relative to a configuration-space result.
#[derive(Clone, Debug, PartialEq)]
pub struct Classification {
    /// A solution box contains the configuration.
    pub inside: bool,
    /// Component of the nearest solution box (`None` when there are no solution boxes).
    pub component: Option<usize>,
    /// Number of components.
    pub components: usize,
    /// Joint-space distance to the nearest solution box (0 when inside).
    pub distance: f64,
    /// Joint-space distance to the nearest singular box, when a singularity analysis exists.
    pub singular_distance: Option<f64>,
    /// What the figures mean for this kind of mechanism, when it differs from the above
    /// (one line, for the reply's message); empty otherwise.
    pub note: String,
}

/// Distance from `x` to the interval `[lo, hi]`; angles (`periodic`) are compared modulo 2π.
pub(crate) fn gap(x: f64, [lo, hi]: Bounds, periodic: bool) -> f64 {
    let plain = |x: f64| if x < lo { lo - x } else if x > hi { x - hi } else { 0.0 };
    if !periodic {
        return plain(x);
    }
    let tau = std::f64::consts::TAU;
    // Try the nearest images of x on both sides of the interval.
    let k = ((0.5 * (lo + hi) - x) / tau).round();
    [-1.0, 0.0, 1.0].iter().map(|d| plain(x + (k + d) * tau)).fold(f64::INFINITY, f64::min)
}

/// Classifies a configuration given as a value per free joint, in `result.joint_names` order;
/// `periodic[i]` says whether joint i is an angle.
///
/// The configuration is inside when some solution box holds every joint value; its component
/// is that of the nearest box in the Euclidean joint-space distance.
pub fn classify(result: &BoxSetResult, values: &[f64], periodic: &[bool], singular: Option<&BoxSetResult>) -> Classification {
    let distance_to = |b: &ResultBox| -> f64 {
        b.joints.iter().zip(values).zip(periodic).map(|((&iv, &x), &p)| gap(x, iv, p).powi(2)).sum::<f64>().sqrt()
    };
    let nearest = |r: &BoxSetResult| {
        r.boxes
            .iter()
            .filter(|b| b.status.is_solution())
            .map(|b| (distance_to(b), b.cluster))
            .fold(None, |best: Option<(f64, Option<usize>)>, (d, c)| match best {
                Some((bd, _)) if bd <= d => best,
                _ => Some((d, c)),
            })
    };
    let (distance, component) = nearest(result).map_or((f64::INFINITY, None), |(d, c)| (d, c));
    Classification {
        inside: distance == 0.0,
        component,
        components: result.clusters,
        distance,
        singular_distance: singular.and_then(nearest).map(|(d, _)| d),
        note: String::new(),
    }
}

/// A node query that has been validated and only needs a thread. `T` is what it returns: a box
/// set (configuration space, solve), a `SingularityResult` or an `IkResult`.
pub trait PreparedRun<T = BoxSetResult>: Send {
    /// Runs to the end (or to a limit, or until `cancel` is raised), reporting progress. An
    /// error is one only the analysis itself could find mid-run (`Prepared::run`).
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> Result<T, JobError>;
}

/// How an `Answer` reads as the node's result.
type Reader<T> = Box<dyn FnOnce(Answer) -> Result<T, JobError> + Send>;

/// A node query answered through the front door: the `Job` it became, prepared on the
/// mechanism (so every check is done before a thread starts), the bounds of its run, and how its
/// `Answer` reads as the node's result. Every run of the node is one of these.
pub(crate) struct JobRun<T> {
    prepared: Prepared,
    limits: Limits,
    threads: usize,
    read: Reader<T>,
}

impl<T: 'static> JobRun<T> {
    /// Prepares `job` on `input`; `read` turns its answer into the node's result.
    pub(crate) fn new(input: &Input, job: Job, limits: Limits, threads: usize, read: impl FnOnce(Answer) -> Result<T, JobError> + Send + 'static) -> Result<Box<dyn PreparedRun<T>>, JobError> {
        let prepared = prepare(input, job)?;
        Ok(Box::new(JobRun { prepared, limits, threads: threads.max(1), read: Box::new(read) }))
    }
}

impl<T> PreparedRun<T> for JobRun<T> {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> Result<T, JobError> {
        let control = Control { limits: self.limits, threads: self.threads, cancel };
        (self.read)(self.prepared.run(&control, progress)?)
    }
}

/// The error for an answer of another job than the one asked (never expected).
pub(crate) fn unexpected(answer: &Answer, asked: &str) -> JobError {
    JobError::Bad(format!("internal error: a {} answer to a {asked} query", answer.name()))
}

/// The bounds of a node run given as solver settings.
pub(crate) fn limits_of(settings: &SolverSettings) -> Limits {
    Limits { max_cells: settings.max_boxes, timeout: settings.timeout, max_memory: settings.max_memory }
}

/// What a singularity run is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularityQuery {
    /// Largest width of certified and undecided boxes (radians), in (0, 1).
    pub precision: f64,
    /// Also search nodes.
    pub nodes: bool,
    /// Stop each search after this many boxes (box pairs for nodes); the run is then incomplete.
    pub max_boxes: u64,
    /// Stop after this long in all; the run is then incomplete.
    pub timeout: Option<Duration>,
    /// Worker threads (the results do not depend on them).
    pub threads: usize,
}

/// A singular point (a cusp), or a box that may hold one.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularPoint {
    /// One interval per joint of `SingularityResult::joint_names` (radians).
    pub joints: Vec<Bounds>,
    /// Its image, one interval per `SingularityResult::workspace_names` coordinate (metres).
    pub workspace: Vec<Bounds>,
    /// True: exactly one cusp is proven in the box. False: the box was left undecided.
    pub certified: bool,
}

/// Two singular points with one image (a node), or a pair of boxes that may hold one.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularPair {
    /// The two joint boxes, each over `SingularityResult::joint_names`.
    pub joints: [Vec<Bounds>; 2],
    /// Their common image, over `SingularityResult::workspace_names`.
    pub workspace: Vec<Bounds>,
    /// True: exactly one pair is proven in the two boxes. False: left undecided.
    pub certified: bool,
}

/// The result of a singularity run.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularityResult {
    /// Robot name.
    pub mechanism: String,
    /// Complete, or which limit stopped a search.
    pub status: Status,
    /// What was asked.
    pub query: SingularityQuery,
    /// The joints the records are over (the singular set does not depend on the others).
    pub joint_names: Vec<String>,
    /// The workspace coordinates of the records' images.
    pub workspace_names: Vec<String>,
    /// Cusps: certified ones first, then undecided boxes of the cusp search.
    pub cusps: Vec<SingularPoint>,
    /// Nodes (empty when not searched): certified ones first, then undecided pairs.
    pub nodes: Vec<SingularPair>,
    /// Boxes covering every singular configuration (where the Jacobian may drop rank).
    pub singular_curves: BoxSetResult,
    /// Boxes covering the configurations that move while the actuated joints are locked.
    pub internal_motions: BoxSetResult,
    /// Boxes processed by all searches.
    pub processed: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// One line: what was found.
    pub summary: String,
    /// The singular sets of a closed-loop mechanism (`None` for 3R chains, whose records are
    /// the cusps, nodes and curves above).
    pub loops: Option<LoopSingularities>,
    /// 3R chains: the verdict of `linkspace singularities --json` (`arm3r::verdict::decide` on
    /// the full-torus run), its reason naming the analysed sub-chain and point when the verdict
    /// does not stand for the arm (`arm3r::select::Scope`); `None` for closed-loop mechanisms.
    pub verdict: Option<crate::analyses::arm3r::verdict::Verdict>,
    /// 3R chains with parallel axes 2 and 3: the certified singular branches, the very
    /// `"singular_branches"` of `linkspace singularities --json` (`arm3r::branches::of`; joints
    /// keyed by the names of `joint_names`, images in `workspace_names`); `None` otherwise.
    pub branches: Option<crate::analyses::arm3r::branches::SingularBranches>,
    /// Six-joint arms whose 3R verdict is a sub-chain's: the whole arm's cuspidality verdict
    /// (`arm_cuspidality`, as `linkspace singularities --json` gives it); `None` otherwise.
    pub arm_cuspidality: Option<ArmVerdictLine>,
}

/// The singular sets of a closed-loop mechanism (`singular`), as `linkspace
/// loop-singularities --json` finds them for the same URDF, fixed joints and settings.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopSingularities {
    /// The actuated joints of the input set.
    pub actuated: Vec<String>,
    /// Where they come from, one line.
    pub actuated_source: String,
    /// One per set searched, in the order cspace, input, output.
    pub sets: Vec<SingularSetResult>,
}

/// One singular set: boxes that together hold every singular configuration of its kind when
/// `boxes.status` is complete and none is undecided.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularSetResult {
    /// `cspace`, `input` or `output`.
    pub kind: &'static str,
    /// The boxes (analysis `singular_set:<kind>`): variables are the configuration then the null
    /// vector, joints the free joints; certified boxes are `Unique`, clusters by configuration.
    pub boxes: BoxSetResult,
    /// Clusters holding a certified box (each holds at least one singular configuration).
    pub proven: usize,
    /// Boxes left undecided by a limit.
    pub undecided: usize,
    /// One line: what was found and what is proven.
    pub summary: String,
}

impl LoopSingularities {
    /// Undecided boxes over every set.
    pub fn undecided(&self) -> usize {
        self.sets.iter().map(|s| s.undecided).sum()
    }

    /// True when every set ran to its end with nothing undecided: every singular configuration
    /// is then in a solution box of some set.
    pub fn complete(&self) -> bool {
        self.sets.iter().all(|s| s.boxes.status.finished() && s.undecided == 0)
    }
}

impl SingularityResult {
    /// The one rule over the searches: a limit, else near-degenerate strips (which travel as
    /// undecided internal-motion boxes), else undecided records.
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        let near = self.internal_motions.boxes.iter().any(|b| b.status == BoxStatus::Undecided);
        crate::kernel::outcome::Completeness::of(self.status, self.undecided(), near)
    }

    /// Undecided records (cusp boxes and node pairs, boxes of a linkage's singular sets).
    pub fn undecided(&self) -> usize {
        self.cusps.iter().filter(|c| !c.certified).count() + self.nodes.iter().filter(|n| !n.certified).count() + self.loops.as_ref().map_or(0, |l| l.undecided())
    }
}

/// What an inverse-kinematics run is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct IkQuery {
    /// The point, in the frame of the URDF's root link (metres).
    pub point: [f64; 3],
    /// Largest width of the returned boxes (radians), in (0, 1).
    pub precision: f64,
    /// Stop after this many boxes; the run is then incomplete.
    pub max_boxes: u64,
    /// Stop after this long (wall clock); the run is then incomplete.
    pub timeout: Option<std::time::Duration>,
    /// Worker threads (the results do not depend on them).
    pub threads: usize,
}

/// One inverse-kinematics solution box.
#[derive(Clone, Debug, PartialEq)]
pub struct IkSolution {
    /// One interval per joint of `IkResult::joint_names` (radians).
    pub joints: Vec<Bounds>,
    /// True: exactly one solution in the box. False: a cluster of undecided boxes that may
    /// hold one solution, several (near a singularity), or a line of them (an internal motion).
    pub unique: bool,
    /// Undecided boxes merged into this one (0 for unique ones).
    pub boxes: usize,
}

/// The result of an inverse-kinematics run.
#[derive(Clone, Debug, PartialEq)]
pub struct IkResult {
    /// Robot name.
    pub mechanism: String,
    /// Every joint of the chain, base first.
    pub joint_names: Vec<String>,
    /// What the point is for the analysis (e.g. its distance from the first axis and its
    /// height along it), with `point_values` enclosing each.
    pub point_names: Vec<String>,
    /// Enclosures of the point's coordinates named by `point_names`.
    pub point_values: Vec<Bounds>,
    /// Unique solutions first, then clusters.
    pub solutions: Vec<IkSolution>,
    /// Complete, or the limit that stopped the run (boxes, cancelled, ...).
    pub status: Status,
    /// Boxes processed.
    pub processed: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_box(joints: Vec<Bounds>, cluster: usize) -> ResultBox {
        ResultBox { status: BoxStatus::Solution, bounds: joints.clone(), joints, level: 0, cluster: Some(cluster), traces: vec![] }
    }

    fn result(boxes: Vec<ResultBox>, clusters: usize) -> BoxSetResult {
        BoxSetResult {
            mechanism: "m".into(),
            analysis: "configuration_space".into(),
            status: Status::Finished,
            settings: SolverSettings { sigma: 0.1, ..Default::default() },
            variables: vec!["a".into(), "b".into()],
            primaries: vec![0, 1],
            joint_names: vec!["a".into(), "b".into()],
            fixed_joints: vec![("f".into(), 1.0)],
            traces: vec![],
            boxes,
            clusters,
            stats: Stats::default(),
        }
    }

    #[test]
    fn angles_are_compared_modulo_two_pi() {
        assert_eq!(gap(0.5, [0.0, 1.0], true), 0.0);
        // -3.1 + 2π = 3.183 lies in [3.1, 3.2]; -3.0 + 2π = 3.283 lies 0.083 above it.
        assert_eq!(gap(-3.1, [3.1, 3.2], true), 0.0);
        assert!((gap(-3.0, [3.1, 3.2], true) - (std::f64::consts::TAU - 6.2)).abs() < 1e-12);
        assert!((gap(-3.0, [3.1, 3.2], false) - 6.1).abs() < 1e-12);
        assert!((gap(2.0 + std::f64::consts::TAU * 3.0, [0.0, 1.0], true) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn classification_names_the_nearest_component() {
        let r = result(vec![one_box(vec![[0.0, 0.1], [0.0, 0.1]], 0), one_box(vec![[2.0, 2.1], [2.0, 2.1]], 1)], 2);
        let c = classify(&r, &[2.05, 2.05], &[true, true], None);
        assert!(c.inside);
        assert_eq!((c.component, c.components, c.distance), (Some(1), 2, 0.0));
        let c = classify(&r, &[0.4, 0.1], &[true, true], Some(&r));
        assert!(!c.inside);
        assert_eq!(c.component, Some(0));
        assert!((c.distance - 0.3).abs() < 1e-12);
        assert!((c.singular_distance.expect("given") - 0.3).abs() < 1e-12);
    }

    #[test]
    fn only_narrow_clusters_are_assembly_modes() {
        let r = result(vec![one_box(vec![[0.0, 0.1], [0.0, 0.1]], 0), one_box(vec![[1.0, 1.1], [1.0, 1.1]], 1), one_box(vec![[1.1, 1.2], [1.0, 1.1]], 1)], 2);
        let modes = r.assembly_modes();
        // Cluster 1 spans 0.2 in `a`, within 4 sigma = 0.4: both clusters are isolated.
        assert_eq!(modes.len(), 2);
        assert_eq!(modes[1].joints[0], ("a".to_string(), 1.1));
        assert_eq!(modes[1].joints[2], ("f".to_string(), 1.0));
        let wide = result(vec![one_box(vec![[0.0, 0.1], [0.0, 0.1]], 0), one_box(vec![[0.1, 0.5], [0.0, 0.1]], 0)], 1);
        assert!(wide.assembly_modes().is_empty());
    }
}

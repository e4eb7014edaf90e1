//! A configuration-space run of a closed-loop linkage (`SolveRun`): the problem built by the
//! builder the model names, its settings validated, and its run, whose pose-model answers are
//! settled to one certified box per assembly where that can be proven.

use super::{AnalysisError, BoxSetResult, ResultBox, TracedBounds};
use crate::formulate::choice::TracedPoint;
use crate::formulate::singular::Coordinates;
use crate::formulate::{Linkage, ModelChoice};
use crate::kernel::interval::{bounds, IntervalBox};
use crate::kernel::search::{components_shared, map_shared, BoxStatus, Enclosure, Limit, Progress, RefinePlan, Refinement, Solver, SolverSettings, Status, Wire};
use crate::kernel::system::VarRole;
use crate::model::Mechanism;
use crate::formulate::spatial::LinkPose;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A configuration-space run of a closed-loop linkage, built and validated: `linkspace solve`
/// and the node's `configuration_space` and `solve` all run one.
#[derive(Clone, Debug)]
pub struct SolveRun {
    problem: Linkage,
    settings: SolverSettings,
}

impl SolveRun {
    /// Validates `settings` for `problem`, so that a bad request is answered before any run.
    pub fn new(problem: Linkage, settings: SolverSettings) -> Result<Self, crate::kernel::search::SolveError> {
        problem.solver(settings.clone())?;
        Ok(Self { problem, settings })
    }

    /// Builds `mechanism` with `model` (planar, spatial, or auto: planar when the planar builder
    /// takes it), the `fixed` joint values and the `traces` to follow, and validates `settings`.
    pub fn build(mechanism: &Mechanism, model: ModelChoice, fixed: &[(String, f64)], traces: &[TracedPoint], settings: SolverSettings) -> Result<Self, AnalysisError> {
        let problem = Linkage::build(mechanism, model, fixed, traces)?;
        Ok(Self::new(problem, settings)?)
    }

    /// The model's degrees of freedom, counted and measured at a configuration Newton finds
    /// (`system::freedom`), with its one-line description: what the run will cover.
    pub fn freedom(&self) -> (crate::kernel::system::Freedom, String) {
        let f = crate::kernel::system::freedom(self.problem.system(), 12, 1);
        (f, describe_freedom(&f, self.settings.sigma))
    }

    /// The built problem.
    pub fn problem(&self) -> &Linkage {
        &self.problem
    }

    /// The settings it runs with.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// The same run with other settings of the same resolution (a front end's limits).
    pub(crate) fn within(self, settings: SolverSettings) -> Self {
        Self { settings, ..self }
    }

    /// Encloses every configuration, within the settings' limits or until `cancel` is raised:
    /// the box set of analysis `solve`, solution boxes first (in the order found), then the
    /// undecided ones, each with its joint values and traced points.
    ///
    /// The timeout covers the whole call: the searches (the main one, the spurious-box check,
    /// the pose model's refinements) take `SEARCH_SHARE` of it, and reading the boxes' joint
    /// values out the rest. Boxes the deadline (or a cancel) leaves unread keep their bounds
    /// and status with joints `[NaN, NaN]`; the run then says which limit stopped it.
    pub fn run(&self, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> BoxSetResult {
        self.run_reading(cancel, progress, None).0
    }

    /// `run`, each box also read out in its links' terms within the same deadline when
    /// `rigid_links` is given (`Mechanism::rigid_links`: those links are not read): the links'
    /// orientations (planar model) or poses (spatial and pose models), one per box in
    /// `BoxSetResult::boxes` order, `LinkReadout::Unread` for a box left unread.
    pub fn run_reading(&self, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress), rigid_links: Option<&BTreeMap<String, String>>) -> (BoxSetResult, Vec<LinkReadout>) {
        let t0 = Instant::now();
        let deadline = self.settings.timeout.map(|t| t0 + t);
        let searches_end = self.settings.timeout.map(|t| t0 + t.mul_f64(SEARCH_SHARE));
        let solver = self.problem.solver(self.settings.clone()).expect("invariant: validated when built").until(searches_end);
        let e = solver.enclose(cancel, progress);
        let e = match &self.problem {
            Linkage::Pose(..) | Linkage::Distances(..) => settle_pose(&solver, e, self.settings.threads, cancel, searches_end.map(|d| d.saturating_duration_since(Instant::now()))),
            _ => e,
        };
        let threads = self.settings.threads;
        let (labels, clusters) = components_shared(&e.solutions, threads);
        let problem = &self.problem;
        let joint_names = problem.free_joints().to_vec();
        // Asked before each box: reading one out is cheap, reading a million is not.
        let stopped = || if cancel.load(Ordering::Relaxed) { Some(Limit::Cancelled) } else { deadline.filter(|&d| Instant::now() >= d).map(|_| Limit::Time) };
        let all: Vec<&IntervalBox> = e.solutions.iter().chain(&e.undecided).collect();
        // Every process reads its share of the boxes out, on its threads.
        let readings = map_shared(&all, threads, |&b| match stopped() {
            Some(limit) => Reading::Unread(limit),
            None => {
                let values = problem.joint_values(b);
                let joints = joint_names.iter().map(|n| values.get(n).map_or([f64::NAN, f64::NAN], |&(lo, hi)| [lo, hi])).collect();
                Reading::Read(joints, rigid_links.map(|rigid| read_links(problem, b, rigid)))
            }
        });
        let unread = readings.iter().find_map(|r| match r {
            Reading::Unread(limit) => Some(*limit),
            Reading::Read(..) => None,
        });
        let statuses = e.tags.iter().copied().zip(labels.iter().map(|&l| Some(l))).chain(e.undecided.iter().map(|_| (BoxStatus::Undecided, None)));
        let mut links = Vec::new();
        let boxes: Vec<ResultBox> = all
            .iter()
            .zip(statuses)
            .zip(readings)
            .map(|((b, (status, cluster)), reading)| {
                let joints = match reading {
                    Reading::Read(joints, read) => {
                        links.extend(read);
                        joints
                    }
                    Reading::Unread(_) => {
                        if rigid_links.is_some() {
                            links.push(LinkReadout::Unread);
                        }
                        vec![[f64::NAN, f64::NAN]; joint_names.len()]
                    }
                };
                ResultBox { status, bounds: b.dims.iter().map(|&x| bounds(x)).collect(), joints, level: b.level, cluster, traces: traced(problem, b) }
            })
            .collect();
        let mut stats = e.stats;
        stats.post_processing_cut_short |= unread.is_some();
        // Every box is still enclosed; what is missing is named by the limit that stopped it.
        let status = match (e.status, unread) {
            (Status::Finished, Some(limit)) => Status::Stopped(limit),
            (s, _) => s,
        };
        let system = problem.system();
        let result = BoxSetResult {
            mechanism: problem.name().to_string(),
            analysis: "solve".to_string(),
            status,
            settings: self.settings.clone(),
            variables: system.vars.iter().map(|v| v.name.clone()).collect(),
            primaries: system.vars.iter().enumerate().filter(|(_, v)| v.role == VarRole::Primary).map(|(i, _)| i).collect(),
            joint_names: joint_names.clone(),
            fixed_joints: problem.fixed_joints().to_vec(),
            traces: problem.trace_names(),
            boxes,
            clusters,
            stats,
        };
        (result, links)
    }
}

/// One box read out: its joints' values (in `free_joints` order) and, when asked, its links;
/// or left unread by the limit that came first.
enum Reading {
    Read(Vec<[f64; 2]>, Option<LinkReadout>),
    Unread(Limit),
}

impl Wire for Reading {
    fn put(&self, out: &mut Vec<u8>) {
        match self {
            Reading::Read(joints, links) => {
                0u8.put(out);
                joints.put(out);
                links.put(out);
            }
            Reading::Unread(limit) => {
                1u8.put(out);
                limit.put(out);
            }
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        match u8::take(input) {
            0 => Reading::Read(Wire::take(input), Wire::take(input)),
            _ => Reading::Unread(Wire::take(input)),
        }
    }
}

impl Wire for LinkReadout {
    fn put(&self, out: &mut Vec<u8>) {
        match self {
            LinkReadout::Angles(angles) => {
                0u8.put(out);
                angles.put(out);
            }
            LinkReadout::Poses(poses) => {
                1u8.put(out);
                poses.put(out);
            }
            LinkReadout::Unread => 2u8.put(out),
        }
    }
    fn take(input: &mut &[u8]) -> Self {
        match u8::take(input) {
            0 => LinkReadout::Angles(Wire::take(input)),
            1 => LinkReadout::Poses(Wire::take(input)),
            _ => LinkReadout::Unread,
        }
    }
}

impl Wire for LinkPose {
    fn put(&self, out: &mut Vec<u8>) {
        self.position.put(out);
        self.quaternion.put(out);
        self.rotation_width.put(out);
    }
    fn take(input: &mut &[u8]) -> Self {
        LinkPose { position: Wire::take(input), quaternion: Wire::take(input), rotation_width: Wire::take(input) }
    }
}

/// What a box says of the mechanism's links, in the model's terms.
#[derive(Clone, Debug)]
pub enum LinkReadout {
    /// Planar model: each link's world-frame orientation (radians).
    Angles(BTreeMap<String, (f64, f64)>),
    /// Spatial and pose models: each link's (the platform's) pose in the root frame.
    Poses(BTreeMap<String, LinkPose>),
    /// Not read: the run's deadline (or a cancel) came first.
    Unread,
}

/// The links of `b` that move on their own (not in `rigid`), read out.
fn read_links(problem: &Linkage, b: &IntervalBox, rigid: &BTreeMap<String, String>) -> LinkReadout {
    let moves = |name: &str| !rigid.contains_key(name);
    match problem {
        Linkage::Planar(p) => LinkReadout::Angles(p.link_angles_of(b, moves)),
        Linkage::Spatial(p, _) => LinkReadout::Poses(p.link_poses_of(b, moves)),
        Linkage::Pose(p, _) => LinkReadout::Poses(BTreeMap::from([(p.platform.clone(), p.link_pose(b))])),
        Linkage::Distances(p, _) => LinkReadout::Poses(BTreeMap::from([(p.platform.clone(), p.link_pose(b))])),
    }
}

/// The share of a run's timeout its searches take; the rest is for reading the boxes out. The
/// read-outs are an enclosure of each joint's (and link's) angle per box, a microsecond or two
/// each: a tenth of the time covers most of those of the box sets a search makes in the other
/// nine tenths (a curve at sigma 1e-12, 26,000 boxes in 3 s; 300 boxes of 600 joints each).
const SEARCH_SHARE: f64 = 0.9;

/// The pose model's refinement: `RefinePlan::default()`'s rounds and cells, on clusters up to 64
/// sigmas wide. An assembly near a singularity of the leg Jacobian leaves uncertified boxes along
/// its near-null direction, the farther the nearer it is (22 to 31 sigmas at sigma 1e-3 for
/// smallest singular values of 4e-5 to 1.3e-4, README); a cluster of a curve of poses (an
/// architecturally singular platform) spends the rounds' cells and stays as found.
fn pose_refine_plan() -> RefinePlan {
    RefinePlan { max_width: 64.0, ..RefinePlan::default() }
}

/// The pose model's answer, one certified box per assembly where it can be proven: each
/// cluster holding an uncertified box (two assemblies close together, say) is searched again at
/// finer sigmas (`Solver::refine`) and replaced when every box of a completed round is
/// certified (the round's start box holds the whole cluster, so no root of it is lost; a round
/// with no box proves the cluster empty); then certified boxes sharing one root are merged
/// (`Solver::merge_shared_certificates`). What cannot be settled is reported as found.
/// `timeout`: what is left of the run's.
fn settle_pose(solver: &Solver<'_>, mut e: Enclosure, threads: usize, cancel: &AtomicBool, timeout: Option<Duration>) -> Enclosure {
    let t0 = Instant::now();
    let (labels, n) = components_shared(&e.solutions, threads);
    let mut solutions = Vec::new();
    let mut tags = Vec::new();
    for k in 0..n {
        let members: Vec<usize> = (0..e.solutions.len()).filter(|&i| labels[i] == k).collect();
        let boxes: Vec<IntervalBox> = members.iter().map(|&i| e.solutions[i].clone()).collect();
        if members.iter().any(|&i| e.tags[i] != BoxStatus::Unique) {
            let left = timeout.map(|t| t.saturating_sub(t0.elapsed()));
            let all_certified = |_: &[IntervalBox], t: &[BoxStatus]| t.iter().all(|&x| x == BoxStatus::Unique);
            if let Refinement::Settled(found) = solver.refine(&boxes, &pose_refine_plan(), left, &all_certified, cancel) {
                solutions.extend(found.solutions);
                tags.extend(found.tags);
                continue;
            }
        }
        solutions.extend(boxes);
        tags.extend(members.iter().map(|&i| e.tags[i]));
    }
    // Refined clusters may hold boxes that share a certificate with their neighbours.
    let (solutions, tags, merged) = solver.merge_shared_certificates(solutions, tags);
    e.stats.certificates_merged += merged;
    e.stats.solutions = solutions.len() as u64;
    e.stats.certified = tags.iter().filter(|&&t| t == BoxStatus::Unique).count() as u64;
    e.solutions = solutions;
    e.tags = tags;
    e
}

/// World coordinates of the problem's traced points over a box, in `trace_names` order.
fn traced(problem: &Linkage, b: &IntervalBox) -> Vec<TracedBounds> {
    match problem {
        Linkage::Planar(p) => p.traces.iter().map(|t| TracedBounds { x: bounds(b.dims[t.x]), y: bounds(b.dims[t.y]), z: None }).collect(),
        Linkage::Pose(..) | Linkage::Distances(..) => Vec::new(),
        Linkage::Spatial(p, _) => p
            .traces
            .iter()
            .map(|t| {
                let [x, y, z] = t.xyz.map(|v| bounds(b.dims[v]));
                TracedBounds { x, y, z: Some(z) }
            })
            .collect(),
    }
}

/// `freedom`'s line: the degrees of freedom of the model and what they mean for the run.
pub fn describe_freedom(f: &crate::kernel::system::Freedom, sigma: f64) -> String {
    let counted = format!("{} unknowns, {} rows", f.unknowns, f.rows);
    match f.at_point {
        Some(l) if l.dof == 0 && l.nearly_singular => format!("0 degrees of freedom ({counted}; the Jacobian is nearly singular at a configuration Newton found, but the configurations do not go on along its near-null direction): isolated assemblies, some close together"),
        Some(l) if l.dof == 0 => format!("0 degrees of freedom ({counted}; the Jacobian has full rank at a configuration Newton found): isolated assemblies"),
        Some(l) if l.dof == 1 && f.counted() <= 0 => format!(
            "1 degree of freedom at a configuration Newton found ({counted}, rank {}): a curve where the count expects isolated assemblies (an overconstrained linkage that moves, an architecturally singular one, or a singular configuration); boxes on it are not certified",
            l.rank
        ),
        Some(l) if l.dof == 1 => format!("1 degree of freedom ({counted}, rank {} at a configuration Newton found): a curve of configurations", l.rank),
        Some(l) => format!(
            "{} degrees of freedom at a configuration Newton found ({counted}, rank {}): a {}-dimensional continuum, whose cover at sigma {sigma:e} takes on the order of {:.0e} boxes; fix {} joints (--fix) for isolated assemblies, or raise --sigma",
            l.dof,
            l.rank,
            l.dof,
            sigma.powi(-(l.dof.min(30) as i32)),
            l.dof
        ),
        None => format!("{} by count ({counted}); no configuration found by Newton to measure it", f.counted()),
    }
}

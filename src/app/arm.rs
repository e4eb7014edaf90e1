//! Serial arms: the 3R positioning structure of a robot description, and the jobs run on it
//! (singularities with the cuspidality verdict, inverse kinematics, collision sets).
//!
//! An `Arm` is read once (`arm3r::prepare`: rounding policy, chain and point, joint limits);
//! each job takes it with the front end's `Control` and returns what happened as values. The
//! CLI prints and writes the JSON reports (`report::manip3r`) from these results; the ROS node
//! converts the same results into its messages.

use crate::analyses::arm3r::{
    self,
    branches::{Attribution, SingularBranches},
    collision::{self, CollisionSet, CollisionSettings, Scene},
    frame::{BaseFrame, Target},
    ik::IkSolutions,
    limits::LimitEffect,
    verdict::{self, Verdict},
    Chain3R, LoadOptions, Manip3rError, Prepared, Singularities,
};
use crate::analyses::arm6r::Chain6R;
use crate::model::Mechanism;
use crate::kernel::search::{Control, Progress};
use inari::Interval;
use std::time::Instant;

use super::{
    gap, Analysis, AnalysisError, MechanismKind, BoxSetResult, Classification, IkQuery, IkResult, IkSolution, PreparedRun, ResultBox, Service, SingularPair, SingularPoint,
    SingularityQuery, SingularityResult,
};
use crate::kernel::interval::bounds;
use crate::analyses::arm3r::{curves::Cover, motion, records::radius};
use crate::kernel::search::{BoxStatus, Limit, Limits, SolveStats as Stats, SolverSettings, Status};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// A serial arm as the 3R analyses read it.
#[derive(Clone, Debug)]
pub struct Arm {
    /// The reduced serial mechanism, what was chosen and changed, and the joint limits.
    pub prepared: Prepared,
    /// The half-section map of the positioning structure.
    pub chain: Chain3R,
    /// Where the chain sits in the robot's root frame.
    pub frame: BaseFrame,
    /// The certified singular branches of an arm whose axes 2 and 3 are parallel.
    pub branches: Option<SingularBranches>,
}

impl Arm {
    /// Reads the arm of `mechanism` as `options` say, every length widened by `uncertainty`
    /// metres (0 for the nominal geometry).
    pub fn load(mechanism: &Mechanism, options: &LoadOptions, uncertainty: f64) -> Result<Self, Manip3rError> {
        let prepared = arm3r::prepare(mechanism, options)?;
        // The chain names its point by the reduced mechanism's link, made up for a joint's origin.
        let chain = Chain3R::from_mechanism(&prepared.mechanism, uncertainty).map_err(|e| match (e, prepared.choice.origin_text()) {
            (Manip3rError::TipDoesNotMove(_), Some(point)) => Manip3rError::TipDoesNotMove(point),
            (Manip3rError::Degenerate(_), Some(point)) => Manip3rError::Degenerate(point),
            (e, _) => e,
        })?;
        let frame = BaseFrame::of(&prepared.mechanism, &chain);
        let branches = arm3r::branches::of(&prepared.mechanism, &chain);
        Ok(Self { prepared, chain, frame, branches })
    }
}

/// What a singularity run is asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingularitiesRequest {
    /// Largest width (radians) of reported and undecided boxes, in (0, 1).
    pub precision: f64,
    /// Also search nodes (pairs of singular points with one image).
    pub nodes: bool,
    /// Run the interval searches even where the verdict is structural (axes 2 and 3 parallel),
    /// where they cannot complete.
    pub search_anyway: bool,
    /// Decide the cuspidality verdict (with its aspects and IK counts) after the searches;
    /// false for the searches alone.
    pub verdict: bool,
}

/// Cusps, nodes, internal motions and the verdict of one arm.
#[derive(Clone, Debug)]
pub struct ArmSingularities {
    /// What was asked.
    pub request: SingularitiesRequest,
    /// The searches' results inside the joint limits (the verdict reads the full torus).
    pub run: Singularities,
    /// The first answer: cuspidal or not, with its argument (`None` when not asked).
    pub verdict: Option<Verdict>,
    /// What the joint limits removed.
    pub limit_effect: LimitEffect,
    /// Axes 2 and 3 parallel, nominal geometry, searches not forced: the cusp answer comes from
    /// the verdict's proof and the interval searches were not run.
    pub structural: bool,
    /// Whether the node search ran (it is not run where the singular branches are curves of
    /// nodes).
    pub nodes_searched: bool,
    /// Where the cusp search's undecided boxes lie relative to the singular branches.
    pub explained: Option<Attribution>,
    /// Searches not run, and why.
    pub not_searched: Option<String>,
    /// Wall-clock seconds of the searches and the verdict.
    pub seconds: f64,
}

/// Cusps, then nodes, then the verdict, within one `control` (one deadline for all).
pub fn singularities(arm: &Arm, request: &SingularitiesRequest, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmSingularities, Manip3rError> {
    arm3r::check_precision(request.precision)?;
    let (chain, mechanism) = (&arm.chain, &arm.prepared.mechanism);
    let structural = chain.uncertainty == 0.0 && !request.search_anyway && verdict::parallel_structure(mechanism).is_some();
    // On arms with known singular branches whole branches are curves of nodes: the isolated-node
    // search floods, so it is not run even when the searches are forced.
    let nodes_searched = request.nodes && arm.branches.is_none();
    let start = Instant::now();
    let mut run = if structural {
        arm3r::structural_singularities(chain, request.precision)?
    } else {
        arm3r::singularities(chain, request.precision, nodes_searched, control, progress)?
    };
    // The verdict reads the full-torus run; the limits then filter what is listed.
    let verdict = request.verdict.then(|| {
        let mut verdict = verdict::decide(mechanism, chain, &run, &arm.prepared.limits, &control.remaining_since(start));
        // An undecided verdict says what blocks it (not for uncertain lengths, nor for certified
        // cusps outside the limits: those reasons say what to do).
        if verdict.cuspidal.is_none() && chain.uncertainty == 0.0 && !run.cusps.cusps.iter().any(|c| c.unique) {
            verdict.reason.push_str(&verdict::blockers(&arm.prepared, chain, request.precision, &control.remaining_since(start)));
        }
        verdict
    });
    let limit_effect = arm.prepared.limits.apply(&mut run);
    let mut explained = None;
    let mut not_searched = None;
    if let Some(b) = &arm.branches {
        if !structural {
            let boxes: Vec<[Interval; 2]> = run.cusps.undecided.iter().map(|u| u.theta).chain(run.cusps.cusps.iter().filter(|c| !c.unique).map(|c| c.theta)).collect();
            if !boxes.is_empty() {
                explained = Some(b.attribute(mechanism, &boxes, 1e-2));
            }
            if request.nodes {
                not_searched = Some("nodes not enumerated: the singular branches are curves of nodes (see the singular branches), which the isolated-node search does not model".to_string());
            }
        }
    }
    if structural {
        not_searched = Some(format!(
            "axes 2 and 3 are parallel: no cusp point, by the verdict's proof; {} (--search-anyway runs the interval searches, which cannot complete here)",
            if request.nodes { "nodes not enumerated: the singular branches cross and map onto shared curves (curves of nodes), which the isolated-node search does not model" } else { "nodes not asked" }
        ));
    }
    Ok(ArmSingularities { request: *request, run, verdict, limit_effect, structural, nodes_searched, explained, not_searched, seconds: start.elapsed().as_secs_f64() })
}

/// A point asked of inverse kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkPoint {
    /// A point of the robot's root frame (metres): every joint of the chain is solved for.
    Root([f64; 3]),
    /// Half-section coordinates in the first joint's frame: distance from the first axis and
    /// height along it (metres). The first joint is free (any angle turns the point about the
    /// axis), so only joints 2 and 3 are solved for.
    HalfSection {
        /// Distance from the first axis.
        radius: f64,
        /// Height along the first axis.
        z: f64,
    },
}

/// Every solution of one inverse-kinematics query.
#[derive(Clone, Debug)]
pub struct ArmIk {
    /// The point asked.
    pub point: IkPoint,
    /// The point as the search took it (`None` for a half-section point, taken exactly).
    pub target: Option<Target>,
    /// Solutions over (θ₂, θ₃) inside the joint limits: unique boxes, then clusters.
    pub solutions: IkSolutions,
    /// What the joint limits removed.
    pub limit_effect: LimitEffect,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Every joint solution of `arm` reaching `point`, within `control`.
pub fn inverse_kinematics(arm: &Arm, point: IkPoint, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmIk, Manip3rError> {
    let start = Instant::now();
    let (mut solutions, target): (_, Option<Target>) = match point {
        IkPoint::HalfSection { radius, z } => (arm3r::ik::solve_with(&arm.chain, radius, z, precision, control, progress)?, None),
        IkPoint::Root(p) => {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(Manip3rError::BadTarget(p));
            }
            let target = arm.frame.target(p);
            (arm3r::ik::solve_target(&arm.chain, target.half_section, precision, control, progress)?, Some(target))
        }
    };
    // Solutions outside the file's joint limits are not solutions of the arm; those on a limit
    // are kept.
    let limit_effect = arm.prepared.limits.apply_ik(&mut solutions, |b| target.map(|t| arm.frame.theta1(&arm.chain, &t, b)));
    Ok(ArmIk { point, target, solutions, limit_effect, seconds: start.elapsed().as_secs_f64() })
}

impl ArmSingularities {
    /// Lines of internal motions the cusp search found.
    pub fn internal_motion_lines(&self) -> usize {
        arm3r::line_count(&self.run.cusps.bands)
    }

    /// The one rule over the searches: the limit that stopped one, else near-degenerate strips,
    /// else undecided boxes and pairs (cusps without a uniqueness proof among them).
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        let (cusps, nodes) = (&self.run.cusps, self.run.nodes.as_ref());
        let status = nodes.map_or(cusps.status, |n| cusps.status.and(n.status));
        let undecided = cusps.undecided.len() + cusps.cusps.iter().filter(|c| !c.unique).count() + nodes.map_or(0, |n| n.undecided.len());
        let near = cusps.bands.iter().any(|b| b.near.is_some());
        crate::kernel::outcome::Completeness::of(status, undecided, near)
    }
}

impl ArmIk {
    /// The first joint's angle for a solution box over (θ₂, θ₃), in the joint's range: `None`
    /// for a half-section point (θ₁ is free), the whole turn where the point or the end point
    /// may lie on the first axis.
    pub fn theta1(&self, arm: &Arm, b: &[Interval; 2]) -> Option<Interval> {
        self.target.map(|t| arm.prepared.limits.in_range(0, arm.frame.theta1(&arm.chain, &t, b)))
    }
}

/// Where the collision capsules of an arm meet, over (θ₂, θ₃).
#[derive(Clone, Debug)]
pub struct ArmCollisions {
    /// The reduced arm, as read.
    pub prepared: Prepared,
    /// Its capsules and the pairs checked.
    pub scene: Scene,
    /// Colliding, free and undecided boxes.
    pub set: CollisionSet,
}

/// The collision set of the arm of `mechanism` (read as `options` say), within `control`.
///
/// Takes the mechanism rather than an `Arm`: collisions need the capsules of the chosen chain,
/// not its half-section map, which may be degenerate where collisions are still well defined.
pub fn collisions(mechanism: &Mechanism, options: &LoadOptions, precision: f64, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<ArmCollisions, Manip3rError> {
    arm3r::check_precision(precision)?;
    let prepared = arm3r::prepare(mechanism, options)?;
    let scene = Scene::from_mechanism(&prepared.mechanism)?;
    let set = collision::classify_with(&scene, &CollisionSettings { precision }, control, progress)?;
    Ok(ArmCollisions { prepared, scene, set })
}

// The ROS node's analysis of an arm: the jobs above, plus a cover of the singular curves and
// the classification of configurations against it.

/// Bisections per axis of the singular-curve cover: 256 × 256 cells of about 0.025 rad, the
/// grid of the README's charts. Fine enough to show the curves and to separate the regions
/// between them, coarse enough for a message of a few thousand boxes.
pub const CURVE_DEPTH: u32 = 8;

/// A serial arm as the node loads it: its 3R positioning structure, read as `linkspace
/// singularities` reads a file with no options.
///
/// An open chain reaches every joint configuration, so there is no configuration space to
/// solve; the default `configuration_space` and `solve` answer "not available".
#[derive(Clone, Debug)]
pub struct Manip3rAnalysis {
    arm: Arc<Arm>,
    /// The six revolute joints of the whole arm, when it has exactly six.
    six: Option<Arc<Chain6R>>,
    /// Values of the six-joint chain the rounding policy changed (the whole-arm proof is about
    /// the geometry after them).
    six_snapped: usize,
    /// Cover of the singular curves, computed once (it does not depend on any request).
    cover: Arc<Cover>,
}

impl Manip3rAnalysis {
    /// Reads the arm (nominal geometry); errors when the mechanism holds no 3R positioning
    /// structure or its map is degenerate.
    pub fn new(mechanism: &Mechanism) -> Result<Self, Manip3rError> {
        let arm = Arm::load(mechanism, &LoadOptions::default(), 0.0)?;
        let cover = Arc::new(Cover::new(&arm.chain, CURVE_DEPTH, &Control::with_limits(Limits::default())));
        let (six, six_snapped) = match super::six::chain6_snapped(mechanism, &LoadOptions::default()) {
            Ok((chain, snapped)) => (Some(Arc::new(chain)), snapped),
            Err(_) => (None, 0),
        };
        Ok(Self { arm: Arc::new(arm), six, six_snapped, cover })
    }

    /// The chain's name tokens for records over (θ₂, θ₃).
    fn record_joints(&self) -> Vec<String> {
        vec![self.arm.chain.joints[1].clone(), self.arm.chain.joints[2].clone()]
    }
}

impl Analysis for Manip3rAnalysis {
    fn mechanism(&self) -> &str {
        &self.arm.chain.name
    }

    fn kind(&self) -> MechanismKind {
        MechanismKind::Manipulator3R
    }

    fn services(&self) -> Vec<Service> {
        // Every arm read as a 3R positioning structure has a path check (its 3R set); a
        // six-revolute one answers the 6R questions too.
        let mut services = vec![Service::Singularities, Service::InverseKinematics, Service::Classify, Service::PathCheck];
        if self.six.is_some() {
            services.insert(3, Service::InverseKinematics6);
        }
        services
    }

    fn limitation(&self) -> String {
        "a 3R manipulator: an open chain reaches every joint configuration, so there is no configuration space to solve (singularities, inverse_kinematics and classify are answered)".to_string()
    }

    fn free_joints(&self) -> Vec<String> {
        self.arm.chain.joints.to_vec()
    }

    fn fixed_joints(&self) -> Vec<(String, f64)> {
        Vec::new()
    }

    fn periodic(&self) -> Vec<bool> {
        vec![true; 3]
    }

    fn singularities(&self, query: &SingularityQuery) -> Result<Box<dyn PreparedRun<SingularityResult>>, AnalysisError> {
        arm3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()));
        }
        Ok(Box::new(SingularityRun { arm: self.arm.clone(), six: self.six.clone(), six_snapped: self.six_snapped, cover: self.cover.clone(), query: query.clone(), joints: self.record_joints() }))
    }

    fn inverse_kinematics(&self, query: &IkQuery) -> Result<Box<dyn PreparedRun<IkResult>>, AnalysisError> {
        if query.point.iter().any(|v| !v.is_finite()) {
            return Err(AnalysisError::BadRequest(Manip3rError::BadTarget(query.point).to_string()));
        }
        arm3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()));
        }
        Ok(Box::new(IkRun { arm: self.arm.clone(), query: query.clone() }))
    }

    fn classify(&self, values: &[f64], _cspace: Option<&BoxSetResult>, _singular: Option<&SingularityResult>) -> Result<Classification, AnalysisError> {
        let c = &self.cover;
        let (t2, t3) = (values[1], values[2]);
        let distance = c.boxes.iter().map(|&(i, j)| (gap(t2, c.bounds(i), true).powi(2) + gap(t3, c.bounds(j), true).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
        let region = c.cell_of(t2, t3).map(|(i, j)| c.region[i * c.n + j]).filter(|&r| r >= 0);
        let note = match region {
            Some(r) => format!(
                "an open 3R chain: every configuration is reachable. Component {r} of {} is a connected region of cells proven free of singularities (det Df keeps one sign there), so it lies in one aspect; two regions may still belong to one aspect. The singular distance is a lower bound on the distance in (θ2, θ3) to the singular set, which lies in the {} boxes of the {CURVE_DEPTH}-level cover",
                c.regions,
                c.boxes.len()
            ),
            None => "an open 3R chain: every configuration is reachable. This one lies in a box of the singular-curve cover (det Df may vanish there), so it belongs to no proven region (component -1); the singular distance is 0".to_string(),
        };
        Ok(Classification {
            inside: true,
            component: region.map(|r| r as usize),
            components: c.regions,
            distance: 0.0,
            singular_distance: Some(if region.is_some() { distance } else { 0.0 }),
            note,
        })
    }
}

/// The cover as a box set over (θ₂, θ₃).
fn box_set(cover: &Cover, mechanism: &str, joints: &[String]) -> BoxSetResult {
    let boxes = cover
        .boxes
        .iter()
        .zip(&cover.cluster)
        .map(|(&(i, j), &c)| {
            let b = vec![cover.bounds(i), cover.bounds(j)];
            ResultBox { status: BoxStatus::Solution, bounds: b.clone(), joints: b, level: 2 * CURVE_DEPTH, cluster: Some(c), traces: vec![] }
        })
        .collect();
    let width = cover.line(1) - cover.line(0);
    BoxSetResult {
        mechanism: mechanism.to_string(),
        analysis: "singular_curves".into(),
        status: Status::Finished,
        settings: SolverSettings { sigma: width, max_boxes: cover.stats.processed, timeout: None, ..Default::default() },
        variables: joints.to_vec(),
        primaries: vec![0, 1],
        joint_names: joints.to_vec(),
        fixed_joints: vec![],
        traces: vec![],
        boxes,
        clusters: cover.clusters,
        stats: Stats { processed: cover.stats.processed, solutions: cover.boxes.len() as u64, max_level: 2 * CURVE_DEPTH, seconds: cover.seconds, ..Default::default() },
    }
}

/// Seconds of the whole-arm cuspidality search in a singularity run (the CLI's default
/// `--arm-budget`).
const WHOLE_ARM_BUDGET: std::time::Duration = std::time::Duration::from_secs(2);

/// A validated singularity run.
struct SingularityRun {
    arm: Arc<Arm>,
    six: Option<Arc<Chain6R>>,
    six_snapped: usize,
    cover: Arc<Cover>,
    query: SingularityQuery,
    joints: Vec<String>,
}

impl PreparedRun<SingularityResult> for SingularityRun {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> SingularityResult {
        let (arm, q) = (&*self.arm, &self.query);
        let chain = &arm.chain;
        let limits = Limits { max_cells: q.max_boxes, timeout: q.timeout, ..Limits::default() };
        let control = Control { limits, threads: q.threads.max(1), cancel };
        let request = SingularitiesRequest { precision: q.precision, nodes: q.nodes, search_anyway: false, verdict: true };
        let found_at = Instant::now();
        let found = singularities(arm, &request, &control, progress).expect("invariant: precision validated when prepared");
        let (cusps, node_search) = (&found.run.cusps, &found.run.nodes);
        let two = |t: &[Interval; 2]| vec![bounds(t[0]), bounds(t[1])];
        let image = |t: [Interval; 2]| {
            let j = chain.jets(t, 0);
            [j.rho.value(), j.z.value()]
        };
        let workspace = |rho: Interval, z: Interval| vec![bounds(radius(rho)), bounds(z)];
        let mut cusp_records: Vec<SingularPoint> = cusps.cusps.iter().map(|c| SingularPoint { joints: two(&c.theta), workspace: workspace(c.rho, c.z), certified: c.unique }).collect();
        cusp_records.extend(cusps.undecided.iter().map(|u| {
            let [rho, z] = image(u.theta);
            SingularPoint { joints: two(&u.theta), workspace: workspace(rho, z), certified: false }
        }));
        let mut node_records = Vec::new();
        if let Some(n) = &node_search {
            node_records.extend(n.nodes.iter().map(|n| SingularPair { joints: [two(&n.theta[0]), two(&n.theta[1])], workspace: workspace(n.rho, n.z), certified: true }));
            node_records.extend(n.undecided.iter().map(|p| {
                let (a, b) = (image(p[0]), image(p[1]));
                SingularPair { joints: [two(&p[0]), two(&p[1])], workspace: workspace(a[0].convex_hull(b[0]), a[1].convex_hull(b[1])), certified: false }
            }));
        }
        let status = found.run.status;
        // The whole arm's verdict, as `singularities --arm-budget` gives it by default, within
        // what is left of the run's time.
        let budget = q.timeout.map_or(WHOLE_ARM_BUDGET, |t| t.saturating_sub(found_at.elapsed()).min(WHOLE_ARM_BUDGET));
        let arm_cuspidality = self.six.as_deref().and_then(|six| super::six::arm_cuspidality_of(six, self.six_snapped, arm, budget, &control)).map(|c| c.line());
        let motions = internal_motions(chain, &cusps.bands, &self.joints, q.precision);
        let processed = cusps.stats.processed + node_search.as_ref().map_or(0, |n| n.stats.processed);
        let certified_nodes = node_search.as_ref().map_or(0, |n| n.nodes.len());
        let summary = format!(
            "{} cusps, {}, {} internal-motion lines, {} undecided, {} cover boxes in {} pieces, {}",
            cusps.cusps.len(),
            if found.nodes_searched {
                format!("{certified_nodes} nodes")
            } else if q.nodes {
                "nodes not searched (the singular branches are curves of nodes)".to_string()
            } else {
                "nodes not searched".to_string()
            },
            motion::line_count(&cusps.bands),
            cusps.undecided.len() + node_search.as_ref().map_or(0, |n| n.undecided.len()),
            self.cover.boxes.len(),
            self.cover.clusters,
            match status {
                Status::Finished => "complete".to_string(),
                Status::Stopped(Limit::Cancelled) => "incomplete (cancelled)".to_string(),
                Status::Stopped(Limit::Boxes) => "incomplete (box limit)".to_string(),
                Status::Stopped(limit) => format!("incomplete ({} limit)", limit.name()),
            }
        );
        // The joint limits' effect is named only when the file has limits.
        let scope = &arm.prepared.choice.scope;
        let verdict = found.verdict.as_ref().expect("invariant: the node asks for the verdict");
        let headline = match &scope.not_answered {
            Some(open) if !scope.stands_for_arm => format!("{}; {open}", verdict.headline(scope)),
            _ => verdict.headline(scope),
        };
        let summary = if arm.prepared.limits.restrict() {
            format!("{headline}; {}; {}", summary, found.limit_effect.text)
        } else {
            format!("{headline}; {}", summary)
        };
        SingularityResult {
            mechanism: chain.name.clone(),
            status,
            query: q.clone(),
            joint_names: self.joints.clone(),
            workspace_names: vec!["radius".into(), "z".into()],
            cusps: cusp_records,
            nodes: node_records,
            singular_curves: box_set(&self.cover, &chain.name, &self.joints),
            internal_motions: motions,
            processed,
            seconds: found.seconds + self.cover.seconds,
            summary,
            loops: None,
            verdict: Some(verdict.scoped(scope)),
            branches: arm.branches.clone(),
            arm_cuspidality,
        }
    }
}

/// The internal-motion lines as a box set: θ₂ over its whole range, θ₃ in each band's
/// enclosure of the lines (as `MotionRecord` of the CLI report).
fn internal_motions(chain: &Chain3R, bands: &[motion::Band], joints: &[String], precision: f64) -> BoxSetResult {
    let full = motion::full_range();
    let boxes = bands
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let bx = vec![bounds(full), b.theta3];
            // A near-degenerate strip (`Band::near`) is not an internal motion: undecided.
            let status = if b.near.is_some() { BoxStatus::Undecided } else { BoxStatus::Solution };
            ResultBox { status, bounds: bx.clone(), joints: bx, level: 0, cluster: Some(k), traces: vec![] }
        })
        .collect();
    BoxSetResult {
        mechanism: chain.name.clone(),
        analysis: "internal_motions".into(),
        status: Status::Finished,
        settings: SolverSettings { sigma: precision, ..Default::default() },
        variables: joints.to_vec(),
        primaries: vec![1],
        joint_names: joints.to_vec(),
        fixed_joints: vec![],
        traces: vec![],
        boxes,
        clusters: bands.len(),
        stats: Stats { solutions: bands.len() as u64, ..Default::default() },
    }
}

/// A validated inverse-kinematics run.
struct IkRun {
    arm: Arc<Arm>,
    query: IkQuery,
}

impl PreparedRun<IkResult> for IkRun {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> IkResult {
        let arm = &*self.arm;
        let chain = &arm.chain;
        let limits = Limits { max_cells: self.query.max_boxes, timeout: self.query.timeout, ..Limits::default() };
        let control = Control { limits, threads: self.query.threads.max(1), cancel };
        let found = inverse_kinematics(arm, IkPoint::Root(self.query.point), self.query.precision, &control, progress).expect("invariant: validated when prepared");
        let target = found.target.expect("invariant: a root-frame point has a target");
        let three = |b: &[Interval; 2]| vec![bounds(found.theta1(arm, b).expect("invariant: a root-frame point fixes θ₁")), bounds(b[0]), bounds(b[1])];
        let s = &found.solutions;
        let mut solutions: Vec<IkSolution> = s.unique.iter().map(|b| IkSolution { joints: three(b), unique: true, boxes: 0 }).collect();
        solutions.extend(s.clusters.iter().map(|c| IkSolution { joints: three(&c.hull), unique: false, boxes: c.boxes }));
        IkResult {
            mechanism: chain.name.clone(),
            joint_names: chain.joints.to_vec(),
            point_names: vec!["radius".into(), "z".into()],
            point_values: vec![bounds(radius(target.half_section[0])), bounds(target.half_section[1])],
            solutions,
            status: s.status,
            processed: s.stats.processed,
            seconds: found.seconds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::{point, Bounds};
    use crate::analyses::arm3r::ik;
    use crate::app::load;
    use crate::model::{urdf, JointKind};
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

    const E: &str = include_str!("../../urdf/orthogonal_3r_e.urdf");
    const F: &str = include_str!("../../urdf/orthogonal_3r_f.urdf");

    fn query() -> SingularityQuery {
        SingularityQuery { precision: 1e-4, nodes: true, max_boxes: 1_000_000, timeout: None, threads: 1 }
    }

    fn revolute(m: &Mechanism) -> Vec<String> {
        m.joints.iter().filter(|j| matches!(j.kind, JointKind::Revolute { .. })).map(|j| j.name.clone()).collect()
    }

    /// The tip's position in the root frame at joint values `q`, in floating point.
    fn forward(m: &Mechanism, q: &[f64]) -> [f64; 3] {
        let names = revolute(m);
        let tip = (0..m.links.len()).find(|&l| m.joints.iter().all(|j| j.parent != l)).expect("a leaf");
        let mut pose = Isometry3::identity();
        for j in m.path_to(tip) {
            let joint = &m.joints[j];
            pose *= joint.origin;
            if let Some(k) = names.iter().position(|n| *n == joint.name) {
                pose *= Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(joint.axis), q[k]));
            }
        }
        let p = pose * Point3::origin();
        [p.x, p.y, p.z]
    }

    #[test]
    #[allow(clippy::approx_constant)] // a sample grid over [-3.14, 3.14], not π
    fn robot_e_has_the_table_counts_and_a_sound_curve_cover() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        assert_eq!(a.kind(), MechanismKind::Manipulator3R);
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(r.status, Status::Finished);
        assert_eq!((r.cusps.iter().filter(|c| c.certified).count(), r.nodes.iter().filter(|n| n.certified).count(), r.undecided()), (4, 2, 0));
        assert_eq!(r.internal_motions.boxes.len(), 0);
        // Every point where det Df changes sign along a fine grid line lies in a cover box.
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        let cover = &r.singular_curves;
        let det = |t2: f64, t3: f64| chain.jets([point(t2), point(t3)], 1).det().value().mid();
        let inside = |t2: f64, t3: f64| cover.boxes.iter().any(|b| b.joints[0][0] <= t2 && t2 <= b.joints[0][1] && b.joints[1][0] <= t3 && t3 <= b.joints[1][1]);
        let mut crossings = 0;
        for k in 0..200 {
            let t3 = -3.1 + 6.2 * k as f64 / 199.0;
            let n = 4000;
            for i in 0..n {
                let (x0, x1) = (-3.14 + 6.28 * i as f64 / n as f64, -3.14 + 6.28 * (i + 1) as f64 / n as f64);
                if det(x0, t3).signum() != det(x1, t3).signum() {
                    crossings += 1;
                    assert!(inside(x0, t3) || inside(x1, t3), "sign change of det at θ2 ≈ {x0}, θ3 = {t3} outside the cover");
                }
            }
        }
        assert!(crossings > 200, "the test must see the curves: {crossings} crossings");
        // The cover is thin: far fewer boxes than the grid.
        assert!(cover.boxes.len() < 256 * 256 / 10, "{} boxes", cover.boxes.len());
    }

    #[test]
    #[allow(clippy::approx_constant)] // a sample grid over [-3.14, 3.14], not π
    fn classification_gives_a_sound_lower_bound_on_the_singular_distance() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        // A cusp's own configuration is singular: distance 0, no region.
        let r = a.singularities(&query()).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        let c = &r.cusps[0].joints;
        let at_cusp = a.classify(&[0.3, 0.5 * (c[0][0] + c[0][1]), 0.5 * (c[1][0] + c[1][1])], None, Some(&r)).expect("3R classifies");
        assert_eq!((at_cusp.component, at_cusp.singular_distance), (None, Some(0.0)));
        // Regular configurations: the distance to the nearest sampled singular point is at
        // least the reported bound, and every sample is in a region.
        let det = |t2: f64, t3: f64| chain.jets([point(t2), point(t3)], 1).det().value().mid();
        let mut singular = Vec::new();
        for k in 0..400 {
            let t3 = -3.1 + 6.2 * k as f64 / 399.0;
            for i in 0..2000 {
                let (x0, x1) = (-3.14 + 6.28 * i as f64 / 2000.0, -3.14 + 6.28 * (i + 1) as f64 / 2000.0);
                if det(x0, t3).signum() != det(x1, t3).signum() {
                    singular.push((0.5 * (x0 + x1), t3));
                }
            }
        }
        let mut seen_regions = std::collections::BTreeSet::new();
        for (t2, t3) in [(0.0, 0.0), (1.0, 2.0), (-2.0, 0.5), (3.0, -3.0), (-0.7, -1.9)] {
            let c = a.classify(&[0.0, t2, t3], None, Some(&r)).expect("classifies");
            let bound = c.singular_distance.expect("known");
            let sampled = singular.iter().map(|&(x, y)| (gap(t2, [x, x], true).powi(2) + gap(t3, [y, y], true).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
            // The samples sit within 0.002 of the curve.
            assert!(bound <= sampled + 0.002, "({t2}, {t3}): bound {bound} above the sampled distance {sampled}");
            if let Some(k) = c.component {
                seen_regions.insert(k);
                assert!(bound > 0.0);
            }
            assert!(c.inside && c.components >= 2);
        }
        assert!(!seen_regions.is_empty());
    }

    /// Test idea: the node honours the file's joint limits as `ik` and `singularities` do.
    /// PUMA 560 limits joint 1 to [-2.7925, 2.7925], joint 2 to [-3.927, 0.7854] and joint 3 to
    /// [-0.7854, 3.927]: on the circle, θ₁ beyond ±2.7925, θ₂ in (0.7854, 2.3562) and θ₃ in
    /// (-2.3562, -0.7854) are out of reach (θ₁ is fixed by the point, so its limits count). The same
    /// arm with continuous joints answers a superset; what the limited one leaves out is
    /// exactly the solutions in those arcs (checked against the decimal limits, not the
    /// library's filter), and some point must lose one.
    #[test]
    #[allow(clippy::approx_constant)] // the decimal limits of puma560.urdf, not π/4
    fn joint_limits_filter_what_the_node_answers() {
        const PUMA: &str = include_str!("../../urdf/puma560.urdf");
        let limited = load(&urdf::parse(PUMA).expect("bundled"), &[], &[]).expect("puma");
        let free = load(&urdf::parse(&PUMA.replace("type=\"revolute\"", "type=\"continuous\"")).expect("continuous"), &[], &[]).expect("puma");
        let tau = std::f64::consts::TAU;
        let outside = |j: &[Bounds]| (j[0][0] > 2.7925 && j[0][1] < -2.7925 + tau) || (j[0][1] < -2.7925 && j[0][0] > 2.7925 - tau) || (j[1][0] > 0.7854 && j[1][1] < -3.927 + tau) || (j[2][0] > 3.927 - tau && j[2][1] < -0.7854);
        // The limited arm states its angles in the joints' ranges: the same solution up to turns.
        let same = |a: &[Bounds], b: &[Bounds]| {
            a.iter().zip(b).all(|(x, y)| {
                let turns = ((x[0] - y[0]) / tau).round() * tau;
                (x[0] - y[0] - turns).abs() < 1e-9 && (x[1] - y[1] - turns).abs() < 1e-9
            })
        };
        let mut dropped = 0;
        for point in [[0.5, 0.0, 0.3], [0.4, 0.2, 0.6], [0.3, -0.3, 0.9], [0.6, 0.1, 0.2], [0.2, 0.2, 0.2]] {
            let q = IkQuery { point, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 };
            let l = limited.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
            let f = free.inverse_kinematics(&q).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
            assert!(l.status.finished() && f.status.finished());
            for s in &l.solutions {
                assert!(f.solutions.iter().any(|t| same(&t.joints, &s.joints)), "{point:?}: {s:?} is not a solution of the free arm");
                assert!(!outside(&s.joints), "{point:?}: {s:?} is outside the limits");
            }
            for t in f.solutions.iter().filter(|t| !l.solutions.iter().any(|s| same(&s.joints, &t.joints))) {
                assert!(outside(&t.joints), "{point:?}: {t:?} was dropped but lies within the limits");
                dropped += 1;
            }
        }
        assert!(dropped > 0, "no point lost a solution to the limits");
        let r = limited.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(r.summary.contains("results outside dropped"), "{}", r.summary);
        let r = free.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(!r.summary.contains("results outside dropped"), "{}", r.summary);
    }

    #[test]
    fn inverse_kinematics_matches_the_cli_search_and_reaches_the_point() {
        let m = urdf::parse(E).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let chain = Chain3R::from_mechanism(&m, 0.0).expect("3R");
        let (r, z) = (1.9, 0.4);
        let reference = ik::solve(&chain, r, z, 1e-8, 200_000).expect("valid");
        // The same (ρ, z) seen from a point turned by 0.7 rad about the first axis.
        let p = [r * 0.7f64.cos(), r * 0.7f64.sin(), z];
        let got = a.inverse_kinematics(&IkQuery { point: p, precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(got.joint_names, vec!["joint1", "joint2", "joint3"]);
        assert_eq!(got.solutions.iter().filter(|s| s.unique).count(), reference.unique.len());
        assert!(reference.unique.len() >= 2);
        for s in got.solutions.iter().filter(|s| s.unique) {
            let q: Vec<f64> = s.joints.iter().map(|b| 0.5 * (b[0] + b[1])).collect();
            let tip = forward(&m, &q);
            let miss = ((tip[0] - p[0]).powi(2) + (tip[1] - p[1]).powi(2) + (tip[2] - p[2]).powi(2)).sqrt();
            assert!(miss < 1e-6, "{q:?} reaches {tip:?}, not {p:?}");
            assert!(s.joints[0][1] - s.joints[0][0] < 1e-6, "θ1 enclosed tightly: {:?}", s.joints[0]);
        }
        // On the point (r, 0, z) the boxes are the CLI's, bit for bit.
        let got = a.inverse_kinematics(&IkQuery { point: [r, 0.0, z], precision: 1e-8, max_boxes: 200_000, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        for (s, u) in got.solutions.iter().zip(&reference.unique) {
            assert_eq!(s.joints[1..], [bounds(u[0]), bounds(u[1])]);
        }
    }

    #[test]
    fn robot_f_reports_its_internal_motions_and_bad_queries_are_refused() {
        let m = urdf::parse(F).expect("bundled");
        let a = load(&m, &[], &[]).expect("3R");
        let r = a.singularities(&SingularityQuery { nodes: false, ..query() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(r.internal_motions.boxes.len(), 2);
        assert!(r.nodes.is_empty());
        let err = |e: AnalysisError| e.to_string();
        assert!(err(a.singularities(&SingularityQuery { precision: 2.0, ..query() }).err().expect("refused")).contains("precision must be a number in (0, 1), got 2"));
        let ik = |point: [f64; 3], precision: f64| a.inverse_kinematics(&IkQuery { point, precision, max_boxes: 1000, timeout: None, threads: 1 }).err().map(err).unwrap_or_default();
        assert!(ik([f64::NAN, 0.0, 0.0], 1e-6).contains("is not finite"));
        assert!(ik([1.0, 0.0, 0.0], 0.0).contains("precision must be a number in (0, 1)"));
        // A tight box limit ends incomplete, with its pending boxes as clusters.
        let short = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 5, timeout: None, threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert!(short.status == Status::Stopped(Limit::Boxes) && short.solutions.iter().any(|s| !s.unique));
        // A timeout stops it too (the node passes its --max-wait, past which no reply is sent).
        let late = a.inverse_kinematics(&IkQuery { point: [1.0, 0.0, 0.2], precision: 1e-9, max_boxes: 1_000_000, timeout: Some(std::time::Duration::ZERO), threads: 1 }).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(late.status, Status::Stopped(Limit::Time));
        // 3R chains take no fixed joints.
        assert!(load(&m, &[("joint2".into(), 0.1)], &[]).err().map(err).unwrap_or_default().contains("takes no fixed joints"));
    }
}

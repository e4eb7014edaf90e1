//! The ROS node's analysis of a serial arm (`Manip3rAnalysis`): the arm jobs of `arm`, run with
//! the node's query types, plus a cover of the singular curves and the classification of
//! configurations against it.

use super::arm::{Arm, IkPoint};
use super::results::{unexpected, JobRun};
use super::{
    gap, Analysis, AnalysisError, Answer, BoxSetResult, Classification, IkAnswer, IkJob, IkQuery, IkResult, IkSolution, Input, Job, JobError, MechanismKind, PreparedRun, ResultBox, Service,
    SingularPair, SingularPoint, SingularitiesAnswer, SingularitiesJob, SingularityQuery, SingularityResult,
};
use crate::analyses::arm3r::{self, collision::Scene, curves::Cover, motion, records::radius, Chain3R, LoadOptions, Manip3rError};
use crate::kernel::interval::bounds;
use crate::kernel::search::{BoxStatus, Control, Limit, Limits, SolveStats as Stats, SolverSettings, Status};
use crate::model::Mechanism;
use inari::Interval;
use std::sync::Arc;


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
    /// Whether the whole arm is a chain of six revolute joints (it answers the 6R questions).
    six: bool,
    /// Why the arm has no collision analysis (its links carry no collision body it reads), or
    /// `None` when it has one.
    no_bodies: Option<String>,
    /// Cover of the singular curves, computed once (it does not depend on any request).
    cover: Arc<Cover>,
    /// The mechanism as the front door takes it: every run is a `Job` prepared on it.
    input: Arc<Input>,
}

impl Manip3rAnalysis {
    /// Reads the arm (nominal geometry); errors when the mechanism holds no 3R positioning
    /// structure or its map is degenerate.
    pub fn new(mechanism: &Mechanism) -> Result<Self, Manip3rError> {
        let arm = Arm::load(mechanism, &LoadOptions::default(), 0.0)?;
        let cover = Arc::new(Cover::new(&arm.chain, CURVE_DEPTH, &Control::with_limits(Limits::default())));
        let six = super::six::chain6_snapped(mechanism, &LoadOptions::default()).is_ok();
        let no_bodies = Scene::from_mechanism(&arm.prepared.mechanism).err().map(|e| e.to_string());
        Ok(Self { arm: Arc::new(arm), six, no_bodies, cover, input: Arc::new(Input::Mechanism(mechanism.clone())) })
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
        if self.six {
            services.insert(3, Service::InverseKinematics6);
        }
        if self.no_bodies.is_none() {
            services.push(Service::Collisions);
        }
        services
    }

    fn limitation(&self) -> String {
        let mut text = "a 3R manipulator: an open chain reaches every joint configuration, so there is no configuration space to solve".to_string();
        if let Some(why) = &self.no_bodies {
            text.push_str(&format!("; no collisions: {why}"));
        }
        text
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

    /// `linkspace singularities`' job with its defaults (the verdict, and the whole-arm
    /// verdict within `WHOLE_ARM_BUDGET`), read with the singular-curve cover.
    fn singularities(&self, query: &SingularityQuery) -> Result<Box<dyn PreparedRun<SingularityResult>>, JobError> {
        arm3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()).into());
        }
        let job = Job::Singularities(SingularitiesJob {
            arm: LoadOptions::default(),
            uncertainty: 0.0,
            precision: query.precision,
            nodes: query.nodes,
            verdict: true,
            search_anyway: false,
            arm_budget: WHOLE_ARM_BUDGET.as_secs_f64(),
        });
        let limits = Limits { max_cells: query.max_boxes, timeout: query.timeout, ..Limits::default() };
        let (cover, query_, joints) = (self.cover.clone(), query.clone(), self.record_joints());
        JobRun::prepare(&self.input, job, limits, query.threads, move |answer| match answer {
            Answer::Singularities(a) => Ok(singularity_result(&a, &cover, query_, joints)),
            other => Err(unexpected(&other, "singularities")),
        })
    }

    /// `linkspace ik`'s job for a point in the root frame.
    fn inverse_kinematics(&self, query: &IkQuery) -> Result<Box<dyn PreparedRun<IkResult>>, JobError> {
        if query.point.iter().any(|v| !v.is_finite()) {
            return Err(AnalysisError::BadRequest(Manip3rError::BadTarget(query.point).to_string()).into());
        }
        arm3r::check_precision(query.precision).map_err(|e| AnalysisError::BadRequest(e.to_string()))?;
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()).into());
        }
        let job = Job::Ik(IkJob { arm: LoadOptions::default(), uncertainty: 0.0, point: IkPoint::Root(query.point), precision: query.precision });
        let limits = Limits { max_cells: query.max_boxes, timeout: query.timeout, ..Limits::default() };
        JobRun::prepare(&self.input, job, limits, query.threads, move |answer| match answer {
            Answer::Ik(a) => Ok(ik_result(&a)),
            other => Err(unexpected(&other, "inverse_kinematics")),
        })
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

/// The node's view of an arm's singularity answer: its records over (θ₂, θ₃) and their
/// images, the singular-curve `cover`, the summary line and the verdicts.
fn singularity_result(answer: &SingularitiesAnswer, cover: &Cover, q: SingularityQuery, joints: Vec<String>) -> SingularityResult {
    let (arm, found) = (&answer.arm, &answer.found);
    let chain = &arm.chain;
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
    // The whole arm's verdict, as `singularities --arm-budget` gives it by default.
    let arm_cuspidality = answer.whole_arm.as_ref().map(|(_, c)| c.line());
    let motions = internal_motions(chain, &cusps.bands, &joints, q.precision);
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
        cover.boxes.len(),
        cover.clusters,
        match status.limit() {
            None => crate::kernel::outcome::Completeness::Complete.word().to_string(),
            Some(Limit::Cancelled) => "incomplete (cancelled)".to_string(),
            Some(Limit::Boxes) => "incomplete (box limit)".to_string(),
            Some(limit) => format!("incomplete ({} limit)", limit.name()),
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
        joint_names: joints.clone(),
        workspace_names: vec!["radius".into(), "z".into()],
        cusps: cusp_records,
        nodes: node_records,
        singular_curves: box_set(cover, &chain.name, &joints),
        internal_motions: motions,
        processed,
        seconds: found.seconds + cover.seconds,
        summary,
        loops: None,
        verdict: Some(verdict.scoped(scope)),
        branches: arm.branches.clone(),
        arm_cuspidality,
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

/// The node's view of an arm's inverse-kinematics answer for a point in the root frame.
fn ik_result(answer: &IkAnswer) -> IkResult {
    let (arm, found) = (&answer.arm, &answer.found);
    let chain = &arm.chain;
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

//! The linkage analysis: the configuration space of a closed-loop mechanism (`formulate::Linkage`:
//! the planar builder when it accepts the mechanism, the spatial one otherwise, chosen as
//! `solve --model auto` does), re-solved on request with other fixed joints or settings. The
//! result is the same as `linkspace solve --json` for the same input.
//!
//! Planar and spatial linkages also answer `singularities` with their singular sets
//! (`singular`: C-space, input and output, through `SingularSets`, the orchestration
//! `linkspace loop-singularities` runs on the same model, so the boxes are those of its
//! `--json`), and `classify` with a lower bound on the joint-space distance to the nearest
//! singular configuration once those sets are complete.

use super::results::{limits_of, unexpected, JobRun};
use super::{
    classify, gap, Actuation, Analysis, Answer, AnalysisError, BoxSetResult, Classification, Input, Job, JobError, LoopAnswer, LoopQuestion, LoopSingularities, LoopSingularitiesJob, MechanismKind,
    PreparedRun, ResultBox, Service, SingularSetResult, SingularityQuery, SingularityResult, SolveJob,
};
use crate::kernel::interval::bounds;
use crate::model::{JointKind, Mechanism};
use crate::formulate::choice::TracedPoint;
use crate::formulate::singular::{Coordinates, SingularProblem};
use crate::analyses::loop_singular::SingularSet;
use crate::formulate::{Linkage, LinkageError, ModelChoice};
use crate::kernel::outcome::Completeness;
use crate::kernel::search::{BoxStatus, Limits, SolveStats, SolverSettings, Status};
use crate::kernel::system::VarRole;

/// A closed-loop linkage, as loaded.
#[derive(Clone, Debug)]
pub struct LinkageAnalysis {
    mechanism: Mechanism,
    fixed: Vec<(String, f64)>,
    traces: Vec<TracedPoint>,
    /// The problem with the load-time fixed joints: names the free joints and the model.
    problem: Linkage,
    /// Actuated joints of the input singular set.
    actuation: Actuation,
    /// The mechanism as the front door takes it: every run is a `Job` prepared on it.
    input: std::sync::Arc<Input>,
}

impl LinkageAnalysis {
    /// Formulates `mechanism` with the load-time `fixed` joints and traced points
    /// `(link, x, y)` in the plane of the link's frame.
    pub fn new(mechanism: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Self, LinkageError> {
        let traces: Vec<TracedPoint> = traces.iter().map(|(l, x, y)| (l.clone(), [*x, *y, 0.0], format!("{l}@{x},{y}"))).collect();
        let problem = Linkage::build(mechanism, ModelChoice::Auto, fixed, &traces)?;
        Ok(Self {
            mechanism: mechanism.clone(),
            fixed: fixed.to_vec(),
            traces,
            problem,
            actuation: Actuation { joints: Vec::new(), source: "none given".to_string() },
            input: std::sync::Arc::new(Input::Mechanism(mechanism.clone())),
        })
    }

    /// The same analysis with these actuated joints (for the input singular set).
    pub fn with_actuation(self, actuation: Actuation) -> Self {
        Self { actuation, ..self }
    }

    /// A `solve` job of the node: `fixed` joints (the load-time ones, or a request's), the
    /// load-time traced points, `settings`; its box set named `analysis`.
    fn solve_run(&self, fixed: &[(String, f64)], settings: &SolverSettings, analysis: &'static str) -> Result<Box<dyn PreparedRun>, JobError> {
        let s = settings;
        let job = Job::Solve(SolveJob { fixed: fixed.to_vec(), traces: self.traces.clone(), model: ModelChoice::Auto, precision: s.sigma, rho: s.rho, use_lp: s.use_lp, newton_width: s.newton_width, lp_backend: s.lp_backend });
        JobRun::new(&self.input, job, limits_of(s), s.threads, move |answer| match answer {
            Answer::Solve(solved) => Ok(BoxSetResult { analysis: analysis.to_string(), ..solved.result }),
            other => Err(unexpected(&other, analysis)),
        })
    }
}

impl Analysis for LinkageAnalysis {
    fn mechanism(&self) -> &str {
        &self.mechanism.name
    }

    fn kind(&self) -> MechanismKind {
        match self.problem {
            Linkage::Planar(_) => MechanismKind::PlanarLinkage,
            Linkage::Spatial(..) => MechanismKind::SpatialLinkage,
            Linkage::Pose(..) | Linkage::Distances(..) => MechanismKind::ParallelPlatform,
        }
    }

    fn services(&self) -> Vec<Service> {
        vec![Service::Solve, Service::Singularities, Service::Classify]
    }

    fn limitation(&self) -> String {
        match &self.problem {
            Linkage::Planar(_) => "a planar linkage: its configuration space and singular sets (C-space, input, output) are analysed; cusps and nodes of the type-II image are not (`linkspace loop-singularities --kind image`), nor is inverse kinematics".to_string(),
            Linkage::Spatial(_, why) => format!("a spatial linkage ({why}): its configuration space and singular sets (C-space, input, output; actuated and output joints are tree joints) are analysed; inverse kinematics is not"),
            Linkage::Pose(_, why) => format!("a parallel platform ({why}): its assembly modes are solved in pose coordinates, its singular sets in the spatial model's joint coordinates; inverse kinematics is not analysed"),
            Linkage::Distances(_, why) => format!("a parallel platform ({why}): its assembly modes are solved in squared distances and heights, its singular sets in the spatial model's joint coordinates; inverse kinematics is not analysed"),
        }
    }

    fn free_joints(&self) -> Vec<String> {
        self.problem.free_joints().to_vec()
    }

    fn fixed_joints(&self) -> Vec<(String, f64)> {
        self.fixed.clone()
    }

    fn periodic(&self) -> Vec<bool> {
        let kind = |name: &str| {
            self.mechanism
                .joints
                .iter()
                .find(|j| j.name == name)
                .map(|j| j.kind)
                .or_else(|| self.mechanism.loops.iter().find(|l| l.name == name).map(|l| l.kind))
        };
        self.problem.free_joints().iter().map(|n| !matches!(kind(n), Some(JointKind::Prismatic { .. }))).collect()
    }

    fn configuration_space(&self, settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        self.solve_run(&self.fixed, settings, "configuration_space")
    }

    fn solve(&self, fixed: &[(String, f64)], settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        self.solve_run(fixed, settings, "solve")
    }

    /// The singular sets with the load-time fixed joints (`loop-singularities`' job): `precision`
    /// is the solver's sigma (the largest width of a box in the configuration and null-vector
    /// variables), `max_boxes` the limit per chart, `timeout` for all sets; `nodes` does not
    /// apply (no image is analysed).
    fn singularities(&self, query: &SingularityQuery) -> Result<Box<dyn PreparedRun<SingularityResult>>, JobError> {
        if !(query.precision > 0.0 && query.precision < 1.0) {
            return Err(AnalysisError::BadRequest(format!("precision must be a number in (0, 1), got {}", query.precision)).into());
        }
        if query.max_boxes == 0 {
            return Err(AnalysisError::BadRequest("max_boxes must be at least 1".into()).into());
        }
        let job = Job::LoopSingularities(LoopSingularitiesJob {
            question: LoopQuestion::Sets(Vec::new()),
            fixed: self.fixed.clone(),
            actuated: Some(self.actuation.joints.clone()),
            output: None,
            precision: query.precision,
        });
        let limits = Limits { max_cells: query.max_boxes, timeout: query.timeout, ..Limits::default() };
        let (query, actuation) = (query.clone(), self.actuation.clone());
        JobRun::new(&self.input, job, limits, query.threads, move |answer| singularity_result(answer, query, actuation))
    }

    /// The configuration-space classification, plus a lower bound on the distance to the nearest
    /// singular configuration once every singular set is complete (else unknown, with why).
    fn classify(&self, values: &[f64], configuration_space: Option<&BoxSetResult>, singularities: Option<&SingularityResult>) -> Result<Classification, AnalysisError> {
        let cspace = configuration_space.ok_or(AnalysisError::NotReady { what: "configuration_space" })?;
        let periodic = self.periodic();
        let mut c = classify(cspace, values, &periodic, None);
        let names = self.free_joints();
        match (&self.problem, singularities.and_then(|s| s.loops.as_ref())) {
            (_, None) => c.note = "the singular sets are not known yet (still being computed, or their run failed: see list_mechanisms)".to_string(),
            (_, Some(loops)) => match singular_distance(loops, &names, values, &periodic) {
                Ok((d, note)) => {
                    c.singular_distance = Some(d);
                    c.note = note;
                }
                Err(why) => c.note = why,
            },
        }
        Ok(c)
    }
}

/// A lower bound on the joint-space distance from `values` (over `names`) to every box of every
/// set, with which set holds the nearest box; an error (why) unless every set is complete.
///
/// Sound: a complete set holds every singular configuration of its kind in its solution boxes
/// (certified or not), each box's joint values are outward enclosures, and the distance to a
/// box is at most the distance to any point in it; the result is lowered by a relative and an
/// absolute 1e-12 for the floating-point rounding of the distance itself.
pub(crate) fn singular_distance(loops: &LoopSingularities, names: &[String], values: &[f64], periodic: &[bool]) -> Result<(f64, String), String> {
    if !loops.complete() {
        let open: Vec<String> = loops
            .sets
            .iter()
            .filter(|s| !(s.boxes.status.finished() && s.undecided == 0))
            .map(|s| match s.boxes.status {
                Status::Stopped(l) => format!("{} ({} limit, {} boxes undecided)", s.kind, l.name(), s.undecided),
                Status::Finished => format!("{} ({} boxes undecided)", s.kind, s.undecided),
            })
            .collect();
        return Err(format!("the singular search did not complete ({}), so no bound on the distance to singularities is claimed", open.join(", ")));
    }
    let mut best: Option<(f64, &'static str)> = None;
    for set in &loops.sets {
        // The set's joints by the analysis's names (the same free joints, looked up by name).
        let index: Vec<usize> = names.iter().map(|n| set.boxes.joint_names.iter().position(|j| j == n)).collect::<Option<_>>().ok_or_else(|| format!("internal: the {} set is over other joints ({})", set.kind, set.boxes.joint_names.join(", ")))?;
        for b in set.boxes.boxes.iter().filter(|b| b.status.is_solution()) {
            let d = index.iter().zip(values).zip(periodic).map(|((&k, &x), &p)| gap(x, b.joints[k], p).powi(2)).sum::<f64>().sqrt();
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, set.kind));
            }
        }
    }
    let searched: Vec<&str> = loops.sets.iter().map(|s| s.kind).collect();
    Ok(match best {
        None => (f64::INFINITY, format!("every singular set searched ({}) is empty, proven by complete searches: no singular configuration of those kinds", searched.join(", "))),
        Some((d, kind)) => (
            (d * (1.0 - 1e-12) - 1e-12).max(0.0),
            format!("the singular distance is a lower bound on the joint-space distance to the nearest singular configuration, which is of the {kind} set ({}; sets searched: {})", kind_meaning(kind), searched.join(", ")),
        ),
    })
}

/// What a kind of singular set is, a few words.
fn kind_meaning(kind: &str) -> &'static str {
    match kind {
        "cspace" => "a bifurcation: the loop constraints lose rank",
        "input" => "type II: with the actuated joints locked the mechanism still moves",
        _ => "type I: the output stands still while the mechanism moves",
    }
}

/// The node's view of a linkage's singular sets: one box set per set, with its summary.
fn singularity_result(answer: Answer, query: SingularityQuery, actuation: Actuation) -> Result<SingularityResult, JobError> {
    let Answer::LoopSingularities(found) = answer else { return Err(unexpected(&answer, "singularities")) };
    let LoopAnswer::Sets { mechanism, sets: problems, solved, settings } = *found else { return Err(JobError::Bad("internal error: not the singular sets".into())) };
    let sets: Vec<SingularSetResult> = problems.problems.iter().zip(&solved).map(|(p, set)| set_result(p, &settings, set)).collect();
    // The run's status: the first limit any set met.
    let status = solved.iter().map(|s| s.status).find(|s| !s.finished()).unwrap_or(Status::Finished);
    let processed = solved.iter().flat_map(|s| &s.stats).map(|s| s.processed).sum();
    let seconds = solved.iter().map(|s| s.seconds).sum();
    let joint_names = problems.problems.first().map(|p| p.linkage.free_joints().to_vec()).unwrap_or_default();
    let summary = format!(
        "{}; actuated: {} ({})",
        sets.iter().map(|s| format!("{}: {}", s.kind, s.summary)).collect::<Vec<_>>().join("; "),
        if actuation.joints.is_empty() { "none".to_string() } else { actuation.joints.join(", ") },
        actuation.source
    );
    let empty = |analysis: &str| BoxSetResult {
        mechanism: mechanism.clone(),
        analysis: analysis.to_string(),
        status: Status::Finished,
        settings: settings.clone(),
        variables: joint_names.clone(),
        primaries: (0..joint_names.len()).collect(),
        joint_names: joint_names.clone(),
        fixed_joints: vec![],
        traces: vec![],
        boxes: vec![],
        clusters: 0,
        stats: SolveStats::default(),
    };
    Ok(SingularityResult {
        mechanism: mechanism.clone(),
        status,
        query,
        joint_names: joint_names.clone(),
        workspace_names: vec![],
        cusps: vec![],
        nodes: vec![],
        // The 3R records have no counterpart here: the sets are in `loops`.
        singular_curves: empty("singular_curves"),
        internal_motions: empty("internal_motions"),
        processed,
        seconds,
        summary,
        loops: Some(LoopSingularities { actuated: actuation.joints.clone(), actuated_source: actuation.source.clone(), sets }),
        verdict: None,
        branches: None,
        arm_cuspidality: None,
    })
}

/// One solved set as a box set: the boxes, joint values and counts of `loop-singularities
/// --json` for the same set.
fn set_result(p: &SingularProblem<Linkage>, settings: &SolverSettings, set: &SingularSet) -> SingularSetResult {
    let names = p.linkage.free_joints().to_vec();
    let chart = &p.augmented;
    let boxes: Vec<ResultBox> = set
        .boxes
        .iter()
        .zip(&set.labels)
        .map(|(sb, &label)| {
            let status = sb.status;
            let values = p.joint_values(&sb.b);
            ResultBox {
                status,
                bounds: sb.b.dims.iter().map(|&x| bounds(x)).collect(),
                joints: names.iter().map(|n| values.get(n).map_or([f64::NAN, f64::NAN], |&(lo, hi)| [lo, hi])).collect(),
                level: sb.b.level,
                cluster: (sb.status != BoxStatus::Undecided).then_some(label),
                traces: vec![],
            }
        })
        .collect();
    let undecided = set.boxes.iter().filter(|b| b.status == BoxStatus::Undecided).count();
    let (clusters, certified_clusters) = (set.clusters.len(), set.certified_clusters());
    let mut stats = SolveStats::default();
    for s in &set.stats {
        stats.processed += s.processed;
        stats.empty += s.empty;
        stats.bisected += s.bisected;
        stats.solutions += s.solutions;
        stats.certified += s.certified;
        stats.max_level = stats.max_level.max(s.max_level);
    }
    stats.seconds = set.seconds;
    let shape = match p.expected_dimension {
        0 => "points",
        1 => "curves",
        d if d < 0 => "generically none",
        _ => "surfaces",
    };
    let n = boxes.len();
    let summary = match set.status {
        Status::Finished if n == 0 => format!("none (proven: a complete search left no box; expected {shape})"),
        Status::Finished if undecided == 0 => format!("{clusters} clusters ({certified_clusters} certified, {} unproven), {n} boxes, {} (expected {shape})", clusters - certified_clusters, Completeness::Complete.word()),
        Status::Finished => format!("{clusters} clusters ({certified_clusters} certified), {n} boxes, {undecided} undecided (expected {shape})"),
        Status::Stopped(l) => format!("incomplete ({} limit): {clusters} clusters ({certified_clusters} certified), {n} boxes, {undecided} undecided (expected {shape})", l.name()),
    };
    SingularSetResult {
        kind: p.kind.name(),
        boxes: BoxSetResult {
            mechanism: p.linkage.name().to_string(),
            analysis: format!("singular_set:{}", p.kind.name()),
            status: set.status,
            settings: settings.clone(),
            variables: chart.vars.iter().map(|v| v.name.clone()).collect(),
            primaries: chart.vars.iter().enumerate().filter(|(_, v)| v.role == VarRole::Primary).map(|(i, _)| i).collect(),
            joint_names: names,
            fixed_joints: p.linkage.fixed_joints().to_vec(),
            traces: vec![],
            boxes,
            clusters: set.clusters.len(),
            stats,
        },
        proven: certified_clusters,
        undecided,
        summary,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;
    use crate::app::{classify, load};
    use crate::model::urdf;
    use std::f64::consts::{PI, TAU};

    const FOUR_BAR: &str = include_str!("../../urdf/four_bar.urdf");

    #[test]
    fn four_bar_with_a_fixed_crank_has_two_assembly_modes() {
        let m = urdf::parse(FOUR_BAR).expect("bundled");
        let a = load(&m, &[("crank_joint".into(), 0.5)], &[("coupler".into(), 2.0, 1.0)]).expect("planar");
        assert_eq!(a.kind(), MechanismKind::PlanarLinkage);
        let settings = SolverSettings { sigma: 1e-5, ..Default::default() };
        let r = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(r.clusters, 2);
        let modes = r.assembly_modes();
        assert_eq!(modes.len(), 2);
        // Each mode's own joint values classify into its own component.
        for m in &modes {
            let values: Vec<f64> = r.joint_names.iter().map(|n| m.joints.iter().find(|(k, _)| k == n).expect("free joint").1).collect();
            let c = classify(&r, &values, &a.periodic(), None);
            assert!(c.inside, "{m:?}");
            assert_eq!(c.component, Some(m.cluster));
        }
        assert_eq!(r.traces, vec!["coupler@2,1".to_string()]);
    }

    #[test]
    fn a_spatial_linkage_loads_on_the_spatial_builder_and_solves_again() {
        let m = urdf::parse(include_str!("../../urdf/rssr.urdf")).expect("bundled");
        let a = load(&m, &[("crank_joint".into(), 0.7)], &[]).expect("spatial");
        assert_eq!(a.kind(), MechanismKind::SpatialLinkage);
        assert!(a.limitation().contains("not planar"), "{}", a.limitation());
        let settings = SolverSettings { sigma: 1e-6, ..Default::default() };
        let r = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        // The RSSR's two assembly modes, each proven.
        assert_eq!((r.clusters, r.assembly_modes().len()), (2, 2));
        assert!(r.boxes.iter().all(|b| b.status == BoxStatus::Unique), "{:?}", r.boxes.iter().map(|b| b.status).collect::<Vec<_>>());
        let again = a.solve(&[("crank_joint".into(), 0.2)], &settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!((again.analysis.as_str(), again.clusters), ("solve", 2));
    }

    /// The bundled four-bar (d 4, crank a 1.5, coupler b 4, rocker c 3.5) with its rocker
    /// actuated through a `<transmission>`.
    fn four_bar_rocker_driven() -> String {
        FOUR_BAR.replace("</robot>", "<transmission name=\"drive\"><type>transmission_interface/SimpleTransmission</type><joint name=\"rocker_joint\"/></transmission></robot>")
    }

    /// The four-bar's configuration at rocker angle `t4` on branch `sign` (free joints in the
    /// analysis's order: crank, coupler, rocker, loop), by the law of cosines; `None` when the
    /// loop does not close there.
    fn four_bar_at(t4: f64, sign: f64) -> Option<Vec<f64>> {
        let (d, a, b, c) = (4.0f64, 1.5f64, 4.0f64, 3.5f64);
        let (bx, by) = (d + c * t4.cos(), c * t4.sin());
        let r2 = bx * bx + by * by;
        // |B − A| = b with A = a(cos θ2, sin θ2): cos(θ2 − φ) = (a² + r² − b²) / (2 a r).
        let k = (a * a + r2 - b * b) / (2.0 * a * r2.sqrt());
        if k.abs() > 1.0 {
            return None;
        }
        let t2 = by.atan2(bx) + sign * k.acos();
        let t3 = (by - a * t2.sin()).atan2(bx - a * t2.cos());
        let wrap = |x: f64| (x + PI).rem_euclid(TAU) - PI;
        Some(vec![wrap(t2), wrap(t3 - t2), wrap(t4), wrap(t4 - t3)])
    }

    /// Joint-space distance with angles compared modulo 2π.
    fn angle_distance(p: &[f64], q: &[f64]) -> f64 {
        p.iter().zip(q).map(|(x, y)| ((x - y).rem_euclid(TAU)).min(TAU - (x - y).rem_euclid(TAU)).powi(2)).sum::<f64>().sqrt()
    }

    #[test]
    fn singular_sets_are_the_closed_form_dead_centres_and_classify_bounds_the_distance_to_them() {
        let xml = four_bar_rocker_driven();
        let m = urdf::parse(&xml).expect("bundled");
        let a = crate::app::load_urdf(&m, &[], &[]).expect("planar");
        assert_eq!(a.services(), vec![Service::Solve, Service::Singularities, Service::Classify]);
        let query = SingularityQuery { precision: 1e-6, nodes: false, max_boxes: 1_000_000, timeout: None, threads: 1 };
        let r = a.singularities(&query).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        let loops = r.loops.as_ref().expect("a linkage's sets");
        assert_eq!(loops.actuated, vec!["rocker_joint".to_string()]);
        assert!(loops.actuated_source.contains("<transmission>"), "{}", loops.actuated_source);
        let kinds: Vec<&str> = loops.sets.iter().map(|s| s.kind).collect();
        assert_eq!(kinds, vec!["cspace", "input", "output"]);
        assert!(loops.complete() && r.status == Status::Finished, "{}", r.summary);
        // Rocker driving: type II where crank and coupler are in line, |B − O2| = a + b or
        // b − a, B = (d, 0) + c(cos θ4, sin θ4): cos θ4 = (l² − d² − c²) / (2 d c).
        let (d, a_, b, c) = (4.0f64, 1.5f64, 4.0f64, 3.5f64);
        let mut dead: Vec<Vec<f64>> = Vec::new();
        for l in [a_ + b, b - a_] {
            let t4 = ((l * l - d * d - c * c) / (2.0 * d * c)).acos();
            for t4 in [t4, -t4] {
                // In line: both branches meet there; take the one that closes best.
                let q = [1.0, -1.0].iter().filter_map(|&s| four_bar_at(t4, s)).next().expect("closes at a dead centre");
                dead.push(q);
            }
        }
        let input = &loops.sets[1];
        assert_eq!((input.proven, input.boxes.clusters, input.undecided), (4, 4, 0), "{}", input.summary);
        for q in &dead {
            let holds = input.boxes.boxes.iter().any(|bx| bx.joints[2][0] - 1e-9 <= q[2] && q[2] <= bx.joints[2][1] + 1e-9);
            assert!(holds, "dead centre at rocker {} in no input box", q[2]);
        }
        // No bifurcation, no type-I singularity with every passive joint as output (proven empty).
        assert_eq!((loops.sets[0].boxes.boxes.len(), loops.sets[2].boxes.boxes.len()), (0, 0), "{} / {}", loops.sets[0].summary, loops.sets[2].summary);

        let settings = SolverSettings { sigma: 1e-2, ..Default::default() };
        let cspace = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        // Configurations on the curve, near and far from the dead centres: the bound is never
        // above the true distance (the set being exactly the four dead centres), and close to it.
        let mut checked = 0;
        for q0 in &dead {
            // Past a dead centre the rocker cannot go (it is one of its extremes): one side closes.
            for delta in [0.0, 1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.5].into_iter().flat_map(|x: f64| [x, -x]) {
                for sign in [1.0, -1.0] {
                    let Some(q) = four_bar_at(q0[2] + delta, sign) else { continue };
                    let cl = a.classify(&q, Some(&cspace), Some(&r)).expect("classifies");
                    assert!(cl.inside, "{q:?} is on the curve (loop joint convention) but classified outside: {cl:?}");
                    let bound = cl.singular_distance.expect("complete sets give a bound");
                    let truth = dead.iter().map(|p| angle_distance(&q, p)).fold(f64::INFINITY, f64::min);
                    assert!(bound <= truth, "{q:?}: bound {bound} above the true distance {truth}");
                    assert!(bound >= truth - 1e-4, "{q:?}: bound {bound} far below the true distance {truth}");
                    assert!(cl.note.contains("input set"), "{}", cl.note);
                    checked += 1;
                }
            }
        }
        assert!(checked >= 40, "{checked} configurations checked");
        // Without a complete singular search there is no bound, and the note says why.
        let short = a.singularities(&SingularityQuery { max_boxes: 3, ..query }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        let cl = a.classify(&dead[0], Some(&cspace), Some(&short)).expect("classifies");
        assert_eq!(cl.singular_distance, None);
        assert!(cl.note.contains("did not complete"), "{}", cl.note);
    }

    #[test]
    fn a_spatial_linkage_serves_its_singular_sets_and_a_bound_on_their_distance() {
        // The RSSR driven by its crank (a transmission): the crank turns fully (no input
        // singularity), no bifurcation, and the rocker (the passive tree joint, the default
        // output) has 4 dead centres, the closed form of `tests/spatial_singularities.rs`.
        let xml = include_str!("../../urdf/rssr.urdf").replace("</robot>", "<transmission name=\"drive\"><type>transmission_interface/SimpleTransmission</type><joint name=\"crank_joint\"/></transmission></robot>");
        let m = urdf::parse(&xml).expect("bundled");
        let a = crate::app::load_urdf(&m, &[], &[]).expect("spatial");
        assert_eq!(a.kind(), MechanismKind::SpatialLinkage);
        let query = SingularityQuery { precision: 1e-6, nodes: false, max_boxes: 1_000_000, timeout: None, threads: 1 };
        let r = a.singularities(&query).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        let loops = r.loops.as_ref().expect("a linkage's sets");
        assert_eq!(loops.actuated, vec!["crank_joint".to_string()]);
        let got: Vec<(&str, usize, usize)> = loops.sets.iter().map(|s| (s.kind, s.boxes.clusters, s.proven)).collect();
        assert_eq!(got, vec![("cspace", 0, 0), ("input", 0, 0), ("output", 4, 4)], "{}", r.summary);
        assert!(loops.complete(), "{}", r.summary);
        let cspace = a.configuration_space(&SolverSettings { sigma: 1e-3, ..Default::default() }).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        let names = a.free_joints();
        let values: Vec<f64> = names.iter().map(|n| if n == "crank_joint" { 0.0 } else { 0.645167 }).collect();
        let c = a.classify(&values, Some(&cspace), Some(&r)).expect("classifies");
        // At a dead centre (to six digits): the bound is known, and small.
        let d = c.singular_distance.expect("complete sets give a bound");
        assert!(d < 1e-5, "{d}: {}", c.note);
    }

    #[test]
    fn bad_requests_fail_before_any_run() {
        let m = urdf::parse(FOUR_BAR).expect("bundled");
        let a = load(&m, &[], &[]).expect("planar");
        let err = |e: Result<Box<dyn PreparedRun>, JobError>| e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err(a.solve(&[("nope".into(), 1.0)], &SolverSettings::default())).contains("no joint or loop named 'nope'"));
        assert!(err(a.solve(&[("crank_joint".into(), f64::NAN)], &SolverSettings::default())).contains("not a finite number"));
        assert!(err(a.solve(&[], &SolverSettings { sigma: f64::NAN, ..Default::default() })).contains("sigma"));
        // A planar linkage answers singularities; bad queries are refused before a run.
        let query = crate::app::SingularityQuery { precision: 1e-4, nodes: true, max_boxes: 1000, timeout: None, threads: 1 };
        assert!(a.singularities(&SingularityQuery { precision: 2.0, ..query.clone() }).err().map(|e| e.to_string()).unwrap_or_default().contains("precision must be a number in (0, 1)"));
        assert!(a.singularities(&SingularityQuery { max_boxes: 0, ..query.clone() }).err().map(|e| e.to_string()).unwrap_or_default().contains("max_boxes must be at least 1"));
        let bad = LinkageAnalysis::new(&m, &[], &[]).expect("planar").with_actuation(Actuation::given(vec!["nope".into()]));
        assert!(bad.singularities(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("'nope' is not a free joint"));
        // A spatial linkage answers too, with the same checks before a run.
        let spatial = load(&urdf::parse(include_str!("../../urdf/rssr.urdf")).expect("bundled"), &[], &[]).expect("spatial");
        assert!(spatial.singularities(&query).is_ok());
        let bad = LinkageAnalysis::new(&urdf::parse(include_str!("../../urdf/spherical_four_bar.urdf")).expect("bundled"), &[], &[]).expect("spatial").with_actuation(Actuation::given(vec!["loop_coupler_rocker".into()]));
        assert!(bad.singularities(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("is a loop joint of a spatial linkage"));
        let query = crate::app::IkQuery { point: [1.0, 0.0, 0.0], precision: 1e-3, max_boxes: 1000, timeout: None, threads: 1 };
        assert!(a.inverse_kinematics(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("inverse_kinematics is not available"));
    }
}

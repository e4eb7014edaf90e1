//! The parallel-platform analysis: the assembly modes of an octahedral platform with its legs
//! fixed, as the enclosure of the unknown squared distances (`PlatformProblem` ->
//! `CayleyMenger`, shared variables with the redundant determinants, clipped by
//! `TrapezoidClip`). The boxes are those of `linkspace distances --redundant --json` for the same
//! input.
//!
//! Joint space is in metres (REP 103), as the node publishes it: the "joints" of a box are the
//! unknown distances `d(a,b)` (enclosed by the square roots of the variables `r(a,b) = d(a,b)²`,
//! outward rounded), the fixed legs are their lengths, and a Solve request's legs are lengths
//! (squared as intervals, so the problem solved is exactly the one with those lengths). The legs
//! given when the mechanism is loaded (`linkspace serve --fix`) are squared lengths, as
//! `linkspace distances --fix` takes them.
//!
//! Runs are certified as the CLI's (`distances::solve`): each certified placement (Krawczyk in
//! coordinates; a placement and its mirror image share their distances) is published as a
//! `Unique` box over the distances (the enclosure of its distances over the certified box), in
//! the cluster it was attributed to; the solution boxes of a cluster left undecided are
//! published `Undecided`, those of settled clusters `Solution`.

use super::results::{limits_of, unexpected, JobRun};
use super::{Analysis, AnalysisError, Answer, BoxSetResult, DistancesAnswer, DistancesJob, Input, Job, JobError, MechanismKind, PreparedRun, ResultBox, Service};
use std::sync::Arc;
use crate::kernel::contract::FaceBounds;
use crate::model::Mechanism;
use crate::formulate::cayley_menger::{BuildOptions, CayleyMenger, Formulation};
use super::distances::DistancesRun;
use crate::formulate::{LegValues, PlatformError};
use crate::analyses::distances::Choice;
use crate::kernel::interval::{bounds, Interval, IntervalBox};
use std::collections::BTreeMap;
use crate::kernel::search::{BoxStatus, SolverSettings};
use crate::kernel::system::VarRole;

/// The formulation the node uses: the fastest of `bench-distances` (shared variables, redundant
/// determinants, Bernstein corners).
const BUILD: BuildOptions = BuildOptions { formulation: Formulation::Shared, redundant: true };
const FACES: FaceBounds = FaceBounds::Corners;

/// A parallel platform with its legs fixed, as loaded.
#[derive(Clone, Debug)]
pub struct PlatformAnalysis {
    mechanism: Mechanism,
    /// The squared leg lengths it was loaded with.
    squared: Vec<(String, f64)>,
    /// The unknown distances `d(a,b)` of the load-time problem (they do not depend on the legs).
    unknowns: Vec<String>,
    /// The mechanism as the front door takes it: every run is a `Job` prepared on it.
    input: Arc<Input>,
}

/// The name of the distance whose square is the unknown `r(a,b)`.
fn distance_name(cm: &CayleyMenger, a: usize, b: usize) -> String {
    format!("d({},{})", cm.problem.points[a].name, cm.problem.points[b].name)
}

/// The lengths, in metres, of legs given as squared lengths.
fn lengths(squared: &[(String, f64)]) -> Vec<(String, f64)> {
    squared.iter().map(|(n, v)| (n.clone(), v.max(0.0).sqrt())).collect()
}

/// The enclosure of `√x` (the distance whose square `x` encloses), as bounds.
fn distance_bounds(x: Interval) -> [f64; 2] {
    bounds(x.sqrt())
}

impl PlatformAnalysis {
    /// Reads the platform of `mechanism` with the squared leg lengths `fixed`.
    pub fn new(mechanism: &Mechanism, fixed: &[(String, f64)]) -> Result<Self, AnalysisError> {
        let run = DistancesRun::platform_with(mechanism, fixed, LegValues::Squared)?;
        let cm = CayleyMenger::build(run.problem(), BUILD).map_err(PlatformError::Distance)?;
        let unknowns = cm.unknowns.iter().map(|u| distance_name(&cm, u.a, u.b)).collect();
        Ok(Self { mechanism: mechanism.clone(), squared: fixed.to_vec(), unknowns, input: Arc::new(Input::Mechanism(mechanism.clone())) })
    }

    /// The node's `distances` job: the legs `fixed` as `legs` says, `settings`; its box set
    /// named `analysis`, over the distances in metres.
    fn distances_run(&self, fixed: &[(String, f64)], legs: LegValues, settings: &SolverSettings, analysis: &'static str) -> Result<Box<dyn PreparedRun>, JobError> {
        let job = Job::Distances(DistancesJob { fixed: fixed.to_vec(), legs, precision: settings.sigma, rho: Some(settings.rho), redundant: BUILD.redundant, formulation: Choice::Shared, faces: FACES });
        let lengths = match legs {
            LegValues::Squared => lengths(fixed),
            LegValues::Lengths => fixed.to_vec(),
        };
        JobRun::new(&self.input, job, limits_of(settings), settings.threads, move |answer| match answer {
            Answer::Distances(d) => Ok(box_set(&d, lengths, analysis)),
            other => Err(unexpected(&other, analysis)),
        })
    }
}

impl Analysis for PlatformAnalysis {
    fn mechanism(&self) -> &str {
        &self.mechanism.name
    }

    fn kind(&self) -> MechanismKind {
        MechanismKind::ParallelPlatform
    }

    fn services(&self) -> Vec<Service> {
        vec![Service::Solve, Service::Classify]
    }

    fn limitation(&self) -> String {
        "a parallel platform: only its assembly modes (the unknown squared distances for fixed legs) are analysed so far (no singularity or inverse-kinematics analysis for platforms yet)".to_string()
    }

    fn free_joints(&self) -> Vec<String> {
        self.unknowns.clone()
    }

    fn fixed_joints(&self) -> Vec<(String, f64)> {
        lengths(&self.squared)
    }

    fn periodic(&self) -> Vec<bool> {
        // Distances, not angles.
        vec![false; self.unknowns.len()]
    }

    fn configuration_space(&self, settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        self.distances_run(&self.squared, LegValues::Squared, settings, "configuration_space")
    }

    fn solve(&self, fixed: &[(String, f64)], settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        // A request's legs are lengths (REP 103).
        self.distances_run(fixed, LegValues::Lengths, settings, "solve")
    }
}

/// The answer of `distances` (the CLI's job, so the published boxes are exactly those of
/// `distances --json`) as the node's box set over the distances; `fixed` are the legs' lengths.
fn box_set(answer: &DistancesAnswer, fixed: Vec<(String, f64)>, analysis: &str) -> BoxSetResult {
    let c = &answer.certified;
    let joint_names: Vec<String> = c.cm.unknowns.iter().map(|u| distance_name(&c.cm, u.a, u.b)).collect();
    // The boxes and distances of `distances --json` for the same run, read off it directly.
    let convert = |b: &IntervalBox, status: BoxStatus, cluster: Option<usize>| {
        let squared: BTreeMap<String, Interval> = c.cm.unknown_intervals(b).into_iter().collect();
        ResultBox {
            status,
            bounds: b.dims.iter().map(|&x| bounds(x)).collect(),
            joints: c.cm.unknowns.iter().map(|u| squared.get(&u.name).map_or([f64::NAN, f64::NAN], |&x| distance_bounds(x))).collect(),
            level: b.level,
            cluster,
            traces: Vec::new(),
        }
    };
    let settled = |k: usize| c.clusters.get(k).is_some_and(|v| v.undecided.is_none());
    let mut boxes: Vec<ResultBox> = c.solutions.iter().zip(&c.cluster).map(|(b, &k)| convert(b, if settled(k) { BoxStatus::Solution } else { BoxStatus::Undecided }, Some(k))).collect();
    // Certified placements: the distances of a placement and of its mirror image are one
    // box (the mirror image is the same solution of the distance system).
    if let Some(pl) = &c.placed {
        let mut seen: Vec<Vec<[f64; 2]>> = Vec::new();
        for root in &c.roots {
            let squared: Vec<Interval> = c.cm.unknowns.iter().map(|u| pl.distance_over(u.a, u.b, &root.certified)).collect();
            let d: Vec<[f64; 2]> = squared.iter().map(|&x| bounds(x)).collect();
            let joints: Vec<[f64; 2]> = squared.iter().map(|&x| distance_bounds(x)).collect();
            let overlaps = |e: &Vec<[f64; 2]>| e.iter().zip(&d).all(|(a, b)| a[0] <= b[1] && b[0] <= a[1]);
            if seen.iter().any(overlaps) {
                continue;
            }
            seen.push(d.clone());
            let mut bounds = vec![[f64::NAN, f64::NAN]; c.cm.system.vars.len()];
            for (u, x) in c.cm.unknowns.iter().zip(&d) {
                bounds[u.var] = *x;
            }
            boxes.push(ResultBox { status: BoxStatus::Unique, bounds, joints, level: 0, cluster: Some(root.cluster), traces: Vec::new() });
        }
    }
    boxes.extend(c.undecided.iter().map(|b| convert(b, BoxStatus::Undecided, None)));
    BoxSetResult {
        mechanism: c.cm.problem.name.clone(),
        analysis: analysis.to_string(),
        status: c.status,
        settings: answer.settings.clone(),
        variables: c.cm.system.vars.iter().map(|v| v.name.clone()).collect(),
        primaries: c.cm.system.vars.iter().enumerate().filter(|(_, v)| v.role == VarRole::Primary).map(|(i, _)| i).collect(),
        joint_names,
        fixed_joints: fixed,
        traces: Vec::new(),
        boxes,
        clusters: c.clusters.len(),
        stats: c.stats.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;
    use crate::app::load;
    use crate::model::urdf;
    use crate::analyses::distances::solve as certified_solve;
    use crate::formulate::PlatformProblem;
    use crate::edges::report::distances::report_certified;
    use crate::kernel::search::Status;

    const OCTAHEDRAL: &str = include_str!("../../urdf/octahedral.urdf");
    const LEGS: [&str; 6] = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"];

    fn config_a() -> Vec<(String, f64)> {
        LEGS.iter().map(|l| l.to_string()).zip([4.25, 5.75, 4.25, 5.75, 4.25, 5.75]).collect()
    }

    #[test]
    fn octahedral_configuration_space_is_the_cli_enclosure() {
        let m = urdf::parse(OCTAHEDRAL).expect("bundled");
        let fixed = config_a();
        let a = load(&m, &fixed, &[]).expect("platform");
        assert_eq!(a.kind(), MechanismKind::ParallelPlatform);
        // The CLI's defaults (`linkspace distances --redundant`).
        let settings = SolverSettings { sigma: 0.01, rho: 0.99, ..Default::default() };
        let r = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(r.status, Status::Finished);
        assert_eq!(r.clusters, 2);
        // The CLI path (`linkspace distances --redundant`), built independently here.
        let p = PlatformProblem::new(&m, &fixed).expect("platform");
        let c = certified_solve(&p.distances, Choice::Shared, true, FACES, settings.clone(), &AtomicBool::new(false)).expect("solves");
        let rep = report_certified(&c, Some(&p), fixed.iter().cloned().collect(), FACES, &settings);
        assert_eq!(rep.clusters, 2);
        assert!(rep.complete);
        let published: Vec<&Vec<[f64; 2]>> = r.boxes.iter().filter(|b| b.status == BoxStatus::Solution).map(|b| &b.bounds).collect();
        let cli: Vec<&Vec<[f64; 2]>> = rep.solutions.iter().map(|s| &s.box_).collect();
        assert_eq!(published, cli);
        // Two assembly modes, each proven (with its mirror image: one distance solution), each
        // inside its cluster's boxes.
        let unique: Vec<_> = r.boxes.iter().filter(|b| b.status == BoxStatus::Unique).collect();
        assert_eq!(unique.len(), 2);
        for u in &unique {
            let k = u.cluster.expect("attributed");
            assert!(r.boxes.iter().filter(|b| b.status == BoxStatus::Solution && b.cluster == Some(k)).any(|b| b.joints.iter().zip(&u.joints).all(|(a, x)| a[0] <= x[1] && x[0] <= a[1])));
        }
        assert!(!r.boxes.iter().any(|b| b.status == BoxStatus::Undecided));
        assert_eq!(r.joint_names.len(), r.boxes[0].joints.len());
        assert!(r.boxes.iter().all(|b| b.joints.iter().all(|j| j[0] <= j[1])));
        // Joint space in metres: the fixed legs are lengths, and every published distance box
        // holds the square root of its squared-distance bounds.
        assert_eq!(r.fixed_joints, fixed.iter().map(|(n, v)| (n.clone(), v.sqrt())).collect::<Vec<_>>());
        assert!(r.joint_names.iter().all(|n| n.starts_with("d(")), "{:?}", r.joint_names);
        for b in r.boxes.iter().filter(|b| b.status == BoxStatus::Solution) {
            for (k, j) in b.joints.iter().enumerate() {
                let var = r.variables.iter().position(|v| *v == r.joint_names[k].replacen("d(", "r(", 1)).expect("the squared distance's variable");
                let squared = b.bounds[var];
                assert!(j[0] * j[0] <= squared[0] * (1.0 + 1e-15) && j[1] * j[1] >= squared[1] * (1.0 - 1e-15), "{j:?} vs {squared:?}");
            }
        }
        // Re-solving with other legs, given as lengths (metres): configuration b.
        let b: Vec<(String, f64)> = LEGS.iter().map(|l| (l.to_string(), f64::sqrt(4.75))).collect();
        let rb = a.solve(&b, &settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {}).expect("runs");
        assert_eq!(rb.analysis, "solve");
        assert_eq!(rb.fixed_joints, b);
        assert!(rb.clusters > 0);
        assert_eq!(rb.boxes.iter().filter(|b| b.status == BoxStatus::Unique).count(), 8, "configuration b: 8 assembly modes");
    }

    #[test]
    fn octahedral_without_legs_is_unsupported_and_bad_legs_fail() {
        let m = urdf::parse(OCTAHEDRAL).expect("bundled");
        let a = load(&m, &[], &[]).expect("listed");
        assert_eq!(a.kind(), MechanismKind::Unsupported);
        let err = a.configuration_space(&SolverSettings::default()).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err.contains("legs are not fixed") && err.contains("--fix"), "{err}");
        let mut partial = config_a();
        partial.pop();
        assert!(load(&m, &partial, &[]).err().map(|e| e.to_string()).unwrap_or_default().contains("leg 'leg35' has no --fix value"));
        assert!(load(&m, &[("nope".into(), 1.0)], &[]).err().map(|e| e.to_string()).unwrap_or_default().contains("no leg"));
        let a = load(&m, &config_a(), &[]).expect("platform");
        let query = crate::app::SingularityQuery { precision: 1e-4, nodes: false, max_boxes: 10, timeout: None, threads: 1 };
        assert!(a.singularities(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("not available"));
        let lengths: Vec<(String, f64)> = config_a().into_iter().map(|(n, v)| (n, v.sqrt())).collect();
        assert!(a.solve(&lengths, &SolverSettings { sigma: -1.0, ..Default::default() }).err().map(|e| e.to_string()).unwrap_or_default().contains("sigma"));
    }
}

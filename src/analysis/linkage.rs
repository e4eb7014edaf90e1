//! The linkage analysis: the configuration space of a closed-loop mechanism (`problems::Linkage`:
//! the planar builder when it accepts the mechanism, the spatial one otherwise, chosen as
//! `solve --model auto` does), re-solved on request with other fixed joints or settings. The
//! result is the same as `linkspace solve --json` for the same input.

use super::{Analysis, AnalysisError, BoxSetResult, PreparedRun, ResultBox, Service};
use crate::interval::components;
use crate::model::{JointKind, Mechanism};
use crate::problems::choice::TracedPoint;
use crate::problems::{Linkage, LinkageError, ModelChoice};
use crate::search::{BoxStatus, Progress, SolverSettings};
use crate::system::VarRole;
use std::sync::atomic::AtomicBool;

/// A closed-loop linkage, as loaded.
#[derive(Clone, Debug)]
pub struct LinkageAnalysis {
    mechanism: Mechanism,
    fixed: Vec<(String, f64)>,
    traces: Vec<TracedPoint>,
    /// The problem with the load-time fixed joints: names the free joints and the model.
    problem: Linkage,
}

impl LinkageAnalysis {
    /// Formulates `mechanism` with the load-time `fixed` joints and traced points
    /// `(link, x, y)` in the plane of the link's frame.
    pub fn new(mechanism: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Self, LinkageError> {
        let traces: Vec<TracedPoint> = traces.iter().map(|(l, x, y)| (l.clone(), [*x, *y, 0.0], format!("{l}@{x},{y}"))).collect();
        let problem = Linkage::build(mechanism, ModelChoice::Auto, fixed, &traces)?;
        Ok(Self { mechanism: mechanism.clone(), fixed: fixed.to_vec(), traces, problem })
    }

    fn prepare(&self, problem: Linkage, settings: &SolverSettings, analysis: &str) -> Result<Box<dyn PreparedRun>, AnalysisError> {
        // Validate now, so that a bad request is answered before any thread starts.
        problem.solver(settings.clone())?;
        Ok(Box::new(LinkageRun { problem, settings: settings.clone(), analysis: analysis.to_string() }))
    }
}

impl Analysis for LinkageAnalysis {
    fn mechanism(&self) -> &str {
        &self.mechanism.name
    }

    fn kind(&self) -> &'static str {
        self.problem.kind()
    }

    fn services(&self) -> Vec<Service> {
        vec![Service::Solve, Service::Classify]
    }

    fn limitation(&self) -> String {
        match &self.problem {
            Linkage::Planar(_) => "a planar linkage: only its configuration space is analysed so far (singular sets: `linkspace loop-singularities`)".to_string(),
            Linkage::Spatial(_, why) => format!("a spatial linkage ({why}): only its configuration space is analysed so far"),
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

    fn configuration_space(&self, settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, AnalysisError> {
        self.prepare(self.problem.clone(), settings, "configuration_space")
    }

    fn solve(&self, fixed: &[(String, f64)], settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, AnalysisError> {
        let problem = Linkage::build(&self.mechanism, ModelChoice::Auto, fixed, &self.traces)?;
        self.prepare(problem, settings, "solve")
    }
}

/// A validated linkage run.
struct LinkageRun {
    problem: Linkage,
    settings: SolverSettings,
    analysis: String,
}

impl PreparedRun for LinkageRun {
    fn run(self: Box<Self>, cancel: &AtomicBool, progress: &mut dyn FnMut(&Progress)) -> BoxSetResult {
        let solver = self.problem.solver(self.settings.clone()).expect("invariant: validated when prepared");
        let e = solver.enclose(cancel, progress);
        // The CLI's report, so the published boxes are exactly those of `solve --json`.
        let report = self.problem.report(&self.settings, e.status, e.stats.clone(), &e.solutions, &e.unique, &e.undecided);
        let labels = components(&e.solutions).0;
        let joint_names = self.problem.free_joints().to_vec();
        let traces = self.problem.trace_names();
        let convert = |record: &crate::report::BoxRecord, status: BoxStatus, cluster: Option<usize>| ResultBox {
            status,
            bounds: record.box_.clone(),
            joints: joint_names.iter().map(|n| record.joints.get(n).copied().unwrap_or([f64::NAN, f64::NAN])).collect(),
            level: record.level,
            cluster,
            traces: traces.iter().map(|t| record.traces.get(t).map_or([[f64::NAN; 2]; 2], |p| [p.x, p.y])).collect(),
        };
        let mut boxes: Vec<ResultBox> = report.solutions.iter().zip(&labels).map(|(r, &l)| convert(r, if r.unique { BoxStatus::Unique } else { BoxStatus::Solution }, Some(l))).collect();
        boxes.extend(report.undecided.iter().map(|r| convert(r, BoxStatus::Undecided, None)));
        BoxSetResult {
            mechanism: report.mechanism,
            analysis: self.analysis,
            status: report.status,
            settings: report.settings,
            variables: report.variables.iter().map(|v| v.name.clone()).collect(),
            primaries: report.variables.iter().enumerate().filter(|(_, v)| v.role == VarRole::Primary).map(|(i, _)| i).collect(),
            joint_names,
            fixed_joints: report.fixed_joints.into_iter().collect(),
            traces,
            boxes,
            clusters: report.clusters,
            stats: report.stats,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{classify, load};
    use crate::model::urdf;

    const FOUR_BAR: &str = include_str!("../../urdf/four_bar.urdf");

    #[test]
    fn four_bar_with_a_fixed_crank_has_two_assembly_modes() {
        let m = urdf::parse(FOUR_BAR).expect("bundled");
        let a = load(&m, &[("crank_joint".into(), 0.5)], &[("coupler".into(), 2.0, 1.0)]).expect("planar");
        assert_eq!(a.kind(), "planar_linkage");
        let settings = SolverSettings { sigma: 1e-5, ..Default::default() };
        let r = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
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
        assert_eq!(a.kind(), "spatial_linkage");
        assert!(a.limitation().contains("not planar"), "{}", a.limitation());
        let settings = SolverSettings { sigma: 1e-6, ..Default::default() };
        let r = a.configuration_space(&settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        // The RSSR's two assembly modes, each proven.
        assert_eq!((r.clusters, r.assembly_modes().len()), (2, 2));
        assert!(r.boxes.iter().all(|b| b.status == BoxStatus::Unique), "{:?}", r.boxes.iter().map(|b| b.status).collect::<Vec<_>>());
        let again = a.solve(&[("crank_joint".into(), 0.2)], &settings).expect("valid").run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!((again.analysis.as_str(), again.clusters), ("solve", 2));
    }

    #[test]
    fn bad_requests_fail_before_any_run() {
        let m = urdf::parse(FOUR_BAR).expect("bundled");
        let a = load(&m, &[], &[]).expect("planar");
        let err = |e: Result<Box<dyn PreparedRun>, AnalysisError>| e.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(err(a.solve(&[("nope".into(), 1.0)], &SolverSettings::default())).contains("no joint or loop named 'nope'"));
        assert!(err(a.solve(&[("crank_joint".into(), f64::NAN)], &SolverSettings::default())).contains("not a finite number"));
        assert!(err(a.solve(&[], &SolverSettings { sigma: f64::NAN, ..Default::default() })).contains("sigma"));
        let query = crate::analysis::SingularityQuery { precision: 1e-4, nodes: true, max_boxes: 1000, timeout: None, threads: 1 };
        assert!(a.singularities(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("singularities is not available for this mechanism"));
        let query = crate::analysis::IkQuery { point: [1.0, 0.0, 0.0], precision: 1e-3, max_boxes: 1000, threads: 1 };
        assert!(a.inverse_kinematics(&query).err().map(|e| e.to_string()).unwrap_or_default().contains("inverse_kinematics is not available"));
    }
}

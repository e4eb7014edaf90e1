//! The node's view of one loaded mechanism: what kind it is, which services it answers, its
//! joints, and its load-time runs (`Analysis`), with `load`, which picks the analysis that fits
//! a `Mechanism`: `Manip3rAnalysis` (a serial arm through its 3R positioning structure),
//! `LinkageAnalysis` (planar or spatial closed-loop linkages), `PlatformAnalysis` (an octahedral
//! platform) or `Unsupported`, which answers every query with `AnalysisError::NotAvailable`.

use super::arm_analysis::Manip3rAnalysis;
use super::linkage::LinkageAnalysis;
use super::loops::Actuation;
use super::platform::PlatformAnalysis;
use super::results::{classify, BoxSetResult, Classification, IkQuery, IkResult, PreparedRun, SingularityQuery, SingularityResult};
use crate::formulate::{LinkageError, PlatformError};
use super::JobError;
use crate::kernel::search::{SolveError, SolverSettings};
use crate::model::Mechanism;
use thiserror::Error;

/// What kind of mechanism an analysis answers for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MechanismKind {
    /// A serial arm, analysed through its 3R positioning structure.
    Manipulator3R,
    /// A serial arm of seven revolute joints, analysed through its self-motion sets.
    Manipulator7R,
    /// A closed-loop linkage on the planar builder.
    PlanarLinkage,
    /// A closed-loop linkage on the spatial builder.
    SpatialLinkage,
    /// An octahedral platform on the Cayley–Menger formulation.
    ParallelPlatform,
    /// Outside every analysis (loaded and listed, with why).
    Unsupported,
}

impl MechanismKind {
    /// The name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            MechanismKind::Manipulator3R => "manipulator_3r",
            MechanismKind::Manipulator7R => "manipulator_7r",
            MechanismKind::PlanarLinkage => "planar_linkage",
            MechanismKind::SpatialLinkage => "spatial_linkage",
            MechanismKind::ParallelPlatform => "parallel_platform",
            MechanismKind::Unsupported => "unsupported",
        }
    }
}

/// The queries a mechanism can be asked; `Analysis::services` lists those it answers with
/// real results.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Service {
    /// Solve again with other settings or fixed joints.
    Solve,
    /// Singular curves, cusps, nodes.
    Singularities,
    /// Certified inverse kinematics of a workspace point.
    InverseKinematics,
    /// Which component of the configuration space a configuration belongs to.
    Classify,
    /// Certified inverse kinematics of a six-revolute arm's tip pose.
    InverseKinematics6,
    /// A joint path checked against the arm's singular sets.
    PathCheck,
    /// Where the arm's collision bodies meet.
    Collisions,
    /// Every configuration of a seven-revolute arm at a tip pose.
    SelfMotion,
}

impl Service {
    /// The name used in messages and service names.
    pub fn name(self) -> &'static str {
        match self {
            Service::Solve => "solve",
            Service::Singularities => "singularities",
            Service::InverseKinematics => "inverse_kinematics",
            Service::Classify => "classify",
            Service::InverseKinematics6 => "inverse_kinematics6",
            Service::PathCheck => "path_check",
            Service::Collisions => "collisions",
            Service::SelfMotion => "self_motion",
        }
    }
}

/// Why a query cannot be answered.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum AnalysisError {
    /// The mechanism's analysis has no math for this query (yet).
    #[error("{service} is not available for this mechanism ('{mechanism}', {kind}): {reason}")]
    NotAvailable {
        /// the query
        service: &'static str,
        /// the mechanism
        mechanism: String,
        /// its kind
        kind: &'static str,
        /// why
        reason: String,
    },
    /// The mechanism cannot be formulated as asked (bad fixed joints, loop cannot close...).
    #[error(transparent)]
    Linkage(#[from] LinkageError),
    /// The platform cannot be formulated as asked (legs not fixed, outside their limits...).
    #[error(transparent)]
    Platform(#[from] PlatformError),
    /// Settings out of range.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The singular sets of a linkage cannot be formulated (bad actuated joints...).
    #[error(transparent)]
    Singular(#[from] crate::formulate::singular::SingularError),
    /// Anything else wrong with the request, named.
    #[error("{0}")]
    BadRequest(String),
    /// The query needs a load-time result that is not there yet (`what`, e.g.
    /// `configuration_space`, is still being computed, or could not be).
    #[error("the {what} is not known yet")]
    NotReady {
        /// the missing result
        what: &'static str,
    },
}

/// What the node can do with one loaded mechanism.
///
/// Every run a query starts is a `Job` prepared by the front door (`app::prepare`) on the
/// mechanism and answered by `Prepared::run`; the analysis says which job a query is and how
/// its `Answer` reads as the node's result. Every query has a default that answers
/// `NotAvailable`, so a new kind of mechanism implements only what its math backs.
pub trait Analysis: Send + Sync {
    /// Robot name.
    fn mechanism(&self) -> &str;
    /// Kind of mechanism.
    fn kind(&self) -> MechanismKind;
    /// The queries answered with real results.
    fn services(&self) -> Vec<Service>;
    /// Why the other queries are not available (shown in their error replies).
    fn limitation(&self) -> String;
    /// Free joints, in file order.
    fn free_joints(&self) -> Vec<String>;
    /// Joints fixed at load time.
    fn fixed_joints(&self) -> Vec<(String, f64)>;
    /// Which free joints are angles (compared modulo 2π), in `free_joints` order.
    fn periodic(&self) -> Vec<bool>;

    /// The run made at load time (the configuration space), with `settings`.
    fn configuration_space(&self, settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        let _ = settings;
        Err(self.not_available(Service::Solve).into())
    }

    /// A new run with other fixed joints (they replace the load-time ones) and settings.
    fn solve(&self, fixed: &[(String, f64)], settings: &SolverSettings) -> Result<Box<dyn PreparedRun>, JobError> {
        let _ = (fixed, settings);
        Err(self.not_available(Service::Solve).into())
    }

    /// The singularity run (singular curves, cusps, nodes).
    fn singularities(&self, query: &SingularityQuery) -> Result<Box<dyn PreparedRun<SingularityResult>>, JobError> {
        let _ = query;
        Err(self.not_available(Service::Singularities).into())
    }

    /// Certified inverse kinematics of a workspace point.
    fn inverse_kinematics(&self, query: &IkQuery) -> Result<Box<dyn PreparedRun<IkResult>>, JobError> {
        let _ = query;
        Err(self.not_available(Service::InverseKinematics).into())
    }

    /// Classifies a configuration, a value per free joint in `free_joints` order, against the
    /// latest load-time results. The default classifies against the configuration space
    /// (`classify`), without a singular distance.
    fn classify(&self, values: &[f64], configuration_space: Option<&BoxSetResult>, singularities: Option<&SingularityResult>) -> Result<Classification, AnalysisError> {
        let _ = singularities;
        let cspace = configuration_space.ok_or(AnalysisError::NotReady { what: "configuration_space" })?;
        Ok(classify(cspace, values, &self.periodic(), None))
    }

    /// The `NotAvailable` error for `service`.
    fn not_available(&self, service: Service) -> AnalysisError {
        AnalysisError::NotAvailable { service: service.name(), mechanism: self.mechanism().to_string(), kind: self.kind().name(), reason: self.limitation() }
    }
}

/// A mechanism no analysis handles yet: loaded and listed, every query answered `NotAvailable`.
#[derive(Clone, Debug)]
pub struct Unsupported {
    name: String,
    joints: Vec<String>,
    reason: String,
}

impl Analysis for Unsupported {
    fn mechanism(&self) -> &str {
        &self.name
    }
    fn kind(&self) -> MechanismKind {
        MechanismKind::Unsupported
    }
    fn services(&self) -> Vec<Service> {
        Vec::new()
    }
    fn limitation(&self) -> String {
        self.reason.clone()
    }
    fn free_joints(&self) -> Vec<String> {
        self.joints.clone()
    }
    fn fixed_joints(&self) -> Vec<(String, f64)> {
        Vec::new()
    }
    fn periodic(&self) -> Vec<bool> {
        vec![true; self.joints.len()]
    }
}

/// A serial arm of seven revolute joints: the node answers its self-motion sets (the 3R and 6R
/// questions need a joint held, which the node's analyses do not take).
#[derive(Clone, Debug)]
pub(crate) struct SevenJointArm {
    name: String,
    joints: Vec<String>,
}

impl Analysis for SevenJointArm {
    fn mechanism(&self) -> &str {
        &self.name
    }
    fn kind(&self) -> MechanismKind {
        MechanismKind::Manipulator7R
    }
    fn services(&self) -> Vec<Service> {
        vec![Service::SelfMotion]
    }
    fn limitation(&self) -> String {
        "a seven-revolute arm: self_motion is answered; its 3R positioning structure and the 6R questions need a joint held (linkspace singularities or ik6 with --fix JOINT=VALUE)".to_string()
    }
    fn free_joints(&self) -> Vec<String> {
        self.joints.clone()
    }
    fn fixed_joints(&self) -> Vec<(String, f64)> {
        Vec::new()
    }
    fn periodic(&self) -> Vec<bool> {
        vec![true; self.joints.len()]
    }
}

/// `load` for a mechanism read from URDF: a linkage's actuated joints come from its
/// `<transmission>` elements (`Actuation::from_transmissions`, the default of `linkspace
/// loop-singularities` as well).
pub fn load_urdf(mechanism: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Box<dyn Analysis>, AnalysisError> {
    load_with(mechanism, fixed, traces, Actuation::from_transmissions(mechanism, fixed))
}

/// Picks the analysis that fits `mechanism`. `fixed` and `traces` are as for
/// `LinkageProblem::new`.
///
/// A serial chain of three revolute joints whose map is not degenerate is a 3R manipulator
/// (it takes no fixed joints or traced points); otherwise a planar linkage is tried. A
/// mechanism outside every analysis loads as `Unsupported`, so the node can still list it and
/// explain; bad fixed joints are an error.
pub fn load(mechanism: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)]) -> Result<Box<dyn Analysis>, AnalysisError> {
    load_with(mechanism, fixed, traces, Actuation { joints: Vec::new(), source: "none given".to_string() })
}

fn load_with(mechanism: &Mechanism, fixed: &[(String, f64)], traces: &[(String, f64, f64)], actuation: Actuation) -> Result<Box<dyn Analysis>, AnalysisError> {
    let not_3r = match Manip3rAnalysis::new(mechanism) {
        Ok(a) => {
            if let Some((joint, _)) = fixed.first() {
                return Err(AnalysisError::BadRequest(format!("--fix {joint}: '{}' is a 3R manipulator, whose analysis takes no fixed joints", mechanism.name)));
            }
            if let Some((link, _, _)) = traces.first() {
                return Err(AnalysisError::BadRequest(format!("--trace {link}: '{}' is a 3R manipulator, whose analysis takes no traced points", mechanism.name)));
            }
            return Ok(Box::new(a));
        }
        Err(e) => e,
    };
    if mechanism.loops.is_empty() && crate::analyses::arm6r::self_motion::default_parameter(mechanism).is_ok() {
        if let Some((joint, _)) = fixed.first() {
            return Err(AnalysisError::BadRequest(format!("--fix {joint}: '{}' is a seven-revolute arm, whose analysis takes no fixed joints", mechanism.name)));
        }
        let joints = mechanism.joints.iter().filter(|j| matches!(j.kind, crate::model::JointKind::Revolute { .. })).map(|j| j.name.clone()).collect();
        return Ok(Box::new(SevenJointArm { name: mechanism.name.clone(), joints }));
    }
    // An octahedral platform: PlatformProblem reads it (the distance formulation of Porta, Thomas, Ros and Torras (2003)). Other
    // mechanisms with spherical loops go to the linkage builders below.
    let spherical = mechanism.loops.iter().any(|l| l.kind == crate::model::JointKind::Spherical);
    let unsupported = |reason: String| -> Box<dyn Analysis> {
        Box::new(Unsupported {
            name: mechanism.name.clone(),
            joints: mechanism.joints.iter().filter(|j| j.kind != crate::model::JointKind::Fixed).map(|j| j.name.clone()).collect(),
            reason,
        })
    };
    match PlatformAnalysis::new(mechanism, fixed) {
        Ok(a) => {
            if let Some((link, _, _)) = traces.first() {
                return Err(AnalysisError::BadRequest(format!("--trace {link}: '{}' is a parallel platform, whose analysis takes no traced points", mechanism.name)));
            }
            return Ok(Box::new(a));
        }
        // No leg fixed at all: loaded and listed, with what it needs.
        Err(AnalysisError::Platform(e @ PlatformError::NotFixed(_))) if fixed.is_empty() => {
            return Ok(unsupported(format!("a parallel platform whose legs are not fixed ({e}); serve it with --fix {}:LEG=SQUARED_LENGTH for each of its six legs", mechanism.name)));
        }
        Err(AnalysisError::Platform(PlatformError::NotAPlatform(_) | PlatformError::Unsupported(_))) => {}
        // A platform with bad --fix values (unknown leg, out of limits, some legs missing).
        Err(e) if spherical => return Err(e),
        Err(_) => {}
    }
    // Any other platform (a 6-6 Stewart, a delta) is a spatial linkage.
    match LinkageAnalysis::new(mechanism, fixed, traces) {
        Ok(a) => Ok(Box::new(a.with_actuation(actuation))),
        Err(e @ (LinkageError::NoLoops | LinkageError::Mimic { .. } | LinkageError::Unsupported(_) | LinkageError::UnderConstrained(_))) => Ok(unsupported(format!(
            "not a linkage the builders take ({e}), and {not_3r}; closed-loop linkages, octahedral platforms and 3R manipulators are analysed so far"
        ))),
        Err(e) => Err(e.into()),
    }
}

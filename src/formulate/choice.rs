//! Which builder a closed-loop mechanism gets: the planar one (one angle per rigid group) when it
//! accepts the mechanism; else the pose one for a platform on six legs, every leg fixed and no
//! point traced; else the spatial one (`--model auto`); or the one the user forces (among them
//! the distance builder, `--model distances`, for the same platforms).
//! One choice for the CLI's `solve` and the node's linkage analysis, so both say the same thing.
//! The singular-set systems differentiate joint coordinates: they take the planar or the
//! spatial builder (`Linkage::build_in_joints`).

use super::{BilaterationProblem, LinkageError, LinkageProblem, PoseProblem, SpatialProblem};
use crate::kernel::search::{SolveError, Solver, SolverSettings};

/// `--model`: which builder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ModelChoice {
    /// Planar whenever the planar builder accepts the mechanism (and every traced point lies in
    /// the plane of its link frame), spatial otherwise.
    #[default]
    Auto,
    /// The planar builder, or its refusal.
    Planar,
    /// The spatial builder, even for a planar mechanism.
    Spatial,
    /// The pose builder (a platform on six legs, each fixed), or its refusal.
    Pose,
    /// The distance builder (the same platforms, squared distances and signed heights), or its
    /// refusal.
    Distances,
}

/// The builder a linkage was built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// One angle per rigid group, one vector equation per loop.
    Planar,
    /// Rotation matrices of linear forms, closures as linear rows.
    Spatial,
    /// A platform's position and rotation, leg rows linear in derived products.
    Pose,
    /// A platform's base-to-platform squared distances and heights (in the style of Porta et al.
    /// 2003).
    Distances,
}

impl Model {
    /// `planar` or `spatial`, as reports write it.
    pub fn name(self) -> &'static str {
        match self {
            Model::Planar => "planar",
            Model::Spatial => "spatial",
            Model::Pose => "pose",
            Model::Distances => "distances",
        }
    }
}

/// Why a mechanism the planar builder accepts is solved with it.
pub(crate) const PLANAR_REASON: &str = "every revolute axis is parallel and every slider lies in the plane: one angle per rigid group";

/// Why a platform is solved in pose coordinates.
pub(crate) const POSE_REASON: &str = "a platform on six legs, every leg fixed: its pose (position, rotation) is the unknown, the legs linear rows";

/// A traced point: link, coordinates in the link's frame, and its name as given (`LINK@X,Y[,Z]`).
pub type TracedPoint = (String, [f64; 3], String);

/// A closed-loop mechanism built by the chosen model.
#[derive(Clone, Debug)]
pub enum Linkage {
    /// The planar builder's system.
    Planar(LinkageProblem),
    /// The spatial builder's system, and why it was chosen.
    Spatial(SpatialProblem, String),
    /// The pose builder's system, and why it was chosen.
    Pose(PoseProblem, String),
    /// The distance builder's system, and why it was chosen.
    Distances(Box<BilaterationProblem>, String),
}

impl Linkage {
    /// Picks the model and builds it, saying why in the spatial case.
    pub fn build(mechanism: &crate::model::Mechanism, choice: ModelChoice, fixed: &[(String, f64)], traces: &[TracedPoint]) -> Result<Self, LinkageError> {
        Self::build_with(mechanism, choice, fixed, traces, true)
    }

    /// As `build`, among the models in joint coordinates only (`--model pose` and `distances` refused, `auto`
    /// planar or spatial): the singular-set systems differentiate joint coordinates.
    pub fn build_in_joints(mechanism: &crate::model::Mechanism, choice: ModelChoice, fixed: &[(String, f64)], traces: &[TracedPoint]) -> Result<Self, LinkageError> {
        Self::build_with(mechanism, choice, fixed, traces, false)
    }

    fn build_with(mechanism: &crate::model::Mechanism, choice: ModelChoice, fixed: &[(String, f64)], traces: &[TracedPoint], pose: bool) -> Result<Self, LinkageError> {
        let flat: Vec<(String, f64, f64)> = traces.iter().map(|(l, p, _)| (l.clone(), p[0], p[1])).collect();
        let off_plane = traces.iter().find(|(_, p, _)| p[2] != 0.0).map(|(_, _, r)| r.clone());
        let spatial = |reason: String| -> Result<Self, LinkageError> { Ok(Self::Spatial(SpatialProblem::new(mechanism, fixed, traces)?, reason)) };
        match choice {
            ModelChoice::Spatial => spatial("forced by --model spatial".into()),
            ModelChoice::Pose | ModelChoice::Distances if !pose => Err(LinkageError::NotJointModel),
            ModelChoice::Distances => match traces.first() {
                Some((_, _, r)) => Err(LinkageError::TraceOnPose(r.clone())),
                None => Ok(Self::Distances(Box::new(BilaterationProblem::new(mechanism, fixed)?), "forced by --model distances".into())),
            },
            ModelChoice::Pose => match traces.first() {
                Some((_, _, r)) => Err(LinkageError::TraceOnPose(r.clone())),
                None => Ok(Self::Pose(PoseProblem::new(mechanism, fixed)?, "forced by --model pose".into())),
            },
            ModelChoice::Planar => match off_plane {
                Some(r) => Err(LinkageError::TraceOffPlane(r)),
                None => Ok(Self::Planar(LinkageProblem::new(mechanism, fixed, &flat)?)),
            },
            ModelChoice::Auto => {
                if let Some(r) = off_plane {
                    return spatial(format!("--trace '{r}' leaves the plane of the link frame"));
                }
                match LinkageProblem::new(mechanism, fixed, &flat) {
                    Ok(p) => Ok(Self::Planar(p)),
                    Err(LinkageError::NonPlanar(why)) => match PoseProblem::new(mechanism, fixed) {
                        Ok(p) if pose && traces.is_empty() => Ok(Self::Pose(p, POSE_REASON.into())),
                        _ => spatial(format!("not planar: {why}")),
                    },
                    Err(e) => Err(e),
                }
            }
        }
    }

    /// Why that builder: what made the mechanism planar, or why the spatial one was taken.
    pub fn model_reason(&self) -> &str {
        match self {
            Self::Planar(_) => PLANAR_REASON,
            Self::Spatial(_, why) | Self::Pose(_, why) | Self::Distances(_, why) => why,
        }
    }

    /// What the spatial builder simplified (legs between ball joints reduced to distances).
    pub fn reductions(&self) -> &[String] {
        match self {
            Self::Planar(_) | Self::Pose(..) | Self::Distances(..) => &[],
            Self::Spatial(p, _) => &p.reductions,
        }
    }

    /// `planar_linkage` or `spatial_linkage`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Planar(_) => "planar_linkage",
            Self::Spatial(..) => "spatial_linkage",
            Self::Pose(..) | Self::Distances(..) => "parallel_platform",
        }
    }

    /// The built system.
    pub fn system(&self) -> &crate::kernel::system::EquationSystem {
        match self {
            Self::Planar(p) => &p.system,
            Self::Spatial(p, _) => &p.system,
            Self::Pose(p, _) => &p.system,
            Self::Distances(p, _) => &p.system,
        }
    }

    /// The solver for the built system (joint-limit filters included).
    pub fn solver(&self, settings: SolverSettings) -> Result<Solver<'_>, SolveError> {
        match self {
            Self::Planar(p) => p.solver(settings),
            Self::Spatial(p, _) => p.solver(settings),
            Self::Pose(p, _) => p.solver(settings),
            Self::Distances(p, _) => p.solver(settings),
        }
    }

    /// Joints (tree and loop) solved for.
    pub fn free_joints(&self) -> &[String] {
        match self {
            Self::Planar(p) => &p.free_joints,
            Self::Spatial(p, _) => &p.free_joints,
            Self::Pose(p, _) => &p.free_joints,
            Self::Distances(p, _) => &p.free_joints,
        }
    }

    /// Names of the traced points, as in the report.
    pub fn trace_names(&self) -> Vec<String> {
        match self {
            Self::Planar(p) => p.traces.iter().map(|t| t.name.clone()).collect(),
            Self::Spatial(p, _) => p.traces.iter().map(|t| t.name.clone()).collect(),
            Self::Pose(..) | Self::Distances(..) => Vec::new(),
        }
    }
}

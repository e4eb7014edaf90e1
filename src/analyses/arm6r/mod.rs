//! Six-revolute arms taken whole: certified inverse kinematics of the tip frame (`ik`) and a
//! whole-arm cuspidality verdict (`cuspidal`), for any 6R chain (no closed form assumed).
//!
//! `Chain6R` reads the six revolute joints from base to tip of a URDF `Mechanism` (fixed joints
//! merged) with every coefficient an interval enclosing the file's decimals; the searches run on
//! the kernel (`search::run`, `contract::krawczyk`). No IO.

pub(crate) mod chain;
pub mod cuspidal;
pub mod ik;
mod invariant_pairs;
pub mod three_parallel;
pub(crate) mod jacobian;
pub mod path;
pub mod pose;
pub mod self_motion;

pub use chain::{Chain6R, Pose64};
pub use cuspidal::{CuspidalVerdict, MostSolutions, SearchOutcome, Witness};
pub use ik::{Ik6Solutions, PoseTarget};
pub use three_parallel::ThreeParallel;
pub use path::{Crossing, PathCheck, SegmentVerdict, Span, SpanReason};
pub use pose::PoseInput;

use thiserror::Error;

/// What is wrong with a 6R problem. Messages are one line and name the culprit.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum Manip6rError {
    /// The base, tip or chain cannot be chosen, or it is not six revolute joints.
    #[error("not a 6R chain: {0}")]
    NotSixR(String),
    /// The pose is not finite.
    #[error("bad pose: {0}")]
    BadPose(String),
    /// A 4×4 pose matrix is not a rigid transform (the defect and its size).
    #[error("not a rigid transform: {0}")]
    NotRigid(String),
    /// A joint path cannot be checked (too few waypoints, a bad number or tolerance).
    #[error("bad path: {0}")]
    BadPath(String),
    /// The requested precision is not in (0, 1).
    #[error("precision must be a number in (0, 1), got {0}")]
    BadPrecision(f64),
}

//! Problem builders: a model in, an `EquationSystem` (plus what is needed to read answers back)
//! out. Builders never solve.

pub(crate) mod angles;
pub(crate) mod bilateration;
pub(crate) mod cayley_menger;
pub(crate) mod choice;
pub(crate) mod coordinates;
pub(crate) mod linkage;
pub(crate) mod platform;
pub(crate) mod pose;
pub(crate) mod singular;
pub(crate) mod spatial;
pub mod torus;
pub(crate) mod stated;

pub use bilateration::BilaterationProblem;
pub use cayley_menger::{cayley_menger_determinant, BuildOptions, CayleyMenger, DistanceError, DistanceProblem, DistanceSolverError, Formulation, Orientation};
pub use choice::{Linkage, Model, ModelChoice, TracedPoint};
pub use coordinates::{Placed, PlacedError};
pub use linkage::{LinkageError, LinkageProblem};
pub use platform::{LegValues, PlatformError, PlatformProblem, Pose};
pub use pose::{PoseLeg, PoseProblem, PoseRows};
pub use singular::image::{CuspFormulation, CuspProblem, ImageError, NodeProblem};
pub use singular::{Coordinates, Output, RateMatrix, SingularError, SingularKind, SingularProblem};
pub use spatial::{LinkPose, SpatialProblem};

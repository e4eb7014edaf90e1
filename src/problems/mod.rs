//! Problem builders: a model in, an `EquationSystem` (plus what is needed to read answers back)
//! out. Builders never solve.

pub(crate) mod angles;
pub mod cayley_menger;
pub mod choice;
pub mod coordinates;
pub mod linkage;
pub mod platform;
pub mod singular;
pub mod spatial;
pub(crate) mod stated;

pub use cayley_menger::{CayleyMenger, DistanceError, DistanceProblem};
pub use choice::{Linkage, Model, ModelChoice};
pub use linkage::{LinkageError, LinkageProblem};
pub use platform::{PlatformError, PlatformProblem};
pub use spatial::SpatialProblem;

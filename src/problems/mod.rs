//! Problem builders: a model in, an `EquationSystem` (plus what is needed to read answers back)
//! out. Builders never solve.

pub mod cayley_menger;
pub mod linkage;

pub use cayley_menger::{CayleyMenger, DistanceError, DistanceProblem};
pub use linkage::{LinkageError, LinkageProblem};

//! Problem builders: a model in, an `EquationSystem` (plus what is needed to read answers back)
//! out. Builders never solve.

pub mod linkage;

pub use linkage::{LinkageError, LinkageProblem};

//! The JSON writers: what the CLI's `--json` options write (schemas in README), one module per
//! command, built from the typed results of `app` and the analyses. Pure data: no IO here.
//!
//! Only this module and `ros` know serde: `kernel` states how the kernel's and `model`'s values
//! are written.

pub mod distances;
pub(crate) mod kernel;
pub mod singular;
pub mod solve;

pub use crate::interval::Bounds;
pub use solve::{BoxRecord, SolveReport, TracedPoint, VariableInfo};

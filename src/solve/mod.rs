//! Branch and prune: settings, the driver, and its outputs.
//!
//! Knows systems and contractors; does no IO and knows nothing of mechanisms, URDF or ROS.

mod driver;
mod parallel;
mod settings;

pub use driver::{default_contractor, process_cpu_seconds, ContractorFactory, BoxSink, BoxStatus, Collect, Enclosure, Limit, Progress, SolveError, Solver, Stats, Status};
pub use settings::{SettingsError, SolverSettings};

//! linkspace: every configuration a mechanism can take, with guarantees.
//!
//! A mechanism (from URDF, `model`) becomes a system of equations (`problems`), which the
//! branch-and-prune kernel (`search`) covers with interval boxes that provably enclose every
//! solution, shrinking boxes with sound contractors (`contract`). What a front end runs on a
//! loaded mechanism (configuration spaces, singularities, inverse kinematics) is `analysis`;
//! the 3R manipulator analyses of seed 003 are `manip3r`; JSON reports are `report`.
//! See ARCHITECTURE.md for the map.
//!
//! # Examples
//!
//! Both assembly modes of the bundled four-bar with its crank at 0.5 rad:
//!
//! ```
//! use linkspace::{model::urdf, problems::LinkageProblem, SolverSettings, Status};
//! use std::sync::atomic::AtomicBool;
//!
//! let mechanism = urdf::parse(include_str!("../urdf/four_bar.urdf")).unwrap();
//! let problem = LinkageProblem::new(&mechanism, &[("crank_joint".into(), 0.5)], &[]).unwrap();
//! let settings = SolverSettings { sigma: 1e-6, ..Default::default() };
//! let found = problem.solver(settings).unwrap().enclose(&AtomicBool::new(false), &mut |_| {});
//! assert_eq!(found.status, Status::Complete);
//! assert_eq!(linkspace::interval::components(&found.solutions).1, 2);
//! ```

#![warn(missing_docs)]

pub mod app;
pub mod contract;
pub mod distances;
pub mod interval;
pub mod joint_path;
mod lp;
pub mod manip3r;
pub mod manip6r;
pub mod model;
#[cfg(feature = "ros")]
pub mod ros;
pub mod problems;
pub mod report;
pub mod search;
pub mod singular;
pub mod sweep;
pub mod system;

pub use app::{load, Analysis, AnalysisError};
pub use interval::{Interval, IntervalBox};
pub use lp::{LpBackend, LpCounters};
pub use model::{Mechanism, ModelError};
pub use search::{Limit, Limits, Progress, Solver, SolverSettings, Status};
pub use system::EquationSystem;

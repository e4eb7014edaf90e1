//! linkspace: every configuration a mechanism can take, with guarantees.
//!
//! A mechanism (from URDF, `model`) becomes a system of equations (`formulate`), which the
//! branch-and-prune kernel (`search`) covers with interval boxes that provably enclose every
//! solution, shrinking boxes with sound contractors (`contract`). What a front end runs on a
//! loaded mechanism (configuration spaces, singularities, inverse kinematics) is `analysis`;
//! the 3R manipulator analyses of seed 003 are `arm3r`; JSON reports are `report`.
//! See ARCHITECTURE.md for the map.
//!
//! # Examples
//!
//! Both assembly modes of the bundled four-bar with its crank at 0.5 rad:
//!
//! ```
//! use linkspace::{model::urdf, formulate::LinkageProblem, SolverSettings, Status};
//! use std::sync::atomic::AtomicBool;
//!
//! let mechanism = urdf::parse(include_str!("../urdf/four_bar.urdf")).unwrap();
//! let problem = LinkageProblem::new(&mechanism, &[("crank_joint".into(), 0.5)], &[]).unwrap();
//! let settings = SolverSettings { sigma: 1e-6, ..Default::default() };
//! let found = problem.solver(settings).unwrap().enclose(&AtomicBool::new(false), &mut |_| {});
//! assert_eq!(found.status, Status::Finished);
//! assert_eq!(linkspace::kernel::interval::components(&found.solutions).1, 2);
//! ```

#![warn(missing_docs)]

pub mod analyses;
pub mod app;
pub mod edges;
pub mod formulate;
pub mod kernel;
pub mod model;

pub use app::{load, Analysis, AnalysisError};
pub use kernel::interval::{Interval, IntervalBox};
pub use kernel::lp::{LpBackend, LpCounters};
pub use kernel::search::{Limit, Limits, Progress, Solver, SolverSettings, Status};
pub use kernel::system::EquationSystem;
pub use model::{Mechanism, ModelError};

//! linkspace: every configuration a mechanism can take, with guarantees.
//!
//! A mechanism (from URDF, `model`) becomes a polynomial system (`problems`), which a
//! branch-and-prune solver (`solve`) covers with interval boxes that provably enclose every
//! solution, shrinking boxes with sound contractors (`contract`, `lp`).
//! See ARCHITECTURE.md for the map.

#![warn(missing_docs)]

pub mod chart;
pub mod analysis;
pub mod contract;
pub mod distances;
pub mod interval;
pub mod lp;
pub mod manip3r;
pub mod model;
#[cfg(feature = "ros")]
pub mod ros;
pub mod problems;
pub mod report;
pub mod search;
pub mod study;
pub mod system;

pub use interval::{Interval, IntervalBox};
pub use search::{Solver, SolverSettings, Status};
pub use system::EquationSystem;

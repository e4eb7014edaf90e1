//! Guaranteed cusps, nodes and internal motions of 3R manipulators, from URDF (seed 003).
//!
//! Owns the kinematic map of a serial chain of three revolute joints (`Chain3R`), its sound
//! evaluation with derivatives over boxes (`taylor`, `trig`), and the searches built on it:
//! internal-motion lines (`motion`), cusps (`cusps`), nodes (`nodes`), inverse kinematics
//! (`ik`), collision sets (`collision`) and the report types (`report`).
//! Every search is branch and prune over (θ₂, θ₃) with interval Newton (Krawczyk) proofs; a box
//! is discarded only when interval arithmetic proves it holds nothing sought.
//! No IO here: the CLI reads files and writes reports.
//!
//! # References
//! R. Benoit, N. Delanoue, S. Lagrange, P. Wenger, *Guaranteed detection of the singularities
//! of 3R robotic manipulators* (seed 003). R. Krawczyk, *Newton-Algorithmen zur Bestimmung von
//! Nullstellen mit Fehlerschranken*, Computing 4 (1969).

pub mod chain;
pub mod collision;
pub mod cusps;
pub mod ik;
pub mod krawczyk;
pub mod motion;
pub mod nodes;
pub mod report;
pub mod taylor;
pub mod trig;

pub use chain::{Chain3R, Jets};
pub use cusps::{Cusp, CuspSearch};
pub use nodes::{Node, NodeSearch};

use thiserror::Error;

/// What is wrong with a 3R problem. Messages are one line and name the culprit.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum Manip3rError {
    /// The mechanism is not a serial chain.
    #[error("not a serial chain: {0}")]
    NotSerial(String),
    /// The chain does not have exactly three revolute joints (or has a prismatic one).
    #[error("not a 3R chain: {0}")]
    NotThreeR(String),
    /// The end point does not move at all.
    #[error("the tip link '{0}' does not move with joints 2 and 3")]
    TipDoesNotMove(String),
    /// det Df vanishes identically: the end point moves along a curve only.
    #[error("the map of tip link '{0}' is degenerate: det Df vanishes everywhere (is the tip on the axis of joint 2 or 3?)")]
    Degenerate(String),
    /// The requested precision is not in (0, 1).
    #[error("precision must be a number in (0, 1), got {0}")]
    BadPrecision(f64),
    /// The requested uncertainty is negative or not finite.
    #[error("uncertainty must be a finite number >= 0, got {0}")]
    BadUncertainty(f64),
    /// A workspace point for inverse kinematics is not finite or has a negative radius.
    #[error("workspace point ({0}, {1}) is not valid: radius must be >= 0 and both finite")]
    BadPoint(f64, f64),
    /// Nothing to check for collisions.
    #[error("no collision geometry: {0}")]
    NoCollisionGeometry(String),
    /// A collision shape that is not a cylinder, capsule or sphere.
    #[error("link '{link}': collision {shape} is not supported (use a cylinder, capsule or sphere)")]
    UnsupportedShape {
        /// the link
        link: String,
        /// the shape's kind
        shape: String,
    },
    /// A base body whose distance to the arm would depend on joint 1.
    #[error("collision body '{0}' on the base is not on the first joint's axis: its distance to the arm depends on joint 1, which collisions does not model")]
    BaseBodyOffAxis(String),
}

/// Checks a precision argument once, before any search.
pub fn check_precision(precision: f64) -> Result<(), Manip3rError> {
    if precision.is_finite() && precision > 0.0 && precision < 1.0 {
        Ok(())
    } else {
        Err(Manip3rError::BadPrecision(precision))
    }
}

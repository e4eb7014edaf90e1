//! The distance job (Cayley–Menger determinants, Porta, Thomas, Ros and Torras (2003)): a platform read from URDF, or a pure distance problem read from
//! a distance file, certified by `distances::solve`. What `linkspace distances` runs (its JSON
//! writer, `report::distances`, reads the result) and what the node's platform analysis publishes.

use crate::kernel::contract::FaceBounds;
use crate::analyses::distances::{choose, solve, Certified, Choice, DistancesError};
use crate::model::Mechanism;
use crate::formulate::cayley_menger::{DistanceError, DistanceProblem};
use crate::formulate::{LegValues, PlatformError, PlatformProblem};
use crate::kernel::search::SolverSettings;
use std::sync::atomic::AtomicBool;

/// How to solve: the formulation, the redundant determinants, the trapezoid sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistancesRequest {
    /// The formulation; `Auto` lets `distances::choose` pick.
    pub formulation: Choice,
    /// Add the redundant determinants (platform: Eq. 7 of Porta, Thomas, Ros and Torras (2003); files: six-point ones).
    pub redundant: bool,
    /// How trapezoid sides are bounded.
    pub faces: FaceBounds,
}

/// A loaded distance problem, with the platform it came from when it came from URDF.
#[derive(Clone, Debug)]
pub struct DistancesRun {
    distances: DistanceProblem,
    platform: Option<PlatformProblem>,
    fixed: Vec<(String, f64)>,
}

impl DistancesRun {
    /// The platform of `mechanism` with its legs `fixed` given as `values` say.
    pub fn platform_with(mechanism: &Mechanism, fixed: &[(String, f64)], values: LegValues) -> Result<Self, PlatformError> {
        let p = PlatformProblem::with_legs(mechanism, fixed, values)?;
        Ok(Self { distances: p.distances.clone(), platform: Some(p), fixed: fixed.to_vec() })
    }

    /// A problem read from a distance file's text (schema in README), with named distances
    /// `fixed`.
    pub fn file(text: &str, fixed: &[(String, f64)]) -> Result<Self, DistanceError> {
        Ok(Self { distances: crate::analyses::distances::file::parse(text, fixed)?, platform: None, fixed: fixed.to_vec() })
    }

    /// The distance problem.
    pub fn problem(&self) -> &DistanceProblem {
        &self.distances
    }

    /// The platform, when the problem came from URDF.
    pub fn platform_problem(&self) -> Option<&PlatformProblem> {
        self.platform.as_ref()
    }

    /// The formulation `asked` resolves to (`Auto`: what `distances::choose` picks).
    pub fn formulation(&self, asked: Choice) -> Choice {
        match asked {
            Choice::Auto => choose(&self.distances),
            c => c,
        }
    }

    /// Joints fixed at load time: the platform's squared leg lengths, or the file's named
    /// distances.
    pub fn fixed(&self) -> &[(String, f64)] {
        &self.fixed
    }

    /// The default rho of a formulation: 0.99 for the determinants, as Porta, Thomas, Ros and Torras (2003) use; 0.9 in
    /// coordinates (points, line), where bisecting is cheaper than slow propagation fixpoints.
    pub fn default_rho(formulation: Choice) -> f64 {
        if matches!(formulation, Choice::Points | Choice::Line) {
            0.9
        } else {
            0.99
        }
    }

    /// Solves. `request.formulation` may be `Auto`.
    pub fn run(&self, request: &DistancesRequest, settings: &SolverSettings, cancel: &AtomicBool) -> Result<Certified, DistancesError> {
        solve(&self.distances, self.formulation(request.formulation), request.redundant, request.faces, settings.clone(), cancel)
    }
}

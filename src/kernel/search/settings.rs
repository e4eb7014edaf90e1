//! Settings of the polynomial solver, validated once.

use crate::kernel::lp::LpBackend;
use std::time::Duration;
use thiserror::Error;

/// What the driver is allowed to do, and when a box counts as a solution.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    /// A box whose primary components are all at most this wide is a solution box. Default 1e-3.
    pub sigma: f64,
    /// Keep shrinking a box while one round leaves less than this fraction of its (primary)
    /// volume; otherwise bisect it. In (0, 1); default 0.95, the value of Porta et al. (2006).
    pub rho: f64,
    /// Stop after processing this many boxes (the run ends `incomplete`). Default 1,000,000.
    pub max_boxes: u64,
    /// Stop after this much wall-clock time (the run ends `incomplete`). Default: none.
    pub timeout: Option<Duration>,
    /// Stop before pending boxes hold more than this many bytes (the run ends `incomplete`).
    /// Default 2 GiB.
    pub max_memory: usize,
    /// Use the LP shrink after propagation. Default true; false leaves propagation alone.
    pub use_lp: bool,
    /// Interval Newton runs on square systems once every primary is at most this wide.
    /// Default 0.25; 0 switches it off.
    pub newton_width: f64,
    /// Worker threads: 1 runs the depth-first serial driver, more the breadth-first parallel
    /// one (same set of boxes). Default 1.
    pub threads: usize,
    /// Which LP solver proposes the multipliers that the safe bound verifies. Default simplex.
    pub lp_backend: LpBackend,
    /// Measure each primary's width in its own unit: its width in the system's initial box
    /// divided by the narrowest such width (`width_units`). `sigma`, `newton_width` and the
    /// choice of the component to bisect then read widths in these units, so a travel spanning
    /// [1, 40] next to cosines spanning [−1, 1] is split as often, relative to its range, as
    /// they are. Default false: widths are absolute (every primary in the same unit).
    pub scaled_widths: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self { sigma: 1e-3, rho: 0.95, max_boxes: 1_000_000, timeout: None, max_memory: super::limits::DEFAULT_MAX_MEMORY, use_lp: true, newton_width: 0.25, threads: 1, lp_backend: LpBackend::Simplex, scaled_widths: false }
    }
}

/// A setting out of range.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SettingsError {
    /// sigma must be a positive finite number.
    #[error("sigma must be a positive finite number, got {0}")]
    Sigma(f64),
    /// rho must lie strictly between 0 and 1.
    #[error("rho must lie strictly between 0 and 1, got {0}")]
    Rho(f64),
    /// newton_width must be a non-negative finite number.
    #[error("newton-width must be a non-negative finite number, got {0}")]
    NewtonWidth(f64),
    /// max_boxes must be at least 1.
    #[error("max-boxes must be at least 1")]
    MaxBoxes,
}

impl SolverSettings {
    /// Checks every field; the driver relies on it.
    pub fn validate(&self) -> Result<(), SettingsError> {
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(SettingsError::Sigma(self.sigma));
        }
        if !(self.rho > 0.0 && self.rho < 1.0) {
            return Err(SettingsError::Rho(self.rho));
        }
        if !(self.newton_width >= 0.0 && self.newton_width.is_finite()) {
            return Err(SettingsError::NewtonWidth(self.newton_width));
        }
        if self.max_boxes == 0 {
            return Err(SettingsError::MaxBoxes);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_nonsense() {
        let bad = |f: fn(&mut SolverSettings)| {
            let mut s = SolverSettings::default();
            f(&mut s);
            s.validate()
        };
        assert_eq!(bad(|s| s.sigma = 0.0), Err(SettingsError::Sigma(0.0)));
        assert!(matches!(bad(|s| s.sigma = f64::NAN), Err(SettingsError::Sigma(_))));
        assert_eq!(bad(|s| s.rho = 1.0), Err(SettingsError::Rho(1.0)));
        assert_eq!(bad(|s| s.max_boxes = 0), Err(SettingsError::MaxBoxes));
        assert_eq!(SolverSettings::default().validate(), Ok(()));
    }
}

//! Singularities of a 6R arm along a piecewise-linear joint path: `joint_path`'s segment
//! checker run on `det J`, whose sign a joint box proves through `jacobian` (`det J` excludes
//! zero on it, with its sign and a lower bound of `|det J|`).
//! No IO.

use super::chain::{Chain6R, Side};
use super::jacobian::{det_enclosure, jacobian_over, regularity};
use super::Manip6rError;
use crate::analyses::joint_path::{self, Proof, SignProof};
use crate::kernel::search::Control;

pub use crate::analyses::joint_path::{Crossing, PathCheck, SegmentVerdict, Span, SpanReason, MAX_PIECES, PIECE_WIDTH};

/// A proven piece whose bound `‖I − Y·J‖∞` exceeds this is cut further (while wider than
/// `PIECE_WIDTH`), so that the reported lower bound of `|det J|` is within a factor
/// `(1 − 0.25)⁶ ≈ 0.18` of the Jacobian's determinant there rather than near zero.
const TIGHT: f64 = 0.25;

/// The arm's `det J` on boxes of its six joints.
struct DetJ(Side<6>);

impl SignProof for DetJ {
    fn joints(&self) -> usize {
        6
    }

    fn prove(&self, b: &[[f64; 2]]) -> Option<Proof> {
        let b: &[[f64; 2]; 6] = b.try_into().ok()?;
        let proof = regularity(&jacobian_over(&self.0, b))?;
        let d = det_enclosure(&proof)?;
        Some(Proof { sign: if d.inf() > 0.0 { 1.0 } else { -1.0 }, min_abs: d.mig(), tight: proof.r <= TIGHT })
    }
}

/// Decides each segment of the path through `waypoints` (joints in `chain.joints` order,
/// radians); crossings narrowed until their joint enclosures are within `tolerance` radians.
/// A limit of `control` (timeout, cancel) leaves the remaining segments `Stopped`.
pub fn check(chain: &Chain6R, waypoints: &[[f64; 6]], tolerance: f64, control: &Control) -> Result<PathCheck, Manip6rError> {
    let rows: Vec<Vec<f64>> = waypoints.iter().map(|w| w.to_vec()).collect();
    joint_path::check(&DetJ(chain.arm()), &rows, tolerance, control).map_err(|e| Manip6rError::BadPath(e.0))
}

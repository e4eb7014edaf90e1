//! Singularities of a 3R positioning structure along a piecewise-linear path in the arm's
//! joints: `joint_path`'s segment checker run on `det Df` of the half-section map
//! (θ₂, θ₃) ↦ (ρ, z) (`Chain3R`). Joint 1 and the joints after the third do not enter `det Df`;
//! they ride along in the waypoints and the reported enclosures.
//!
//! On a joint box, `det Df` is enclosed twice and the two intersected: naturally (its jet's
//! value over the box) and by the mean-value form `det Df(c) + ∇det Df(B)·(B − c)` about the
//! box's centre `c` (the centre's value enclosed on the point box), which is tight on the thin
//! boxes of a segment's pieces. A box whose enclosure excludes zero is proven, with the sign and
//! the enclosure's least magnitude.
//! No IO.

use super::chain::Chain3R;
use super::Manip3rError;
use crate::kernel::interval::{interval, point};
use crate::analyses::joint_path::{self, PathCheck, Proof, SignProof};
use crate::kernel::search::Control;

/// A proof whose lower bound of `|det Df|` is below this fraction of the enclosure's largest
/// magnitude is cut further (while wider than `joint_path::PIECE_WIDTH`), so that the reported
/// bound is within that factor of `det Df` there rather than near zero.
const TIGHT: f64 = 0.25;

/// `det Df` of `chain` on boxes of a path's joints, θ₂ and θ₃ at the places `theta`.
pub(crate) struct DetDf<'a> {
    chain: &'a Chain3R,
    theta: [usize; 2],
    joints: usize,
}

impl<'a> DetDf<'a> {
    /// `det Df` read on waypoints of `joints` values, θ₂ and θ₃ the values at `theta`.
    pub(crate) fn new(chain: &'a Chain3R, theta: [usize; 2], joints: usize) -> Self {
        Self { chain, theta, joints }
    }
}

impl SignProof for DetDf<'_> {
    fn joints(&self) -> usize {
        self.joints
    }

    fn prove(&self, b: &[[f64; 2]]) -> Option<Proof> {
        let [i, j] = self.theta;
        let boxed = [interval(b[i][0], b[i][1]), interval(b[j][0], b[j][1])];
        let over = self.chain.derived(boxed, 2).det;
        let natural = over.value();
        let centre = [0.5 * (b[i][0] + b[i][1]), 0.5 * (b[j][0] + b[j][1])];
        let at_centre = self.chain.derived(centre.map(point), 1).det.value();
        let grad = over.grad();
        let mean_value = at_centre + grad[0] * (boxed[0] - point(centre[0])) + grad[1] * (boxed[1] - point(centre[1]));
        let d = natural.intersection(mean_value);
        if d.is_empty() || d.contains(0.0) {
            return None;
        }
        Some(Proof { sign: if d.inf() > 0.0 { 1.0 } else { -1.0 }, min_abs: d.mig(), tight: d.mig() >= TIGHT * d.mag() })
    }
}

/// Decides each segment of the path through `waypoints` (radians, `joints` values each, θ₂ and
/// θ₃ of `chain` at the places `theta`) against `det Df = 0`; crossings narrowed until their
/// joint enclosures are within `tolerance` radians. A limit of `control` leaves the remaining
/// segments `Stopped`.
pub fn check(chain: &Chain3R, theta: [usize; 2], joints: usize, waypoints: &[Vec<f64>], tolerance: f64, control: &Control) -> Result<PathCheck, Manip3rError> {
    if theta[0] >= joints || theta[1] >= joints || theta[0] == theta[1] {
        return Err(Manip3rError::BadPath(format!("joints 2 and 3 of the sub-chain at places {:?} of {joints}", theta)));
    }
    joint_path::check(&DetDf::new(chain, theta, joints), waypoints, tolerance, control).map_err(|e| Manip3rError::BadPath(e.0))
}

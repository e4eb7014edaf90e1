//! Singularities along a piecewise-linear joint path, each segment decided with a proof.
//!
//! A segment `q(t) = x + t·(y − x)`, t ∈ [0, 1], is cut into pieces until each piece's joint
//! box is proven regular (`jacobian`: `det J` excludes zero on it, with its sign and a lower
//! bound of `|det J|`) or is narrower than `PIECE_WIDTH`. Pieces left unproven form runs. A
//! run between proven pieces of opposite signs holds a sign change of `det J` (it is continuous
//! along the segment): a crossing, whose parameter is then narrowed by bisection, a point's
//! sign certified on a box padded for the rounding of `q(t)`, until the enclosure is within the
//! tolerance in joint space. Other runs (same sign on both sides, or at an end of the segment)
//! may hold a zero of `det J` without a proven sign change: they are reported as such.
//! No IO.

use super::chain::Chain6R;
use super::jacobian::{det_enclosure, jacobian_over, regularity};
use super::Manip6rError;
use crate::search::{Control, Limit};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Pieces narrower than this (in the segment's parameter) are no longer cut while covering it.
pub const PIECE_WIDTH: f64 = 1.0 / 16384.0;
/// Pieces examined per segment before the rest of it is left unproven.
pub const MAX_PIECES: usize = 200_000;
/// A proven piece whose bound `‖I − Y·J‖∞` exceeds this is cut further (while wider than
/// `PIECE_WIDTH`), so that the reported lower bound of `|det J|` is within a factor
/// `(1 − 0.25)⁶ ≈ 0.18` of the Jacobian's determinant there rather than near zero.
const TIGHT: f64 = 0.25;

/// What one segment holds.
#[derive(Clone, Debug, PartialEq)]
pub enum SegmentVerdict {
    /// `det J` is proven nonzero on the whole segment.
    Clear {
        /// Its sign (±1).
        sign: f64,
        /// A proven lower bound of `|det J|` on the segment.
        min_abs_det: f64,
        /// Pieces proven.
        pieces: usize,
    },
    /// `det J` is proven to change sign (at least once) within each crossing's enclosure.
    Crosses {
        /// The crossings, in order along the segment.
        crossings: Vec<Crossing>,
        /// Other stretches where `det J` may vanish without a proven sign change.
        undecided: Vec<Span>,
    },
    /// `det J` may vanish on these stretches; no sign change is proven.
    Undecided {
        /// The stretches, in order.
        spans: Vec<Span>,
    },
    /// Not decided: a limit stopped the run first.
    Stopped(Limit),
}

/// A proven sign change of `det J`.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    /// Enclosure `[t_lo, t_hi]` of the parameter (some t inside has `det J = 0`).
    pub t: [f64; 2],
    /// The joints over that enclosure (`[lo, hi]` each, radians).
    pub joints: [[f64; 2]; 6],
    /// The sign of `det J` before the crossing (after it, the opposite).
    pub sign_before: f64,
    /// Whether the enclosure reached the tolerance (else a point inside could not be given a
    /// sign: `det J` is too close to zero there).
    pub narrowed: bool,
}

/// A stretch `[t_lo, t_hi]` on which `det J` may vanish.
#[derive(Clone, Debug, PartialEq)]
pub struct Span {
    /// The parameter's range.
    pub t: [f64; 2],
    /// The joints over it (`[lo, hi]` each, radians).
    pub joints: [[f64; 2]; 6],
    /// Why no sign change is claimed.
    pub reason: SpanReason,
}

/// Why a stretch is undecided rather than a crossing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpanReason {
    /// `det J` has the same proven sign on both sides: it may touch zero (or cross it an even
    /// number of times), or the enclosure is too loose there.
    SameSignBothSides,
    /// The stretch reaches the segment's start or end, where no sign is proven on the far side.
    AtEnd,
    /// The piece budget ran out before the stretch was examined.
    PieceBudget,
}

/// The verdicts of a path: one per segment, in order.
#[derive(Clone, Debug)]
pub struct PathCheck {
    /// The waypoints, joints in the chain's order.
    pub waypoints: Vec<[f64; 6]>,
    /// One per segment (waypoint k to k + 1).
    pub segments: Vec<SegmentVerdict>,
}

/// Decides each segment of the path through `waypoints` (joints in `chain.joints` order,
/// radians); crossings narrowed until their joint enclosures are within `tolerance` radians.
/// A limit of `control` (timeout, cancel) leaves the remaining segments `Stopped`.
pub fn check(chain: &Chain6R, waypoints: &[[f64; 6]], tolerance: f64, control: &Control) -> Result<PathCheck, Manip6rError> {
    if waypoints.len() < 2 {
        return Err(Manip6rError::BadPath(format!("{} waypoint(s): a path needs at least two", waypoints.len())));
    }
    if let Some((k, _)) = waypoints.iter().enumerate().find(|(_, w)| !w.iter().all(|x| x.is_finite())) {
        return Err(Manip6rError::BadPath(format!("waypoint {} is not six finite numbers", k + 1)));
    }
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(Manip6rError::BadPath(format!("the tolerance must be a positive number of radians, got {tolerance}")));
    }
    let start = Instant::now();
    let stop = || -> Option<Limit> {
        if control.cancel.load(Ordering::Relaxed) {
            Some(Limit::Cancelled)
        } else if control.limits.timeout.is_some_and(|t| start.elapsed() >= t) {
            Some(Limit::Time)
        } else {
            None
        }
    };
    let arm = chain.arm();
    let mut segments = Vec::new();
    for w in waypoints.windows(2) {
        let verdict = match stop() {
            Some(limit) => SegmentVerdict::Stopped(limit),
            None => Segment { arm: &arm, x: w[0], y: w[1] }.decide(tolerance, &stop),
        };
        segments.push(verdict);
    }
    Ok(PathCheck { waypoints: waypoints.to_vec(), segments })
}

struct Segment<'a> {
    arm: &'a super::chain::Side<6>,
    x: [f64; 6],
    y: [f64; 6],
}

/// A piece of the cover: proven (sign, lower bound of |det J|) or not.
#[derive(Clone, Copy, Debug)]
struct Piece {
    t0: f64,
    t1: f64,
    proof: Option<(f64, f64)>,
    /// Left unexamined when the budget ran out.
    skipped: bool,
}

impl Segment<'_> {
    fn at(&self, t: f64) -> [f64; 6] {
        [0, 1, 2, 3, 4, 5].map(|k| self.x[k] + t * (self.y[k] - self.x[k]))
    }

    /// A box holding the exact segment points for t ∈ [t0, t1]: the hull of the computed ends,
    /// padded for the rounding of `at`.
    fn hull(&self, t0: f64, t1: f64) -> [[f64; 2]; 6] {
        let (a, b) = (self.at(t0), self.at(t1));
        [0, 1, 2, 3, 4, 5].map(|k| {
            let pad = 4.0 * f64::EPSILON * (1.0 + self.x[k].abs() + self.y[k].abs());
            [a[k].min(b[k]) - pad, a[k].max(b[k]) + pad]
        })
    }

    /// The proven sign, lower bound of |det J| and contraction bound over the piece.
    fn prove(&self, t0: f64, t1: f64) -> Option<(f64, f64, f64)> {
        let proof = regularity(&jacobian_over(self.arm, &self.hull(t0, t1)))?;
        let d = det_enclosure(&proof)?;
        Some((if d.inf() > 0.0 { 1.0 } else { -1.0 }, d.mig(), proof.r))
    }

    fn decide(&self, tolerance: f64, stop: &dyn Fn() -> Option<Limit>) -> SegmentVerdict {
        // Cover [0, 1] by pieces, depth first, left to right.
        let mut pieces: Vec<Piece> = Vec::new();
        let mut stack = vec![(0.0f64, 1.0f64)];
        let mut examined = 0;
        while let Some((t0, t1)) = stack.pop() {
            if examined >= MAX_PIECES {
                pieces.push(Piece { t0, t1, proof: None, skipped: true });
                continue;
            }
            if examined % 256 == 0 {
                if let Some(limit) = stop() {
                    return SegmentVerdict::Stopped(limit);
                }
            }
            examined += 1;
            let narrow = t1 - t0 <= PIECE_WIDTH;
            match self.prove(t0, t1) {
                Some((sign, bound, r)) if r <= TIGHT || narrow => pieces.push(Piece { t0, t1, proof: Some((sign, bound)), skipped: false }),
                _ if narrow => pieces.push(Piece { t0, t1, proof: None, skipped: false }),
                _ => {
                    let tm = 0.5 * (t0 + t1);
                    stack.push((tm, t1));
                    stack.push((t0, tm));
                }
            }
        }
        // Runs of unproven pieces, with the proven signs on either side.
        let mut crossings = Vec::new();
        let mut spans = Vec::new();
        let mut i = 0;
        while i < pieces.len() {
            if pieces[i].proof.is_some() {
                i += 1;
                continue;
            }
            let first = i;
            let mut skipped = false;
            while i < pieces.len() && pieces[i].proof.is_none() {
                skipped |= pieces[i].skipped;
                i += 1;
            }
            let (lo, hi) = (pieces[first].t0, pieces[i - 1].t1);
            let before = first.checked_sub(1).and_then(|k| pieces[k].proof).map(|p| p.0);
            let after = pieces.get(i).and_then(|p| p.proof).map(|p| p.0);
            match (before, after) {
                (Some(a), Some(b)) if a != b => {
                    if let Some(limit) = stop() {
                        return SegmentVerdict::Stopped(limit);
                    }
                    crossings.push(self.narrow(lo, hi, a, tolerance));
                }
                _ => {
                    let reason = if skipped {
                        SpanReason::PieceBudget
                    } else if before.is_none() || after.is_none() {
                        SpanReason::AtEnd
                    } else {
                        SpanReason::SameSignBothSides
                    };
                    spans.push(Span { t: [lo, hi], joints: self.hull(lo, hi), reason });
                }
            }
        }
        if !crossings.is_empty() {
            return SegmentVerdict::Crosses { crossings, undecided: spans };
        }
        if !spans.is_empty() {
            return SegmentVerdict::Undecided { spans };
        }
        // Every piece proven: one sign throughout (det J is continuous and never zero).
        let sign = pieces[0].proof.expect("invariant: all proven").0;
        let min_abs_det = pieces.iter().filter_map(|p| p.proof).fold(f64::INFINITY, |m, p| m.min(p.1));
        SegmentVerdict::Clear { sign, min_abs_det, pieces: pieces.len() }
    }

    /// Bisects the sign change in `[lo, hi]` (sign `before` proven at `lo`, the opposite at
    /// `hi`) until its joint enclosure is within `tolerance`, or a midpoint's sign cannot be
    /// proven.
    fn narrow(&self, mut lo: f64, mut hi: f64, before: f64, tolerance: f64) -> Crossing {
        let span = (0..6).fold(0.0f64, |m, k| m.max((self.y[k] - self.x[k]).abs()));
        let mut narrowed = true;
        while (hi - lo) * span > tolerance {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            match self.prove(mid, mid) {
                Some((sign, _, _)) if sign == before => lo = mid,
                Some(_) => hi = mid,
                None => {
                    narrowed = false;
                    break;
                }
            }
        }
        Crossing { t: [lo, hi], joints: self.hull(lo, hi), sign_before: before, narrowed }
    }
}

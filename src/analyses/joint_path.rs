//! Singularities along a piecewise-linear joint path, each segment decided with a proof, for
//! any determinant whose sign can be proven on a box of joints (`SignProof`): the 6R arm's
//! `det J` (`arm6r::path`) and a 3R positioning structure's `det Df` (`arm3r::path`).
//!
//! A segment `q(t) = x + t·(y − x)`, t ∈ [0, 1], is cut into pieces until each piece's joint
//! box is proven regular (the determinant excludes zero on it, with its sign and a lower bound
//! of its magnitude) or is narrower than `PIECE_WIDTH`. Pieces left unproven form runs. A run
//! between proven pieces of opposite signs holds a sign change of the determinant (it is
//! continuous along the segment): a crossing, whose parameter is then narrowed by bisection, a
//! point's sign certified on a box padded for the rounding of `q(t)`, until the enclosure is
//! within the tolerance in joint space. Other runs (same sign on both sides, or at an end of
//! the segment) may hold a zero without a proven sign change: they are reported as such.
//! No IO.

use crate::kernel::search::{Budget, Control, Limit};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use thiserror::Error;

/// Pieces narrower than this (in the segment's parameter) are no longer cut while covering it.
pub const PIECE_WIDTH: f64 = 1.0 / 16384.0;
/// Pieces examined per segment before the rest of it is left unproven.
pub const MAX_PIECES: usize = 200_000;

/// A proof that a determinant excludes zero on a box of joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proof {
    /// The determinant's sign there (±1).
    pub sign: f64,
    /// A proven lower bound of its magnitude there.
    pub min_abs: f64,
    /// Whether the bound is close enough to the determinant's size that cutting the box further
    /// would not tighten it much (a loose proof is cut while wider than `PIECE_WIDTH`).
    pub tight: bool,
}

/// A determinant of the joints whose sign can be proven on a box of them (shared by the threads
/// that decide segments side by side).
pub trait SignProof: Sync {
    /// How many joints a waypoint holds.
    fn joints(&self) -> usize;
    /// A proof over the box `b` (`[lo, hi]` per joint, `joints()` of them), or None when the
    /// determinant may vanish there or the enclosure is too loose to tell.
    fn prove(&self, b: &[[f64; 2]]) -> Option<Proof>;
}

/// A path that cannot be checked (too few waypoints, a bad number or tolerance).
#[derive(Debug, Error, PartialEq)]
#[error("{0}")]
pub struct BadPath(pub String);

/// What one segment holds.
#[derive(Clone, Debug, PartialEq)]
pub enum SegmentVerdict {
    /// The determinant is proven nonzero on the whole segment.
    Clear {
        /// Its sign (±1).
        sign: f64,
        /// A proven lower bound of its magnitude on the segment.
        min_abs_det: f64,
        /// Pieces proven.
        pieces: usize,
    },
    /// The determinant is proven to change sign (at least once) within each crossing's enclosure.
    Crosses {
        /// The crossings, in order along the segment.
        crossings: Vec<Crossing>,
        /// Other stretches where the determinant may vanish without a proven sign change.
        undecided: Vec<Span>,
    },
    /// The determinant may vanish on these stretches; no sign change is proven.
    Undecided {
        /// The stretches, in order.
        spans: Vec<Span>,
    },
    /// Not decided: a limit stopped the run first.
    Stopped(Limit),
}

/// A proven sign change of the determinant.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    /// Enclosure `[t_lo, t_hi]` of the parameter (some t inside is a zero).
    pub t: [f64; 2],
    /// The joints over that enclosure (`[lo, hi]` each, radians), in the waypoints' order.
    pub joints: Vec<[f64; 2]>,
    /// The determinant's sign before the crossing (after it, the opposite).
    pub sign_before: f64,
    /// Whether the enclosure reached the tolerance (else a point inside could not be given a
    /// sign: the determinant is too close to zero there).
    pub narrowed: bool,
}

/// A stretch `[t_lo, t_hi]` on which the determinant may vanish.
#[derive(Clone, Debug, PartialEq)]
pub struct Span {
    /// The parameter's range.
    pub t: [f64; 2],
    /// The joints over it (`[lo, hi]` each, radians), in the waypoints' order.
    pub joints: Vec<[f64; 2]>,
    /// Why no sign change is claimed.
    pub reason: SpanReason,
}

/// Why a stretch is undecided rather than a crossing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpanReason {
    /// The determinant has the same proven sign on both sides: it may touch zero (or cross it
    /// an even number of times), or the enclosure is too loose there.
    SameSignBothSides,
    /// The stretch reaches the segment's start or end, where no sign is proven on the far side.
    AtEnd,
    /// The piece budget ran out before the stretch was examined.
    PieceBudget,
}

/// The verdicts of a path: one per segment, in order.
#[derive(Clone, Debug)]
pub struct PathCheck {
    /// The waypoints, joints in the determinant's order.
    pub waypoints: Vec<Vec<f64>>,
    /// One per segment (waypoint k to k + 1).
    pub segments: Vec<SegmentVerdict>,
}

/// Decides each segment of the path through `waypoints` (`det.joints()` values each, radians)
/// against the zero set of `det`; crossings narrowed until their joint enclosures are within
/// `tolerance` radians. `control` bounds the whole path: its timeout and cancel flag, its cells
/// (pieces examined, over every segment), its memory (bytes the pieces and pending stretches of
/// the segments being decided hold) and its threads (segments decided side by side, each on
/// one thread: the same verdicts for any count). A limit leaves the segment it stops, and
/// those not started, `Stopped`.
pub fn check(det: &dyn SignProof, waypoints: &[Vec<f64>], tolerance: f64, control: &Control) -> Result<PathCheck, BadPath> {
    let n = det.joints();
    if waypoints.len() < 2 {
        return Err(BadPath(format!("{} waypoint(s): a path needs at least two", waypoints.len())));
    }
    if let Some((k, _)) = waypoints.iter().enumerate().find(|(_, w)| w.len() != n || !w.iter().all(|x| x.is_finite())) {
        return Err(BadPath(format!("waypoint {} is not {} finite numbers", k + 1, number_word(n))));
    }
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(BadPath(format!("the tolerance must be a positive number of radians, got {tolerance}")));
    }
    let budget = Budget::start(control.limits, control.cancel);
    let work = Work { pieces: AtomicU64::new(0), bytes: AtomicUsize::new(0) };
    // The first limit met stops every segment: those being decided and those not started.
    let first = std::sync::OnceLock::new();
    let stop = || {
        if let Some(&limit) = first.get() {
            return Some(limit);
        }
        let limit = budget.interrupted().or_else(|| {
            if work.pieces.load(Ordering::Relaxed) > control.limits.max_cells {
                Some(Limit::Boxes)
            } else if work.bytes.load(Ordering::Relaxed) > control.limits.max_memory {
                Some(Limit::Memory)
            } else {
                None
            }
        })?;
        Some(*first.get_or_init(|| limit))
    };
    let pairs: Vec<&[Vec<f64>]> = waypoints.windows(2).collect();
    let segments = crate::kernel::search::map_parallel(&pairs, control.threads, |w| match stop() {
        Some(limit) => SegmentVerdict::Stopped(limit),
        None => Segment { det, x: &w[0], y: &w[1] }.decide(tolerance, &stop, &work),
    });
    Ok(PathCheck { waypoints: waypoints.to_vec(), segments })
}

/// Segments by verdict.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathCounts {
    /// det proven nonzero throughout.
    pub clear: usize,
    /// A sign change of det proven.
    pub crosses: usize,
    /// det may vanish, no sign change proven.
    pub touches_or_undecided: usize,
    /// Not decided (a limit stopped the run).
    pub not_decided: usize,
}

impl SpanReason {
    /// The name used in reports and messages.
    pub fn name(self) -> &'static str {
        match self {
            SpanReason::SameSignBothSides => "same_sign_both_sides",
            SpanReason::AtEnd => "at_segment_end",
            SpanReason::PieceBudget => "piece_budget",
        }
    }
}

impl SegmentVerdict {
    /// The name used in reports and messages.
    pub fn name(&self) -> &'static str {
        match self {
            SegmentVerdict::Clear { .. } => "clear",
            SegmentVerdict::Crosses { .. } => "crosses",
            SegmentVerdict::Undecided { .. } => "touches_or_undecided",
            SegmentVerdict::Stopped(_) => "not_decided",
        }
    }

    /// Why, in one line, the determinant named `det`.
    pub fn reason(&self, det: &str) -> String {
        match self {
            SegmentVerdict::Clear { sign, min_abs_det, pieces } => format!("{det} proven {} on the whole segment ({pieces} pieces), |{det}| >= {min_abs_det:.3e}", if *sign > 0.0 { "positive" } else { "negative" }),
            SegmentVerdict::Crosses { crossings, .. } => {
                let at: Vec<String> = crossings.iter().map(|c| format!("t in [{:.12}, {:.12}]", c.t[0], c.t[1])).collect();
                format!("{det} proven to change sign: {}", at.join(", "))
            }
            SegmentVerdict::Undecided { spans } => {
                let at: Vec<String> = spans.iter().map(|s| format!("t in [{:.6}, {:.6}] ({})", s.t[0], s.t[1], s.reason.name())).collect();
                format!("{det} may vanish, no sign change proven: {}", at.join(", "))
            }
            SegmentVerdict::Stopped(limit) => format!("not decided: the run stopped on its {} limit first", limit.name()),
        }
    }
}

impl PathCheck {
    /// Segments by verdict.
    pub fn counts(&self) -> PathCounts {
        let mut c = PathCounts::default();
        for s in &self.segments {
            match s {
                SegmentVerdict::Clear { .. } => c.clear += 1,
                SegmentVerdict::Crosses { .. } => c.crosses += 1,
                SegmentVerdict::Undecided { .. } => c.touches_or_undecided += 1,
                SegmentVerdict::Stopped(_) => c.not_decided += 1,
            }
        }
        c
    }

    /// The one rule: the first limit that stopped a segment, else the segments with a
    /// stretch left undecided (or a crossing not narrowed to the tolerance).
    pub fn completeness(&self) -> crate::kernel::outcome::Completeness {
        use crate::kernel::outcome::{Completeness, Status};
        let stopped = self.segments.iter().find_map(|s| match s {
            SegmentVerdict::Stopped(l) => Some(*l),
            _ => None,
        });
        let open = self
            .segments
            .iter()
            .filter(|s| match s {
                SegmentVerdict::Clear { .. } => false,
                SegmentVerdict::Crosses { crossings, undecided } => !undecided.is_empty() || crossings.iter().any(|c| !c.narrowed),
                SegmentVerdict::Undecided { .. } | SegmentVerdict::Stopped(_) => true,
            })
            .count();
        Completeness::of(stopped.map_or(Status::Finished, Status::Stopped), open, false)
    }
}

/// Small counts in words, as messages about six-joint waypoints have always said them.
fn number_word(n: usize) -> String {
    match n {
        3 => "three".into(),
        6 => "six".into(),
        _ => n.to_string(),
    }
}

/// What the segments being decided use, counted against `Control::limits`.
struct Work {
    /// Pieces examined, over every segment.
    pieces: AtomicU64,
    /// Bytes the segments being decided hold in pieces and pending stretches.
    bytes: AtomicUsize,
}

/// Pieces examined between two updates of the memory held.
const CHECK_EVERY: usize = 256;

struct Segment<'a> {
    det: &'a dyn SignProof,
    x: &'a [f64],
    y: &'a [f64],
}

/// A piece of the cover: proven (sign, lower bound of |det|) or not.
#[derive(Clone, Copy, Debug)]
struct Piece {
    t0: f64,
    t1: f64,
    proof: Option<(f64, f64)>,
    /// Left unexamined when the budget ran out.
    skipped: bool,
}

impl Segment<'_> {
    fn at(&self, t: f64) -> Vec<f64> {
        self.x.iter().zip(self.y).map(|(x, y)| x + t * (y - x)).collect()
    }

    /// A box holding the exact segment points for t ∈ [t0, t1]: the hull of the computed ends,
    /// padded for the rounding of `at`.
    fn hull(&self, t0: f64, t1: f64) -> Vec<[f64; 2]> {
        let (a, b) = (self.at(t0), self.at(t1));
        (0..self.x.len())
            .map(|k| {
                let pad = 4.0 * f64::EPSILON * (1.0 + self.x[k].abs() + self.y[k].abs());
                [a[k].min(b[k]) - pad, a[k].max(b[k]) + pad]
            })
            .collect()
    }

    fn prove(&self, t0: f64, t1: f64) -> Option<Proof> {
        self.det.prove(&self.hull(t0, t1))
    }

    fn decide(&self, tolerance: f64, stop: &(dyn Fn() -> Option<Limit> + Sync), work: &Work) -> SegmentVerdict {
        // What this segment holds, as last added to `work.bytes` (given back when it ends).
        let mut held = 0usize;
        let verdict = self.cover(tolerance, stop, work, &mut held);
        work.bytes.fetch_sub(held, Ordering::Relaxed);
        verdict
    }

    fn cover(&self, tolerance: f64, stop: &(dyn Fn() -> Option<Limit> + Sync), work: &Work, held: &mut usize) -> SegmentVerdict {
        // Cover [0, 1] by pieces, depth first, left to right.
        let mut pieces: Vec<Piece> = Vec::new();
        let mut stack = vec![(0.0f64, 1.0f64)];
        let mut examined = 0;
        while let Some((t0, t1)) = stack.pop() {
            if examined >= MAX_PIECES {
                pieces.push(Piece { t0, t1, proof: None, skipped: true });
                continue;
            }
            if examined % CHECK_EVERY == 0 {
                let now = pieces.capacity() * std::mem::size_of::<Piece>() + stack.capacity() * std::mem::size_of::<(f64, f64)>();
                if now >= *held {
                    work.bytes.fetch_add(now - *held, Ordering::Relaxed);
                } else {
                    work.bytes.fetch_sub(*held - now, Ordering::Relaxed);
                }
                *held = now;
            }
            // Every piece counts against the box limit, asked before each, so that one thread
            // stops at the same piece whatever the clock says.
            work.pieces.fetch_add(1, Ordering::Relaxed);
            if let Some(limit) = stop() {
                return SegmentVerdict::Stopped(limit);
            }
            examined += 1;
            let narrow = t1 - t0 <= PIECE_WIDTH;
            match self.prove(t0, t1) {
                Some(p) if p.tight || narrow => pieces.push(Piece { t0, t1, proof: Some((p.sign, p.min_abs)), skipped: false }),
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
        // Every piece proven: one sign throughout (the determinant is continuous and never zero).
        let sign = pieces[0].proof.expect("invariant: all proven").0;
        let min_abs_det = pieces.iter().filter_map(|p| p.proof).fold(f64::INFINITY, |m, p| m.min(p.1));
        SegmentVerdict::Clear { sign, min_abs_det, pieces: pieces.len() }
    }

    /// Bisects the sign change in `[lo, hi]` (sign `before` proven at `lo`, the opposite at
    /// `hi`) until its joint enclosure is within `tolerance`, or a midpoint's sign cannot be
    /// proven.
    fn narrow(&self, mut lo: f64, mut hi: f64, before: f64, tolerance: f64) -> Crossing {
        let span = self.x.iter().zip(self.y).fold(0.0f64, |m, (x, y)| m.max((y - x).abs()));
        let mut narrowed = true;
        while (hi - lo) * span > tolerance {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            match self.prove(mid, mid) {
                Some(p) if p.sign == before => lo = mid,
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicBool;

    /// `det = (q₀ − 0.3)·(q₁ + 2)`, proven from its interval value on the box.
    struct Toy;

    impl SignProof for Toy {
        fn joints(&self) -> usize {
            2
        }

        fn prove(&self, b: &[[f64; 2]]) -> Option<Proof> {
            let d = crate::kernel::interval::interval(b[0][0], b[0][1]) - crate::kernel::interval::point(0.3);
            let e = crate::kernel::interval::interval(b[1][0], b[1][1]) + crate::kernel::interval::point(2.0);
            let v = d * e;
            (!v.contains(0.0)).then(|| Proof { sign: v.inf().signum(), min_abs: v.mig(), tight: v.mig() >= 0.25 * v.mag() })
        }
    }

    #[test]
    fn a_sign_change_is_a_crossing_and_a_zero_free_segment_is_clear() {
        let cancel = AtomicBool::new(false);
        let control = Control { limits: Default::default(), threads: 1, cancel: &cancel };
        let w = [vec![0.0, 0.0], vec![1.0, 1.0], vec![2.0, 0.5]];
        let found = check(&Toy, &w, 1e-10, &control).expect("checks");
        let SegmentVerdict::Crosses { crossings, undecided } = &found.segments[0] else { panic!("{:?}", found.segments[0]) };
        assert!(undecided.is_empty() && crossings.len() == 1);
        assert!(crossings[0].t[0] <= 0.3 && 0.3 <= crossings[0].t[1] && crossings[0].narrowed && crossings[0].sign_before == -1.0, "{crossings:?}");
        let SegmentVerdict::Clear { sign, min_abs_det, .. } = found.segments[1] else { panic!("{:?}", found.segments[1]) };
        assert!(sign == 1.0 && min_abs_det > 0.0 && min_abs_det <= 0.7 * 2.5);
        assert_eq!(check(&Toy, &[vec![0.0, 0.0], vec![1.0]], 1e-9, &control).err(), Some(BadPath("waypoint 2 is not 2 finite numbers".into())));
    }

    /// Every limit of the control stops the path, the segment it falls in and those after:
    /// along q₀ = 0.3 the toy determinant vanishes on the whole first segment, which is cut
    /// down to `PIECE_WIDTH` (16,384 pieces, half a megabyte).
    #[test]
    fn every_limit_of_the_control_stops_the_path() {
        use crate::kernel::search::Limits;
        let cancel = AtomicBool::new(false);
        let w = [vec![0.3, 0.0], vec![0.3, 1.0], vec![1.0, 1.0], vec![0.0, 0.5]];
        let with = |limits: Limits, threads: usize| check(&Toy, &w, 1e-10, &Control { limits, threads, cancel: &cancel }).expect("checks").segments;
        let free = with(Limits::default(), 1);
        assert!(matches!(free[0], SegmentVerdict::Undecided { .. }) && matches!(free[2], SegmentVerdict::Crosses { .. }), "{free:?}");
        assert_eq!(with(Limits::default(), 3), free, "the verdicts of one thread");
        for (limits, limit) in [(Limits { max_memory: 1000, ..Limits::default() }, Limit::Memory), (Limits { max_cells: 100, ..Limits::default() }, Limit::Boxes)] {
            for threads in [1, 2] {
                let stopped = with(limits, threads);
                assert_eq!(stopped[0], SegmentVerdict::Stopped(limit), "{limit:?}, {threads} threads");
                assert!(stopped.iter().filter(|s| **s == SegmentVerdict::Stopped(limit)).count() >= if threads == 1 { 3 } else { 1 }, "{stopped:?}");
            }
        }
        let stopped = with(Limits { max_cells: 100, ..Limits::default() }, 1);
        assert!(stopped.iter().all(|s| *s == SegmentVerdict::Stopped(Limit::Boxes)), "{stopped:?}");
    }
}

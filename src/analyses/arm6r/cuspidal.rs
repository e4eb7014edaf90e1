//! Whole-arm cuspidality of a 6R arm: a certified witness, or an honest "undecided".
//!
//! An arm is cuspidal iff two inverse-kinematics solutions of one pose (distinct on the joint
//! torus) are joined by a joint-space path on which `det J` never vanishes. A witness is such
//! a pose, two certified solutions (`ik` boxes, each holding exactly one) and a piecewise-linear
//! path between them whose every piece is proven free of singularities: the interval Jacobian
//! over a box holding the piece is regular (`‖I − Y·J(B)‖∞ < 1` with `Y ≈ mid(J)⁻¹`, in
//! outward arithmetic), pieces subdivided until proven. The path starts and ends inside the
//! solutions' boxes, which are proven regular too, so it reaches the exact solutions.
//!
//! The search samples joint vectors, solves their poses, and for pairs with the same sign of
//! `det J` tries the straight line, then paths through a few random waypoints of that sign,
//! within a time budget. Proving an arm non-cuspidal needs a theorem, which this module does
//! not apply (the caller states when one does, e.g. a spherical wrist and the 3R verdict).

// Matrix and joint indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::chain::{Chain6R, Side};
use super::jacobian::regular_over;
use super::ik::{self, PoseTarget};
use super::Pose64;
use crate::kernel::interval::Interval;
use crate::kernel::search::{Control, Limits};
use std::time::{Duration, Instant};

/// A proof that the arm is cuspidal (see the module doc).
#[derive(Clone, Debug)]
pub struct Witness {
    /// The pose (tip frame in the base frame), as computed in `f64`; the solutions are certified
    /// for every rigid pose within `pose_radius` of it entry-wise.
    pub pose: Pose64,
    /// The entry-wise radius of the pose enclosure solved.
    pub pose_radius: f64,
    /// The two solutions' boxes, each proven to hold exactly one solution.
    pub from: [Interval; 6],
    /// See `from`.
    pub to: [Interval; 6],
    /// The path's vertices, from the midpoint of `from` to the midpoint of `to`.
    pub path: Vec<[f64; 6]>,
    /// Boxes proven free of singularities along the path (the pieces after subdivision).
    pub pieces: usize,
    /// The sign of `det J` along the path.
    pub det_sign: f64,
    /// The smallest `|det J|` seen at the sampled points of the path (`f64`, for the report).
    pub min_abs_det: f64,
}

/// The pose with the most solutions the search solved: a certified lower bound on the arm's
/// maximum number of inverse-kinematics solutions.
#[derive(Clone, Debug)]
pub struct MostSolutions {
    /// Solutions at `pose`, each in its own box proven to hold exactly one, no two the same
    /// configuration.
    pub count: usize,
    /// The pose (tip frame in the base frame), as computed in `f64`; certified for every rigid
    /// pose within `pose_radius` of it entry-wise.
    pub pose: Pose64,
    /// See `pose`.
    pub pose_radius: f64,
}

/// What a search found: the verdict, and the pose with the most certified solutions seen.
#[derive(Clone, Debug)]
pub struct SearchOutcome {
    /// Cuspidal with a witness, or undecided.
    pub verdict: CuspidalVerdict,
    /// `None` when no pose was solved.
    pub most: Option<MostSolutions>,
}

/// The whole-arm verdict.
#[derive(Clone, Debug)]
pub enum CuspidalVerdict {
    /// Proven by a witness.
    Cuspidal(Box<Witness>),
    /// No witness found within the budget: nothing is claimed.
    Undecided {
        /// Poses whose solutions were examined.
        poses: usize,
        /// Pairs of solutions with the same sign of `det J` tried.
        pairs: usize,
    },
}

/// A small deterministic generator (SplitMix64), so that a run is reproducible from its seed.
pub(super) struct Rng(pub(super) u64);

impl Rng {
    pub(super) fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    pub(super) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// Proves the segment `x → y` free of singularities by subdividing it into at most
/// `max_pieces` pieces; the number used, or None.
fn prove_segment(arm: &Side<6>, x: &[f64; 6], y: &[f64; 6], max_pieces: usize) -> Option<usize> {
    let mut stack = vec![(0.0f64, 1.0f64)];
    let mut proven = 0;
    let at = |t: f64| -> [f64; 6] { [0, 1, 2, 3, 4, 5].map(|k| x[k] + t * (y[k] - x[k])) };
    while let Some((t0, t1)) = stack.pop() {
        let (a, b) = (at(t0), at(t1));
        // The piece is the segment between a and b: its hull, padded for the rounding of `at`.
        let bx = [0, 1, 2, 3, 4, 5].map(|k| {
            let pad = 4.0 * f64::EPSILON * (1.0 + x[k].abs() + y[k].abs());
            [a[k].min(b[k]) - pad, a[k].max(b[k]) + pad]
        });
        if regular_over(arm, &bx) {
            proven += 1;
            continue;
        }
        if proven + stack.len() + 2 > max_pieces || t1 - t0 < 1e-9 {
            return None;
        }
        let tm = 0.5 * (t0 + t1);
        stack.push((tm, t1));
        stack.push((t0, tm));
    }
    Some(proven)
}

/// `det J` sampled densely along the polyline: its smallest magnitude when the sign stays
/// `sign` throughout, else None (a cheap screen before the proof).
fn screen(chain: &Chain6R, path: &[[f64; 6]], sign: f64) -> Option<f64> {
    let mut least = f64::INFINITY;
    for w in path.windows(2) {
        for i in 0..=64 {
            let t = i as f64 / 64.0;
            let q = [0, 1, 2, 3, 4, 5].map(|k| w[0][k] + t * (w[1][k] - w[0][k]));
            let d = chain.det_jacobian(&q) * sign;
            if d.is_nan() || d <= 0.0 {
                return None;
            }
            least = least.min(d);
        }
    }
    Some(least)
}

/// Whether the two boxes hold the same configuration of the torus: every coordinate meets
/// modulo a turn.
fn same_on_torus(a: &[Interval; 6], b: &[Interval; 6]) -> bool {
    let turn = std::f64::consts::TAU;
    (0..6).all(|d| (-2..=2).any(|n: i32| {
        let s = n as f64 * turn;
        a[d].inf() <= b[d].sup() + s + 1e-9 && b[d].inf() + s <= a[d].sup() + 1e-9
    }))
}

fn mid6(b: &[Interval; 6]) -> [f64; 6] {
    b.map(|x| x.mid())
}

fn hull(b: &[Interval; 6]) -> [[f64; 2]; 6] {
    b.map(|x| [x.inf(), x.sup()])
}

/// Searches a witness (module doc) for `budget`, from `seed`; `control` bounds each IK solve
/// and its cancel flag stops the search.
pub fn search(chain: &Chain6R, budget: Duration, seed: u64, control: &Control) -> SearchOutcome {
    let start = Instant::now();
    // Cuspidality is a property of configurations: joint limits play no part, one turn per
    // joint holds every configuration once.
    let chain = &chain.clone().within_one_turn();
    let arm = chain.arm();
    let mut rng = Rng(seed);
    let (mut poses, mut pairs) = (0, 0);
    let mut most: Option<MostSolutions> = None;
    let limits = Limits { max_cells: control.limits.max_cells.min(400_000), ..control.limits };
    let ik_control = Control { limits, ..*control };
    let radius = 1e-12;
    let in_range = |rng: &mut Rng| -> [f64; 6] { [0, 1, 2, 3, 4, 5].map(|k| rng.uniform(chain.ranges[k].0, chain.ranges[k].1)) };
    while start.elapsed() < budget && !control.cancel.load(std::sync::atomic::Ordering::Relaxed) {
        let q = in_range(&mut rng);
        let pose = chain.pose(&q);
        let Ok(target) = PoseTarget::around(&pose, radius) else { continue };
        let Ok(sol) = ik::solve(chain, &target, 1e-11, &ik_control) else { continue };
        poses += 1;
        let distinct = (0..sol.unique.len()).filter(|&i| !(0..i).any(|j| same_on_torus(&sol.unique[i], &sol.unique[j]))).count();
        if most.as_ref().is_none_or(|m: &MostSolutions| distinct > m.count) {
            most = Some(MostSolutions { count: distinct, pose, pose_radius: radius });
        }
        let signs: Vec<f64> = sol.unique.iter().map(|u| chain.det_jacobian(&mid6(u)).signum()).collect();
        for i in 0..sol.unique.len() {
            for j in i + 1..sol.unique.len() {
                let (a, b) = (&sol.unique[i], &sol.unique[j]);
                if signs[i] != signs[j] || signs[i] == 0.0 || same_on_torus(a, b) {
                    continue;
                }
                pairs += 1;
                if !(regular_over(&arm, &hull(a)) && regular_over(&arm, &hull(b))) {
                    continue;
                }
                let (qa, qb) = (mid6(a), mid6(b));
                let mut candidates: Vec<Vec<[f64; 6]>> = vec![vec![qa, qb]];
                for _ in 0..40 {
                    let w = in_range(&mut rng);
                    if chain.det_jacobian(&w).signum() != signs[i] {
                        continue;
                    }
                    candidates.push(vec![qa, w, qb]);
                    let w2 = in_range(&mut rng);
                    if chain.det_jacobian(&w2).signum() == signs[i] {
                        candidates.push(vec![qa, w, w2, qb]);
                    }
                }
                for path in candidates {
                    if start.elapsed() >= budget {
                        break;
                    }
                    let Some(least) = screen(chain, &path, signs[i]) else { continue };
                    let mut pieces = 0;
                    let proven = path.windows(2).all(|w| match prove_segment(&arm, &w[0], &w[1], 4096) {
                        Some(n) => {
                            pieces += n;
                            true
                        }
                        None => false,
                    });
                    if proven {
                        let verdict = CuspidalVerdict::Cuspidal(Box::new(Witness {
                            pose,
                            pose_radius: radius,
                            from: *a,
                            to: *b,
                            path,
                            pieces: pieces + 2,
                            det_sign: signs[i],
                            min_abs_det: least,
                        }));
                        return SearchOutcome { verdict, most };
                    }
                }
            }
        }
    }
    SearchOutcome { verdict: CuspidalVerdict::Undecided { poses, pairs }, most }
}

//! The JSON of `linkspace ik6` and the `arm_cuspidality` section of `singularities` for
//! six-joint arms, and of `path-check` (against the 6R arm's or a 3R positioning structure's
//! singular set), from `app`'s results.

use super::kernel::CompletenessDef;
use crate::kernel::outcome::Completeness;
use crate::app::{ArmCuspidality, ArmIk6, ArmPathCheck};
use crate::kernel::interval::Interval;
use crate::analyses::joint_path::{PathCounts, SegmentVerdict, Span};
use crate::analyses::arm6r::{Chain6R, CuspidalVerdict, MostSolutions};

use serde::Serialize;
use std::collections::BTreeMap;

/// One solution box: joint name → [lo, hi] (radians).
pub type JointBoxes = BTreeMap<String, [f64; 2]>;

fn joints(chain: &Chain6R, b: &[Interval; 6]) -> JointBoxes {
    chain.joints.iter().zip(b).map(|(n, x)| (n.clone(), [x.inf(), x.sup()])).collect()
}

/// What `linkspace ik6 --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct Ik6Report {
    /// Base and tip links.
    pub base: String,
    /// See `base`.
    pub tip: String,
    /// The six joints, base first.
    pub joints: Vec<String>,
    /// The pose as given (base frame): 6 numbers x, y, z, roll, pitch, yaw; 7 x, y, z, qx, qy,
    /// qz, qw; 16 a 4x4 matrix, row-major.
    pub pose: Vec<f64>,
    /// `status` and, when incomplete, `limit`.
    #[serde(flatten, serialize_with = "CompletenessDef::serialize")]
    pub completeness: Completeness,
    /// Boxes each proven to hold exactly one solution.
    pub unique: Vec<JointBoxes>,
    /// Hulls of undecided boxes (near singular poses): each may hold solutions.
    pub clusters: Vec<JointBoxes>,
    /// At a wrist- or shoulder-singular pose: where the singular branches' solutions lie, on
    /// curves (or, just off the singularity, at isolated points on them).
    pub curves: Vec<CurveRecord>,
    /// Boxes processed (for the closed form: candidates certified).
    pub processed: u64,
    /// Which method answered: `closed_form` (a recognised geometry, every candidate certified),
    /// `search` (branch and prune), or `closed_form_and_search` (the certified candidates, and
    /// branch and prune on a box about each candidate left).
    pub method: &'static str,
    /// For a geometry the closed form applies to, why it left this pose, or some of its
    /// candidates, to the search (a
    /// discriminant holding 0 near a singular pose, an angle at a joint limit, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closed_form_declined: Option<&'static str>,
    /// Wall time (seconds).
    pub seconds: f64,
}

impl Ik6Report {
    /// The report of a query.
    pub fn of(chain: &Chain6R, found: &ArmIk6) -> Self {
        let s = &found.solutions;
        Ik6Report {
            base: chain.base.clone(),
            tip: chain.tip.clone(),
            joints: chain.joints.to_vec(),
            pose: found.pose.numbers().to_vec(),
            completeness: Completeness::of(s.status, s.clusters.len(), false),
            unique: s.unique.iter().map(|b| joints(chain, b)).collect(),
            clusters: s.clusters.iter().map(|c| joints(chain, &c.hull)).collect(),
            curves: s.curves.iter().map(|c| CurveRecord { kind: c.kind.name(), moving: c.kind.moving().iter().map(|&k| chain.joints[k].clone()).collect(), ranges: joints(chain, &c.hull), cover: c.cover.iter().map(|b| joints(chain, b)).collect() }).collect(),
            processed: s.stats.processed,
            method: s.method.name(),
            closed_form_declined: s.method.declined().map(|d| d.name()),
            seconds: found.seconds,
        }
    }
}

/// A singular branch's solutions: enclosed by `cover` (each box may hold solutions).
#[derive(Clone, Debug, Serialize)]
pub struct CurveRecord {
    /// `wrist_singular` (joints 4 and 6 turn together, one branch of joints 1–3) or
    /// `shoulder_singular` (the wrist centre on axis 1: joint 1 turns freely, joints 4–6
    /// follow; every branch's boxes).
    pub kind: &'static str,
    /// The joints that move along the curve.
    pub moving: Vec<String>,
    /// The joints' ranges along it (the cover's hull).
    pub ranges: JointBoxes,
    /// Boxes enclosing the solutions within the joint ranges, the curve's parameter (joint 4,
    /// or joint 1 at the shoulder) in pieces at most 1/32 rad wide.
    pub cover: Vec<JointBoxes>,
}

/// The `arm_cuspidality` field of `singularities --json` for six-joint arms.
#[derive(Clone, Debug, Serialize)]
pub struct ArmCuspidalityReport {
    /// The arm: base, tip and its six joints.
    pub arm: String,
    /// `cuspidal`, `non_cuspidal` (proven by a theorem the `proof` states), `undecided`, or
    /// `as_positioning_structure` (spherical wrist: the 3R verdict is the arm's).
    pub verdict: &'static str,
    /// Why, in one line.
    pub reason: String,
    /// The theorem a `non_cuspidal` verdict applies: its conditions, proven on the file's
    /// geometry, and its argument.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub proof: Option<String>,
    /// The witness of a cuspidal verdict.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub witness: Option<WitnessRecord>,
    /// The pose with the most inverse-kinematics solutions the witness search solved: a
    /// certified lower bound on the arm's maximum (none for verdicts that need no search).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub most_solutions: Option<MostSolutionsRecord>,
}

/// A pose and how many solutions it has, each certified in its own box.
#[derive(Clone, Debug, Serialize)]
pub struct MostSolutionsRecord {
    /// Distinct solutions, each proven unique in its box.
    pub count: usize,
    /// The pose's rotation (row-major) and translation, base frame.
    pub pose_rotation: [[f64; 3]; 3],
    /// See `pose_rotation`.
    pub pose_translation: [f64; 3],
    /// Entry-wise radius of the pose enclosure solved.
    pub pose_radius: f64,
}

impl MostSolutionsRecord {
    fn of(m: &MostSolutions) -> Self {
        MostSolutionsRecord { count: m.count, pose_rotation: m.pose.r, pose_translation: m.pose.t, pose_radius: m.pose_radius }
    }
}

/// A cuspidality witness: a pose, two certified solutions, a path proven free of singularities.
#[derive(Clone, Debug, Serialize)]
pub struct WitnessRecord {
    /// The pose's rotation (row-major) and translation, base frame.
    pub pose_rotation: [[f64; 3]; 3],
    /// See `pose_rotation`.
    pub pose_translation: [f64; 3],
    /// Entry-wise radius of the pose enclosure solved.
    pub pose_radius: f64,
    /// The two solutions' boxes, each holding exactly one.
    pub from: JointBoxes,
    /// See `from`.
    pub to: JointBoxes,
    /// The path's vertices (radians, joints base first).
    pub path: Vec<[f64; 6]>,
    /// Boxes proven free of singularities along it.
    pub pieces: usize,
    /// The sign of det J along the path.
    pub det_sign: f64,
    /// The smallest |det J| at the sampled points.
    pub min_abs_det: f64,
}

impl ArmCuspidalityReport {
    /// The section of an arm's verdict.
    pub fn of(chain: &Chain6R, c: &ArmCuspidality) -> Self {
        let arm = format!("{} -> {} ({})", chain.base, chain.tip, chain.joints.join(", "));
        let line = c.line();
        let witness = match c {
            ArmCuspidality::Searched { verdict: CuspidalVerdict::Cuspidal(w), .. } => Some(WitnessRecord {
                pose_rotation: w.pose.r,
                pose_translation: w.pose.t,
                pose_radius: w.pose_radius,
                from: joints(chain, &w.from),
                to: joints(chain, &w.to),
                path: w.path.clone(),
                pieces: w.pieces,
                det_sign: w.det_sign,
                min_abs_det: w.min_abs_det,
            }),
            _ => None,
        };
        let proof = matches!(c, ArmCuspidality::ThreeParallel { .. }).then(|| crate::analyses::arm6r::three_parallel::CITATION.to_string());
        let most_solutions = match c {
            ArmCuspidality::Searched { most: Some(m), .. } => Some(MostSolutionsRecord::of(m)),
            _ => None,
        };
        ArmCuspidalityReport { arm, verdict: line.verdict.name(), reason: line.reason, proof, witness, most_solutions }
    }
}

/// What `linkspace path-check --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct PathCheckReport {
    /// The arm: base, tip and the joints of the waypoints.
    pub arm: String,
    /// The singular set checked against: `6r` (the six-revolute arm's, det J = 0) or `3r` (its
    /// 3R positioning structure's, det Df = 0).
    pub singular_set: &'static str,
    /// What the verdicts concern: the arm, or the 3R sub-chain and its point, and the
    /// determinant (`det J` or `det Df`; "det" in the fields below).
    pub subject: String,
    /// The joints, in the order of the waypoints' values.
    pub joints: Vec<String>,
    /// Radians: the width crossings were narrowed to (joint space).
    pub tolerance: f64,
    /// `complete` (every segment clear or crossing, narrowed), or `incomplete` with `limit`:
    /// the limit that stopped a segment, else `undecided`.
    #[serde(flatten, serialize_with = "super::kernel::CompletenessDef::serialize")]
    pub status: crate::kernel::outcome::Completeness,
    /// Segments by verdict.
    #[serde(with = "PathCountsDef")]
    pub counts: PathCounts,
    /// One per segment, in order.
    pub segments: Vec<SegmentRecord>,
    /// Wall time (seconds).
    pub seconds: f64,
    #[serde(skip)]
    headline: String,
}

/// `joint_path::PathCounts`, field by field.
#[derive(Serialize)]
#[serde(remote = "PathCounts")]
struct PathCountsDef {
    clear: usize,
    crosses: usize,
    touches_or_undecided: usize,
    not_decided: usize,
}

/// One segment's verdict.
#[derive(Clone, Debug, Serialize)]
pub struct SegmentRecord {
    /// The segment's start and end waypoints (radians, joints in order).
    pub from: Vec<f64>,
    /// See `from`.
    pub to: Vec<f64>,
    /// `clear`, `crosses`, `touches_or_undecided` or `not_decided`.
    pub verdict: &'static str,
    /// Why, in one line.
    pub reason: String,
    /// For `clear`: the sign of det on the segment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub det_sign: Option<f64>,
    /// For `clear`: a proven lower bound of |det| on the segment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_abs_det: Option<f64>,
    /// For `crosses`: each proven sign change.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub crossings: Vec<CrossingRecord>,
    /// Stretches where det may vanish without a proven sign change.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub undecided: Vec<SpanRecord>,
}

/// A proven sign change of det on a segment.
#[derive(Clone, Debug, Serialize)]
pub struct CrossingRecord {
    /// Enclosure [t_lo, t_hi] of the segment parameter (0 at `from`, 1 at `to`).
    pub t: [f64; 2],
    /// The joints over it: joint name → [lo, hi].
    pub joints: JointBoxes,
    /// The sign of det before the crossing.
    pub sign_before: f64,
    /// Whether the enclosure reached the tolerance.
    pub narrowed: bool,
}

/// A stretch where det may vanish.
#[derive(Clone, Debug, Serialize)]
pub struct SpanRecord {
    /// The parameter's range.
    pub t: [f64; 2],
    /// The joints over it: joint name → [lo, hi].
    pub joints: JointBoxes,
    /// `same_sign_both_sides`, `at_segment_end` or `piece_budget`.
    pub reason: &'static str,
}

fn joint_bounds(joints: &[String], b: &[[f64; 2]]) -> JointBoxes {
    joints.iter().zip(b).map(|(n, x)| (n.clone(), *x)).collect()
}

impl PathCheckReport {
    /// The report of a check.
    pub fn of(found: &ArmPathCheck) -> Self {
        let names = &found.joints;
        let det = found.set.det();
        let spans = |s: &[Span]| -> Vec<SpanRecord> { s.iter().map(|s| SpanRecord { t: s.t, joints: joint_bounds(names, &s.joints), reason: s.reason.name() }).collect() };
        let w = &found.check.waypoints;
        let segments = found
            .check
            .segments
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let mut record = SegmentRecord {
                    from: w[k].clone(),
                    to: w[k + 1].clone(),
                    verdict: v.name(),
                    reason: v.reason(det),
                    det_sign: None,
                    min_abs_det: None,
                    crossings: Vec::new(),
                    undecided: Vec::new(),
                };
                match v {
                    SegmentVerdict::Clear { sign, min_abs_det, .. } => {
                        record.det_sign = Some(*sign);
                        record.min_abs_det = Some(*min_abs_det);
                    }
                    SegmentVerdict::Crosses { crossings, undecided } => {
                        record.crossings = crossings
                            .iter()
                            .map(|c| CrossingRecord { t: c.t, joints: joint_bounds(names, &c.joints), sign_before: c.sign_before, narrowed: c.narrowed })
                            .collect();
                        record.undecided = spans(undecided);
                    }
                    SegmentVerdict::Undecided { spans: s } => record.undecided = spans(s),
                    SegmentVerdict::Stopped(_) => {}
                }
                record
            })
            .collect();
        PathCheckReport {
            arm: found.arm.clone(),
            singular_set: found.set.name(),
            subject: found.subject.clone(),
            joints: names.clone(),
            tolerance: found.tolerance,
            status: found.completeness(),
            counts: found.check.counts(),
            segments,
            seconds: found.seconds,
            headline: found.headline(),
        }
    }

    /// The one-line summary (`ArmPathCheck::headline`).
    pub fn headline(&self) -> String {
        self.headline.clone()
    }
}

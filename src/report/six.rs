//! The JSON of `linkspace ik6` and the `arm_cuspidality` section of `singularities` for
//! six-joint arms, from `app`'s results.

use super::manip3r::Completeness;
use crate::app::{ArmCuspidality, ArmIk6};
use crate::interval::Interval;
use crate::manip6r::{Chain6R, CuspidalVerdict, MostSolutions};
use crate::search::Incompleteness;
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
    /// The pose: x, y, z, roll, pitch, yaw (base frame).
    pub pose: [f64; 6],
    /// `status` and, when incomplete, `limit`.
    #[serde(flatten)]
    pub completeness: Completeness,
    /// Boxes each proven to hold exactly one solution.
    pub unique: Vec<JointBoxes>,
    /// Hulls of undecided boxes (near singular poses): each may hold solutions.
    pub clusters: Vec<JointBoxes>,
    /// Boxes processed.
    pub processed: u64,
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
            pose: found.pose,
            completeness: Completeness(Incompleteness::of(s.status, s.clusters.len(), false)),
            unique: s.unique.iter().map(|b| joints(chain, b)).collect(),
            clusters: s.clusters.iter().map(|c| joints(chain, &c.hull)).collect(),
            processed: s.stats.processed,
            seconds: found.seconds,
        }
    }
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
    fn of(m: &Option<MostSolutions>) -> Option<Self> {
        m.as_ref().map(|m| MostSolutionsRecord { count: m.count, pose_rotation: m.pose.r, pose_translation: m.pose.t, pose_radius: m.pose_radius })
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
        match c {
            ArmCuspidality::PositioningVerdict => ArmCuspidalityReport {
                arm,
                verdict: "as_positioning_structure",
                reason: "spherical wrist: the arm is cuspidal iff its 3R positioning structure is (the verdict above is the arm's)".into(),
                proof: None,
                witness: None,
                most_solutions: None,
            },
            ArmCuspidality::ThreeParallel { proof, snapped } => ArmCuspidalityReport {
                arm,
                verdict: "non_cuspidal",
                reason: format!(
                    "UR family proven on the {}: axes 2, 3, 4 exactly parallel (distances {:.6} and {:.6}), axis 1 not parallel to them, axis 5 normal to them, axes 5 and 6 meeting at right angles; det J = ±g1·g3·g5 (shoulder, elbow, wrist) and the signs of the three factors tell every pose's solutions apart, so no two lie in one aspect",
                    if snapped.is_empty() { "file's geometry as written".to_string() } else { format!("geometry after snapping {} values to quarter turns / coordinate axes", snapped.len()) },
                    proof.l2.mid(),
                    proof.l3.mid()
                ),
                proof: Some(crate::manip6r::three_parallel::CITATION.to_string()),
                witness: None,
                most_solutions: None,
            },
            ArmCuspidality::Searched { verdict: CuspidalVerdict::Cuspidal(w), seconds, most, .. } => ArmCuspidalityReport {
                arm,
                verdict: "cuspidal",
                reason: format!("witness found in {seconds:.1} s: two certified solutions of one pose joined by a path on which det J is proven nonzero ({} pieces)", w.pieces),
                proof: None,
                witness: Some(WitnessRecord {
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
                most_solutions: MostSolutionsRecord::of(most),
            },
            ArmCuspidality::Searched { verdict: CuspidalVerdict::Undecided { poses, pairs }, budget, most, .. } => ArmCuspidalityReport {
                arm,
                verdict: "undecided",
                reason: format!("no witness found within the budget ({budget:.0} s: {poses} poses solved, {pairs} pairs of solutions with one sign of det J tried); non-cuspidality is not proven"),
                proof: None,
                witness: None,
                most_solutions: MostSolutionsRecord::of(most),
            },
        }
    }
}

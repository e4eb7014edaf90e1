//! What `linkspace singularities`, `linkspace ik` and `linkspace collisions` write with `--json`
//! (schema in README), built from the application layer's results (`app::arm`).
//!
//! Pure data; no IO. Joint intervals are keyed by URDF joint name, workspace intervals give the
//! radius (distance of the end point from the first axis, √ρ) and z (along the first axis, from
//! the first joint's origin). The 3R analyses' own records (`arm3r`'s verdict, singular
//! branches, chain choice, joint limits) are written through the remote definitions at the end.

use crate::app::{Arm, ArmIk, IkPoint, SingularitiesAnswer};
use crate::analyses::arm3r::branches::{Attribution, CrossingRecord, FoldSample, ImageRecord, IsolatedNode, SingularBranch, SingularBranches};
use crate::analyses::arm3r::chain::Chain3R;
use crate::analyses::arm3r::cusps::{CuspDiscard, CuspSearch, Reason};
use crate::analyses::arm3r::ik::IkSolutions;
use crate::analyses::arm3r::limits::{JointLimits, LimitEffect};
use crate::analyses::arm3r::motion::{self, Band};
use crate::analyses::arm3r::nodes::{NodeDiscard, NodeSearch};
use crate::kernel::interval::Bounds;
use crate::analyses::arm3r::records::{bounds, joints, workspace};
pub use crate::analyses::arm3r::{Joints, Workspace};
use crate::analyses::arm3r::select::{Choice, Scope};
use super::verdicts::{VerdictRecord, Verdicts};
use crate::analyses::arm3r::Prepared;
use crate::model::rounding::Snap;
use super::kernel::CompletenessDef;
use crate::kernel::outcome::{Completeness, Incompleteness};
use inari::Interval;
use serde::Serialize;

/// One cusp.
#[derive(Clone, Debug, Serialize)]
pub struct CuspRecord {
    /// Joint box holding the cusp.
    pub joints: Joints,
    /// Its image.
    #[serde(with = "WorkspaceDef")]
    pub workspace: Workspace,
    /// True when exactly one cusp is proven in the box.
    pub unique: bool,
}

/// One node: two joint boxes with a shared image.
#[derive(Clone, Debug, Serialize)]
pub struct NodeRecord {
    /// The two joint boxes, each holding one of the two singular points.
    pub points: [Joints; 2],
    /// Their shared image.
    #[serde(with = "WorkspaceDef")]
    pub workspace: Workspace,
    /// True when exactly one pair is proven in the two boxes.
    pub unique: bool,
}

/// An internal-motion strip.
#[derive(Clone, Debug, Serialize)]
pub struct MotionRecord {
    /// Joint box covering the lines: the second joint over its whole range, the third in the
    /// enclosure of the lines.
    pub joints: Joints,
    /// The strip of the third joint set aside by the searches (the lines plus one cell a side).
    pub strip: Bounds,
    /// Present for a near-degenerate strip (not an internal motion, undecided): the end point
    /// may come within this many metres of axis 2 there, but is nowhere proven on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_degenerate: Option<f64>,
}

/// An undecided box of the cusp search.
#[derive(Clone, Debug, Serialize)]
pub struct UndecidedCusp {
    /// Joint box.
    pub joints: Joints,
    /// Why it is undecided.
    #[serde(with = "ReasonDef")]
    pub reason: Reason,
}

/// An undecided pair of the node search.
#[derive(Clone, Debug, Serialize)]
pub struct UndecidedNode {
    /// The two joint boxes.
    pub points: [Joints; 2],
}

/// Undecided boxes, by search.
#[derive(Clone, Debug, Serialize)]
pub struct UndecidedRecords {
    /// Of the cusp search.
    pub cusps: Vec<UndecidedCusp>,
    /// Of the node search.
    pub nodes: Vec<UndecidedNode>,
}

/// Settings echoed in the report.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// Precision (radians).
    pub precision: f64,
    /// Whether nodes were searched.
    pub nodes: bool,
    /// Half-width added to every length.
    pub uncertainty: f64,
}

/// Counters of the cusp search: the kernel's `Stats` under the report's names.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct CuspStats {
    /// Boxes processed.
    pub processed: u64,
    /// Discarded because det Df ≠ 0 on them.
    pub regular: u64,
    /// Discarded because a row of system (2) ≠ 0 on them.
    pub not_tangent: u64,
    /// Discarded by Krawczyk (no zero).
    pub krawczyk_empty: u64,
    /// Bisections.
    pub bisected: u64,
    /// Boxes set aside inside internal-motion strips.
    pub in_strips: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl From<&CuspSearch> for CuspStats {
    fn from(c: &CuspSearch) -> Self {
        let s = &c.stats;
        CuspStats {
            processed: s.processed,
            regular: s.discarded(CuspDiscard::Regular),
            not_tangent: s.discarded(CuspDiscard::NotTangent),
            krawczyk_empty: s.discarded(CuspDiscard::KrawczykEmpty),
            bisected: s.split - c.contracted,
            in_strips: s.discarded(CuspDiscard::InStrips),
            seconds: c.seconds,
        }
    }
}

/// Counters of the node search: the kernel's `Stats` under the report's names.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct NodeStats {
    /// Pairs processed.
    pub pairs: u64,
    /// Dropped because the images are disjoint.
    pub apart: u64,
    /// Dropped by the mean-value injectivity certificate.
    pub injective: u64,
    /// Dropped by a cusp-neighbourhood certificate.
    pub near_cusp: u64,
    /// Dropped by Krawczyk.
    pub krawczyk_empty: u64,
    /// Pairs set aside because a box lies in an internal-motion strip.
    pub in_strips: u64,
    /// Boxes of the tree.
    pub cells: u64,
    /// Cusp neighbourhoods certified (of all cusps given).
    pub cusp_regions: u64,
    /// Clusters of pairs left at the precision settled afterwards by ε-inflation.
    pub settled: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl From<&NodeSearch> for NodeStats {
    fn from(n: &NodeSearch) -> Self {
        let s = &n.stats;
        NodeStats {
            pairs: s.processed,
            apart: s.discarded(NodeDiscard::Apart),
            injective: s.discarded(NodeDiscard::Injective),
            near_cusp: s.discarded(NodeDiscard::NearCusp),
            krawczyk_empty: s.discarded(NodeDiscard::KrawczykEmpty),
            in_strips: s.discarded(NodeDiscard::InStrips),
            cells: n.cells,
            cusp_regions: n.cusp_regions,
            settled: n.settled,
            seconds: n.seconds,
        }
    }
}

/// Counters.
#[derive(Clone, Debug, Serialize)]
pub struct SearchCounts {
    /// Of the cusp search.
    pub cusps: CuspStats,
    /// Of the node search, when run.
    pub nodes: Option<NodeStats>,
    /// Total wall-clock seconds.
    pub seconds: f64,
}

/// What `linkspace singularities --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct SingularityReport {
    /// Robot name.
    pub robot: String,
    /// The three revolute joints, base first.
    pub joints: [String; 3],
    /// Link whose origin is the end point.
    pub tip_link: String,
    /// Settings.
    pub settings: Settings,
    /// `status` and, when incomplete, `limit` (why).
    #[serde(flatten, serialize_with = "CompletenessDef::serialize")]
    pub completeness: Completeness,
    /// Certified cusps.
    pub cusps: Vec<CuspRecord>,
    /// Certified nodes (absent when not searched).
    pub nodes: Option<Vec<NodeRecord>>,
    /// Internal-motion lines.
    pub internal_motions: Vec<MotionRecord>,
    /// Undecided boxes (at most `MAX_LISTED` of each search; `undecided_total` counts all).
    pub undecided: UndecidedRecords,
    /// Undecided boxes (cusp search) and pairs (node search), all of them.
    pub undecided_total: [usize; 2],
    /// Counters.
    pub stats: SearchCounts,
    /// The arm's cuspidality verdict, with its scope (`report::verdicts`): the positioning
    /// structure's when it speaks for the arm, else the whole arm's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verdict: Option<VerdictRecord>,
    /// The positioning sub-chain's verdict when it is not the arm's, with its scope.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sub_chain_verdict: Option<VerdictRecord>,
    /// A six-joint arm's whole-arm cuspidality section (how it was decided).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_cuspidality: Option<super::six::ArmCuspidalityReport>,
    /// How the file was read (`chain`, `rounding`, `joint_limits` in the JSON); `None` for a
    /// report built from searches alone.
    #[serde(flatten)]
    pub reading: Option<Reading>,
    /// Searches not run, and why (structural arms: the cusp answer comes from the proof).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_searched: Option<String>,
    /// Arms with axes 2 and 3 exactly parallel: the singular set as certified branches
    /// (`arm3r::branches`).
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "some_branches")]
    pub singular_branches: Option<SingularBranches>,
    /// `--search-anyway` on such an arm: where the cusp search's undecided boxes (and cusp
    /// boxes without a uniqueness proof) lie, and whether the branches' argument explains them.
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "some_attribution")]
    pub explained_undecided: Option<Attribution>,
}

/// Undecided boxes listed in a report, at most, per search: the counts are always given, and
/// a flooded run must not write gigabytes of JSON.
pub const MAX_LISTED: usize = 10_000;

/// The rounding policy as applied.
#[derive(Clone, Debug, Serialize)]
pub struct Rounding {
    /// `false` with `--exact-geometry`.
    pub snapping: bool,
    /// Angle tolerance (radians).
    pub tolerance: f64,
    /// Every value changed.
    #[serde(serialize_with = "super::kernel::snaps")]
    pub snaps: Vec<Snap>,
}

impl Rounding {
    /// From a prepared arm.
    pub fn of(p: &Prepared) -> Self {
        Rounding { snapping: !p.exact_geometry, tolerance: p.snap_tolerance, snaps: p.snaps.clone() }
    }
}

/// How a file was read for a 3R report: what `arm3r::prepare` chose and changed, and what the
/// joint limits removed. Every 3R report of a file (`singularities`, `ik`) carries the same three
/// fields; flattened, they keep their place and names in the report's JSON object.
#[derive(Clone, Debug, Serialize)]
pub struct Reading {
    /// Which chain and point of the file were analysed, and why.
    #[serde(with = "ChoiceDef")]
    pub chain: Choice,
    /// The rounding policy's changes.
    pub rounding: Rounding,
    /// Joint limits and what they removed.
    #[serde(with = "LimitEffectDef")]
    pub joint_limits: LimitEffect,
}

impl Reading {
    /// From a prepared arm and what its limits did to the results.
    pub fn of(p: &Prepared, joint_limits: LimitEffect) -> Self {
        Reading { chain: p.choice.clone(), rounding: Rounding::of(p), joint_limits }
    }
}

impl SingularityReport {
    /// Builds the report from a cusp search and an optional node search.
    pub fn new(chain: &Chain3R, precision: f64, cusps: &CuspSearch, nodes: Option<&NodeSearch>, seconds: f64) -> Self {
        let status = nodes.map_or(cusps.status, |n| cusps.status.and(n.status));
        // Counted as `app` counts its uncertified records, for the one rule of `Incompleteness::of`.
        let undecided = cusps.undecided.len() + cusps.cusps.iter().filter(|c| !c.unique).count() + nodes.map_or(0, |n| n.undecided.len());
        let near = cusps.bands.iter().any(|b| b.near.is_some());
        let completeness = Completeness::of(status, undecided, near);
        let internal_motions = cusps
            .bands
            .iter()
            .map(|b: &Band| {
                let full = motion::full_range();
                MotionRecord { joints: joints(chain, &[full, crate::kernel::interval::interval(b.theta3[0], b.theta3[1])]), strip: b.strip, near_degenerate: b.near }
            })
            .collect();
        SingularityReport {
            robot: chain.name.clone(),
            joints: chain.joints.clone(),
            tip_link: chain.tip_link.clone(),
            settings: Settings { precision, nodes: nodes.is_some(), uncertainty: chain.uncertainty },
            completeness,
            cusps: cusps.cusps.iter().map(|c| CuspRecord { joints: joints(chain, &c.theta), workspace: workspace(c.rho, c.z), unique: c.unique }).collect(),
            nodes: nodes.map(|n| {
                n.nodes
                    .iter()
                    .map(|n| NodeRecord { points: [joints(chain, &n.theta[0]), joints(chain, &n.theta[1])], workspace: workspace(n.rho, n.z), unique: true })
                    .collect()
            }),
            internal_motions,
            undecided: UndecidedRecords {
                cusps: cusps.undecided.iter().take(MAX_LISTED).map(|u| UndecidedCusp { joints: joints(chain, &u.theta), reason: u.reason }).collect(),
                nodes: nodes.map_or(Vec::new(), |n| n.undecided.iter().take(MAX_LISTED).map(|p| UndecidedNode { points: [joints(chain, &p[0]), joints(chain, &p[1])] }).collect()),
            },
            undecided_total: [cusps.undecided.len(), nodes.map_or(0, |n| n.undecided.len())],
            stats: SearchCounts { cusps: CuspStats::from(cusps), nodes: nodes.map(NodeStats::from), seconds },
            verdict: None,
            sub_chain_verdict: None,
            arm_cuspidality: None,
            reading: None,
            not_searched: None,
            singular_branches: None,
            explained_undecided: None,
        }
    }
}

impl SingularityReport {
    /// What `linkspace singularities --json` writes of `found`, a run on `arm`.
    pub fn of(answer: &SingularitiesAnswer) -> Self {
        let (arm, found) = (&answer.arm, &answer.found);
        let run = &found.run;
        let mut report = SingularityReport::new(&arm.chain, found.request.precision, &run.cusps, run.nodes.as_ref(), found.seconds);
        let verdicts = Verdicts::of(answer);
        report.verdict = verdicts.arm;
        report.sub_chain_verdict = verdicts.sub_chain;
        let mut reading = Reading::of(&arm.prepared, found.limit_effect.clone());
        if let (Some(a), false) = (&verdicts.whole_arm, arm.prepared.choice.scope.stands_for_arm) {
            reading.chain.scope.not_answered = Some(format!("not the arm's verdict: the whole arm's ({}) is `verdict`", a.arm));
        }
        report.arm_cuspidality = verdicts.whole_arm;
        report.reading = Some(reading);
        if let Some(a) = &found.explained {
            report.explain(a.clone());
        }
        report.not_searched = found.not_searched.clone();
        report.singular_branches = arm.branches.clone();
        report
    }

    /// Records where the cusp search's undecided boxes lie (`attribution`). When the branches'
    /// argument proves that none holds a cusp, no cusp was certified (a certified one would
    /// contradict it: then nothing is moved), the node search left nothing undecided and the
    /// only reason for `incomplete` was undecided boxes, they are moved out of `undecided`
    /// (and cusp boxes without a uniqueness proof out of `cusps`) and the report is complete.
    pub fn explain(&mut self, attribution: Attribution) {
        let moves = attribution.explained && self.completeness == Completeness::Incomplete(Incompleteness::Undecided) && self.undecided_total[1] == 0 && self.cusps.iter().all(|c| !c.unique);
        if moves {
            self.undecided.cusps.clear();
            self.undecided_total[0] = 0;
            self.cusps.clear();
            self.completeness = Completeness::Complete;
        }
        self.explained_undecided = Some(attribution);
    }
}

/// One inverse-kinematics solution box.
#[derive(Clone, Debug, Serialize)]
pub struct IkRecord {
    /// Joint box.
    pub joints: Joints,
    /// True: exactly one solution in the box. False: a cluster that may hold several (near a
    /// singularity) or a line (an internal motion).
    pub unique: bool,
    /// Undecided boxes merged into this record (0 for unique ones).
    pub boxes: usize,
}

/// What `linkspace ik --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct IkReport {
    /// Robot name.
    pub robot: String,
    /// The query: (radius, z) in the first joint's frame, or (x, y, z) in the root frame.
    pub point: Vec<f64>,
    /// `status` and, when incomplete, `limit`: the limit that stopped the run (`boxes`, `time`,
    /// `memory` or `cancelled`).
    #[serde(flatten, serialize_with = "CompletenessDef::serialize")]
    pub completeness: Completeness,
    /// Solutions, unique ones first.
    pub solutions: Vec<IkRecord>,
    /// Boxes processed.
    pub processed: u64,
    /// How the file was read (`chain`, `rounding`, `joint_limits` in the JSON); `None` for a
    /// report built from searches alone.
    #[serde(flatten)]
    pub reading: Option<Reading>,
}

impl IkReport {
    /// Builds the report of a query; `theta1` encloses the first joint's angle of a solution
    /// box over (θ₂, θ₃) when the point fixes it (`None`: the first joint is free and not
    /// listed).
    pub fn new(chain: &Chain3R, point: Vec<f64>, s: &IkSolutions, theta1: impl Fn(&[Interval; 2]) -> Option<Interval>) -> Self {
        let record = |b: &[Interval; 2]| {
            let mut j = joints(chain, b);
            if let Some(t) = theta1(b) {
                j.insert(chain.joints[0].clone(), bounds(t));
            }
            j
        };
        let mut solutions: Vec<IkRecord> = s.unique.iter().map(|b| IkRecord { joints: record(b), unique: true, boxes: 0 }).collect();
        solutions.extend(s.clusters.iter().map(|c| IkRecord { joints: record(&c.hull), unique: false, boxes: c.boxes }));
        IkReport { robot: chain.name.clone(), point, completeness: Completeness::of_run(s.status), solutions, processed: s.stats.processed, reading: None }
    }

    /// What `linkspace ik --json` writes of `found`, a query on `arm`.
    pub fn of(arm: &Arm, found: &ArmIk) -> Self {
        let point = match found.point {
            IkPoint::Root(p) => p.to_vec(),
            IkPoint::HalfSection { radius, z } => vec![radius, z],
        };
        let mut report = IkReport::new(&arm.chain, point, &found.solutions, |b| found.theta1(arm, b));
        report.reading = Some(Reading::of(&arm.prepared, found.limit_effect.clone()));
        report
    }
}

// How the 3R analyses' records are written: `arm3r` knows no serde, so each record it
// contributes to a report is stated here field for field (a field added there and not here
// fails to compile).

#[derive(Serialize)]
#[serde(remote = "Workspace")]
struct WorkspaceDef {
    radius: Bounds,
    z: Bounds,
}

/// `cusps::Reason`: `grad_det_may_vanish`, `precision`, `limit`.
#[derive(Serialize)]
#[serde(remote = "Reason", rename_all = "snake_case")]
enum ReasonDef {
    GradDetMayVanish,
    Precision,
    Limit,
}




/// `select::Choice`, the locked joints as `[name, value]` pairs.
#[derive(Serialize)]
#[serde(remote = "Choice")]
struct ChoiceDef {
    base: String,
    tip: String,
    joints: [String; 3],
    wrist_joints: Vec<String>,
    locked: Vec<(String, f64)>,
    point_link: String,
    point: [f64; 3],
    wrist_miss: f64,
    reason: String,
    spherical_wrist: Option<bool>,
    #[serde(with = "ScopeDef")]
    scope: Scope,
}

/// `select::Scope`: what a verdict on the chosen chain and point is about.
#[derive(Serialize)]
#[serde(remote = "Scope")]
struct ScopeDef {
    subject: String,
    stands_for_arm: bool,
    not_answered: Option<String>,
}

#[derive(Serialize)]
#[serde(remote = "JointLimits")]
struct JointLimitsDef {
    joints: [String; 3],
    limits: [Option<[f64; 2]>; 3],
    ignored: bool,
}

#[derive(Serialize)]
#[serde(remote = "LimitEffect")]
struct LimitEffectDef {
    #[serde(with = "JointLimitsDef")]
    limits: JointLimits,
    dropped: u64,
    on_limit: u64,
    text: String,
}

/// `branches::CrossingRecord`, without the enclosure kept for attribution.
#[derive(Serialize)]
#[serde(remote = "CrossingRecord")]
struct CrossingRecordDef {
    name: String,
    joints: Joints,
    #[serde(with = "WorkspaceDef")]
    workspace: Workspace,
    #[serde(skip)]
    theta: [Interval; 2],
}

list_with!(crossing_records, CrossingRecord, "CrossingRecordDef");

#[derive(Serialize)]
#[serde(remote = "FoldSample")]
struct FoldSampleDef {
    theta3: f64,
    theta2: [Bounds; 2],
}

list_with!(fold_samples, FoldSample, "FoldSampleDef");

#[derive(Serialize)]
#[serde(remote = "ImageRecord")]
struct ImageRecordDef {
    description: String,
    radius: Bounds,
    z: Bounds,
}

/// `branches::SingularBranch`: `joints` only for a θ₃ line, `samples` only for the fold of g.
#[derive(Serialize)]
#[serde(remote = "SingularBranch")]
struct SingularBranchDef {
    name: String,
    kind: &'static str,
    description: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    joints: Option<Joints>,
    #[serde(skip_serializing_if = "Vec::is_empty", serialize_with = "fold_samples")]
    samples: Vec<FoldSample>,
    #[serde(with = "ImageRecordDef")]
    image: ImageRecord,
    curve_of_nodes: Option<bool>,
    #[serde(serialize_with = "crossing_records")]
    crossings: Vec<CrossingRecord>,
    proof: String,
    #[serde(skip)]
    theta3: Option<Interval>,
}

list_with!(singular_branches, SingularBranch, "SingularBranchDef");

#[derive(Serialize)]
#[serde(remote = "IsolatedNode")]
struct IsolatedNodeDef {
    points: [Joints; 2],
    #[serde(with = "WorkspaceDef")]
    workspace: Workspace,
}

list_with!(isolated_nodes, IsolatedNode, "IsolatedNodeDef");

/// `"singular_branches"`.
#[derive(Serialize)]
#[serde(remote = "SingularBranches")]
struct SingularBranchesDef {
    #[serde(serialize_with = "singular_branches")]
    branches: Vec<SingularBranch>,
    crossings: Option<usize>,
    #[serde(serialize_with = "isolated_nodes")]
    isolated_nodes: Vec<IsolatedNode>,
    l2: Bounds,
    l3: Bounds,
    d: Bounds,
    no_cusp_proven: bool,
    argument: String,
}

some_with!(some_branches, SingularBranches, "SingularBranchesDef");

/// `branches::Attribution`, the counts per crossing and per branch as `[name, count]` pairs.
#[derive(Serialize)]
#[serde(remote = "Attribution")]
struct AttributionDef {
    boxes: usize,
    near_crossings: Vec<(String, usize)>,
    radius: f64,
    max_distance: f64,
    on_branch: Vec<(String, usize)>,
    elsewhere: usize,
    explained: bool,
    text: String,
}

some_with!(some_attribution, Attribution, "AttributionDef");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::arm3r::{prepare, structural_singularities, LoadOptions};

    /// The JSON keys of `report` at the top level, in the written order.
    fn keys(report: &impl Serialize) -> Vec<String> {
        let text = serde_json::to_string_pretty(report).expect("serialises");
        text.lines().filter_map(|l| l.strip_prefix("  \"")).filter_map(|l| l.split_once('"')).map(|(k, _)| k.to_string()).collect()
    }

    #[test]
    fn the_reading_keeps_its_place_in_the_json_and_is_absent_without_one() {
        let p = prepare(&crate::model::urdf::parse(include_str!("../../../urdf/puma560.urdf")).expect("parses"), &LoadOptions::default()).expect("3R");
        let chain = Chain3R::from_mechanism(&p.mechanism, 0.0).expect("3R");
        let run = structural_singularities(&chain, 1e-4, &crate::kernel::search::Control::with_limits(Default::default())).expect("precision");
        let mut r = SingularityReport::new(&chain, 1e-4, &run.cusps, None, 0.0);
        r.not_searched = Some("structural".into());
        let bare = keys(&r);
        assert!(!bare.iter().any(|k| ["chain", "rounding", "joint_limits"].contains(&k.as_str())), "{bare:?}");
        r.reading = Some(Reading::of(&p, Default::default()));
        // Where the three optional fields always were: after the counters (and the verdict),
        // before `not_searched`.
        let at = |k: &str| keys(&r).iter().position(|x| x == k).unwrap_or_else(|| panic!("{k} missing"));
        assert_eq!([at("stats") + 1, at("chain") + 1, at("rounding") + 1, at("joint_limits") + 1], [at("chain"), at("rounding"), at("joint_limits"), at("not_searched")]);
        assert_eq!(keys(&r).len(), bare.len() + 3);
    }
}

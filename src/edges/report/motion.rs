//! The JSON of `linkspace loop-singularities --kind motion`: an input motion of a 1-dof loop
//! checked against the input's singular set, from `app::InputMotionCheck`.

use crate::app::{InputMotionCheck, MotionVerdict};
use serde::Serialize;
use std::collections::BTreeMap;

/// Joint name → [lo, hi] (radians or metres).
pub type JointBoxes = BTreeMap<String, [f64; 2]>;

/// What `loop-singularities --kind motion --json` writes.
#[derive(Clone, Debug, Serialize)]
pub struct MotionReport {
    /// The mechanism.
    pub mechanism: String,
    /// The singular set checked against: "input singularities of M, actuated J".
    pub singular_set: String,
    /// The actuated joint.
    pub actuated: String,
    /// Its start and end values.
    pub from: f64,
    /// See `from`.
    pub to: f64,
    /// The joints of the assembly, in order.
    pub joints: Vec<String>,
    /// The assembly as given.
    pub assembly: Vec<f64>,
    /// The configuration at `from` (Newton from the assembly), proven unique in this box.
    pub start: JointBoxes,
    /// `clear`, `undecided` or `not_decided` (a limit stopped it).
    pub verdict: &'static str,
    /// `complete` (clear), or `incomplete` with `limit`: the limit that stopped the check, or
    /// `undecided`.
    #[serde(flatten, serialize_with = "super::kernel::CompletenessDef::serialize")]
    pub status: crate::kernel::outcome::Completeness,
    /// Why, in one line.
    pub reason: String,
    /// The input value up to which every step is proven (`to` when clear).
    pub proven_to: f64,
    /// For `undecided`: a certified turning point of the input next to where the proof stopped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_turning_point: Option<JointBoxes>,
    /// The certificate: per step of the input, a box holding exactly one configuration of the
    /// branch for every input value of the step.
    pub steps: Vec<MotionStepRecord>,
    /// Wall time (seconds).
    pub seconds: f64,
}

/// One proven step.
#[derive(Clone, Debug, Serialize)]
pub struct MotionStepRecord {
    /// The input's range.
    pub input: [f64; 2],
    /// The joints over the step's box.
    pub joints: JointBoxes,
}

impl MotionReport {
    /// The report of a check.
    pub fn of(found: &InputMotionCheck) -> Self {
        let r = &found.request;
        let set = found.set_name();
        let (verdict, reason, proven_to, near) = match &found.verdict {
            MotionVerdict::Clear => ("clear", format!("every step from {} to {} proven: no {set} on the way ({} steps; output singularities not examined)", r.from, r.to, found.steps.len()), r.to, None),
            MotionVerdict::Undecided { from, reason, near } => {
                let named = near.as_ref().map_or(String::new(), |n| {
                    let mid: Vec<String> = n.iter().map(|(k, b)| format!("{k}={:.6}", 0.5 * (b[0] + b[1]))).collect();
                    format!("; near the certified turning point at {}", mid.join(" "))
                });
                ("undecided", format!("undecided from {} = {from} on: {reason}{named}", r.actuated), *from, near.clone())
            }
            MotionVerdict::Stopped { from, limit } => ("not_decided", format!("proven up to {} = {from}; the run stopped on its {} limit first", r.actuated, limit.name()), *from, None),
        };
        MotionReport {
            mechanism: found.mechanism.clone(),
            singular_set: set,
            actuated: r.actuated.clone(),
            from: r.from,
            to: r.to,
            joints: found.joints.clone(),
            assembly: r.assembly.clone(),
            start: found.start.clone(),
            verdict,
            status: found.completeness(),
            reason,
            proven_to,
            near_turning_point: near,
            steps: found.steps.iter().map(|s| MotionStepRecord { input: s.input, joints: s.joints.clone() }).collect(),
            seconds: found.seconds,
        }
    }
}

//! What `singularities --json` says about cuspidality, each verdict with what it concerns: the
//! top-level `verdict` is always the arm's (its positioning structure's when that speaks for
//! the arm, else the whole-arm verdict of a six-joint arm, else an undecided one saying what is
//! open), and a sub-chain's verdict sits under `sub_chain_verdict` with its scope.

use super::six::{ArmCuspidalityReport, WitnessRecord};
use crate::analyses::arm3r::verdict::Verdict;
use crate::app::{ArmCuspidality, Scope, SingularitiesAnswer};
use serde::Serialize;

/// What a verdict concerns, as written: `{"kind": "mechanism"}` or `{"kind": "sub_chain",
/// "joints": [...], "point": "..."}`.
#[derive(Clone, Debug, Serialize)]
pub struct ScopeRecord {
    /// `mechanism` or `sub_chain`.
    pub kind: &'static str,
    /// The sub-chain's joints, base first.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joints: Option<Vec<String>>,
    /// The sub-chain and the point it positions, in words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
}

impl ScopeRecord {
    /// The record of `scope`.
    pub fn of(scope: &Scope) -> Self {
        match scope {
            Scope::Mechanism => ScopeRecord { kind: scope.name(), joints: None, point: None },
            Scope::SubChain { joints, point } => ScopeRecord { kind: scope.name(), joints: Some(joints.clone()), point: Some(point.clone()) },
        }
    }
}

/// A cuspidality verdict with its scope and its proof, witness or reason.
#[derive(Clone, Debug, Serialize)]
pub struct VerdictRecord {
    /// `true`, `false`, or `null` (undecided).
    pub cuspidal: Option<bool>,
    /// Aspects on the full torus, when proven (positioning-structure verdicts).
    pub aspects: Option<u32>,
    /// Largest number of IK solutions of one point, when proven (positioning-structure
    /// verdicts).
    pub max_ik_solutions: Option<u32>,
    /// True when `cuspidal` rests on a proof or a certified witness.
    pub certified: bool,
    /// The argument used, or why there is none.
    pub reason: String,
    /// What the verdict concerns.
    pub scope: ScopeRecord,
    /// The theorem a whole-arm `false` applies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub proof: Option<String>,
    /// The witness of a whole-arm `true`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub witness: Option<WitnessRecord>,
}

impl VerdictRecord {
    fn positioning(v: &Verdict, scope: &Scope) -> Self {
        VerdictRecord { cuspidal: v.cuspidal, aspects: v.aspects, max_ik_solutions: v.max_ik_solutions, certified: v.certified, reason: v.reason.clone(), scope: ScopeRecord::of(scope), proof: None, witness: None }
    }

    fn whole_arm(c: &ArmCuspidality, report: &ArmCuspidalityReport) -> Self {
        let cuspidal = c.line().verdict.cuspidal();
        VerdictRecord {
            cuspidal,
            aspects: None,
            max_ik_solutions: None,
            certified: cuspidal.is_some(),
            reason: format!("{}: {}", report.arm, report.reason),
            scope: ScopeRecord::of(&Scope::Mechanism),
            proof: report.proof.clone(),
            witness: report.witness.clone(),
        }
    }

    fn open(question: &str) -> Self {
        VerdictRecord { cuspidal: None, aspects: None, max_ik_solutions: None, certified: false, reason: question.to_string(), scope: ScopeRecord::of(&Scope::Mechanism), proof: None, witness: None }
    }
}

/// The verdicts of a singularity answer: the arm's, the sub-chain's when it is not the arm's,
/// and the whole-arm section of a six-joint arm.
pub struct Verdicts {
    /// The arm's.
    pub arm: Option<VerdictRecord>,
    /// The positioning sub-chain's, when it is not the arm's.
    pub sub_chain: Option<VerdictRecord>,
    /// The whole-arm section.
    pub whole_arm: Option<ArmCuspidalityReport>,
}

impl Verdicts {
    /// From the answer (`None` everywhere when no verdict was asked).
    pub fn of(a: &SingularitiesAnswer) -> Self {
        let whole_arm = a.whole_arm.as_ref().map(|(chain, c)| (c, ArmCuspidalityReport::of(chain, c)));
        let Some(v) = &a.found.verdict else {
            return Verdicts { arm: None, sub_chain: None, whole_arm: whole_arm.map(|(_, r)| r) };
        };
        let scope = a.sub_chain_scope();
        let (arm, sub_chain) = match (&scope, &whole_arm) {
            (Scope::Mechanism, _) => (VerdictRecord::positioning(v, &scope), None),
            (Scope::SubChain { .. }, Some((c, report))) => (VerdictRecord::whole_arm(c, report), Some(VerdictRecord::positioning(v, &scope))),
            (Scope::SubChain { .. }, None) => {
                let open = a.arm.prepared.choice.scope.not_answered.clone().unwrap_or_else(|| "the arm's verdict was not searched".into());
                (VerdictRecord::open(&open), Some(VerdictRecord::positioning(v, &scope)))
            }
        };
        Verdicts { arm: Some(arm), sub_chain, whole_arm: whole_arm.map(|(_, r)| r) }
    }
}

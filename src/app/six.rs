//! Six-revolute arms taken whole: certified inverse kinematics of the tip frame and the
//! whole-arm cuspidality verdict (`arm6r`), with the 3R jobs' loading options.

use super::arm::Arm;
use crate::analyses::arm3r::LoadOptions;
use crate::analyses::arm6r::self_motion::{self, SelfMotionSet};
use crate::analyses::arm6r::{cuspidal, ik, three_parallel, Chain6R, CuspidalVerdict, Ik6Solutions, Manip6rError, MostSolutions, PoseInput, SearchOutcome, ThreeParallel};
use crate::model::{rounding, Mechanism};
use crate::kernel::search::Control;
use std::time::{Duration, Instant};

/// The arm's six joints as `arm6r` reads them, after the rounding policy of `options`
/// (`--base`/`--tip` honoured, joints held by `--fix` folded into the fixed transforms; a
/// point does not apply to the whole arm).
pub fn chain6(m: &Mechanism, options: &LoadOptions) -> Result<Chain6R, Manip6rError> {
    chain6_snapped(m, options).map(|(chain, _)| chain)
}

/// `chain6`, with how many values the rounding policy changed on the joints from the chain's
/// base to its tip (the whole-arm proof is about the geometry after them); `--ignore-limits`
/// sets the file's joint limits aside.
pub(crate) fn chain6_snapped(m: &Mechanism, options: &LoadOptions) -> Result<(Chain6R, usize), Manip6rError> {
    let (chain, snapped) = chain6_rounded(m, options)?;
    Ok((if options.ignore_limits { chain.without_limits() } else { chain }, snapped))
}

fn chain6_rounded(m: &Mechanism, options: &LoadOptions) -> Result<(Chain6R, usize), Manip6rError> {
    if options.exact_geometry || options.snap_tolerance == 0.0 {
        return Ok((Chain6R::holding(m, options.spec.base.as_deref(), options.spec.tip.as_deref(), &options.spec.locks)?, 0));
    }
    let (rounded, snaps) = rounding::snap(m, options.snap_tolerance);
    let chain = Chain6R::holding(&rounded, options.spec.base.as_deref(), options.spec.tip.as_deref(), &options.spec.locks)?;
    let (Some(base), Some(tip)) = (rounded.link(&chain.base), rounded.link(&chain.tip)) else { return Ok((chain, 0)) };
    let below_base: Vec<usize> = rounded.path_to(base);
    let on_chain: Vec<&str> = rounded.path_to(tip).into_iter().filter(|j| !below_base.contains(j)).map(|j| rounded.joints[j].name.as_str()).collect();
    let snapped = snaps.iter().filter(|s| on_chain.contains(&s.joint.as_str())).count();
    Ok((chain, snapped))
}

/// What `ik6` found.
#[derive(Clone, Debug)]
pub struct ArmIk6 {
    /// The pose asked for, as written (its count names the form).
    pub pose: PoseInput,
    /// The certified solutions.
    pub solutions: Ik6Solutions,
    /// Wall time of the search.
    pub seconds: f64,
}

/// Every solution within the joint ranges of the tip pose (base frame; metres, radians; any
/// form of `PoseInput`), boxes tightened to `precision`.
pub fn inverse_kinematics6(chain: &Chain6R, pose: PoseInput, precision: f64, control: &Control) -> Result<ArmIk6, Manip6rError> {
    let start = Instant::now();
    let target = pose.target()?;
    let solutions = ik::solve(chain, &target, precision, control)?;
    Ok(ArmIk6 { pose, solutions, seconds: start.elapsed().as_secs_f64() })
}

/// What `self-motion` found.
#[derive(Clone, Debug)]
pub struct ArmSelfMotion {
    /// The pose asked for, as written.
    pub pose: PoseInput,
    /// The cover of the set.
    pub set: SelfMotionSet,
    /// Wall time.
    pub seconds: f64,
}

impl ArmSelfMotion {
    /// The run in one line, as the CLI prints it (before its time) and the node's reply says it.
    pub fn headline(&self) -> String {
        let set = &self.set;
        format!(
            "{}: {} boxes in {} clusters, {} certified pieces of arc, {} cells of {:.4} rad over [{:.6}, {:.6}] ({} searched), status {}",
            set.joints[set.parameter],
            set.boxes.len(),
            set.clusters,
            set.certified(),
            set.cells.1,
            set.cell,
            set.range.0 + 0.0,
            set.range.1 + 0.0,
            set.cells.0,
            set.completeness().text()
        )
    }
}

/// Every configuration of the seven-revolute arm of `m` (read as `options` say: base, tip, the
/// rounding policy) at the job's tip pose, its parameter joint (default: the third) cut into
/// cells and the other joints' boxes as the job says, within `control`.
pub fn self_motion(m: &Mechanism, options: &LoadOptions, job: &super::SelfMotionJob, control: &Control) -> Result<ArmSelfMotion, Manip6rError> {
    let (pose, cell, precision) = (job.pose, job.cell, job.precision);
    let start = Instant::now();
    let target = pose.target()?;
    let rounded;
    let m = if options.exact_geometry || options.snap_tolerance == 0.0 {
        m
    } else {
        rounded = rounding::snap(m, options.snap_tolerance).0;
        &rounded
    };
    let parameter = match &job.parameter {
        Some(p) => p.clone(),
        None => self_motion::default_parameter(m)?,
    };
    let set = self_motion::cover(m, options.spec.base.as_deref(), options.spec.tip.as_deref(), &parameter, job.range, &target, cell, precision, control)?;
    Ok(ArmSelfMotion { pose, set, seconds: start.elapsed().as_secs_f64() })
}

/// The whole-arm cuspidality verdict of a six-joint arm.
#[derive(Clone, Debug)]
pub enum ArmCuspidality {
    /// The wrist is spherical: the arm is cuspidal iff its 3R positioning structure is, so the
    /// 3R verdict is the arm's.
    PositioningVerdict,
    /// Proven not cuspidal: the arm is of the UR family (`arm6r::three_parallel`, whose proof
    /// the report cites).
    ThreeParallel {
        /// What the recognition proved.
        proof: ThreeParallel,
        /// How many values the rounding policy changed on the chain: the proof is about the
        /// geometry after them (0 when the file is exactly of the family as written).
        snapped: usize,
    },
    /// A witness search ran (`arm6r::cuspidal`).
    Searched {
        /// Cuspidal with a witness, or undecided.
        verdict: CuspidalVerdict,
        /// The pose with the most certified solutions the search solved.
        most: Option<MostSolutions>,
        /// The search's budget and time spent.
        budget: f64,
        /// Wall time spent.
        seconds: f64,
        /// The chain's near-degenerate pairs of axes (`Chain6R::near_degeneracies`): a verdict
        /// about the geometry as written, which a tiny change may turn.
        near: Vec<String>,
    },
}

/// The whole-arm verdict for a six-joint arm whose 3R verdict is about a sub-chain (`None`
/// for other arms, whose 3R verdict is already the arm's or does not apply). A spherical wrist
/// needs no search: the 3R verdict speaks for the arm. Otherwise a witness is searched within
/// `budget` (and `control`).
pub fn arm_cuspidality(m: &Mechanism, arm: &Arm, options: &LoadOptions, budget: Duration, control: &Control) -> Option<(Chain6R, ArmCuspidality)> {
    if !whole_arm_applies(arm) {
        return None;
    }
    let (chain, snapped) = chain6_snapped(m, options).ok()?;
    let verdict = arm_cuspidality_of(&chain, snapped, arm, budget, control)?;
    Some((chain, verdict))
}


/// Whether the arm's 3R verdict is a sub-chain's that the whole arm's may differ from: three
/// wrist joints, none locked.
fn whole_arm_applies(arm: &Arm) -> bool {
    let choice = &arm.prepared.choice;
    choice.wrist_joints.len() == 3 && choice.locked.is_empty()
}

/// `arm_cuspidality` on a chain already read, `snapped` values of it changed by the rounding
/// policy (`chain6_snapped`). The UR family is proven non-cuspidal before any search.
pub fn arm_cuspidality_of(chain: &Chain6R, snapped: usize, arm: &Arm, budget: Duration, control: &Control) -> Option<ArmCuspidality> {
    if !whole_arm_applies(arm) {
        return None;
    }
    if arm.prepared.choice.spherical_wrist == Some(true) {
        return Some(ArmCuspidality::PositioningVerdict);
    }
    if let Some(proof) = three_parallel::recognise(chain) {
        return Some(ArmCuspidality::ThreeParallel { proof, snapped });
    }
    let start = Instant::now();
    let SearchOutcome { verdict, most } = cuspidal::search(chain, budget, 1, control);
    let seconds = start.elapsed().as_secs_f64();
    Some(ArmCuspidality::Searched { verdict, most, budget: budget.as_secs_f64(), seconds, near: chain.near_degeneracies() })
}

/// A whole-arm verdict in words: what the JSON's `arm_cuspidality` and the singularity topic say.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmVerdictLine {
    /// The verdict.
    pub verdict: ArmVerdict,
    /// Why, in one line.
    pub reason: String,
}

/// A whole-arm cuspidality verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmVerdict {
    /// Two solutions of one pose joined by a path free of singularities (a certified witness).
    Cuspidal,
    /// Proven not cuspidal (by a theorem the proof states).
    NonCuspidal,
    /// Neither found nor proven.
    Undecided,
    /// The wrist is spherical: the positioning structure's verdict is the arm's.
    AsPositioningStructure,
}

impl ArmVerdict {
    /// `Some(true)` cuspidal, `Some(false)` proven not, `None` undecided (or left to the
    /// positioning structure's verdict).
    pub fn cuspidal(self) -> Option<bool> {
        match self {
            ArmVerdict::Cuspidal => Some(true),
            ArmVerdict::NonCuspidal => Some(false),
            ArmVerdict::Undecided | ArmVerdict::AsPositioningStructure => None,
        }
    }

    /// `cuspidal`, `non_cuspidal`, `undecided` or `as_positioning_structure`, as reports and
    /// messages write it.
    pub fn name(self) -> &'static str {
        match self {
            ArmVerdict::Cuspidal => "cuspidal",
            ArmVerdict::NonCuspidal => "non_cuspidal",
            ArmVerdict::Undecided => "undecided",
            ArmVerdict::AsPositioningStructure => "as_positioning_structure",
        }
    }
}

impl ArmCuspidality {
    /// The verdict's name and reason.
    pub fn line(&self) -> ArmVerdictLine {
        match self {
            ArmCuspidality::PositioningVerdict => ArmVerdictLine {
                verdict: ArmVerdict::AsPositioningStructure,
                reason: "spherical wrist: the arm is cuspidal iff its 3R positioning structure is (the verdict above is the arm's)".into(),
            },
            ArmCuspidality::ThreeParallel { proof, snapped } => ArmVerdictLine {
                verdict: ArmVerdict::NonCuspidal,
                reason: format!(
                    "UR family proven on the {}: axes 2, 3, 4 exactly parallel (distances {:.6} and {:.6}), axis 1 not parallel to them, axis 5 normal to them, axes 5 and 6 meeting at right angles; det J = ±g1·g3·g5 (shoulder, elbow, wrist) and the signs of the three factors tell every pose's solutions apart, so no two lie in one aspect",
                    if *snapped == 0 { "file's geometry as written".to_string() } else { format!("geometry after snapping {snapped} values to quarter turns / coordinate axes") },
                    proof.l2.mid(),
                    proof.l3.mid()
                ),
            },
            ArmCuspidality::Searched { verdict: CuspidalVerdict::Cuspidal(w), seconds, near, .. } => ArmVerdictLine {
                verdict: ArmVerdict::Cuspidal,
                reason: format!("witness found in {seconds:.1} s: two certified solutions of one pose joined by a path on which det J is proven nonzero ({} pieces){}", w.pieces, near_words(near, "the witness is for the geometry as written")),
            },
            ArmCuspidality::Searched { verdict: CuspidalVerdict::Undecided { poses, pairs }, budget, near, .. } => ArmVerdictLine {
                verdict: ArmVerdict::Undecided,
                reason: format!(
                    "no witness found within the budget ({budget:.0} s: {poses} poses solved, {pairs} pairs of solutions with one sign of det J tried; --arm-budget gives more); non-cuspidality is not proven{}",
                    near_words(near, "a tiny change of it may turn the verdict")
                ),
            },
        }
    }
}

/// What a whole-arm verdict adds for near-degenerate geometry, as the 3R verdicts word it.
fn near_words(near: &[String], consequence: &str) -> String {
    if near.is_empty() {
        String::new()
    } else {
        format!("; near-degenerate geometry: {} ({consequence})", near.join("; "))
    }
}

//! Six-revolute arms taken whole: certified inverse kinematics of the tip frame and the
//! whole-arm cuspidality verdict (`manip6r`), with the 3R jobs' loading options.

use super::arm::Arm;
use crate::manip3r::LoadOptions;
use crate::manip6r::{cuspidal, ik, three_parallel, Chain6R, CuspidalVerdict, Ik6Solutions, Manip6rError, MostSolutions, PoseTarget, SearchOutcome, ThreeParallel};
use crate::model::{rounding, Mechanism};
use crate::search::Control;
use std::time::{Duration, Instant};

/// The arm's six joints as `manip6r` reads them, after the rounding policy of `options`
/// (`--base`/`--tip` honoured; locks and points do not apply to the whole arm).
pub fn chain6(m: &Mechanism, options: &LoadOptions) -> Result<Chain6R, Manip6rError> {
    let rounded = if options.exact_geometry || options.snap_tolerance == 0.0 { m.clone() } else { rounding::snap(m, options.snap_tolerance).0 };
    Chain6R::from_mechanism(&rounded, options.spec.base.as_deref(), options.spec.tip.as_deref())
}

/// What `ik6` found.
#[derive(Clone, Debug)]
pub struct ArmIk6 {
    /// The pose asked for: x, y, z, roll, pitch, yaw.
    pub pose: [f64; 6],
    /// The certified solutions.
    pub solutions: Ik6Solutions,
    /// Wall time of the search.
    pub seconds: f64,
}

/// Every solution within the joint ranges of the tip pose `x, y, z, roll, pitch, yaw` (base
/// frame; metres, radians), boxes tightened to `precision`.
pub fn inverse_kinematics6(chain: &Chain6R, pose: [f64; 6], precision: f64, control: &Control) -> Result<ArmIk6, Manip6rError> {
    let start = Instant::now();
    let target = PoseTarget::stated(pose)?;
    let solutions = ik::solve(chain, &target, precision, control)?;
    Ok(ArmIk6 { pose, solutions, seconds: start.elapsed().as_secs_f64() })
}

/// The whole-arm cuspidality verdict of a six-joint arm.
#[derive(Clone, Debug)]
pub enum ArmCuspidality {
    /// The wrist is spherical: the arm is cuspidal iff its 3R positioning structure is, so the
    /// 3R verdict is the arm's.
    PositioningVerdict,
    /// Proven not cuspidal: the arm is of the UR family (`manip6r::three_parallel`, whose proof
    /// the report cites).
    ThreeParallel {
        /// What the recognition proved.
        proof: ThreeParallel,
        /// Values the rounding policy changed on the chain: the proof is about the geometry
        /// after them (empty when the file is exactly of the family as written).
        snapped: Vec<rounding::Snap>,
    },
    /// A witness search ran (`manip6r::cuspidal`).
    Searched {
        /// Cuspidal with a witness, or undecided.
        verdict: CuspidalVerdict,
        /// The pose with the most certified solutions the search solved.
        most: Option<MostSolutions>,
        /// The search's budget and time spent.
        budget: f64,
        /// Wall time spent.
        seconds: f64,
    },
}

/// The whole-arm verdict for a six-joint arm whose 3R verdict is about a sub-chain (`None`
/// for other arms, whose 3R verdict is already the arm's or does not apply). A spherical wrist
/// needs no search: the 3R verdict speaks for the arm; nor does an arm of the UR family, proven
/// not cuspidal. Otherwise a witness is searched within `budget` (and `control`).
pub fn arm_cuspidality(m: &Mechanism, arm: &Arm, options: &LoadOptions, budget: Duration, control: &Control) -> Option<(Chain6R, ArmCuspidality)> {
    let choice = &arm.prepared.choice;
    if choice.wrist_joints.len() != 3 || !choice.locked.is_empty() {
        return None;
    }
    let chain = chain6(m, options).ok()?;
    if choice.spherical_wrist == Some(true) {
        return Some((chain, ArmCuspidality::PositioningVerdict));
    }
    if let Some(proof) = three_parallel::recognise(&chain) {
        return Some((chain, ArmCuspidality::ThreeParallel { proof, snapped: snaps_on_chain(m, options) }));
    }
    let start = Instant::now();
    let SearchOutcome { verdict, most } = cuspidal::search(&chain, budget, 1, control);
    let seconds = start.elapsed().as_secs_f64();
    Some((chain, ArmCuspidality::Searched { verdict, most, budget: budget.as_secs_f64(), seconds }))
}

/// What the rounding policy of `options` changes on the joints from the chain's base to its tip.
fn snaps_on_chain(m: &Mechanism, options: &LoadOptions) -> Vec<rounding::Snap> {
    if options.exact_geometry || options.snap_tolerance == 0.0 {
        return Vec::new();
    }
    let (rounded, snaps) = rounding::snap(m, options.snap_tolerance);
    let Ok(chain) = Chain6R::from_mechanism(&rounded, options.spec.base.as_deref(), options.spec.tip.as_deref()) else { return Vec::new() };
    let (Some(base), Some(tip)) = (rounded.link(&chain.base), rounded.link(&chain.tip)) else { return Vec::new() };
    let below_base: Vec<usize> = rounded.path_to(base);
    let on_chain: Vec<&str> = rounded.path_to(tip).into_iter().filter(|j| !below_base.contains(j)).map(|j| rounded.joints[j].name.as_str()).collect();
    snaps.into_iter().filter(|s| on_chain.contains(&s.joint.as_str())).collect()
}

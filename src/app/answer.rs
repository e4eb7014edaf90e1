//! What a run answers: one `Answer` variant per `Job` variant, plain data that the edges
//! translate (`edges::report` into JSON, the CLI into text, `edges::ros` into messages) and
//! never patch. Every answer says whether it is complete by the one rule
//! (`Completeness::of`).

use crate::analyses::arm6r::Chain6R;
use crate::analyses::distances::Certified;
use crate::analyses::loop_singular::image::{ImagePoints, ImageReport};
use crate::analyses::loop_singular::SingularSet;
use crate::analyses::sweep::TaskResult;
use crate::kernel::outcome::{Completeness, Incompleteness, Scope};
use crate::kernel::search::SolverSettings;
use std::collections::BTreeMap;

use super::arm::{Arm, ArmCollisions, ArmIk, ArmSingularities};
use super::distances::{DistancesRequest, DistancesRun};
use super::solve::{LinkReadout, SolveRun};
use crate::analyses::loop_singular::SingularSets;
use crate::analyses::input_motion::InputMotionCheck;
use super::path::ArmPathCheck;
use super::six::{ArmCuspidality, ArmIk6, ArmSelfMotion};
use super::BoxSetResult;

/// The answer to one `Job`.
#[derive(Clone, Debug)]
pub enum Answer {
    /// `Job::Solve`.
    Solve(Box<SolveAnswer>),
    /// `Job::Singularities`.
    Singularities(Box<SingularitiesAnswer>),
    /// `Job::Ik`.
    Ik(Box<IkAnswer>),
    /// `Job::Ik6`.
    Ik6(Box<Ik6Answer>),
    /// `Job::SelfMotion`.
    SelfMotion(Box<ArmSelfMotion>),
    /// `Job::PathCheck`.
    PathCheck(Box<PathCheckAnswer>),
    /// `Job::Collisions`.
    Collisions(Box<CollisionsAnswer>),
    /// `Job::Distances`.
    Distances(Box<DistancesAnswer>),
    /// `Job::LoopSingularities`.
    LoopSingularities(Box<LoopAnswer>),
    /// `Job::SweepTask`.
    SweepTask(Box<TaskResult>),
}

/// Every configuration of a linkage, as boxes.
#[derive(Clone, Debug)]
pub struct SolveAnswer {
    /// The built problem and the settings it ran with.
    pub run: SolveRun,
    /// The boxes.
    pub result: BoxSetResult,
    /// Per box of `result`, its links read out (within the run's deadline, as its joints).
    pub links: Vec<LinkReadout>,
    /// The model's degrees of freedom, in one line.
    pub freedom: String,
    /// Links merged into one rigid body, each to the body's first link.
    pub rigid_links: BTreeMap<String, String>,
}

impl SolveAnswer {
    /// The one rule: the limit that stopped the run, else the boxes left undecided.
    pub fn completeness(&self) -> Completeness {
        self.result.completeness()
    }

    /// The builder's name (`planar`, `spatial`, `pose`, `distances`).
    pub fn model_name(&self) -> &'static str {
        use crate::formulate::Coordinates;
        self.run.problem().model().name()
    }

    /// Why that builder.
    pub fn model_reason(&self) -> &str {
        self.run.problem().model_reason()
    }

    /// What the builder removed from the model (merged links, dropped variables), one line each.
    pub fn reductions(&self) -> &[String] {
        self.run.problem().reductions()
    }
}

/// Cusps, nodes, internal motions and the verdicts of an arm.
#[derive(Clone, Debug)]
pub struct SingularitiesAnswer {
    /// The arm as read.
    pub arm: Arm,
    /// What the searches found, and the 3R positioning structure's verdict.
    pub found: ArmSingularities,
    /// A six-joint arm's whole-arm cuspidality verdict (when its 3R verdict is a sub-chain's or
    /// its wrist is spherical), with the chain it is about.
    pub whole_arm: Option<(Chain6R, ArmCuspidality)>,
}

/// Whose verdict a singularity answer's 3R verdict is.
impl SingularitiesAnswer {
    /// What the positioning structure's verdict concerns: the arm, or the sub-chain and point.
    pub fn sub_chain_scope(&self) -> Scope {
        let choice = &self.arm.prepared.choice;
        if choice.scope.stands_for_arm {
            Scope::Mechanism
        } else {
            Scope::SubChain { joints: self.arm.chain.joints.to_vec(), point: choice.scope.subject.clone() }
        }
    }
}

/// Every solution of an arm's positioning structure for a point.
#[derive(Clone, Debug)]
pub struct IkAnswer {
    /// The arm as read.
    pub arm: Arm,
    /// The solutions.
    pub found: ArmIk,
}

/// Every solution of a six-revolute arm for a pose.
#[derive(Clone, Debug)]
pub struct Ik6Answer {
    /// The chain solved.
    pub chain: Chain6R,
    /// The solutions.
    pub found: ArmIk6,
}

/// One verdict per segment of a joint path.
#[derive(Clone, Debug)]
pub struct PathCheckAnswer {
    /// The verdicts.
    pub found: ArmPathCheck,
    /// For the 3R set: which chain and point were read, and why.
    pub chain: Option<String>,
}

/// Where an arm's collision capsules meet.
#[derive(Clone, Debug)]
pub struct CollisionsAnswer {
    /// The sets.
    pub found: ArmCollisions,
    /// The precision asked.
    pub precision: f64,
}

/// The solutions of a distance problem, each cluster certified or undecided.
#[derive(Clone, Debug)]
pub struct DistancesAnswer {
    /// The problem solved.
    pub run: DistancesRun,
    /// What was asked of it.
    pub request: DistancesRequest,
    /// The settings it ran with.
    pub settings: SolverSettings,
    /// The solutions.
    pub certified: Certified,
}

/// What `Job::LoopSingularities` found.
#[derive(Clone, Debug)]
pub enum LoopAnswer {
    /// The singular sets asked.
    Sets {
        /// Robot name.
        mechanism: String,
        /// The built problems.
        sets: SingularSets,
        /// One solved set per problem.
        solved: Vec<SingularSet>,
        /// The settings they ran with.
        settings: SolverSettings,
    },
    /// The type-II image.
    Image(Box<ImageReport>),
    /// The type-II image's cusps or nodes.
    Points(Box<ImagePoints>),
    /// An input motion followed.
    Motion(Box<InputMotionCheck>),
}

impl Answer {
    /// The job's name, as `Job::name` spells it.
    pub fn name(&self) -> &'static str {
        match self {
            Answer::Solve(_) => "solve",
            Answer::Singularities(_) => "singularities",
            Answer::Ik(_) => "ik",
            Answer::Ik6(_) => "ik6",
            Answer::SelfMotion(_) => "self-motion",
            Answer::PathCheck(_) => "path-check",
            Answer::Collisions(_) => "collisions",
            Answer::Distances(_) => "distances",
            Answer::LoopSingularities(_) => "loop-singularities",
            Answer::SweepTask(_) => "sweep",
        }
    }

    /// Whether the answer is complete: no limit stopped it and nothing is left undecided.
    pub fn completeness(&self) -> Completeness {
        match self {
            Answer::Solve(a) => a.completeness(),
            Answer::Singularities(a) => a.found.completeness(),
            Answer::Ik(a) => Completeness::of_run(a.found.solutions.status),
            Answer::Ik6(a) => Completeness::of(a.found.solutions.status, a.found.solutions.clusters.len(), false),
            Answer::SelfMotion(a) => a.set.completeness(),
            Answer::PathCheck(a) => a.found.completeness(),
            Answer::Collisions(a) => a.found.set.completeness(),
            Answer::Distances(a) => a.certified.completeness(),
            Answer::LoopSingularities(a) => match a.as_ref() {
                LoopAnswer::Sets { solved, .. } => solved.iter().map(SingularSet::completeness).fold(Completeness::Complete, Completeness::and),
                LoopAnswer::Image(r) => r.completeness(),
                LoopAnswer::Points(r) => r.completeness(),
                LoopAnswer::Motion(m) => m.completeness(),
            },
            Answer::SweepTask(t) => t.completeness(),
        }
    }

    /// The reason of an incomplete answer, or `None`.
    pub fn incompleteness(&self) -> Option<Incompleteness> {
        self.completeness().reason()
    }
}

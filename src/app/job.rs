//! The questions a front end may ask, as plain data: one `Job` variant per question. A front end
//! (the CLI, the ROS node, the Python package) translates its own request into a `Job`, and
//! nothing else: `prepare` validates it against the `Input`, `Prepared::run` answers it within a
//! `Control`. The resolution of every job is one number, its `precision`: the largest width of a
//! reported box, in the job's own variables (`Job::default_precision`).

use crate::analyses::arm3r::LoadOptions;
use crate::analyses::arm6r::PoseInput;
use crate::analyses::distances::Choice;
use crate::analyses::sweep::{Plan, Task};
use crate::formulate::{LegValues, ModelChoice, Output, SingularKind, TracedPoint};
use crate::kernel::contract::FaceBounds;
use crate::kernel::lp::LpBackend;
use crate::kernel::search::Limits;

use super::arm::IkPoint;

/// `ik6`'s timeout when none is given. A pose whose solutions form a continuum (a wrist
/// singularity: joints 4 and 6 aligned, only their sum or difference fixed) is covered by boxes
/// along the whole curve and never completes: at the home pose of a Motoman GP7-like arm the
/// 20,000,000-box default ran past 600 s and 579 MB. Regular poses take well under a second.
pub const IK6_DEFAULT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(60);
use super::path::PathSet;

/// One question, with everything it needs but the mechanism and the bounds of the run.
#[derive(Clone, Debug)]
pub enum Job {
    /// Every configuration of a closed-loop linkage (`linkspace solve`).
    Solve(SolveJob),
    /// Cusps, nodes, internal motions and the cuspidality verdict of an arm
    /// (`linkspace singularities`).
    Singularities(SingularitiesJob),
    /// Every solution of an arm's 3R positioning structure for a point (`linkspace ik`).
    Ik(IkJob),
    /// Every solution of a six-revolute arm for a pose of its tip (`linkspace ik6`).
    Ik6(Ik6Job),
    /// Every configuration of a seven-revolute arm at a pose of its tip, a union of curves
    /// (`linkspace self-motion`).
    SelfMotion(SelfMotionJob),
    /// Where a joint path meets a singularity (`linkspace path-check`).
    PathCheck(PathCheckJob),
    /// Where an arm's collision capsules meet (`linkspace collisions`).
    Collisions(CollisionsJob),
    /// A distance problem by Cayley–Menger determinants (`linkspace distances`).
    Distances(DistancesJob),
    /// The singular sets, type-II image or input motion of a closed-loop linkage
    /// (`linkspace loop-singularities`).
    LoopSingularities(LoopSingularitiesJob),
    /// One task of a design sweep (`linkspace sweep` runs one per grid point).
    SweepTask(SweepTaskJob),
}

/// `Job::Solve`.
#[derive(Clone, Debug)]
pub struct SolveJob {
    /// Joints (or loops) held at a value: radians or metres.
    pub fixed: Vec<(String, f64)>,
    /// Points followed in world coordinates: link, point in its frame, name as written.
    pub traces: Vec<TracedPoint>,
    /// Which builder.
    pub model: ModelChoice,
    /// Largest width of a solution box in every primary variable (the solver's sigma).
    pub precision: f64,
    /// Keep shrinking a box while a round leaves less than this share of its volume.
    pub rho: f64,
    /// Shrink with LPs (false: interval propagation only).
    pub use_lp: bool,
    /// Interval Newton once every primary is at most this wide (0: never).
    pub newton_width: f64,
    /// The LP solver proposing the multipliers the safe bound verifies.
    pub lp_backend: LpBackend,
}

impl Default for SolveJob {
    fn default() -> Self {
        let s = crate::kernel::search::SolverSettings::default();
        Self { fixed: Vec::new(), traces: Vec::new(), model: ModelChoice::Auto, precision: s.sigma, rho: s.rho, use_lp: s.use_lp, newton_width: s.newton_width, lp_backend: s.lp_backend }
    }
}

/// How a serial arm is read by every arm job: the chain (base, tip, point, held joints), the
/// rounding policy and the joint limits.
pub type ArmOptions = LoadOptions;

/// `Job::Singularities`.
#[derive(Clone, Debug)]
pub struct SingularitiesJob {
    /// How the arm is read.
    pub arm: ArmOptions,
    /// Every length of the file widened to an interval of this half-width (metres).
    pub uncertainty: f64,
    /// Largest width (radians) of reported and undecided boxes, in (0, 1).
    pub precision: f64,
    /// Also search nodes.
    pub nodes: bool,
    /// Decide the cuspidality verdict (false: the searches alone).
    pub verdict: bool,
    /// Run the interval searches even where the verdict is structural.
    pub search_anyway: bool,
    /// Seconds for the whole-arm cuspidality search of a six-joint arm (0: not searched).
    pub arm_budget: f64,
}

/// `Job::Ik`.
#[derive(Clone, Debug)]
pub struct IkJob {
    /// How the arm is read.
    pub arm: ArmOptions,
    /// Every length of the file widened to an interval of this half-width (metres).
    pub uncertainty: f64,
    /// The point to reach.
    pub point: IkPoint,
    /// Largest width (radians) of reported boxes, in (0, 1).
    pub precision: f64,
}

/// `Job::Ik6`.
#[derive(Clone, Debug)]
pub struct Ik6Job {
    /// How the arm is read (base and tip; the rounding policy).
    pub arm: ArmOptions,
    /// The tip frame's pose in the base frame.
    pub pose: PoseInput,
    /// Largest width (radians) of reported boxes, in (0, 1).
    pub precision: f64,
}

/// `Job::SelfMotion`.
#[derive(Clone, Debug)]
pub struct SelfMotionJob {
    /// How the arm is read (base and tip; the rounding policy).
    pub arm: ArmOptions,
    /// The tip frame's pose in the base frame.
    pub pose: PoseInput,
    /// The joint whose range is cut into cells (default: the third revolute joint).
    pub parameter: Option<String>,
    /// The part of the parameter's range searched (default: its limits, at most a turn).
    pub range: Option<(f64, f64)>,
    /// Width (radians) of the parameter's cells, in (0, 1].
    pub cell: f64,
    /// Largest width (radians) of the other joints' boxes, in (0, 1).
    pub precision: f64,
}

/// `Job::PathCheck`.
#[derive(Clone, Debug)]
pub struct PathCheckJob {
    /// How the arm is read.
    pub arm: ArmOptions,
    /// The waypoints, each the joint values (radians) of `joint_names`.
    pub waypoints: Vec<Vec<f64>>,
    /// The joints of the waypoints' values, in order (a trajectory's columns, any order, more
    /// joints allowed); empty: the checked set's joints in their order.
    pub joint_names: Vec<String>,
    /// The singular set: the six-revolute arm's or its 3R positioning structure's; `None`
    /// picks the six-revolute arm's when the file has one and no sub-chain was chosen.
    pub set: Option<PathSet>,
    /// Radians: crossings are narrowed until the joints' enclosure is this wide.
    pub precision: f64,
}

/// `Job::Collisions`.
#[derive(Clone, Debug)]
pub struct CollisionsJob {
    /// How the arm is read.
    pub arm: ArmOptions,
    /// Largest width (radians) of undecided boxes, in (0, 1).
    pub precision: f64,
}

/// `Job::Distances`.
#[derive(Clone, Debug)]
pub struct DistancesJob {
    /// Squared lengths of legs (platform) or of named distances (distance file).
    pub fixed: Vec<(String, f64)>,
    /// How a platform's `fixed` legs are given: squared lengths (as `linkspace distances
    /// --fix` takes them) or lengths (as the node's Solve requests, REP 103). A length is squared
    /// as an interval, so the problem solved is exactly the one with that length.
    pub legs: LegValues,
    /// Largest width of a solution box in every unknown squared distance.
    pub precision: f64,
    /// `None`: the formulation's default (0.99 for the determinants, 0.9 for coordinates).
    pub rho: Option<f64>,
    /// Add the redundant determinants.
    pub redundant: bool,
    /// Variables for the unknown distances.
    pub formulation: Choice,
    /// How the trapezoid sides are bounded.
    pub faces: FaceBounds,
}

/// What `Job::LoopSingularities` asks.
#[derive(Clone, Debug, PartialEq)]
pub enum LoopQuestion {
    /// These singular sets (empty: every set the actuation defines).
    Sets(Vec<SingularKind>),
    /// The type-II image on a grid of this many cells per side.
    Image {
        /// Cells per side.
        grid: usize,
    },
    /// The type-II image's cusps alone.
    Cusps,
    /// The type-II image's nodes alone.
    Nodes,
    /// Follow the input motion of one actuated joint from an assembly.
    Motion(MotionSpan),
}

/// The span of an input motion.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionSpan {
    /// The actuated joint's start value.
    pub from: f64,
    /// Its end value.
    pub to: f64,
    /// The assembly at `from`: a value per free joint.
    pub assembly: Vec<f64>,
    /// Largest parameter step.
    pub max_step: f64,
    /// Smallest parameter step before the check gives up.
    pub min_step: f64,
}

/// `Job::LoopSingularities`.
#[derive(Clone, Debug)]
pub struct LoopSingularitiesJob {
    /// What to answer.
    pub question: LoopQuestion,
    /// Joints held at a value.
    pub fixed: Vec<(String, f64)>,
    /// The actuated joints (`None`: the file's transmissions).
    pub actuated: Option<Vec<String>>,
    /// The output of the output singular set.
    pub output: Option<Output>,
    /// Largest width of a reported box.
    pub precision: f64,
}

/// `Job::SweepTask`.
#[derive(Clone, Debug)]
pub struct SweepTaskJob {
    /// The sweep.
    pub plan: Plan,
    /// The task: its index and parameter values.
    pub task: Task,
}

impl Job {
    /// The question's name, as the CLI's subcommand spells it.
    pub fn name(&self) -> &'static str {
        match self {
            Job::Solve(_) => "solve",
            Job::Singularities(_) => "singularities",
            Job::Ik(_) => "ik",
            Job::Ik6(_) => "ik6",
            Job::SelfMotion(_) => "self-motion",
            Job::PathCheck(_) => "path-check",
            Job::Collisions(_) => "collisions",
            Job::Distances(_) => "distances",
            Job::LoopSingularities(_) => "loop-singularities",
            Job::SweepTask(_) => "sweep",
        }
    }

    /// The bounds a run of this job takes when the front end sets none: the kernel's, with the
    /// job's own box budget (`singularities`' per search), for the singularity searches a
    /// tighter memory bound on pending cells, and for `ik6` a timeout (`IK6_DEFAULT_TIMEOUT`).
    pub fn default_limits(name: &str) -> Limits {
        let base = Limits::default();
        match name {
            "singularities" => Limits { max_cells: 5_000_000, max_memory: 256 << 20, ..base },
            "ik" => Limits { max_cells: 200_000, ..base },
            "ik6" | "self-motion" => Limits { max_cells: 20_000_000, timeout: Some(IK6_DEFAULT_TIMEOUT), ..base },
            "collisions" => Limits { max_cells: crate::analyses::arm3r::collision::DEFAULT_MAX_BOXES, ..base },
            // Segments of a joint path, each checked whole.
            "path-check" => Limits { max_cells: 10_000_000, ..base },
            _ => base,
        }
    }

    /// The job's default `precision`, by name (see each job's field).
    pub fn default_precision(name: &str) -> f64 {
        match name {
            "solve" => crate::kernel::search::SolverSettings::default().sigma,
            "distances" => 0.01,
            "loop-singularities" | "singularities" => 1e-4,
            "ik" => 1e-6,
            "ik6" | "path-check" => 1e-9,
            "collisions" => 1e-2,
            "self-motion" => 0.1,
            _ => 1e-3,
        }
    }
}

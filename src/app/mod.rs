//! The front door: a `Job` (one variant per question) is checked against an `Input` by
//! `prepare` and answered by `Prepared::run` within a `Control`, as one `Answer`. Every front
//! end (the CLI, the ROS node, the Python package) translates its requests into jobs and its
//! answers into its own output, and names nothing below this module.
//!
//! The node keeps one `Analysis` per loaded mechanism (`load` picks it: `Manip3rAnalysis`,
//! `LinkageAnalysis`, `PlatformAnalysis` or `Unsupported`): what the mechanism is, which
//! services it answers, which `Job` each query is with the mechanism's load-time options, and how
//! the `Answer` reads as the plain-data shapes of the node's messages (`results`).
//!
//! No IO and no async here: a front end prepares a run (all validation happens then, so bad
//! requests are answered at once), moves it to a thread of its own and converts the answer.

mod analysis;
mod answer;
mod info;
pub(crate) mod arm;
mod arm_analysis;
pub(crate) mod distances;
mod job;
pub(crate) mod linkage;
pub(crate) mod loops;
mod merge;
pub(crate) mod path;
mod prepare;
mod results;
mod solve;
mod platform;
pub(crate) mod six;
pub(crate) mod sweep;

/// Items the front ends inside the crate (the node) and the lab and tests (feature `internals`)
/// name, which a program using linkspace does not: public with `internals`, else crate-wide.
macro_rules! internal_use {
    ($($path:tt)*) => {
        #[cfg(feature = "internals")]
        pub use $($path)*;
        #[cfg(not(feature = "internals"))]
        pub(crate) use $($path)*;
    };
}

// The front door: a `Job` in, an `Answer` out.
pub use answer::{Answer, CollisionsAnswer, DistancesAnswer, Ik6Answer, IkAnswer, LoopAnswer, PathCheckAnswer, SingularitiesAnswer, SolveAnswer};
pub use job::{ArmOptions, CollisionsJob, DistancesJob, Ik6Job, IkJob, Job, LoopQuestion, LoopSingularitiesJob, MotionSpan, PathCheckJob, SelfMotionJob, SingularitiesJob, SolveJob, SweepTaskJob};
internal_use!(job::IK6_DEFAULT_TIMEOUT);
pub use prepare::{prepare, Input, JobError, Prepared};
// What a front end shows of a mechanism before asking it anything.
pub use info::{describe, questions, JointInfo, LoopInfo, MechanismInfo, Questions};
// The outcome vocabulary and the bounds of a run.
pub use crate::kernel::outcome::{BoxStatus, Completeness, Incompleteness, Limit, Scope, Status};
pub use crate::kernel::search::{Control, Limits, Progress, SolverSettings};
// How a run is shared among processes (the binary's MPI ranks give the kernel its `Peers`).
pub use crate::kernel::search::{rank_and_size, share_searches, Peers};
// The options the jobs take.
pub use crate::analyses::arm3r::{check_precision, ChainSpec};
pub use crate::analyses::arm6r::PoseInput;
pub use crate::analyses::distances::Choice as DistanceFormulation;
pub use crate::formulate::{LegValues, Model as LinkageModel, ModelChoice, Output, SingularKind, TracedPoint};
pub use crate::kernel::contract::FaceBounds;
pub use crate::kernel::lp::LpBackend;
pub use crate::model::rounding::ANGLE_TOLERANCE as SNAP_TOLERANCE;
pub use arm::IkPoint;
pub use path::PathSet;
// Mechanisms as read, and the records answers carry that front ends name.
pub use crate::model::Mechanism;
pub use crate::analyses::input_motion::{motion_joints, InputMotionCheck};
pub use crate::analyses::loop_singular::image::{ImagePoints, ImageReport};
internal_use!(crate::analyses::loop_singular::image::{ImageCusp, ImageNode});
internal_use!(results::ResultBox);
internal_use!(crate::model::urdf::parse as parse_urdf);
/// A design sweep's spec, tasks and result lines, which the sweep command reads and writes.
pub mod sweeps {
    pub use crate::analyses::sweep::{csv, map_svg, parse, read_done, run_tasks, Header, Plan, Summary, Sweep, Task, TaskResult, TaskStatus, DEFAULT_MAX_TASKS};
    pub use super::sweep::{answer_task, check_sweep};
}

// The node's view of a loaded mechanism and the shapes its messages are made from.
internal_use!(analysis::{load, load_urdf, Analysis, AnalysisError, MechanismKind, Service, Unsupported});
internal_use!(results::{classify, PreparedRun, AssemblyMode, BoxSetResult, Classification, IkQuery, IkResult, IkSolution, LoopSingularities, SingularPair, SingularPoint, SingularSetResult, SingularityQuery, SingularityResult, TracedBounds});
pub(crate) use results::gap;
// The analyses' entry points and typed results, which the answers carry.
internal_use!(crate::kernel::search::SolveStats);
internal_use!(crate::analyses::arm3r::{branches::SingularBranches, joints_over, LoadOptions});
internal_use!(crate::analyses::arm6r::{Chain6R, SegmentVerdict});
internal_use!(crate::kernel::interval::{Bounds, Interval});
internal_use!(arm::{collisions, inverse_kinematics, singularities, Arm, ArmCollisions, ArmIk, ArmSingularities, SingularitiesRequest});
internal_use!(arm_analysis::{Manip3rAnalysis, CURVE_DEPTH});
internal_use!(distances::{DistancesRun, DistancesRequest});
internal_use!(linkage::LinkageAnalysis);
internal_use!(solve::{describe_freedom, LinkReadout, SolveRun});
internal_use!(crate::analyses::loop_singular::SingularSets);
internal_use!(loops::{all_kinds, analyse_image, image_points, Actuation, ImageAnalysisError, ImageSearch});
internal_use!(crate::analyses::input_motion::{check_input_motion, MotionError, MotionRequest, MotionStep, MotionVerdict});
internal_use!(platform::PlatformAnalysis);
internal_use!(path::{check_path, check_path3, positioning_joints, ArmPathCheck});
internal_use!(six::{arm_cuspidality, arm_cuspidality_of, chain6, inverse_kinematics6, self_motion, ArmCuspidality, ArmIk6, ArmSelfMotion, ArmVerdict, ArmVerdictLine});
internal_use!(sweep::sweep_task);

//! linkspace: every configuration a mechanism can take, with guarantees.
//!
//! The front door is `app`: a `Job` (one variant per question) is checked against its `Input`
//! by `app::prepare` and answered by `Prepared::run` within a `Control`, as one `Answer` that
//! says what is proven (`BoxStatus` per box, `Completeness` per answer, `Scope` per verdict).
//! Below it, by layer: the analyses (`analyses`, one folder per question), the builders
//! (`formulate`), mechanisms read from URDF (`model`), and the branch-and-prune kernel
//! (`kernel`), which covers a system with interval boxes that provably enclose every solution.
//! What answers become outside is `edges` (JSON reports, the ROS 2 node). See ARCHITECTURE.md.
//!
//! # Examples
//!
//! Both assembly modes of the bundled four-bar with its crank at 0.5 rad, each proven unique:
//!
//! ```
//! use linkspace::app::{self, Answer, BoxStatus, Completeness, Control, Input, Job, Limits, SolveJob};
//! use std::sync::atomic::AtomicBool;
//!
//! let input = Input::urdf(include_str!("../urdf/four_bar.urdf")).unwrap();
//! let job = Job::Solve(SolveJob { fixed: vec![("crank_joint".into(), 0.5)], precision: 1e-6, ..SolveJob::default() });
//! let cancel = AtomicBool::new(false);
//! let control = Control { limits: Limits::default(), threads: 1, cancel: &cancel };
//! let answer = app::prepare(&input, job).unwrap().run(&control, &mut |_| {}).unwrap();
//! assert_eq!(answer.completeness(), Completeness::Complete);
//! let Answer::Solve(solved) = answer else { unreachable!() };
//! assert_eq!(solved.result.clusters, 2);
//! assert!(solved.result.boxes.iter().all(|b| b.status == BoxStatus::Unique));
//! ```

#![warn(missing_docs)]
// What is public is what the crate root reaches: an item public inside a private module says
// `pub(crate)`. (The library's alone: a binary or a test has no public items.)
#![warn(unreachable_pub)]

pub mod analyses;
pub mod app;
pub mod edges;
pub mod formulate;
pub mod kernel;
pub mod model;

pub use app::{load, Analysis, AnalysisError};
pub use kernel::interval::{Interval, IntervalBox};
pub use kernel::lp::{LpBackend, LpCounters};
pub use kernel::search::{Limit, Limits, Progress, Solver, SolverSettings, Status};
pub use kernel::system::EquationSystem;
pub use model::{Mechanism, ModelError};

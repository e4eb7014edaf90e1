//! linkspace: every configuration a mechanism can take, with guarantees.
//!
//! The front door is `app`: a `Job` (one variant per question) is checked against its `Input`
//! by `app::prepare` and answered by `Prepared::run` within a `Control`, as one `Answer` that
//! says what is proven (`BoxStatus` per box, `Completeness` per answer, `Scope` per verdict).
//! What answers become outside is `edges`: JSON reports and the text the CLI prints
//! (`edges::report`), the ROS 2 node (`edges::ros`). Below the front door, private (public only
//! with the `internals` feature, for the project's own lab and tests): the analyses (one folder
//! per question), the builders, mechanisms read from URDF, and the branch-and-prune kernel,
//! which covers a system with interval boxes that provably enclose every solution. See
//! ARCHITECTURE.md and docs/manual/library.md.
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
// Without `internals` the layers below `app` are private, and what only the lab and the tests
// reach of them is neither reachable nor used by the product: that is by design, not dead code.
#![cfg_attr(not(feature = "internals"), allow(unreachable_pub, dead_code, unused_imports))]

/// A layer below the front door: private to the crate, public with the `internals` feature
/// (the project's own lab, tests and benchmarks; not a stable interface).
macro_rules! layer {
    ($name:ident) => {
        #[cfg(feature = "internals")]
        pub mod $name;
        #[cfg(not(feature = "internals"))]
        mod $name;
    };
}

pub mod app;
pub mod edges;

layer!(analyses);
layer!(formulate);
layer!(kernel);
layer!(model);

//! The branch-and-prune kernel: interval arithmetic, equation systems, contractors, LPs with
//! verified bounds, the one search loop, and the outcome vocabulary every result speaks. No IO;
//! it knows no mechanism, URDF, ROS or Python.

pub mod contract;
pub mod interval;
pub(crate) mod lp;
pub mod outcome;
pub mod search;
pub mod system;
pub mod taylor;

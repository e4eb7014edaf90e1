//! What the answers become outside the library: JSON reports (`report`) and, with the `ros`
//! feature, the ROS 2 node's messages and event loop (`ros`). Both are pure translations of
//! `app::Answer` values.

pub mod report;
#[cfg(feature = "ros")]
pub mod ros;

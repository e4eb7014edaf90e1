//! Integration tests, one binary (ripgrep style). Each module says what belongs in it.

/// Shared helpers: running the library on bundled URDFs, independent references.
mod util;
/// Planar linkages from URDF against closed forms and independently traced curves.
mod linkage;
/// The command line: bad input gives one clear line and a non-zero exit.
mod cli;
/// The ROS 2 node against real rclpy over DDS on loopback: topics, services, load.
#[cfg(feature = "ros")]
mod topics;

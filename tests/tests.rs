//! Integration tests, one binary (ripgrep style). Each module says what belongs in it.

/// The invariants of ARCHITECTURE.md read off the source: layers, no cycle, adapters.
mod architecture;
/// Shared helpers: running the library on bundled URDFs, independent references.
mod util;
/// Planar linkages from URDF against closed forms and independently traced curves.
mod linkage;
/// Every configuration of the stated mechanism, with limits, tiny and rounded coefficients.
mod soundness;
/// The command line: bad input gives one clear line and a non-zero exit.
mod cli;
/// What runs after branch and prune keeps the run's limits and says when it was cut short.
mod post_processing;
/// Every command stopped by `--timeout` ends, names the time limit and drops nothing.
mod deadlines;
/// Random four-bars, slider-cranks and six-bars against a high-precision reference.
mod random_linkages;
/// Instances built to break solvers: branch and prune against Newton–Raphson.
mod stability;
/// 3R manipulators from URDF: the map of Benoit et al. (2019), Table 1 counts, dense-sampling
/// references.
mod manip3r;
/// Real arms' URDFs: chain choice, rounding, limits, the verdict, three conventions.
mod real_arms;
/// Seven-revolute arms' self-motion sets against Newton's method on forward kinematics.
mod self_motion;
/// `linkspace sweep`: verdicts and counts over design grids against references without the solver.
mod sweeps;
/// Distance problems through Cayley–Menger determinants: octahedral platform, four spheres.
mod cayley_menger;
/// Distance answers certified (Krawczyk in coordinates) or labelled undecided.
mod certified_distances;
/// Spatial linkages (Bennett, RSSR, spherical four-bar) against closed forms; the
/// planar fixtures through the spatial builder.
mod spatial;
/// Singular sets of planar closed-loop linkages against closed forms, grids and Newton.
mod closed_loop_singularities;
/// Input motions of 1-dof loops checked by tube following against closed forms.
mod input_motion;
/// Every assembly `solve --fix` certifies starts the input-motion check: random and bundled
/// loops, typed back at 6 and 17 digits and whole turns away; starts off the mechanism refused.
mod motion_starts;
/// Singular sets of spatial linkages: RSSR and spherical four-bar singular points against their
/// closed-form input–output relations.
mod spatial_singularities;
/// `linkspace chart`: the singular-set charts of closed loops and the 3R workspace
/// regions show what the references of the other modules establish.
mod charts;
/// Searches shared by MPI ranks report what one process reports.
mod shared;
/// The ROS 2 node against real rclpy over DDS on loopback: topics, services, load.
#[cfg(feature = "ros")]
mod topics;
/// Six-revolute arms whole: certified IK against forward kinematics and a closed form, and
/// the whole-arm cuspidality witness re-checked in `f64`.
mod six_r;
/// Spherical-wrist arms in closed form against the search and forward kinematics.
mod spherical_wrist;
/// Spherical-wrist arms at and near the wrist singularity: a branch answered as a curve,
/// against forward kinematics.
mod wrist_singular;
/// Arms with axes 2, 3, 4 parallel (the UR family) in closed form against the search and
/// forward kinematics.
mod three_parallel_ik;
/// Joint paths against a 3R positioning structure's singular set: crossings through singular
/// points and clear segments from an `f64` forward-kinematics reference.
mod path_check_3r;
/// The Python package: its pytest suite (answers equal the CLI's, references, Ctrl-C, limits,
/// errors, types), in a venv made by scripts/python_env.sh.
mod python;

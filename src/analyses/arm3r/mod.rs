//! Guaranteed cusps, nodes and internal motions of 3R manipulators, from URDF (Benoit, Delanoue,
//! Lagrange and Wenger 2019).
//!
//! Owns the kinematic map of a serial chain of three revolute joints (`Chain3R`), its sound
//! evaluation with derivatives over boxes (`taylor`, over `interval::trig`), and the searches built on it:
//! internal-motion lines (`motion`), cusps (`cusps`), nodes (`nodes`), inverse kinematics
//! (`ik`), collision sets (`collision`), and the joint and workspace records of their results
//! (`records`; `report::manip3r` writes them as JSON).
//! Every search is branch and prune over (θ₂, θ₃) with interval Newton (Krawczyk) proofs; a box
//! is discarded only when interval arithmetic proves it holds nothing sought. Each is a
//! `search::Prune` run by the kernel within a `Control` (`drive`); `singularities` runs cusps
//! then nodes for every front end.
//! No IO here: the CLI reads files and writes reports.
//!
//! # References
//! R. Benoit, N. Delanoue, S. Lagrange, P. Wenger, *Guaranteed detection of the singularities
//! of 3R robotic manipulators*, Mechanical Sciences (2019). R. Krawczyk,
//! *Newton-Algorithmen zur Bestimmung von Nullstellen mit Fehlerschranken*, Computing 4 (1969).

// The searches and readings a caller drives directly are namespaces of their own (`cusps::search`,
// `ik::solve`, `collision::classify`, ...); the rest is reached through the list below.
pub(crate) mod aspects;
pub mod branches;
pub(crate) mod chain;
pub mod collision;
pub(crate) mod curves;
pub mod cusps;
pub(crate) mod drive;
pub(crate) mod frame;
pub mod ik;
pub(crate) mod limits;
pub(crate) mod map;
pub(crate) mod motion;
pub mod nodes;
pub mod path;
pub(crate) mod records;
pub(crate) mod select;
pub mod verdict;

pub use chain::{Chain3R, Jets};
pub use curves::Cover;
pub use cusps::{Cusp, CuspSearch};
pub use drive::Order;
pub use frame::BaseFrame;
pub use limits::JointLimits;
pub use map::TorusMap;
pub use motion::{bands, line_count, Band, PI_UP};
pub use nodes::{Node, NodeSearch};
pub use records::{joints_over, radius, Joints, Workspace};
pub use select::ChainSpec;

use crate::kernel::search::{Control, Progress, Status};
use std::time::Instant;
use thiserror::Error;

/// What is wrong with a 3R problem. Messages are one line and name the culprit.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum Manip3rError {
    /// The mechanism is not a serial chain.
    #[error("not a serial chain: {0}")]
    NotSerial(String),
    /// `--base`, `--tip`, `--tip-point` or `--lock` cannot be honoured.
    #[error("cannot choose the chain: {0}")]
    Selection(String),
    /// The chain does not have exactly three revolute joints (or has a prismatic one).
    #[error("not a 3R chain: {0}")]
    NotThreeR(String),
    /// The end point does not move at all.
    #[error("the analysed point {0} does not move with joints 2 and 3: choose another with --tip-point LINK@X,Y,Z")]
    TipDoesNotMove(String),
    /// det Df vanishes identically: the end point moves along a curve only.
    #[error("the map of the analysed point {0} is degenerate: det Df vanishes everywhere (is the point on the axis of joint 2 or 3?): choose another with --tip-point LINK@X,Y,Z")]
    Degenerate(String),
    /// The snapping tolerance is not in [0, `rounding::LARGEST_TOLERANCE`].
    #[error("snap tolerance must be a number of radians in [0, 0.01], got {0}")]
    BadSnapTolerance(f64),
    /// The requested precision is not in (0, 1).
    #[error("precision must be a number in (0, 1), got {0}")]
    BadPrecision(f64),
    /// A joint path cannot be checked (too few waypoints, a bad number or tolerance).
    #[error("bad path: {0}")]
    BadPath(String),
    /// The requested uncertainty is negative or not finite.
    #[error("uncertainty must be a finite number >= 0, got {0}")]
    BadUncertainty(f64),
    /// An uncertainty as large as a length of the chain: that length could vanish or change
    /// sign, and the arm would be no particular geometry at all.
    #[error("--uncertainty {h}: every length would have to stay away from 0, but joint '{joint}' has a length of {length} m along {axis}; give an uncertainty below {length}")]
    UncertaintyTooLarge {
        /// The half-width asked for.
        h: f64,
        /// The joint whose origin holds the shortest length.
        joint: String,
        /// That length's magnitude (metres).
        length: f64,
        /// Its component: x, y or z of the joint origin.
        axis: &'static str,
    },
    /// A workspace point for inverse kinematics is not finite or has a negative radius.
    #[error("workspace point ({0}, {1}) is not valid: radius must be >= 0 and both finite")]
    BadPoint(f64, f64),
    /// A point of the root frame for inverse kinematics is not finite.
    #[error("point ({}, {}, {}) is not finite", .0[0], .0[1], .0[2])]
    BadTarget([f64; 3]),
    /// Nothing to check for collisions.
    #[error("no collision geometry: {0}")]
    NoCollisionGeometry(String),
    /// A collision shape that is not a cylinder, capsule or sphere.
    #[error("link '{link}': collision {shape} is not supported (use a cylinder, capsule or sphere)")]
    UnsupportedShape {
        /// the link
        link: String,
        /// the shape's kind
        shape: String,
    },
    /// A base body whose distance to the arm would depend on joint 1.
    #[error("collision body '{0}' on the base is not on the first joint's axis: its distance to the arm depends on joint 1, which collisions does not model")]
    BaseBodyOffAxis(String),
}

/// Checks a precision argument once, before any search.
pub fn check_precision(precision: f64) -> Result<(), Manip3rError> {
    if precision.is_finite() && precision > 0.0 && precision < 1.0 {
        Ok(())
    } else {
        Err(Manip3rError::BadPrecision(precision))
    }
}

/// Cusps, internal motions and (when asked) nodes of one chain, from one run.
#[derive(Clone, Debug)]
pub struct Singularities {
    /// The cusp search, with the internal-motion bands.
    pub cusps: CuspSearch,
    /// The node search, when asked for.
    pub nodes: Option<NodeSearch>,
    /// `Complete` when both searches are; otherwise the first limit that stopped one.
    pub status: Status,
    /// Wall-clock seconds of the whole run.
    pub seconds: f64,
}

/// Cusps, then nodes, within one `control`: the CLI and the ROS node both run this, so they
/// bound a request the same way.
///
/// - One deadline for the whole run: the node search gets what the cusp search left of
///   `control.limits.timeout` (none left: it stops at once, its start pair pending).
/// - The cell budget `control.limits.max_cells` holds for each search (boxes, then pairs).
/// - One cancel flag; a cancelled cusp search still hands its certified cusps to the node
///   search, which then stops at once too (cancelled), so every pending cell is reported.
///
/// `progress` sees the cusp search's share decided in [0, ½] and the node search's in [½, 1]
/// (when nodes are searched).
pub fn singularities(chain: &Chain3R, precision: f64, with_nodes: bool, control: &Control, progress: &mut dyn FnMut(&Progress)) -> Result<Singularities, Manip3rError> {
    check_precision(precision)?;
    let start = Instant::now();
    let share = if with_nodes { 0.5 } else { 1.0 };
    let found = cusps::search_with(chain, &cusps::CuspSettings { precision, method: cusps::Method::Krawczyk }, control, &mut |p| {
        progress(&Progress { decided: p.decided * share, ..*p })
    })?;
    let node_search = if with_nodes {
        let control = control.remaining_since(start);
        let settings = nodes::NodeSettings { precision };
        Some(nodes::search_with(chain, &found.cusps, &found.bands, &settings, &control, &mut |p| progress(&Progress { decided: 0.5 + 0.5 * p.decided, ..*p }))?)
    } else {
        None
    };
    let status = node_search.as_ref().map_or(found.status, |n| found.status.and(n.status));
    Ok(Singularities { cusps: found, nodes: node_search, status, seconds: start.elapsed().as_secs_f64() })
}

/// How a mechanism is turned into the analysed 3R chain: the rounding policy, the chain
/// choice and the joint limits (CLI flags `--exact-geometry`, `--snap-tolerance`, `--base`,
/// `--tip`, `--tip-point`, `--lock`, `--ignore-limits`).
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Which chain and point.
    pub spec: select::ChainSpec,
    /// Skip the rounding policy (`crate::model::rounding`).
    pub exact_geometry: bool,
    /// The rounding policy's tolerance (radians; default `rounding::ANGLE_TOLERANCE`); 0 takes
    /// every value as written, as `exact_geometry` does.
    pub snap_tolerance: f64,
    /// Analyse the full torus whatever the files' limits say.
    pub ignore_limits: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { spec: select::ChainSpec::default(), exact_geometry: false, snap_tolerance: crate::model::rounding::ANGLE_TOLERANCE, ignore_limits: false }
    }
}

/// A real arm made ready for the 3R analyses.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The reduced serial mechanism (base to the analysed point), rounded unless exact geometry.
    pub mechanism: crate::model::Mechanism,
    /// What was chosen and why.
    pub choice: select::Choice,
    /// What the rounding policy changed (empty with exact geometry).
    pub snaps: Vec<crate::model::rounding::Snap>,
    /// Whether the rounding policy was skipped (`--exact-geometry`, or a tolerance of 0).
    pub exact_geometry: bool,
    /// The rounding policy's tolerance as asked (radians).
    pub snap_tolerance: f64,
    /// The largest offset from a quarter turn or a coordinate axis left as written on the chain
    /// (`rounding::offsets`), when at most `rounding::LARGEST_TOLERANCE`: what a larger
    /// tolerance would snap.
    pub unsnapped: Option<f64>,
    /// Limits of the three joints, `None` where absent or ignored.
    pub limits: limits::JointLimits,
}

/// Rounding, then chain choice: the one way every 3R command reads a file.
pub fn prepare(m: &crate::model::Mechanism, options: &LoadOptions) -> Result<Prepared, Manip3rError> {
    let tolerance = options.snap_tolerance;
    if !crate::model::rounding::valid_tolerance(tolerance) {
        return Err(Manip3rError::BadSnapTolerance(tolerance));
    }
    let exact_geometry = options.exact_geometry || tolerance == 0.0;
    let (rounded, mut snaps) = if exact_geometry { (m.clone(), Vec::new()) } else { crate::model::rounding::snap(m, tolerance) };
    // Lock values are joint angles written as the file's are: snapped alike.
    let mut spec = options.spec.clone();
    if !exact_geometry {
        for (joint, v) in &mut spec.locks {
            // Not past a limit the written value honours (a lock at a limit written 3.14159).
            let within = |q: f64| match rounded.joint(joint).map(|j| rounded.joints[j].kind) {
                Some(crate::model::JointKind::Revolute { limits: Some((lo, hi)) }) => lo <= q && q <= hi,
                _ => true,
            };
            if let Some(q) = crate::model::rounding::snap_value(*v, tolerance).filter(|&q| within(q)) {
                snaps.push(crate::model::rounding::Snap { joint: joint.clone(), what: "lock".into(), original: [*v, 0.0, 0.0], snapped: [q, 0.0, 0.0] });
                *v = q;
            }
        }
    }
    let (mechanism, choice) = select::positioning(&rounded, &spec, tolerance)?;
    // Only what the analysis reads is listed: snaps on the chosen chain (side links and
    // fingers off it do not enter).
    let on_chain: Vec<&str> = rounded.link(&choice.tip).map_or(Vec::new(), |t| rounded.path_to(t).iter().map(|&j| rounded.joints[j].name.as_str()).collect());
    snaps.retain(|s| on_chain.contains(&s.joint.as_str()));
    let unsnapped = rounded
        .joints
        .iter()
        .filter(|j| on_chain.contains(&j.name.as_str()))
        .flat_map(crate::model::rounding::offsets)
        .filter(|&d| d > 0.0 && d <= crate::model::rounding::LARGEST_TOLERANCE)
        .reduce(f64::max);
    let limits = limits::JointLimits::of(&mechanism, &choice.joints, options.ignore_limits);
    Ok(Prepared { mechanism, choice, snaps, exact_geometry, snap_tolerance: tolerance, unsnapped, limits })
}

/// For an arm whose verdict is structural (`verdict::parallel_structure`): the cusp search's
/// answer without a search, and no node search.
///
/// Cusp points are excluded by the proof (f is injective on every aspect, and three solutions
/// merge at a cusp value, two of them in one aspect), so the cusp list is empty and complete.
/// The interval search would not say so: where the two singular branches (elbow fold, and the
/// fold of (ρ, z) where the point crosses the plane of axis 1) cross, ∇det = 0 and every box
/// there satisfies the system (2) of Benoit et al. (2019) without Krawczyk being able to decide it,
/// and branches mapped onto one curve (curves of nodes) flood the node search. Internal-motion
/// lines are still searched (cheap, and they exist when the point can reach axis 2).
pub fn structural_singularities(chain: &Chain3R, precision: f64, control: &Control) -> Result<Singularities, Manip3rError> {
    check_precision(precision)?;
    let start = Instant::now();
    let (bands, status) = motion::bands_within(chain, precision, control);
    let seconds = start.elapsed().as_secs_f64();
    let cusps = CuspSearch { cusps: Vec::new(), undecided: Vec::new(), bands, status, stats: Default::default(), contracted: 0, seconds };
    Ok(Singularities { cusps, nodes: None, status, seconds })
}

//! The command line: argument parsing and the `solve` command. `anyhow` lives here and in main.

#[cfg(feature = "ros")]
mod ros_args;
#[cfg(feature = "ros")]
mod serve;
#[cfg(feature = "mpi")]
mod ranks;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use linkspace::model::urdf;
use linkspace::formulate::TracedPoint;
use linkspace::formulate::ModelChoice;
use linkspace::LpBackend;
use linkspace::app::{self, Arm, IkPoint};
use linkspace::analyses::arm3r::{self, collision};
use linkspace::analyses::arm6r::PoseInput;
use linkspace::app::Bounds;
use linkspace::formulate::Coordinates;
use linkspace::edges::report;
use linkspace::kernel::search::Control;
use linkspace::kernel::search::{BoxStatus, Limits, Progress, SolverSettings};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

pub(crate) mod distances;
mod loop_singularities;
mod sweep;

#[derive(Parser)]
#[command(name = "linkspace", version, about = "Every configuration a mechanism can take, with guarantees.")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The bounds every command takes: `#[command(flatten)]` into each command's arguments.
#[derive(clap::Args, Clone, Debug)]
pub(crate) struct LimitArgs {
    /// Stop after processing this many boxes (box pairs for nodes); the run is then reported
    /// incomplete. Default: the command's (solve, distances, serve 1,000,000; ik 200,000;
    /// collisions 5,000,000; singularities 5,000,000 per search).
    #[arg(long, value_name = "N")]
    max_boxes: Option<u64>,
    /// Stop after this many seconds; the run is then reported incomplete.
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<f64>,
    /// Stop before pending boxes hold more than this many MiB; the run is then reported
    /// incomplete.
    // The kernel's default; `singularities` sets its own in `parse_args`, and each --help shows it.
    #[arg(long, value_name = "MIB", default_value_t = (Limits::default().max_memory >> 20) as u64)]
    max_memory: u64,
    /// Worker threads (1: depth first on one thread; more: breadth first level by level, the
    /// same boxes).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: u16,
}

impl LimitArgs {
    /// The kernel's limits, with `default_boxes` where `--max-boxes` is not given.
    pub(crate) fn limits(&self, default_boxes: u64) -> Result<Limits> {
        let max_cells = self.max_boxes.unwrap_or(default_boxes);
        if max_cells == 0 {
            bail!("--max-boxes must be at least 1");
        }
        if self.max_memory == 0 {
            bail!("--max-memory must be at least 1 MiB");
        }
        let max_memory = usize::try_from(self.max_memory.saturating_mul(1 << 20)).unwrap_or(usize::MAX);
        Ok(Limits { max_cells, timeout: seconds_arg(self.timeout)?, max_memory })
    }

    /// Worker threads asked for (at least 1).
    pub(crate) fn threads(&self) -> usize {
        usize::from(self.threads.max(1))
    }

    /// Solver settings with these limits (and `default_boxes`) over `base`.
    pub(crate) fn solver_settings(&self, default_boxes: u64, base: SolverSettings) -> Result<SolverSettings> {
        let l = self.limits(default_boxes)?;
        Ok(SolverSettings { max_boxes: l.max_cells, timeout: l.timeout, max_memory: l.max_memory, threads: self.threads(), ..base })
    }
}

/// How a real arm's file becomes the analysed 3R chain (every 3R command takes these).
#[derive(clap::Args, Clone, Debug, Default)]
pub(crate) struct ChainArgs {
    /// Base link of the chain (KDL/MoveIt convention). Default: the root link.
    #[arg(long, value_name = "LINK")]
    base: Option<String>,
    /// Tip link of the chain. Default: the end link of the longest revolute path (side links
    /// such as tool0 or flange on fixed joints are not candidates).
    #[arg(long, value_name = "LINK")]
    tip: Option<String>,
    /// Analyse this point (coordinates in LINK's frame) instead of the tip's origin or the
    /// wrist centre; joints after the third must not move it.
    #[arg(long, value_name = "LINK@X,Y,Z", allow_hyphen_values = true)]
    tip_point: Option<String>,
    /// Hold a revolute joint at a value (radians), e.g. one joint of a 7R arm. Repeatable.
    #[arg(long, value_name = "JOINT=VALUE", allow_hyphen_values = true)]
    lock: Vec<String>,
    /// Take every angle as written: no snapping of near quarter turns (see README).
    #[arg(long, conflicts_with = "snap_tolerance")]
    exact_geometry: bool,
    /// Snap angles within this many radians of a quarter turn (axes of a coordinate axis), at
    /// most 0.01; 0 takes every value as written. Default 1e-5 (covers `1.5708`; `1.571` needs 3e-4).
    #[arg(long, value_name = "RAD")]
    snap_tolerance: Option<f64>,
    /// Analyse the full torus, ignoring the file's joint limits.
    #[arg(long)]
    ignore_limits: bool,
}

impl ChainArgs {
    /// The options, with every flag parsed (one clear line on bad input).
    pub(crate) fn options(&self) -> Result<arm3r::LoadOptions> {
        let tip_point = match &self.tip_point {
            None => None,
            Some(text) => {
                let (link, xyz) = text.split_once('@').with_context(|| format!("--tip-point '{text}': expected LINK@X,Y,Z"))?;
                let v: Vec<f64> = xyz.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| anyhow::anyhow!("--tip-point '{text}': X,Y,Z must be three numbers"))?;
                let [x, y, z] = v.as_slice() else { bail!("--tip-point '{text}': X,Y,Z must be three numbers") };
                Some((link.to_string(), [*x, *y, *z]))
            }
        };
        let locks = self
            .lock
            .iter()
            .map(|text| {
                let (j, v) = text.split_once('=').with_context(|| format!("--lock '{text}': expected JOINT=VALUE"))?;
                let v: f64 = v.trim().parse().map_err(|_| anyhow::anyhow!("--lock '{text}': '{v}' is not a number"))?;
                Ok((j.to_string(), v))
            })
            .collect::<Result<Vec<_>>>()?;
        let spec = arm3r::ChainSpec { base: self.base.clone(), tip: self.tip.clone(), tip_point, locks, length_tolerance: 0.0 };
        let snap_tolerance = self.snap_tolerance.unwrap_or(linkspace::model::rounding::ANGLE_TOLERANCE);
        Ok(arm3r::LoadOptions { spec, exact_geometry: self.exact_geometry, snap_tolerance, ignore_limits: self.ignore_limits })
    }
}

#[derive(Subcommand)]
enum Command {
    /// Enclose every configuration of a closed-loop linkage described in URDF (planar or spatial).
    Solve(SolveArgs),
    /// Certified cusps, nodes and internal motions of a 3R chain described in URDF.
    Singularities(SingularitiesArgs),
    /// Every joint solution of an arm's 3R positioning structure for a point (X,Y,Z or R,Z).
    Ik(IkArgs),
    /// Every joint solution of a six-revolute arm for a pose of its tip frame, each certified.
    Ik6(Ik6Args),
    /// Where an arm's joint path (straight segments between waypoints) meets a singularity of
    /// the six-revolute arm (det J = 0) or of its 3R positioning structure (det Df = 0): each
    /// segment clear, crossing, or touching/undecided, with proofs.
    PathCheck(PathCheckArgs),
    /// Solve a distance problem by Cayley–Menger determinants: a platform in URDF or a JSON file.
    Distances(distances::DistancesArgs),
    /// Run the ROS 2 node: analyse each URDF, publish the results, serve queries (launch_notes.md).
    #[cfg(feature = "ros")]
    Serve(serve::ServeArgs),
    /// Joint configurations (joint 2, joint 3) of a 3R chain where its collision capsules meet.
    Collisions(CollisionsArgs),
    /// Certified singular sets (C-space, input/type II, output/type I) of a planar closed-loop linkage.
    LoopSingularities(loop_singularities::LoopSingularitiesArgs),
    /// Run one analysis over a grid (or a list) of design parameters of a URDF (a JSON spec).
    Sweep(sweep::SweepArgs),
}

#[derive(clap::Args)]
struct CollisionsArgs {
    /// URDF file of a 3R chain with <collision> cylinders, capsules or spheres.
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// Largest width (radians) of undecided boxes, in (0, 1).
    #[arg(long, default_value_t = 1e-2, allow_hyphen_values = true)]
    precision: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum SingularitiesKind {
    /// Cusps and internal-motion lines, the cuspidality verdict (aspects, IK solutions; the
    /// whole arm's for a six-joint arm), and nodes with --nodes.
    All,
    /// The cusps and internal-motion lines alone (no verdict, no nodes).
    Cusps,
    /// The cusps, internal-motion lines and nodes (no verdict): the node search needs the
    /// cusps.
    Nodes,
}

#[derive(clap::Args)]
struct SingularitiesArgs {
    /// URDF file of an arm: its 3R positioning structure is analysed (see --base, --tip, --tip-point, --lock).
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// Largest width (radians) of reported and undecided boxes, in (0, 1).
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    precision: f64,
    /// What to answer.
    #[arg(long, value_enum, default_value_t = SingularitiesKind::All)]
    kind: SingularitiesKind,
    /// Also search nodes (pairs of singular points with one image).
    #[arg(long)]
    nodes: bool,
    /// Turn every length of the URDF into an interval of this half-width (metres).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    uncertainty: f64,
    /// Run the interval searches even when the verdict is structural (parallel axes 2 and 3),
    /// where they cannot complete (crossing branches, curves of nodes); bounded by the limits.
    #[arg(long)]
    search_anyway: bool,
    #[command(flatten)]
    limits: LimitArgs,
    /// Seconds for the whole-arm cuspidality search of a six-joint arm without a spherical
    /// wrist (0: not searched).
    #[arg(long, default_value_t = 2.0, value_name = "SECONDS")]
    arm_budget: f64,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(clap::Args)]
struct IkArgs {
    /// URDF file of an arm (its 3R positioning structure, as for singularities).
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// The point to reach: X,Y,Z in the frame of the root link (every joint is solved for), or
    /// R,Z: distance from the first axis and height along it, in the first joint's frame (the
    /// first joint is then free; joints 2 and 3 are solved for).
    #[arg(long, value_name = "X,Y,Z|R,Z", allow_hyphen_values = true)]
    point: String,
    /// Largest width (radians) of reported boxes, in (0, 1).
    #[arg(long, default_value_t = 1e-6, allow_hyphen_values = true)]
    precision: f64,
    /// Turn every length of the URDF into an interval of this half-width (metres).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    uncertainty: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(clap::Args)]
struct Ik6Args {
    /// URDF file of an arm with six revolute joints from base to tip (fixed joints merged).
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// The tip frame's pose in the base frame (metres, radians), comma-separated; the count of
    /// numbers names the form: 6 = X,Y,Z,ROLL,PITCH,YAW (URDF convention, Rz·Ry·Rx); 7 =
    /// X,Y,Z,QX,QY,QZ,QW (a quaternion, normalised; zero refused); 16 = a 4x4 homogeneous
    /// transform, row-major (rotation block orthonormal and last row 0,0,0,1 to within 1e-6).
    #[arg(long, value_name = "6|7|16 NUMBERS", allow_hyphen_values = true)]
    pose: String,
    /// Largest width (radians) of reported boxes, in (0, 1).
    #[arg(long, default_value_t = 1e-9, allow_hyphen_values = true)]
    precision: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(clap::Args)]
struct PathCheckArgs {
    /// URDF file of an arm: six revolute joints from base to tip (fixed joints merged) for the
    /// 6R set; any serial arm with at least three for the 3R set.
    urdf: PathBuf,
    #[command(flatten)]
    chain: ChainArgs,
    /// The waypoints: "q1;q2;...", each the joint values (radians) comma-separated: for the 6R
    /// set the six in the order ik6 prints them; for the 3R set the sub-chain's three, then
    /// the joints after them on the chain (locked joints left out).
    #[arg(long, value_name = "Q1;Q2;...", allow_hyphen_values = true, conflicts_with = "waypoints_file", required_unless_present = "waypoints_file")]
    waypoints: Option<String>,
    /// The waypoints as a JSON list of lists of numbers (radians, joints as for --waypoints).
    #[arg(long, value_name = "FILE")]
    waypoints_file: Option<PathBuf>,
    /// The singular set to check against: 6r, the six-revolute arm's (det J = 0); 3r, its 3R
    /// positioning structure's (det Df = 0 of the sub-chain and point `singularities` analyses).
    /// Default: 6r when a chain of six revolute joints is found from base to tip (as ik6 reads
    /// it) and no --lock or --tip-point is given, else 3r.
    #[arg(long, value_enum)]
    singular_set: Option<SingularSetArg>,
    /// Radians: crossings are narrowed until the joints' enclosure is this wide.
    #[arg(long, default_value_t = 1e-9, allow_hyphen_values = true)]
    tolerance: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Write the report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// `path-check --singular-set`.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
enum SingularSetArg {
    #[value(name = "6r")]
    SixR,
    #[value(name = "3r")]
    ThreeR,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Backend {
    Simplex,
    Clarabel,
}

impl From<Backend> for LpBackend {
    fn from(b: Backend) -> Self {
        match b {
            Backend::Simplex => LpBackend::Simplex,
            Backend::Clarabel => LpBackend::Clarabel,
        }
    }
}

/// `solve --model`.
#[derive(Clone, Copy, Debug, PartialEq, clap::ValueEnum)]
enum ModelArg {
    Auto,
    Planar,
    Spatial,
    Pose,
    Distances,
}

impl From<ModelArg> for ModelChoice {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Auto => ModelChoice::Auto,
            ModelArg::Planar => ModelChoice::Planar,
            ModelArg::Spatial => ModelChoice::Spatial,
            ModelArg::Pose => ModelChoice::Pose,
            ModelArg::Distances => ModelChoice::Distances,
        }
    }
}

#[derive(clap::Args)]
struct SolveArgs {
    /// URDF file (loops closed with the <loop> extension, see README).
    urdf: PathBuf,
    /// Fix a joint (or loop) value: radians for revolute, metres for prismatic. Repeatable.
    #[arg(long = "fix", value_name = "JOINT=VALUE")]
    fix: Vec<String>,
    /// Solution boxes are at most this wide in every primary variable.
    #[arg(long, default_value_t = 1e-3)]
    sigma: f64,
    /// Keep shrinking a box while a round leaves less than this share of its volume.
    #[arg(long, default_value_t = 0.95)]
    rho: f64,
    #[command(flatten)]
    limits: LimitArgs,
    /// Trace a point given in a link's frame: LINK@X,Y (planar) or LINK@X,Y,Z. Repeatable.
    #[arg(long = "trace", value_name = "LINK@X,Y[,Z]")]
    trace: Vec<String>,
    /// Which builder: planar (one angle per rigid group), spatial (any loop of revolute,
    /// prismatic, spherical, universal, cylindrical and fixed joints), pose (a platform on six
    /// legs, every leg fixed: its position and rotation), distances (the same platforms: squared
    /// base-to-platform distances and heights, seed 004's style), or auto: planar when the
    /// mechanism is planar, else pose for a platform with every leg fixed and no traced point,
    /// else spatial.
    #[arg(long, value_enum, default_value_t = ModelArg::Auto)]
    model: ModelArg,
    /// Shrink by interval propagation only (no LP): for comparisons.
    #[arg(long)]
    no_lp: bool,
    /// Interval Newton (square systems) once every primary is at most this wide; 0 disables it.
    #[arg(long, default_value_t = 0.25)]
    newton_width: f64,
    /// LP solver proposing the multipliers that the safe bound verifies.
    #[arg(long, value_enum, default_value_t = Backend::Simplex)]
    lp: Backend,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Parses arguments and runs; errors come back as one chain of context.
pub fn run() -> Result<()> {
    let cli = parse_args(std::env::args_os());
    // Held to the end: dropping it finalises MPI.
    #[cfg(feature = "mpi")]
    let ranks = ranks::join()?;
    #[cfg(feature = "mpi")]
    if ranks.is_some() && linkspace::kernel::search::rank_and_size().1 > 1 && matches!(cli.command, Command::Serve(_)) {
        bail!("serve runs in one process: start it without mpirun");
    }
    match cli.command {
        Command::Solve(args) => solve(args),
        Command::Singularities(args) => singularities(args),
        Command::Ik(args) => ik(args),
        Command::Ik6(args) => ik6(args),
        Command::PathCheck(args) => path_check(args),
        Command::Distances(args) => distances::run(args),
        #[cfg(feature = "ros")]
        Command::Serve(args) => serve::serve(args),
        Command::Collisions(args) => collisions(args),
        Command::LoopSingularities(args) => loop_singularities::run(args),
        Command::Sweep(args) => sweep::run(args),
    }
}

/// Parses the command line; on bad input prints one line and exits with clap's usage code (2).
///
/// Values may be negative everywhere (`--sigma -1` means the same as `--sigma=-1`, and
/// gets the same one-line complaint from the settings' own check). Every other error of clap's
/// (unknown flag, missing value, unparsable number) is flattened to one line: its multi-line
/// usage text would bury the message. `--help` and `--version` print as usual.
fn parse_args<I, T>(args: I) -> Cli
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    use clap::{CommandFactory, FromArgMatches};
    // An option's value may start with a hyphen (`--sigma -1e-3`: clap's own test for a
    // negative number misses exponents); positionals keep clap's rule, so a flag is never
    // taken for a file name. An option whose value is optional (`--robot-description-topic
    // [TOPIC]`) keeps clap's rule too, or it would swallow the next flag as its value.
    // `singularities` bounds the pending cells of a flooding search (near-degenerate geometry)
    // well below the kernel's general default; its --help shows its own.
    let command = Cli::command().mut_subcommand("singularities", |s| s.mut_arg("max_memory", |a| a.default_value(SINGULARITIES_MAX_MEMORY_MIB)));
    let command = command.mut_subcommands(|s| {
        s.mut_args(|a| match (a.get_action().takes_values(), a.is_positional()) {
            (true, false) if a.get_num_args().is_some_and(|r| r.min_values() == 0) => a,
            (true, false) => a.allow_hyphen_values(true),
            (true, true) => a.allow_negative_numbers(true),
            _ => a,
        })
    });
    let parsed = command.try_get_matches_from(args).and_then(|m| Cli::from_arg_matches(&m));
    match parsed {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand) {
                e.exit();
            }
            eprintln!("error: {}", one_line(&e.to_string()));
            std::process::exit(e.exit_code());
        }
    }
}

/// clap's error text as one line: the message and its tips, without the usage block.
fn one_line(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        if line.is_empty() {
            continue;
        }
        let line = line.strip_prefix("error: ").unwrap_or(line);
        if !out.is_empty() {
            out.push_str(if out.ends_with(':') { " " } else { "; " });
        }
        out.push_str(line);
    }
    out
}

fn parse_fix(s: &str) -> Result<(String, f64)> {
    let (name, value) = s.split_once('=').with_context(|| format!("--fix '{s}': expected JOINT=VALUE"))?;
    let v: f64 = value.trim().parse().with_context(|| format!("--fix '{s}': '{value}' is not a number"))?;
    Ok((name.trim().to_string(), v))
}

#[cfg(feature = "ros")]
fn parse_trace(s: &str) -> Result<(String, f64, f64)> {
    let (link, xy) = s.split_once('@').with_context(|| format!("--trace '{s}': expected LINK@X,Y"))?;
    let (x, y) = xy.split_once(',').with_context(|| format!("--trace '{s}': expected LINK@X,Y"))?;
    let x: f64 = x.trim().parse().with_context(|| format!("--trace '{s}': '{x}' is not a number"))?;
    let y: f64 = y.trim().parse().with_context(|| format!("--trace '{s}': '{y}' is not a number"))?;
    if !(x.is_finite() && y.is_finite()) {
        bail!("--trace '{s}': coordinates must be finite");
    }
    Ok((link.to_string(), x, y))
}

/// `LINK@X,Y` or `LINK@X,Y,Z`: the link, the point (z = 0 when two numbers are given), and the
/// name as written.
fn parse_trace3(s: &str) -> Result<(String, [f64; 3])> {
    let (link, xy) = s.split_once('@').with_context(|| format!("--trace '{s}': expected LINK@X,Y or LINK@X,Y,Z"))?;
    let parts: Vec<&str> = xy.split(',').collect();
    if !(parts.len() == 2 || parts.len() == 3) {
        bail!("--trace '{s}': expected LINK@X,Y or LINK@X,Y,Z");
    }
    let mut p = [0.0; 3];
    for (k, t) in parts.iter().enumerate() {
        p[k] = t.trim().parse().with_context(|| format!("--trace '{s}': '{t}' is not a number"))?;
    }
    if !p.iter().all(|v: &f64| v.is_finite()) {
        bail!("--trace '{s}': coordinates must be finite");
    }
    Ok((link.to_string(), p))
}

fn solve(args: SolveArgs) -> Result<()> {
    let base = SolverSettings { sigma: args.sigma, rho: args.rho, use_lp: !args.no_lp, newton_width: args.newton_width, lp_backend: args.lp.into(), ..SolverSettings::default() };
    let settings = args.limits.solver_settings(SolverSettings::default().max_boxes, base)?;
    settings.validate()?;
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let traces = args.trace.iter().map(|s| parse_trace3(s)).collect::<Result<Vec<_>>>()?;
    let xml = std::fs::read_to_string(&args.urdf).with_context(|| format!("reading {}", args.urdf.display()))?;
    let mechanism = urdf::parse(&xml).with_context(|| format!("loading {}", args.urdf.display()))?;
    let named: Vec<TracedPoint> = traces.iter().zip(&args.trace).map(|((l, p), r)| (l.clone(), *p, r.clone())).collect();
    let job = app::SolveRun::build(&mechanism, args.model.into(), &fixed, &named, settings).with_context(|| format!("building {}", args.urdf.display()))?;
    let (freedom, freedom_line) = job.freedom();
    if freedom.at_point.is_some_and(|l| l.dof >= 2) {
        // Said before the run: covering a continuum of two or more dimensions takes long.
        eprintln!("linkspace: {}: {freedom_line}", mechanism.name);
    }
    let show = std::io::stderr().is_terminal();
    let mut progress = |p: &Progress| {
        if show {
            eprint!("\r{:5.1}% decided, {} boxes processed, {} pending   ", 100.0 * p.decided, p.processed, p.pending);
            let _ = std::io::stderr().flush();
        }
    };
    let result = job.run(&AtomicBool::new(false), &mut progress);
    if show {
        eprintln!();
    }
    let solutions: Vec<&app::ResultBox> = result.boxes.iter().filter(|b| b.status.is_solution()).collect();
    let proven = result.boxes.iter().filter(|b| b.status == BoxStatus::Unique).count();
    let undecided = result.boxes.len() - solutions.len();
    let stats = &result.stats;
    // Write through a handle: `println!` panics when the reader of a pipe has gone.
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} proven, {} undecided ({} solution boxes in {} clusters), status {}, {} boxes processed ({} empty, {} bisected), {} LPs, {:.3} s",
        result.mechanism,
        proven,
        undecided,
        solutions.len(),
        result.clusters,
        match result.status {
            linkspace::Status::Finished => "complete".to_string(),
            linkspace::Status::Stopped(l) => format!("incomplete ({l:?} limit, {undecided} boxes undecided)"),
        },
        stats.processed,
        stats.empty,
        stats.bisected,
        stats.lp.solved,
        stats.seconds
    )
    .ok();
    // "Proven": a box certified (Krawczyk) to hold exactly one configuration; the other solution
    // boxes are not refuted at sigma (points of a curve, or roots not yet proven).
    let problem = job.problem();
    writeln!(out, "  model: {} ({})", problem.model().name(), problem.model_reason()).ok();
    writeln!(out, "  freedom: {freedom_line}").ok();
    for r in problem.reductions() {
        writeln!(out, "  reduced: {r}").ok();
    }
    if result.status == linkspace::Status::Finished && solutions.is_empty() {
        // A complete run with no box is a proof, and says something about the input.
        let why = if fixed.is_empty() { "the loops cannot close as written, within the joint limits" } else { "no assembly has the fixed values given" };
        writeln!(out, "  no configuration: every box was proven empty, so {why}").ok();
    }
    if stats.post_processing_cut_short {
        // Honest about what the limit cost: these boxes were reported without the deeper
        // search that drops near misses, so the count may include a few spurious ones.
        writeln!(out, "  the time limit cut the spurious-box check short: some lone boxes were kept unexamined").ok();
    }
    if solutions.len() <= 20 {
        for (k, s) in solutions.iter().enumerate() {
            // By joint name, as the JSON lists them.
            let mut joints: Vec<(&String, &Bounds)> = result.joint_names.iter().zip(&s.joints).collect();
            joints.sort_by(|a, b| a.0.cmp(b.0));
            let joints: Vec<String> = joints.iter().map(|(n, [lo, hi])| format!("{n}={:.6}", 0.5 * (lo + hi))).collect();
            writeln!(out, "  #{k}: {}", joints.join(" ")).ok();
        }
    }
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&report::SolveReport::new(problem, &result, mechanism.rigid_links()))?;
        write_file(&path, text)?;
    }
    Ok(())
}

/// Writes a report; under `mpirun`, only rank 0 writes (every rank holds the same result).
pub(crate) fn write_file(path: &std::path::Path, contents: impl AsRef<[u8]>) -> Result<()> {
    #[cfg(feature = "mpi")]
    if !ranks::writes() {
        return Ok(());
    }
    std::fs::write(path, contents).with_context(|| format!("writing {}", path.display()))
}

/// Reads a file's robot description.
fn load_mechanism(path: &std::path::Path) -> Result<linkspace::Mechanism> {
    let xml = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    urdf::parse(&xml).with_context(|| format!("loading {}", path.display()))
}

/// Reads a file as every 3R command does: rounding policy, chain choice, limits.
fn load_arm(path: &std::path::Path, uncertainty: f64, args: &ChainArgs) -> Result<Arm> {
    let options = args.options()?;
    let mechanism = load_mechanism(path)?;
    Arm::load(&mechanism, &options, uncertainty).with_context(|| format!("loading {}", path.display()))
}

/// Default `--max-boxes` of `singularities`, per search. `--max-memory` bounds the pending
/// cells and, separately, the node search's box tree (kept whole until the run ends).
pub(crate) const SINGULARITIES_MAX_BOXES: u64 = 5_000_000;

/// Default `--max-memory` of `singularities` (MiB of pending cells).
const SINGULARITIES_MAX_MEMORY_MIB: &str = "256";

/// `--timeout` as a duration: positive and finite, or absent.
pub(crate) fn seconds_arg(t: Option<f64>) -> Result<Option<Duration>> {
    match t {
        Some(t) if t.is_finite() && t > 0.0 => Ok(Some(Duration::from_secs_f64(t.min(1e9)))),
        Some(t) => bail!("--timeout must be a positive number of seconds, got {t}"),
        None => Ok(None),
    }
}

fn singularities(args: SingularitiesArgs) -> Result<()> {
    arm3r::check_precision(args.precision)?;
    let limits = args.limits.limits(SINGULARITIES_MAX_BOXES)?;
    if args.kind == SingularitiesKind::Cusps && args.nodes {
        bail!("--kind cusps searches no nodes: drop --nodes, or give --kind nodes");
    }
    // Read once: the whole-arm section reads the same mechanism.
    let options = args.chain.options()?;
    let mechanism = load_mechanism(&args.urdf)?;
    let arm = Arm::load(&mechanism, &options, args.uncertainty).with_context(|| format!("loading {}", args.urdf.display()))?;
    let cancel = AtomicBool::new(false);
    let control = Control { limits, threads: args.limits.threads(), cancel: &cancel };
    let verdict = args.kind == SingularitiesKind::All;
    let nodes = args.nodes || args.kind == SingularitiesKind::Nodes;
    let request = app::SingularitiesRequest { precision: args.precision, nodes, search_anyway: args.search_anyway, verdict };
    let found = app::singularities(&arm, &request, &control, &mut |_| {})?;
    let report = report::manip3r::SingularityReport::of(&arm, &found);
    let (prepared, effect) = (&arm.prepared, &found.limit_effect);
    let mut out = std::io::stdout().lock();
    let scope = &prepared.choice.scope;
    // Searched before printing, so that the sub-chain's verdict can point to the arm's.
    let arm_section = if verdict { whole_arm(&args, &mechanism, &options, &arm, &control)? } else { None };
    if let Some(v) = &found.verdict {
        writeln!(out, "{}", v.headline(scope)).ok();
    }
    if let Some(open) = scope.not_answered.as_ref().filter(|_| verdict && !scope.stands_for_arm) {
        match &arm_section {
            Some(a) => writeln!(out, "  not the arm's verdict: the whole arm's is the line `arm {}` below", a.arm).ok(),
            None => writeln!(out, "  {open}").ok(),
        };
    }
    let node_text = report.nodes.as_ref().map_or("nodes not searched".to_string(), |n| format!("{} nodes", n.len()));
    let undecided = report.undecided_total[0] + report.undecided_total[1];
    writeln!(
        out,
        "{}: {} cusps, {node_text}, {} internal-motion lines, {}{undecided} undecided, status {}{}, {:.3} s",
        report.robot,
        report.cusps.len(),
        linkspace::analyses::arm3r::line_count(&found.run.cusps.bands),
        match report.internal_motions.iter().filter(|m| m.near_degenerate.is_some()).count() {
            0 => String::new(),
            n => format!("{n} near-degenerate strips (undecided), "),
        },
        report.completeness.word(),
        report.completeness.reason().map_or(String::new(), |l| format!(" ({})", l.name())),
        report.stats.seconds
    )
    .ok();
    let mid = |b: &[f64; 2]| 0.5 * (b[0] + b[1]);
    let fmt = |j: &arm3r::Joints| j.iter().map(|(n, b)| format!("{n}={:.6}", mid(b))).collect::<Vec<_>>().join(" ");
    if let Some(why) = &report.not_searched {
        writeln!(out, "  not searched: {why}").ok();
    }
    writeln!(out, "  chain: {}", prepared.choice.reason).ok();
    for line in report.singular_branches.iter().flat_map(|b| b.lines()) {
        writeln!(out, "  {line}").ok();
    }
    if let Some(a) = &report.explained_undecided {
        writeln!(out, "  undecided cusp boxes: {}", a.text).ok();
    }
    let snaps = &prepared.snaps;
    if prepared.exact_geometry {
        let why = if prepared.snap_tolerance == 0.0 { "--snap-tolerance 0" } else { "--exact-geometry" };
        writeln!(out, "  rounding: off ({why}): angles taken as written").ok();
    } else {
        writeln!(out, "  rounding: {} values snapped to quarter turns / coordinate axes (tolerance {:e} rad)", snaps.len(), prepared.snap_tolerance).ok();
        for sn in snaps {
            if sn.what == "lock" {
                writeln!(out, "    {} lock: {} -> {}", sn.joint, sn.original[0], sn.snapped[0]).ok();
            } else {
                writeln!(out, "    {} {}: {:?} -> {:?}", sn.joint, sn.what, sn.original, sn.snapped).ok();
            }
        }
    }
    writeln!(out, "  {}", effect.text).ok();
    for c in &report.cusps {
        writeln!(out, "  cusp {} -> radius {:.6} z {:.6}", fmt(&c.joints), mid(&c.workspace.radius), mid(&c.workspace.z)).ok();
    }
    for n in report.nodes.iter().flatten() {
        writeln!(out, "  node {} & {} -> radius {:.6} z {:.6}", fmt(&n.points[0]), fmt(&n.points[1]), mid(&n.workspace.radius), mid(&n.workspace.z)).ok();
    }
    for m in &report.internal_motions {
        let kind = if m.near_degenerate.is_some() { "near-degenerate strip (undecided)" } else { "internal motion" };
        writeln!(out, "  {kind} {}", m.joints.iter().map(|(n, b)| format!("{n} in [{:.6}, {:.6}]", b[0], b[1])).collect::<Vec<_>>().join(", ")).ok();
    }
    if let Some(a) = &arm_section {
        writeln!(out, "arm {}: {} ({})", a.arm, a.verdict, a.reason).ok();
        if let Some(proof) = &a.proof {
            writeln!(out, "  proof: {proof}").ok();
        }
        if let Some(w) = &a.witness {
            let fmt = |b: &std::collections::BTreeMap<String, [f64; 2]>| b.iter().map(|(n, x)| format!("{n}={:.6}", 0.5 * (x[0] + x[1]))).collect::<Vec<_>>().join(" ");
            writeln!(out, "  witness pose translation {:?}; solutions {} and {}; min |det J| on the path {:.3e}", w.pose_translation, fmt(&w.from), fmt(&w.to), w.min_abs_det).ok();
        }
        if let Some(m) = &a.most_solutions {
            writeln!(out, "  at least {} inverse-kinematics solutions at one pose (each certified in its own box; pose translation {:?}, the most the search solved)", m.count, m.pose_translation).ok();
        }
    }
    if let Some(path) = args.json {
        let mut value = serde_json::to_value(&report)?;
        if let (Some(a), Some(map)) = (&arm_section, value.as_object_mut()) {
            map.insert("arm_cuspidality".into(), serde_json::to_value(a)?);
            // The sub-chain's verdict now points to the arm's, as the text does.
            if let Some(open) = map.get_mut("chain").and_then(|c| c.get_mut("scope")).and_then(|s| s.get_mut("not_answered")).filter(|o| o.is_string()) {
                *open = serde_json::Value::String("not the arm's verdict: the whole arm's is arm_cuspidality".into());
            }
        }
        write_file(&path, serde_json::to_string_pretty(&value)?)?;
    }
    Ok(())
}

/// The whole-arm verdict of a six-joint arm whose 3R verdict is a sub-chain's (or whose wrist
/// is spherical), as its report section; `None` for other arms or `--arm-budget 0`.
fn whole_arm(args: &SingularitiesArgs, mechanism: &linkspace::Mechanism, options: &arm3r::LoadOptions, arm: &Arm, control: &Control) -> Result<Option<report::six::ArmCuspidalityReport>> {
    if !(args.arm_budget.is_finite() && args.arm_budget >= 0.0) {
        bail!("--arm-budget must be a number of seconds >= 0, got {}", args.arm_budget);
    }
    if args.arm_budget == 0.0 {
        return Ok(None);
    }
    // Within the run's --timeout too.
    let budget = control.limits.timeout.map_or(Duration::from_secs_f64(args.arm_budget), |t| t.min(Duration::from_secs_f64(args.arm_budget)));
    let found = app::arm_cuspidality(mechanism, arm, options, budget, control);
    Ok(found.map(|(chain, c)| report::six::ArmCuspidalityReport::of(&chain, &c)))
}

fn ik6(args: Ik6Args) -> Result<()> {
    let values: Vec<f64> = args
        .pose
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|_| anyhow::anyhow!("--pose '{}': '{}' is not a number", args.pose, t.trim())))
        .collect::<Result<_>>()?;
    let pose = PoseInput::from_numbers(&values).map_err(|e| anyhow::anyhow!("--pose '{}': {e}", args.pose))?;
    let options = args.chain.options()?;
    let mechanism = load_mechanism(&args.urdf)?;
    let chain = app::chain6(&mechanism, &options).with_context(|| format!("loading {}", args.urdf.display()))?;
    let cancel = AtomicBool::new(false);
    let control = Control { limits: args.limits.limits(20_000_000)?, threads: args.limits.threads(), cancel: &cancel };
    let found = app::inverse_kinematics6(&chain, pose, args.precision, &control)?;
    let report = report::six::Ik6Report::of(&chain, &found);
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{} -> {}: {} solutions proven unique, {} clusters undecided, status {}, {} boxes, {:.3} s",
        report.base,
        report.tip,
        report.unique.len(),
        report.clusters.len(),
        report.completeness.word(),
        report.processed,
        report.seconds
    )
    .ok();
    writeln!(out, "  joint ranges: {}", chain.joints.iter().zip(&chain.ranges).map(|(n, r)| format!("{n} [{:.6}, {:.6}]", r.0, r.1)).collect::<Vec<_>>().join(", ")).ok();
    for (tag, boxes) in [("unique", &report.unique), ("cluster (may hold solutions)", &report.clusters)] {
        for b in boxes {
            // In the file's joint order, each in its own range.
            let text: Vec<String> = chain.joints.iter().map(|n| (n, b[n])).map(|(n, x)| format!("{n} in [{:.9}, {:.9}]", x[0], x[1])).collect();
            writeln!(out, "  {} ({tag})", text.join(", ")).ok();
        }
    }
    if let Some(path) = args.json {
        write_file(&path, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}

/// The waypoints of `--waypoints` ("q1;q2;...") or `--waypoints-file` (JSON), `n` values each.
fn waypoints(args: &PathCheckArgs, n: usize) -> Result<Vec<Vec<f64>>> {
    let rows: Vec<Vec<f64>> = match (&args.waypoints, &args.waypoints_file) {
        (Some(text), _) => text
            .split(';')
            .filter(|w| !w.trim().is_empty())
            .map(|w| w.split(',').map(|t| t.trim().parse::<f64>().map_err(|_| anyhow::anyhow!("--waypoints: '{}' is not a number", t.trim()))).collect::<Result<Vec<f64>>>())
            .collect::<Result<_>>()?,
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            serde_json::from_str(&text).with_context(|| format!("{}: expected a JSON list of lists of numbers", path.display()))?
        }
        (None, None) => bail!("give --waypoints or --waypoints-file"),
    };
    if let Some((k, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != n) {
        bail!("waypoint {} has {} joint values: expected {n}", k + 1, r.len());
    }
    Ok(rows)
}

fn path_check(args: PathCheckArgs) -> Result<()> {
    let options = args.chain.options()?;
    let mechanism = load_mechanism(&args.urdf)?;
    let sub_chain_chosen = args.chain.tip_point.is_some() || !args.chain.lock.is_empty();
    let set = match args.singular_set {
        Some(set) => set,
        None if !sub_chain_chosen && app::chain6(&mechanism, &options).is_ok() => SingularSetArg::SixR,
        None => SingularSetArg::ThreeR,
    };
    let cancel = AtomicBool::new(false);
    let control = Control { limits: args.limits.limits(1)?, threads: 1, cancel: &cancel };
    let found = match set {
        SingularSetArg::SixR => {
            if sub_chain_chosen {
                bail!("--lock and --tip-point choose a 3R sub-chain and its point: they apply with --singular-set 3r");
            }
            let points = waypoints(&args, 6)?;
            let chain = app::chain6(&mechanism, &options).with_context(|| format!("loading {}", args.urdf.display()))?;
            let points: Vec<[f64; 6]> = points.into_iter().map(|w| <[f64; 6]>::try_from(w).expect("invariant: six values checked")).collect();
            app::check_path(&chain, &points, args.tolerance, &control)?
        }
        SingularSetArg::ThreeR => {
            let arm = Arm::load(&mechanism, &options, 0.0).with_context(|| format!("loading {}", args.urdf.display()))?;
            let points = waypoints(&args, app::positioning_joints(&arm).len())?;
            let found = app::check_path3(&arm, &points, args.tolerance, &control)?;
            eprintln!("chain: {}", arm.prepared.choice.reason);
            found
        }
    };
    let report = report::six::PathCheckReport::of(&found);
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", report.headline()).ok();
    for (k, s) in report.segments.iter().enumerate() {
        writeln!(out, "  segment {} ({} -> {}): {}: {}", k + 1, k + 1, k + 2, s.verdict, s.reason).ok();
        for c in &s.crossings {
            let text: Vec<String> = report.joints.iter().map(|n| format!("{n} in [{:.9}, {:.9}]", c.joints[n][0], c.joints[n][1])).collect();
            writeln!(out, "    crossing at t in [{:.12}, {:.12}]: {}", c.t[0], c.t[1], text.join(", ")).ok();
        }
    }
    if let Some(path) = args.json {
        write_file(&path, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}

fn collisions(args: CollisionsArgs) -> Result<()> {
    arm3r::check_precision(args.precision)?;
    let limits = args.limits.limits(collision::DEFAULT_MAX_BOXES)?;
    let options = args.chain.options()?;
    let mechanism = load_mechanism(&args.urdf)?;
    let cancel = AtomicBool::new(false);
    let control = Control { limits, threads: args.limits.threads(), cancel: &cancel };
    let found = app::collisions(&mechanism, &options, args.precision, &control, &mut |_| {}).with_context(|| format!("loading {}", args.urdf.display()))?;
    eprintln!("chain: {}", found.prepared.choice.reason);
    let set = &found.set;
    let report = report::manip3r::CollisionReport::of(&found, args.precision);
    let s = &report.stats;
    let total = s.colliding_area + s.free_area + s.undecided_area;
    let pct = |a: f64| 100.0 * a / total;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} pairs; colliding {} boxes ({:.2} % of joint space), free {} ({:.2} %), undecided {} ({:.2} %), status {}, {:.3} s",
        report.robot,
        report.pairs.len(),
        report.colliding.len(),
        pct(s.colliding_area),
        report.free.len(),
        pct(s.free_area),
        report.undecided.len(),
        pct(s.undecided_area),
        report.completeness.word(),
        s.seconds
    )
    .ok();
    for (k, p) in report.pairs.iter().enumerate() {
        let boxes = set.colliding.iter().filter(|c| c.pair == k).count();
        writeln!(out, "  {} x {}: proven colliding on {boxes} boxes", p[0], p[1]).ok();
    }
    if let Some(path) = args.json {
        write_file(&path, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}

fn ik(args: IkArgs) -> Result<()> {
    let point = parse_ik_point(&args.point)?;
    arm3r::check_precision(args.precision)?;
    let arm = load_arm(&args.urdf, args.uncertainty, &args.chain)?;
    let cancel = AtomicBool::new(false);
    let control = Control { limits: args.limits.limits(200_000)?, threads: args.limits.threads(), cancel: &cancel };
    let found = app::inverse_kinematics(&arm, point, args.precision, &control, &mut |_| {})?;
    let report = report::manip3r::IkReport::of(&arm, &found);
    let s = &found.solutions;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}: {} solutions proven unique, {} clusters undecided, status {}", report.robot, s.unique.len(), s.clusters.len(), report.completeness.word()).ok();
    writeln!(out, "  chain: {}", arm.prepared.choice.reason).ok();
    writeln!(out, "  {}", found.limit_effect.text).ok();
    for sol in &report.solutions {
        let text: Vec<String> = sol.joints.iter().map(|(n, b)| format!("{n} in [{:.9}, {:.9}]", b[0], b[1])).collect();
        let tag = match (sol.unique, sol.boxes) {
            (true, _) => "unique".to_string(),
            (false, 0) => format!("internal-motion line: every {} solves the point; the strip about it is not searched", arm.chain.joints[1]),
            (false, n) => format!("cluster of {n} boxes (one or more solutions)"),
        };
        writeln!(out, "  {} ({tag})", text.join(", ")).ok();
    }
    if let Some(path) = args.json {
        write_file(&path, serde_json::to_string_pretty(&report)?)?;
    }
    Ok(())
}

/// `--point`: `X,Y,Z` in the root frame, or `R,Z` in the first joint's frame.
fn parse_ik_point(text: &str) -> Result<IkPoint> {
    let values: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|_| anyhow::anyhow!("--point '{text}': '{}' is not a number", t.trim())))
        .collect::<Result<_>>()?;
    match values.as_slice() {
        [x, y, z] => Ok(IkPoint::Root([*x, *y, *z])),
        [radius, z] => Ok(IkPoint::HalfSection { radius: *radius, z: *z }),
        _ => bail!("--point '{text}': expected X,Y,Z (root frame) or R,Z (distance from the first axis, height along it)"),
    }
}

//! The command line: argument parsing and the `solve` command. `anyhow` lives here and in main.

#[cfg(feature = "ros")]
mod ros_args;
#[cfg(feature = "ros")]
mod serve;
#[cfg(feature = "mpi")]
mod ranks;


use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use linkspace::app::{self, Answer, CollisionsJob, Control, IkJob, IkPoint, Job, Limits, LpBackend, ModelChoice, PathCheckJob, PathSet, Progress, SingularitiesJob, SolveJob, TracedPoint};
use linkspace::edges::report;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

pub(crate) mod distances;
mod ik6;
mod self_motion;
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
    /// Stop after processing this many boxes (box pairs for nodes; pieces of segments for a
    /// path check); the run is then reported incomplete. Default: the command's (solve,
    /// distances, loop-singularities, serve 1,000,000; ik 200,000; collisions 5,000,000;
    /// singularities 5,000,000 per search; ik6 20,000,000; path-check 10,000,000).
    #[arg(long, value_name = "N")]
    pub(crate) max_boxes: Option<u64>,
    /// Stop after this many seconds, counted from the start of the command (reading the file
    /// included), with every answer's post-processing and report inside them; the run is then
    /// reported incomplete. Default: none (ik6: 60).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) timeout: Option<f64>,
    /// Stop before pending boxes hold more than this many MiB; the run is then reported
    /// incomplete.
    // Each command's default (its job's) is added to the help in `parse_args`.
    #[arg(long, value_name = "MIB")]
    pub(crate) max_memory: Option<u64>,
    /// Worker threads (1: depth first on one thread; more: breadth first level by level, the
    /// same boxes).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: u16,
}

impl LimitArgs {
    /// The kernel's limits, with the job's `default` cells where `--max-boxes` is not given.
    pub(crate) fn limits(&self, default: Limits) -> Result<Limits> {
        let max_cells = self.max_boxes.unwrap_or(default.max_cells);
        if max_cells == 0 {
            bail!("--max-boxes must be at least 1");
        }
        let max_memory = match self.max_memory {
            Some(0) => bail!("--max-memory must be at least 1 MiB"),
            Some(mib) => usize::try_from(mib.saturating_mul(1 << 20)).unwrap_or(usize::MAX),
            None => default.max_memory,
        };
        Ok(Limits { max_cells, timeout: seconds_arg(self.timeout)?.or(default.timeout), max_memory })
    }

    /// Solver settings with these limits over `base` (the node's load-time runs).
    #[cfg(feature = "ros")]
    pub(crate) fn solver_settings(&self, base: app::SolverSettings) -> Result<app::SolverSettings> {
        let l = self.limits(Limits { max_cells: base.max_boxes, timeout: base.timeout, max_memory: base.max_memory })?;
        Ok(app::SolverSettings { max_boxes: l.max_cells, timeout: l.timeout, max_memory: l.max_memory, threads: self.threads(), ..base })
    }

    /// Worker threads asked for (at least 1).
    pub(crate) fn threads(&self) -> usize {
        usize::from(self.threads.max(1))
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
    #[arg(long = "fix", alias = "lock", value_name = "JOINT=VALUE", allow_hyphen_values = true)]
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
    pub(crate) fn options(&self) -> Result<app::ArmOptions> {
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
                let (j, v) = text.split_once('=').with_context(|| format!("--fix '{text}': expected JOINT=VALUE"))?;
                let v: f64 = v.trim().parse().map_err(|_| anyhow::anyhow!("--fix '{text}': '{v}' is not a number"))?;
                Ok((j.to_string(), v))
            })
            .collect::<Result<Vec<_>>>()?;
        let spec = app::ChainSpec { base: self.base.clone(), tip: self.tip.clone(), tip_point, locks, length_tolerance: 0.0 };
        let snap_tolerance = self.snap_tolerance.unwrap_or(app::SNAP_TOLERANCE);
        Ok(app::ArmOptions { spec, exact_geometry: self.exact_geometry, snap_tolerance, ignore_limits: self.ignore_limits })
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
    Ik6(ik6::Ik6Args),
    /// Every configuration of a seven-revolute arm at a pose of its tip (its self-motion set), as certified boxes along curves.
    SelfMotion(self_motion::SelfMotionArgs),
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
    /// it) and no --fix or --tip-point is given, else 3r.
    #[arg(long, value_enum)]
    singular_set: Option<SingularSetArg>,
    /// Radians: crossings are narrowed until the joints' enclosure is this wide.
    #[arg(long, alias = "tolerance", default_value_t = 1e-9, allow_hyphen_values = true)]
    precision: f64,
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
    #[arg(long, alias = "sigma", default_value_t = 1e-3)]
    precision: f64,
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
    /// base-to-platform distances and heights, as in Porta, Thomas, Ros and Torras (2003)), or auto: planar when the
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
    if ranks.is_some() && linkspace::app::rank_and_size().1 > 1 && matches!(cli.command, Command::Serve(_)) {
        bail!("serve runs in one process: start it without mpirun");
    }
    match cli.command {
        Command::Solve(args) => solve(args),
        Command::Singularities(args) => singularities(args),
        Command::Ik(args) => ik(args),
        Command::Ik6(args) => ik6::run(args),
        Command::SelfMotion(args) => self_motion::run(args),
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
/// Values may be negative everywhere (`--precision -1` means the same as `--precision=-1`, and
/// gets the same one-line complaint from the settings' own check). Every other error of clap's
/// (unknown flag, missing value, unparsable number) is flattened to one line: its multi-line
/// usage text would bury the message. `--help` and `--version` print as usual.
fn parse_args<I, T>(args: I) -> Cli
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    use clap::{CommandFactory, FromArgMatches};
    // An option's value may start with a hyphen (`--precision -1e-3`: clap's own test for a
    // negative number misses exponents); positionals keep clap's rule, so a flag is never
    // taken for a file name. An option whose value is optional (`--robot-description-topic
    // [TOPIC]`) keeps clap's rule too, or it would swallow the next flag as its value.
    let command = Cli::command().mut_subcommands(|s| {
        s.mut_args(|a| match (a.get_action().takes_values(), a.is_positional()) {
            (true, false) if a.get_num_args().is_some_and(|r| r.min_values() == 0) => a,
            (true, false) => a.allow_hyphen_values(true),
            (true, true) => a.allow_negative_numbers(true),
            _ => a,
        })
    });
    // The memory bound each command's job takes by default, in its --help.
    let command = command.mut_subcommands(|s| {
        let mib = match s.get_name() {
            "sweep" => sweep::DEFAULT_TASK_MEMORY_MIB,
            name => (Job::default_limits(name).max_memory >> 20) as u64,
        };
        s.mut_arg("max_memory", |a| {
            let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
            a.help(format!("{help} [default: {mib}]"))
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
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let traces = args.trace.iter().map(|s| parse_trace3(s)).collect::<Result<Vec<_>>>()?;
    let traces: Vec<TracedPoint> = traces.into_iter().zip(&args.trace).map(|((l, p), r)| (l, p, r.clone())).collect();
    let job = SolveJob { fixed, traces, model: args.model.into(), precision: args.precision, rho: args.rho, use_lp: !args.no_lp, newton_width: args.newton_width, lp_backend: args.lp.into() };
    execute(&args.urdf, Job::Solve(job), &args.limits, args.json.as_deref())
}

/// The one route of every command: read the file, prepare the job (one clear line on bad
/// input), run it within the limits, print the answer and write its JSON report.
pub(crate) fn execute(path: &Path, job: Job, limits: &LimitArgs, json: Option<&Path>) -> Result<()> {
    let answer = answer(path, job, limits)?;
    // A closed pipe ends the printing quietly (`println!` would panic).
    std::io::stdout().lock().write_all(report::text(&answer).as_bytes()).ok();
    if let Some(out) = json {
        write_json(out, &answer)?;
    }
    Ok(())
}

/// The answer to `job` about the file at `path`, within `limits`.
pub(crate) fn answer(path: &Path, job: Job, limits: &LimitArgs) -> Result<Answer> {
    // `--timeout` counts from here: reading and building a large mechanism are part of the run.
    let start = std::time::Instant::now();
    let control_limits = limits.limits(Job::default_limits(job.name()))?;
    let input = read_input(path, &job)?;
    run_job(path, &input, job, control_limits, limits, start)
}

/// The file at `path` as `job` reads it (a distance file or a URDF).
pub(crate) fn read_input(path: &Path, job: &Job) -> Result<app::Input> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    match job {
        Job::Distances(_) => app::Input::read(&path.to_string_lossy(), &text),
        _ => app::Input::urdf(&text),
    }
    .with_context(|| format!("loading {}", path.display()))
}

/// Prepares `job` on `input` (read from `path`) and runs it within `control_limits`, counted
/// from `start`, on the threads of `limits`.
pub(crate) fn run_job(path: &Path, input: &app::Input, job: Job, control_limits: Limits, limits: &LimitArgs, start: std::time::Instant) -> Result<Answer> {
    let verb = match job {
        Job::Solve(_) | Job::Distances(_) | Job::LoopSingularities(_) => "building",
        _ => "loading",
    };
    let prepared = app::prepare(input, job).with_context(|| format!("{verb} {}", path.display()))?;
    if let Some(notice) = prepared.notice() {
        eprintln!("linkspace: {notice}");
    }
    let cancel = AtomicBool::new(false);
    let control = Control { limits: control_limits, threads: limits.threads(), cancel: &cancel }.remaining_since(start);
    let show = std::io::stderr().is_terminal();
    let mut progress = |p: &Progress| {
        if show {
            eprint!("\r{:5.1}% decided, {} boxes processed, {} pending   ", 100.0 * p.decided, p.processed, p.pending);
            let _ = std::io::stderr().flush();
        }
    };
    let answer = prepared.run(&control, &mut progress);
    if show {
        eprintln!();
    }
    answer.with_context(|| format!("analysing {}", path.display()))
}

/// Writes a report; under `mpirun`, only rank 0 writes (every rank holds the same result).
pub(crate) fn write_file(path: &std::path::Path, contents: impl AsRef<[u8]>) -> Result<()> {
    write_with(path, |out| Ok(out.write_all(contents.as_ref())?))
}

/// Writes `answer`'s JSON report to `path` as it is encoded (rank 0 of a shared run alone:
/// the others skip the encoding too).
pub(crate) fn write_json(path: &std::path::Path, answer: &Answer) -> Result<()> {
    write_with(path, |out| Ok(report::json(answer, out)?))
}

/// Creates the file at `path` and lets `write` fill it, buffered; under `mpirun`, on rank 0
/// only, so the other ranks neither encode nor write.
fn write_with(path: &std::path::Path, write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>) -> Result<()> {
    #[cfg(feature = "mpi")]
    if !ranks::writes() {
        return Ok(());
    }
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?);
    write(&mut out).and_then(|()| Ok(out.flush()?)).with_context(|| format!("writing {}", path.display()))
}

/// `--timeout` as a duration: positive and finite, or absent.
pub(crate) fn seconds_arg(t: Option<f64>) -> Result<Option<Duration>> {
    match t {
        Some(t) if t.is_finite() && t > 0.0 => Ok(Some(Duration::from_secs_f64(t.min(1e9)))),
        Some(t) => bail!("--timeout must be a positive number of seconds, got {t}"),
        None => Ok(None),
    }
}

fn singularities(args: SingularitiesArgs) -> Result<()> {
    if args.kind == SingularitiesKind::Cusps && args.nodes {
        bail!("--kind cusps searches no nodes: drop --nodes, or give --kind nodes");
    }
    let job = SingularitiesJob {
        arm: args.chain.options()?,
        uncertainty: args.uncertainty,
        precision: args.precision,
        nodes: args.nodes || args.kind == SingularitiesKind::Nodes,
        verdict: args.kind == SingularitiesKind::All,
        search_anyway: args.search_anyway,
        arm_budget: args.arm_budget,
    };
    execute(&args.urdf, Job::Singularities(job), &args.limits, args.json.as_deref())
}

/// The waypoints of `--waypoints` ("q1;q2;...") or `--waypoints-file` (JSON).
fn waypoints(args: &PathCheckArgs) -> Result<Vec<Vec<f64>>> {
    match (&args.waypoints, &args.waypoints_file) {
        (Some(text), _) => text
            .split(';')
            .filter(|w| !w.trim().is_empty())
            .map(|w| w.split(',').map(|t| t.trim().parse::<f64>().map_err(|_| anyhow::anyhow!("--waypoints: '{}' is not a number", t.trim()))).collect::<Result<Vec<f64>>>())
            .collect(),
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            serde_json::from_str(&text).with_context(|| format!("{}: expected a JSON list of lists of numbers", path.display()))
        }
        (None, None) => bail!("give --waypoints or --waypoints-file"),
    }
}

fn path_check(args: PathCheckArgs) -> Result<()> {
    let set = args.singular_set.map(|s| match s {
        SingularSetArg::SixR => PathSet::Arm6R,
        SingularSetArg::ThreeR => PathSet::Positioning3R,
    });
    let job = PathCheckJob { arm: args.chain.options()?, waypoints: waypoints(&args)?, joint_names: Vec::new(), set, precision: args.precision };
    execute(&args.urdf, Job::PathCheck(job), &args.limits, args.json.as_deref())
}

fn collisions(args: CollisionsArgs) -> Result<()> {
    let job = CollisionsJob { arm: args.chain.options()?, precision: args.precision };
    execute(&args.urdf, Job::Collisions(job), &args.limits, args.json.as_deref())
}

fn ik(args: IkArgs) -> Result<()> {
    let job = IkJob { arm: args.chain.options()?, uncertainty: args.uncertainty, point: parse_ik_point(&args.point)?, precision: args.precision };
    execute(&args.urdf, Job::Ik(job), &args.limits, args.json.as_deref())
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

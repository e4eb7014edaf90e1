//! The command line: argument parsing and the `solve` command. `anyhow` lives here and in main.

#[cfg(feature = "ros")]
mod serve;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use linkspace::model::urdf;
use linkspace::problems::LinkageProblem;
use linkspace::lp::LpBackend;
use linkspace::solve::{Progress, Solver, SolverSettings};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

#[derive(Parser)]
#[command(name = "linkspace", version, about = "Every configuration a mechanism can take, with guarantees.")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Enclose every configuration of a planar closed-loop linkage described in URDF.
    Solve(SolveArgs),
    /// Time the bundled double butterfly, rigid and mobile, against a baseline in the same run.
    Bench(BenchArgs),
    /// Run the ROS 2 node: analyse each URDF, publish the results, serve queries (launch_notes.md).
    #[cfg(feature = "ros")]
    Serve(serve::ServeArgs),
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

#[derive(clap::Args)]
struct BenchArgs {
    /// Runs per case; the median is reported.
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    /// Mobile-case sigma.
    #[arg(long, default_value_t = 0.05)]
    mobile_sigma: f64,
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
    /// Stop after this many boxes (the run is then reported incomplete).
    #[arg(long, default_value_t = 1_000_000)]
    max_boxes: u64,
    /// Stop after this many seconds (the run is then reported incomplete).
    #[arg(long)]
    timeout: Option<f64>,
    /// Trace a point given in a link's frame: LINK@X,Y. Repeatable.
    #[arg(long = "trace", value_name = "LINK@X,Y")]
    trace: Vec<String>,
    /// Shrink by interval propagation only (no LP): for comparisons.
    #[arg(long)]
    no_lp: bool,
    /// LP solver proposing the multipliers that the safe bound verifies.
    #[arg(long, value_enum, default_value_t = Backend::Simplex)]
    lp: Backend,
    /// Write the full report as JSON here.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Parses arguments and runs; errors come back as one chain of context.
pub fn run() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Solve(args) => solve(args),
        Command::Bench(args) => bench(args),
        #[cfg(feature = "ros")]
        Command::Serve(args) => serve::serve(args),
    }
}

fn parse_fix(s: &str) -> Result<(String, f64)> {
    let (name, value) = s.split_once('=').with_context(|| format!("--fix '{s}': expected JOINT=VALUE"))?;
    let v: f64 = value.trim().parse().with_context(|| format!("--fix '{s}': '{value}' is not a number"))?;
    Ok((name.trim().to_string(), v))
}

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

fn solve(args: SolveArgs) -> Result<()> {
    let timeout = match args.timeout {
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t.min(1e9))),
        Some(t) => bail!("--timeout must be a positive number of seconds, got {t}"),
        None => None,
    };
    let settings = SolverSettings { sigma: args.sigma, rho: args.rho, max_boxes: args.max_boxes, timeout, use_lp: !args.no_lp, lp_backend: args.lp.into() };
    settings.validate()?;
    let fixed = args.fix.iter().map(|s| parse_fix(s)).collect::<Result<Vec<_>>>()?;
    let traces = args.trace.iter().map(|s| parse_trace(s)).collect::<Result<Vec<_>>>()?;
    let xml = std::fs::read_to_string(&args.urdf).with_context(|| format!("reading {}", args.urdf.display()))?;
    let mechanism = urdf::parse(&xml).with_context(|| format!("loading {}", args.urdf.display()))?;
    let problem = LinkageProblem::new(&mechanism, &fixed, &traces).with_context(|| format!("building {}", args.urdf.display()))?;
    let solver = Solver::new(&problem.system, settings.clone())?;
    let show = std::io::stderr().is_terminal();
    let mut progress = |p: &Progress| {
        if show {
            eprint!("\r{:5.1}% decided, {} boxes processed, {} pending   ", 100.0 * p.decided, p.processed, p.pending);
            let _ = std::io::stderr().flush();
        }
    };
    let result = solver.enclose(&AtomicBool::new(false), &mut progress);
    if show {
        eprintln!();
    }
    let status = result.status;
    let report = problem.report(&settings, result.status, result.stats, &result.solutions, &result.undecided);
    // Write through a handle: `println!` panics when the reader of a pipe has gone.
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} solution boxes in {} clusters, status {}, {} boxes processed ({} empty, {} bisected), {} LPs, {:.3} s",
        report.mechanism,
        report.solutions.len(),
        report.clusters,
        match status {
            linkspace::Status::Complete => "complete".to_string(),
            linkspace::Status::Incomplete(l) => format!("incomplete ({l:?} limit, {} boxes undecided)", report.undecided.len()),
        },
        report.stats.processed,
        report.stats.empty,
        report.stats.bisected,
        report.stats.lp.solved,
        report.stats.seconds
    )
    .ok();
    if report.solutions.len() <= 20 {
        for (k, s) in report.solutions.iter().enumerate() {
            let joints: Vec<String> = s.joints.iter().map(|(n, [lo, hi])| format!("{n}={:.6}", 0.5 * (lo + hi))).collect();
            writeln!(out, "  #{k}: {}", joints.join(" ")).ok();
        }
    }
    if let Some(path) = args.json {
        let text = serde_json::to_string_pretty(&report)?;
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The bundled butterfly, compiled in so `bench` runs from anywhere.
const BUTTERFLY: &str = include_str!("../urdf/double_butterfly.urdf");

fn bench(args: BenchArgs) -> Result<()> {
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    let mechanism = urdf::parse(BUTTERFLY).context("bundled double_butterfly.urdf")?;
    let rigid = LinkageProblem::new(&mechanism, &[("joint6".to_string(), 12f64.atan2(5.0))], &[])?;
    let mobile = LinkageProblem::new(&mechanism, &[], &[])?;
    let cases = [("rigid, theta6 = atan2(12,5), sigma 1e-4", &rigid, 1e-4, 0.15, 15, 6), ("mobile", &mobile, args.mobile_sigma, 28.9, 2523, 1229)];
    let mut out = std::io::stdout().lock();
    writeln!(out, "case | LP backend | median s | boxes processed | solution boxes | clusters | LPs | vs clarabel (same run)").ok();
    for (name, problem, sigma, cuik_s, cuik_boxes, cuik_sol) in cases {
        let mut medians = Vec::new();
        for backend in [LpBackend::Clarabel, LpBackend::Simplex] {
            let settings = SolverSettings { sigma, lp_backend: backend, ..Default::default() };
            let solver = Solver::new(&problem.system, settings)?;
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..args.repeat {
                let e = solver.enclose(&AtomicBool::new(false), &mut |_| {});
                times.push(e.stats.seconds);
                last = Some(e);
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let median = times[times.len() / 2];
            let e = last.expect("repeat >= 1");
            let clusters = linkspace::interval::components(&e.solutions).1;
            let ratio = medians.first().map_or("1.00x (baseline)".to_string(), |base: &f64| format!("{:.2}x faster", base / median));
            writeln!(out, "{name} | {backend:?} | {median:.4} | {} | {} | {clusters} | {} | {ratio}", e.stats.processed, e.solutions.len(), e.stats.lp.solved).ok();
            medians.push(median);
        }
        writeln!(out, "{name} | CuikSuite (published in research/double_butterfly.md, not run here) | {cuik_s} | {cuik_boxes} | {cuik_sol} | | | {:.1}x faster than CuikSuite", cuik_s / medians[1]).ok();
    }
    Ok(())
}

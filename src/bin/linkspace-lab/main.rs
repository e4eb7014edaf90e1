//! `linkspace-lab`: the benches, the charts and the stability study behind the README's
//! figures, kept out of the `linkspace` product binary. A client of the library's public API
//! only; each figure is one command (`cargo lab bench`).

mod bench;
mod bench3r;
mod bench_arms;
mod charts;
mod distances;
mod ibex;
mod loops;
mod plot;
mod scaling;
mod spatial;
mod study;

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "linkspace-lab", version, about = "Benches and charts behind linkspace's published figures.")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Draw SVG charts from fresh runs of the bundled problems into a folder.
    Chart(ChartArgs),
    /// Time the bundled double butterfly, rigid and mobile, against a baseline in the same run.
    Bench(bench::BenchArgs),
    /// Time cusp and node searches on the bundled 3R robots against baselines in the same run.
    Bench3r(bench3r::Bench3rArgs),
    /// Time the cases of Porta et al. (2003) (octahedral platform, four spheres) against baselines
    /// in the same run.
    BenchDistances(distances::BenchArgs),
    /// Time singular-set searches of closed-loop linkages against baselines in the same run.
    BenchLoopSingularities(loops::BenchArgs),
    /// Time the spatial builder: planar fixtures against the planar model, spatial ones with
    /// and without the LP shrink, each in the same run.
    BenchSpatial(spatial::BenchArgs),
    /// Record a planar solve's search tree and predict its time on 1 to 1024 MPI ranks.
    Scaling(scaling::ScalingArgs),
}

#[derive(clap::Args)]
struct ChartArgs {
    /// Folder for the SVG files (created if missing).
    dir: PathBuf,
    /// Shorter sweeps (a minute instead of several).
    #[arg(long)]
    quick: bool,
    /// Only these chart groups, comma separated: speed, cspace, convergence, stability,
    /// singular3r, collisions, distances, cusps, loops (default: all).
    #[arg(long, value_delimiter = ',', value_name = "GROUP,...")]
    only: Vec<String>,
}

fn main() -> ExitCode {
    let result = match parse_args() {
        Command::Chart(args) => charts::run(&args.dir, args.quick, &args.only),
        Command::Bench(args) => bench::run(args),
        Command::Bench3r(args) => bench3r::run(args),
        Command::BenchDistances(args) => distances::bench(args),
        Command::BenchLoopSingularities(args) => loops::bench(args),
        Command::BenchSpatial(args) => spatial::bench(args),
        Command::Scaling(args) => scaling::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// `--repeat` and the like: at least one run.
fn check_repeat(repeat: usize) -> Result<()> {
    if repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    Ok(())
}

/// A time against a baseline measured in the same run: "2.10x faster" or "1.25x slower".
fn speed_against(baseline: f64, time: f64) -> String {
    let speed = baseline / time.max(1e-9);
    if speed >= 1.0 {
        format!("{speed:.2}x faster")
    } else {
        format!("{:.2}x slower", 1.0 / speed)
    }
}

/// The median of `v` (the upper one for an even count); `v` is not empty.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Parses the command line as `linkspace` does: option values may start with a hyphen (so
/// `--repeat -1` is reported as a bad value, not an unknown flag), and every error is one line
/// on stderr with clap's exit code; `--help` and `--version` print as usual.
fn parse_args() -> Command {
    use clap::{CommandFactory, FromArgMatches};
    let command = Cli::command().mut_subcommands(|s| {
        s.mut_args(|a| match (a.get_action().takes_values(), a.is_positional()) {
            (true, false) => a.allow_hyphen_values(true),
            (true, true) => a.allow_negative_numbers(true),
            _ => a,
        })
    });
    match command.try_get_matches_from(std::env::args_os()).and_then(|m| Cli::from_arg_matches(&m)) {
        Ok(cli) => cli.command,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand) {
                e.exit();
            }
            let text = e.to_string();
            let lines: Vec<&str> = text.lines().map(str::trim).take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information")).filter(|l| !l.is_empty()).collect();
            eprintln!("error: {}", lines.join(" ").trim_start_matches("error: "));
            std::process::exit(e.exit_code());
        }
    }
}

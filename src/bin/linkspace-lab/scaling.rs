//! `linkspace-lab scaling URDF`: the search tree of one planar solve recorded level by level,
//! and the time it predicts for N MPI ranks sharing the whole run (`mpirun -np N linkspace
//! solve ...`), up to 1024.
//!
//! The search is modelled as the shared driver runs it (`search::run_shared`): per level, the
//! cells are dealt in chunks round robin, so the slowest rank decides `ceil(chunks / N)`
//! chunks; then one gather (`latency` per doubling of N); then every rank decodes every
//! decision (`decode` per cell: the part that does not shrink with N). A cell costs the
//! search's CPU time over its cells.
//!
//! What follows the search (re-examining isolated boxes, labelling the components, reading the
//! boxes out) is measured: the whole run (`app::SolveRun`) on one thread and on two, in this
//! process, gives its serial part `s` and its shared part `p` (`post(1) = s + p`,
//! `post(2) = s + p / 2`); on N ranks it takes `s + p / N`, plus three gathers of `gather`
//! seconds per box each (every rank receives every result).

use anyhow::{Context, Result};
use linkspace::model::urdf;
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::interval::IntervalBox;
use linkspace::app::SolveRun;
use linkspace::formulate::ModelChoice;
use linkspace::kernel::search::{BoxSink, BoxStatus, Progress, SolverSettings};
use std::ops::ControlFlow;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

#[derive(clap::Args)]
pub struct ScalingArgs {
    /// A planar or spatial closed-loop linkage.
    urdf: PathBuf,
    /// Boxes no wider than this are solutions.
    #[arg(long, default_value_t = 0.1)]
    sigma: f64,
    /// Seconds one gather takes per doubling of the ranks (MPI_Allgatherv latency).
    #[arg(long, default_value_t = 20e-6)]
    latency: f64,
    /// Seconds every rank spends per cell of a level to encode, move and decode its decision;
    /// fitted to `--two-ranks` when that is given.
    #[arg(long, default_value_t = 2e-6)]
    decode: f64,
    /// Seconds every rank spends per box to receive one shared result of the post-processing
    /// (a probe's verdict, a slice's pairs, a box's read-out); three such gathers follow a
    /// search.
    #[arg(long, default_value_t = 1e-6)]
    gather: f64,
    /// The measured search seconds (`stats.seconds`) of this solve on 2 ranks of one thread:
    /// fits `--decode`.
    #[arg(long, value_name = "SECONDS")]
    two_ranks: Option<f64>,
}

/// The predicted search seconds on `n` ranks.
fn predict(levels: &[usize], cell: f64, latency: f64, decode: f64, n: usize) -> f64 {
    levels
        .iter()
        .map(|&cells| {
            let chunk = (cells / (n * 8)).clamp(1, 256);
            let chunks = cells.div_ceil(chunk);
            let slowest = chunks.div_ceil(n) * chunk;
            let talk = if n > 1 { latency * (n as f64).log2().ceil() + decode * cells as f64 } else { 0.0 };
            slowest.min(cells) as f64 * cell + talk
        })
        .sum()
}

pub fn run(args: ScalingArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.urdf).with_context(|| format!("reading {}", args.urdf.display()))?;
    let m = urdf::parse(&text)?;
    let problem = LinkageProblem::new(&m, &[], &[])?;
    // The level-by-level driver on one thread, which reports after each level; the search
    // alone (no post-processing), so that a cell's cost is the search's.
    let solver = problem.solver(SolverSettings { sigma: args.sigma, threads: 1, ..SolverSettings::default() })?;
    struct Levels {
        sizes: Vec<usize>,
        processed: u64,
    }
    impl BoxSink for Levels {
        fn emit(&mut self, _: BoxStatus, _: &IntervalBox) -> ControlFlow<()> {
            ControlFlow::Continue(())
        }
        fn progress(&mut self, p: &Progress) {
            // After each level: what it processed, and the next level waiting.
            if p.processed > self.processed {
                self.processed = p.processed;
                self.sizes.push(p.pending);
            }
        }
    }
    let mut sink = Levels { sizes: vec![1], processed: 0 };
    let (_, stats) = solver.run_parallel(1, &AtomicBool::new(false), &mut sink, None);
    let mut levels = sink.sizes;
    levels.retain(|&n| n > 0);
    let cells: usize = levels.iter().sum();
    let cell = stats.cpu_seconds / cells as f64;
    let decode = match args.two_ranks {
        Some(t2) => ((t2 - predict(&levels, cell, args.latency, 0.0, 2)) / cells as f64).max(0.0),
        None => args.decode,
    };
    // The whole run on one thread and on two: what follows the search, and its serial part.
    let post = |threads: usize| -> Result<(f64, usize)> {
        let run = SolveRun::build(&m, ModelChoice::Auto, &[], &[], SolverSettings { sigma: args.sigma, threads, ..SolverSettings::default() })?;
        let t0 = std::time::Instant::now();
        let result = run.run(&AtomicBool::new(false), &mut |_| {});
        // `stats.seconds`: the search with its re-examination of isolated boxes.
        Ok(((t0.elapsed().as_secs_f64() - result.stats.seconds).max(0.0), result.boxes.len()))
    };
    let (post1, boxes) = post(1)?;
    let (post2, _) = post(2)?;
    let shared = (2.0 * (post1 - post2)).clamp(0.0, post1);
    let serial = post1 - shared;
    let whole = |n: usize| {
        let gathers = if n > 1 { 3.0 * args.latency * (n as f64).log2().ceil() + 3.0 * args.gather * boxes as f64 } else { 0.0 };
        predict(&levels, cell, args.latency, decode, n) + serial + shared / n as f64 + gathers
    };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}: sigma {}, {} levels, {cells} cells, {:.1} µs CPU per cell; latency {:.1} µs per doubling, decode {:.2} µs per cell{}", m.name, args.sigma, levels.len(), cell * 1e6, args.latency * 1e6, decode * 1e6, if args.two_ranks.is_some() { " (fitted to --two-ranks)" } else { "" })?;
    writeln!(out, "after the search: {post1:.3} s on one thread, {post2:.3} s on two (measured): {serial:.3} s serial, {shared:.3} s shared; {boxes} boxes")?;
    writeln!(out, "| ranks | predicted search | search efficiency | predicted whole run | speed-up | efficiency |")?;
    writeln!(out, "|---|---|---|---|---|---|")?;
    let (one, one_whole) = (predict(&levels, cell, args.latency, decode, 1), whole(1));
    for k in 0..=10 {
        let n = 1usize << k;
        let (t, w) = (predict(&levels, cell, args.latency, decode, n), whole(n));
        writeln!(out, "| {n} | {t:.3} s | {:.0} % | {w:.3} s | {:.1}x | {:.0} % |", 100.0 * one / t / n as f64, one_whole / w, 100.0 * one_whole / w / n as f64)?;
    }
    Ok(())
}

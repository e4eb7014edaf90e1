//! `linkspace sweep SPEC`: reads the spec and the URDF, runs each task as a `Job::SweepTask`, appends each
//! result to `results.jsonl` as it finishes, then writes the table, the summary and the map.
//!
//! Under `mpirun` (feature `mpi`) the ranks share the tasks: rank R runs the pending tasks whose
//! index is R modulo the number of ranks, each on its own `--threads`. Rank 0 appends its
//! results to `results.jsonl` as they finish, the others to `results.rank-R.jsonl` (with the
//! same header), so an interrupted sweep loses nothing; at the end rank 0 gathers every rank's
//! results into `results.jsonl` and removes the rank files. `--resume` reads them all.

use anyhow::{bail, Context, Result};
use linkspace::app;
use linkspace::app::Limits;
use linkspace::app::sweeps::{self as sweep, Header, Summary, Sweep, TaskResult, DEFAULT_MAX_TASKS};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Seconds a task may take when neither the spec nor the command line says.
const DEFAULT_TASK_TIMEOUT: f64 = 60.0;
/// MiB of pending boxes a task may hold when neither says: several tasks run at once.
pub(crate) const DEFAULT_TASK_MEMORY_MIB: u64 = 256;

#[derive(clap::Args)]
pub(crate) struct SweepArgs {
    /// The sweep spec (JSON; README "Design sweeps").
    spec: PathBuf,
    /// Directory for results.jsonl, results.csv, summary.json and map.svg. Default: the spec's
    /// file name without extension, with `-results`, in the current directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Continue the sweep whose results are in --out: tasks already there are skipped.
    #[arg(long)]
    resume: bool,
    /// Refuse a sweep of more tasks than this.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_TASKS)]
    max_tasks: usize,
    /// Each task's limits (over the spec's `limits`; defaults: 60 s and 256 MiB per task, the
    /// analysis's boxes), and `--threads`: tasks run at a time, each on one thread.
    #[command(flatten)]
    limits: super::LimitArgs,
}

pub(crate) fn run(args: SweepArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.spec).with_context(|| format!("reading {}", args.spec.display()))?;
    let plan = sweep::parse(&text).with_context(|| format!("reading {}", args.spec.display()))?;
    let urdf_path = args.spec.parent().unwrap_or(Path::new(".")).join(&plan.urdf);
    let urdf_text = std::fs::read_to_string(&urdf_path).with_context(|| format!("reading {} (the spec's urdf)", urdf_path.display()))?;
    let input = app::Input::urdf(&urdf_text).with_context(|| format!("loading {}", urdf_path.display()))?;
    let mechanism = input.mechanism()?;
    let tasks = plan.tasks(args.max_tasks)?;
    app::sweeps::check_sweep(&plan, mechanism, &tasks).with_context(|| format!("checking {} against {}", args.spec.display(), urdf_path.display()))?;
    let limits = limits(&args, &plan)?;

    let out = args.out.clone().unwrap_or_else(|| PathBuf::from(format!("{}-results", args.spec.file_stem().map_or("sweep".into(), |s| s.to_string_lossy()))));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let jsonl = out.join("results.jsonl");
    let header = Header::new(&plan, &urdf_text, tasks.len());
    let existing = match std::fs::read_to_string(&jsonl) {
        Ok(t) if !t.trim().is_empty() => Some(t),
        Ok(_) => None,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => return Err(e).with_context(|| format!("reading {}", jsonl.display())),
    };
    let (rank, ranks) = linkspace::app::rank_and_size();
    // Rank 0 reads and rewrites the results; the others learn what is done (or that rank 0
    // refused) from it, so no rank waits for one that stopped.
    let prepared = if rank == 0 { prepare(&out, &jsonl, &existing, args.resume, &header, &tasks) } else { Ok(Vec::new()) };
    let (earlier, done_before): (Vec<TaskResult>, HashSet<usize>) = if ranks > 1 {
        let mine: Vec<u8> = match &prepared {
            Ok(earlier) => std::iter::once(1u8).chain(earlier.iter().flat_map(|r| (r.index as u64).to_le_bytes())).collect(),
            Err(_) => vec![0u8],
        };
        let from_rank_0 = gather(mine).swap_remove(0);
        let Some((1, indices)) = from_rank_0.split_first() else {
            return Err(prepared.err().unwrap_or_else(|| anyhow::anyhow!("rank 0 stopped before the sweep started")));
        };
        let done: HashSet<usize> = indices.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().expect("eight bytes")) as usize).collect();
        (prepared?, done)
    } else {
        let earlier = prepared?;
        let done = earlier.iter().map(|r| r.index).collect();
        (earlier, done)
    };
    let mut done = done_before.clone();
    let my_file = if rank == 0 { jsonl.clone() } else { out.join(format!("results.rank-{rank}.jsonl")) };
    if rank != 0 {
        std::fs::write(&my_file, header.line() + "\n").with_context(|| format!("writing {}", my_file.display()))?;
    }
    let mut file = std::fs::OpenOptions::new().append(true).open(&my_file).with_context(|| format!("opening {}", my_file.display()))?;
    // Another rank's tasks are, for this one, as good as done.
    let already_done = done.len();
    done.extend(tasks.iter().map(|t| t.index).filter(|i| i % ranks != rank));
    let labels = header.parameters.clone();
    let threads = args.limits.threads();
    let total = tasks.len();
    let mut results = earlier;
    let mut run_now = 0usize;
    let start = Instant::now();
    if already_done > 0 {
        eprintln!("resuming: {already_done} of {total} tasks already done");
    }
    let cancel = AtomicBool::new(false);
    let run_one = |task: &sweep::Task| sweep::answer_task(&input, &plan, task, &limits, &cancel);
    sweep::run_tasks(&tasks, threads, &done, run_one, |r: TaskResult| -> Result<()> {
        writeln!(file, "{}", serde_json::to_string(&r)?).and_then(|_| file.flush()).with_context(|| format!("writing {}", my_file.display()))?;
        run_now += 1;
        let params: Vec<String> = labels.iter().zip(&r.values).map(|(l, v)| format!("{l}={v}")).collect();
        let what = match (&r.verdict, r.count, &r.error) {
            (_, _, Some(e)) => format!("failed: {e}"),
            (Some(v), Some(c), _) => format!("{v} ({c} cusps proven, {} undecided)", r.undecided),
            (_, Some(c), _) => format!("{c} assembly modes ({} proven boxes, {} undecided)", r.proven, r.undecided),
            _ => String::new(),
        };
        let limit = r.limit.as_deref().map_or(String::new(), |l| format!(", {l} limit"));
        eprintln!("[{}/{total}] task {} {}: {what}, {}{limit}, {:.3} s", results.len() + 1, r.index, params.join(" "), r.status.name(), r.seconds);
        results.push(r);
        Ok(())
    })?;
    if ranks > 1 {
        // Every rank's results of this run to rank 0, which writes them all.
        let mine: Vec<u8> = results.iter().filter(|r| r.index % ranks == rank && !done_before.contains(&r.index)).map(|r| serde_json::to_string(r).map(|l| l + "\n")).collect::<Result<String, _>>()?.into_bytes();
        let all = gather(mine);
        if rank != 0 {
            std::fs::remove_file(&my_file).with_context(|| format!("removing {}", my_file.display()))?;
            return Ok(());
        }
        for (other, bytes) in all.iter().enumerate().skip(1) {
            for line in String::from_utf8_lossy(bytes).lines() {
                let r: TaskResult = serde_json::from_str(line).with_context(|| format!("a result from rank {other}"))?;
                writeln!(file, "{line}").with_context(|| format!("writing {}", jsonl.display()))?;
                run_now += 1;
                results.push(r);
            }
        }
        file.flush().with_context(|| format!("writing {}", jsonl.display()))?;
    }
    let wall = start.elapsed().as_secs_f64();
    results.sort_by_key(|r| r.index);

    std::fs::write(out.join("results.csv"), sweep::csv(&labels, &results)).with_context(|| format!("writing {}", out.join("results.csv").display()))?;
    let summary = Summary::of(&header, &results, run_now, wall, threads);
    std::fs::write(out.join("summary.json"), serde_json::to_string_pretty(&summary)?).with_context(|| format!("writing {}", out.join("summary.json").display()))?;
    let map = plan.map_axes().map(|axes| {
        let title = format!("{} of {} over ({}, {})", plan.analysis.name(), mechanism.name, labels[axes[0]], labels[axes[1]]);
        sweep::map_svg(&title, &labels, axes, &results)
    });
    if let Some(svg) = &map {
        std::fs::write(out.join("map.svg"), svg).with_context(|| format!("writing {}", out.join("map.svg").display()))?;
    }
    let counts = |m: &std::collections::BTreeMap<String, usize>| m.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ");
    let mut stdout = std::io::stdout().lock();
    writeln!(
        stdout,
        "{}: {} of {total} tasks done ({run_now} now), {}; {}: {}; {wall:.3} s wall, {threads} at a time ({:.3} s of tasks); results in {}{}",
        mechanism.name,
        results.len(),
        counts(&summary.by_status),
        if matches!(plan.analysis, Sweep::Cuspidality { .. }) { "verdicts" } else { "assembly modes" },
        counts(&summary.by_outcome),
        summary.task_seconds,
        out.display(),
        if map.is_none() { " (no map: one parameter)" } else { "" }
    )
    .ok();
    Ok(())
}

/// Rank 0's start: the results already written (with `--resume`), `results.jsonl` rewritten
/// from them with whole lines only, and the rank files of a stopped run on ranks merged in.
fn prepare(out: &Path, jsonl: &Path, existing: &Option<String>, resume: bool, header: &Header, tasks: &[sweep::Task]) -> Result<Vec<TaskResult>> {
    let mut earlier = match (existing, resume) {
        (Some(_), false) => bail!("{} exists: --resume continues that sweep, or choose another --out", jsonl.display()),
        (Some(t), true) => sweep::read_done(t, header, tasks)?,
        (None, _) => Vec::new(),
    };
    // What other ranks had finished when an earlier run on ranks stopped.
    for path in rank_files(out)? {
        if !resume {
            bail!("{} exists: --resume continues that sweep, or choose another --out", path.display());
        }
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        for r in sweep::read_done(&text, header, tasks).with_context(|| format!("reading {}", path.display()))? {
            if !earlier.iter().any(|e: &TaskResult| e.index == r.index) {
                earlier.push(r);
            }
        }
    }
    earlier.sort_by_key(|r| r.index);
    // Rewritten from what was read: a line cut short by an interruption is dropped, so the
    // file stays one header and whole lines.
    let mut lines = header.line() + "\n";
    for r in &earlier {
        lines.push_str(&serde_json::to_string(r)?);
        lines.push('\n');
    }
    std::fs::write(jsonl, lines).with_context(|| format!("writing {}", jsonl.display()))?;
    for path in rank_files(out)? {
        std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
    }
    Ok(earlier)
}

/// The results files of ranks other than 0 in `out` (left by a run on ranks that stopped).
fn rank_files(out: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(out).with_context(|| format!("listing {}", out.display()))? {
        let path = entry.with_context(|| format!("listing {}", out.display()))?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if name.starts_with("results.rank-") && name.ends_with(".jsonl") {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Every rank's bytes, in rank order (this process's alone without MPI).
fn gather(mine: Vec<u8>) -> Vec<Vec<u8>> {
    #[cfg(feature = "mpi")]
    if linkspace::app::rank_and_size().1 > 1 {
        return super::ranks::all_gather(&mine);
    }
    vec![mine]
}

/// Each task's limits: the command line over the spec over the defaults.
fn limits(args: &SweepArgs, plan: &sweep::Plan) -> Result<Limits> {
    let timeout = args.limits.timeout.or(plan.limits.timeout).unwrap_or(DEFAULT_TASK_TIMEOUT);
    let timeout = super::seconds_arg(Some(timeout))?.unwrap_or(Duration::from_secs_f64(DEFAULT_TASK_TIMEOUT));
    let default_boxes = match plan.analysis {
        Sweep::Cuspidality { .. } => app::Job::default_limits("singularities").max_cells,
        Sweep::AssemblyModes { .. } => app::Job::default_limits("solve").max_cells,
    };
    let max_cells = args.limits.max_boxes.or(plan.limits.max_boxes).unwrap_or(default_boxes);
    if max_cells == 0 {
        bail!("--max-boxes must be at least 1");
    }
    let mib = args.limits.max_memory.or(plan.limits.max_memory_mib).unwrap_or(DEFAULT_TASK_MEMORY_MIB);
    if mib == 0 {
        bail!("--max-memory must be at least 1 MiB");
    }
    Ok(Limits { max_cells, timeout: Some(timeout), max_memory: usize::try_from(mib.saturating_mul(1 << 20)).unwrap_or(usize::MAX) })
}

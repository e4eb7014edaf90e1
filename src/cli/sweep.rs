//! `linkspace sweep SPEC`: reads the spec and the URDF, runs `app::run_sweep`, appends each
//! result to `results.jsonl` as it finishes, then writes the table, the summary and the map.

use anyhow::{bail, Context, Result};
use linkspace::app;
use linkspace::model::urdf;
use linkspace::search::Limits;
use linkspace::sweep::{self, Header, Summary, Sweep, TaskResult, DEFAULT_MAX_TASKS};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Seconds a task may take when neither the spec nor the command line says.
const DEFAULT_TASK_TIMEOUT: f64 = 60.0;
/// MiB of pending boxes a task may hold when neither says: several tasks run at once.
const DEFAULT_TASK_MEMORY_MIB: u64 = 256;

#[derive(clap::Args)]
pub(crate) struct SweepArgs {
    /// The sweep spec (JSON; README "Design sweeps").
    spec: PathBuf,
    /// Directory for results.jsonl, results.csv, summary.json and map.svg. Default: the spec's
    /// file name without extension, with `-results`, in the current directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Tasks run at a time (each on one thread).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: u16,
    /// Continue the sweep whose results are in --out: tasks already there are skipped.
    #[arg(long)]
    resume: bool,
    /// Refuse a sweep of more tasks than this.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_TASKS)]
    max_tasks: usize,
    /// Seconds per task (overrides the spec's limits.timeout; default 60).
    #[arg(long, value_name = "SECONDS")]
    timeout: Option<f64>,
    /// Boxes per task (overrides the spec's limits.max_boxes; default: the analysis's, as for
    /// singularities and solve).
    #[arg(long, value_name = "N")]
    max_boxes: Option<u64>,
    /// MiB of pending boxes per task (overrides the spec's limits.max_memory; default 256).
    #[arg(long, value_name = "MIB")]
    max_memory: Option<u64>,
}

pub(crate) fn run(args: SweepArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.spec).with_context(|| format!("reading {}", args.spec.display()))?;
    let plan = sweep::parse(&text).with_context(|| format!("reading {}", args.spec.display()))?;
    let urdf_path = args.spec.parent().unwrap_or(Path::new(".")).join(&plan.urdf);
    let urdf_text = std::fs::read_to_string(&urdf_path).with_context(|| format!("reading {} (the spec's urdf)", urdf_path.display()))?;
    let mechanism = urdf::parse(&urdf_text).with_context(|| format!("loading {}", urdf_path.display()))?;
    let tasks = plan.tasks(args.max_tasks)?;
    app::check_sweep(&plan, &mechanism, &tasks).with_context(|| format!("checking {} against {}", args.spec.display(), urdf_path.display()))?;
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
    let earlier = match (&existing, args.resume) {
        (Some(_), false) => bail!("{} exists: --resume continues that sweep, or choose another --out", jsonl.display()),
        (Some(t), true) => sweep::read_done(t, &header, &tasks)?,
        (None, _) => Vec::new(),
    };
    // Rewritten from what was read: a line cut short by an interruption is dropped, so the
    // file stays one header and whole lines.
    let mut lines = header.line() + "\n";
    for r in &earlier {
        lines.push_str(&serde_json::to_string(r)?);
        lines.push('\n');
    }
    std::fs::write(&jsonl, lines).with_context(|| format!("writing {}", jsonl.display()))?;
    let mut file = std::fs::OpenOptions::new().append(true).open(&jsonl).with_context(|| format!("opening {}", jsonl.display()))?;

    let done: HashSet<usize> = earlier.iter().map(|r| r.index).collect();
    let labels = header.parameters.clone();
    let threads = usize::from(args.threads.max(1));
    let total = tasks.len();
    let mut results = earlier;
    let mut run_now = 0usize;
    let start = Instant::now();
    if !done.is_empty() {
        eprintln!("resuming: {} of {total} tasks already done", done.len());
    }
    let cancel = AtomicBool::new(false);
    app::run_sweep(&plan, &mechanism, &tasks, threads, &done, &limits, &cancel, |r: TaskResult| -> Result<()> {
        writeln!(file, "{}", serde_json::to_string(&r)?).and_then(|_| file.flush()).with_context(|| format!("writing {}", jsonl.display()))?;
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

/// Each task's limits: the command line over the spec over the defaults.
fn limits(args: &SweepArgs, plan: &sweep::Plan) -> Result<Limits> {
    let timeout = args.timeout.or(plan.limits.timeout).unwrap_or(DEFAULT_TASK_TIMEOUT);
    let timeout = super::seconds_arg(Some(timeout))?.unwrap_or(Duration::from_secs_f64(DEFAULT_TASK_TIMEOUT));
    let default_boxes = match plan.analysis {
        Sweep::Cuspidality { .. } => super::SINGULARITIES_MAX_BOXES,
        Sweep::AssemblyModes { .. } => linkspace::SolverSettings::default().max_boxes,
    };
    let max_cells = args.max_boxes.or(plan.limits.max_boxes).unwrap_or(default_boxes);
    if max_cells == 0 {
        bail!("--max-boxes must be at least 1");
    }
    let mib = args.max_memory.or(plan.limits.max_memory_mib).unwrap_or(DEFAULT_TASK_MEMORY_MIB);
    if mib == 0 {
        bail!("--max-memory must be at least 1 MiB");
    }
    Ok(Limits { max_cells, timeout: Some(timeout), max_memory: usize::try_from(mib.saturating_mul(1 << 20)).unwrap_or(usize::MAX) })
}

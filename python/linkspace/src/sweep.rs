//! `linkspace.sweep`: a design sweep as `linkspace sweep SPEC --out DIR` runs it
//! (`src/cli/sweep.rs`), in one process: every task a `Job::SweepTask` through the front door,
//! `threads` at a time, supervised like every run (Ctrl-C, progress as tasks done); the same
//! results, table, summary and map, written to `out` in the CLI's formats when given. Resuming
//! and MPI ranks stay the CLI's.

use crate::run::supervise;
use crate::{error, input_error};
use linkspace::app::sweeps::{self, Header, Summary, Sweep, TaskResult, DEFAULT_MAX_TASKS};
use linkspace::app::{self, Limits, Progress};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Seconds and MiB a task may take when neither the spec nor the call says (the CLI's).
const DEFAULT_TASK_TIMEOUT: f64 = 60.0;
const DEFAULT_TASK_MEMORY_MIB: u64 = 256;

/// What a sweep gives back: one JSON line per task (index order), the summary (JSON), the table
/// (CSV) and the map (SVG, when the sweep has two parameters).
type Outcome = (Vec<String>, String, String, Option<String>);

fn get<'py, T: for<'a> FromPyObject<'a, 'py>>(options: &Bound<'py, PyDict>, key: &str) -> PyResult<Option<T>> {
    match options.get_item(key)?.filter(|v| !v.is_none()) {
        None => Ok(None),
        Some(v) => v.extract::<T>().map(Some).map_err(|_| pyo3::exceptions::PyTypeError::new_err(format!("{key}: expected a number"))),
    }
}

/// Each task's limits: the call over the spec over the defaults, as the CLI's `limits`.
fn limits(py: Python<'_>, options: &Bound<'_, PyDict>, plan: &sweeps::Plan) -> PyResult<Limits> {
    let timeout = get::<f64>(options, "timeout")?.or(plan.limits.timeout).unwrap_or(DEFAULT_TASK_TIMEOUT);
    if !(timeout.is_finite() && timeout > 0.0) {
        return Err(input_error(py, format!("--timeout must be a positive number of seconds, got {timeout}")));
    }
    let default_boxes = match plan.analysis {
        Sweep::Cuspidality { .. } => app::Job::default_limits("singularities").max_cells,
        Sweep::AssemblyModes { .. } => app::Job::default_limits("solve").max_cells,
    };
    let max_cells = get::<u64>(options, "max_boxes")?.or(plan.limits.max_boxes).unwrap_or(default_boxes);
    if max_cells == 0 {
        return Err(input_error(py, "--max-boxes must be at least 1".into()));
    }
    let mib = get::<u64>(options, "max_memory")?.or(plan.limits.max_memory_mib).unwrap_or(DEFAULT_TASK_MEMORY_MIB);
    if mib == 0 {
        return Err(input_error(py, "--max-memory must be at least 1 MiB".into()));
    }
    Ok(Limits { max_cells, timeout: Some(Duration::from_secs_f64(timeout.min(1e9))), max_memory: usize::try_from(mib.saturating_mul(1 << 20)).unwrap_or(usize::MAX) })
}

fn io_error(py: Python<'_>, what: &str, path: &Path, e: &dyn std::fmt::Display) -> PyErr {
    error(py, "InputError", format!("{what} {}: {e}", path.display()))
}

/// Runs the sweep of the spec at `spec`; see the module's comment.
#[pyfunction]
#[pyo3(signature = (spec, out, options, progress=None))]
pub(crate) fn sweep(py: Python<'_>, spec: PathBuf, out: Option<PathBuf>, options: &Bound<'_, PyDict>, progress: Option<Bound<'_, PyAny>>) -> PyResult<Outcome> {
    let text = std::fs::read_to_string(&spec).map_err(|e| io_error(py, "reading", &spec, &e))?;
    let plan = sweeps::parse(&text).map_err(|e| input_error(py, format!("reading {}: {e}", spec.display())))?;
    let urdf_path = spec.parent().unwrap_or(Path::new(".")).join(&plan.urdf);
    let urdf_text = std::fs::read_to_string(&urdf_path).map_err(|e| input_error(py, format!("reading {} (the spec's urdf): {e}", urdf_path.display())))?;
    let input = app::Input::urdf(&urdf_text).map_err(|e| input_error(py, format!("loading {}: {e}", urdf_path.display())))?;
    let mechanism = input.mechanism().map_err(|e| input_error(py, e.to_string()))?;
    let tasks = plan.tasks(get::<usize>(options, "max_tasks")?.unwrap_or(DEFAULT_MAX_TASKS)).map_err(|e| input_error(py, e.to_string()))?;
    app::sweeps::check_sweep(&plan, mechanism, &tasks).map_err(|e| input_error(py, format!("checking {} against {}: {e}", spec.display(), urdf_path.display())))?;
    let limits = limits(py, options, &plan)?;
    let threads = get::<usize>(options, "threads")?.unwrap_or(1);
    if !(1..=1024).contains(&threads) {
        return Err(input_error(py, format!("invalid value '{threads}' for '--threads <THREADS>': {threads} is not in 1..=1024")));
    }
    let header = Header::new(&plan, &urdf_text, tasks.len());
    let mut file = match &out {
        None => None,
        Some(dir) => {
            std::fs::create_dir_all(dir).map_err(|e| io_error(py, "creating", dir, &e))?;
            let jsonl = dir.join("results.jsonl");
            if std::fs::metadata(&jsonl).is_ok_and(|m| m.len() > 0) {
                return Err(input_error(py, format!("{} exists: choose another out (the CLI's --resume continues that sweep)", jsonl.display())));
            }
            let mut f = std::fs::File::create(&jsonl).map_err(|e| io_error(py, "writing", &jsonl, &e))?;
            writeln!(f, "{}", header.line()).map_err(|e| io_error(py, "writing", &jsonl, &e))?;
            Some((f, jsonl))
        }
    };
    let start = Instant::now();
    let total = tasks.len();
    let ran = supervise(py, progress.as_ref(), |cancel, report| -> Result<Vec<TaskResult>, String> {
        let mut results = Vec::with_capacity(total);
        sweeps::run_tasks(&tasks, threads, &HashSet::new(), |t| sweeps::answer_task(&input, &plan, t, &limits, cancel), |r: TaskResult| -> Result<(), String> {
            if let Some((f, path)) = file.as_mut() {
                let line = serde_json::to_string(&r).map_err(|e| e.to_string())?;
                writeln!(f, "{line}").and_then(|_| f.flush()).map_err(|e| format!("writing {}: {e}", path.display()))?;
            }
            results.push(r);
            report(Progress { processed: results.len() as u64, pending: total - results.len(), decided: results.len() as f64 / total.max(1) as f64 });
            Ok(())
        })?;
        Ok(results)
    })?;
    let mut results = ran.map_err(|e| input_error(py, e))?;
    let wall = start.elapsed().as_secs_f64();
    results.sort_by_key(|r| r.index);
    let labels = header.parameters.clone();
    let csv = sweeps::csv(&labels, &results);
    let summary = Summary::of(&header, &results, results.len(), wall, threads);
    let summary = serde_json::to_string_pretty(&summary).map_err(|e| input_error(py, e.to_string()))?;
    let map = plan.map_axes().map(|axes| {
        let title = format!("{} of {} over ({}, {})", plan.analysis.name(), mechanism.name, labels[axes[0]], labels[axes[1]]);
        sweeps::map_svg(&title, &labels, axes, &results)
    });
    if let Some(dir) = &out {
        let write = |name: &str, text: &str| std::fs::write(dir.join(name), text).map_err(|e| io_error(py, "writing", &dir.join(name), &e));
        write("results.csv", &csv)?;
        write("summary.json", &summary)?;
        if let Some(svg) = &map {
            write("map.svg", svg)?;
        }
    }
    let rows = results.iter().map(serde_json::to_string).collect::<Result<Vec<_>, _>>().map_err(|e| input_error(py, e.to_string()))?;
    Ok((rows, summary, csv, map))
}

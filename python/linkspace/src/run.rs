//! One run as Python expects it: the job is prepared and run on a thread of its own with the
//! GIL released, while the calling thread wakes every 50 ms to look for Ctrl-C (a
//! `KeyboardInterrupt` raises the run's cancel flag; the run stops within the kernel's cancel
//! latency, and the interrupt is raised once it has) and to call the `progress` callback. A
//! Rust panic never crosses into Python: it becomes `linkspace.InternalError`.

use crate::options::RunBounds;
use crate::{error, input_error};
use linkspace::app::{self, Answer, Control, Input, Job, Progress};
use linkspace::edges::report;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant};

/// How often the calling thread looks for Ctrl-C and progress while a run runs.
const POLL: Duration = Duration::from_millis(50);

/// A worker's stack: the CLI runs its jobs on the main thread (8 MiB); the searches recurse
/// little, but a panic is the only way out of a stack overflow, and it would end Python.
const STACK: usize = 64 << 20;

/// The text of a panic's payload.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned()).unwrap_or_else(|| "a panic without a message".into())
}

fn internal(py: Python<'_>, what: String) -> PyErr {
    error(py, "InternalError", format!("internal error (please report it): {what}"))
}

/// `f()`, with a panic turned into `InternalError`.
pub(crate) fn guarded<T>(py: Python<'_>, f: impl FnOnce() -> T) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|p| internal(py, panic_text(p.as_ref())))
}

/// A job's error as the CLI words it: what it was doing to the input, then why.
fn job_error(py: Python<'_>, verb: &str, source: &str, e: &app::JobError) -> PyErr {
    let message = format!("{verb} {source}: {e}");
    if e.is_unsupported() {
        error(py, "UnsupportedError", message)
    } else if verb == "analysing" {
        error(py, "AnalysisError", message)
    } else {
        input_error(py, message)
    }
}

/// The latest progress of a run, and whether it has ended, guarded together.
#[derive(Default)]
struct Shared {
    progress: Option<Progress>,
    done: bool,
}

/// `work(cancel, report)` on a worker thread with the GIL released, while this thread wakes
/// every `POLL` to look for Ctrl-C (which raises `cancel`) and to pass what `work` last
/// reported to `progress`; see the module's comment. A panic in `work` is `InternalError`.
pub(crate) fn supervise<T: Send>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, work: impl FnOnce(&AtomicBool, &(dyn Fn(Progress) + Sync)) -> T + Send) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    let shared = Mutex::new(Shared::default());
    let wake = Condvar::new();
    let mut raised: Option<PyErr> = None;
    let outcome = std::thread::scope(|s| {
        let worker = std::thread::Builder::new().name("linkspace-run".into()).stack_size(STACK).spawn_scoped(s, || {
            let report = |p: Progress| {
                if let Ok(mut g) = shared.lock() {
                    g.progress = Some(p);
                }
            };
            let out = catch_unwind(AssertUnwindSafe(|| work(&cancel, &report)));
            // Raised even when the work panicked, so the caller never waits forever.
            if let Ok(mut g) = shared.lock() {
                g.done = true;
            }
            wake.notify_all();
            out
        });
        let worker = match worker {
            Ok(w) => w,
            Err(e) => return Err(internal(py, format!("cannot start a thread for the run: {e}"))),
        };
        loop {
            let (done, latest) = py.detach(|| {
                let Ok(g) = shared.lock() else { return (true, None) };
                let Ok((mut g, _)) = wake.wait_timeout_while(g, POLL, |g| !g.done) else { return (true, None) };
                (g.done, g.progress.take())
            });
            if done {
                break;
            }
            if raised.is_none() {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
            if let (Some(p), Some(callback), None) = (latest, progress, &raised) {
                if let Err(e) = callback.call1((p.decided, p.processed, p.pending)) {
                    cancel.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
        }
        match worker.join() {
            Ok(Ok(out)) => Ok(out),
            Ok(Err(p)) | Err(p) => Err(internal(py, panic_text(p.as_ref()))),
        }
    })?;
    match raised {
        Some(e) => Err(e),
        None => Ok(outcome),
    }
}

/// Prepares `job` against `input` and runs it within `bounds`, supervised.
pub(crate) fn run(py: Python<'_>, input: &Input, source: &str, job: Job, bounds: RunBounds, progress: Option<Bound<'_, PyAny>>) -> PyResult<NativeAnswer> {
    let verb = match job {
        Job::Solve(_) | Job::Distances(_) | Job::LoopSingularities(_) => "building",
        _ => "loading",
    };
    let start = Instant::now();
    let prepared = py.detach(|| catch_unwind(AssertUnwindSafe(|| app::prepare(input, job)))).map_err(|p| internal(py, panic_text(p.as_ref())))?;
    let prepared = prepared.map_err(|e| job_error(py, verb, source, &e))?;
    let notice = prepared.notice().map(str::to_string);
    let (answer, ran) = supervise(py, progress.as_ref(), |cancel, report| {
        let control = Control { limits: bounds.limits, threads: bounds.threads, cancel };
        let answer = prepared.run(&control, &mut |p: &Progress| report(*p));
        (answer, start.elapsed())
    })?;
    let answer = answer.map_err(|e| job_error(py, "analysing", source, &e))?;
    Ok(NativeAnswer { answer, notice, seconds: ran.as_secs_f64() })
}

/// An answer of the library, held for the Python result object built from it.
#[pyclass(frozen, module = "linkspace._native")]
pub struct NativeAnswer {
    answer: Answer,
    notice: Option<String>,
    seconds: f64,
}

#[pymethods]
impl NativeAnswer {
    /// The question's name, as the CLI's subcommand spells it.
    #[getter]
    fn name(&self) -> &'static str {
        self.answer.name()
    }

    /// What the CLI prints before such a run (a continuum of two or more dimensions to
    /// cover), if anything.
    #[getter]
    fn notice(&self) -> Option<&str> {
        self.notice.as_deref()
    }

    /// Seconds from the start of `app::prepare` to the end of `Prepared::run`, on the worker
    /// thread: the library's time, which the binding's overhead is measured against.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The JSON report, as the CLI's `--json` writes it (`edges::report::json`).
    fn json(&self, py: Python<'_>) -> PyResult<String> {
        let written = py.detach(|| {
            catch_unwind(AssertUnwindSafe(|| {
                let mut text = Vec::new();
                report::json(&self.answer, &mut text).map(|()| String::from_utf8(text).expect("invariant: serde_json writes UTF-8"))
            }))
        });
        written.map_err(|p| internal(py, panic_text(p.as_ref())))?.map_err(|e| internal(py, format!("writing the report: {e}")))
    }

    /// `(word, reason)`: `complete` and `None`, or `incomplete` and why (a limit's name,
    /// `undecided`, `near_degenerate`), by the one rule (`Answer::completeness`).
    fn completeness(&self) -> (&'static str, Option<&'static str>) {
        let c = self.answer.completeness();
        (c.word(), c.reason().map(|r| r.name()))
    }

    /// A solve answer's boxes as arrays, solution boxes first (the report's `solutions`, then
    /// its `undecided`): `columns` (free joints), `lo` and `hi` (n × columns), `variables`
    /// with `variables_lo` and `variables_hi` (n × variables, the raw boxes), `tags`,
    /// `clusters` (-1 for undecided boxes), `cluster_count`, `levels` and `mechanism`. `None`
    /// for other answers.
    fn solve_boxes<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Answer::Solve(a) = &self.answer else { return Ok(None) };
        let r = &a.result;
        let n = r.boxes.len();
        let array = |joints: bool, side: usize, cols: usize| {
            let v: Vec<f64> = r.boxes.iter().flat_map(|b| if joints { &b.joints } else { &b.bounds }).map(|iv| iv[side]).collect();
            PyArray1::from_vec(py, v).reshape([n, cols])
        };
        let (nj, nv) = (r.joint_names.len(), r.variables.len());
        let d = PyDict::new(py);
        d.set_item("mechanism", &r.mechanism)?;
        d.set_item("cluster_count", r.clusters)?;
        d.set_item("columns", &r.joint_names)?;
        d.set_item("lo", array(true, 0, nj)?)?;
        d.set_item("hi", array(true, 1, nj)?)?;
        d.set_item("variables", &r.variables)?;
        d.set_item("variables_lo", array(false, 0, nv)?)?;
        d.set_item("variables_hi", array(false, 1, nv)?)?;
        d.set_item("tags", r.boxes.iter().map(|b| b.status.name()).collect::<Vec<_>>())?;
        d.set_item("clusters", PyArray1::from_vec(py, r.boxes.iter().map(|b| b.cluster.map_or(-1, |c| c as i64)).collect()))?;
        d.set_item("levels", PyArray1::from_vec(py, r.boxes.iter().map(|b| i64::from(b.level)).collect()))?;
        Ok(Some(d))
    }
}

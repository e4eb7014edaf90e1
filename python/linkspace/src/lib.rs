//! `linkspace._native`: the extension module under the Python package `linkspace`. It
//! translates only, as the CLI does: keyword arguments become a `Job` (`options`), the job goes
//! through the front door (`app::prepare`, `Prepared::run`) on a thread of its own while the
//! calling thread watches for Ctrl-C (`run`), and the `Answer` comes back as its JSON report
//! (`edges::report::json`, the CLI's `--json`) plus, for box sets, numpy arrays. The typed
//! Python objects are built from those by the pure-Python package.

mod options;
mod run;
mod sweep;

use linkspace::app::{self, Input, Job};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A Python exception of the package (`linkspace._errors`) with `message`.
pub(crate) fn error(py: Python<'_>, class: &str, message: String) -> PyErr {
    match py.import("linkspace._errors").and_then(|m| m.getattr(class)).and_then(|c| c.call1((message.clone(),))) {
        Ok(e) => PyErr::from_value(e),
        // The package is not importable (the module loaded on its own): a plain error still
        // carries the message.
        Err(_) => pyo3::exceptions::PyRuntimeError::new_err(message),
    }
}

/// `InputError` with `message`: the request or the file is wrong.
pub(crate) fn input_error(py: Python<'_>, message: String) -> PyErr {
    error(py, "InputError", message)
}

/// A loaded input: a mechanism read from URDF, or a distance file.
#[pyclass(frozen, module = "linkspace._native")]
pub struct Model {
    pub(crate) input: Input,
    /// How the CLI names the input in its messages: the file's path, or the robot's name.
    pub(crate) source: String,
}

#[pymethods]
impl Model {
    /// How messages name the input.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// True for a distance file (only `distances` reads it).
    #[getter]
    fn is_distance_file(&self) -> bool {
        matches!(self.input, Input::DistanceFile(_))
    }

    /// The links, joints and loops, as a dict (`app::describe`); `None` for a distance file.
    fn describe<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Input::Mechanism(m) = &self.input else { return Ok(None) };
        let info = app::describe(m);
        let d = PyDict::new(py);
        d.set_item("name", &info.name)?;
        d.set_item("links", &info.links)?;
        d.set_item("actuated", &info.actuated)?;
        let joints = info
            .joints
            .iter()
            .map(|j| {
                let e = PyDict::new(py);
                e.set_item("name", &j.name)?;
                e.set_item("type", j.kind)?;
                e.set_item("limits", j.limits)?;
                e.set_item("parent", &j.parent)?;
                e.set_item("child", &j.child)?;
                e.set_item("axis", j.axis)?;
                e.set_item("mimic", j.mimic.clone())?;
                Ok(e)
            })
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("joints", joints)?;
        let loops = info
            .loops
            .iter()
            .map(|l| {
                let e = PyDict::new(py);
                e.set_item("name", &l.name)?;
                e.set_item("type", l.kind)?;
                e.set_item("predecessor", &l.predecessor)?;
                e.set_item("successor", &l.successor)?;
                e.set_item("limits", l.limits)?;
                Ok(e)
            })
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("loops", loops)?;
        Ok(Some(d))
    }

    /// The node's view of the mechanism (`app::questions`): kind,
    /// services, free joints and, when it is outside every analysis, why.
    fn analysis<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let Input::Mechanism(m) = &self.input else {
            d.set_item("kind", "distance_problem")?;
            d.set_item("services", vec!["distances"])?;
            d.set_item("free_joints", Vec::<String>::new())?;
            d.set_item("limitation", "a distance file: only distances reads it")?;
            return Ok(d);
        };
        let q = run::guarded(py, || app::questions(m))?;
        d.set_item("kind", q.kind)?;
        d.set_item("services", q.services)?;
        d.set_item("free_joints", q.free_joints)?;
        d.set_item("limitation", q.limitation)?;
        Ok(d)
    }

    /// Runs the question `job` (its CLI name) with `options` (the keyword arguments), calling
    /// `progress(decided, processed, pending)` from this thread now and then.
    #[pyo3(signature = (job, options, progress=None))]
    fn run(&self, py: Python<'_>, job: &str, options: &Bound<'_, PyDict>, progress: Option<Bound<'_, PyAny>>) -> PyResult<run::NativeAnswer> {
        let (job, control) = options::job(py, job, &self.input, options)?;
        run::run(py, &self.input, &self.source, job, control, progress)
    }
}

/// Reads `text` (URDF, or a distance file when it is not XML and `name` does not end in
/// `.urdf`), naming it `source` in messages.
#[pyfunction]
fn load(py: Python<'_>, name: &str, text: &str, source: &str) -> PyResult<Model> {
    let input = run::guarded(py, || Input::read(name, text))?.map_err(|e| input_error(py, format!("loading {source}: {e}")))?;
    Ok(Model { input, source: source.to_string() })
}

/// A job's defaults by its CLI name: precision, max_boxes and max_memory (MiB), as the CLI
/// takes them when no flag is given.
#[pyfunction]
fn defaults<'py>(py: Python<'py>, job: &str) -> PyResult<Bound<'py, PyDict>> {
    let limits = Job::default_limits(job);
    let d = PyDict::new(py);
    d.set_item("precision", Job::default_precision(job))?;
    d.set_item("max_boxes", limits.max_cells)?;
    d.set_item("max_memory", limits.max_memory >> 20)?;
    Ok(d)
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_class::<run::NativeAnswer>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

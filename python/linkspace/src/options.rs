//! Keyword arguments into a `Job` and its bounds, as the CLI turns its flags into them
//! (`src/cli.rs`, `src/cli/*.rs`): the same names (snake case), the same defaults (the job's
//! `Job::default_precision` and `Job::default_limits`, and the CLI's literals, which the Python
//! signatures repeat) and the same one-line complaints.

use crate::input_error;
use linkspace::app::{self, ChainSpec, CollisionsJob, DistanceFormulation, DistancesJob, FaceBounds, Ik6Job, SelfMotionJob, IkJob, IkPoint, Input, Job, LegValues, Limits, ArmOptions, LoopQuestion, LoopSingularitiesJob, LpBackend, ModelChoice, MotionSpan, Output, PathCheckJob, PathSet, PoseInput, SingularKind, SingularitiesJob, SolveJob};
use numpy::{PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyMapping};
use std::time::Duration;

/// The bounds of one run: what `app::Control` takes besides the cancel flag.
pub(crate) struct RunBounds {
    pub(crate) limits: Limits,
    pub(crate) threads: usize,
}

/// The keyword arguments of one call; a key that is absent or `None` is not given.
struct Opts<'a, 'py> {
    py: Python<'py>,
    d: &'a Bound<'py, PyDict>,
}

impl<'py> Opts<'_, 'py> {
    fn get(&self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        Ok(self.d.get_item(key)?.filter(|v| !v.is_none()))
    }

    fn typed<T: for<'a> FromPyObject<'a, 'py>>(&self, key: &str, what: &str) -> PyResult<Option<T>> {
        match self.get(key)? {
            None => Ok(None),
            Some(v) => v.extract::<T>().map(Some).map_err(|_| PyTypeError::new_err(format!("{key}: expected {what}, got {}", v.get_type().name().map_or_else(|_| "?".into(), |n| n.to_string())))),
        }
    }

    fn f64(&self, key: &str) -> PyResult<Option<f64>> {
        self.typed::<f64>(key, "a number")
    }

    fn f64_or(&self, key: &str, default: f64) -> PyResult<f64> {
        Ok(self.f64(key)?.unwrap_or(default))
    }

    fn flag(&self, key: &str) -> PyResult<bool> {
        Ok(self.typed::<bool>(key, "True or False")?.unwrap_or(false))
    }

    fn string(&self, key: &str) -> PyResult<Option<String>> {
        self.typed::<String>(key, "a string")
    }

    /// One of `choices` (the CLI's value names), or `default`.
    fn choice(&self, key: &str, choices: &[&'static str], default: &'static str) -> PyResult<&'static str> {
        match self.string(key)? {
            None => Ok(default),
            Some(s) => choices.iter().copied().find(|c| *c == s).ok_or_else(|| input_error(self.py, format!("{key} '{s}': expected one of {}", choices.join(", ")))),
        }
    }

    /// Names as a list of strings or one comma-separated string (as the CLI's flag takes them).
    fn names(&self, key: &str, flag: &str) -> PyResult<Option<Vec<String>>> {
        let Some(v) = self.get(key)? else { return Ok(None) };
        let names: Vec<String> = match v.extract::<String>() {
            Ok(s) => s.split(',').map(|x| x.trim().to_string()).collect(),
            Err(_) => v.extract::<Vec<String>>().map_err(|_| PyTypeError::new_err(format!("{key}: expected a list of names")))?,
        };
        if names.iter().any(|x| x.is_empty()) {
            return Err(input_error(self.py, format!("{flag} '{}': expected joint names separated by commas", names.join(","))));
        }
        Ok(Some(names))
    }

    /// `{name: value}` pairs in the mapping's order (`--fix NAME=VALUE`, repeated).
    fn fixes(&self, key: &str) -> PyResult<Vec<(String, f64)>> {
        let Some(v) = self.get(key)? else { return Ok(Vec::new()) };
        let map = v.cast::<PyMapping>().map_err(|_| PyTypeError::new_err(format!("{key}: expected a dict of name to value")))?;
        let mut out = Vec::new();
        for item in map.items()?.iter() {
            let (name, value): (String, Bound<'py, PyAny>) = item.extract().map_err(|_| PyTypeError::new_err(format!("{key}: expected a dict of name to value")))?;
            let value: f64 = value.extract().map_err(|_| PyTypeError::new_err(format!("{key}: the value of '{name}' is not a number")))?;
            out.push((name.trim().to_string(), value));
        }
        Ok(out)
    }

    /// Numbers of any array-like (flattened in row-major order).
    fn numbers(&self, key: &str) -> PyResult<Option<Vec<f64>>> {
        match self.get(key)? {
            None => Ok(None),
            Some(v) => {
                let a: PyReadonlyArrayDyn<'py, f64> = v.extract().map_err(|_| PyTypeError::new_err(format!("{key}: expected an array of numbers")))?;
                Ok(Some(a.as_array().iter().copied().collect()))
            }
        }
    }
}

/// The job and bounds of `name` (the CLI's subcommand) from `options`.
pub(crate) fn job(py: Python<'_>, name: &str, input: &Input, options: &Bound<'_, PyDict>) -> PyResult<(Job, RunBounds)> {
    let o = Opts { py, d: options };
    let precision = o.f64_or("precision", Job::default_precision(name))?;
    let job = match name {
        "solve" => solve(&o, precision)?,
        "singularities" => singularities(&o, precision)?,
        "ik" => Job::Ik(IkJob { arm: chain(&o)?, uncertainty: o.f64_or("uncertainty", 0.0)?, point: ik_point(&o)?, precision }),
        "ik6" => ik6(&o, precision)?,
        "self-motion" => self_motion(&o, precision)?,
        "path-check" => path_check(&o, precision)?,
        "collisions" => Job::Collisions(CollisionsJob { arm: chain(&o)?, precision }),
        "distances" => distances(&o, precision)?,
        "loop-singularities" => loop_singularities(&o, input, precision)?,
        other => return Err(input_error(py, format!("no question '{other}'"))),
    };
    Ok((job, bounds(&o, name)?))
}

/// `LimitArgs::limits`: the job's defaults where nothing is given.
fn bounds(o: &Opts<'_, '_>, name: &str) -> PyResult<RunBounds> {
    let default = Job::default_limits(name);
    let max_cells = match o.typed::<u64>("max_boxes", "a whole number")? {
        Some(0) => return Err(input_error(o.py, "--max-boxes must be at least 1".into())),
        Some(n) => n,
        None => default.max_cells,
    };
    let max_memory = match o.typed::<u64>("max_memory", "a whole number of MiB")? {
        Some(0) => return Err(input_error(o.py, "--max-memory must be at least 1 MiB".into())),
        Some(mib) => usize::try_from(mib.saturating_mul(1 << 20)).unwrap_or(usize::MAX),
        None => default.max_memory,
    };
    let timeout = match o.f64("timeout")? {
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t.min(1e9))),
        Some(t) => return Err(input_error(o.py, format!("--timeout must be a positive number of seconds, got {t}"))),
        None => None,
    };
    let threads = match o.typed::<u64>("threads", "a whole number")? {
        None => 1,
        Some(n @ 1..=1024) => n as usize,
        Some(n) => return Err(input_error(o.py, format!("invalid value '{n}' for '--threads <THREADS>': {n} is not in 1..=1024"))),
    };
    Ok(RunBounds { limits: Limits { max_cells, timeout, max_memory }, threads })
}

/// `ChainArgs::options`: how an arm's file becomes the analysed chain.
fn chain(o: &Opts<'_, '_>) -> PyResult<ArmOptions> {
    let tip_point = match o.string("tip_point")? {
        None => None,
        Some(text) => {
            let bad = || input_error(o.py, format!("--tip-point '{text}': X,Y,Z must be three numbers"));
            let (link, xyz) = text.split_once('@').ok_or_else(|| input_error(o.py, format!("--tip-point '{text}': expected LINK@X,Y,Z")))?;
            let v: Vec<f64> = xyz.split(',').map(|t| t.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
            let [x, y, z] = v.as_slice() else { return Err(bad()) };
            Some((link.to_string(), [*x, *y, *z]))
        }
    };
    let exact_geometry = o.flag("exact_geometry")?;
    let snap_tolerance = o.f64("snap_tolerance")?;
    if exact_geometry && snap_tolerance.is_some() {
        return Err(input_error(o.py, "the argument '--exact-geometry' cannot be used with '--snap-tolerance <RAD>'".into()));
    }
    let spec = ChainSpec { base: o.string("base")?, tip: o.string("tip")?, tip_point, locks: o.fixes("fix")?, length_tolerance: 0.0 };
    Ok(ArmOptions { spec, exact_geometry, snap_tolerance: snap_tolerance.unwrap_or(app::SNAP_TOLERANCE), ignore_limits: o.flag("ignore_limits")? })
}

/// `--trace LINK@X,Y[,Z]`: the link, the point (z = 0 for two numbers) and the name as written.
fn trace(o: &Opts<'_, '_>, s: &str) -> PyResult<(String, [f64; 3], String)> {
    let shape = || input_error(o.py, format!("--trace '{s}': expected LINK@X,Y or LINK@X,Y,Z"));
    let (link, xy) = s.split_once('@').ok_or_else(shape)?;
    let parts: Vec<&str> = xy.split(',').collect();
    if !(parts.len() == 2 || parts.len() == 3) {
        return Err(shape());
    }
    let mut p = [0.0f64; 3];
    for (k, t) in parts.iter().enumerate() {
        p[k] = t.trim().parse().map_err(|_| input_error(o.py, format!("--trace '{s}': '{t}' is not a number")))?;
    }
    if !p.iter().all(|v| v.is_finite()) {
        return Err(input_error(o.py, format!("--trace '{s}': coordinates must be finite")));
    }
    Ok((link.to_string(), p, s.to_string()))
}

fn solve(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let base = SolveJob::default();
    let traces = o.typed::<Vec<String>>("trace", "a list of LINK@X,Y[,Z] strings")?.unwrap_or_default().iter().map(|s| trace(o, s)).collect::<PyResult<Vec<_>>>()?;
    let model = match o.choice("model", &["auto", "planar", "spatial", "pose", "distances"], "auto")? {
        "planar" => ModelChoice::Planar,
        "spatial" => ModelChoice::Spatial,
        "pose" => ModelChoice::Pose,
        "distances" => ModelChoice::Distances,
        _ => ModelChoice::Auto,
    };
    let lp_backend = if o.choice("lp", &["simplex", "clarabel"], "simplex")? == "clarabel" { LpBackend::Clarabel } else { LpBackend::Simplex };
    Ok(Job::Solve(SolveJob {
        fixed: o.fixes("fix")?,
        traces,
        model,
        precision,
        rho: o.f64_or("rho", base.rho)?,
        use_lp: !o.flag("no_lp")?,
        newton_width: o.f64_or("newton_width", base.newton_width)?,
        lp_backend,
    }))
}

fn singularities(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let kind = o.choice("kind", &["all", "cusps", "nodes"], "all")?;
    let nodes = o.flag("nodes")?;
    if kind == "cusps" && nodes {
        return Err(input_error(o.py, "--kind cusps searches no nodes: drop --nodes, or give --kind nodes".into()));
    }
    Ok(Job::Singularities(SingularitiesJob {
        arm: chain(o)?,
        uncertainty: o.f64_or("uncertainty", 0.0)?,
        precision,
        nodes: nodes || kind == "nodes",
        verdict: kind == "all",
        search_anyway: o.flag("search_anyway")?,
        arm_budget: o.f64_or("arm_budget", 2.0)?,
    }))
}

/// `--point`: X,Y,Z in the root frame, or R,Z in the first joint's frame.
fn ik_point(o: &Opts<'_, '_>) -> PyResult<IkPoint> {
    let values = o.numbers("point")?.ok_or_else(|| PyTypeError::new_err("ik: a point is needed"))?;
    match values.as_slice() {
        [x, y, z] => Ok(IkPoint::Root([*x, *y, *z])),
        [radius, z] => Ok(IkPoint::HalfSection { radius: *radius, z: *z }),
        _ => Err(input_error(o.py, format!("--point {values:?}: expected X,Y,Z (root frame) or R,Z (distance from the first axis, height along it)"))),
    }
}

fn ik6(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let values = o.numbers("pose")?.ok_or_else(|| PyTypeError::new_err("ik6: a pose is needed"))?;
    let pose = PoseInput::from_numbers(&values).map_err(|e| input_error(o.py, format!("--pose {values:?}: {e}")))?;
    Ok(Job::Ik6(Ik6Job { arm: chain(o)?, pose, precision }))
}

fn self_motion(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let values = o.numbers("pose")?.ok_or_else(|| PyTypeError::new_err("self_motion: a pose is needed"))?;
    let pose = PoseInput::from_numbers(&values).map_err(|e| input_error(o.py, format!("--pose {values:?}: {e}")))?;
    let range = match o.numbers("range")?.as_deref() {
        None => None,
        Some([lo, hi]) => Some((*lo, *hi)),
        Some(other) => return Err(input_error(o.py, format!("--range {other:?}: expected two numbers (lo, hi)"))),
    };
    let cell = o.f64_or("cell", 0.002)?;
    Ok(Job::SelfMotion(SelfMotionJob { arm: chain(o)?, pose, parameter: o.string("parameter")?, range, cell, precision }))
}

fn path_check(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let waypoints = match o.get("waypoints")? {
        None => return Err(PyTypeError::new_err("path_check: waypoints are needed")),
        Some(v) => {
            let a: PyReadonlyArray2<'_, f64> = v.extract().map_err(|_| PyTypeError::new_err("waypoints: expected a 2-D array of joint values, one row per waypoint"))?;
            a.as_array().rows().into_iter().map(|r| r.to_vec()).collect()
        }
    };
    let set = match o.choice("singular_set", &["6r", "3r", "auto"], "auto")? {
        "6r" => Some(PathSet::Arm6R),
        "3r" => Some(PathSet::Positioning3R),
        _ => None,
    };
    let joint_names = o.names("joint_names", "joint_names")?.unwrap_or_default();
    Ok(Job::PathCheck(PathCheckJob { arm: chain(o)?, waypoints, joint_names, set, precision }))
}

fn distances(o: &Opts<'_, '_>, precision: f64) -> PyResult<Job> {
    let formulation = match o.choice("formulation", &["auto", "points", "line", "shared", "split"], "auto")? {
        "points" => DistanceFormulation::Points,
        "line" => DistanceFormulation::Line,
        "shared" => DistanceFormulation::Shared,
        "split" => DistanceFormulation::Split,
        _ => DistanceFormulation::Auto,
    };
    let faces = if o.choice("faces", &["corners", "interval"], "corners")? == "corners" { FaceBounds::Corners } else { FaceBounds::IntervalArithmetic };
    // Squared leg lengths, as `linkspace distances --fix` takes them.
    Ok(Job::Distances(DistancesJob { fixed: o.fixes("fix")?, legs: LegValues::Squared, precision, rho: o.f64("rho")?, redundant: o.flag("redundant")?, formulation, faces }))
}

/// `--output LINK@X,Y` or joints `J1,J2`.
fn output(o: &Opts<'_, '_>) -> PyResult<Option<Output>> {
    let Some(v) = o.get("output")? else { return Ok(None) };
    let text: Option<String> = v.extract().ok();
    if let Some(s) = text.as_deref().filter(|s| s.contains('@')) {
        let (link, xy) = s.split_once('@').expect("has @");
        let shape = || input_error(o.py, format!("--output '{s}': expected LINK@X,Y with finite coordinates"));
        let (x, y) = xy.split_once(',').ok_or_else(shape)?;
        let (x, y): (f64, f64) = (x.trim().parse().map_err(|_| shape())?, y.trim().parse().map_err(|_| shape())?);
        if !(x.is_finite() && y.is_finite()) || link.trim().is_empty() {
            return Err(shape());
        }
        return Ok(Some(Output::Point { link: link.trim().to_string(), x, y }));
    }
    Ok(o.names("output", "--output")?.map(Output::Joints))
}

fn loop_singularities(o: &Opts<'_, '_>, input: &Input, precision: f64) -> PyResult<Job> {
    let fixed = o.fixes("fix")?;
    let kinds = ["cspace", "input", "output", "all", "image", "cusps", "nodes", "motion"];
    let question = match o.choice("kind", &kinds, "all")? {
        "cspace" => LoopQuestion::Sets(vec![SingularKind::Cspace]),
        "input" => LoopQuestion::Sets(vec![SingularKind::Input]),
        "output" => LoopQuestion::Sets(vec![SingularKind::Output]),
        "image" => LoopQuestion::Image { grid: o.typed::<usize>("grid", "a whole number")?.unwrap_or(128) },
        "cusps" => LoopQuestion::Cusps,
        "nodes" => LoopQuestion::Nodes,
        "motion" => {
            let (Some(from), Some(to), Some(assembly)) = (o.f64("from_")?, o.f64("to")?, o.numbers("assembly")?) else {
                let joints = input.mechanism().ok().and_then(|m| app::motion_joints(m, &fixed).ok()).map(|j| j.join(", ")).unwrap_or_default();
                return Err(input_error(o.py, format!("--kind motion needs --from A --to B --assembly Q1,Q2,... (the free joints: {joints})")));
            };
            LoopQuestion::Motion(MotionSpan { from, to, assembly, max_step: o.f64_or("max_step", 0.05)?, min_step: o.f64_or("min_step", 1e-6)? })
        }
        _ => LoopQuestion::Sets(Vec::new()),
    };
    Ok(Job::LoopSingularities(LoopSingularitiesJob { question, actuated: o.names("actuated", "--actuated")?, output: output(o)?, fixed, precision }))
}

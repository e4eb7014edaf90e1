//! Design-space sweeps: one analysis run over a grid (or a list) of design parameters of a
//! mechanism, each design an independent task with its own limits.
//!
//! `spec` reads the sweep file into a `Plan`; `Plan::tasks` expands it (cartesian product or the
//! listed tuples, bounded); `apply` edits a parsed `Mechanism` (joint and loop origins) and
//! collects the `fix` values, so no file is rewritten or parsed twice; `run_tasks` runs tasks on
//! threads and hands each result to one writer as it finishes; `records` is the results' format
//! (JSON lines, CSV, summary) and the resume check; `chart` draws the map as SVG text. The
//! analyses themselves are `app::sweep`'s.

mod chart;
mod records;
mod run;
mod spec;

pub use chart::map_svg;
pub use records::{csv, fingerprint, read_done, Header, Summary, TaskResult, TaskStatus};
pub use run::run_tasks;
pub use spec::{parse, MAX_STEPS};

use crate::model::{Mechanism, ModelError};
use thiserror::Error;

/// The default bound on the number of tasks of one sweep.
pub const DEFAULT_MAX_TASKS: usize = 100_000;

/// What is wrong with a sweep, in one line.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SweepError {
    /// A field of the spec file.
    #[error("sweep spec, {field}: {problem}")]
    Spec {
        /// the field, e.g. `parameters[1].steps`
        field: String,
        /// what is wrong with it
        problem: String,
    },
    /// The grid is larger than allowed.
    #[error("the sweep has {tasks} tasks, more than the {max} allowed (--max-tasks)")]
    TooManyTasks {
        /// tasks of the spec (saturated)
        tasks: u128,
        /// the bound
        max: usize,
    },
    /// A parameter does not fit the mechanism (unknown joint, a fix on a fixed joint...).
    #[error("parameter '{param}': {problem}")]
    Parameter {
        /// the parameter as written
        param: String,
        /// what is wrong
        problem: String,
    },
    /// An edited origin is not a valid pose.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The results file to resume from belongs to another sweep or is damaged.
    #[error("cannot resume: {0}")]
    Resume(String),
}

/// One design parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Parameter {
    /// A coordinate of a tree joint's origin: `joint.NAME.xyz.I` or `joint.NAME.rpy.I`.
    JointOrigin {
        /// joint name
        joint: String,
        /// roll, pitch, yaw rather than x, y, z
        rpy: bool,
        /// 0, 1 or 2
        axis: usize,
    },
    /// A coordinate of a loop closure frame: `loop.NAME.predecessor.xyz.I` (or `successor`, `rpy`).
    LoopOrigin {
        /// loop name
        closure: String,
        /// the successor's frame rather than the predecessor's
        successor: bool,
        /// roll, pitch, yaw rather than x, y, z
        rpy: bool,
        /// 0, 1 or 2
        axis: usize,
    },
    /// A joint value the analysis holds fixed (`--fix JOINT=VALUE`): `fix.JOINT`.
    Fix {
        /// joint or loop name
        joint: String,
    },
}

impl Parameter {
    /// Reads `joint.NAME.xyz.I`, `joint.NAME.rpy.I`, `loop.NAME.predecessor.xyz.I`,
    /// `loop.NAME.successor.rpy.I`, `fix.JOINT` (names may contain dots).
    pub fn parse(text: &str) -> Result<Self, String> {
        let expected = "expected joint.NAME.xyz.I, joint.NAME.rpy.I, loop.NAME.predecessor.xyz.I (successor, rpy) or fix.JOINT";
        let coordinate = |rest: &str| -> Option<(String, bool, usize)> {
            let (rest, axis) = rest.rsplit_once('.')?;
            let axis = match axis {
                "0" => 0,
                "1" => 1,
                "2" => 2,
                _ => return None,
            };
            let (name, part) = rest.rsplit_once('.')?;
            let rpy = match part {
                "xyz" => false,
                "rpy" => true,
                _ => return None,
            };
            (!name.is_empty()).then(|| (name.to_string(), rpy, axis))
        };
        if let Some(joint) = text.strip_prefix("fix.") {
            if joint.is_empty() {
                return Err(format!("'{text}': {expected}"));
            }
            return Ok(Parameter::Fix { joint: joint.to_string() });
        }
        if let Some(rest) = text.strip_prefix("joint.") {
            let (joint, rpy, axis) = coordinate(rest).ok_or_else(|| format!("'{text}': {expected}"))?;
            return Ok(Parameter::JointOrigin { joint, rpy, axis });
        }
        if let Some(rest) = text.strip_prefix("loop.") {
            let (name, rpy, axis) = coordinate(rest).ok_or_else(|| format!("'{text}': {expected}"))?;
            let (closure, successor) = if let Some(c) = name.strip_suffix(".predecessor") {
                (c, false)
            } else if let Some(c) = name.strip_suffix(".successor") {
                (c, true)
            } else {
                return Err(format!("'{text}': {expected}"));
            };
            return Ok(Parameter::LoopOrigin { closure: closure.to_string(), successor, rpy, axis });
        }
        Err(format!("'{text}': {expected}"))
    }

    /// As written in a spec.
    pub fn text(&self) -> String {
        let part = |rpy: bool| if rpy { "rpy" } else { "xyz" };
        match self {
            Parameter::JointOrigin { joint, rpy, axis } => format!("joint.{joint}.{}.{axis}", part(*rpy)),
            Parameter::LoopOrigin { closure, successor, rpy, axis } => format!("loop.{closure}.{}.{}.{axis}", if *successor { "successor" } else { "predecessor" }, part(*rpy)),
            Parameter::Fix { joint } => format!("fix.{joint}"),
        }
    }
}

/// Which analysis each task runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sweep {
    /// The 3R arm's cuspidality verdict (`app::singularities`), cusps at this precision.
    Cuspidality {
        /// radians
        precision: f64,
    },
    /// The assembly modes of a closed-loop mechanism with its `fix` values (`app::SolveRun`).
    AssemblyModes {
        /// solution box width
        sigma: f64,
    },
}

impl Sweep {
    /// The name in the spec and the results.
    pub fn name(self) -> &'static str {
        match self {
            Sweep::Cuspidality { .. } => "cuspidality",
            Sweep::AssemblyModes { .. } => "assembly_modes",
        }
    }
}

/// Limits of each task as the spec gives them (the front end fills in its defaults).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TaskLimits {
    /// Seconds.
    pub timeout: Option<f64>,
    /// Boxes processed.
    pub max_boxes: Option<u64>,
    /// MiB of pending boxes.
    pub max_memory_mib: Option<u64>,
}

/// A checked sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The URDF path as written (relative to the spec file).
    pub urdf: String,
    /// The analysis of each task.
    pub analysis: Sweep,
    /// Varied parameters: label and target, in spec order.
    pub parameters: Vec<(String, Parameter)>,
    /// Values of each parameter (empty when `tuples` lists the tasks).
    pub axes: Vec<Vec<f64>>,
    /// Explicit tasks, one value per parameter each.
    pub tuples: Option<Vec<Vec<f64>>>,
    /// Parameters held at one value in every task.
    pub constants: Vec<(Parameter, f64)>,
    /// Per-task limits from the spec.
    pub limits: TaskLimits,
    /// Indices of the map's x and y parameters, when the spec names them.
    pub map: Option<[usize; 2]>,
}

/// One design: its index in the sweep and a value per parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    /// Position in the expansion (row-major: the last parameter varies fastest).
    pub index: usize,
    /// One value per `Plan::parameters`.
    pub values: Vec<f64>,
}

impl Plan {
    /// Number of tasks, saturating.
    pub fn task_count(&self) -> u128 {
        match &self.tuples {
            Some(t) => t.len() as u128,
            None => self.axes.iter().fold(1u128, |n, a| n.saturating_mul(a.len() as u128)),
        }
    }

    /// Every task, or `TooManyTasks` (counted before anything is expanded).
    pub fn tasks(&self, max_tasks: usize) -> Result<Vec<Task>, SweepError> {
        let n = self.task_count();
        if n > max_tasks as u128 {
            return Err(SweepError::TooManyTasks { tasks: n, max: max_tasks });
        }
        if let Some(t) = &self.tuples {
            return Ok(t.iter().enumerate().map(|(index, v)| Task { index, values: v.clone() }).collect());
        }
        let n = n as usize;
        let mut tasks = Vec::with_capacity(n);
        for index in 0..n {
            let mut rest = index;
            let mut values = vec![0.0; self.axes.len()];
            for (k, axis) in self.axes.iter().enumerate().rev() {
                values[k] = axis[rest % axis.len()];
                rest /= axis.len();
            }
            tasks.push(Task { index, values });
        }
        Ok(tasks)
    }

    /// The map's two parameters: the spec's choice, else the first two.
    pub fn map_axes(&self) -> Option<[usize; 2]> {
        self.map.or((self.parameters.len() >= 2).then_some([0, 1]))
    }
}

/// The mechanism of one task: `base` with the constants and the task's values applied to
/// joint and loop origins, and the `fix` values (constants first) for the analysis.
pub fn apply(base: &Mechanism, plan: &Plan, task: &Task) -> Result<(Mechanism, Vec<(String, f64)>), SweepError> {
    let mut m = base.clone();
    let mut fixed: Vec<(String, f64)> = Vec::new();
    let edits = plan.constants.iter().map(|(p, v)| (p, *v)).chain(plan.parameters.iter().map(|(_, p)| p).zip(task.values.iter().copied()));
    for (param, value) in edits {
        let unknown = |what: &str| SweepError::Parameter { param: param.text(), problem: format!("the mechanism has no {what}") };
        match param {
            Parameter::JointOrigin { joint, rpy, axis } => {
                let j = m.joint(joint).ok_or_else(|| unknown(&format!("joint '{joint}'")))?;
                let mut xyz: [f64; 3] = m.joints[j].origin.translation.vector.into();
                let mut angles = m.joints[j].rpy;
                if *rpy { angles[*axis] = value } else { xyz[*axis] = value }
                m.set_joint_origin(j, xyz, angles)?;
            }
            Parameter::LoopOrigin { closure, successor, rpy, axis } => {
                let l = m.loops.iter().position(|l| l.name == *closure).ok_or_else(|| unknown(&format!("loop '{closure}'")))?;
                let c = &m.loops[l];
                let (origin, angles) = if *successor { (&c.successor_origin, c.successor_rpy) } else { (&c.predecessor_origin, c.predecessor_rpy) };
                let (mut xyz, mut angles): ([f64; 3], [f64; 3]) = (origin.translation.vector.into(), angles);
                if *rpy { angles[*axis] = value } else { xyz[*axis] = value }
                m.set_loop_origin(l, *successor, xyz, angles)?;
            }
            Parameter::Fix { joint } => {
                if m.joint(joint).is_none() && !m.loops.iter().any(|l| l.name == *joint) {
                    return Err(unknown(&format!("joint or loop '{joint}'")));
                }
                match fixed.iter_mut().find(|(n, _)| n == joint) {
                    Some(f) => f.1 = value,
                    None => fixed.push((joint.clone(), value)),
                }
            }
        }
    }
    Ok((m, fixed))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ARM: &str = r#"{"urdf": "arm.urdf", "analysis": "cuspidality",
        "parameters": [{"param": "joint.joint3.xyz.0", "label": "d3", "from": 1, "to": 2, "steps": 3},
                       {"param": "joint.tool_joint.xyz.0", "label": "d4", "values": [0.5, 1.5]}],
        "constants": {"joint.joint3.xyz.1": 0.25}}"#;

    #[test]
    fn a_grid_expands_row_major_and_edits_the_origins() {
        let plan = parse(ARM).expect("valid");
        let tasks = plan.tasks(100).expect("small");
        assert_eq!(tasks.len(), 6);
        assert_eq!(tasks[1].values, vec![1.0, 1.5]);
        assert_eq!(tasks[2].values, vec![1.5, 0.5]);
        let m = crate::model::urdf::parse(include_str!("../../../urdf/orthogonal_3r_a.urdf")).expect("bundled");
        let (edited, fixed) = apply(&m, &plan, &tasks[5]).expect("applies");
        assert!(fixed.is_empty());
        let t = |name: &str| edited.joints[edited.joint(name).expect("joint")].origin.translation.vector;
        assert_eq!((t("joint3").x, t("joint3").y, t("tool_joint").x), (2.0, 0.25, 1.5));
        assert!(matches!(plan.tasks(5), Err(SweepError::TooManyTasks { tasks: 6, max: 5 })));
        let grid = parse(r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "from": 0.3, "to": 2.7, "steps": 5}]}"#).expect("valid");
        assert_eq!(grid.axes[0], vec![0.3, 0.9, 1.5, 2.1, 2.7], "the decimals of the grid");
    }

    #[test]
    fn bad_specs_name_the_field() {
        let cases = [
            (r#"{"urdf": "a", "analysis": "x", "parameters": []}"#, "analysis"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": []}"#, "parameters"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "joint.j.abc.0", "values": [1]}]}"#, "parameters[0].param"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "from": 1, "to": 2, "steps": 0}]}"#, "parameters[0].steps"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "from": 1, "to": 2}]}"#, "parameters[0]"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "from": 1, "to": 2, "steps": 1000000000000}]}"#, "parameters[0].steps"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "values": [1]}], "tuples": [[1, 2]]}"#, "parameters[0]"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j"}], "tuples": [[1, 2]]}"#, "tuples[0]"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "values": [1]}], "limits": {"timeout": -1}}"#, "limits.timeout"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "values": [1]}], "bogus": 1}"#, "bogus"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "values": [1], "step": 2}]}"#, "parameters[0]"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "from": 1, "to": 2, "steps": -3}]}"#, "parameters[0]"),
            (r#"{"urdf": 3, "analysis": "cuspidality", "parameters": []}"#, "urdf"),
            (r#"{"analysis": "cuspidality", "parameters": []}"#, "urdf"),
            (r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "fix.j", "values": [1]}], "limits": {"max_boxes": "many"}}"#, "limits"),
            (r#"[1, 2]"#, "(file)"),
            (r#"{"urdf": "a", "#, "(file)"),
        ];
        for (text, field) in cases {
            let e = parse(text).expect_err(text).to_string();
            assert!(e.starts_with(&format!("sweep spec, {field}:")) && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn parameters_read_back_as_written() {
        for text in ["joint.a.b.xyz.2", "joint.j.rpy.0", "loop.b2.predecessor.xyz.1", "loop.l.successor.rpy.2", "fix.rho1"] {
            assert_eq!(Parameter::parse(text).expect(text).text(), text);
        }
        for text in ["joint.j.xyz.3", "joint..xyz.0", "loop.l.xyz.0", "fix.", "link.a.xyz.0"] {
            assert!(Parameter::parse(text).is_err(), "{text}");
        }
    }

    #[test]
    fn loop_frames_angles_and_fixed_values_are_applied() {
        let plan = parse(
            r#"{"urdf": "a", "analysis": "assembly_modes",
                "parameters": [{"param": "loop.b2.predecessor.xyz.0", "values": [18]}, {"param": "joint.a2_joint.rpy.2", "values": [0.5]}, {"param": "fix.rho1", "values": [9]}],
                "constants": {"fix.rho3": 12}}"#,
        )
        .expect("valid");
        let m = crate::model::urdf::parse(include_str!("../../../urdf/three_rpr.urdf")).expect("bundled");
        let (edited, fixed) = apply(&m, &plan, &plan.tasks(10).expect("one")[0]).expect("applies");
        let b2 = edited.loops.iter().position(|l| l.name == "b2").expect("loop");
        assert_eq!(edited.loops[b2].predecessor_origin.translation.vector.x, 18.0);
        assert_eq!(edited.loops[b2].successor_origin, m.loops[b2].successor_origin, "the other side is left alone");
        let a2 = &edited.joints[edited.joint("a2_joint").expect("joint")];
        assert_eq!((a2.rpy, a2.origin.translation.vector.x), ([0.0, 0.0, 0.5], 15.91));
        assert!((a2.origin.rotation.euler_angles().2 - 0.5).abs() < 1e-15);
        // Constants first, then the task's values.
        assert_eq!(fixed, vec![("rho3".to_string(), 12.0), ("rho1".to_string(), 9.0)]);
    }

    #[test]
    fn unknown_joints_are_named() {
        let plan = parse(r#"{"urdf": "a", "analysis": "cuspidality", "parameters": [{"param": "joint.nope.xyz.0", "values": [1]}]}"#).expect("valid");
        let m = crate::model::urdf::parse(include_str!("../../../urdf/orthogonal_3r_a.urdf")).expect("bundled");
        let e = apply(&m, &plan, &plan.tasks(10).expect("one")[0]).expect_err("unknown").to_string();
        assert_eq!(e, "parameter 'joint.nope.xyz.0': the mechanism has no joint 'nope'");
    }
}

//! The sweep file (JSON): what to vary, over which values, and which analysis to run on each
//! design. Read once and checked into a `Plan`; every error names the field at fault.

use super::{Parameter, Plan, Sweep, SweepError, TaskLimits};
use serde::de::DeserializeOwned;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The file as written (README "Design sweeps" documents each field).
#[derive(Debug)]
struct SpecFile {
    /// The URDF, relative to the spec file's directory.
    urdf: String,
    /// `cuspidality` or `assembly_modes`.
    analysis: String,
    /// The varied parameters: each a range or a list of values.
    parameters: Vec<ParameterFile>,
    /// Explicit tasks, one value per parameter each, instead of the cartesian product.
    tuples: Option<Vec<Vec<f64>>>,
    /// Parameters held at one value in every task.
    constants: BTreeMap<String, f64>,
    /// Cusp search precision (radians), for `cuspidality`.
    precision: Option<f64>,
    /// Solution box width, for `assembly_modes`.
    sigma: Option<f64>,
    /// Limits of each task.
    limits: LimitsFile,
    /// Which two parameters the map shows (default: the first two).
    map: Option<[String; 2]>,
}

/// The spec's fields.
const FIELDS: [&str; 9] = ["urdf", "analysis", "parameters", "tuples", "constants", "precision", "sigma", "limits", "map"];

impl SpecFile {
    /// Reads the file field by field, so that a value of the wrong type is named by its field.
    fn read(text: &str) -> Result<Self, SweepError> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| bad("(file)", e.to_string()))?;
        let serde_json::Value::Object(map) = value else { return Err(bad("(file)", "expected a JSON object")) };
        if let Some(k) = map.keys().find(|k| !FIELDS.contains(&k.as_str())) {
            return Err(bad(k.as_str(), format!("unknown field; expected one of {}", FIELDS.join(", "))));
        }
        fn get<T: DeserializeOwned>(map: &serde_json::Map<String, serde_json::Value>, name: &str) -> Result<Option<T>, SweepError> {
            map.get(name).map(|v| serde_json::from_value(v.clone()).map_err(|e| bad(name, e.to_string()))).transpose()
        }
        let parameters: Vec<serde_json::Value> = get(&map, "parameters")?.ok_or_else(|| bad("parameters", "missing"))?;
        let parameters = parameters
            .into_iter()
            .enumerate()
            .map(|(k, v)| serde_json::from_value(v).map_err(|e| bad(format!("parameters[{k}]"), e.to_string())))
            .collect::<Result<_, _>>()?;
        Ok(Self {
            urdf: get(&map, "urdf")?.ok_or_else(|| bad("urdf", "missing"))?,
            analysis: get(&map, "analysis")?.ok_or_else(|| bad("analysis", "missing"))?,
            parameters,
            tuples: get(&map, "tuples")?,
            constants: get(&map, "constants")?.unwrap_or_default(),
            precision: get(&map, "precision")?,
            sigma: get(&map, "sigma")?,
            limits: get(&map, "limits")?.unwrap_or_default(),
            map: get(&map, "map")?,
        })
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct ParameterFile {
    /// What is varied: `joint.NAME.xyz.I`, `joint.NAME.rpy.I`, `loop.NAME.predecessor.xyz.I`
    /// (or `successor`, `rpy`), `fix.JOINT`.
    param: String,
    /// Column and axis name; default `param`.
    #[serde(default)]
    label: Option<String>,
    #[serde(default)]
    from: Option<f64>,
    #[serde(default)]
    to: Option<f64>,
    #[serde(default)]
    steps: Option<u64>,
    #[serde(default)]
    values: Option<Vec<f64>>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct LimitsFile {
    timeout: Option<f64>,
    max_boxes: Option<u64>,
    max_memory: Option<u64>,
}

/// The most values one range may list.
pub const MAX_STEPS: u64 = 10_000_000;

fn bad(field: impl Into<String>, problem: impl Into<String>) -> SweepError {
    SweepError::Spec { field: field.into(), problem: problem.into() }
}

/// Reads a spec's text into a checked plan (`urdf` is left relative: the caller resolves it).
pub fn parse(text: &str) -> Result<Plan, SweepError> {
    let file = SpecFile::read(text)?;
    let analysis = match file.analysis.as_str() {
        "cuspidality" => Sweep::Cuspidality { precision: file.precision.unwrap_or(1e-4) },
        "assembly_modes" => Sweep::AssemblyModes { sigma: file.sigma.unwrap_or(1e-3) },
        other => return Err(bad("analysis", format!("'{other}': expected cuspidality or assembly_modes"))),
    };
    match analysis {
        Sweep::Cuspidality { precision } if !(precision > 0.0 && precision < 1.0) => return Err(bad("precision", format!("{precision}: must lie in (0, 1)"))),
        Sweep::AssemblyModes { sigma } if !(sigma > 0.0 && sigma.is_finite()) => return Err(bad("sigma", format!("{sigma}: must be positive"))),
        _ => {}
    }
    if file.sigma.is_some() && matches!(analysis, Sweep::Cuspidality { .. }) {
        return Err(bad("sigma", "is for assembly_modes; cuspidality takes precision"));
    }
    if file.precision.is_some() && matches!(analysis, Sweep::AssemblyModes { .. }) {
        return Err(bad("precision", "is for cuspidality; assembly_modes takes sigma"));
    }
    if file.parameters.is_empty() {
        return Err(bad("parameters", "list at least one parameter"));
    }
    let mut parameters = Vec::new();
    let mut axes = Vec::new();
    for (k, p) in file.parameters.iter().enumerate() {
        let field = format!("parameters[{k}]");
        let target = Parameter::parse(&p.param).map_err(|problem| bad(format!("{field}.param"), problem))?;
        let label = p.label.clone().unwrap_or_else(|| p.param.clone());
        if parameters.iter().any(|(l, _): &(String, Parameter)| *l == label) {
            return Err(bad(format!("{field}.label"), format!("'{label}' names two parameters")));
        }
        if parameters.iter().any(|(_, t)| *t == target) {
            return Err(bad(format!("{field}.param"), format!("'{}' is varied twice", p.param)));
        }
        let values = match (&p.values, p.from, p.to, p.steps) {
            (Some(_), Some(_), _, _) | (Some(_), _, Some(_), _) | (Some(_), _, _, Some(_)) => return Err(bad(&field, "give either values or from, to, steps")),
            (Some(v), None, None, None) if file.tuples.is_none() => {
                if v.is_empty() {
                    return Err(bad(format!("{field}.values"), "is empty"));
                }
                v.clone()
            }
            (None, Some(from), Some(to), Some(steps)) if file.tuples.is_none() => {
                if !(from.is_finite() && to.is_finite()) {
                    return Err(bad(&field, "from and to must be finite"));
                }
                match steps {
                    0 => return Err(bad(format!("{field}.steps"), "must be at least 1")),
                    // Values are listed when the spec is read, before the task count is bounded.
                    n if n > MAX_STEPS => return Err(bad(format!("{field}.steps"), format!("{n}: at most {MAX_STEPS}"))),
                    1 if from != to => return Err(bad(format!("{field}.steps"), "1 step needs from = to")),
                    1 => vec![from],
                    // Rounded to 12 significant digits: the decimals a user reads in the grid
                    // (0.9, not 0.9000000000000001), which the results and a resume key on.
                    n => (0..n).map(|i| from + (to - from) * i as f64 / (n - 1) as f64).map(|v| format!("{v:.11e}").parse().unwrap_or(v)).collect(),
                }
            }
            (None, None, None, None) if file.tuples.is_some() => Vec::new(),
            _ if file.tuples.is_some() => return Err(bad(&field, "with tuples, a parameter takes only param and label")),
            _ => return Err(bad(&field, "give values, or from, to and steps")),
        };
        if let Some(x) = values.iter().find(|x| !x.is_finite()) {
            return Err(bad(format!("{field}.values"), format!("{x} is not finite")));
        }
        parameters.push((label, target));
        axes.push(values);
    }
    let mut constants = Vec::new();
    for (param, value) in &file.constants {
        let target = Parameter::parse(param).map_err(|problem| bad(format!("constants.{param}"), problem))?;
        if !value.is_finite() {
            return Err(bad(format!("constants.{param}"), "is not finite"));
        }
        if parameters.iter().any(|(_, t)| *t == target) {
            return Err(bad(format!("constants.{param}"), "is also varied"));
        }
        constants.push((target, *value));
    }
    let tuples = match file.tuples {
        None => None,
        Some(t) => {
            if t.is_empty() {
                return Err(bad("tuples", "is empty"));
            }
            for (k, row) in t.iter().enumerate() {
                if row.len() != parameters.len() {
                    return Err(bad(format!("tuples[{k}]"), format!("has {} values for {} parameters", row.len(), parameters.len())));
                }
                if row.iter().any(|x| !x.is_finite()) {
                    return Err(bad(format!("tuples[{k}]"), "a value is not finite"));
                }
            }
            Some(t)
        }
    };
    let l = &file.limits;
    if let Some(t) = l.timeout.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(bad("limits.timeout", format!("{t}: must be a positive number of seconds")));
    }
    if l.max_boxes == Some(0) {
        return Err(bad("limits.max_boxes", "must be at least 1"));
    }
    if l.max_memory == Some(0) {
        return Err(bad("limits.max_memory", "must be at least 1 MiB"));
    }
    let limits = TaskLimits { timeout: l.timeout, max_boxes: l.max_boxes, max_memory_mib: l.max_memory };
    let map = match file.map {
        None => None,
        Some([x, y]) => {
            let find = |name: &str| parameters.iter().position(|(l, _)| l == name).ok_or_else(|| bad("map", format!("'{name}' is not a parameter label")));
            let (i, j) = (find(&x)?, find(&y)?);
            if i == j {
                return Err(bad("map", "names one parameter twice"));
            }
            Some([i, j])
        }
    };
    if file.urdf.trim().is_empty() {
        return Err(bad("urdf", "is empty"));
    }
    Ok(Plan { urdf: file.urdf, analysis, parameters, axes, tuples, constants, limits, map })
}

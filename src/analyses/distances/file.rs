//! The JSON format for pure distance problems (schema in README, "Distance problems"), read into
//! a `DistanceProblem`. Parses text; opens no files.
//!
//! ```json
//! {
//!   "name": "four_spheres",
//!   "points": [{"name": "c1", "xyz": [1, 1, 1]}, {"name": "t"}],
//!   "distances": [{"between": ["c1", "t"], "squared": 2.1025},
//!                 {"between": ["c2", "t"], "range": [0, 20]},
//!                 {"between": ["c1", "u"], "name": "leg1"}],
//!   "point_line": [{"point": "c2", "line": ["t", "u"], "squared": 2.1025}],
//!   "orient": [{"segment": ["t", "u"], "toward": "c2"}],
//!   "equations": [["c1", "c2", "c3", "c4", "t"]],
//!   "redundant": [["c1", "c2", "c3", "c4", "t", "u"]],
//!   "lines": [["t", "u"]]
//! }
//! ```

use crate::formulate::cayley_menger::{DistanceError, DistanceProblem, Orientation};
use crate::kernel::interval::{interval, point};
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    name: String,
    points: Vec<PointSpec>,
    #[serde(default)]
    distances: Vec<DistanceSpec>,
    #[serde(default)]
    point_line: Vec<PointLineSpec>,
    #[serde(default)]
    orient: Vec<OrientSpec>,
    equations: Option<Vec<Vec<String>>>,
    redundant: Option<Vec<Vec<String>>>,
    #[serde(default)]
    lines: Vec<[String; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointSpec {
    name: String,
    xyz: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DistanceSpec {
    between: [String; 2],
    squared: Option<f64>,
    range: Option<[f64; 2]>,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointLineSpec {
    point: String,
    line: [String; 2],
    squared: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OrientSpec {
    segment: [String; 2],
    toward: String,
}

/// Parses a distance file; `fixed` gives values (squared) to distances named in the file, like
/// the legs of a platform. A named distance without a value must be fixed.
///
/// # Examples
///
/// ```
/// use linkspace::analyses::distances::file as distance_file;
/// let text = r#"{"points": [{"name": "a", "xyz": [0,0,0]}, {"name": "b", "xyz": [1,0,0]},
///                {"name": "c", "xyz": [0,1,0]}, {"name": "d"}],
///                "distances": [{"between": ["a","d"], "squared": 1}, {"between": ["b","d"], "name": "bd"}]}"#;
/// let p = distance_file::parse(text, &[("bd".to_string(), 2.0)]).unwrap();
/// assert_eq!(p.points.len(), 4);
/// ```
pub fn parse(text: &str, fixed: &[(String, f64)]) -> Result<DistanceProblem, DistanceError> {
    let file: File = serde_json::from_str(text).map_err(|e| DistanceError::Naming(format!("malformed distance file: {e}")))?;
    let mut p = DistanceProblem::new(if file.name.is_empty() { "distances".to_string() } else { file.name });
    for pt in &file.points {
        p.add_point(pt.name.clone(), pt.xyz)?;
    }
    let names: Vec<String> = file.points.iter().map(|q| q.name.clone()).collect();
    let find = |name: &str| names.iter().position(|n| n == name).ok_or_else(|| DistanceError::Naming(format!("unknown point '{name}'")));
    let mut used = vec![false; fixed.len()];
    for d in &file.distances {
        let (a, b) = (find(&d.between[0])?, find(&d.between[1])?);
        let given = match &d.name {
            Some(n) => fixed.iter().position(|(m, _)| m == n).map(|k| {
                used[k] = true;
                fixed[k].1
            }),
            None => None,
        };
        match (given.or(d.squared), d.range) {
            (Some(_), Some(_)) => return Err(DistanceError::BadValue { what: format!("distance {}-{}", d.between[0], d.between[1]), problem: "give either a squared value or a range, not both".into() }),
            (Some(v), None) => {
                if !v.is_finite() {
                    return Err(DistanceError::BadValue { what: format!("distance {}-{}", d.between[0], d.between[1]), problem: "not a finite number".into() });
                }
                p.set_known(a, b, point(v))?
            }
            (None, Some([lo, hi])) => {
                if !(lo <= hi) {
                    return Err(DistanceError::BadValue { what: format!("distance {}-{}", d.between[0], d.between[1]), problem: format!("range [{lo}, {hi}] is inverted") });
                }
                p.set_range(a, b, interval(lo, hi))?
            }
            (None, None) => {
                if let Some(n) = &d.name {
                    return Err(DistanceError::Underdetermined { unknowns: 1, detail: format!("distance '{n}' has no value: fix it with --fix {n}=VALUE") });
                }
            }
        }
    }
    if let Some(k) = used.iter().position(|u| !u) {
        return Err(DistanceError::Naming(format!("--fix: no distance named '{}'", fixed[k].0)));
    }
    for pl in &file.point_line {
        if !(pl.squared.is_finite() && pl.squared >= 0.0) {
            return Err(DistanceError::BadValue { what: format!("point_line {}", pl.point), problem: "squared distance must be a nonnegative finite number".into() });
        }
        p.add_point_line(find(&pl.point)?, find(&pl.line[0])?, find(&pl.line[1])?, point(pl.squared))?;
    }
    for o in &file.orient {
        p.orientations.push(Orientation { a: find(&o.segment[0])?, b: find(&o.segment[1])?, toward: find(&o.toward)? });
    }
    let sets = |list: &Option<Vec<Vec<String>>>| -> Result<Option<Vec<Vec<usize>>>, DistanceError> {
        list.as_ref().map(|l| l.iter().map(|s| s.iter().map(|n| find(n)).collect::<Result<Vec<_>, _>>()).collect::<Result<Vec<_>, _>>()).transpose()
    };
    p.equations = sets(&file.equations)?;
    p.redundant = sets(&file.redundant)?;
    for [a, b] in &file.lines {
        let line = (find(a)?, find(b)?);
        p.lines.push(line);
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_problem() {
        let base = r#"{"points": [{"name": "a"}, {"name": "b"}], "distances": [DIST]}"#;
        let cases = [
            (r#"{"between": ["a", "zz"], "squared": 1}"#, "unknown point 'zz'"),
            (r#"{"between": ["a", "b"], "squared": -1}"#, "positive"),
            (r#"{"between": ["a", "b"], "squared": 1, "range": [0, 2]}"#, "not both"),
            (r#"{"between": ["a", "b"], "range": [2, 1]}"#, "inverted"),
            (r#"{"between": ["a", "b"], "name": "leg"}"#, "--fix leg=VALUE"),
            (r#"{"between": ["a", "b"], "colour": 1}"#, "malformed"),
        ];
        for (dist, needle) in cases {
            let err = parse(&base.replace("DIST", dist), &[]).expect_err(dist).to_string();
            assert!(err.contains(needle), "{err} should mention {needle}");
        }
        let err = parse(&base.replace("DIST", r#"{"between": ["a", "b"], "squared": 1}"#), &[("x".into(), 1.0)]).unwrap_err().to_string();
        assert!(err.contains("no distance named 'x'"), "{err}");
    }
}

//! The results of a sweep as written: one JSON line per finished task after a header line
//! (`results.jsonl`, appended as tasks finish), the table as CSV, a summary; and the check that
//! lets an interrupted sweep resume (same spec, same URDF, tasks keyed by index and values).

use super::{Plan, SweepError, Task};
use crate::kernel::outcome::{Completeness, Incompleteness};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How a task ended: its analysis ran, complete or not (`limit` says why not), or it could
/// not run. Written as `complete`, `incomplete` or `failed`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskStatus {
    /// The analysis ran; complete by the one rule, or open (`TaskResult::limit` names why).
    Ran(Completeness),
    /// It could not run (bad geometry, an error); `error` says why.
    Failed,
}

impl TaskStatus {
    /// As in the records.
    pub fn name(self) -> &'static str {
        match self {
            TaskStatus::Ran(c) => c.word(),
            TaskStatus::Failed => "failed",
        }
    }
}

impl Serialize for TaskStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for TaskStatus {
    /// The reason of an incomplete task is its record's `limit`, read by `TaskResult::completeness`.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let word = String::deserialize(deserializer)?;
        if word == TaskStatus::Failed.name() {
            return Ok(TaskStatus::Failed);
        }
        if word == Completeness::Complete.word() {
            return Ok(TaskStatus::Ran(Completeness::Complete));
        }
        if word == Completeness::Incomplete(Incompleteness::Undecided).word() {
            return Ok(TaskStatus::Ran(Completeness::Incomplete(Incompleteness::Undecided)));
        }
        Err(serde::de::Error::custom(format!("unknown task status '{word}'")))
    }
}

/// One finished task: a line of `results.jsonl`, a row of the CSV.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct TaskResult {
    /// The task's index in the expansion.
    pub index: usize,
    /// Its parameter values, in the header's order.
    pub values: Vec<f64>,
    /// How it ended.
    pub status: TaskStatus,
    /// Why it is incomplete: the limit that stopped it (`boxes`, `time`, `memory`...), else
    /// `undecided` (boxes or cusps left without a proof).
    #[serde(default)]
    pub limit: Option<String>,
    /// `cuspidal`, `non_cuspidal` or `undecided` (cuspidality); none for assembly modes.
    #[serde(default)]
    pub verdict: Option<String>,
    /// What is counted: certified cusps, or assembly modes (solution clusters).
    #[serde(default)]
    pub count: Option<u64>,
    /// Boxes proven to hold exactly one solution (cusps, configurations).
    pub proven: u64,
    /// Boxes left undecided.
    pub undecided: u64,
    /// Why it failed.
    #[serde(default)]
    pub error: Option<String>,
    /// Wall-clock seconds of the task.
    pub seconds: f64,
}

impl TaskResult {
    /// Whether the task's answer is complete: its status, with the reason its record names.
    /// A task that failed decided nothing: it is incomplete, everything in it undecided.
    pub fn completeness(&self) -> Completeness {
        match self.status {
            TaskStatus::Ran(Completeness::Complete) => Completeness::Complete,
            TaskStatus::Ran(c) => Completeness::Incomplete(self.limit.as_deref().and_then(Incompleteness::from_name).or(c.reason()).unwrap_or(Incompleteness::Undecided)),
            TaskStatus::Failed => Completeness::Incomplete(Incompleteness::Undecided),
        }
    }

    /// A task that could not run.
    pub fn failed(task: &Task, error: String, seconds: f64) -> Self {
        Self { index: task.index, values: task.values.clone(), status: TaskStatus::Failed, limit: None, verdict: None, count: None, proven: 0, undecided: 0, error: Some(error), seconds }
    }
}

/// The first line of `results.jsonl`: which sweep the lines belong to.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct Header {
    /// Hash of the spec's content and of the URDF's text (`fingerprint`).
    pub fingerprint: String,
    /// The analysis.
    pub analysis: String,
    /// Parameter labels, the order of every line's `values`.
    pub parameters: Vec<String>,
    /// Number of tasks.
    pub tasks: usize,
}

/// The header line's wrapper: `{"sweep": {...}}`, so it is never read as a result.
#[derive(Serialize, Deserialize)]
struct HeaderLine {
    sweep: Header,
}

impl Header {
    /// The header of `plan` over `tasks`, with the URDF's text.
    pub fn new(plan: &Plan, urdf_text: &str, tasks: usize) -> Self {
        Self { fingerprint: fingerprint(plan, urdf_text), analysis: plan.analysis.name().to_string(), parameters: plan.parameters.iter().map(|(l, _)| l.clone()).collect(), tasks }
    }

    /// The line to write first (without newline).
    pub fn line(&self) -> String {
        serde_json::to_string(&HeaderLine { sweep: self.clone() }).unwrap_or_default()
    }
}

/// A stable hash (FNV-1a, 64 bits) of what decides the results: analysis and its setting,
/// parameters, values, constants, and the URDF's text. Limits, threads and the map are not in
/// it: a sweep may resume with other limits.
pub fn fingerprint(plan: &Plan, urdf_text: &str) -> String {
    let mut text = format!("{}|{:?}|", plan.analysis.name(), plan.analysis);
    for (label, p) in &plan.parameters {
        text.push_str(&format!("{label}={};", p.text()));
    }
    for axis in &plan.axes {
        text.push_str(&format!("{:?};", axis.iter().map(|v| v.to_bits()).collect::<Vec<_>>()));
    }
    for row in plan.tuples.iter().flatten() {
        text.push_str(&format!("{:?};", row.iter().map(|v| v.to_bits()).collect::<Vec<_>>()));
    }
    for (p, v) in &plan.constants {
        text.push_str(&format!("{}={};", p.text(), v.to_bits()));
    }
    text.push('|');
    text.push_str(urdf_text);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The results already in a `results.jsonl` text, checked against `header` and `tasks`.
///
/// Refuses (one line) a file of another sweep (header, fingerprint, a task's values differ) or a
/// damaged line before the last; a damaged last line (the sweep was stopped while writing it) is
/// dropped, so its task runs again. A task listed twice keeps its first result.
pub fn read_done(text: &str, header: &Header, tasks: &[Task]) -> Result<Vec<TaskResult>, SweepError> {
    let lines: Vec<(usize, &str)> = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()).collect();
    let Some(&(_, first)) = lines.first() else { return Ok(Vec::new()) };
    let found: Header = serde_json::from_str::<HeaderLine>(first).map(|h| h.sweep).map_err(|_| SweepError::Resume("the results file does not start with a sweep header".into()))?;
    if found.fingerprint != header.fingerprint || found.parameters != header.parameters || found.analysis != header.analysis || found.tasks != header.tasks {
        return Err(SweepError::Resume(format!(
            "the spec or the URDF changed since the results were written (fingerprint {} there, {} now); use another --out, or remove the results to start again",
            found.fingerprint, header.fingerprint
        )));
    }
    let mut done: BTreeMap<usize, TaskResult> = BTreeMap::new();
    let last = lines.len() - 1;
    for (k, &(n, line)) in lines.iter().enumerate().skip(1) {
        let r: TaskResult = match serde_json::from_str(line) {
            Ok(r) => r,
            Err(_) if k == last => continue,
            Err(e) => return Err(SweepError::Resume(format!("line {} of the results file is not a result ({e})", n + 1))),
        };
        let same = tasks.get(r.index).is_some_and(|t| t.values.len() == r.values.len() && t.values.iter().zip(&r.values).all(|(a, b)| a.to_bits() == b.to_bits()));
        if !same {
            return Err(SweepError::Resume(format!("line {} holds task {} with values {:?}, which this spec does not have", n + 1, r.index, r.values)));
        }
        done.entry(r.index).or_insert(r);
    }
    Ok(done.into_values().collect())
}

/// A CSV field: quoted when it holds a comma, quote or newline.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The table: one row per result (in index order), a column per parameter.
pub fn csv(labels: &[String], results: &[TaskResult]) -> String {
    let mut out = String::from("index");
    for l in labels {
        out.push(',');
        out.push_str(&field(l));
    }
    out.push_str(",status,limit,verdict,count,proven,undecided,seconds,error\n");
    let mut rows: Vec<&TaskResult> = results.iter().collect();
    rows.sort_by_key(|r| r.index);
    for r in rows {
        out.push_str(&r.index.to_string());
        for v in &r.values {
            out.push_str(&format!(",{v}"));
        }
        let opt = |s: &Option<String>| s.as_deref().map(field).unwrap_or_default();
        out.push_str(&format!(
            ",{},{},{},{},{},{},{:.6},{}\n",
            r.status.name(),
            opt(&r.limit),
            opt(&r.verdict),
            r.count.map(|c| c.to_string()).unwrap_or_default(),
            r.proven,
            r.undecided,
            r.seconds,
            opt(&r.error)
        ));
    }
    out
}

/// The summary of a sweep's results.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct Summary {
    /// The analysis.
    pub analysis: String,
    /// Parameter labels.
    pub parameters: Vec<String>,
    /// Tasks of the sweep.
    pub tasks: usize,
    /// Tasks with a result (this run and earlier ones).
    pub finished: usize,
    /// Tasks run by this invocation.
    pub run_now: usize,
    /// Results by status (`complete`, `incomplete`, `failed`).
    pub by_status: BTreeMap<String, usize>,
    /// Results by verdict (cuspidality) or by count (assembly modes; `undecided` when the count
    /// is not proven: a limit, or undecided boxes).
    pub by_outcome: BTreeMap<String, usize>,
    /// Sum of the tasks' seconds.
    pub task_seconds: f64,
    /// Wall-clock seconds of this invocation.
    pub wall_seconds: f64,
    /// Tasks run at a time.
    pub threads: usize,
}

impl Summary {
    /// Counts `results` (every finished task) of a sweep of `header`.
    pub fn of(header: &Header, results: &[TaskResult], run_now: usize, wall_seconds: f64, threads: usize) -> Self {
        let mut by_status = BTreeMap::new();
        let mut by_outcome = BTreeMap::new();
        for r in results {
            *by_status.entry(r.status.name().to_string()).or_insert(0) += 1;
            *by_outcome.entry(outcome(r)).or_insert(0) += 1;
        }
        Self {
            analysis: header.analysis.clone(),
            parameters: header.parameters.clone(),
            tasks: header.tasks,
            finished: results.len(),
            run_now,
            by_status,
            by_outcome,
            task_seconds: results.iter().map(|r| r.seconds).sum(),
            wall_seconds,
            threads,
        }
    }
}

/// What the map shows for a result: the verdict, or the count when it is proven, `failed`, or
/// `undecided`.
pub(super) fn outcome(r: &TaskResult) -> String {
    match (r.status, &r.verdict, r.count) {
        (TaskStatus::Failed, _, _) => "failed".into(),
        (_, Some(v), _) => v.clone(),
        (TaskStatus::Ran(Completeness::Complete), None, Some(c)) if r.undecided == 0 => c.to_string(),
        _ => "undecided".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Plan {
        super::super::parse(r#"{"urdf": "a", "analysis": "assembly_modes", "parameters": [{"param": "fix.r", "values": [1, 2, 3]}]}"#).expect("valid")
    }

    fn result(task: &Task) -> TaskResult {
        TaskResult { index: task.index, values: task.values.clone(), status: TaskStatus::Ran(Completeness::Complete), limit: None, verdict: None, count: Some(2), proven: 2, undecided: 0, error: None, seconds: 0.5 }
    }

    #[test]
    fn results_resume_only_on_the_same_sweep() {
        let p = plan();
        let tasks = p.tasks(10).expect("small");
        let header = Header::new(&p, "<robot/>", tasks.len());
        let line = |t: &Task| serde_json::to_string(&result(t)).expect("plain");
        // A damaged last line is dropped; its task runs again.
        let text = format!("{}\n{}\n{}\n{{\"index\": 2, \"val", header.line(), line(&tasks[0]), line(&tasks[1]));
        let done = read_done(&text, &header, &tasks).expect("same sweep");
        assert_eq!(done.iter().map(|r| r.index).collect::<Vec<_>>(), vec![0, 1]);
        assert_eq!(done[1], result(&tasks[1]));
        // Another URDF text: refused in one line.
        let other = Header::new(&p, "<robot name='x'/>", tasks.len());
        let e = read_done(&text, &other, &tasks).expect_err("changed").to_string();
        assert!(e.starts_with("cannot resume: the spec or the URDF changed") && !e.contains('\n'), "{e}");
        // A line whose values this spec does not have.
        let mut moved = result(&tasks[1]);
        moved.values = vec![2.5];
        let text = format!("{}\n{}\n{}\n", header.line(), serde_json::to_string(&moved).expect("plain"), line(&tasks[0]));
        assert!(read_done(&text, &header, &tasks).expect_err("moved").to_string().contains("task 1 with values [2.5]"));
    }

    #[test]
    fn csv_quotes_errors_and_sorts_rows() {
        let p = plan();
        let tasks = p.tasks(10).expect("small");
        let mut failed = TaskResult::failed(&tasks[0], "bad, \"very\"".into(), 0.0);
        failed.index = 0;
        let table = csv(&["r".into()], &[result(&tasks[1]), failed]);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines[0], "index,r,status,limit,verdict,count,proven,undecided,seconds,error");
        assert_eq!(lines[1], "0,1,failed,,,,0,0,0.000000,\"bad, \"\"very\"\"\"");
        assert_eq!(lines[2], "1,2,complete,,,2,2,0,0.500000,");
    }
}

//! Design sweeps: one job of this module per task of a `sweep::Plan`, each on its own edited
//! mechanism, single-threaded, within its own limits; `sweep::run_tasks` runs them side by side.
//!
//! A task that cannot run (the edited arm is degenerate, a leg length is out of its limits) is
//! a failed result, not an error: the sweep goes on.

use super::{singularities, Arm, SingularitiesRequest, SolveRun};
use crate::analyses::arm3r::LoadOptions;
use crate::model::Mechanism;
use crate::formulate::ModelChoice;
use crate::kernel::outcome::Completeness;
use crate::kernel::search::{BoxStatus, Control, Limit, Limits, SolverSettings, Status};
use crate::analyses::sweep::{self, Parameter, Plan, Sweep, SweepError, Task, TaskResult, TaskStatus};

use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Checks that `plan` fits `base` before any task runs: every parameter names a joint or loop
/// of the mechanism, and the analysis takes the kind of parameters given.
pub fn check_sweep(plan: &Plan, base: &Mechanism, tasks: &[Task]) -> Result<(), SweepError> {
    if let Sweep::Cuspidality { .. } = plan.analysis {
        let fix = plan.parameters.iter().map(|(_, p)| p).chain(plan.constants.iter().map(|(p, _)| p)).find(|p| matches!(p, Parameter::Fix { .. }));
        if let Some(p) = fix {
            return Err(SweepError::Parameter { param: p.text(), problem: "the cuspidality of an arm takes no fixed joints".into() });
        }
    }
    if let Some(first) = tasks.first() {
        sweep::apply(base, plan, first)?;
    }
    Ok(())
}

/// Runs one task of `plan` on `base` within `limits`, on the calling thread.
pub fn sweep_task(plan: &Plan, base: &Mechanism, task: &Task, limits: &Limits, cancel: &AtomicBool) -> TaskResult {
    let start = Instant::now();
    let failed = |e: String| TaskResult::failed(task, e, start.elapsed().as_secs_f64());
    let (mechanism, fixed) = match sweep::apply(base, plan, task) {
        Ok(m) => m,
        Err(e) => return failed(e.to_string()),
    };
    let control = Control { limits: *limits, threads: 1, cancel };
    let result = |status: Status, verdict: Option<String>, count: Option<u64>, proven: u64, undecided: u64| {
        // The one rule: a finished run with undecided boxes is incomplete too.
        let completeness = Completeness::of(status, undecided as usize, false);
        let (status, limit) = (TaskStatus::Ran(completeness), completeness.reason().map(|r| r.name().to_string()));
        TaskResult { index: task.index, values: task.values.clone(), status, limit, verdict, count, proven, undecided, error: None, seconds: start.elapsed().as_secs_f64() }
    };
    match plan.analysis {
        Sweep::Cuspidality { precision } => {
            let arm = match Arm::load(&mechanism, &LoadOptions::default(), 0.0) {
                Ok(a) => a,
                Err(e) => return failed(e.to_string()),
            };
            let request = SingularitiesRequest { precision, nodes: false, search_anyway: false, verdict: true };
            let found = match singularities(&arm, &request, &control, &mut |_| {}) {
                Ok(f) => f,
                Err(e) => return failed(e.to_string()),
            };
            let cusps = &found.run.cusps;
            let proven = cusps.cusps.iter().filter(|c| c.unique).count() as u64;
            let undecided = (cusps.cusps.len() as u64 - proven) + cusps.undecided.len() as u64;
            let cuspidal = found.verdict.as_ref().and_then(|v| v.cuspidal);
            let verdict = match cuspidal {
                Some(true) => "cuspidal",
                Some(false) => "non_cuspidal",
                None => "undecided",
            };
            // The verdict runs after the searches on what is left of the deadline: an undecided
            // verdict past the deadline was cut short, whatever the searches' status.
            let out_of_time = limits.timeout.is_some_and(|t| start.elapsed() >= t);
            let status = match found.run.status {
                Status::Finished if cuspidal.is_none() && out_of_time => Status::Stopped(Limit::Time),
                s => s,
            };
            result(status, Some(verdict.into()), Some(proven), proven, undecided)
        }
        Sweep::AssemblyModes { sigma } => {
            let settings = SolverSettings { sigma, max_boxes: limits.max_cells, timeout: limits.timeout, max_memory: limits.max_memory, threads: 1, ..SolverSettings::default() };
            let job = match SolveRun::build(&mechanism, ModelChoice::Auto, &fixed, &[], settings) {
                Ok(j) => j,
                Err(e) => return failed(e.to_string()),
            };
            let found = job.run(cancel, &mut |_| {});
            let proven = found.boxes.iter().filter(|b| b.status == BoxStatus::Unique).count() as u64;
            let undecided = found.boxes.iter().filter(|b| !b.status.is_solution()).count() as u64;
            result(found.status, None, Some(found.assembly_modes().len() as u64), proven, undecided)
        }
    }
}

/// One task through the front door, as every front end runs a sweep's tasks: `Job::SweepTask`
/// on the base mechanism `input`, within the task's `limits` on one thread. A task that cannot
/// be prepared or run is a failed row, not an error, so one bad grid point does not stop a sweep.
pub fn answer_task(input: &super::Input, plan: &Plan, task: &Task, limits: &Limits, cancel: &AtomicBool) -> TaskResult {
    let start = Instant::now();
    let job = super::Job::SweepTask(super::SweepTaskJob { plan: plan.clone(), task: task.clone() });
    let control = Control { limits: *limits, threads: 1, cancel };
    match super::prepare(input, job).and_then(|p| p.run(&control, &mut |_| {})) {
        Ok(super::Answer::SweepTask(r)) => *r,
        Ok(other) => TaskResult::failed(task, format!("internal error: a {} answer to a sweep task", other.name()), start.elapsed().as_secs_f64()),
        Err(e) => TaskResult::failed(task, e.to_string(), start.elapsed().as_secs_f64()),
    }
}

//! The task loop: tasks on threads of one process, each result handed to one writer as soon as
//! it finishes. Another way of distributing tasks (processes, ranks) replaces this function and
//! keeps `run_one` and `on_result` as they are.

use super::{Task, TaskResult};
use std::collections::HashSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

/// Runs every task of `tasks` whose index is not in `already_done`, `threads` at a time, with
/// `run_one`; `on_result` gets each result on the calling thread, in the order they finish.
///
/// A task that panics is recorded as failed and the others go on. When `on_result` fails (the
/// results cannot be written), no further task starts; the ones running finish, their results
/// are dropped, and the error is returned.
pub fn run_tasks<E>(
    tasks: &[Task],
    threads: usize,
    already_done: &HashSet<usize>,
    run_one: impl Fn(&Task) -> TaskResult + Sync,
    mut on_result: impl FnMut(TaskResult) -> Result<(), E>,
) -> Result<(), E> {
    let pending: Vec<&Task> = tasks.iter().filter(|t| !already_done.contains(&t.index)).collect();
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let (send, receive) = mpsc::channel::<TaskResult>();
    let workers = threads.clamp(1, pending.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..workers {
            let send = send.clone();
            let (pending, next, stop, run_one) = (&pending, &next, &stop, &run_one);
            scope.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let Some(task) = pending.get(next.fetch_add(1, Ordering::Relaxed)) else { break };
                    let start = Instant::now();
                    let result = catch_unwind(AssertUnwindSafe(|| run_one(task))).unwrap_or_else(|panic| {
                        let what = panic.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| panic.downcast_ref::<String>().cloned()).unwrap_or_default();
                        TaskResult::failed(task, format!("internal error: {what}"), start.elapsed().as_secs_f64())
                    });
                    if send.send(result).is_err() {
                        break;
                    }
                }
            });
        }
        drop(send);
        let mut outcome = Ok(());
        for result in receive {
            if outcome.is_ok() {
                if let Err(e) = on_result(result) {
                    stop.store(true, Ordering::Relaxed);
                    outcome = Err(e);
                }
            }
        }
        outcome
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyses::sweep::TaskStatus;

    fn tasks(n: usize) -> Vec<Task> {
        (0..n).map(|index| Task { index, values: vec![index as f64] }).collect()
    }

    fn ok(t: &Task) -> TaskResult {
        TaskResult { index: t.index, values: t.values.clone(), status: TaskStatus::Ran(crate::kernel::outcome::Completeness::Complete), limit: None, verdict: None, count: Some(t.index as u64), proven: 0, undecided: 0, error: None, seconds: 0.0 }
    }

    #[test]
    fn every_pending_task_runs_once_on_any_thread_count() {
        for threads in [1, 3, 16] {
            let done: HashSet<usize> = [2, 5].into_iter().collect();
            let mut seen = Vec::new();
            run_tasks::<()>(&tasks(10), threads, &done, ok, |r| {
                seen.push(r.index);
                Ok(())
            })
            .expect("no writer error");
            seen.sort_unstable();
            assert_eq!(seen, vec![0, 1, 3, 4, 6, 7, 8, 9], "{threads} threads");
        }
    }

    #[test]
    fn a_panicking_task_is_recorded_and_a_writer_error_stops_the_loop() {
        let run = |t: &Task| if t.index == 1 { panic!("boom") } else { ok(t) };
        let mut got = Vec::new();
        run_tasks::<()>(&tasks(3), 2, &HashSet::new(), run, |r| {
            got.push(r);
            Ok(())
        })
        .expect("no writer error");
        let failed = got.iter().find(|r| r.index == 1).expect("recorded");
        assert_eq!((failed.status, failed.error.as_deref()), (TaskStatus::Failed, Some("internal error: boom")));
        let mut written = 0;
        let e = run_tasks(&tasks(50), 1, &HashSet::new(), ok, |_| {
            written += 1;
            if written == 3 { Err("disk full") } else { Ok(()) }
        });
        assert_eq!((e, written), (Err("disk full"), 3));
    }
}

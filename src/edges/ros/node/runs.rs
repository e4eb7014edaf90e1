//! The life of a run: what it is for (`RunKind`), what it returns (`Outcome`), its start on a
//! thread of its own, its progress, and where its result goes when it ends (the mechanism's
//! topics, the replies waiting for it, the action goal it executes).
//!
//! The loop keeps every run in `State::runs` until it ends; a run of a mechanism analysed
//! again meanwhile (a newer generation) ends without a result. Nothing here decodes a request:
//! `requests` and `goals` check a request and prepare its work before a run starts.

use super::requests::singularity_reply;
use super::{panic_text, Event, RunState, Severity};
use crate::app::Completeness;
use crate::app::{BoxSetResult, IkResult, Service, SingularityQuery, SingularityResult};
use crate::edges::ros::convert;
use crate::edges::ros::msgs::{self, BoxSet, SolveActionResult, SolveFeedback, SolveGoal, SolveResponse};
use crate::app::{Limit, Status};
use ros2_client::action::{ExecutingGoalHandle, GoalEndStatus};
use ros2_client::log::LogLevel;
use ros2_client::RmwRequestId;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// What a run returns.
#[allow(clippy::large_enum_variant)] // one per run, moved once: not worth a Box
pub(super) enum Outcome {
    BoxSet(BoxSetResult),
    Singularities(SingularityResult),
    InverseKinematics(IkResult),
    /// A job run through the front door (`app::prepare`, `Prepared::run`).
    Answer(Result<crate::app::Answer, String>),
    /// Several jobs run in turn, each answer (or why it failed) in order.
    Answers(Vec<Result<crate::app::Answer, String>>),
}

impl Outcome {
    /// (boxes processed, boxes left pending, complete) for the final progress message.
    fn counts(&self) -> (u64, usize, bool) {
        match self {
            Outcome::BoxSet(r) => (r.stats.processed, r.boxes.iter().filter(|b| b.status == crate::app::BoxStatus::Undecided).count(), r.status == Status::Finished),
            Outcome::Singularities(r) => (r.processed, r.undecided(), r.status == Status::Finished),
            Outcome::InverseKinematics(r) => (r.processed, 0, r.status == Status::Finished),
            Outcome::Answer(a) => answer_counts(a),
            Outcome::Answers(all) => all.iter().map(answer_counts).fold((0, 0, true), |(p, q, c), (p1, q1, c1)| (p + p1, q + q1, c && c1)),
        }
    }
}

/// `Outcome::counts` of one front-door answer.
fn answer_counts(answer: &Result<crate::app::Answer, String>) -> (u64, usize, bool) {
    let Ok(a) = answer else { return (0, 0, false) };
    let (processed, pending) = match a {
        crate::app::Answer::Ik6(a) => (a.found.solutions.stats.processed, a.found.solutions.clusters.len()),
        crate::app::Answer::PathCheck(a) => (a.found.check.segments.len() as u64, 0),
        crate::app::Answer::Collisions(a) => (a.found.set.stats.processed, a.found.set.undecided.len()),
        crate::app::Answer::SelfMotion(a) => (a.set.stats.processed, a.set.boxes.len() - a.set.certified()),
        _ => (0, 0),
    };
    (processed, pending, a.completeness().is_complete())
}

/// A run's work, moved to its thread: its outcome, or why it failed (in one line).
pub(super) type Work = Box<dyn FnOnce(&AtomicBool, &mut dyn FnMut(&crate::app::Progress)) -> Result<Outcome, String> + Send>;

/// What a run is for, which decides where its result goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum RunKind {
    ConfigurationSpace,
    Solve,
    /// A goal of the Solve action: feedback is its progress, its result goes to the action.
    SolveAction,
    /// `load_time`: the run made at load, published on `~/<robot>/singularities`; otherwise a
    /// Singularities request with its own settings, answered in the reply only.
    Singularities { load_time: bool },
    InverseKinematics,
    InverseKinematics6,
    PathCheck,
    Collisions,
    SelfMotion,
}

impl RunKind {
    /// Runs started by a request, which count against `NodeLimits::max_runs`.
    pub(super) fn requested(self) -> bool {
        matches!(self, RunKind::Solve | RunKind::SolveAction | RunKind::Singularities { load_time: false } | RunKind::InverseKinematics | RunKind::InverseKinematics6 | RunKind::PathCheck | RunKind::Collisions | RunKind::SelfMotion)
    }

    /// The `analysis` field of its progress messages.
    pub(super) fn analysis(self) -> &'static str {
        match self {
            RunKind::ConfigurationSpace => "configuration_space",
            RunKind::Solve | RunKind::SolveAction => "solve",
            RunKind::Singularities { .. } => "singularities",
            RunKind::InverseKinematics => "inverse_kinematics",
            RunKind::InverseKinematics6 => "inverse_kinematics6",
            RunKind::PathCheck => "path_check",
            RunKind::Collisions => "collisions",
            RunKind::SelfMotion => "self_motion",
        }
    }
}

pub(super) struct Run {
    pub(super) mechanism: usize,
    /// The mechanism's generation when the run started: a run of a replaced mechanism (new
    /// robot_description, new settings) is dropped when it ends.
    pub(super) generation: u64,
    pub(super) kind: RunKind,
    pub(super) cancel: Arc<AtomicBool>,
    /// Requests waiting for this run (of the service its kind answers), with when to stop
    /// waiting.
    pub(super) waiters: Vec<(RmwRequestId, Instant)>,
    /// The latest share of the volume decided.
    pub(super) decided: f64,
    /// The action goal this run executes (`RunKind::SolveAction`).
    pub(super) goal: Option<ExecutingGoalHandle<SolveGoal>>,
}

impl super::State {
    /// Starts the load-time analyses of mechanism `k`.
    pub(super) fn start_load_time(&mut self, k: usize) {
        let a = &self.mechanisms[k].loaded.analysis;
        let cspace = a.configuration_space(&self.settings);
        let query = SingularityQuery { precision: self.precision, nodes: true, max_boxes: self.settings.max_boxes, timeout: self.settings.timeout, threads: self.settings.threads };
        let singular = a.singularities(&query);
        let mut started = false;
        match cspace {
            Ok(prepared) => {
                self.start(k, RunKind::ConfigurationSpace, Box::new(move |c, p| prepared.run(c, p).map(Outcome::BoxSet).map_err(|e| e.to_string())));
                started = true;
            }
            // An open chain has no configuration space to solve: that is not worth a warning.
            Err(e) => {
                let a = &self.mechanisms[k].loaded.analysis;
                let level = if a.services().contains(&Service::Solve) { LogLevel::Warn } else { LogLevel::Debug };
                self.log(level, format!("{}: no configuration space: {e}", a.mechanism()))
            }
        }
        match singular {
            Ok(prepared) => {
                let run = self.start(k, RunKind::Singularities { load_time: true }, Box::new(move |c, p| prepared.run(c, p).map(Outcome::Singularities).map_err(|e| e.to_string())));
                self.mechanisms[k].singularity_run = Some(run);
                started = true;
            }
            Err(e) => {
                // Said in list_mechanisms too, unless the kind has no singularity analysis at all.
                if self.mechanisms[k].loaded.analysis.services().contains(&Service::Singularities) {
                    self.mechanisms[k].singular_note = format!("no singularities: {}", convert::bounded(&e.to_string(), convert::ECHO_MESSAGE));
                }
                self.publish_no_singularities(k, e.to_string());
            }
        }
        let m = &mut self.mechanisms[k];
        if started {
            m.state = RunState::Running;
            m.message = m.singular_note.clone();
        } else {
            m.state = RunState::Unavailable;
            m.message = m.loaded.analysis.limitation();
        }
    }
    /// Ends every run of mechanism `k` and clears its results: it is analysed again.
    pub(super) fn retire(&mut self, k: usize) {
        for r in self.runs.values() {
            if r.mechanism == k {
                r.cancel.store(true, Ordering::Relaxed);
            }
        }
        let generation = self.next_generation;
        self.next_generation += 1;
        let m = &mut self.mechanisms[k];
        m.generation = generation;
        m.configuration_space = None;
        m.published = None;
        m.singularities = None;
        m.published_singularities = None;
        m.singularity_run = None;
        m.cspace_note = String::new();
        m.singular_note = String::new();
    }
    /// The state and message of mechanism `k` after a load-time run ended: `running` while
    /// another load-time run of it goes; then complete when every load-time result is, else
    /// incomplete. The message joins each analysis's line.
    fn settle(&mut self, k: usize) {
        let generation = self.mechanisms[k].generation;
        let going = self.runs.values().any(|r| r.mechanism == k && r.generation == generation && matches!(r.kind, RunKind::ConfigurationSpace | RunKind::Singularities { load_time: true }));
        let m = &mut self.mechanisms[k];
        m.message = [&m.cspace_note, &m.singular_note].into_iter().filter(|n| !n.is_empty()).cloned().collect::<Vec<_>>().join("; ");
        let cspace = m.configuration_space.as_ref().map_or(Completeness::Complete, |c| c.completeness());
        let singular = m.singularities.as_ref().map_or(Completeness::Complete, |s| s.completeness());
        m.state = if going { RunState::Running } else { RunState::Finished(cspace.and(singular)) };
    }
    /// Starts `job` on a thread of its own; returns its run id.
    pub(super) fn start(&mut self, mechanism: usize, kind: RunKind, job: Work) -> u64 {
        let run = self.next_run;
        self.next_run += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        let generation = self.mechanisms[mechanism].generation;
        self.runs.insert(run, Run { mechanism, generation, kind, cancel: cancel.clone(), waiters: Vec::new(), decided: 0.0, goal: None });
        let events = self.events.clone();
        std::thread::spawn(move || {
            let progress_events = events.clone();
            let mut progress = move |p: &crate::app::Progress| {
                // Progress is lossy by design: a full queue drops a snapshot, not the run.
                let _ = progress_events.try_send(Event::Progress { run, progress: *p });
            };
            let result = match catch_unwind(AssertUnwindSafe(|| job(&cancel, &mut progress))) {
                Ok(result) => result,
                Err(p) => Err(format!("internal error: {}", panic_text(p.as_ref()))),
            };
            let _ = events.send_blocking(Event::Finished { run, result });
        });
        run
    }
    pub(super) fn progress(&self, run: u64, p: crate::app::Progress, done: bool) {
        let Some(r) = self.runs.get(&run) else { return };
        let m = &self.mechanisms[r.mechanism];
        if r.generation != m.generation {
            return;
        }
        let msg = msgs::Progress {
            header: convert::header(&convert::joint_frame(m.loaded.analysis.mechanism())),
            mechanism: m.loaded.analysis.mechanism().to_string(),
            analysis: r.kind.analysis().into(),
            run_id: run,
            processed: p.processed,
            pending: p.pending as u64,
            decided: p.decided,
            done,
        };
        if let Some(h) = r.goal.clone() {
            let (action, feedback) = (self.action.clone(), SolveFeedback { progress: msg.clone() });
            smol::spawn(async move {
                let _ = action.publish_feedback(h, feedback).await;
            })
            .detach();
        }
        if let Err(e) = m.topics.progress.publish(msg) {
            say!("linkspace: publishing {}/progress: {e:?}", m.prefix);
        }
    }
    pub(super) async fn finished(&mut self, run: u64, result: Result<Outcome, String>) {
        let (processed, pending, complete) = result.as_ref().map_or((0, 0, false), |o| o.counts());
        // What a limit left undecided is still pending.
        let decided = if complete { 1.0 } else { self.runs.get(&run).map_or(0.0, |r| r.decided) };
        self.progress(run, crate::app::Progress { processed, pending, decided }, true);
        let Some(r) = self.runs.remove(&run) else { return };
        self.finished.push_back(run);
        if self.finished.len() > 4096 {
            self.finished.pop_front();
        }
        let name = self.mechanisms[r.mechanism].loaded.analysis.mechanism().to_string();
        if r.generation != self.mechanisms[r.mechanism].generation {
            if let Some(h) = r.goal {
                self.goal_result(h, GoalEndStatus::Aborted, SolveActionResult { ok: false, message: format!("run {run} ended without a result: its mechanism was analysed again"), run_id: run, ..Default::default() });
            }
            for (id, _) in r.waiters {
                self.reply_error(r.kind, id, format!("run {run} ended without a result: its mechanism was analysed again (new robot_description or settings)"));
            }
            return;
        }
        let outcome = match result {
            Ok(outcome) => outcome,
            Err(why) => {
                let message = format!("run {run} of '{name}' failed: {why}");
                say!("linkspace: {message}");
                let m = &mut self.mechanisms[r.mechanism];
                if matches!(r.kind, RunKind::ConfigurationSpace | RunKind::Singularities { load_time: true }) {
                    m.state = RunState::Failed;
                    m.message = message.clone();
                }
                if r.kind == (RunKind::Singularities { load_time: true }) {
                    m.singularity_run = None;
                }
                if let Some(h) = r.goal {
                    self.goal_result(h, GoalEndStatus::Aborted, SolveActionResult { ok: false, message: message.clone(), run_id: run, ..Default::default() });
                }
                for (id, _) in r.waiters {
                    self.reply_error(r.kind, id, message.clone());
                }
                return;
            }
        };
        match outcome {
            Outcome::BoxSet(result) => self.finished_box_set(run, r, result).await,
            Outcome::Singularities(result) => self.finished_singularities(run, r, result).await,
            Outcome::InverseKinematics(result) => {
                if self.log_level <= Severity::Info {
                    say!("linkspace: {name}: run {run} (inverse kinematics): {} solutions, {} boxes, {:.3} s", result.solutions.len(), result.processed, result.seconds);
                }
                let reply = convert::ik_response(&result);
                for (id, _) in r.waiters {
                    self.reply_ik(id, reply.clone());
                }
            }
            Outcome::Answer(Err(message)) => {
                for (id, _) in r.waiters {
                    self.reply_error(r.kind, id, message.clone());
                }
            }
            Outcome::Answer(Ok(crate::app::Answer::Ik6(a))) => {
                if self.log_level <= Severity::Info {
                    let s = &a.found.solutions;
                    say!("linkspace: {name}: run {run} (6R inverse kinematics): {} solutions, {} undecided clusters, {:.3} s", s.unique.len(), s.clusters.len(), a.found.seconds);
                }
                let reply = convert::ik6_response(&a.chain, &a.found);
                for (id, _) in r.waiters {
                    self.reply_ik6(id, reply.clone());
                }
            }
            Outcome::Answer(Ok(crate::app::Answer::PathCheck(a))) => {
                let reply = convert::path_check_response(&a.found);
                for (id, _) in r.waiters {
                    self.reply_path_check(id, reply.clone());
                }
            }
            Outcome::Answer(Ok(crate::app::Answer::Collisions(a))) => {
                let reply = convert::collisions_response(&a.found);
                for (id, _) in r.waiters {
                    self.reply_collisions(id, reply.clone());
                }
            }
            Outcome::Answer(Ok(crate::app::Answer::SelfMotion(a))) => {
                let reply = convert::self_motion_response(&a);
                for (id, _) in r.waiters {
                    self.reply_self_motion(id, reply.clone());
                }
            }
            Outcome::Answers(answers) => {
                let reply = convert::ik6_many_response(&answers);
                if self.log_level <= Severity::Info {
                    say!("linkspace: {name}: run {run} (6R inverse kinematics): {}", reply.message);
                }
                for (id, _) in r.waiters {
                    self.reply_ik6(id, reply.clone());
                }
            }
            Outcome::Answer(Ok(other)) => {
                for (id, _) in r.waiters {
                    self.reply_error(r.kind, id, format!("internal error: a {} answer for a {} request", other.name(), r.kind.analysis()));
                }
            }
        }
    }
    async fn finished_box_set(&mut self, run: u64, r: Run, result: BoxSetResult) {
        let name = self.mechanisms[r.mechanism].loaded.analysis.mechanism().to_string();
        let max_bytes = (self.limits.max_set_megabytes * 1e6) as usize;
        let set = match result.within_bytes(max_bytes) {
            None => convert::box_set(&result, run),
            Some(merged) => {
                self.log(
                    LogLevel::Warn,
                    format!("{name}: run {run}: {} boxes ({:.1} MB) merged into {} boxes to stay within max_set_megabytes {}", result.boxes.len(), result.wire_bytes() as f64 / 1e6, merged.boxes.len(), self.limits.max_set_megabytes),
                );
                BoxSet { merged_from: result.boxes.len() as u64, ..convert::box_set(&merged, run) }
            }
        };
        let m = &mut self.mechanisms[r.mechanism];
        let status = result.completeness().text();
        let summary = format!("{name}: run {run} ({:?}) {status}: {} boxes, {} clusters, {:.3} s", r.kind, result.boxes.len(), result.clusters, result.stats.seconds);
        match r.kind {
            RunKind::ConfigurationSpace => {
                m.cspace_note = format!("run {run}: {status}, {} boxes in {} clusters", result.boxes.len(), result.clusters);
                let markers = convert::markers(&result, &m.loaded.root_link, self.limits.max_markers);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    say!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
                m.published = Some((set, markers));
                for (js, mode) in convert::assembly_modes(&result, run, &m.loaded.root_link) {
                    if let Err(e) = m.topics.assembly_modes.async_publish(js).await {
                        say!("linkspace: publishing {}/assembly_modes: {e:?}", m.prefix);
                    }
                    if let Err(e) = m.topics.assembly_mode.async_publish(mode).await {
                        say!("linkspace: publishing {}/assembly_mode: {e:?}", m.prefix);
                    }
                }
                m.configuration_space = Some(Arc::new(result));
                self.publish_markers(r.mechanism).await;
                self.settle(r.mechanism);
                if self.log_level <= Severity::Info {
                    say!("linkspace: {name}: published configuration_space");
                }
            }
            RunKind::Solve => {
                if let Err(e) = m.topics.solve_result.async_publish(set.clone()).await {
                    say!("linkspace: publishing {}/solve_result: {e:?}", m.prefix);
                }
                let message = format!("run {run}: {status}");
                for (id, _) in r.waiters {
                    self.reply_solve(id, SolveResponse { ok: true, message: message.clone(), run_id: run, done: true, result: set.clone() });
                }
                if self.log_level <= Severity::Info {
                    say!("linkspace: {name}: published solve_result of run {run}");
                }
            }
            RunKind::SolveAction => {
                if let Err(e) = m.topics.solve_result.async_publish(set.clone()).await {
                    say!("linkspace: publishing {}/solve_result: {e:?}", m.prefix);
                }
                let cancelled = result.status == Status::Stopped(Limit::Cancelled);
                if let Some(h) = r.goal {
                    let end = if cancelled { GoalEndStatus::Canceled } else { GoalEndStatus::Succeeded };
                    self.goal_result(h, end, SolveActionResult { ok: true, message: format!("run {run}: {status}"), run_id: run, result: set });
                }
            }
            RunKind::Singularities { .. } | RunKind::InverseKinematics | RunKind::InverseKinematics6 | RunKind::PathCheck | RunKind::Collisions | RunKind::SelfMotion => say!("linkspace: {name}: run {run} returned a box set for a {:?} run", r.kind),
        }
        self.log(LogLevel::Info, summary);
    }
    async fn finished_singularities(&mut self, run: u64, r: Run, result: SingularityResult) {
        let report = convert::singularity_report(&result, run);
        let m = &mut self.mechanisms[r.mechanism];
        let name = m.loaded.analysis.mechanism().to_string();
        if self.log_level <= Severity::Info {
            say!("linkspace: {name}: run {run} (singularities, precision {}): {}, {:.3} s", result.query.precision, result.summary, result.seconds);
        }
        if r.kind == (RunKind::Singularities { load_time: true }) {
            m.singular_note = format!("run {run}: {}", result.summary);
            let markers = convert::singularity_markers(&result, self.limits.max_markers);
            if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                say!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
            }
            m.published_singularities = Some((report.clone(), markers));
            m.singularities = Some(Arc::new(result));
            m.singularity_run = None;
            self.publish_markers(r.mechanism).await;
            self.settle(r.mechanism);
            if self.log_level <= Severity::Info {
                say!("linkspace: {name}: published singularities");
            }
        }
        let reply = singularity_reply(&report);
        for (id, _) in r.waiters {
            self.reply_singularities(id, reply.clone());
        }
    }
    /// Answers requests whose wait ran out. A Solve run goes on and its result will be
    /// published; so does the load-time singularity analysis. Other queries are answered only
    /// in their reply, so theirs is an error (their runs are bounded, so this is rare).
    pub(super) fn expire_waits(&mut self) {
        let now = Instant::now();
        let mut due = Vec::new();
        for (&run, r) in self.runs.iter_mut() {
            let (gone, kept): (Vec<_>, Vec<_>) = r.waiters.drain(..).partition(|(_, deadline)| *deadline <= now);
            r.waiters = kept;
            let prefix = &self.mechanisms[r.mechanism].prefix;
            for (id, _) in gone {
                due.push((r.kind, id, run, prefix.clone()));
            }
        }
        for (kind, id, run, prefix) in due {
            match kind {
                RunKind::Solve => self.reply_solve(
                    id,
                    SolveResponse { ok: true, message: format!("run {run} is still going; its result will be published on {prefix}/solve_result"), run_id: run, done: false, ..Default::default() },
                ),
                RunKind::Singularities { load_time: true } => {
                    self.reply_error(kind, id, format!("the load-time singularity analysis (run {run}) is still going; its report will be published on {prefix}/singularities"))
                }
                _ => self.reply_error(kind, id, format!("run {run} did not finish within {} s (the node's --max-wait); its result will not be sent", self.limits.max_wait)),
            }
        }
    }
    /// Why a new requested run is refused, if it is: `max_runs` are going on.
    pub(super) fn busy(&self) -> Option<String> {
        let busy = self.runs.values().filter(|r| r.kind.requested()).count();
        (busy >= self.limits.max_runs).then(|| format!("busy: {busy} requested runs are going on (the node's limit, --max-runs); retry when one ends or cancel a solve"))
    }
}

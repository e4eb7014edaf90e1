//! The event loop: context → node → topics and servers → spinner → one loop over `Event`.
//!
//! Every trigger of work is an `Event` on one channel: a decoded service request, progress or
//! the end of a run (from its thread), and a clock tick that answers requests whose wait ran
//! out. The loop owns all state, so no locks; handlers run under `catch_unwind`, so a request
//! that trips a bug is answered with an error instead of taking the node down.
//!
//! Runs (the load-time analyses, requested solves, singularity and inverse-kinematics queries)
//! go on threads of their own. At most `NodeLimits::max_runs` requested runs go on at once, each
//! bounded by the request's `max_boxes` and `timeout` (within the node's limits), so memory
//! stays bounded however many requests arrive: the excess is refused with a reason.
//!
//! Files: this one holds what the loop owns (`State`, `Mechanism`, `Event`), `run` and the
//! dispatch of events. `setup` creates the DDS entities in the order above, `parameters` owns
//! the ROS parameters and the robot_description, `requests` the service handlers, `goals` the
//! Solve action, `runs` the life of a run from its start to where its result goes, and
//! `publish` the latched topics.

mod goals;
mod parameters;
mod publish;
mod requests;
mod runs;
mod setup;

use super::msgs::{BoxSet, MarkerArray, SingularityReport, SolveGoal, TfMessage};
use super::{Loaded, NodeLimits, ServeConfig, Severity};
use crate::app::{BoxSetResult, SingularityResult};
use crate::app::SolverSettings;
use anyhow::{Context as _, Result};
use goals::SolveAction;
use publish::Topics;
use requests::{Request, Servers};
use ros2_client::action::{CancelHandle, NewGoalHandle};
use ros2_client::log::LogLevel;
use ros2_client::{rosout, Node, NodeName, ParameterValue, Publisher};
use runs::{Outcome, Run};
use std::collections::{BTreeMap, VecDeque};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Everything that makes the loop do something.
#[allow(clippy::large_enum_variant)] // one event at a time through a channel: not worth a Box
enum Event {
    Request(Request),
    Progress { run: u64, progress: crate::app::Progress },
    /// A run ended; `Err` when it panicked (its payload, as text).
    Finished { run: u64, result: Result<Outcome, String> },
    Tick,
    /// Time to publish the latest configuration spaces again (`--republish`).
    Republish,
    /// A ROS parameter was set (already validated).
    Parameter(String, ParameterValue),
    /// A URDF arrived on `--robot-description-topic`.
    RobotDescription(String),
    /// A goal of the Solve action.
    Goal(NewGoalHandle<SolveGoal>),
    /// A cancel request of the Solve action.
    GoalCancel(CancelHandle),
    /// Another participant on the domain holds a node of this node's name (the warning).
    NameTaken(String),
}

struct Mechanism {
    loaded: Loaded,
    generation: u64,
    prefix: String,
    topics: Topics,
    /// The latest configuration space, and its messages (kept for `--republish`).
    configuration_space: Option<Arc<BoxSetResult>>,
    published: Option<(BoxSet, MarkerArray)>,
    /// The latest load-time singularity result and its messages (kept for replies and
    /// `--republish`), and the load-time run while it goes.
    singularities: Option<Arc<SingularityResult>>,
    published_singularities: Option<(SingularityReport, MarkerArray)>,
    singularity_run: Option<u64>,
    state: RunState,
    message: String,
    /// One line per load-time analysis (configuration space, singularities) as it ends, the
    /// parts of `message` (a linkage has both).
    cspace_note: String,
    singular_note: String,
}

/// Where a mechanism's load-time analyses stand (`list_mechanisms`' `state`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RunState {
    /// A load-time run goes.
    Running,
    /// Every load-time run ended: complete when every result is (the one rule), else why not.
    Finished(crate::app::Completeness),
    /// A load-time run failed (internal error).
    Failed,
    /// The kind has no load-time analysis.
    Unavailable,
}

impl RunState {
    fn name(self) -> &'static str {
        match self {
            RunState::Running => "running",
            RunState::Finished(c) => c.word(),
            RunState::Failed => "failed",
            RunState::Unavailable => "unavailable",
        }
    }
}

fn mechanism_entry(loaded: Loaded, prefix: String, topics: Topics, generation: u64) -> Mechanism {
    Mechanism {
        loaded,
        generation,
        prefix,
        topics,
        configuration_space: None,
        published: None,
        singularities: None,
        published_singularities: None,
        singularity_run: None,
        state: RunState::Running,
        message: String::new(),
        cspace_note: String::new(),
        singular_note: String::new(),
    }
}

struct State {
    node: Node,
    base: String,
    rosout: bool,
    /// The least severe lines written (stderr and `/rosout`).
    log_level: Severity,
    config: ServeConfig,
    tf_static: Publisher<TfMessage>,
    action: Arc<SolveAction>,
    /// The robot_description the node holds (parameter and topic).
    description: String,
    next_generation: u64,
    mechanisms: Vec<Mechanism>,
    servers: Rc<Servers>,
    runs: BTreeMap<u64, Run>,
    /// Recently finished run ids, so Cancel can tell "finished" from "unknown".
    finished: VecDeque<u64>,
    next_run: u64,
    limits: NodeLimits,
    settings: SolverSettings,
    /// Precision of the load-time singularity analyses.
    precision: f64,
    events: smol::channel::Sender<Event>,
}

/// Runs the node until the process is stopped: context → node → topics and servers → spinner
/// → event loop, each step a function of its own (`setup`, `parameters`, `goals`, `publish`).
pub(crate) fn run(config: ServeConfig, loaded: Vec<Loaded>) -> Result<()> {
    let context = setup::join_domain(&config)?;
    // ros2-client's own wording of a bad name is not fit to show; say what a ROS name allows.
    let node_name = NodeName::new(&config.namespace, &config.node_name).map_err(|_| {
        anyhow::anyhow!("node name {}/{}: a ROS node name is letters, digits and underscores, not starting with a digit, in a namespace of such tokens separated by '/'", config.namespace, config.node_name)
    })?;
    // Bounded: a flood of requests waits in DDS (and is eventually refused) instead of
    // growing this queue.
    let (tx, rx) = smol::channel::bounded::<Event>(256);
    let options = parameters::node_options(&config, tx.clone());
    let mut node = context.new_node(node_name, options).context("creating the node")?;
    let base = format!("{}/{}", config.namespace.trim_end_matches('/'), config.node_name);
    let mapping = setup::service_mapping(config.mapping);

    let mechanisms = setup::mechanisms(&mut node, &base, loaded)?;
    let action = goals::action_server(&mut node, mapping, &base)?;
    let tf_static = publish::tf_static(&mut node)?;
    let servers = setup::servers(&mut node, mapping, &base)?;

    let ex = smol::LocalExecutor::new();
    setup::spawn_spinner(&mut node, &ex)?;
    if let Some(topic) = &config.robot_description_topic {
        setup::subscribe_robot_description(&mut node, &ex, topic, tx.clone())?;
    }
    setup::watch_for_namesakes(&context, &mut node, &ex, tx.clone())?;
    goals::forward_goals(&ex, &action, &tx);
    setup::forward_requests(&ex, &servers, &tx);
    setup::spawn_timers(&ex, config.republish, &tx);

    let next_generation = mechanisms.len() as u64;
    let description = config.sources.iter().find(|s| s.description).map_or(String::new(), |s| s.xml.clone());
    let mut state = State {
        node,
        base: base.clone(),
        rosout: config.rosout,
        log_level: config.log_level,
        config: config.clone(),
        tf_static,
        action,
        description,
        next_generation,
        mechanisms,
        servers,
        runs: BTreeMap::new(),
        finished: VecDeque::new(),
        next_run: 1,
        limits: config.limits.clone(),
        settings: config.settings.clone(),
        precision: config.precision,
        events: tx,
    };
    for k in 0..state.mechanisms.len() {
        state.start_load_time(k);
    }
    state.publish_static_transforms();
    state.log(
        LogLevel::Info,
        format!(
            "ready: node {base} on domain {} ({:?} mapping, {:?} network), mechanisms: {}",
            config.domain,
            config.mapping,
            config.network,
            state.mechanisms.iter().map(|m| m.prefix.as_str()).collect::<Vec<_>>().join(" ")
        ),
    );

    catch_stop_signals();
    event_loop(&ex, &rx, &mut state);
    state.stop();
    // Dropping the node and then the context (in that order, as declared in reverse) ends the
    // DDS participant, which tells the other participants it is gone.
    drop(state);
    drop(ex);
    Ok(())
}

/// Raised by SIGINT or SIGTERM (Ctrl-C under `ros2 launch`, `kill`, a service manager): the
/// event loop ends at its next tick and the node leaves the graph, exit status 0.
static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_stop_signal(_signal: libc::c_int) {
    // Only an atomic store: all a signal handler may safely do.
    STOP.store(true, Ordering::SeqCst);
}

/// SIGINT and SIGTERM raise `STOP` instead of killing the process.
fn catch_stop_signals() {
    let handler = on_stop_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
}

/// Handles the events one at a time, in the order they arrive; the tasks spawned on `ex`
/// (spinner, request streams, timers) run while it waits. `state` holds a sender, so the
/// channel never closes: the loop runs until SIGINT or SIGTERM, seen at the next event (a tick
/// comes every 50 ms).
fn event_loop(ex: &smol::LocalExecutor<'_>, rx: &smol::channel::Receiver<Event>, state: &mut State) {
    smol::block_on(ex.run(async {
        while let Ok(event) = rx.recv().await {
            if STOP.load(Ordering::SeqCst) {
                break;
            }
            state.handle(event).await;
        }
    }));
}

/// Text of a panic payload.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned()).unwrap_or_else(|| "unknown panic".to_string())
}

/// ros2-client's log level as the node's severity.
fn severity(level: LogLevel) -> Severity {
    match level {
        LogLevel::Debug => Severity::Debug,
        LogLevel::Info => Severity::Info,
        LogLevel::Warn => Severity::Warn,
        LogLevel::Error => Severity::Error,
        LogLevel::Fatal => Severity::Fatal,
    }
}

impl State {
    /// Ends every run (their threads stop at their next cancel check; their results are not
    /// awaited) and says so.
    fn stop(&mut self) {
        for r in self.runs.values() {
            r.cancel.store(true, Ordering::Relaxed);
        }
        self.log(LogLevel::Info, format!("stopping: {} runs cancelled", self.runs.len()));
    }

    /// Logs a line on stderr and, unless `--disable-rosout-logs`, on `/rosout`, if `level` is
    /// at least the node's `--log-level`.
    fn log(&self, level: LogLevel, message: String) {
        if severity(level) < self.log_level {
            return;
        }
        say!("linkspace: {message}");
        if self.rosout {
            rosout!(self.node, level, "{}", message);
        }
    }

    async fn handle(&mut self, event: Event) {
        match event {
            Event::Request(request) => self.request(request),
            Event::Progress { run, progress } => {
                if let Some(r) = self.runs.get_mut(&run) {
                    r.decided = progress.decided;
                }
                self.progress(run, progress, false)
            }
            Event::Finished { run, result } => self.finished(run, result).await,
            Event::Tick => self.expire_waits(),
            Event::NameTaken(message) => self.log(LogLevel::Warn, message),
            Event::Republish => self.republish().await,
            // Under catch_unwind like requests: a bug logs an error and the node goes on.
            Event::Parameter(name, value) => {
                if let Err(p) = catch_unwind(AssertUnwindSafe(|| self.parameter(&name, value))) {
                    self.log(LogLevel::Error, format!("internal error while applying parameter {name}: {}", panic_text(p.as_ref())));
                }
            }
            Event::Goal(h) => self.goal(h).await,
            Event::GoalCancel(c) => self.goal_cancel(c).await,
            Event::RobotDescription(xml) => {
                if let Err(p) = catch_unwind(AssertUnwindSafe(|| self.new_description(xml, "topic robot_description"))) {
                    self.log(LogLevel::Error, format!("internal error while loading a robot_description: {}", panic_text(p.as_ref())));
                }
            }
        }
    }
}


/// A duration of `s` seconds for a deadline or a run's timeout: `Duration::from_secs_f64`
/// panics above about 1.8e19 s, and a parameter such as `max_wait` may be set to any finite
/// value (1e300 was accepted); past a year a deadline is as good as none.
fn seconds(s: f64) -> Duration {
    Duration::from_secs_f64(if s.is_nan() { 0.0 } else { s.clamp(0.0, 365.0 * 86_400.0) })
}

#[cfg(test)]
mod tests {
    /// Test idea: any finite limit a user may set (`--max-wait 1e300` was accepted) gives a
    /// deadline instead of the panic of `Duration::from_secs_f64`.
    #[test]
    fn every_seconds_value_gives_a_duration() {
        use super::seconds;
        assert_eq!(seconds(2.5), std::time::Duration::from_millis(2500));
        assert_eq!(seconds(1e300), std::time::Duration::from_secs(365 * 86_400));
        assert_eq!(seconds(f64::NAN), std::time::Duration::ZERO);
        assert_eq!(seconds(-1.0), std::time::Duration::ZERO);
    }
}

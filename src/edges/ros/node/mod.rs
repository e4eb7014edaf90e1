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

use super::convert;
use super::msgs::{self, *};
use super::{NodeLimits, Loaded, Mapping, Network, ServeConfig, Severity, Source};
use crate::app::{AnalysisError, BoxSetResult, IkQuery, IkResult, Service, SingularityQuery, SingularityResult};
use crate::kernel::search::{Limit, SolverSettings, Status};
use anyhow::{Context as _, Result};
use futures::StreamExt;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::action::{ActionServerQosPolicies, AsyncActionServer, CancelHandle, ExecutingGoalHandle, GoalEndStatus, GoalError, NewGoalHandle};
use ros2_client::log::LogLevel;
use ros2_client::entities_info::ParticipantEntitiesInfo;
use ros2_client::ActionTypeName;
use ros2_client::{rosout, Context, Message, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher, QosProfile, RmwRequestId, Server, ServiceMapping, ServiceTypeName};
use std::collections::{BTreeMap, VecDeque};
use std::net::{IpAddr, Ipv4Addr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Everything that makes the loop do something.
#[allow(clippy::large_enum_variant)] // one event at a time through a channel: not worth a Box
enum Event {
    Request(Request),
    Progress { run: u64, progress: crate::kernel::search::Progress },
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

/// The Solve action server (`~/solve`, `linkspace_msgs/action/Solve`).
type SolveAction = AsyncActionServer<SolveGoal, SolveActionResult, SolveFeedback>;

/// What a run returns.
#[allow(clippy::large_enum_variant)] // one per run, moved once: not worth a Box
enum Outcome {
    BoxSet(BoxSetResult),
    Singularities(SingularityResult),
    InverseKinematics(IkResult),
    /// A job run through the front door (`app::prepare`, `Prepared::run`).
    Answer(Result<crate::app::Answer, String>),
}

impl Outcome {
    /// (boxes processed, boxes left pending, complete) for the final progress message.
    fn counts(&self) -> (u64, usize, bool) {
        match self {
            Outcome::BoxSet(r) => (r.stats.processed, r.boxes.iter().filter(|b| b.status == crate::kernel::search::BoxStatus::Undecided).count(), r.status == Status::Finished),
            Outcome::Singularities(r) => (r.processed, r.undecided(), r.status == Status::Finished),
            Outcome::InverseKinematics(r) => (r.processed, 0, r.status == Status::Finished),
            Outcome::Answer(Ok(a)) => {
                let (processed, pending) = match a {
                    crate::app::Answer::Ik6(a) => (a.found.solutions.stats.processed, a.found.solutions.clusters.len()),
                    crate::app::Answer::PathCheck(a) => (a.found.check.segments.len() as u64, 0),
                    _ => (0, 0),
                };
                (processed, pending, a.completeness().is_complete())
            }
            Outcome::Answer(Err(_)) => (0, 0, false),
        }
    }
}

/// A run's work, moved to its thread.
type Work = Box<dyn FnOnce(&AtomicBool, &mut dyn FnMut(&crate::kernel::search::Progress)) -> Outcome + Send>;

/// A decoded service request with the id its reply must carry.
enum Request {
    Solve(RmwRequestId, SolveRequest),
    Cancel(RmwRequestId, CancelRequest),
    Singularities(RmwRequestId, SingularitiesRequest),
    InverseKinematics(RmwRequestId, InverseKinematicsRequest),
    Classify(RmwRequestId, ClassifyRequest),
    InverseKinematics6(RmwRequestId, InverseKinematics6Request),
    PathCheck(RmwRequestId, PathCheckRequest),
    List(RmwRequestId),
}

/// The publishers of one mechanism, under `~/<robot>/`.
struct Topics {
    configuration_space: Publisher<BoxSet>,
    solve_result: Publisher<BoxSet>,
    singularities: Publisher<SingularityReport>,
    progress: Publisher<msgs::Progress>,
    markers: Publisher<MarkerArray>,
    assembly_modes: Publisher<JointState>,
    assembly_mode: Publisher<AssemblyMode>,
}

struct Servers {
    solve: Server<SolveRequest, SolveResponse>,
    cancel: Server<CancelRequest, CancelResponse>,
    singularities: Server<SingularitiesRequest, SingularitiesResponse>,
    inverse_kinematics: Server<InverseKinematicsRequest, InverseKinematicsResponse>,
    classify: Server<ClassifyRequest, ClassifyResponse>,
    inverse_kinematics6: Server<InverseKinematics6Request, InverseKinematics6Response>,
    path_check: Server<PathCheckRequest, PathCheckResponse>,
    list: Server<ListMechanismsRequest, ListMechanismsResponse>,
}

/// What a run is for, which decides where its result goes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum RunKind {
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
}

impl RunKind {
    /// Runs started by a request, which count against `NodeLimits::max_runs`.
    fn requested(self) -> bool {
        matches!(self, RunKind::Solve | RunKind::SolveAction | RunKind::Singularities { load_time: false } | RunKind::InverseKinematics | RunKind::InverseKinematics6 | RunKind::PathCheck)
    }

    /// The `analysis` field of its progress messages.
    fn analysis(self) -> &'static str {
        match self {
            RunKind::ConfigurationSpace => "configuration_space",
            RunKind::Solve | RunKind::SolveAction => "solve",
            RunKind::Singularities { .. } => "singularities",
            RunKind::InverseKinematics => "inverse_kinematics",
            RunKind::InverseKinematics6 => "inverse_kinematics6",
            RunKind::PathCheck => "path_check",
        }
    }
}

struct Run {
    mechanism: usize,
    /// The mechanism's generation when the run started: a run of a replaced mechanism (new
    /// robot_description, new settings) is dropped when it ends.
    generation: u64,
    kind: RunKind,
    cancel: Arc<AtomicBool>,
    /// Requests waiting for this run (of the service its kind answers), with when to stop
    /// waiting.
    waiters: Vec<(RmwRequestId, Instant)>,
    /// The latest share of the volume decided.
    decided: f64,
    /// The action goal this run executes (`RunKind::SolveAction`).
    goal: Option<ExecutingGoalHandle<SolveGoal>>,
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
    /// Every load-time result is complete.
    Complete,
    /// A load-time result stopped on a limit.
    Incomplete,
    /// A load-time run failed (internal error).
    Failed,
    /// The kind has no load-time analysis.
    Unavailable,
}

impl RunState {
    fn name(self) -> &'static str {
        match self {
            RunState::Running => "running",
            RunState::Complete => "complete",
            RunState::Incomplete => "incomplete",
            RunState::Failed => "failed",
            RunState::Unavailable => "unavailable",
        }
    }
}

/// What `~/<robot>/markers` carries: the configuration-space markers, then the singularity
/// markers after them (one `DELETEALL` first), so that a late subscriber of the latched topic
/// gets both for a linkage that has both.
fn combined_markers(m: &Mechanism) -> Option<MarkerArray> {
    match (&m.published, &m.published_singularities) {
        (None, None) => None,
        (Some((_, a)), None) | (None, Some((_, a))) => Some(a.clone()),
        (Some((_, a)), Some((_, b))) => {
            let mut all = a.clone();
            // Both start with their own DELETEALL; one is enough.
            all.markers.extend(b.markers.iter().filter(|x| x.action != msgs::marker::DELETEALL).cloned());
            Some(all)
        }
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

/// Reliable + TransientLocal + KeepLast(depth): a late subscriber still gets the latest.
fn latched(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_secs(1)))
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth })
}

/// Reliable and volatile like rclpy's service default, but deeper than its keep-last 10: a
/// burst of requests (or of replies to one client) must not overwrite unacknowledged ones.
/// The node's participant bounds each writer's history by bytes too (`max_history_bytes`).
fn service_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_secs(1)))
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 256 })
}

fn publisher<M: Message>(node: &mut Node, prefix: &str, name: &str, package: &str, type_name: &str, qos: QosProfile) -> Result<Publisher<M>> {
    let topic_name = Name::new(prefix, name).with_context(|| format!("topic name {prefix}/{name}"))?;
    let topic = node.create_topic(&topic_name, MessageTypeName::new(package, type_name), &qos).with_context(|| format!("creating topic {prefix}/{name}"))?;
    node.create_publisher(&topic, None).with_context(|| format!("creating publisher {prefix}/{name}"))
}

/// Reliable + TransientLocal + KeepLast(depth) with the history depth explicit: RustDDS (patched,
/// vendor/README.md) then holds at most `depth` samples while no reader is matched, and drops
/// acknowledged ones beyond it.
fn topics(node: &mut Node, prefix: &str) -> Result<Topics> {
    Ok(Topics {
        configuration_space: publisher(node, prefix, "configuration_space", "linkspace_msgs", "BoxSet", latched(1))?,
        solve_result: publisher(node, prefix, "solve_result", "linkspace_msgs", "BoxSet", latched(1))?,
        singularities: publisher(node, prefix, "singularities", "linkspace_msgs", "SingularityReport", latched(1))?,
        progress: publisher(node, prefix, "progress", "linkspace_msgs", "Progress", latched(1))?,
        markers: publisher(node, prefix, "markers", "visualization_msgs", "MarkerArray", latched(1))?,
        // Deep enough for every assembly mode of one result.
        assembly_modes: publisher(node, prefix, "assembly_modes", "sensor_msgs", "JointState", latched(64))?,
        assembly_mode: publisher(node, prefix, "assembly_mode", "linkspace_msgs", "AssemblyMode", latched(64))?,
    })
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

/// The node's ROS parameters: their initial values (from the command line, `-p` and
/// `--params-file`), checked by `check_parameter` when set through the parameter services.
fn declared_parameters(config: &ServeConfig) -> Vec<(&'static str, ParameterValue)> {
    let description = config.sources.iter().find(|s| s.description).map_or(String::new(), |s| s.xml.clone());
    let l = &config.limits;
    vec![
        ("robot_description", ParameterValue::String(description)),
        ("sigma", ParameterValue::Double(config.settings.sigma)),
        ("rho", ParameterValue::Double(config.settings.rho)),
        ("precision", ParameterValue::Double(config.precision)),
        ("max_request_boxes", ParameterValue::Integer(l.max_boxes.min(i64::MAX as u64) as i64)),
        ("max_request_timeout", ParameterValue::Double(l.max_timeout)),
        ("max_wait", ParameterValue::Double(l.max_wait)),
        ("max_runs", ParameterValue::Integer(l.max_runs as i64)),
        ("max_markers", ParameterValue::Integer(l.max_markers as i64)),
        ("max_set_megabytes", ParameterValue::Double(l.max_set_megabytes)),
    ]
}

/// Whether a parameter value is acceptable; the reason otherwise (one line, shown by
/// `ros2 param set`). A URDF must parse.
fn check_parameter(name: &str, value: &ParameterValue) -> Result<(), String> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    match (name, value) {
        ("robot_description", ParameterValue::String(xml)) if xml.trim().is_empty() => Ok(()),
        ("robot_description", ParameterValue::String(xml)) => crate::model::urdf::parse(xml).map(|_| ()).map_err(|e| format!("robot_description: {}", convert::bounded(&e.to_string(), convert::ECHO_MESSAGE))),
        ("sigma", ParameterValue::Double(v)) if positive(*v) => Ok(()),
        ("rho", ParameterValue::Double(v)) if *v > 0.0 && *v < 1.0 => Ok(()),
        ("precision", ParameterValue::Double(v)) if *v > 0.0 && *v < 1.0 => Ok(()),
        ("max_request_timeout" | "max_set_megabytes", ParameterValue::Double(v)) if positive(*v) => Ok(()),
        ("max_wait", ParameterValue::Double(v)) if v.is_finite() && *v >= 0.0 => Ok(()),
        ("max_request_boxes" | "max_runs" | "max_markers", ParameterValue::Integer(v)) if *v > 0 => Ok(()),
        ("robot_description", _) => Err("robot_description must be a string (URDF XML)".into()),
        ("sigma" | "max_request_timeout" | "max_set_megabytes", _) => Err(format!("{name} must be a positive finite double")),
        ("rho" | "precision", _) => Err(format!("{name} must be a double in (0, 1)")),
        ("max_wait", _) => Err("max_wait must be a finite double >= 0".into()),
        ("max_request_boxes" | "max_runs" | "max_markers", _) => Err(format!("{name} must be a positive integer")),
        _ => Err(format!("'{}' is not a parameter of this node", convert::bounded(name, convert::ECHO_NAME))),
    }
}

fn server<Q: Message + Clone + 'static, A: Message + 'static>(node: &mut Node, mapping: ServiceMapping, prefix: &str, name: &str, type_name: &str) -> Result<Server<Q, A>> {
    let service_name = Name::new(prefix, name).with_context(|| format!("service name {prefix}/{name}"))?;
    node.create_server(mapping, &service_name, &ServiceTypeName::new("linkspace_msgs", type_name), service_qos(), service_qos())
        .with_context(|| format!("creating service {prefix}/{name}"))
}

/// Text of a panic payload.
fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned()).unwrap_or_else(|| "unknown panic".to_string())
}

/// Forwards every request of `server` into the event channel.
fn forward<Q: Message + Clone + 'static, A: Message + 'static>(
    ex: &smol::LocalExecutor<'_>,
    servers: Rc<Servers>,
    pick: fn(&Servers) -> &Server<Q, A>,
    wrap: fn(RmwRequestId, Q) -> Request,
    events: smol::channel::Sender<Event>,
) {
    ex.spawn(async move {
        // One stream for the server's life, as ros2-client's own server example does, rather
        // than a new reader stream per request.
        let mut requests = pick(&servers).receive_request_stream();
        while let Some(r) = requests.next().await {
            match r {
                Ok((id, q)) => {
                    if events.send(Event::Request(wrap(id, q))).await.is_err() {
                        break;
                    }
                }
                // A sample that does not decode (wrong type or mapping) is dropped here: there
                // is no request id to answer it with.
                Err(e) => eprintln!("linkspace: dropped an undecodable request: {e:?}"),
            }
        }
    })
    .detach();
}

/// Runs the node until the process is stopped.
pub(crate) fn run(config: ServeConfig, loaded: Vec<Loaded>) -> Result<()> {
    // The service reply writers keep 256 samples (service_qos): with replies of megabytes the
    // byte bound is what holds their memory.
    let mut builder = DomainParticipantBuilder::new(config.domain).writer_history_max_bytes(config.max_history_bytes);
    if config.network == Network::Loopback {
        // RustDDS then announces and sends only on 127.0.0.1, and finds same-host participants
        // by unicast to the well-known discovery ports on loopback.
        builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    let participant = builder.build().with_context(|| format!("joining DDS domain {}", config.domain))?;
    let context = Context::from_domain_participant(participant).context("creating the ROS 2 context")?;
    let node_name = NodeName::new(&config.namespace, &config.node_name).with_context(|| format!("node name {}/{}", config.namespace, config.node_name))?;
    // Bounded: a flood of requests waits in DDS (and is eventually refused) instead of
    // growing this queue.
    let (tx, rx) = smol::channel::bounded::<Event>(256);
    let mut options = NodeOptions::new().enable_rosout(config.rosout).start_parameter_services(true);
    for (name, value) in declared_parameters(&config) {
        options = options.declare_parameter(name, value);
    }
    let set_events = tx.clone();
    // A robot_description is checked as the node will load it (URDF, formulation, the
    // load-time --fix and --trace that name its robot), so `ros2 param set` reports why not.
    let load_config = config.clone();
    let validate = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        check_parameter(name, value)?;
        match value {
            ParameterValue::String(xml) if name == "robot_description" && !xml.trim().is_empty() => {
                let source = Source { label: "robot_description".into(), xml: xml.clone(), description: true };
                let (mut fixes, mut traces) = (vec![false; load_config.fixed.len()], vec![false; load_config.traces.len()]);
                super::load_one(&source, &load_config, &mut fixes, &mut traces).map(|_| ()).map_err(|e| convert::bounded(&format!("{e:#}"), convert::ECHO_MESSAGE))
            }
            _ => Ok(()),
        }
    };
    let validator = move |name: &str, value: &ParameterValue| -> Result<(), String> {
        // It runs in ros2-client's spinner: a bug must refuse the value, not stop the spinner.
        catch_unwind(AssertUnwindSafe(|| validate(name, value))).unwrap_or_else(|p| Err(format!("internal error while checking {name}: {}", panic_text(p.as_ref()))))
    };
    options = options.parameter_validator(Box::new(validator)).parameter_set_action(Box::new(move |name: &str, value: &ParameterValue| {
        // Applied by the event loop; a full queue refuses the change rather than block DDS.
        set_events.try_send(Event::Parameter(name.to_string(), value.clone())).map_err(|_| "the node is busy; retry".to_string())
    }));
    let mut node = context.new_node(node_name, options).context("creating the node")?;
    let base = format!("{}/{}", config.namespace.trim_end_matches('/'), config.node_name);
    let mapping = match config.mapping {
        Mapping::Enhanced => ServiceMapping::Enhanced,
        Mapping::Cyclone => ServiceMapping::Cyclone,
        Mapping::Basic => ServiceMapping::Basic,
    };

    let mut mechanisms = Vec::new();
    for (k, l) in loaded.into_iter().enumerate() {
        let prefix = format!("{base}/{}", l.token);
        let topics = topics(&mut node, &prefix)?;
        mechanisms.push(mechanism_entry(l, prefix, topics, k as u64));
    }
    let action_qos = ActionServerQosPolicies {
        goal_service: service_qos(),
        result_service: service_qos(),
        cancel_service: service_qos(),
        feedback_publisher: QosProfile::publisher_default().reliability_reliable(WhenFull::Wait(Duration::from_secs(1))).durability(Durability::Volatile).history(History::KeepLast { depth: 16 }),
        status_publisher: latched(1),
    };
    let action_name = Name::new(&base, "solve").context("action name solve")?;
    let action = Arc::new(AsyncActionServer::new(
        node.create_action_server::<SolveGoal, SolveActionResult, SolveFeedback>(mapping, &action_name, &ActionTypeName::new("linkspace_msgs", "Solve"), action_qos).context("creating the Solve action")?,
    ));
    let tf_topic = node
        .create_topic(&Name::new("/", "tf_static").context("/tf_static")?, MessageTypeName::new("tf2_msgs", "TFMessage"), &latched(1))
        .context("creating topic /tf_static")?;
    let tf_static = node.create_publisher(&tf_topic, None).context("creating publisher /tf_static")?;
    let servers = Rc::new(Servers {
        solve: server(&mut node, mapping, &base, "solve", "Solve")?,
        cancel: server(&mut node, mapping, &base, "cancel", "Cancel")?,
        singularities: server(&mut node, mapping, &base, "singularities", "Singularities")?,
        inverse_kinematics: server(&mut node, mapping, &base, "inverse_kinematics", "InverseKinematics")?,
        classify: server(&mut node, mapping, &base, "classify", "Classify")?,
        inverse_kinematics6: server(&mut node, mapping, &base, "inverse_kinematics6", "InverseKinematics6")?,
        path_check: server(&mut node, mapping, &base, "path_check", "PathCheck")?,
        list: server(&mut node, mapping, &base, "list_mechanisms", "ListMechanisms")?,
    });

    let ex = smol::LocalExecutor::new();
    let spinner = node.spinner().context("starting the node's spinner")?;
    ex.spawn(async move {
        if let Err(e) = spinner.spin().await {
            eprintln!("linkspace: spinner stopped: {e:?}");
        }
    })
    .detach();

    if let Some(topic) = &config.robot_description_topic {
        let (ns, name) = match topic.rsplit_once('/') {
            Some((ns, name)) => (if ns.is_empty() { "/" } else { ns }, name),
            None => ("/", topic.as_str()),
        };
        let name = Name::new(ns, name).with_context(|| format!("--robot-description-topic {topic}"))?;
        let t = node.create_topic(&name, MessageTypeName::new("std_msgs", "String"), &latched(1)).with_context(|| format!("creating topic {topic}"))?;
        let sub = node.create_subscription::<StringMsg>(&t, Some(latched(1))).with_context(|| format!("subscribing to {topic}"))?;
        let events = tx.clone();
        ex.spawn(async move {
            let stream = sub.async_stream();
            futures::pin_mut!(stream);
            while let Some(r) = stream.next().await {
                match r {
                    Ok((msg, _)) => {
                        if events.send(Event::RobotDescription(msg.data)).await.is_err() {
                            break;
                        }
                    }
                    Err(e) => eprintln!("linkspace: dropped an undecodable robot_description: {e:?}"),
                }
            }
        })
        .detach();
    }
    watch_for_namesakes(&context, &mut node, &ex, tx.clone())?;
    {
        let (goals, events) = (action.clone(), tx.clone());
        ex.spawn(async move {
            loop {
                match goals.receive_new_goal().await {
                    Ok(h) => {
                        if events.send(Event::Goal(h)).await.is_err() {
                            break;
                        }
                    }
                    Err(e) => eprintln!("linkspace: dropped an undecodable Solve goal: {e:?}"),
                }
            }
        })
        .detach();
        let (cancels, events) = (action.clone(), tx.clone());
        ex.spawn(async move {
            loop {
                match cancels.receive_cancel_request().await {
                    Ok(c) => {
                        if events.send(Event::GoalCancel(c)).await.is_err() {
                            break;
                        }
                    }
                    Err(e) => eprintln!("linkspace: dropped an undecodable Solve cancel request: {e:?}"),
                }
            }
        })
        .detach();
    }
    forward(&ex, servers.clone(), |s| &s.solve, Request::Solve, tx.clone());
    forward(&ex, servers.clone(), |s| &s.cancel, Request::Cancel, tx.clone());
    forward(&ex, servers.clone(), |s| &s.singularities, Request::Singularities, tx.clone());
    forward(&ex, servers.clone(), |s| &s.inverse_kinematics, Request::InverseKinematics, tx.clone());
    forward(&ex, servers.clone(), |s| &s.classify, Request::Classify, tx.clone());
    forward(&ex, servers.clone(), |s| &s.inverse_kinematics6, Request::InverseKinematics6, tx.clone());
    forward(&ex, servers.clone(), |s| &s.path_check, Request::PathCheck, tx.clone());
    forward(&ex, servers.clone(), |s| &s.list, |id, _| Request::List(id), tx.clone());
    let ticks = tx.clone();
    ex.spawn(async move {
        loop {
            smol::Timer::after(Duration::from_millis(50)).await;
            if ticks.send(Event::Tick).await.is_err() {
                break;
            }
        }
    })
    .detach();

    if let Some(period) = config.republish {
        let republish = tx.clone();
        ex.spawn(async move {
            loop {
                smol::Timer::after(period).await;
                if republish.send(Event::Republish).await.is_err() {
                    break;
                }
            }
        })
        .detach();
    }

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

    smol::block_on(ex.run(async {
        while let Ok(event) = rx.recv().await {
            state.handle(event).await;
        }
    }));
    Ok(())
}

fn solve_error(message: String) -> SolveResponse {
    SolveResponse { ok: false, message, ..Default::default() }
}

/// Two nodes of one name on a domain serve the same service names, so each answers the other's
/// clients: warn (once per other participant) when `ros_discovery_info`, where every ROS 2
/// participant lists its nodes and `ros2 node list` reads them, shows this node's name elsewhere.
fn watch_for_namesakes(context: &Context, node: &mut Node, ex: &smol::LocalExecutor<'_>, events: smol::channel::Sender<Event>) -> Result<()> {
    let own = context.participant_entities_info().gid();
    let name = node.fully_qualified_name();
    let domain = node.domain_id();
    let qos = latched(64);
    let topic = context
        .create_topic("ros_discovery_info".to_string(), MessageTypeName::new("rmw_dds_common", "ParticipantEntitiesInfo"), &qos)
        .context("creating topic ros_discovery_info")?;
    let sub = node.create_subscription::<ParticipantEntitiesInfo>(&topic, Some(qos)).context("subscribing to ros_discovery_info")?;
    ex.spawn(async move {
        let mut warned = std::collections::BTreeSet::new();
        let stream = sub.async_stream();
        futures::pin_mut!(stream);
        while let Some(r) = stream.next().await {
            let Ok((info, _)) = r else { continue };
            let namesake = info.nodes().iter().any(|n| {
                let ns = n.namespace().trim_end_matches('/');
                format!("{ns}/{}", n.name()) == name
            });
            if info.gid() != own && namesake && warned.insert(info.gid()) {
                let message = format!(
                    "another node named {name} is also on domain {domain}: clients of either get replies from both; give this one another name (--node-name NAME or --ros-args -r __node:=NAME) or namespace"
                );
                if events.send(Event::NameTaken(message)).await.is_err() {
                    break;
                }
            }
        }
    })
    .detach();
    Ok(())
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

/// A Singularities reply carrying the whole `report` (the patched RustDDS sends replies of any
/// size: vendor/README.md).
fn singularity_reply(report: &SingularityReport) -> SingularitiesResponse {
    SingularitiesResponse { ok: true, message: report.message.clone(), report: report.clone() }
}

impl State {
    /// Logs a line on stderr and, unless `--disable-rosout-logs`, on `/rosout`, if `level` is
    /// at least the node's `--log-level`.
    fn log(&self, level: LogLevel, message: String) {
        if severity(level) < self.log_level {
            return;
        }
        eprintln!("linkspace: {message}");
        if self.rosout {
            rosout!(self.node, level, "{}", message);
        }
    }

    /// Starts the load-time analyses of mechanism `k`.
    fn start_load_time(&mut self, k: usize) {
        let a = &self.mechanisms[k].loaded.analysis;
        let cspace = a.configuration_space(&self.settings);
        let query = SingularityQuery { precision: self.precision, nodes: true, max_boxes: self.settings.max_boxes, timeout: self.settings.timeout, threads: self.settings.threads };
        let singular = a.singularities(&query);
        let mut started = false;
        match cspace {
            Ok(prepared) => {
                self.start(k, RunKind::ConfigurationSpace, Box::new(move |c, p| Outcome::BoxSet(prepared.run(c, p))));
                started = true;
            }
            Err(e) => self.log(LogLevel::Warn, format!("{}: no configuration space: {e}", self.mechanisms[k].loaded.analysis.mechanism())),
        }
        match singular {
            Ok(prepared) => {
                let run = self.start(k, RunKind::Singularities { load_time: true }, Box::new(move |c, p| Outcome::Singularities(prepared.run(c, p))));
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

    /// Publishes `/tf_static`: each mechanism's `<robot>/joint_space` under its root link.
    fn publish_static_transforms(&self) {
        let frames: Vec<(String, String)> = self.mechanisms.iter().map(|m| (m.loaded.root_link.clone(), convert::joint_frame(m.loaded.analysis.mechanism()))).collect();
        if let Err(e) = self.tf_static.publish(convert::static_transforms(&frames)) {
            eprintln!("linkspace: publishing /tf_static: {e:?}");
        }
    }

    /// Ends every run of mechanism `k` and clears its results: it is analysed again.
    fn retire(&mut self, k: usize) {
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
        let complete = m.configuration_space.as_ref().is_none_or(|c| c.status == Status::Finished) && m.singularities.as_ref().is_none_or(|s| s.status == Status::Finished);
        m.state = if going {
            RunState::Running
        } else if complete {
            RunState::Complete
        } else {
            RunState::Incomplete
        };
    }

    /// Publishes the latched markers of mechanism `k` (`combined_markers`).
    async fn publish_markers(&self, k: usize) {
        let m = &self.mechanisms[k];
        if let Some(markers) = combined_markers(m) {
            if let Err(e) = m.topics.markers.async_publish(markers).await {
                eprintln!("linkspace: publishing {}/markers: {e:?}", m.prefix);
            }
        }
    }

    /// A new robot_description (parameter or topic): replaces the mechanism that came from
    /// one (or adds it), and analyses it again. Errors are one line, logged.
    fn new_description(&mut self, xml: String, origin: &str) {
        if xml == self.description {
            return;
        }
        if xml.trim().is_empty() {
            self.description = xml;
            return;
        }
        let source = Source { label: origin.to_string(), xml: xml.clone(), description: true };
        let (mut fixes, mut traces) = (vec![false; self.config.fixed.len()], vec![false; self.config.traces.len()]);
        let loaded = match super::load_one(&source, &self.config, &mut fixes, &mut traces) {
            Ok(l) => l,
            Err(e) => return self.log(LogLevel::Error, convert::bounded(&format!("{e:#}"), convert::ECHO_MESSAGE).to_string()),
        };
        let slot = self.mechanisms.iter().position(|m| m.loaded.description);
        let name = loaded.analysis.mechanism().to_string();
        if let Some(other) = self.mechanisms.iter().enumerate().find(|(k, m)| Some(*k) != slot && (m.loaded.analysis.mechanism() == name || m.loaded.token == loaded.token)) {
            return self.log(LogLevel::Error, format!("{origin}: a mechanism named '{}' is already loaded from another source", other.1.loaded.analysis.mechanism()));
        }
        self.description = xml.clone();
        if origin != "parameter robot_description" {
            // Keep the parameter in step with what the node analyses (its set action sees
            // the same text and does nothing).
            let _ = self.node.set_parameter("robot_description", ParameterValue::String(xml));
        }
        let prefix = format!("{}/{}", self.base, loaded.token);
        let k = match slot {
            Some(k) => {
                self.retire(k);
                if self.mechanisms[k].prefix != prefix {
                    match topics(&mut self.node, &prefix) {
                        Ok(t) => self.mechanisms[k].topics = t,
                        Err(e) => return self.log(LogLevel::Error, format!("{origin}: {e:#}")),
                    }
                    self.mechanisms[k].prefix = prefix;
                }
                self.mechanisms[k].loaded = loaded;
                k
            }
            None => {
                let t = match topics(&mut self.node, &prefix) {
                    Ok(t) => t,
                    Err(e) => return self.log(LogLevel::Error, format!("{origin}: {e:#}")),
                };
                let generation = self.next_generation;
                self.next_generation += 1;
                self.mechanisms.push(mechanism_entry(loaded, prefix, t, generation));
                self.mechanisms.len() - 1
            }
        };
        self.log(LogLevel::Info, format!("{name}: new robot_description from {origin}; analysing again"));
        self.start_load_time(k);
        self.publish_static_transforms();
    }

    /// A parameter set through the parameter services (validated by `check_parameter`).
    fn parameter(&mut self, name: &str, value: ParameterValue) {
        let before = (self.settings.clone(), self.precision);
        match (name, value) {
            ("robot_description", ParameterValue::String(xml)) => return self.new_description(xml, "parameter robot_description"),
            ("sigma", ParameterValue::Double(v)) => self.settings.sigma = v,
            ("rho", ParameterValue::Double(v)) => self.settings.rho = v,
            ("precision", ParameterValue::Double(v)) => self.precision = v,
            ("max_request_boxes", ParameterValue::Integer(v)) => self.limits.max_boxes = v.max(1) as u64,
            ("max_request_timeout", ParameterValue::Double(v)) => self.limits.max_timeout = v,
            ("max_wait", ParameterValue::Double(v)) => self.limits.max_wait = v,
            ("max_runs", ParameterValue::Integer(v)) => self.limits.max_runs = v.max(1) as usize,
            ("max_markers", ParameterValue::Integer(v)) => self.limits.max_markers = v.max(1) as usize,
            ("max_set_megabytes", ParameterValue::Double(v)) => self.limits.max_set_megabytes = v,
            _ => return,
        }
        // New load-time settings: every mechanism is analysed again with them.
        if (self.settings.clone(), self.precision) != before {
            self.log(LogLevel::Info, format!("parameter {name} changed: analysing every mechanism again"));
            for k in 0..self.mechanisms.len() {
                self.retire(k);
                self.start_load_time(k);
            }
        }
    }

    /// Publishes that the mechanism has no singularity analysis (ok = false, with the reason),
    /// so that a subscriber learns why instead of waiting.
    fn publish_no_singularities(&self, k: usize, reason: String) {
        let m = &self.mechanisms[k];
        let report = SingularityReport { header: convert::header(&convert::joint_frame(m.loaded.analysis.mechanism())), mechanism: m.loaded.analysis.mechanism().to_string(), ok: false, message: reason, ..convert::no_report() };
        if let Err(e) = m.topics.singularities.publish(report) {
            eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
        }
    }

    /// Starts `job` on a thread of its own; returns its run id.
    fn start(&mut self, mechanism: usize, kind: RunKind, job: Work) -> u64 {
        let run = self.next_run;
        self.next_run += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        let generation = self.mechanisms[mechanism].generation;
        self.runs.insert(run, Run { mechanism, generation, kind, cancel: cancel.clone(), waiters: Vec::new(), decided: 0.0, goal: None });
        let events = self.events.clone();
        std::thread::spawn(move || {
            let progress_events = events.clone();
            let mut progress = move |p: &crate::kernel::search::Progress| {
                // Progress is lossy by design: a full queue drops a snapshot, not the run.
                let _ = progress_events.try_send(Event::Progress { run, progress: *p });
            };
            let result = catch_unwind(AssertUnwindSafe(|| job(&cancel, &mut progress))).map_err(|p| panic_text(p.as_ref()));
            let _ = events.send_blocking(Event::Finished { run, result });
        });
        run
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

    fn progress(&self, run: u64, p: crate::kernel::search::Progress, done: bool) {
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
            eprintln!("linkspace: publishing {}/progress: {e:?}", m.prefix);
        }
    }

    async fn finished(&mut self, run: u64, result: Result<Outcome, String>) {
        let (processed, pending, complete) = result.as_ref().map_or((0, 0, false), |o| o.counts());
        // What a limit left undecided is still pending.
        let decided = if complete { 1.0 } else { self.runs.get(&run).map_or(0.0, |r| r.decided) };
        self.progress(run, crate::kernel::search::Progress { processed, pending, decided }, true);
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
            Err(panic) => {
                let message = format!("run {run} of '{name}' failed: internal error: {panic}");
                eprintln!("linkspace: {message}");
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
                    eprintln!("linkspace: {name}: run {run} (inverse kinematics): {} solutions, {} boxes, {:.3} s", result.solutions.len(), result.processed, result.seconds);
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
                    eprintln!("linkspace: {name}: run {run} (6R inverse kinematics): {} solutions, {} undecided clusters, {:.3} s", s.unique.len(), s.clusters.len(), a.found.seconds);
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
        let undecided = result.boxes.iter().filter(|b| b.status == crate::app::BoxStatus::Undecided).count();
        let status = crate::app::Completeness::of(result.status, undecided, false).text();
        let summary = format!("{name}: run {run} ({:?}) {status}: {} boxes, {} clusters, {:.3} s", r.kind, result.boxes.len(), result.clusters, result.stats.seconds);
        match r.kind {
            RunKind::ConfigurationSpace => {
                m.cspace_note = format!("run {run}: {status}, {} boxes in {} clusters", result.boxes.len(), result.clusters);
                let markers = convert::markers(&result, &m.loaded.root_link, self.limits.max_markers);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
                m.published = Some((set, markers));
                for (js, mode) in convert::assembly_modes(&result, run, &m.loaded.root_link) {
                    if let Err(e) = m.topics.assembly_modes.async_publish(js).await {
                        eprintln!("linkspace: publishing {}/assembly_modes: {e:?}", m.prefix);
                    }
                    if let Err(e) = m.topics.assembly_mode.async_publish(mode).await {
                        eprintln!("linkspace: publishing {}/assembly_mode: {e:?}", m.prefix);
                    }
                }
                m.configuration_space = Some(Arc::new(result));
                self.publish_markers(r.mechanism).await;
                self.settle(r.mechanism);
                if self.log_level <= Severity::Info {
                    eprintln!("linkspace: {name}: published configuration_space");
                }
            }
            RunKind::Solve => {
                if let Err(e) = m.topics.solve_result.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/solve_result: {e:?}", m.prefix);
                }
                let message = format!("run {run}: {status}");
                for (id, _) in r.waiters {
                    self.reply_solve(id, SolveResponse { ok: true, message: message.clone(), run_id: run, done: true, result: set.clone() });
                }
                if self.log_level <= Severity::Info {
                    eprintln!("linkspace: {name}: published solve_result of run {run}");
                }
            }
            RunKind::SolveAction => {
                if let Err(e) = m.topics.solve_result.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/solve_result: {e:?}", m.prefix);
                }
                let cancelled = result.status == Status::Stopped(Limit::Cancelled);
                if let Some(h) = r.goal {
                    let end = if cancelled { GoalEndStatus::Canceled } else { GoalEndStatus::Succeeded };
                    self.goal_result(h, end, SolveActionResult { ok: true, message: format!("run {run}: {status}"), run_id: run, result: set });
                }
            }
            RunKind::Singularities { .. } | RunKind::InverseKinematics | RunKind::InverseKinematics6 | RunKind::PathCheck => eprintln!("linkspace: {name}: run {run} returned a box set for a {:?} run", r.kind),
        }
        self.log(LogLevel::Info, summary);
    }

    async fn finished_singularities(&mut self, run: u64, r: Run, result: SingularityResult) {
        let report = convert::singularity_report(&result, run);
        let m = &mut self.mechanisms[r.mechanism];
        let name = m.loaded.analysis.mechanism().to_string();
        if self.log_level <= Severity::Info {
            eprintln!("linkspace: {name}: run {run} (singularities, precision {}): {}, {:.3} s", result.query.precision, result.summary, result.seconds);
        }
        if r.kind == (RunKind::Singularities { load_time: true }) {
            m.singular_note = format!("run {run}: {}", result.summary);
            let markers = convert::singularity_markers(&result, self.limits.max_markers);
            if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
            }
            m.published_singularities = Some((report.clone(), markers));
            m.singularities = Some(Arc::new(result));
            m.singularity_run = None;
            self.publish_markers(r.mechanism).await;
            self.settle(r.mechanism);
            if self.log_level <= Severity::Info {
                eprintln!("linkspace: {name}: published singularities");
            }
        }
        let reply = singularity_reply(&report);
        for (id, _) in r.waiters {
            self.reply_singularities(id, reply.clone());
        }
    }

    /// Publishes every latest configuration space (and its markers) again, stamped now: for
    /// tools that subscribe with volatile durability (RViz's default), and for throughput
    /// measurements.
    async fn republish(&mut self) {
        for k in 0..self.mechanisms.len() {
            let m = &mut self.mechanisms[k];
            if let Some((set, _)) = &mut m.published {
                set.header = convert::header(&set.header.frame_id);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
            }
            if let Some((report, _)) = &mut m.published_singularities {
                report.header = convert::header(&report.header.frame_id);
                if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                    eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
                }
            }
            self.publish_markers(k).await;
        }
    }

    /// Answers requests whose wait ran out. A Solve run goes on and its result will be
    /// published; so does the load-time singularity analysis. Other queries are answered only
    /// in their reply, so theirs is an error (their runs are bounded, so this is rare).
    fn expire_waits(&mut self) {
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

    /// An error reply of the service that `kind` answers.
    fn reply_error(&self, kind: RunKind, id: RmwRequestId, message: String) {
        match kind {
            RunKind::Solve | RunKind::SolveAction | RunKind::ConfigurationSpace => self.reply_solve(id, solve_error(message)),
            RunKind::Singularities { .. } => self.reply_singularities(id, SingularitiesResponse { ok: false, message, report: convert::no_report() }),
            RunKind::InverseKinematics => self.reply_ik(id, InverseKinematicsResponse { ok: false, message, ..Default::default() }),
            RunKind::InverseKinematics6 => self.reply_ik6(id, InverseKinematics6Response { ok: false, message, ..Default::default() }),
            RunKind::PathCheck => self.reply_path_check(id, PathCheckResponse { ok: false, message, ..Default::default() }),
        }
    }

    fn reply_path_check(&self, id: RmwRequestId, reply: PathCheckResponse) {
        if let Err(e) = self.servers.path_check.send_response(id, reply) {
            eprintln!("linkspace: sending a path_check reply: {e:?}");
        }
    }

    fn reply_singularities(&self, id: RmwRequestId, reply: SingularitiesResponse) {
        if let Err(e) = self.servers.singularities.send_response(id, reply) {
            eprintln!("linkspace: sending a singularities reply: {e:?}");
        }
    }

    fn reply_ik(&self, id: RmwRequestId, reply: InverseKinematicsResponse) {
        if let Err(e) = self.servers.inverse_kinematics.send_response(id, reply) {
            eprintln!("linkspace: sending an inverse_kinematics reply: {e:?}");
        }
    }

    fn reply_ik6(&self, id: RmwRequestId, reply: InverseKinematics6Response) {
        if let Err(e) = self.servers.inverse_kinematics6.send_response(id, reply) {
            eprintln!("linkspace: sending an inverse_kinematics6 reply: {e:?}");
        }
    }

    fn reply_solve(&self, id: RmwRequestId, reply: SolveResponse) {
        if let Err(e) = self.servers.solve.send_response(id, reply) {
            eprintln!("linkspace: sending a solve reply: {e:?}");
        }
    }

    /// Handles one request under `catch_unwind`: a bug answers with an error and the node goes on.
    fn request(&mut self, request: Request) {
        let servers = self.servers.clone();
        let internal = |p: Box<dyn std::any::Any + Send>| format!("internal error while handling the request: {}", panic_text(p.as_ref()));
        let sent = match request {
            Request::Solve(id, q) => match catch_unwind(AssertUnwindSafe(|| self.solve(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.solve.send_response(id, a),
                Err(p) => servers.solve.send_response(id, solve_error(internal(p))),
            },
            Request::Cancel(id, q) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.cancel(q))).unwrap_or_else(|p| CancelResponse { ok: false, message: internal(p) });
                servers.cancel.send_response(id, a)
            }
            Request::Singularities(id, q) => match catch_unwind(AssertUnwindSafe(|| self.singularities(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.singularities.send_response(id, a),
                Err(p) => servers.singularities.send_response(id, SingularitiesResponse { ok: false, message: internal(p), report: convert::no_report() }),
            },
            Request::InverseKinematics(id, q) => match catch_unwind(AssertUnwindSafe(|| self.inverse_kinematics(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.inverse_kinematics.send_response(id, a),
                Err(p) => servers.inverse_kinematics.send_response(id, InverseKinematicsResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::Classify(id, q) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.classify(q))).unwrap_or_else(|p| ClassifyResponse { ok: false, message: internal(p), component: -1, ..Default::default() });
                servers.classify.send_response(id, a)
            }
            Request::InverseKinematics6(id, q) => match catch_unwind(AssertUnwindSafe(|| self.inverse_kinematics6(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.inverse_kinematics6.send_response(id, a),
                Err(p) => servers.inverse_kinematics6.send_response(id, InverseKinematics6Response { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::PathCheck(id, q) => match catch_unwind(AssertUnwindSafe(|| self.path_check(id, q))) {
                Ok(None) => Ok(()),
                Ok(Some(a)) => servers.path_check.send_response(id, a),
                Err(p) => servers.path_check.send_response(id, PathCheckResponse { ok: false, message: internal(p), ..Default::default() }),
            },
            Request::List(id) => {
                let a = catch_unwind(AssertUnwindSafe(|| self.list())).unwrap_or_else(|_| ListMechanismsResponse::default());
                servers.list.send_response(id, a)
            }
        };
        if let Err(e) = sent {
            eprintln!("linkspace: sending a reply: {e:?}");
        }
    }

    fn mechanism(&self, name: &str) -> Result<usize, String> {
        self.mechanisms.iter().position(|m| m.loaded.analysis.mechanism() == name).ok_or_else(|| {
            let names: Vec<&str> = self.mechanisms.iter().map(|m| m.loaded.analysis.mechanism()).collect();
            format!("no mechanism named '{}' is loaded (loaded: {})", convert::bounded(name, convert::ECHO_NAME), names.join(", "))
        })
    }

    /// Validates and starts a run; `None` when the reply waits for the run.
    fn solve(&mut self, id: RmwRequestId, q: SolveRequest) -> Option<SolveResponse> {
        let (k, job) = match self.solve_job(&q) {
            Ok(j) => j,
            Err(e) => return Some(solve_error(e)),
        };
        let run = self.start(k, RunKind::Solve, job);
        if q.wait > 0.0 {
            let r = self.runs.get_mut(&run).expect("invariant: just started");
            r.waiters.push((id, Instant::now() + seconds(q.wait)));
            None
        } else {
            Some(SolveResponse { ok: true, message: format!("run {run} started; its result will be published on {}/solve_result", self.mechanisms[k].prefix), run_id: run, done: false, ..Default::default() })
        }
    }

    /// A Solve request checked and prepared (the mechanism and the run), or why not.
    fn solve_job(&self, q: &SolveRequest) -> Result<(usize, Work), String> {
        let k = self.mechanism(&q.mechanism)?;
        let limits = &self.limits;
        let s = &q.settings;
        if q.fixed_joint_names.len() != q.fixed_joint_values.len() {
            return Err(format!("{} fixed joint names but {} values", q.fixed_joint_names.len(), q.fixed_joint_values.len()));
        }
        if let Some((i, name)) = q.fixed_joint_names.iter().enumerate().find(|(i, n)| q.fixed_joint_names[..*i].contains(n)) {
            return Err(format!("joint '{}' is fixed twice (fixed_joint_names[{i}])", convert::bounded(name, convert::ECHO_NAME)));
        }
        if s.max_boxes == 0 {
            return Err(format!("settings.max_boxes must be given: every run is bounded (1 to {})", limits.max_boxes));
        }
        if s.max_boxes > limits.max_boxes {
            return Err(format!("settings.max_boxes {} is larger than this node's limit {} (--max-request-boxes)", s.max_boxes, limits.max_boxes));
        }
        // Settings.msg: timeout 0 means no time limit of the request's own; the node's
        // --max-request-timeout still bounds the run (and max_boxes always does).
        if !(s.timeout >= 0.0 && s.timeout <= limits.max_timeout) {
            return Err(format!("settings.timeout {} s is out of range: give 0 (the node's limit) to {} s (--max-request-timeout)", s.timeout, limits.max_timeout));
        }
        let timeout = if s.timeout == 0.0 { limits.max_timeout } else { s.timeout };
        if !(q.wait >= 0.0 && q.wait <= limits.max_wait) {
            return Err(format!("wait {} s is out of range: give 0 <= wait <= {} s", q.wait, limits.max_wait));
        }
        if let Some(busy) = self.busy() {
            return Err(busy);
        }
        let settings = SolverSettings { sigma: s.sigma, rho: s.rho, max_boxes: s.max_boxes, timeout: Some(seconds(timeout)), ..self.settings.clone() };
        let fixed: Vec<(String, f64)> = q.fixed_joint_names.iter().cloned().zip(q.fixed_joint_values.iter().copied()).collect();
        let prepared = match self.mechanisms[k].loaded.analysis.solve(&fixed, &settings) {
            Ok(p) => p,
            // The error may quote the request (a joint name): bounded.
            Err(e) => return Err(convert::bounded(&e.to_string(), convert::ECHO_MESSAGE)),
        };
        Ok((k, Box::new(move |c, p| Outcome::BoxSet(prepared.run(c, p)))))
    }

    /// A goal of the Solve action: accepted and executed at once; a goal the Solve service
    /// would refuse ends ABORTED with the reason in its result (a rejected goal carries none).
    async fn goal(&mut self, h: NewGoalHandle<SolveGoal>) {
        let Some(goal) = self.action.get_new_goal(h.clone()) else { return };
        let q = SolveRequest { mechanism: goal.mechanism, fixed_joint_names: goal.fixed_joint_names, fixed_joint_values: goal.fixed_joint_values, settings: goal.settings, wait: 0.0 };
        let prepared = catch_unwind(AssertUnwindSafe(|| self.solve_job(&q))).unwrap_or_else(|p| Err(format!("internal error while handling the goal: {}", panic_text(p.as_ref()))));
        let executing = match self.action.accept_goal(h).await {
            Ok(accepted) => self.action.start_executing_goal(accepted).await,
            Err(e) => Err(e),
        };
        let executing = match executing {
            Ok(x) => x,
            Err(e) => return eprintln!("linkspace: a Solve goal could not be started: {e:?}"),
        };
        match prepared {
            Err(message) => self.goal_result(executing, GoalEndStatus::Aborted, SolveActionResult { ok: false, message, ..Default::default() }),
            Ok((k, job)) => {
                let run = self.start(k, RunKind::SolveAction, job);
                self.runs.get_mut(&run).expect("invariant: just started").goal = Some(executing);
            }
        }
    }

    /// Sends a goal's result when its client asks for it (on smol's global executor, so the
    /// loop does not wait for the client); a client that never asks is given up after 60 s.
    fn goal_result(&self, h: ExecutingGoalHandle<SolveGoal>, end: GoalEndStatus, result: SolveActionResult) {
        let action = self.action.clone();
        smol::spawn(async move {
            let send = action.send_result_response(h, end, result);
            let give_up = async {
                smol::Timer::after(Duration::from_secs(60)).await;
                Err(GoalError::NoSuchGoal)
            };
            if let Err(e) = futures::future::select(Box::pin(send), Box::pin(give_up)).await.factor_first().0 {
                eprintln!("linkspace: sending a Solve action result: {e:?}");
            }
        })
        .detach();
    }

    /// A cancel request of the Solve action: the runs of the goals it names are cancelled
    /// (their incomplete results end the goals as CANCELED).
    async fn goal_cancel(&mut self, c: CancelHandle) {
        let mut cancelling = Vec::new();
        for r in self.runs.values() {
            if let Some(h) = &r.goal {
                if c.contains_goal(&h.goal_id()) {
                    r.cancel.store(true, Ordering::Relaxed);
                    cancelling.push(h.goal_id());
                }
            }
        }
        if let Err(e) = self.action.respond_to_cancel_requests(&c, cancelling.into_iter()).await {
            eprintln!("linkspace: answering a Solve action cancel: {e:?}");
        }
    }

    fn cancel(&mut self, q: CancelRequest) -> CancelResponse {
        match self.runs.get(&q.run_id) {
            Some(r) if r.kind.requested() => {
                r.cancel.store(true, Ordering::Relaxed);
                let prefix = &self.mechanisms[r.mechanism].prefix;
                let whereto = match r.kind {
                    RunKind::Solve => format!("will be published on {prefix}/solve_result"),
                    RunKind::SolveAction => format!("will be the action's result (status CANCELED) and published on {prefix}/solve_result"),
                    _ => "will be in the reply to its request".to_string(),
                };
                CancelResponse { ok: true, message: format!("run {} cancelled; its incomplete result {whereto}", q.run_id) }
            }
            Some(_) => CancelResponse { ok: false, message: format!("run {} is a load-time analysis and cannot be cancelled", q.run_id) },
            None if self.finished.contains(&q.run_id) => CancelResponse { ok: false, message: format!("run {} has already finished", q.run_id) },
            None => CancelResponse { ok: false, message: format!("no run {}", q.run_id) },
        }
    }

    /// Why a new requested run is refused, if it is: `max_runs` are going on.
    fn busy(&self) -> Option<String> {
        let busy = self.runs.values().filter(|r| r.kind.requested()).count();
        (busy >= self.limits.max_runs).then(|| format!("busy: {busy} requested runs are going on (the node's limit, --max-runs); retry when one ends or cancel a solve"))
    }

    /// A request's box limit: 0 means the node's limit; more is refused.
    fn box_limit(&self, max_boxes: u64) -> Result<u64, String> {
        match max_boxes {
            0 => Ok(self.limits.max_boxes),
            n if n > self.limits.max_boxes => Err(format!("max_boxes {n} is larger than this node's limit {} (--max-request-boxes)", self.limits.max_boxes)),
            n => Ok(n),
        }
    }

    /// Answers with the load-time report, or starts a run with the request's settings; `None`
    /// when the reply waits for a run.
    fn singularities(&mut self, id: RmwRequestId, q: SingularitiesRequest) -> Option<SingularitiesResponse> {
        let refuse = |message: String| Some(SingularitiesResponse { ok: false, message, report: convert::no_report() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let m = &self.mechanisms[k];
        let a = &m.loaded.analysis;
        if !a.services().contains(&Service::Singularities) {
            return refuse(a.not_available(Service::Singularities).to_string());
        }
        if q.precision == 0.0 {
            if let Some((report, _)) = &m.published_singularities {
                return Some(singularity_reply(report));
            }
            let Some(run) = m.singularity_run else { return refuse(format!("no singularity report for '{}': {}", q.mechanism, m.message)) };
            let deadline = Instant::now() + seconds(self.limits.max_wait);
            self.runs.get_mut(&run).expect("invariant: the load-time run is going").waiters.push((id, deadline));
            return None;
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let longest = self.limits.max_timeout.min(self.limits.max_wait);
        if !(q.timeout >= 0.0 && q.timeout <= longest) {
            return refuse(format!("timeout {} s is out of range: give 0 (the node's limit) to {longest} s (--max-request-timeout and --max-wait)", q.timeout));
        }
        let timeout = if q.timeout == 0.0 { longest } else { q.timeout };
        let query = SingularityQuery { precision: q.precision, nodes: q.nodes, max_boxes, timeout: Some(seconds(timeout)), threads: self.settings.threads };
        let prepared = match a.singularities(&query) {
            Ok(p) => p,
            Err(e) => return refuse(e.to_string()),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::Singularities { load_time: false }, Box::new(move |c, p| Outcome::Singularities(prepared.run(c, p))));
        // The searches stop at `timeout`; the margin covers building the report.
        let deadline = Instant::now() + seconds(timeout + 10.0);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        None
    }

    /// Validates and starts an inverse-kinematics run; `None` when the reply waits for it.
    fn inverse_kinematics(&mut self, id: RmwRequestId, q: InverseKinematicsRequest) -> Option<InverseKinematicsResponse> {
        let refuse = |message: String| Some(InverseKinematicsResponse { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let p = [q.point.x, q.point.y, q.point.z];
        if p.iter().any(|v| !v.is_finite()) {
            return refuse(format!("point ({}, {}, {}) is not finite", p[0], p[1], p[2]));
        }
        // Squares of the coordinates must stay finite (the analysis works with radius²); no
        // manipulator reaches that far anyway.
        const FARTHEST: f64 = 1e100;
        if p.iter().any(|v| v.abs() > FARTHEST) {
            return refuse(format!("point ({:e}, {:e}, {:e}) is out of range: give coordinates of at most {FARTHEST:e} m in magnitude", p[0], p[1], p[2]));
        }
        if !(q.sigma.is_finite() && q.sigma > 0.0) {
            return refuse(format!("sigma must be a positive finite number, got {}", q.sigma));
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let prepared = match self.mechanisms[k].loaded.analysis.inverse_kinematics(&IkQuery { point: p, precision: q.sigma, max_boxes, timeout: Some(seconds(self.limits.max_wait)), threads: self.settings.threads }) {
            Ok(p) => p,
            Err(e) => return refuse(convert::bounded(&e.to_string(), convert::ECHO_MESSAGE)),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::InverseKinematics, Box::new(move |c, p| Outcome::InverseKinematics(prepared.run(c, p))));
        // Bounded by boxes and by the node's longest wait, after which its reply could not be sent.
        let deadline = Instant::now() + seconds(self.limits.max_wait);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        None
    }

    /// The six joints of a loaded arm, or why there are none.
    /// Prepares `job` for mechanism `k` on the event loop (every check that needs no search:
    /// a bad request is answered at once) and starts its run on a thread of its own, bounded by
    /// `limits` and the node's threads; the reply waits at most the node's longest wait.
    fn start_job(&mut self, id: RmwRequestId, k: usize, kind: RunKind, job: crate::app::Job, limits: crate::app::Limits) -> Result<(), String> {
        let prepared = crate::app::prepare(&self.mechanisms[k].loaded.input, job).map_err(|e| e.to_string())?;
        if let Some(busy) = self.busy() {
            return Err(busy);
        }
        let threads = self.settings.threads.max(1);
        let run = self.start(
            k,
            kind,
            Box::new(move |cancel, progress| {
                let control = crate::app::Control { limits, threads, cancel };
                Outcome::Answer(prepared.run(&control, progress).map_err(|e| e.to_string()))
            }),
        );
        let deadline = Instant::now() + seconds(self.limits.max_wait);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        Ok(())
    }

    /// Certified inverse kinematics of a six-revolute arm's tip pose, run as every search of
    /// the node on a thread of its own; `None` when the reply waits for it. Bounded by the
    /// request's boxes and the node's longest wait, and counted against `--max-runs`.
    fn inverse_kinematics6(&mut self, id: RmwRequestId, q: InverseKinematics6Request) -> Option<InverseKinematics6Response> {
        let refuse = |message: String| Some(InverseKinematics6Response { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let (p, o) = (&q.pose.position, &q.pose.orientation);
        let pose = match crate::app::PoseInput::from_numbers(&[p.x, p.y, p.z, o.x, o.y, o.z, o.w]) {
            Ok(pose) => pose,
            Err(e) => return refuse(e.to_string()),
        };
        if !(q.sigma.is_finite() && q.sigma > 0.0 && q.sigma < 1.0) {
            return refuse(format!("sigma must be a number in (0, 1), got {}", q.sigma));
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let limits = crate::app::Limits { max_cells: max_boxes, timeout: Some(seconds(self.limits.max_wait)), ..Default::default() };
        let job = crate::app::Job::Ik6(crate::app::Ik6Job { arm: crate::app::LoadOptions::default(), pose, precision: q.sigma });
        self.start_job(id, k, RunKind::InverseKinematics6, job, limits).err().and_then(|e| refuse(format!("inverse_kinematics6: {e}")))
    }

    /// A joint path's singularities, run on a thread of its own as every search of the node,
    /// within the request's timeout (at most the node's longest wait); `None` when the reply
    /// waits for it.
    fn path_check(&mut self, id: RmwRequestId, q: PathCheckRequest) -> Option<PathCheckResponse> {
        let refuse = |message: String| Some(PathCheckResponse { ok: false, message, ..Default::default() });
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let set = match q.singular_set.as_str() {
            "6r" => Some(crate::app::PathSet::Arm6R),
            "3r" => Some(crate::app::PathSet::Positioning3R),
            "" => None,
            other => return refuse(format!("singular_set must be \"6r\", \"3r\" or empty, got \"{}\"", convert::bounded(other, convert::ECHO_NAME))),
        };
        let t = &q.trajectory;
        let mut waypoints: Vec<Vec<f64>> = Vec::with_capacity(t.points.len().min(1 << 16));
        for (k, point) in t.points.iter().enumerate() {
            if point.positions.len() != t.joint_names.len() {
                return refuse(format!("point {k} has {} positions for {} joint names", point.positions.len(), t.joint_names.len()));
            }
            waypoints.push(point.positions.clone());
        }
        let precision = if q.tolerance == 0.0 { crate::app::Job::default_precision("path-check") } else { q.tolerance };
        if !(q.timeout.is_finite() && q.timeout >= 0.0) {
            return refuse(format!("timeout must be a number of seconds >= 0, got {}", q.timeout));
        }
        let timeout = if q.timeout == 0.0 { self.limits.max_wait } else { q.timeout.min(self.limits.max_wait) };
        let limits = crate::app::Limits { timeout: Some(seconds(timeout)), ..crate::app::Job::default_limits("path-check") };
        let job = crate::app::Job::PathCheck(crate::app::PathCheckJob { arm: crate::app::LoadOptions::default(), waypoints, joint_names: t.joint_names.clone(), set, precision });
        let name = convert::bounded(&q.mechanism, convert::ECHO_NAME);
        self.start_job(id, k, RunKind::PathCheck, job, limits).err().and_then(|e| refuse(format!("path_check: '{name}': {e}")))
    }

    fn classify(&mut self, q: ClassifyRequest) -> ClassifyResponse {
        let refuse = |message: String| ClassifyResponse { ok: false, message, component: -1, ..Default::default() };
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return refuse(e),
        };
        let m = &self.mechanisms[k];
        let a = &m.loaded.analysis;
        if !a.services().contains(&Service::Classify) {
            return refuse(a.not_available(Service::Classify).to_string());
        }
        if q.joint_names.len() != q.joint_values.len() {
            return refuse(format!("{} joint names but {} values", q.joint_names.len(), q.joint_values.len()));
        }
        let free = a.free_joints();
        let mut values = vec![f64::NAN; free.len()];
        for (name, &v) in q.joint_names.iter().zip(&q.joint_values) {
            let Some(i) = free.iter().position(|f| f == name) else {
                return refuse(format!("'{}' is not a free joint of '{}' (free joints: {})", convert::bounded(name, convert::ECHO_NAME), q.mechanism, free.join(", ")));
            };
            if !v.is_finite() {
                return refuse(format!("joint '{name}': {v} is not a finite number"));
            }
            values[i] = v;
        }
        if let Some(i) = values.iter().position(|v| v.is_nan()) {
            return refuse(format!("no value for free joint '{}' (give every free joint: {})", free[i], free.join(", ")));
        }
        let c = match a.classify(&values, m.configuration_space.as_deref(), m.singularities.as_deref()) {
            Ok(c) => c,
            Err(AnalysisError::NotReady { what }) => {
                return refuse(format!("the {} of '{}' is not known yet ({}); retry when {}/{what} is published", what.replace('_', " "), q.mechanism, m.state.name(), m.prefix));
            }
            Err(e) => return refuse(e.to_string()),
        };
        let mut message = match c.component {
            Some(comp) if c.inside => format!("inside component {comp} of {}", c.components),
            Some(comp) => format!("outside every box; nearest is component {comp} of {} at distance {:.6}", c.components, c.distance),
            None if c.inside => format!("in no component of {}", c.components),
            None => "the configuration space is empty".to_string(),
        };
        match c.singular_distance {
            // The note says why when the analysis has singularities but no bound yet.
            None if a.services().contains(&Service::Singularities) => message.push_str("; distance to singularities unknown"),
            None => message.push_str(&format!("; distance to singularities unknown: {}", a.not_available(Service::Singularities))),
            Some(d) if d.is_infinite() => message.push_str("; no singular configuration"),
            Some(d) => message.push_str(&format!("; at least {d:.6} from every singular configuration")),
        }
        if !c.note.is_empty() {
            message.push_str(&format!(" ({})", c.note));
        }
        if m.configuration_space.as_ref().is_some_and(|cs| cs.status != Status::Finished) {
            message.push_str("; the configuration space is incomplete (undecided boxes are not classified)");
        }
        ClassifyResponse {
            ok: true,
            message,
            inside: c.inside,
            component: c.component.map_or(-1, |x| x as i32),
            components: c.components as u32,
            distance: c.distance,
            singular_distance_known: c.singular_distance.is_some(),
            singular_distance: c.singular_distance.unwrap_or(f64::NAN),
        }
    }

    fn list(&self) -> ListMechanismsResponse {
        ListMechanismsResponse {
            mechanisms: self
                .mechanisms
                .iter()
                .map(|m| {
                    let a = &m.loaded.analysis;
                    let fixed = a.fixed_joints();
                    MechanismInfo {
                        name: a.mechanism().to_string(),
                        kind: a.kind().name().to_string(),
                        services: a.services().iter().map(|s| s.name().to_string()).collect(),
                        free_joints: a.free_joints(),
                        fixed_joint_names: fixed.iter().map(|(n, _)| n.clone()).collect(),
                        fixed_joint_values: fixed.iter().map(|(_, v)| *v).collect(),
                        state: m.state.name().to_string(),
                        message: if m.message.is_empty() && a.services().is_empty() { a.limitation() } else { m.message.clone() },
                        topic_prefix: m.prefix.clone(),
                    }
                })
                .collect(),
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

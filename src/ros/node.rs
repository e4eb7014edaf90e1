//! The event loop: context → node → topics and servers → spinner → one loop over `Event`.
//!
//! Every trigger of work is an `Event` on one channel: a decoded service request, progress or
//! the end of a run (from its thread), and a clock tick that answers requests whose wait ran
//! out. The loop owns all state, so no locks; handlers run under `catch_unwind`, so a request
//! that trips a bug is answered with an error instead of taking the node down.
//!
//! Runs (the load-time analyses, requested solves, singularity and inverse-kinematics queries)
//! go on threads of their own. At most `Limits::max_runs` requested runs go on at once, each
//! bounded by the request's `max_boxes` and `timeout` (within the node's limits), so memory
//! stays bounded however many requests arrive: the excess is refused with a reason.

use super::convert;
use super::msgs::{self, *};
use super::{Limits, Loaded, Mapping, Network, ServeConfig};
use crate::analysis::{AnalysisError, BoxSetResult, IkQuery, IkResult, Service, SingularityQuery, SingularityResult};
use crate::search::{SolverSettings, Status};
use anyhow::{Context as _, Result};
use futures::StreamExt;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Context, Message, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile, RmwRequestId, Server, ServiceMapping, ServiceTypeName};
use std::collections::{BTreeMap, VecDeque};
use std::net::{IpAddr, Ipv4Addr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Everything that makes the loop do something.
enum Event {
    Request(Request),
    Progress { run: u64, progress: crate::search::Progress },
    /// A run ended; `Err` when it panicked (its payload, as text).
    Finished { run: u64, result: Result<Outcome, String> },
    Tick,
    /// Time to publish the latest configuration spaces again (`--republish`).
    Republish,
}

/// What a run returns.
enum Outcome {
    BoxSet(BoxSetResult),
    Singularities(SingularityResult),
    InverseKinematics(IkResult),
}

impl Outcome {
    /// (boxes processed, boxes left pending, complete) for the final progress message.
    fn counts(&self) -> (u64, usize, bool) {
        match self {
            Outcome::BoxSet(r) => (r.stats.processed, r.boxes.iter().filter(|b| b.status == crate::search::BoxStatus::Undecided).count(), r.status == Status::Complete),
            Outcome::Singularities(r) => (r.processed, r.undecided(), r.status == Status::Complete),
            Outcome::InverseKinematics(r) => (r.processed, 0, r.status == Status::Complete),
        }
    }
}

/// A run's work, moved to its thread.
type Job = Box<dyn FnOnce(&AtomicBool, &mut dyn FnMut(&crate::search::Progress)) -> Outcome + Send>;

/// A decoded service request with the id its reply must carry.
enum Request {
    Solve(RmwRequestId, SolveRequest),
    Cancel(RmwRequestId, CancelRequest),
    Singularities(RmwRequestId, SingularitiesRequest),
    InverseKinematics(RmwRequestId, InverseKinematicsRequest),
    Classify(RmwRequestId, ClassifyRequest),
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
}

struct Servers {
    solve: Server<SolveRequest, SolveResponse>,
    cancel: Server<CancelRequest, CancelResponse>,
    singularities: Server<SingularitiesRequest, SingularitiesResponse>,
    inverse_kinematics: Server<InverseKinematicsRequest, InverseKinematicsResponse>,
    classify: Server<ClassifyRequest, ClassifyResponse>,
    list: Server<ListMechanismsRequest, ListMechanismsResponse>,
}

/// What a run is for, which decides where its result goes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum RunKind {
    ConfigurationSpace,
    Solve,
    /// `load_time`: the run made at load, published on `~/<robot>/singularities`; otherwise a
    /// Singularities request with its own settings, answered in the reply only.
    Singularities { load_time: bool },
    InverseKinematics,
}

impl RunKind {
    /// Runs started by a request, which count against `Limits::max_runs`.
    fn requested(self) -> bool {
        matches!(self, RunKind::Solve | RunKind::Singularities { load_time: false } | RunKind::InverseKinematics)
    }

    /// The `analysis` field of its progress messages.
    fn analysis(self) -> &'static str {
        match self {
            RunKind::ConfigurationSpace => "configuration_space",
            RunKind::Solve => "solve",
            RunKind::Singularities { .. } => "singularities",
            RunKind::InverseKinematics => "inverse_kinematics",
        }
    }
}

struct Run {
    mechanism: usize,
    kind: RunKind,
    cancel: Arc<AtomicBool>,
    /// Requests waiting for this run (of the service its kind answers), with when to stop
    /// waiting.
    waiters: Vec<(RmwRequestId, Instant)>,
    /// The latest share of the volume decided.
    decided: f64,
}

struct Mechanism {
    loaded: Loaded,
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
    state: String,
    message: String,
}

struct State {
    mechanisms: Vec<Mechanism>,
    servers: Rc<Servers>,
    runs: BTreeMap<u64, Run>,
    /// Recently finished run ids, so Cancel can tell "finished" from "unknown".
    finished: VecDeque<u64>,
    next_run: u64,
    limits: Limits,
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
    let mut builder = DomainParticipantBuilder::new(config.domain);
    if config.network == Network::Loopback {
        // RustDDS then announces and sends only on 127.0.0.1, and finds same-host participants
        // by unicast to the well-known discovery ports on loopback.
        builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
    }
    let participant = builder.build().with_context(|| format!("joining DDS domain {}", config.domain))?;
    let context = Context::from_domain_participant(participant).context("creating the ROS 2 context")?;
    let node_name = NodeName::new(&config.namespace, &config.node_name).with_context(|| format!("node name {}/{}", config.namespace, config.node_name))?;
    let mut node = context.new_node(node_name, NodeOptions::new().enable_rosout(true)).context("creating the node")?;
    let base = format!("{}/{}", config.namespace.trim_end_matches('/'), config.node_name);
    let mapping = match config.mapping {
        Mapping::Enhanced => ServiceMapping::Enhanced,
        Mapping::Cyclone => ServiceMapping::Cyclone,
        Mapping::Basic => ServiceMapping::Basic,
    };

    let mut mechanisms = Vec::new();
    for l in loaded {
        let prefix = format!("{base}/{}", l.token);
        let topics = Topics {
            configuration_space: publisher(&mut node, &prefix, "configuration_space", "linkspace_msgs", "BoxSet", latched(1))?,
            solve_result: publisher(&mut node, &prefix, "solve_result", "linkspace_msgs", "BoxSet", latched(1))?,
            singularities: publisher(&mut node, &prefix, "singularities", "linkspace_msgs", "SingularityReport", latched(1))?,
            progress: publisher(&mut node, &prefix, "progress", "linkspace_msgs", "Progress", latched(1))?,
            markers: publisher(&mut node, &prefix, "markers", "visualization_msgs", "MarkerArray", latched(1))?,
            // Deep enough for every assembly mode of one result.
            assembly_modes: publisher(&mut node, &prefix, "assembly_modes", "sensor_msgs", "JointState", latched(64))?,
        };
        mechanisms.push(Mechanism {
            loaded: l,
            prefix,
            topics,
            configuration_space: None,
            published: None,
            singularities: None,
            published_singularities: None,
            singularity_run: None,
            state: "running".into(),
            message: String::new(),
        });
    }
    let servers = Rc::new(Servers {
        solve: server(&mut node, mapping, &base, "solve", "Solve")?,
        cancel: server(&mut node, mapping, &base, "cancel", "Cancel")?,
        singularities: server(&mut node, mapping, &base, "singularities", "Singularities")?,
        inverse_kinematics: server(&mut node, mapping, &base, "inverse_kinematics", "InverseKinematics")?,
        classify: server(&mut node, mapping, &base, "classify", "Classify")?,
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

    // Bounded: a flood of requests waits in DDS (and is eventually refused) instead of
    // growing this queue.
    let (tx, rx) = smol::channel::bounded::<Event>(256);
    forward(&ex, servers.clone(), |s| &s.solve, Request::Solve, tx.clone());
    forward(&ex, servers.clone(), |s| &s.cancel, Request::Cancel, tx.clone());
    forward(&ex, servers.clone(), |s| &s.singularities, Request::Singularities, tx.clone());
    forward(&ex, servers.clone(), |s| &s.inverse_kinematics, Request::InverseKinematics, tx.clone());
    forward(&ex, servers.clone(), |s| &s.classify, Request::Classify, tx.clone());
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

    let mut state = State {
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
    state.start_load_time_runs();
    eprintln!(
        "linkspace: ready: node {base} on domain {} ({:?} mapping, {:?} network), mechanisms: {}",
        config.domain,
        config.mapping,
        config.network,
        state.mechanisms.iter().map(|m| m.prefix.as_str()).collect::<Vec<_>>().join(" ")
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

/// A Singularities reply carrying `report`, cut to what a service reply can carry.
fn singularity_reply(report: &SingularityReport, topic: &str) -> SingularitiesResponse {
    let mut report = report.clone();
    let mut message = report.message.clone();
    if let Some(note) = convert::fit_singularity_reply(&mut report, topic) {
        message = format!("{message}; {note}");
    }
    SingularitiesResponse { ok: true, message, report }
}

impl State {
    fn start_load_time_runs(&mut self) {
        for k in 0..self.mechanisms.len() {
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
                Err(e) => eprintln!("linkspace: {}: no configuration space: {e}", self.mechanisms[k].loaded.analysis.mechanism()),
            }
            match singular {
                Ok(prepared) => {
                    let run = self.start(k, RunKind::Singularities { load_time: true }, Box::new(move |c, p| Outcome::Singularities(prepared.run(c, p))));
                    self.mechanisms[k].singularity_run = Some(run);
                    started = true;
                }
                Err(e) => self.publish_no_singularities(k, e.to_string()),
            }
            if !started {
                let m = &mut self.mechanisms[k];
                m.state = "unavailable".into();
                m.message = m.loaded.analysis.limitation();
            }
        }
    }

    /// Publishes that the mechanism has no singularity analysis (ok = false, with the reason),
    /// so that a subscriber learns why instead of waiting.
    fn publish_no_singularities(&self, k: usize, reason: String) {
        let m = &self.mechanisms[k];
        let report = SingularityReport { header: convert::header(""), mechanism: m.loaded.analysis.mechanism().to_string(), ok: false, message: reason, ..Default::default() };
        if let Err(e) = m.topics.singularities.publish(report) {
            eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
        }
    }

    /// Starts `job` on a thread of its own; returns its run id.
    fn start(&mut self, mechanism: usize, kind: RunKind, job: Job) -> u64 {
        let run = self.next_run;
        self.next_run += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        self.runs.insert(run, Run { mechanism, kind, cancel: cancel.clone(), waiters: Vec::new(), decided: 0.0 });
        let events = self.events.clone();
        std::thread::spawn(move || {
            let progress_events = events.clone();
            let mut progress = move |p: &crate::search::Progress| {
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
            Event::Republish => self.republish().await,
        }
    }

    fn progress(&self, run: u64, p: crate::search::Progress, done: bool) {
        let Some(r) = self.runs.get(&run) else { return };
        // An inverse-kinematics query is answered in its reply; it has no volume to report.
        if r.kind == RunKind::InverseKinematics {
            return;
        }
        let m = &self.mechanisms[r.mechanism];
        let msg = msgs::Progress {
            header: convert::header(""),
            mechanism: m.loaded.analysis.mechanism().to_string(),
            analysis: r.kind.analysis().into(),
            run_id: run,
            processed: p.processed,
            pending: p.pending as u64,
            decided: p.decided,
            done,
        };
        if let Err(e) = m.topics.progress.publish(msg) {
            eprintln!("linkspace: publishing {}/progress: {e:?}", m.prefix);
        }
    }

    async fn finished(&mut self, run: u64, result: Result<Outcome, String>) {
        let (processed, pending, complete) = result.as_ref().map_or((0, 0, false), |o| o.counts());
        // What a limit left undecided is still pending.
        let decided = if complete { 1.0 } else { self.runs.get(&run).map_or(0.0, |r| r.decided) };
        self.progress(run, crate::search::Progress { processed, pending, decided }, true);
        let Some(r) = self.runs.remove(&run) else { return };
        self.finished.push_back(run);
        if self.finished.len() > 4096 {
            self.finished.pop_front();
        }
        let name = self.mechanisms[r.mechanism].loaded.analysis.mechanism().to_string();
        let outcome = match result {
            Ok(outcome) => outcome,
            Err(panic) => {
                let message = format!("run {run} of '{name}' failed: internal error: {panic}");
                eprintln!("linkspace: {message}");
                let m = &mut self.mechanisms[r.mechanism];
                if matches!(r.kind, RunKind::ConfigurationSpace | RunKind::Singularities { load_time: true }) {
                    m.state = "failed".into();
                    m.message = message.clone();
                }
                if r.kind == (RunKind::Singularities { load_time: true }) {
                    m.singularity_run = None;
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
                eprintln!("linkspace: {name}: run {run} (inverse kinematics): {} solutions, {} boxes, {:.3} s", result.solutions.len(), result.processed, result.seconds);
                let mut reply = convert::ik_response(&result);
                if let Some(note) = convert::fit_ik_reply(&mut reply) {
                    reply.message = format!("{}; {note}", reply.message);
                }
                for (id, _) in r.waiters {
                    self.reply_ik(id, reply.clone());
                }
            }
        }
    }

    async fn finished_box_set(&mut self, run: u64, r: Run, result: BoxSetResult) {
        let m = &mut self.mechanisms[r.mechanism];
        let name = m.loaded.analysis.mechanism().to_string();
        let set = convert::box_set(&result, run);
        let status = match result.status {
            Status::Complete => "complete".to_string(),
            Status::Incomplete(l) => format!("incomplete ({} limit)", convert::limit_name(l)),
        };
        eprintln!("linkspace: {name}: run {run} ({:?}) {status}: {} boxes, {} clusters, {:.3} s", r.kind, result.boxes.len(), result.clusters, result.stats.seconds);
        match r.kind {
            RunKind::ConfigurationSpace => {
                m.state = if result.status == Status::Complete { "complete".into() } else { "incomplete".into() };
                m.message = format!("run {run}: {status}, {} boxes in {} clusters", result.boxes.len(), result.clusters);
                let markers = convert::markers(&result, &m.loaded.root_link, self.limits.max_markers);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
                if let Err(e) = m.topics.markers.async_publish(markers.clone()).await {
                    eprintln!("linkspace: publishing {}/markers: {e:?}", m.prefix);
                }
                m.published = Some((set, markers));
                for js in convert::assembly_modes(&result) {
                    if let Err(e) = m.topics.assembly_modes.async_publish(js).await {
                        eprintln!("linkspace: publishing {}/assembly_modes: {e:?}", m.prefix);
                    }
                }
                m.configuration_space = Some(Arc::new(result));
                eprintln!("linkspace: {name}: published configuration_space");
            }
            RunKind::Solve => {
                if let Err(e) = m.topics.solve_result.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/solve_result: {e:?}", m.prefix);
                }
                let mut message = format!("run {run}: {status}");
                let mut reply_set = set.clone();
                if convert::box_set_bytes(&set) > convert::REPLY_BUDGET {
                    convert::strip_boxes(&mut reply_set);
                    message.push_str(&format!(
                        "; its {} boxes are left out of this reply (a service reply must stay under {} KiB) and are on {}/solve_result",
                        set.box_status.len(),
                        convert::REPLY_BUDGET / 1024,
                        m.prefix
                    ));
                }
                for (id, _) in r.waiters {
                    self.reply_solve(id, SolveResponse { ok: true, message: message.clone(), run_id: run, done: true, result: reply_set.clone() });
                }
                eprintln!("linkspace: {name}: published solve_result of run {run}");
            }
            RunKind::Singularities { .. } | RunKind::InverseKinematics => eprintln!("linkspace: {name}: run {run} returned a box set for a {:?} run", r.kind),
        }
    }

    async fn finished_singularities(&mut self, run: u64, r: Run, result: SingularityResult) {
        let report = convert::singularity_report(&result, run);
        let m = &mut self.mechanisms[r.mechanism];
        let name = m.loaded.analysis.mechanism().to_string();
        eprintln!("linkspace: {name}: run {run} (singularities, precision {}): {}, {:.3} s", result.query.precision, result.summary, result.seconds);
        if r.kind == (RunKind::Singularities { load_time: true }) {
            m.state = if result.status == Status::Complete { "complete".into() } else { "incomplete".into() };
            m.message = format!("run {run}: {}", result.summary);
            let markers = convert::singularity_markers(&result, self.limits.max_markers);
            if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
            }
            if let Err(e) = m.topics.markers.async_publish(markers.clone()).await {
                eprintln!("linkspace: publishing {}/markers: {e:?}", m.prefix);
            }
            m.published_singularities = Some((report.clone(), markers));
            m.singularities = Some(Arc::new(result));
            m.singularity_run = None;
            eprintln!("linkspace: {name}: published singularities");
        }
        let reply = singularity_reply(&report, &format!("{}/singularities", self.mechanisms[r.mechanism].prefix));
        for (id, _) in r.waiters {
            self.reply_singularities(id, reply.clone());
        }
    }

    /// Publishes every latest configuration space (and its markers) again, stamped now: for
    /// tools that subscribe with volatile durability (RViz's default), and for throughput
    /// measurements.
    async fn republish(&mut self) {
        for m in &mut self.mechanisms {
            if let Some((set, markers)) = &mut m.published {
                set.header = convert::header(&set.header.frame_id);
                if let Err(e) = m.topics.configuration_space.async_publish(set.clone()).await {
                    eprintln!("linkspace: publishing {}/configuration_space: {e:?}", m.prefix);
                }
                if let Err(e) = m.topics.markers.async_publish(markers.clone()).await {
                    eprintln!("linkspace: publishing {}/markers: {e:?}", m.prefix);
                }
            }
            if let Some((report, markers)) = &mut m.published_singularities {
                report.header = convert::header(&report.header.frame_id);
                if let Err(e) = m.topics.singularities.async_publish(report.clone()).await {
                    eprintln!("linkspace: publishing {}/singularities: {e:?}", m.prefix);
                }
                if let Err(e) = m.topics.markers.async_publish(markers.clone()).await {
                    eprintln!("linkspace: publishing {}/markers: {e:?}", m.prefix);
                }
            }
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
            RunKind::Solve | RunKind::ConfigurationSpace => self.reply_solve(id, solve_error(message)),
            RunKind::Singularities { .. } => self.reply_singularities(id, SingularitiesResponse { ok: false, message, ..Default::default() }),
            RunKind::InverseKinematics => self.reply_ik(id, InverseKinematicsResponse { ok: false, message, ..Default::default() }),
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
                Err(p) => servers.singularities.send_response(id, SingularitiesResponse { ok: false, message: internal(p), ..Default::default() }),
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
            format!("no mechanism named '{name}' is loaded (loaded: {})", names.join(", "))
        })
    }

    /// Validates and starts a run; `None` when the reply waits for the run.
    fn solve(&mut self, id: RmwRequestId, q: SolveRequest) -> Option<SolveResponse> {
        let k = match self.mechanism(&q.mechanism) {
            Ok(k) => k,
            Err(e) => return Some(solve_error(e)),
        };
        let limits = &self.limits;
        let s = &q.settings;
        if q.fixed_joint_names.len() != q.fixed_joint_values.len() {
            return Some(solve_error(format!("{} fixed joint names but {} values", q.fixed_joint_names.len(), q.fixed_joint_values.len())));
        }
        if s.max_boxes == 0 {
            return Some(solve_error(format!("settings.max_boxes must be given: every run is bounded (1 to {})", limits.max_boxes)));
        }
        if s.max_boxes > limits.max_boxes {
            return Some(solve_error(format!("settings.max_boxes {} is larger than this node's limit {} (--max-request-boxes)", s.max_boxes, limits.max_boxes)));
        }
        if !(s.timeout > 0.0 && s.timeout <= limits.max_timeout) {
            return Some(solve_error(format!("settings.timeout {} s is out of range: give 0 < timeout <= {} s (--max-request-timeout)", s.timeout, limits.max_timeout)));
        }
        if !(q.wait >= 0.0 && q.wait <= limits.max_wait) {
            return Some(solve_error(format!("wait {} s is out of range: give 0 <= wait <= {} s", q.wait, limits.max_wait)));
        }
        if let Some(busy) = self.busy() {
            return Some(solve_error(busy));
        }
        let settings = SolverSettings { sigma: s.sigma, rho: s.rho, max_boxes: s.max_boxes, timeout: Some(Duration::from_secs_f64(s.timeout)), ..self.settings.clone() };
        let fixed: Vec<(String, f64)> = q.fixed_joint_names.iter().cloned().zip(q.fixed_joint_values.iter().copied()).collect();
        let prepared = match self.mechanisms[k].loaded.analysis.solve(&fixed, &settings) {
            Ok(p) => p,
            Err(e) => return Some(solve_error(e.to_string())),
        };
        let run = self.start(k, RunKind::Solve, Box::new(move |c, p| Outcome::BoxSet(prepared.run(c, p))));
        if q.wait > 0.0 {
            let r = self.runs.get_mut(&run).expect("invariant: just started");
            r.waiters.push((id, Instant::now() + Duration::from_secs_f64(q.wait)));
            None
        } else {
            Some(SolveResponse { ok: true, message: format!("run {run} started; its result will be published on {}/solve_result", self.mechanisms[k].prefix), run_id: run, done: false, ..Default::default() })
        }
    }

    fn cancel(&mut self, q: CancelRequest) -> CancelResponse {
        match self.runs.get(&q.run_id) {
            Some(r) if r.kind == RunKind::Solve => {
                r.cancel.store(true, Ordering::Relaxed);
                let prefix = &self.mechanisms[r.mechanism].prefix;
                CancelResponse { ok: true, message: format!("run {} cancelled; its incomplete result will be published on {prefix}/solve_result", q.run_id) }
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
        let refuse = |message: String| Some(SingularitiesResponse { ok: false, message, ..Default::default() });
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
                return Some(singularity_reply(report, &format!("{}/singularities", m.prefix)));
            }
            let Some(run) = m.singularity_run else { return refuse(format!("no singularity report for '{}': {}", q.mechanism, m.message)) };
            let deadline = Instant::now() + Duration::from_secs_f64(self.limits.max_wait);
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
        let query = SingularityQuery { precision: q.precision, nodes: q.nodes, max_boxes, timeout: Some(Duration::from_secs_f64(timeout)), threads: self.settings.threads };
        let prepared = match a.singularities(&query) {
            Ok(p) => p,
            Err(e) => return refuse(e.to_string()),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::Singularities { load_time: false }, Box::new(move |c, p| Outcome::Singularities(prepared.run(c, p))));
        // The searches stop at `timeout`; the margin covers building the report.
        let deadline = Instant::now() + Duration::from_secs_f64(timeout + 10.0);
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
        if !(q.sigma.is_finite() && q.sigma > 0.0) {
            return refuse(format!("sigma must be a positive finite number, got {}", q.sigma));
        }
        let max_boxes = match self.box_limit(q.max_boxes) {
            Ok(n) => n,
            Err(e) => return refuse(e),
        };
        let prepared = match self.mechanisms[k].loaded.analysis.inverse_kinematics(&IkQuery { point: p, precision: q.sigma, max_boxes, threads: self.settings.threads }) {
            Ok(p) => p,
            Err(e) => return refuse(e.to_string()),
        };
        if let Some(busy) = self.busy() {
            return refuse(busy);
        }
        let run = self.start(k, RunKind::InverseKinematics, Box::new(move |c, p| Outcome::InverseKinematics(prepared.run(c, p))));
        // Bounded by boxes, not time: the node's longest wait is the safety net.
        let deadline = Instant::now() + Duration::from_secs_f64(self.limits.max_wait);
        self.runs.get_mut(&run).expect("invariant: just started").waiters.push((id, deadline));
        None
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
                return refuse(format!("'{name}' is not a free joint of '{}' (free joints: {})", q.mechanism, free.join(", ")));
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
                return refuse(format!("the {} of '{}' is not known yet ({}); retry when {}/{what} is published", what.replace('_', " "), q.mechanism, m.state, m.prefix));
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
            None => message.push_str(&format!("; distance to singularities unknown: {}", a.not_available(Service::Singularities))),
            Some(d) => message.push_str(&format!("; at least {d:.6} from every singular configuration")),
        }
        if !c.note.is_empty() {
            message.push_str(&format!(" ({})", c.note));
        }
        if m.configuration_space.as_ref().is_some_and(|cs| cs.status != Status::Complete) {
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
                        kind: a.kind().to_string(),
                        services: a.services().iter().map(|s| s.name().to_string()).collect(),
                        free_joints: a.free_joints(),
                        fixed_joint_names: fixed.iter().map(|(n, _)| n.clone()).collect(),
                        fixed_joint_values: fixed.iter().map(|(_, v)| *v).collect(),
                        state: m.state.clone(),
                        message: if m.message.is_empty() && a.services().is_empty() { a.limitation() } else { m.message.clone() },
                        topic_prefix: m.prefix.clone(),
                    }
                })
                .collect(),
        }
    }
}

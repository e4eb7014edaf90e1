//! The ROS 2 node (`linkspace serve`): the only module that knows ros2-client, QoS, CDR and
//! async.
//!
//! `serve` loads every mechanism first (bad input fails before any DDS traffic), then joins
//! the DDS domain and runs the event loop of `node`. The analyses themselves (`crate::app`)
//! run on threads of their own and know nothing of ROS.
//!
//! Files: `msgs` mirrors `msgs/` (the wire types), `convert` turns results into messages,
//! `node` is the event loop with the publishers and service servers.

/// A line on stderr that never panics (`eprintln!` does when stderr is closed): a node whose
/// launcher went away and took its stderr pipe keeps serving instead of dying at its next line.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

mod convert;
pub(crate) mod msgs;
mod node;

pub use convert::bounded;

use crate::app::{self, Analysis};

use crate::app::SolverSettings;
use anyhow::{bail, Context as _, Result};

/// How service requests and replies are laid out on DDS; it must match the caller's RMW.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mapping {
    /// rmw_fastrtps_cpp (Jazzy's default) and rmw_connextdds: the RPC-over-DDS "enhanced"
    /// mapping, request ids in the sample metadata.
    Enhanced,
    /// rmw_cyclonedds_cpp: a 16-byte header (client id, sequence number) before the body.
    Cyclone,
    /// The RPC-over-DDS "basic" mapping (untested against any RMW).
    Basic,
}

/// Which network interfaces DDS may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Network {
    /// 127.0.0.1 only: discovery by unicast to the well-known ports on loopback.
    Loopback,
    /// Every interface, with multicast discovery: what a ROS 2 node normally does.
    All,
}

/// Default of `ServeConfig::max_history_bytes`, in MiB: four replies of 16 MB.
pub const DEFAULT_MAX_HISTORY_MB: usize = 64;

/// What a request may ask for; beyond it the node refuses with a reason.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeLimits {
    /// Largest `settings.max_boxes` of a Solve request.
    pub max_boxes: u64,
    /// Largest `settings.timeout` of a Solve request, seconds.
    pub max_timeout: f64,
    /// Longest `wait` of a Solve request (and longest wait of the other queries), seconds.
    pub max_wait: f64,
    /// Requested runs that may go on at once; more are refused until one ends.
    pub max_runs: usize,
    /// Boxes drawn per marker namespace.
    pub max_markers: usize,
    /// Largest box set sent (topic sample or reply), megabytes of box columns: a larger one is
    /// sent merged into fewer boxes (`BoxSet.merged_from`).
    pub max_set_megabytes: f64,
}

impl Default for NodeLimits {
    fn default() -> Self {
        Self { max_boxes: 200_000, max_timeout: 300.0, max_wait: 30.0, max_runs: 4, max_markers: 20_000, max_set_megabytes: 16.0 }
    }
}

/// ROS 2's log severities, least severe first: the node writes lines at `ServeConfig::log_level`
/// and above (`--ros-args --log-level`), on stderr and `/rosout` alike.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// Detail for debugging.
    Debug,
    /// Progress: ready, each finished run, new descriptions, parameter changes.
    #[default]
    Info,
    /// Something the user should look at (a name taken twice, an analysis not available).
    Warn,
    /// A refused description, an internal error.
    Error,
    /// The node cannot go on.
    Fatal,
}

/// A URDF to load, with a label for error messages (its path, or `robot_description`).
#[derive(Clone, Debug)]
pub struct Source {
    /// Where it came from.
    pub label: String,
    /// The URDF text.
    pub xml: String,
    /// It is the node's `robot_description` parameter: setting the parameter (or a message on
    /// `--robot-description-topic`) replaces this mechanism.
    pub description: bool,
}

/// Everything `serve` needs.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// The mechanisms.
    pub sources: Vec<Source>,
    /// Load-time fixed joints: (robot or `None` for every robot, joint, value).
    pub fixed: Vec<(Option<String>, String, f64)>,
    /// Traced points: (robot or `None`, link, x, y).
    pub traces: Vec<(Option<String>, String, f64, f64)>,
    /// Settings of the load-time analyses.
    pub settings: SolverSettings,
    /// Precision (radians) of the load-time singularity analyses of 3R manipulators.
    pub precision: f64,
    /// DDS domain (ROS_DOMAIN_ID).
    pub domain: u16,
    /// Node namespace, e.g. `/` or `/robots`.
    pub namespace: String,
    /// Node name.
    pub node_name: String,
    /// Service mapping.
    pub mapping: Mapping,
    /// Network interfaces.
    pub network: Network,
    /// Request limits.
    pub limits: NodeLimits,
    /// Publish the configuration spaces again at this period (none: only when they change).
    pub republish: Option<std::time::Duration>,
    /// Most bytes of samples each DDS writer of the node (a service's replies, a topic) keeps
    /// for repair and late joiners, and each topic the node reads (a service's requests) keeps
    /// once received; the oldest go first, the newest always stays.
    pub max_history_bytes: usize,
    /// Take URDFs from this topic (std_msgs/String, TransientLocal), e.g. `/robot_description`.
    pub robot_description_topic: Option<String>,
    /// Log to `/rosout` as well as stderr.
    pub rosout: bool,
    /// The least severe lines written.
    pub log_level: Severity,
}

/// A loaded mechanism, ready for the node.
pub(crate) struct Loaded {
    pub analysis: Box<dyn Analysis>,
    /// The ground link, the frame of world-space markers.
    pub root_link: String,
    /// The robot name as a ROS name token.
    pub token: String,
    /// It came from the `robot_description` parameter or topic (see `Source::description`).
    pub description: bool,
    /// The mechanism as the front door takes it: every job the node runs is prepared on it.
    pub input: std::sync::Arc<app::Input>,
}

/// A robot name as one token of a ROS name: letters, digits and single underscores, not
/// starting with a digit.
pub(crate) fn name_token(name: &str) -> String {
    let mut t = String::new();
    for c in name.chars() {
        let c = if c.is_ascii_alphanumeric() { c } else { '_' };
        if !(c == '_' && t.ends_with('_')) {
            t.push(c);
        }
    }
    let t = t.trim_matches('_').to_string();
    if t.is_empty() || t.starts_with(|c: char| c.is_ascii_digit()) {
        format!("m_{t}")
    } else {
        t
    }
}

/// Parses and formulates one URDF with the load-time fixes and traces that name its robot (or
/// no robot); marks in `used_fixes`, `used_traces` which ones applied.
pub(crate) fn load_one(s: &Source, config: &ServeConfig, used_fixes: &mut [bool], used_traces: &mut [bool]) -> Result<Loaded> {
    let m = app::parse_urdf(&s.xml).with_context(|| format!("loading {}", s.label))?;
    let mine = |robot: &Option<String>| robot.as_deref().is_none_or(|r| r == m.name);
    let mut fixed: Vec<(String, f64)> = Vec::new();
    for (k, (robot, joint, value)) in config.fixed.iter().enumerate() {
        if mine(robot) {
            used_fixes[k] = true;
            if fixed.iter().any(|(j, _)| j == joint) {
                bail!("loading {}: joint '{joint}' is fixed twice (--fix)", s.label);
            }
            fixed.push((joint.clone(), *value));
        }
    }
    let mut traces = Vec::new();
    for (k, (robot, link, x, y)) in config.traces.iter().enumerate() {
        if mine(robot) {
            used_traces[k] = true;
            traces.push((link.clone(), *x, *y));
        }
    }
    let analysis = app::load_urdf(&m, &fixed, &traces).with_context(|| format!("loading {}", s.label))?;
    Ok(Loaded { analysis, root_link: m.links[m.root].name.clone(), token: name_token(&m.name), description: s.description, input: std::sync::Arc::new(app::Input::Mechanism(m)) })
}

/// Parses and formulates every mechanism of `config`.
pub(crate) fn load(config: &ServeConfig) -> Result<Vec<Loaded>> {
    let mut loaded: Vec<Loaded> = Vec::new();
    let mut used_fixes = vec![false; config.fixed.len()];
    let mut used_traces = vec![false; config.traces.len()];
    for s in &config.sources {
        let l = load_one(s, config, &mut used_fixes, &mut used_traces)?;
        let name = l.analysis.mechanism().to_string();
        if loaded.iter().any(|o| o.analysis.mechanism() == name || o.token == l.token) {
            bail!("{}: a mechanism named '{name}' is already loaded", s.label);
        }
        loaded.push(l);
    }
    // With a description topic, a fix or trace may name a robot that has not arrived yet.
    let later = config.robot_description_topic.is_some();
    if let Some(k) = used_fixes.iter().position(|u| !u).filter(|_| !later) {
        bail!("--fix {}:{}: no mechanism of that name is loaded", config.fixed[k].0.as_deref().unwrap_or(""), config.fixed[k].1);
    }
    if let Some(k) = used_traces.iter().position(|u| !u).filter(|_| !later) {
        bail!("--trace {}:{}: no mechanism of that name is loaded", config.traces[k].0.as_deref().unwrap_or(""), config.traces[k].1);
    }
    if loaded.is_empty() && config.robot_description_topic.is_none() {
        bail!("no mechanism to serve: give at least one URDF, --robot-description, -p robot_description:=... or --robot-description-topic");
    }
    Ok(loaded)
}

/// Why the node could not start, or stopped: one line, the context chain outermost first
/// ("loading robot.urdf: ...", "joining DDS domain 7: ..."). Opaque: the middleware's own
/// error types stay inside this module.
#[derive(Debug, thiserror::Error)]
#[error("{0:#}")]
pub struct ServeError(anyhow::Error);

/// Runs the node until the process is stopped.
pub fn serve(config: ServeConfig) -> Result<(), ServeError> {
    let loaded = load(&config).map_err(ServeError)?;
    node::run(config, loaded).map_err(ServeError)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robot_names_become_valid_tokens() {
        assert_eq!(name_token("four_bar"), "four_bar");
        assert_eq!(name_token("my-robot v2"), "my_robot_v2");
        assert_eq!(name_token("__x__y"), "x_y");
        assert_eq!(name_token("3r"), "m_3r");
        assert_eq!(name_token("***"), "m_");
    }

    #[test]
    fn loading_reports_bad_input_by_label() {
        let four_bar = include_str!("../../../urdf/four_bar.urdf");
        let config = |sources: Vec<Source>, fixed: Vec<(Option<String>, String, f64)>| ServeConfig {
            sources,
            fixed,
            traces: vec![],
            settings: SolverSettings::default(),
            precision: 1e-4,
            domain: 0,
            namespace: "/".into(),
            node_name: "linkspace".into(),
            mapping: Mapping::Enhanced,
            network: Network::Loopback,
            limits: NodeLimits::default(),
            republish: None,
            max_history_bytes: DEFAULT_MAX_HISTORY_MB << 20,
            robot_description_topic: None,
            rosout: false,
            log_level: Severity::Info,
        };
        let src = |label: &str, xml: &str| Source { label: label.into(), xml: xml.into(), description: false };
        let err = |c: ServeConfig| format!("{:#}", load(&c).err().expect("should fail"));
        assert!(err(config(vec![src("bad.urdf", "<robot")], vec![])).contains("loading bad.urdf: malformed URDF"));
        assert!(err(config(vec![src("a", four_bar), src("b", four_bar)], vec![])).contains("b: a mechanism named 'four_bar' is already loaded"));
        assert!(err(config(vec![src("a", four_bar)], vec![(Some("ghost".into()), "crank_joint".into(), 0.5)])).contains("no mechanism of that name"));
        assert!(err(config(vec![src("a", four_bar)], vec![(None, "nope".into(), 0.5)])).contains("no joint or loop named 'nope'"));
        let twice = vec![(None, "crank_joint".into(), 0.5), (Some("four_bar".into()), "crank_joint".into(), 0.7)];
        assert!(err(config(vec![src("a", four_bar)], twice)).contains("joint 'crank_joint' is fixed twice"));
        let ok = load(&config(vec![src("a", four_bar)], vec![(Some("four_bar".into()), "crank_joint".into(), 0.5)])).expect("loads");
        assert_eq!(ok[0].analysis.fixed_joints(), vec![("crank_joint".to_string(), 0.5)]);
        assert_eq!(ok[0].root_link, "ground");
    }
}

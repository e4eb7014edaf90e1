//! `linkspace serve`: arguments of the ROS 2 node, turned into `ros::ServeConfig`.

use super::ros_args::parse_ros_args;
use super::{parse_fix, parse_trace};
use anyhow::{bail, Context, Result};
use linkspace::edges::ros::{self, NodeLimits, Mapping, Network, ServeConfig, Severity, Source};
use linkspace::app::{self, SolverSettings};
use std::io::Read;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Clone, Copy, clap::ValueEnum)]
enum MappingArg {
    /// rmw_fastrtps_cpp (Jazzy's default RMW) and rmw_connextdds.
    Enhanced,
    /// rmw_cyclonedds_cpp.
    Cyclone,
    /// RPC-over-DDS basic mapping.
    Basic,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum NetworkArg {
    /// 127.0.0.1 only.
    Loopback,
    /// Every interface, multicast discovery.
    All,
}

#[derive(clap::Args)]
pub struct ServeArgs {
    /// URDF files to serve ('-' reads one from standard input).
    urdf: Vec<PathBuf>,
    /// A URDF given as a string, as the robot_description parameter holds it. Repeatable.
    #[arg(long = "robot-description", value_name = "URDF_XML")]
    robot_description: Vec<String>,
    /// DDS domain; default: $ROS_DOMAIN_ID, else 0.
    #[arg(long)]
    domain: Option<u16>,
    /// Node namespace.
    #[arg(long, default_value = "/")]
    namespace: String,
    /// Node name.
    #[arg(long, default_value = "linkspace")]
    node_name: String,
    /// Service mapping of the callers' RMW; default: cyclone when $RMW_IMPLEMENTATION is
    /// rmw_cyclonedds_cpp, else enhanced (Jazzy's default, Fast DDS).
    #[arg(long, value_enum)]
    service_mapping: Option<MappingArg>,
    /// Network interfaces DDS may use.
    #[arg(long, value_enum, default_value_t = NetworkArg::Loopback)]
    network: NetworkArg,
    /// Fix a joint for the load-time analysis: [ROBOT:]JOINT=VALUE. Repeatable.
    #[arg(long = "fix", value_name = "[ROBOT:]JOINT=VALUE")]
    fix: Vec<String>,
    /// Trace a point of a link: [ROBOT:]LINK@X,Y. Repeatable.
    #[arg(long = "trace", value_name = "[ROBOT:]LINK@X,Y")]
    trace: Vec<String>,
    /// Load-time analyses: solution boxes are at most this wide.
    #[arg(long, default_value_t = 1e-3)]
    sigma: f64,
    /// Load-time analyses: shrink while a round leaves less than this share of the volume.
    #[arg(long, default_value_t = 0.95)]
    rho: f64,
    /// Load-time analyses: bounds of each run.
    #[command(flatten)]
    limits: super::LimitArgs,
    /// Load-time singularity analyses: largest width of the certified boxes of 3R manipulators
    /// (radians), and the sigma of planar linkages' singular sets (their
    /// `loop-singularities --sigma`), in (0, 1).
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    precision: f64,
    /// Largest max_boxes a Solve request may ask for.
    #[arg(long, default_value_t = NodeLimits::default().max_boxes)]
    max_request_boxes: u64,
    /// Largest timeout (seconds) a Solve request may ask for.
    #[arg(long, default_value_t = NodeLimits::default().max_timeout)]
    max_request_timeout: f64,
    /// Longest a Solve request may wait for its result before the reply (seconds).
    #[arg(long, default_value_t = NodeLimits::default().max_wait)]
    max_wait: f64,
    /// Requested runs that may go on at once; more are refused.
    #[arg(long, default_value_t = NodeLimits::default().max_runs)]
    max_runs: usize,
    /// Boxes drawn per marker namespace.
    #[arg(long, default_value_t = NodeLimits::default().max_markers)]
    max_markers: usize,
    /// Largest box set sent on a topic or in a reply, megabytes of boxes; a larger set is sent
    /// merged into fewer, larger boxes (each the hull of neighbours of one cluster, so every
    /// solution stays enclosed), and BoxSet.merged_from says how many boxes the run found.
    #[arg(long, default_value_t = NodeLimits::default().max_set_megabytes)]
    max_set_megabytes: f64,
    /// Publish the configuration spaces and markers again every this many seconds (for
    /// subscribers with volatile durability, such as RViz's default); 0: only when they change.
    #[arg(long, default_value_t = 0.0)]
    republish: f64,
    /// Most MiB of samples each of the node's DDS writers (one per service's replies, one per
    /// topic) keeps for repair and late joiners, and each topic it reads (one per service's
    /// requests) keeps once received; the oldest go first, the newest always stays.
    #[arg(long, value_name = "MIB", default_value_t = linkspace::edges::ros::DEFAULT_MAX_HISTORY_MB)]
    max_history_mb: usize,
    /// Also take the URDF from this topic (std_msgs/String, TransientLocal, as
    /// robot_state_publisher publishes it); each new one replaces the mechanism and is analysed
    /// again. Without a value: /robot_description.
    #[arg(long = "robot-description-topic", value_name = "TOPIC", num_args = 0..=1, default_missing_value = "/robot_description")]
    robot_description_topic: Option<String>,
    /// ROS 2 arguments, as `ros2 run` and launch files pass them: -r __ns:=/NS, -r __node:=NAME,
    /// -p NAME:=VALUE (robot_description, sigma, rho, precision, max_request_boxes,
    /// max_request_timeout, max_wait, max_runs, max_markers, max_set_megabytes, republish), --params-file FILE,
    /// --log-level LEVEL.
    /// Everything after it is taken as ROS arguments.
    #[arg(long = "ros-args", value_name = "ARGS", num_args = 0.., allow_hyphen_values = true)]
    ros_args: Option<Vec<String>>,
    /// The robot_description parameter given by -p or --params-file.
    #[arg(skip)]
    param_description: Option<String>,
}

/// `[ROBOT:]REST` → (robot, rest); the robot prefix ends at the first ':' before `stop`.
/// The node passes megabyte buffers (box sets, their serialized samples and fragments) between
/// its executor, DDS and solver threads. glibc gives each thread an arena of its own (up to 8
/// per core), keeps what is freed there, and after the first free of a large block serves
/// later ones from the heap too (its mmap threshold adapts upwards), so resident memory wandered
/// by tens of MB from one republication to the next with nothing retained (61-84 MB for the
/// four-bar at `--republish 0.05` under load). Two arenas and a fixed threshold (blocks of 256
/// KiB or more are mapped, and unmapped when freed) make resident memory follow live memory:
/// measured under load over 45 s, a floor constant to the MB. Called before any thread starts,
/// as glibc requires for these settings to hold everywhere.
fn bound_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; no other thread is running yet.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 2);
        libc::mallopt(libc::M_MMAP_THRESHOLD, 256 * 1024);
    }
}

fn robot_prefix(s: &str, stop: char) -> (Option<String>, &str) {
    match (s.find(':'), s.find(stop)) {
        (Some(c), Some(e)) if c < e => (Some(s[..c].to_string()), &s[c + 1..]),
        _ => (None, s),
    }
}

pub fn serve(mut args: ServeArgs) -> Result<()> {
    bound_malloc_arenas();
    let mut rosout = true;
    let mut log_level = Severity::Info;
    if let Some(tokens) = args.ros_args.take() {
        let ros = parse_ros_args(&tokens, &args.node_name, &args.namespace)?;
        if let Some(ns) = ros.namespace {
            args.namespace = ns;
        }
        if let Some(n) = ros.node_name {
            args.node_name = n;
        }
        apply_params(&mut args, &ros.params)?;
        rosout = !ros.no_rosout;
        log_level = ros.log_level.unwrap_or(log_level);
    }
    let domain = match args.domain {
        Some(d) => d,
        None => match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => v.trim().parse().with_context(|| format!("ROS_DOMAIN_ID '{v}' is not a domain id"))?,
            _ => 0,
        },
    };
    // DDS port arithmetic (7400 + 250 * domain + ...) leaves u16 above 232.
    if domain > 232 {
        bail!("domain {domain} is out of range: ROS 2 domain ids go from 0 to 232");
    }
    let settings = args.limits.solver_settings(SolverSettings { sigma: args.sigma, rho: args.rho, ..Default::default() })?;
    settings.validate()?;
    app::check_precision(args.precision)?;
    let limits = NodeLimits { max_boxes: args.max_request_boxes, max_timeout: args.max_request_timeout, max_wait: args.max_wait, max_runs: args.max_runs, max_markers: args.max_markers, max_set_megabytes: args.max_set_megabytes };
    if limits.max_boxes == 0 || !(limits.max_timeout > 0.0 && limits.max_timeout.is_finite()) || !(limits.max_wait >= 0.0 && limits.max_wait.is_finite()) || limits.max_runs == 0 {
        bail!("--max-request-boxes, --max-request-timeout and --max-runs must be positive, --max-wait at least 0");
    }

    let republish = match args.republish {
        0.0 => None,
        t if t.is_finite() && t >= 0.001 => Some(Duration::from_secs_f64(t)),
        t => bail!("--republish must be 0 (off) or at least 0.001 seconds, got {t}"),
    };
    let mut sources = Vec::new();
    for path in &args.urdf {
        let xml = if path.as_os_str() == "-" {
            let mut s = String::new();
            std::io::stdin().read_to_string(&mut s).context("reading a URDF from standard input")?;
            s
        } else {
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?
        };
        sources.push(Source { label: path.display().to_string(), xml, description: false });
    }
    let single = args.robot_description.len() == 1 && args.param_description.is_none();
    for (k, xml) in args.robot_description.iter().enumerate() {
        sources.push(Source { label: format!("--robot-description #{}", k + 1), xml: xml.clone(), description: single });
    }
    if let Some(xml) = args.param_description.take().filter(|x| !x.trim().is_empty()) {
        sources.push(Source { label: "parameter robot_description".into(), xml, description: true });
    }
    let several = sources.len() > 1;
    let mut fixed = Vec::new();
    for f in &args.fix {
        let (robot, rest) = robot_prefix(f, '=');
        if robot.is_none() && several {
            bail!("--fix '{f}': with several mechanisms, name the robot: ROBOT:JOINT=VALUE");
        }
        let (joint, value) = parse_fix(rest)?;
        fixed.push((robot, joint, value));
    }
    let mut traces = Vec::new();
    for t in &args.trace {
        let (robot, rest) = robot_prefix(t, '@');
        if robot.is_none() && several {
            bail!("--trace '{t}': with several mechanisms, name the robot: ROBOT:LINK@X,Y");
        }
        let (link, x, y) = parse_trace(rest)?;
        traces.push((robot, link, x, y));
    }
    let mapping = match args.service_mapping {
        Some(MappingArg::Enhanced) => Mapping::Enhanced,
        Some(MappingArg::Cyclone) => Mapping::Cyclone,
        Some(MappingArg::Basic) => Mapping::Basic,
        None if std::env::var("RMW_IMPLEMENTATION").is_ok_and(|v| v == "rmw_cyclonedds_cpp") => Mapping::Cyclone,
        None => Mapping::Enhanced,
    };
    let network = match args.network {
        NetworkArg::Loopback => Network::Loopback,
        NetworkArg::All => Network::All,
    };
    ros::serve(ServeConfig {
        sources,
        fixed,
        traces,
        settings,
        precision: args.precision,
        domain,
        namespace: args.namespace,
        node_name: args.node_name,
        mapping,
        network,
        limits,
        republish,
        max_history_bytes: args.max_history_mb.max(1).saturating_mul(1 << 20),
        robot_description_topic: args.robot_description_topic,
        rosout,
        log_level,
    })?;
    Ok(())
}

/// A parameter's text as a number, for `-p`, `--params-file`.
fn param_number<T: std::str::FromStr>(name: &str, value: &str) -> Result<T> {
    value.trim().parse().map_err(|_| anyhow::anyhow!("parameter {name}: '{}' is not a valid value", linkspace::edges::ros::bounded(value, 80)))
}

/// Applies ROS parameters onto the command-line settings (they win over the flags).
fn apply_params(args: &mut ServeArgs, params: &[(String, String)]) -> Result<()> {
    for (name, value) in params {
        match name.as_str() {
            "robot_description" => args.param_description = Some(value.clone()),
            "sigma" => args.sigma = param_number(name, value)?,
            "rho" => args.rho = param_number(name, value)?,
            "precision" => args.precision = param_number(name, value)?,
            "max_request_boxes" => args.max_request_boxes = param_number(name, value)?,
            "max_request_timeout" => args.max_request_timeout = param_number(name, value)?,
            "max_wait" => args.max_wait = param_number(name, value)?,
            "max_runs" => args.max_runs = param_number(name, value)?,
            "max_markers" => args.max_markers = param_number(name, value)?,
            "max_set_megabytes" => args.max_set_megabytes = param_number(name, value)?,
            "republish" => args.republish = param_number(name, value)?,
            "use_sim_time" => {}
            other => bail!(
                "parameter '{}' is not a parameter of this node (robot_description, sigma, rho, precision, max_request_boxes, max_request_timeout, max_wait, max_runs, max_markers, max_set_megabytes, republish)",
                linkspace::edges::ros::bounded(other, 80)
            ),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::robot_prefix;

    #[test]
    fn robot_prefixes_end_before_the_value() {
        assert_eq!(robot_prefix("four_bar:crank=1", '='), (Some("four_bar".to_string()), "crank=1"));
        assert_eq!(robot_prefix("crank=1", '='), (None, "crank=1"));
        assert_eq!(robot_prefix("link@1:2,3", '@'), (None, "link@1:2,3"));
    }
}

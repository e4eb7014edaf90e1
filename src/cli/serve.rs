//! `linkspace serve`: arguments of the ROS 2 node, turned into `ros::ServeConfig`.

use super::{parse_fix, parse_trace};
use anyhow::{bail, Context, Result};
use linkspace::ros::{self, NodeLimits, Mapping, Network, ServeConfig, Source};
use linkspace::search::SolverSettings;
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
    /// Publish the configuration spaces and markers again every this many seconds (for
    /// subscribers with volatile durability, such as RViz's default); 0: only when they change.
    #[arg(long, default_value_t = 0.0)]
    republish: f64,
    /// Also take the URDF from this topic (std_msgs/String, TransientLocal, as
    /// robot_state_publisher publishes it); each new one replaces the mechanism and is analysed
    /// again. Without a value: /robot_description.
    #[arg(long = "robot-description-topic", value_name = "TOPIC", num_args = 0..=1, default_missing_value = "/robot_description")]
    robot_description_topic: Option<String>,
    /// ROS 2 arguments, as `ros2 run` and launch files pass them: -r __ns:=/NS, -r __node:=NAME,
    /// -p NAME:=VALUE (robot_description, sigma, rho, precision, max_request_boxes,
    /// max_request_timeout, max_wait, max_runs, max_markers, republish), --params-file FILE.
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
    if let Some(tokens) = args.ros_args.take() {
        let ros = parse_ros_args(&tokens, &args.node_name)?;
        if let Some(ns) = ros.namespace {
            args.namespace = ns;
        }
        if let Some(n) = ros.node_name {
            args.node_name = n;
        }
        apply_params(&mut args, &ros.params)?;
        rosout = !ros.no_rosout;
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
    let settings = args.limits.solver_settings(SolverSettings::default().max_boxes, SolverSettings { sigma: args.sigma, rho: args.rho, ..Default::default() })?;
    settings.validate()?;
    linkspace::manip3r::check_precision(args.precision)?;
    let limits = NodeLimits { max_boxes: args.max_request_boxes, max_timeout: args.max_request_timeout, max_wait: args.max_wait, max_runs: args.max_runs, max_markers: args.max_markers };
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
        robot_description_topic: args.robot_description_topic,
        rosout,
    })?;
    Ok(())
}

/// What `--ros-args` asked for (the ROS 2 command-line grammar, the parts a node honours).
#[derive(Debug, Default, PartialEq)]
struct RosArgs {
    namespace: Option<String>,
    node_name: Option<String>,
    /// Parameters in the order given (`--params-file` files and `-p`), later ones win.
    params: Vec<(String, String)>,
    /// `--disable-rosout-logs`.
    no_rosout: bool,
}

/// The value of a ROS argument that takes one.
fn next_value<'a>(it: &mut std::slice::Iter<'a, String>, flag: &str) -> Result<&'a String> {
    it.next().with_context(|| format!("--ros-args: {flag} needs a value"))
}

/// Parses the tokens after `--ros-args`: `-r`/`--remap` (`__ns:=`, `__node:=`/`__name:=`, with an
/// optional `NODE:` prefix), `-p`/`--param NAME:=VALUE`, `--params-file FILE`, `--log-level`
/// and the rosout/stdout switches (accepted). Anything else is refused with a reason.
fn parse_ros_args(tokens: &[String], node_name: &str) -> Result<RosArgs> {
    let mut out = RosArgs::default();
    let mut it = tokens.iter();
    // A `NODE:` prefix applies the rule to that node only: ours, or not at all.
    let for_us = |rule: &str| -> Option<String> {
        match rule.split_once(':') {
            Some((node, rest)) if !node.is_empty() && !rest.starts_with('=') && !node.starts_with('_') => (node == node_name).then(|| rest.to_string()),
            _ => Some(rule.to_string()),
        }
    };
    while let Some(t) = it.next() {
        match t.as_str() {
            "--ros-args" => {}
            "--" => {
                if let Some(rest) = it.next() {
                    bail!("--ros-args: '{rest}' after '--': give linkspace's own options before --ros-args");
                }
            }
            "-r" | "--remap" => {
                let rule = next_value(&mut it, t)?;
                let Some(rule) = for_us(rule) else { continue };
                let (from, to) = rule.split_once(":=").with_context(|| format!("--ros-args -r '{rule}': expected FROM:=TO"))?;
                match from {
                    "__ns" => {
                        if !to.starts_with('/') {
                            bail!("--ros-args -r __ns:={to}: a namespace starts with '/'");
                        }
                        out.namespace = Some(to.to_string());
                    }
                    "__node" | "__name" => out.node_name = Some(to.to_string()),
                    _ => bail!("--ros-args -r {from}:={to}: only the node's name and namespace can be remapped (__node, __ns), not topics or services"),
                }
            }
            "-p" | "--param" => {
                let p = next_value(&mut it, t)?;
                let Some(p) = for_us(p) else { continue };
                let (name, value) = p.split_once(":=").with_context(|| format!("--ros-args -p '{p}': expected NAME:=VALUE"))?;
                out.params.push((name.to_string(), yaml_scalar(value)));
            }
            "--params-file" => {
                let path = next_value(&mut it, t)?;
                let text = std::fs::read_to_string(path).with_context(|| format!("--ros-args --params-file {path}"))?;
                let params = params_file(&text, node_name).with_context(|| format!("--ros-args --params-file {path}"))?;
                out.params.extend(params);
            }
            "--log-level" => {
                next_value(&mut it, t)?;
            }
            "--enable-rosout-logs" | "--enable-stdout-logs" | "--disable-stdout-logs" | "--enable-external-lib-logs" | "--disable-external-lib-logs" => {}
            "--disable-rosout-logs" => out.no_rosout = true,
            "-e" | "--enclave" => bail!("--ros-args {t}: security enclaves are not supported by this node"),
            other => bail!("--ros-args: '{other}' is not understood (this node takes -r __ns:=/NS, -r __node:=NAME, -p NAME:=VALUE, --params-file FILE, --log-level)"),
        }
    }
    Ok(out)
}

/// A YAML scalar as text: quotes removed.
fn yaml_scalar(v: &str) -> String {
    let v = v.trim();
    for q in ['"', '\''] {
        if v.len() >= 2 && v.starts_with(q) && v.ends_with(q) {
            return v[1..v.len() - 1].to_string();
        }
    }
    v.to_string()
}

/// The parameters for `node_name` in a ROS 2 parameters file: the sections `/**`, `NODE` and
/// `/NS/NODE`-style keys ending in the node name, each with `ros__parameters:` holding
/// `name: scalar` lines or block scalars (`|`, for a URDF). Nested maps and lists are refused.
fn params_file(text: &str, node_name: &str) -> Result<Vec<(String, String)>> {
    let lines: Vec<&str> = text.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut out = Vec::new();
    let mut section: Option<bool> = None; // Some(ours) inside a node section
    let mut in_params = false;
    let mut k = 0;
    while k < lines.len() {
        let line = lines[k];
        k += 1;
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') || trimmed == "---" {
            continue;
        }
        let (key, rest) = trimmed.split_once(':').with_context(|| format!("line {k}: expected KEY: VALUE"))?;
        let key = yaml_scalar(key);
        let rest = rest.trim();
        match indent(line) {
            0 => {
                let ours = key == "/**" || key == "**" || key.trim_start_matches('/').rsplit('/').next() == Some(node_name);
                section = Some(ours);
                in_params = false;
            }
            _ if section.is_none() => bail!("line {k}: indented before any node section"),
            _ if key == "ros__parameters" => in_params = true,
            _ if !in_params => bail!("line {k}: '{key}' outside ros__parameters"),
            ind => {
                let value = if rest == "|" || rest == ">" || rest == "|-" || rest == ">-" {
                    // A block scalar: the following lines indented deeper.
                    let mut block = Vec::new();
                    let mut base = None;
                    while k < lines.len() && (lines[k].trim().is_empty() || indent(lines[k]) > ind) {
                        let l = lines[k];
                        k += 1;
                        if l.trim().is_empty() {
                            block.push(String::new());
                            continue;
                        }
                        let b = *base.get_or_insert(indent(l));
                        block.push(l.get(b.min(indent(l))..).unwrap_or("").to_string());
                    }
                    let sep = if rest.starts_with('>') { " " } else { "\n" };
                    let mut v = block.join(sep).trim_end().to_string();
                    if !rest.ends_with('-') {
                        v.push('\n');
                    }
                    v
                } else if rest.is_empty() || rest.starts_with('[') || rest.starts_with('-') || rest.starts_with('{') {
                    bail!("line {k}: parameter '{key}': only scalar values are supported");
                } else {
                    yaml_scalar(rest.split(" #").next().unwrap_or(rest))
                };
                if section == Some(true) {
                    out.push((key, value));
                }
            }
        }
    }
    Ok(out)
}

/// A parameter's text as a number, for `-p`, `--params-file`.
fn param_number<T: std::str::FromStr>(name: &str, value: &str) -> Result<T> {
    value.trim().parse().map_err(|_| anyhow::anyhow!("parameter {name}: '{}' is not a valid value", linkspace::ros::bounded(value, 80)))
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
            "republish" => args.republish = param_number(name, value)?,
            "use_sim_time" => {}
            other => bail!(
                "parameter '{}' is not a parameter of this node (robot_description, sigma, rho, precision, max_request_boxes, max_request_timeout, max_wait, max_runs, max_markers, republish)",
                linkspace::ros::bounded(other, 80)
            ),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{params_file, parse_ros_args, robot_prefix, RosArgs};

    #[test]
    fn robot_prefixes_end_before_the_value() {
        assert_eq!(robot_prefix("four_bar:crank=1", '='), (Some("four_bar".to_string()), "crank=1"));
        assert_eq!(robot_prefix("crank=1", '='), (None, "crank=1"));
        assert_eq!(robot_prefix("link@1:2,3", '@'), (None, "link@1:2,3"));
    }

    // Test idea: the ROS 2 argument grammar as `ros2 run` and launch files write it, and a
    // parameters file in the layout `ros2 param dump` writes, including a URDF as a block
    // scalar; what the node does not honour is refused with a reason, not ignored.
    #[test]
    fn ros_args_and_params_files_are_read_the_ros_way() {
        let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let got = parse_ros_args(&v(&["-r", "__ns:=/lab", "-r", "linkspace:__node:=ls", "-p", "sigma:=1e-4", "--log-level", "debug", "-p", "other_node:sigma:=5"]), "linkspace").expect("parses");
        assert_eq!(got, RosArgs { namespace: Some("/lab".into()), node_name: Some("ls".into()), params: vec![("sigma".into(), "1e-4".into())], no_rosout: false });
        let err = |s: &[&str]| format!("{:#}", parse_ros_args(&v(s), "linkspace").expect_err("refused"));
        assert!(err(&["-r", "chatter:=talk"]).contains("only the node's name and namespace can be remapped"));
        assert!(err(&["-r", "__ns:=lab"]).contains("a namespace starts with '/'"));
        assert!(err(&["--bogus"]).contains("'--bogus' is not understood"));
        assert!(err(&["-p"]).contains("-p needs a value"));
        assert!(err(&["--", "x.urdf"]).contains("before --ros-args"));

        let file = "# dumped\n/lab/linkspace:\n  ros__parameters:\n    precision: 0.001\n    max_runs: 2\n    robot_description: |\n      <robot name=\"r\">\n        <link name=\"a\"/>\n      </robot>\n    use_sim_time: false\nother:\n  ros__parameters:\n    sigma: 9.0\n/**:\n  ros__parameters:\n    rho: \"0.9\"\n";
        let p = params_file(file, "linkspace").expect("parses");
        assert_eq!(p[0], ("precision".to_string(), "0.001".to_string()));
        assert_eq!(p[1], ("max_runs".to_string(), "2".to_string()));
        assert_eq!(p[2], ("robot_description".to_string(), "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n".to_string()));
        assert_eq!(p[4], ("rho".to_string(), "0.9".to_string()));
        assert_eq!(p.len(), 5, "{p:?}");
        assert!(format!("{:#}", params_file("linkspace:\n  ros__parameters:\n    joints: [1, 2]\n", "linkspace").expect_err("list")).contains("only scalar values"));
    }
}

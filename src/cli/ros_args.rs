//! The ROS 2 arguments of `linkspace serve` (everything after `--ros-args`) and the parameter
//! files they name: the one module that reads parameters, and the only one that knows YAML.
//!
//! Files are read with a YAML parser, so whatever `launch_ros` writes for `parameters=[{...}]`
//! (PyYAML's `yaml.dump`: a URDF as a multi-line quoted scalar) and whatever `ros2 param dump`
//! writes (block scalars) reads the same.

use anyhow::{bail, Context, Result};
use linkspace::edges::ros::Severity;
use yaml_rust2::{Yaml, YamlLoader};

/// What `--ros-args` asked for (the ROS 2 command-line grammar, the parts a node honours).
#[derive(Debug, Default, PartialEq)]
pub(super) struct RosArgs {
    pub namespace: Option<String>,
    pub node_name: Option<String>,
    /// Parameters in the order given (`--params-file` files and `-p`), later ones win.
    pub params: Vec<(String, String)>,
    /// `--disable-rosout-logs`.
    pub no_rosout: bool,
    /// `--log-level LEVEL` (or `NODE:=LEVEL` naming this node).
    pub log_level: Option<Severity>,
}

/// One parameter source, in command-line order; files are resolved once the node's final name
/// is known (a `-r __node:=` after `--params-file` still selects the file's section).
enum Given {
    Param(String, String),
    File(String, String),
}

/// The value of a ROS argument that takes one.
fn next_value<'a>(it: &mut std::slice::Iter<'a, String>, flag: &str) -> Result<&'a String> {
    it.next().with_context(|| format!("--ros-args: {flag} needs a value"))
}

/// A ROS 2 severity name, any case.
fn severity(level: &str) -> Result<Severity> {
    Ok(match level.to_ascii_lowercase().as_str() {
        "debug" => Severity::Debug,
        "info" => Severity::Info,
        "warn" | "warning" => Severity::Warn,
        "error" => Severity::Error,
        "fatal" => Severity::Fatal,
        _ => bail!("--ros-args --log-level '{}': expected debug, info, warn, error or fatal", linkspace::edges::ros::bounded(level, 80)),
    })
}

/// Parses the tokens after `--ros-args`: `-r`/`--remap` (`__ns:=`, `__node:=`/`__name:=`, with an
/// optional `NODE:` prefix), `-p`/`--param NAME:=VALUE`, `--params-file FILE`, `--log-level`
/// (a level, or `LOGGER:=LEVEL`: this node's logger is its name, or its fully qualified name
/// with dots, `lab.linkspace`; other loggers are not this node's) and the rosout/stdout switches
/// (accepted). Anything else is refused with a reason. `node_name` and `namespace` are the
/// node's before remapping.
pub(super) fn parse_ros_args(tokens: &[String], node_name: &str, namespace: &str) -> Result<RosArgs> {
    let mut out = RosArgs::default();
    let mut given = Vec::new();
    let mut loggers = Vec::new();
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
                given.push(Given::Param(name.to_string(), unquoted(value)));
            }
            "--params-file" => {
                let path = next_value(&mut it, t)?;
                let text = std::fs::read_to_string(path).with_context(|| format!("--ros-args --params-file {path}"))?;
                given.push(Given::File(path.clone(), text));
            }
            "--log-level" => {
                let level = next_value(&mut it, t)?;
                match level.split_once(":=") {
                    Some((logger, level)) => loggers.push((logger.to_string(), severity(level)?)),
                    None => out.log_level = Some(severity(level)?),
                }
            }
            "--enable-rosout-logs" | "--enable-stdout-logs" | "--disable-stdout-logs" | "--enable-external-lib-logs" | "--disable-external-lib-logs" => {}
            "--disable-rosout-logs" => out.no_rosout = true,
            "-e" | "--enclave" => bail!("--ros-args {t}: security enclaves are not supported by this node"),
            other => bail!("--ros-args: '{other}' is not understood (this node takes -r __ns:=/NS, -r __node:=NAME, -p NAME:=VALUE, --params-file FILE, --log-level)"),
        }
    }
    let name = out.node_name.clone().unwrap_or_else(|| node_name.to_string());
    let namespace = out.namespace.clone().unwrap_or_else(|| namespace.to_string());
    let qualified = format!("{}/{name}", namespace.trim_end_matches('/')).trim_start_matches('/').replace('/', ".");
    // A logger's own level wins over the default level, as in rcutils.
    if let Some((_, level)) = loggers.iter().rev().find(|(logger, _)| *logger == name || *logger == qualified) {
        out.log_level = Some(*level);
    }
    for g in given {
        match g {
            Given::Param(name, value) => out.params.push((name, value)),
            Given::File(path, text) => out.params.extend(params_file(&text, &name, &namespace).with_context(|| format!("--ros-args --params-file {path}"))?),
        }
    }
    Ok(out)
}

/// A `-p` value as text: surrounding quotes removed.
fn unquoted(v: &str) -> String {
    let v = v.trim();
    for q in ['"', '\''] {
        if v.len() >= 2 && v.starts_with(q) && v.ends_with(q) {
            return v[1..v.len() - 1].to_string();
        }
    }
    v.to_string()
}

/// Whether a parameters file's section key names this node: `/**` (every node), `/**/NAME`,
/// `NAME`, or `/NS/NAME` with this node's namespace (a relative key names the node at the root,
/// as rcl reads it).
fn names_this_node(key: &str, node_name: &str, namespace: &str) -> bool {
    if key == "/**" || key == "**" || key == format!("/**/{node_name}") {
        return true;
    }
    let key = key.trim_start_matches('/');
    let (ns, name) = key.rsplit_once('/').unwrap_or(("", key));
    name == node_name && ns.trim_matches('/') == namespace.trim_matches('/')
}

/// A parameter value as the text `apply_params` reads.
fn scalar_text(name: &str, value: &Yaml) -> Result<String> {
    Ok(match value {
        Yaml::String(s) | Yaml::Real(s) => s.clone(),
        Yaml::Integer(i) => i.to_string(),
        Yaml::Boolean(b) => b.to_string(),
        Yaml::Null => bail!("parameter '{name}' has no value"),
        _ => bail!("parameter '{name}': only scalar values are supported"),
    })
}

/// The `ros__parameters` of one section, nested maps flattened to dotted names as ROS does.
fn collect(prefix: &str, params: &Yaml, out: &mut Vec<(String, String)>) -> Result<()> {
    let Yaml::Hash(map) = params else { bail!("'{}' must hold NAME: VALUE entries", if prefix.is_empty() { "ros__parameters" } else { prefix }) };
    for (key, value) in map {
        let key = key_text(key)?;
        let name = if prefix.is_empty() { key } else { format!("{prefix}.{key}") };
        match value {
            Yaml::Hash(_) => collect(&name, value, out)?,
            _ => out.push((name.clone(), scalar_text(&name, value)?)),
        }
    }
    Ok(())
}

fn key_text(key: &Yaml) -> Result<String> {
    match key {
        Yaml::String(s) | Yaml::Real(s) => Ok(s.clone()),
        Yaml::Integer(i) => Ok(i.to_string()),
        Yaml::Boolean(b) => Ok(b.to_string()),
        _ => bail!("a key that is not a name: {key:?}"),
    }
}

/// The parameters for this node in a ROS 2 parameters file: every section whose key names it
/// (`/**`, `NODE`, `/NS/NODE`), in file order, each `NODE: {ros__parameters: {NAME: VALUE}}`.
/// Lists are refused; other sections are skipped.
pub(super) fn params_file(text: &str, node_name: &str, namespace: &str) -> Result<Vec<(String, String)>> {
    let docs = YamlLoader::load_from_str(text).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut out = Vec::new();
    let Some(doc) = docs.into_iter().next() else { return Ok(out) };
    let sections = match doc {
        Yaml::Hash(h) => h,
        Yaml::Null => return Ok(out),
        _ => bail!("expected NODE: {{ros__parameters: ...}} sections"),
    };
    for (key, section) in &sections {
        let key = key_text(key)?;
        let Yaml::Hash(inner) = section else { bail!("section '{key}': expected ros__parameters") };
        for (k, params) in inner {
            if key_text(k)? != "ros__parameters" {
                bail!("section '{key}': '{}' outside ros__parameters", key_text(k)?);
            }
            let mut these = Vec::new();
            collect("", params, &mut these).with_context(|| format!("section '{key}'"))?;
            if names_this_node(&key, node_name, namespace) {
                out.extend(these);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{params_file, parse_ros_args, RosArgs, Severity};

    fn v(s: &[&str]) -> Vec<String> {
        s.iter().map(|x| x.to_string()).collect()
    }

    // Test idea: the ROS 2 argument grammar as `ros2 run` and launch files write it; what the
    // node does not honour is refused with a reason, not ignored.
    #[test]
    fn ros_args_are_read_the_ros_way() {
        let got = parse_ros_args(&v(&["-r", "__ns:=/lab", "-r", "linkspace:__node:=ls", "-p", "sigma:=1e-4", "--log-level", "debug", "-p", "other_node:sigma:=5"]), "linkspace", "/").expect("parses");
        assert_eq!(got, RosArgs { namespace: Some("/lab".into()), node_name: Some("ls".into()), params: vec![("sigma".into(), "1e-4".into())], no_rosout: false, log_level: Some(Severity::Debug) });
        let err = |s: &[&str]| format!("{:#}", parse_ros_args(&v(s), "linkspace", "/").expect_err("refused"));
        assert!(err(&["-r", "chatter:=talk"]).contains("only the node's name and namespace can be remapped"));
        assert!(err(&["-r", "__ns:=lab"]).contains("a namespace starts with '/'"));
        assert!(err(&["--bogus"]).contains("'--bogus' is not understood"));
        assert!(err(&["-p"]).contains("-p needs a value"));
        assert!(err(&["--", "x.urdf"]).contains("before --ros-args"));
        assert!(err(&["--log-level", "loud"]).contains("expected debug, info, warn, error or fatal"));
    }

    // Test idea: `--log-level` as rcutils reads it: a default level, and a logger's own level
    // (the node's name or its dotted fully qualified name) winning over it; other loggers'
    // levels are not this node's.
    #[test]
    fn log_levels_name_the_default_or_this_nodes_logger() {
        let level = |s: &[&str]| parse_ros_args(&v(s), "linkspace", "/").expect("parses").log_level;
        assert_eq!(level(&[]), None);
        assert_eq!(level(&["--log-level", "WARN"]), Some(Severity::Warn));
        assert_eq!(level(&["--log-level", "linkspace:=error", "--log-level", "debug"]), Some(Severity::Error));
        assert_eq!(level(&["-r", "__ns:=/lab", "--log-level", "lab.linkspace:=fatal"]), Some(Severity::Fatal));
        assert_eq!(level(&["--log-level", "rcl:=debug"]), None);
    }

    // Test idea: the layout `ros2 param dump` writes (a URDF as a block scalar), sections for
    // other nodes skipped, and the file launch_ros writes for `parameters=[{...}]`: PyYAML's
    // dump of a multi-line URDF is a quoted scalar over several lines, which must read back to the
    // same text.
    #[test]
    fn params_files_are_read_as_yaml() {
        let file = "# dumped\n/lab/linkspace:\n  ros__parameters:\n    precision: 0.001\n    max_runs: 2\n    robot_description: |\n      <robot name=\"r\">\n        <link name=\"a\"/>\n      </robot>\n    use_sim_time: false\nother:\n  ros__parameters:\n    sigma: 9.0\n/**:\n  ros__parameters:\n    rho: \"0.9\"\n";
        let p = params_file(file, "linkspace", "/lab").expect("parses");
        assert_eq!(p[0], ("precision".to_string(), "0.001".to_string()));
        assert_eq!(p[1], ("max_runs".to_string(), "2".to_string()));
        assert_eq!(p[2], ("robot_description".to_string(), "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n".to_string()));
        assert_eq!(p[3], ("use_sim_time".to_string(), "false".to_string()));
        assert_eq!(p[4], ("rho".to_string(), "0.9".to_string()));
        assert_eq!(p.len(), 5, "{p:?}");
        assert!(params_file(file, "linkspace", "/").expect("parses").iter().all(|(n, _)| n == "rho"), "/lab/linkspace is not /linkspace");
        assert!(format!("{:#}", params_file("linkspace:\n  ros__parameters:\n    joints: [1, 2]\n", "linkspace", "/").expect_err("list")).contains("only scalar values"));
        // What launch_ros writes for `parameters=[{'robot_description': urdf, 'sigma': 1e-05}]`:
        // `yaml.dump({'/**': {'ros__parameters': {...}}}, default_flow_style=False)` (PyYAML 6),
        // a double-quoted scalar with escapes, broken across lines with a trailing backslash.
        let launch = "/**:\n  ros__parameters:\n    robot_description: \"<?xml version=\\\"1.0\\\"?>\\n<robot name=\\\"r\\\">\\n  <link name=\\\"\\\n      a\\\"/>\\n</robot>\\n\"\n    sigma: 1.0e-05\n";
        let p = params_file(launch, "linkspace", "/").expect("parses");
        assert_eq!(p, vec![("robot_description".to_string(), "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\n".to_string()), ("sigma".to_string(), "1.0e-05".to_string())]);
        let nested = params_file("/**:\n  ros__parameters:\n    group:\n      inner: 3\n", "linkspace", "/").expect("parses");
        assert_eq!(nested, vec![("group.inner".to_string(), "3".to_string())]);
    }
}

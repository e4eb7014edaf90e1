//! Test idea: run `linkspace serve` as a subprocess and talk to it from real rclpy (ROS 2
//! Jazzy with Fast DDS, pinned PyPI wheels in a venv that `scripts/ros_env.sh` makes), over
//! real DDS on loopback only. What arrives must be what `linkspace solve --json` computes for
//! the same URDF: same variables, same boxes bit for bit, same clusters. Subscribers start
//! after the node has published, so every topic check is also a late-joiner check. Services
//! are called with good and bad requests, and a load of 100 requests in flight must all be
//! answered or refused with a reason while the node stays alive and small.
//!
//! Each test has its own DDS domain; every wait has a timeout. The Python side is
//! `tests/ros_client.py` and `scripts/plot_boxes.py`. `LINKSPACE_SKIP_ROS=1` skips these tests
//! (loudly) on a machine without PyPI.

use serde_json::{json, Value};
use std::collections::BTreeSet;
use std::io::Read;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// A finished subprocess: (success, stdout, stderr).
fn run_with_timeout(mut cmd: Command, timeout: Duration) -> (bool, String, String) {
    let mut child = cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap_or_else(|e| panic!("starting {cmd:?}: {e}"));
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let out = drain(Box::new(child.stdout.take().expect("piped")));
    let err = drain(Box::new(child.stderr.take().expect("piped")));
    let end = Instant::now() + timeout;
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break Some(status);
        }
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let (out, err) = (out.join().expect("stdout reader"), err.join().expect("stderr reader"));
    match status {
        Some(s) => (s.success(), out, err),
        None => panic!("{cmd:?} timed out after {timeout:?}\nstdout: {out}\nstderr: {err}"),
    }
}

/// The venv's python, made once per test run by the project's own script; `None` when skipped.
fn python() -> Option<&'static str> {
    static PYTHON: OnceLock<Option<String>> = OnceLock::new();
    PYTHON
        .get_or_init(|| {
            if std::env::var("LINKSPACE_SKIP_ROS").is_ok_and(|v| v == "1") {
                eprintln!("LINKSPACE_SKIP_ROS=1: the ROS 2 tests are SKIPPED");
                return None;
            }
            let venv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("../ros-venv");
            let mut cmd = Command::new("sh");
            cmd.arg(format!("{ROOT}/scripts/ros_env.sh")).arg(&venv);
            // Installing the wheels and building linkspace_msgs takes a few minutes the first time.
            let (ok, out, err) = run_with_timeout(cmd, Duration::from_secs(1500));
            assert!(ok, "scripts/ros_env.sh failed:\n{err}");
            Some(out.lines().last().expect("ros_env.sh prints the python").trim().to_string())
        })
        .as_deref()
}

/// The environment a Python user sets to reach the node on loopback (launch_notes.md).
fn ros_env(cmd: &mut Command, domain: u16) {
    let logs = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ros-log");
    cmd.env("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "SYSTEM_DEFAULT")
        .env("FASTRTPS_DEFAULT_PROFILES_FILE", format!("{ROOT}/scripts/fastdds_loopback.xml"))
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("ROS_LOG_DIR", logs)
        .env_remove("ROS_LOCALHOST_ONLY")
        .env_remove("ROS_STATIC_PEERS");
}

/// Runs a Python script of the repo; returns its stdout.
fn py_run(python: &str, domain: u16, script: &str, args: &[&str], timeout: Duration) -> (String, String) {
    let mut cmd = Command::new(python);
    cmd.arg(format!("{ROOT}/{script}")).args(args);
    ros_env(&mut cmd, domain);
    let (ok, out, err) = run_with_timeout(cmd, timeout);
    assert!(ok, "{script} {args:?} failed:\nstdout: {out}\nstderr: {err}");
    (out, err)
}

/// Runs a Python script of the repo and parses the JSON on its last stdout line.
fn py(python: &str, domain: u16, script: &str, args: &[&str], timeout: Duration) -> Value {
    let (out, err) = py_run(python, domain, script, args, timeout);
    let last = out.lines().last().unwrap_or_else(|| panic!("{script} printed nothing; stderr: {err}"));
    serde_json::from_str(last).unwrap_or_else(|e| panic!("{script}: bad JSON ({e}): {last}\nstderr: {err}"))
}

/// `linkspace serve` as a subprocess, killed when dropped.
struct Node {
    child: Child,
    log: Arc<Mutex<String>>,
}

impl Node {
    fn start(domain: u16, args: &[&str]) -> Node {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_linkspace"));
        // Before the caller's arguments, which may end with --ros-args.
        cmd.arg("serve").args(["--domain", &domain.to_string(), "--network", "loopback"]).args(args);
        Node::spawn(cmd)
    }

    /// Starts a node with a command line of the caller's.
    fn spawn(mut cmd: Command) -> Node {
        let mut child = cmd.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap_or_else(|e| panic!("starting {cmd:?}: {e}"));
        let log = Arc::new(Mutex::new(String::new()));
        let mut stderr = child.stderr.take().expect("piped");
        let sink = log.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = stderr.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock().expect("log lock").push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        Node { child, log }
    }

    fn log(&self) -> String {
        self.log.lock().expect("log lock").clone()
    }

    /// Waits until the node's stderr holds every needle.
    fn wait_for(&mut self, needles: &[&str], timeout: Duration) {
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            let log = self.log();
            if needles.iter().all(|n| log.contains(n)) {
                return;
            }
            assert!(self.alive(), "the node exited:\n{log}");
            std::thread::sleep(Duration::from_millis(50));
        }
        panic!("the node did not print {needles:?} within {timeout:?}:\n{}", self.log());
    }

    fn alive(&mut self) -> bool {
        self.child.try_wait().expect("wait").is_none()
    }

    /// A memory figure from /proc (VmRSS, VmHWM), in KiB.
    fn memory_kib(&self, field: &str) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).expect("/proc status");
        let line = status.lines().find(|l| l.starts_with(field)).unwrap_or_else(|| panic!("{field} not in /proc status"));
        line.split_whitespace().nth(1).and_then(|v| v.parse().ok()).expect("a number of kB")
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `linkspace solve ARGS --json` → the report.
fn solve_json(args: &[&str]) -> Value {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("topics-ref-{}-{}.json", std::process::id(), args.join("_").replace(['/', '@', ',', '='], "-")));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_linkspace"));
    cmd.arg("solve").args(args).arg("--json").arg(&path);
    let (ok, _, err) = run_with_timeout(cmd, Duration::from_secs(120));
    assert!(ok, "linkspace solve {args:?}: {err}");
    let v = serde_json::from_str(&std::fs::read_to_string(&path).expect("json written")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    v
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

/// The BoxSet (as JSON from Python) holds exactly the report's boxes, in the same order.
fn assert_same_boxes(set: &Value, report: &Value) {
    let names: Vec<&str> = report["variables"].as_array().expect("variables").iter().map(|v| v["name"].as_str().expect("name")).collect();
    let set_names: Vec<&str> = set["variable_names"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
    assert_eq!(set_names, names);
    let dim = names.len();
    assert_eq!(set["dim"], json!(dim));
    let solutions = report["solutions"].as_array().expect("solutions");
    let undecided = report["undecided"].as_array().expect("undecided");
    let records: Vec<&Value> = solutions.iter().chain(undecided).collect();
    let (lower, upper) = (floats(&set["lower"]), floats(&set["upper"]));
    assert_eq!(lower.len(), records.len() * dim, "box count");
    assert_eq!(upper.len(), records.len() * dim);
    let joint_names: Vec<&str> = set["joint_names"].as_array().expect("joint names").iter().map(|v| v.as_str().expect("str")).collect();
    let (jl, ju) = (floats(&set["joint_lower"]), floats(&set["joint_upper"]));
    for (i, r) in records.iter().enumerate() {
        for (k, b) in r["box"].as_array().expect("box").iter().enumerate() {
            assert_eq!([lower[i * dim + k], upper[i * dim + k]], [b[0].as_f64().expect("lo"), b[1].as_f64().expect("hi")], "box {i}, {}", names[k]);
        }
        for (k, j) in joint_names.iter().enumerate() {
            let b = &r["joints"][j];
            assert_eq!([jl[i * joint_names.len() + k], ju[i * joint_names.len() + k]], [b[0].as_f64().expect("lo"), b[1].as_f64().expect("hi")], "box {i}, joint {j}");
        }
        assert_eq!(set["level"][i], r["level"]);
    }
    let statuses = set["box_status"].as_array().expect("statuses");
    // Box.SOLUTION (0) or Box.UNIQUE (2) for solutions, as the report's `unique` says.
    let unique = solutions.iter().filter(|r| r["unique"] == json!(true)).count();
    assert_eq!(statuses.iter().filter(|s| **s == json!(2)).count(), unique, "certified boxes travel as Box.UNIQUE");
    assert_eq!(statuses.iter().filter(|s| **s == json!(0)).count(), solutions.len() - unique);
    assert_eq!(set["stats"]["certified"], report["stats"]["certified"]);
    assert_eq!(set["stats"]["post_processing_cut_short"], report["stats"]["post_processing_cut_short"]);
    assert_eq!(set["clusters"], report["clusters"]);
    let complete = report["status"] == "complete";
    assert_eq!(set["status"], json!(if complete { 0 } else { 1 }));
    assert_eq!(set["limit"], report.get("limit").cloned().filter(|l| !l.is_null()).unwrap_or(json!("")));
    assert_eq!(set["stats"]["processed"], report["stats"]["processed"]);
    let fixed: Vec<(String, f64)> = report["fixed_joints"].as_object().expect("fixed").iter().map(|(k, v)| (k.clone(), v.as_f64().expect("value"))).collect();
    let set_fixed: Vec<(String, f64)> = set["fixed_joint_names"].as_array().expect("names").iter().zip(floats(&set["fixed_joint_values"])).map(|(n, v)| (n.as_str().expect("str").to_string(), v)).collect();
    assert_eq!(set_fixed, fixed);
}

#[test]
fn topics_carry_the_solver_result_to_late_rclpy_subscribers() {
    let Some(python) = python() else { return };
    let domain = 41;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let slider = format!("{ROOT}/urdf/slider_crank.urdf");
    let octahedral = format!("{ROOT}/urdf/octahedral.urdf");
    let legs = [("leg15", 4.25), ("leg16", 5.75), ("leg26", 4.25), ("leg24", 5.75), ("leg34", 4.25), ("leg35", 5.75)].map(|(l, v)| format!("octahedral:{l}={v}"));
    let mut args = vec![four_bar.as_str(), slider.as_str(), octahedral.as_str(), "--fix", "four_bar:crank_joint=0.5", "--trace", "four_bar:coupler@2,1", "--sigma", "1e-3"];
    for l in &legs {
        args.extend(["--fix", l.as_str()]);
    }
    let mut node = Node::start(domain, &args);
    node.wait_for(&["four_bar: published configuration_space", "slider_crank: published configuration_space", "octahedral: published configuration_space"], Duration::from_secs(120));

    // Two isolated assembly modes, with a traced coupler point.
    let reference = solve_json(&[&four_bar, "--fix", "crank_joint=0.5", "--trace", "coupler@2,1", "--sigma", "1e-3"]);
    let got = py(python, domain, "tests/ros_client.py", &["topics", "--prefix", "/linkspace/four_bar", "--modes", "2"], Duration::from_secs(90));
    assert_eq!(got["complete"], json!(true), "{got}");
    let set = &got["configuration_space"];
    assert_eq!(set["mechanism"], "four_bar");
    assert_eq!(set["analysis"], "configuration_space");
    assert_same_boxes(set, &reference);
    assert_eq!(set["clusters"], json!(2));
    // Frames: the box set is in the joint-space frame, which the node itself ties to the root
    // link on /tf_static.
    assert_eq!(set["header"]["frame_id"], "four_bar/joint_space");
    // Read with tf2_msgs/TFMessage (built into the venv by scripts/ros_env.sh): the node's three
    // mechanisms, each joint-space frame an identity child of its root link.
    assert_eq!(got["tf_static_publishers"], json!(1));
    let frames = got["tf_static"].as_array().expect("transforms");
    let four_bar_frame = frames.iter().find(|t| t["child"] == "four_bar/joint_space").unwrap_or_else(|| panic!("no four_bar/joint_space on /tf_static: {frames:?}"));
    assert_eq!(four_bar_frame["parent"], "ground");
    assert_eq!(four_bar_frame["translation"], json!([0.0, 0.0, 0.0]));
    assert_eq!(four_bar_frame["rotation"], json!([0.0, 0.0, 0.0, 1.0]));

    // Markers: DELETEALL, then one cube per box in joint space and one per box for the trace.
    let markers = got["markers"].as_array().expect("markers");
    assert_eq!(markers[0]["action"], json!(3));
    let n = reference["solutions"].as_array().expect("solutions").len();
    assert_eq!(markers.iter().filter(|m| m["ns"] == "configuration_space").count(), n);
    let traced: Vec<&Value> = markers.iter().filter(|m| m["ns"] == "trace:coupler@2,1").collect();
    assert_eq!(traced.len(), n);
    assert_eq!(traced[0]["frame"], "ground");
    for (m, s) in traced.iter().zip(reference["solutions"].as_array().expect("solutions")) {
        let x = floats(&s["traces"]["coupler@2,1"]["x"]);
        assert!((m["position"][0].as_f64().expect("x") - 0.5 * (x[0] + x[1])).abs() < 1e-12);
    }

    // One JointState per assembly mode; each lies in its own solution box.
    let modes = got["assembly_modes"].as_array().expect("modes");
    assert_eq!(modes.len(), 2, "{modes:?}");
    // Each JointState is in the root link's frame; its index, count and cluster are in the
    // AssemblyMode of the same configuration on the parallel topic.
    let indexed = got["assembly_mode"].as_array().expect("assembly_mode");
    assert_eq!(indexed.len(), 2, "{indexed:?}");
    for (k, (js, m)) in modes.iter().zip(indexed).enumerate() {
        assert_eq!(js["frame"], "ground");
        assert_eq!((m["mode"].as_u64(), m["modes"].as_u64(), m["header"]["frame_id"].as_str()), (Some(k as u64), Some(2), Some("ground")));
        assert_eq!((&m["joint_names"], &m["positions"]), (&js["name"], &js["position"]));
        assert_eq!(m["run_id"], set["run_id"]);
    }
    for (k, mode) in modes.iter().enumerate() {
        let names: Vec<&str> = mode["name"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
        let pos = floats(&mode["position"]);
        assert_eq!(names.last(), Some(&"crank_joint"));
        assert_eq!(pos.last(), Some(&0.5));
        let inside = reference["solutions"].as_array().expect("solutions").iter().any(|s| {
            names.iter().zip(&pos).all(|(n, p)| s["joints"].get(*n).is_none_or(|b| b[0].as_f64().expect("lo") <= *p && *p <= b[1].as_f64().expect("hi")))
        });
        assert!(inside, "mode {k} {mode} lies in no solution box");
    }
    assert_eq!(got["progress"]["done"], json!(true));
    assert_eq!(got["progress"]["decided"], json!(1.0));
    // A planar linkage publishes its singular sets: with the crank fixed and no transmission,
    // the C-space and output sets (no actuators, so no input set), both proven empty.
    assert_eq!(got["singularities"]["ok"], json!(true), "{}", got["singularities"]);

    // The octahedral platform, legs fixed at serve time (configuration a): its two assembly
    // modes, as `linkspace distances --redundant` finds them.
    let got = py(python, domain, "tests/ros_client.py", &["topics", "--prefix", "/linkspace/octahedral", "--modes", "2"], Duration::from_secs(90));
    assert_eq!(got["complete"], json!(true), "{got}");
    let set = &got["configuration_space"];
    assert_eq!(set["mechanism"], "octahedral");
    assert_eq!(set["clusters"], json!(2), "{set}");
    // REP 103 in the box set too: the fixed legs are lengths, and the joint-space boxes are the
    // unknown distances d(a,b) in metres, each holding the square root of its variable r(a,b).
    let fixed_names: Vec<&str> = set["fixed_joint_names"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
    let fixed_values = floats(&set["fixed_joint_values"]);
    let k = fixed_names.iter().position(|n| *n == "leg15").expect("leg15 is fixed");
    assert!((fixed_values[k] - f64::sqrt(4.25)).abs() < 1e-12, "leg15 published as {}", fixed_values[k]);
    let joint_names: Vec<&str> = set["joint_names"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
    let variables: Vec<&str> = set["variable_names"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
    let (dim, width) = (variables.len(), joint_names.len());
    let (lower, upper, joint_lower, joint_upper) = (floats(&set["lower"]), floats(&set["upper"]), floats(&set["joint_lower"]), floats(&set["joint_upper"]));
    for (j, name) in joint_names.iter().enumerate() {
        assert!(name.starts_with("d("), "{name} is not a distance");
        let v = variables.iter().position(|x| *x == name.replacen("d(", "r(", 1)).expect("its squared distance");
        for b in 0..lower.len() / dim {
            let (lo, hi) = (joint_lower[b * width + j], joint_upper[b * width + j]);
            assert!(lo * lo <= lower[b * dim + v] * (1.0 + 1e-12) && hi * hi >= upper[b * dim + v] * (1.0 - 1e-12), "box {b}: {name} [{lo}, {hi}]");
        }
    }
    // REP 103: the legs' squared lengths (the analysis's unknowns and the --fix values) travel
    // as lengths in metres.
    for mode in got["assembly_modes"].as_array().expect("modes") {
        let names: Vec<&str> = mode["name"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
        let pos = floats(&mode["position"]);
        for (leg, squared) in [("leg15", 4.25), ("leg16", 5.75)] {
            let k = names.iter().position(|n| *n == leg).expect("a fixed leg");
            assert!((pos[k] - f64::sqrt(squared)).abs() < 1e-12, "{leg}: {} is not the length sqrt({squared})", pos[k]);
        }
    }
    assert!(got["singularities"]["message"].as_str().expect("message").contains("not available for this mechanism"));

    // A curve of about 9,000 boxes (a sample of about a megabyte), through plot_boxes.py, which
    // also draws it.
    let reference = solve_json(&[&slider, "--sigma", "1e-3"]);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let (png, dump) = (dir.join("slider_crank.png"), dir.join("slider_crank.json"));
    let _ = std::fs::remove_file(&png);
    let _ = std::fs::remove_file(&dump);
    py_run(python, domain, "scripts/plot_boxes.py", &["--mechanism", "slider_crank", "--png", png.to_str().expect("utf-8"), "--json", dump.to_str().expect("utf-8")], Duration::from_secs(90));
    let set: Value = serde_json::from_str(&std::fs::read_to_string(&dump).expect("plot_boxes wrote JSON")).expect("valid JSON");
    assert!(reference["solutions"].as_array().expect("solutions").len() > 5_000);
    assert_same_boxes(&set, &reference);
    assert!(std::fs::metadata(&png).expect("plot_boxes wrote a PNG").len() > 10_000);
    assert!(node.alive());
}

/// One service call for the script of `ros_client.py services`.
/// Runs a script of service calls (`tests/ros_client.py services`) written to a file named
/// after `name`, and returns what the client printed.
fn services(python: &str, domain: u16, name: &str, script: impl AsRef<[u8]>, timeout: Duration) -> Value {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}.json", std::process::id()));
    std::fs::write(&path, script).expect("script written");
    let got = py(python, domain, "tests/ros_client.py", &["services", "--script", path.to_str().expect("utf-8")], timeout);
    let _ = std::fs::remove_file(&path);
    got
}

fn call(service: &str, kind: &str, request: Value) -> Value {
    json!({"service": format!("/linkspace/{service}"), "type": kind, "request": request})
}

fn settings(sigma: f64, max_boxes: u64, timeout: f64) -> Value {
    json!({"sigma": sigma, "rho": 0.95, "max_boxes": max_boxes, "timeout": timeout})
}

#[test]
fn services_answer_good_requests_and_refuse_bad_ones_with_reasons() {
    let Some(python) = python() else { return };
    let domain = 42;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    // A spatial variant, given as a robot_description string: loaded on the spatial builder (its
    // crank turns about x, so the loop closes only with the crank at 0 or π), listed, and refused
    // what linkages do not answer.
    let tilted = std::fs::read_to_string(&four_bar).expect("fixture").replacen("<robot name=\"four_bar\"", "<robot name=\"tilted\"", 1).replacen("<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>", 1);
    assert!(tilted.contains("name=\"tilted\""));
    let mut node = Node::start(domain, &[&four_bar, "--robot-description", &tilted, "--fix", "four_bar:crank_joint=0.5", "--trace", "four_bar:coupler@2,1", "--sigma", "1e-5", "--max-request-boxes", "500000"]);
    node.wait_for(&["four_bar: published configuration_space", "four_bar: published singularities"], Duration::from_secs(60));

    let loaded = solve_json(&[&four_bar, "--fix", "crank_joint=0.5", "--trace", "coupler@2,1", "--sigma", "1e-5"]);
    let again = solve_json(&[&four_bar, "--fix", "crank_joint=1", "--trace", "coupler@2,1", "--sigma", "1e-5", "--max-boxes", "100000", "--timeout", "60"]);
    // A configuration of the first assembly mode, and one far from every box.
    let mode: Vec<(String, f64)> = loaded["solutions"][0]["joints"].as_object().expect("joints").iter().map(|(k, v)| (k.clone(), 0.5 * (v[0].as_f64().expect("lo") + v[1].as_f64().expect("hi")))).collect();
    let names: Vec<&str> = mode.iter().map(|(k, _)| k.as_str()).collect();
    let values: Vec<f64> = mode.iter().map(|(_, v)| *v).collect();
    let far: Vec<f64> = values.iter().map(|v| v + 1.0).collect();
    let fine = settings(1e-5, 100_000, 60.0);
    let long = settings(1e-7, 400_000, 120.0);
    let script = json!([
        call("list_mechanisms", "ListMechanisms", json!({})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["crank_joint"], "fixed_joint_values": [1.0], "settings": fine, "wait": 20.0})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["crank_joint"], "fixed_joint_values": [1.2], "settings": fine, "wait": 20.0})),
        {"subscribe": "/linkspace/four_bar/solve_result"},
        call("solve", "Solve", json!({"mechanism": "ghost", "settings": fine})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": {"sigma": f64::NAN, "rho": 0.95, "max_boxes": 10, "timeout": 1.0}})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["crank_joint"], "fixed_joint_values": [f64::NAN], "settings": fine})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": settings(1e-3, 1_000_000_000_000, 10.0)})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": settings(1e-3, 1000, -1.0)})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["nope"], "fixed_joint_values": [1.0], "settings": fine})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": fine, "wait": 1e9})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": long, "wait": 0.0})),
        call("cancel", "Cancel", json!({"run_id": 7})),
        {"sleep": 2.0},
        {"subscribe": "/linkspace/four_bar/solve_result"},
        call("cancel", "Cancel", json!({"run_id": 7})),
        call("cancel", "Cancel", json!({"run_id": 999_999})),
        call("singularities", "Singularities", json!({"mechanism": "four_bar"})),
        call("singularities", "Singularities", json!({"mechanism": "tilted"})),
        call("inverse_kinematics", "InverseKinematics", json!({"mechanism": "four_bar", "point": [1.0, 2.0, 0.0], "sigma": 1e-3})),
        call("inverse_kinematics", "InverseKinematics", json!({"mechanism": "tilted", "point": [f64::NAN, 0.0, 0.0], "sigma": 1e-3})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": names, "joint_values": values})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": names, "joint_values": far})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": names, "joint_values": [f64::NAN, 0.0, 0.0]})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": &names[..2], "joint_values": &values[..2]})),
        call("classify", "Classify", json!({"mechanism": "ghost", "joint_names": names, "joint_values": values})),
        call("classify", "Classify", json!({"mechanism": "tilted", "joint_names": names, "joint_values": values})),
        call("list_mechanisms", "ListMechanisms", json!({})),
        {"subscribe": "/linkspace/four_bar/progress", "type": "Progress"},
    ]);
    // serde_json writes NaN as null; the script file carries it as the string "NaN".
    let text = serde_json::to_string(&script).expect("json").replace("null", "\"NaN\"");
    let got = services(python, domain, "services", text, Duration::from_secs(240));
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    let refused = |k: usize, needle: &str| {
        assert_eq!(r[k]["ok"], json!(false), "step {k} should be refused: {}", r[k]);
        let m = r[k]["message"].as_str().expect("message");
        assert!(m.contains(needle), "step {k}: '{m}' should mention '{needle}'");
    };

    // list_mechanisms: both, with their kinds and what they answer.
    let list = r[0]["mechanisms"].as_array().expect("mechanisms");
    assert_eq!(list.len(), 2);
    assert_eq!((list[0]["name"].as_str(), list[0]["kind"].as_str(), list[0]["state"].as_str()), (Some("four_bar"), Some("planar_linkage"), Some("complete")));
    assert_eq!(list[0]["services"], json!(["solve", "singularities", "classify"]));
    assert_eq!(list[0]["topic_prefix"], "/linkspace/four_bar");
    assert_eq!((list[1]["name"].as_str(), list[1]["kind"].as_str()), (Some("tilted"), Some("spatial_linkage")));
    assert!(list[1]["message"].as_str().expect("message").contains("complete, 2 boxes in 2 clusters"), "the crank at 0 and at π: {}", list[1]);
    assert_eq!(list[1]["services"], json!(["solve", "singularities", "classify"]));

    // Solve again with another crank angle: the same boxes as the CLI.
    assert_eq!((r[1]["ok"].clone(), r[1]["done"].clone()), (json!(true), json!(true)), "{}", r[1]);
    assert_eq!(r[1]["result"]["analysis"], "solve");
    assert_same_boxes(&r[1]["result"], &again);
    // A subscriber joining after two solves gets the latest. (RustDDS may still hold an older
    // sample that another reader has not acknowledged and send it first; the last one counts.)
    let latest = r[3]["received"].as_array().expect("received").last().expect("the late joiner got the latest result");
    assert_eq!(latest["run_id"], r[2]["run_id"]);
    assert_eq!(latest["fixed_joint_values"], json!([1.2]));

    refused(4, "no mechanism named 'ghost' is loaded (loaded: four_bar, tilted)");
    refused(5, "sigma must be a positive finite number");
    refused(6, "not a finite number");
    refused(7, "larger than this node's limit 500000");
    refused(8, "settings.timeout -1 s is out of range");
    refused(9, "no joint or loop named 'nope'");
    refused(10, "wait 1000000000 s is out of range");

    // A long run, answered at once with its id (runs 1 to 4 are the load-time analyses: the
    // four-bar's configuration space and singular sets, the tilted one's),
    // cancelled, and published incomplete.
    assert_eq!((r[11]["ok"].clone(), r[11]["done"].clone(), r[11]["run_id"].clone()), (json!(true), json!(false), json!(7)), "{}", r[11]);
    assert!(r[11]["message"].as_str().expect("message").contains("/linkspace/four_bar/solve_result"));
    assert_eq!(r[12]["ok"], json!(true), "{}", r[12]);
    let cancelled = r[14]["received"].as_array().and_then(|v| v.last()).cloned().unwrap_or_default();
    assert!(cancelled.is_object(), "no result after the cancel: {}\nnode log:\n{}", r[14], node.log());
    assert_eq!((cancelled["run_id"].clone(), cancelled["status"].clone(), cancelled["limit"].clone()), (json!(7), json!(1), json!("cancelled")));
    assert!(cancelled["box_status"].as_array().expect("statuses").contains(&json!(1)), "a cancelled run reports its undecided boxes");
    refused(15, "run 7 has already finished");
    refused(16, "no run 999999");

    // The planar four-bar answers singularities with its load-time sets (crank fixed, no
    // transmission: C-space and output, both proven empty); so does the spatial one (the
    // spatial model's sets: C-space and output); inverse kinematics has no math yet.
    assert_eq!((r[17]["ok"].clone(), r[17]["report"]["set_kinds"].clone(), r[17]["report"]["complete"].clone()), (json!(true), json!(["cspace", "output"]), json!(true)), "{}", r[17]);
    assert_eq!(r[17]["report"]["actuated"], json!([]));
    assert_eq!((r[18]["ok"].clone(), r[18]["report"]["set_kinds"].clone()), (json!(true), json!(["cspace", "output"])), "{}", r[18]);
    refused(19, "inverse_kinematics is not available for this mechanism ('four_bar'");
    refused(20, "is not finite");

    // Classification: inside the first mode's component; outside, with the nearest component.
    assert_eq!((r[21]["ok"].clone(), r[21]["inside"].clone(), r[21]["component"].clone(), r[21]["components"].clone()), (json!(true), json!(true), json!(0), json!(2)), "{}", r[21]);
    // Complete, empty singular sets: no singular configuration of those kinds at any distance.
    assert_eq!((r[21]["singular_distance_known"].clone(), r[21]["singular_distance"].clone()), (json!(true), json!("inf")), "{}", r[21]);
    assert!(r[21]["message"].as_str().expect("message").contains("no singular configuration"), "{}", r[21]);
    assert_eq!((r[22]["ok"].clone(), r[22]["inside"].clone()), (json!(true), json!(false)), "{}", r[22]);
    assert!(r[22]["distance"].as_f64().expect("distance") > 0.1);
    refused(23, "is not a finite number");
    refused(24, "no value for free joint");
    refused(25, "no mechanism named 'ghost'");
    refused(26, "no value for free joint 'crank_joint'");
    assert_eq!(r[27]["mechanisms"].as_array().expect("mechanisms").len(), 2);
    // The last progress is the cancelled run's end: done, part of the volume decided.
    let progress = r[28]["received"].as_array().and_then(|v| v.last()).cloned().unwrap_or_default();
    assert_eq!((progress["run_id"].clone(), progress["analysis"].clone(), progress["done"].clone()), (json!(7), json!("solve"), json!(true)), "{progress}");
    let decided = progress["decided"].as_f64().expect("decided");
    assert!((0.0..1.0).contains(&decided) && progress["processed"].as_u64().expect("processed") > 0, "{progress}");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

#[test]
fn a_hundred_requests_in_flight_are_all_answered_and_the_node_stays_small() {
    let Some(python) = python() else { return };
    let domain = 43;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    // Two runs at a time, 20,000 boxes each at most: the bound the memory check relies on.
    let mut node = Node::start(domain, &[&four_bar, "--fix", "four_bar:crank_joint=0.5", "--sigma", "1e-5", "--max-runs", "2", "--max-request-boxes", "20000"]);
    node.wait_for(&["four_bar: published configuration_space"], Duration::from_secs(60));
    let before = node.memory_kib("VmRSS:");
    let joints = json!({"coupler_joint": 0.2668, "rocker_joint": 1.5145, "loop_coupler_rocker": 0.7477});
    let got = py(python, domain, "tests/ros_client.py", &["load", "--mechanism", "four_bar", "--joints", &joints.to_string(), "--clients", "4", "--requests", "100", "--timeout", "60"], Duration::from_secs(180));
    let replies = got["replies"].as_array().expect("replies");
    assert_eq!(replies.len(), 100);
    let unanswered: Vec<&Value> = replies.iter().filter(|r| r["answered"] != json!(true)).collect();
    assert!(unanswered.is_empty(), "{} requests got no reply: {unanswered:?}\nnode log:\n{}", unanswered.len(), node.log());
    for r in replies {
        if r["ok"] != json!(true) {
            assert!(!r["message"].as_str().unwrap_or("").is_empty(), "a refusal without a reason: {r}");
        }
    }
    let busy = replies.iter().filter(|r| r["message"].as_str().is_some_and(|m| m.starts_with("busy"))).count();
    let started = replies.iter().filter(|r| r["kind"] == "solve" && r["ok"] == json!(true)).count();
    assert!(busy > 0 && started >= 2, "20 long solves against --max-runs 2: {started} started, {busy} refused as busy");
    assert!(replies.iter().any(|r| r["kind"] == "classify" && r["ok"] == json!(true)));
    assert!(replies.iter().any(|r| r["kind"] == "classify" && r["message"].as_str().is_some_and(|m| m.contains("ghost"))));
    assert!(node.alive(), "the node died under load:\n{}", node.log());
    let (after, peak) = (node.memory_kib("VmRSS:"), node.memory_kib("VmHWM:"));
    eprintln!("node memory: {before} KiB before the load, {after} KiB after, peak {peak} KiB; {:.2} s for 100 requests", got["seconds"].as_f64().unwrap_or(f64::NAN));
    // Two runs of at most 20,000 six-variable boxes are a few MB; 256 MiB would mean a leak or
    // an unbounded queue.
    assert!(peak < 256 * 1024, "peak RSS {peak} KiB");
}

#[test]
fn bad_serve_input_stops_the_node_with_one_line_before_any_dds_traffic() {
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let slider = format!("{ROOT}/urdf/slider_crank.urdf");
    let cases: [(Vec<&str>, &str); 11] = [
        (vec!["/nonexistent.urdf"], "reading /nonexistent.urdf"),
        (vec![&four_bar, "--ros-args", "-r", "chatter:=talk"], "only the node's name and namespace can be remapped"),
        (vec![&four_bar, "--ros-args", "-p", "sigma:=abc"], "parameter sigma: 'abc' is not a valid value"),
        (vec![&four_bar, "--ros-args", "--params-file", "/nonexistent.yaml"], "--params-file /nonexistent.yaml"),
        (vec!["--ros-args", "-p", "robot_description:=<robot"], "parameter robot_description: malformed URDF"),
        (vec![], "no mechanism to serve"),
        (vec![&four_bar, "--domain", "300"], "domain 300 is out of range"),
        (vec![&four_bar, "--fix", "nope=1"], "no joint or loop named 'nope'"),
        (vec![&four_bar, &slider, "--fix", "crank_joint=1"], "with several mechanisms, name the robot"),
        (vec![&four_bar, &four_bar], "a mechanism named 'four_bar' is already loaded"),
        (vec![&four_bar, "--robot-description", "<robot"], "--robot-description #1: malformed URDF"),
    ];
    for (args, needle) in cases {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_linkspace"));
        // A domain of its own, in case a case wrongly starts the node.
        cmd.arg("serve").args(["--network", "loopback"]).args(&args).env("ROS_DOMAIN_ID", "44");
        let (ok, _, err) = run_with_timeout(cmd, Duration::from_secs(20));
        assert!(!ok, "{args:?} should fail");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: expected one line, got {err}");
        assert!(lines[0].starts_with("error: ") && lines[0].contains(needle), "{args:?}: '{}' should mention '{needle}'", lines[0]);
    }
}

#[test]
fn a_cyclone_dds_client_gets_the_same_boxes_and_replies_with_the_cyclone_mapping() {
    let Some(python) = python() else { return };
    let domain = 45;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let mut node = Node::start(domain, &[&four_bar, "--fix", "crank_joint=0.5", "--sigma", "1e-5", "--service-mapping", "cyclone"]);
    node.wait_for(&["Cyclone mapping", "four_bar: published configuration_space"], Duration::from_secs(60));
    let reference = solve_json(&[&four_bar, "--fix", "crank_joint=0.5", "--sigma", "1e-5"]);
    let mut cmd = Command::new(python);
    cmd.arg(format!("{ROOT}/tests/cyclone_client.py"))
        .args(["--prefix", "/linkspace/four_bar", "--mechanism", "four_bar"])
        .env("CYCLONEDDS_URI", format!("file://{ROOT}/scripts/cyclonedds_loopback.xml"))
        .env("ROS_DOMAIN_ID", domain.to_string());
    let (ok, out, err) = run_with_timeout(cmd, Duration::from_secs(90));
    assert!(ok, "cyclone_client.py failed:\n{out}\n{err}");
    let got: Value = serde_json::from_str(out.lines().last().expect("a line")).expect("JSON");
    assert_same_boxes(&got["configuration_space"], &reference);
    let list = &got["list"];
    assert!(list.get("error").is_none(), "{list}");
    assert_eq!(list["mechanisms"][0]["name"], "four_bar");
    assert_eq!(list["mechanisms"][0]["free_joints"], json!(["coupler_joint", "rocker_joint", "loop_coupler_rocker"]));
    let refused = &got["classify_ghost"];
    assert_eq!(refused["ok"], json!(false), "{refused}");
    assert!(refused["message"].as_str().expect("message").contains("no mechanism named 'ghost'"));
    assert!(node.alive());
}

/// `linkspace CMD ARGS --json FILE` → the report.
fn cli_json(cmd: &str, args: &[&str]) -> Value {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("topics-{cmd}-{}-{}.json", std::process::id(), args.join("_").replace(['/', '@', ',', '='], "-")));
    let mut c = Command::new(env!("CARGO_BIN_EXE_linkspace"));
    c.arg(cmd).args(args).arg("--json").arg(&path);
    let (ok, _, err) = run_with_timeout(c, Duration::from_secs(120));
    assert!(ok, "linkspace {cmd} {args:?}: {err}");
    let v = serde_json::from_str(&std::fs::read_to_string(&path).expect("json written")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    v
}

fn bounds(v: &Value) -> [f64; 2] {
    [v[0].as_f64().expect("lo"), v[1].as_f64().expect("hi")]
}

/// Intervals of a message (`[{lower, upper}]`) as pairs.
fn intervals(v: &Value) -> Vec<[f64; 2]> {
    v.as_array().expect("intervals").iter().map(|i| [i["lower"].as_f64().expect("lower"), i["upper"].as_f64().expect("upper")]).collect()
}

/// Joint intervals of a CLI record (`{"joint2": [lo, hi], ...}`) in the order of `names`.
fn by_name(record: &Value, names: &[&str]) -> Vec<[f64; 2]> {
    names.iter().map(|n| bounds(&record[n])).collect()
}

/// The singularity report (as JSON from Python) holds exactly the CLI report's records, in
/// the same order: certified ones, then undecided ones.
fn assert_same_singularities(report: &Value, cli: &Value) {
    assert_eq!(report["ok"], json!(true), "{}", report["message"]);
    let names: Vec<&str> = report["joint_names"].as_array().expect("joint names").iter().map(|v| v.as_str().expect("str")).collect();
    assert_eq!(names, vec![cli["joints"][1].as_str().expect("joint2"), cli["joints"][2].as_str().expect("joint3")]);
    assert_eq!(report["workspace_names"], json!(["radius", "z"]));
    assert_eq!(report["complete"], json!(cli["status"] == "complete"));
    assert_eq!(report["precision"], cli["settings"]["precision"]);
    let workspace = |w: &Value| vec![bounds(&w["radius"]), bounds(&w["z"])];
    let cusps = report["cusps"].as_array().expect("cusps");
    let (cli_cusps, cli_undecided) = (cli["cusps"].as_array().expect("cusps"), cli["undecided"]["cusps"].as_array().expect("undecided"));
    assert_eq!(cusps.len(), cli_cusps.len() + cli_undecided.len(), "cusp records");
    for (c, r) in cusps.iter().zip(cli_cusps) {
        assert_eq!(intervals(&c["joints"]), by_name(&r["joints"], &names));
        assert_eq!(intervals(&c["workspace"]), workspace(&r["workspace"]));
        assert_eq!(c["certified"], r["unique"]);
    }
    for (c, r) in cusps[cli_cusps.len()..].iter().zip(cli_undecided) {
        assert_eq!(intervals(&c["joints"]), by_name(&r["joints"], &names));
        assert_eq!(c["certified"], json!(false));
    }
    let nodes = report["nodes"].as_array().expect("nodes");
    let (cli_nodes, cli_pairs) = (cli["nodes"].as_array().expect("nodes searched"), cli["undecided"]["nodes"].as_array().expect("undecided"));
    assert_eq!(nodes.len(), cli_nodes.len() + cli_pairs.len(), "node records");
    for (n, r) in nodes.iter().zip(cli_nodes) {
        assert_eq!(intervals(&n["joints_a"]), by_name(&r["points"][0], &names));
        assert_eq!(intervals(&n["joints_b"]), by_name(&r["points"][1], &names));
        assert_eq!(intervals(&n["workspace"]), workspace(&r["workspace"]));
        assert_eq!(n["certified"], json!(true));
    }
    let motions = &report["internal_motions"];
    let lines = cli["internal_motions"].as_array().expect("internal motions");
    assert_eq!(motions["dim"], json!(2));
    let (lower, upper) = (floats(&motions["lower"]), floats(&motions["upper"]));
    assert_eq!(lower.len(), 2 * lines.len(), "internal-motion boxes");
    for (k, line) in lines.iter().enumerate() {
        let b = by_name(&line["joints"], &names);
        assert_eq!([[lower[2 * k], upper[2 * k]], [lower[2 * k + 1], upper[2 * k + 1]]], [b[0], b[1]], "line {k}");
    }
    // The cover of the singular curves (no CLI counterpart; service replies leave its boxes
    // out) must hold every certified cusp and node point: two independent computations of the
    // same singular set.
    let curves = &report["singular_curves"];
    assert_eq!((curves["analysis"].as_str(), curves["dim"].as_u64(), curves["status"].as_u64()), (Some("singular_curves"), Some(2), Some(0)));
    let (cl, cu) = (floats(&curves["lower"]), floats(&curves["upper"]));
    assert_eq!(cl.len(), cu.len());
    if cl.is_empty() {
        return;
    }
    let covered = |b: &[[f64; 2]]| (0..cl.len() / 2).any(|k| (0..2).all(|d| cl[2 * k + d] <= b[d][1] && b[d][0] <= cu[2 * k + d]));
    for c in cusps.iter().filter(|c| c["certified"] == json!(true)) {
        assert!(covered(&intervals(&c["joints"])), "cusp {c} outside the curve cover");
    }
    for n in nodes.iter().filter(|n| n["certified"] == json!(true)) {
        assert!(covered(&intervals(&n["joints_a"])) && covered(&intervals(&n["joints_b"])), "node {n} outside the curve cover");
    }
}

/// The report's verdict and singular branches (appended fields) are the CLI report's
/// `verdict` and `singular_branches`, field for field; no branches when the CLI has none.
fn assert_same_verdict_and_branches(report: &Value, cli: &Value) {
    let v = &cli["verdict"];
    let tri = |x: &Value| json!(match x.as_bool() { Some(true) => 1, Some(false) => 0, None => -1 });
    let count = |x: &Value| json!(x.as_i64().unwrap_or(-1));
    assert_eq!(report["cuspidal"], tri(&v["cuspidal"]), "{v}");
    assert_eq!((report["aspects"].clone(), report["max_ik_solutions"].clone()), (count(&v["aspects"]), count(&v["max_ik_solutions"])), "{v}");
    assert_eq!((report["verdict_certified"].clone(), report["verdict_reason"].clone()), (v["certified"].clone(), v["reason"].clone()));
    let names: Vec<&str> = report["joint_names"].as_array().expect("joint names").iter().map(|v| v.as_str().expect("str")).collect();
    let crossings = &report["branch_crossings"];
    assert_eq!((crossings["analysis"].as_str(), crossings["dim"].as_u64()), (Some("branch_crossings"), Some(4)));
    let Some(b) = cli.get("singular_branches").filter(|b| !b.is_null()) else {
        for k in ["branch_names", "branch_kinds", "crossing_names", "branch_images", "branch_isolated_nodes"] {
            assert_eq!(report[k], json!([]), "{k}");
        }
        assert_eq!(crossings["lower"], json!([]));
        return;
    };
    let branches = b["branches"].as_array().expect("branches");
    let field = |k: &str| branches.iter().map(|x| x[k].clone()).collect::<Vec<Value>>();
    assert_eq!(report["branch_names"], json!(field("name")));
    assert_eq!(report["branch_kinds"], json!(field("kind")));
    assert_eq!(report["branch_descriptions"], json!(field("description")));
    assert_eq!(report["branch_proofs"], json!(field("proof")));
    assert_eq!(report["branch_curve_of_nodes"], json!(branches.iter().map(|x| tri(&x["curve_of_nodes"])).collect::<Vec<_>>()));
    assert_eq!(report["branch_image_descriptions"], json!(branches.iter().map(|x| x["image"]["description"].clone()).collect::<Vec<_>>()));
    let images: Vec<[f64; 2]> = branches.iter().flat_map(|x| [bounds(&x["image"]["radius"]), bounds(&x["image"]["z"])]).collect();
    assert_eq!(intervals(&report["branch_images"]), images);
    // Each crossing once, in the order first met, on the branches listing it.
    let mut cli_crossings: Vec<(Value, Vec<u32>)> = Vec::new();
    for (i, x) in branches.iter().enumerate() {
        for c in x["crossings"].as_array().expect("crossings") {
            match cli_crossings.iter_mut().find(|(y, _)| y == c) {
                Some((_, on)) => on.push(i as u32),
                None => cli_crossings.push((c.clone(), vec![i as u32])),
            }
        }
    }
    assert_eq!(report["crossing_names"], json!(cli_crossings.iter().map(|(c, _)| c["name"].clone()).collect::<Vec<_>>()));
    assert_eq!(report["crossing_branches"], json!(cli_crossings.iter().flat_map(|(_, on)| on.clone()).collect::<Vec<_>>()));
    let (lower, upper) = (floats(&crossings["lower"]), floats(&crossings["upper"]));
    assert_eq!(lower.len(), 4 * cli_crossings.len());
    for (k, (c, _)) in cli_crossings.iter().enumerate() {
        let mut want = by_name(&c["joints"], &names);
        want.extend([bounds(&c["workspace"]["radius"]), bounds(&c["workspace"]["z"])]);
        let got: Vec<[f64; 2]> = (0..4).map(|d| [lower[4 * k + d], upper[4 * k + d]]).collect();
        assert_eq!(got, want, "crossing {k}");
    }
    assert_eq!(crossings["box_status"], json!(vec![2; cli_crossings.len()]));
    assert_eq!(crossings["status"], json!(if b["crossings"].is_null() { 1 } else { 0 }));
    assert_eq!(report["branch_isolated_nodes"].as_array().expect("nodes").len(), b["isolated_nodes"].as_array().expect("nodes").len());
    assert_eq!((report["branches_no_cusp_proven"].clone(), report["branches_argument"].clone()), (b["no_cusp_proven"].clone(), b["argument"].clone()));
}

/// The tip of a 3R URDF at joint values `q` (floating point), by composing the URDF transforms.
fn forward_kinematics(urdf_path: &str, q: &[f64]) -> [f64; 3] {
    use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion};
    let m = linkspace::model::urdf::parse(&std::fs::read_to_string(urdf_path).expect("fixture")).expect("parses");
    let tip = (0..m.links.len()).find(|&l| m.joints.iter().all(|j| j.parent != l)).expect("a leaf");
    let mut pose = Isometry3::identity();
    let mut k = 0;
    for j in m.path_to(tip) {
        let joint = &m.joints[j];
        pose *= joint.origin;
        if matches!(joint.kind, linkspace::model::JointKind::Revolute { .. }) {
            pose *= Isometry3::from_parts(Translation3::identity(), UnitQuaternion::from_axis_angle(&Unit::new_normalize(joint.axis), q[k]));
            k += 1;
        }
    }
    let p = pose * Point3::origin();
    [p.x, p.y, p.z]
}

#[test]
fn a_3r_manipulator_publishes_its_singularities_and_answers_inverse_kinematics() {
    let Some(python) = python() else { return };
    let domain = 46;
    let (e, f) = (format!("{ROOT}/urdf/orthogonal_3r_e.urdf"), format!("{ROOT}/urdf/orthogonal_3r_f.urdf"));
    // A real 6R arm beside them (axes 2 and 3 parallel): its verdict and singular branches.
    let puma = format!("{ROOT}/urdf/puma560.urdf");
    let mut node = Node::start(domain, &[&e, &f, &puma, "--max-request-boxes", "300000"]);
    node.wait_for(&["orthogonal_3r_e: published singularities", "orthogonal_3r_f: published singularities", "puma560: published singularities"], Duration::from_secs(120));

    // The latched topics, to a late subscriber: the same records as the CLI.
    let got = py(
        python,
        domain,
        "tests/ros_client.py",
        &["singular", "--prefix", "/linkspace/orthogonal_3r_e", "--prefix", "/linkspace/orthogonal_3r_f", "--prefix", "/linkspace/puma560"],
        Duration::from_secs(90),
    );
    assert_eq!(got["complete"], json!(true), "{got}");
    let (ref_e, ref_f, ref_puma) = (cli_json("singularities", &[&e, "--nodes"]), cli_json("singularities", &[&f, "--nodes"]), cli_json("singularities", &[&puma, "--nodes"]));
    let report_e = &got["/linkspace/orthogonal_3r_e"]["singularities"];
    assert_same_singularities(report_e, &ref_e);
    assert_same_singularities(&got["/linkspace/orthogonal_3r_f"]["singularities"], &ref_f);
    // The verdict and singular branches, as the CLI's: e cuspidal with 2 aspects and 4
    // solutions, f non-cuspidal, the PUMA non-cuspidal with 4 aspects, at most 4 solutions and
    // three branches crossing in 4 points (no cusp search, no node search: the proof).
    let report_puma = &got["/linkspace/puma560"]["singularities"];
    for (report, cli) in [(report_e, &ref_e), (&got["/linkspace/orthogonal_3r_f"]["singularities"], &ref_f), (report_puma, &ref_puma)] {
        assert_same_verdict_and_branches(report, cli);
    }
    assert_eq!((report_e["cuspidal"].clone(), report_e["aspects"].clone(), report_e["max_ik_solutions"].clone()), (json!(1), json!(2), json!(4)));
    assert_eq!((report_puma["cuspidal"].clone(), report_puma["aspects"].clone(), report_puma["max_ik_solutions"].clone()), (json!(0), json!(4), json!(4)));
    assert_eq!((report_puma["crossing_names"].as_array().map(Vec::len), report_puma["branch_names"].as_array().map(Vec::len)), (Some(4), Some(3)));
    assert_eq!((report_puma["ok"].clone(), report_puma["complete"].clone(), report_puma["cusps"].clone(), report_puma["nodes"].clone()), (json!(true), json!(true), json!([]), json!([])));
    // Robot e: 4 cusps, 2 nodes; robot f: 2 nodes and its two internal-motion lines.
    let certified = |r: &Value, k: &str| r[k].as_array().expect("records").iter().filter(|c| c["certified"] == json!(true)).count();
    assert_eq!((certified(report_e, "cusps"), certified(report_e, "nodes")), (4, 2));
    let report_f = &got["/linkspace/orthogonal_3r_f"]["singularities"];
    for report in [report_e, report_f] {
        assert!(floats(&report["singular_curves"]["lower"]).len() > 2 * 500, "the topic carries the whole curve cover");
    }
    assert_eq!((certified(report_f, "cusps"), certified(report_f, "nodes"), floats(&report_f["internal_motions"]["lower"]).len()), (0, 2, 4));
    // Markers: DELETEALL, one cube per cover box and per line, a sphere per cusp and per node point.
    let markers = got["/linkspace/orthogonal_3r_e"]["markers"].as_array().expect("markers");
    assert_eq!(markers[0]["action"], json!(3));
    let count = |ns: &str| markers.iter().filter(|m| m["ns"] == ns).count();
    assert_eq!((count("singular_curves"), count("cusps"), count("nodes")), (floats(&report_e["singular_curves"]["lower"]).len() / 2, 4, 4));
    assert_eq!(markers[1]["frame"], "orthogonal_3r_e/joint_space");
    let progress = &got["/linkspace/orthogonal_3r_e"]["progress"];
    assert_eq!((progress["analysis"].as_str(), progress["done"].clone(), progress["decided"].clone()), (Some("singularities"), json!(true), json!(1.0)));

    // Services.
    let (r, z) = (1.9, 0.4);
    let ik_ref = cli_json("ik", &[&e, "--point", &format!("{r},{z}"), "--precision", "1e-6"]);
    let ik_ref_short = cli_json("ik", &[&e, "--point", &format!("{r},{z}"), "--precision", "1e-6", "--max-boxes", "40"]);
    let cusp = report_e["cusps"][0]["joints"].as_array().expect("cusp").iter().map(|i| 0.5 * (i["lower"].as_f64().expect("lo") + i["upper"].as_f64().expect("hi"))).collect::<Vec<f64>>();
    let ik = |point: [f64; 3], sigma: f64, max_boxes: u64| call("inverse_kinematics", "InverseKinematics", json!({"mechanism": "orthogonal_3r_e", "point": point, "sigma": sigma, "max_boxes": max_boxes}));
    let sing = |mechanism: &str, precision: f64, nodes: bool, max_boxes: u64, timeout: f64| {
        call("singularities", "Singularities", json!({"mechanism": mechanism, "precision": precision, "nodes": nodes, "max_boxes": max_boxes, "timeout": timeout}))
    };
    let classify = |q: [f64; 3]| call("classify", "Classify", json!({"mechanism": "orthogonal_3r_e", "joint_names": ["joint1", "joint2", "joint3"], "joint_values": q}));
    let phi: f64 = 0.7;
    let script = json!([
        call("list_mechanisms", "ListMechanisms", json!({})),
        ik([r, 0.0, z], 1e-6, 0),
        ik([r * phi.cos(), r * phi.sin(), z], 1e-6, 0),
        ik([r, 0.0, z], 1e-6, 40),
        ik([f64::NAN, 0.0, z], 1e-6, 0),
        ik([r, 0.0, z], 2.0, 0),
        ik([r, 0.0, z], 1e-6, 1_000_000_000),
        sing("orthogonal_3r_e", 0.0, false, 0, 0.0),
        sing("orthogonal_3r_f", 1e-3, true, 0, 0.0),
        sing("orthogonal_3r_e", 2.0, true, 0, 0.0),
        sing("orthogonal_3r_e", 1e-3, true, 1_000_000_000, 0.0),
        sing("orthogonal_3r_e", 1e-3, true, 0, 1e9),
        sing("orthogonal_3r_e", 1e-6, true, 50, 5.0),
        classify([0.3, 0.0, 0.0]),
        classify([0.3, cusp[0], cusp[1]]),
        classify([0.3, f64::NAN, 0.0]),
        call("solve", "Solve", json!({"mechanism": "orthogonal_3r_e", "settings": settings(1e-3, 1000, 1.0)})),
    ]);
    let text = serde_json::to_string(&script).expect("json").replace("null", "\"NaN\"");
    let got = services(python, domain, "services-3r", text, Duration::from_secs(180));
    let r_ = got["results"].as_array().expect("results");
    for (k, x) in r_.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    let refused = |k: usize, needle: &str| {
        assert_eq!(r_[k]["ok"], json!(false), "step {k} should be refused: {}", r_[k]);
        let m = r_[k]["message"].as_str().expect("message");
        assert!(m.contains(needle), "step {k}: '{m}' should mention '{needle}'");
    };

    let list = r_[0]["mechanisms"].as_array().expect("mechanisms");
    assert_eq!((list[0]["kind"].as_str(), list[0]["state"].as_str()), (Some("manipulator_3r"), Some("complete")));
    assert_eq!(list[0]["services"], json!(["singularities", "inverse_kinematics", "classify", "path_check"]));
    assert_eq!(list[0]["free_joints"], json!(["joint1", "joint2", "joint3"]));

    // Inverse kinematics of (r, 0, z): the CLI's boxes for joints 2 and 3, unique ones and
    // clusters alike, and a first joint that puts the tip on the point.
    let check_ik = |reply: &Value, reference: &Value| {
        assert_eq!(reply["ok"], json!(true), "{reply}");
        assert_eq!(reply["joint_names"], json!(["joint1", "joint2", "joint3"]));
        assert_eq!(reply["complete"], json!(reference["status"] == "complete"));
        assert_eq!(reply["processed"], reference["processed"]);
        let sols = reply["solutions"].as_array().expect("solutions");
        let refs = reference["solutions"].as_array().expect("solutions");
        assert_eq!(sols.len(), refs.len());
        for (k, (s, rf)) in sols.iter().zip(refs).enumerate() {
            let iv = intervals(&s["intervals"]);
            assert_eq!(iv[1..], by_name(&rf["joints"], &["joint2", "joint3"])[..], "solution {k}");
            assert_eq!(reply["unique"][k], rf["unique"]);
            assert_eq!(reply["merged_boxes"][k], rf["boxes"]);
        }
    };
    check_ik(&r_[1], &ik_ref);
    assert!(ik_ref["solutions"].as_array().expect("solutions").iter().filter(|s| s["unique"] == json!(true)).count() >= 2);
    // The point seen by the analysis: radius and z of (r, 0, z), enclosed (√ρ rounds outward).
    let seen = intervals(&r_[1]["point_values"]);
    assert!(seen[0][0] <= r && r <= seen[0][1] && seen[0][1] - seen[0][0] < 1e-15 && seen[1] == [z, z], "{seen:?}");
    for (k, point) in [(1, [r, 0.0, z]), (2, [r * phi.cos(), r * phi.sin(), z])] {
        for (s, unique) in r_[k]["solutions"].as_array().expect("solutions").iter().zip(r_[k]["unique"].as_array().expect("unique")) {
            if *unique != json!(true) {
                continue;
            }
            let q: Vec<f64> = intervals(&s["intervals"]).iter().map(|b| 0.5 * (b[0] + b[1])).collect();
            let tip = forward_kinematics(&e, &q);
            let miss = (0..3).map(|i| (tip[i] - point[i]).powi(2)).sum::<f64>().sqrt();
            assert!(miss < 1e-5, "step {k}: {q:?} puts the tip at {tip:?}, not {point:?}");
        }
    }
    // The same unique solutions from the turned point, with θ1 turned by φ.
    assert_eq!(r_[2]["unique"], r_[1]["unique"]);
    // A box limit: incomplete, as the CLI with the same limit, pending boxes in clusters.
    check_ik(&r_[3], &ik_ref_short);
    assert_eq!(r_[3]["complete"], json!(false));
    refused(4, "is not finite");
    refused(5, "precision must be a number in (0, 1), got 2");
    refused(6, "larger than this node's limit 300000");

    // The load-time report again, and a new run at another precision for robot f.
    assert_eq!(r_[7]["ok"], json!(true));
    assert_eq!(r_[7]["report"]["cusps"], report_e["cusps"]);
    assert_eq!(r_[7]["report"]["nodes"], report_e["nodes"]);
    let f_coarse = cli_json("singularities", &[&f, "--nodes", "--precision", "1e-3"]);
    assert_same_singularities(&r_[8]["report"], &f_coarse);
    // The whole report, the singular-curve cover included, is in the reply (fragmented replies
    // reach rclpy with the patched RustDDS).
    assert!(floats(&r_[8]["report"]["singular_curves"]["lower"]).len() > 2 * 500, "the reply carries the curve cover");
    assert!(r_[8]["bytes"].as_u64().expect("bytes") > 64 * 1024, "{}", r_[8]["bytes"]);
    refused(9, "precision must be a number in (0, 1), got 2");
    refused(10, "larger than this node's limit 300000");
    refused(11, "timeout 1000000000 s is out of range");
    // 50 boxes cannot decide robot e at 1e-6: an honest incomplete report with undecided records.
    assert_eq!((r_[12]["ok"].clone(), r_[12]["report"]["complete"].clone()), (json!(true), json!(false)), "{}", r_[12]);
    assert!(r_[12]["report"]["cusps"].as_array().expect("cusps").iter().any(|c| c["certified"] == json!(false)));

    // Classification: a regular configuration lies in a proven region, away from the curves;
    // a cusp is singular.
    assert_eq!((r_[13]["ok"].clone(), r_[13]["inside"].clone(), r_[13]["singular_distance_known"].clone()), (json!(true), json!(true), json!(true)), "{}", r_[13]);
    assert!(r_[13]["component"].as_i64().expect("component") >= 0 && r_[13]["singular_distance"].as_f64().expect("distance") > 0.0, "{}", r_[13]);
    assert_eq!((r_[14]["component"].clone(), r_[14]["singular_distance"].clone()), (json!(-1), json!(0.0)), "{}", r_[14]);
    refused(15, "is not a finite number");
    refused(16, "solve is not available for this mechanism ('orthogonal_3r_e', manipulator_3r)");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: a singularity run requested through rclpy reports progress while it goes, and a
/// Cancel with the run id seen in that progress ends it early. The reply is then an honest
/// incomplete report that names the limit (cancelled), and the node stays up. The robot is one
/// whose node search takes about a second, so the cancel lands while it runs.
#[test]
fn a_singularity_run_shows_progress_and_is_cancelled_from_rclpy() {
    let Some(python) = python() else { return };
    let domain = 47;
    let g = format!("{ROOT}/urdf/orthogonal_3r_near_boundary.urdf");
    let mut node = Node::start(domain, &[&g, "--max-request-boxes", "20000000", "--max-request-timeout", "120"]);
    node.wait_for(&["orthogonal_3r_near_boundary: published singularities"], Duration::from_secs(120));
    let request = json!({"mechanism": "orthogonal_3r_near_boundary", "precision": 1e-4, "nodes": true, "max_boxes": 0, "timeout": 0.0});
    let script = json!([{"cancel_during": call("singularities", "Singularities", request), "progress": "/linkspace/orthogonal_3r_near_boundary/progress"}]);
    let got = services(python, domain, "cancel-3r", serde_json::to_string(&script).expect("json"), Duration::from_secs(120));
    let step = &got["results"][0];
    assert!(step.get("error").is_none(), "{step}\nnode log:\n{}", node.log());
    let progress = &step["progress"];
    assert_eq!((progress["analysis"].as_str(), progress["done"].clone()), (Some("singularities"), json!(false)), "{progress}");
    assert_eq!(step["cancel"]["ok"], json!(true), "{step}");
    assert!(step["cancel"]["message"].as_str().expect("message").contains("will be in the reply"), "{step}");
    let report = &step["reply"]["report"];
    assert_eq!((step["reply"]["ok"].clone(), report["run_id"].clone()), (json!(true), progress["run_id"].clone()), "{step}");
    assert_eq!((report["complete"].clone(), report["limit"].clone()), (json!(false), json!("cancelled")), "{}\nprogress {progress}\ntimes {}\nnode log:\n{}", report["message"], step["seconds"], node.log());
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: service replies far above one UDP datagram (a Solve answered with its ~2 MB box
/// set, a Singularities report with its curve cover) reach real rclpy intact: the reply equals
/// the CLI's result. Before the RustDDS patch (vendor/README.md) every fragmented reply was
/// dropped by Fast DDS and stalled the service for every client. A request whose mechanism
/// name has 65,300 characters gets a short error, and a second rclpy process calling the same
/// service at the same time is answered throughout. Smaller refusals ride along:
/// a joint fixed twice, an IK point at 1e300, and `timeout 0` meaning the node's limit.
#[test]
fn large_replies_reach_rclpy_and_a_long_name_blocks_no_one() {
    let Some(python) = python() else { return };
    let domain = 48;
    let (four_bar, e) = (format!("{ROOT}/urdf/four_bar.urdf"), format!("{ROOT}/urdf/orthogonal_3r_e.urdf"));
    let mut node = Node::start(domain, &[&four_bar, &e, "--max-request-boxes", "1000000"]);
    node.wait_for(&["four_bar: published configuration_space", "orthogonal_3r_e: published singularities"], Duration::from_secs(120));
    let reference = solve_json(&[&four_bar, "--sigma", "1.5e-3"]);
    let long_name = "m".repeat(65_300);
    let free = ["crank_joint", "coupler_joint", "rocker_joint"];
    let script = json!([
        call("solve", "Solve", json!({"mechanism": "four_bar", "settings": settings(1.5e-3, 1_000_000, 0.0), "wait": 30.0})),
        call("classify", "Classify", json!({"mechanism": long_name, "joint_names": free, "joint_values": [0.1, 0.2, 0.3]})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": [long_name.clone()], "joint_values": [0.1]})),
        call("list_mechanisms", "ListMechanisms", json!({})),
        call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["crank_joint", "crank_joint"], "fixed_joint_values": [0.5, 0.7], "settings": settings(1e-3, 1000, 1.0)})),
        call("inverse_kinematics", "InverseKinematics", json!({"mechanism": "orthogonal_3r_e", "point": [1e300, 1e300, 1e300], "sigma": 1e-3})),
        call("singularities", "Singularities", json!({"mechanism": "orthogonal_3r_e"})),
    ]);
    let other = json!([
        {"sleep": 0.5},
        call("list_mechanisms", "ListMechanisms", json!({})),
        {"sleep": 1.0},
        call("list_mechanisms", "ListMechanisms", json!({})),
        {"sleep": 1.0},
        call("list_mechanisms", "ListMechanisms", json!({})),
    ]);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let (path, other_path) = (dir.join(format!("large-{}.json", std::process::id())), dir.join(format!("large-other-{}.json", std::process::id())));
    std::fs::write(&path, serde_json::to_string(&script).expect("json")).expect("script written");
    std::fs::write(&other_path, serde_json::to_string(&other).expect("json")).expect("script written");
    let (got, side) = std::thread::scope(|s| {
        let a = s.spawn(|| py(python, domain, "tests/ros_client.py", &["services", "--script", path.to_str().expect("utf-8")], Duration::from_secs(180)));
        let b = s.spawn(|| py(python, domain, "tests/ros_client.py", &["services", "--script", other_path.to_str().expect("utf-8"), "--timeout", "30"], Duration::from_secs(180)));
        (a.join().expect("first client"), b.join().expect("second client"))
    });
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(&other_path);
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate().chain(side["results"].as_array().expect("results").iter().enumerate()) {
        assert!(x.get("error").is_none(), "step {k}: {}\nnode log:\n{}", linkspace::edges::ros::bounded(&x.to_string(), 2000), linkspace::edges::ros::bounded(&node.log(), 20_000));
    }
    // A Solve answered with all its boxes (about 2 MB), equal to the CLI's.
    let bytes = r[0]["bytes"].as_u64().expect("bytes");
    eprintln!("Solve reply: {} boxes, {bytes} bytes of CDR, {:.1} ms", r[0]["result"]["box_status"].as_array().map_or(0, |b| b.len()), 1e3 * r[0]["seconds"].as_f64().unwrap_or(0.0));
    assert!(bytes > 1_000_000, "a reply of megabytes: {bytes} bytes");
    assert_eq!((r[0]["ok"].clone(), r[0]["done"].clone()), (json!(true), json!(true)), "{}", r[0]["message"]);
    assert_same_boxes(&r[0]["result"], &reference);
    // timeout 0: no limit of the request's own; the node's --max-request-timeout applies.
    assert_eq!(r[0]["result"]["settings"]["timeout"], json!(300.0));
    // Long names are echoed truncated, in a short reply; the service goes on.
    for k in [1, 2] {
        let m = r[k]["message"].as_str().expect("message");
        assert_eq!(r[k]["ok"], json!(false));
        assert!(m.len() < 600 && m.contains("more characters)"), "step {k}: {} bytes: {}", m.len(), linkspace::edges::ros::bounded(m, 300));
        assert!((r[k]["bytes"].as_u64().expect("bytes") as usize) < 1000);
    }
    assert!(r[1]["message"].as_str().expect("message").starts_with("no mechanism named 'mmmm"));
    assert_eq!(r[3]["mechanisms"].as_array().expect("mechanisms").len(), 2);
    assert_eq!(r[4]["ok"], json!(false));
    assert!(r[4]["message"].as_str().expect("message").contains("joint 'crank_joint' is fixed twice"), "{}", r[4]);
    assert_eq!(r[5]["ok"], json!(false));
    assert!(r[5]["message"].as_str().expect("message").contains("out of range: give coordinates of at most 1e100 m"), "{}", r[5]);
    // The load-time report with its curve cover (1030 boxes for robot e).
    assert!(floats(&r[6]["report"]["singular_curves"]["lower"]).len() >= 2 * 1000, "the reply carries the curve cover");
    // The other client, calling while all of the above went on, was answered every time.
    let answered = side["results"].as_array().expect("results").iter().filter(|x| x.get("mechanisms").is_some()).count();
    assert_eq!(answered, 3, "{side}");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: a service reply of megabytes far beyond a socket buffer (two Solve replies of
/// about 16 MB: the four-bar at sigma 1e-6, 188,000 boxes processed) reaches rclpy whole, every
/// time. RustDDS as published sent such a sample in one burst that overflowed the reader's
/// receive buffer and then repaired the lost fragments at 2 KiB per 10 ms (vendor/README.md):
/// such replies took from 20 s to over a minute. The client waits 60 s per reply; the times are
/// printed (scripts/bench_replies.py measures them against rclpy).
#[test]
fn replies_of_sixteen_megabytes_reach_rclpy_whole() {
    let Some(python) = python() else { return };
    let domain = 56;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let mut node = Node::start(domain, &[&four_bar, "--sigma", "1e-2", "--max-request-boxes", "1000000", "--max-wait", "120"]);
    node.wait_for(&["four_bar: published configuration_space"], Duration::from_secs(120));
    let big = call("solve", "Solve", json!({"mechanism": "four_bar", "settings": settings(1e-6, 188_000, 0.0), "wait": 120.0}));
    let script = json!([
        {"brief": true, "timeout": 180.0, "service": big["service"], "type": big["type"], "request": big["request"]},
        {"brief": true, "timeout": 180.0, "service": big["service"], "type": big["type"], "request": big["request"]},
    ]);
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("sixteen-{}.json", std::process::id()));
    std::fs::write(&path, serde_json::to_string(&script).expect("json")).expect("script written");
    let got = py(python, domain, "tests/ros_client.py", &["services", "--script", path.to_str().expect("utf-8"), "--timeout", "60"], Duration::from_secs(600));
    let _ = std::fs::remove_file(&path);
    for (k, r) in got["results"].as_array().expect("results").iter().enumerate() {
        assert!(r.get("error").is_none(), "reply {k}: {r}\nnode log:\n{}", linkspace::edges::ros::bounded(&node.log(), 20_000));
        assert_eq!(r["ok"], json!(true), "{r}");
        let bytes = r["bytes"].as_u64().expect("bytes");
        eprintln!("reply {k}: {bytes} bytes after {:.2} s (the run included)", r["seconds"].as_f64().unwrap_or(f64::NAN));
        assert!(bytes > 15_000_000, "a reply of 16 MB: {bytes} bytes");
    }
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: the node's reply history is bounded by bytes, not by its 256 samples. With
/// `--max-history-mb 4`, sixteen Solve replies of about 2 MB (33 MB in all, eight times the
/// budget) leave the node's resident memory (VmRSS) within the budget plus 16 MB of the level
/// after the first reply, once the client has gone. Before, every reply stayed until 256 of them
/// were held (25 replies of 2.9 MB: +104 MB, kept after the client left).
#[test]
fn reply_history_is_bounded_by_bytes() {
    let Some(python) = python() else { return };
    let domain = 57;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let budget_mib = 4;
    let mut node = Node::start(domain, &[&four_bar, "--sigma", "1e-2", "--max-request-boxes", "1000000", "--max-history-mb", &budget_mib.to_string()]);
    node.wait_for(&["four_bar: published configuration_space", "four_bar: published singularities"], Duration::from_secs(120));
    let solve = call("solve", "Solve", json!({"mechanism": "four_bar", "settings": settings(1.5e-3, 1_000_000, 0.0), "wait": 30.0}));
    let step = json!({"brief": true, "service": solve["service"], "type": solve["type"], "request": solve["request"]});
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let run = |n: usize, name: &str| -> Vec<u64> {
        let path = dir.join(format!("history-{name}-{}.json", std::process::id()));
        std::fs::write(&path, serde_json::to_string(&vec![step.clone(); n]).expect("json")).expect("script written");
        let got = py(python, domain, "tests/ros_client.py", &["services", "--script", path.to_str().expect("utf-8"), "--timeout", "60"], Duration::from_secs(600));
        let _ = std::fs::remove_file(&path);
        got["results"]
            .as_array()
            .expect("results")
            .iter()
            .map(|r| {
                assert!(r.get("error").is_none() && r["ok"] == json!(true), "{r}\nnode log:\n{}", linkspace::edges::ros::bounded(&node.log(), 20_000));
                r["bytes"].as_u64().expect("bytes")
            })
            .collect()
    };
    // The level after one reply: the solver's and the allocator's working memory included.
    run(1, "first");
    std::thread::sleep(Duration::from_secs(1));
    let before = node.memory_kib("VmRSS:");
    let sizes = run(16, "many");
    let total: u64 = sizes.iter().sum();
    assert!(total > 4 * (budget_mib << 20), "{total} bytes of replies against a budget of {budget_mib} MiB");
    std::thread::sleep(Duration::from_secs(2));
    let after = node.memory_kib("VmRSS:");
    eprintln!("VmRSS {before} KiB after one reply, {after} KiB after {} more ({total} bytes), budget {budget_mib} MiB", sizes.len());
    assert!(after <= before + (budget_mib + 16) * 1024, "VmRSS grew from {before} to {after} KiB over {total} bytes of replies");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: the node's request history is bounded by bytes too. A service's request reader
/// keeps what it received in RustDDS's topic cache, read or not, up to its depth (256) by count.
/// With `--max-history-mb 4`, 64 Classify requests of 1 MB (a mechanism name of a million
/// characters, refused with a short reply) leave the node's resident memory (VmRSS) within the
/// budget plus 16 MB of the level after the first one. Before the reader's byte bound every
/// request stayed (320 such requests: 190 MB).
#[test]
fn request_history_is_bounded_by_bytes() {
    let Some(python) = python() else { return };
    let domain = 67;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let budget_mib: u64 = 4;
    let mut node = Node::start(domain, &[&four_bar, "--sigma", "1e-2", "--max-history-mb", &budget_mib.to_string()]);
    node.wait_for(&["four_bar: published configuration_space", "four_bar: published singularities"], Duration::from_secs(120));
    let name = "m".repeat(1 << 20);
    let classify = call("classify", "Classify", json!({"mechanism": name, "joint_names": ["crank_joint"], "joint_values": [0.1]}));
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let run = |n: usize, tag: &str| -> usize {
        let mut step = classify.clone();
        step["repeat"] = json!(n);
        let path = dir.join(format!("requests-{tag}-{}.json", std::process::id()));
        std::fs::write(&path, serde_json::to_string(&[step]).expect("json")).expect("script written");
        let got = py(python, domain, "tests/ros_client.py", &["services", "--script", path.to_str().expect("utf-8"), "--timeout", "60"], Duration::from_secs(600));
        let _ = std::fs::remove_file(&path);
        let results = got["results"].as_array().expect("results");
        for r in results {
            let refused = r["ok"] == json!(false) && r["message"].as_str().is_some_and(|m| m.starts_with("no mechanism named 'mmmm"));
            assert!(r.get("error").is_none() && refused, "{}\nnode log:\n{}", linkspace::edges::ros::bounded(&r.to_string(), 2000), linkspace::edges::ros::bounded(&node.log(), 20_000));
        }
        results.len()
    };
    // The level after one request: the allocator's and DDS's working memory included.
    run(1, "first");
    std::thread::sleep(Duration::from_secs(1));
    let before = node.memory_kib("VmRSS:");
    let n = run(64, "many");
    assert_eq!(n, 64);
    std::thread::sleep(Duration::from_secs(2));
    let after = node.memory_kib("VmRSS:");
    eprintln!("VmRSS {before} KiB after one request, {after} KiB after {n} more of 1 MiB, budget {budget_mib} MiB");
    assert!(after <= before + (budget_mib + 16) * 1024, "VmRSS grew from {before} to {after} KiB over {n} requests of 1 MiB");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Benchmark, not a test (ignored): `cargo test --release --test integration
/// topics::reply_delivery_benchmark -- --ignored --nocapture` runs scripts/bench_replies.py on
/// this build: delivery times of Solve replies of 1, 4, 16 and 32 MB, ten tries each, from the
/// node and from an rclpy server sending the same replies (the baseline). About half an hour.
/// LINKSPACE_BENCH_SIZES and LINKSPACE_BENCH_TRIES change the sizes (MB, comma separated) and
/// the tries.
#[test]
#[ignore]
fn reply_delivery_benchmark() {
    let Some(python) = python() else { return };
    let sizes = std::env::var("LINKSPACE_BENCH_SIZES").unwrap_or_else(|_| "1,4,16,32".into());
    let tries = std::env::var("LINKSPACE_BENCH_TRIES").unwrap_or_else(|_| "10".into());
    let mut cmd = Command::new(python);
    cmd.arg(format!("{ROOT}/scripts/bench_replies.py")).args(["--linkspace", env!("CARGO_BIN_EXE_linkspace"), "--sizes", &sizes, "--tries", &tries, "--domain", "58"]);
    let (ok, out, err) = run_with_timeout(cmd, Duration::from_secs(7200));
    assert!(ok, "bench_replies.py failed:\n{out}\n{err}");
    println!("{out}");
}

/// Test idea: memory stays bounded when a writer has no matched reader. The node republishes a
/// box set of about 2 MB (the four-bar's free curve at sigma 1e-3, 14,336 boxes) every 50 ms with
/// nobody subscribed; unpatched RustDDS kept every sample of such a TransientLocal writer and
/// grew by tens of MB/s. Resident memory (VmRSS from /proc) is sampled every second: what is
/// retained is the floor of a window (its minimum). Samples in flight are live memory too: on a
/// loaded machine (the rest of the suite running beside the node) a few of them (2 MB each) stay
/// queued for seconds at a time, so the floor of the last ten seconds may stand above the first
/// window's by up to 10% plus four samples (8 MiB) over 15 s more (LINKSPACE_RSS_SECONDS=60 for a
/// full minute), and the peak is bounded separately, at 1.5 times the first window's peak.
/// Unbounded retention grows by more than that every second and fails both by far. No Python
/// needed.
#[test]
fn memory_stays_flat_when_nobody_subscribes() {
    if std::env::var("LINKSPACE_SKIP_ROS").is_ok_and(|v| v == "1") {
        eprintln!("LINKSPACE_SKIP_ROS=1: SKIPPED");
        return;
    }
    let domain = 49;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let mut node = Node::start(domain, &[&four_bar, "--republish", "0.05"]);
    // Both load-time runs (configuration space and singular sets) finished: their one-time
    // allocations are not growth.
    node.wait_for(&["four_bar: published configuration_space", "four_bar: published singularities"], Duration::from_secs(120));
    let mut sample = |seconds: u64| -> Vec<u64> {
        (0..seconds)
            .map(|_| {
                std::thread::sleep(Duration::from_secs(1));
                assert!(node.alive(), "the node died:\n{}", node.log());
                node.memory_kib("VmRSS")
            })
            .collect()
    };
    let first = sample(5);
    let seconds: u64 = std::env::var("LINKSPACE_RSS_SECONDS").ok().and_then(|v| v.parse().ok()).unwrap_or(15);
    let rest = sample(seconds);
    let floor_peak = |w: &[u64]| (*w.iter().min().expect("samples"), *w.iter().max().expect("samples"));
    let (start_floor, start_peak) = floor_peak(&first);
    let (end_floor, _) = floor_peak(&rest[rest.len().saturating_sub(10)..]);
    let (_, rest_peak) = floor_peak(&rest);
    eprintln!("--republish 0.05, no subscriber, 5+{seconds} s: VmRSS floor {start_floor} -> {end_floor} KiB, peak {start_peak} -> {rest_peak} KiB ({first:?} {rest:?})");
    const IN_FLIGHT_KIB: f64 = 4.0 * 2048.0;
    assert!(end_floor as f64 <= 1.10 * start_floor as f64 + IN_FLIGHT_KIB, "retained memory grew from {start_floor} KiB to {end_floor} KiB in {seconds} s: {first:?} {rest:?}");
    assert!(rest_peak as f64 <= 1.5 * start_peak as f64, "peak memory grew from {start_peak} KiB to {rest_peak} KiB in {seconds} s: {first:?} {rest:?}");
}

/// Test idea: the node starts the way `ros2 run` and launch files start nodes, and takes its URDF
/// the ROS way. Started with `--ros-args -r __ns:=/lab -p sigma:=1e-2 --params-file FILE` and
/// `--robot-description-topic` but no URDF, it analyses the URDF rclpy publishes latched on
/// /robot_description (as robot_state_publisher does) with those settings, under /lab. Its
/// parameters read back through the ROS parameter service; bad values are refused with a
/// reason; setting `robot_description` to another URDF from rclpy replaces the mechanism and its
/// new analysis is published. The node's log lines reach /rosout.
#[test]
fn started_the_ros_way_it_takes_its_urdf_from_a_topic_and_a_parameter() {
    let Some(python) = python() else { return };
    let domain = 50;
    let (four_bar, slider) = (format!("{ROOT}/urdf/four_bar.urdf"), format!("{ROOT}/urdf/slider_crank.urdf"));
    let params = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("params-{}.yaml", std::process::id()));
    std::fs::write(&params, "/lab/linkspace:\n  ros__parameters:\n    max_runs: 3\n    precision: 0.001\n").expect("params file");
    let mut node = Node::start(domain, &["--robot-description-topic", "--ros-args", "-r", "__ns:=/lab", "-p", "sigma:=1e-2", "--params-file", params.to_str().expect("utf-8")]);
    node.wait_for(&["ready: node /lab/linkspace"], Duration::from_secs(60));
    let got = py(
        python,
        domain,
        "tests/ros_client.py",
        &["rosstart", "--node", "/lab/linkspace", "--urdf", &four_bar, "--mechanism", "four_bar", "--urdf2", &slider, "--mechanism2", "slider_crank", "--timeout", "60"],
        Duration::from_secs(180),
    );
    let _ = std::fs::remove_file(&params);
    assert!(got.get("error").is_none(), "{got}\nnode log:\n{}", node.log());
    assert_eq!(got["first"], json!(true), "{got}\nnode log:\n{}", node.log());
    assert_eq!(got["first_set"]["mechanism"], "four_bar");
    assert_eq!(got["first_set"]["settings"]["sigma"], json!(1e-2), "-p sigma:=1e-2");
    assert_eq!(got["first_set"]["header"]["frame_id"], "four_bar/joint_space");
    let reference = solve_json(&[&four_bar, "--sigma", "1e-2"]);
    assert_eq!(got["first_set"]["boxes"].as_u64(), Some(reference["solutions"].as_array().expect("solutions").len() as u64 + reference["undecided"].as_array().expect("undecided").len() as u64));
    // Parameters: -p, the file, and the URDF taken from the topic.
    let get = got["get"].as_array().expect("get");
    assert_eq!((get[0]["double_value"].clone(), get[1]["integer_value"].clone(), get[2]["double_value"].clone()), (json!(1e-2), json!(3), json!(1e-3)), "{got}");
    assert_eq!(get[3]["string_value"].as_str(), Some(std::fs::read_to_string(&four_bar).expect("fixture").as_str()));
    let bad = got["bad"].as_array().expect("bad");
    assert!(bad.iter().all(|r| r["successful"] == json!(false)), "{bad:?}");
    assert!(bad[0]["reason"].as_str().expect("reason").contains("sigma must be a positive finite double"), "{bad:?}");
    assert!(bad[1]["reason"].as_str().expect("reason").starts_with("robot_description: "), "{bad:?}");
    assert!(bad[2]["reason"].as_str().expect("reason").contains("ghost"), "{bad:?}");
    assert_eq!(got["good"][0]["successful"], json!(true), "{got}");
    assert_eq!(got["second"], json!(true), "the new robot_description was not analysed:\n{}", node.log());
    assert_eq!(got["second_set"]["mechanism"], "slider_crank");
    let rosout: Vec<&str> = got["rosout"].as_array().expect("rosout").iter().map(|m| m.as_str().expect("str")).collect();
    assert!(rosout.iter().any(|m| m.contains("new robot_description from topic")), "{rosout:?}");
    assert!(rosout.iter().any(|m| m.contains("slider_crank: new robot_description from parameter")), "{rosout:?}");
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: the Solve action from rclpy's ActionClient, as ROS users run long work. A goal is
/// accepted, reports its progress as feedback, and ends SUCCEEDED with a box set equal to the
/// CLI's JSON; a long goal cancelled after its first feedback ends CANCELED with its incomplete
/// result (limit "cancelled"); a goal the Solve service would refuse ends ABORTED with the
/// reason in its result.
#[test]
fn the_solve_action_gives_feedback_honours_cancel_and_returns_the_cli_boxes() {
    let Some(python) = python() else { return };
    let domain = 51;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let mut node = Node::start(domain, &[&four_bar, "--max-request-boxes", "1000000"]);
    node.wait_for(&["four_bar: published configuration_space"], Duration::from_secs(120));
    let reference = solve_json(&[&four_bar, "--sigma", "1.5e-3"]);
    let script = json!([
        {"goal": {"mechanism": "four_bar", "settings": settings(1.5e-3, 1_000_000, 0.0)}},
        {"goal": {"mechanism": "four_bar", "settings": settings(1e-7, 1_000_000, 120.0)}, "cancel": true},
        {"goal": {"mechanism": "ghost", "settings": settings(1e-3, 1000, 1.0)}},
    ]);
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("action-{}.json", std::process::id()));
    std::fs::write(&path, serde_json::to_string(&script).expect("json")).expect("script written");
    let got = py(python, domain, "tests/ros_client.py", &["action", "--script", path.to_str().expect("utf-8"), "--timeout", "120"], Duration::from_secs(300));
    let _ = std::fs::remove_file(&path);
    assert!(got.get("error").is_none(), "{got}");
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "goal {k}: {}\nnode log:\n{}", linkspace::edges::ros::bounded(&x.to_string(), 2000), node.log());
        assert_eq!(x["accepted"], json!(true), "goal {k}");
    }
    // action_msgs/GoalStatus: 4 SUCCEEDED, 5 CANCELED, 6 ABORTED.
    assert_eq!(r[0]["status"], json!(4), "{}", r[0]["result"]["message"]);
    assert_eq!(r[0]["result"]["ok"], json!(true));
    assert_same_boxes(&r[0]["result"]["result"], &reference);
    assert!(r[0]["feedback_count"].as_u64().expect("count") >= 1, "no feedback");
    assert_eq!((r[0]["first_feedback"]["analysis"].as_str(), r[0]["first_feedback"]["run_id"].clone()), (Some("solve"), r[0]["result"]["run_id"].clone()));
    assert_eq!(r[1]["cancel_return_code"], json!(0), "the cancel was accepted: {}", r[1]);
    assert_eq!(r[1]["status"], json!(5), "{}", r[1]["result"]["message"]);
    let cancelled = &r[1]["result"]["result"];
    assert_eq!((cancelled["status"].clone(), cancelled["limit"].clone()), (json!(1), json!("cancelled")));
    assert_eq!(r[2]["status"], json!(6));
    assert_eq!(r[2]["result"]["ok"], json!(false));
    assert!(r[2]["result"]["message"].as_str().expect("message").contains("no mechanism named 'ghost'"), "{}", r[2]);
    assert!(node.alive(), "the node died:\n{}", node.log());
}


/// Test idea: the regression-test helper users asked for (python/linkspace_testing, installed
/// with pip into the ROS venv) works as documented: its own suite passes (curves compared by
/// enclosure across sigmas against the closed-form four-bar curve, another mechanism and a
/// missing branch caught, certified roots by containment, `box_set` under `--log-level warn`);
/// its example test starts the node through the pytest fixture, waits for the four-bar's box set
/// and finds it matches the stored golden set by containment; the same example fails, naming the
/// roots, against a golden set with one certified box moved by 0.05.
#[test]
fn the_regression_test_helper_passes_its_suite_and_example_and_catches_a_perturbed_golden_set() {
    let Some(python) = python() else { return };
    let domain = 52;
    let package = format!("{ROOT}/python/linkspace_testing");
    let mut pip = Command::new(python);
    pip.args(["-m", "pip", "install", "-q", "--disable-pip-version-check", &package]);
    let (ok, _, err) = run_with_timeout(pip, Duration::from_secs(300));
    assert!(ok, "pip install python/linkspace_testing failed:\n{err}");
    let pytest = |dir: &str, golden_dir: Option<&str>| {
        let mut cmd = Command::new(python);
        cmd.args(["-m", "pytest", "-q", "-p", "no:cacheprovider", &format!("{package}/{dir}")]).env("LINKSPACE_BIN", env!("CARGO_BIN_EXE_linkspace"));
        ros_env(&mut cmd, domain);
        if let Some(d) = golden_dir {
            cmd.env("LINKSPACE_GOLDEN_DIR", d);
        }
        run_with_timeout(cmd, Duration::from_secs(300))
    };
    let (ok, out, err) = pytest("tests", None);
    let summary = out.lines().rev().find(|l| l.contains(" passed")).unwrap_or_default();
    assert!(ok && summary.contains("6 passed") && !summary.contains("skipped"), "the plugin's suite should pass:\n{out}\n{err}");
    let (ok, out, err) = pytest("examples", None);
    assert!(ok && out.contains("1 passed"), "the example should pass:\n{out}\n{err}");

    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("golden-perturbed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let name = "four_bar_crank_0.5.json";
    let mut golden: Value = serde_json::from_str(&std::fs::read_to_string(format!("{package}/examples/golden/{name}")).expect("golden")).expect("json");
    for key in ["lower", "upper"] {
        let x = golden[key][0].as_f64().expect("bound");
        golden[key][0] = json!(x + 0.05);
    }
    std::fs::write(dir.join(name), serde_json::to_string(&golden).expect("json")).expect("perturbed golden");
    let (ok, out, err) = pytest("examples", Some(dir.to_str().expect("utf-8")));
    let _ = std::fs::remove_dir_all(&dir);
    assert!(!ok && out.contains("1 failed") && out.contains("lie in no box"), "the example should fail against the perturbed set:\n{out}\n{err}");
}

/// Test idea: a closed-loop mechanism's singular sets travel on `~/<robot>/singularities` as
/// `linkspace loop-singularities --json` computes them for the same URDF and settings (same
/// kinds, boxes bit for bit, same certificates and counts), with their markers; and `classify`
/// answers a lower bound on the distance to them that the CLI's boxes confirm. The four-bar's
/// rocker is actuated through a `<transmission>` (the default both front ends read), so the
/// input set is its four dead centres.
#[test]
fn a_linkage_publishes_its_singular_sets_as_the_cli_finds_them() {
    let Some(python) = python() else { return };
    let domain = 53;
    let xml = std::fs::read_to_string(format!("{ROOT}/urdf/four_bar.urdf")).expect("fixture").replace(
        "</robot>",
        "<transmission name=\"drive\"><type>transmission_interface/SimpleTransmission</type><joint name=\"rocker_joint\"/></transmission></robot>",
    );
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("four_bar_rocker_driven-{}.urdf", std::process::id()));
    std::fs::write(&path, &xml).expect("written");
    let file = path.to_str().expect("utf-8");
    let mut node = Node::start(domain, &[file, "--sigma", "1e-2", "--precision", "1e-6"]);
    node.wait_for(&["four_bar: published singularities", "four_bar: published configuration_space"], Duration::from_secs(120));
    let got = py(python, domain, "tests/ros_client.py", &["singular", "--prefix", "/linkspace/four_bar"], Duration::from_secs(90));
    let cli = cli_json("loop-singularities", &[file, "--sigma", "1e-6"]);
    let report = &got["/linkspace/four_bar"]["singularities"];
    assert_eq!((report["ok"].clone(), report["complete"].clone()), (json!(true), json!(true)), "{}", report["message"]);
    assert_eq!((report["actuated"].clone(), report["set_kinds"].clone()), (json!(["rocker_joint"]), json!(["cspace", "input", "output"])));
    assert!(report["actuated_source"].as_str().expect("source").contains("<transmission>"), "{}", report["actuated_source"]);
    let cli_sets = cli.as_array().expect("one report per set");
    let sets = report["sets"].as_array().expect("sets");
    assert_eq!(sets.len(), cli_sets.len());
    let mut input_points = Vec::new();
    for (k, (set, c)) in sets.iter().zip(cli_sets).enumerate() {
        let kind = c["kind"].as_str().expect("kind");
        assert_eq!(report["set_kinds"][k], json!(kind));
        assert_eq!(set["analysis"], json!(format!("singular_set:{kind}")));
        assert_eq!((set["status"].clone(), c["status"].clone()), (json!(0), json!("complete")), "{kind}");
        assert_eq!(report["set_proven"][k], c["summary"]["certified_clusters"], "{kind}");
        assert_eq!(report["set_undecided"][k], c["summary"]["undecided_boxes"], "{kind}");
        assert_eq!(set["clusters"], c["summary"]["clusters"], "{kind}");
        // The same boxes, in the same order, with the same joint enclosures and certificates.
        let names: Vec<&str> = set["joint_names"].as_array().expect("names").iter().map(|v| v.as_str().expect("str")).collect();
        let (lo, hi) = (floats(&set["joint_lower"]), floats(&set["joint_upper"]));
        let boxes = c["boxes"].as_array().expect("boxes");
        assert_eq!(lo.len(), names.len() * boxes.len(), "{kind}: box count");
        for (i, b) in boxes.iter().enumerate() {
            let want = by_name(&b["joints"], &names);
            let have: Vec<[f64; 2]> = (0..names.len()).map(|j| [lo[i * names.len() + j], hi[i * names.len() + j]]).collect();
            assert_eq!(have, want, "{kind} box {i}");
            let status = match b["status"].as_str().expect("status") {
                "unique" => 2,
                "solution" => 0,
                _ => 1,
            };
            assert_eq!(set["box_status"][i], json!(status), "{kind} box {i}");
            if kind == "input" {
                input_points.push(want);
            }
        }
    }
    // The rocker-driven four-bar: no bifurcation, four certified dead centres, no type-I set.
    assert_eq!(report["set_proven"], json!([0, 4, 0]));
    assert!(report["set_verdicts"][0].as_str().expect("verdict").starts_with("none (proven"), "{}", report["set_verdicts"]);
    // One marker per box of the input set, after the configuration-space markers of the same
    // latched array.
    let markers = got["/linkspace/four_bar"]["markers"].as_array().expect("markers");
    assert_eq!(markers.iter().filter(|m| m["ns"] == "singular_set:input").count(), input_points.len());
    assert!(markers.iter().any(|m| m["ns"] == "configuration_space"), "the configuration-space markers stay");
    assert_eq!(markers.iter().filter(|m| m["action"] == json!(3)).count(), 1, "one DELETEALL");

    // Classify at a configuration near a dead centre and at the dead centre itself: the bound is
    // at most the distance to the nearest CLI box's middle (a singular configuration lies there,
    // within half a box width).
    let names = ["crank_joint", "coupler_joint", "rocker_joint", "loop_coupler_rocker"];
    let middle: Vec<f64> = input_points[0].iter().map(|b| 0.5 * (b[0] + b[1])).collect();
    let near: Vec<f64> = middle.iter().enumerate().map(|(i, v)| if i == 0 { v + 0.05 } else { *v }).collect();
    let script = json!([
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": names, "joint_values": middle})),
        call("classify", "Classify", json!({"mechanism": "four_bar", "joint_names": names, "joint_values": near})),
        call("singularities", "Singularities", json!({"mechanism": "four_bar"})),
    ]);
    let spath = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("linkage-singular-{}.json", std::process::id()));
    std::fs::write(&spath, serde_json::to_string(&script).expect("json")).expect("script written");
    let r = py(python, domain, "tests/ros_client.py", &["services", "--script", spath.to_str().expect("utf-8")], Duration::from_secs(120));
    let _ = std::fs::remove_file(&spath);
    let r = r["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none() && x["ok"] == json!(true), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    assert_eq!(r[0]["singular_distance_known"], json!(true), "{}", r[0]);
    assert!(r[0]["singular_distance"].as_f64().expect("distance") <= 1e-6, "{}", r[0]);
    let bound = r[1]["singular_distance"].as_f64().expect("distance");
    let to_middles = input_points.iter().map(|p| p.iter().zip(&near).map(|(b, x)| (0.5 * (b[0] + b[1]) - x).powi(2)).sum::<f64>().sqrt()).fold(f64::INFINITY, f64::min);
    assert!(bound > 0.0 && bound <= to_middles + 1e-6, "bound {bound} against {to_middles}: {}", r[1]);
    assert!(r[1]["message"].as_str().expect("message").contains("input set"), "{}", r[1]);
    // The service answers with the load-time report.
    assert_eq!(r[2]["report"]["set_proven"], json!([0, 4, 0]));
    let _ = std::fs::remove_file(&path);
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: the package under `ros/linkspace_bringup`, installed with its own CMakeLists.txt
/// (ament_cmake from the venv, the binary under test as `lib/linkspace_bringup/linkspace`), started
/// the way its launch file starts it: robot_description is the output of `xacro` on the package's
/// four-bar xacro file, written to a parameters file as launch_ros writes `parameters=[{...}]`
/// (PyYAML: a multi-line quoted scalar) after the package's own parameters file. ROS's launch
/// tools have no PyPI wheels, so `tests/launch_check.py` builds that command line from the
/// installed launch file's functions and the ament index. The node must load the description and
/// answer a Solve request from rclpy with the CLI's boxes for `urdf/four_bar.urdf`.
#[test]
fn the_launch_package_starts_the_node_with_a_xacro_description_that_answers_rclpy() {
    let Some(python) = python() else { return };
    let domain = 54;
    let venv_bin = std::path::Path::new(python).parent().expect("venv bin").to_path_buf();
    let path = format!("{}:{}", venv_bin.display(), std::env::var("PATH").unwrap_or_default());
    let work = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("launch-{}", std::process::id()));
    let (build, prefix) = (work.join("build"), work.join("install"));
    let venv = venv_bin.parent().expect("venv");
    let cmake = |args: Vec<String>| {
        let mut cmd = Command::new("cmake");
        cmd.args(args).env("PATH", &path);
        let (ok, out, err) = run_with_timeout(cmd, Duration::from_secs(120));
        assert!(ok, "cmake failed:\n{out}\n{err}");
    };
    cmake(vec![
        "-S".into(),
        format!("{ROOT}/ros/linkspace_bringup"),
        "-B".into(),
        build.display().to_string(),
        format!("-DCMAKE_PREFIX_PATH={}", venv.display()),
        format!("-DCMAKE_INSTALL_PREFIX={}", prefix.display()),
        format!("-DLINKSPACE_BIN={}", env!("CARGO_BIN_EXE_linkspace")),
    ]);
    cmake(vec!["--build".into(), build.display().to_string()]);
    cmake(vec!["--install".into(), build.display().to_string()]);

    let mut cmd = Command::new(python);
    cmd.arg(format!("{ROOT}/tests/launch_check.py")).env("AMENT_PREFIX_PATH", &prefix).env("PATH", &path);
    let (ok, out, err) = run_with_timeout(cmd, Duration::from_secs(60));
    assert!(ok, "launch_check.py failed:\n{out}\n{err}");
    let launch: Value = serde_json::from_str(out.lines().last().expect("a JSON line")).expect("JSON");
    let argv: Vec<String> = launch["argv"].as_array().expect("argv").iter().map(|a| a.as_str().expect("str").to_string()).collect();
    assert_eq!(argv[0], prefix.join("lib/linkspace_bringup/linkspace").display().to_string());
    let written = std::fs::read_to_string(launch["params_files"][1].as_str().expect("path")).expect("launch params file");
    assert!(written.lines().count() > 10, "robot_description should span many lines, as PyYAML dumps it:\n{written}");
    let description = launch["robot_description"].as_str().expect("xacro output");
    assert!(description.contains("<robot name=\"four_bar\">") && !description.contains("xacro:"), "{description}");

    let mut cmd = Command::new(&argv[0]);
    cmd.args(&argv[1..]);
    ros_env(&mut cmd, domain);
    let mut node = Node::spawn(cmd);
    node.wait_for(&["ready: node /linkspace on domain 54", "four_bar: published configuration_space"], Duration::from_secs(90));
    let _ = std::fs::remove_file(launch["params_files"][1].as_str().expect("path"));

    let script = json!([call("solve", "Solve", json!({"mechanism": "four_bar", "fixed_joint_names": ["crank_joint"], "fixed_joint_values": [0.5], "settings": settings(1e-3, 100000, 60.0), "wait": 30.0}))]);
    let file = work.join("script.json");
    std::fs::write(&file, script.to_string()).expect("script written");
    let got = py(python, domain, "tests/ros_client.py", &["services", "--script", file.to_str().expect("utf-8")], Duration::from_secs(120));
    let _ = std::fs::remove_dir_all(&work);
    let reply = &got["results"][0];
    assert!(reply.get("error").is_none() && reply["ok"] == json!(true), "{reply}\nnode log:\n{}", node.log());
    let reference = solve_json(&[&format!("{ROOT}/urdf/four_bar.urdf"), "--fix", "crank_joint=0.5", "--sigma", "1e-3"]);
    assert_same_boxes(&reply["result"], &reference);
    assert!(node.alive(), "the node died:\n{}", node.log());
}

/// Test idea: two nodes of one name on a domain answer each other's clients, so the one that
/// joins says so in one line (as `ros2 node list` would show the name twice), while a node of
/// another name says nothing; `--log-level warn` keeps that warning and drops the INFO lines
/// (ready, published results).
#[test]
fn a_node_warns_once_when_its_name_is_taken_on_the_domain_and_log_level_warn_hides_info() {
    let domain = 55;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let slider = format!("{ROOT}/urdf/slider_crank.urdf");
    let mut first = Node::start(domain, &[&four_bar]);
    first.wait_for(&["ready: node /linkspace"], Duration::from_secs(60));
    let mut other = Node::start(domain, &[&slider, "--node-name", "other"]);
    let mut second = Node::start(domain, &[&slider, "--ros-args", "--log-level", "warn"]);
    let warning = "another node named /linkspace is also on domain 55";
    second.wait_for(&[warning], Duration::from_secs(60));
    first.wait_for(&[warning], Duration::from_secs(30));
    other.wait_for(&["slider_crank: published configuration_space"], Duration::from_secs(60));
    let log = second.log();
    let lines: Vec<&str> = log.lines().collect();
    assert_eq!(lines.len(), 1, "one warning line and nothing at INFO under --log-level warn:\n{log}");
    assert!(lines[0].contains("give this one another name"), "{log}");
    assert!(!other.log().contains("another node named"), "a node of another name was warned:\n{}", other.log());
    assert_eq!(first.log().matches(warning).count(), 1, "once per other participant:\n{}", first.log());
}

/// Test idea: a configuration space bigger than `--max-set-megabytes` travels merged, and the
/// merged set still encloses every box the CLI finds, each in a box of its own cluster; the set
/// says how many boxes it merged and the node says so in its log. Before the cap, the same run
/// published every box whatever its size.
#[test]
fn a_set_above_the_size_cap_travels_merged_and_still_encloses_every_box() {
    let Some(python) = python() else { return };
    let domain = 61;
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    let reference = solve_json(&[&four_bar, "--sigma", "2e-3"]);
    let found = reference["solutions"].as_array().expect("solutions").len();
    assert!(found > 3_000, "{found} boxes");
    let mut node = Node::start(domain, &[&four_bar, "--sigma", "2e-3", "--max-set-megabytes", "0.05"]);
    node.wait_for(&["four_bar: published configuration_space", "merged into"], Duration::from_secs(120));
    let got = py(python, domain, "tests/ros_client.py", &["topics", "--prefix", "/linkspace/four_bar"], Duration::from_secs(90));
    let set = &got["configuration_space"];
    assert_eq!(set["merged_from"], json!(found), "{}", set["merged_from"]);
    let dim = set["dim"].as_u64().expect("dim") as usize;
    let (lower, upper) = (floats(&set["lower"]), floats(&set["upper"]));
    let sent = lower.len() / dim;
    let per_box = 16 * (dim + set["joint_names"].as_array().expect("names").len()) + 9;
    assert!(sent * per_box <= 50_000 + 4 * per_box, "{sent} boxes of {per_box} bytes sent under a 0.05 MB cap");
    let clusters: Vec<i64> = set["cluster"].as_array().expect("clusters").iter().map(|c| c.as_i64().expect("int")).collect();
    assert_eq!(set["clusters"], reference["clusters"]);
    for (i, s) in reference["solutions"].as_array().expect("solutions").iter().enumerate() {
        let b: Vec<[f64; 2]> = s["box"].as_array().expect("box").iter().map(|x| [x[0].as_f64().expect("lo"), x[1].as_f64().expect("hi")]).collect();
        let held = (0..sent).any(|k| clusters[k] >= 0 && (0..dim).all(|d| lower[k * dim + d] <= b[d][0] && b[d][1] <= upper[k * dim + d]));
        assert!(held, "solution box {i} lies in no merged solution box");
    }
    assert!(node.alive());
}

/// The 6R services on UR5 and the CRX fixture, against the CLI: inverse_kinematics6 of a pose
/// given as a geometry_msgs/Pose (the boxes of `ik6` with the same quaternion), path_check of a
/// JointTrajectory whose joints come in another order (the verdicts and crossing of
/// `path-check`), one clear line for a missing joint or a zero quaternion, and the whole-arm
/// cuspidality verdict on the singularity topic (that of `singularities --json`).
#[test]
fn six_joint_arms_answer_inverse_kinematics6_and_path_check() {
    let Some(python) = python() else { return };
    let domain = 62;
    let (ur5, crx) = (format!("{ROOT}/urdf/ur5.urdf"), format!("{ROOT}/tests/data/fanuc_crx10ial_style.urdf"));
    let mut node = Node::start(domain, &[&ur5, &crx]);
    node.wait_for(&["ur5: published singularities", "fanuc_crx10ial: published singularities"], Duration::from_secs(180));

    let (position, quaternion) = ([0.3, 0.2, 0.4], [0.5, 0.5, 0.5, 0.5]);
    let pose_arg = format!("{},{},{},{},{},{},{}", position[0], position[1], position[2], quaternion[0], quaternion[1], quaternion[2], quaternion[3]);
    let ik_ref = cli_json("ik6", &[&ur5, "--pose", &pose_arg, "--precision", "1e-9"]);
    let joints = ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"];
    let (a, b) = ([0.3, -1.0, 1.2, -0.5, -0.4, 0.7], [0.5, -1.2, 1.4, -0.3, 0.6, 0.2]);
    let waypoints = format!("{};{}", a.map(|x| x.to_string()).join(","), b.map(|x| x.to_string()).join(","));
    let path_ref = cli_json("path-check", &[&ur5, "--waypoints", &waypoints]);
    let crx_ref = cli_json("singularities", &[&crx]);
    // The trajectory lists the joints last to first.
    let reversed: Vec<&str> = joints.iter().rev().copied().collect();
    let point = |q: &[f64; 6]| json!({"positions": q.iter().rev().copied().collect::<Vec<f64>>()});
    let ik6 = |q: [f64; 4]| {
        call("inverse_kinematics6", "InverseKinematics6", json!({"mechanism": "ur5", "pose": {"position": position, "orientation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]}}, "sigma": 1e-9}))
    };
    let ik6_many = |qs: &[[f64; 4]]| {
        let poses: Vec<Value> = qs.iter().map(|q| json!({"position": position, "orientation": {"x": q[0], "y": q[1], "z": q[2], "w": q[3]}})).collect();
        call("inverse_kinematics6", "InverseKinematics6", json!({"mechanism": "ur5", "poses": poses, "sigma": 1e-9}))
    };
    let script = json!([
        ik6(quaternion),
        call("path_check", "PathCheck", json!({"mechanism": "ur5", "trajectory": {"joint_names": reversed, "points": [point(&a), point(&b)]}})),
        call("path_check", "PathCheck", json!({"mechanism": "ur5", "trajectory": {"joint_names": &reversed[1..], "points": [{"positions": vec![0.0; 5]}, {"positions": vec![0.1; 5]}]}})),
        ik6([0.0; 4]),
        {"subscribe": "/linkspace/fanuc_crx10ial/singularities", "type": "SingularityReport"},
        ik6_many(&[quaternion, quaternion.map(|x| 2.0 * x)]),
        ik6_many(&[quaternion, [0.0; 4]]),
    ]);
    let got = services(python, domain, "services-6r", serde_json::to_string(&script).expect("json"), Duration::from_secs(180));
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }

    // Inverse kinematics: the CLI's unique boxes, in its order, over the same joints.
    assert_eq!((r[0]["ok"].clone(), r[0]["complete"].clone()), (json!(true), json!(true)), "{}", r[0]);
    assert_eq!(r[0]["joint_names"], json!(joints));
    let unique = ik_ref["unique"].as_array().expect("unique");
    assert!(!unique.is_empty(), "the pose is reachable: {ik_ref}");
    let boxes = r[0]["solutions"].as_array().expect("solutions");
    assert_eq!(boxes.len(), unique.len());
    // Solved as a run of the node (its own thread), not inside the request handler.
    let ran = format!("(6R inverse kinematics): {} solutions", unique.len());
    assert!(node.log().contains(&ran), "no 6R run logged:\n{}", node.log());
    for (got, want) in boxes.iter().zip(unique) {
        for (k, j) in joints.iter().enumerate() {
            let iv = &got["intervals"][k];
            assert_eq!((iv["lower"].as_f64(), iv["upper"].as_f64()), (want[j][0].as_f64(), want[j][1].as_f64()), "{j}");
        }
    }

    // Path check: the CLI's verdict, reason and crossing.
    let segment = &path_ref["segments"][0];
    assert_eq!(segment["verdict"], json!("crosses"));
    assert_eq!(r[1]["verdicts"], json!(["crosses"]), "{}", r[1]);
    assert_eq!(r[1]["reasons"][0], segment["reason"]);
    assert_eq!(r[1]["crossing_segments"], json!([0]));
    let t = &segment["crossings"][0]["t"];
    assert_eq!((r[1]["crossing_t"][0]["lower"].as_f64(), r[1]["crossing_t"][0]["upper"].as_f64()), (t[0].as_f64(), t[1].as_f64()));
    assert_eq!(r[1]["crossing_joints"].as_array().map(Vec::len), Some(6));
    assert!(r[1]["message"].as_str().expect("headline").contains("1 cross a singularity"), "{}", r[1]);

    // Refusals, one line each.
    assert_eq!(r[2]["ok"], json!(false));
    assert!(r[2]["message"].as_str().expect("message").contains("the trajectory has no joint 'joint_6'"), "{}", r[2]);
    assert_eq!(r[3]["ok"], json!(false));
    assert!(r[3]["message"].as_str().expect("message").contains("the quaternion is zero"), "{}", r[3]);

    // The whole-arm verdict on the topic, as the CLI's.
    let report = &r[4]["received"][0];
    assert_eq!(report["arm_cuspidality"], crx_ref["arm_cuspidality"]["verdict"], "{}", report["arm_cuspidality_reason"]);

    // Many poses in one request: an answer per pose, in order, each the single pose's boxes (the
    // quaternion's scale does not matter); a bad pose is refused by its index.
    assert_eq!((r[5]["ok"].clone(), r[5]["complete"].clone(), r[5]["joint_names"].clone()), (json!(true), json!(true), json!(joints)), "{}", r[5]);
    let results = r[5]["results"].as_array().expect("results");
    assert_eq!(results.len(), 2);
    for one in results {
        assert_eq!((one["ok"].clone(), one["complete"].clone(), one["unique"].clone()), (json!(true), json!(true), r[0]["unique"].clone()), "{one}");
        assert_eq!(one["solutions"], r[0]["solutions"]);
    }
    assert_eq!(r[6]["ok"], json!(false));
    assert!(r[6]["message"].as_str().expect("message").contains("inverse_kinematics6: poses[1]: bad pose: the quaternion is zero"), "{}", r[6]);
}

/// path_check on a 3R arm checks its positioning structure's det Df (the default for an arm
/// without six revolute joints), as `path-check` does: verdict, reason, crossing, set and
/// subject; asking for the 6R set or an unknown one is refused in one line.
#[test]
fn three_joint_arms_answer_path_check_against_det_df() {
    let Some(python) = python() else { return };
    let domain = 63;
    let b = format!("{ROOT}/urdf/orthogonal_3r_b.urdf");
    let mut node = Node::start(domain, &[&b]);
    node.wait_for(&["orthogonal_3r_b: published singularities"], Duration::from_secs(180));
    let (from, to) = ([0.1, 0.2, 0.3], [0.2, 0.4, 0.6]);
    let waypoints = format!("{};{}", from.map(|x| x.to_string()).join(","), to.map(|x| x.to_string()).join(","));
    let want = cli_json("path-check", &[&b, "--waypoints", &waypoints]);
    let trajectory = json!({"joint_names": ["joint1", "joint2", "joint3"], "points": [{"positions": from}, {"positions": to}]});
    let script = json!([
        call("path_check", "PathCheck", json!({"mechanism": "orthogonal_3r_b", "trajectory": trajectory})),
        call("path_check", "PathCheck", json!({"mechanism": "orthogonal_3r_b", "trajectory": trajectory, "singular_set": "6r"})),
        call("path_check", "PathCheck", json!({"mechanism": "orthogonal_3r_b", "trajectory": trajectory, "singular_set": "4r"})),
    ]);
    let got = services(python, domain, "services-3r-path", serde_json::to_string(&script).expect("json"), Duration::from_secs(180));
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    let segment = &want["segments"][0];
    assert_eq!((want["singular_set"].clone(), segment["verdict"].clone()), (json!("3r"), json!("crosses")), "{want}");
    assert_eq!((r[0]["ok"].clone(), r[0]["singular_set"].clone(), r[0]["subject"].clone()), (json!(true), json!("3r"), want["subject"].clone()), "{}", r[0]);
    assert_eq!(r[0]["verdicts"], json!(["crosses"]));
    assert_eq!(r[0]["reasons"][0], segment["reason"]);
    let t = &segment["crossings"][0]["t"];
    assert_eq!((r[0]["crossing_t"][0]["lower"].as_f64(), r[0]["crossing_t"][0]["upper"].as_f64()), (t[0].as_f64(), t[1].as_f64()));
    assert_eq!(r[0]["crossing_joints"].as_array().map(Vec::len), Some(3));
    assert_eq!(r[1]["ok"], json!(false));
    assert!(r[1]["message"].as_str().expect("message").contains("is not an arm with six revolute joints"), "{}", r[1]);
    assert_eq!(r[2]["ok"], json!(false));
    assert!(r[2]["message"].as_str().expect("message").contains("singular_set must be \"6r\", \"3r\" or empty"), "{}", r[2]);
}

/// Sends `signal` (a `kill` name: INT, TERM) to `child` and waits at most `timeout` for it to
/// end; its exit status, or `None` if it did not end.
fn signal_and_wait(child: &mut Child, signal: &str, timeout: Duration) -> Option<std::process::ExitStatus> {
    let sent = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().expect("kill runs");
    assert!(sent.success(), "kill -{signal}");
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        if let Some(status) = child.try_wait().expect("wait") {
            return Some(status);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    None
}

/// Test idea: SIGINT (Ctrl-C under `ros2 launch`) and SIGTERM stop the node cleanly, exit
/// status 0, saying so; and a node whose stderr pipe has closed (its launcher gone) keeps
/// running and still stops cleanly. Before, either signal killed the node (status -2 or -15,
/// "process has died" in launch) and a log line to a closed stderr ended it with status 101.
#[test]
fn sigint_and_sigterm_stop_the_node_cleanly_even_with_its_stderr_closed() {
    let four_bar = format!("{ROOT}/urdf/four_bar.urdf");
    for (domain, signal) in [(64, "INT"), (65, "TERM")] {
        let mut node = Node::start(domain, &[&four_bar]);
        node.wait_for(&["four_bar: published configuration_space"], Duration::from_secs(60));
        let status = signal_and_wait(&mut node.child, signal, Duration::from_secs(20)).unwrap_or_else(|| panic!("SIG{signal} did not stop the node:\n{}", node.log()));
        assert_eq!(status.code(), Some(0), "SIG{signal}: {status:?}\n{}", node.log());
        std::thread::sleep(Duration::from_millis(100));
        assert!(node.log().contains("stopping"), "SIG{signal}: the node says it stops:\n{}", node.log());
    }
    // Its stderr read up to the ready line, then closed.
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_linkspace"));
    cmd.arg("serve").args(["--domain", "66", "--network", "loopback", &four_bar]);
    let mut child = cmd.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("starts");
    let mut stderr = child.stderr.take().expect("piped");
    let mut seen = String::new();
    let mut buf = [0u8; 4096];
    while !seen.contains("published configuration_space") {
        let n = stderr.read(&mut buf).expect("reads");
        assert!(n > 0, "the node ended:\n{seen}");
        seen.push_str(&String::from_utf8_lossy(&buf[..n]));
    }
    drop(stderr);
    std::thread::sleep(Duration::from_millis(500));
    assert!(child.try_wait().expect("wait").is_none(), "the node ended when its stderr closed");
    let status = signal_and_wait(&mut child, "TERM", Duration::from_secs(20));
    if status.is_none() {
        let _ = child.kill();
    }
    assert_eq!(status.and_then(|s| s.code()), Some(0), "a node with its stderr closed stops cleanly: {status:?}");
}

/// The collision set over rclpy: the boxes `linkspace collisions` finds, listed for an arm
/// with collision bodies only, and refusals in one line.
#[test]
fn an_arm_with_collision_bodies_answers_collisions_as_the_cli() {
    let Some(python) = python() else { return };
    let domain = 44;
    let (column, bare) = (format!("{ROOT}/urdf/orthogonal_3r_a_column.urdf"), format!("{ROOT}/urdf/orthogonal_3r_a.urdf"));
    let mut node = Node::start(domain, &[&column, &bare]);
    node.wait_for(&["orthogonal_3r_a_column: published singularities", "orthogonal_3r_a: published singularities"], Duration::from_secs(120));
    let reference = cli_json("collisions", &[&column, "--precision", "0.05"]);
    let ask = |mechanism: &str, precision: f64, max_boxes: u64| call("collisions", "Collisions", json!({"mechanism": mechanism, "precision": precision, "max_boxes": max_boxes}));
    let script = json!([
        call("list_mechanisms", "ListMechanisms", json!({})),
        ask("orthogonal_3r_a_column", 0.05, 0),
        ask("orthogonal_3r_a", 0.05, 0),
        ask("orthogonal_3r_a_column", 2.0, 0),
        ask("orthogonal_3r_a_column", 0.05, 20),
    ]);
    let got = services(python, domain, "services-collisions", serde_json::to_string(&script).expect("json"), Duration::from_secs(120));
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    let list = r[0]["mechanisms"].as_array().expect("mechanisms");
    let services = |name: &str| list.iter().find(|m| m["name"] == name).map(|m| m["services"].clone()).expect("listed");
    assert_eq!(services("orthogonal_3r_a_column"), json!(["singularities", "inverse_kinematics", "classify", "path_check", "collisions"]));
    assert_eq!(services("orthogonal_3r_a"), json!(["singularities", "inverse_kinematics", "classify", "path_check"]));

    // The CLI's boxes, each kind as a set (the order of a parallel search is not fixed).
    let reply = &r[1];
    assert_eq!(reply["ok"], json!(true), "{reply}");
    assert_eq!(reply["joint_names"], json!(["joint2", "joint3"]));
    let as_set = |boxes: &Value| -> BTreeSet<String> { boxes.as_array().expect("boxes").iter().map(|b| format!("{:?}", intervals(&b["intervals"]))).collect() };
    let cli_set = |kind: &str| -> BTreeSet<String> {
        reference[kind].as_array().expect("records").iter().map(|b| format!("{:?}", vec![bounds(&b["joints"]["joint2"]), bounds(&b["joints"]["joint3"])])).collect()
    };
    for kind in ["colliding", "free", "undecided"] {
        assert_eq!(as_set(&reply[kind]), cli_set(kind), "{kind} boxes");
    }
    // Each colliding box names the pair the CLI proves there.
    let names = reply["body_names"].as_array().expect("bodies");
    let pair = |k: usize| {
        let p = reply["colliding_pairs"][k].as_u64().expect("pair") as usize;
        let name = |side: &str| names[reply[side][p].as_u64().expect("index") as usize].clone();
        json!([name("pair_first"), name("pair_second")])
    };
    let cli_pairs: BTreeSet<String> = reference["colliding"].as_array().expect("records").iter().map(|c| format!("{:?} {}", vec![bounds(&c["joints"]["joint2"]), bounds(&c["joints"]["joint3"])], c["pair"])).collect();
    let node_pairs: BTreeSet<String> = (0..reply["colliding"].as_array().expect("boxes").len()).map(|k| format!("{:?} {}", intervals(&reply["colliding"][k]["intervals"]), pair(k))).collect();
    assert_eq!(node_pairs, cli_pairs);
    assert_eq!(reply["complete"], json!(false), "boundary boxes stay undecided at 0.05");
    assert!(reply["message"].as_str().expect("message").contains("incomplete (undecided)"), "{reply}");
    // Refusals: no bodies (with why), a precision outside (0, 1); a box limit ends it
    // incomplete, naming the limit.
    assert_eq!(r[2]["ok"], json!(false));
    assert!(r[2]["message"].as_str().expect("message").contains("no collision geometry"), "{}", r[2]);
    assert_eq!(r[3]["ok"], json!(false));
    assert!(r[3]["message"].as_str().expect("message").contains("precision must be a number in (0, 1)"), "{}", r[3]);
    assert_eq!((r[4]["ok"].clone(), r[4]["complete"].clone()), (json!(true), json!(false)), "{}", r[4]);
    assert!(r[4]["message"].as_str().expect("message").contains("boxes limit"), "{}", r[4]);
}

/// A seven-joint arm is listed with its self-motion sets and answers them as the CLI does.
#[test]
fn a_seven_joint_arm_answers_self_motion_as_the_cli() {
    let Some(python) = python() else { return };
    let domain = 58;
    let iiwa = format!("{ROOT}/urdf/iiwa14.urdf");
    // No load-time run to wait for: the client waits for the service.
    let node = Node::start(domain, &[&iiwa]);
    // The pose of (0.3, 0.5, 0.2, -1.2, 0.4, 0.8, -0.3), as a quaternion both sides read alike.
    let m = [
        [-0.7046693449477761, -0.596490311367875, 0.38424005873298434, 0.5916102118239036],
        [-0.30927920399833303, 0.7456041523856864, 0.5902718203670058, 0.31993425847528145],
        [-0.6385824052266311, 0.2971089974899393, -0.7098864383445381, 0.5911640897600512],
    ];
    let r = nalgebra::Rotation3::from_matrix(&nalgebra::Matrix3::from_fn(|i, j| m[i][j]));
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(&r);
    let pose = [m[0][3], m[1][3], m[2][3], q.i, q.j, q.k, q.w];
    let text: Vec<String> = pose.iter().map(|x| format!("{x:?}")).collect();
    let reference = cli_json("self-motion", &[&iiwa, "--pose", &text.join(","), "--range", "0.1,0.3"]);
    let ask = |orientation: [f64; 4]| {
        let request = json!({"mechanism": "iiwa14", "pose": {"position": [pose[0], pose[1], pose[2]], "orientation": {"x": orientation[0], "y": orientation[1], "z": orientation[2], "w": orientation[3]}}, "range_lower": 0.1, "range_upper": 0.3});
        call("self_motion", "SelfMotion", request)
    };
    let script = json!([call("list_mechanisms", "ListMechanisms", json!({})), ask([pose[3], pose[4], pose[5], pose[6]]), ask([0.0; 4])]);
    let got = services(python, domain, "services-7r", serde_json::to_string(&script).expect("json"), Duration::from_secs(120));
    let r = got["results"].as_array().expect("results");
    for (k, x) in r.iter().enumerate() {
        assert!(x.get("error").is_none(), "step {k}: {x}\nnode log:\n{}", node.log());
    }
    let listed = &r[0]["mechanisms"][0];
    assert_eq!((listed["kind"].clone(), listed["services"].clone()), (json!("manipulator_7r"), json!(["self_motion"])), "{listed}");
    let reply = &r[1];
    assert_eq!((reply["ok"].clone(), reply["parameter"].clone()), (json!(true), json!("joint_3")), "{reply}");
    let joints: Vec<String> = reference["joints"].as_array().expect("joints").iter().map(|n| n.as_str().expect("name").to_string()).collect();
    assert_eq!(reply["joint_names"], json!(joints));
    let tag = |status: &Value| match status.as_u64() {
        Some(2) => "unique",
        Some(0) => "solution",
        _ => "undecided",
    };
    let node_boxes: BTreeSet<String> = reply["boxes"].as_array().expect("boxes").iter().map(|b| format!("{:?} {}", intervals(&b["intervals"]), tag(&b["status"]))).collect();
    let cli_boxes: BTreeSet<String> = reference["boxes"].as_array().expect("boxes").iter().map(|b| format!("{:?} {}", joints.iter().map(|n| bounds(&b["joints"][n])).collect::<Vec<_>>(), b["tag"].as_str().expect("tag"))).collect();
    assert!(!cli_boxes.is_empty());
    assert_eq!(node_boxes, cli_boxes, "the node's boxes are the CLI's");
    assert_eq!(reply["certified"].as_u64(), reference["certified"].as_u64());
    assert_eq!(r[2]["ok"], json!(false));
    assert!(r[2]["message"].as_str().expect("message").contains("the quaternion is zero"), "{}", r[2]);
}

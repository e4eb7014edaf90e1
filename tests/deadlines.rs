//! Test idea: every command stopped by `--timeout` ends, says `incomplete` with the time limit
//! named, and still encloses everything sought (every box it did not finish is reported
//! undecided, none dropped), whatever phase the deadline fell in: the search, the spurious-box
//! check, the read-outs of joint values, the settling of distance boxes, the walk for internal-
//! motion strips, an input motion's steps. The references are closed forms and known
//! configurations, computed here without the solver. No clock is asserted on: a watchdog kills a
//! run that does not end in a minute, which fails the test instead of hanging it.

use std::f64::consts::PI;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const LINKSPACE: &str = env!("CARGO_BIN_EXE_linkspace");

/// How long a run with `--timeout 1` may take before the test calls it hung.
const WATCHDOG: Duration = Duration::from_secs(60);

fn repo(path: &str) -> String {
    format!("{}/{path}", env!("CARGO_MANIFEST_DIR"))
}

/// A file under the temporary directory, removed when dropped.
struct Temp(std::path::PathBuf);

impl Temp {
    fn new(name: &str) -> Temp {
        Temp(std::env::temp_dir().join(format!("linkspace-deadline-{}-{name}", std::process::id())))
    }
    fn with(name: &str, text: &str) -> Temp {
        let t = Temp::new(name);
        std::fs::write(&t.0, text).expect("temp file");
        t
    }
    fn path(&self) -> &str {
        self.0.to_str().expect("utf-8 temp path")
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0).or_else(|_| std::fs::remove_dir_all(&self.0));
    }
}

/// Runs the binary; panics (after killing it) if it has not ended within `WATCHDOG`. Output goes
/// to files, so a long report cannot fill a pipe and stall the run.
fn run(args: &[&str]) -> String {
    let (out, err) = (Temp::new(&format!("out-{}", args.join("_").len())), Temp::new(&format!("err-{}", args.len())));
    let mut child = Command::new(LINKSPACE)
        .args(args)
        .stdout(Stdio::from(std::fs::File::create(&out.0).expect("stdout file")))
        .stderr(Stdio::from(std::fs::File::create(&err.0).expect("stderr file")))
        .spawn()
        .expect("binary runs");
    let t0 = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if t0.elapsed() > WATCHDOG {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} did not end within {WATCHDOG:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (out, err) = (std::fs::read_to_string(&out.0).unwrap_or_default(), std::fs::read_to_string(&err.0).unwrap_or_default());
    assert!(status.success(), "{args:?}: {err}");
    out
}

/// `run` with `--json` into a temporary file, the report parsed.
fn run_json(name: &str, args: &[&str]) -> (String, serde_json::Value) {
    let json = Temp::new(&format!("{name}.json"));
    let mut all = args.to_vec();
    all.extend(["--json", json.path()]);
    let out = run(&all);
    let report = serde_json::from_str(&std::fs::read_to_string(&json.0).expect("report written")).expect("json");
    (out, report)
}

fn assert_stopped_on_time(what: &str, report: &serde_json::Value) {
    assert_eq!((report["status"].as_str(), report["limit"].as_str()), (Some("incomplete"), Some("time")), "{what}: {}", &report.to_string()[..report.to_string().len().min(400)]);
}

/// A box as `[lo, hi]` pairs.
fn intervals(b: &serde_json::Value) -> Vec<[f64; 2]> {
    b.as_array().expect("a box").iter().map(|x| [x[0].as_f64().unwrap_or(f64::NAN), x[1].as_f64().unwrap_or(f64::NAN)]).collect()
}

fn inside(b: &[[f64; 2]], x: &[f64], slack: f64) -> bool {
    b.iter().zip(x).all(|(d, &v)| d[0] - slack <= v && v <= d[1] + slack)
}

/// The bundled four-bar (ground 4, crank 1.5, coupler 4, rocker 3.5) at crank angle `t2`: the
/// world angles of crank, coupler and rocker on each of the two assemblies, by the two circles'
/// intersection.
fn four_bar(t2: f64) -> Vec<[f64; 3]> {
    let (a, b, c, d) = (1.5, 4.0, 3.5, 4.0);
    let p = [a * t2.cos(), a * t2.sin()];
    let (dx, dy) = (d - p[0], -p[1]);
    let n = dx.hypot(dy);
    let along = (b * b - c * c + n * n) / (2.0 * n);
    let across = (b * b - along * along).sqrt();
    [1.0, -1.0]
        .iter()
        .map(|s| {
            let q = [p[0] + along * dx / n - s * across * dy / n, p[1] + along * dy / n + s * across * dx / n];
            [t2, (q[1] - p[1]).atan2(q[0] - p[0]), q[1].atan2(q[0] - d)]
        })
        .collect()
}

/// The solve report's boxes, solution and undecided, in its variables.
fn solve_boxes(report: &serde_json::Value) -> Vec<Vec<[f64; 2]>> {
    ["solutions", "undecided"].iter().flat_map(|k| report[k].as_array().expect("boxes").iter().map(|b| intervals(&b["box"]))).collect()
}

/// A curve at sigma 1e-12 (26,000 solution boxes in 3 s, whose read-outs took 1.2 s past the
/// deadline): stopped by the time limit, with every assembly of a grid of crank angles inside a
/// reported box, and every box either read out or marked unread.
#[test]
fn a_curve_at_a_fine_precision_stops_on_time_and_keeps_every_configuration() {
    let (out, report) = run_json("curve", &["solve", &repo("urdf/four_bar.urdf"), "--precision", "1e-12", "--timeout", "1"]);
    assert_stopped_on_time("four-bar", &report);
    assert!(out.contains("status incomplete (time limit"), "{out}");
    let boxes = solve_boxes(&report);
    for k in 0..200 {
        let t2 = -PI + 2.0 * PI * (k as f64 + 0.5) / 200.0;
        for [c, k3, r] in four_bar(t2) {
            let x = [c.cos(), c.sin(), k3.cos(), k3.sin(), r.cos(), r.sin()];
            assert!(boxes.iter().any(|b| inside(b, &x, 1e-9)), "crank {t2}: {x:?} in no box");
        }
    }
    // A box is read out (finite joints) or left unread by the deadline (null): never half.
    for b in report["solutions"].as_array().expect("boxes") {
        let joints: Vec<bool> = b["joints"].as_object().expect("joints").values().map(|j| j[0].is_null()).collect();
        assert!(joints.iter().all(|&u| u) || joints.iter().all(|&u| !u), "{b}");
    }
}

/// 200 four-bars on one ground (600 angles; 400 boxes of 1,200 variables read out 1.4 s past
/// the deadline): stopped on time, the configuration with every crank at 0.5 (upper assembly)
/// inside a reported box.
#[test]
fn two_hundred_loops_stop_on_time_and_keep_a_known_configuration() {
    let mut urdf = String::from("<robot name='many_four_bars'><link name='ground'/>");
    for i in 0..200 {
        let y = 10 * i;
        urdf += &format!(
            "<link name='crank{i}'/><link name='coupler{i}'/><link name='rocker{i}'/>\
             <joint name='crank_joint{i}' type='continuous'><parent link='ground'/><child link='crank{i}'/><origin xyz='0 {y} 0'/><axis xyz='0 0 1'/></joint>\
             <joint name='coupler_joint{i}' type='continuous'><parent link='crank{i}'/><child link='coupler{i}'/><origin xyz='1.5 0 0'/><axis xyz='0 0 1'/></joint>\
             <joint name='rocker_joint{i}' type='continuous'><parent link='ground'/><child link='rocker{i}'/><origin xyz='4 {y} 0'/><axis xyz='0 0 1'/></joint>\
             <loop name='loop{i}' type='revolute'><predecessor link='coupler{i}'><origin xyz='4 0 0'/></predecessor><successor link='rocker{i}'><origin xyz='3.5 0 0'/></successor><axis xyz='0 0 1'/></loop>"
        );
    }
    urdf += "</robot>";
    let file = Temp::with("many.urdf", &urdf);
    let (_, report) = run_json("many", &["solve", file.path(), "--timeout", "1"]);
    assert_stopped_on_time("200 four-bars", &report);
    let [c, k, r] = four_bar(0.5)[0];
    let value = |name: &str| -> f64 {
        let link = name.trim_start_matches("cos_").trim_start_matches("sin_").trim_end_matches(|ch: char| ch.is_ascii_digit());
        let angle = match link {
            "crank" => c,
            "coupler" => k,
            "rocker" => r,
            other => panic!("unexpected variable {other}"),
        };
        if name.starts_with("cos_") {
            angle.cos()
        } else {
            angle.sin()
        }
    };
    let x: Vec<f64> = report["variables"].as_array().expect("variables").iter().map(|v| value(v["name"].as_str().expect("name"))).collect();
    let boxes = solve_boxes(&report);
    assert!(!boxes.is_empty());
    assert!(boxes.iter().any(|b| inside(b, &x, 1e-9)), "the configuration at crank 0.5 is in no box");
}

/// A loop closing a chain of 3,000 joints: reading and building it are part of the time.
#[test]
fn a_three_thousand_joint_chain_stops_on_time() {
    let mut urdf = String::from("<robot name='long_chain'><link name='ground'/>");
    let mut parent = String::from("ground");
    for i in 0..3000 {
        let x = if i == 0 { 0.0 } else { 0.01 };
        urdf += &format!("<link name='l{i}'/><joint name='j{i}' type='continuous'><parent link='{parent}'/><child link='l{i}'/><origin xyz='{x} 0 0'/><axis xyz='0 0 1'/></joint>");
        parent = format!("l{i}");
    }
    urdf += &format!("<loop name='close' type='revolute'><predecessor link='{parent}'><origin xyz='0.01 0 0'/></predecessor><successor link='ground'><origin xyz='5 0 0'/></successor><axis xyz='0 0 1'/></loop></robot>");
    let file = Temp::with("chain.urdf", &urdf);
    let (out, report) = run_json("chain", &["solve", file.path(), "--timeout", "1"]);
    assert_stopped_on_time("3,000-joint chain", &report);
    assert!(out.contains("status incomplete (time limit"), "{out}");
    assert!(!solve_boxes(&report).is_empty(), "the unsearched space is reported undecided");
}

/// The octahedral manipulator with equal legs at 1e-9 (whose settling ran 1.4 s past the
/// deadline, each deeper search on a full timeout of its own): stopped on time, both tangency
/// points (r14 = r36 = 3.25 and 6.25, closed form) inside a reported box.
#[test]
fn distance_settling_stops_on_time_and_keeps_the_tangencies() {
    let legs: Vec<String> = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"].iter().map(|l| format!("{l}=4.75")).collect();
    let mut args = vec!["distances".to_string(), repo("urdf/octahedral.urdf"), "--precision".into(), "1e-9".into(), "--timeout".into(), "1".into()];
    for l in &legs {
        args.extend(["--fix".to_string(), l.clone()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (out, report) = run_json("octahedral", &args);
    assert_stopped_on_time("octahedral", &report);
    assert!(out.contains("status incomplete (time limit"), "{out}");
    let boxes: Vec<Vec<[f64; 2]>> = ["solutions", "undecided"].iter().flat_map(|k| report[k].as_array().expect("boxes").iter().map(|b| intervals(&b["box"]))).collect();
    for v in [3.25, 6.25] {
        assert!(boxes.iter().any(|b| inside(b, &[v, v], 1e-9)), "tangency at {v} in no box");
    }
}

/// A one-task sweep whose task is a fine solve: the task's record says incomplete, time.
#[test]
fn a_sweep_task_stops_on_time() {
    let dir = Temp::new("sweep");
    std::fs::create_dir_all(&dir.0).expect("dir");
    std::fs::copy(repo("urdf/four_bar.urdf"), dir.0.join("four_bar.urdf")).expect("copy");
    let spec = dir.0.join("one.json");
    std::fs::write(&spec, r#"{"urdf": "four_bar.urdf", "analysis": "assembly_modes", "parameters": [{"param": "joint.rocker_joint.xyz.0", "label": "d", "values": [4.0]}], "sigma": 1e-12}"#).expect("spec");
    let results = dir.0.join("results");
    run(&["sweep", spec.to_str().expect("utf-8"), "--out", results.to_str().expect("utf-8"), "--timeout", "1"]);
    let lines = std::fs::read_to_string(results.join("results.jsonl")).expect("results");
    let task: serde_json::Value = serde_json::from_str(lines.lines().nth(1).expect("one task")).expect("json");
    assert_eq!((task["status"].as_str(), task["limit"].as_str()), (Some("incomplete"), Some("time")), "{task}");
}

/// The four-bar's crank driven from 0.5 to 5000 (which ran 9.4 s with `--timeout 3`): stopped
/// on time, each proven step's box holding the closed-form configuration at its start.
#[test]
fn a_long_input_motion_stops_on_time_and_its_steps_hold_the_branch() {
    let (out, report) = run_json("motion", &["loop-singularities", &repo("urdf/four_bar.urdf"), "--kind", "motion", "--actuated", "crank_joint", "--from", "0.5", "--to", "5000", "--assembly", "0.5,0.2668,1.5145,0.7477", "--timeout", "1"]);
    assert_stopped_on_time("motion", &report);
    assert_eq!(report["verdict"].as_str(), Some("not_decided"));
    assert!(out.contains("time limit"), "{out}");
    let steps = report["steps"].as_array().expect("steps");
    assert!(!steps.is_empty());
    let wrapped = |x: f64, b: &serde_json::Value| {
        let (lo, hi) = (b[0].as_f64().expect("lo"), b[1].as_f64().expect("hi"));
        let k = ((0.5 * (lo + hi) - x) / (2.0 * PI)).round();
        let x = x + 2.0 * PI * k;
        lo - 1e-9 <= x && x <= hi + 1e-9
    };
    for s in steps.iter().step_by(steps.len() / 50 + 1) {
        let t2 = s["input"][0].as_f64().expect("input");
        // The branch of the assembly given (the upper one: rocker at 1.5145 for crank 0.5).
        let [c, k, r] = four_bar(t2)[0];
        let j = &s["joints"];
        assert!(wrapped(c, &j["crank_joint"]) && wrapped(k - c, &j["coupler_joint"]) && wrapped(r, &j["rocker_joint"]) && wrapped(r - k, &j["loop_coupler_rocker"]), "step at {t2}: {s}");
    }
}

/// An uncertain arm (lengths ± 0.05) at precision 1e-10, whose walk for internal-motion strips
/// split a whole stretch of θ₃ down to the precision (it ran past 60 s): `ik` and
/// `singularities` stop on time.
#[test]
fn the_walk_for_internal_motion_strips_stops_on_time() {
    let f = repo("urdf/orthogonal_3r_f.urdf");
    let (out, report) = run_json("ik-f", &["ik", &f, "--point", "1,0,0.5", "--uncertainty", "0.05", "--precision", "1e-10", "--timeout", "1"]);
    assert_stopped_on_time("ik", &report);
    assert!(out.contains("status incomplete (time limit)"), "{out}");
    // Nothing is claimed unique where the search did not go.
    assert!(report["solutions"].as_array().expect("solutions").iter().all(|s| s["unique"].as_bool() != Some(true)));
    let (out, report) = run_json("sing-f", &["singularities", &f, "--uncertainty", "0.05", "--precision", "1e-10", "--timeout", "1"]);
    assert_stopped_on_time("singularities", &report);
    assert!(out.contains("status incomplete (time limit)"), "{out}");
}

/// A six-revolute arm in the style of a Motoman GP7 at its home pose, where joints 4 and 6 are
/// aligned (joint 5 at 0) and the solutions form a curve: answered completely within its
/// timeout, the home configuration inside the curve's cover; and `ik6` without `--timeout` is
/// bounded too.
#[test]
fn a_wrist_singular_pose_is_answered_within_its_timeout() {
    let joint = |name: &str, parent: &str, child: &str, xyz: &str, axis: &str, lo: f64, hi: f64| {
        format!("<joint name='{name}' type='revolute'><origin xyz='{xyz}' rpy='0 0 0'/><parent link='{parent}'/><child link='{child}'/><axis xyz='{axis}'/><limit lower='{lo}' upper='{hi}' effort='0' velocity='1'/></joint>")
    };
    let links = ["base_link", "link_1_s", "link_2_l", "link_3_u", "link_4_r", "link_5_b", "link_6_t"];
    let mut urdf = String::from("<robot name='gp7_style'>");
    for l in links {
        urdf += &format!("<link name='{l}'/>");
    }
    for (k, (name, xyz, axis, lo, hi)) in [
        ("joint_1_s", "0 0 0.330", "0 0 1", -2.967, 2.967),
        ("joint_2_l", "0.040 0 0", "0 1 0", -1.1344, 2.5307),
        ("joint_3_u", "0 0 0.445", "0 -1 0", -1.2217, 3.3161),
        ("joint_4_r", "0.440 0 0.040", "-1 0 0", -3.3161, 3.3161),
        ("joint_5_b", "0 0 0", "0 -1 0", -2.3562, 2.3562),
        ("joint_6_t", "0.080 0 0", "-1 0 0", -7.9412, 7.9412),
    ]
    .into_iter()
    .enumerate()
    {
        urdf += &joint(name, links[k], links[k + 1], xyz, axis, lo, hi);
    }
    urdf += "</robot>";
    let file = Temp::with("gp7.urdf", &urdf);
    // At home every joint is 0: the tip at x = 0.04 + 0.44 + 0.08, z = 0.33 + 0.445 + 0.04.
    let (out, report) = run_json("ik6", &["ik6", file.path(), "--pose", "0.56,0,0.815,0,0,0", "--timeout", "1"]);
    assert_eq!(report["status"].as_str(), Some("complete"), "{out}");
    assert!(out.contains("wrist singular: joint_4_r, joint_6_t move together"), "{out}");
    let names = ["joint_1_s", "joint_2_l", "joint_3_u", "joint_4_r", "joint_5_b", "joint_6_t"];
    let held = |b: &serde_json::Value| names.iter().all(|n| b[n][0].as_f64().expect("lo") <= 0.0 && 0.0 <= b[n][1].as_f64().expect("hi"));
    let curves = report["curves"].as_array().expect("curves");
    assert!(curves.iter().flat_map(|c| c["cover"].as_array().expect("cover")).any(held), "the home configuration is in no box of a curve: {report}");
    assert!(linkspace::app::Job::default_limits("ik6").timeout.is_some_and(|t| t <= Duration::from_secs(60)), "ik6 is bounded by default");
}

/// The tip frame of the bundled UR5 with joint 6's origin moved 0.01 m along the common normal
/// of axes 5 and 6, so that they no longer meet and no closed form applies, at `q`: each joint
/// origin `(roll, x, z)` followed by a turn about its z axis (the file's DH-style frames).
fn skew_wrist_ur5_pose(q: [f64; 6]) -> Vec<f64> {
    type M = [[f64; 4]; 4];
    let mul = |a: &M, b: &M| -> M { std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum())) };
    let frame = |roll: f64, x: f64, z: f64, yaw: f64| -> M {
        // Rx(roll) · Rz(yaw), translated by (x, 0, z).
        let (cr, sr, cy, sy) = (roll.cos(), roll.sin(), yaw.cos(), yaw.sin());
        [[cy, -sy, 0.0, x], [cr * sy, cr * cy, -sr, 0.0], [sr * sy, sr * cy, cr, z], [0.0, 0.0, 0.0, 1.0]]
    };
    let origins = [(0.0, 0.0, 0.0), (PI / 2.0, 0.0, 0.089159), (0.0, -0.425, 0.0), (0.0, -0.39225, 0.0), (PI / 2.0, 0.0, 0.10915), (-PI / 2.0, 0.01, 0.09465)];
    let mut t = frame(0.0, 0.0, 0.0, 0.0);
    for (&(roll, x, z), &qk) in origins.iter().zip(&q) {
        t = mul(&t, &frame(roll, x, z, qk));
    }
    t = mul(&t, &frame(0.0, 0.0, 0.0823, 0.0));
    t.iter().flatten().copied().collect()
}

/// That arm with joint 5 at 0, where axis 6 is parallel to axes 2, 3 and 4 and the solutions form
/// a curve the search must cover on its own: stopped on time, the configuration inside a
/// reported box, and the work done counted (the pairs of the first traversal with the cells).
#[test]
fn a_singular_pose_only_the_search_answers_stops_on_time() {
    let urdf = std::fs::read_to_string(repo("urdf/ur5.urdf")).expect("ur5");
    let (joint_6, moved) = ("<origin rpy=\"-1.570796327 0 0\" xyz=\"0 0 0.09465\"/>", "<origin rpy=\"-1.570796327 0 0\" xyz=\"0.01 0 0.09465\"/>");
    assert!(urdf.contains(joint_6), "joint 6's origin as the pose below takes it");
    let file = Temp::with("ur5_skew_wrist.urdf", &urdf.replace(joint_6, moved));
    let q = [0.0, -1.0, 1.0, 0.3, 0.0, 0.5];
    let pose = skew_wrist_ur5_pose(q).iter().map(|v| format!("{v:.15}")).collect::<Vec<_>>().join(",");
    let (out, report) = run_json("ik6-skew", &["ik6", file.path(), "--pose", &pose, "--timeout", "1"]);
    assert_stopped_on_time("ik6", &report);
    assert!(out.contains("status incomplete (time limit)"), "{out}");
    let names = ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"];
    let held = |b: &serde_json::Value| names.iter().zip(q).all(|(n, v)| b[n][0].as_f64().expect("lo") <= v && v <= b[n][1].as_f64().expect("hi"));
    let unique = report["unique"].as_array().expect("unique");
    let clusters = report["clusters"].as_array().expect("clusters");
    assert!(unique.iter().chain(clusters).any(held), "the configuration is in no box: {report}");
    assert!(report["processed"].as_u64().expect("processed") > 1000, "{}", report["processed"]);
}

/// The node search of the type-II image names the limit that stopped it, in text and JSON.
#[test]
fn an_image_search_stopped_on_time_names_the_limit() {
    let (out, report) = run_json("nodes", &["loop-singularities", &repo("urdf/five_bar_unequal.urdf"), "--actuated", "crank1_joint,crank2_joint", "--kind", "nodes", "--precision", "1e-2", "--timeout", "1"]);
    assert_stopped_on_time("nodes", &report);
    assert!(out.contains("status incomplete (time limit)"), "{out}");
}

/// `path-check` takes the limits every command takes and honours each: `--max-boxes` counts the
/// pieces its segments are cut into (a path stopped by it says so, segment by segment), and
/// `--threads` decides segments side by side with the verdicts of one thread.
#[test]
fn a_path_check_honours_its_box_limit_and_threads() {
    let ur5 = repo("urdf/ur5.urdf");
    let path = "0,-1,1,0,-0.4,0;0,-1,1,0,0.6,0;0.3,-1.2,1.1,0.2,0.6,0.4;0.3,-1.2,1.1,0.2,-0.5,0.4;0,-1,1,0,-0.4,0";
    let (out, stopped) = run_json("path-boxes", &["path-check", &ur5, "--waypoints", path, "--max-boxes", "3"]);
    assert_eq!((stopped["status"].as_str(), stopped["limit"].as_str()), (Some("incomplete"), Some("boxes")), "{stopped}");
    assert!(out.contains("not decided (stopped on the boxes limit)"), "{out}");
    assert!(stopped["segments"].as_array().expect("segments").iter().all(|s| s["verdict"].as_str() == Some("not_decided")), "{stopped}");
    let segments = |threads: &str| -> Vec<serde_json::Value> {
        let (_, r) = run_json(&format!("path-{threads}"), &["path-check", &ur5, "--waypoints", path, "--threads", threads]);
        assert_eq!(r["status"].as_str(), Some("complete"), "{r}");
        r["segments"].as_array().expect("segments").clone()
    };
    let one = segments("1");
    assert_eq!(one.iter().filter(|s| s["verdict"].as_str() == Some("crosses")).count(), 2, "{one:?}");
    assert_eq!(one, segments("3"));
}

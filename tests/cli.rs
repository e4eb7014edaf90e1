//! Test idea: run the real binary on bad input and check the contract: non-zero exit, one line
//! on stderr that names the problem, never a panic. And the good path writes the documented JSON.

use std::process::Command;

/// The product binary, and the lab binary of benches and charts.
const LINKSPACE: &str = env!("CARGO_BIN_EXE_linkspace");
const LAB: &str = env!("CARGO_BIN_EXE_linkspace-lab");

fn run(args: &[&str]) -> (bool, String, String) {
    run_bin(LINKSPACE, args)
}

fn run_bin(bin: &str, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(bin).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn fixture(name: &str) -> String {
    format!("{}/urdf/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A temporary URDF made from a bundled one with one text replacement.
fn variant(name: &str, from: &str, to: &str) -> tempfile_path::Path {
    let text = std::fs::read_to_string(fixture(name)).expect("fixture");
    assert!(text.contains(from), "{from} not in {name}");
    tempfile_path::Path::write(&text.replacen(from, to, 1))
}

mod tempfile_path {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    pub struct Path(pub std::path::PathBuf);
    impl Path {
        pub fn write(text: &str) -> Path {
            let p = std::env::temp_dir().join(format!("linkspace-test-{}-{}.urdf", std::process::id(), NEXT.fetch_add(1, Ordering::Relaxed)));
            std::fs::write(&p, text).expect("temp file");
            Path(p)
        }
        pub fn as_str(&self) -> &str {
            self.0.to_str().expect("utf-8 temp path")
        }
    }
    impl Drop for Path {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }
}

fn assert_clear_error(args: &[&str], needle: &str) {
    assert_clear_error_of(LINKSPACE, args, needle)
}

fn assert_clear_error_of(bin: &str, args: &[&str], needle: &str) {
    let (ok, _, err) = run_bin(bin, args);
    assert!(!ok, "{args:?} should fail");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one line, got {err}");
    assert!(lines[0].starts_with("error: ") && lines[0].contains(needle), "{args:?}: '{}' should mention '{needle}'", lines[0]);
}

#[test]
fn bad_input_gives_one_clear_line() {
    let fb = fixture("four_bar.urdf");
    let sc = fixture("slider_crank.urdf");
    assert_clear_error(&["solve", "/nonexistent.urdf"], "reading /nonexistent.urdf");
    let broken = tempfile_path::Path::write("<robot name='x'><link name='a'>");
    assert_clear_error(&["solve", broken.as_str()], "malformed URDF");
    assert_clear_error(&["solve", &fb, "--fix", "nope=1"], "no joint or loop named 'nope'");
    assert_clear_error(&["solve", &fb, "--fix", "crank_joint"], "expected JOINT=VALUE");
    // A seven-joint arm asked a six-joint question: refused, saying which joint to hold and how.
    let iiwa = fixture("iiwa14.urdf");
    assert_clear_error(&["ik6", &iiwa, "--pose", "0.4,0.1,0.6,0,3.14159,0"], "hold 1 of them with --fix JOINT=VALUE (e.g. --fix joint_3=0)");
    assert_clear_error(&["ik6", &fixture("ur5.urdf"), "--fix", "joint_9=0", "--pose", "0.4,0.1,0.6,0,3.14159,0"], "--fix: 'joint_9' is not a joint of the file");
    assert_clear_error(&["solve", &fb, "--fix", "crank_joint=NaN"], "not a finite number");
    assert_clear_error(&["solve", &sc, "--fix", "slider_joint=9"], "outside its limits");
    assert_clear_error(&["solve", &fb, "--sigma", "0"], "sigma must be a positive");
    assert_clear_error(&["solve", &fb, "--sigma", "NaN"], "sigma must be a positive");
    assert_clear_error(&["solve", &fb, "--rho", "1.5"], "rho must lie strictly between 0 and 1");
    assert_clear_error(&["solve", &fb, "--trace", "ghost@1,2"], "no link named 'ghost'");
    // A rocker of length 30 can never reach the coupler: the loop cannot close.
    let long = variant("four_bar.urdf", "<successor link=\"rocker\"><origin xyz=\"3.5 0 0\"", "<successor link=\"rocker\"><origin xyz=\"30 0 0\"");
    assert_clear_error(&["solve", long.as_str()], "loop 'loop_coupler_rocker' cannot close");
    // The spherical four-bar's rocker axis 46 nm off the common centre: its chains miss each
    // other, which the error says with the gap (the spatial builder's closure check).
    let gap = variant("spherical_four_bar.urdf", "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0.8414709848078965", "<origin xyz=\"0 0 4.6e-8\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0.8414709848078965");
    assert_clear_error(&["solve", gap.as_str()], "cannot close as written: whatever the joint values, one of its closure rows");
    // The model's freedoms, measured before the run: a 3-dimensional continuum is announced at
    // once on stderr (the run then covers it within its limits); isolated assemblies say so.
    let (_, out, err) = run(&["solve", &fixture("delta.urdf"), "--timeout", "0.5"]);
    assert!(err.contains("delta: 3 degrees of freedom at a configuration Newton found") && err.contains("fix 3 joints"), "{err}");
    assert!(out.contains("  freedom: 3 degrees of freedom"), "{out}");
    let (_, out, _) = run(&["solve", &fb, "--fix", "crank_joint=0.5"]);
    assert!(out.contains("  freedom: 0 degrees of freedom (4 unknowns, 4 rows;"), "{out}");
    // A complete run with no box says what that proves.
    let (ok, out, _) = run(&["solve", &fb, "--fix", "crank_joint=0.5", "--fix", "rocker_joint=0.1"]);
    assert!(ok && out.contains("0 solution boxes") && out.contains("no configuration: every box was proven empty, so no assembly has the fixed values given"), "{out}");
    // A joint turning about x makes the mechanism spatial.
    let tilted = variant("four_bar.urdf", "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>");
    assert_clear_error(&["solve", tilted.as_str(), "--model", "planar"], "not planar");
    // A tree has nothing to close.
    let tree = tempfile_path::Path::write("<robot name='arm'><link name='a'/><link name='b'/><joint name='j' type='continuous'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/></joint></robot>");
    assert_clear_error(&["solve", tree.as_str()], "no <loop> closure");
}

#[test]
fn limits_end_the_run_incomplete_with_every_box_reported() {
    let dir = std::env::temp_dir().join(format!("linkspace-limit-{}.json", std::process::id()));
    let (ok, out, err) = run(&["solve", &fixture("double_butterfly.urdf"), "--max-boxes", "5", "--json", dir.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    assert!(out.contains("incomplete (boxes limit"), "{out}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&dir).expect("json written")).expect("valid json");
    let _ = std::fs::remove_file(&dir);
    assert_eq!(report["status"], "incomplete");
    assert_eq!(report["limit"], "boxes");
    assert!(!report["undecided"].as_array().expect("array").is_empty());
}

#[test]
fn json_report_follows_the_documented_schema() {
    let path = std::env::temp_dir().join(format!("linkspace-schema-{}.json", std::process::id()));
    let (ok, _, err) = run(&["solve", &fixture("four_bar.urdf"), "--fix", "crank_joint=0.5", "--sigma", "1e-5", "--trace", "coupler@2,1", "--json", path.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    assert_eq!(r["mechanism"], "four_bar");
    assert_eq!(r["status"], "complete");
    assert_eq!(r["fixed_joints"]["crank_joint"], 0.5);
    assert_eq!(r["clusters"], 2);
    let s = &r["solutions"][0];
    for key in ["joints", "link_angles", "traces", "box", "level"] {
        assert!(!s[key].is_null(), "solution lacks {key}");
    }
    assert!(s["joints"]["rocker_joint"].is_array());
    assert!(s["link_angles"]["ground"].is_array());
    assert!(s["traces"]["coupler@2,1"]["x"].is_array());
    for key in ["processed", "empty", "bisected", "solutions", "seconds"] {
        assert!(r["stats"][key].is_number(), "stats lacks {key}");
    }
    // Without a time limit the spurious-box check runs to its end, and the report says so.
    assert_eq!(r["stats"]["post_processing_cut_short"], false);
    assert_eq!(r["settings"]["sigma"], 1e-5);
}

#[test]
fn solve_picks_the_model_and_reports_spatial_poses() {
    let path = std::env::temp_dir().join(format!("linkspace-spatial-{}.json", std::process::id()));
    let p = path.to_str().expect("utf-8");
    let (ok, out, err) = run(&["solve", &fixture("four_bar.urdf"), "--fix", "crank_joint=0.5", "--json", p]);
    assert!(ok, "{err}");
    assert!(out.contains("model: planar"), "{out}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    assert_eq!(r["model"], "planar");
    let (ok, out, err) = run(&["solve", &fixture("rssr.urdf"), "--fix", "crank_joint=0.6", "--trace", "rocker@1.5,0,0", "--json", p]);
    assert!(ok, "{err}");
    assert!(out.contains("model: spatial (not planar") && out.contains("rssr: 2 proven, 0 undecided (2 solution boxes in 2 clusters)"), "{out}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    assert_eq!(r["model"], "spatial");
    assert!(r["model_reason"].as_str().expect("text").contains("coupler_ball"));
    let s = &r["solutions"][0];
    assert!(s["joints"]["rocker_joint"].is_array());
    assert_eq!(s["link_poses"]["rocker"]["quaternion"].as_array().expect("w, x, y, z").len(), 4);
    assert!(s["link_poses"]["rocker"]["position"].is_array());
    assert!(s["traces"]["rocker@1.5,0,0"]["z"].is_array());
    assert_clear_error(&["solve", &fixture("rssr.urdf"), "--model", "planar"], "not planar");
    assert_clear_error(&["solve", &fixture("four_bar.urdf"), "--model", "planar", "--trace", "coupler@1,0,2"], "plane z = 0");
}

/// A temporary 3R URDF from a bundled orthogonal robot with one replacement.
fn robot_variant(case: &str, from: &str, to: &str) -> tempfile_path::Path {
    variant(&format!("orthogonal_3r_{case}.urdf"), from, to)
}

#[test]
fn singularities_bad_input_gives_one_clear_line() {
    let e = fixture("orthogonal_3r_e.urdf");
    assert_clear_error(&["singularities", "/nonexistent.urdf"], "reading /nonexistent.urdf");
    assert_clear_error(&["singularities", &e, "--precision", "0"], "precision must be a number in (0, 1)");
    assert_clear_error(&["singularities", &e, "--precision", "NaN"], "precision must be a number in (0, 1)");
    assert_clear_error(&["singularities", &e, "--precision", "-1e-3"], "precision must be a number in (0, 1)");
    assert_clear_error(&["singularities", &e, "--uncertainty", "-1"], "uncertainty must be a finite number >= 0");
    // A planar linkage with loops is not a serial chain.
    assert_clear_error(&["singularities", &fixture("four_bar.urdf")], "not a serial chain");
    // Welding joint 3 leaves two revolute joints.
    let two = robot_variant("e", "<joint name=\"joint3\" type=\"continuous\">", "<joint name=\"joint3\" type=\"fixed\">");
    assert_clear_error(&["singularities", two.as_str()], "not a 3R chain: the chain from 'base' to 'tool' has 2 revolute joints");
    let prismatic = robot_variant("e", "<joint name=\"joint3\" type=\"continuous\">", "<joint name=\"joint3\" type=\"prismatic\"><limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/>");
    assert_clear_error(&["singularities", prismatic.as_str()], "joint 'joint3' is prismatic");
    // All lengths zero: the tip sits on every axis and never moves.
    let still = variant_all("orthogonal_3r_e.urdf", &[("xyz=\"1 0 0\"", "xyz=\"0 0 0\""), ("xyz=\"1.5 0.5 0\"", "xyz=\"0 0 0\""), ("xyz=\"0.7 0 0\"", "xyz=\"0 0 0\"")]);
    assert_clear_error(&["singularities", still.as_str()], "does not move");
    assert_clear_error(&["singularities", still.as_str()], "--tip-point LINK@X,Y,Z");
    // Tip on the third axis: it moves with joint 2 only, det Df = 0 everywhere.
    let on_axis3 = robot_variant("e", "<origin xyz=\"0.7 0 0\" rpy=\"0 0 0\"/>", "<origin xyz=\"0 0 0.3\" rpy=\"0 0 0\"/>");
    assert_clear_error(&["singularities", on_axis3.as_str()], "degenerate");
    assert_clear_error(&["ik", &e, "--point", "1.2"], "expected X,Y,Z (root frame) or R,Z");
    assert_clear_error(&["ik", &e, "--point", "-1,0"], "radius must be >= 0");
    assert_clear_error(&["ik", &e, "--point", "x,0"], "'x' is not a number");
}

/// A variant with several replacements.
fn variant_all(name: &str, edits: &[(&str, &str)]) -> tempfile_path::Path {
    let mut text = std::fs::read_to_string(fixture(name)).expect("fixture");
    for (from, to) in edits {
        assert!(text.contains(from), "{from} not in {name}");
        text = text.replacen(from, to, 1);
    }
    tempfile_path::Path::write(&text)
}

#[test]
#[allow(clippy::approx_constant)] // a loose bound just inside −π, not π
fn singularities_json_follows_the_documented_schema() {
    let path = std::env::temp_dir().join(format!("linkspace-3r-{}.json", std::process::id()));
    let (ok, out, err) = run(&["singularities", &fixture("orthogonal_3r_f.urdf"), "--nodes", "--json", path.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    // The verdict comes first, then the counts.
    assert!(out.starts_with("verdict: NON-CUSPIDAL (certified)"), "{out}");
    assert!(out.lines().nth(1).is_some_and(|l| l.starts_with("orthogonal_3r_f: 0 cusps, 2 nodes, 2 internal-motion lines, 0 undecided, status complete")), "{out}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    assert_eq!(r["robot"], "orthogonal_3r_f");
    assert_eq!(r["status"], "complete");
    assert_eq!(r["verdict"]["cuspidal"], false);
    assert_eq!(r["verdict"]["certified"], true);
    // Robot f: 4 aspects proven by the cover; IK solutions unbounded (internal-motion lines).
    assert!(r["verdict"]["reason"].is_string() && r["verdict"]["aspects"] == 4);
    assert!(r["verdict"]["max_ik_solutions"].is_null(), "{}", r["verdict"]);
    assert_eq!(r["chain"]["joints"][2], "joint3");
    assert_eq!(r["rounding"]["snapping"], true);
    assert_eq!(r["undecided_total"][0], 0);
    assert_eq!(r["joints"][1], "joint2");
    assert_eq!(r["settings"]["precision"], 1e-4);
    assert_eq!(r["cusps"].as_array().expect("array").len(), 0);
    let node = &r["nodes"][0];
    assert!(node["points"][0]["joint2"].is_array() && node["points"][1]["joint3"].is_array());
    assert!(node["workspace"]["radius"].is_array() && node["workspace"]["z"].is_array());
    assert_eq!(node["unique"], true);
    let motion = &r["internal_motions"][0];
    assert!(motion["joints"]["joint2"][0].as_f64().expect("number") < -3.14);
    assert!(motion["strip"].is_array());
    assert!(r["undecided"]["cusps"].as_array().expect("array").is_empty());
    assert!(r["undecided"]["nodes"].as_array().expect("array").is_empty());
    for key in ["processed", "regular", "not_tangent", "krawczyk_empty", "bisected", "in_strips", "seconds"] {
        assert!(r["stats"]["cusps"][key].is_number(), "stats.cusps lacks {key}");
    }
    assert!(r["stats"]["nodes"]["pairs"].is_number());
    // And a cusp record, from robot e.
    let (ok, _, err) = run(&["singularities", &fixture("orthogonal_3r_e.urdf"), "--json", path.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    assert_eq!(r["cusps"].as_array().expect("array").len(), 4);
    assert_eq!(r["verdict"]["cuspidal"], true);
    assert_eq!(r["cusps"][0]["unique"], true);
    assert!(r["cusps"][0]["joints"]["joint3"].is_array() && r["cusps"][0]["workspace"]["radius"].is_array());
    assert!(r["nodes"].is_null());
}

/// `singularities --kind cusps` gives the cusps and internal-motion lines of the full run,
/// without the verdict (no `verdict` in the JSON, no verdict line); `--kind nodes` adds the
/// nodes; `--kind cusps --nodes` is refused in one line.
#[test]
fn singularities_kind_runs_the_searches_without_the_verdict() {
    let path = std::env::temp_dir().join(format!("linkspace-3r-kind-{}.json", std::process::id()));
    let json = |args: &[&str]| -> (String, serde_json::Value) {
        let mut all = vec!["singularities", args[0], "--json", path.to_str().expect("utf-8")];
        all.extend_from_slice(&args[1..]);
        let (ok, out, err) = run(&all);
        assert!(ok, "{err}");
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
        let _ = std::fs::remove_file(&path);
        (out, r)
    };
    for robot in ["orthogonal_3r_e.urdf", "orthogonal_3r_f.urdf"] {
        let f = fixture(robot);
        let (_, full) = json(&[&f]);
        let (out, cusps) = json(&[&f, "--kind", "cusps"]);
        assert!(!out.contains("verdict") && out.starts_with("orthogonal_3r_"), "{out}");
        assert!(cusps.get("verdict").is_none() && full["verdict"].is_object());
        for key in ["cusps", "internal_motions", "undecided_total", "status"] {
            assert_eq!(cusps[key], full[key], "{robot}: {key}");
        }
        assert!(cusps["nodes"].is_null());
        let (_, nodes) = json(&[&f, "--kind", "nodes"]);
        assert!(nodes.get("verdict").is_none() && nodes["nodes"].is_array());
        assert_eq!(nodes["cusps"], full["cusps"]);
    }
    assert_clear_error(&["singularities", &fixture("orthogonal_3r_e.urdf"), "--kind", "cusps", "--nodes"], "--kind cusps searches no nodes");
}

/// `ik6` on the CRX fixture: a reachable pose is solved complete with twelve unique boxes, in
/// the joints' own ranges (joint 3 beyond π); a pose of five numbers is refused in one line.
#[test]
fn ik6_solves_a_pose_of_a_six_joint_arm() {
    let crx = format!("{}/tests/data/fanuc_crx10ial_style.urdf", env!("CARGO_MANIFEST_DIR"));
    assert_clear_error(&["ik6", &crx, "--pose", "1,2,3,4,5"], "5 numbers: expected 6 (x,y,z,roll,pitch,yaw), 7 (x,y,z,qx,qy,qz,qw) or 16");
    let (ok, out, err) = run(&["ik6", &crx, "--pose", "0.5,0.2,0.6,0.3,0.2,0.1"]);
    assert!(ok, "{err}");
    assert!(out.starts_with("base_link -> tool0: 12 solutions proven unique, 0 clusters undecided, status complete"), "{out}");
    assert!(out.contains("joint_1 in [0.729757621, 0.729757621]"), "{out}");
}

/// `ik6 --poses`: every pose of a file answered in the file's order, each line of the JSON
/// Lines report the report `--pose` writes for that pose; a bad line is refused before anything
/// is solved, naming its line.
#[test]
fn ik6_answers_a_file_of_poses_in_order() {
    let crx = format!("{}/tests/data/fanuc_crx10ial_style.urdf", env!("CARGO_MANIFEST_DIR"));
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let poses = ["0.5,0.2,0.6,0.3,0.2,0.1", "0.4,-0.1,0.5,0,1.2,0", "0.5,0.2,0.6,0.28714435005478384,0.21204102212359124,0.06854159710096422,1.9666948865127118"];
    let file = dir.join(format!("ik6-poses-{}.txt", std::process::id()));
    std::fs::write(&file, format!("# x, y, z and a rotation\n{}\n\n{}\n{}\n", poses[0], poses[1], poses[2])).expect("written");
    let jsonl = dir.join(format!("ik6-poses-{}.jsonl", std::process::id()));
    let (ok, out, err) = run(&["ik6", &crx, "--poses", file.to_str().expect("utf-8"), "--json", jsonl.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    let headers: Vec<&str> = out.lines().filter(|l| l.starts_with("pose ")).collect();
    assert_eq!(headers.len(), 3, "{out}");
    assert!(headers[0].starts_with("pose 0 (line 2): base_link -> tool0: 12 solutions proven unique"), "{out}");
    assert!(headers[2].starts_with("pose 2 (line 5): "), "{out}");
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(&jsonl).expect("written").lines().map(|l| serde_json::from_str(l).expect("one JSON object per line")).collect();
    assert_eq!(lines.len(), 3);
    for (k, pose) in poses.iter().enumerate() {
        let one = dir.join(format!("ik6-pose-{k}-{}.json", std::process::id()));
        let (ok, _, err) = run(&["ik6", &crx, "--pose", pose, "--json", one.to_str().expect("utf-8")]);
        assert!(ok, "{err}");
        let alone: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&one).expect("written")).expect("json");
        for key in ["pose", "joints", "unique", "clusters", "status"] {
            assert_eq!(lines[k][key], alone[key], "pose {k}: {key}");
        }
    }
    let bad = dir.join(format!("ik6-poses-bad-{}.txt", std::process::id()));
    std::fs::write(&bad, format!("{}\n1,2,3,4,5\n", poses[0])).expect("written");
    assert_clear_error(&["ik6", &crx, "--poses", bad.to_str().expect("utf-8")], "line 2: '1,2,3,4,5': bad pose: 5 numbers");
    std::fs::write(&bad, "# nothing\n\n").expect("written");
    assert_clear_error(&["ik6", &crx, "--poses", bad.to_str().expect("utf-8")], "no pose in the file");
    assert_clear_error(&["ik6", &crx, "--poses", file.to_str().expect("utf-8"), "--pose", poses[0]], "cannot be used with");
    for f in [file, jsonl, bad] {
        let _ = std::fs::remove_file(f);
    }
}

/// `ik6 --pose` in its three forms: the pose above as a quaternion (scaled by 2, normalised by
/// the solver) and as a 4x4 matrix printed to 9 decimals (computed here from the rpy angles in
/// Python's double precision) gives the same twelve configurations; a non-rigid matrix and a zero
/// quaternion are refused in one line naming the defect.
#[test]
fn ik6_takes_a_quaternion_or_a_matrix() {
    let crx = format!("{}/tests/data/fanuc_crx10ial_style.urdf", env!("CARGO_MANIFEST_DIR"));
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let solve = |pose: &str, name: &str| -> serde_json::Value {
        let path = dir.join(format!("ik6-{name}-{}.json", std::process::id()));
        let (ok, _, err) = run(&["ik6", &crx, "--pose", pose, "--json", path.to_str().expect("utf-8")]);
        assert!(ok, "{err}");
        serde_json::from_str(&std::fs::read_to_string(&path).expect("written")).expect("json")
    };
    let rpy = solve("0.5,0.2,0.6,0.3,0.2,0.1", "rpy");
    let quaternion = solve("0.5,0.2,0.6,0.28714435005478384,0.21204102212359124,0.06854159710096422,1.9666948865127118", "quaternion");
    let matrix = solve(
        "0.975170327,-0.036957014,0.218350663,0.5,0.097843395,0.956425086,-0.275095847,0.2,-0.198669331,0.289629478,0.936293364,0.6,0,0,0,1",
        "matrix",
    );
    assert_eq!(rpy["pose"].as_array().map(Vec::len), Some(6));
    assert_eq!(quaternion["pose"].as_array().map(Vec::len), Some(7));
    assert_eq!(matrix["pose"].as_array().map(Vec::len), Some(16));
    let joints = |r: &serde_json::Value| -> Vec<Vec<f64>> {
        let names: Vec<String> = r["joints"].as_array().expect("joints").iter().map(|n| n.as_str().expect("name").to_string()).collect();
        r["unique"].as_array().expect("unique").iter().map(|b| names.iter().map(|n| b[n][0].as_f64().expect("bound")).collect()).collect()
    };
    let reference = joints(&rpy);
    assert_eq!(reference.len(), 12);
    for (form, other) in [("quaternion", joints(&quaternion)), ("matrix", joints(&matrix))] {
        assert_eq!(other.len(), 12, "{form}");
        // The same configurations (a joint whose range exceeds a turn compared modulo 2π).
        let same = |a: &Vec<f64>, b: &Vec<f64>| a.iter().zip(b).all(|(x, y)| ((x - y) / std::f64::consts::TAU).round().mul_add(-std::f64::consts::TAU, x - y).abs() < 1e-7);
        for a in &reference {
            assert!(other.iter().any(|b| same(a, b)), "{form}: {a:?} not among {other:?}");
        }
    }
    assert_clear_error(&["ik6", &crx, "--pose", "0,0,0,0,0,0,0"], "the quaternion is zero");
    assert_clear_error(&["ik6", &crx, "--pose", "1.1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1"], "not orthonormal: |RᵀR − I| (Frobenius) is 2.100e-1");
    assert_clear_error(&["ik6", &crx, "--pose", "1,0,0,0, 0,1,0,0, 0,0,-1,0, 0,0,0,1"], "a reflection");
}

/// `path-check` on UR5: a crossing of θ5 = 0, a clear segment and a touch at the last waypoint,
/// the same from `--waypoints` and from a JSON `--waypoints-file`; the headline counts them.
#[test]
fn path_check_counts_crossing_touching_and_clear_segments() {
    let ur5 = format!("{}/urdf/ur5.urdf", env!("CARGO_MANIFEST_DIR"));
    let w = [[0.3, -1.0, 1.2, -0.5, -0.4, 0.7], [0.5, -1.2, 1.4, -0.3, 0.6, 0.2], [0.8, -1.3, 1.5, -0.2, 1.0, 0.1], [0.4, -1.1, 1.3, -0.4, 0.0, 0.5]];
    let text: Vec<String> = w.iter().map(|q| q.map(|x| x.to_string()).join(",")).collect();
    let (ok, out, err) = run(&["path-check", &ur5, "--waypoints", &text.join(";")]);
    assert!(ok, "{err}");
    assert!(out.starts_with("world -> tool0 (joint_1, joint_2, joint_3, joint_4, joint_5, joint_6): 3 segments: 1 cross a singularity, 1 touch or undecided, 1 clear"), "{out}");
    let file = tempfile_path::Path::write(&serde_json::to_string(&w).expect("json"));
    let (ok, from_file, err) = run(&["path-check", &ur5, "--waypoints-file", file.as_str()]);
    assert!(ok, "{err}");
    assert_eq!(out, from_file);
    assert_clear_error(&["path-check", &ur5, "--waypoints", "0,0,0,0,0,0"], "1 waypoint(s): a path needs at least two");
    assert_clear_error(&["path-check", &ur5, "--waypoints", "0,0,0,0,0;1,1,1,1,1,1"], "waypoint 1 has 5 joint values: expected 6");
}

/// `path-check --singular-set`: a 3R arm is checked against det Df by default, a six-joint arm
/// against det J unless 3r is asked for (then over its six joints, det Df of its sub-chain);
/// the 6R set of a 3R arm, or a sub-chain option with it, is one clear line.
#[test]
fn path_check_names_the_singular_set() {
    let ur5 = format!("{}/urdf/ur5.urdf", env!("CARGO_MANIFEST_DIR"));
    let (ok, out, err) = run(&["path-check", &fixture("orthogonal_3r_b.urdf"), "--waypoints", "0.1,0.2,0.3;0.2,0.4,0.6"]);
    assert!(ok, "{err}");
    assert!(out.starts_with("3R arm 'orthogonal_3r_b' (joint1, joint2, joint3), point tool@0,0,0: det Df: 1 segments: 1 cross a singularity"), "{out}");
    let (ok, out, err) = run(&["path-check", &ur5, "--singular-set", "3r", "--waypoints", "0.3,-1.0,1.2,-0.5,-0.4,0.7;0.5,-1.2,-1.4,-0.3,0.6,0.2"]);
    assert!(ok, "{err}");
    assert!(out.starts_with("3R sub-chain joints 1-3 (joint_1, joint_2, joint_3) of 'ur5', point link_3@"), "{out}");
    assert!(out.contains("det Df proven to change sign"), "{out}");
    assert_clear_error(&["path-check", &fixture("orthogonal_3r_b.urdf"), "--singular-set", "6r", "--waypoints", "0,0,0,0,0,0;1,1,1,1,1,1"], "not a 6R chain");
    assert_clear_error(&["path-check", &ur5, "--singular-set", "6r", "--fix", "joint_6=0", "--waypoints", "0,0,0,0,0,0;1,1,1,1,1,1"], "they apply with --singular-set 3r");
    assert_clear_error(&["path-check", &fixture("orthogonal_3r_b.urdf"), "--waypoints", "0,0,0,0,0,0;1,1,1,1,1,1"], "waypoint 1 has 6 joint values: expected 3");
}

#[test]
fn ik_reports_every_solution() {
    let (ok, out, err) = run(&["ik", &fixture("orthogonal_3r_e.urdf"), "--point", "1.3,0.2"]);
    assert!(ok, "{err}");
    assert!(out.starts_with("orthogonal_3r_e: 2 solutions proven unique, 0 clusters undecided, status complete"), "{out}");
}

/// Test idea: `ik` takes a point of the root frame as the node does; on the point (r, 0, z) of
/// robot e (first axis along z through the origin) joints 2 and 3 are those of the half-section
/// query (r, z), and joint 1 is enclosed; turning the point by φ about the first axis turns
/// joint 1 by φ and leaves joints 2 and 3.
#[test]
fn ik_takes_a_point_of_the_root_frame() {
    let e = fixture("orthogonal_3r_e.urdf");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let query = |point: &str, name: &str| -> serde_json::Value {
        let path = dir.join(format!("ik-{name}-{}.json", std::process::id()));
        let (ok, _, err) = run(&["ik", &e, "--point", point, "--precision", "1e-8", "--json", path.to_str().expect("utf-8")]);
        assert!(ok, "{err}");
        let v = serde_json::from_str(&std::fs::read_to_string(&path).expect("report")).expect("json");
        let _ = std::fs::remove_file(&path);
        v
    };
    let (r, z, phi) = (1.9f64, 0.4f64, 0.7f64);
    let half = query(&format!("{r},{z}"), "half");
    let root = query(&format!("{r},0,{z}"), "root");
    let turned = query(&format!("{},{},{z}", r * phi.cos(), r * phi.sin()), "turned");
    let solutions = |v: &serde_json::Value| v["solutions"].as_array().expect("solutions").clone();
    let (h, a, t) = (solutions(&half), solutions(&root), solutions(&turned));
    assert!(h.len() >= 2 && h.iter().all(|s| s["unique"] == true), "{half}");
    assert_eq!((a.len(), t.len()), (h.len(), h.len()));
    let mid = |s: &serde_json::Value, j: &str| 0.5 * (s["joints"][j][0].as_f64().expect("lo") + s["joints"][j][1].as_f64().expect("hi"));
    for ((hs, rs), ts) in h.iter().zip(&a).zip(&t) {
        assert!(hs["joints"].get("joint1").is_none(), "joint 1 is free for a half-section point");
        assert_eq!((&rs["joints"]["joint2"], &rs["joints"]["joint3"]), (&hs["joints"]["joint2"], &hs["joints"]["joint3"]));
        let width = rs["joints"]["joint1"][1].as_f64().expect("hi") - rs["joints"]["joint1"][0].as_f64().expect("lo");
        assert!((0.0..1e-6).contains(&width), "joint 1 enclosed: {rs}");
        let turn = mid(ts, "joint1") - mid(rs, "joint1");
        assert!((turn - phi).abs() < 1e-6, "joint 1 turns with the point: {turn}");
        assert!((mid(ts, "joint2") - mid(hs, "joint2")).abs() < 1e-6 && (mid(ts, "joint3") - mid(hs, "joint3")).abs() < 1e-6);
    }
    assert_eq!(root["point"], serde_json::json!([r, 0.0, z]));
}

/// Test idea: with a point of the root frame joint 1 is fixed, so its limits count. On PUMA 560
/// (joint_1 in [-2.7925, 2.7925] in the file) the point (0.4, 0.2, 0.3) has four solutions on
/// the full torus, two of them with joint 1 near -3.02: with the file's limits those two are
/// dropped and said so, and every listed joint 1 lies within its limits.
#[test]
fn ik_of_a_root_frame_point_honours_the_first_joints_limits() {
    let puma = fixture("puma560.urdf");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let query = |extra: &[&str], name: &str| -> serde_json::Value {
        let path = dir.join(format!("ik-puma-{name}-{}.json", std::process::id()));
        let mut args = vec!["ik", &puma, "--point", "0.4,0.2,0.3", "--json", path.to_str().expect("utf-8")];
        args.extend_from_slice(extra);
        let (ok, _, err) = run(&args);
        assert!(ok, "{err}");
        let v = serde_json::from_str(&std::fs::read_to_string(&path).expect("report")).expect("json");
        let _ = std::fs::remove_file(&path);
        v
    };
    let joint1 = |v: &serde_json::Value| -> Vec<[f64; 2]> {
        v["solutions"].as_array().expect("solutions").iter().map(|s| [s["joints"]["joint_1"][0].as_f64().expect("lo"), s["joints"]["joint_1"][1].as_f64().expect("hi")]).collect()
    };
    let free = query(&["--ignore-limits"], "free");
    let limited = query(&[], "limited");
    let (all, kept) = (joint1(&free), joint1(&limited));
    assert_eq!(all.len(), 4, "{free}");
    let outside = all.iter().filter(|j| j[1] < -2.7925 || j[0] > 2.7925).count();
    assert_eq!(outside, 2, "two configurations turn joint 1 past its limit: {all:?}");
    assert_eq!(kept.len(), 2, "{limited}");
    assert!(kept.iter().all(|j| -2.7925 <= j[0] && j[1] <= 2.7925), "{kept:?}");
    assert_eq!(limited["joint_limits"]["dropped"], 2);
}

#[test]
fn collisions_bad_input_and_json_schema() {
    let scene = fixture("orthogonal_3r_a_column.urdf");
    assert_clear_error(&["collisions", &fixture("orthogonal_3r_a.urdf")], "no collision geometry: no link of 'orthogonal_3r_a' has a <collision> cylinder, capsule or sphere");
    assert_clear_error(&["collisions", &scene, "--precision", "0"], "precision must be a number in (0, 1)");
    assert_clear_error(&["collisions", &scene, "--precision", "NaN"], "precision must be a number in (0, 1)");
    assert_clear_error(&["collisions", &fixture("four_bar.urdf")], "not a serial chain");
    let meshed = variant("orthogonal_3r_a_column.urdf", r#"<cylinder radius="0.3" length="3"/>"#, r#"<mesh filename="column.stl"/>"#);
    assert_clear_error(&["collisions", meshed.as_str()], "link 'base': collision mesh is not supported");
    let path = std::env::temp_dir().join(format!("linkspace-collisions-{}.json", std::process::id()));
    let (ok, out, err) = run(&["collisions", &scene, "--precision", "0.05", "--json", path.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    assert!(out.starts_with("orthogonal_3r_a_column: 2 pairs; colliding "), "{out}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("valid json");
    let _ = std::fs::remove_file(&path);
    assert_eq!(r["robot"], "orthogonal_3r_a_column");
    // Boundary boxes neither proven colliding nor free leave the classification open: the
    // one rule says incomplete, and why.
    let undecided = r["undecided"].as_array().expect("undecided boxes").len();
    assert!(undecided > 0, "a precision of 0.05 leaves boundary boxes");
    assert_eq!((r["status"].clone(), r["limit"].clone()), (serde_json::json!("incomplete"), serde_json::json!("undecided")));
    assert_eq!(r["precision"], 0.05);
    assert_eq!(r["bodies"][0]["name"], "column");
    assert_eq!(r["bodies"][0]["link"], "base");
    assert_eq!(r["bodies"][0]["radius"], 0.3);
    assert!(r["bodies"][0]["segment"][1][2].as_f64().expect("number") == 2.0);
    assert_eq!(r["pairs"][1][1], "forearm");
    assert_eq!(r["colliding"][0]["pair"][0], "column");
    assert!(r["colliding"][0]["joints"]["joint2"].is_array() && r["free"][0]["joints"]["joint3"].is_array());
    assert!(r["undecided"][0]["joints"]["joint2"].is_array());
    for key in ["processed", "bisected", "colliding_area", "free_area", "undecided_area", "seconds"] {
        assert!(r["stats"][key].is_number(), "stats lacks {key}");
    }
}

/// A negative number after a flag is a value, not a flag of its own, and bad input gets one
/// line, not clap's several lines of usage: every spelling (`--sigma -1` as `--sigma=-1`), for
/// every subcommand.
#[test]
fn bad_input_gets_one_line_however_it_is_spelled() {
    let fb = fixture("four_bar.urdf");
    let e = fixture("orthogonal_3r_e.urdf");
    let scene = fixture("orthogonal_3r_a_column.urdf");
    let platform = fixture("octahedral.urdf");
    for sigma in [["--sigma", "-1"].as_slice(), ["--sigma=-1"].as_slice(), ["--sigma", "-1e-3"].as_slice()] {
        let mut args = vec!["solve", fb.as_str()];
        args.extend_from_slice(sigma);
        assert_clear_error(&args, "sigma must be a positive");
    }
    assert_clear_error(&["solve", &fb, "--rho", "-0.5"], "rho must lie strictly between 0 and 1");
    assert_clear_error(&["solve", &fb, "--timeout", "-10"], "--timeout must be a positive number of seconds");
    assert_clear_error(&["solve", &fb, "--newton-width", "-1"], "newton");
    // Errors clap itself finds: a count that cannot be negative, an unknown flag, a missing
    // value, a missing file, a bad choice.
    assert_clear_error(&["solve", &fb, "--max-boxes", "-1"], "invalid value '-1' for '--max-boxes");
    assert_clear_error(&["solve", &fb, "--threads", "0"], "--threads");
    assert_clear_error(&["solve", &fb, "--bogus"], "unexpected argument '--bogus'");
    assert_clear_error(&["solve", &fb, "--sigma"], "a value is required for '--precision");
    assert_clear_error(&["solve"], "required arguments were not provided: <URDF>");
    assert_clear_error(&["solve", &fb, "--lp", "gurobi"], "invalid value 'gurobi' for '--lp");
    assert_clear_error(&["nonsense"], "unrecognized subcommand 'nonsense'");
    // The other subcommands.
    assert_clear_error(&["singularities", &e, "--precision", "-0.5"], "precision must be a number in (0, 1)");
    assert_clear_error(&["singularities", &e, "--timeout", "-1"], "--timeout must be a positive number of seconds");
    assert_clear_error(&["singularities", &e, "--max-boxes", "-5"], "invalid value '-5' for '--max-boxes");
    assert_clear_error(&["ik", &e, "--point", "1,0", "--precision", "-1"], "precision must be a number in (0, 1)");
    assert_clear_error(&["ik", &e], "--point");
    assert_clear_error(&["collisions", &scene, "--precision", "-0.1"], "precision must be a number in (0, 1)");
    assert_clear_error(&["collisions", &scene, "--timeout", "-3"], "--timeout must be a positive number of seconds");
    assert_clear_error(&["distances", &platform, "--sigma", "-1"], "sigma must be a positive");
    assert_clear_error(&["distances", &platform, "--timeout", "-1"], "--timeout must be a positive number of seconds");
    // The lab binary's benches and charts keep the same contract.
    assert_clear_error_of(LAB, &["bench", "--repeat", "-1"], "invalid value '-1' for '--repeat");
    assert_clear_error_of(LAB, &["bench3r", "--repeat", "-2"], "invalid value '-2' for '--repeat");
    assert_clear_error_of(LAB, &["bench-distances", "--repeat", "-1"], "invalid value '-1' for '--repeat");
    assert_clear_error_of(LAB, &["bench", "--repeat", "0"], "--repeat must be at least 1");
    assert_clear_error_of(LAB, &["chart"], "required arguments were not provided: <DIR>");
    assert_clear_error_of(LAB, &["chart", "/nonexistent", "--only", "nope"], "unknown chart group 'nope'");
    #[cfg(feature = "ros")]
    assert_clear_error(&["serve", &fb, "--sigma", "-1"], "sigma must be a positive");
}

/// `--help` keeps clap's full text on stdout and succeeds; only errors are flattened.
#[test]
fn help_is_still_the_full_text() {
    for args in [["--help"].as_slice(), ["solve", "--help"].as_slice(), ["distances", "-h"].as_slice()] {
        let (ok, out, err) = run(args);
        assert!(ok, "{args:?}: {err}");
        assert!(out.contains("Usage:") && out.lines().count() > 5, "{args:?}: {out}");
    }
    let (ok, out, _) = run(&["--version"]);
    assert!(ok && out.starts_with("linkspace "), "{out}");
}

/// The benches and charts live in `linkspace-lab`; the product lists none of them.
#[test]
fn the_product_lists_no_bench_or_chart() {
    let (ok, out, err) = run(&["--help"]);
    assert!(ok, "{err}");
    for command in ["chart", "bench", "bench3r", "bench-distances", "bench-loop-singularities", "bench-spatial"] {
        assert!(!out.lines().any(|l| l.trim_start().starts_with(&format!("{command} "))), "linkspace --help lists {command}:\n{out}");
        assert_clear_error(&[command], &format!("unrecognized subcommand '{command}'"));
        let (ok, out, err) = run_bin(LAB, &[command, "--help"]);
        assert!(ok && out.contains("Usage:"), "linkspace-lab {command} --help: {err}");
    }
}

/// `linkspace-lab bench3r --arms`: one row per bundled real arm and robot of Benoit et al. (2019),
/// the shipped path complete with nothing undecided, the baseline reported with its status. Tiny
/// baseline limits keep it to a few seconds; no timing is asserted.
#[test]
fn bench3r_arms_has_a_row_per_robot_and_the_new_path_completes() {
    let (ok, out, err) = run_bin(LAB, &["bench3r", "--arms", "--repeat", "1", "--timeout", "0.5", "--max-boxes", "20000"]);
    assert!(ok, "{err}");
    for robot in ["puma560", "kuka_kr16", "ur5", "iiwa14", "a", "b", "d", "e", "f"] {
        let row = out.lines().find(|l| l.starts_with(&format!("{robot} | "))).unwrap_or_else(|| panic!("no row for {robot}:\n{out}"));
        let cells: Vec<&str> = row.split(" | ").collect();
        assert_eq!(cells.len(), 12, "{row}");
        assert_eq!(cells[3], "complete", "{row}");
        assert_eq!(cells[4], "0", "{row}");
        assert!(cells[8].starts_with("complete") || cells[8].starts_with("incomplete ("), "{row}");
        for i in [1, 2, 6, 7, 10, 11] {
            assert!(cells[i].parse::<f64>().is_ok_and(|x| x >= 0.0), "{row}");
        }
    }
}

/// `linkspace-lab bench3r` divides only by a peer it ran itself: without `ibexsolve` on PATH no
/// row has a ratio against Ibex and the stored figures come as dated references; with one (here a
/// stand-in script that keeps the models it is given and reports three boxes), each robot's row
/// has the peer's CPU time, its counts and a ratio, robot f's model over the θ₃ ranges outside
/// its two internal-motion strips.
#[test]
fn bench3r_divides_only_by_a_peer_run_in_the_same_invocation() {
    let lab = |path: &str| {
        let out = Command::new(LAB).args(["bench3r", "--repeat", "1"]).env("PATH", path).output().expect("binary runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let rows = |out: &str| -> Vec<Vec<String>> { out.lines().filter(|l| ["a", "b", "d", "e", "f"].iter().any(|r| l.starts_with(&format!("{r} | ")))).map(|l| l.split(" | ").map(str::to_string).collect()).collect() };
    let alone = lab("/nonexistent");
    assert!(alone.contains("ibexsolve not on PATH"), "{alone}");
    assert!(alone.contains("recorded 2026-11-25") && alone.contains("f: cusps 0.0318 s"), "{alone}");
    let got = rows(&alone);
    assert_eq!(got.len(), 5, "{alone}");
    for row in &got {
        assert_eq!(&row[7..10], ["-", "-", "-"], "{row:?}");
    }
    let dir = std::env::temp_dir().join(format!("linkspace-fake-peer-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("models")).expect("temp dir");
    let script = format!(
        "#!/bin/sh\nfor a in \"$@\"; do last=\"$a\"; done\ncp \"$last\" {}/models/\nprintf ' solving successful!\\n number of inner boxes:\\t3\\n number of boundary boxes:\\t0\\n number of unknown boxes:\\t1\\n'\n",
        dir.display()
    );
    let exe = dir.join("ibexsolve");
    std::fs::write(&exe, script).expect("script");
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    let with_peer = lab(&format!("{}:/usr/bin:/bin", dir.display()));
    assert!(with_peer.contains("baseline peer:") && with_peer.contains("ibexsolve (run here"), "{with_peer}");
    for row in rows(&with_peer) {
        assert!(row[7].parse::<f64>().is_ok_and(|t| t >= 0.0), "{row:?}");
        let pieces = if row[0] == "f" { 3 } else { 1 };
        assert_eq!(row[8], format!("{}, {}", 3 * pieces, pieces), "{row:?}");
        assert!(row[9].ends_with("faster") || row[9].ends_with("slower"), "{row:?}");
    }
    let models: Vec<String> = std::fs::read_dir(dir.join("models")).expect("models").map(|e| std::fs::read_to_string(e.expect("entry").path()).expect("model")).collect();
    assert_eq!(models.len(), 7);
    assert!(models.iter().all(|m| m.contains("det_df(t2, t3) = 0;") && m.contains("g2(t2, t3) = 0;")));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_deeply_nested_document_gets_one_line() {
    let depth = 20_000;
    let deep = tempfile_path::Path::write(&format!("<robot name=\"r\"><link name=\"a\"/>{}{}</robot>", "<x>".repeat(depth), "</x>".repeat(depth)));
    assert_clear_error(&["solve", deep.as_str()], "nested more than 256 deep");
    assert_clear_error(&["singularities", deep.as_str()], "nested more than 256 deep");
}

/// The image analysis ends within its deadline, however fine the raster: a grid of 1000 cells
/// per axis is a million cells, which the raster marks per image box, checking the deadline as
/// it goes. A deadline bound, not a speed test: the margin is the brief's 10 % plus 0.5 s.
#[test]
fn the_image_analysis_honours_its_deadline_and_its_memory_limit() {
    let five_bar = fixture("five_bar.urdf");
    let t0 = std::time::Instant::now();
    let (ok, out, err) = run(&["loop-singularities", &five_bar, "--actuated", "crank1_joint,crank2_joint", "--kind", "image", "--grid", "1000", "--timeout", "3"]);
    let elapsed = t0.elapsed().as_secs_f64();
    assert!(ok, "{err}");
    assert!(out.contains("status incomplete"), "{out}");
    assert!(elapsed < 3.0 * 1.1 + 0.5, "took {elapsed:.2} s for --timeout 3");
    // A raster that would hold more than the memory limit is refused before any search.
    assert_clear_error(&["loop-singularities", &five_bar, "--actuated", "crank1_joint,crank2_joint", "--kind", "image", "--grid", "20000"], "raster of regions needs about");
}

/// A ball joint takes no single `--fix` value, and says so; an uncertainty as large as a
/// length of the arm (10 m, 1e308 m on robot e) is refused naming that length, instead of
/// analysing a geometry whose lengths may vanish (which read as one internal-motion line over
/// the whole range, certified).
#[test]
fn a_ball_joint_and_an_uncertainty_wider_than_a_length_are_named() {
    assert_clear_error(&["solve", &fixture("delta.urdf"), "--fix", "elbow1=0.3"], "joint 'elbow1' is a ball joint");
    let e = fixture("orthogonal_3r_e.urdf");
    for h in ["10", "1e308"] {
        assert_clear_error(&["singularities", &e, "--uncertainty", h], "every length would have to stay away from 0");
    }
    let (ok, _, err) = run(&["singularities", &e, "--uncertainty", "1e-3"]);
    assert!(ok, "a small uncertainty is analysed: {err}");
}

/// A box whose one shrink takes minutes (an LP per side of each of hundreds of variables)
/// still ends at the deadline: 200 independent four-bars on one ground (600 angles), and one
/// loop closing a chain of 1,000 joints, for `solve` and `loop-singularities` (whose charts, one
/// per joint, are built one at a time). Before the LP checked the deadline, `solve` ran 58 s
/// and 92 s with `--timeout 8`. A deadline bound, not a speed test.
#[test]
fn one_long_box_does_not_outlast_the_deadline() {
    let mut many = String::from("<robot name='many_four_bars'><link name='ground'/>");
    for i in 0..200 {
        let y = 10 * i;
        many += &format!(
            "<link name='crank{i}'/><link name='coupler{i}'/><link name='rocker{i}'/>\
             <joint name='crank_joint{i}' type='continuous'><parent link='ground'/><child link='crank{i}'/><origin xyz='0 {y} 0'/><axis xyz='0 0 1'/></joint>\
             <joint name='coupler_joint{i}' type='continuous'><parent link='crank{i}'/><child link='coupler{i}'/><origin xyz='1.5 0 0'/><axis xyz='0 0 1'/></joint>\
             <joint name='rocker_joint{i}' type='continuous'><parent link='ground'/><child link='rocker{i}'/><origin xyz='4 {y} 0'/><axis xyz='0 0 1'/></joint>\
             <loop name='loop{i}' type='revolute'><predecessor link='coupler{i}'><origin xyz='4 0 0'/></predecessor><successor link='rocker{i}'><origin xyz='3.5 0 0'/></successor><axis xyz='0 0 1'/></loop>"
        );
    }
    many += "</robot>";
    let mut chain = String::from("<robot name='long_chain'><link name='ground'/>");
    let mut parent = String::from("ground");
    for i in 0..1000 {
        let x = if i == 0 { 0.0 } else { 0.01 };
        chain += &format!("<link name='l{i}'/><joint name='j{i}' type='continuous'><parent link='{parent}'/><child link='l{i}'/><origin xyz='{x} 0 0'/><axis xyz='0 0 1'/></joint>");
        parent = format!("l{i}");
    }
    chain += &format!("<loop name='close' type='revolute'><predecessor link='{parent}'><origin xyz='0.01 0 0'/></predecessor><successor link='ground'><origin xyz='5 0 0'/></successor><axis xyz='0 0 1'/></loop></robot>");
    for (name, text) in [("many_four_bars", many), ("long_chain", chain)] {
        let path = tempfile_path::Path::write(&text);
        for command in ["solve", "loop-singularities"] {
            let t0 = std::time::Instant::now();
            let (ok, out, err) = run(&[command, path.as_str(), "--timeout", "2"]);
            let elapsed = t0.elapsed().as_secs_f64();
            assert!(ok, "{command} {name}: {err}");
            assert!(out.contains("status incomplete (time limit"), "{command} {name}: {out}");
            assert!(elapsed < 2.0 * 1.1 + 2.0, "{command} {name}: took {elapsed:.2} s for --timeout 2");
        }
    }
}

/// Fixed links cost nothing: the four-bar with 300 sensor and tool frames (a chain of fixed
/// joints off the ground and a star of them on the coupler) has the same variables and the same
/// boxes as the bare four-bar, and its boxes list the same links; the frames are listed once,
/// each with the link it moves with.
#[test]
fn fixed_links_add_no_variable_and_no_per_box_output() {
    let bare = std::fs::read_to_string(fixture("four_bar.urdf")).expect("fixture");
    let mut frames = String::new();
    for i in 0..150 {
        let parent = if i == 0 { "ground".to_string() } else { format!("frame{}", i - 1) };
        frames += &format!("<link name=\"frame{i}\"/><joint name=\"frame{i}_joint\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"frame{i}\"/><origin xyz=\"0.01 0 0\" rpy=\"0 0 0.1\"/><axis xyz=\"0 0 0\"/></joint>");
        frames += &format!("<link name=\"tool{i}\"/><joint name=\"tool{i}_joint\" type=\"fixed\"><parent link=\"coupler\"/><child link=\"tool{i}\"/><origin xyz=\"0 0.01 0\"/></joint>");
    }
    let framed = tempfile_path::Path::write(&bare.replace("</robot>", &format!("{frames}</robot>")));
    let json = |urdf: &str| -> serde_json::Value {
        let path = std::env::temp_dir().join(format!("linkspace-frames-{}-{}.json", std::process::id(), urdf.len()));
        let (ok, _, err) = run(&["solve", urdf, "--sigma", "0.1", "--json", path.to_str().expect("utf-8")]);
        assert!(ok, "{err}");
        let v = serde_json::from_str(&std::fs::read_to_string(&path).expect("written")).expect("json");
        let _ = std::fs::remove_file(&path);
        v
    };
    let (a, b) = (json(&fixture("four_bar.urdf")), json(framed.as_str()));
    assert_eq!(a["variables"], b["variables"]);
    assert_eq!(a["solutions"].as_array().map(Vec::len), b["solutions"].as_array().map(Vec::len));
    for (x, y) in a["solutions"].as_array().expect("boxes").iter().zip(b["solutions"].as_array().expect("boxes")) {
        assert_eq!(x["box"], y["box"]);
        assert_eq!(x["link_angles"], y["link_angles"], "a box lists the links that move on their own only");
    }
    let rigid = b["rigid_links"].as_object().expect("listed once");
    assert_eq!(rigid.len(), 300);
    assert_eq!((rigid["frame149"].as_str(), rigid["tool7"].as_str()), (Some("ground"), Some("coupler")));
    assert!(a.get("rigid_links").is_none(), "no fixed link, no list");
}

/// `--kind cusps` and `--kind nodes` run one search of the type-II image alone: the generic
/// five-bar has no cusp (the image test in `closed_loop_singularities` checks that against the
/// gap function's critical points), and its node search (about 40 s to complete) stopped after a
/// second says so and which search it was.
#[test]
fn one_search_of_the_image_runs_alone() {
    let five_bar = fixture("five_bar_unequal.urdf");
    let report = |kind: &str, extra: &[&str]| -> (String, serde_json::Value) {
        let path = std::env::temp_dir().join(format!("linkspace-points-{kind}-{}.json", std::process::id()));
        let mut args = vec!["loop-singularities", five_bar.as_str(), "--actuated", "crank1_joint,crank2_joint", "--kind", kind, "--sigma", "1e-2", "--json", path.to_str().expect("utf-8")];
        args.extend_from_slice(extra);
        let (ok, out, err) = run(&args);
        assert!(ok, "{err}");
        let json = serde_json::from_str(&std::fs::read_to_string(&path).expect("written")).expect("json");
        let _ = std::fs::remove_file(&path);
        (out, json)
    };
    let (out, cusps) = report("cusps", &[]);
    assert!(out.contains("type-II image cusps: 0 proven, 0 undecided; status complete"), "{out}");
    assert_eq!((cusps["search"].as_str(), cusps["status"].as_str(), cusps["counts"]["proven"].as_u64()), (Some("cusps"), Some("complete"), Some(0)));
    assert!(cusps.get("regions").is_none() && cusps.get("verdict").is_none());
    let (out, nodes) = report("nodes", &["--timeout", "1"]);
    assert!(out.contains("type-II image nodes:") && out.contains("status incomplete"), "{out}");
    assert_eq!((nodes["search"].as_str(), nodes["status"].as_str()), (Some("nodes"), Some("incomplete")));
}

/// Each command's --help states the --max-memory default that command uses: `singularities`
/// bounds its pending cells at 256 MiB, the others at the kernel's 2048.
#[test]
fn each_command_shows_its_own_memory_default() {
    let line = |command: &str| {
        let (ok, out, _) = run(&[command, "--help"]);
        assert!(ok, "{command} --help");
        // The option and its text (on the next lines when clap lays the help out long).
        let lines: Vec<&str> = out.lines().collect();
        lines.iter().position(|l| l.contains("--max-memory")).map(|k| lines[k..(k + 4).min(lines.len())].join(" ")).unwrap_or_default()
    };
    assert!(line("singularities").contains("[default: 256]"), "{}", line("singularities"));
    for command in ["solve", "ik", "collisions", "distances", "loop-singularities"] {
        assert!(line(command).contains("[default: 2048]"), "{command}: {}", line(command));
    }
    assert_clear_error(&["ik", &fixture("puma560.urdf"), "--point", "0.5,0,0.3", "--max-memory", "0"], "--max-memory must be at least 1 MiB");
}

/// `ik6` at the KR16's home pose (every joint at 0: joint 5 lines axes 4 and 6 up; the pose
/// written here as the matrix its frames give at 0): the answer is complete in closed form,
/// one wrist-singular curve whose cover spans joints 4 and 6 over their whole ranges with
/// joints 1–3 and 5 pinned at 0 and holds the home configuration; the text names the curve.
#[test]
fn ik6_answers_a_wrist_singular_pose_with_a_curve() {
    let kr16 = format!("{}/urdf/kuka_kr16.urdf", env!("CARGO_MANIFEST_DIR"));
    let path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("ik6-home-{}.json", std::process::id()));
    let home = "1,0,0,0.905,0,-1,0,0,0,0,-1,-0.153,0,0,0,1";
    let (ok, out, err) = run(&["ik6", &kr16, "--pose", home, "--json", path.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    assert!(out.contains("1 singular curves") && out.contains("(wrist singular: joint_4, joint_6 move together along a curve;"), "{out}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("written")).expect("json");
    assert_eq!((r["status"].as_str(), r["method"].as_str()), (Some("complete"), Some("closed_form")), "{r}");
    let curves = r["curves"].as_array().expect("curves");
    assert_eq!(curves.len(), 1, "{r}");
    assert_eq!((&curves[0]["kind"], &curves[0]["moving"]), (&serde_json::json!("wrist_singular"), &serde_json::json!(["joint_4", "joint_6"])));
    let range = |j: &str| [0, 1].map(|e| curves[0]["ranges"][j][e].as_f64().expect("bound"));
    for j in ["joint_4", "joint_6"] {
        assert_eq!(range(j), [-6.1087, 6.1087], "{j}");
    }
    for (j, within) in [("joint_1", 1e-12), ("joint_2", 1e-12), ("joint_3", 1e-12), ("joint_5", 1e-6)] {
        let [lo, hi] = range(j);
        assert!(lo <= 0.0 && hi >= 0.0 && hi - lo < 2.0 * within, "{j}: [{lo}, {hi}]");
    }
    let holds_home = |b: &serde_json::Value| ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"].iter().all(|j| b[j][0].as_f64().unwrap_or(f64::NAN) <= 0.0 && b[j][1].as_f64().unwrap_or(f64::NAN) >= 0.0);
    assert!(curves[0]["cover"].as_array().expect("cover").iter().any(holds_home), "{r}");
}

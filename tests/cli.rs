//! Test idea: run the real binary on bad input and check the contract: non-zero exit, one line
//! on stderr that names the problem, never a panic. And the good path writes the documented JSON.

use std::process::Command;

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_linkspace")).args(args).output().expect("binary runs");
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
    let (ok, _, err) = run(args);
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
    assert_clear_error(&["solve", &fb, "--fix", "crank_joint=NaN"], "not a finite number");
    assert_clear_error(&["solve", &sc, "--fix", "slider_joint=9"], "outside its limits");
    assert_clear_error(&["solve", &fb, "--sigma", "0"], "sigma must be a positive");
    assert_clear_error(&["solve", &fb, "--sigma", "NaN"], "sigma must be a positive");
    assert_clear_error(&["solve", &fb, "--rho", "1.5"], "rho must lie strictly between 0 and 1");
    assert_clear_error(&["solve", &fb, "--trace", "ghost@1,2"], "no link named 'ghost'");
    // A rocker of length 30 can never reach the coupler: the loop cannot close.
    let long = variant("four_bar.urdf", "<successor link=\"rocker\"><origin xyz=\"3.5 0 0\"", "<successor link=\"rocker\"><origin xyz=\"30 0 0\"");
    assert_clear_error(&["solve", long.as_str()], "loop 'loop_coupler_rocker' cannot close");
    // A joint turning about x makes the mechanism spatial.
    let tilted = variant("four_bar.urdf", "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>");
    assert_clear_error(&["solve", tilted.as_str()], "not planar");
}

#[test]
fn limits_end_the_run_incomplete_with_every_box_reported() {
    let dir = std::env::temp_dir().join(format!("linkspace-limit-{}.json", std::process::id()));
    let (ok, out, err) = run(&["solve", &fixture("double_butterfly.urdf"), "--max-boxes", "5", "--json", dir.to_str().expect("utf-8")]);
    assert!(ok, "{err}");
    assert!(out.contains("incomplete (Boxes limit"), "{out}");
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
    assert_eq!(r["settings"]["sigma"], 1e-5);
}

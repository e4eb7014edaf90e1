//! Test idea: a sweep's verdicts and counts are checked design by design against references
//! computed without the solver, at designs away from the surfaces where they change; and the
//! command keeps its contract (results as they come, resume, one-line refusals, failed tasks
//! recorded while the sweep goes on).
//!
//! - Cuspidality of orthogonal 3R arms (d2 = 1, r2 = 0.5, r3 = 0) over (d3, d4): the dense
//!   sampling of `arm3r::sample` (marching squares on det Df = 0, cusps where the image turns
//!   back) counts the cusps; cuspidal iff at least one (Salunkhe et al. 2022 for generic 3R).
//! - Assembly modes of the 3-RPR over (ρ1, ρ2) at ρ3 = 12: for each platform angle φ the leg
//!   equations 2 and 3 minus equation 1 are linear in the platform position, so the poses are
//!   the roots in φ of one continuous function, found by sign changes on a dense grid and
//!   polished by bisection, each checked against the three leg equations.
//!
//! Margin: the references are used only where they are locally constant, i.e. where the same
//! count comes out at the design and at its four neighbours a fixed step away in each varied
//! parameter (0.05 for the arm's lengths, 0.25 for the leg lengths: a quarter of the grid step
//! or less). A separating surface closer than that step changes the count at a neighbour and the
//! design is left out; at least 20 of the 25 designs must be kept.

use linkspace::app;
use linkspace::model::urdf;
use linkspace::analyses::sweep::{self, TaskResult, TaskStatus};
use std::collections::HashSet;
use std::process::Command;
use std::sync::atomic::AtomicBool;

const LINKSPACE: &str = env!("CARGO_BIN_EXE_linkspace");

fn repo(path: &str) -> String {
    format!("{}/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(LINKSPACE).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// A fresh directory under the system's temp dir.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("linkspace-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn results(dir: &std::path::Path) -> Vec<TaskResult> {
    let text = std::fs::read_to_string(dir.join("results.jsonl")).expect("results written");
    text.lines().skip(1).map(|l| serde_json::from_str(l).expect("a result per line")).collect()
}

/// The verdict the dense sampling gives (cusps > 0), when it is the same at the design and at
/// its four neighbours `step` away in d3 and d4.
fn sampled_verdict(d3: f64, d4: f64, step: f64) -> Option<bool> {
    let cuspidal = |d3: f64, d4: f64| !crate::manip3r::sample((1.0, d3, d4, 0.5, 0.0), 800).cusps.is_empty();
    let here = cuspidal(d3, d4);
    [(step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)].iter().all(|(a, b)| cuspidal(d3 + a, d4 + b) == here).then_some(here)
}

#[test]
fn orthogonal_3r_cuspidality_matches_dense_sampling() {
    let dir = scratch("3r");
    let spec = dir.join("spec.json");
    std::fs::write(
        &spec,
        format!(
            r#"{{"urdf": "{}", "analysis": "cuspidality",
                "parameters": [{{"param": "joint.joint3.xyz.0", "label": "d3", "from": 0.3, "to": 2.7, "steps": 5}},
                               {{"param": "joint.tool_joint.xyz.0", "label": "d4", "from": 0.2, "to": 2.6, "steps": 5}}],
                "constants": {{"joint.joint3.xyz.1": 0.5}}, "limits": {{"timeout": 30}}}}"#,
            repo("examples/sweeps/orthogonal_3r.urdf")
        ),
    )
    .expect("spec written");
    let out = dir.join("out");
    let (ok, stdout, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--threads", "2"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("25 of 25 tasks done (25 now), complete 25"), "{stdout}");
    let found = results(&out);
    assert_eq!(found.len(), 25);
    let (mut kept, mut seen) = (0, HashSet::new());
    for r in &found {
        assert_eq!((r.status, r.undecided), (TaskStatus::Ran(linkspace::app::Completeness::Complete), 0), "{r:?}");
        let cuspidal = match r.verdict.as_deref() {
            Some("cuspidal") => true,
            Some("non_cuspidal") => false,
            other => panic!("task {}: verdict {other:?}", r.index),
        };
        // Cuspidal exactly when cusps are proven.
        assert_eq!(cuspidal, r.proven > 0, "{r:?}");
        if let Some(want) = sampled_verdict(r.values[0], r.values[1], 0.05) {
            assert_eq!(cuspidal, want, "d3 = {}, d4 = {}: sweep says cuspidal = {cuspidal}", r.values[0], r.values[1]);
            kept += 1;
            seen.insert(want);
        }
    }
    assert!(kept >= 20, "only {kept} designs away from the separating surfaces");
    assert_eq!(seen.len(), 2, "both verdicts are checked");
    for file in ["results.csv", "summary.json", "map.svg"] {
        assert!(out.join(file).is_file(), "{file} written");
    }
    let csv = std::fs::read_to_string(out.join("results.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 26);
    assert!(csv.starts_with("index,d3,d4,status,limit,verdict,count,proven,undecided,seconds,error\n"));
    let svg = std::fs::read_to_string(out.join("map.svg")).expect("svg");
    assert_eq!(svg.matches("<rect").count(), 25 + 2 + 2, "25 cells, background, frame, a legend entry per verdict");

    // Resume: nothing left to run; an interrupted last line is dropped and its task rerun.
    let (ok, stdout, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--resume"]);
    assert!(ok && stdout.contains("25 of 25 tasks done (0 now)"), "{stdout}{stderr}");
    let jsonl = out.join("results.jsonl");
    let text = std::fs::read_to_string(&jsonl).expect("results");
    let cut = text.trim_end().rfind('\n').expect("lines") + 12;
    std::fs::write(&jsonl, &text[..cut]).expect("cut");
    let (ok, stdout, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--resume"]);
    assert!(ok && stdout.contains("25 of 25 tasks done (1 now)"), "{stdout}{stderr}");
    assert_eq!(results(&out).len(), 25);
    // Without --resume the results are not overwritten; with another spec they are not mixed.
    let (ok, _, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8")]);
    assert!(!ok && stderr.contains("--resume continues that sweep") && stderr.trim().lines().count() == 1, "{stderr}");
    let changed = std::fs::read_to_string(&spec).expect("spec").replace("\"steps\": 5}],", "\"steps\": 4}],");
    std::fs::write(&spec, changed).expect("spec rewritten");
    let (ok, _, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--resume"]);
    assert!(!ok && stderr.contains("cannot resume: the spec or the URDF changed") && stderr.trim().lines().count() == 1, "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The 3-RPR of `urdf/three_rpr.urdf`: base A, platform B (B1 at the platform origin).
const BASE: [[f64; 2]; 3] = [[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]];
const PLATFORM: [[f64; 2]; 3] = [[0.0, 0.0], [17.04, 0.0], [13.236373, 16.096708]];

/// Number of platform poses with leg lengths `rho`, without the solver (module comment).
pub(crate) fn poses(rho: [f64; 3]) -> usize {
    // For angle φ: P = N / D from the two linear equations; h = |N|² − ρ1² D² vanishes at poses.
    let h = |phi: f64| {
        let (c, s) = (phi.cos(), phi.sin());
        let mut rows = [[0.0; 3]; 2];
        for i in 1..3 {
            let b = [c * PLATFORM[i][0] - s * PLATFORM[i][1] - BASE[i][0], s * PLATFORM[i][0] + c * PLATFORM[i][1] - BASE[i][1]];
            rows[i - 1] = [2.0 * b[0], 2.0 * b[1], rho[i] * rho[i] - rho[0] * rho[0] - (b[0] * b[0] + b[1] * b[1])];
        }
        let d = rows[0][0] * rows[1][1] - rows[0][1] * rows[1][0];
        let nx = rows[0][2] * rows[1][1] - rows[0][1] * rows[1][2];
        let ny = rows[0][0] * rows[1][2] - rows[0][2] * rows[1][0];
        (nx * nx + ny * ny - rho[0] * rho[0] * d * d, [nx / d, ny / d])
    };
    let n = 20_000;
    let at = |k: usize| -std::f64::consts::PI + std::f64::consts::TAU * k as f64 / n as f64;
    let mut count = 0;
    for k in 0..n {
        let (mut a, mut b) = (at(k), at(k + 1));
        let (mut ha, hb) = (h(a).0, h(b).0);
        if (ha > 0.0) == (hb > 0.0) {
            continue;
        }
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            let hm = h(m).0;
            if (hm > 0.0) == (ha > 0.0) {
                (a, ha) = (m, hm);
            } else {
                b = m;
            }
        }
        let phi = 0.5 * (a + b);
        let p = h(phi).1;
        let (c, s) = (phi.cos(), phi.sin());
        let legs_hold = (0..3).all(|i| {
            let x = p[0] + c * PLATFORM[i][0] - s * PLATFORM[i][1] - BASE[i][0];
            let y = p[1] + s * PLATFORM[i][0] + c * PLATFORM[i][1] - BASE[i][1];
            ((x * x + y * y).sqrt() - rho[i]).abs() < 1e-6
        });
        count += usize::from(legs_hold);
    }
    count
}

#[test]
fn three_rpr_assembly_modes_match_an_independent_count() {
    let spec = std::fs::read_to_string(repo("examples/sweeps/three_rpr_assembly_modes.json")).expect("shipped spec");
    // The shipped spec's design, on a 5 × 5 grid.
    assert!(spec.contains("\"steps\": 17"), "the shipped grid");
    let spec = spec.replace("\"steps\": 17", "\"steps\": 5");
    let plan = sweep::parse(&spec).expect("valid");
    let mechanism = urdf::parse(&std::fs::read_to_string(repo("urdf/three_rpr.urdf")).expect("bundled")).expect("parses");
    let tasks = plan.tasks(100).expect("small");
    app::sweeps::check_sweep(&plan, &mechanism, &tasks).expect("fits");
    let limits = linkspace::app::Limits { max_cells: 1_000_000, timeout: Some(std::time::Duration::from_secs(30)), max_memory: 256 << 20 };
    let mut found = Vec::new();
    let cancel = AtomicBool::new(false);
    sweep::run_tasks::<()>(&tasks, 2, &HashSet::new(), |t| app::sweep_task(&plan, &mechanism, t, &limits, &cancel), |r| {
        found.push(r);
        Ok(())
    })
    .expect("no writer");
    assert_eq!(found.len(), 25);
    let (mut kept, mut counts) = (0, HashSet::new());
    for r in &found {
        let [r1, r2] = [r.values[0], r.values[1]];
        assert_eq!((r.status, r.undecided), (TaskStatus::Ran(linkspace::app::Completeness::Complete), 0), "{r:?}");
        let count = r.count.expect("counted") as usize;
        assert_eq!(count as u64, r.proven, "every mode proven: {r:?}");
        let here = poses([r1, r2, 12.0]);
        let stable = [(0.25, 0.0), (-0.25, 0.0), (0.0, 0.25), (0.0, -0.25)].iter().all(|(a, b)| poses([r1 + a, r2 + b, 12.0]) == here);
        if stable {
            assert_eq!(count, here, "rho1 = {r1}, rho2 = {r2}");
            kept += 1;
            counts.insert(here);
        }
    }
    assert!(kept >= 20, "only {kept} designs away from the singular surfaces");
    assert!(counts.len() >= 2, "several counts checked: {counts:?}");
}

#[test]
fn a_failing_task_is_recorded_and_the_sweep_goes_on() {
    let dir = scratch("fail");
    let spec = dir.join("spec.json");
    // ρ1 = 0.5 is outside the leg's limits [1, 40]: that task fails, the other runs.
    std::fs::write(
        &spec,
        format!(
            r#"{{"urdf": "{}", "analysis": "assembly_modes", "parameters": [{{"param": "fix.rho1"}}, {{"param": "fix.rho2"}}],
                "tuples": [[0.5, 12], [14.98, 15.38]], "constants": {{"fix.rho3": 12}}}}"#,
            repo("urdf/three_rpr.urdf")
        ),
    )
    .expect("spec");
    let out = dir.join("out");
    let (ok, stdout, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8")]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("complete 1, failed 1"), "{stdout}");
    let found = results(&out);
    let failed = found.iter().find(|r| r.index == 0).expect("recorded");
    assert_eq!(failed.status, TaskStatus::Failed);
    assert!(failed.error.as_deref().is_some_and(|e| e.contains("rho1")), "{failed:?}");
    assert_eq!(found.iter().find(|r| r.index == 1).expect("ran").count, Some(6));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_sweeps_are_refused_in_one_line() {
    let dir = scratch("bad");
    let spec = dir.join("spec.json");
    let arm = repo("examples/sweeps/orthogonal_3r.urdf");
    let cases = [
        (format!(r#"{{"urdf": "{arm}", "analysis": "cuspidality", "parameters": [{{"param": "joint.joint3.xyz.0", "from": 1, "to": 2}}]}}"#), "parameters[0]: give values, or from, to and steps"),
        (format!(r#"{{"urdf": "{arm}", "analysis": "cuspidality", "parameters": [{{"param": "joint.nope.xyz.0", "values": [1]}}]}}"#), "the mechanism has no joint 'nope'"),
        (format!(r#"{{"urdf": "{arm}", "analysis": "cuspidality", "parameters": [{{"param": "fix.joint2", "values": [1]}}]}}"#), "takes no fixed joints"),
        (
            format!(r#"{{"urdf": "{arm}", "analysis": "cuspidality", "parameters": [{{"param": "joint.joint3.xyz.0", "from": 1, "to": 2, "steps": 1000}}, {{"param": "joint.joint3.xyz.1", "from": 1, "to": 2, "steps": 1000}}]}}"#),
            "the sweep has 1000000 tasks, more than the 100000 allowed (--max-tasks)",
        ),
        (r#"{"urdf": "missing.urdf", "analysis": "cuspidality", "parameters": [{"param": "fix.a", "values": [1]}]}"#.to_string(), "missing.urdf"),
    ];
    for (text, needle) in cases {
        std::fs::write(&spec, &text).expect("spec");
        let (ok, _, stderr) = run(&["sweep", spec.to_str().expect("utf-8"), "--out", dir.join("out").to_str().expect("utf-8")]);
        assert!(!ok && stderr.contains(needle) && stderr.trim().lines().count() == 1 && !stderr.contains("panicked"), "{needle}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

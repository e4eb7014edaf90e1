//! Input motions of the bundled crank-rocker four-bar (`four_bar.urdf`: d = 4, a = 1.5,
//! b = 4, c = 3.5), the rocker actuated, checked by tube following (`app::check_input_motion`)
//! against closed forms: the rocker's turning points are where crank and coupler are in line,
//! and along a motion each configuration of the assembly's branch follows from the two circles
//! about the crank's pivot and the rocker's tip.

use super::util::urdf_text;
use linkspace::app::{check_input_motion, InputMotionCheck, MotionRequest, MotionVerdict};
use linkspace::model::urdf;
use linkspace::kernel::search::Control;
use std::f64::consts::PI;
use std::process::Command;
use std::sync::atomic::AtomicBool;

const D: f64 = 4.0;
const A: f64 = 1.5;
const B: f64 = 4.0;
const C: f64 = 3.5;

/// The rocker's turning point with the crank tip at distance `r` from its pivot (a + b or b − a),
/// on the upper branch (rocker tip above the ground line): law of cosines at the rocker pivot.
fn turning(r: f64) -> f64 {
    PI - ((D * D + C * C - r * r) / (2.0 * D * C)).acos()
}

/// (crank, coupler, rocker, loop joint) at rocker angle `t4`, the crank tip on the side `side`
/// (±1) of the line from the crank pivot to the rocker tip: the two circles' intersection.
fn configuration(t4: f64, side: f64) -> [f64; 4] {
    let tip = [D + C * t4.cos(), C * t4.sin()];
    let n = tip[0].hypot(tip[1]);
    let along = (A * A - B * B + n * n) / (2.0 * n);
    let across = (A * A - along * along).max(0.0).sqrt();
    let e = [tip[0] / n, tip[1] / n];
    let p = [along * e[0] - side * across * e[1], along * e[1] + side * across * e[0]];
    let t2 = p[1].atan2(p[0]);
    let t3 = (tip[1] - p[1]).atan2(tip[0] - p[0]);
    [t2, t3 - t2, t4, t4 - t3]
}

fn gap(x: f64, y: f64) -> f64 {
    let d = (x - y).rem_euclid(2.0 * PI);
    d.min(2.0 * PI - d)
}

fn holds(b: [f64; 2], x: f64) -> bool {
    let k = ((0.5 * (b[0] + b[1]) - x) / (2.0 * PI)).round();
    let x = x + 2.0 * PI * k;
    b[0] <= x && x <= b[1]
}

const JOINTS: [&str; 4] = ["crank_joint", "coupler_joint", "rocker_joint", "loop_coupler_rocker"];

fn check(from: f64, to: f64, side: f64) -> InputMotionCheck {
    let m = urdf::parse(&urdf_text("four_bar.urdf")).expect("fixture parses");
    // An approximate assembly: the closed form rounded to three decimals.
    let assembly = configuration(from, side).iter().map(|v| (v * 1e3).round() / 1e3).collect();
    let request = MotionRequest { actuated: "rocker_joint".into(), from, to, assembly, max_step: 0.05, min_step: 1e-6, name_turning_point: true };
    let cancel = AtomicBool::new(false);
    let control = Control { limits: Default::default(), threads: 1, cancel: &cancel };
    let found = check_input_motion(&m, &[], &request, &control).expect("checks");
    assert_eq!(found.joints, JOINTS);
    found
}

/// Every step's box holds the closed-form configuration of the branch at inputs across it.
fn assert_steps_follow_the_branch(found: &InputMotionCheck, side: f64) {
    assert!(!found.steps.is_empty());
    for s in &found.steps {
        for k in 0..=8 {
            let t4 = s.input[0] + (s.input[1] - s.input[0]) * k as f64 / 8.0;
            let q = configuration(t4, side);
            for (name, v) in JOINTS.iter().zip(q) {
                assert!(holds(s.joints[*name], v), "step {:?}: {name} = {v} not in {:?}", s.input, s.joints[*name]);
            }
        }
    }
}

#[test]
fn a_rocker_motion_inside_its_range_is_clear_and_its_boxes_hold_the_closed_form_branch() {
    let (lo, hi) = (turning(A + B), turning(B - A));
    assert!(lo < 1.8 && 2.2 < hi, "the motion lies inside the rocker's range [{lo}, {hi}]");
    for side in [1.0, -1.0] {
        let found = check(1.8, 2.2, side);
        assert_eq!(found.verdict, MotionVerdict::Clear, "side {side}");
        assert_steps_follow_the_branch(&found, side);
        let covered = found.steps.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| (l.min(s.input[0]), h.max(s.input[1])));
        assert_eq!(covered, (1.8, 2.2));
        // And back.
        assert_eq!(check(2.2, 1.8, side).verdict, MotionVerdict::Clear);
    }
}

#[test]
fn a_rocker_motion_past_its_turning_points_is_undecided_from_just_before_them() {
    for (from, to, limit) in [(1.8, 2.6, turning(B - A)), (1.8, 1.3, turning(A + B))] {
        let found = check(from, to, 1.0);
        let MotionVerdict::Undecided { from: stop, near, .. } = &found.verdict else { panic!("{:?}", found.verdict) };
        // Proven no further than the turning point, and stopped close to it.
        assert!((stop - from) * (limit - stop) >= 0.0 && (stop - limit).abs() < 1e-3, "stopped at {stop}, turning point {limit}");
        assert_steps_follow_the_branch(&found, 1.0);
        let near = near.as_ref().expect("the certified turning point is named");
        assert!(holds(near["rocker_joint"], limit) || gap(0.5 * (near["rocker_joint"][0] + near["rocker_joint"][1]), limit) < 1e-6, "{near:?}");
    }
}

#[test]
fn loop_singularities_kind_motion_writes_the_verdict_and_the_certificate() {
    let dir = std::env::temp_dir().join(format!("linkspace-motion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let json = dir.join("motion.json");
    let assembly: Vec<String> = configuration(1.8, 1.0).iter().map(|v| format!("{v:.4}")).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_linkspace"))
        .args(["loop-singularities", &format!("{}/urdf/four_bar.urdf", env!("CARGO_MANIFEST_DIR")), "--kind", "motion", "--actuated", "rocker_joint", "--from", "1.8", "--to", "2.6"])
        .args(["--assembly", &assembly.join(","), "--json", json.to_str().expect("utf-8")])
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("JSON");
    assert_eq!(r["singular_set"], "input singularities of four_bar, actuated rocker_joint");
    assert_eq!(r["verdict"], "undecided");
    assert!((r["proven_to"].as_f64().expect("number") - turning(B - A)).abs() < 1e-3);
    assert!(r["reason"].as_str().expect("text").contains("near the certified turning point"));
    assert!(!r["steps"].as_array().expect("steps").is_empty());
    std::fs::remove_dir_all(&dir).ok();
}

/// The double butterfly driven by joint 6, from an assembly at θ6 = −0.01 (four decimals) on a
/// branch where θ6 turns back at two turning points: motions towards them stop just before the
/// turning points that the independent continuation reference
/// (`closed_loop_singularities::trace`, (θ7, θ6) = (joint7, joint6)) finds on that branch, and a
/// motion between them is clear, with no reference turning point inside its boxes.
#[test]
fn double_butterfly_motions_of_joint6_stop_at_the_reference_turning_points_and_clear_between() {
    let (_, stationary) = super::closed_loop_singularities::trace::all(&super::closed_loop_singularities::butterfly_starts());
    let reference: Vec<(f64, f64)> = stationary.iter().map(|q| (q[6], q[5])).collect();
    let m = urdf::parse(&urdf_text("double_butterfly.urdf")).expect("fixture parses");
    // joint7, joint2, joint1, joint5, joint6, joint3, joint4, loop15, loop13, loop24
    let assembly = vec![2.087, -0.6555, 2.0986, 1.4214, -0.01, 2.3761, 2.164, -2.1088, -1.164, 0.7225];
    let cancel = AtomicBool::new(false);
    let control = Control { limits: Default::default(), threads: 1, cancel: &cancel };
    let run = |from: f64, to: f64| {
        let request = MotionRequest { actuated: "joint6".into(), from, to, assembly: assembly.clone(), max_step: 0.05, min_step: 1e-6, name_turning_point: true };
        check_input_motion(&m, &[], &request, &control).expect("checks")
    };
    // No reference turning point lies in a proven step's box.
    let assert_no_reference_inside = |found: &InputMotionCheck| {
        for s in &found.steps {
            for &(r7, r6) in &reference {
                assert!(!(s.input[0] <= r6 && r6 <= s.input[1] && holds(s.joints["joint7"], r7)), "turning point ({r7}, {r6}) inside step {:?}", s.input);
            }
        }
    };
    for (from, to) in [(-0.3, 0.2), (-0.5, -2.0)] {
        let found = run(from, to);
        let MotionVerdict::Undecided { from: stop, near, .. } = &found.verdict else { panic!("{from} -> {to}: {:?}", found.verdict) };
        let last = found.steps.last().expect("steps");
        let (r7, r6) = *reference
            .iter()
            .min_by(|a, b| (gap(a.1, *stop) + gap(a.0, 0.5 * (last.joints["joint7"][0] + last.joints["joint7"][1]))).total_cmp(&(gap(b.1, *stop) + gap(b.0, 0.5 * (last.joints["joint7"][0] + last.joints["joint7"][1])))))
            .expect("reference points");
        assert!((stop - from) * (r6 - stop) >= 0.0 && (stop - r6).abs() < 1e-3, "{from} -> {to}: stopped at {stop}, reference turning point ({r7}, {r6})");
        assert!(gap(0.5 * (last.joints["joint7"][0] + last.joints["joint7"][1]), r7) < 0.05, "joint7 {:?} against {r7}", last.joints["joint7"]);
        let near = near.as_ref().expect("named");
        assert!(gap(0.5 * (near["joint6"][0] + near["joint6"][1]), r6) < 1e-5 && gap(0.5 * (near["joint7"][0] + near["joint7"][1]), r7) < 1e-5, "{near:?}");
        assert_no_reference_inside(&found);
    }
    let found = run(-1.2, 0.0);
    assert_eq!(found.verdict, MotionVerdict::Clear);
    assert_no_reference_inside(&found);
}

/// The start is read as the builder reads joint values (`LinkageProblem::point_from_joints`):
/// the closed-form configuration, its angles any number of turns out, is a point of the loop's
/// system (every row vanishes, the loop joint's value unused) whose joint readings are the
/// closed form's modulo 2π.
#[test]
fn closed_form_configurations_any_turns_out_are_points_of_the_loop() {
    let p = super::util::problem("four_bar.urdf", &[], &[]);
    assert_eq!(p.free_joints, JOINTS);
    // Inside the rocker's range [1.4996, 2.4747].
    for (k, t4) in [1.6, 1.8, 2.2, 2.4].into_iter().enumerate() {
        for side in [1.0, -1.0] {
            let q = configuration(t4, side);
            let turns = [[0.0; 4], [3.0, -2.0, 1.0, 5.0], [-1.0, 4.0, -3.0, 0.0]][k % 3];
            let given: Vec<f64> = q.iter().zip(turns).map(|(v, n)| v + n * 2.0 * PI).collect();
            let x = p.point_from_joints(&given).expect("four values");
            for e in &p.system.equations {
                assert!(e.residual(&x).abs() < 1e-12, "t4 {t4}, side {side}: residual {}", e.residual(&x));
            }
            let read = p.joint_values(&linkspace::kernel::interval::IntervalBox::new(x.iter().map(|&v| linkspace::kernel::interval::point(v)).collect()));
            for (name, v) in JOINTS.iter().zip(q) {
                let (lo, hi) = read[*name];
                assert!(gap(0.5 * (lo + hi), v) < 1e-12, "t4 {t4}, side {side}: {name} reads [{lo}, {hi}], closed form {v}");
            }
        }
    }
}

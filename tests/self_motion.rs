//! `linkspace self-motion` on the KUKA LBR iiwa 14 (`urdf/iiwa14.urdf`, angles as written):
//! the cover holds every configuration at the pose, against Newton's method on the arm's forward
//! kinematics written here from the file's numbers (no code of the solver).

use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, Vector3};
use std::process::Command;

const IIWA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/iiwa14.urdf");

/// A joint of the file: revolute or fixed, its origin and axis.
struct Joint {
    revolute: bool,
    xyz: [f64; 3],
    rpy: [f64; 3],
    axis: [f64; 3],
    limits: (f64, f64),
}

fn attr(element: &str, tag: &str, name: &str) -> Option<String> {
    let at = element.find(&format!("<{tag}"))?;
    let rest = &element[at..element[at..].find('>').map_or(element.len(), |e| at + e)];
    let key = format!("{name}=\"");
    let start = rest.find(&key)? + key.len();
    Some(rest[start..start + rest[start..].find('"')?].to_string())
}

fn numbers(text: Option<String>) -> [f64; 3] {
    let v: Vec<f64> = text.unwrap_or_else(|| "0 0 0".into()).split_whitespace().map(|x| x.parse().expect("a number")).collect();
    [v[0], v[1], v[2]]
}

/// The joints in file order (the iiwa's file lists them from the base to the tool).
fn chain() -> Vec<Joint> {
    let xml = std::fs::read_to_string(IIWA).expect("bundled");
    xml.split("<joint ")
        .skip(1)
        .map(|j| {
            let j = &j[..j.find("</joint>").expect("closed")];
            let revolute = j.starts_with(&format!("name=\"{}\" type=\"revolute\"", j.split('"').nth(1).expect("name")));
            let limits = (attr(j, "limit", "lower").map_or(0.0, |x| x.parse().expect("lower")), attr(j, "limit", "upper").map_or(0.0, |x| x.parse().expect("upper")));
            Joint { revolute, xyz: numbers(attr(j, "origin", "xyz")), rpy: numbers(attr(j, "origin", "rpy")), axis: numbers(attr(j, "axis", "xyz")), limits }
        })
        .collect()
}

fn rpy(r: [f64; 3]) -> Matrix3<f64> {
    let rot = |axis: Vector3<f64>, t: f64| *nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), t).matrix();
    rot(Vector3::z(), r[2]) * rot(Vector3::y(), r[1]) * rot(Vector3::x(), r[0])
}

fn fk(chain: &[Joint], q: &[f64]) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    let mut k = 0;
    for j in chain {
        let mut step = Matrix4::identity();
        step.fixed_view_mut::<3, 3>(0, 0).copy_from(&rpy(j.rpy));
        step.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::from(j.xyz));
        t *= step;
        if j.revolute {
            let turn = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::from(j.axis)), q[k]);
            t *= turn.to_homogeneous();
            k += 1;
        }
    }
    t
}

/// Gauss–Newton on the twelve entries of the pose for the six joints other than `held`, from
/// `q`; `None` unless it converges to 1e-12.
fn newton(chain: &[Joint], target: &Matrix4<f64>, mut q: Vec<f64>, held: usize) -> Option<Vec<f64>> {
    let free: Vec<usize> = (0..7).filter(|&k| k != held).collect();
    let residual = |q: &[f64]| DVector::from_iterator(12, (fk(chain, q) - target).rows(0, 3).iter().copied());
    for _ in 0..60 {
        let r = residual(&q);
        if r.norm() < 1e-12 {
            return Some(q);
        }
        let mut jac = DMatrix::zeros(12, 6);
        for (c, &k) in free.iter().enumerate() {
            let mut p = q.clone();
            p[k] += 1e-7;
            jac.set_column(c, &((residual(&p) - &r) / 1e-7));
        }
        let step = jac.svd(true, true).solve(&r, 1e-12).ok()?;
        for (c, &k) in free.iter().enumerate() {
            q[k] -= step[c];
        }
    }
    (residual(&q).norm() < 1e-12).then_some(q)
}

struct Cover {
    joints: Vec<String>,
    boxes: Vec<(Vec<[f64; 2]>, String)>,
}

fn self_motion(target: &Matrix4<f64>, range: &str) -> (Cover, serde_json::Value) {
    let pose: Vec<String> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).map(|(i, j)| format!("{:.17e}", target[(i, j)])).collect();
    let json = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("self-motion-{}-{range}.json", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_linkspace"))
        .args(["self-motion", IIWA, "--exact-geometry", "--parameter", "joint_3", "--range", range, "--pose", &pose.join(","), "--json"])
        .arg(&json)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("json");
    let _ = std::fs::remove_file(&json);
    let joints: Vec<String> = report["joints"].as_array().expect("joints").iter().map(|n| n.as_str().expect("name").to_string()).collect();
    let boxes = report["boxes"]
        .as_array()
        .expect("boxes")
        .iter()
        .map(|b| (joints.iter().map(|n| [b["joints"][n][0].as_f64().expect("lo"), b["joints"][n][1].as_f64().expect("hi")]).collect(), b["tag"].as_str().expect("tag").to_string()))
        .collect();
    (Cover { joints, boxes }, report)
}

fn covered(cover: &Cover, q: &[f64]) -> bool {
    cover.boxes.iter().any(|(b, _)| b.iter().zip(q).all(|(x, v)| x[0] - 1e-9 <= *v && *v <= x[1] + 1e-9))
}

/// The arc through a configuration, followed by Newton in steps of the parameter, and every
/// configuration found from random starts at one parameter value, lie in the cover; each
/// certified box sampled holds the configuration Newton finds from its centre.
#[test]
fn the_cover_holds_every_configuration_newton_finds() {
    let chain = chain();
    let limits: Vec<(f64, f64)> = chain.iter().filter(|j| j.revolute).map(|j| j.limits).collect();
    let within = |q: &[f64]| q.iter().zip(&limits).all(|(v, (lo, hi))| lo <= v && v <= hi);
    let q0 = vec![0.3, 0.5, 0.2, -1.2, 0.4, 0.8, -0.3];
    let target = fk(&chain, &q0);
    let (cover, report) = self_motion(&target, "-0.2,0.6");
    assert_eq!(cover.joints[2], "joint_3");
    assert_eq!(report["cells_searched"], report["cells"], "every cell searched: {}", report["status"]);
    let certified = cover.boxes.iter().filter(|(_, t)| t == "unique").count();
    assert!(certified * 5 >= cover.boxes.len() * 4, "{certified} of {} boxes certified", cover.boxes.len());
    // The arc through q0, both ways.
    for direction in [-1.0, 1.0] {
        let mut q = q0.clone();
        while (-0.2..=0.6).contains(&(q[2] + direction * 0.01)) {
            q[2] += direction * 0.01;
            q = newton(&chain, &target, q, 2).expect("the arc continues");
            if within(&q) {
                assert!(covered(&cover, &q), "configuration {q:?} on the arc in no box");
            }
        }
    }
    // Every configuration at joint_3 = 0.1 that Newton reaches from a random start.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = |lo: f64, hi: f64| {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut found = 0;
    for _ in 0..150 {
        let start: Vec<f64> = (0..7).map(|k| if k == 2 { 0.1 } else { uniform(limits[k].0, limits[k].1) }).collect();
        if let Some(q) = newton(&chain, &target, start, 2).filter(|q| within(q)) {
            assert!(covered(&cover, &q), "configuration {q:?} at joint_3 = 0.1 in no box");
            found += 1;
        }
    }
    assert!(found > 0, "Newton found no configuration at joint_3 = 0.1");
    // Certified boxes hold the configuration at their centre's parameter.
    for (b, _) in cover.boxes.iter().filter(|(_, t)| t == "unique").step_by(97) {
        let centre: Vec<f64> = b.iter().map(|x| 0.5 * (x[0] + x[1])).collect();
        let q = newton(&chain, &target, centre, 2).expect("Newton converges in a certified box");
        assert!(b.iter().zip(&q).all(|(x, v)| x[0] - 1e-9 <= *v && *v <= x[1] + 1e-9), "{q:?} left its certified box {b:?}");
    }
}

/// Bad input is refused in one line naming it.
#[test]
fn bad_self_motion_input_is_one_line() {
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_linkspace")).arg("self-motion").args(args).output().expect("runs");
        assert!(!out.status.success(), "{args:?} should fail");
        String::from_utf8_lossy(&out.stderr).trim().to_string()
    };
    let pose = "0.4,0.1,0.6,0,3.14159,0";
    let ur5 = concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/ur5.urdf");
    for (args, needle) in [
        (vec![ur5, "--pose", pose], "the longest revolute path of 'ur5' has 6"),
        (vec![IIWA, "--pose", pose, "--parameter", "joint_9"], "'joint_9' is not a joint of the file"),
        (vec![IIWA, "--pose", pose, "--cell", "0"], "the cell width must be a number of radians in (0, 1]"),
        (vec![IIWA, "--pose", pose, "--range", "3,4"], "--range 3,4: not an interval that meets the range of 'joint_3'"),
        (vec![IIWA, "--pose", pose, "--fix", "joint_3=0"], "self-motion holds no joint"),
    ] {
        let err = run(&args);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: '{err}' should say '{needle}'");
    }
}

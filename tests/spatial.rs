//! Test idea: solve spatial linkages from URDF through the spatial builder (`formulate::spatial`)
//! and compare with references that never call the solver: closed forms of the Bennett
//! linkage's input–output relation, of the RSSR four-bar (a distance, linear in cos φ, sin φ for
//! a fixed crank) and of the spherical four-bar (an angle between two axes, linear likewise).
//! Soundness: every reference point lies in some box. Tightness: every box lies near the
//! reference set. And the planar fixtures give the same answers through both builders.

use crate::util::{problem, urdf_text};
use linkspace::kernel::interval::components;
use linkspace::model::urdf;
use linkspace::app::SolveRun;
use linkspace::formulate::Coordinates;
use linkspace::formulate::{Linkage, LinkageError, Model, ModelChoice, PoseProblem, PoseRows, SpatialProblem};
use linkspace::kernel::search::BoxStatus;
use linkspace::kernel::search::{Enclosure, SolverSettings};
use linkspace::app::Status;
use linkspace::kernel::interval::IntervalBox;
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::sync::atomic::AtomicBool;

fn spatial(name: &str, fixed: &[(&str, f64)]) -> SpatialProblem {
    let m = urdf::parse(&urdf_text(name)).expect("bundled URDF parses");
    let fixed: Vec<(String, f64)> = fixed.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    SpatialProblem::new(&m, &fixed, &[]).expect("bundled mechanism builds")
}

fn enclose(system: &linkspace::kernel::search::Solver<'_>) -> Enclosure {
    let e = system.enclose(&AtomicBool::new(false), &mut |_| {});
    assert_eq!(e.status, Status::Finished);
    e
}

fn solve(p: &SpatialProblem, sigma: f64) -> Enclosure {
    enclose(&p.solver(SolverSettings { sigma, ..Default::default() }).expect("valid settings"))
}

/// `v` lies in `[lo, hi]` modulo 2π (angles) or plainly, with `slack`.
fn holds(iv: (f64, f64), v: f64, angle: bool, slack: f64) -> bool {
    if !angle {
        return iv.0 - slack <= v && v <= iv.1 + slack;
    }
    let mid = 0.5 * (iv.0 + iv.1);
    let v = v - TAU * ((v - mid) / TAU).round();
    iv.0 - slack <= v && v <= iv.1 + slack
}

/// Does some box hold every named joint value?
fn covered(p: &SpatialProblem, boxes: &[IntervalBox], want: &[(&str, f64)], slack: f64) -> bool {
    boxes.iter().any(|b| {
        let j = p.joint_values(b);
        want.iter().all(|(n, v)| holds(j[*n], *v, true, slack))
    })
}

fn mid(iv: (f64, f64)) -> f64 {
    0.5 * (iv.0 + iv.1)
}

// ---------- RSSR: crank about z through the origin (length 1), rocker about y through (3, 0, 1)
// (length 1.5), coupler 3.2 ----------

/// Both rocker angles for crank angle `t`: `P cos φ + Q sin φ = R` from `|B − A|² = L²`.
fn rssr_closed_form(t: f64) -> Vec<f64> {
    let (l, r2) = (3.2f64, 1.5f64);
    let (ax, ay) = (t.cos(), t.sin());
    let dx = 3.0 - ax;
    // |(dx + r2 c, −ay, 1 − r2 s)|² = dx² + ay² + 1 + r2² + 2 r2 dx c − 2 r2 s
    let (p, q) = (2.0 * r2 * dx, -2.0 * r2);
    let r = l * l - dx * dx - ay * ay - 1.0 - r2 * r2;
    let h = p.hypot(q);
    if r.abs() > h {
        return Vec::new();
    }
    let base = q.atan2(p);
    let spread = (r / h).acos();
    vec![base + spread, base - spread]
}

#[test]
fn rssr_has_both_assembly_modes_certified_for_a_fixed_crank() {
    for t in [0.6, -1.0, 2.0, 3.0] {
        let p = spatial("rssr.urdf", &[("crank_joint", t)]);
        assert!(p.is_square(), "a fixed crank leaves a square system");
        assert_eq!(p.reductions.len(), 1, "the coupler becomes a distance: {:?}", p.reductions);
        let e = solve(&p, 1e-6);
        let reference = rssr_closed_form(t);
        assert_eq!(reference.len(), 2, "crank {t}: the fixture assembles in two modes");
        assert_eq!(e.solutions.len(), 2, "crank {t}: one box per mode");
        assert!(e.tags.iter().all(|&t| t == linkspace::app::BoxStatus::Unique), "crank {t}: both modes certified by Krawczyk");
        for phi in reference {
            assert!(covered(&p, &e.solutions, &[("rocker_joint", phi)], 1e-12), "crank {t}: rocker {phi} in no box");
        }
    }
}

#[test]
fn rssr_configuration_curve_is_covered_and_tight() {
    let p = spatial("rssr.urdf", &[]);
    let sigma = 0.02;
    let e = solve(&p, sigma);
    let mut points = 0;
    for k in 0..200 {
        let t = -PI + TAU * (k as f64 + 0.5) / 200.0;
        for phi in rssr_closed_form(t) {
            points += 1;
            assert!(covered(&p, &e.solutions, &[("crank_joint", t), ("rocker_joint", phi)], 1e-12), "({t}, {phi}) in no box");
        }
    }
    assert!(points > 100, "the sweep crosses the curve");
    // Every box lies near the curve: the distance residual at its midpoint is of order sigma.
    for b in &e.solutions {
        let j = p.joint_values(b);
        let (t, phi) = (mid(j["crank_joint"]), mid(j["rocker_joint"]));
        let a = [t.cos(), t.sin(), 0.0];
        let bb = [3.0 + 1.5 * phi.cos(), 0.0, 1.0 - 1.5 * phi.sin()];
        let d = ((bb[0] - a[0]).powi(2) + (bb[1] - a[1]).powi(2) + (bb[2] - a[2]).powi(2)).sqrt();
        assert!((d - 3.2).abs() < 10.0 * sigma, "box at ({t}, {phi}) is {d} apart, far from the curve");
    }
}

#[test]
fn rssr_poses_and_3d_traces_match_the_closed_form() {
    let m = urdf::parse(&urdf_text("rssr.urdf")).expect("parses");
    let t = 0.6;
    let p = SpatialProblem::new(&m, &[("crank_joint".into(), t)], &[("rocker".into(), [1.5, 0.0, 0.0], "rocker@1.5,0,0".into())]).expect("builds");
    let e = solve(&p, 1e-6);
    for phi in rssr_closed_form(t) {
        let want = [3.0 + 1.5 * phi.cos(), 0.0, 1.0 - 1.5 * phi.sin()];
        let b = e
            .solutions
            .iter()
            .find(|b| holds(p.joint_values(b)["rocker_joint"], phi, true, 1e-12))
            .expect("the mode is covered");
        let tr = &p.traces[0];
        for (i, w) in want.iter().enumerate() {
            let d = b.dims[tr.xyz[i]];
            assert!(d.inf() - 1e-12 <= *w && *w <= d.sup() + 1e-12, "trace coordinate {i}: {w} not in {d:?}");
        }
        let poses = p.link_poses(b);
        let rocker = &poses["rocker"];
        let q = rocker.quaternion.expect("the rocker's rotation is known");
        // A turn by φ about y: (cos φ/2, 0, sin φ/2, 0) up to sign.
        let (w, y) = ((phi / 2.0).cos(), (phi / 2.0).sin());
        let same = (q[0] - w).abs() + q[1].abs() + (q[2] - y).abs() + q[3].abs();
        let flipped = (q[0] + w).abs() + q[1].abs() + (q[2] + y).abs() + q[3].abs();
        assert!(same.min(flipped) < 1e-5, "rocker quaternion {q:?} for φ = {phi}");
        let pos = rocker.position.expect("placed");
        assert!(pos[0][0] <= 3.0 && 3.0 <= pos[0][1] && pos[2][0] <= 1.0 && 1.0 <= pos[2][1]);
        // The coupler spins between its balls: its position is its first ball, its rotation unknown.
        assert!(poses["coupler"].quaternion.is_none());
        let c = poses["coupler"].position.expect("the first ball");
        assert!(c[0][0] <= t.cos() + 1e-12 && t.cos() - 1e-12 <= c[0][1]);
    }
}

// ---------- Spherical four-bar: u1 = z, u4 = Ry(1) z, u2 = Ry(0.5) z on the crank, the closing
// axis Ry(1.4) z on the coupler and Ry(1.8) z on the rocker ----------

fn rotate(a: [f64; 3], t: f64, v: [f64; 3]) -> [f64; 3] {
    let (c, s) = (t.cos(), t.sin());
    let d = a[0] * v[0] + a[1] * v[1] + a[2] * v[2];
    let x = [a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]];
    [0, 1, 2].map(|i| v[i] * c + x[i] * s + a[i] * d * (1.0 - c))
}

fn ry(t: f64) -> [f64; 3] {
    [t.sin(), 0.0, t.cos()]
}

/// Both rocker angles for crank angle `t`: `u2(t)·Rot(u4, φ) w0 = cos 0.9`.
fn spherical_closed_form(t: f64) -> Vec<f64> {
    let u2 = rotate([0.0, 0.0, 1.0], t, ry(0.5));
    let (u4, w0) = (ry(1.0), ry(1.8));
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let d = dot(u4, w0);
    let p = dot(u2, [0, 1, 2].map(|i| w0[i] - u4[i] * d));
    let x = [u4[1] * w0[2] - u4[2] * w0[1], u4[2] * w0[0] - u4[0] * w0[2], u4[0] * w0[1] - u4[1] * w0[0]];
    let q = dot(u2, x);
    let r = 0.9f64.cos() - dot(u2, u4) * d;
    let h = p.hypot(q);
    if r.abs() > h {
        return Vec::new();
    }
    let (base, spread) = (q.atan2(p), (r / h).acos());
    vec![base + spread, base - spread]
}

#[test]
fn spherical_four_bar_modes_and_curve_match_the_closed_form() {
    for t in [0.4, 2.0, -2.5] {
        let p = spatial("spherical_four_bar.urdf", &[("crank_joint", t)]);
        assert!(p.is_square(), "crank {t}: the closing axes give two rows, the system is square");
        let e = solve(&p, 1e-6);
        assert_eq!(components(&e.solutions).1, 2, "crank {t}: two assembly modes");
        assert_eq!(e.tags.iter().filter(|&&t| t == linkspace::app::BoxStatus::Unique).count(), 2, "crank {t}: both modes certified");
        for phi in spherical_closed_form(t) {
            assert!(covered(&p, &e.solutions, &[("rocker_joint", phi)], 1e-12), "crank {t}: rocker {phi} in no box");
        }
    }
    let p = spatial("spherical_four_bar.urdf", &[]);
    let sigma = 0.02;
    let e = solve(&p, sigma);
    assert_eq!(components(&e.solutions).1, 2, "the crank turns fully on two branches");
    for k in 0..100 {
        let t = -PI + TAU * (k as f64 + 0.5) / 100.0;
        for phi in spherical_closed_form(t) {
            assert!(covered(&p, &e.solutions, &[("crank_joint", t), ("rocker_joint", phi)], 1e-12), "({t}, {phi}) in no box");
        }
    }
    for b in &e.solutions {
        let j = p.joint_values(b);
        let (t, phi) = (mid(j["crank_joint"]), mid(j["rocker_joint"]));
        let u2 = rotate([0.0, 0.0, 1.0], t, ry(0.5));
        let u3 = rotate(ry(1.0), phi, ry(1.8));
        let angle = (u2[0] * u3[0] + u2[1] * u3[1] + u2[2] * u3[2]).clamp(-1.0, 1.0).acos();
        assert!((angle - 0.9).abs() < 10.0 * sigma, "box at ({t}, {phi}): coupler arc {angle}");
    }
}

// ---------- Bennett: DH links (1, π/6), (2, π/2), (1, π/6), (2, π/2) ----------

fn bennett_k() -> f64 {
    let (a, b) = (PI / 6.0, PI / 2.0);
    ((b + a) / 2.0).sin() / ((b - a) / 2.0).sin()
}

/// `tan(θ1/2)·tan(θ2/2) = K`, `θ3 = −θ1`, `θ4 = −θ2`.
fn bennett_closed_form(t1: f64) -> [f64; 4] {
    let t2 = 2.0 * (bennett_k() / (t1 / 2.0).tan()).atan();
    [t1, t2, -t1, -t2]
}

#[test]
fn bennett_curve_matches_bennetts_relation() {
    let p = spatial("bennett.urdf", &[]);
    let sigma = 0.02;
    let e = solve(&p, sigma);
    assert_eq!(components(&e.solutions).1, 1, "one closed curve");
    let names = ["joint1", "joint2", "joint3", "joint4"];
    for k in 0..100 {
        let t1 = -PI + TAU * (k as f64 + 0.5) / 100.0;
        let r = bennett_closed_form(t1);
        let want: Vec<(&str, f64)> = names.iter().copied().zip(r).collect();
        assert!(covered(&p, &e.solutions, &want, 1e-9), "{want:?} in no box");
    }
    let k = bennett_k();
    for b in &e.solutions {
        let j = p.joint_values(b);
        let (t1, t2) = (mid(j["joint1"]), mid(j["joint2"]));
        // sin(θ1/2) sin(θ2/2) − K cos(θ1/2) cos(θ2/2) = 0, bounded derivatives: O(sigma) off.
        let res = (t1 / 2.0).sin() * (t2 / 2.0).sin() - k * (t1 / 2.0).cos() * (t2 / 2.0).cos();
        assert!(res.abs() < 20.0 * sigma, "box at ({t1}, {t2}): residual {res}");
        let t3 = mid(j["joint3"]);
        assert!(holds(j["joint3"], -t1, true, 10.0 * sigma), "joint3 {t3} is not −joint1 {t1}");
    }
    // A fixed input leaves one configuration.
    for t1 in [1.0, -2.0] {
        let p = spatial("bennett.urdf", &[("joint1", t1)]);
        let e = solve(&p, 1e-6);
        assert_eq!(components(&e.solutions).1, 1, "joint1 = {t1}: one configuration");
        let r = bennett_closed_form(t1);
        assert!(covered(&p, &e.solutions, &[("joint2", r[1]), ("joint3", r[2]), ("joint4", r[3])], 1e-9), "joint1 = {t1}: {r:?} in no box");
    }
}

// ---------- the planar fixtures through the spatial builder ----------

/// Planar and spatial runs of the same fixture: same boxes count and certificates, and every
/// planar box meets a spatial box in every joint (values within box widths).
fn same_answers(name: &str, fixed: &[(&str, f64)], sigma: f64) {
    let planar = problem(name, fixed, &[]);
    let settings = SolverSettings { sigma, ..Default::default() };
    let pe = enclose(&planar.solver(settings.clone()).expect("settings"));
    let sp = spatial(name, fixed);
    let se = enclose(&sp.solver(settings).expect("settings"));
    assert_eq!(components(&pe.solutions).1, components(&se.solutions).1, "{name} {fixed:?}: clusters");
    assert_eq!(pe.tags.iter().filter(|&&t| t == linkspace::app::BoxStatus::Unique).count(), se.tags.iter().filter(|&&t| t == linkspace::app::BoxStatus::Unique).count(), "{name} {fixed:?}: certified assemblies");
    let planar_names: Vec<String> = planar.free_joints.clone();
    assert_eq!(planar_names.iter().collect::<std::collections::BTreeSet<_>>(), sp.free_joints.iter().collect(), "{name}: the same free joints");
    let meets = |a: (f64, f64), b: (f64, f64)| {
        let shift = TAU * ((mid(a) - mid(b)) / TAU).round();
        a.0 <= b.1 + shift + 1e-9 && b.0 + shift <= a.1 + 1e-9
    };
    for b in &pe.solutions {
        let pj: BTreeMap<String, (f64, f64)> = planar.joint_values(b);
        let found = se.solutions.iter().any(|s| {
            let sj = sp.joint_values(s);
            pj.iter().all(|(n, &iv)| if n.starts_with("slider") { iv.0 <= sj[n].1 + 1e-9 && sj[n].0 <= iv.1 + 1e-9 } else { meets(iv, sj[n]) })
        });
        assert!(found, "{name} {fixed:?}: planar box {pj:?} meets no spatial box");
    }
}

#[test]
fn planar_fixtures_give_the_same_answers_through_the_spatial_builder() {
    for t in [0.5, 2.0, -1.3] {
        same_answers("four_bar.urdf", &[("crank_joint", t)], 1e-6);
    }
    for t in [1.0, -2.5] {
        same_answers("slider_crank.urdf", &[("crank_joint", t)], 1e-6);
    }
    same_answers("watt_six_bar.urdf", &[("crank_joint", 0.7)], 1e-6);
    same_answers("five_bar.urdf", &[("crank1_joint", 1.8), ("crank2_joint", 1.2)], 1e-6);
    same_answers("double_butterfly.urdf", &[("joint6", 1.1760052070951352)], 1e-6);
}

// ---------- bad input: one error value, never a panic ----------

#[test]
fn bad_spatial_input_is_one_clear_error() {
    let build = |text: &str| SpatialProblem::new(&urdf::parse(text).expect("parses"), &[], &[]).map(|_| ()).expect_err("refused");
    // A coupler of 30 cannot reach from the crank to the rocker.
    let long = urdf_text("rssr.urdf").replace("xyz=\"3.2 0 0\"", "xyz=\"30 0 0\"");
    assert_eq!(build(&long), LinkageError::CannotClose("rocker_ball".into()));
    // A ball joint on no loop: the link's orientation is free.
    let dangling = urdf_text("rssr.urdf").replace(
        "<loop name=\"rocker_ball\"",
        "<link name=\"flail\"/><joint name=\"flail_ball\" type=\"spherical\"><parent link=\"rocker\"/><child link=\"flail\"/></joint>\n  <loop name=\"rocker_ball\"",
    );
    assert!(matches!(build(&dangling), LinkageError::UnderConstrained(ref s) if s.contains("flail_ball")));
    // Tracing a point of a rod that spins between its balls.
    let m = urdf::parse(&urdf_text("rssr.urdf")).expect("parses");
    let e = SpatialProblem::new(&m, &[], &[("coupler".into(), [1.0, 0.0, 0.0], "coupler@1,0,0".into())]).map(|_| ()).expect_err("refused");
    assert!(matches!(e, LinkageError::UnderConstrained(ref s) if s.contains("spins freely")), "{e}");
    // A ball joint cannot be fixed to a value, and the refusal says it is a ball joint.
    let e = SpatialProblem::new(&m, &[("coupler_ball".into(), 1.0)], &[]).map(|_| ()).expect_err("refused");
    assert_eq!(e, LinkageError::NotOneValue("coupler_ball".into(), "ball"));
    // Unsupported closure types are refused by the reader, with the type named.
    let odd = urdf_text("rssr.urdf").replace("type=\"spherical\">\n    <predecessor", "type=\"planar\">\n    <predecessor");
    let e = urdf::parse(&odd).expect_err("refused").to_string();
    assert!(e.contains("planar") && e.contains("rocker_ball"), "{e}");
    // A universal loop needs its second axis.
    let u = urdf_text("rssr.urdf").replace("type=\"spherical\">\n    <predecessor", "type=\"universal\">\n    <predecessor");
    assert!(urdf::parse(&u).expect_err("refused").to_string().contains("axis2"));
}

// ---------- the other closure types: a weld, a universal joint, a cylindrical joint ----------

#[test]
fn weld_and_universal_closures_hold_their_constraints() {
    // The four-bar's coupler–rocker pin welded at the angle the closed form gives: one pose.
    let t = 0.5;
    let p = spatial("four_bar.urdf", &[("crank_joint", t)]);
    let e = solve(&p, 1e-6);
    let b = &e.solutions[0];
    let j = p.joint_values(b);
    let psi = mid(j["loop_coupler_rocker"]);
    let welded = urdf_text("four_bar.urdf").replace("type=\"revolute\">", "type=\"fixed\">").replace(
        "<successor link=\"rocker\"><origin xyz=\"3.5 0 0\" rpy=\"0 0 0\"/>",
        &format!("<successor link=\"rocker\"><origin xyz=\"3.5 0 0\" rpy=\"0 0 {}\"/>", -psi),
    );
    let m = urdf::parse(&welded).expect("parses");
    // Welded, the four-bar is a rigid triangle on the rocker: with the crank free, one pose
    // (the one above) up to the sigma of psi.
    let wp = SpatialProblem::new(&m, &[], &[]).expect("builds");
    let we = solve(&wp, 1e-4);
    assert!(!we.solutions.is_empty(), "the welded pose exists");
    assert!(we.solutions.iter().any(|s| holds(wp.joint_values(s)["crank_joint"], t, true, 1e-3)), "the weld holds the crank at {t}");
    // Universal: the RSSR with its rocker ball replaced by a universal joint whose axes are the
    // rocker's y and the coupler's z: more constrained than a ball, so every configuration of
    // the universal version is one of the RSSR's (the closure points still coincide).
    let u = urdf_text("rssr.urdf")
        .replace("type=\"spherical\">\n    <predecessor", "type=\"universal\">\n    <predecessor")
        .replace("<successor link=\"rocker\"><origin xyz=\"1.5 0 0\" rpy=\"0 0 0\"/></successor>", "<successor link=\"rocker\"><origin xyz=\"1.5 0 0\" rpy=\"0 0 0\"/></successor><axis xyz=\"0 0 1\"/><axis2 xyz=\"0 1 0\"/>");
    let m = urdf::parse(&u).expect("parses");
    let up = SpatialProblem::new(&m, &[("crank_joint".into(), 0.6)], &[]).expect("builds");
    let ue = solve(&up, 0.05);
    assert!(!ue.solutions.is_empty(), "the universal closure assembles");
    for s in &ue.solutions {
        let phi = up.joint_values(s)["rocker_joint"];
        let near = rssr_closed_form(0.6).into_iter().any(|r| holds(phi, r, true, 0.2));
        assert!(near, "universal-closure box at rocker {phi:?} is no RSSR configuration");
    }
}

#[test]
fn cylindrical_closure_slides_and_turns_about_its_axis() {
    // An arm turning about z at the origin, closed onto a ground rail along x through
    // (2, 0, 0) by a cylindrical joint at the arm's origin: the arm must lie along +x (the sign
    // filter removes the mirror along −x), the closure slides 2 and does not turn.
    let text = "<robot name='rail'><link name='ground'/><link name='arm'/>\
        <joint name='swing' type='continuous'><parent link='ground'/><child link='arm'/><axis xyz='0 0 1'/></joint>\
        <loop name='sleeve' type='cylindrical'><predecessor link='arm'/><successor link='ground'><origin xyz='2 0 0'/></successor>\
        <axis xyz='1 0 0'/><limit lower='-5' upper='5'/></loop></robot>";
    let m = urdf::parse(text).expect("parses");
    let p = SpatialProblem::new(&m, &[], &[]).expect("builds");
    assert_eq!(p.free_joints, vec!["swing".to_string(), "sleeve".into(), "sleeve.travel".into()]);
    let e = solve(&p, 1e-6);
    assert_eq!(components(&e.solutions).1, 1, "one configuration, not its mirror");
    let j = p.joint_values(&e.solutions[0]);
    assert!(holds(j["swing"], 0.0, true, 1e-9) && holds(j["sleeve"], 0.0, true, 1e-9) && holds(j["sleeve.travel"], 2.0, false, 1e-9), "{j:?}");
}

// ---------- delta robot and 6-6 Stewart platform: references from scripts/dev (refs12),
// computed without linkspace: closed-form three-sphere intersection, and monodromy + homotopy
// continuation refined in mpmath ----------

fn reference(name: &str) -> serde_json::Value {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).expect("reference file")).expect("valid json")
}

/// `--fix` values as the references state them (decimal strings, passed as written).
fn fixed_from(case: &serde_json::Value, key: &str) -> Vec<(String, f64)> {
    case[key].as_object().expect("object").iter().map(|(k, v)| (k.clone(), v.as_str().expect("decimal string").parse().expect("number"))).collect()
}

#[test]
fn delta_forward_kinematics_has_both_assemblies_certified() {
    let refs = reference("delta_fk.json");
    let m = urdf::parse(&urdf_text("delta.urdf")).expect("parses");
    for case in refs["cases"].as_array().expect("cases") {
        let name = case["name"].as_str().expect("name");
        let fixed = fixed_from(case, "actuators");
        let p = SpatialProblem::new(&m, &fixed, &[]).expect("builds");
        assert_eq!(p.reductions.len(), 3, "{name}: three forearms become distances");
        assert!(p.is_square(), "{name}: forward kinematics is square");
        let e = solve(&p, 1e-7);
        let count = case["real_solutions"].as_u64().expect("count") as usize;
        assert_eq!(components(&e.solutions).1, count, "{name}: assemblies");
        assert!(e.tags.iter().all(|&t| t == linkspace::app::BoxStatus::Unique), "{name}: every box certified");
        for s in case["solutions"].as_array().expect("solutions") {
            let want: Vec<(&str, f64)> = ["platform_x", "platform_y", "platform_z"].iter().map(|&k| (k, s["joints"][k].as_f64().expect("number"))).collect();
            let found = e.solutions.iter().any(|b| {
                let j = p.joint_values(b);
                want.iter().all(|(k, v)| holds(j[*k], *v, false, 1e-12))
            });
            assert!(found, "{name}: assembly {want:?} in no box");
        }
    }
}

#[test]
fn stewart_platform_search_never_drops_a_reference_assembly() {
    // The whole search takes minutes (README; `stewart_platform_assemblies_are_all_certified`
    // runs it): a bounded run, in which solution and undecided boxes together must still hold
    // every real assembly.
    let refs = reference("stewart_6_6_fk.json");
    let m = urdf::parse(&urdf_text("stewart_6_6.urdf")).expect("parses");
    let case = &refs["cases"][0];
    let fixed = fixed_from(case, "leg_lengths");
    let p = SpatialProblem::new(&m, &fixed, &[]).expect("builds");
    assert_eq!(p.reductions.len(), 6, "six legs become distances");
    assert!(p.is_square(), "forward kinematics is square");
    let settings = SolverSettings { sigma: 1e-4, max_boxes: 400, ..Default::default() };
    let e = p.solver(settings).expect("settings").enclose(&AtomicBool::new(false), &mut |_| {});
    let mut all = e.solutions.clone();
    all.extend(e.undecided.iter().cloned());
    for s in case["solutions"].as_array().expect("solutions") {
        let pos = s["platform_position"].as_array().expect("xyz");
        let rpy = s["platform_rpy"].as_array().expect("rpy");
        let f = |v: &serde_json::Value| v.as_f64().expect("number");
        let want = [
            ("platform_pose.x", f(&pos[0]), false),
            ("platform_pose.y", f(&pos[1]), false),
            ("platform_pose.z", f(&pos[2]), false),
            ("platform_pose.yaw", f(&rpy[2]), true),
            ("platform_pose.pitch", f(&rpy[1]), true),
            ("platform_pose.roll", f(&rpy[0]), true),
        ];
        let found = all.iter().any(|b| {
            let j = p.joint_values(b);
            want.iter().all(|(k, v, angle)| holds(j[*k], *v, *angle, 1e-9))
        });
        assert!(found, "assembly at {pos:?}, rpy {rpy:?} in no box");
    }
}

/// The full forward kinematics of the 6-6 platform: every real assembly of the reference, each
/// in a certified box, and no other.
#[test]
#[ignore = "long: about 2.5 minutes on two shared cores"]
fn stewart_platform_assemblies_are_all_certified() {
    let refs = reference("stewart_6_6_fk.json");
    let m = urdf::parse(&urdf_text("stewart_6_6.urdf")).expect("parses");
    let case = &refs["cases"][0];
    let p = SpatialProblem::new(&m, &fixed_from(case, "leg_lengths"), &[]).expect("builds");
    let e = solve(&p, 1e-4);
    let count = case["real_solutions"].as_u64().expect("count") as usize;
    assert_eq!(components(&e.solutions).1, count, "real assemblies");
    assert!(e.tags.iter().all(|&t| t == linkspace::app::BoxStatus::Unique), "every box certified");
    // One certificate per assembly: two certified boxes of one assembly are merged.
    assert_eq!(e.solutions.len(), count, "certified boxes");
    let f = |v: &serde_json::Value| v.as_f64().expect("number");
    for s in case["solutions"].as_array().expect("solutions") {
        let (pos, rpy) = (&s["platform_position"], &s["platform_rpy"]);
        let found = e.solutions.iter().any(|b| {
            let j = p.joint_values(b);
            holds(j["platform_pose.x"], f(&pos[0]), false, 1e-9)
                && holds(j["platform_pose.y"], f(&pos[1]), false, 1e-9)
                && holds(j["platform_pose.z"], f(&pos[2]), false, 1e-9)
                && holds(j["platform_pose.yaw"], f(&rpy[2]), true, 1e-9)
                && holds(j["platform_pose.pitch"], f(&rpy[1]), true, 1e-9)
                && holds(j["platform_pose.roll"], f(&rpy[0]), true, 1e-9)
        });
        assert!(found, "assembly at {pos}, rpy {rpy} in no box");
    }
}

/// One case of a Stewart reference through `solve --model pose` (`app::SolveRun`, what the CLI
/// and the node run) at default settings: every real assembly in exactly one certified box, every
/// box certified and holding one of them, the joint values (position, roll, pitch, yaw) enclosing
/// the reference's.
fn stewart_pose_case(index: usize) {
    stewart_pose_reference_case("stewart_6_6.urdf", "stewart_6_6_fk.json", index);
}

fn stewart_pose_reference_case(platform: &str, reference_file: &str, index: usize) {
    let refs = reference(reference_file);
    let m = urdf::parse(&urdf_text(platform)).expect("parses");
    let case = &refs["cases"][index];
    let name = case["name"].as_str().expect("name");
    let fixed = fixed_from(case, "leg_lengths");
    let job = SolveRun::build(&m, ModelChoice::Pose, &fixed, &[], SolverSettings { threads: 1, ..Default::default() }).expect("builds");
    assert_eq!(job.problem().model(), Model::Pose);
    let r = job.run(&AtomicBool::new(false), &mut |_| {});
    assert_eq!(r.status, Status::Finished, "{name}");
    let count = case["real_solutions"].as_u64().expect("count") as usize;
    assert!(r.boxes.iter().all(|b| b.status == BoxStatus::Unique), "{name}: every box certified: {:?}", r.boxes.iter().map(|b| b.status).collect::<Vec<_>>());
    assert_eq!(r.boxes.len(), count, "{name}: one box per real assembly");
    let var = |n: &str| r.variables.iter().position(|v| v == n).expect("pose variable");
    let position = ["tx", "ty", "tz"].map(var);
    let rotation = [["R11", "R12", "R13"], ["R21", "R22", "R23"], ["R31", "R32", "R33"]].map(|row| row.map(var));
    let f = |v: &serde_json::Value| v.as_f64().expect("number");
    let inside = |[lo, hi]: [f64; 2], v: f64| lo - 1e-12 <= v && v <= hi + 1e-12;
    let mut held = vec![0; r.boxes.len()];
    for s in case["solutions"].as_array().expect("solutions") {
        let pos = &s["platform_position"];
        let rot = &s["platform_rotation_matrix"];
        let holding: Vec<usize> = (0..r.boxes.len())
            .filter(|&k| {
                let b = &r.boxes[k].bounds;
                (0..3).all(|i| inside(b[position[i]], f(&pos[i])) && (0..3).all(|j| inside(b[rotation[i][j]], f(&rot[i][j]))))
            })
            .collect();
        assert_eq!(holding.len(), 1, "{name}: assembly at {pos} in {} certified boxes", holding.len());
        let k = holding[0];
        held[k] += 1;
        let joints: BTreeMap<&str, (f64, f64)> = r.joint_names.iter().map(|n| n.as_str()).zip(r.boxes[k].joints.iter().map(|j| (j[0], j[1]))).collect();
        let rpy = &s["platform_rpy"];
        for (joint, v, angle) in [("x", f(&pos[0]), false), ("y", f(&pos[1]), false), ("z", f(&pos[2]), false), ("roll", f(&rpy[0]), true), ("pitch", f(&rpy[1]), true), ("yaw", f(&rpy[2]), true)] {
            let j = joints[format!("platform_pose.{joint}").as_str()];
            assert!(holds(j, v, angle, 1e-9), "{name}: {joint} {v} outside {j:?}");
        }
    }
    assert!(held.iter().all(|&h| h == 1), "{name}: a certified box without a reference assembly: {held:?}");
}

#[test]
fn stewart_pose_model_certifies_each_assembly_once_from_pose() {
    stewart_pose_case(0);
}

#[test]
fn stewart_pose_model_certifies_each_assembly_once_many_real() {
    stewart_pose_case(1);
}

#[test]
fn stewart_pose_model_certifies_each_assembly_once_near_singular() {
    // Two assemblies 1.7e-3 apart: their cluster is searched again at finer sigmas.
    stewart_pose_case(2);
}

#[test]
fn stewart_pose_model_certifies_each_of_36_assemblies_once() {
    // Dietmaier's platform of 40 real assemblies, perturbed: 36 real, several near a singularity
    // (smallest singular values of the leg Jacobian 1.1e-3, 2.8e-3, 3.3e-3, 4.1e-3).
    let refs = reference("stewart_40_fk.json");
    assert_eq!(refs["cases"][0]["real_solutions"].as_u64(), Some(36));
    stewart_pose_reference_case("stewart_40.urdf", "stewart_40_fk.json", 0);
}

#[test]
fn stewart_pose_model_certifies_assemblies_near_a_singularity_once() {
    // The same platform perturbed less: 38 real, three with a leg Jacobian's smallest singular
    // value below 1.3e-4 (3.8e-5 the least), whose unproven boxes at sigma 1e-3 stretch 22 to
    // 31 sigmas along the near-null direction: each cluster is searched again at finer sigmas.
    let refs = reference("stewart_40_near_singular_fk.json");
    assert_eq!(refs["cases"][0]["real_solutions"].as_u64(), Some(38));
    stewart_pose_reference_case("stewart_40_near_singular.urdf", "stewart_40_near_singular_fk.json", 0);
}

#[test]
fn stewart_pose_model_certifies_two_assemblies_5e_5_apart_in_two_boxes() {
    // stewart_40.urdf at lengths across a fold of the leg map (scripts/dev/stewart_close_pair.py):
    // 28 real, two of them 5.4e-5 apart (position plus rotation, Frobenius), both with a leg
    // Jacobian's smallest singular value 8.8e-7.
    let refs = reference("stewart_40_close_pair_fk.json");
    let case = &refs["cases"][0];
    assert_eq!(case["real_solutions"].as_u64(), Some(28));
    let pose = |s: &serde_json::Value| -> Vec<f64> {
        let rows = s["platform_rotation_matrix"].as_array().expect("rows").iter().flat_map(|r| r.as_array().expect("row").clone());
        s["platform_position"].as_array().expect("position").iter().cloned().chain(rows).map(|v| v.as_f64().expect("number")).collect()
    };
    let poses: Vec<Vec<f64>> = case["solutions"].as_array().expect("solutions").iter().map(pose).collect();
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let distance = |a: &[f64], b: &[f64]| {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        norm(&d[..3]) + norm(&d[3..])
    };
    let closest = (0..poses.len()).flat_map(|i| (i + 1..poses.len()).map(move |j| (i, j))).map(|(i, j)| distance(&poses[i], &poses[j])).fold(f64::INFINITY, f64::min);
    assert!(closest < 1e-4, "the closest pair is {closest:e} apart");
    let stated = case["closest_real_pair"]["distance_position_plus_rotation_frobenius"].as_f64().expect("distance");
    assert!((closest - stated).abs() < 1e-9, "{closest:e} against the stated {stated:e}");
    stewart_pose_reference_case("stewart_40.urdf", "stewart_40_close_pair_fk.json", 0);
    // The diagnosis before the run tells isolated assemblies with a nearly singular Jacobian
    // from a curve of them.
    let m = urdf::parse(&urdf_text("stewart_40.urdf")).expect("parses");
    let job = SolveRun::build(&m, ModelChoice::Pose, &fixed_from(case, "leg_lengths"), &[], SolverSettings { threads: 1, ..Default::default() }).expect("builds");
    let (freedom, line) = job.freedom();
    assert_eq!(freedom.at_point.map(|l| (l.dof, l.nearly_singular)), Some((0, true)), "{line}");
    assert!(line.contains("isolated assemblies, some close together"), "{line}");
}

/// One case of a Stewart reference through `solve --model distances` at default settings: every
/// box certified, one per real assembly, each holding exactly one reference pose in its joint
/// values (position, roll, pitch, yaw).
fn stewart_distance_reference_case(platform: &str, reference_file: &str, index: usize) {
    let refs = reference(reference_file);
    let m = urdf::parse(&urdf_text(platform)).expect("parses");
    let case = &refs["cases"][index];
    let name = case["name"].as_str().expect("name");
    let fixed = fixed_from(case, "leg_lengths");
    let job = SolveRun::build(&m, ModelChoice::Distances, &fixed, &[], SolverSettings { threads: 1, ..Default::default() }).expect("builds");
    assert_eq!(job.problem().model(), Model::Distances);
    assert!(job.problem().system().vars.iter().any(|v| v.name.starts_with("r(P")), "squared distances are the unknowns");
    let r = job.run(&AtomicBool::new(false), &mut |_| {});
    assert_eq!(r.status, Status::Finished, "{name}");
    let count = case["real_solutions"].as_u64().expect("count") as usize;
    assert!(r.boxes.iter().all(|b| b.status == BoxStatus::Unique), "{name}: every box certified: {:?}", r.boxes.iter().map(|b| b.status).collect::<Vec<_>>());
    assert_eq!(r.boxes.len(), count, "{name}: one box per real assembly");
    let f = |v: &serde_json::Value| v.as_f64().expect("number");
    let mut held = vec![0; r.boxes.len()];
    for s in case["solutions"].as_array().expect("solutions") {
        let (pos, rpy) = (&s["platform_position"], &s["platform_rpy"]);
        let want = [("x", f(&pos[0]), false), ("y", f(&pos[1]), false), ("z", f(&pos[2]), false), ("roll", f(&rpy[0]), true), ("pitch", f(&rpy[1]), true), ("yaw", f(&rpy[2]), true)];
        let holding: Vec<usize> = (0..r.boxes.len())
            .filter(|&k| {
                let joints: BTreeMap<&str, (f64, f64)> = r.joint_names.iter().map(|n| n.as_str()).zip(r.boxes[k].joints.iter().map(|j| (j[0], j[1]))).collect();
                want.iter().all(|(joint, v, angle)| holds(joints[format!("platform_pose.{joint}").as_str()], *v, *angle, 1e-9))
            })
            .collect();
        assert_eq!(holding.len(), 1, "{name}: assembly at {pos}, rpy {rpy} in {} certified boxes", holding.len());
        held[holding[0]] += 1;
    }
    assert!(held.iter().all(|&h| h == 1), "{name}: a certified box without a reference assembly: {held:?}");
}

#[test]
fn stewart_distance_model_certifies_each_assembly_once_from_pose() {
    stewart_distance_reference_case("stewart_6_6.urdf", "stewart_6_6_fk.json", 0);
}

#[test]
fn a_platform_with_every_leg_fixed_gets_the_pose_model_by_default() {
    let refs = reference("stewart_6_6_fk.json");
    let m = urdf::parse(&urdf_text("stewart_6_6.urdf")).expect("parses");
    let fixed = fixed_from(&refs["cases"][0], "leg_lengths");
    let auto = Linkage::build(&m, ModelChoice::Auto, &fixed, &[]).expect("builds");
    assert_eq!(auto.model(), Model::Pose, "{}", auto.model_reason());
    // A leg left free: a curve of poses, in joint coordinates.
    let partial = Linkage::build(&m, ModelChoice::Auto, &fixed[1..], &[]).expect("builds");
    assert_eq!(partial.model(), Model::Spatial);
    // Forced, on a mechanism that is no platform: a clear refusal.
    let rssr = urdf::parse(&urdf_text("rssr.urdf")).expect("parses");
    let err = Linkage::build(&rssr, ModelChoice::Pose, &[], &[]).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("--model pose") && err.contains("not a parallel platform"), "{err}");
    let err = Linkage::build(&rssr, ModelChoice::Distances, &[], &[]).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(err.contains("not a parallel platform"), "{err}");
    assert!(matches!(Linkage::build_in_joints(&m, ModelChoice::Distances, &fixed, &[]), Err(LinkageError::NotJointModel)));
    // The redundant rows narrow boxes but change no answer.
    let p = PoseProblem::with_rows(&m, &fixed, PoseRows::Redundant).expect("builds");
    assert!(!p.is_square());
    let e = enclose(&p.solver(SolverSettings::default()).expect("valid settings"));
    assert_eq!(components(&e.solutions).1, 8);
}

// ---------- soundness of every contractor on the spatial systems ----------

/// A true configuration of each fixture as a point in its system's variables: primaries from
/// the closed forms (or the Stewart reference), derived variables from their definitions.
fn true_point(which: usize, at: f64) -> (SpatialProblem, Vec<f64>, String) {
    let set = |p: &SpatialProblem, x: &mut Vec<f64>, name: &str, v: f64| {
        let i = p.system.var(name).unwrap_or_else(|| panic!("variable {name}"));
        x[i] = v;
    };
    let angle = |p: &SpatialProblem, x: &mut Vec<f64>, joint: &str, t: f64| {
        set(p, x, &format!("cos_{joint}"), t.cos());
        set(p, x, &format!("sin_{joint}"), t.sin());
    };
    let t = -PI + TAU * at;
    let (p, mut x, what) = match which {
        0 => {
            let p = spatial("bennett.urdf", &[]);
            let mut x = vec![f64::NAN; p.system.vars.len()];
            let r = bennett_closed_form(t);
            for (k, j) in ["joint1", "joint2", "joint3"].iter().enumerate() {
                angle(&p, &mut x, j, r[k]);
            }
            (p, x, format!("Bennett at joint1 = {t}"))
        }
        1 => {
            let p = spatial("rssr.urdf", &[]);
            let mut x = vec![f64::NAN; p.system.vars.len()];
            // A crank angle where the RSSR assembles, on one of its two modes.
            let t = 0.6 + 0.5 * (at - 0.5);
            let phi = rssr_closed_form(t)[usize::from(at > 0.5)];
            angle(&p, &mut x, "crank_joint", t);
            angle(&p, &mut x, "rocker_joint", phi);
            (p, x, format!("RSSR at crank {t}, rocker {phi}"))
        }
        2 => {
            let p = spatial("spherical_four_bar.urdf", &[]);
            let mut x = vec![f64::NAN; p.system.vars.len()];
            let phi = spherical_closed_form(t)[0];
            // The coupler's own angle: the turn about u2 that brings Ry(1.4) z onto u3.
            let u2 = rotate([0.0, 0.0, 1.0], t, ry(0.5));
            let u3 = rotate(ry(1.0), phi, ry(1.8));
            let w = rotate([0.0, 0.0, 1.0], t, ry(1.4));
            let along = |v: [f64; 3]| { let d = v[0] * u2[0] + v[1] * u2[1] + v[2] * u2[2]; [v[0] - d * u2[0], v[1] - d * u2[1], v[2] - d * u2[2]] };
            let (a, b) = (along(w), along(u3));
            let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            let psi = (cross[0] * u2[0] + cross[1] * u2[1] + cross[2] * u2[2]).atan2(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
            angle(&p, &mut x, "crank_joint", t);
            angle(&p, &mut x, "coupler_joint", psi);
            angle(&p, &mut x, "rocker_joint", phi);
            (p, x, format!("spherical four-bar at crank {t}"))
        }
        _ => {
            let refs = reference("stewart_6_6_fk.json");
            let case = &refs["cases"][0];
            let m = urdf::parse(&urdf_text("stewart_6_6.urdf")).expect("parses");
            let p = SpatialProblem::new(&m, &fixed_from(case, "leg_lengths"), &[]).expect("builds");
            let sols = case["solutions"].as_array().expect("solutions");
            let s = &sols[((at * sols.len() as f64) as usize).min(sols.len() - 1)];
            let f = |v: &serde_json::Value| v.as_f64().expect("number");
            let mut x = vec![f64::NAN; p.system.vars.len()];
            for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                set(&p, &mut x, &format!("platform_pose.{axis}"), f(&s["platform_position"][k]));
            }
            for (k, part) in ["roll", "pitch", "yaw"].iter().enumerate() {
                angle(&p, &mut x, &format!("platform_pose.{part}"), f(&s["platform_rpy"][k]));
            }
            (p, x, format!("Stewart assembly at {}", s["platform_position"]))
        }
    };
    assert!(p.complete_point(&mut x), "{what}: every derived variable follows");
    for e in &p.system.equations {
        assert!(e.residual(&x).abs() < 1e-9, "{what}: the point solves the system (residual {})", e.residual(&x));
    }
    (p, x, what)
}

// A box around a true configuration never loses it, whatever the box, under every contractor.
proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
    #[test]
    fn no_contractor_removes_a_true_spatial_configuration(which in 0usize..4, at in 0.01f64..0.99, widths in proptest::collection::vec(1e-6f64..0.6, 16), offsets in proptest::collection::vec(0.0f64..1.0, 16)) {
        use linkspace::kernel::contract::{Contraction, Contractor, LpShrink, Newton, Propagation};
        let (p, x, what) = true_point(which, at);
        let mut b = p.system.initial_box();
        for (i, d) in b.dims.iter_mut().enumerate() {
            let (w, f) = (widths[i % 16], offsets[i % 16]);
            let lo = (x[i] - w * f - 1e-9).max(d.inf());
            let hi = (x[i] + w * (1.0 - f) + 1e-9).min(d.sup());
            *d = linkspace::kernel::interval::interval(lo, hi);
        }
        let inside = |b: &IntervalBox| b.dims.iter().zip(&x).all(|(d, &v)| d.inf() - 1e-9 <= v && v <= d.sup() + 1e-9);
        proptest::prop_assert!(inside(&b), "{}: the start box holds the point (domains enclose it)", what);
        let mut steps: Vec<Box<dyn Contractor>> = vec![Box::new(Propagation::new(&p.system)), Box::new(LpShrink::new(&p.system))];
        if let Some(n) = Newton::new(&p.system, 1.0) {
            steps.push(Box::new(n));
        }
        for step in &mut steps {
            let mut c = b.clone();
            for _ in 0..3 {
                proptest::prop_assert_ne!(step.contract(&mut c), Contraction::Empty, "{} emptied a box holding {}", step.name(), what);
            }
            proptest::prop_assert!(inside(&c), "{} cut the true configuration {}", step.name(), what);
        }
        proptest::prop_assert!(p.limit_verdict(&b) != linkspace::kernel::contract::Inclusion::Outside, "the filters drop {}", what);
    }
}

#[test]
fn a_rod_with_welded_frames_is_still_a_distance() {
    // A marker frame welded to the RSSR's coupler, with the ball closure moved onto it: the
    // same mechanism, so the same two certified modes.
    let text = urdf_text("rssr.urdf")
        .replace(
            "<loop name=\"rocker_ball\"",
            "<link name=\"marker\"/><joint name=\"marker_weld\" type=\"fixed\"><parent link=\"coupler\"/><child link=\"marker\"/><origin xyz=\"1 0 0\" rpy=\"0 0 1.5707963267948966\"/></joint>\n  <loop name=\"rocker_ball\"",
        )
        .replace("<predecessor link=\"coupler\"><origin xyz=\"3.2 0 0\"", "<predecessor link=\"marker\"><origin xyz=\"0 -2.2 0\"");
    let m = urdf::parse(&text).expect("parses");
    let p = SpatialProblem::new(&m, &[("crank_joint".into(), 0.6)], &[]).expect("builds");
    assert_eq!(p.reductions.len(), 1, "{:?}", p.reductions);
    assert!(p.is_square());
    let e = solve(&p, 1e-6);
    assert_eq!(e.solutions.len(), 2);
    assert!(e.tags.iter().all(|&t| t == linkspace::app::BoxStatus::Unique));
    for phi in rssr_closed_form(0.6) {
        assert!(covered(&p, &e.solutions, &[("rocker_joint", phi)], 1e-9), "rocker {phi} in no box");
    }
}

// ---------- placement: the same certified answers wherever the mechanism stands ----------

/// `xml` hung from a new root link by a fixed joint at `xyz`, `rpy`, written as given (short,
/// truncated decimals, as vendor files write them).
fn placed(xml: &str, xyz: &str, rpy: &str) -> String {
    let children: Vec<&str> = xml.split("<child link=\"").skip(1).map(|s| &s[..s.find('"').expect("closing quote")]).collect();
    let root = xml
        .split("<link name=\"")
        .skip(1)
        .map(|s| &s[..s.find('"').expect("closing quote")])
        .find(|l| !children.contains(l))
        .expect("a root link");
    let placement = format!("<link name=\"placement_world\"/>\n  <joint name=\"placement\" type=\"fixed\"><parent link=\"placement_world\"/><child link=\"{root}\"/><origin xyz=\"{xyz}\" rpy=\"{rpy}\"/></joint>\n  ");
    let at = xml.find("<link ").expect("a link");
    format!("{}{placement}{}", &xml[..at], &xml[at..])
}

/// Proven boxes, all boxes, undecided boxes.
fn certified_counts(xml: &str, fixed: &[(&str, f64)]) -> (usize, usize, usize) {
    let m = urdf::parse(xml).expect("parses");
    let fixed: Vec<(String, f64)> = fixed.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    let p = SpatialProblem::new(&m, &fixed, &[]).expect("builds");
    let e = solve(&p, 1e-6);
    (e.tags.iter().filter(|t| **t == linkspace::app::BoxStatus::Unique).count(), e.solutions.len(), e.undecided.len())
}

/// Random rigid placements of the bundled spatial mechanisms (and of the planar four-bar taken
/// as spatial, turned about the normal of its plane), rpy truncated to a few decimals: the same
/// proven counts as at the origin. Closure rows that only rounding keeps from cancelling (the
/// same stated placement reached by two paths) must not make the system non-square.
///
/// A planar mechanism tilted out of its plane is not among them: taken as spatial, its axis rows
/// then hold unknowns whose coefficients vanish only to rounding (the model has more rows than
/// freedoms), which is why the builder's choice solves it planar.
#[test]
fn placement_in_space_does_not_change_the_certified_answers() {
    // File, fixed joints, and whether placements tilt it (else they only turn it about z).
    type Case = (&'static str, &'static [(&'static str, f64)], bool);
    let cases: [Case; 4] = [
        ("spherical_four_bar.urdf", &[("crank_joint", 0.4)], true),
        ("rssr.urdf", &[("crank_joint", 0.6)], true),
        ("four_bar.urdf", &[("crank_joint", 0.5)], false),
        ("delta.urdf", &[("actuator1", 0.2), ("actuator2", 0.75), ("actuator3", -0.1)], true),
    ];
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = |lo: f64, hi: f64| {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    for (file, fixed, tilt) in cases {
        let xml = urdf_text(file);
        let at_origin = certified_counts(&xml, fixed);
        assert!(at_origin.0 > 0 && at_origin.0 == at_origin.1 && at_origin.2 == 0, "{file} at the origin: {at_origin:?}");
        for k in 0..6 {
            let xyz = format!("{:.3} {:.3} {:.3}", uniform(-2.0, 2.0), uniform(-2.0, 2.0), uniform(-2.0, 2.0));
            let digits = 2 + k % 4;
            let (roll, pitch, yaw) = (uniform(-PI, PI), uniform(-1.5, 1.5), uniform(-PI, PI));
            let rpy = if tilt { format!("{roll:.digits$} {pitch:.digits$} {yaw:.digits$}") } else { format!("0 0 {yaw:.digits$}") };
            let moved = placed(&xml, &xyz, &rpy);
            assert_eq!(certified_counts(&moved, fixed), at_origin, "{file} placed at xyz {xyz}, rpy {rpy}");
        }
    }
    // The spherical four-bar with its centre written on both ground joints, off the origin.
    let xml = urdf_text("spherical_four_bar.urdf");
    let ground = |joint: &str, xml: &str| {
        let at = xml.find(&format!("<joint name=\"{joint}\"")).expect("joint");
        let origin = at + xml[at..].find("<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>").expect("origin");
        format!("{}<origin xyz=\"0.317 -1.25 2.09\" rpy=\"0.31 -0.7 2.5\"/>{}", &xml[..origin], &xml[origin + "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>".len()..])
    };
    let off = ground("rocker_joint", &ground("crank_joint", &xml));
    assert_eq!(certified_counts(&off, &[("crank_joint", 0.4)]), certified_counts(&xml, &[("crank_joint", 0.4)]));
}

/// However a file roots a six-legged platform — a world link above its base, a mounting plate
/// between the base and the legs, a tool flange on the platform, all by fixed joints, at random
/// placements written to a few decimals — the builder picks the pose model and certifies the
/// same assemblies as for the bundled file.
#[test]
fn fixed_joints_around_a_platform_change_neither_the_model_nor_the_assemblies() {
    let refs = reference("stewart_6_6_fk.json");
    let case = &refs["cases"][0];
    let fixed = fixed_from(case, "leg_lengths");
    let count = case["real_solutions"].as_u64().expect("count") as usize;
    let xml = urdf_text("stewart_6_6.urdf");
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = |lo: f64, hi: f64| {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    let mut variants = vec![("as bundled".to_string(), xml.clone())];
    for k in 0..3 {
        let xyz = format!("{:.3} {:.3} {:.3}", uniform(-2.0, 2.0), uniform(-2.0, 2.0), uniform(-2.0, 2.0));
        let digits = 2 + k;
        let rpy = format!("{:.digits$} {:.digits$} {:.digits$}", uniform(-PI, PI), uniform(-1.5, 1.5), uniform(-PI, PI));
        variants.push((format!("under a world link at xyz {xyz}, rpy {rpy}"), placed(&xml, &xyz, &rpy)));
    }
    // The legs hang from a plate fixed to the base; the platform carries a flange.
    let extra = "<link name=\"plate\"/>\n  <joint name=\"plate_mount\" type=\"fixed\"><parent link=\"base\"/><child link=\"plate\"/></joint>\n  <link name=\"flange\"/>\n  <joint name=\"flange_mount\" type=\"fixed\"><parent link=\"platform\"/><child link=\"flange\"/><origin xyz=\"0 0 0.05\" rpy=\"0 0 1.5708\"/></joint>\n  ";
    let at = xml.find("<link name=\"base\">").expect("base link");
    let mut plated = format!("{}{extra}{}", &xml[..at], &xml[at..]);
    for leg in 1..=6 {
        let joint = format!("<joint name=\"leg{leg}_base\" type=\"spherical\">\n    <parent link=\"base\"/>");
        assert!(plated.contains(&joint), "leg {leg}'s base joint");
        plated = plated.replace(&joint, &format!("<joint name=\"leg{leg}_base\" type=\"spherical\">\n    <parent link=\"plate\"/>"));
    }
    variants.push(("with a mounting plate and a flange".to_string(), plated.clone()));
    variants.push(("with a plate and a flange, under a world link".to_string(), placed(&plated, "0.1 -0.25 1.3", "0.01 -0.7 2.5")));
    for (what, text) in variants {
        let m = urdf::parse(&text).expect("parses");
        let job = SolveRun::build(&m, ModelChoice::Auto, &fixed, &[], SolverSettings { threads: 1, ..Default::default() }).expect("builds");
        assert_eq!(job.problem().model(), Model::Pose, "{what}");
        let r = job.run(&AtomicBool::new(false), &mut |_| {});
        assert_eq!(r.status, Status::Finished, "{what}");
        let unique = r.boxes.iter().filter(|b| b.status == BoxStatus::Unique).count();
        assert_eq!((unique, r.boxes.len()), (count, count), "{what}: one certified box per real assembly");
    }
}

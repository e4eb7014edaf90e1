//! Test idea: each way of losing or misreporting a configuration as a mechanism whose answer is known in closed form (circle
//! intersections, computed here or with mpmath at 300 bits where noted), solved through the
//! library; the boxes must enclose every configuration of the stated mechanism and keep every
//! filter and certificate honest.

use linkspace::model::urdf;
use linkspace::formulate::{LinkageError, LinkageProblem};
use linkspace::kernel::search::{SolverSettings, Status};
use linkspace::kernel::interval::IntervalBox;
use std::f64::consts::{PI, TAU};
use std::sync::atomic::AtomicBool;

/// A four-bar in the style of `urdf/four_bar.urdf`: crank `a` at O2 = (0, 0), coupler `b`,
/// rocker `c` at O4 = (d, 0), all axes +z; `rocker` is the rocker joint's opening tag and
/// `rocker_limit`, `loop_limit` are inserted verbatim.
fn four_bar(a: &str, b: &str, c: &str, d: &str, rocker: &str, rocker_limit: &str, loop_limit: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="fb">
  <link name="ground"/><link name="crank"/><link name="coupler"/><link name="rocker"/>
  <joint name="crank_joint" type="continuous"><parent link="ground"/><child link="crank"/><origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="coupler_joint" type="continuous"><parent link="crank"/><child link="coupler"/><origin xyz="{a} 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  {rocker}<parent link="ground"/><child link="rocker"/><origin xyz="{d} 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>{rocker_limit}</joint>
  <loop name="loop" type="revolute">
    <predecessor link="coupler"><origin xyz="{b} 0 0" rpy="0 0 0"/></predecessor>
    <successor link="rocker"><origin xyz="{c} 0 0" rpy="0 0 0"/></successor>
    <axis xyz="0 0 1"/>{loop_limit}
  </loop>
</robot>"#
    )
}

const CONTINUOUS: &str = r#"<joint name="rocker_joint" type="continuous">"#;

fn build(xml: &str, fixed: &[(&str, f64)]) -> Result<LinkageProblem, LinkageError> {
    let m = urdf::parse(xml).expect("fixture parses");
    let fixed: Vec<(String, f64)> = fixed.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    LinkageProblem::new(&m, &fixed, &[])
}

struct Run {
    status: Status,
    boxes: Vec<IntervalBox>,
    unique: Vec<bool>,
}

fn run(p: &LinkageProblem, sigma: f64, newton_width: f64) -> Run {
    let settings = SolverSettings { sigma, newton_width, ..Default::default() };
    let e = p.solver(settings).expect("valid settings").enclose(&AtomicBool::new(false), &mut |_| {});
    Run { status: e.status, boxes: e.solutions, unique: e.tags.iter().map(|t| *t == linkspace::app::BoxStatus::Unique).collect() }
}

/// The two assemblies (coupler angle φ3, rocker angle φ4, world radians) of a four-bar with the
/// crank at world angle `t`: the coupler's far end on the circle of radius `b` about the crank
/// pin and on the circle of radius `c` about O4.
fn assemblies(a: f64, b: f64, c: f64, d: f64, t: f64) -> Vec<(f64, f64)> {
    let (bx, by) = (a * t.cos(), a * t.sin());
    let (ux, uy) = (d - bx, -by);
    let dist = ux.hypot(uy);
    let x = (dist * dist + b * b - c * c) / (2.0 * dist);
    let h = (b * b - x * x).sqrt();
    [1.0, -1.0]
        .iter()
        .map(|&side| {
            let (px, py) = (bx + (x * ux - side * h * uy) / dist, by + (x * uy + side * h * ux) / dist);
            ((py - by).atan2(px - bx), py.atan2(px - d))
        })
        .collect()
}

/// `x` lies in `[lo, hi]` modulo 2π, with `slack`.
fn holds_angle((lo, hi): (f64, f64), x: f64, slack: f64) -> bool {
    (-3..=3).any(|k| {
        let y = x + TAU * f64::from(k);
        lo - slack <= y && y <= hi + slack
    })
}

fn joint(p: &LinkageProblem, b: &IntervalBox, name: &str) -> (f64, f64) {
    p.joint_values(b)[name]
}

/// Limits six turns away, [1 + 6π, 2 + 6π], keep the configuration whose rocker
/// angle 1.5145 ≡ 20.364 lies inside them (a filter trying only offsets of −2..=2 turns loses it).
#[test]
fn limits_several_turns_away_keep_their_configurations() {
    let six_pi = 3.0 * TAU;
    let limit = format!(r#"<limit lower="{}" upper="{}" effort="1" velocity="1"/>"#, 1.0 + six_pi, 2.0 + six_pi);
    let xml = four_bar("1.5", "4", "3.5", "4", r#"<joint name="rocker_joint" type="revolute">"#, &limit, "");
    let p = build(&xml, &[("crank_joint", 0.5)]).expect("builds");
    let refs = assemblies(1.5, 4.0, 3.5, 4.0, 0.5);
    let inside: Vec<f64> = refs.iter().map(|r| r.1).filter(|r| r.rem_euclid(TAU) >= 1.0 && r.rem_euclid(TAU) <= 2.0).collect();
    assert_eq!(inside.len(), 1, "the fixture has one assembly within the limits: {refs:?}");
    for newton_width in [0.0, 0.25] {
        let r = run(&p, 1e-6, newton_width);
        assert_eq!(r.status, Status::Finished);
        assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "rocker_joint"), inside[0], 1e-9)), "newton width {newton_width}: the rocker at {} is lost", inside[0]);
    }
}

/// With `<limit lower="0" upper="1"/>` on the loop, a root that Krawczyk
/// certifies outside the limit must not be reported, and the one inside still is.
#[test]
fn certified_roots_still_meet_the_loop_limits() {
    let xml = four_bar("1.5", "4", "3.5", "4", CONTINUOUS, "", r#"<limit lower="0" upper="1"/>"#);
    let p = build(&xml, &[("crank_joint", 0.5)]).expect("builds");
    let loop_values: Vec<f64> = assemblies(1.5, 4.0, 3.5, 4.0, 0.5).iter().map(|(p3, p4)| (p4 - p3 + PI).rem_euclid(TAU) - PI).collect();
    let inside: Vec<f64> = loop_values.iter().copied().filter(|v| (0.0..=1.0).contains(v)).collect();
    assert_eq!(inside.len(), 1, "one assembly inside the loop limit: {loop_values:?}");
    let r = run(&p, 1e-6, 0.25);
    assert_eq!(r.status, Status::Finished);
    for b in &r.boxes {
        let (lo, hi) = joint(&p, b, "loop");
        assert!(hi >= 0.0 && lo <= 1.0, "a box outside the loop limit [0, 1] is reported: loop in [{lo}, {hi}]");
    }
    assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "loop"), inside[0], 1e-9)));
    assert!(r.unique.iter().any(|&u| u), "the root inside the limit is still certified");
}

/// A coupler of 1e-12 beside a crank of 1000 is a term, not noise. The stated
/// mechanism (O4 at 3000, rocker 2000 − 5e-13) puts the coupler at cos φ = (D² + b² − c²)/(2Db)
/// = 0.5 + 1.9e-16 (D = 2000, b = 1e-12: exact decimal arithmetic by hand), so φ = ±60°.
#[test]
fn tiny_terms_are_bounded_not_dropped() {
    let xml = four_bar("1000", "1e-12", "1999.9999999999995", "3000", CONTINUOUS, "", "");
    let p = build(&xml, &[("crank_joint", 0.0)]).expect("builds");
    let r = run(&p, 1e-3, 0.25);
    assert_eq!(r.status, Status::Finished);
    for phi in [PI / 3.0, -PI / 3.0] {
        assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "coupler_joint"), phi, 1e-9)), "the assembly with the coupler at {phi} is lost ({} boxes)", r.boxes.len());
    }
}

/// The same four-bar scaled by 1e±200 has the same joint values.
#[test]
fn scaled_mechanisms_give_the_same_answers() {
    let reference = assemblies(1.5, 4.0, 3.5, 4.0, 0.5);
    for scale in ["", "e-200", "e200"] {
        let n = |v: &str| format!("{v}{scale}");
        let xml = four_bar(&n("1.5"), &n("4"), &n("3.5"), &n("4"), CONTINUOUS, "", "");
        let p = match build(&xml, &[("crank_joint", 0.5)]) {
            Ok(p) => p,
            Err(e) => panic!("scale {scale}: {e}"),
        };
        let r = run(&p, 1e-6, 0.25);
        assert_eq!(r.status, Status::Finished, "scale {scale}");
        for (p4, _) in reference.iter().map(|(p3, p4)| (*p4, p3)) {
            assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "rocker_joint"), p4, 1e-9)), "scale {scale}: rocker at {p4} lost");
        }
    }
}

/// Coefficients from `--fix crank_joint=0.305` enclose 1.5·cos 0.305 − 4 and
/// 1.5·sin 0.305 exactly (brackets: the f64 neighbours of the 300-bit mpmath values), where the
/// old builder stored the nearest f64 as if exact.
#[test]
fn coefficients_enclose_their_exact_values() {
    let xml = four_bar("1.5", "4", "3.5", "4", CONTINUOUS, "", "");
    let p = build(&xml, &[("crank_joint", 0.305)]).expect("builds");
    let brackets = [(-2.5692295711484094, -2.569229571148409), (0.45043976281389225, 0.4504397628138923)];
    for (lo, hi) in brackets {
        let holds = |c: linkspace::kernel::interval::Interval| (c.inf() <= lo && c.sup() >= hi) || (c.inf() <= -hi && c.sup() >= -lo);
        assert!(p.system.equations.iter().any(|e| holds(e.constant)), "no loop constant encloses [{lo}, {hi}]: {:?}", p.system.equations.iter().map(|e| e.constant).collect::<Vec<_>>());
    }
}

/// Read-outs at `--fix crank_joint=1e8` are outward rounded around the true
/// values (1e8 ≡ 1.94269513450401446 mod 2π, mpmath at 300 bits); 1e16 is refused in one line.
#[test]
fn large_fixed_values_read_out_soundly_or_are_refused() {
    let xml = four_bar("1.5", "4", "3.5", "4", CONTINUOUS, "", "");
    let p = build(&xml, &[("crank_joint", 1e8)]).expect("builds");
    let t = 1.9426951345040145;
    let r = run(&p, 1e-10, 0.25);
    assert_eq!(r.status, Status::Finished);
    for (p3, _) in assemblies(1.5, 4.0, 3.5, 4.0, t) {
        let coupler = p3 - t;
        // The closed form in f64 is good to a few 1e-15 here; the old read-out missed by 1.3e-8.
        assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "coupler_joint"), coupler, 1e-13)), "coupler_joint {coupler} missed: {:?}", r.boxes.iter().map(|b| joint(&p, b, "coupler_joint")).collect::<Vec<_>>());
    }
    for v in [1e16, 1e300] {
        let e = build(&xml, &[("crank_joint", v)]).err().unwrap_or_else(|| panic!("--fix crank_joint={v} is not refused"));
        assert!(e.to_string().contains("modulo 2π") && !e.to_string().contains('\n'), "{e}");
    }
}

/// A parallelogram four-bar (crank 1, coupler 2, rocker 1, O4 at 2) with the
/// crank at 0.5 has its coupler exactly at its rest orientation in one assembly; both roots are
/// regular and must be certified.
#[test]
fn roots_at_the_rest_orientation_are_certified() {
    let xml = four_bar("1", "2", "1", "2", CONTINUOUS, "", "");
    let p = build(&xml, &[("crank_joint", 0.5)]).expect("builds");
    let r = run(&p, 1e-6, 0.25);
    assert_eq!(r.status, Status::Finished);
    let refs = assemblies(1.0, 2.0, 1.0, 2.0, 0.5);
    assert!(refs.iter().any(|(p3, _)| p3.abs() < 1e-12), "one assembly has the coupler at rest: {refs:?}");
    assert_eq!(r.boxes.len(), 2, "{:?}", r.boxes);
    assert_eq!(r.unique, vec![true, true]);
    for (p3, _) in refs {
        assert!(r.boxes.iter().any(|b| holds_angle(joint(&p, b, "coupler_joint"), p3 - 0.5, 1e-9)));
    }
}

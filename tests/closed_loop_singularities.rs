//! Issue 13: singular sets of planar closed-loop linkages (`problems::singular`) against
//! references of our own that never call the solver: closed forms for four-bars, a sheet-wise
//! grid plus Newton for the double butterfly's turning points of θ6, a dense actuator grid for
//! the five-bar's type-II curves.

use super::util::urdf_text;
use linkspace::model::urdf;
use linkspace::problems::singular::{BoxKind, Output, SingularKind, SingularProblem, SingularSet};
use linkspace::search::{SolverSettings, Status};
use std::f64::consts::PI;
use std::process::Command;
use std::sync::atomic::AtomicBool;

/// A four-bar in URDF: ground pivots (0, 0) and (d, 0), crank a, coupler b, rocker c, joints named
/// as in the bundled `four_bar.urdf`.
fn four_bar(d: f64, a: f64, b: f64, c: f64) -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="four_bar_{d}_{a}_{b}_{c}">
  <link name="ground"/><link name="crank"/><link name="coupler"/><link name="rocker"/>
  <joint name="crank_joint" type="continuous"><parent link="ground"/><child link="crank"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="coupler_joint" type="continuous"><parent link="crank"/><child link="coupler"/>
    <origin xyz="{a} 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="rocker_joint" type="continuous"><parent link="ground"/><child link="rocker"/>
    <origin xyz="{d} 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <loop name="loop_coupler_rocker" type="revolute">
    <predecessor link="coupler"><origin xyz="{b} 0 0" rpy="0 0 0"/></predecessor>
    <successor link="rocker"><origin xyz="{c} 0 0" rpy="0 0 0"/></successor>
    <axis xyz="0 0 1"/>
  </loop>
</robot>"#
    )
}

fn run(xml: &str, kind: SingularKind, actuated: &[&str], output: Option<Output>, sigma: f64) -> (SingularProblem, SingularSet) {
    let m = urdf::parse(xml).expect("URDF parses");
    let actuated: Vec<String> = actuated.iter().map(|s| s.to_string()).collect();
    let p = SingularProblem::new(&m, &[], kind, &actuated, output).expect("builds");
    let set = p.solve(&SolverSettings { sigma, ..Default::default() }, &AtomicBool::new(false)).expect("valid settings");
    (p, set)
}

/// Distance between two angles modulo 2π.
fn angle_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    d.min(2.0 * PI - d)
}

/// Does the interval [lo, hi] (radians) hold `x` modulo 2π, within `slack`?
fn holds_angle(iv: (f64, f64), x: f64, slack: f64) -> bool {
    let k = ((x - iv.0) / (2.0 * PI)).floor();
    let x0 = x - k * 2.0 * PI; // x0 in [lo, lo + 2π)
    (x0 <= iv.1 + slack) || (x0 - 2.0 * PI >= iv.0 - slack) || angle_gap(x, iv.0) <= slack || angle_gap(x, iv.1) <= slack
}

/// One value of `joint` per cluster (its hull over the cluster's boxes), with the certificate.
fn cluster_values(p: &SingularProblem, set: &SingularSet, joint: &str) -> Vec<((f64, f64), bool)> {
    set.clusters
        .iter()
        .map(|c| {
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for &i in &c.boxes {
                let v = p.joint_values(&set.boxes[i].b)[joint];
                lo = lo.min(v.0);
                hi = hi.max(v.1);
            }
            ((lo, hi), c.certified)
        })
        .collect()
}

/// Every reference value in exactly one cluster, every cluster holding exactly one reference,
/// all certified, the run complete: none missed, none extra.
fn same_points(p: &SingularProblem, set: &SingularSet, joint: &str, reference: &[f64], what: &str) {
    same_points_with(p, set, joint, reference, what, true, 1e-6)
}

/// `same_points`, with or without requiring certificates, clusters up to `width` wide.
fn same_points_with(p: &SingularProblem, set: &SingularSet, joint: &str, reference: &[f64], what: &str, certified_only: bool, width: f64) {
    assert_eq!(set.status, Status::Complete, "{what}");
    let got = cluster_values(p, set, joint);
    assert_eq!(got.len(), reference.len(), "{what}: clusters {got:?} against the closed form {reference:?}");
    for (iv, certified) in &got {
        assert!(*certified || !certified_only, "{what}: cluster {iv:?} not certified");
        assert!(iv.1 - iv.0 < width, "{what}: cluster {iv:?} is not a point");
        let n = reference.iter().filter(|&&r| holds_angle(*iv, r, 1e-9)).count();
        assert_eq!(n, 1, "{what}: cluster {iv:?} holds {n} closed-form values of {reference:?}");
    }
}

/// `±acos(x)` when |x| < 1.
fn both_signs(x: f64) -> Vec<f64> {
    if x.abs() < 1.0 {
        vec![x.acos(), -x.acos()]
    } else {
        Vec::new()
    }
}

/// Closed forms. Input (crank driving): coupler and rocker in line, |A − O4| = b + c or |b − c|
/// with A = a(cos θ2, sin θ2). Output (rocker angle): crank and coupler in line, |B − O2| = a + b
/// or |a − b| with B = (d, 0) + c(cos θ4, sin θ4). Both by the law of cosines.
fn four_bar_reference(d: f64, a: f64, b: f64, c: f64) -> (Vec<f64>, Vec<f64>) {
    let input = [b + c, (b - c).abs()].iter().flat_map(|l| both_signs((a * a + d * d - l * l) / (2.0 * a * d))).collect();
    let output = [a + b, (a - b).abs()].iter().flat_map(|l| both_signs((l * l - d * d - c * c) / (2.0 * d * c))).collect();
    (input, output)
}

fn check_four_bar(xml: &str, (d, a, b, c): (f64, f64, f64, f64), counts: (usize, usize)) {
    let (input_ref, output_ref) = four_bar_reference(d, a, b, c);
    assert_eq!((input_ref.len(), output_ref.len()), counts, "the closed form itself");
    let (p, set) = run(xml, SingularKind::Input, &["crank_joint"], None, 1e-6);
    same_points(&p, &set, "crank_joint", &input_ref, "input singularities (crank driving)");
    let (p, set) = run(xml, SingularKind::Output, &["crank_joint"], Some(Output::Joints(vec!["rocker_joint".into()])), 1e-6);
    same_points(&p, &set, "rocker_joint", &output_ref, "output singularities (rocker angle)");
    // The same set through the velocity of the rocker's tip: it stands still exactly when the
    // rocker does. Two velocity rows for one condition (the tip moves on a circle) make the
    // system overdetermined, so Krawczyk cannot certify: unproven clusters, honestly reported,
    // at the same places and no others.
    let tip = Output::Point { link: "rocker".into(), x: c, y: 0.0 };
    let (p, set) = run(xml, SingularKind::Output, &["crank_joint"], Some(tip), 1e-6);
    assert_eq!(set.certified_clusters(), 0);
    same_points_with(&p, &set, "rocker_joint", &output_ref, "output singularities (rocker tip)", false, 1e-4);
    // A generic four-bar has no bifurcation: proven by an empty, complete run.
    let (_, set) = run(xml, SingularKind::Cspace, &[], None, 1e-6);
    assert_eq!((set.status, set.boxes.len()), (Status::Complete, 0), "C-space singularities of a generic four-bar");
}

#[test]
fn grashof_four_bar_dead_centres_match_the_closed_form() {
    // The bundled crank-rocker: the crank turns fully (no input singularity), the rocker has
    // its two dead centres on each assembly branch (4 in all).
    check_four_bar(&urdf_text("four_bar.urdf"), (4.0, 1.5, 4.0, 3.5), (0, 4));
}

#[test]
fn non_grashof_four_bar_turning_points_match_the_closed_form() {
    // s + l = 2.5 + 4 > p + q = 3 + 3: a triple rocker; the crank turns back where coupler and
    // rocker stretch out in line (2 points), the rocker where crank and coupler do (2 points).
    let (d, a, b, c) = (4.0, 3.0, 2.5, 3.0);
    check_four_bar(&four_bar(d, a, b, c), (d, a, b, c), (2, 2));
}

#[test]
fn a_folding_parallelogram_has_certified_free_bifurcations() {
    // d = b, a = c: the parallelogram branch crosses the anti-parallelogram branch where all bars
    // are in line (θ2 = 0 and θ2 = π): the loop rows lose rank there. The C-space system is
    // overdetermined at those points (no Krawczyk certificate), so they come as unproven boxes
    // near the two closed-form configurations, and nowhere else.
    let xml = four_bar(3.0, 1.0, 3.0, 1.0);
    let (p, set) = run(&xml, SingularKind::Cspace, &[], None, 1e-5);
    assert_eq!(set.status, Status::Complete);
    let got = cluster_values(&p, &set, "crank_joint");
    assert_eq!(got.len(), 2, "{got:?}");
    for r in [0.0, PI] {
        assert!(got.iter().any(|(iv, _)| holds_angle(*iv, r, 1e-4)), "bifurcation at crank {r} missing from {got:?}");
    }
}

#[test]
fn bad_actuation_gets_one_clear_line() {
    let bin = env!("CARGO_BIN_EXE_linkspace");
    let four = format!("{}/urdf/four_bar.urdf", env!("CARGO_MANIFEST_DIR"));
    let cases: [(&[&str], &str); 5] = [
        (&["--kind", "input", "--actuated", "nope"], "'nope' is not a free joint"),
        (&["--kind", "input", "--actuated", "crank_joint,rocker_joint"], "as many actuated joints as degrees of freedom"),
        (&["--kind", "input"], "as many actuated joints as degrees of freedom"),
        (&["--kind", "output", "--output", "rocker@1,x"], "is not a number"),
        (&["--kind", "input", "--actuated", "crank_joint,crank_joint"], "named twice"),
    ];
    for (args, expected) in cases {
        let out = Command::new(bin).arg("loop-singularities").arg(&four).args(args).output().expect("binary runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

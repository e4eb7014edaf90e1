//! Singular sets of planar closed-loop linkages (`formulate::singular`) against
//! references of our own that never call the solver: closed forms for four-bars, a sheet-wise
//! grid plus Newton for the double butterfly's turning points of θ6, a dense actuator grid for
//! the five-bar's type-II curves.

use super::util::urdf_text;
use linkspace::model::urdf;
use linkspace::formulate::{CuspFormulation, CuspProblem};
use linkspace::formulate::{Output, SingularKind, SingularProblem};
use linkspace::analyses::loop_singular::SingularSet;
use linkspace::kernel::outcome::BoxStatus;
use linkspace::kernel::search::{SolverSettings, Status};
use std::f64::consts::PI;
use std::process::Command;
use std::sync::atomic::AtomicBool;

/// A four-bar in URDF: ground pivots (0, 0) and (d, 0), crank a, coupler b, rocker c, joints named
/// as in the bundled `four_bar.urdf`.
pub(super) fn four_bar(d: f64, a: f64, b: f64, c: f64) -> String {
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
    assert_eq!(set.status, Status::Finished, "{what}");
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
    assert_eq!((set.status, set.boxes.len()), (Status::Finished, 0), "C-space singularities of a generic four-bar");
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
    assert_eq!(set.status, Status::Finished);
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

/// The double butterfly of the bundled URDF, from the loop equations in its header comment:
///   A: l7 u7 + a2 u2 + a1 u1 − l5 u5 + (b0, 0) = 0
///   B: l7 u7 + a2 u2 + b1 R(γ1) u1 − l3 u3 − c6 R(η6) u6 + a0 (cos γ0, −sin γ0) = 0
///   C: l7 u7 + b2 R(γ2) u2 − l4 u4 − b6 u6 + a0 (cos γ0, −sin γ0) = 0
/// Given (θ7, θ6), C leaves |·| = l4 for θ2 (two circle intersections, sheet σ1), then A leaves
/// |·| = l5 for θ1 (sheet σ2); B becomes one scalar h_σ(θ7, θ6) = |…|² − l3² on each of the 4
/// sheets. The curve of the mechanism is {h_σ = 0}; θ6 is stationary along it where
/// ∂h_σ/∂θ7 = 0 (its tangent is then along θ7).
mod butterfly {
    const A0: f64 = 7.0;
    const B0: f64 = 13.0;
    const A1: f64 = 7.0;
    const B1: f64 = 6.0;
    const A2: f64 = 5.0;
    const B2: f64 = 3.0;
    const B6: f64 = 3.0;
    const C6: f64 = 2.0;
    const L3: f64 = 7.0;
    const L4: f64 = 9.0;
    const L5: f64 = 12.0;
    const L7: f64 = 11.0;

    fn u(t: f64) -> [f64; 2] {
        [t.cos(), t.sin()]
    }

    /// h on sheet (s1, s2), or None where the sheet does not exist.
    pub fn h(t7: f64, t6: f64, s1: f64, s2: f64) -> Option<f64> {
        sheet(t7, t6, s1, s2).map(|x| x.0)
    }

    /// (θ2, θ1) of the sheet point.
    pub fn angles(t7: f64, t6: f64, s1: f64, s2: f64) -> Option<(f64, f64)> {
        sheet(t7, t6, s1, s2).map(|x| (x.1, x.2))
    }

    fn sheet(t7: f64, t6: f64, s1: f64, s2: f64) -> Option<(f64, f64, f64)> {
        let (g0, g1, g2) = (3f64.atan2(4.0), 5f64.atan2(12.0), 4f64.atan2(3.0));
        let base = [A0 * g0.cos(), -A0 * g0.sin()];
        let (u7, u6) = (u(t7), u(t6));
        let p = [L7 * u7[0] - B6 * u6[0] + base[0], L7 * u7[1] - B6 * u6[1] + base[1]];
        let np = p[0].hypot(p[1]);
        let r = (L4 * L4 - np * np - B2 * B2) / (2.0 * B2 * np);
        if r.is_nan() || r.abs() > 1.0 {
            return None;
        }
        let t2 = p[1].atan2(p[0]) + s1 * r.acos() - g2;
        let u2 = u(t2);
        let q = [L7 * u7[0] + A2 * u2[0] + B0, L7 * u7[1] + A2 * u2[1]];
        let nq = q[0].hypot(q[1]);
        let r2 = (L5 * L5 - nq * nq - A1 * A1) / (2.0 * A1 * nq);
        if r2.is_nan() || r2.abs() > 1.0 {
            return None;
        }
        let t1 = q[1].atan2(q[0]) + s2 * r2.acos();
        let (v1, v6) = (u(t1 + g1), u(t6 + g0));
        let w = [
            L7 * u7[0] + A2 * u2[0] + B1 * v1[0] - C6 * v6[0] + base[0],
            L7 * u7[1] + A2 * u2[1] + B1 * v1[1] - C6 * v6[1] + base[1],
        ];
        Some((w[0] * w[0] + w[1] * w[1] - L3 * L3, t2, t1))
    }

    /// ∂h/∂θ7 by a central difference on the same sheet.
    pub fn h7(t7: f64, t6: f64, s1: f64, s2: f64) -> Option<f64> {
        let d = 1e-6;
        Some((h(t7 + d, t6, s1, s2)? - h(t7 - d, t6, s1, s2)?) / (2.0 * d))
    }

    /// Newton on (h, ∂h/∂θ7) = 0 from (t7, t6), finite-difference Jacobian; None unless it
    /// converges within `reach` of the start.
    pub fn polish(mut t7: f64, mut t6: f64, s1: f64, s2: f64, reach: f64) -> Option<(f64, f64)> {
        let (t7_0, t6_0) = (t7, t6);
        let e = 1e-5;
        for _ in 0..40 {
            let f = [h(t7, t6, s1, s2)?, h7(t7, t6, s1, s2)?];
            let j = [
                [(h(t7 + e, t6, s1, s2)? - h(t7 - e, t6, s1, s2)?) / (2.0 * e), (h(t7, t6 + e, s1, s2)? - h(t7, t6 - e, s1, s2)?) / (2.0 * e)],
                [(h7(t7 + e, t6, s1, s2)? - h7(t7 - e, t6, s1, s2)?) / (2.0 * e), (h7(t7, t6 + e, s1, s2)? - h7(t7, t6 - e, s1, s2)?) / (2.0 * e)],
            ];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let d7 = (f[0] * j[1][1] - f[1] * j[0][1]) / det;
            let d6 = (j[0][0] * f[1] - j[1][0] * f[0]) / det;
            t7 -= d7;
            t6 -= d6;
            if (t7 - t7_0).abs() > reach || (t6 - t6_0).abs() > reach {
                return None;
            }
            if d7.abs() < 1e-12 && d6.abs() < 1e-12 {
                break;
            }
        }
        let f = [h(t7, t6, s1, s2)?, h7(t7, t6, s1, s2)?];
        (f[0].abs() < 1e-8 && f[1].abs() < 1e-5).then_some((t7, t6))
    }

    /// Every stationary point of θ6 on the curve, as (θ7, θ6): on an n × n grid of each sheet,
    /// every cell whose corners show sign changes of both h and ∂h/∂θ7 is polished by Newton;
    /// duplicates (the same point from neighbouring cells) are merged.
    pub fn turning_points(n: usize) -> Vec<(f64, f64)> {
        use std::f64::consts::PI;
        let step = 2.0 * PI / n as f64;
        let at = |k: usize| -PI + step * (k % n) as f64;
        let mut found: Vec<(f64, f64)> = Vec::new();
        for (s1, s2) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            let grid: Vec<Option<(f64, f64)>> = (0..n * n)
                .map(|k| {
                    let (i, j) = (k / n, k % n);
                    Some((h(at(i), at(j), s1, s2)?, h7(at(i), at(j), s1, s2)?))
                })
                .collect();
            for i in 0..n {
                for j in 0..n {
                    let corners = [(i, j), ((i + 1) % n, j), (i, (j + 1) % n), ((i + 1) % n, (j + 1) % n)].map(|(a, b)| grid[a * n + b]);
                    if corners.iter().any(|c| c.is_none()) {
                        continue;
                    }
                    let c: Vec<(f64, f64)> = corners.iter().flatten().copied().collect();
                    let changes = |f: &dyn Fn(&(f64, f64)) -> f64| c.iter().any(|x| f(x) <= 0.0) && c.iter().any(|x| f(x) >= 0.0);
                    if !(changes(&|x| x.0) && changes(&|x| x.1)) {
                        continue;
                    }
                    if let Some((t7, t6)) = polish(at(i) + 0.5 * step, at(j) + 0.5 * step, s1, s2, 3.0 * step) {
                        let gap = |a: f64, b: f64| super::angle_gap(a, b);
                        if !found.iter().any(|&(a, b)| gap(a, t7) < 1e-6 && gap(b, t6) < 1e-6) {
                            found.push((t7, t6));
                        }
                    }
                }
            }
        }
        found
    }
}


/// Continuation of the double butterfly's curve in all seven link angles, where it has no fold:
/// pseudo-arclength steps along the tangent (the generalised cross product of the 6 × 7
/// Jacobian of loops A, B, C), a sign change of the tangent's θ6 component marks a stationary
/// point of θ6, polished by Newton on the augmented system (loops, det of the passive Jacobian).
/// Branches are started from points of the sheet grid until every grid point lies on a traced
/// branch, so no branch the grid touches is missed.
pub(super) mod trace {
    use nalgebra::{DMatrix, DVector};
    use std::f64::consts::PI;

    /// One loop: its terms and its constant.
    type Loop = (Vec<(f64, usize, f64)>, [f64; 2]);

    /// (coefficient, angle index 0..7 for θ1..θ7, offset): the terms of loops A, B, C.
    fn loops() -> [Loop; 3] {
        let (g0, g1, g2) = (3f64.atan2(4.0), 5f64.atan2(12.0), 4f64.atan2(3.0));
        let base = [7.0 * g0.cos(), -7.0 * g0.sin()];
        [
            (vec![(11.0, 6, 0.0), (5.0, 1, 0.0), (7.0, 0, 0.0), (-12.0, 4, 0.0)], [13.0, 0.0]),
            (vec![(11.0, 6, 0.0), (5.0, 1, 0.0), (6.0, 0, g1), (-7.0, 2, 0.0), (-2.0, 5, g0)], base),
            (vec![(11.0, 6, 0.0), (3.0, 1, g2), (-9.0, 3, 0.0), (-3.0, 5, 0.0)], base),
        ]
    }

    pub fn f(q: &[f64]) -> DVector<f64> {
        let mut out = DVector::zeros(6);
        for (k, (terms, c)) in loops().iter().enumerate() {
            let (mut x, mut y) = (c[0], c[1]);
            for &(a, i, o) in terms {
                x += a * (q[i] + o).cos();
                y += a * (q[i] + o).sin();
            }
            out[2 * k] = x;
            out[2 * k + 1] = y;
        }
        out
    }

    pub fn jac(q: &[f64]) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(6, 7);
        for (k, (terms, _)) in loops().iter().enumerate() {
            for &(a, i, o) in terms {
                j[(2 * k, i)] -= a * (q[i] + o).sin();
                j[(2 * k + 1, i)] += a * (q[i] + o).cos();
            }
        }
        j
    }

    /// Generalised cross product of the rows: the tangent, oriented continuously.
    pub fn tangent(q: &[f64]) -> DVector<f64> {
        let j = jac(q);
        DVector::from_fn(7, |i, _| {
            let minor = j.clone().remove_column(i);
            if i % 2 == 0 { minor.determinant() } else { -minor.determinant() }
        })
    }

    /// Newton on `F(q) = 0` plus `extra(q) = 0` (7 × 7, finite-difference row for `extra`).
    fn newton(mut q: Vec<f64>, extra: &dyn Fn(&[f64]) -> f64) -> Option<Vec<f64>> {
        for _ in 0..30 {
            let mut m = DMatrix::zeros(7, 7);
            m.view_mut((0, 0), (6, 7)).copy_from(&jac(&q));
            let e = extra(&q);
            for i in 0..7 {
                let (mut a, mut b) = (q.clone(), q.clone());
                a[i] += 1e-7;
                b[i] -= 1e-7;
                m[(6, i)] = (extra(&a) - extra(&b)) / 2e-7;
            }
            let mut r = f(&q).insert_row(6, e);
            r.neg_mut();
            let d = m.lu().solve(&r)?;
            for i in 0..7 {
                q[i] += d[i];
            }
            if d.amax() < 1e-13 {
                break;
            }
        }
        (f(&q).amax() < 1e-10).then_some(q)
    }

    /// Full configuration from (θ7, θ6, θ2, θ1) of a sheet point, corrected with θ6 held.
    pub fn lift(t7: f64, t6: f64, t2: f64, t1: f64) -> Option<Vec<f64>> {
        let (g0, g1, g2) = (3f64.atan2(4.0), 5f64.atan2(12.0), 4f64.atan2(3.0));
        let base = [7.0 * g0.cos(), -7.0 * g0.sin()];
        let ang = |x: f64, y: f64| y.atan2(x);
        let t4 = ang(11.0 * t7.cos() + 3.0 * (t2 + g2).cos() - 3.0 * t6.cos() + base[0], 11.0 * t7.sin() + 3.0 * (t2 + g2).sin() - 3.0 * t6.sin() + base[1]);
        let t5 = ang(11.0 * t7.cos() + 5.0 * t2.cos() + 7.0 * t1.cos() + 13.0, 11.0 * t7.sin() + 5.0 * t2.sin() + 7.0 * t1.sin());
        let t3 = ang(
            11.0 * t7.cos() + 5.0 * t2.cos() + 6.0 * (t1 + g1).cos() - 2.0 * (t6 + g0).cos() + base[0],
            11.0 * t7.sin() + 5.0 * t2.sin() + 6.0 * (t1 + g1).sin() - 2.0 * (t6 + g0).sin() + base[1],
        );
        let q = vec![t1, t2, t3, t4, t5, t6, t7];
        newton(q, &|x: &[f64]| x[5] - t6)
    }

    fn gap(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| super::angle_gap(*x, *y)).fold(0.0, f64::max)
    }

    /// Traces the closed branch through `start`; returns its points and its stationary points
    /// of θ6.
    pub fn branch(start: &[f64]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let h = 0.01;
        let mut q = start.to_vec();
        let mut t = tangent(&q).normalize();
        let mut points = vec![q.clone()];
        let mut stationary: Vec<Vec<f64>> = Vec::new();
        for step in 0..200_000 {
            let mut len = h;
            let next = loop {
                let pred: Vec<f64> = (0..7).map(|i| q[i] + len * t[i]).collect();
                let tt = t.clone();
                let pc = pred.clone();
                if let Some(n) = newton(pred, &move |x: &[f64]| (0..7).map(|i| tt[i] * (x[i] - pc[i])).sum()) {
                    if gap(&n, &q) < 2.0 * len {
                        break n;
                    }
                }
                len *= 0.5;
                assert!(len > 1e-9, "continuation stalled at {q:?}");
            };
            let mut tn = tangent(&next).normalize();
            if tn.dot(&t) < 0.0 {
                tn.neg_mut();
            }
            if t[5].signum() != tn[5].signum() {
                // det of the passive Jacobian (θ6's column removed) vanishes in between.
                let mid: Vec<f64> = (0..7).map(|i| 0.5 * (q[i] + next[i])).collect();
                let p = newton(mid, &|x: &[f64]| jac(x).remove_column(5).determinant()).expect("stationary point polishes");
                stationary.push(p);
            }
            q = next;
            t = tn;
            points.push(q.clone());
            if step > 10 && gap(&q, start) < 0.5 * h {
                break;
            }
        }
        (points, stationary)
    }

    /// Every stationary point of θ6 over every branch that one of `starts` lies on.
    pub fn all(starts: &[Vec<f64>]) -> (usize, Vec<Vec<f64>>) {
        let mut covered = vec![false; starts.len()];
        let mut branches = 0;
        let mut out: Vec<Vec<f64>> = Vec::new();
        while let Some(k) = covered.iter().position(|c| !c) {
            let (points, stationary) = branch(&starts[k]);
            branches += 1;
            for (i, s) in starts.iter().enumerate() {
                covered[i] = covered[i] || points.iter().any(|p| gap(p, s) < 0.02);
            }
            assert!(covered[k]);
            for p in stationary {
                if !out.iter().any(|o| gap(o, &p) < 1e-7) {
                    out.push(p);
                }
            }
        }
        let _ = PI;
        (branches, out)
    }
}

/// Starting points for `trace`: zeros of h along θ7 on rows of θ6, every sheet, lifted.
pub(super) fn butterfly_starts() -> Vec<Vec<f64>> {
    let mut starts = Vec::new();
    let n = 1000;
    let step = 2.0 * PI / n as f64;
    for row in 0..60 {
        let t6 = -PI + row as f64 * 2.0 * PI / 60.0;
        for (s1, s2) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            for i in 0..n {
                let (a, b) = (-PI + i as f64 * step, -PI + (i + 1) as f64 * step);
                let (Some(ha), Some(hb)) = (butterfly::h(a, t6, s1, s2), butterfly::h(b, t6, s1, s2)) else { continue };
                if ha.signum() == hb.signum() {
                    continue;
                }
                let (mut lo, mut hi) = (a, b);
                for _ in 0..60 {
                    let m = 0.5 * (lo + hi);
                    match butterfly::h(m, t6, s1, s2) {
                        Some(hm) if hm.signum() == ha.signum() => lo = m,
                        Some(_) => hi = m,
                        None => break,
                    }
                }
                let t7 = 0.5 * (lo + hi);
                if let Some((t2, t1)) = butterfly::angles(t7, t6, s1, s2) {
                    if let Some(q) = trace::lift(t7, t6, t2, t1) {
                        starts.push(q);
                    }
                }
            }
        }
    }
    starts
}

#[test]
fn double_butterfly_turning_points_of_theta6_match_an_independent_grid_and_newton() {
    let (branches, stationary) = trace::all(&butterfly_starts());
    assert_eq!(branches, 4, "the butterfly's curve has 4 branches (Porta, Ros and Thomas 2006)");
    let reference: Vec<(f64, f64)> = stationary.iter().map(|q| (q[6], q[5])).collect();
    // The grid-and-Newton reference on the sheets finds a subset (it skips cells at the sheets'
    // folds): every point it finds is one of the continuation's.
    for (r7, r6) in butterfly::turning_points(400) {
        assert!(reference.iter().any(|&(a, b)| angle_gap(a, r7) < 1e-5 && angle_gap(b, r6) < 1e-5), "grid point ({r7}, {r6}) not found by continuation");
    }
    let (p, set) = run(&urdf_text("double_butterfly.urdf"), SingularKind::Input, &["joint6"], None, 1e-4);
    assert_eq!(set.status, Status::Finished);
    type Turning = ((f64, f64), (f64, f64), bool);
    let got: Vec<Turning> = cluster_values(&p, &set, "joint7")
        .into_iter()
        .zip(cluster_values(&p, &set, "joint6"))
        .map(|((t7, c), (t6, _))| (t7, t6, c))
        .collect();
    assert_eq!(got.len(), reference.len(), "solver {got:?}\nreference {reference:?}");
    let slack = 1e-5;
    for (t7, t6, certified) in &got {
        assert!(certified, "cluster at joint7 {t7:?}, joint6 {t6:?} not certified");
        let n = reference.iter().filter(|&&(r7, r6)| holds_angle(*t7, r7, slack) && holds_angle(*t6, r6, slack)).count();
        assert_eq!(n, 1, "cluster at joint7 {t7:?}, joint6 {t6:?} holds {n} reference points");
    }
    for &(r7, r6) in &reference {
        assert!(got.iter().any(|(t7, t6, _)| holds_angle(*t7, r7, slack) && holds_angle(*t6, r6, slack)), "reference turning point ({r7}, {r6}) missed");
    }
    // Every box is certified (the ±v symmetry is gone: one chart owns each direction).
    assert!(set.boxes.iter().all(|b| b.status == BoxStatus::Unique));
}

/// The bundled five-bar: A1 = (0, 0), A2 = (1.5, 0), cranks 2, rods 2.5, both cranks actuated.
/// Dense-grid reference in actuator space: at each (θ1, θ2) the assembly modes are the two
/// intersections of the rods' circles about the crank tips B1, B2; the passive Jacobian (rod
/// angles) is singular where the rods are in line. On the grid, the rods can be in line only
/// where the modes appear or vanish (the grid edges where their number changes, refined by
/// bisection on that predicate) or where B1 = B2 (grid cells where |B1 − B2| is small, refined
/// by Newton on B1 − B2 = 0). The grid also checks that the rods' cross product never changes
/// sign within a mode between neighbours: no other singular curve exists.
#[test]
fn five_bar_type_two_curves_match_a_dense_grid() {
    let tips = |t1: f64, t2: f64| ([2.0 * t1.cos(), 2.0 * t1.sin()], [1.5 + 2.0 * t2.cos(), 2.0 * t2.sin()]);
    // The rods' cross product in each mode, or None where the mechanism does not assemble.
    let modes = |t1: f64, t2: f64| -> Option<[f64; 2]> {
        let (b1, b2) = tips(t1, t2);
        let d = [b2[0] - b1[0], b2[1] - b1[1]];
        let n = d[0].hypot(d[1]);
        if n > 5.0 || n == 0.0 {
            return None;
        }
        let along = 0.5 * n;
        let across = (2.5f64 * 2.5 - along * along).max(0.0).sqrt();
        let e = [d[0] / n, d[1] / n];
        Some([1.0, -1.0].map(|s| {
            let p = [b1[0] + along * e[0] - s * across * e[1], b1[1] + along * e[1] + s * across * e[0]];
            let (r1, r2) = ([p[0] - b1[0], p[1] - b1[1]], [p[0] - b2[0], p[1] - b2[1]]);
            r1[0] * r2[1] - r1[1] * r2[0]
        }))
    };
    let n = 400;
    let step = 2.0 * PI / n as f64;
    let at = |k: usize| -PI + step * k as f64;
    let mut reference: Vec<(f64, f64)> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let here = modes(at(i), at(j));
            for (di, dj) in [(1, 0), (0, 1)] {
                let (a, b) = ((at(i), at(j)), (at(i) + di as f64 * step, at(j) + dj as f64 * step));
                let there = modes(b.0, b.1);
                match (here, there) {
                    (Some(x), Some(y)) => {
                        for m in 0..2 {
                            assert!(x[m].signum() == y[m].signum() || x[m].abs() < 1e-9 || y[m].abs() < 1e-9, "rods' cross product changes sign inside mode {m} at {a:?}");
                        }
                    }
                    (None, None) => {}
                    _ => {
                        let (mut lo, mut hi) = (0.0, 1.0);
                        for _ in 0..50 {
                            let m = 0.5 * (lo + hi);
                            let x = (a.0 + m * (b.0 - a.0), a.1 + m * (b.1 - a.1));
                            if modes(x.0, x.1).is_some() == here.is_some() {
                                lo = m;
                            } else {
                                hi = m;
                            }
                        }
                        let m = 0.5 * (lo + hi);
                        reference.push((a.0 + m * (b.0 - a.0), a.1 + m * (b.1 - a.1)));
                    }
                }
            }
        }
    }
    // B1 = B2: Newton from cells where the tips nearly meet.
    let mut folded: Vec<(f64, f64)> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (b1, b2) = tips(at(i), at(j));
            if (b1[0] - b2[0]).hypot(b1[1] - b2[1]) > 4.0 * step {
                continue;
            }
            let (mut t1, mut t2) = (at(i), at(j));
            for _ in 0..30 {
                let (b1, b2) = tips(t1, t2);
                let f = [b1[0] - b2[0], b1[1] - b2[1]];
                let jm = [[-2.0 * t1.sin(), 2.0 * t2.sin()], [2.0 * t1.cos(), -2.0 * t2.cos()]];
                let det = jm[0][0] * jm[1][1] - jm[0][1] * jm[1][0];
                t1 -= (f[0] * jm[1][1] - f[1] * jm[0][1]) / det;
                t2 -= (jm[0][0] * f[1] - jm[1][0] * f[0]) / det;
            }
            if !folded.iter().any(|&(a, b)| angle_gap(a, t1) < 1e-6 && angle_gap(b, t2) < 1e-6) {
                folded.push((t1, t2));
            }
        }
    }
    assert_eq!(folded.len(), 2, "the tips meet at two actuator points: {folded:?}");
    assert!(reference.len() > 500);

    let sigma = 1e-2;
    let (p, set) = run(&urdf_text("five_bar.urdf"), SingularKind::Input, &["crank1_joint", "crank2_joint"], None, sigma);
    assert_eq!(set.status, Status::Finished);
    let images: Vec<[(f64, f64); 2]> = set.boxes.iter().map(|b| {
        let v = p.actuator_values(&b.b);
        [v[0], v[1]]
    }).collect();
    // None missed: every reference point lies in the image of some box (slack: the bisection's
    // and the read-out's rounding only).
    for &(r1, r2) in reference.iter().chain(&folded) {
        assert!(images.iter().any(|im| holds_angle(im[0], r1, 1e-6) && holds_angle(im[1], r2, 1e-6)), "reference point ({r1}, {r2}) not covered");
    }
    // None extra: every box lies near a reference point (within its own width plus a grid
    // step, the reference's spacing along the curve).
    for im in &images {
        let c = (0.5 * (im[0].0 + im[0].1), 0.5 * (im[1].0 + im[1].1));
        let reach = (im[0].1 - im[0].0).max(im[1].1 - im[1].0) + 2.0 * step;
        assert!(reference.iter().chain(&folded).any(|&(r1, r2)| angle_gap(c.0, r1) <= reach && angle_gap(c.1, r2) <= reach), "box at {im:?} is far from every reference point");
    }
    // Three clusters in configuration space: the stretched-rods curve and, over each point
    // where the tips meet, the circle of overlapping rods.
    assert_eq!(set.clusters.len(), 3);
}

/// Five-bars with A1 = (0, 0), A2 = (1.5, 0), cranks 2, rods `r1`, `r2`: the references of the
/// type-II image below never call the solver.
mod five_bar_ref {
    use std::f64::consts::PI;

    /// Crank tips B1, B2.
    pub fn tips(t1: f64, t2: f64) -> ([f64; 2], [f64; 2]) {
        ([2.0 * t1.cos(), 2.0 * t1.sin()], [1.5 + 2.0 * t2.cos(), 2.0 * t2.sin()])
    }

    /// |B1 − B2|: the mechanism assembles when it lies in [|r1 − r2|, r1 + r2], and the rods are
    /// in line (type II) at either end; the image of the type-II set is a union of level sets.
    pub fn gap(t1: f64, t2: f64) -> f64 {
        let (b1, b2) = tips(t1, t2);
        (b1[0] - b2[0]).hypot(b1[1] - b2[1])
    }

    /// Assembly modes by circle intersection.
    pub fn modes(t1: f64, t2: f64, r1: f64, r2: f64) -> usize {
        let d = gap(t1, t2);
        if d > r1 + r2 || d < (r1 - r2).abs() {
            0
        } else if d == r1 + r2 || d == (r1 - r2).abs() {
            1
        } else {
            2
        }
    }

    /// Critical points of f = |B1 − B2|² on the torus: Newton on ∇f from a grid, deduplicated.
    /// A singular point of a level set of f is one of them (the cusps and nodes of the image).
    pub fn critical_points() -> Vec<(f64, f64)> {
        let grad = |t1: f64, t2: f64| {
            let (b1, b2) = tips(t1, t2);
            let d = [b1[0] - b2[0], b1[1] - b2[1]];
            [2.0 * (d[0] * -2.0 * t1.sin() + d[1] * 2.0 * t1.cos()), -2.0 * (d[0] * -2.0 * t2.sin() + d[1] * 2.0 * t2.cos())]
        };
        let mut out: Vec<(f64, f64)> = Vec::new();
        let n = 40;
        for i in 0..n {
            for j in 0..n {
                let (mut x, mut y) = (-PI + 2.0 * PI * i as f64 / n as f64, -PI + 2.0 * PI * j as f64 / n as f64);
                for _ in 0..60 {
                    let g = grad(x, y);
                    let h = 1e-6;
                    let (gx, gy) = (grad(x + h, y), grad(x, y + h));
                    let m = [[(gx[0] - g[0]) / h, (gy[0] - g[0]) / h], [(gx[1] - g[1]) / h, (gy[1] - g[1]) / h]];
                    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
                    if det.abs() < 1e-12 {
                        break;
                    }
                    x -= (g[0] * m[1][1] - g[1] * m[0][1]) / det;
                    y -= (m[0][0] * g[1] - m[1][0] * g[0]) / det;
                }
                let g = grad(x, y);
                let (x, y) = ((x + PI).rem_euclid(2.0 * PI) - PI, (y + PI).rem_euclid(2.0 * PI) - PI);
                if g[0].hypot(g[1]) < 1e-10 && !out.iter().any(|&(a, b)| super::angle_gap(a, x) < 1e-6 && super::angle_gap(b, y) < 1e-6) {
                    out.push((x, y));
                }
            }
        }
        out
    }

    /// Points of the type-II image: grid edges where the number of modes changes, bisected.
    pub fn curve_points(n: usize, r1: f64, r2: f64) -> Vec<(f64, f64)> {
        let step = 2.0 * PI / n as f64;
        let at = |k: usize| -PI + step * k as f64;
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let a = (at(i), at(j));
                let here = modes(a.0, a.1, r1, r2);
                for (di, dj) in [(1.0, 0.0), (0.0, 1.0)] {
                    let b = (a.0 + di * step, a.1 + dj * step);
                    if modes(b.0, b.1, r1, r2) == here {
                        continue;
                    }
                    let (mut lo, mut hi) = (0.0, 1.0);
                    for _ in 0..50 {
                        let m = 0.5 * (lo + hi);
                        if modes(a.0 + m * (b.0 - a.0), a.1 + m * (b.1 - a.1), r1, r2) == here {
                            lo = m;
                        } else {
                            hi = m;
                        }
                    }
                    let m = 0.5 * (lo + hi);
                    out.push((a.0 + m * (b.0 - a.0), a.1 + m * (b.1 - a.1)));
                }
            }
        }
        out
    }

    /// ActuatorRegions of the torus cut by the levels |r1 ± r2| of the gap: connected components of a
    /// grid's cells by band (below, between, above), with the modes of each (4-neighbours, wrapping).
    pub fn regions(n: usize, r1: f64, r2: f64) -> Vec<usize> {
        let step = 2.0 * PI / n as f64;
        let band = |i: usize, j: usize| {
            let d = gap(-PI + step * (i as f64 + 0.5), -PI + step * (j as f64 + 0.5));
            (d > (r1 - r2).abs()) as u8 + (d > r1 + r2) as u8
        };
        let mut label = vec![usize::MAX; n * n];
        let mut modes_of = Vec::new();
        for s in 0..n * n {
            if label[s] != usize::MAX {
                continue;
            }
            let id = modes_of.len();
            let b = band(s / n, s % n);
            modes_of.push(if b == 1 { 2 } else { 0 });
            label[s] = id;
            let mut stack = vec![s];
            while let Some(c) = stack.pop() {
                let (i, j) = (c / n, c % n);
                for (a, b2) in [((i + 1) % n, j), ((i + n - 1) % n, j), (i, (j + 1) % n), (i, (j + n - 1) % n)] {
                    let k = a * n + b2;
                    if label[k] == usize::MAX && band(a, b2) == b {
                        label[k] = id;
                        stack.push(k);
                    }
                }
            }
        }
        modes_of
    }
}

const FIVE_BAR_ACTUATORS: [&str; 2] = ["crank1_joint", "crank2_joint"];

/// The generic five-bar (rods 2.5 and 2): its type-II image is the two regular level sets
/// |B1 − B2| = 4.5 and 0.5, so no cusp and no node (the critical values of the gap are 0, 1.5,
/// 2.5, 5.5, found by Newton on its gradient); four regions (between the levels, 2 modes; above
/// 4.5 and the two discs below 0.5, none), counted on a grid of our own; and no assembly-mode
/// change without crossing: the verdict is "no".
#[test]
fn five_bar_image_has_no_cusp_no_node_and_four_regions_as_the_references() {
    use five_bar_ref::*;
    let (r1, r2) = (2.5, 2.0);
    let critical = critical_points();
    assert_eq!(critical.len(), 6, "critical points of the gap: {critical:?}");
    for &(a, b) in &critical {
        let d = gap(a, b);
        assert!((d - (r1 + r2)).abs() > 0.1 && (d - (r1 - r2)).abs() > 0.1, "critical point ({a}, {b}) at gap {d} lies on a type-II level");
    }
    let reference_regions = regions(256, r1, r2);
    assert_eq!(reference_regions.len(), 4);

    let m = urdf::parse(&urdf_text("five_bar_unequal.urdf")).expect("parses");
    let actuated: Vec<String> = FIVE_BAR_ACTUATORS.iter().map(|s| s.to_string()).collect();
    let settings = SolverSettings { sigma: 1e-2, ..Default::default() };
    let r = linkspace::app::analyse_image(&m, &[], &actuated, &settings, 64, &AtomicBool::new(false)).expect("analyses");
    assert!(r.status.is_complete());
    assert_eq!((r.cusp_counts.proven, r.cusp_counts.undecided), (0, 0), "cusps {:?}", r.cusps);
    // The cusp search alone (`--kind cusps`) agrees: none, proven.
    let alone = linkspace::app::image_points(&m, &[], &actuated, linkspace::app::ImageSearch::Cusps, &settings, &AtomicBool::new(false)).expect("runs");
    assert_eq!((alone.status.is_complete(), alone.counts.proven, alone.counts.undecided, alone.cusps.len()), (true, 0, 0, 0));
    assert_eq!((r.node_counts.proven, r.node_counts.undecided), (0, 0), "nodes {:?}", r.nodes);
    assert!(r.injective > 0);
    assert_eq!(r.regions.regions.len(), reference_regions.len());
    let mut got: Vec<usize> = Vec::new();
    for g in &r.regions.regions {
        let expected = modes(g.sample[0], g.sample[1], r1, r2);
        assert_eq!(g.configurations, Some(expected), "region at {:?}", g.sample);
        if expected == 2 {
            assert_eq!(g.signs, Some([1, 1]), "the two modes have opposite det F_p");
        }
        got.push(expected);
    }
    let mut want = reference_regions.clone();
    got.sort();
    want.sort();
    assert_eq!(got, want);
    assert_eq!(r.verdict.answer, Some(false), "{}", r.verdict.reason);

    // The cover the regions were cut by holds every reference point of both curves.
    let (p, set) = run(&urdf_text("five_bar_unequal.urdf"), SingularKind::Input, &FIVE_BAR_ACTUATORS, None, 1e-2);
    let images: Vec<Vec<(f64, f64)>> = set.boxes.iter().map(|b| p.actuator_values(&b.b)).collect();
    let points = curve_points(200, r1, r2);
    assert!(points.len() > 200);
    for &(a, b) in &points {
        assert!(images.iter().any(|im| holds_angle(im[0], a, 1e-6) && holds_angle(im[1], b, 1e-6)), "reference point ({a}, {b}) not covered");
    }
}

/// The bundled five-bar's equal rods fold onto each other over a whole circle of configurations
/// where the crank tips meet (two actuator points, the minima of the gap): along that circle
/// the kernel of the actuator map is the circle's tangent, so the cusp system has a curve of
/// roots there. The search reports exactly those (never proven, never elsewhere), against the
/// two points found by Newton on B1 = B2.
#[test]
fn five_bar_equal_rods_cusp_roots_are_the_folded_circles() {
    use five_bar_ref::*;
    let critical = critical_points();
    let meets: Vec<(f64, f64)> = critical.iter().copied().filter(|&(a, b)| gap(a, b) < 1e-9).collect();
    assert_eq!(meets.len(), 2, "{critical:?}");
    let m = urdf::parse(&urdf_text("five_bar.urdf")).expect("parses");
    let actuated: Vec<String> = FIVE_BAR_ACTUATORS.iter().map(|s| s.to_string()).collect();
    let p = SingularProblem::new(&m, &[], SingularKind::Input, &actuated, None).expect("builds");
    let cusps = CuspProblem::new(&m, &p).expect("2 dof").solve(&p, &SolverSettings { sigma: 5e-2, ..Default::default() }, &AtomicBool::new(false)).expect("runs");
    assert_eq!(cusps.status, Status::Finished);
    assert_eq!(cusps.proven(), 0);
    assert!(!cusps.points.is_empty());
    // Each record says why it is undecided: a curve of roots is never proven.
    for r in linkspace::analyses::loop_singular::image::cusp_records(&p, &cusps) {
        assert!(!r.unique && r.reason.as_deref().is_some_and(|why| why.contains("without a Krawczyk proof") || why.contains("μ may vanish")), "{r:?}");
    }
    let mut hit = [false; 2];
    for pt in &cusps.points {
        for b in &pt.boxes {
            let v = p.actuator_values(b);
            let near: Vec<usize> = (0..2).filter(|&i| holds_angle(v[0], meets[i].0, 1e-6) && holds_angle(v[1], meets[i].1, 1e-6)).collect();
            assert_eq!(near.len(), 1, "cusp-system box at {v:?} is not over a point where the tips meet");
            hit[near[0]] = true;
        }
    }
    assert_eq!(hit, [true, true]);
}

/// The bundled 3-RPR with leg 3 locked at ρ3 = 17, parametrised by the angle α3 of leg 3 and the
/// platform's angle φ (B3 on the circle about A3, B1 and B2 from the platform), so that C is the
/// torus and the actuator map (α3, φ) ↦ (ρ1, ρ2) = (|B1 − A1|, |B2 − A2|) is explicit. Its
/// cusps: zeros of (J, ∇J·k), J the map's Jacobian determinant and k its kernel, by Newton
/// (central differences) from a grid. No solver.
pub(crate) mod three_rpr_ref {
    use std::f64::consts::PI;

    const A: [[f64; 2]; 3] = [[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]];
    /// Platform points in the platform frame, as written in `three_rpr.urdf`.
    const B: [[f64; 2]; 3] = [[0.0, 0.0], [17.04, 0.0], [13.236373, 16.096708]];

    pub fn rho(a3: f64, phi: f64, r3: f64) -> [f64; 2] {
        let b3 = [A[2][0] + r3 * a3.cos(), A[2][1] + r3 * a3.sin()];
        let rot = |v: [f64; 2]| [phi.cos() * v[0] - phi.sin() * v[1], phi.sin() * v[0] + phi.cos() * v[1]];
        let (r3v, r2v) = (rot(B[2]), rot(B[1]));
        let b1 = [b3[0] - r3v[0], b3[1] - r3v[1]];
        let b2 = [b1[0] + r2v[0], b1[1] + r2v[1]];
        [(b1[0] - A[0][0]).hypot(b1[1] - A[0][1]), (b2[0] - A[1][0]).hypot(b2[1] - A[1][1])]
    }

    fn jac(a: f64, f: f64, r3: f64) -> [[f64; 2]; 2] {
        let h = 1e-5;
        let (pa, ma, pf, mf) = (rho(a + h, f, r3), rho(a - h, f, r3), rho(a, f + h, r3), rho(a, f - h, r3));
        [[(pa[0] - ma[0]) / (2.0 * h), (pf[0] - mf[0]) / (2.0 * h)], [(pa[1] - ma[1]) / (2.0 * h), (pf[1] - mf[1]) / (2.0 * h)]]
    }

    fn det(a: f64, f: f64, r3: f64) -> f64 {
        let m = jac(a, f, r3);
        m[0][0] * m[1][1] - m[0][1] * m[1][0]
    }

    /// ∇J along the kernel of the Jacobian: zero where the kernel is tangent to J = 0.
    fn tangency(a: f64, f: f64, r3: f64) -> f64 {
        let m = jac(a, f, r3);
        let k = if m[0][0].abs() + m[0][1].abs() >= m[1][0].abs() + m[1][1].abs() { [-m[0][1], m[0][0]] } else { [-m[1][1], m[1][0]] };
        let h = 1e-3;
        let ja = (det(a + h, f, r3) - det(a - h, f, r3)) / (2.0 * h);
        let jf = (det(a, f + h, r3) - det(a, f - h, r3)) / (2.0 * h);
        ja * k[0] + jf * k[1]
    }

    /// The cusps' images (ρ1, ρ2).
    pub fn cusps(r3: f64) -> Vec<[f64; 2]> {
        let mut found: Vec<(f64, f64)> = Vec::new();
        let n = 48;
        for i in 0..n {
            for j in 0..n {
                let (mut x, mut y) = (-PI + 2.0 * PI * (i as f64 + 0.5) / n as f64, -PI + 2.0 * PI * (j as f64 + 0.5) / n as f64);
                let mut converged = false;
                for _ in 0..50 {
                    let f = [det(x, y, r3), tangency(x, y, r3)];
                    let e = 1e-4;
                    let (fx, fy) = ([det(x + e, y, r3), tangency(x + e, y, r3)], [det(x, y + e, r3), tangency(x, y + e, r3)]);
                    let m = [[(fx[0] - f[0]) / e, (fy[0] - f[0]) / e], [(fx[1] - f[1]) / e, (fy[1] - f[1]) / e]];
                    let d = m[0][0] * m[1][1] - m[0][1] * m[1][0];
                    if d == 0.0 || !d.is_finite() {
                        break;
                    }
                    let (dx, dy) = ((f[0] * m[1][1] - f[1] * m[0][1]) / d, (m[0][0] * f[1] - m[1][0] * f[0]) / d);
                    x -= dx;
                    y -= dy;
                    if dx.abs() + dy.abs() > 1.0 {
                        break;
                    }
                    if dx.abs() + dy.abs() < 1e-9 {
                        converged = true;
                        break;
                    }
                }
                let (x, y) = ((x + PI).rem_euclid(2.0 * PI) - PI, (y + PI).rem_euclid(2.0 * PI) - PI);
                if converged && !found.iter().any(|&(u, v)| super::angle_gap(u, x) < 1e-5 && super::angle_gap(v, y) < 1e-5) {
                    found.push((x, y));
                }
            }
        }
        found.into_iter().map(|(x, y)| rho(x, y, r3)).collect()
    }
}

/// The 3-RPR with ρ3 = 17 in `formulation`: every cusp of its type-II image in (ρ1, ρ2)
/// certified, against the independent Newton of `three_rpr_ref` (none missed, none extra).
fn three_rpr_cusps_match(formulation: CuspFormulation) {
    let reference = three_rpr_ref::cusps(17.0);
    assert_eq!(reference.len(), 6, "{reference:?}");
    let m = urdf::parse(&urdf_text("three_rpr.urdf")).expect("parses");
    let actuated = vec!["rho1".to_string(), "rho2".to_string()];
    let p = SingularProblem::new(&m, &[("rho3".to_string(), 17.0)], SingularKind::Input, &actuated, None).expect("builds");
    let cp = CuspProblem::with_formulation(&m, &p, formulation).expect("2 dof");
    assert_eq!(cp.formulation, formulation);
    let cusps = cp.solve(&p, &SolverSettings { sigma: 1e-3, ..Default::default() }, &AtomicBool::new(false)).expect("runs");
    assert_eq!(cusps.status, Status::Finished);
    let images: Vec<(Vec<(f64, f64)>, bool)> = cusps
        .points
        .iter()
        .map(|pt| {
            let mut hull = vec![(f64::INFINITY, f64::NEG_INFINITY); 2];
            for b in &pt.boxes {
                for (h, v) in hull.iter_mut().zip(cp.actuator_values(&p, b)) {
                    *h = (h.0.min(v.0), h.1.max(v.1));
                }
            }
            (hull, pt.certified() && !pt.degenerate)
        })
        .collect();
    assert_eq!(images.len(), reference.len(), "solver {images:?}\nreference {reference:?}");
    for (hull, certified) in &images {
        assert!(certified, "cusp at {hull:?} not certified");
        let n = reference.iter().filter(|r| (0..2).all(|i| hull[i].0 - 1e-5 <= r[i] && r[i] <= hull[i].1 + 1e-5)).count();
        assert_eq!(n, 1, "cusp at {hull:?} holds {n} reference cusps");
    }
    assert_eq!(cusps.proven(), reference.len());
}

/// The default (`Auto`) picks the torus formulation for the 3-RPR.
#[test]
fn three_rpr_cusps_match_an_independent_newton() {
    let m = urdf::parse(&urdf_text("three_rpr.urdf")).expect("parses");
    let p = SingularProblem::new(&m, &[("rho3".to_string(), 17.0)], SingularKind::Input, &["rho1".to_string(), "rho2".to_string()], None).expect("builds");
    assert_eq!(CuspProblem::new(&m, &p).expect("2 dof").formulation, CuspFormulation::Torus);
    three_rpr_cusps_match(CuspFormulation::Torus);
}

/// The pose formulation (the platform's angles with the null vector and tangent as unknowns)
/// finds the same cusps.
#[test]
fn three_rpr_cusps_in_pose_coordinates_match_an_independent_newton() {
    three_rpr_cusps_match(CuspFormulation::Pose);
}

/// The joint-coordinate formulation finds the same cusps; it runs in scaled widths
/// (`CuspProblem::solve`): in absolute widths it ran over ten minutes without finishing (16 of
/// its 36 chart pairs open; see `diag_three_rpr_cusp_charts`).
#[test]
#[ignore = "long: about 40 s"]
fn three_rpr_cusps_in_joint_coordinates_match_an_independent_newton() {
    three_rpr_cusps_match(CuspFormulation::Coordinates);
}

/// `loop-singularities --kind cusps` on the 3-RPR (ρ3 = 17): the cusp system solved on its own,
/// without the type-II cover; every cusp of the reference in one certified record of its own,
/// none extra, none undecided.
#[test]
fn three_rpr_cusps_alone_on_the_command_line_match_an_independent_newton() {
    three_rpr_cusps_on_the_command_line("1e-3");
}

/// At the image's sigma (5e-2) the first search leaves three cusps in unproven clusters; their
/// finer re-search proves them: the same six certified records.
#[test]
fn three_rpr_cusps_at_a_coarse_sigma_are_proven_by_refinement() {
    three_rpr_cusps_on_the_command_line("5e-2");
}

fn three_rpr_cusps_on_the_command_line(sigma: &str) {
    let reference = three_rpr_ref::cusps(17.0);
    let path = std::env::temp_dir().join(format!("linkspace-three-rpr-cusps-{sigma}-{}.json", std::process::id()));
    let urdf = format!("{}/urdf/three_rpr.urdf", env!("CARGO_MANIFEST_DIR"));
    let args = ["loop-singularities", &urdf, "--fix", "rho3=17", "--actuated", "rho1,rho2", "--kind", "cusps", "--sigma", sigma, "--threads", "1", "--json", path.to_str().expect("utf-8")];
    let out = Command::new(env!("CARGO_BIN_EXE_linkspace")).args(args).output().expect("binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("type-II image cusps: 6 proven, 0 undecided; status complete"), "{text}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).expect("written")).expect("json");
    let _ = std::fs::remove_file(&path);
    assert_eq!((r["counts"]["proven"].as_u64(), r["counts"]["undecided"].as_u64(), r["status"].as_str()), (Some(6), Some(0), Some("complete")));
    let cusps = r["cusps"].as_array().expect("cusps");
    assert_eq!(cusps.len(), reference.len());
    for c in cusps {
        assert_eq!(c["unique"], true, "{c}");
        assert!(c.get("reason").is_none(), "a certified cusp carries no reason: {c}");
        let hull = |j: &str| (c["workspace"][j][0].as_f64().expect("lower"), c["workspace"][j][1].as_f64().expect("upper"));
        let (r1, r2) = (hull("rho1"), hull("rho2"));
        let n = reference.iter().filter(|x| r1.0 - 1e-5 <= x[0] && x[0] <= r1.1 + 1e-5 && r2.0 - 1e-5 <= x[1] && x[1] <= r2.1 + 1e-5).count();
        assert_eq!(n, 1, "record {c} holds {n} reference cusps");
    }
}

/// The whole type-II image of the 3-RPR at ρ3 = 17 at the image's sigma (5e-2): complete,
/// nothing undecided, verdict yes; its cusps are those of the cusp search alone, all six of the
/// independent Newton; and over each region's sample, where the count is stable a quarter
/// away, as many assembly modes as the independent count of poses (`sweeps::poses`, roots in
/// the platform angle of the leg equations, no solver).
#[test]
fn three_rpr_whole_image_is_complete_and_matches_independent_counts() {
    let m = urdf::parse(&urdf_text("three_rpr.urdf")).expect("parses");
    let (fixed, actuated) = (vec![("rho3".to_string(), 17.0)], vec!["rho1".to_string(), "rho2".to_string()]);
    let settings = SolverSettings { sigma: 5e-2, threads: 1, timeout: Some(std::time::Duration::from_secs(120)), ..Default::default() };
    let image = linkspace::app::analyse_image(&m, &fixed, &actuated, &settings, 128, &AtomicBool::new(false)).expect("analyses");
    assert!(image.status.is_complete(), "{:?} {:?} {:?}", image.cusp_counts, image.node_counts, image.regions.regions.iter().map(|r| r.configurations).collect::<Vec<_>>());
    assert_eq!((image.cusp_counts.proven, image.cusp_counts.undecided), (6, 0));
    assert_eq!(image.node_counts.undecided, 0);
    assert_eq!(image.verdict.answer, Some(true));
    let reference = three_rpr_ref::cusps(17.0);
    for c in &image.cusps {
        let (r1, r2) = (c.workspace["rho1"], c.workspace["rho2"]);
        let n = reference.iter().filter(|x| r1[0] - 1e-5 <= x[0] && x[0] <= r1[1] + 1e-5 && r2[0] - 1e-5 <= x[1] && x[1] <= r2[1] + 1e-5).count();
        assert_eq!(n, 1, "cusp {c:?} holds {n} reference cusps");
    }
    let alone = linkspace::app::image_points(&m, &fixed, &actuated, linkspace::app::ImageSearch::Cusps, &settings, &AtomicBool::new(false)).expect("runs");
    let records = |cusps: &[linkspace::analyses::loop_singular::image::ImageCusp]| cusps.iter().map(|c| (c.workspace.clone(), c.unique, c.reason.clone())).collect::<Vec<_>>();
    assert_eq!(records(&image.cusps), records(&alone.cusps));
    let mut checked = std::collections::BTreeSet::new();
    for r in &image.regions.regions {
        let count = r.configurations.expect("every region counted");
        let [p, n] = r.signs.expect("every sign proven");
        assert_eq!(p + n, count);
        let here = crate::sweeps::poses([r.sample[0], r.sample[1], 17.0]);
        let stable = [(0.25, 0.0), (-0.25, 0.0), (0.0, 0.25), (0.0, -0.25)].iter().all(|(a, b)| crate::sweeps::poses([r.sample[0] + a, r.sample[1] + b, 17.0]) == here);
        if stable {
            assert_eq!(count, here, "region sampled at {:?}", r.sample);
            checked.insert(here);
        }
    }
    assert!(checked.len() >= 3, "counts checked: {checked:?}");
}

/// Diagnostics, not a check: per cusp chart pair of the 3-RPR (rho3 = 17), the solver's counters
/// within `DIAG_SECS` seconds a chart (default 10). Knobs: `DIAG_LP=0` (propagation only),
/// `DIAG_NW` (newton_width), `DIAG_RHO`, `DIAG_SCALED=1` (scaled widths), `DIAG_VARS=1` (print the
/// primaries), `DIAG_SIGMA`, `DIAG_DERIVED=v,w,mu` (those variables made derived:
/// not bisected, not LP targets), `DIAG_CHARTS="0,0;1,3"`, `DIAG_COVER=S` (also time the
/// type-II cover at sigma S, 120 s at most). Run:
/// `cargo test --release --test integration closed_loop_singularities::diag -- --ignored --nocapture`.
#[test]
#[ignore = "diagnostics (minutes)"]
fn diag_three_rpr_cusp_charts() {
    use linkspace::kernel::system::VarRole;
    let env = |k: &str, d: &str| std::env::var(k).unwrap_or_else(|_| d.to_string());
    let m = urdf::parse(&urdf_text("three_rpr.urdf")).expect("parses");
    let actuated = vec!["rho1".to_string(), "rho2".to_string()];
    let p = SingularProblem::new(&m, &[("rho3".to_string(), 17.0)], SingularKind::Input, &actuated, None).expect("builds");
    let cp = CuspProblem::with_formulation(&m, &p, CuspFormulation::Coordinates).expect("2 dof");
    let secs: u64 = env("DIAG_SECS", "10").parse().unwrap();
    let use_lp = env("DIAG_LP", "1") == "1";
    let nw: f64 = env("DIAG_NW", "0.25").parse().unwrap();
    let sigma: f64 = env("DIAG_SIGMA", "1e-3").parse().unwrap();
    let derived = env("DIAG_DERIVED", "");
    let only = env("DIAG_CHARTS", "");
    let scaled_widths = env("DIAG_SCALED", "0") == "1";
    if let Ok(cs) = std::env::var("DIAG_COVER") {
        let t = std::time::Instant::now();
        let set = p.solve(&SolverSettings { sigma: cs.parse().unwrap(), use_lp, scaled_widths, timeout: Some(std::time::Duration::from_secs(120)), ..Default::default() }, &AtomicBool::new(false)).unwrap();
        let processed: u64 = set.stats.iter().map(|s| s.processed).sum();
        eprintln!("cover at {cs}: {:?} {} boxes, {} clusters, processed {processed}, {:.2}s", set.status, set.boxes.len(), set.clusters.len(), t.elapsed().as_secs_f64());
    }
    if env("DIAG_VARS", "0") == "1" {
        let s = &cp.charts[0].1;
        let names: Vec<String> = s.primaries().iter().map(|&i| format!("{} {:?}", s.vars[i].name, s.vars[i].domain)).collect();
        eprintln!("{} vars, {} equations, {} primaries: {names:?}", s.vars.len(), s.equations.len(), names.len());
    }
    let t0 = std::time::Instant::now();
    for ((k, tau), chart) in &cp.charts {
        if !only.is_empty() && !only.split(';').any(|c| c == format!("{k},{tau}")) {
            continue;
        }
        let mut chart = chart.clone();
        for v in chart.vars.iter_mut() {
            if derived.split(',').any(|d| !d.is_empty() && (v.name.starts_with(&format!("{d}_")) || v.name == d)) {
                v.role = VarRole::Derived;
            }
        }
        let rho: f64 = env("DIAG_RHO", "0.95").parse().unwrap();
        let st = SolverSettings { sigma, rho, use_lp, newton_width: nw, scaled_widths, timeout: Some(std::time::Duration::from_secs(secs)), ..Default::default() };
        let e = p.linkage.extended_solver(&chart, st).unwrap().enclose(&AtomicBool::new(false), &mut |_| {});
        if e.stats.processed > 1 {
            eprintln!("chart ({k},{tau}): {:?} processed {} sols {} uniq {} undecided {} maxlvl {} rounds {} lp {} {:.2}s", e.status, e.stats.processed, e.solutions.len(), e.tags.iter().filter(|t| **t == linkspace::app::BoxStatus::Unique).count(), e.undecided.len(), e.stats.max_level, e.stats.shrink_rounds, e.stats.lp.solved, e.stats.seconds);
            for (b, u) in e.solutions.iter().zip(e.tags.iter().map(|t| *t == linkspace::app::BoxStatus::Unique)) {
                eprintln!("   sol {u} {:?}", p.actuator_values(b));
            }
        }
    }
    eprintln!("total {:.1}s", t0.elapsed().as_secs_f64());
}

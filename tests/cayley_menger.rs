//! Test idea: distance problems solved through Cayley–Menger determinants against independent
//! references. The octahedral platform's solutions are checked by placing the platform from the
//! solved distances and measuring every leg again in coordinates; the four-spheres lines are
//! compared with lines found by Newton's method on a coordinate formulation (point + direction),
//! and each is measured against the four centres.

use linkspace::kernel::contract::FaceBounds;
use linkspace::kernel::interval::{components, point};
use linkspace::model::urdf;
use linkspace::formulate::{BuildOptions, CayleyMenger, DistanceProblem, Formulation};
use linkspace::analyses::distances::file as distance_file;
use linkspace::formulate::PlatformProblem;
use linkspace::edges::report::distances::{report, DistancesReport};
use linkspace::kernel::search::{Enclosure, SolverSettings, Status};
use linkspace::kernel::interval::IntervalBox;
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;

/// The octahedral manipulator of Porta, Thomas, Ros and Torras (2003): base side √3, platform side
/// √3/2, legs p1p5, p1p6, p2p6, p2p4, p3p4, p3p5 with squared lengths `legs` in that order.
/// Built by hand, independently of the URDF reader.
pub fn octahedral(legs: [f64; 6]) -> DistanceProblem {
    let mut p = DistanceProblem::new("octahedral");
    let deg = std::f64::consts::PI / 180.0;
    for (k, a) in [0.0f64, 120.0, 240.0].into_iter().enumerate() {
        p.add_point(format!("p{}", k + 1), Some([(a * deg).cos(), (a * deg).sin(), 0.0])).unwrap();
    }
    for k in 4..=6 {
        p.add_point(format!("p{k}"), None).unwrap();
    }
    for (a, b) in [(3, 4), (3, 5), (4, 5)] {
        p.set_known(a, b, point(0.75)).unwrap();
    }
    for ((a, b), r) in [(0, 4), (0, 5), (1, 5), (1, 3), (2, 3), (2, 4)].into_iter().zip(legs) {
        p.set_known(a, b, point(r)).unwrap();
    }
    // Eqs. (6) of Porta et al. (2003), and their Eq. (7) on request.
    p.equations = Some(vec![vec![0, 2, 3, 4, 5], vec![0, 1, 2, 3, 5]]);
    p.redundant = Some(vec![vec![1, 2, 3, 4, 5], vec![0, 1, 3, 4, 5], vec![0, 1, 2, 4, 5], vec![0, 1, 2, 3, 4]]);
    p
}

pub const CONFIG_A: [f64; 6] = [4.25, 5.75, 4.25, 5.75, 4.25, 5.75];
pub const CONFIG_B: [f64; 6] = [4.75; 6];

pub fn solve(cm: &CayleyMenger, faces: FaceBounds, sigma: f64, rho: f64) -> Enclosure {
    let settings = SolverSettings { sigma, rho, ..Default::default() };
    cm.solver(faces, settings).expect("valid").enclose(&AtomicBool::new(false), &mut |_| {})
}

pub fn four_spheres(orient: bool) -> DistanceProblem {
    let mut p = DistanceProblem::new("four_spheres");
    for (k, c) in [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]].into_iter().enumerate() {
        p.add_point(format!("c{}", k + 1), Some(c)).unwrap();
    }
    let t = p.add_point("t", None).unwrap();
    let u = p.add_point("u", None).unwrap();
    let rho2 = 1.45f64 * 1.45;
    p.set_known(0, t, point(rho2)).unwrap();
    p.set_known(0, u, point(rho2) + point(1.0)).unwrap();
    p.set_known(t, u, point(1.0)).unwrap();
    for c in 1..4 {
        p.add_point_line(c, t, u, point(rho2)).unwrap();
    }
    p.lines.push((t, u));
    if orient {
        p.orientations.push(linkspace::formulate::Orientation { a: t, b: u, toward: 1 });
    }
    p
}


const LEGS: [&str; 6] = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"];

fn platform(legs: [f64; 6]) -> PlatformProblem {
    let m = urdf::parse(&crate::util::urdf_text("octahedral.urdf")).expect("bundled URDF parses");
    let fixed: Vec<(String, f64)> = LEGS.iter().map(|l| l.to_string()).zip(legs).collect();
    PlatformProblem::new(&m, &fixed).expect("bundled platform builds")
}

fn shared(redundant: bool) -> BuildOptions {
    BuildOptions { formulation: Formulation::Shared, redundant }
}

fn run_report(p: &PlatformProblem, options: BuildOptions, sigma: f64) -> (CayleyMenger, DistancesReport, Vec<IntervalBox>) {
    let cm = CayleyMenger::build(&p.distances, options).expect("builds");
    let settings = SolverSettings { sigma, rho: 0.9, ..Default::default() };
    let e = solve(&cm, FaceBounds::Corners, sigma, 0.9);
    assert_eq!(e.status, Status::Finished);
    let r = report(&cm, Some(p), BTreeMap::new(), FaceBounds::Corners, &settings, e.status, e.stats, &e.solutions, &e.undecided);
    (cm, r, e.solutions)
}

/// Does some box hold the unknowns `want` (name → exact value)?
fn holds(cm: &CayleyMenger, boxes: &[IntervalBox], want: &[(&str, f64)]) -> bool {
    holds_within(cm, boxes, want, 1e-9)
}

/// The same, allowing `slack` for the rounding of a reference computed in floating point.
fn holds_within(cm: &CayleyMenger, boxes: &[IntervalBox], want: &[(&str, f64)], slack: f64) -> bool {
    boxes.iter().any(|b| {
        let got = cm.unknown_intervals(b);
        want.iter().all(|(n, v)| got.iter().any(|(m, i)| m == n && i.inf() - slack <= *v && *v <= i.sup() + slack))
    })
}

#[test]
fn the_urdf_platform_is_the_seed_formulation() {
    let p = platform(CONFIG_A);
    let by_hand = octahedral(CONFIG_A);
    for a in 0..6 {
        for b in a + 1..6 {
            match (p.distances.known(a, b), by_hand.known(a, b)) {
                (Some(x), Some(y)) => assert!((x.mid() - y.mid()).abs() < 1e-12, "r{}{}", a + 1, b + 1),
                (x, y) => assert_eq!(x.is_some(), y.is_some(), "r{}{}", a + 1, b + 1),
            }
        }
    }
    let cm = CayleyMenger::build(&p.distances, shared(false)).unwrap();
    assert_eq!(cm.labels, ["CM(p1, p3, p4, p5, p6)", "CM(p1, p2, p3, p4, p6)"]);
    assert_eq!(cm.unknowns.iter().map(|u| u.name.as_str()).collect::<Vec<_>>(), ["r(p1,p4)", "r(p3,p6)"]);
    let red = CayleyMenger::build(&p.distances, shared(true)).unwrap();
    assert_eq!(red.equations.len(), 6);
    assert_eq!(red.unknowns.len(), 3);
}

/// Closed form for configuration a (every solution keeps the 3-fold symmetry): the platform stays
/// parallel to the base, turned by θ, at height h, with cos(60°+θ) − cos(300°+θ) = −1.5, so θ = 60°
/// (h = 2, r14 = r36 = 5.75) or θ = 120° (h = √3.5, r14 = r36 = 4.25).
#[test]
fn configuration_a_has_exactly_two_solutions_and_four_poses() {
    let p = platform(CONFIG_A);
    for options in [shared(false), BuildOptions { formulation: Formulation::Split, redundant: false }, shared(true)] {
        let (cm, r, boxes) = run_report(&p, options, 1e-3);
        assert_eq!(r.clusters, 2, "{options:?}");
        for v in [4.25, 5.75] {
            assert!(holds(&cm, &boxes, &[("r(p1,p4)", v), ("r(p3,p6)", v)]), "{options:?} lost r14 = r36 = {v}");
        }
        assert_eq!(r.placements, 4, "{options:?}: two poses and their mirror images");
        let mut found = Vec::new();
        for s in &r.solutions {
            for pose in &s.poses {
                assert!(pose.leg_residual < 1e-2, "legs remeasured on the pose: {pose:?}");
                found.push((pose.position[2], pose.rpy[2]));
            }
        }
        let deg = std::f64::consts::PI / 180.0;
        for (h, yaw) in [(2.0, 60.0 * deg), (3.5f64.sqrt(), 120.0 * deg)] {
            for z in [h, -h] {
                assert!(found.iter().any(|(fz, fy)| (fz - z).abs() < 1e-3 && (fy - yaw).abs() < 1e-3), "{options:?}: no pose at z {z}, yaw {yaw}: {found:?}");
            }
        }
    }
}

fn cm_value(cm: &CayleyMenger, e: usize, x: [f64; 2]) -> f64 {
    cm.equations[e].eval_point(&x)
}

/// Newton's method on the two equations (6) in (r14, r36), with a central-difference Jacobian;
/// returns the distance to `root` after `steps` steps.
#[allow(clippy::needless_range_loop)] // a 2 × 2 Jacobian filled by (equation, variable)
fn newton(cm: &CayleyMenger, start: [f64; 2], root: [f64; 2], steps: usize) -> f64 {
    let mut x = start;
    for _ in 0..steps {
        let h = 1e-6;
        let f = [cm_value(cm, 0, x), cm_value(cm, 1, x)];
        let mut j = [[0.0; 2]; 2];
        for e in 0..2 {
            for v in 0..2 {
                let (mut a, mut b) = (x, x);
                a[v] += h;
                b[v] -= h;
                j[e][v] = (cm_value(cm, e, a) - cm_value(cm, e, b)) / (2.0 * h);
            }
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det == 0.0 {
            break;
        }
        x = [x[0] - (j[1][1] * f[0] - j[0][1] * f[1]) / det, x[1] - (-j[1][0] * f[0] + j[0][0] * f[1]) / det];
    }
    ((x[0] - root[0]).powi(2) + (x[1] - root[1]).powi(2)).sqrt()
}

/// Normalised Jacobian determinant |det J| / (|∇f| |∇g|): 0 where the two curves are tangent.
fn tangency(cm: &CayleyMenger, x: [f64; 2]) -> f64 {
    let h = 1e-5;
    let g = |e: usize| {
        let d = |v: usize| {
            let (mut a, mut b) = (x, x);
            a[v] += h;
            b[v] -= h;
            (cm_value(cm, e, a) - cm_value(cm, e, b)) / (2.0 * h)
        };
        [d(0), d(1)]
    };
    let (f, k) = (g(0), g(1));
    (f[0] * k[1] - f[1] * k[0]).abs() / ((f[0].hypot(f[1])) * (k[0].hypot(k[1])))
}

/// Configuration b: 6 points in (r14, r36), two of them tangencies where two assembly modes
/// share (r14, r36) (closed form: the platform parallel to the base, turned by 0° at h = 2, or by
/// 180° at h = √3, gives r14 = r25 = r36 = 6.25 and 3.25; each shares its (r14, r36) with a mode
/// where r25 differs). The redundant system separates them: 8 modes, 16 poses.
#[test]
fn configuration_b_tangencies_clusters_and_newton() {
    let p = platform(CONFIG_B);
    let (plain, r_plain, boxes_plain) = run_report(&p, shared(false), 1e-3);
    let (red, r_red, boxes_red) = run_report(&p, shared(true), 1e-3);
    for v in [3.25, 6.25] {
        assert!(holds(&plain, &boxes_plain, &[("r(p1,p4)", v), ("r(p3,p6)", v)]), "non-redundant lost the tangency at {v}");
        assert!(holds(&red, &boxes_red, &[("r(p1,p4)", v), ("r(p2,p5)", v), ("r(p3,p6)", v)]), "redundant lost r = {v}");
    }
    // Six distinct points in the (r14, r36) projection of the redundant solution.
    let mut projected: Vec<[f64; 2]> = Vec::new();
    for b in &boxes_red {
        let u = red.unknown_intervals(b);
        let q = [u[0].1.mid(), u[2].1.mid()];
        if !projected.iter().any(|o| (o[0] - q[0]).abs() < 1e-2 && (o[1] - q[1]).abs() < 1e-2) {
            projected.push(q);
        }
    }
    assert_eq!(projected.len(), 6, "{projected:?}");
    assert_eq!(r_red.clusters, 8);
    assert_eq!(r_red.placements, 16);
    for s in &r_red.solutions {
        assert!(s.poses.iter().all(|p| p.leg_residual < 1e-2));
    }
    // Cluster effect at the tangencies: without redundancy many boxes pile up around them; the
    // redundant equations leave at most two per point.
    let near = |cm: &CayleyMenger, boxes: &[IntervalBox], v: f64| {
        boxes.iter().filter(|b| cm.unknown_intervals(b).iter().filter(|(n, _)| n != "r(p2,p5)").all(|(_, i)| (i.mid() - v).abs() < 0.05)).count()
    };
    for v in [3.25, 6.25] {
        let (a, b) = (near(&plain, &boxes_plain, v), near(&red, &boxes_red, v));
        assert!(a >= 5 * b.max(1) && b <= 2, "tangency {v}: {a} boxes without, {b} with redundant equations");
    }
    assert!(r_plain.clusters > 6);
    // Where Newton fails: the Jacobian of Eqs. (6) is singular at the tangencies, not at a
    // transversal root; from 0.05 away Newton creeps there (linear convergence) while the boxes
    // above hold the root with a proof that nothing else is near.
    let a = CayleyMenger::build(&platform(CONFIG_A).distances, shared(false)).unwrap();
    assert!(tangency(&plain, [6.25, 6.25]) < 1e-4 && tangency(&plain, [3.25, 3.25]) < 1e-4);
    assert!(tangency(&a, [4.25, 4.25]) > 1e-2);
    assert!(newton(&a, [4.30, 4.21], [4.25, 4.25], 6) < 1e-9);
    assert!(newton(&plain, [6.30, 6.21], [6.25, 6.25], 6) > 1e-4);
}

#[test]
fn corners_prune_more_than_interval_arithmetic_and_redundancy_helps() {
    // Table I of Porta et al. (2003), qualitatively: interval-arithmetic trapezoids process more
    // boxes.
    for legs in [CONFIG_A, CONFIG_B] {
        let cm = CayleyMenger::build(&octahedral(legs), BuildOptions { formulation: Formulation::Split, redundant: false }).unwrap();
        let corners = solve(&cm, FaceBounds::Corners, 0.1, 0.9);
        let ia = solve(&cm, FaceBounds::IntervalArithmetic, 0.1, 0.9);
        assert!(ia.stats.processed > 5 * corners.stats.processed, "{} vs {}", ia.stats.processed, corners.stats.processed);
    }
    let b = |redundant| solve(&CayleyMenger::build(&octahedral(CONFIG_B), shared(redundant)).unwrap(), FaceBounds::Corners, 1e-3, 0.9);
    assert!(b(true).solutions.len() < b(false).solutions.len());
}

/// Lines tangent to four unit-ish spheres by Newton's method in coordinates, independently of
/// the determinants: unknowns p (a point of the line) and d (its direction), equations
/// |(c_k − p) × d|² = ρ² for the four centres, |d|² = 1, p·d = 0; many deterministic starts.
fn reference_lines(centres: &[Vector3<f64>], rho: f64) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let residual = |x: &[f64; 6]| -> [f64; 6] {
        let p = Vector3::new(x[0], x[1], x[2]);
        let d = Vector3::new(x[3], x[4], x[5]);
        let mut r = [0.0; 6];
        for k in 0..4 {
            r[k] = (centres[k] - p).cross(&d).norm_squared() - rho * rho;
        }
        r[4] = d.norm_squared() - 1.0;
        r[5] = p.dot(&d);
        r
    };
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut found: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
    for _ in 0..3000 {
        let mut x = [rnd(), rnd(), rnd(), rnd(), rnd(), rnd()];
        for _ in 0..40 {
            let f = residual(&x);
            let mut j = nalgebra::Matrix6::zeros();
            for v in 0..6 {
                let (mut a, mut b) = (x, x);
                a[v] += 1e-7;
                b[v] -= 1e-7;
                let (fa, fb) = (residual(&a), residual(&b));
                for e in 0..6 {
                    j[(e, v)] = (fa[e] - fb[e]) / 2e-7;
                }
            }
            let Some(step) = j.lu().solve(&nalgebra::Vector6::from_row_slice(&f)) else { break };
            for v in 0..6 {
                x[v] -= step[v];
            }
        }
        if residual(&x).iter().all(|r| r.abs() < 1e-10) {
            let p = Vector3::new(x[0], x[1], x[2]);
            let mut d = Vector3::new(x[3], x[4], x[5]);
            if d.iter().find(|c| c.abs() > 1e-9).is_some_and(|c| *c < 0.0) {
                d = -d;
            }
            if !found.iter().any(|(q, e)| (q - p).norm() < 1e-6 && (e - d).norm() < 1e-6) {
                found.push((p, d));
            }
        }
    }
    found
}

#[test]
fn the_twelve_lines_tangent_to_four_spheres() {
    let text = std::fs::read_to_string(format!("{}/urdf/four_spheres.json", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let d = distance_file::parse(&text, &[]).unwrap();
    let centres: Vec<Vector3<f64>> = d.points.iter().filter_map(|p| p.xyz).map(|c| Vector3::new(c[0], c[1], c[2])).collect();
    let reference = reference_lines(&centres, 1.45);
    assert_eq!(reference.len(), 12, "Newton reference");
    let cm = CayleyMenger::build(&d, shared(false)).unwrap();
    let settings = SolverSettings { sigma: 0.01, rho: 0.99, ..Default::default() };
    let e = solve(&cm, FaceBounds::Corners, 0.01, 0.99);
    assert_eq!(e.status, Status::Finished);
    let r = report(&cm, None, BTreeMap::new(), FaceBounds::Corners, &settings, e.status, e.stats, &e.solutions, &e.undecided);
    assert_eq!(r.clusters, 12);
    assert_eq!(r.placements, 12);
    // Each reference line is found, and each cluster's line touches all four spheres.
    let mut matched = [false; 12];
    for c in 0..r.clusters {
        let line = &r.solutions.iter().find(|s| s.cluster == c).unwrap().lines[0];
        for (name, dist) in &line.distance_from {
            assert!((dist - 1.45).abs() < 0.01, "cluster {c}: distance from {name} is {dist}");
        }
        let (p, dir) = (Vector3::from(line.point), Vector3::from(line.direction));
        let k = reference.iter().position(|(q, e)| (q - p).norm() < 0.02 && (e - dir).norm().min((e + dir).norm()) < 0.02);
        let k = k.unwrap_or_else(|| panic!("cluster {c}: line {p:?} {dir:?} is none of the reference lines"));
        matched[k] = true;
    }
    assert!(matched.iter().all(|&m| m));
    // Soundness: each reference line's distances (from its tangent point t on sphere 1 and
    // u = t ± direction) lie in some solution box, for the orientation the file keeps.
    for (q, d) in &reference {
        let t = q + d * (centres[0] - q).dot(d);
        let enclosed = [*d, -*d].iter().any(|dir| {
            let u = t + dir;
            let want: Vec<(String, f64)> = (1..4).flat_map(|k| [(format!("r(c{},t)", k + 1), (centres[k] - t).norm_squared()), (format!("r(c{},u)", k + 1), (centres[k] - u).norm_squared())]).collect();
            let want: Vec<(&str, f64)> = want.iter().map(|(n, v)| (n.as_str(), *v)).collect();
            holds_within(&cm, &e.solutions, &want, 1e-7)
        });
        assert!(enclosed, "reference line {q:?} {d:?} is in no solution box");
    }
}

#[test]
fn the_bundled_file_is_the_seeds_four_spheres_and_c1_c2_alone_do_not_decide() {
    let text = std::fs::read_to_string(format!("{}/urdf/four_spheres.json", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let file = distance_file::parse(&text, &[]).unwrap();
    let by_hand = four_spheres(true);
    for a in 0..6 {
        for b in a + 1..6 {
            assert_eq!(file.known(a, b).map(|r| r.mid()), by_hand.known(a, b).map(|r| r.mid()), "pair {a} {b}");
        }
    }
    assert_eq!(file.point_lines, by_hand.point_lines);
    // C1 and C2 only: five equations in six unknowns (the one-dimensional continuum of Porta et al.
    // 2003).
    let mut c12 = four_spheres(true);
    c12.equations = Some(vec![vec![0, 1, 2, 3, 4], vec![0, 1, 2, 3, 5]]);
    let err = CayleyMenger::build(&c12, shared(false)).unwrap_err().to_string();
    assert!(err.contains("underdetermined: 6 unknown squared distances but only 5 equations"), "{err}");
}

/// Without the orientation choice each line comes twice (u on either side of t): at least 24
/// clusters (near a few solutions the clusters split at this sigma), and both orientations of
/// every reference line lie in solution boxes.
#[test]
#[ignore = "long: about 10 s"]
fn both_orientations_give_each_line_twice() {
    let p = four_spheres(false);
    let centres: Vec<Vector3<f64>> = p.points.iter().filter_map(|q| q.xyz).map(|c| Vector3::new(c[0], c[1], c[2])).collect();
    let cm = CayleyMenger::build(&p, shared(false)).unwrap();
    let e = solve(&cm, FaceBounds::Corners, 0.01, 0.99);
    assert_eq!(e.status, Status::Finished);
    assert!(components(&e.solutions).1 >= 24);
    for (q, d) in reference_lines(&centres, 1.45) {
        let t = q + d * (centres[0] - q).dot(&d);
        for dir in [d, -d] {
            let u = t + dir;
            let want: Vec<(String, f64)> = (1..4).flat_map(|k| [(format!("r(c{},t)", k + 1), (centres[k] - t).norm_squared()), (format!("r(c{},u)", k + 1), (centres[k] - u).norm_squared())]).collect();
            let want: Vec<(&str, f64)> = want.iter().map(|(n, v)| (n.as_str(), *v)).collect();
            assert!(holds_within(&cm, &e.solutions, &want, 1e-7), "line {q:?} {dir:?} lost");
        }
    }
}

fn cli(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_linkspace")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into_owned(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn temp(name: &str, text: &str) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!("linkspace-cm-{}-{name}", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn distances_cli_reports_and_rejects_bad_input_in_one_line() {
    let urdf = format!("{}/urdf/octahedral.urdf", env!("CARGO_MANIFEST_DIR"));
    let fix = |vals: [f64; 6]| -> Vec<String> { LEGS.iter().zip(vals).flat_map(|(l, v)| ["--fix".to_string(), format!("{l}={v}")]).collect() };
    let json = std::env::temp_dir().join(format!("linkspace-cm-{}-a.json", std::process::id()));
    let mut args: Vec<String> = vec!["distances".into(), urdf.clone()];
    args.extend(fix(CONFIG_A));
    args.extend(["--json".into(), json.to_str().unwrap().into()]);
    let (ok, out, err) = cli(&args.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert!(ok, "{err}");
    assert!(out.starts_with("octahedral: 4 proven, 0 undecided (2 solution boxes in 2 clusters, 4 distinct poses"), "{out}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let _ = std::fs::remove_file(&json);
    assert_eq!(v["status"], "complete");
    assert_eq!(v["clusters"], 2);
    assert_eq!(v["solutions"][0]["poses"].as_array().unwrap().len(), 2);
    assert!(v["solutions"][0]["distances"]["r(p1,p4)"].is_array());

    let bad = |args: Vec<String>, needle: &str| {
        let (ok, _, err) = cli(&args.iter().map(|s| s.as_str()).collect::<Vec<_>>());
        assert!(!ok && !err.contains("panicked"), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
        assert!(lines[0].starts_with("error: ") && lines[0].contains(needle), "'{}' should mention '{needle}'", lines[0]);
    };
    let with = |vals: [f64; 6]| -> Vec<String> {
        let mut a = vec!["distances".to_string(), urdf.clone()];
        a.extend(fix(vals));
        a
    };
    // Legs p1p5 and p1p6 of squared lengths 0.3 and 5.75 cannot meet the platform side √0.75.
    bad(with([0.3, 5.75, 4.25, 5.75, 4.25, 5.75]), "violate the triangle inequality");
    bad(with(CONFIG_A)[..12].to_vec(), "leg 'leg35' has no --fix value");
    bad(with([20.0, 5.75, 4.25, 5.75, 4.25, 5.75]), "must lie in [0.25, 16]");
    let mut unknown = with(CONFIG_A);
    unknown.extend(["--fix".into(), "leg99=1".into()]);
    bad(unknown, "no leg (prismatic joint) named 'leg99'");
    let collinear = temp("collinear.json", r#"{"points": [{"name": "a", "xyz": [0,0,0]}, {"name": "b", "xyz": [1,0,0]}, {"name": "c", "xyz": [2,0,0]}, {"name": "d"}, {"name": "e"}],
        "distances": [{"between": ["a","d"], "squared": 1}, {"between": ["b","d"], "squared": 1}, {"between": ["c","d"], "squared": 3}, {"between": ["a","e"], "squared": 1}, {"between": ["b","e"], "squared": 1}, {"between": ["c","e"], "squared": 3}]}"#);
    bad(vec!["distances".into(), collinear.to_str().unwrap().into()], "degenerate base: a, b, c are collinear");
    let loose = temp("loose.json", r#"{"points": [{"name": "a", "xyz": [0,0,0]}, {"name": "b", "xyz": [1,0,0]}, {"name": "c", "xyz": [0,1,0]}, {"name": "d"}, {"name": "e"}],
        "distances": [{"between": ["a","d"], "squared": 1}, {"between": ["b","d"], "squared": 1}, {"between": ["a","e"], "squared": 1}]}"#);
    bad(vec!["distances".into(), loose.to_str().unwrap().into()], "underdetermined");
    let broken = temp("broken.json", "{\"points\": [");
    bad(vec!["distances".into(), broken.to_str().unwrap().into()], "malformed distance file");
    bad(vec!["distances".into(), "/nonexistent.json".into()], "reading /nonexistent.json");
    for p in [collinear, loose, broken] {
        let _ = std::fs::remove_file(p);
    }
}

/// The parallel driver gives exactly the serial set of boxes on the distance problems.
#[test]
fn parallel_and_serial_drivers_agree_on_distance_problems() {
    let cases = [(octahedral(CONFIG_A), 1e-3, 0.9), (octahedral(CONFIG_B), 1e-3, 0.9), (four_spheres(true), 0.1, 0.99)];
    for (p, sigma, rho) in cases {
        let cm = CayleyMenger::build(&p, BuildOptions { formulation: Formulation::Shared, redundant: true }).expect("builds");
        let mut sets = Vec::new();
        for threads in [1, 2] {
            let settings = SolverSettings { sigma, rho, threads, ..Default::default() };
            let e = cm.solver(FaceBounds::Corners, settings).expect("valid").enclose(&AtomicBool::new(false), &mut |_| {});
            assert_eq!(e.status, Status::Finished);
            let mut boxes: Vec<Vec<(u64, u64)>> = e.solutions.iter().map(|b| b.dims.iter().map(|d| (d.inf().to_bits(), d.sup().to_bits())).collect()).collect();
            boxes.sort();
            sets.push((boxes, e.stats.processed));
        }
        assert!(!sets[0].0.is_empty());
        assert_eq!(sets[0], sets[1], "{}: 2 threads give other boxes", p.name);
    }
}

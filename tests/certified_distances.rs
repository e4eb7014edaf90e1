//! Test idea (issue 15): every answer of a distance problem is certified or labelled. Proven
//! placements are checked against references computed without the solver: lines tangent to four
//! spheres by floating-point Newton on the point-and-direction system from many seeded starts
//! (a lower bound on the set of lines: every line found must be proven, none lost), and each
//! proven line is measured against the four spheres in coordinates (no spurious one).

use linkspace::contract::FaceBounds;
use linkspace::distances::{solve, Certified, Choice};
use linkspace::interval::point;
use linkspace::problems::cayley_menger::DistanceProblem;
use linkspace::search::SolverSettings;
use nalgebra::{Matrix6, Vector3, Vector6};
use std::sync::atomic::AtomicBool;

use super::cayley_menger::{four_spheres, octahedral, CONFIG_A, CONFIG_B};

fn run(p: &DistanceProblem, choice: Choice, redundant: bool, sigma: f64) -> Certified {
    let settings = SolverSettings { sigma, rho: 0.99, ..Default::default() };
    solve(p, choice, redundant, FaceBounds::Corners, settings, &AtomicBool::new(false)).expect("solves")
}

/// Lines tangent to spheres (centres `c`, radii `r`) from the problem's `t`, `u` (indices 4, 5).
fn spheres(c: [[f64; 3]; 4], r: [f64; 4]) -> DistanceProblem {
    let mut p = DistanceProblem::new("spheres");
    for (k, x) in c.into_iter().enumerate() {
        p.add_point(format!("c{}", k + 1), Some(x)).unwrap();
    }
    let t = p.add_point("t", None).unwrap();
    let u = p.add_point("u", None).unwrap();
    p.set_known(0, t, point(r[0]) * point(r[0])).unwrap();
    p.set_known(0, u, point(r[0]) * point(r[0]) + point(1.0)).unwrap();
    p.set_known(t, u, point(1.0)).unwrap();
    for k in 1..4 {
        p.add_point_line(k, t, u, point(r[k]) * point(r[k])).unwrap();
    }
    p.orientations.push(linkspace::problems::cayley_menger::Orientation { a: t, b: u, toward: 1 });
    p.lines.push((t, u));
    p
}

/// A line as (foot point nearest the origin, direction with a positive first significant part).
fn canonical(p: Vector3<f64>, d: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let d = d.normalize();
    let s = if d.iter().find(|v| v.abs() > 1e-6).is_some_and(|v| *v < 0.0) { -1.0 } else { 1.0 };
    (p - d * p.dot(&d), d * s)
}

/// Reference lines: Newton on `|c_i − p|² − ((c_i − p)·d)² = r_i²`, `p·d = 0`, `|d|² = 1` from
/// `starts` seeded starts, deduplicated. Independent of the solver.
fn reference_lines(c: [[f64; 3]; 4], r: [f64; 4], starts: usize, seed: u64) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut s = seed;
    let mut next = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let c: Vec<Vector3<f64>> = c.iter().map(|x| Vector3::from(*x)).collect();
    let f = |x: &Vector6<f64>| {
        let (p, d) = (Vector3::new(x[0], x[1], x[2]), Vector3::new(x[3], x[4], x[5]));
        let mut v = Vector6::zeros();
        for i in 0..4 {
            let w = c[i] - p;
            v[i] = w.norm_squared() - w.dot(&d).powi(2) - r[i] * r[i];
        }
        v[4] = p.dot(&d);
        v[5] = d.norm_squared() - 1.0;
        v
    };
    let mut found: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
    for _ in 0..starts {
        let mut x = Vector6::new(2.0 * next(), 2.0 * next(), 2.0 * next(), next(), next(), next());
        for _ in 0..60 {
            // Jacobian by central differences: plenty for Newton's quadratic phase in f64.
            let mut j = Matrix6::zeros();
            for k in 0..6 {
                let mut e = Vector6::zeros();
                e[k] = 1e-7;
                j.set_column(k, &((f(&(x + e)) - f(&(x - e))) / 2e-7));
            }
            let Some(step) = j.lu().solve(&f(&x)) else { break };
            x -= step;
        }
        if !(f(&x).amax() < 1e-10) {
            continue;
        }
        let line = canonical(Vector3::new(x[0], x[1], x[2]), Vector3::new(x[3], x[4], x[5]));
        if !found.iter().any(|l| (l.0 - line.0).amax() < 1e-6 && (l.1 - line.1).amax() < 1e-6) {
            found.push(line);
        }
    }
    found
}

/// The proven lines of a run, one per certified placement.
fn proven_lines(c: &Certified) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    c.roots.iter().map(|r| canonical(Vector3::from(r.points[4]), Vector3::from(r.points[5]) - Vector3::from(r.points[4]))).collect()
}

/// Every reference line proven, every proven line tangent to the four spheres, nothing undecided.
fn check_spheres(c: [[f64; 3]; 4], r: [f64; 4], seed: u64) {
    let p = spheres(c, r);
    let out = run(&p, Choice::Auto, false, 0.01);
    let refs = reference_lines(c, r, 3000, seed);
    let lines = proven_lines(&out);
    for l in &lines {
        for i in 0..4 {
            let w = Vector3::from(c[i]) - l.0;
            let dist = (w - l.1 * w.dot(&l.1)).norm();
            assert!((dist - r[i]).abs() < 1e-6, "seed {seed}: proven line {l:?} is at {dist} from c{}, radius {}", i + 1, r[i]);
        }
    }
    for l in &refs {
        assert!(lines.iter().any(|m| (m.0 - l.0).amax() < 1e-5 && (m.1 - l.1).amax() < 1e-5), "seed {seed}: reference line {l:?} lost; proven {lines:?}");
    }
    assert_eq!(out.proven(), lines.len());
    assert_eq!(out.proven(), refs.len(), "seed {seed}: {} proven, {} reference lines", out.proven(), refs.len());
    assert_eq!(out.undecided_regions(), 0, "seed {seed}: {:?}", out.clusters);
    assert!(out.complete());
    assert!(out.clusters.iter().all(|v| v.proven >= 1), "seed {seed}: a cluster without a proven line: {:?}", out.clusters);
}

#[test]
fn four_spheres_twelve_proven_lines_nothing_undecided() {
    let out = run(&four_spheres(true), Choice::Auto, false, 0.01);
    assert_eq!(out.proven(), 12, "{:?}", out.clusters);
    assert_eq!(out.undecided_regions(), 0, "{:?}", out.clusters);
    assert_eq!(out.clusters.len(), 12);
    assert!(out.complete());
}

#[test]
fn other_sphere_sets_give_no_spurious_cluster() {
    let tet = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
    check_spheres(tet, [1.42, 1.44, 1.46, 1.48], 1);
    check_spheres([[0.0, 0.0, 0.0], [2.3, 0.1, -0.2], [0.4, 2.1, 0.3], [0.2, 0.5, 2.6]], [1.5; 4], 2);
}

#[test]
fn randomized_sphere_sets_every_line_proven() {
    let mut s = 0x5eed_u64;
    let mut next = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for seed in 0..4 {
        // A perturbed regular tetrahedron and radii near the value with 12 real lines.
        let base = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
        let c = base.map(|x| x.map(|v| v + 0.2 * (next() - 0.5)));
        let r = [0; 4].map(|_| 1.35 + 0.2 * next());
        check_spheres(c, r, 100 + seed);
    }
}

#[test]
fn octahedral_every_assembly_mode_proven() {
    for (legs, poses) in [(CONFIG_A, 4), (CONFIG_B, 16)] {
        for redundant in [false, true] {
            let out = run(&octahedral(legs), Choice::Auto, redundant, 0.01);
            // Every assembly mode and its mirror image through the base plane.
            assert_eq!(out.proven(), poses, "{legs:?} redundant {redundant}: {:?}", out.clusters);
            // Whatever is not proven says why.
            assert!(out.clusters.iter().all(|v| v.proven > 0 || v.undecided.is_some()));
            if redundant || legs == CONFIG_A {
                assert_eq!(out.undecided_regions(), 0, "{legs:?} redundant {redundant}: {:?}", out.clusters);
            }
        }
    }
}

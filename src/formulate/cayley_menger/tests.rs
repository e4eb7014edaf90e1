//! Unit tests of the Cayley–Menger builder: determinants against volumes, derived rows,
//! the two formulations' degrees, and embeddings.

use super::*;
use nalgebra::Vector3;

fn random_points(seed: u64, n: usize) -> Vec<Vector3<f64>> {
    let mut s = seed;
    let mut next = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
    };
    (0..n).map(|_| Vector3::new(next(), next(), next())).collect()
}

fn entry_of(p: &[Vector3<f64>]) -> impl Fn(usize, usize) -> Poly + '_ {
    move |i, j| Poly::constant(point((p[i] - p[j]).norm_squared()))
}

#[test]
fn determinants_match_the_seed_formulas() {
    for seed in 0..5 {
        let p = random_points(seed, 6);
        let e = entry_of(&p);
        let val = |n: usize| cayley_menger_determinant(n, &e).unwrap().eval(&[]).mid();
        assert!((val(2) - 2.0 * (p[0] - p[1]).norm_squared()).abs() < 1e-9);
        let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
        assert!((val(3) + 16.0 * area * area).abs() < 1e-8);
        let vol = (p[1] - p[0]).dot(&(p[2] - p[0]).cross(&(p[3] - p[0]))) / 6.0;
        assert!((val(4) - 288.0 * vol * vol).abs() < 1e-7 * (1.0 + val(4).abs()));
        assert!(val(5).abs() < 1e-7 * 1e3, "Ξ5 = {}", val(5));
        assert!(val(6).abs() < 1e-6 * 1e4, "Ξ6 = {}", val(6));
    }
    assert!(cayley_menger_determinant(7, &|_, _| Poly::zero()).is_err());
}

#[test]
fn derived_constraints_vanish_where_they_should() {
    let p = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 2.0, 0.0), Vector3::new(2.0, 4.0, 0.0)];
    assert!(collinear(&entry_of(&p)).eval(&[]).contains(0.0));
    // (1, 1, 0) is at distance 1 from the x-axis through (0,0,0) and (2,0,0).
    let r = [Vector3::new(1.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0)];
    assert!(point_line(&entry_of(&r), point(1.0)).eval(&[]).contains(0.0));
    assert!(!point_line(&entry_of(&r), point(1.1)).eval(&[]).contains(0.0));
}

#[test]
fn split_determinants_are_multilinear_and_shared_ones_quadratic() {
    let mut p = DistanceProblem::new("t");
    for (k, c) in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].into_iter().enumerate() {
        p.add_point(format!("b{k}"), Some(c)).unwrap();
    }
    let q = p.add_point("q", None).unwrap();
    // q at (0.5, 0.5, 0.5): the distance to b3 is the unknown.
    for (b, r) in [(0, 0.75), (1, 0.75), (2, 0.75)] {
        p.set_known(q, b, point(r)).unwrap();
    }
    let split = CayleyMenger::build(&p, BuildOptions::default()).unwrap();
    assert!(split.equations.iter().all(|e| e.is_multilinear()));
    assert_eq!(split.unknowns.len(), 1);
    let shared = CayleyMenger::build(&p, BuildOptions { formulation: Formulation::Shared, redundant: false }).unwrap();
    assert!(!shared.equations[0].is_multilinear());
    // The true value 0.75 is a root; 1.0 is not.
    assert!(shared.equations[0].eval(&[point(0.75)]).contains(0.0));
    assert!(!shared.equations[0].eval(&[point(1.0)]).contains(0.0));
}

#[test]
fn embedding_recovers_the_points_up_to_mirror() {
    let pts = random_points(7, 6);
    let mut p = DistanceProblem::new("e");
    for (k, v) in pts.iter().enumerate() {
        p.add_point(format!("p{k}"), (k < 3).then_some([v.x, v.y, v.z])).unwrap();
    }
    let r: Vec<Vec<Option<f64>>> = (0..6).map(|i| (0..6).map(|j| (i != j).then(|| (pts[i] - pts[j]).norm_squared())).collect()).collect();
    let found = embed(&p, &r, 1e-9);
    assert_eq!(found.len(), 2);
    let hit = found.iter().any(|e| e.iter().zip(&pts).all(|(a, b)| (Vector3::new(a[0], a[1], a[2]) - b).norm() < 1e-6));
    assert!(hit, "{found:?} vs {pts:?}");
}

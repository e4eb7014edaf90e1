//! Test idea: every answer of a distance problem is certified or labelled. Proven
//! placements are checked against references computed without the solver: lines tangent to four
//! spheres by floating-point Newton on the point-and-direction system from many seeded starts
//! (a lower bound on the set of lines: every line found must be proven, none lost), and each
//! proven line is measured against the four spheres in coordinates (no spurious one).

use linkspace::kernel::contract::FaceBounds;
use linkspace::analyses::distances::{solve, Certified, Choice};
use linkspace::kernel::interval::point;
use linkspace::formulate::DistanceProblem;
use linkspace::kernel::search::SolverSettings;
use nalgebra::{Matrix6, Vector3, Vector6};
use std::sync::atomic::AtomicBool;

use super::cayley_menger::{four_spheres, octahedral, CONFIG_A, CONFIG_B};

fn run(p: &DistanceProblem, choice: Choice, redundant: bool, sigma: f64) -> Certified {
    let settings = SolverSettings { sigma, rho: 0.99, ..Default::default() };
    solve(p, choice, redundant, FaceBounds::Corners, settings, &AtomicBool::new(false)).expect("solves")
}

/// Lines tangent to spheres (centres `c`, radii `r`) from the problem's `t`, `u` (indices 4, 5).
#[allow(clippy::needless_range_loop)] // point k pairs with radius r[k]
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
    p.orientations.push(linkspace::formulate::Orientation { a: t, b: u, toward: 1 });
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
    // Without the redundant determinants too: the boxes along the common tangent of
    // configuration b's two curves, which no certified placement meets, are searched again with
    // every determinant and proven empty. At sigma 0.1 as well as 0.01.
    for sigma in [0.01, 0.1] {
        for (legs, poses) in [(CONFIG_A, 4), (CONFIG_B, 16)] {
            for redundant in [false, true] {
                let out = run(&octahedral(legs), Choice::Auto, redundant, sigma);
                // Every assembly mode and its mirror image through the base plane.
                assert_eq!(out.proven(), poses, "{legs:?} redundant {redundant} sigma {sigma}: {:?}", out.clusters);
                assert_eq!(out.undecided_regions(), 0, "{legs:?} redundant {redundant} sigma {sigma}: {:?}", out.clusters);
                assert_eq!(out.roots.len(), poses);
                // Each proven placement measured again in coordinates: every leg at its length,
                // the platform triangle intact, and no two placements alike.
                let legs_at = [(0, 4), (0, 5), (1, 5), (1, 3), (2, 3), (2, 4)];
                for r in &out.roots {
                    let d2 = |a: usize, b: usize| (0..3).map(|k| (r.points[a][k] - r.points[b][k]).powi(2)).sum::<f64>();
                    for ((a, b), want) in legs_at.into_iter().zip(legs) {
                        assert!((d2(a, b) - want).abs() < 1e-6, "leg p{}p{}: {} for {want}", a + 1, b + 1, d2(a, b));
                    }
                    for (a, b) in [(3, 4), (3, 5), (4, 5)] {
                        assert!((d2(a, b) - 0.75).abs() < 1e-6);
                    }
                }
                for (i, p) in out.roots.iter().enumerate() {
                    for q in &out.roots[..i] {
                        let apart = p.points.iter().zip(&q.points).flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs())).fold(0.0, f64::max);
                        assert!(apart > 1e-3, "two proven placements alike");
                    }
                }
            }
        }
    }
}

#[test]
fn distinct_placements_count_the_proven_ones_at_coarse_sigma() {
    // Placed from box midpoints and compared within ten box widths, the 16 poses of
    // configuration b came out as 6 at sigma 0.1; from the certified roots, all 16.
    let m = linkspace::model::urdf::parse(&std::fs::read_to_string("urdf/octahedral.urdf").unwrap()).unwrap();
    let fixed: Vec<(String, f64)> = ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"].iter().map(|l| (l.to_string(), 4.75)).collect();
    let platform = linkspace::formulate::PlatformProblem::new(&m, &fixed).unwrap();
    for sigma in [0.01, 0.1] {
        let settings = SolverSettings { sigma, rho: 0.9, ..Default::default() };
        let out = solve(&platform.distances, Choice::Auto, false, FaceBounds::Corners, settings.clone(), &AtomicBool::new(false)).unwrap();
        let rep = linkspace::edges::report::distances::report_certified(&out, Some(&platform), Default::default(), FaceBounds::Corners, &settings);
        assert_eq!((rep.proven, rep.placements), (16, 16), "sigma {sigma}");
    }
    // The four spheres: 12 proven lines, 12 distinct lines, at sigma 0.1 too.
    let settings = SolverSettings { sigma: 0.1, rho: 0.9, ..Default::default() };
    let out = solve(&four_spheres(true), Choice::Auto, false, FaceBounds::Corners, settings.clone(), &AtomicBool::new(false)).unwrap();
    let rep = linkspace::edges::report::distances::report_certified(&out, None, Default::default(), FaceBounds::Corners, &settings);
    assert_eq!((rep.proven, rep.placements), (12, 12));
}

// ---------- references from the resultant (no solver involved) ----------
//
// A line with unit direction d, tangent to sphere 1 at t = c1 + x (x ⟂ d, |x| = r1), is at
// distance r_i from c_i iff 2 x·e_i = r_i² − r1² − |e_i|² + (d·e_i)², e_i = c1 − c_i. So x is a
// quadratic function of d (when the e_i are independent), and with d = (1, s, w) not normalised
// x̃ = adj(E)(K|d|² + (d·e)²) = 2 det(E) |d|² x must satisfy the cubic x̃·d = 0 and the quartic
// |x̃|² = 4 det(E)² r1² |d|⁴ (Macdonald, Pach and Theobald: 12 lines at most). Their resultant in
// w is a polynomial in s of degree 12, computed in 320-bit floating point by evaluation at 13
// points and interpolation; its real roots (Durand–Kerner), then the common real root w of the
// cubic and the quartic, give every line whose direction has a non-zero first component
// (almost all sphere sets).

use astro_float::{BigFloat, RoundingMode};

const BITS: usize = 320;
const RM: RoundingMode = RoundingMode::ToEven;

#[derive(Clone, Debug)]
struct R(BigFloat);

impl R {
    fn f(x: f64) -> R {
        R(BigFloat::from_f64(x, BITS))
    }
    fn add(&self, o: &R) -> R {
        R(self.0.add(&o.0, BITS, RM))
    }
    fn sub(&self, o: &R) -> R {
        R(self.0.sub(&o.0, BITS, RM))
    }
    fn mul(&self, o: &R) -> R {
        R(self.0.mul(&o.0, BITS, RM))
    }
    fn div(&self, o: &R) -> R {
        R(self.0.div(&o.0, BITS, RM))
    }
    fn to_f64(&self) -> f64 {
        // Through the decimal string: astro-float has no direct conversion.
        format!("{}", self.0).parse().expect("a finite number")
    }
    fn abs(&self) -> R {
        R(self.0.abs())
    }
}

/// Complex numbers over R, for Durand–Kerner.
#[derive(Clone, Debug)]
struct C(R, R);

impl C {
    fn add(&self, o: &C) -> C {
        C(self.0.add(&o.0), self.1.add(&o.1))
    }
    fn sub(&self, o: &C) -> C {
        C(self.0.sub(&o.0), self.1.sub(&o.1))
    }
    fn mul(&self, o: &C) -> C {
        C(self.0.mul(&o.0).sub(&self.1.mul(&o.1)), self.0.mul(&o.1).add(&self.1.mul(&o.0)))
    }
    fn div(&self, o: &C) -> C {
        let n = o.0.mul(&o.0).add(&o.1.mul(&o.1));
        let re = self.0.mul(&o.0).add(&self.1.mul(&o.1));
        let im = self.1.mul(&o.0).sub(&self.0.mul(&o.1));
        C(re.div(&n), im.div(&n))
    }
}

/// Bivariate polynomial in (s, w): `c[i][j]` multiplies `s^i w^j`, degrees below 5.
#[derive(Clone)]
struct P2(Vec<Vec<R>>);

impl P2 {
    fn zero() -> P2 {
        P2(vec![vec![R::f(0.0); 5]; 5])
    }
    fn constant(c: &R) -> P2 {
        let mut p = P2::zero();
        p.0[0][0] = c.clone();
        p
    }
    fn add(&self, o: &P2) -> P2 {
        P2((0..5).map(|i| (0..5).map(|j| self.0[i][j].add(&o.0[i][j])).collect()).collect())
    }
    fn scale(&self, c: &R) -> P2 {
        P2(self.0.iter().map(|row| row.iter().map(|v| v.mul(c)).collect()).collect())
    }
    fn mul(&self, o: &P2) -> P2 {
        let mut out = P2::zero();
        for i in 0..5 {
            for j in 0..5 {
                if self.0[i][j].0.is_zero() {
                    continue;
                }
                for k in 0..5 - i {
                    for l in 0..5 - j {
                        if !o.0[k][l].0.is_zero() {
                            out.0[i + k][j + l] = out.0[i + k][j + l].add(&self.0[i][j].mul(&o.0[k][l]));
                        }
                    }
                }
            }
        }
        out
    }
    /// Coefficients in w at a given s.
    fn at_s(&self, s: &R) -> Vec<R> {
        (0..5).map(|j| (0..5).rev().fold(R::f(0.0), |acc, i| acc.mul(s).add(&self.0[i][j]))).collect()
    }
}

/// Horner evaluation of `coef` (low to high) at a complex point.
fn horner(coef: &[R], z: &C) -> C {
    coef.iter().rev().fold(C(R::f(0.0), R::f(0.0)), |acc, c| acc.mul(z).add(&C(c.clone(), R::f(0.0))))
}

/// Every complex root of `coef` (low to high; leading coefficients negligible against the largest
/// are dropped), by Durand–Kerner in 320-bit arithmetic.
fn roots(coef: &[R]) -> Vec<C> {
    let big = coef.iter().map(|c| c.to_f64().abs()).fold(0.0, f64::max);
    let mut n = coef.len();
    while n > 1 && coef[n - 1].to_f64().abs() <= 1e-40 * big {
        n -= 1;
    }
    let lead = coef[n - 1].clone();
    let monic: Vec<R> = coef[..n].iter().map(|c| c.div(&lead)).collect();
    let deg = n - 1;
    let seed = C(R::f(0.4), R::f(0.9));
    let mut z: Vec<C> = Vec::new();
    let mut p = C(R::f(1.0), R::f(0.0));
    for _ in 0..deg {
        z.push(p.clone());
        p = p.mul(&seed);
    }
    for _ in 0..400 {
        let mut moved: f64 = 0.0;
        for k in 0..deg {
            let mut den = C(R::f(1.0), R::f(0.0));
            for m in 0..deg {
                if m != k {
                    den = den.mul(&z[k].sub(&z[m]));
                }
            }
            let step = horner(&monic, &z[k]).div(&den);
            moved = moved.max(step.0.to_f64().abs() + step.1.to_f64().abs());
            z[k] = z[k].sub(&step);
        }
        if moved < 1e-60 {
            break;
        }
    }
    z
}

/// Determinant by Gaussian elimination with partial pivoting.
#[allow(clippy::needless_range_loop)] // Gaussian elimination: indices read as the formula
fn det(mut a: Vec<Vec<R>>) -> R {
    let n = a.len();
    let mut d = R::f(1.0);
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().0.partial_cmp(&a[j][k].abs().0).expect("finite")).expect("rows");
        if p != k {
            a.swap(p, k);
            d = R::f(0.0).sub(&d);
        }
        if a[k][k].0.is_zero() {
            return R::f(0.0);
        }
        d = d.mul(&a[k][k]);
        for i in k + 1..n {
            let f = a[i][k].div(&a[k][k]);
            for j in k..n {
                a[i][j] = a[i][j].sub(&f.mul(&a[k][j]));
            }
        }
    }
    d
}

/// The lines tangent to four spheres, from the resultant; canonical form as `canonical`.
fn resultant_lines(c: [[f64; 3]; 4], r: [f64; 4]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    // A generic rotation first (back at the end), so that no line of a symmetric set has a
    // direction with a zero first component; its rounding moves the centres by ~1e-16.
    let q = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
    let c = c.map(|x| (q * Vector3::from(x)).into());
    let lines = resultant_lines_in_frame(c, r);
    lines.into_iter().map(|(p, d)| canonical(q.inverse() * p, q.inverse() * d)).collect()
}

fn resultant_lines_in_frame(c: [[f64; 3]; 4], r: [f64; 4]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let cr: Vec<Vec<R>> = c.iter().map(|x| x.iter().map(|&v| R::f(v)).collect()).collect();
    let rr: Vec<R> = r.iter().map(|&v| R::f(v).mul(&R::f(v))).collect();
    // e_i = c1 − c_i, K_i = r_i² − r1² − |e_i|².
    let e: Vec<Vec<R>> = (1..4).map(|i| (0..3).map(|k| cr[0][k].sub(&cr[i][k])).collect()).collect();
    let k: Vec<R> = (0..3).map(|i| rr[i + 1].sub(&rr[0]).sub(&e[i].iter().fold(R::f(0.0), |a, v| a.add(&v.mul(v))))).collect();
    // adj(E) with E's rows e_i: adj = cofactor matrixᵀ, E·adj = det·I.
    let m = |i: usize, j: usize| e[i][j].clone();
    let cof = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m(r0, c0).mul(&m(r1, c1)).sub(&m(r0, c1).mul(&m(r1, c0)))
    };
    let det_e = (0..3).fold(R::f(0.0), |a, j| a.add(&m(0, j).mul(&cof(0, j))));
    // x = E⁻¹ q / 2 with (E x)_i = e_i·x: x_j = Σ_i adj_ji q_i / (2 det) and adj_ji = cof(i, j).
    let mut d = [P2::constant(&R::f(1.0)), P2::zero(), P2::zero()];
    d[1].0[1][0] = R::f(1.0);
    d[2].0[0][1] = R::f(1.0);
    let norm = d.iter().fold(P2::zero(), |a, v| a.add(&v.mul(v)));
    let q: Vec<P2> = (0..3).map(|i| {
        let y = (0..3).fold(P2::zero(), |a, kk| a.add(&d[kk].scale(&e[i][kk])));
        norm.scale(&k[i]).add(&y.mul(&y))
    }).collect();
    let xt: Vec<P2> = (0..3).map(|j| (0..3).fold(P2::zero(), |a, i| a.add(&q[i].scale(&cof(i, j))))).collect();
    let f3 = (0..3).fold(P2::zero(), |a, j| a.add(&xt[j].mul(&d[j])));
    let four_det2_a = R::f(4.0).mul(&det_e).mul(&det_e).mul(&rr[0]);
    let f4 = (0..3).fold(P2::zero(), |a, j| a.add(&xt[j].mul(&xt[j]))).add(&norm.mul(&norm).scale(&R::f(0.0).sub(&four_det2_a)));
    // Sylvester matrix of f3 (degree 3 in w) and f4 (degree 4 in w) at s.
    let res = |s: &R| {
        let (a, b) = (f3.at_s(s), f4.at_s(s));
        let mut rows = Vec::new();
        for shift in 0..4 {
            let mut row = vec![R::f(0.0); 7];
            for j in 0..4 {
                row[shift + j] = a[3 - j].clone();
            }
            rows.push(row);
        }
        for shift in 0..3 {
            let mut row = vec![R::f(0.0); 7];
            for j in 0..5 {
                row[shift + j] = b[4 - j].clone();
            }
            rows.push(row);
        }
        det(rows)
    };
    // Interpolation at s = −6..6 (Newton's divided differences, then the monomial form).
    let xs: Vec<R> = (-6..=6).map(|v| R::f(v as f64)).collect();
    let mut dd: Vec<R> = xs.iter().map(&res).collect();
    for l in 1..xs.len() {
        for i in (l..xs.len()).rev() {
            dd[i] = dd[i].sub(&dd[i - 1]).div(&xs[i].sub(&xs[i - l]));
        }
    }
    let mut poly = vec![R::f(0.0); xs.len()];
    for i in (0..xs.len()).rev() {
        // poly = poly·(s − x_i) + dd_i
        let mut next = vec![R::f(0.0); xs.len()];
        for p in 0..xs.len() - 1 {
            next[p + 1] = next[p + 1].add(&poly[p]);
            next[p] = next[p].sub(&poly[p].mul(&xs[i]));
        }
        next[0] = next[0].add(&dd[i]);
        poly = next;
    }
    let mut lines: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
    for z in roots(&poly) {
        if z.1.to_f64().abs() > 1e-25 * (1.0 + z.0.to_f64().abs()) {
            continue;
        }
        let s = z.0.clone();
        // The common real root w of the cubic and the quartic at s.
        let (a, b) = (f3.at_s(&s), f4.at_s(&s));
        let scale4 = b.iter().map(|v| v.to_f64().abs()).fold(0.0, f64::max);
        let best = roots(&a[..4])
            .into_iter()
            .filter(|w| w.1.to_f64().abs() <= 1e-25 * (1.0 + w.0.to_f64().abs()))
            .map(|w| (horner(&b, &C(w.0.clone(), R::f(0.0))).0.to_f64().abs(), w.0))
            .min_by(|x, y| x.0.total_cmp(&y.0));
        let Some((residual, w)) = best else { continue };
        if residual > 1e-30 * scale4.max(1.0) {
            continue;
        }
        let dir = Vector3::new(1.0, s.to_f64(), w.to_f64());
        let n2 = dir.norm_squared();
        // x = x̃ / (2 det |d|²)
        let at = |p: &P2| {
            let co = p.at_s(&s);
            co.iter().rev().fold(R::f(0.0), |acc, v| acc.mul(&w).add(v))
        };
        let x = Vector3::new(at(&xt[0]).to_f64(), at(&xt[1]).to_f64(), at(&xt[2]).to_f64()) / (2.0 * det_e.to_f64() * n2);
        let line = canonical(Vector3::from(c[0]) + x, dir);
        if !lines.iter().any(|l| (l.0 - line.0).amax() < 1e-9 && (l.1 - line.1).amax() < 1e-9) {
            lines.push(line);
        }
    }
    lines
}

#[test]
fn resultant_reference_matches_the_bundled_twelve() {
    let c = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
    // The bundled file's radii: 1.45 (squared 2.1025).
    let lines = resultant_lines(c, [1.45; 4]);
    for l in &lines {
        for ci in c {
            let w = Vector3::from(ci) - l.0;
            assert!(((w - l.1 * w.dot(&l.1)).norm() - 1.45).abs() < 1e-9, "{l:?}");
        }
    }
    assert_eq!(lines.len(), 12, "{lines:?}");
    let out = run(&four_spheres(true), Choice::Auto, false, 0.01);
    let proven = proven_lines(&out);
    for l in &lines {
        assert!(proven.iter().any(|m| (m.0 - l.0).amax() < 1e-6 && (m.1 - l.1).amax() < 1e-6), "{l:?} lost: {proven:?}");
    }
}

/// Sphere sets from a seeded generator: centres in a cube, radii in a range; references from
/// the resultant. Every reference line proven, every proven line a reference line (no spurious
/// one), no cluster without a proven line, nothing undecided.
#[test]
fn randomized_sphere_sets_against_the_resultant() {
    let mut s = 0x15_u64;
    let mut next = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut counts = Vec::new();
    for seed in 0..10 {
        // Half the sets anywhere in a cube, half a perturbed regular tetrahedron with radii
        // around the value that gives 12 lines (so that counts from 0 to 12 come up).
        let c: [[f64; 3]; 4] = if seed % 2 == 0 {
            [0; 4].map(|_| [0; 3].map(|_| 3.0 * (next() - 0.5)))
        } else {
            [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]].map(|x| x.map(|v| v + 0.6 * (next() - 0.5)))
        };
        let r = if seed % 2 == 0 { [0; 4].map(|_| 0.8 + 0.8 * next()) } else { [0; 4].map(|_| 1.3 + 0.3 * next()) };
        let refs = resultant_lines(c, r);
        let out = run(&spheres(c, r), Choice::Auto, false, 0.01);
        let lines = proven_lines(&out);
        counts.push((refs.len(), out.proven(), out.clusters.len()));
        for l in &refs {
            assert!(lines.iter().any(|m| (m.0 - l.0).amax() < 1e-6 && (m.1 - l.1).amax() < 1e-6), "set {seed} {c:?} {r:?}: reference line {l:?} lost; proven {lines:?}");
        }
        for m in &lines {
            assert!(refs.iter().any(|l| (m.0 - l.0).amax() < 1e-6 && (m.1 - l.1).amax() < 1e-6), "set {seed}: proven line {m:?} is not a reference line {refs:?}");
        }
        assert_eq!(out.proven(), refs.len(), "set {seed}");
        assert_eq!(out.undecided_regions(), 0, "set {seed}: {:?}", out.clusters);
        assert!(out.complete(), "set {seed}");
        assert!(out.clusters.iter().all(|v| v.proven == 1), "set {seed}: {:?}", out.clusters);
    }
    eprintln!("(reference lines, proven, clusters) per set: {counts:?}");
    // The generator must exercise more than empty sets.
    assert!(counts.iter().filter(|c| c.0 > 0).count() >= 3, "{counts:?}");
}

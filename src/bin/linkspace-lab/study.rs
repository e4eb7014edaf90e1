//! Stability study: instances built to break solvers, solved by branch and prune and by plain
//! floating-point Newton–Raphson from a grid of starts, with what each finds, misses or
//! duplicates.
//!
//! The references are independent of the solvers: closed forms (circle intersections of the
//! bundled four-bar) and Newton-refined roots of hand-written equations where no closed form
//! exists. No timing is asserted anywhere; the figures are reported.

use linkspace::model::urdf;
use linkspace::formulate::LinkageProblem;
use linkspace::kernel::search::{SolverSettings, Status};
use linkspace::kernel::system::{EquationSystem, Monomial};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

/// Plain Newton–Raphson on a square system from `x`: `Some(root)` when the residual falls
/// below 1e-10 within 60 steps, `None` when it diverges, stalls or meets a singular Jacobian.
pub fn newton_raphson(system: &EquationSystem, mut x: Vec<f64>) -> Option<Vec<f64>> {
    let n = x.len();
    if system.equations.len() != n {
        return None;
    }
    for _ in 0..60 {
        let f = DVector::from_iterator(n, system.equations.iter().map(|e| e.residual(&x)));
        if f.norm() < 1e-10 {
            return Some(x);
        }
        let mut j = DMatrix::zeros(n, n);
        for (k, e) in system.equations.iter().enumerate() {
            for t in &e.terms {
                let c = t.coef.mid();
                match t.mono {
                    Monomial::Linear(v) => j[(k, v)] += c,
                    Monomial::Square(v) => j[(k, v)] += 2.0 * c * x[v],
                    Monomial::Product(a, b) => {
                        j[(k, a)] += c * x[b];
                        j[(k, b)] += c * x[a];
                    }
                }
            }
        }
        let step = j.lu().solve(&(-f))?;
        for (xi, s) in x.iter_mut().zip(step.iter()) {
            *xi += s;
        }
        if !x.iter().all(|v| v.is_finite() && v.abs() < 1e6) {
            return None;
        }
    }
    None
}

/// What each method did on one instance.
#[derive(Clone, Debug, Serialize)]
pub struct Finding {
    /// Instance name.
    pub instance: String,
    /// What makes it hard.
    pub difficulty: String,
    /// Number of reference roots.
    pub reference_roots: usize,
    /// Distance between the two closest reference roots (in the system's variables).
    pub closest_pair: f64,
    /// Branch and prune: solution boxes.
    pub boxes: usize,
    /// Branch and prune: clusters of solution boxes.
    pub clusters: usize,
    /// Branch and prune: certified-unique boxes.
    pub certified: usize,
    /// Branch and prune: reference roots in no solution box (must be 0).
    pub lost: usize,
    /// Branch and prune: seconds.
    pub seconds: f64,
    /// Newton–Raphson: number of starts.
    pub nr_starts: usize,
    /// Newton–Raphson: starts that converged.
    pub nr_converged: usize,
    /// Newton–Raphson: distinct points converged to (1e-6 apart).
    pub nr_distinct: usize,
    /// Newton–Raphson: reference roots no start reached (within 1e-6).
    pub nr_missed: usize,
    /// Newton–Raphson: converged points near no reference root.
    pub nr_spurious: usize,
}

/// One instance: a problem, its references, a sigma, and the starts for Newton–Raphson.
struct Instance {
    name: String,
    difficulty: String,
    problem: LinkageProblem,
    sigma: f64,
    roots: Vec<Vec<f64>>,
    starts: Vec<Vec<f64>>,
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt()
}

fn study(i: &Instance) -> Finding {
    let settings = SolverSettings { sigma: i.sigma, max_boxes: 200_000, ..Default::default() };
    let e = i.problem.solver(settings).expect("invariant: study settings are valid").enclose(&AtomicBool::new(false), &mut |_| {});
    // The reference points are rounded to floats; allow that rounding and nothing more.
    let inside = |x: &[f64]| e.solutions.iter().any(|b| b.dims.iter().zip(x).all(|(d, &v)| d.inf() - 1e-9 <= v && v <= d.sup() + 1e-9));
    let lost = i.roots.iter().filter(|r| !inside(r)).count() + usize::from(e.status != Status::Finished);
    let mut converged: Vec<Vec<f64>> = Vec::new();
    let mut distinct: Vec<Vec<f64>> = Vec::new();
    for s in &i.starts {
        if let Some(x) = newton_raphson(&i.problem.system, s.clone()) {
            if !distinct.iter().any(|d| distance(d, &x) < 1e-6) {
                distinct.push(x.clone());
            }
            converged.push(x);
        }
    }
    let nr_missed = i.roots.iter().filter(|r| !distinct.iter().any(|d| distance(d, r) < 1e-6)).count();
    let nr_spurious = distinct.iter().filter(|d| !i.roots.iter().any(|r| distance(d, r) < 1e-6)).count();
    let mut closest = f64::INFINITY;
    for (k, a) in i.roots.iter().enumerate() {
        for b in &i.roots[k + 1..] {
            closest = closest.min(distance(a, b));
        }
    }
    Finding {
        instance: i.name.clone(),
        difficulty: i.difficulty.clone(),
        reference_roots: i.roots.len(),
        closest_pair: closest,
        boxes: e.solutions.len(),
        clusters: linkspace::kernel::interval::components(&e.solutions).1,
        certified: e.tags.iter().filter(|&&t| t == linkspace::app::BoxStatus::Unique).count(),
        lost,
        seconds: e.stats.seconds,
        nr_starts: i.starts.len(),
        nr_converged: converged.len(),
        nr_distinct: distinct.len(),
        nr_missed,
        nr_spurious,
    }
}

/// The bundled four-bar's dimensions (see its URDF header): crank, coupler, rocker, ground.
const FOUR_BAR: (f64, f64, f64, f64) = (1.5, 4.0, 3.5, 4.0);

/// Rocker angle (its lower limit) where the crank and coupler are stretched in line: the two assembly modes of
/// the rocker-driven four-bar meet there (a double root, singular Jacobian).
pub fn four_bar_tangent_rocker_angle() -> f64 {
    let (a, b, c, d) = FOUR_BAR;
    // |O2 B| = a + b with B = O4 + c·u(θ4).
    (((a + b).powi(2) - d * d - c * c) / (2.0 * d * c)).acos()
}

/// Crank and coupler angles of the rocker-driven four-bar at rocker angle `t4` (0, 1 or 2).
fn four_bar_by_rocker(t4: f64) -> Vec<(f64, f64)> {
    let (a, b, c, d) = FOUR_BAR;
    let pb = [d + c * t4.cos(), c * t4.sin()];
    let dist = (pb[0] * pb[0] + pb[1] * pb[1]).sqrt();
    // Crank tip A on circle(O2, a) ∩ circle(B, b).
    let along = (a * a - b * b + dist * dist) / (2.0 * dist);
    let h2 = a * a - along * along;
    // Rounding at the limit itself may push h² just below zero: that is the double root.
    if h2 < -1e-12 {
        return vec![];
    }
    let h2 = h2.max(0.0);
    let h = h2.sqrt();
    let signs: &[f64] = if h == 0.0 { &[1.0] } else { &[1.0, -1.0] };
    signs
        .iter()
        .map(|s| {
            let pa = [along * pb[0] / dist - s * h * pb[1] / dist, along * pb[1] / dist + s * h * pb[0] / dist];
            (pa[1].atan2(pa[0]), (pb[1] - pa[1]).atan2(pb[0] - pa[0]))
        })
        .collect()
}

fn grid(dims: usize, count: usize) -> Vec<Vec<f64>> {
    // Halton points: deterministic, evenly spread starts in [−π, π]^dims.
    const PRIMES: [u32; 8] = [2, 3, 5, 7, 11, 13, 17, 19];
    (1..=count)
        .map(|k| {
            (0..dims)
                .map(|d| {
                    let (mut f, mut r, mut i, p) = (1.0, 0.0, k as u32, PRIMES[d % 8]);
                    while i > 0 {
                        f /= p as f64;
                        r += f * (i % p) as f64;
                        i /= p;
                    }
                    -PI + 2.0 * PI * r
                })
                .collect()
        })
        .collect()
}

fn four_bar_instance(delta: f64, sigma: f64) -> Instance {
    let m = urdf::parse(include_str!("../../../urdf/four_bar.urdf")).expect("invariant: bundled four-bar parses");
    // The rocker reaches angles at and above the limit: δ > 0 is inside, δ < 0 beyond.
    let t4 = four_bar_tangent_rocker_angle() + delta;
    let problem = LinkageProblem::new(&m, &[("rocker_joint".into(), t4)], &[]).expect("invariant: bundled four-bar builds");
    let point = |t2: f64, t3: f64| {
        let angles: BTreeMap<String, f64> = [("crank".to_string(), t2), ("coupler".to_string(), t3), ("rocker".to_string(), t4), ("ground".to_string(), 0.0)].into_iter().collect();
        problem.point_from(&angles, &BTreeMap::new()).expect("invariant: all angles given")
    };
    let roots = four_bar_by_rocker(t4).into_iter().map(|(t2, t3)| point(t2, t3)).collect();
    let starts = grid(2, 256).into_iter().map(|g| point(g[0], g[1])).collect();
    let (name, difficulty) = if delta == 0.0 {
        ("four-bar, rocker at its limit".to_string(), "double root: the two assembly modes meet, singular Jacobian".to_string())
    } else if delta > 0.0 {
        (format!("four-bar, rocker {delta:.0e} inside its limit, sigma {sigma:.0e}"), "two roots about √δ apart; closer than sigma when δ is small".to_string())
    } else {
        (format!("four-bar, rocker {:.0e} beyond its limit", -delta), "no real root, but a near-root where the residual is tiny".to_string())
    };
    Instance { name, difficulty, problem, sigma, roots, starts }
}

fn butterfly_instance() -> Instance {
    let m = urdf::parse(include_str!("../../../urdf/double_butterfly.urdf")).expect("invariant: bundled butterfly parses");
    let t6 = 12f64.atan2(5.0);
    let problem = LinkageProblem::new(&m, &[("joint6".into(), t6)], &[]).expect("invariant: bundled butterfly builds");
    let point = |t: &[f64]| {
        let mut angles: BTreeMap<String, f64> = [1, 2, 3, 4, 5, 7].iter().zip(t).map(|(i, v)| (format!("link{i}"), *v)).collect();
        angles.insert("link6".into(), t6);
        angles.insert("link0".into(), 0.0);
        problem.point_from(&angles, &BTreeMap::new()).expect("invariant: all angles given")
    };
    // References: the paper's Table I rows (θ1, θ2, θ3, θ4, θ5, θ7), polished by Newton.
    let table = [
        [-0.49432, 0.78082, -0.81924, -2.42719, -0.14221, -2.96808],
        [1.72770, 1.13865, 2.58872, -2.66043, 1.31799, 3.12666],
        [0.55303, -0.71931, -1.20077, -1.96316, -0.13237, -2.96187],
        [-2.66940, -0.64814, -0.40126, 0.56972, 0.41105, 1.54821],
        [-2.25882, 2.77062, -0.24061, -0.01687, 0.41213, 0.86916],
        [0.41351, 2.44496, 2.10929, -2.79537, 1.08684, 2.71005],
    ];
    let roots = table.iter().map(|r| newton_raphson(&problem.system, point(r)).expect("invariant: Table I rows are regular roots")).collect();
    let starts = grid(6, 512).iter().map(|g| point(g)).collect();
    Instance { name: "double butterfly, rigid".into(), difficulty: "six regular roots among eighteen complex ones; a 12-unknown start grid".into(), problem, sigma: 1e-6, roots, starts }
}

/// Runs every planar instance of the study.
pub fn planar_findings() -> Vec<Finding> {
    let mut instances = [butterfly_instance(), four_bar_instance(0.0, 1e-6), four_bar_instance(1e-8, 1e-6), four_bar_instance(1e-8, 1e-3), four_bar_instance(1e-4, 1e-6), four_bar_instance(-1e-8, 1e-6)];
    instances.iter_mut().map(|i| study(i)).collect()
}

/// The rocker-limit family: for each `δ`, (δ, closest reference pair, our clusters, NR distinct
/// roots found, reference roots): how each method resolves two roots as they merge.
pub fn tangency_sweep(deltas: &[f64], sigma: f64) -> Vec<(f64, Finding)> {
    deltas.iter().map(|&d| (d, study(&four_bar_instance(d, sigma)))).collect()
}

/// A Markdown table of findings.
pub fn markdown(findings: &[Finding]) -> String {
    let mut s = String::from("| instance | difficulty | roots | closest pair | our boxes | clusters | certified | lost | s | NR starts | NR converged | NR distinct | NR missed | NR spurious |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for f in findings {
        s += &format!(
            "| {} | {} | {} | {:.1e} | {} | {} | {} | {} | {:.3} | {} | {} | {} | {} | {} |\n",
            f.instance, f.difficulty, f.reference_roots, f.closest_pair, f.boxes, f.clusters, f.certified, f.lost, f.seconds, f.nr_starts, f.nr_converged, f.nr_distinct, f.nr_missed, f.nr_spurious
        );
    }
    s
}

// ---------------------------------------------------------------------------------------------
// 3R inverse kinematics where methods fail: next to a cusp, at a cusp, on an internal motion.

use linkspace::analyses::arm3r::{cusps, ik, Chain3R};

fn wrap(d: f64) -> f64 {
    (d + PI).rem_euclid(2.0 * PI) - PI
}

fn torus_distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (wrap(a[0] - b[0]).powi(2) + wrap(a[1] - b[1]).powi(2)).sqrt()
}

/// Newton–Raphson on `f(θ) = target` with a central-difference Jacobian.
fn newton_3r(chain: &Chain3R, target: [f64; 2], mut t: [f64; 2]) -> Option<[f64; 2]> {
    for _ in 0..60 {
        let f = chain.eval_f64(t[0], t[1]);
        let r = [f[0] - target[0], f[1] - target[1]];
        if (r[0] * r[0] + r[1] * r[1]).sqrt() < 1e-10 {
            return Some([wrap(t[0]), wrap(t[1])]);
        }
        let h = 1e-7;
        let col = |k: usize| {
            let (mut p, mut m) = (t, t);
            p[k] += h;
            m[k] -= h;
            let (fp, fm) = (chain.eval_f64(p[0], p[1]), chain.eval_f64(m[0], m[1]));
            [(fp[0] - fm[0]) / (2.0 * h), (fp[1] - fm[1]) / (2.0 * h)]
        };
        let (c0, c1) = (col(0), col(1));
        let det = c0[0] * c1[1] - c1[0] * c0[1];
        if !(det.abs() > 1e-300) {
            return None;
        }
        t[0] -= (r[0] * c1[1] - c1[0] * r[1]) / det;
        t[1] -= (c0[0] * r[1] - r[0] * c0[1]) / det;
        if !(t[0].is_finite() && t[1].is_finite()) {
            return None;
        }
    }
    None
}

/// Every isolated root of `f(θ) = target` by brute force: a 600×600 grid, Newton from every
/// cell whose residual is a local minimum, duplicates merged. Independent of both solvers.
fn brute_force_roots(chain: &Chain3R, target: [f64; 2]) -> Vec<[f64; 2]> {
    let n = 600;
    let step = 2.0 * PI / n as f64;
    let res = |i: usize, j: usize| {
        let f = chain.eval_f64(-PI + step * i as f64, -PI + step * j as f64);
        ((f[0] - target[0]).powi(2) + (f[1] - target[1]).powi(2)).sqrt()
    };
    let grid: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| res(i, j)).collect()).collect();
    let mut roots: Vec<[f64; 2]> = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let v = grid[i][j];
            let is_min = (-1i64..=1).all(|di| (-1i64..=1).all(|dj| grid[((i as i64 + di).rem_euclid(n as i64)) as usize][((j as i64 + dj).rem_euclid(n as i64)) as usize] >= v));
            if is_min {
                if let Some(r) = newton_3r(chain, target, [-PI + step * i as f64, -PI + step * j as f64]) {
                    if !roots.iter().any(|q| torus_distance(*q, r) < 1e-7) {
                        roots.push(r);
                    }
                }
            }
        }
    }
    roots
}

fn study_ik(name: &str, difficulty: &str, chain: &Chain3R, target: [f64; 2], roots: Vec<[f64; 2]>, line: Option<f64>) -> Finding {
    // A line of solutions needs about 2π/precision boxes to cover: a coarser precision there.
    let precision = if line.is_some() { 1e-3 } else { 1e-6 };
    let t0 = std::time::Instant::now();
    let sol = ik::solve(chain, target[0].max(0.0).sqrt(), target[1], precision, 2_000_000).expect("invariant: valid query");
    let seconds = t0.elapsed().as_secs_f64();
    let inside = |b: &[linkspace::kernel::interval::Interval; 2], t: [f64; 2]| {
        (0..2).all(|k| (-1..=1).any(|turn| {
            let v = t[k] + 2.0 * PI * f64::from(turn);
            b[k].inf() - 1e-9 <= v && v <= b[k].sup() + 1e-9
        }))
    };
    let covered = |t: [f64; 2]| sol.unique.iter().any(|b| inside(b, t)) || sol.clusters.iter().any(|c| inside(&c.hull, t));
    let mut lost = roots.iter().filter(|r| !covered(**r)).count() + usize::from(!sol.status.finished());
    if let Some(t3) = line {
        lost += (0..64).filter(|k| !covered([-PI + 2.0 * PI * (*k as f64 + 0.5) / 64.0, t3])).count();
    }
    let starts = grid(2, 256);
    let mut converged = Vec::new();
    let mut distinct: Vec<[f64; 2]> = Vec::new();
    for s0 in &starts {
        if let Some(x) = newton_3r(chain, target, [s0[0], s0[1]]) {
            if !distinct.iter().any(|d| torus_distance(*d, x) < 1e-6) {
                distinct.push(x);
            }
            converged.push(x);
        }
    }
    let near_reference = |d: &[f64; 2]| roots.iter().any(|r| torus_distance(*r, *d) < 1e-6) || line.is_some_and(|t3| wrap(d[1] - t3).abs() < 1e-6);
    let mut closest = f64::INFINITY;
    for (k, a) in roots.iter().enumerate() {
        for b in &roots[k + 1..] {
            closest = closest.min(torus_distance(*a, *b));
        }
    }
    Finding {
        instance: name.into(),
        difficulty: difficulty.into(),
        reference_roots: roots.len() + usize::from(line.is_some()),
        closest_pair: closest,
        boxes: sol.unique.len() + sol.clusters.iter().map(|c| c.boxes).sum::<usize>(),
        clusters: sol.unique.len() + sol.clusters.len(),
        certified: sol.unique.len(),
        lost,
        seconds,
        nr_starts: starts.len(),
        nr_converged: converged.len(),
        nr_distinct: distinct.len(),
        nr_missed: roots.iter().filter(|r| !distinct.iter().any(|d| torus_distance(*d, **r) < 1e-6)).count(),
        nr_spurious: distinct.iter().filter(|d| !near_reference(d)).count(),
    }
}

/// The 3R instances: inverse kinematics at a regular point, next to a cusp, at a cusp, and on
/// an internal motion.
pub fn manip3r_findings() -> Vec<Finding> {
    let load = |text: &str| Chain3R::from_mechanism(&urdf::parse(text).expect("invariant: bundled robot parses"), 0.0).expect("invariant: bundled robot is 3R");
    let a = load(include_str!("../../../urdf/orthogonal_3r_a.urdf"));
    let f = load(include_str!("../../../urdf/orthogonal_3r_f.urdf"));
    let mut out = Vec::new();
    let regular = a.eval_f64(0.4, -1.2);
    out.push(study_ik("3R robot a, IK at a regular point", "isolated regular roots", &a, regular, brute_force_roots(&a, regular), None));
    let found = cusps::search(&a, &cusps::CuspSettings { precision: 1e-12, ..Default::default() }).expect("invariant: valid settings");
    let c = found.cusps.first().expect("robot a has cusps");
    let cusp = [c.theta[0].mid(), c.theta[1].mid()];
    let near = a.eval_f64(cusp[0] + 1e-3, cusp[1]);
    out.push(study_ik("3R robot a, IK 1e-3 from a cusp", "three roots close together, nearly singular Jacobian", &a, near, brute_force_roots(&a, near), None));
    let at = a.eval_f64(cusp[0], cusp[1]);
    let mut at_roots = brute_force_roots(&a, at);
    // The triple root itself: Newton from a grid only creeps towards it; the certified cusp box
    // (a different solver from the IK search under study) gives it.
    at_roots.retain(|r| torus_distance(*r, cusp) > 1e-3);
    at_roots.push(cusp);
    out.push(study_ik("3R robot a, IK at a cusp", "a triple root: singular Jacobian, quadratic-free convergence", &a, at, at_roots, None));
    let bands = linkspace::analyses::arm3r::bands(&f, 1e-9);
    let band = bands.first().expect("robot f has internal motions");
    let t3 = 0.5 * (band.theta3[0] + band.theta3[1]);
    let line_point = f.eval_f64(0.0, t3);
    let mut line_roots = brute_force_roots(&f, line_point);
    line_roots.retain(|r| wrap(r[1] - t3).abs() > 1e-4);
    out.push(study_ik("3R robot f, IK on an internal motion", "a whole line of solutions (θ2 free): every point has a singular Jacobian", &f, line_point, line_roots, Some(t3)));
    out
}

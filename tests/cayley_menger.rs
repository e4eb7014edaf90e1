//! Test idea: distance problems solved through Cayley–Menger determinants against independent
//! references. The octahedral platform's solutions are checked by placing the platform from the
//! solved distances and measuring every leg again in coordinates; the four-spheres lines are
//! compared with lines found by Newton's method on a coordinate formulation (point + direction),
//! and each is measured against the four centres.

use linkspace::contract::FaceBounds;
use linkspace::interval::{components, point};
use linkspace::problems::cayley_menger::{BuildOptions, CayleyMenger, DistanceProblem, Formulation};
use linkspace::solve::{Enclosure, Solver, SolverSettings};
use std::sync::atomic::AtomicBool;

/// The seed's octahedral manipulator: base side √3, platform side √3/2, legs p1p5, p1p6, p2p6,
/// p2p4, p3p4, p3p5 with squared lengths `legs` in that order.
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
    // The seed's Eqs. (6), and its Eq. (7) on request.
    p.equations = Some(vec![vec![0, 2, 3, 4, 5], vec![0, 1, 2, 3, 5]]);
    p.redundant = Some(vec![vec![1, 2, 3, 4, 5], vec![0, 1, 3, 4, 5], vec![0, 1, 2, 4, 5], vec![0, 1, 2, 3, 4]]);
    p
}

pub const CONFIG_A: [f64; 6] = [4.25, 5.75, 4.25, 5.75, 4.25, 5.75];
pub const CONFIG_B: [f64; 6] = [4.75; 6];

pub fn solve(cm: &CayleyMenger, faces: FaceBounds, sigma: f64, rho: f64) -> Enclosure {
    let clip = cm.contractor(faces).expect("compiles");
    let settings = SolverSettings { sigma, rho, ..Default::default() };
    let solver = Solver::new(&cm.system, settings).expect("valid").with_contractor(Box::new(move |_, _| Box::new(clip.clone())));
    solver.enclose(&AtomicBool::new(false), &mut |_| {})
}

#[test]
fn octahedral_timing_probe() {
    for (name, legs) in [("a", CONFIG_A), ("b", CONFIG_B)] {
        for redundant in [false, true] {
            for formulation in [Formulation::Split, Formulation::Shared] {
                for faces in [FaceBounds::Corners, FaceBounds::IntervalArithmetic] {
                    if formulation == Formulation::Shared && faces == FaceBounds::IntervalArithmetic { continue; }
                    let cm = CayleyMenger::build(&octahedral(legs), BuildOptions { formulation, redundant }).unwrap();
                    let e = solve(&cm, faces, 0.1, 0.9);
                    let (_, clusters) = components(&e.solutions);
                    eprintln!("{name} red={redundant} {formulation:?} {faces:?}: {:?} processed {} sols {} clusters {} {:.4}s", e.status, e.stats.processed, e.solutions.len(), clusters, e.stats.seconds);
                    for b in &e.solutions { eprintln!("   {:?}", cm.unknown_intervals(b).iter().map(|(n, i)| format!("{n}=[{:.4},{:.4}]", i.inf(), i.sup())).collect::<Vec<_>>()); }
                }
            }
        }
    }
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
    if orient {
        p.orientations.push(linkspace::problems::cayley_menger::Orientation { a: t, b: u, toward: 1 });
    }
    p
}

#[test]
fn four_spheres_timing_probe() {
    let env = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
    let (sigma, rho) = (env("SIGMA", 0.1), env("RHO", 0.99));
    for orient in [true] {
        for redundant in [true, false] {
            for formulation in [Formulation::Shared] {
                let cm = CayleyMenger::build(&four_spheres(orient), BuildOptions { formulation, redundant }).unwrap();
                let clip = cm.contractor(FaceBounds::Corners).unwrap();
                let settings = SolverSettings { sigma, rho, max_boxes: 200_000, timeout: Some(std::time::Duration::from_secs(60)), ..Default::default() };
                let solver = Solver::new(&cm.system, settings).expect("valid").with_contractor(Box::new(move |_, _| Box::new(clip.clone())));
                let t = std::time::Instant::now();
                let e = solver.enclose(&AtomicBool::new(false), &mut |_| {});
                let (_, clusters) = components(&e.solutions);
                eprintln!("sigma {sigma} rho {rho} orient={orient} red={redundant} {formulation:?}: {:?} processed {} rounds {} sols {} clusters {} {:.4}s total {:.3}", e.status, e.stats.processed, e.stats.shrink_rounds, e.solutions.len(), clusters, e.stats.seconds, t.elapsed().as_secs_f64());
            }
        }
    }
}
#[test]
fn dbg_embed() {
    let cm = CayleyMenger::build(&octahedral(CONFIG_A), BuildOptions { formulation: Formulation::Shared, redundant: false }).unwrap();
    let x = [4.25000001, 4.25008];
    let r = cm.distances(&x);
    for tol in [1e-9, 1.6e-3] {
        let e = linkspace::problems::cayley_menger::embed(&cm.problem, &r, tol);
        eprintln!("tol {tol}: {}", e.len());
        for p in &e { eprintln!("  {:?}", p); }
    }
}

//! Test idea: solve the bundled planar linkages through the whole pipeline (URDF → system →
//! branch and prune) and compare with references computed here independently: closed forms for
//! the four-bar and slider-crank, the paper's Table I and a hand-written Newton solver for the
//! rigid double butterfly, and a pseudo-arclength continuation of the mobile one.

use crate::util::{covered, problem, solve};
use linkspace::kernel::interval::components;
use linkspace::app::Status;
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::f64::consts::PI;

// ---------- the double butterfly, by hand from the three loop equations of Porta et al. (2006) ----------

fn g0() -> f64 {
    3f64.atan2(4.0)
}

/// The three loops, six scalar equations, over θ1..θ7 (index 0..6).
fn butterfly(t: &[f64]) -> DVector<f64> {
    let (a0, b0, a1, b1, a2, b2, b6, c6) = (7.0, 13.0, 7.0, 6.0, 5.0, 3.0, 3.0, 2.0);
    let (l3, l4, l5, l7) = (7.0, 9.0, 12.0, 11.0);
    let (g1, g2, e6) = (5f64.atan2(12.0), 4f64.atan2(3.0), g0());
    let u = |a: f64| [a.cos(), a.sin()];
    let th = |i: usize| t[i - 1];
    let mut f = DVector::zeros(6);
    for k in 0..2 {
        let ground = [a0 * g0().cos(), -a0 * g0().sin()];
        f[k] = l7 * u(th(7))[k] + a2 * u(th(2))[k] + a1 * u(th(1))[k] - l5 * u(th(5))[k] + [b0, 0.0][k];
        f[2 + k] = l7 * u(th(7))[k] + a2 * u(th(2))[k] + b1 * u(th(1) + g1)[k] - l3 * u(th(3))[k] - c6 * u(th(6) + e6)[k] + ground[k];
        f[4 + k] = l7 * u(th(7))[k] + b2 * u(th(2) + g2)[k] - l4 * u(th(4))[k] - b6 * u(th(6))[k] + ground[k];
    }
    f
}

fn jacobian(t: &[f64]) -> DMatrix<f64> {
    let h = 1e-7;
    let f0 = butterfly(t);
    let mut j = DMatrix::zeros(6, 7);
    for i in 0..7 {
        let mut tp = t.to_vec();
        tp[i] += h;
        let mut tm = t.to_vec();
        tm[i] -= h;
        let col = (butterfly(&tp) - butterfly(&tm)) / (2.0 * h);
        j.set_column(i, &col);
        let _ = &f0;
    }
    j
}

/// Newton on the square system with θ6 held: refines a rough root.
fn refine_rigid(mut t: Vec<f64>) -> Vec<f64> {
    for _ in 0..50 {
        let f = butterfly(&t);
        let j = jacobian(&t);
        let cols: Vec<usize> = vec![0, 1, 2, 3, 4, 6];
        let js = DMatrix::from_fn(6, 6, |r, c| j[(r, cols[c])]);
        let step = js.lu().solve(&(-f)).expect("regular Jacobian at a Table I root");
        for (c, &i) in cols.iter().enumerate() {
            t[i] += step[c];
        }
        if step.norm() < 1e-15 {
            break;
        }
    }
    t
}

fn table_one() -> Vec<Vec<f64>> {
    // θ1..θ7 of the paper's Table I, rounded to 5 digits; θ6 = atan2(12, 5).
    let t6 = 12f64.atan2(5.0);
    [
        [-0.49432, 0.78082, -0.81924, -2.42719, -0.14221, t6, -2.96808],
        [1.72770, 1.13865, 2.58872, -2.66043, 1.31799, t6, 3.12666],
        [0.55303, -0.71931, -1.20077, -1.96316, -0.13237, t6, -2.96187],
        [-2.66940, -0.64814, -0.40126, 0.56972, 0.41105, t6, 1.54821],
        [-2.25882, 2.77062, -0.24061, -0.01687, 0.41213, t6, 0.86916],
        [0.41351, 2.44496, 2.10929, -2.79537, 1.08684, t6, 2.71005],
    ]
    .iter()
    .map(|r| r.to_vec())
    .collect()
}

fn angles_map(t: &[f64]) -> BTreeMap<String, f64> {
    let mut m: BTreeMap<String, f64> = (1..=7).map(|i| (format!("link{i}"), t[i - 1])).collect();
    m.insert("link0".into(), 0.0);
    m
}

#[test]
fn rigid_butterfly_has_exactly_the_six_table_one_solutions() {
    let t6 = 12f64.atan2(5.0);
    let p = problem("double_butterfly.urdf", &[("joint6", t6)], &[]);
    let sigma = 1e-4;
    let run = solve(&p, sigma);
    assert_eq!(run.status, Status::Finished);
    let (labels, clusters) = components(&run.solutions);
    assert_eq!(clusters, 6, "{} boxes", run.solutions.len());
    // Regular roots: interval Newton certifies each box to hold exactly one solution.
    assert!(run.unique.iter().all(|&u| u), "uncertified boxes: {:?}", run.unique);
    for b in &run.solutions {
        assert!(b.dims.iter().zip(&p.system.vars).all(|(d, v)| v.role != linkspace::kernel::system::VarRole::Primary || d.wid() <= sigma));
    }
    let mut hit = vec![false; clusters];
    for row in table_one() {
        // The 5-digit row itself lies in a box's link-angle enclosure, rounding allowed for …
        let inside: Vec<usize> = run
            .solutions
            .iter()
            .enumerate()
            .filter(|(_, b)| {
                let a = p.link_angles(b);
                (1..=7).all(|i| {
                    let (lo, hi) = a[&format!("link{i}")];
                    lo - 5e-6 <= row[i - 1] && row[i - 1] <= hi + 5e-6
                })
            })
            .map(|(k, _)| k)
            .collect();
        assert!(!inside.is_empty(), "Table I row {row:?} is in no solution box");
        // … and the exact root, refined independently, lies in the box's variables.
        let exact = refine_rigid(row.clone());
        let x = p.point_from(&angles_map(&exact), &BTreeMap::new()).expect("all angles given");
        assert!(covered(&run.solutions, &x, 1e-12), "refined root {exact:?} lost");
        hit[labels[inside[0]]] = true;
    }
    assert!(hit.iter().all(|&h| h), "a cluster holds no Table I row");
}

/// Pseudo-arclength continuation of the curve F(θ) = 0 from `start`, until it closes.
fn trace_branch(start: &[f64], h: f64) -> Vec<Vec<f64>> {
    let wrap = |d: f64| (d + PI).rem_euclid(2.0 * PI) - PI;
    let null = |j: &DMatrix<f64>, prev: &DVector<f64>| -> DVector<f64> {
        let mut a = DMatrix::zeros(7, 7);
        a.rows_mut(0, 6).copy_from(j);
        a.row_mut(6).copy_from(&prev.transpose());
        let mut rhs = DVector::zeros(7);
        rhs[6] = 1.0;
        let v = a.lu().solve(&rhs).expect("regular augmented Jacobian on the curve");
        v.normalize()
    };
    let mut x = DVector::from_column_slice(start);
    // Any direction not orthogonal to the curve starts it; θ6 is a fine guess.
    let mut t = null(&jacobian(x.as_slice()), &DVector::from_fn(7, |i, _| if i == 5 { 1.0 } else { 0.0 }));
    let mut out = vec![start.to_vec()];
    for step in 0..20_000 {
        let xp = &x + &t * h;
        let mut y = xp.clone();
        for _ in 0..20 {
            let f = butterfly(y.as_slice());
            let mut a = DMatrix::zeros(7, 7);
            a.rows_mut(0, 6).copy_from(&jacobian(y.as_slice()));
            a.row_mut(6).copy_from(&t.transpose());
            let mut rhs = DVector::zeros(7);
            rhs.rows_mut(0, 6).copy_from(&(-f));
            rhs[6] = -t.dot(&(&y - &xp));
            let d = a.lu().solve(&rhs).expect("regular corrector");
            y += &d;
            if d.norm() < 1e-13 {
                break;
            }
        }
        assert!(butterfly(y.as_slice()).norm() < 1e-9, "corrector failed");
        t = null(&jacobian(y.as_slice()), &t);
        x = y;
        out.push(x.as_slice().to_vec());
        let back = (0..7).map(|i| wrap(x[i] - start[i]).powi(2)).sum::<f64>().sqrt();
        if step > 20 && back < 0.6 * h {
            return out;
        }
    }
    panic!("branch did not close");
}

#[test]
fn mobile_butterfly_is_four_closed_branches_at_every_sigma() {
    let p = problem("double_butterfly.urdf", &[], &[]);
    // Traced from every rigid root; a root already on a traced branch adds nothing.
    let branches = mobile_branches();
    assert_eq!(branches.len(), 4, "the six rigid roots lie on four branches");
    let points: Vec<Vec<Vec<f64>>> = branches
        .iter()
        .map(|b| b.iter().map(|q| p.point_from(&angles_map(q), &BTreeMap::new()).expect("angles")).collect())
        .collect();
    for sigma in [0.5, 0.2, 0.1, 0.05] {
        let run = solve(&p, sigma);
        assert_eq!(run.status, Status::Finished);
        let (labels, clusters) = components(&run.solutions);
        assert_eq!(clusters, 4, "sigma {sigma}: {clusters} clusters");
        let mut cluster_of_branch = std::collections::BTreeSet::new();
        for branch in &points {
            let mut seen = std::collections::BTreeSet::new();
            for x in branch {
                let k = run.solutions.iter().position(|b| b.dims.iter().zip(x).all(|(d, &v)| d.inf() - 1e-12 <= v && v <= d.sup() + 1e-12));
                let k = k.unwrap_or_else(|| panic!("sigma {sigma}: curve point {x:?} is in no solution box"));
                seen.insert(labels[k]);
            }
            assert_eq!(seen.len(), 1, "sigma {sigma}: a branch spans several clusters");
            cluster_of_branch.extend(seen);
        }
        assert_eq!(cluster_of_branch.len(), 4, "sigma {sigma}: two branches share a cluster");
    }
}

/// Both assembly modes of a four-bar by intersecting two circles: rocker angles and coupler
/// points for crank angle `t2`.
fn four_bar_closed_form(t2: f64) -> Vec<(f64, [f64; 2])> {
    let (a, b, c, d) = (1.5, 4.0, 3.5, 4.0);
    let pa = [a * t2.cos(), a * t2.sin()];
    let q = [d, 0.0];
    let (dx, dy) = (q[0] - pa[0], q[1] - pa[1]);
    let dist = (dx * dx + dy * dy).sqrt();
    let along = (b * b - c * c + dist * dist) / (2.0 * dist);
    let h = (b * b - along * along).sqrt();
    [-1.0, 1.0]
        .iter()
        .map(|s| {
            let pb = [pa[0] + along * dx / dist - s * h * dy / dist, pa[1] + along * dy / dist + s * h * dx / dist];
            let t4 = (pb[1] - q[1]).atan2(pb[0] - q[0]);
            let t3 = (pb[1] - pa[1]).atan2(pb[0] - pa[0]);
            // The coupler point (2, 1) in the coupler frame.
            let cp = [pa[0] + 2.0 * t3.cos() - t3.sin(), pa[1] + 2.0 * t3.sin() + t3.cos()];
            (t4, cp)
        })
        .collect()
}

#[test]
fn four_bar_matches_the_closed_form_across_the_crank_range() {
    for k in 0..12 {
        let t2 = -PI + 2.0 * PI * (k as f64 + 0.5) / 12.0;
        let p = problem("four_bar.urdf", &[("crank_joint", t2)], &[("coupler", 2.0, 1.0)]);
        let run = solve(&p, 1e-6);
        assert_eq!(run.status, Status::Finished);
        assert_eq!(components(&run.solutions).1, 2, "crank {t2}: two assembly modes");
        for (t4, cp) in four_bar_closed_form(t2) {
            let hit = run.solutions.iter().any(|b| {
                let rocker = p.link_angles(b)["rocker"];
                let tp = p.traces.iter().find(|t| t.name == "coupler@2,1").expect("traced");
                let near = |v: f64, x: linkspace::kernel::interval::Interval| x.inf() - 1e-9 <= v && v <= x.sup() + 1e-9;
                rocker.0 - 1e-9 <= t4 && t4 <= rocker.1 + 1e-9 && near(cp[0], b.dims[tp.x]) && near(cp[1], b.dims[tp.y])
            });
            assert!(hit, "crank {t2}: rocker {t4} / coupler point {cp:?} in no box");
        }
    }
}

#[test]
fn slider_crank_matches_the_closed_form() {
    let (r, l) = (1.0f64, 3.0f64);
    for k in 0..12 {
        let t = -PI + 2.0 * PI * (k as f64 + 0.25) / 12.0;
        let p = problem("slider_crank.urdf", &[("crank_joint", t)], &[]);
        let run = solve(&p, 1e-6);
        assert_eq!(run.status, Status::Finished);
        // The other root, x = r cos t − √…, is negative: outside the slider's limits [0, 5].
        assert_eq!(components(&run.solutions).1, 1);
        let x = r * t.cos() + (l * l - r * r * t.sin().powi(2)).sqrt();
        let travel = p.joint_values(&run.solutions[0])["slider_joint"];
        assert!(travel.0 - 1e-12 <= x && x <= travel.1 + 1e-12, "crank {t}: slider {x} not in {travel:?}");
    }
}

#[test]
fn watt_six_bar_assembles_in_four_modes_for_a_driven_crank() {
    // Two four-bar loops, two assembly modes each.
    let p = problem("watt_six_bar.urdf", &[("crank_joint", 0.7)], &[]);
    let run = solve(&p, 1e-6);
    assert_eq!(run.status, Status::Finished);
    assert_eq!(components(&run.solutions).1, 4);
    for b in &run.solutions {
        let x = b.midpoint();
        assert!(p.system.max_residual(&x) < 1e-5);
    }
}

// Soundness of every contractor on the real system: a box around a true configuration of the
// mobile butterfly (a point of a traced branch) never loses it, whatever the box.
proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    #[test]
    fn no_contractor_removes_a_true_configuration(which in 0usize..4, at in 0.0f64..1.0, widths in proptest::collection::vec(1e-6f64..0.6, 14), offsets in proptest::collection::vec(0.0f64..1.0, 14)) {
        use linkspace::kernel::contract::{Contraction, Contractor, LpShrink, Newton, Propagation};
        use linkspace::app::LpBackend;
        let p = problem("double_butterfly.urdf", &[], &[]);
        let branches = mobile_branches();
        let branch = &branches[which % branches.len()];
        let q = &branch[((at * branch.len() as f64) as usize).min(branch.len() - 1)];
        let x = p.point_from(&angles_map(q), &BTreeMap::new()).expect("angles");
        let mut b = p.system.initial_box();
        for (i, d) in b.dims.iter_mut().enumerate() {
            let (w, f) = (widths[i % 14], offsets[i % 14]);
            // Margins of 1e-9 keep the real point, not just its float image, inside.
            let lo = (x[i] - w * f - 1e-9).max(d.inf());
            let hi = (x[i] + w * (1.0 - f) + 1e-9).min(d.sup());
            *d = linkspace::kernel::interval::interval(lo, hi);
        }
        let inside = |b: &linkspace::kernel::interval::IntervalBox| b.dims.iter().zip(&x).all(|(d, &v)| d.inf() - 1e-9 <= v && v <= d.sup() + 1e-9);
        let mut steps: Vec<Box<dyn Contractor>> = vec![Box::new(Propagation::new(&p.system))];
        for backend in [LpBackend::Simplex, LpBackend::Clarabel] {
            let mut lp = LpShrink::new(&p.system);
            lp.backend = backend;
            steps.push(Box::new(lp));
        }
        if let Some(n) = Newton::new(&p.system, 1.0) {
            steps.push(Box::new(n));
        }
        for step in &mut steps {
            let mut c = b.clone();
            for _ in 0..3 {
                proptest::prop_assert_ne!(step.contract(&mut c), Contraction::Empty, "{} emptied a box holding {:?}", step.name(), q);
            }
            proptest::prop_assert!(inside(&c), "{} cut the true configuration {:?}", step.name(), q);
        }
    }
}

/// The four branches of the mobile butterfly, traced once per test binary.
fn mobile_branches() -> &'static Vec<Vec<Vec<f64>>> {
    static BRANCHES: std::sync::OnceLock<Vec<Vec<Vec<f64>>>> = std::sync::OnceLock::new();
    BRANCHES.get_or_init(|| {
        let wrap = |d: f64| (d + PI).rem_euclid(2.0 * PI) - PI;
        let mut branches: Vec<Vec<Vec<f64>>> = Vec::new();
        for row in table_one() {
            let root = refine_rigid(row);
            let known = branches.iter().any(|b| b.iter().any(|q| (0..7).all(|i| wrap(q[i] - root[i]).abs() < 0.02)));
            if !known {
                branches.push(trace_branch(&root, 0.01));
            }
        }
        branches
    })
}

/// The parallel driver gives exactly the serial set of boxes, on every bundled problem.
#[test]
fn parallel_and_serial_drivers_give_identical_box_sets() {
    use linkspace::kernel::search::SolverSettings;
    use std::sync::atomic::AtomicBool;
    let cases: Vec<(linkspace::formulate::LinkageProblem, f64)> = vec![
        (problem("double_butterfly.urdf", &[("joint6", 12f64.atan2(5.0))], &[]), 1e-4),
        (problem("double_butterfly.urdf", &[], &[]), 0.2),
        (problem("four_bar.urdf", &[], &[("coupler", 2.0, 1.0)]), 0.05),
        (problem("slider_crank.urdf", &[], &[]), 0.05),
        (problem("watt_six_bar.urdf", &[], &[]), 0.2),
    ];
    let canonical = |mut v: Vec<(Vec<(u64, u64)>, bool)>| {
        v.sort();
        v
    };
    for (p, sigma) in &cases {
        let mut sets = Vec::new();
        for threads in [1, 2, 3] {
            let settings = SolverSettings { sigma: *sigma, threads, ..Default::default() };
            let e = p.solver(settings).expect("valid").enclose(&AtomicBool::new(false), &mut |_| {});
            assert_eq!(e.status, Status::Finished);
            let boxes = e.solutions.iter().zip(&e.tags).map(|(b, &t)| (b.dims.iter().map(|d| (d.inf().to_bits(), d.sup().to_bits())).collect(), t == linkspace::app::BoxStatus::Unique)).collect();
            sets.push((threads, canonical(boxes), e.stats.processed));
        }
        for (threads, set, processed) in &sets[1..] {
            assert_eq!(set.len(), sets[0].1.len(), "{}: {threads} threads", p.name);
            assert!(*set == sets[0].1, "{}: {threads} threads give other boxes", p.name);
            assert_eq!(*processed, sets[0].2, "{}: {threads} threads processed another tree", p.name);
        }
    }
}

#[test]
fn limits_on_a_joint_away_from_the_ground_bound_the_search() {
    use linkspace::model::urdf;
    use linkspace::formulate::LinkageProblem;
    // The coupler may turn only within [-1, 1] rad relative to the crank: one of the two
    // assembly modes of every crank angle violates it somewhere along the crank's turn.
    let text = crate::util::urdf_text("four_bar.urdf").replacen(
        "<joint name=\"coupler_joint\" type=\"continuous\">",
        "<joint name=\"coupler_joint\" type=\"revolute\"><limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/>",
        1,
    );
    let m = urdf::parse(&text).expect("variant parses");
    for k in 0..8 {
        let t2 = -PI + 2.0 * PI * (k as f64 + 0.5) / 8.0;
        let limited = LinkageProblem::new(&m, &[("crank_joint".into(), t2)], &[]).expect("builds");
        let run = solve(&limited, 1e-6);
        assert_eq!(run.status, Status::Finished);
        // Reference: the closed-form modes whose coupler angle relative to the crank is within the limits.
        let expected: Vec<f64> = four_bar_closed_form(t2)
            .into_iter()
            .filter(|(t4, _)| {
                let (a, b, c, d) = (1.5f64, 4.0f64, 3.5f64, 4.0f64);
                let pa = [a * t2.cos(), a * t2.sin()];
                let pb = [d + c * t4.cos(), c * t4.sin()];
                let t3 = (pb[1] - pa[1]).atan2(pb[0] - pa[0]);
                let _ = b;
                let rel = (t3 - t2 + PI).rem_euclid(2.0 * PI) - PI;
                rel.abs() <= 1.0
            })
            .map(|(t4, _)| t4)
            .collect();
        assert_eq!(components(&run.solutions).1, expected.len(), "crank {t2}");
        for t4 in expected {
            assert!(run.solutions.iter().any(|b| {
                let r = limited.link_angles(b)["rocker"];
                r.0 - 1e-9 <= t4 && t4 <= r.1 + 1e-9
            }), "crank {t2}: mode with rocker {t4} lost");
        }
        for b in &run.solutions {
            let (lo, hi) = limited.joint_values(b)["coupler_joint"];
            assert!(hi >= -1.0 - 1e-9 && lo <= 1.0 + 1e-9, "crank {t2}: box outside the limits");
        }
    }
    // With the crank free the coupler's parent moves: the limit filter must do the work.
    let free = LinkageProblem::new(&m, &[], &[]).expect("builds");
    let unlimited = problem("four_bar.urdf", &[], &[]);
    let (with, without) = (solve(&free, 0.02), solve(&unlimited, 0.02));
    assert!(with.solutions.len() < without.solutions.len());
    for b in &with.solutions {
        let (lo, hi) = free.joint_values(b)["coupler_joint"];
        assert!(hi >= -1.0 - 1e-9 && lo <= 1.0 + 1e-9, "a box of the free run lies outside the limits: [{lo}, {hi}]");
    }
    // Nothing within the limits is lost: sampled closed-form configurations inside them are covered.
    for k in 0..64 {
        let t2 = -PI + 2.0 * PI * (k as f64 + 0.5) / 64.0;
        for (t4, _) in four_bar_closed_form(t2) {
            let (a, c, d) = (1.5f64, 3.5f64, 4.0f64);
            let pa = [a * t2.cos(), a * t2.sin()];
            let pb = [d + c * t4.cos(), c * t4.sin()];
            let t3 = (pb[1] - pa[1]).atan2(pb[0] - pa[0]);
            if ((t3 - t2 + PI).rem_euclid(2.0 * PI) - PI).abs() <= 1.0 {
                let angles: BTreeMap<String, f64> = [("crank", t2), ("coupler", t3), ("rocker", t4), ("ground", 0.0)].iter().map(|(n, v)| (n.to_string(), *v)).collect();
                let x = free.point_from(&angles, &BTreeMap::new()).expect("angles");
                assert!(covered(&with.solutions, &x, 1e-9), "crank {t2}: a configuration within the limits was cut");
            }
        }
    }
}

/// Fixing every joint asks whether one stated configuration closes: a complete run with no box
/// when it provably does not, one box (a point, never "unique": nothing is left to certify)
/// when rounding cannot refute it. Neither is bad input.
#[test]
fn fixing_every_joint_answers_with_one_box_or_none() {
    // Crank 0, coupler π/3: the coupler tip (3.5, 2√3) is 3.5 from O4 = (4, 0) exactly, at the
    // rocker angle atan2(2√3, −0.5).
    let (coupler, rocker) = (PI / 3.0, (2.0 * 3f64.sqrt()).atan2(-0.5));
    let closes = problem("four_bar.urdf", &[("crank_joint", 0.0), ("coupler_joint", coupler), ("rocker_joint", rocker)], &[]);
    let run = solve(&closes, 1e-6);
    assert_eq!((run.status, run.solutions.len(), run.unique.iter().filter(|&&u| u).count()), (Status::Finished, 1, 0));
    let off = problem("four_bar.urdf", &[("crank_joint", 0.0), ("coupler_joint", coupler), ("rocker_joint", rocker + 1e-9)], &[]);
    let run = solve(&off, 1e-6);
    assert_eq!((run.status, run.solutions.len()), (Status::Finished, 0));
}

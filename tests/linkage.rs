//! Test idea: solve the bundled planar linkages through the whole pipeline (URDF → system →
//! branch and prune) and compare with references computed here independently: closed forms for
//! the four-bar and slider-crank, the paper's Table I and a hand-written Newton solver for the
//! rigid double butterfly, and a pseudo-arclength continuation of the mobile one.

use crate::util::{covered, problem, solve};
use linkspace::interval::components;
use linkspace::Status;
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeMap;
use std::f64::consts::PI;

// ---------- the double butterfly, written out by hand from research/double_butterfly.md ----------

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
    assert_eq!(run.status, Status::Complete);
    let (labels, clusters) = components(&run.solutions);
    assert_eq!(clusters, 6, "{} boxes", run.solutions.len());
    for b in &run.solutions {
        assert!(b.dims.iter().zip(&p.system.vars).all(|(d, v)| v.role != linkspace::system::VarRole::Primary || d.wid() <= sigma));
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
fn mobile_butterfly_boxes_cover_every_traced_branch() {
    let p = problem("double_butterfly.urdf", &[], &[]);
    let run = solve(&p, 0.1);
    assert_eq!(run.status, Status::Complete);
    let (labels, clusters) = components(&run.solutions);
    // Trace from every rigid root; a root already on a traced branch adds nothing.
    let mut branches: Vec<Vec<Vec<f64>>> = Vec::new();
    for row in table_one() {
        let root = refine_rigid(row);
        let wrap = |d: f64| (d + PI).rem_euclid(2.0 * PI) - PI;
        let known = branches.iter().any(|b| b.iter().any(|q| (0..7).all(|i| wrap(q[i] - root[i]).abs() < 0.02)));
        if !known {
            branches.push(trace_branch(&root, 0.01));
        }
    }
    let mut cluster_of_branch = Vec::new();
    for branch in &branches {
        let mut seen = std::collections::BTreeSet::new();
        for q in branch {
            let x = p.point_from(&angles_map(q), &BTreeMap::new()).expect("angles");
            let k = run.solutions.iter().position(|b| b.dims.iter().zip(&x).all(|(d, &v)| d.inf() - 1e-12 <= v && v <= d.sup() + 1e-12));
            let k = k.unwrap_or_else(|| panic!("curve point {q:?} is in no solution box"));
            seen.insert(labels[k]);
        }
        assert_eq!(seen.len(), 1, "a branch spans several clusters");
        cluster_of_branch.push(*seen.iter().next().expect("non-empty"));
    }
    eprintln!("branches {} clusters {} boxes {}", branches.len(), clusters, run.solutions.len());
}

//! Test idea: arms whose axes 2, 3, 4 are parallel and whose axes 5 and 6 meet (the UR family)
//! are answered in closed form, and the answer is the search's. Poses come from the forward
//! kinematics of `spherical_wrist` (written from the file's joints, no solver code): every
//! generating joint vector lies in exactly one certified box, every box the search certifies
//! lies in exactly one closed-form box and the counts agree. At the wrist singularity (joint 5
//! at 0) the closed form answers with a curve, with the elbow stretched out (joint 3 at 0) with
//! the double root's boxes undecided; near them (1e-6, 1e-9) it certifies, answers so or leaves
//! the pose to the search, and the generating vector is never lost.

use super::spherical_wrist::{agree, both, control, forward, holds, mechanism, meets, random_q, Lcg};
use linkspace::analyses::arm6r::ik::{self, Ik6Method};
use linkspace::analyses::arm6r::{Chain6R, PoseTarget};
use linkspace::kernel::interval::Interval;
use linkspace::model::{rounding, urdf, Mechanism};
use std::time::{Duration, Instant};

/// The UR5 as a DH table (`urdf/ur5.urdf`) and as ROS writes it (link frames not on the DH
/// axes, a base turned by a half turn, a tool frame).
const ARMS: [(&str, &str); 2] = [("ur5", "urdf/ur5.urdf"), ("ur5_ros_style", "tests/data/ur5_ros_style.urdf")];

/// The chain of `m`, each joint's range cut to one turn: the search then answers in well under
/// a second (over the files' ±2π it finds every solution's copies, up to 2⁶ of each).
fn one_turn(m: &Mechanism) -> Chain6R {
    Chain6R::from_mechanism(m, None, None).expect("six joints").within_one_turn()
}

/// A quarter turn as vendor files write it, truncated (the rounding policy snaps it).
#[allow(clippy::approx_constant)]
const QUARTER: f64 = 1.570796327;

/// A member of the family in modified DH (joint i's origin `Tx(a)·Tz(d)·Rx(α)`), with offsets
/// between axes 1 and 2 and between axes 4 and 5, axis 1 at `alpha1` to axis 2, and axis 5 at
/// `alpha4` to axis 4 (a quarter turn in the UR family; any angle but 0 here).
fn family(seed: u64, alpha1: f64, alpha4: f64) -> Mechanism {
    let mut rng = Lcg(seed);
    let alpha = [0.0, alpha1, 0.0, 0.0, alpha4, -QUARTER];
    let a = [0.0, rng.uniform(-0.1, 0.1), rng.uniform(0.2, 0.6), rng.uniform(-0.6, -0.2), rng.uniform(-0.1, 0.1), 0.0];
    let mut xml = String::from("<robot name=\"family\"><link name=\"l0\"/>");
    for i in 0..6 {
        let d = rng.uniform(-0.2, 0.2);
        xml += &format!(
            "<link name=\"l{}\"/><joint name=\"j{}\" type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/><origin xyz=\"{} 0 {d}\" rpy=\"{} 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"1\" velocity=\"1\"/></joint>",
            i + 1, i + 1, i + 1, a[i], alpha[i]
        );
    }
    xml += "<link name=\"tool\"/><joint name=\"jt\" type=\"fixed\"><parent link=\"l6\"/><child link=\"tool\"/><origin xyz=\"0.02 0 0.1\" rpy=\"0.3 0.2 0.1\"/></joint></robot>";
    rounding::snap(&urdf::parse(&xml).expect("parses"), rounding::ANGLE_TOLERANCE).0
}

#[test]
fn ur_arms_are_answered_in_closed_form_as_the_search_answers() {
    let mut rng = Lcg(2013);
    let mut arms: Vec<(String, Mechanism)> = ARMS.iter().map(|(name, file)| (name.to_string(), mechanism(file))).collect();
    arms.push(("family 1".into(), family(1, QUARTER, QUARTER)));
    arms.push(("family 2".into(), family(2, 0.7, 1.2)));
    for (name, m) in &arms {
        let chain = one_turn(m);
        let mut counts = std::collections::BTreeMap::new();
        for _ in 0..10 {
            let q = random_q(&chain, &mut rng);
            let (solved, searched) = both(m, &chain, &q, None);
            assert_eq!(solved.method, Ik6Method::ClosedForm, "{name} q {q:?}");
            assert_eq!(searched.method, Ik6Method::Search);
            agree(name, &q, &solved, &searched);
            *counts.entry(solved.unique.len()).or_insert(0) += 1;
        }
        println!("{name}: solution counts {counts:?}");
        assert!(counts.keys().any(|&n| n >= 4), "{name}: {counts:?}");
    }
}

/// Over the files' whole ranges (±2π: each solution's copies a turn apart are solutions too)
/// the closed form gives every copy, each in its own box, and `q` in one.
#[test]
fn every_copy_within_two_turns_is_certified() {
    let mut rng = Lcg(1985);
    for (name, file) in ARMS {
        let m = mechanism(file);
        let chain = Chain6R::from_mechanism(&m, None, None).expect("six joints");
        let within = one_turn(&m);
        for _ in 0..4 {
            let q = random_q(&chain, &mut rng);
            let target = PoseTarget::around(&forward(&m, &chain, &q), 1e-12).expect("finite");
            let all = ik::solve(&chain, &target, 1e-10, &control(None)).expect("solves");
            let one = ik::solve(&within, &target, 1e-10, &control(None)).expect("solves");
            assert_eq!((all.method, one.method), (Ik6Method::ClosedForm, Ik6Method::ClosedForm), "{name} q {q:?}");
            assert_eq!(all.unique.iter().filter(|b| holds(b, &q)).count(), 1, "{name} q {q:?}");
            // Each copy of a one-turn solution: per joint, its angle plus each multiple of a
            // turn that stays within ±2π.
            let copies: usize = one
                .unique
                .iter()
                .map(|b| (0..6).map(|d| [-2.0, -1.0, 0.0, 1.0, 2.0].iter().filter(|&&k| { let x = b[d].mid() + k * std::f64::consts::TAU; chain.ranges[d].0 <= x && x <= chain.ranges[d].1 }).count()).product::<usize>())
                .sum();
            assert_eq!(all.unique.len(), copies, "{name} q {q:?}");
        }
    }
}

/// Joint 5 at 0 (axis 6 along axes 2–4: joints 2, 3, 4 and 6 turn together), 1e-6 and 1e-9,
/// the pose enclosed within 4e-15; then joint 3 at 0, 1e-6, 1e-9 (the elbow outstretched:
/// the law of cosines' two roots coincide). With joint 5 at 0 the closed form answers with a
/// curve; with joint 3 at 0 it answers alone, the boxes about the double root undecided;
/// whichever answers holds `q`, and every box the search certifies meets exactly one of its
/// unique boxes, or its clusters or curves.
#[test]
fn at_and_near_the_wrist_and_elbow_singularities_nothing_is_lost() {
    let mut rng = Lcg(5);
    for (name, file) in ARMS {
        let m = mechanism(file);
        let chain = one_turn(&m);
        for (joint, value) in [(4, 0.0), (4, 1e-6), (4, 1e-9), (2, 0.0), (2, 1e-6), (2, 1e-9)] {
            let mut q = random_q(&chain, &mut rng);
            q[joint] = value;
            let t = Instant::now();
            let target = PoseTarget::around(&forward(&m, &chain, &q), 4e-15).expect("finite");
            let found = ik::solve(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("solves");
            println!(
                "{name} joint {} = {value:e}: {} by {} ({:?}), {} unique, {} clusters, {:?}, {:.2} s",
                joint + 1,
                found.status.finished(),
                found.method.name(),
                found.method.declined(),
                found.unique.len(),
                found.clusters.len(),
                found.status,
                t.elapsed().as_secs_f64()
            );
            let curves: Vec<&[Interval; 6]> = found.curves.iter().flat_map(|c| &c.cover).collect();
            match (joint, value) {
                (4, 0.0) => assert!(found.method == Ik6Method::ClosedForm && found.curves.iter().any(|c| c.kind == ik::CurveKind::WristAligned), "{name}: {:?}", found.method),
                (2, 0.0) => assert!(found.method == Ik6Method::ClosedForm && !found.clusters.is_empty() && found.clusters.iter().any(|c| holds(&c.hull, &q)), "{name}: {found:?}"),
                _ => {}
            }
            let lost = !found.unique.iter().any(|b| holds(b, &q)) && !found.clusters.iter().any(|c| holds(&c.hull, &q)) && !curves.iter().any(|b| holds(b, &q));
            assert!(!lost, "{name} q {q:?}: {found:?}");
            if found.method == Ik6Method::ClosedForm {
                let searched = ik::search(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("searches");
                if curves.is_empty() && found.clusters.is_empty() {
                    agree(name, &q, &found, &searched);
                }
                for s in &searched.unique {
                    let elsewhere = curves.iter().any(|c| meets(c, s)) || found.clusters.iter().any(|c| meets(&c.hull, s));
                    let claims = found.unique.iter().filter(|u| meets(u, s)).count() + usize::from(elsewhere);
                    assert_eq!(claims, 1, "{name} q {q:?}: search box {s:?}");
                }
            }
        }
    }
}

/// Every real solution of 30 poses each of the two UR5 files from `scripts/dev/ik6_reference.py`
/// (monodromy and parameter homotopy refined at 60 digits, two seeds; no interval code), joints
/// turning freely: each in exactly one certified box, each box holding one, nothing undecided;
/// the closed form answers the poses that are not singular.
#[test]
fn ur_arms_match_the_homotopy_references() {
    use super::six_r::homotopy_reference::{check, summary};
    let found = check("ik6_reference_ur.json", |_, _| true);
    let names: Vec<&str> = found.iter().map(|(name, _, _, _)| name.as_str()).collect();
    assert_eq!(names, ["ur5", "ur5_ros"]);
    summary(&found);
    for (name, hist, _, closed) in &found {
        assert_eq!(hist.values().sum::<usize>(), 30, "{name}");
        assert!(hist.keys().any(|&n| n == 8), "{name}: {hist:?}");
        assert!(*closed >= 28, "{name}: {closed} of 30 in closed form");
    }
}

/// Median microseconds per pose, closed form against the search on the same poses (release
/// build, one thread, one-turn ranges): a measurement, not a check.
#[test]
#[ignore = "long: timing figures"]
fn closed_form_and_search_timings() {
    let poses: usize = std::env::var("UR_POSES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for (name, file) in ARMS {
        let m = mechanism(file);
        let chain = one_turn(&m);
        let mut rng = Lcg(2026);
        let (mut closed, mut searched, mut methods) = (Vec::new(), Vec::new(), 0);
        for _ in 0..poses {
            let q = random_q(&chain, &mut rng);
            let target = PoseTarget::around(&forward(&m, &chain, &q), 1e-12).expect("finite");
            let t = Instant::now();
            let a = ik::solve(&chain, &target, 1e-10, &control(None)).expect("solves");
            closed.push(1e6 * t.elapsed().as_secs_f64());
            methods += usize::from(a.method == Ik6Method::ClosedForm);
            let t = Instant::now();
            ik::search(&chain, &target, 1e-10, &control(None)).expect("searches");
            searched.push(1e6 * t.elapsed().as_secs_f64());
        }
        println!(
            "{name}: {poses} poses, {methods} in closed form; median {:.1} us (max {:.0}) closed form, {:.0} us (max {:.0}) search, ratio {:.0}",
            median(closed.clone()),
            closed.iter().cloned().fold(0.0, f64::max),
            median(searched.clone()),
            searched.iter().cloned().fold(0.0, f64::max),
            median(searched.clone()) / median(closed.clone())
        );
    }
}

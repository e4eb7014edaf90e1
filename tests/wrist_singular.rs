//! Test idea: at a wrist-singular pose (joint 5 lining axes 4 and 6 up) a spherical-wrist arm's
//! solutions of the generating branch form a curve on which joints 4 and 6 turn together; the
//! answer reports that branch as a curve, its cover enclosing the curve, and certifies the
//! isolated solutions of the other branches. The reference is forward kinematics written in
//! the tests (no solver code): which of `θ₄ + t, θ₆ ∓ t` keeps the pose is read off it, and every
//! point of that curve within the limits must lie in the cover. Just off the singularity
//! (joint 5 at 1e-9) the generating configuration and its wrist flip lie in the answer. On a
//! UR-family arm at joint 5 = 0 axis 6 lines up with axes 2, 3, 4: joint 6 turns freely, joints
//! 2–4 following, and the reference curve is traced by Gauss–Newton on forward kinematics.

use crate::spherical_wrist::{control, forward, holds, mechanism, meets, random_q, Lcg};
use linkspace::analyses::arm6r::ik::{self, Ik6Method};
use linkspace::analyses::arm6r::{Chain6R, Ik6Solutions, Pose64, PoseTarget};
use linkspace::kernel::interval::Interval;
use linkspace::kernel::search::Status;
use std::f64::consts::{PI, TAU};
use std::time::Duration;

const ARMS: [&str; 3] = ["urdf/puma560.urdf", "urdf/kuka_kr16.urdf", "urdf/staubli_tx90.urdf"];

fn distance(a: &Pose64, b: &Pose64) -> f64 {
    let r = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| (a.r[i][j] - b.r[i][j]).abs());
    r.chain((0..3).map(|i| (a.t[i] - b.t[i]).abs())).fold(0.0, f64::max)
}

/// The copies of `x` (modulo a turn) within the joint's range.
fn copies(chain: &Chain6R, k: usize, x: f64) -> Vec<f64> {
    let (lo, hi) = chain.ranges[k];
    (-3..=3).map(|n| x + n as f64 * TAU).filter(|y| (lo..=hi).contains(y)).collect()
}

/// Whether the answer holds `q`: in a unique box, a cluster or a curve's cover.
fn kept(found: &Ik6Solutions, q: &[f64; 6]) -> bool {
    found.unique.iter().any(|b| holds(b, q)) || found.clusters.iter().any(|c| holds(&c.hull, q)) || found.curves.iter().flat_map(|c| &c.cover).any(|b| holds(b, q))
}

fn singular_q(chain: &Chain6R, rng: &mut Lcg, q5: f64) -> [f64; 6] {
    let mut q = random_q(chain, rng);
    q[4] = q5;
    q
}

/// Joint 5 at 0 on three arms, four poses each: answered in closed form within a second, with
/// at least one curve; every point of the generating curve within the limits (joint 4 on a
/// grid of 1e-3 rad, joint 6 following it) lies in a curve's cover; each unique box's centre
/// has the pose; no unique box meets a curve; and every box the search certifies (2 s) meets
/// exactly one unique box of the answer or one of its curves.
#[test]
fn at_the_wrist_singularity_the_branch_is_answered_as_a_curve() {
    let mut rng = Lcg(1989);
    for file in ARMS {
        let m = mechanism(file);
        let chain = Chain6R::from_mechanism(&m, None, None).expect("six joints");
        for _ in 0..4 {
            let q = singular_q(&chain, &mut rng, 0.0);
            let pose = forward(&m, &chain, &q);
            let target = PoseTarget::around(&pose, 4e-15).expect("finite");
            let found = ik::solve(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("solves");
            println!("{file} q {q:?}: {:?}, {} unique, {} curves ({} boxes), {:.4} s", found.method, found.unique.len(), found.curves.len(), found.curves.iter().map(|c| c.cover.len()).sum::<usize>(), found.stats.seconds);
            assert_eq!(found.method, Ik6Method::ClosedForm, "{file} q {q:?}");
            assert!(found.status == Status::Finished && found.clusters.is_empty() && !found.curves.is_empty(), "{file} q {q:?}: {found:?}");
            // The generating curve: joints 4 and 6 turned together, the sign read off the pose.
            let along = |sign: f64, t: f64| {
                let mut p = q;
                (p[3], p[5]) = (q[3] + t, q[5] - sign * t);
                p
            };
            let sign = [1.0, -1.0].into_iter().find(|&s| distance(&forward(&m, &chain, &along(s, 0.7)), &pose) < 1e-12).expect("joints 4 and 6 turn together at joint 5 = 0");
            let mut points = 0;
            let (lo, hi) = chain.ranges[3];
            for i in 0..=((hi - lo) / 1e-3) as usize {
                let t4 = lo + i as f64 * 1e-3;
                let p = along(sign, t4 - q[3]);
                for t6 in copies(&chain, 5, p[5]) {
                    let p = [p[0], p[1], p[2], t4, 0.0, t6];
                    points += 1;
                    assert!(found.curves.iter().flat_map(|c| &c.cover).any(|b| holds(b, &p)), "{file}: curve point {p:?} not covered");
                }
            }
            assert!(points > 1000, "{file}: {points} points of the curve within the limits");
            for b in &found.unique {
                let centre = b.map(|x| x.mid());
                assert!(distance(&forward(&m, &chain, &centre), &pose) < 1e-9, "{file}: unique box {b:?}");
                assert!(!found.curves.iter().flat_map(|c| &c.cover).any(|c| meets(b, c)), "{file}: unique box {b:?} on a curve");
            }
            let searched = ik::search(&chain, &target, 1e-10, &control(Some(Duration::from_secs(2)))).expect("searches");
            println!("  the search alone: {:?}, {} unique, {} clusters, {:.2} s", searched.status, searched.unique.len(), searched.clusters.len(), searched.stats.seconds);
            for s in &searched.unique {
                let claims = found.unique.iter().filter(|u| meets(u, s)).count() + usize::from(found.curves.iter().flat_map(|c| &c.cover).any(|c| meets(c, s)));
                assert_eq!(claims, 1, "{file} q {q:?}: search box {s:?}");
            }
        }
    }
}

/// Joint 5 at 1e-9: the enclosures cannot tell this pose from a singular one, so the branch is
/// a curve again; the generating configuration and its wrist flip (joint 4 and 6 a half turn
/// on, joint 5 negated: the same pose, read off forward kinematics) both lie in the answer.
/// The cover's boxes are narrow across the curve: joint 5 within 1e-4 of 0 (about the square
/// root of the enclosures' width, as at a double root).
#[test]
fn just_off_the_wrist_singularity_both_wrist_flips_are_kept() {
    let mut rng = Lcg(2022);
    for file in ARMS {
        let m = mechanism(file);
        let chain = Chain6R::from_mechanism(&m, None, None).expect("six joints");
        for _ in 0..4 {
            let q = singular_q(&chain, &mut rng, 1e-9);
            let pose = forward(&m, &chain, &q);
            let target = PoseTarget::around(&pose, 4e-15).expect("finite");
            let found = ik::solve(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("solves");
            assert!(found.status == Status::Finished && found.method != Ik6Method::Search, "{file} q {q:?}: {found:?}");
            assert!(kept(&found, &q), "{file} q {q:?}: {found:?}");
            let flip = [q[0], q[1], q[2], q[3] + PI, -q[4], q[5] + PI];
            assert!(distance(&forward(&m, &chain, &flip), &pose) < 1e-12, "{file}: the wrist flip keeps the pose");
            for t4 in copies(&chain, 3, flip[3]) {
                for t6 in copies(&chain, 5, flip[5]) {
                    let f = [flip[0], flip[1], flip[2], t4, flip[4], t6];
                    assert!(kept(&found, &f), "{file} flip {f:?}: {found:?}");
                }
            }
            let across: Vec<Interval> = found.curves.iter().flat_map(|c| &c.cover).map(|b| b[4]).collect();
            let widest = across.iter().map(|x| x.mag()).fold(0.0, f64::max);
            println!("{file}: joint 5 within {widest:.1e} of 0 across the curve");
            assert!(widest < 1e-4, "{file}: joint 5 across the curve {widest:e}");
        }
    }
}

/// The pose of `link`'s frame at `q` (the chain's joints in order, those past `link` unused).
fn forward_to(m: &linkspace::model::Mechanism, link: &str, q: &[f64; 6]) -> Pose64 {
    let mut free = q.iter();
    let mut pose = Pose64::IDENTITY;
    for j in m.path_to(m.link(link).expect("link")) {
        let joint = &m.joints[j];
        let o = joint.origin.translation.vector;
        let origin = match joint.exact_rotation {
            Some(r) => Pose64 { r, t: [o[0], o[1], o[2]] },
            None => Pose64::from_xyz_rpy([o[0], o[1], o[2], joint.rpy[0], joint.rpy[1], joint.rpy[2]]),
        };
        pose = pose.then(&origin);
        if let linkspace::model::JointKind::Revolute { .. } = joint.kind {
            let n = (joint.axis[0].powi(2) + joint.axis[1].powi(2) + joint.axis[2].powi(2)).sqrt();
            pose = pose.then(&crate::spherical_wrist::about([joint.axis[0] / n, joint.axis[1] / n, joint.axis[2] / n], *free.next().expect("six joints")));
        }
    }
    pose
}

/// Joints 4–6 moved by Newton's method (finite differences) until the tip has `pose`'s
/// rotation, joints 1–3 held; `None` when it does not converge (near a wrist singularity).
fn wrist_newton(m: &linkspace::model::Mechanism, chain: &Chain6R, q: [f64; 6], pose: &Pose64) -> Option<[f64; 6]> {
    let error = |q: &[f64; 6]| {
        let r = forward(m, chain, q).r;
        // The skew part of Rᵀ_target·R: zero where the rotations agree (near each other).
        let e = |i: usize, j: usize| (0..3).map(|k| pose.r[k][i] * r[k][j]).sum::<f64>();
        [e(2, 1) - e(1, 2), e(0, 2) - e(2, 0), e(1, 0) - e(0, 1)]
    };
    let mut q = q;
    for _ in 0..30 {
        let f = error(&q);
        if f.iter().all(|x| x.abs() < 1e-14) {
            return (distance(&forward(m, chain, &q), pose) < 1e-10).then_some(q);
        }
        let cols: Vec<[f64; 3]> = (3..6).map(|k| {
            let mut p = q;
            p[k] += 1e-7;
            let g = error(&p);
            [0, 1, 2].map(|i| (g[i] - f[i]) / 1e-7)
        }).collect();
        let a = |i: usize, j: usize| cols[j][i];
        let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0)) + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
        if det.abs() < 1e-6 {
            return None;
        }
        // Cramer's rule for the step.
        for j in 0..3 {
            let col = |c: usize, i: usize| if c == j { -f[i] } else { a(i, c) };
            let dj = col(0, 0) * (col(1, 1) * col(2, 2) - col(2, 1) * col(1, 2)) - col(1, 0) * (col(0, 1) * col(2, 2) - col(2, 1) * col(0, 2)) + col(2, 0) * (col(0, 1) * col(1, 2) - col(1, 1) * col(0, 2));
            q[3 + j] += dj / det;
        }
    }
    None
}

/// The KR16 with its wrist centre (joint 5's origin) on axis 1, joint 3 found by bisection in
/// the forward kinematics: joint 1 turns freely. The answer is complete in closed form with a
/// `Shoulder` curve whose cover spans joint 1's range, and it holds every point of the
/// reference curve: joint 1 stepped by 0.01 rad over its range from the generating
/// configuration, joints 4–6 followed by Newton's method on the tip's rotation (every point
/// checked on the whole pose; those beyond a wrist joint's limits are no solutions).
#[test]
fn at_the_shoulder_singularity_joint_1_turns_freely_on_a_curve() {
    let m = mechanism("urdf/kuka_kr16.urdf");
    let chain = Chain6R::from_mechanism(&m, None, None).expect("six joints");
    let radial = |t2: f64, t3: f64| forward_to(&m, "link_5", &[0.0, t2, t3, 0.0, 0.0, 0.0]).t[0];
    let (lo3, hi3) = chain.ranges[2];
    let (t2, mut bracket) = [-1.0, -1.5, -2.0, -0.5].into_iter().find_map(|t2| {
        let grid: Vec<f64> = (0..=400).map(|i| lo3 + (hi3 - lo3) * i as f64 / 400.0).collect();
        grid.windows(2).find(|w| radial(t2, w[0]).signum() != radial(t2, w[1]).signum()).map(|w| (t2, [w[0], w[1]]))
    }).expect("the wrist centre crosses axis 1");
    for _ in 0..200 {
        let mid = 0.5 * (bracket[0] + bracket[1]);
        bracket = if radial(t2, mid).signum() == radial(t2, bracket[0]).signum() { [mid, bracket[1]] } else { [bracket[0], mid] };
    }
    let q = [0.4, t2, bracket[0], 0.7, 0.9, -0.5];
    let centre = forward_to(&m, "link_5", &q).t;
    assert!(centre[0].hypot(centre[1]) < 1e-14, "wrist centre {centre:?}");
    let pose = forward(&m, &chain, &q);
    let target = PoseTarget::around(&pose, 4e-15).expect("finite");
    let found = ik::solve(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("solves");
    let shoulder: Vec<&[Interval; 6]> = found.curves.iter().filter(|c| c.kind == ik::CurveKind::Shoulder).flat_map(|c| &c.cover).collect();
    println!("KR16 at the shoulder singularity: {:?}, {} unique, {} curves, {} boxes at the shoulder, {:.4} s", found.method, found.unique.len(), found.curves.len(), shoulder.len(), found.stats.seconds);
    assert_eq!(found.method, Ik6Method::ClosedForm);
    assert!(found.status == Status::Finished && found.clusters.is_empty() && !shoulder.is_empty(), "{found:?}");
    let (lo1, hi1) = chain.ranges[0];
    let (mut points, mut newton_failed) = (0, 0);
    for direction in [1.0, -1.0] {
        let mut p = q;
        loop {
            p[0] += direction * 0.01;
            if !(lo1..=hi1).contains(&p[0]) {
                break;
            }
            let Some(next) = wrist_newton(&m, &chain, p, &pose) else {
                newton_failed += 1;
                break;
            };
            p = next;
            // A point beyond a wrist joint's limits is no solution within them.
            let mut wrapped = p;
            let within = (3..6).all(|k| copies(&chain, k, p[k]).first().map(|&c| wrapped[k] = c).is_some());
            if !within {
                continue;
            }
            points += 1;
            assert!(shoulder.iter().any(|b| holds(b, &wrapped)), "curve point {wrapped:?} not covered");
        }
    }
    println!("  {points} reference points covered ({newton_failed} directions ended by Newton)");
    assert!(points > 300, "{points} reference points");
}

/// `q` with the joints `free` moved by Gauss–Newton's method (finite differences) until the tip
/// has `pose` (position and rotation), the others held; `None` when it does not converge (at a
/// fold of the curve, where the elbow stretches out).
fn pose_newton(m: &linkspace::model::Mechanism, chain: &Chain6R, q: [f64; 6], pose: &Pose64, free: [usize; 3]) -> Option<[f64; 6]> {
    let error = |q: &[f64; 6]| {
        let p = forward(m, chain, q);
        let e = |i: usize, j: usize| (0..3).map(|k| pose.r[k][i] * p.r[k][j]).sum::<f64>();
        [p.t[0] - pose.t[0], p.t[1] - pose.t[1], p.t[2] - pose.t[2], e(2, 1) - e(1, 2), e(0, 2) - e(2, 0), e(1, 0) - e(0, 1)]
    };
    let det3 = |a: &[[f64; 3]; 3]| a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    let mut q = q;
    for _ in 0..40 {
        let f = error(&q);
        if f.iter().all(|x| x.abs() < 1e-13) {
            return (distance(&forward(m, chain, &q), pose) < 1e-10).then_some(q);
        }
        let cols: Vec<[f64; 6]> = free.iter().map(|&k| {
            let mut p = q;
            p[k] += 1e-7;
            let g = error(&p);
            std::array::from_fn(|i| (g[i] - f[i]) / 1e-7)
        }).collect();
        // The normal equations JᵀJ δ = −Jᵀf, by Cramer's rule.
        let jtj: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| (0..6).map(|r| cols[i][r] * cols[j][r]).sum()));
        let jtf: [f64; 3] = std::array::from_fn(|i| -(0..6).map(|r| cols[i][r] * f[r]).sum::<f64>());
        let det = det3(&jtj);
        if det.abs() < 1e-10 {
            return None;
        }
        for (j, &k) in free.iter().enumerate() {
            let mut a = jtj;
            for i in 0..3 {
                a[i][j] = jtf[i];
            }
            q[k] += det3(&a) / det;
        }
    }
    None
}

const UR_ARMS: [&str; 2] = ["urdf/ur5.urdf", "tests/data/ur5_ros_style.urdf"];

/// Joint 5 at 0 on the UR5 files (axis 6 along axes 2, 3, 4): answered completely in closed
/// form with a curve on which joints 2, 3, 4 and 6 move; the reference curve is joint 6 stepped
/// by 0.01 rad over its range from the generating configuration (and from the other elbow),
/// joints 2–4 followed by Gauss–Newton on the whole pose, joints 1 and 5 held: every point in
/// the cover. Each unique box's centre has the pose, and none meets the cover.
#[test]
fn at_the_aligned_wrist_of_a_ur_arm_joint_6_turns_freely_on_a_curve() {
    let mut rng = Lcg(2013);
    for file in UR_ARMS {
        let m = mechanism(file);
        let chain = Chain6R::from_mechanism(&m, None, None).expect("six joints");
        for _ in 0..3 {
            let q = singular_q(&chain, &mut rng, 0.0);
            let pose = forward(&m, &chain, &q);
            let target = PoseTarget::around(&pose, 4e-15).expect("finite");
            let found = ik::solve(&chain, &target, 1e-10, &control(Some(Duration::from_secs(5)))).expect("solves");
            let cover: Vec<&[Interval; 6]> = found.curves.iter().filter(|c| c.kind == ik::CurveKind::WristAligned).flat_map(|c| &c.cover).collect();
            println!("{file} q {q:?}: {:?}, {} unique, {} curves ({} boxes), {:.4} s", found.method, found.unique.len(), found.curves.len(), cover.len(), found.stats.seconds);
            assert_eq!(found.method, Ik6Method::ClosedForm, "{file} q {q:?}");
            assert!(found.status == Status::Finished && found.clusters.is_empty() && !cover.is_empty(), "{file} q {q:?}: {found:?}");
            let (lo, hi) = chain.ranges[5];
            let mut points = 0;
            let other_elbow = pose_newton(&m, &chain, [q[0], q[1] + 0.3, -q[2], q[3], q[4], q[5]], &pose, [1, 2, 3]);
            for start in [Some(q), other_elbow].into_iter().flatten() {
                for direction in [1.0, -1.0] {
                    let mut p = start;
                    while (lo..=hi).contains(&p[5]) {
                        let Some(next) = pose_newton(&m, &chain, p, &pose, [1, 2, 3]) else { break };
                        p = next;
                        // A point beyond a joint's limits is no solution within them.
                        let mut wrapped = p;
                        if (1..4).all(|k| copies(&chain, k, p[k]).first().map(|&c| wrapped[k] = c).is_some()) {
                            points += 1;
                            assert!(cover.iter().any(|b| holds(b, &wrapped)), "{file}: curve point {wrapped:?} not covered");
                        }
                        p[5] += direction * 0.01;
                    }
                }
            }
            println!("  {points} reference points covered");
            assert!(points > 300, "{file}: {points} reference points");
            for b in &found.unique {
                let centre = b.map(|x| x.mid());
                assert!(distance(&forward(&m, &chain, &centre), &pose) < 1e-9, "{file}: unique box {b:?}");
                assert!(!cover.iter().any(|c| meets(b, c)), "{file}: unique box {b:?} on the curve");
            }
        }
    }
}

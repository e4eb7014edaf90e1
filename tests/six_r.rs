//! Certified 6R inverse kinematics against references computed without the solver: poses
//! from forward kinematics of known joint vectors (the solver must return a box holding each),
//! every returned box mapping back to the pose, and UR5 counts against an independent closed
//! form. The cuspidality witness of the CRX fixture re-checked in `f64`.

use linkspace::analyses::arm6r::{ik, Chain6R, CuspidalVerdict, Pose64, PoseTarget};
use linkspace::model::{rounding, urdf};
use linkspace::kernel::search::{Control, Limits, Status};
use std::path::Path;
use std::time::{Duration, Instant};

fn repo(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).expect("bundled file")
}

pub fn chain_of(xml: &str) -> Chain6R {
    let m = urdf::parse(xml).expect("parses");
    let (m, _) = rounding::snap(&m, rounding::ANGLE_TOLERANCE);
    Chain6R::from_mechanism(&m, None, None).expect("a 6R chain")
}

/// A general 6R in modified DH (`a`, `α`, `d` per joint), as a URDF.
pub fn random_dh(seed: u64) -> String {
    let mut rng = Lcg(seed);
    let mut xml = String::from("<robot name=\"dh\"><link name=\"l0\"/>");
    let (mut a, mut alpha, mut d) = (0.0, 0.0, 0.0);
    for i in 1..=6 {
        xml += &format!(
            "<link name=\"l{i}\"/><joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/><origin xyz=\"{a} 0 {d}\" rpy=\"{alpha} 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"1\" velocity=\"1\"/></joint>",
            i - 1
        );
        a = rng.uniform(0.1, 0.6);
        alpha = rng.uniform(0.3, 2.8);
        d = rng.uniform(-0.4, 0.4);
    }
    xml += &format!("<link name=\"tool\"/><joint name=\"jt\" type=\"fixed\"><parent link=\"l6\"/><child link=\"tool\"/><origin xyz=\"{a} 0 {d}\" rpy=\"{alpha} 0 0\"/></joint></robot>");
    xml
}

pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn control() -> Control<'static> {
    static NEVER: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    Control { limits: Limits { max_cells: 3_000_000, ..Limits::default() }, threads: 1, cancel: &NEVER }
}

/// Solves FK(q) and checks: complete, a unique box holds q, every unique box maps to the pose.
/// Returns the number of unique boxes and the time.
fn check_pose(chain: &Chain6R, q: &[f64; 6]) -> (usize, Duration) {
    let pose = chain.pose(q);
    let target = PoseTarget::around(&pose, 1e-12).expect("finite");
    let t = Instant::now();
    let sol = ik::solve(chain, &target, 1e-10, &control()).expect("solves");
    let dt = t.elapsed();
    assert_eq!(sol.status, Status::Finished, "q = {q:?}");
    let holds = |b: &[linkspace::kernel::interval::Interval; 6]| (0..6).all(|k| b[k].inf() - 1e-7 <= q[k] && q[k] <= b[k].sup() + 1e-7);
    assert!(sol.unique.iter().any(holds) || sol.clusters.iter().any(|c| holds(&c.hull)), "q = {q:?} lost: {:?}", sol.unique);
    for u in &sol.unique {
        let m = u.map(|x| x.mid());
        assert!(chain.pose(&m).distance(&pose) < 1e-6, "a box off the pose: {u:?}");
        assert!(u.iter().all(|x| x.wid() < 1e-6));
    }
    (sol.unique.len(), dt)
}

fn random_q(chain: &Chain6R, rng: &mut Lcg) -> [f64; 6] {
    [0, 1, 2, 3, 4, 5].map(|k| {
        let (lo, hi) = chain.ranges[k];
        rng.uniform(lo.max(-3.1), hi.min(3.1))
    })
}

fn sweep(chain: &Chain6R, poses: usize, seed: u64) -> (Vec<usize>, Vec<f64>) {
    let mut rng = Lcg(seed);
    let (mut counts, mut times) = (Vec::new(), Vec::new());
    for _ in 0..poses {
        let q = random_q(chain, &mut rng);
        let (n, dt) = check_pose(chain, &q);
        counts.push(n);
        times.push(dt.as_secs_f64());
    }
    (counts, times)
}

#[test]
fn random_general_6r_loses_no_solution() {
    for seed in 1..=3 {
        let chain = chain_of(&random_dh(seed));
        let (counts, _) = sweep(&chain, 4, seed);
        assert!(counts.iter().all(|n| (1..=16).contains(n)), "{counts:?}");
    }
}

#[test]
fn bundled_arms_lose_no_solution() {
    for file in ["urdf/puma560.urdf", "urdf/ur5.urdf", "urdf/kuka_kr16.urdf", "tests/data/fanuc_crx10ial_style.urdf", "tests/data/abb_irb140_style.urdf"] {
        let chain = chain_of(&repo(file)).within_one_turn();
        sweep(&chain, 3, 7);
    }
}

/// Median time per pose and the solution counts (release build, one thread).
#[test]
#[ignore = "long: timing figures"]
fn timing_figures() {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for (name, xml) in [("general 6R", random_dh(11)), ("ur5", repo("urdf/ur5.urdf")), ("crx", repo("tests/data/fanuc_crx10ial_style.urdf")), ("puma", repo("urdf/puma560.urdf"))] {
        let chain = chain_of(&xml).within_one_turn();
        let (counts, times) = sweep(&chain, 50, 3);
        let mut hist = std::collections::BTreeMap::new();
        for c in counts {
            *hist.entry(c).or_insert(0) += 1;
        }
        println!("{name}: median {:.1} ms, max {:.1} ms, counts {hist:?}", 1e3 * median(times.clone()), 1e3 * times.iter().cloned().fold(0.0, f64::max));
    }
}

#[test]
#[ignore = "long: counters"]
fn counters() {
    let file = std::env::var("SIX_R_ARM").unwrap_or_default();
    let chain = if file.is_empty() { chain_of(&random_dh(1)) } else { chain_of(&repo(&file)) };
    let mut rng = Lcg(7);
    for _ in 0..3 {
        let q = random_q(&chain, &mut rng);
        let target = PoseTarget::around(&chain.pose(&q), 1e-12).expect("finite");
        let t = Instant::now();
        let sol = ik::solve(&chain, &target, 1e-10, &control()).expect("solves");
        println!("{:?} {} unique, {} clusters {:?} {:?}", t.elapsed(), sol.unique.len(), sol.clusters.len(), sol.status, sol.stats);
    }
}

fn never() -> &'static std::sync::atomic::AtomicBool {
    static NEVER: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    &NEVER
}

/// The CRX fixture is cuspidal: the witness re-checked in `f64` (both ends map to the pose,
/// det J keeps its sign along the path sampled densely).
#[test]
fn crx_is_cuspidal_with_a_witness_checked_in_f64() {
    let chain = chain_of(&repo("tests/data/fanuc_crx10ial_style.urdf"));
    let control = Control { limits: Limits { max_cells: 3_000_000, ..Limits::default() }, threads: 1, cancel: never() };
    let t = Instant::now();
    let outcome = linkspace::analyses::arm6r::cuspidal::search(&chain, Duration::from_secs(600), 1, &control);
    let CuspidalVerdict::Cuspidal(w) = outcome.verdict else { panic!("no witness: {:?}", outcome.verdict) };
    // The most solutions seen: at least the witness's two, at most a 6R's sixteen.
    let most = outcome.most.expect("poses were solved");
    assert!((2..=16).contains(&most.count), "{most:?}");
    println!("CRX witness in {:.1} s: {} pieces, min |det J| {:.3e}", t.elapsed().as_secs_f64(), w.pieces, w.min_abs_det);
    let ends: [[f64; 6]; 2] = [w.path[0], *w.path.last().expect("a path")];
    for q in ends {
        assert!(chain.pose(&q).distance(&w.pose) < 1e-7);
    }
    assert!((0..6).any(|k| {
        let d = (ends[0][k] - ends[1][k]).rem_euclid(std::f64::consts::TAU);
        d > 1e-3 && d < std::f64::consts::TAU - 1e-3
    }), "two distinct configurations");
    for seg in w.path.windows(2) {
        for i in 0..=2000 {
            let t = i as f64 / 2000.0;
            let q: [f64; 6] = [0, 1, 2, 3, 4, 5].map(|k| seg[0][k] + t * (seg[1][k] - seg[0][k]));
            assert!(chain.det_jacobian(&q) * w.det_sign > 0.0, "det J changes sign at {q:?}");
        }
    }
}

/// UR5 (three consecutive parallel axes) is never reported cuspidal.
#[test]
fn ur5_is_never_cuspidal() {
    let chain = chain_of(&repo("urdf/ur5.urdf"));
    let control = Control { limits: Limits { max_cells: 3_000_000, ..Limits::default() }, threads: 1, cancel: never() };
    let outcome = linkspace::analyses::arm6r::cuspidal::search(&chain, Duration::from_secs(20), 1, &control);
    assert!(matches!(outcome.verdict, CuspidalVerdict::Undecided { .. }), "{:?}", outcome.verdict);
    // The most solutions the search certified at one pose: exactly the closed form's count
    // there (the file is the DH table).
    let most = outcome.most.expect("poses were solved");
    let mut t = nalgebra::Matrix4::identity();
    for i in 0..3 {
        for j in 0..3 {
            t[(i, j)] = most.pose.r[i][j];
        }
        t[(i, 3)] = most.pose.t[i];
    }
    assert_eq!(most.count, ur5_closed_form::solve(&t).len(), "{most:?}");
    assert!(most.count <= 8);
}

/// UR5 (`urdf/ur5.urdf` is the standard DH table, tool0 = frame 6) against an independent
/// closed form: the number of configurations for poses of random joint vectors.
mod ur5_closed_form {
    use nalgebra::{Matrix4, Vector3};
    const D: [f64; 6] = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823];
    const A: [f64; 6] = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0];
    const ALPHA: [f64; 6] = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2, 0.0];

    fn dh(i: usize, t: f64) -> Matrix4<f64> {
        let (s, c) = t.sin_cos();
        let (sa, ca) = ALPHA[i].sin_cos();
        Matrix4::new(c, -s * ca, s * sa, A[i] * c, s, c * ca, -c * sa, A[i] * s, 0.0, sa, ca, D[i], 0.0, 0.0, 0.0, 1.0)
    }

    pub fn fk(q: &[f64; 6]) -> Matrix4<f64> {
        (0..6).fold(Matrix4::identity(), |t, i| t * dh(i, q[i]))
    }

    /// Every configuration of the pose `t` (Hawkins' closed form), each checked by `fk`.
    pub fn solve(t: &Matrix4<f64>) -> Vec<[f64; 6]> {
        let (n, o, a, p) = (t.fixed_view::<3, 1>(0, 0), t.fixed_view::<3, 1>(0, 1), t.fixed_view::<3, 1>(0, 2), t.fixed_view::<3, 1>(0, 3));
        let p05: Vector3<f64> = p - a * D[5];
        let r = p05.x.hypot(p05.y);
        let mut out = Vec::new();
        if r < D[3].abs() {
            return out;
        }
        for s1sign in [1.0, -1.0] {
            let t1 = p05.y.atan2(p05.x) + s1sign * (D[3] / r).acos() + std::f64::consts::FRAC_PI_2;
            let (s1, c1) = t1.sin_cos();
            let c5 = (p.x * s1 - p.y * c1 - D[3]) / D[5];
            if c5.abs() > 1.0 {
                continue;
            }
            for s5sign in [1.0, -1.0] {
                let t5 = s5sign * c5.acos();
                let s5 = t5.sin();
                let t6 = (-(o.x * s1 - o.y * c1) / s5).atan2((n.x * s1 - n.y * c1) / s5);
                let t14 = dh(0, t1).try_inverse().expect("rigid") * t * (dh(4, t5) * dh(5, t6)).try_inverse().expect("rigid");
                let (px, pz) = (t14[(0, 3)], t14[(1, 3)]);
                // Frame 1 after joint 1's α: the planar chain lies in its x–y plane.
                let len2 = px * px + pz * pz;
                let c3 = (len2 - A[1] * A[1] - A[2] * A[2]) / (2.0 * A[1] * A[2]);
                if c3.abs() > 1.0 {
                    continue;
                }
                for s3sign in [1.0, -1.0] {
                    let t3 = s3sign * c3.acos();
                    let t2 = pz.atan2(px) - (A[2] * t3.sin()).atan2(A[1] + A[2] * t3.cos());
                    let t34 = (dh(1, t2) * dh(2, t3)).try_inverse().expect("rigid") * t14;
                    let t4 = t34[(1, 0)].atan2(t34[(0, 0)]);
                    let q = [t1, t2, t3, t4, t5, t6];
                    if (fk(&q) - t).norm() < 1e-8 {
                        out.push(q);
                    }
                }
            }
        }
        out
    }
}

#[test]
fn ur5_counts_match_the_closed_form() {
    ur5_against_the_closed_form(12, 5);
}

/// The same on 1,000 random poses (about two minutes in release on two shared cores).
#[test]
#[ignore = "long: 1,000 poses"]
fn ur5_counts_match_the_closed_form_on_a_thousand_poses() {
    ur5_against_the_closed_form(1000, 1000);
}

/// Random poses of UR5 (from random joint vectors): `ik6` finds exactly the closed form's
/// solutions, each in its own certified box, the box holding that solution.
fn ur5_against_the_closed_form(poses: usize, seed: u64) {
    let chain = chain_of(&repo("urdf/ur5.urdf")).within_one_turn();
    let mut rng = Lcg(seed);
    for _ in 0..poses {
        let q = random_q(&chain, &mut rng);
        let t = ur5_closed_form::fk(&q);
        let pose = chain.pose(&q);
        let m = Pose64 { r: [0, 1, 2].map(|i| [0, 1, 2].map(|j| t[(i, j)])), t: [t[(0, 3)], t[(1, 3)], t[(2, 3)]] };
        assert!(pose.distance(&m) < 1e-9, "the file is the DH table: {pose:?} {m:?}");
        let analytic = ur5_closed_form::solve(&t);
        assert!(analytic.iter().any(|a| (0..6).all(|k| (a[k] - q[k]).rem_euclid(std::f64::consts::TAU).min((q[k] - a[k]).rem_euclid(std::f64::consts::TAU)) < 1e-6)), "closed form misses q");
        let sol = ik::solve(&chain, &PoseTarget::around(&pose, 1e-12).expect("finite"), 1e-10, &control()).expect("solves");
        assert_eq!(sol.status, Status::Finished);
        assert!(sol.clusters.is_empty());
        assert_eq!(sol.unique.len(), analytic.len(), "q = {q:?}");
        let near = |a: f64, b: f64| (a - b).rem_euclid(std::f64::consts::TAU).min((b - a).rem_euclid(std::f64::consts::TAU)) < 1e-6;
        for a in &analytic {
            let holding: Vec<_> = sol.unique.iter().filter(|u| (0..6).all(|k| near(a[k], u[k].mid()))).collect();
            assert_eq!(holding.len(), 1, "closed-form solution {a:?} of q = {q:?} in {} boxes", holding.len());
        }
    }
}

/// A quarter turn as vendor files write it, truncated (the rounding policy snaps it).
#[allow(clippy::approx_constant)]
const QUARTER: f64 = 1.570796327;

/// A member of the UR family in modified DH (joint i's origin `Tx(a)·Tz(d)·Rx(α)`), with
/// offsets between axes 1 and 2 and between axes 4 and 5, and axis 1 at `alpha1` to axis 2.
fn ur_family_dh(seed: u64, alpha1: f64) -> String {
    let mut rng = Lcg(seed);
    let alpha = [0.0, alpha1, 0.0, 0.0, QUARTER, -QUARTER];
    let a = [0.0, rng.uniform(-0.1, 0.1), rng.uniform(0.2, 0.6), rng.uniform(-0.6, -0.2), rng.uniform(-0.1, 0.1), 0.0];
    let mut xml = String::from("<robot name=\"ur_family\"><link name=\"l0\"/>");
    for i in 0..6 {
        let d = rng.uniform(-0.2, 0.2);
        xml += &format!(
            "<link name=\"l{}\"/><joint name=\"j{}\" type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/><origin xyz=\"{} 0 {d}\" rpy=\"{} 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"1\" velocity=\"1\"/></joint>",
            i + 1, i + 1, i + 1, a[i], alpha[i]
        );
    }
    xml + "<link name=\"tool\"/><joint name=\"jt\" type=\"fixed\"><parent link=\"l6\"/><child link=\"tool\"/><origin xyz=\"0.02 0 0.1\" rpy=\"0.3 0.2 0.1\"/></joint></robot>"
}

/// The non-cuspidality proof's two claims checked on the solver's output: every certified
/// solution of a pose has a sign pattern of (shoulder, elbow, wrist) factors of its own, and
/// the patterns pick the closed-form roots (one sign of the shoulder factor, one θ1; one sign
/// of shoulder and wrist, one θ5).
#[test]
fn ur_family_solutions_differ_in_the_signs_of_det_j_factors() {
    use linkspace::analyses::arm6r::three_parallel;
    let arms = [repo("urdf/ur5.urdf"), repo("tests/data/ur5_ros_style.urdf"), ur_family_dh(3, QUARTER), ur_family_dh(4, 0.7)];
    let same_angle = |x: f64, y: f64| (x - y).rem_euclid(std::f64::consts::TAU).min((y - x).rem_euclid(std::f64::consts::TAU)) < 1e-6;
    let mut most = 0;
    for (n, xml) in arms.iter().enumerate() {
        let chain = chain_of(xml).within_one_turn();
        assert!(three_parallel::recognise(&chain).is_some(), "arm {n} recognised");
        let mut rng = Lcg(10 + n as u64);
        for _ in 0..6 {
            let q = random_q(&chain, &mut rng);
            let pose = chain.pose(&q);
            let sol = ik::solve(&chain, &PoseTarget::around(&pose, 1e-12).expect("finite"), 1e-10, &control()).expect("solves");
            assert_eq!(sol.status, Status::Finished);
            most = most.max(sol.unique.len());
            let mids: Vec<[f64; 6]> = sol.unique.iter().map(|u| u.map(|x| x.mid())).collect();
            let signs: Vec<[bool; 3]> = mids
                .iter()
                .map(|m| {
                    let g = three_parallel::factors(&chain, m);
                    assert!(g.iter().all(|x| x.abs() > 1e-9), "a regular solution: {g:?}");
                    g.map(|x| x > 0.0)
                })
                .collect();
            for i in 0..mids.len() {
                for j in i + 1..mids.len() {
                    assert_ne!(signs[i], signs[j], "arm {n}: two solutions with one sign pattern: {:?} {:?}", mids[i], mids[j]);
                    if signs[i][0] == signs[j][0] {
                        assert!(same_angle(mids[i][0], mids[j][0]), "one shoulder sign, one theta1");
                        if signs[i][2] == signs[j][2] {
                            assert!(same_angle(mids[i][4], mids[j][4]), "one shoulder and wrist sign, one theta5");
                        }
                    } else {
                        assert!(!same_angle(mids[i][0], mids[j][0]), "the shoulder sign tells the theta1 roots apart");
                    }
                }
            }
        }
    }
    assert_eq!(most, 8, "poses with all eight patterns seen");
}

/// The recognition asks for exact relations: axis 3 tilted by 0.01 rad is out of the family,
/// and so are the CRX (axes 2, 3 parallel only) and the spherical-wrist arms.
#[test]
fn near_ur_arms_and_other_arms_are_not_recognised() {
    use linkspace::analyses::arm6r::three_parallel;
    let ur5 = repo("urdf/ur5.urdf");
    let tilted = ur5.replacen("<origin rpy=\"0 0 0\" xyz=\"-0.425 0 0\"/>", "<origin rpy=\"0.01 0 0\" xyz=\"-0.425 0 0\"/>", 1);
    assert_ne!(tilted, ur5);
    assert!(three_parallel::recognise(&chain_of(&tilted)).is_none());
    for file in ["tests/data/fanuc_crx10ial_style.urdf", "urdf/puma560.urdf", "urdf/kuka_kr16.urdf", "tests/data/abb_irb140_style.urdf", "tests/data/doosan_style_6r.urdf"] {
        assert!(three_parallel::recognise(&chain_of(&repo(file))).is_none(), "{file}");
    }
    // Taken as written (no snapping), the truncated quarter turns are not exact.
    let m = urdf::parse(&ur5).expect("parses");
    assert!(three_parallel::recognise(&Chain6R::from_mechanism(&m, None, None).expect("6R")).is_none());
}

/// Path checks on UR5 against the closed form of its wrist singularity: det J has the factor
/// sin θ5, so a straight segment on which θ5 runs from −0.4 to 0.6 (elbow and shoulder well away
/// from theirs) crosses det J = 0 exactly where θ5 = 0, at t = 0.4; a segment with θ5 in
/// [0.5, 1] is clear, its reported bound below |det J| sampled densely in `f64`; θ5 down to 0
/// and back touches at the shared waypoint without a proven sign change.
mod path_check {
    use super::*;
    use linkspace::analyses::arm6r::{path, SegmentVerdict, SpanReason};

    fn ur5() -> Chain6R {
        chain_of(&repo("urdf/ur5.urdf"))
    }

    fn lerp(x: &[f64; 6], y: &[f64; 6], t: f64) -> [f64; 6] {
        [0, 1, 2, 3, 4, 5].map(|k| x[k] + t * (y[k] - x[k]))
    }

    #[test]
    fn a_crossing_of_the_wrist_singularity_is_where_theta5_vanishes() {
        let chain = ur5();
        let (a, b) = ([0.3, -1.0, 1.2, -0.5, -0.4, 0.7], [0.5, -1.2, 1.4, -0.3, 0.6, 0.2]);
        // The reference: the wrist singularity is θ5 = 0 on this arm (det J changes sign there).
        assert!(chain.det_jacobian(&lerp(&a, &b, 0.39)) * chain.det_jacobian(&lerp(&a, &b, 0.41)) < 0.0);
        let found = path::check(&chain, &[a, b], 1e-9, &control()).expect("checks");
        let SegmentVerdict::Crosses { crossings, undecided } = &found.segments[0] else { panic!("{:?}", found.segments[0]) };
        assert!(undecided.is_empty(), "{undecided:?}");
        assert_eq!(crossings.len(), 1, "{crossings:?}");
        let c = &crossings[0];
        let t_exact = 0.4;
        assert!(c.narrowed && c.t[0] <= t_exact + 1e-15 && t_exact - 1e-15 <= c.t[1], "{c:?}");
        assert!((c.t[1] - c.t[0]) <= 1e-9, "{c:?}");
        assert!(c.joints[4][0] <= 0.0 && 0.0 <= c.joints[4][1], "{c:?}");
        assert_eq!(c.sign_before, chain.det_jacobian(&a).signum());
    }

    #[test]
    fn a_clear_segment_bounds_det_j_from_below() {
        let chain = ur5();
        let (a, b) = ([0.3, -1.0, 1.2, -0.5, 0.5, 0.7], [0.8, -1.3, 1.5, -0.2, 1.0, 0.1]);
        let found = path::check(&chain, &[a, b], 1e-9, &control()).expect("checks");
        let SegmentVerdict::Clear { sign, min_abs_det, .. } = found.segments[0] else { panic!("{:?}", found.segments[0]) };
        let sampled = (0..=20_000).map(|i| chain.det_jacobian(&lerp(&a, &b, i as f64 / 20_000.0)));
        let least = sampled.clone().fold(f64::INFINITY, |m, d| m.min(d.abs()));
        assert!(sampled.clone().all(|d| d.signum() == sign));
        assert!(min_abs_det > 0.0 && min_abs_det <= least, "bound {min_abs_det} above the sampled {least}");
        // Not a vacuous bound: within the factor the proof allows (0.75⁶ ≈ 0.18, and the cover's slack).
        assert!(min_abs_det >= 0.01 * least, "bound {min_abs_det}, sampled {least}");
    }

    #[test]
    fn touching_the_wrist_singularity_is_not_a_crossing() {
        let chain = ur5();
        let w = [[0.3, -1.0, 1.2, -0.5, 0.4, 0.7], [0.4, -1.1, 1.3, -0.4, 0.0, 0.5], [0.5, -1.2, 1.4, -0.3, 0.4, 0.2]];
        let found = path::check(&chain, &w, 1e-9, &control()).expect("checks");
        for (k, s) in found.segments.iter().enumerate() {
            let SegmentVerdict::Undecided { spans } = s else { panic!("segment {k}: {s:?}") };
            assert_eq!(spans.len(), 1, "{spans:?}");
            assert_eq!(spans[0].reason, SpanReason::AtEnd);
            // At the shared waypoint: the end of the first segment, the start of the second.
            let end = if k == 0 { spans[0].t[1] } else { spans[0].t[0] };
            assert_eq!(end, if k == 0 { 1.0 } else { 0.0 });
            assert!(spans[0].t[1] - spans[0].t[0] < 1e-3, "{spans:?}");
        }
    }

    #[test]
    fn a_stopped_run_decides_nothing_more() {
        static NEVER: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
        let stopped = Control { limits: Limits { timeout: Some(Duration::ZERO), ..Limits::default() }, threads: 1, cancel: &NEVER };
        let w = [[0.3, -1.0, 1.2, -0.5, 0.4, 0.7], [0.5, -1.2, 1.4, -0.3, 0.6, 0.2]];
        let found = path::check(&ur5(), &w, 1e-9, &stopped).expect("checks");
        assert!(matches!(found.segments[0], SegmentVerdict::Stopped(linkspace::kernel::search::Limit::Time)), "{:?}", found.segments);
        assert!(path::check(&ur5(), &w[..1], 1e-9, &control()).is_err());
    }
}

/// Every real solution of poses of a general 6R (`tests/data/ik6_general_6r.urdf`, up to 16),
/// of the CRX fixture, and of the IRB 140-style and Doosan-style fixtures, from `scripts/dev/ik6_reference.py` (monodromy and parameter
/// homotopy, refined at 60 digits, two seeds; no interval code): the certified solutions are
/// exactly the reference's, one per box, nothing undecided.
pub(crate) mod homotopy_reference {
    use super::*;
    use serde_json::Value;

    fn reference(file: &str) -> Value {
        serde_json::from_str(&repo(&format!("tests/data/{file}"))).expect("reference JSON")
    }

    fn numbers(v: &Value) -> Vec<f64> {
        v.as_array().expect("a list").iter().map(|x| x.as_f64().expect("a number")).collect()
    }

    fn six(v: &Value) -> [f64; 6] {
        numbers(v).try_into().expect("six angles")
    }

    /// `x` (radians) in the interval `[lo, hi]` up to `slack`, modulo a turn.
    fn holds(lo: f64, hi: f64, x: f64, slack: f64) -> bool {
        let mid = 0.5 * (lo + hi);
        let x = mid + (x - mid + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        lo - slack <= x && x <= hi + slack
    }

    /// Per fixture: its name, the histogram of solution counts, (pose, seconds) per pose, and
    /// how many poses the closed form answered.
    pub(crate) type Checked = (String, std::collections::BTreeMap<usize, usize>, Vec<(usize, f64)>, usize);

    /// Checks the poses of every fixture of `file` that `pick` selects (from the pose's index and
    /// the index of the fixture's first pose with the most solutions); returns per fixture the
    /// histogram of solution counts and the solver's times (seconds).
    pub(crate) fn check(file: &str, pick: impl Fn(usize, usize) -> bool) -> Vec<Checked> {
        let refs = reference(file);
        // Solutions are written with 17 significant digits, or 9 in a compact file.
        let slack = if refs.get("compact").and_then(Value::as_bool) == Some(true) { 2e-8 } else { 1e-9 };
        let mut out = Vec::new();
        for fixture in refs["fixtures"].as_array().expect("fixtures") {
            let name = fixture["name"].as_str().expect("a name");
            let chain = chain_of(&repo(fixture["urdf"].as_str().expect("a file"))).within_one_turn();
            // The reference's one-turn ranges are the chain's.
            for (k, r) in fixture["ranges"].as_array().expect("ranges").iter().enumerate() {
                if r.is_null() {
                    assert!(chain.continuous[k], "{name}: joint {k} turns freely");
                } else {
                    let r = numbers(r);
                    assert!(!chain.continuous[k] && (chain.ranges[k].0 - r[0]).abs() < 1e-12 && (chain.ranges[k].1 - r[1]).abs() < 1e-12, "{name}: joint {k} {:?} {r:?}", chain.ranges[k]);
                }
            }
            let (mut hist, mut times, mut closed) = (std::collections::BTreeMap::new(), Vec::new(), 0);
            let poses = fixture["poses"].as_array().expect("poses");
            let count = |p: &Value| p["solutions"].as_array().expect("solutions").len();
            let most = poses.iter().map(count).max().expect("poses");
            let first_most = poses.iter().position(|p| count(p) == most).expect("poses");
            for (i, p) in poses.iter().enumerate() {
                if !pick(i, first_most) {
                    continue;
                }
                let q = six(&p["q"]);
                // A compact file leaves the pose out: it is q's (the reference solved q's pose
                // at 60 digits; the two differ by rounding).
                let pose = match p.get("pose") {
                    Some(m) => {
                        let m: Vec<Vec<f64>> = m.as_array().expect("4x4").iter().map(numbers).collect();
                        Pose64 { r: [0, 1, 2].map(|r| [0, 1, 2].map(|c| m[r][c])), t: [m[0][3], m[1][3], m[2][3]] }
                    }
                    None => chain.pose(&q),
                };
                assert!(chain.pose(&q).distance(&pose) < 1e-9, "{name} pose {i}: the reference's pose is q's");
                let expected: Vec<[f64; 6]> = p["solutions"].as_array().expect("solutions").iter().map(six).collect();
                let t = Instant::now();
                let sol = ik::solve(&chain, &PoseTarget::around(&pose, 1e-12).expect("finite"), 1e-10, &control()).expect("solves");
                times.push((i, t.elapsed().as_secs_f64()));
                closed += usize::from(sol.method == ik::Ik6Method::ClosedForm);
                assert_eq!(sol.status, Status::Finished, "{name} pose {i}");
                assert!(sol.clusters.is_empty(), "{name} pose {i}: undecided {:?}", sol.clusters);
                let inside = |u: &[linkspace::kernel::interval::Interval; 6], a: &[f64; 6]| (0..6).all(|k| holds(u[k].inf(), u[k].sup(), a[k], slack));
                for a in &expected {
                    let n = sol.unique.iter().filter(|u| inside(u, a)).count();
                    assert_eq!(n, 1, "{name} pose {i}: reference solution {a:?} in {n} certified boxes of {:?}", sol.unique);
                }
                for u in &sol.unique {
                    let n = expected.iter().filter(|a| inside(u, a)).count();
                    assert_eq!(n, 1, "{name} pose {i}: certified box {u:?} holds {n} reference solutions of {expected:?}");
                }
                assert_eq!(sol.unique.len(), expected.len(), "{name} pose {i}");
                *hist.entry(expected.len()).or_insert(0) += 1;
            }
            out.push((name.to_string(), hist, times, closed));
        }
        out
    }

    /// Per fixture: the counts, the median and maximum time, and the slowest poses (index: ms).
    pub(crate) fn summary(found: &[Checked]) {
        for (name, hist, times, closed) in found {
            let mut t = times.clone();
            t.sort_by(|a, b| a.1.total_cmp(&b.1));
            let slowest: Vec<String> = t.iter().rev().take(8).map(|(i, s)| format!("{i}: {:.0}", 1e3 * s)).collect();
            let over = |limit: f64| t.iter().filter(|p| p.1 > limit).count();
            println!(
                "{name}: {} poses ({closed} in closed form), counts {hist:?}, median {:.1} ms, max {:.1} ms; over 50 / 100 / 250 ms: {} / {} / {}; slowest (pose: ms) {}",
                t.len(),
                1e3 * t[t.len() / 2].1,
                1e3 * t[t.len() - 1].1,
                over(0.05),
                over(0.1),
                over(0.25),
                slowest.join(", ")
            );
        }
    }

    /// Every pose of the default file: 30 per fixture, the most solutions 6 for the general 6R
    /// and 16 for the CRX; a few seconds in release.
    #[test]
    fn certified_solutions_are_the_homotopy_references() {
        let found = check("ik6_reference.json", |_, _| true);
        let most: Vec<usize> = found.iter().map(|(_, hist, _, _)| *hist.keys().last().expect("poses")).collect();
        assert_eq!(most, [6, 16]);
        summary(&found);
    }

    /// The IRB 140-style arm (spherical wrist, joint 4's frame on axis 3) and the Doosan-style
    /// arm (offset wrist): 30 poses each, up to 8 solutions (`tests/data/ik6_reference_vendors.json`,
    /// the same generator).
    #[test]
    fn vendor_style_arms_match_the_homotopy_references() {
        let found = check("ik6_reference_vendors.json", |_, _| true);
        let names: Vec<&str> = found.iter().map(|(name, _, _, _)| name.as_str()).collect();
        assert_eq!(names, ["irb140", "doosan"]);
        assert!(found.iter().all(|(_, hist, _, _)| hist.values().sum::<usize>() == 30 && hist.keys().any(|&n| n >= 4)));
        summary(&found);
    }

    /// 1,000 poses per fixture (`tests/data/ik6_reference_1000.json`, compact). `IK6_REFERENCE`
    /// names another file of `tests/data` (`ik6_reference_irb140_1000.json`: the IRB 140-style
    /// arm, or a checkpoint of the generator) and `IK6_POSES`
    /// (`a..b`) a range of poses, to check part of a file.
    #[test]
    #[ignore = "long: 1,000 poses per fixture"]
    fn certified_solutions_are_the_homotopy_references_on_a_thousand_poses() {
        let file = std::env::var("IK6_REFERENCE").unwrap_or_else(|_| "ik6_reference_1000.json".into());
        let range = std::env::var("IK6_POSES").ok().map(|r| {
            let (a, b) = r.split_once("..").expect("IK6_POSES=a..b");
            a.parse::<usize>().expect("a number")..b.parse::<usize>().expect("a number")
        });
        let found = check(&file, |i, _| range.as_ref().is_none_or(|r| r.contains(&i)));
        summary(&found);
        if range.is_none() {
            assert!(found.iter().all(|(_, hist, _, _)| hist.values().sum::<usize>() == 1000));
        }
    }
}

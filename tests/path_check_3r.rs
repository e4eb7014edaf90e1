//! Test idea: joint paths checked against a 3R positioning structure's singular set
//! (`det Df = 0` of (θ₂, θ₃) ↦ (ρ, z)) are compared with a reference computed without the
//! library's map: the analysed point's forward kinematics composed in `f64` from the parsed
//! URDF joints, and `det Df` from the exact derivative columns `ωₖ × (p − oₖ)` of joints 2 and
//! 3 (ρ = |(p − o₁)⊥|² and z = ω₁·(p − o₁) about the first axis line (o₁, ω₁)).
//!
//! Random segments through a singular point found by bisection on that reference (crossing it
//! transversally, and changing its sign once on dense samples) must be reported crossing, the
//! enclosure holding the point; random segments on which dense samples plus a Lipschitz margin
//! keep `|det Df|` away from zero must be reported clear, with the sampled sign and a lower
//! bound below the sampled least `|det Df|`. Bundled arms: the orthogonal 3R robots of Benoit et
//! al. (2019), UR5 and the CRX fixture (six joints, wrist not spherical: the sub-chain's point is
//! on axis 4).

use linkspace::app::{self, Arm, PathSet};
use linkspace::analyses::joint_path::SegmentVerdict;
use linkspace::analyses::arm3r::LoadOptions;
use linkspace::model::{urdf, JointKind, Mechanism};
use crate::util::SplitMix;
use linkspace::kernel::search::{Control, Limits};
use nalgebra::{Isometry3, Point3, Unit, UnitQuaternion, Vector3};
use std::sync::atomic::AtomicBool;

static NEVER: AtomicBool = AtomicBool::new(false);

fn control() -> Control<'static> {
    Control { limits: Limits::default(), threads: 1, cancel: &NEVER }
}

/// The analysed point's `det Df` in `f64`, from the parsed file (see the module doc).
struct Reference {
    mechanism: Mechanism,
    /// Joints from the root to the point's link.
    path: Vec<usize>,
    /// The point in that link's frame.
    point: Point3<f64>,
    /// The waypoints' joints, in order.
    joints: Vec<String>,
    /// The sub-chain's three joints.
    three: [String; 3],
}

impl Reference {
    fn of(file: &str, arm: &Arm) -> Self {
        let text = std::fs::read_to_string(format!("{}/{file}", env!("CARGO_MANIFEST_DIR"))).expect("fixture");
        let mechanism = urdf::parse(&text).expect("parses");
        let choice = &arm.prepared.choice;
        let link = mechanism.link(&choice.point_link).expect("the point's link is a link of the file");
        let path = mechanism.path_to(link);
        Reference { mechanism, path, point: Point3::from(choice.point), joints: app::positioning_joints(arm), three: choice.joints.clone() }
    }

    fn det(&self, q: &[f64]) -> f64 {
        let mut pose = Isometry3::identity();
        // (origin, direction) of each of the three axes, in the root frame.
        let mut axes: Vec<(Vector3<f64>, Vector3<f64>)> = Vec::new();
        for &j in &self.path {
            let joint = &self.mechanism.joints[j];
            pose *= joint.origin;
            if matches!(joint.kind, JointKind::Revolute { .. }) {
                let k = self.joints.iter().position(|n| *n == joint.name).expect("a joint of the waypoints");
                if self.three.contains(&joint.name) {
                    axes.push((pose.translation.vector, pose.rotation * joint.axis.normalize()));
                }
                pose *= UnitQuaternion::from_axis_angle(&Unit::new_normalize(joint.axis), q[k]);
            }
        }
        assert_eq!(axes.len(), 3);
        let p = (pose * self.point).coords;
        let (o1, w1) = axes[0];
        let rel = p - o1;
        let perp = rel - w1 * w1.dot(&rel);
        let column = |(o, w): (Vector3<f64>, Vector3<f64>)| {
            let dp = w.cross(&(p - o));
            // ρ' = 2 (p − o₁)⊥ · dp (the perpendicular part is orthogonal to ω₁); z' = ω₁ · dp.
            (2.0 * perp.dot(&dp), w1.dot(&dp))
        };
        let (r2, z2) = column(axes[1]);
        let (r3, z3) = column(axes[2]);
        r2 * z3 - r3 * z2
    }
}

fn lerp(x: &[f64], y: &[f64], t: f64) -> Vec<f64> {
    x.iter().zip(y).map(|(a, b)| a + t * (b - a)).collect()
}

fn load(file: &str) -> (Arm, Reference) {
    let text = std::fs::read_to_string(format!("{}/{file}", env!("CARGO_MANIFEST_DIR"))).expect("fixture");
    let m = urdf::parse(&text).expect("parses");
    // As written: the reference composes the file's own transforms.
    let options = LoadOptions { exact_geometry: true, ..LoadOptions::default() };
    let arm = Arm::load(&m, &options, 0.0).expect("an arm");
    let reference = Reference::of(file, &arm);
    (arm, reference)
}

const ARMS: [&str; 6] = [
    "urdf/orthogonal_3r_a.urdf",
    "urdf/orthogonal_3r_b.urdf",
    "urdf/orthogonal_3r_e.urdf",
    "urdf/orthogonal_3r_f.urdf",
    "urdf/ur5.urdf",
    "tests/data/fanuc_crx10ial_style.urdf",
];

/// The reference agrees with the library's map where both are far from zero (same sign), so
/// the two speak of one determinant.
#[test]
fn the_reference_is_the_library_det_df() {
    let mut rng = SplitMix(7);
    for file in ARMS {
        let (arm, reference) = load(file);
        let n = reference.joints.len();
        for _ in 0..50 {
            let q: Vec<f64> = (0..n).map(|_| rng.uniform(-3.0, 3.0)).collect();
            let want = reference.det(&q);
            let got = arm.chain.jets([linkspace::kernel::interval::point(q[1]), linkspace::kernel::interval::point(q[2])], 1).det().value();
            assert!(got.inf() - 1e-9 * (1.0 + want.abs()) <= want && want <= got.sup() + 1e-9 * (1.0 + want.abs()), "{file} at {q:?}: {want} vs {got:?}");
        }
    }
}

/// A segment of `reference` crossing `det Df = 0` once, transversally, at a known parameter:
/// (from, to, t*), or None when the random line found none fit for the test.
fn crossing_segment(reference: &Reference, rng: &mut SplitMix) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let n = reference.joints.len();
    let q: Vec<f64> = (0..n).map(|_| rng.uniform(-3.0, 3.0)).collect();
    let v: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
    let f = |s: f64| reference.det(&q.iter().zip(&v).map(|(a, b)| a + s * b).collect::<Vec<f64>>());
    // The first sign change along s ∈ [0, 2], then bisection to the last bit.
    let steps = 400;
    let (mut lo, mut hi) = (0..steps).map(|i| (2.0 * i as f64 / steps as f64, 2.0 * (i + 1) as f64 / steps as f64)).find(|&(a, b)| f(a) * f(b) < 0.0)?;
    let sign_lo = f(lo).signum();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if f(mid).signum() == sign_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let root = 0.5 * (lo + hi);
    let (before, after) = (rng.uniform(0.05, 0.3), rng.uniform(0.05, 0.3));
    let (a, b) = (root - before, root + after);
    let x: Vec<f64> = q.iter().zip(&v).map(|(q, v)| q + a * v).collect();
    let y: Vec<f64> = q.iter().zip(&v).map(|(q, v)| q + b * v).collect();
    let t_star = before / (before + after);
    // Transversal and alone: on dense samples, one sign change, and |det| grows away from the
    // root at least linearly (no second zero or tangency nearby).
    let samples = 2000;
    let g = |t: f64| reference.det(&lerp(&x, &y, t));
    let scale = (0..=samples).map(|i| g(i as f64 / samples as f64).abs()).fold(0.0, f64::max);
    let slope = (g(t_star + 1e-6) - g(t_star - 1e-6)).abs() / 2e-6;
    if !(slope > 1e-2 * scale) {
        return None;
    }
    let changes = (0..samples).filter(|&i| g(i as f64 / samples as f64) * g((i + 1) as f64 / samples as f64) <= 0.0).count();
    let far = (0..=samples).map(|i| i as f64 / samples as f64).filter(|t| (t - t_star).abs() > 0.02).all(|t| g(t).abs() > 0.25 * slope * (t - t_star).abs().min(0.05));
    (changes == 1 && far).then_some((x, y, t_star))
}

#[test]
fn segments_through_a_singular_point_cross_there() {
    let mut rng = SplitMix(2024);
    for file in ARMS {
        let (arm, reference) = load(file);
        let mut tried = 0;
        let mut checked = 0;
        while checked < 12 && tried < 400 {
            tried += 1;
            let Some((x, y, t_star)) = crossing_segment(&reference, &mut rng) else { continue };
            checked += 1;
            let found = app::check_path3(&arm, &[x.clone(), y.clone()], 1e-9, &control()).expect("checks");
            assert_eq!(found.set, PathSet::Positioning3R);
            let SegmentVerdict::Crosses { crossings, undecided } = &found.check.segments[0] else { panic!("{file} {x:?} -> {y:?} (t* = {t_star}): {:?}", found.check.segments[0]) };
            assert!(undecided.is_empty(), "{file}: {undecided:?}");
            assert_eq!(crossings.len(), 1, "{file}: {crossings:?}");
            let c = &crossings[0];
            let slack = 1e-12;
            assert!(c.narrowed && c.t[0] - slack <= t_star && t_star <= c.t[1] + slack, "{file}: t* = {t_star}, {c:?}");
            let at = lerp(&x, &y, t_star);
            for (k, (v, iv)) in at.iter().zip(&c.joints).enumerate() {
                assert!(iv[0] - slack <= *v && *v <= iv[1] + slack, "{file}: joint {k} = {v} outside {iv:?}");
                assert!(iv[1] - iv[0] <= 1e-9 + 1e-15, "{file}: joint {k} enclosure {iv:?} wider than the tolerance");
            }
            assert_eq!(c.sign_before, reference.det(&x).signum(), "{file}");
        }
        assert!(checked >= 8, "{file}: only {checked} crossing segments built in {tried} tries");
    }
}

#[test]
fn segments_away_from_the_singular_set_are_clear() {
    let mut rng = SplitMix(99);
    for file in ARMS {
        let (arm, reference) = load(file);
        let n = reference.joints.len();
        let (mut tried, mut checked) = (0, 0);
        while checked < 12 && tried < 400 {
            tried += 1;
            let x: Vec<f64> = (0..n).map(|_| rng.uniform(-3.0, 3.0)).collect();
            let y: Vec<f64> = x.iter().map(|v| v + rng.uniform(-0.5, 0.5)).collect();
            let samples = 4000;
            let h = 1.0 / samples as f64;
            let values: Vec<f64> = (0..=samples).map(|i| reference.det(&lerp(&x, &y, i as f64 * h))).collect();
            let least = values.iter().fold(f64::INFINITY, |m, d| m.min(d.abs()));
            // A Lipschitz constant of det along the segment, from the sampled differences with a
            // factor 4 of room: between samples, |det| stays above least − L·h/2.
            let lipschitz = 4.0 * values.windows(2).map(|w| (w[1] - w[0]).abs() / h).fold(0.0, f64::max);
            let same_sign = values.iter().all(|d| d.signum() == values[0].signum());
            if !(same_sign && least > lipschitz * h && least > 1e-3 * values.iter().fold(0.0f64, |m, d| m.max(d.abs()))) {
                continue;
            }
            checked += 1;
            let found = app::check_path3(&arm, &[x.clone(), y.clone()], 1e-9, &control()).expect("checks");
            let SegmentVerdict::Clear { sign, min_abs_det, .. } = found.check.segments[0] else { panic!("{file} {x:?} -> {y:?}: {:?}", found.check.segments[0]) };
            assert_eq!(sign, values[0].signum(), "{file}");
            assert!(min_abs_det > 0.0 && min_abs_det <= least, "{file}: bound {min_abs_det} above the sampled {least}");
            assert!(min_abs_det >= 0.05 * least, "{file}: bound {min_abs_det} far below the sampled {least}");
        }
        assert!(checked >= 8, "{file}: only {checked} clear segments built in {tried} tries");
    }
}

/// The report names the set: the sub-chain and point with det Df, the waypoints over the arm's
/// joints; joint 1 and the wrist joints do not move det Df.
#[test]
fn the_report_names_the_sub_chain_and_its_point() {
    let (arm, reference) = load("urdf/ur5.urdf");
    assert_eq!(reference.joints, ["joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"]);
    // Only joints 1 and 4-6 move: det Df is constant along the segment.
    let (x, y) = (vec![0.3, -1.0, 1.2, -0.5, -0.4, 0.7], vec![2.3, -1.0, 1.2, 1.5, 2.4, -2.7]);
    let found = app::check_path3(&arm, &[x.clone(), y.clone()], 1e-9, &control()).expect("checks");
    assert!(matches!(found.check.segments[0], SegmentVerdict::Clear { pieces: 1, .. }), "{:?}", found.check.segments[0]);
    let report = linkspace::edges::report::six::PathCheckReport::of(&found);
    assert_eq!(report.singular_set, "3r");
    assert!(report.subject.starts_with("3R sub-chain joints 1-3 (joint_1, joint_2, joint_3) of 'ur5', point link_3@") && report.subject.ends_with(": det Df"), "{}", report.subject);
    assert!(report.headline().starts_with(&report.subject), "{}", report.headline());
    assert!(report.segments[0].reason.starts_with("det Df proven"), "{}", report.segments[0].reason);
    // Waypoints of another length are refused in one line.
    let err = app::check_path3(&arm, &[x, vec![0.0; 5]], 1e-9, &control()).expect_err("refused");
    assert_eq!(err.to_string(), "bad path: waypoint 2 is not six finite numbers");
}

//! The one rounding policy: orientations written with a truncated π/2 are snapped to exact.
//!
//! Vendor URDFs write quarter turns as `1.5707963267948966`, `1.570796`, `1.5708` or
//! `3.14159`. Taken literally these are tiny twists (up to 3.7e-6 rad) that turn a robot with
//! parallel or orthogonal axes into a near-degenerate one: internal-motion lines become thin
//! tubes no finite search can decide, and real nodes split. The designer meant the quarter turn.
//!
//! Policy (applied once to a `Mechanism`, before any analysis, with a tolerance: by default
//! [`ANGLE_TOLERANCE`], at most [`LARGEST_TOLERANCE`]; 0 takes every value as written):
//! - every roll, pitch or yaw within the tolerance of a multiple of π/2 becomes that
//!   multiple; when all three of a joint's angles are quarter turns, the joint gets its exact
//!   rotation matrix (entries −1, 0, 1; `Joint::exact_rotation`), since the quaternion of a
//!   quarter turn cannot be stored exactly;
//! - every revolute or prismatic axis within the tolerance (as an angle) of a coordinate
//!   axis of its joint frame becomes that coordinate axis. With exact quarter-turn frames this
//!   makes axes that were within the tolerance of parallel or orthogonal exactly so.
//!
//! Every change is listed as a [`Snap`] (joint, what, original, snapped); a value that is
//! already exact is not listed. Loop closures (`<loop>`) are left as written: the planar
//! builders enclose the stated decimals themselves. `--exact-geometry` skips this module.

use super::{Joint, JointKind, Mechanism};
use nalgebra::{UnitQuaternion, Vector3};
use std::f64::consts::FRAC_PI_2;

/// Angles (radians) within this of a quarter-turn multiple are snapped. 1e-5 covers every
/// common truncation (`1.5708` is 3.7e-6 off, `3.14159` 2.7e-6) and is far below any twist a
/// designer means (the smallest machined offsets are degrees). The default tolerance.
pub const ANGLE_TOLERANCE: f64 = 1e-5;

/// The largest tolerance accepted: 0.01 rad (0.57°) stays below the smallest twist a designer
/// means, and covers quarter turns written with three decimals (`1.571` is 2.0e-4 off).
pub const LARGEST_TOLERANCE: f64 = 1e-2;

/// Whether `tolerance` (radians) is one the policy takes: finite, in [0, [`LARGEST_TOLERANCE`]].
pub fn valid_tolerance(tolerance: f64) -> bool {
    (0.0..=LARGEST_TOLERANCE).contains(&tolerance)
}

/// One value the policy changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Snap {
    /// The joint's name.
    pub joint: String,
    /// `"rpy"`, `"axis"` or `"lock"` (a `--lock` value, in `original[0]` and `snapped[0]`).
    pub what: String,
    /// As written in the file.
    pub original: [f64; 3],
    /// As analysed.
    pub snapped: [f64; 3],
}

/// The nearest multiple of π/2 when within `tolerance`: `(k mod 4, k·π/2)`.
fn quarter(x: f64, tolerance: f64) -> Option<(i64, f64)> {
    let k = (x / FRAC_PI_2).round();
    // k·FRAC_PI_2 is the f64 nearest to k·π/2 for |k| ≤ 4 (checked in a test), and the
    // matrix built from k mod 4 is exact whatever the f64 says.
    ((x - k * FRAC_PI_2).abs() <= tolerance).then(|| ((k as i64).rem_euclid(4), k * FRAC_PI_2))
}

/// cos and sin of k quarter turns, exactly.
fn cs(k: i64) -> (f64, f64) {
    match k {
        0 => (1.0, 0.0),
        1 => (0.0, 1.0),
        2 => (-1.0, 0.0),
        _ => (0.0, -1.0),
    }
}

fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    // Entries are −1, 0, 1 with one non-zero per row: every sum is exact.
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j]))
}

/// URDF's fixed-axis roll–pitch–yaw, `Rz(yaw)·Ry(pitch)·Rx(roll)`, for quarter turns.
fn exact_rpy(k: [i64; 3]) -> [[f64; 3]; 3] {
    let (cr, sr) = cs(k[0]);
    let (cp, sp) = cs(k[1]);
    let (cy, sy) = cs(k[2]);
    let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
    let ry = [[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]];
    let rz = [[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]];
    mul(&rz, &mul(&ry, &rx))
}

/// A joint value (a lock) within `tolerance` of a quarter-turn multiple, snapped to it as the
/// file's angles are; `None` when it is not near one or already exact.
pub fn snap_value(v: f64, tolerance: f64) -> Option<f64> {
    quarter(v, tolerance).map(|(_, q)| q).filter(|&q| q != v)
}

/// The exact rotation by `v` about `axis` when `v` is a quarter-turn multiple (as the f64
/// `k·π/2`) and `axis` a unit coordinate axis; `None` otherwise.
pub fn exact_turn(axis: &Vector3<f64>, v: f64) -> Option<[[f64; 3]; 3]> {
    // Only a value that is exactly the stored quarter turn (checked below) qualifies.
    let (k, q) = quarter(v, 0.0)?;
    let i = (0..3).find(|&i| axis[i].abs() == 1.0)?;
    if q != v || axis.norm_squared() != 1.0 {
        return None;
    }
    // About −e the turn is −k quarter turns about e.
    let k = if axis[i] < 0.0 { (-k).rem_euclid(4) } else { k };
    let mut turns = [0; 3];
    turns[i] = k;
    Some(exact_rpy(turns))
}

/// The product of two exact rotations (entries −1, 0, 1), exactly.
pub fn compose(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    mul(a, b)
}

/// The coordinate axis nearest in angle to `a`, and the sine of the angle (|component across it|).
fn nearest_axis(a: &Vector3<f64>) -> (usize, f64) {
    let i = (0..3).max_by(|&x, &y| a[x].abs().total_cmp(&a[y].abs())).expect("three components");
    (i, (a.norm_squared() - a[i] * a[i]).max(0.0).sqrt())
}

/// How far each of `joint`'s values lies from what the policy would make it (0 when exact):
/// each roll, pitch and yaw from its nearest quarter turn, a revolute or prismatic axis (as the
/// sine of the angle) from its nearest coordinate axis. The tolerance that snaps a value is at
/// least its offset.
pub fn offsets(joint: &Joint) -> Vec<f64> {
    let mut out: Vec<f64> = joint.rpy.iter().map(|&x| (x - (x / FRAC_PI_2).round() * FRAC_PI_2).abs()).collect();
    if matches!(joint.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }) {
        out.push(nearest_axis(&joint.axis).1);
    }
    out
}

/// The mechanism with the policy applied at `tolerance` (radians), and the list of what changed.
pub fn snap(m: &Mechanism, tolerance: f64) -> (Mechanism, Vec<Snap>) {
    let mut out = m.clone();
    let mut snaps = Vec::new();
    for j in &mut out.joints {
        let q = j.rpy.map(|x| quarter(x, tolerance));
        let snapped = [0, 1, 2].map(|i| q[i].map_or(j.rpy[i], |(_, v)| v));
        if snapped != j.rpy {
            snaps.push(Snap { joint: j.name.clone(), what: "rpy".into(), original: j.rpy, snapped });
            j.rpy = snapped;
            j.origin.rotation = UnitQuaternion::from_euler_angles(snapped[0], snapped[1], snapped[2]);
        }
        if let [Some((a, _)), Some((b, _)), Some((c, _))] = q {
            j.exact_rotation = Some(exact_rpy([a, b, c]));
        }
        if matches!(j.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }) {
            let a = j.axis;
            let (i, across) = nearest_axis(&a);
            if across <= tolerance && across > 0.0 {
                let mut e = Vector3::zeros();
                e[i] = a[i].signum();
                snaps.push(Snap { joint: j.name.clone(), what: "axis".into(), original: [a[0], a[1], a[2]], snapped: [e[0], e[1], e[2]] });
                j.axis = e;
            }
        }
    }
    (out, snaps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turn_multiples_are_the_nearest_f64() {
        // The f64 stored for k·π/2 is what `1.5707963267948966` etc. parse to.
        for k in -4..=4 {
            let v = k as f64 * FRAC_PI_2;
            assert_eq!(quarter(v, ANGLE_TOLERANCE).map(|x| x.1), Some(v));
        }
        assert_eq!("1.5707963267948966".parse::<f64>().ok(), Some(FRAC_PI_2));
    }

    #[test]
    fn truncated_quarter_turns_snap_and_others_do_not() {
        for text in ["1.5708", "1.570796", "1.5707963267948966", "3.14159", "-1.5708", "0"] {
            assert!(quarter(text.parse().expect("number"), ANGLE_TOLERANCE).is_some(), "{text}");
        }
        for text in ["1.57", "0.001", "1.5709", "3.1415"] {
            assert!(quarter(text.parse().expect("number"), ANGLE_TOLERANCE).is_none(), "{text}");
        }
    }

    #[test]
    fn exact_rotation_matches_nalgebra_to_rounding() {
        for a in 0..4 {
            for b in 0..4 {
                for c in 0..4 {
                    let e = exact_rpy([a, b, c]);
                    let m = UnitQuaternion::from_euler_angles(a as f64 * FRAC_PI_2, b as f64 * FRAC_PI_2, c as f64 * FRAC_PI_2).to_rotation_matrix();
                    for i in 0..3 {
                        for j in 0..3 {
                            assert!((e[i][j] - m[(i, j)]).abs() < 1e-12, "{a} {b} {c}: {e:?} vs {m}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    #[allow(clippy::approx_constant)] // 1.5708 is the file's rounded value that gets snapped
    fn snaps_are_listed_with_original_and_snapped_values() {
        let xml = "<robot name='r'><link name='a'/><link name='b'/>\
            <joint name='j' type='revolute'><parent link='a'/><child link='b'/><origin rpy='1.5708 0 0'/><axis xyz='0 0.000001 1'/>\
            <limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>";
        let m = super::super::urdf::parse(xml).expect("parses");
        let (s, snaps) = snap(&m, ANGLE_TOLERANCE);
        assert_eq!(snaps.len(), 2, "{snaps:?}");
        assert_eq!(snaps[0].original[0], 1.5708);
        assert_eq!(snaps[0].snapped[0], FRAC_PI_2);
        assert_eq!(s.joints[0].axis, Vector3::z());
        assert_eq!(s.joints[0].exact_rotation, Some([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]));
    }

    #[test]
    #[allow(clippy::approx_constant)] // truncated quarter turns as files write them, not π/2
    fn the_tolerance_decides_what_snaps() {
        // `1.571` is 2.04e-4 rad off a quarter turn: kept at the default, snapped at 3e-4.
        assert_eq!(quarter(1.571, ANGLE_TOLERANCE), None);
        assert_eq!(quarter(1.571, 3e-4), Some((1, FRAC_PI_2)));
        assert_eq!(snap_value(1.571, 3e-4), Some(FRAC_PI_2));
        // 0 takes every value as written (an exact quarter turn is already what it is).
        assert_eq!(snap_value(1.5708, 0.0), None);
        assert!(valid_tolerance(0.0) && valid_tolerance(LARGEST_TOLERANCE) && valid_tolerance(3e-4));
        assert!(!valid_tolerance(-1e-5) && !valid_tolerance(0.5) && !valid_tolerance(f64::NAN));
        // The offsets say which tolerance would snap a joint's values.
        let xml = "<robot name='r'><link name='a'/><link name='b'/>\
            <joint name='j' type='revolute'><parent link='a'/><child link='b'/><origin rpy='1.571 0 0'/><axis xyz='0 0 1'/>\
            <limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>";
        let m = super::super::urdf::parse(xml).expect("parses");
        let off = offsets(&m.joints[0]);
        assert_eq!(off.len(), 4);
        assert!((off[0] - (1.571 - FRAC_PI_2)).abs() < 1e-15 && off[1..] == [0.0; 3], "{off:?}");
    }

    #[test]
    #[allow(clippy::approx_constant)] // the truncated values a user types, not π
    fn joint_values_snap_and_turn_exactly() {
        assert_eq!(snap_value(3.14159, ANGLE_TOLERANCE), Some(std::f64::consts::PI));
        assert_eq!(snap_value(std::f64::consts::PI, ANGLE_TOLERANCE), None, "already exact");
        assert_eq!(snap_value(0.5, ANGLE_TOLERANCE), None);
        assert_eq!(exact_turn(&Vector3::z(), FRAC_PI_2), Some([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]));
        assert_eq!(exact_turn(&-Vector3::z(), FRAC_PI_2), Some([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]));
        assert_eq!(exact_turn(&Vector3::z(), 1.5708), None, "not a stored quarter turn");
        assert_eq!(exact_turn(&Vector3::new(0.6, 0.8, 0.0), FRAC_PI_2), None);
    }
}

//! The three ways a tip pose is written, told apart by how many numbers they take:
//! 6 `x, y, z, roll, pitch, yaw` (URDF convention), 7 `x, y, z, qx, qy, qz, qw` (a quaternion,
//! normalised here), 16 a 4×4 homogeneous transform, row-major.
//!
//! Each becomes a `PoseTarget` whose entries enclose the exact rigid transform its decimals
//! imply: the rpy rotation of the stated angles; the rotation of the stated quaternion divided
//! by its squared norm (every nonzero quaternion gives an exact rotation, so no normalisation
//! in floating point is trusted); for a matrix, the rotation nearest to the stated one (its
//! polar factor), within the stated entries widened by a bound on their distance to it.

// Matrix indices read as the formulas they implement.
#![allow(clippy::needless_range_loop)]

use super::ik::PoseTarget;
use super::Manip6rError;
use crate::kernel::interval::{interval, point, Interval};
use crate::analyses::arm6r::chain::IAffine;
use crate::formulate::angles::stated;

/// Largest departure from a rigid transform accepted in a 4×4 matrix: the Frobenius norm of
/// `RᵀR − I` and each entry of the last row against `0, 0, 0, 1`. Decimals printed to 7 digits
/// pass; the solutions are then certified for every pose within that distance entry-wise.
pub const RIGID_TOLERANCE: f64 = 1e-6;

/// A tip pose as the user wrote it (base frame; metres, radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PoseInput {
    /// `x, y, z, roll, pitch, yaw`.
    XyzRpy([f64; 6]),
    /// `x, y, z, qx, qy, qz, qw`, any nonzero norm.
    XyzQuaternion([f64; 7]),
    /// A 4×4 homogeneous transform, row-major.
    Matrix([f64; 16]),
}

impl PoseInput {
    /// The form the count of `v` names: 6, 7 or 16 numbers.
    pub fn from_numbers(v: &[f64]) -> Result<PoseInput, Manip6rError> {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(Manip6rError::BadPose(format!("{x} is not a finite number")));
        }
        Ok(match v.len() {
            6 => PoseInput::XyzRpy(v.try_into().expect("invariant: six numbers")),
            7 => PoseInput::XyzQuaternion(v.try_into().expect("invariant: seven numbers")),
            16 => PoseInput::Matrix(v.try_into().expect("invariant: sixteen numbers")),
            n => return Err(Manip6rError::BadPose(format!("{n} numbers: expected 6 (x,y,z,roll,pitch,yaw), 7 (x,y,z,qx,qy,qz,qw) or 16 (a 4x4 matrix, row-major)"))),
        })
    }

    /// The numbers as given.
    pub fn numbers(&self) -> &[f64] {
        match self {
            PoseInput::XyzRpy(v) => v,
            PoseInput::XyzQuaternion(v) => v,
            PoseInput::Matrix(v) => v,
        }
    }

    /// The form's name in reports: `xyz_rpy`, `xyz_quaternion`, `matrix`.
    pub fn form(&self) -> &'static str {
        match self {
            PoseInput::XyzRpy(_) => "xyz_rpy",
            PoseInput::XyzQuaternion(_) => "xyz_quaternion",
            PoseInput::Matrix(_) => "matrix",
        }
    }

    /// The enclosure solved for (module doc), or why the numbers are no rigid pose.
    pub fn target(&self) -> Result<PoseTarget, Manip6rError> {
        if let Some(x) = self.numbers().iter().find(|x| !x.is_finite()) {
            return Err(Manip6rError::BadPose(format!("{x} is not a finite number")));
        }
        match self {
            PoseInput::XyzRpy(v) => PoseTarget::stated(*v),
            PoseInput::XyzQuaternion(v) => Ok(PoseTarget(IAffine { r: quaternion_rotation([v[3], v[4], v[5], v[6]])?, t: [stated(v[0]), stated(v[1]), stated(v[2])] })),
            PoseInput::Matrix(v) => matrix_target(v),
        }
    }
}

/// The rotation of `q = (x, y, z, w)` over its squared norm, which is exact for any nonzero q.
fn quaternion_rotation(q: [f64; 4]) -> Result<[[Interval; 3]; 3], Manip6rError> {
    let [x, y, z, w] = q.map(stated);
    let n2 = x.sqr() + y.sqr() + z.sqr() + w.sqr();
    if n2.inf() <= 0.0 {
        return Err(Manip6rError::BadPose("the quaternion is zero (or too small to normalise): it names no rotation".into()));
    }
    let two = point(2.0);
    let r = [
        [w.sqr() + x.sqr() - y.sqr() - z.sqr(), two * (x * y - w * z), two * (x * z + w * y)],
        [two * (x * y + w * z), w.sqr() - x.sqr() + y.sqr() - z.sqr(), two * (y * z - w * x)],
        [two * (x * z - w * y), two * (y * z + w * x), w.sqr() - x.sqr() - y.sqr() + z.sqr()],
    ];
    Ok(r.map(|row| row.map(|e| e / n2)))
}

/// The enclosure of a stated 4×4 transform's rigid part, or its defect named with its size.
///
/// With `M` the stated rotation block and `R` its polar factor (the nearest rotation when
/// `det M > 0`), `|Mᵢⱼ − Rᵢⱼ| ≤ ‖M − R‖₂ = maxᵢ |σᵢ − 1| ≤ maxᵢ |σᵢ² − 1| = ‖MᵀM − I‖₂ ≤ ‖MᵀM − I‖_F`,
/// so widening the stated entries by an outward bound `e` of the last norm encloses `R`.
fn matrix_target(v: &[f64; 16]) -> Result<PoseTarget, Manip6rError> {
    let last = [v[12], v[13], v[14], v[15] - 1.0];
    let off = last.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if off > RIGID_TOLERANCE {
        return Err(Manip6rError::NotRigid(format!(
            "the last row must be 0,0,0,1, got {},{},{},{} (off by {off:.3e}; at most {RIGID_TOLERANCE:e} accepted)",
            v[12], v[13], v[14], v[15]
        )));
    }
    let m: [[Interval; 3]; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|j| stated(v[4 * i + j])));
    let mut frobenius2 = point(0.0);
    for i in 0..3 {
        for j in 0..3 {
            let g = m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j] - point(if i == j { 1.0 } else { 0.0 });
            frobenius2 += g.sqr();
        }
    }
    let e = frobenius2.sqrt().sup();
    if !(e <= RIGID_TOLERANCE) {
        return Err(Manip6rError::NotRigid(format!(
            "the rotation block is not orthonormal: |RᵀR − I| (Frobenius) is {e:.3e}; at most {RIGID_TOLERANCE:e} accepted"
        )));
    }
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if det.sup() < 0.0 {
        return Err(Manip6rError::NotRigid(format!("the rotation block is a reflection: its determinant is {:.6}", det.mid())));
    }
    let widen = interval(-e, e);
    let r = m.map(|row| row.map(|x| x + widen));
    Ok(PoseTarget(IAffine { r, t: [stated(v[3]), stated(v[7]), stated(v[11])] }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn holds(t: &PoseTarget, r: &[[f64; 3]; 3], p: [f64; 3]) -> bool {
        (0..3).all(|i| (0..3).all(|j| t.0.r[i][j].contains(r[i][j])) && t.0.t[i].contains(p[i]))
    }

    #[test]
    fn the_count_names_the_form() {
        assert!(matches!(PoseInput::from_numbers(&[0.0; 6]), Ok(PoseInput::XyzRpy(_))));
        assert!(matches!(PoseInput::from_numbers(&[0.0; 7]), Ok(PoseInput::XyzQuaternion(_))));
        assert!(matches!(PoseInput::from_numbers(&[0.0; 16]), Ok(PoseInput::Matrix(_))));
        let e = PoseInput::from_numbers(&[0.0; 9]).unwrap_err().to_string();
        assert!(e.contains("9 numbers") && e.contains("16"), "{e}");
        assert!(PoseInput::from_numbers(&[f64::NAN; 6]).is_err());
    }

    #[test]
    fn a_quaternion_encloses_its_rotation_unnormalised() {
        // A half turn about z scaled by 3: (0, 0, 3, 0) is Rz(π).
        let t = PoseInput::XyzQuaternion([0.1, 0.2, 0.3, 0.0, 0.0, 3.0, 0.0]).target().expect("rigid");
        assert!(holds(&t, &[[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]], [0.1, 0.2, 0.3]));
        // A quarter turn about x: (sin π/4, 0, 0, cos π/4), against the rpy enclosure of (π/2, 0, 0).
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let t = PoseInput::XyzQuaternion([0.0, 0.0, 0.0, h, 0.0, 0.0, h]).target().expect("rigid");
        let rpy = crate::formulate::stated::rpy([std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        for i in 0..3 {
            for j in 0..3 {
                assert!(!t.0.r[i][j].disjoint(rpy[i][j]), "{i}{j}");
                assert!(t.0.r[i][j].wid() < 1e-14);
            }
        }
        let e = PoseInput::XyzQuaternion([0.0; 7]).target().unwrap_err().to_string();
        assert!(e.contains("zero"), "{e}");
    }

    #[test]
    fn a_matrix_is_rigid_or_named_defective() {
        let (s, c) = 0.3f64.sin_cos();
        let r = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let m = [c, -s, 0.0, 1.0, s, c, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 1.0];
        let t = PoseInput::Matrix(m).target().expect("rigid");
        assert!(holds(&t, &r, [1.0, 2.0, 3.0]));
        // Seven decimals: accepted, and the nearest rotation enclosed.
        let rounded = m.map(|x| (x * 1e7).round() / 1e7);
        let t = PoseInput::Matrix(rounded).target().expect("within tolerance");
        assert!(holds(&t, &r, [1.0, 2.0, 3.0]));
        let mut scaled = m;
        scaled[0] *= 1.01;
        let e = PoseInput::Matrix(scaled).target().unwrap_err().to_string();
        assert!(e.contains("orthonormal") && e.contains("1.877e-2"), "{e}");
        let mut reflected = m;
        reflected[10] = -1.0;
        let e = PoseInput::Matrix(reflected).target().unwrap_err().to_string();
        assert!(e.contains("reflection"), "{e}");
        let mut projective = m;
        projective[14] = 0.5;
        let e = PoseInput::Matrix(projective).target().unwrap_err().to_string();
        assert!(e.contains("last row") && e.contains("5.000e-1"), "{e}");
    }
}

//! The stated model in interval arithmetic: rotations, translations and axes that enclose the
//! exact values of the decimals written in a file.
//!
//! A parsed decimal is the nearest `f64` to it, so `angles::stated` (one ulp each way) encloses
//! it; rotations are then products of elementary rotations whose sines and cosines come from the
//! sound `interval::trig`, in outward-rounded inari arithmetic. Axes arrive normalised in `f64`
//! (a sum of squares, a square root and a division: under 3 ulps per component, plus half an ulp
//! for the parse); they are enclosed by 8 ulps relative, and components that are exactly 0 or ±1
//! stay exact, so axis-aligned models keep point coefficients.

use super::angles::{cos_sin, stated};
use crate::kernel::interval::{interval, point, Interval};
use nalgebra::{Rotation3, Vector3};

/// A 3-vector of intervals.
pub(crate) type IVec3 = [Interval; 3];
/// A 3×3 matrix of intervals, row-major.
pub(crate) type IMat3 = [[Interval; 3]; 3];

/// The identity, exact.
pub(crate) fn identity() -> IMat3 {
    let (o, z) = (point(1.0), point(0.0));
    [[o, z, z], [z, o, z], [z, z, o]]
}

/// `a·b`.
pub(crate) fn mul(a: &IMat3, b: &IMat3) -> IMat3 {
    let mut out = [[point(0.0); 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
        }
    }
    out
}

/// `a·v`.
pub(crate) fn apply(a: &IMat3, v: &IVec3) -> IVec3 {
    [0, 1, 2].map(|r| a[r][0] * v[0] + a[r][1] * v[1] + a[r][2] * v[2])
}

/// `aᵀ·v`.
pub(crate) fn apply_transposed(a: &IMat3, v: &IVec3) -> IVec3 {
    [0, 1, 2].map(|c| a[0][c] * v[0] + a[1][c] * v[1] + a[2][c] * v[2])
}

/// The rotation about the unit `axis` by every angle in `theta` (Rodrigues:
/// `a aᵀ + cos θ (I − a aᵀ) + sin θ [a]×`), enclosing the exact one for every axis in `axis`:
/// for a stated angle (`angles::stated`) the file's, for a range each entry over all of it (a
/// joint held over an interval).
pub(crate) fn about_axis_over(axis: &IVec3, theta: Interval) -> IMat3 {
    let (c, s) = cos_sin(theta);
    let a = axis;
    let cross = [[point(0.0), -a[2], a[1]], [a[2], point(0.0), -a[0]], [-a[1], a[0], point(0.0)]];
    let mut r = [[point(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = point(if i == j { 1.0 } else { 0.0 });
            r[i][j] = a[i] * a[j] + c * (id - a[i] * a[j]) + s * cross[i][j];
        }
    }
    r
}

/// The URDF rotation `Rz(yaw)·Ry(pitch)·Rx(roll)` of the stated angles.
pub(crate) fn rpy(rpy: [f64; 3]) -> IMat3 {
    let (cr, sr) = cos_sin(stated(rpy[0]));
    let (cp, sp) = cos_sin(stated(rpy[1]));
    let (cy, sy) = cos_sin(stated(rpy[2]));
    let z = point(0.0);
    let o = point(1.0);
    let rx = [[o, z, z], [z, cr, -sr], [z, sr, cr]];
    let ry = [[cp, z, sp], [z, o, z], [-sp, z, cp]];
    let rz = [[cy, -sy, z], [sy, cy, z], [z, z, o]];
    mul(&rz, &mul(&ry, &rx))
}

/// The stated translation.
pub(crate) fn translation(v: &Vector3<f64>) -> IVec3 {
    [stated(v.x), stated(v.y), stated(v.z)]
}

/// An enclosure of the stated unit axis from its `f64` normalisation.
pub(crate) fn axis(v: &Vector3<f64>) -> IVec3 {
    let c = |x: f64| {
        if x == 0.0 || x.abs() == 1.0 {
            point(x)
        } else {
            let e = 8.0 * f64::EPSILON * x.abs();
            interval(x - e, x + e)
        }
    };
    [c(v.x), c(v.y), c(v.z)]
}

/// The plane basis (e1, e2, normal) as columns: exact for the plane z = 0, else the `f64`
/// rotation taking z to the normal, widened by 4·2⁻⁵² per entry (nalgebra's construction is
/// within a few ulps of an exact rotation, which the widened matrix then holds).
pub(crate) fn basis(r: &Rotation3<f64>) -> IMat3 {
    let m = r.matrix();
    if *r == Rotation3::identity() {
        return identity();
    }
    let e = 4.0 * f64::EPSILON;
    let mut out = identity();
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = interval(m[(i, j)] - e, m[(i, j)] + e);
        }
    }
    out
}

/// The frame of `link` in the frame of its ancestor `from` (the root, or a link on its path)
/// through the joints between them, each at its origin (its stated rotation and translation):
/// the placement of a link held to `from` by fixed joints.
pub(crate) fn placement(m: &crate::model::Mechanism, from: usize, link: usize) -> (IMat3, IVec3) {
    let above = if from == m.root { 0 } else { m.path_to(from).len() };
    let (mut r, mut p) = (identity(), [point(0.0); 3]);
    for j in m.path_to(link).into_iter().skip(above) {
        let joint = &m.joints[j];
        let rot = match joint.exact_rotation {
            Some(e) => e.map(|row| row.map(point)),
            None => rpy(joint.rpy),
        };
        let step = apply(&r, &translation(&joint.origin.translation.vector));
        p = [0, 1, 2].map(|i| p[i] + step[i]);
        r = mul(&r, &rot);
    }
    (r, p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    #[test]
    fn rpy_encloses_nalgebra_and_keeps_zero_exact() {
        assert_eq!(rpy([0.0; 3]), identity());
        let (r, p, y) = (0.3, -1.2, 2.5);
        let m = rpy([r, p, y]);
        let q = UnitQuaternion::from_euler_angles(r, p, y).to_rotation_matrix();
        for i in 0..3 {
            for j in 0..3 {
                let d = m[i][j];
                assert!(d.inf() - 1e-15 <= q[(i, j)] && q[(i, j)] <= d.sup() + 1e-15 && d.wid() < 1e-13, "{i}{j} {d:?}");
            }
        }
    }
}

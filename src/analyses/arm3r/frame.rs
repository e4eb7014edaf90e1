//! Where a 3R chain sits in its robot's root frame: a point of the root frame as the
//! half-section coordinates (ρ, z) the searches take, and the first joint's angle that turns the
//! chain onto the point.
//!
//! The searches work over (θ₂, θ₃) in the first joint's frame: ρ is the squared distance of the
//! end point from the first axis, z its height along it. A point given in the root frame is
//! carried there in interval arithmetic (its coordinates then are enclosures, not numbers), and
//! θ₁ is the angle, about the first axis, between the end point's direction and the point's.

use super::Chain3R;
use crate::kernel::interval::{interval, point};
use crate::model::Mechanism;
use inari::Interval;

type V3 = [Interval; 3];

fn dot(a: &V3, b: &V3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The first joint's frame in the root link's, and a basis of the plane normal to the first
/// axis in which θ₁ is measured.
#[derive(Clone, Debug)]
pub struct BaseFrame {
    /// The first joint's frame in the root link's: rotation (rows) and translation.
    rotation: [V3; 3],
    translation: V3,
    /// The first axis in the first joint's frame, and two unit vectors completing a
    /// right-handed basis (`e1 × e2 = axis`).
    axis: V3,
    e1: V3,
    e2: V3,
}

/// A point of the root frame as the searches see it.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    /// Enclosures of (ρ, z) of the point in the first joint's frame.
    pub half_section: [Interval; 2],
    /// Direction of the point about the first axis (`None` on the axis: θ₁ is free).
    pub direction: Option<Interval>,
}

impl BaseFrame {
    /// The frame of `chain`'s first joint in `mechanism`, the reduced serial mechanism the chain
    /// was built from (`arm3r::prepare`).
    pub fn of(mechanism: &Mechanism, chain: &Chain3R) -> Self {
        let first = mechanism.joint(&chain.joints[0]).expect("invariant: the chain names its joints");
        // Compose the joint origins from the root down to the first revolute joint, in interval
        // arithmetic (as `Chain3R` does for the rest of the chain).
        let mut r: [V3; 3] = [[point(1.0), point(0.0), point(0.0)], [point(0.0), point(1.0), point(0.0)], [point(0.0), point(0.0), point(1.0)]];
        let mut t: V3 = [point(0.0); 3];
        for j in mechanism.path_to(mechanism.joints[first].child) {
            let iso = &mechanism.joints[j].origin;
            let m = mechanism.joints[j].rotation_matrix();
            let o: [V3; 3] = [0, 1, 2].map(|i| [0, 1, 2].map(|k| point(m[i][k])));
            let v = iso.translation.vector;
            let ov: V3 = [point(v[0]), point(v[1]), point(v[2])];
            // (r, t) ∘ (o, ov) = (r·o, r·ov + t)
            let rows = r;
            r = [0, 1, 2].map(|i| [0, 1, 2].map(|k| rows[i][0] * o[0][k] + rows[i][1] * o[1][k] + rows[i][2] * o[2][k]));
            t = [0, 1, 2].map(|i| dot(&rows[i], &ov) + t[i]);
        }
        let a = mechanism.joints[first].axis;
        let axis = [point(a[0]), point(a[1]), point(a[2])];
        // e1: the unit vector of the coordinate axis least aligned with a₁, made perpendicular.
        // It need not be exact: θ₁ is measured from it, and the same e1 serves the point and
        // the end point.
        let k = (0..3).min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs())).expect("three axes");
        let mut u = [0.0; 3];
        u[k] = 1.0;
        let d = a[k];
        let mut e1 = [u[0] - d * a[0], u[1] - d * a[1], u[2] - d * a[2]];
        let n = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
        e1 = e1.map(|x| x / n);
        let e2 = [a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2], a[0] * e1[1] - a[1] * e1[0]];
        Self { rotation: r, translation: t, axis, e1: e1.map(point), e2: e2.map(point) }
    }

    /// The point `p` (root frame) in the first joint's frame: `Rᵀ(p − t)`, the rotation taken
    /// as exact (as every URDF rotation is in this crate).
    fn to_first_joint(&self, p: [f64; 3]) -> V3 {
        let d: V3 = [0, 1, 2].map(|i| point(p[i]) - self.translation[i]);
        let r = &self.rotation;
        [0, 1, 2].map(|k| r[0][k] * d[0] + r[1][k] * d[1] + r[2][k] * d[2])
    }

    /// Direction about the first axis of a vector perpendicular to it (radians), or `None` when
    /// it may vanish or its enclosure spans half a turn or more.
    fn direction(&self, v: &V3) -> Option<Interval> {
        crate::kernel::interval::angle::arg(dot(v, &self.e1), dot(v, &self.e2)).filter(|a| a.wid() < 3.0)
    }

    /// The point `p` of the root frame (metres) as the searches take it.
    pub fn target(&self, p: [f64; 3]) -> Target {
        let local = self.to_first_joint(p);
        let z = dot(&local, &self.axis);
        let perp: V3 = [0, 1, 2].map(|i| local[i] - z * self.axis[i]);
        let rho = dot(&perp, &perp).intersection(interval(0.0, f64::INFINITY));
        Target { half_section: [rho, z], direction: self.direction(&perp) }
    }

    /// The first joint's angle that turns the end point at (θ₂, θ₃) ∈ `b` onto the direction of
    /// `target`: an enclosure in about [−π, π], or the whole turn when the point or the end
    /// point may lie on the first axis.
    pub fn theta1(&self, chain: &Chain3R, target: &Target, b: &[Interval; 2]) -> Interval {
        match (target.direction, self.direction(&chain.perp(*b))) {
            (Some(t), Some(u)) => crate::kernel::interval::angle::wrap(t - u),
            _ => super::motion::full_range(),
        }
    }
}

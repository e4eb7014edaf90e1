//! A theorem for the UR family: six-revolute arms whose axes 2, 3, 4 are parallel, with
//! axis 5 perpendicular to them and axis 6 meeting axis 5 at right angles, are not cuspidal.
//!
//! `recognise` proves the conditions below on the chain's interval coefficients (exact zeros
//! where a relation must hold exactly, strict signs where a quantity must not vanish), on the
//! geometry the chain was built from (after the rounding policy, when one applied).
//!
//! # Conditions (joints numbered 1 to 6 from the base)
//!
//! 1. axes 2, 3, 4 are parallel, of direction `u`;
//! 2. axis 1 is not parallel to `u`;
//! 3. axis 5 is perpendicular to `u`;
//! 4. axes 5 and 6 meet, at a point `W`, at right angles;
//! 5. axes 2 and 3 are distinct (distance `l₂ > 0`), and so are axes 3 and 4 (`l₃ > 0`).
//!
//! Nothing else is assumed: any offsets along the axes (UR's `d1, d4, d5, d6`), any lengths
//! `a2, a3`, an offset between axes 1 and 2 or between axes 4 and 5, any tool frame. The UR
//! DH table (`α = π/2, 0, 0, π/2, −π/2, 0`) satisfies them.
//!
//! # The three factors
//!
//! With `z₁` the direction of axis 1 and `O` a point on it, `v`, `w` the directions of axes 5
//! and 6, and `Aᵢ` any point of axis i, all at one configuration in the base frame:
//! - shoulder `g₁ = (z₁ × u)·(W − O)`: the signed distance (times `|z₁ × u|`) of `W` from the
//!   plane through axis 1 parallel to `u`;
//! - elbow `g₃ = ((A₃ − A₂) × (A₄ − A₃))·u`: twice the signed area of the triangle the axes
//!   2, 3, 4 cut in a plane normal to `u` (`l₂ l₃ sin θ₃` in DH terms);
//! - wrist `g₅ = (u × w)·v`: the sine of the angle from `u` to axis 6 about axis 5 (`± sin θ₅`).
//!
//! For standard UR DH parameters `g₁ = ±(a₂c₂ + a₃c₂₃ + d₅s₂₃₄)`. Over the whole family
//! `det J = κ·g₁·g₃·g₅` with `κ = ±1` fixed per arm (checked in the tests against
//! `Chain6R::det_jacobian` on random members and configurations). The proof needs less:
//!
//! **Each factor vanishes only where `det J` does.** `g₃ = 0`: axes 2, 3, 4 are parallel and
//! coplanar, so `A₃ = (1−t)A₂ + tA₄ + αu` and joint 3's twist `(u, A₃ × u)` is the affine
//! combination of joints 2's and 4's. `g₅ = 0`: axis 6 is parallel to `u` (`w ⟂ v`, `u ⟂ v`),
//! and four parallel axes have twists in the 3-dimensional space `{(λu, m): m ⟂ u}`. `g₁ = 0`:
//! the line through `W` along `u` is parallel to axes 2, 3, 4, meets axes 5 and 6 at `W`, and
//! lies in the plane of axis 1 and `u`, so it meets axis 1 (not parallel to `u`): a force along
//! it does no work on any joint's twist, so the twists are dependent.
//! Hence on an aspect (a connected set of configurations where `det J ≠ 0`) every factor keeps
//! its sign.
//!
//! **The signs of `(g₁, g₅, g₃)` tell the inverse-kinematics solutions of a pose apart** (each
//! sign picks one of the two roots of one step of the closed-form solution):
//! - The pose fixes axis 6 and `W` on it. Joints 2, 3, 4 turn about lines parallel to `u`, so
//!   they keep every point's coordinate along `u` in link 1; axis 5 is normal to `u`, so all of
//!   it, `W` included, lies at one constant coordinate `h`: `u(θ₁)·(W − O) = h`. As `u(θ₁)` turns
//!   about `z₁`, this reads `c + s·ρ cos(θ₁ − φ) = h` (`s = |z₁ × u| > 0`), while
//!   `g₁ = s·ρ sin(θ₁ − φ)`: its two roots have opposite `g₁`, which is 0 exactly where they
//!   coincide. The sign of `g₁` fixes θ₁.
//! - Link 1 placed, `u·w` is fixed by the pose; `u` and `w` are both normal to `v`, so
//!   `u·w = cos φ₅` and `g₅ = sin φ₅` with `φ₅ = θ₅ + const`: the sign of `g₅` fixes θ₅.
//! - With `g₅ ≠ 0`, axis 6 is not along `u`, so the orientation `Rᵤ(θ₂+θ₃+θ₄)·M(θ₅)·R(θ₆)`
//!   fixes `θ₂+θ₃+θ₄` and θ₆. Link 4 is then placed (its orientation, and its point `W`), hence
//!   the trace `A₄` of axis 4 in a plane normal to `u`, and `A₂` (link 1). `A₃` lies at `l₂` from
//!   `A₂` and `l₃` from `A₄`: two points mirrored across `A₂A₄`, of opposite `g₃`. The sign of
//!   `g₃` fixes `A₃`, hence θ₂ and θ₃ (`l₂, l₃ > 0`), and θ₄.
//!
//! So two distinct non-singular solutions of one pose differ in the sign of a factor, lie in
//! different aspects, and no path joins them without crossing `det J = 0`: the arm is not
//! cuspidal (and has at most 2³ = 8 solutions per pose, one per sign pattern).
//!
//! That the postures of a non-cuspidal arm can be told apart by the signs of the factors of
//! `det J` is the criterion recalled in the introduction of Salunkhe et al., arXiv:2202.08686;
//! the proof above, for this family, is the product's own.

use super::Chain6R;
use crate::kernel::interval::{strict_sign, Interval};
use crate::formulate::stated;

/// The one-line statement the report cites.
pub const CITATION: &str = "axes 2, 3, 4 parallel (u), axis 1 not parallel to u, axis 5 normal to u, axes 5 and 6 meeting at right angles at W: det J = ±g1·g3·g5 with shoulder g1 = (z1 × u)·(W − O), elbow g3 = ((A3 − A2) × (A4 − A3))·u, wrist g5 = (u × w)·v; each factor vanishes only where det J does, so it keeps its sign on an aspect, and the signs of (g1, g5, g3) pick the roots of the closed-form inverse kinematics (theta1, theta5, theta3) one each, so distinct solutions of a pose lie in distinct aspects (linkspace's own proof, arm6r::three_parallel; the signs-of-factors criterion as recalled by Salunkhe et al., arXiv:2202.08686)";

type V3 = [Interval; 3];

/// What `recognise` proved: the arm belongs to the family (module doc), with these enclosures.
#[derive(Clone, Copy, Debug)]
pub struct ThreeParallel {
    /// Distance between axes 2 and 3 (metres), proven positive.
    pub l2: Interval,
    /// Distance between axes 3 and 4 (metres), proven positive.
    pub l3: Interval,
}

fn cross(a: &V3, b: &V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: &V3, b: &V3) -> Interval {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn exact_zero(x: Interval) -> bool {
    x.inf() == 0.0 && x.sup() == 0.0
}

/// Proves the conditions of the module doc on `chain`'s coefficients, or `None` when one is not
/// proven (it may be false, or hold only up to rounding the enclosures cannot exclude).
///
/// Every relation is between consecutive axes, so it is tested in the frame of the first of
/// the two after its rotation: there axis k is the line through the origin along its stated
/// axis, and axis k+1 is joint k+1's origin applied to its own (the relation holds at every θ).
pub fn recognise(chain: &Chain6R) -> Option<ThreeParallel> {
    let axis = |k: usize| chain.axes[k];
    // Axis k+1 seen from joint k's frame: direction and a point.
    let next = |k: usize| (stated::apply(&chain.pre[k + 1].r, &chain.axes[k + 1]), chain.pre[k + 1].t);
    let (d2, _) = next(0);
    let (d3, p3) = next(1);
    let (d4, p4) = next(2);
    let (d5, _) = next(3);
    let (d6, p6) = next(4);
    let zero = |v: &V3| v.iter().all(|x| exact_zero(*x));
    let nonzero = |v: &V3| v.iter().any(|x| strict_sign(*x).is_some());
    // 1: axes 2, 3, 4 parallel; 2: axis 1 not along them.
    if !(zero(&cross(&axis(1), &d3)) && zero(&cross(&axis(2), &d4)) && nonzero(&cross(&axis(0), &d2))) {
        return None;
    }
    // 3: axis 5 normal to axis 4; 4: axis 6 normal to axis 5 and meeting it.
    if !(exact_zero(dot(&axis(3), &d5)) && exact_zero(dot(&axis(4), &d6)) && exact_zero(dot(&p6, &cross(&axis(4), &d6)))) {
        return None;
    }
    // 5: the distances of parallel unit axes, |p × a|.
    let dist = |p: &V3, a: &V3| {
        let c = cross(p, a);
        dot(&c, &c).sqrt()
    };
    let (l2, l3) = (dist(&p3, &axis(1)), dist(&p4, &axis(2)));
    if !(l2.inf() > 0.0 && l3.inf() > 0.0) {
        return None;
    }
    Some(ThreeParallel { l2, l3 })
}

/// The shoulder, elbow and wrist factors `[g₁, g₃, g₅]` of the module doc at `q`, in `f64`
/// (from the midpoints of the coefficients): for checks and reports, not for proofs.
pub fn factors(chain: &Chain6R, q: &[f64; 6]) -> [f64; 3] {
    let ax = chain.joint_axes(q);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let (z1, o) = ax[0];
    let u = ax[1].0;
    let (v, p5) = ax[4];
    let (w, p6) = ax[5];
    // Axes 5 and 6 meet at right angles: W is the foot of p6 on axis 5.
    let s = dot(sub(p6, p5), v);
    let wp = [0, 1, 2].map(|i| p5[i] + s * v[i]);
    let g1 = dot(cross(z1, u), sub(wp, o));
    let g3 = dot(cross(sub(ax[2].1, ax[1].1), sub(ax[3].1, ax[2].1)), u);
    let g5 = dot(cross(u, w), v);
    [g1, g3, g5]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{rounding, urdf};

    /// A quarter turn as vendor files write it, truncated (the rounding policy snaps it).
    #[allow(clippy::approx_constant)]
    const QUARTER: f64 = 1.570796327;

    /// A member of the family in modified DH (joint i's origin `Tx(a)·Tz(d)·Rx(α)`), the
    /// quarter turns written truncated as vendors do; `alpha1` the angle between axes 1 and 2.
    pub(crate) fn family(seed: u64, alpha1: f64, offsets: bool) -> String {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut uniform = |lo: f64, hi: f64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            lo + (hi - lo) * ((x >> 11) as f64 / (1u64 << 53) as f64)
        };
        let alpha = [0.0, alpha1, 0.0, 0.0, QUARTER, -QUARTER];
        let mut a = [0.0, 0.0, uniform(0.2, 0.6), uniform(-0.6, -0.2), 0.0, 0.0];
        if offsets {
            a[1] = uniform(-0.1, 0.1);
            a[4] = uniform(-0.1, 0.1);
        }
        let d: Vec<f64> = (0..6).map(|_| uniform(-0.2, 0.2)).collect();
        let mut xml = String::from("<robot name=\"family\"><link name=\"l0\"/>");
        for i in 0..6 {
            xml += &format!(
                "<link name=\"l{}\"/><joint name=\"j{}\" type=\"revolute\"><parent link=\"l{i}\"/><child link=\"l{}\"/><origin xyz=\"{} 0 {}\" rpy=\"{} 0 0\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3.14159\" upper=\"3.14159\" effort=\"1\" velocity=\"1\"/></joint>",
                i + 1, i + 1, i + 1, a[i], d[i], alpha[i]
            );
        }
        xml += &format!("<link name=\"tool\"/><joint name=\"jt\" type=\"fixed\"><parent link=\"l6\"/><child link=\"tool\"/><origin xyz=\"{} 0 {}\" rpy=\"0.3 0.2 0.1\"/></joint></robot>", uniform(-0.1, 0.1), uniform(0.0, 0.2));
        xml
    }

    pub(crate) fn chain(xml: &str) -> Chain6R {
        let m = urdf::parse(xml).expect("parses");
        Chain6R::from_mechanism(&rounding::snap(&m, rounding::ANGLE_TOLERANCE).0, None, None).expect("6R")
    }

    #[test]
    fn det_j_is_the_product_of_the_three_factors() {
        let mut x = 12345u64;
        let mut uniform = |lo: f64, hi: f64| {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((x >> 11) as f64 / (1u64 << 53) as f64)
        };
        for seed in 1..=12 {
            for (alpha1, offsets) in [(QUARTER, false), (QUARTER, true), (-QUARTER, true), (0.7, true)] {
                let c = chain(&family(seed, alpha1, offsets));
                assert!(recognise(&c).is_some(), "seed {seed}, alpha1 {alpha1}");
                // One sign per arm: det J = κ·g1·g3·g5 with κ = ±1.
                let mut kappa = None;
                for _ in 0..40 {
                    let q = [0; 6].map(|_| uniform(-3.1, 3.1));
                    let [g1, g3, g5] = factors(&c, &q);
                    let det = c.det_jacobian(&q);
                    let product = g1 * g3 * g5;
                    let k = *kappa.get_or_insert(det.signum() * product.signum());
                    assert!((det - k * product).abs() < 1e-12 + 1e-9 * det.abs().max(product.abs()), "seed {seed}, alpha1 {alpha1}: det {det:e}, g1 g3 g5 {product:e}");
                }
            }
        }
    }

    #[test]
    fn factors_match_the_ur_dh_formulas() {
        // UR DH (standard): g3 = a2 a3 s3, g5 = ±s5, g1 = ±(a2 c2 + a3 c23 + d5 s234).
        let xml = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/urdf/ur5.urdf")).expect("bundled");
        let c = chain(&xml);
        assert!(recognise(&c).is_some());
        let (a2, a3, d5) = (-0.425, -0.39225, 0.09465);
        for q in [[0.1, 0.2, 0.3, 0.4, 0.5, 0.6], [-2.0, 1.0, -0.7, 2.5, -1.2, 0.3], [1.0, -1.5, 2.2, -0.4, 2.9, -2.0]] {
            let [g1, g3, g5] = factors(&c, &q);
            let f = a2 * q[1].cos() + a3 * (q[1] + q[2]).cos() + d5 * (q[1] + q[2] + q[3]).sin();
            assert!((g1.abs() - f.abs()).abs() < 1e-12, "{g1} {f}");
            assert!((g3.abs() - (a2 * a3 * q[2].sin()).abs()).abs() < 1e-12);
            assert!((g5.abs() - q[4].sin().abs()).abs() < 1e-12);
        }
    }
}

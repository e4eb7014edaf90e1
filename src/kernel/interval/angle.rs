//! Angles of interval vectors: a proven enclosure of arg(x, y), and the shift of an angle
//! interval by whole turns.
//!
//! # Why the enclosure is proven
//!
//! inari is built without its `gmp` feature, so it has no `atan2`; and the platform's
//! `f64::atan2` documents no error bound. `arg` therefore uses correctly rounded field
//! operations and square root only, each result moved one ulp outward (`fast::Iv`: IEEE 754
//! rounds to nearest, within half an ulp). At each corner of the box (exact `f64` coordinates)
//! the angle is reduced to `atan t` with `t ∈ [0, 1]`; three halvings
//! `atan t = 2·atan(t / (1 + √(1 + t²)))` bring `t` below tan(π/32) < 0.1, and there the
//! alternating series `u − u³/3 + … + u¹⁷/17` is within `u¹⁹/19` (< 10⁻²⁰) of atan u, on the
//! low side. Every step is an interval operation and π comes from inari's enclosing constants,
//! so each corner's angle is enclosed within some ten ulps, with no assumption on any library.
//! (Inline `f64` steps rather than inari's calls: the angles are what every box's joint values
//! are read from, a few per joint, for boxes by the hundred thousand.)

use super::fast::Iv;
use super::{point, Interval};

/// `a / b` for `0 ≤ a` and `0 < b` (bounds), outward.
#[inline(always)]
fn div_positive(a: Iv, b: Iv) -> Iv {
    Iv { lo: (a.lo / b.hi).next_down().max(0.0), hi: (a.hi / b.lo).next_up() }
}

/// `a · b`, two products for nonnegative bounds (every product in `atan_unit`), else `Iv::mul`.
#[inline(always)]
fn mul_nonnegative(a: Iv, b: Iv) -> Iv {
    if a.lo >= 0.0 && b.lo >= 0.0 {
        Iv { lo: (a.lo * b.lo).next_down().max(0.0), hi: (a.hi * b.hi).next_up() }
    } else {
        a.mul(b)
    }
}

/// `√a` for `0 ≤ a`, outward.
#[inline(always)]
fn sqrt_positive(a: Iv) -> Iv {
    Iv { lo: a.lo.sqrt().next_down().max(0.0), hi: a.hi.sqrt().next_up() }
}

/// `1 / (2k + 1)`, outward.
#[inline(always)]
fn odd_reciprocal(k: u32) -> Iv {
    let x = 1.0 / f64::from(2 * k + 1);
    Iv { lo: x.next_down(), hi: x.next_up() }
}

/// atan over `t ⊂ [0, 1]` (bounds).
fn atan_unit(t: Iv) -> Iv {
    if t.hi == 0.0 {
        return Iv::ZERO;
    }
    let one = Iv { lo: 1.0, hi: 1.0 };
    let mut u = t;
    for _ in 0..3 {
        u = div_positive(u, one.add(sqrt_positive(one.add(mul_nonnegative(u, u)))));
    }
    // atan u = u·Σ (−u²)ᵏ/(2k+1): Horner over k = 8 down to 0, then the remainder of an
    // alternating series with decreasing terms, between the next term and 0.
    let u2 = mul_nonnegative(u, u);
    let mut sum = odd_reciprocal(8);
    for k in (0..8).rev() {
        sum = odd_reciprocal(k).sub(mul_nonnegative(u2, sum));
    }
    let mut next = u.hi;
    for _ in 0..18 {
        next = (next * u.hi).next_up();
    }
    let rest = (next / 19.0).next_up();
    mul_nonnegative(u, sum).add(Iv { lo: -rest, hi: 0.0 }).scale(8.0)
}

/// The angle of the nonzero point `(x, y)`: in [0, π] for `y ≥ 0` (π on the negative axis);
/// for `y < 0` in (−π, 0), or in (π, 2π) when `past_pi`.
fn corner_angle(x: f64, y: f64, past_pi: bool) -> Interval {
    let (ax, ay) = (x.abs(), y.abs());
    // The ratio of two exact doubles, at most 1, enclosed by its rounding moved outward (an
    // underflow to 0 too: next_up(0) is the least positive double).
    let ratio = |a: f64, b: f64| {
        if a == 0.0 {
            return Iv::ZERO;
        }
        let r = a / b;
        Iv { lo: r.next_down().max(0.0), hi: r.next_up().min(1.0) }
    };
    let in_quadrant = if ay <= ax { atan_unit(ratio(ay, ax)).to() } else { Interval::FRAC_PI_2 - atan_unit(ratio(ax, ay)).to() };
    let upper = if x < 0.0 { Interval::PI - in_quadrant } else { in_quadrant };
    match (y < 0.0, past_pi) {
        (false, _) => upper,
        (true, false) => -upper,
        (true, true) => Interval::TAU - upper,
    }
}

/// A proven enclosure of the angles of every vector of the box `[x]×[y]`, as one connected
/// interval, or `None` when the box may hold the origin (or is empty or unbounded).
///
/// Within [−π, π], except for a box across the negative x-axis (the branch cut), whose angles
/// are given within (π/2, 3π/2) to stay connected. A box that misses the origin sees it under
/// less than half a turn, and its extreme angles are at corners: the result is the hull of the
/// corners' proven angles (see the module doc).
pub fn arg(x: Interval, y: Interval) -> Option<Interval> {
    let bounded = |v: Interval| !v.is_empty() && v.inf().is_finite() && v.sup().is_finite();
    if !bounded(x) || !bounded(y) || (x.contains(0.0) && y.contains(0.0)) {
        return None;
    }
    let across_cut = x.sup() < 0.0 && y.contains(0.0);
    let corners = [(x.inf(), y.inf()), (x.inf(), y.sup()), (x.sup(), y.inf()), (x.sup(), y.sup())];
    Some(corners.iter().fold(Interval::EMPTY, |hull, &(a, b)| hull.convex_hull(corner_angle(a, b, across_cut))))
}

/// `x` shifted by a multiple of 2π so that its midpoint lies in [−π, π].
pub fn wrap(x: Interval) -> Interval {
    let k = (x.mid() / std::f64::consts::TAU).round();
    if k == 0.0 {
        x
    } else {
        x - point(k) * Interval::TAU
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use crate::kernel::interval::trig::{cos, sin};
    use proptest::prelude::*;

    /// True when `(x, y)` is proven to lie outside the arc of directions `a`, checked
    /// independently of `arg` with the sound sine and cosine: a vector lies in an arc narrower
    /// than half a turn exactly when it is counter-clockwise of (or on) its first direction and
    /// clockwise of (or on) its last. Wider arcs are split in two.
    fn proven_outside(x: f64, y: f64, a: Interval) -> bool {
        if a.wid() >= 3.0 {
            let m = a.mid();
            return proven_outside(x, y, interval(a.inf(), m)) && proven_outside(x, y, interval(m, a.sup()));
        }
        let (lo, hi) = (point(a.inf()), point(a.sup()));
        let (x, y) = (point(x), point(y));
        let ccw_of_lo = cos(lo) * y - sin(lo) * x;
        let cw_of_hi = sin(hi) * x - cos(hi) * y;
        ccw_of_lo.sup() < 0.0 || cw_of_hi.sup() < 0.0
    }

    /// Points of the box: its corners, edge midpoints, centre and some interior points.
    fn samples(x: Interval, y: Interval) -> Vec<(f64, f64)> {
        let along = |v: Interval| [0.0, 0.01, 0.25, 0.5, 0.75, 0.99, 1.0].map(|f| (v.inf() + f * (v.sup() - v.inf())).clamp(v.inf(), v.sup()));
        along(x).iter().flat_map(|&a| along(y).map(move |b| (a, b))).collect()
    }

    fn check_box(x: Interval, y: Interval) -> Result<(), TestCaseError> {
        let Some(a) = arg(x, y) else {
            prop_assert!(x.contains(0.0) && y.contains(0.0), "refused a box away from the origin: {x:?} {y:?}");
            return Ok(());
        };
        prop_assert!(a.inf() >= -Interval::PI.sup() && a.sup() <= 1.5 * Interval::PI.sup() + 1e-12, "{a:?}");
        for (px, py) in samples(x, y) {
            prop_assert!(!proven_outside(px, py, a), "({px}, {py}) of {x:?}×{y:?} outside {a:?}");
        }
        // Tight: within a few ulps of the corners' f64 angles (taken across the cut when needed).
        let corners = [(x.inf(), y.inf()), (x.inf(), y.sup()), (x.sup(), y.inf()), (x.sup(), y.sup())];
        let lift = |t: f64| if a.sup() > std::f64::consts::PI && t < 0.0 { t + std::f64::consts::TAU } else { t };
        let seen = corners.iter().map(|&(cx, cy)| lift(cy.atan2(cx)));
        let (lo, hi) = seen.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), t| (l.min(t), h.max(t)));
        prop_assert!(a.inf() > lo - 1e-14 && a.sup() < hi + 1e-14, "{a:?} much wider than [{lo}, {hi}]");
        Ok(())
    }

    #[test]
    fn arg_of_exact_angles_and_machin_identity() {
        let pi = Interval::PI;
        let cases = [((1.0, 0.0), point(0.0)), ((0.0, 2.0), Interval::FRAC_PI_2), ((-3.0, 0.0), pi), ((1.0, 1.0), Interval::FRAC_PI_4), ((-1.0, -1.0), -(pi - Interval::FRAC_PI_4)), ((0.0, -1.0), -Interval::FRAC_PI_2)];
        for ((x, y), want) in cases {
            let a = arg(point(x), point(y)).expect("away from 0");
            // Each operation moves its result one ulp outward: some ten ulps of π in all.
            assert!(!a.disjoint(want) && a.wid() < 1e-14, "({x}, {y}): {a:?}");
        }
        assert_eq!(arg(point(2.0), point(0.0)), Some(point(0.0)));
        // π/4 = 4·atan(1/5) − atan(1/239) exercises the series away from exact cases.
        let machin = point(4.0) * arg(point(5.0), point(1.0)).expect("") - arg(point(239.0), point(1.0)).expect("");
        assert!(!machin.disjoint(Interval::FRAC_PI_4) && machin.wid() < 1e-14, "{machin:?}");
        // atan(1/2) + atan(1/3) = π/4 as well.
        let euler = arg(point(2.0), point(1.0)).expect("") + arg(point(3.0), point(1.0)).expect("");
        assert!(!euler.disjoint(Interval::FRAC_PI_4) && euler.wid() < 1e-14, "{euler:?}");
    }

    #[test]
    fn arg_refuses_the_origin_and_unbounded_boxes() {
        assert!(arg(interval(-1e-3, 1e-3), interval(-1e-3, 1e-3)).is_none());
        assert!(arg(point(0.0), point(0.0)).is_none());
        assert!(arg(interval(0.0, 1.0), interval(0.0, 1.0)).is_none());
        assert!(arg(Interval::ENTIRE, point(1.0)).is_none());
        assert!(arg(Interval::EMPTY, point(1.0)).is_none());
    }

    #[test]
    fn arg_across_the_branch_cut_stays_connected() {
        let a = arg(interval(-1.0, -0.9), interval(-0.1, 0.1)).expect("away from 0");
        assert!(a.contains(std::f64::consts::PI) && a.wid() < 0.3, "{a:?}");
        // Touching the cut from below: still one interval past π.
        let below = arg(interval(-2.0, -1.0), interval(-1.0, 0.0)).expect("away from 0");
        assert!(below.inf() < std::f64::consts::PI + 1e-15 && below.sup() > 3.9 && below.sup() < 4.0, "{below:?}");
        check_box(interval(-1.0, -0.9), interval(-0.1, 0.1)).expect("sound");
        check_box(interval(-2.0, -1.0), interval(-1.0, 0.0)).expect("sound");
    }

    #[test]
    fn directions_on_a_circle_are_enclosed() {
        for k in 0..64 {
            let angle = -3.1 + 6.2 * f64::from(k) / 63.0;
            let (x, y) = (2.0 * angle.cos(), 2.0 * angle.sin());
            let (bx, by) = (interval(x - 1e-3, x + 1e-3), interval(y - 1e-3, y + 1e-3));
            let d = arg(bx, by).expect("away from 0");
            assert!(d.wid() < 2e-3, "{angle}: {d:?}");
            check_box(bx, by).expect("sound");
            let unit = arg(point(angle.cos()), point(angle.sin())).expect("a unit vector");
            assert!(unit.wid() <= 1e-14, "{unit:?}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn arg_encloses_every_sampled_point(cx in -4.0f64..4.0, cy in -4.0f64..4.0, scale in -16i32..1, wx in 0.0f64..1.0, wy in 0.0f64..1.0, axis in 0u8..6) {
            let (wx, wy) = (wx * 2f64.powi(scale), wy * 2f64.powi(scale));
            // Boxes anywhere, on the axes, on the negative x-axis (the cut) and of one point.
            let (x, y) = match axis {
                0 => (interval(cx, cx + wx), interval(cy, cy + wy)),
                1 => (interval(cx, cx + wx), point(0.0)),
                2 => (point(0.0), interval(cy, cy + wy)),
                3 => (interval(-cx.abs() - wx - 1e-300, -cx.abs() - 1e-300), interval(-wy, wy * 0.5)),
                4 => (point(cx), point(cy)),
                _ => (interval(cx, cx.next_up()), interval(cy, cy.next_up())),
            };
            check_box(x, y)?;
        }
    }

    #[test]
    fn wrap_moves_the_midpoint_into_one_turn() {
        let w = wrap(interval(7.0, 7.5));
        assert!(w.contains(7.0 - std::f64::consts::TAU) && w.contains(7.5 - std::f64::consts::TAU));
        assert_eq!(wrap(interval(-1.0, 1.0)), interval(-1.0, 1.0));
    }
}

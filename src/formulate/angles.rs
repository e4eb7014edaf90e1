//! Angles as intervals: sound reduction modulo 2π, read-outs from `(cos, sin)` boxes, wrapping,
//! and the test of an angle interval against joint limits taken modulo 2π.
//!
//! Everything here is outward rounded: an angle interval encloses every value it stands for.
//! A value is reduced modulo 2π by a three-part Cody–Waite split of 2π (the first two parts
//! short enough that `k·part` is exact for `|k| ≤ 2²⁶`, the third an interval enclosing the rest),
//! so `v − 2πk` keeps the accuracy of `v`'s own ulp instead of losing `|k|·ulp(2π)`. Beyond
//! `MAX_REDUCIBLE` radians the split is no longer exact and a value is refused.

use crate::kernel::contract::Inclusion;
use crate::kernel::interval::{interval, point, Interval};
use crate::kernel::interval::trig;

/// Largest `|value|` (radians) that `reduce` accepts: 2²⁶ turns, where `k·TAU_A` stops being exact.
pub(crate) const MAX_REDUCIBLE: f64 = 4.0e8;

/// fl(2π) with its low 27 mantissa bits cleared: 26 significant bits.
const TAU_A: f64 = 6.283185243606567;
/// fl(2π) − TAU_A, exact: 27 significant bits.
const TAU_B: f64 = 6.357301884918343e-8;
/// 2π − fl(2π) lies in this interval (computed at 300 bits with mpmath).
const TAU_C: (f64, f64) = (2.449293598294706e-16, 2.4492935982947064e-16);

/// 2π as an interval.
pub(crate) fn tau() -> Interval {
    Interval::TAU
}

/// `x − 2πk` for an integer-valued `k` with `|k| ≤ 2²⁶`, outward rounded and as tight as `x`.
fn minus_turns(x: Interval, k: f64) -> Interval {
    debug_assert!(k == k.trunc() && k.abs() <= 67_108_864.0);
    // k·TAU_A and k·TAU_B are exact (26 + 26 and 26 + 27 significant bits).
    x - point(k * TAU_A) - point(k * TAU_B) - point(k) * interval(TAU_C.0, TAU_C.1)
}

/// An interval enclosing `x − 2πk` for the integer `k` that brings `x`'s midpoint nearest 0, or
/// `None` when `x` is too large (beyond `MAX_REDUCIBLE`) to reduce accurately.
pub(crate) fn reduce(x: Interval) -> Option<Interval> {
    if x.is_empty() || !(x.mag() <= MAX_REDUCIBLE) {
        return None;
    }
    let k = (x.mid() / std::f64::consts::TAU).round();
    Some(minus_turns(x, k))
}

/// The decimal a parsed `f64` stands for lies within half an ulp of it (parsing rounds to
/// nearest): `[prev(x), next(x)]` encloses it. Zero stays exact (a written zero is zero).
pub(crate) fn stated(x: f64) -> Interval {
    if x == 0.0 {
        point(0.0)
    } else {
        interval(x.next_down(), x.next_up())
    }
}

/// `(cos x, sin x)` enclosed; exact at the point 0, so axis-aligned models keep point coefficients.
pub(crate) fn cos_sin(x: Interval) -> (Interval, Interval) {
    if x.inf() == 0.0 && x.sup() == 0.0 {
        return (point(1.0), point(0.0));
    }
    (trig::cos(x), trig::sin(x))
}

/// Margin beyond ±π of the whole-turn interval: any margin is sound, since [−π, π] already holds
/// every angle.
const TURN_MARGIN: f64 = 4.0e-15;

/// The angles `atan2(s, c)` over the box `[c]×[s]`, as one connected interval (it may exceed
/// (−π, π] to stay connected; the whole circle when the box holds the origin): the proven
/// `interval::angle::arg`. Empty for an empty box.
pub(crate) fn angle_interval(c: Interval, s: Interval) -> Interval {
    let pi = std::f64::consts::PI;
    if c.is_empty() || s.is_empty() {
        return Interval::EMPTY;
    }
    crate::kernel::interval::angle::arg(c, s).unwrap_or(interval(-pi, pi) + interval(-TURN_MARGIN, TURN_MARGIN))
}

/// The same set of angles, shifted by a whole number of turns so that its midpoint lies in
/// (−π, π]; wider than a turn gives [−π, π] (outward).
pub(crate) fn wrap(x: Interval) -> Interval {
    let pi = std::f64::consts::PI;
    if x.is_empty() || !(x.wid() < std::f64::consts::TAU) {
        return interval(-pi, pi) + interval(-TURN_MARGIN, TURN_MARGIN);
    }
    match reduce(x) {
        Some(r) => r,
        None => interval(-pi, pi) + interval(-TURN_MARGIN, TURN_MARGIN),
    }
}

/// Where the angle interval `r` lies with respect to the limits `[lower, upper]` modulo 2π.
///
/// `lower`, `upper` enclose the stated limits. `Outside` means no angle of `r` is congruent to a
/// value within the limits; `Inside` that every one is. Limits too large to reduce accurately
/// give `Straddles` unless they span a whole turn.
pub(crate) fn against_limits(r: Interval, lower: Interval, upper: Interval) -> Inclusion {
    let span = upper - lower;
    if span.inf() >= tau().sup() {
        return Inclusion::Inside;
    }
    if !(r.wid() < std::f64::consts::TAU) {
        return Inclusion::Straddles;
    }
    let (Some(r), Some(lo)) = (reduce(r), reduce(lower)) else { return Inclusion::Straddles };
    // Both now sit within about a turn of 0, and `lo + span` within two: turns −3..=3 cover
    // every congruent copy of the limit range that could meet `r`.
    let hi = lo + span;
    let mut inside = false;
    let mut meets = false;
    for j in -3..=3 {
        let shift = point(f64::from(j)) * tau();
        let (a, b) = (lo + shift, hi + shift);
        if !(r.sup() < a.inf() || r.inf() > b.sup()) {
            meets = true;
        }
        if r.inf() >= a.sup() && r.sup() <= b.inf() {
            inside = true;
        }
    }
    if inside {
        Inclusion::Inside
    } else if meets {
        Inclusion::Straddles
    } else {
        Inclusion::Outside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduction_keeps_the_accuracy_of_the_value() {
        // 1e8 − 2π·k and 20 − 6π, bracketed by the f64s around the 300-bit values (mpmath).
        let r = reduce(point(1e8)).expect("reducible");
        assert!(r.inf() <= 1.9426951345040144 && r.sup() >= 1.9426951345040147 && r.wid() < 1e-14, "{r:?}");
        let r = reduce(point(20.0)).expect("reducible");
        assert!(r.inf() <= 1.1504440784612404 && r.sup() >= 1.1504440784612406 && r.wid() < 1e-14, "{r:?}");
        assert!(reduce(point(1e16)).is_none() && reduce(point(1e300)).is_none());
    }

    #[test]
    fn multi_turn_limits_are_compared_modulo_a_turn() {
        let six_pi = 3.0 * std::f64::consts::TAU;
        let (lo, hi) = (stated(1.0 + six_pi), stated(2.0 + six_pi));
        assert_eq!(against_limits(interval(1.51, 1.52), lo, hi), Inclusion::Inside);
        assert_eq!(against_limits(interval(-1.0, 0.5), lo, hi), Inclusion::Outside);
        assert_eq!(against_limits(interval(0.9, 1.1), lo, hi), Inclusion::Straddles);
        let four_pi = stated(2.0 * std::f64::consts::TAU);
        assert_eq!(against_limits(interval(3.0, 3.1), -four_pi, four_pi), Inclusion::Inside);
    }

    #[test]
    fn angle_interval_handles_the_branch_cut() {
        let a = angle_interval(interval(-1.0, -0.9), interval(-0.1, 0.1));
        assert!(a.inf() < std::f64::consts::PI && a.sup() > std::f64::consts::PI && a.wid() < 0.3);
        let a = angle_interval(interval(0.5, 0.6), interval(0.7, 0.8));
        assert!(a.inf() <= 0.8f64.atan2(0.6) && a.sup() >= 0.7f64.atan2(0.5));
    }
}

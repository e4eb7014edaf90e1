//! Sound interval sine and cosine, and the angle of a direction known up to a box.
//!
//! inari is built without its `gmp` feature, so it has no elementary functions; these are ours.
//!
//! # Error bound
//!
//! The bounds come from the platform's `f64::sin`/`f64::cos` at the interval's end points
//! (glibc documents at most 1 ulp of error for both on x86-64, with exact argument reduction at
//! any magnitude), widened by `|v|·2⁻⁴⁸ + 2⁻¹⁰²²`, that is by at least 16 ulps, and clamped to
//! [-1, 1].
//! Between the end points the functions are monotone unless the interval holds an extremum
//! (`kπ` for cosine, `π/2 + kπ` for sine); whether it does is decided on `x/π` with a relative
//! slack of 1e-9, so in doubt an extremum is assumed, which only widens the result.
//! Intervals wider than 2π, unbounded or empty give [-1, 1] (empty for empty).

use inari::Interval;

/// From this width on, sin and cos give [-1, 1] without looking further. Just under 2π, so that
/// an interval of a full turn whose width rounded down is still caught; any threshold is sound,
/// since [-1, 1] encloses every value.
#[allow(clippy::approx_constant)] // a threshold below 2π, not an approximation of it
const NEARLY_A_TURN: f64 = 6.28;

/// Widening of an end-point value: far above the libm error, far below any width we use.
fn widen(v: f64) -> (f64, f64) {
    let e = v.abs() * f64::powi(2.0, -48) + f64::MIN_POSITIVE;
    (v - e, v + e)
}

/// Does `[lo, hi]` (in units of π, shifted by `shift`) possibly hold an integer `n`, and which
/// parities occur? Returns (holds an even n, holds an odd n), erring towards `true`.
fn integers_inside(lo: f64, hi: f64, shift: f64) -> (bool, bool) {
    let a = lo / std::f64::consts::PI - shift;
    let b = hi / std::f64::consts::PI - shift;
    let slack = 1e-9 * (1.0 + a.abs().max(b.abs()));
    let first = (a - slack).ceil();
    let last = (b + slack).floor();
    if first > last {
        return (false, false);
    }
    if last - first >= 1.0 {
        return (true, true);
    }
    let even = first.rem_euclid(2.0) == 0.0;
    (even, !even)
}

fn hull(values: &[f64], hits_max: bool, hits_min: bool) -> Interval {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in values {
        let (a, b) = widen(v);
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if hits_max {
        hi = 1.0;
    }
    if hits_min {
        lo = -1.0;
    }
    crate::kernel::interval::interval(lo.max(-1.0), hi.min(1.0))
}

/// An enclosure of `{sin t : t ∈ x}`.
///
/// # Examples
/// ```
/// use linkspace::kernel::interval::trig::sin;
/// use linkspace::kernel::interval::interval;
/// let s = sin(interval(1.0, 2.0));
/// assert!(s.contains(1.0) && s.contains(1f64.sin()) && s.inf() <= 2f64.sin().min(1f64.sin()));
/// ```
pub fn sin(x: Interval) -> Interval {
    if x.is_empty() {
        return Interval::EMPTY;
    }
    let (lo, hi) = (x.inf(), x.sup());
    if !(lo.is_finite() && hi.is_finite()) || hi - lo >= NEARLY_A_TURN {
        return crate::kernel::interval::interval(-1.0, 1.0);
    }
    // sin has a maximum at π/2 + 2kπ and a minimum at π/2 + (2k+1)π.
    let (max, min) = integers_inside(lo, hi, 0.5);
    hull(&[lo.sin(), hi.sin()], max, min)
}

/// An enclosure of `{cos t : t ∈ x}`.
///
/// # Examples
/// ```
/// use linkspace::kernel::interval::trig::cos;
/// use linkspace::kernel::interval::interval;
/// assert_eq!(cos(interval(-0.1, 0.1)).sup(), 1.0);
/// ```
pub fn cos(x: Interval) -> Interval {
    if x.is_empty() {
        return Interval::EMPTY;
    }
    let (lo, hi) = (x.inf(), x.sup());
    if !(lo.is_finite() && hi.is_finite()) || hi - lo >= NEARLY_A_TURN {
        return crate::kernel::interval::interval(-1.0, 1.0);
    }
    // cos has a maximum at 2kπ and a minimum at (2k+1)π.
    let (max, min) = integers_inside(lo, hi, 0.0);
    hull(&[lo.cos(), hi.cos()], max, min)
}

/// An interval `φ` such that every angle `θ` whose direction `(cos θ, sin θ)` is a positive
/// multiple of some `(c, s)` in the box `c × s` is `φ` modulo a turn; `None` when the box holds
/// the origin (any angle) or is not finite.
///
/// A box without the origin lies in an open half-plane through it, so its directions span less
/// than a half turn, and the extreme ones are those of corners: the corners' angles, taken
/// relative to the centre's, bound them. `atan2` (glibc: within 2 ulps) is widened by 1e-14,
/// over 10 ulps of any angle up to a turn.
///
/// # Examples
/// ```
/// use linkspace::kernel::interval::trig::angle;
/// use linkspace::kernel::interval::interval;
/// // Directions just left of (−1, 0): the angle straddles ±π, returned about π.
/// let phi = angle(interval(-1.0, -0.9), interval(-0.01, 0.01)).expect("no origin");
/// assert!(phi.contains(std::f64::consts::PI) && phi.wid() < 0.03);
/// assert!(angle(interval(-1.0, 1.0), interval(0.0, 0.1)).is_none());
/// ```
pub fn angle(c: Interval, s: Interval) -> Option<Interval> {
    if c.is_empty() || s.is_empty() || c.contains(0.0) && s.contains(0.0) {
        return None;
    }
    let (c0, c1, s0, s1) = (c.inf(), c.sup(), s.inf(), s.sup());
    if ![c0, c1, s0, s1].iter().all(|x| x.is_finite()) {
        return None;
    }
    let centre = (0.5 * (s0 + s1)).atan2(0.5 * (c0 + c1));
    let relative = |y: f64, x: f64| {
        let d = y.atan2(x) - centre;
        // Within a half turn of the centre's angle: bring it to (−π, π].
        if d > std::f64::consts::PI {
            d - std::f64::consts::TAU
        } else if d <= -std::f64::consts::PI {
            d + std::f64::consts::TAU
        } else {
            d
        }
    };
    let corners = [relative(s0, c0), relative(s0, c1), relative(s1, c0), relative(s1, c1)];
    let lo = corners.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = corners.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    const SLACK: f64 = 1e-14;
    Some(crate::kernel::interval::interval(centre + lo - SLACK, centre + hi + SLACK))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::interval::interval;
    use proptest::prelude::*;

    #[test]
    fn extrema_inside_are_included() {
        assert_eq!(cos(interval(-0.5, 0.5)).sup(), 1.0);
        assert_eq!(cos(interval(3.0, 3.3)).inf(), -1.0);
        assert_eq!(sin(interval(1.5, 1.6)).sup(), 1.0);
        assert_eq!(sin(interval(-1.6, -1.5)).inf(), -1.0);
        assert_eq!(sin(interval(0.0, 7.0)), interval(-1.0, 1.0));
        // π itself is not a double: cos of the double below π is just above -1.
        let c = cos(interval(std::f64::consts::PI, std::f64::consts::PI));
        assert!(c.contains(-1.0) || c.inf() > -1.0);
    }

    proptest! {
        /// Random boxes without the origin and points in them: the point's angle is in the
        /// enclosure modulo a turn.
        #[test]
        fn angles_of_boxes_hold_every_sampled_direction(c0 in -2.0f64..2.0, wc in 0.0f64..1.0, s0 in -2.0f64..2.0, ws in 0.0f64..1.0, tc in 0.0f64..=1.0, ts in 0.0f64..=1.0, scale in 0.1f64..10.0) {
            let (c, s) = (interval(c0, c0 + wc), interval(s0, s0 + ws));
            let (x, y) = (c0 + tc * wc, s0 + ts * ws);
            match angle(c, s) {
                None => prop_assert!(c.contains(0.0) && s.contains(0.0)),
                Some(phi) => {
                    let theta = (scale * y).atan2(scale * x);
                    let turns = ((phi.mid() - theta) / std::f64::consts::TAU).round();
                    prop_assert!(phi.contains(theta + turns * std::f64::consts::TAU), "{phi:?} misses {theta} of ({x}, {y})");
                    prop_assert!(phi.wid() < std::f64::consts::PI + 1e-9);
                }
            }
        }

        #[test]
        fn enclosures_hold_every_sampled_point(lo in -20.0f64..20.0, w in 0.0f64..4.0, t in 0.0f64..=1.0) {
            let x = interval(lo, lo + w);
            let v = lo + t * w;
            prop_assert!(sin(x).contains(v.sin()), "sin {:?} misses {}", x, v);
            prop_assert!(cos(x).contains(v.cos()), "cos {:?} misses {}", x, v);
            // And they are tight: within 1e-12 of the sampled hull on narrow intervals.
            if w < 1e-3 {
                let s = sin(x);
                prop_assert!(s.wid() <= (lo.sin() - (lo + w).sin()).abs() + 1e-3 * w + 1e-12);
            }
        }
    }
}
